//! Fill-reducing ordering of the sparse Cholesky factorisation: faer's AMD against METIS nested
//! dissection, on the SPD tangent of disc grids (`bench_support::particle_grid_tangent`: element
//! tangent + contact-zone springs + a small mass term), sequential:
//! - `*_analyze_factor`: symbolic analysis (ordering included) + numeric factorisation, the work
//!   after every pattern change;
//! - `*_factor`: numeric factorisation with the analysis reused, the work of a Newton iteration.
//!
//! The fill (nonzeros of L, simplicial count) of each ordering is printed before the timings.
//! Run: `cargo bench --bench ordering`.
use criterion::{criterion_group, criterion_main, Criterion};
use mpfem::bench_support::particle_grid_tangent;
use mpfem::linalg::direct::{cholesky_factor_nnz, FaerCholesky, FillOrdering};
use mpfem::linalg::LinearSolver;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    // (discs per side, mesh size): about 17 000 and 66 000 unknowns.
    for (n, h) in [(4usize, 1.0), (10, 0.5)] {
        let a = particle_grid_tangent(n, h);
        let fill: Vec<usize> = [FillOrdering::Amd, FillOrdering::Metis]
            .iter()
            .map(|&o| cholesky_factor_nnz(&a, o).expect("symbolic"))
            .collect();
        println!(
            "discs {n}x{n}, h = {h}: {} unknowns, nnz(A) = {}; nnz(L): AMD {}, METIS ND {} (METIS/AMD = {:.3})",
            a.nrows,
            a.nnz(),
            fill[0],
            fill[1],
            fill[1] as f64 / fill[0] as f64
        );
        let mut g = c.benchmark_group(format!("cholesky_discs_{n}x{n}_{}k", a.nrows / 1000));
        g.sample_size(10);
        for (name, o) in [("amd", FillOrdering::Amd), ("metis", FillOrdering::Metis)] {
            g.bench_function(format!("{name}_analyze_factor"), |bn| {
                bn.iter(|| {
                    let mut s = FaerCholesky::new(1).with_ordering(o);
                    s.analyze(&a).expect("analyze");
                    s.factor(&a).expect("factor");
                    black_box(s.factor_len());
                })
            });
            let mut s = FaerCholesky::new(1).with_ordering(o);
            s.analyze(&a).expect("analyze");
            println!("  {name}: factor storage {} values, supernodal: {:?}", s.factor_len().unwrap_or(0), s.is_supernodal());
            g.bench_function(format!("{name}_factor"), |bn| {
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
