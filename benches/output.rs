//! Writing one output step to `results.h5` (+ the XDMF rewrite) for 10⁵ and 10⁶ nodes: the
//! gathered write of a distributed run (rank 0 holds the whole state and writes it alone), next
//! to a bare HDF5 write of the same number of f64 values in one dataset (the floor any writer,
//! serial or parallel HDF5, has to pay on this disk). Grids of n × n aluminium discs, 145 nodes
//! and 128 elements a disc, in their initial state (the values do not change the cost).
//! Run: `cargo bench --bench output` (release; about 2 GB of temporary files in the system
//! temp folder, removed at the end). The figure is the ratio of the two times in one run. The
//! discs: `bench_support::disc_grid_case` at solid ratio 0.70, mesh size 5 mm.
use criterion::{criterion_group, criterion_main, Criterion};
use mpfem::model::Model;
use mpfem::results::ResultsWriter;
use mpfem::solver::Simulation;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("output_step");
    g.sample_size(10);
    let root = std::env::temp_dir().join(format!("mpfem-bench-output-{}", std::process::id()));
    for n in [26usize, 83] {
        let extra = "[contact]\nmethod = \"penalty\"\ncontact = \"sliding\"\n[solver]\nlinear = \"pcg\"\npreconditioner = \"jacobi\"\n";
        let text = mpfem::bench_support::disc_grid_case(n, 50.0 * n as f64, 0.70, 5.0, extra);
        let case = mpfem::case::parse(&text, std::path::Path::new(".")).expect("benchmark case");
        let model = Model::from_case(&case).expect("benchmark model");
        let sim = Simulation::new(model, case.time, case.solver).expect("benchmark simulation");
        let nodes = sim.model.n_nodes();
        let cells = sim.model.elements.len();
        let dir = root.join(format!("n{n}"));
        std::fs::create_dir_all(&dir).unwrap();
        let columns = mpfem::output::history_columns(&sim.model);
        let mut w = ResultsWriter::create(&dir, 1, &columns).unwrap();
        let mut step = 0;
        g.bench_function(format!("results_h5_{nodes}_nodes_{cells}_cells"), |b| {
            b.iter(|| {
                step += 1;
                w.write_step(&sim.snapshot(), step, step as f64).unwrap();
            })
        });
        if step == 0 {
            // (the benchmark was filtered out: one step to measure the size of)
            w.write_step(&sim.snapshot(), 1, 1.0).unwrap();
        }
        drop(w);
        // the same number of bytes as one output step holds (all its datasets), as f64 in one
        // dataset
        let bytes: u64 = {
            let f = mpfem::h5::open(&dir.join("results.h5")).unwrap();
            let g1 = f.group("steps/000001").unwrap();
            g1.datasets().unwrap().iter().map(|d| d.storage_size()).sum()
        };
        let values = (bytes as usize / 8).max(1);
        eprintln!("{nodes} nodes, {cells} cells: one output step holds {bytes} bytes of datasets");
        let raw = dir.join("raw.h5");
        let data = vec![1.0f64; values];
        let f = mpfem::h5::create(&raw).unwrap();
        let mut k = 0;
        g.bench_function(format!("bare_h5_{values}_f64"), |b| {
            b.iter(|| {
                k += 1;
                f.new_dataset::<f64>().shape(values).create(format!("d{k}").as_str()).unwrap().write_raw(&data).unwrap();
                f.flush().unwrap();
            })
        });
        drop(f);
        let _ = std::fs::remove_dir_all(&dir);
    }
    let _ = std::fs::remove_dir_all(&root);
}

criterion_group!(benches, bench);
criterion_main!(benches);
