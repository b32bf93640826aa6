//! Memory of a process's part against the whole model (issue 21's owned + ghost state): an
//! `n × n` grid of elastic discs with the barrier contact, a few steps, on every process of an
//! `mpirun`; each process prints its resident memory (Linux's VmRSS) after building the whole
//! model from the case (every process still does, once), after building its part and dropping
//! the whole model, and its peak (VmHWM) at the end, with its node and element counts.
//!
//!     cargo build --release --features petsc --example parts_memory
//!     mpirun -n 2 target/release/examples/parts_memory 32 3        # parts on 2 processes
//!     target/release/examples/parts_memory 32 3 whole              # the whole model, faer
//!
//! Arguments: the grid's side n (default 32: 1,024 discs) or a case file (`.toml`), the steps
//! (default 3; 0: to the case's end), and `whole` to run the whole model serially instead of a
//! part. Each process prints the last step's time, solid ratio and wall pressures too, so that
//! a part's run can be held against the whole one's.

use mpfem::model::Model;
use mpfem::parallel::part::RankPart;
use mpfem::solver::Simulation;
use std::ops::ControlFlow;

/// A field of /proc/self/status in MB (Linux), NaN elsewhere.
fn status_mb(field: &str) -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with(field)).and_then(|l| l.split_whitespace().nth(1)).and_then(|v| v.parse::<f64>().ok()))
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|v| v.parse().ok()).unwrap_or(32);
    let file = args.get(1).filter(|v| v.ends_with(".toml")).cloned();
    let steps: usize = args.get(2).and_then(|v| v.parse().ok()).unwrap_or(3);
    let whole_run = args.get(3).is_some_and(|v| v == "whole");
    let comm = mpfem::parallel::launch();
    let (rank, size) = (comm.rank(), comm.size());
    let side = 10.0 * n as f64;
    let (text, dir) = match &file {
        Some(f) => (std::fs::read_to_string(f).expect("the case file"), std::path::Path::new(f).parent().map(|p| p.to_path_buf()).unwrap_or_default()),
        None => (mpfem::bench_support::disc_grid_case(n, side, 0.75, 2.0, ""), std::path::PathBuf::from(".")),
    };
    let case = mpfem::case::parse(&text, &dir).expect("case");
    let whole = Model::from_case(&case).expect("model");
    let (n_nodes, n_elements) = (whole.n_nodes(), whole.elements.len());
    let rss_whole = status_mb("VmRSS:");
    let (mut sim, local) = if whole_run {
        let sim = Simulation::new(whole, case.time.clone(), case.solver.clone()).expect("simulation");
        (sim, (n_nodes, n_elements))
    } else {
        let _petsc = Box::leak(Box::new(mpfem::linalg::petsc::start("").expect("PETSc")));
        let mut owner: Vec<f64> = mpfem::distribute::partition_particles(&whole, size).iter().map(|&o| o as f64).collect();
        comm.broadcast(&mut owner);
        let owner: Vec<usize> = owner.iter().map(|&o| o as usize).collect();
        // ghosts within a quarter of the median particle's size
        let mut sizes: Vec<f64> = mpfem::distribute::particles(&whole).iter().map(|p| (p.max[0] - p.min[0]).max(p.max[1] - p.min[1])).collect();
        sizes.sort_by(f64::total_cmp);
        let reach = 0.25 * sizes[sizes.len() / 2];
        let part = RankPart::new(&whole, &whole.x0, &owner, reach, comm.clone()).expect("part");
        drop(whole);
        let local = (part.model.n_nodes(), part.model.elements.len());
        (Simulation::new_part(part, case.time.clone(), case.solver.clone()).expect("part simulation"), local)
    };
    let rss_part = status_mb("VmRSS:");
    let mut done = 0;
    let mut last = String::new();
    let t0 = std::time::Instant::now();
    let summary = sim.run_controlled(&mut |_, r| {
        done += 1;
        if let Some(c) = &r.compaction {
            last = format!("t = {:.9e} s, solid ratio {:.9e}, pressures {:?}", r.time, c.solid_ratio, c.pressure);
        }
        if steps > 0 && done >= steps {
            ControlFlow::Break("steps done".into())
        } else {
            ControlFlow::Continue(())
        }
    });
    let seconds = t0.elapsed().as_secs_f64();
    println!(
        "rank {rank} of {size} ({}): {} of {n_nodes} nodes, {} of {n_elements} elements; VmRSS {rss_whole:.0} MB with the whole model, {rss_part:.0} MB with the simulation built; peak {:.0} MB; {done} steps in {seconds:.1} s ({}); last step: {last}",
        if whole_run { "whole" } else { "part" },
        local.0,
        local.1,
        status_mb("VmHWM:"),
        match summary {
            Ok(s) => s.stop_reason,
            Err(e) => format!("failed: {e}"),
        }
    );
}
