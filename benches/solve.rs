//! One linear solve of the tangent of our own assembly (320 × 320 elastic block, 205 440 free
//! unknowns), all sequential (faer's global parallelism is set to `Par::Seq`, our solvers get
//! 1 thread):
//! - `ours_*`: numeric factorisation + solve with the symbolic analysis reused, as in a Newton
//!   loop;
//! - `ours_*_with_analysis`: analysis + factorisation + solve, the same work as
//! - `bare_faer_*`: `sp_lu` / `sp_cholesky` + solve called directly on the same matrix.
//! - `solve_205k_threads`: our LU and Cholesky factorisation + solve on 1 and 2 threads (2 were
//!   slower here: LU 1.38 against 1.01 s, Cholesky 0.374 against 0.242 s, 2026-12-01).
//! Run: `cargo bench --bench solve`.
use criterion::{criterion_group, criterion_main, Criterion};
use mpfem::bench_support::{assembly_fixture, Law};
use mpfem::linalg::{direct, make_solver, LinearSolverKind, Preconditioner, SolverOptions};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    let mut fx = assembly_fixture(320, Law::Elastic, 2);
    fx.assemble();
    let (kk, b) = fx.system();
    assert!(kk.nrows >= 200_000, "system has {} unknowns", kk.nrows);
    let mut g = c.benchmark_group("solve_205k");
    g.sample_size(10);
    for kind in [LinearSolverKind::Lu, LinearSolverKind::Cholesky, LinearSolverKind::Pcg] {
        let opts = SolverOptions { kind, preconditioner: Preconditioner::Ic0, pcg_tol: 1e-8, pcg_max_iterations: 20_000, threads: 1, ..Default::default() };
        let mut s = make_solver(&opts);
        s.analyze(&kk).expect("analyze");
        let mut x = vec![0.0; b.len()];
        g.bench_function(format!("ours_{kind:?}"), |bn| {
            bn.iter(|| {
                s.factor(&kk).expect("factor");
                x.iter_mut().for_each(|v| *v = 0.0);
                s.solve(&kk, &b, &mut x).expect("solve");
                black_box(&x);
            })
        });
        if kind != LinearSolverKind::Pcg {
            g.bench_function(format!("ours_{kind:?}_with_analysis"), |bn| {
                bn.iter(|| {
                    let mut s = make_solver(&opts);
                    s.analyze(&kk).expect("analyze");
                    s.factor(&kk).expect("factor");
                    s.solve(&kk, &b, &mut x).expect("solve");
                    black_box(&x);
                })
            });
        }
    }
    g.bench_function("bare_faer_lu", |bn| bn.iter(|| black_box(direct::bare_faer_lu_solve(&kk, &b))));
    g.bench_function("bare_faer_cholesky", |bn| bn.iter(|| black_box(direct::bare_faer_cholesky_solve(&kk, &b))));
    g.finish();
    // the same factorisation + solve on 1 and 2 threads (`Par::rayon(2)`): whether rank 0 of a
    // 2-rank run would gain from the core of the rank that waits for it (measured 2026-12-01,
    // idle machine: LU 1.01 s on 1 thread, 1.38 s on 2; Cholesky 0.242 s and 0.374 s — slower,
    // so the gathered factorisation keeps one thread a rank)
    let mut g = c.benchmark_group("solve_205k_threads");
    g.sample_size(10);
    for kind in [LinearSolverKind::Lu, LinearSolverKind::Cholesky] {
        for threads in [1, 2] {
            let opts = SolverOptions { kind, threads, ..Default::default() };
            let mut s = make_solver(&opts);
            s.analyze(&kk).expect("analyze");
            let mut x = vec![0.0; b.len()];
            g.bench_function(format!("ours_{kind:?}_{threads}_threads"), |bn| {
                bn.iter(|| {
                    s.factor(&kk).expect("factor");
                    s.solve(&kk, &b, &mut x).expect("solve");
                    black_box(&x);
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
