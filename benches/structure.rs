//! faer's two kernel families for the sparse Cholesky factorisation, simplicial (up-looking,
//! one column at a time) and supernodal (dense blocks), on the tangents of random disc
//! packings (`bench_support::packing_tangent`: element tangent + contact springs between
//! particles within a reach + a small mass term), AMD ordering, sequential. faer picks the
//! supernodal kernels when its flop count exceeds 40 times the factor's entries; a packing's
//! tangent, nearly block-diagonal, mostly falls below that. The reach sets how far the
//! particles are coupled: 0 is a loose packing's block-diagonal tangent.
//! - `*_simplicial`, `*_supernodal`: numeric factorisation with the analysis reused (the work
//!   of a Newton iteration), each kernel family forced.
//!
//! The factor's size, the flop ratio and faer's own choice are printed before the timings.
//! Run: `cargo bench --bench structure`.
use criterion::{criterion_group, criterion_main, Criterion};
use mpfem::bench_support::{packing_tangent, random_discs_case};
use mpfem::linalg::direct::{FactorStructure, FaerCholesky};
use mpfem::linalg::LinearSolver;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    // (discs, die side mm, contact reach mm): about 1,600, 6,500, 26,000 and 103,000 unknowns
    for (count, side, reach) in [(16usize, 40.0, 0.0), (16, 40.0, 2.0), (64, 80.0, 0.0), (64, 80.0, 2.0), (256, 160.0, 0.0), (256, 160.0, 2.0), (1024, 320.0, 0.0), (1024, 320.0, 2.0)] {
        let a = packing_tangent(&random_discs_case(count, side, 2.0), reach);
        let mut auto = FaerCholesky::new(1).with_structure(FactorStructure::FaerChoice);
        auto.analyze(&a).expect("analyze");
        println!("{count} discs, reach {reach} mm: {} unknowns, nnz(A) = {}, factor storage {}, faer's choice supernodal: {:?}", a.nrows, a.nnz(), auto.factor_len().unwrap_or(0), auto.is_supernodal());
        let mut g = c.benchmark_group(format!("structure_{count}_discs_reach_{reach}"));
        g.sample_size(10);
        for (name, st) in [("simplicial", FactorStructure::Simplicial), ("supernodal", FactorStructure::Supernodal)] {
            let mut s = FaerCholesky::new(1).with_structure(st);
            s.analyze(&a).expect("analyze");
            println!("  {name}: factor storage {}", s.factor_len().unwrap_or(0));
            g.bench_function(name, |bn| {
                bn.iter(|| {
                    s.factor(&a).expect("factor");
                    black_box(s.kind());
                })
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
