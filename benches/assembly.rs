//! Element assembly (internal force + tangent) on a 320 × 320 mesh (102 400 elements,
//! 206 082 dofs), elastic and J2 (Table 1, loaded into the plastic range), sequential and on 2
//! threads. Run: `cargo bench --bench assembly`. Elements per second = 102 400 / time.
use criterion::{criterion_group, criterion_main, Criterion};
use mpfem::bench_support::{assembly_fixture, Law};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("assembly_102400_elements");
    g.sample_size(10);
    for law in [Law::Elastic, Law::J2] {
        for threads in [1usize, 2] {
            let mut fx = assembly_fixture(320, law, threads);
            g.bench_function(format!("{law:?}_threads{threads}"), |b| b.iter(|| black_box(fx.assemble())));
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
