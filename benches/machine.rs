//! What this machine gives the solver's kernels, measured the way they run (one run, both
//! thread counts side by side, so that the ratios are of one moment of a shared machine):
//!
//! - `memory_stream`: the STREAM triad a = b + s c over three 128 MiB arrays (24 bytes a
//!   value: two read, one written), sequential and split over a 2-thread rayon pool. Its
//!   bytes per second are the memory-bandwidth floor of the element assembly: streaming the
//!   element data once (docs/architecture.md, "Element kernels against the bandwidth floor").
//! - `dense_gemm_1024`: faer's dense product of two 1024 × 1024 matrices with `Par::Seq` and
//!   `Par::rayon(2)`: whether the two cores are two cores for compute-bound floating-point
//!   work (they are when it takes about half the time).
//! - `dense_llt`: faer's dense Cholesky factorisation in place, 1024 and 96 wide, both
//!   parallelisms: the large block of a top separator and the small one typical of a 2D mesh's
//!   supernodes, which is where faer's sparse factorisation spends its time (see
//!   `benches/solve.rs`, `solve_205k_threads`).
//!
//! Run: `cargo bench --bench machine`.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltRegularization};
use faer::{Accum, Mat, Par};
use rayon::prelude::*;
use std::hint::black_box;

fn pars() -> [(&'static str, Par); 2] {
    [("1_thread", Par::Seq), ("2_threads", Par::rayon(2))]
}

fn stream(c: &mut Criterion) {
    const N: usize = 16 << 20; // 16 Mi values = 128 MiB an array
    let b: Vec<f64> = (0..N).map(|i| i as f64).collect();
    let cc: Vec<f64> = (0..N).map(|i| (N - i) as f64).collect();
    let mut a = vec![0.0; N];
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("a 2-thread pool");
    let mut g = c.benchmark_group("memory_stream");
    g.sample_size(10);
    g.throughput(Throughput::Bytes((3 * N * std::mem::size_of::<f64>()) as u64));
    g.bench_function("triad_1_thread", |bn| {
        bn.iter(|| {
            for ((a, b), c) in a.iter_mut().zip(&b).zip(&cc) {
                *a = b + 3.0 * c;
            }
            black_box(&a);
        })
    });
    g.bench_function("triad_2_threads", |bn| {
        bn.iter(|| {
            pool.install(|| {
                a.par_chunks_mut(1 << 16).zip(b.par_chunks(1 << 16)).zip(cc.par_chunks(1 << 16)).for_each(|((a, b), c)| {
                    for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                        *a = b + 3.0 * c;
                    }
                })
            });
            black_box(&a);
        })
    });
    g.finish();
}

fn spd(n: usize) -> Mat<f64> {
    // a well-conditioned symmetric positive definite matrix: diagonally dominant
    Mat::from_fn(n, n, |i, j| if i == j { 2.0 * n as f64 } else { 1.0 / (1.0 + (i as f64 - j as f64).abs()) })
}

fn dense(c: &mut Criterion) {
    let n = 1024;
    let (x, y) = (spd(n), spd(n));
    let mut z = Mat::<f64>::zeros(n, n);
    let mut g = c.benchmark_group("dense_gemm_1024");
    g.sample_size(10);
    g.throughput(Throughput::Elements((2 * n * n * n) as u64));
    for (name, par) in pars() {
        g.bench_function(name, |bn| {
            bn.iter(|| {
                faer::linalg::matmul::matmul(z.as_mut(), Accum::Replace, x.as_ref(), y.as_ref(), 1.0, par);
                black_box(&z);
            })
        });
    }
    g.finish();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("a 2-thread pool");
    let mut g = c.benchmark_group("dense_llt");
    g.sample_size(10);
    for n in [1024usize, 96] {
        let a0 = spd(n);
        for (name, par) in pars() {
            let params = Default::default();
            let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(n, par, params));
            let mut a = a0.clone();
            g.bench_with_input(BenchmarkId::new(name, n), &n, |bn, _| {
                bn.iter(|| {
                    a.copy_from(&a0);
                    let r = cholesky_in_place(a.as_mut(), LltRegularization::default(), par, MemStack::new(&mut mem), params);
                    black_box(r.is_ok());
                })
            });
            if par != Par::Seq {
                // the same called from a worker of the pool (rayon's joins then stay on it)
                g.bench_with_input(BenchmarkId::new(format!("{name}_in_pool"), n), &n, |bn, _| {
                    bn.iter(|| {
                        pool.install(|| {
                            a.copy_from(&a0);
                            let r = cholesky_in_place(a.as_mut(), LltRegularization::default(), par, MemStack::new(&mut mem), params);
                            black_box(r.is_ok());
                        })
                    })
                });
            }
        }
    }
    g.finish();
}

criterion_group!(benches, stream, dense);
criterion_main!(benches);
