//! The projection of the barrier pairs' Hessians onto the positive semi-definite matrices,
//! 1,000 pairs: the cyclic Jacobi of `contact::barrier::project_psd` on 4 × 4 and 6 × 6
//! matrices drawn like a pair's (a large positive rank-one part and a smaller indefinite
//! one), beside nalgebra's symmetric eigen-decomposition of the same (Householder
//! tridiagonalisation and implicit QL) for reference; and an edge point's 8 × 8 Hessian
//! projected on its 6 relative directions (`project_psd_relative`) against its 4-wide range
//! (`project_psd_point_on_edge`, what the solver does). Run: `cargo bench --bench projection`.
use criterion::{criterion_group, criterion_main, Criterion};
use mpfem::bench_support::edge_point_hessian;
use mpfem::contact::barrier::{project_psd, project_psd_point_on_edge, project_psd_relative};
use nalgebra::SMatrix;
use std::hint::black_box;

fn sample<const N: usize>(seed: &mut u64) -> [[f64; N]; N] {
    let mut rnd = || {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (*seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let g: [f64; N] = std::array::from_fn(|_| rnd());
    let mut h = [[0.0; N]; N];
    for i in 0..N {
        for j in 0..=i {
            let v = 1e3 * g[i] * g[j] + rnd();
            h[i][j] = v;
            h[j][i] = v;
        }
    }
    h
}

macro_rules! by_nalgebra {
    ($name:ident, $n:literal) => {
        fn $name(h: &mut [[f64; $n]; $n]) {
            let m = SMatrix::<f64, $n, $n>::from_fn(|i, j| 0.5 * (h[i][j] + h[j][i]));
            let e = m.symmetric_eigen();
            if e.eigenvalues.iter().all(|&l| l >= 0.0) {
                return;
            }
            for i in 0..$n {
                for k in 0..$n {
                    h[i][k] = (0..$n).map(|m| e.eigenvectors[(i, m)] * e.eigenvalues[m].max(0.0) * e.eigenvectors[(k, m)]).sum();
                }
            }
        }
    };
}
by_nalgebra!(by_nalgebra4, 4);
by_nalgebra!(by_nalgebra6, 6);

fn bench(c: &mut Criterion) {
    let mut seed = 7u64;
    let m4: Vec<[[f64; 4]; 4]> = (0..1000).map(|_| sample::<4>(&mut seed)).collect();
    let m6: Vec<[[f64; 6]; 6]> = (0..1000).map(|_| sample::<6>(&mut seed)).collect();
    // the two agree
    let mut worst: f64 = 0.0;
    for h in &m6 {
        let (mut a, mut b) = (*h, *h);
        project_psd(&mut a);
        by_nalgebra6(&mut b);
        let norm: f64 = h.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
        let diff: f64 = a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
        worst = worst.max(diff / norm);
    }
    eprintln!("largest relative difference, 6 x 6: {worst:e}");
    // edge points' Hessians Jᵀ K J (see the unit test of `project_psd_point_on_edge`)
    let quads: Vec<([[f64; 8]; 8], f64)> = m4
        .iter()
        .enumerate()
        .map(|(n, k)| {
            let xi = (n % 97) as f64 / 97.0;
            (edge_point_hessian(k, xi), xi)
        })
        .collect();
    let mut worst_range: f64 = 0.0;
    for (h, xi) in &quads {
        let (mut a, mut b) = (*h, *h);
        project_psd_relative::<8, 6>(&mut a);
        project_psd_point_on_edge(&mut b, *xi);
        let norm: f64 = h.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
        let diff: f64 = a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
        worst_range = worst_range.max(diff / norm);
    }
    eprintln!("largest relative difference, an edge point on its range against its relative motions: {worst_range:e}");
    let mut g = c.benchmark_group("project_psd_1000");
    g.bench_function("edge_point_relative_6", |b| b.iter(|| for (h, _) in &quads { let mut x = *h; project_psd_relative::<8, 6>(&mut x); black_box(x); }));
    g.bench_function("edge_point_range_4", |b| b.iter(|| for (h, xi) in &quads { let mut x = *h; project_psd_point_on_edge(&mut x, *xi); black_box(x); }));
    g.bench_function("jacobi_4", |b| b.iter(|| for h in &m4 { let mut x = *h; project_psd(&mut x); black_box(x); }));
    g.bench_function("nalgebra_4", |b| b.iter(|| for h in &m4 { let mut x = *h; by_nalgebra4(&mut x); black_box(x); }));
    g.bench_function("jacobi_6", |b| b.iter(|| for h in &m6 { let mut x = *h; project_psd(&mut x); black_box(x); }));
    g.bench_function("nalgebra_6", |b| b.iter(|| for h in &m6 { let mut x = *h; by_nalgebra6(&mut x); black_box(x); }));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
