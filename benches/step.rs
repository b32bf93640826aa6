//! One compaction step and one change of contact pairs.
//!
//! - `step_discs_4x4`: `Simulation::advance` of one 0.05 s step of a 4 × 4 grid of elastic
//!   aluminium discs with Coulomb friction 0.2, from the converged state after 4 steps
//!   (contact established; the state is restored before every sample, so each sample is the
//!   same step: pair selection, pattern, Newton with assembly, contact, factorisation);
//!   `step_discs_4x4_single` the same step without the barrier's double step at double roots
//!   (`Simulation::set_barrier_double_step`), for its gain.
//! - `pair_change_*`: the assembler's pattern switched between the pair sets of two
//!   configurations of a disc grid (`bench_support::pair_change_fixture`: every other disc
//!   moved by 0.4 element sizes, so the contact zones have other pairs), incrementally
//!   (`switch`, what a step does now) and rebuilt from the mesh (`rebuild`, what it did before).
//!
//! Run: `cargo bench --bench step`. For a step time before/after a change, measured in one
//! run on whole jobs with two binaries: `scripts/step_bench.sh OLD NEW`.
use criterion::{criterion_group, criterion_main, Criterion};
use mpfem::bench_support::{disc_grid_case, pair_change_fixture};
use std::hint::black_box;

fn step(c: &mut Criterion) {
    let text = disc_grid_case(4, 100.0, 0.76, 2.0, "[contact]\ncontact = \"rubbing\"\nfriction = 0.2\n[solver]\nthreads = 1\n");
    let case = mpfem::case::parse(&text, std::path::Path::new(".")).expect("case");
    let model = mpfem::model::Model::from_case(&case).expect("model");
    let mut sim = mpfem::solver::Simulation::new(model, case.time, case.solver).expect("simulation");
    for _ in 0..4 {
        sim.advance(0.05).expect("a converged step");
    }
    let state = sim.state();
    let mut g = c.benchmark_group("step");
    g.sample_size(10);
    // (the default, then without the barrier's double step: its gain in one run)
    for (name, on) in [("step_discs_4x4", true), ("step_discs_4x4_single", false)] {
        sim.set_barrier_double_step(on);
        sim.set_state(state.clone()).expect("state");
        let its = sim.advance(0.05).expect("a converged step").newton_iterations;
        eprintln!("{name}: {its} Newton iterations");
        g.bench_function(name, |b| {
            b.iter(|| {
                sim.set_state(state.clone()).expect("state");
                black_box(sim.advance(0.05).expect("a converged step").newton_iterations)
            })
        });
    }
    sim.set_barrier_double_step(true);
    g.finish();
}

fn pair_change(c: &mut Criterion) {
    let mut g = c.benchmark_group("pair_change");
    g.sample_size(10);
    for (n, h) in [(8usize, 5.0), (16, 5.0)] {
        let mut fx = pair_change_fixture(n, h);
        println!("discs {n}x{n}, h = {h}: {} elements, pairs {} / {}", fx.model.elements.len(), fx.pairs[0].len(), fx.pairs[1].len());
        let mut k = 0;
        g.bench_function(format!("switch_{n}x{n}"), |b| {
            b.iter(|| {
                k = 1 - k;
                black_box(fx.switch(k))
            })
        });
        g.bench_function(format!("rebuild_{n}x{n}"), |b| {
            b.iter(|| {
                k = 1 - k;
                black_box(fx.rebuild(k))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, step, pair_change);
criterion_main!(benches);
