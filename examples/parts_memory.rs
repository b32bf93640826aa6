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
//! Arguments: the grid's side n (default 32: 1,024 discs), the steps (default 3), and `whole`
//! to run the whole model serially instead of a part.

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
    let steps: usize = args.get(2).and_then(|v| v.parse().ok()).unwrap_or(3);
    let whole_run = args.get(3).is_some_and(|v| v == "whole");
    let comm = mpfem::parallel::launch();
    let (rank, size) = (comm.rank(), comm.size());
    let side = 10.0 * n as f64;
    let text = mpfem::bench_support::disc_grid_case(n, side, 0.75, 2.0, "");
    let case = mpfem::case::parse(&text, std::path::Path::new(".")).expect("case");
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
        let part = RankPart::new(&whole, &whole.x0, &owner, 0.25 * side / n as f64, comm.clone()).expect("part");
        drop(whole);
        let local = (part.model.n_nodes(), part.model.elements.len());
        (Simulation::new_part(part, case.time.clone(), case.solver.clone()).expect("part simulation"), local)
    };
    let rss_part = status_mb("VmRSS:");
    let mut done = 0;
    let t0 = std::time::Instant::now();
    let summary = sim.run_controlled(&mut |_, _| {
        done += 1;
        if done >= steps {
            ControlFlow::Break("steps done".into())
        } else {
            ControlFlow::Continue(())
        }
    });
    let seconds = t0.elapsed().as_secs_f64();
    println!(
        "rank {rank} of {size} ({}): {} of {n_nodes} nodes, {} of {n_elements} elements; VmRSS {rss_whole:.0} MB with the whole model, {rss_part:.0} MB with the simulation built; peak {:.0} MB; {done} steps in {seconds:.1} s ({})",
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
