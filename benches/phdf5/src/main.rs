//! One mpfem output step written five ways (three writers) on the ranks of `mpirun -n P`, for
//! about 10⁵ and 10⁶ nodes, to answer "parallel HDF5 or a gathered write?" on this machine:
//!
//! * `gathered`: every rank holds its 1/P of each dataset; they are gathered to rank 0
//!   (`MPI_Gatherv`, one a dataset), which writes the file alone through HDF5's default
//!   (sec2) driver. The time includes the gather.
//! * `gathered_reused`: the same, with rank 0's receive buffers allocated once and reused
//!   (the gathers then copy into memory already mapped).
//! * `parallel_collective` and `parallel_independent`: the file is opened on all ranks through
//!   the MPI-IO driver and each rank writes its rows of each dataset (a hyperslab) with a
//!   collective, or an independent, transfer.
//! * `bare`: rank 0 writes the same number of bytes as f64 in one dataset of a new file: the
//!   floor of any writer on this disk.
//!
//! Each time runs from a barrier to the close of the file (flush and close included) on the
//! last rank to finish. The datasets have the shape of `ResultsWriter::write_step` for a run
//! without contact data (as in `benches/output.rs`): per node `coordinates` (2 f64),
//! `displacement` and `velocity` (3 f64 each); per cell `cells` (4 i64), `particle_id` and
//! `material_id` (i32) and 8 f64 cell fields; the node and cell counts are those of the
//! 26 × 26 and 83 × 83 disc grids there (15.3 MB and 156 MB a step). After every write rank 0
//! reads the file back and compares every value with the one expected, outside the timing,
//! then removes the file. Files go to `$PHDF5_DIR` (default: the system temp folder).
//!
//! Output: one `RESULT` line a (size, method) on rank 0, read by `scripts/phdf5_bench.sh`.
//! `REPS` sets the repetitions kept (default 5, after one warm-up); `SIZES=small` runs only the
//! 10⁵ case; `SYNC=1` adds an fsync of the closed file to every time.

use hdf5::H5Type;
use hdf5_sys::h5d::{H5Dget_space, H5Dwrite};
use hdf5_sys::h5p::{H5FD_mpio_xfer_t, H5Pclose, H5Pcreate, H5Pset_dxpl_mpio};
use hdf5_sys::h5s::{H5S_seloper_t, H5Sclose, H5Screate_simple, H5Sselect_hyperslab};
use mpi::datatype::{Equivalence, PartitionMut};
use mpi::raw::AsRaw;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The node and cell counts of the two disc grids of `benches/output.rs`.
const SIZES: [(usize, usize); 2] = [(98_020, 86_528), (998_905, 881_792)];

#[derive(Clone, Copy)]
enum Kind {
    F64,
    I64,
    I32,
}

/// One dataset of an output step: name, per node (else per cell), values a row, type.
struct Spec {
    name: &'static str,
    per_node: bool,
    width: usize,
    kind: Kind,
}

const fn spec(name: &'static str, per_node: bool, width: usize, kind: Kind) -> Spec {
    Spec {
        name,
        per_node,
        width,
        kind,
    }
}

const SPECS: [Spec; 14] = [
    spec("coordinates", true, 2, Kind::F64),
    spec("cells", false, 4, Kind::I64),
    spec("particle_id", false, 1, Kind::I32),
    spec("material_id", false, 1, Kind::I32),
    spec("displacement", true, 3, Kind::F64),
    spec("velocity", true, 3, Kind::F64),
    spec("sxx", false, 1, Kind::F64),
    spec("syy", false, 1, Kind::F64),
    spec("sxy", false, 1, Kind::F64),
    spec("szz", false, 1, Kind::F64),
    spec("von_mises", false, 1, Kind::F64),
    spec("pressure", false, 1, Kind::F64),
    spec("eps_p", false, 1, Kind::F64),
    spec("eps_c", false, 1, Kind::F64),
];

/// The value at flat index `j` of dataset `d`: distinct across datasets and positions, so a
/// row written to the wrong place or not at all is caught by the read-back.
trait Value: H5Type + Equivalence + Copy + Default + PartialEq + std::fmt::Debug {
    fn at(d: usize, j: usize) -> Self;
}
impl Value for f64 {
    fn at(d: usize, j: usize) -> Self {
        j as f64 * 0.5 + d as f64 * 1e7
    }
}
impl Value for i64 {
    fn at(d: usize, j: usize) -> Self {
        (j as i64) * 3 + (d as i64) * 100_000_000
    }
}
impl Value for i32 {
    fn at(d: usize, j: usize) -> Self {
        (j % 1_000_003) as i32 + (d as i32) * 10_000_000
    }
}

enum Data {
    F64(Vec<f64>),
    I64(Vec<i64>),
    I32(Vec<i32>),
}

fn fill<T: Value>(d: usize, range: std::ops::Range<usize>) -> Vec<T> {
    range.map(|j| T::at(d, j)).collect()
}

/// Rows `[lo, hi)` of `rows` held by `rank` of `size`.
fn share(rows: usize, rank: usize, size: usize) -> (usize, usize) {
    (rows * rank / size, rows * (rank + 1) / size)
}

struct Step {
    nodes: usize,
    cells: usize,
    /// this rank's rows of every dataset, in the order of `SPECS`
    local: Vec<Data>,
}

impl Step {
    fn new(nodes: usize, cells: usize, rank: usize, size: usize) -> Self {
        let local = SPECS
            .iter()
            .enumerate()
            .map(|(d, s)| {
                let rows = if s.per_node { nodes } else { cells };
                let (lo, hi) = share(rows, rank, size);
                let r = lo * s.width..hi * s.width;
                match s.kind {
                    Kind::F64 => Data::F64(fill(d, r)),
                    Kind::I64 => Data::I64(fill(d, r)),
                    Kind::I32 => Data::I32(fill(d, r)),
                }
            })
            .collect();
        Step {
            nodes,
            cells,
            local,
        }
    }
    fn rows(&self, s: &Spec) -> usize {
        if s.per_node {
            self.nodes
        } else {
            self.cells
        }
    }
    fn bytes(&self) -> usize {
        SPECS
            .iter()
            .map(|s| {
                let size = match s.kind {
                    Kind::F64 | Kind::I64 => 8,
                    Kind::I32 => 4,
                };
                self.rows(s) * s.width * size
            })
            .sum()
    }
}

/// A barrier the waiting ranks sleep in (Open MPI's blocking barrier spins, and would take
/// one of the two cores from the rank writing). All ranks must call it at the same point: a
/// non-blocking barrier does not match a blocking one.
fn sleepy_barrier(world: &SimpleCommunicator) {
    let mut req = world.immediate_barrier();
    loop {
        match req.test() {
            Ok(_) => return,
            Err(r) => {
                req = r;
                std::thread::sleep(Duration::from_micros(200));
            }
        }
    }
}

/// With `SYNC=1`, rank 0 also fsyncs the closed file (inside the timing), so that the time is
/// that of the disk rather than of the page cache. All ranks share one page cache here, so one
/// fsync covers the bytes every rank wrote.
fn sync_if_asked(world: &SimpleCommunicator, path: &Path) {
    if world.rank() == 0 && std::env::var("SYNC").as_deref() == Ok("1") {
        std::fs::File::open(path)
            .and_then(|f| f.sync_all())
            .expect("fsync");
    }
}

fn serial_builder() -> hdf5::FileBuilder {
    let mut b = hdf5::File::with_options();
    b.with_fapl(|p| p.file_locking(false));
    b
}

fn step_group(file: &hdf5::File) -> hdf5::Result<hdf5::Group> {
    let g = file.create_group("steps/000001")?;
    g.new_attr::<f64>().create("time")?.write_scalar(&1.0f64)?;
    g.new_attr::<u64>().create("step")?.write_scalar(&1u64)?;
    Ok(g)
}

/// Gathers one dataset into `all` on rank 0. An `all` of the wrong length (a fresh one) is
/// replaced by a new allocation, whose pages are first touched by the gather itself.
fn gather_one<T: Value>(
    world: &SimpleCommunicator,
    local: &[T],
    width: usize,
    rows: usize,
    all: &mut Vec<T>,
) {
    let size = world.size() as usize;
    let root = world.process_at_rank(0);
    if world.rank() == 0 {
        let counts: Vec<i32> = (0..size)
            .map(|r| {
                let (lo, hi) = share(rows, r, size);
                ((hi - lo) * width) as i32
            })
            .collect();
        let displs: Vec<i32> = (0..size)
            .map(|r| (share(rows, r, size).0 * width) as i32)
            .collect();
        if all.len() != rows * width {
            *all = vec![T::default(); rows * width];
        }
        let mut part = PartitionMut::new(&mut all[..], counts, displs);
        root.gather_varcount_into_root(local, &mut part);
    } else {
        root.gather_varcount_into(local);
    }
}

/// A whole dataset from one process, as `ResultsWriter::write_step` writes it.
fn write_whole<T: Value>(g: &hdf5::Group, name: &str, shape: Vec<usize>, v: &[T]) {
    g.new_dataset::<T>()
        .shape(shape)
        .create(name)
        .expect("dataset")
        .write_raw(v)
        .expect("write");
}

/// (a) gather to rank 0, which writes alone with the default driver. `full` holds rank 0's
/// receive buffers: empty for new ones (allocated inside the timing, as a writer that builds
/// its arrays each step would), or those of an earlier call, reused. Returns the time and,
/// on rank 0, the part of it spent in the gathers.
fn gathered(
    world: &SimpleCommunicator,
    step: &Step,
    path: &Path,
    full: &mut Vec<Data>,
) -> (f64, f64) {
    if full.is_empty() {
        for s in &SPECS {
            full.push(match s.kind {
                Kind::F64 => Data::F64(Vec::new()),
                Kind::I64 => Data::I64(Vec::new()),
                Kind::I32 => Data::I32(Vec::new()),
            });
        }
    }
    world.barrier();
    let t0 = Instant::now();
    for ((s, data), all) in SPECS.iter().zip(&step.local).zip(full.iter_mut()) {
        let rows = step.rows(s);
        match (data, all) {
            (Data::F64(v), Data::F64(a)) => gather_one(world, v, s.width, rows, a),
            (Data::I64(v), Data::I64(a)) => gather_one(world, v, s.width, rows, a),
            (Data::I32(v), Data::I32(a)) => gather_one(world, v, s.width, rows, a),
            _ => unreachable!(),
        }
    }
    let t_gather = t0.elapsed().as_secs_f64();
    if world.rank() == 0 {
        let file = serial_builder().create(path).expect("create");
        let g = step_group(&file).expect("group");
        for (s, data) in SPECS.iter().zip(full.iter()) {
            let rows = step.rows(s);
            let shape = if s.width == 1 {
                vec![rows]
            } else {
                vec![rows, s.width]
            };
            match data {
                Data::F64(v) => write_whole(&g, s.name, shape, v),
                Data::I64(v) => write_whole(&g, s.name, shape, v),
                Data::I32(v) => write_whole(&g, s.name, shape, v),
            }
        }
        file.flush().expect("flush");
        drop(g);
        file.close().expect("close");
        sync_if_asked(world, path);
    }
    let t = t0.elapsed().as_secs_f64();
    sleepy_barrier(world);
    (max_time(world, t), t_gather)
}

/// Rank 0 gets the largest of the ranks' times.
fn max_time(world: &SimpleCommunicator, t: f64) -> f64 {
    let root = world.process_at_rank(0);
    if world.rank() == 0 {
        let mut all = vec![0.0f64; world.size() as usize];
        root.gather_into_root(&t, &mut all[..]);
        all.into_iter().fold(0.0, f64::max)
    } else {
        root.gather_into(&t);
        t
    }
}

/// This rank's rows of one dataset written as a hyperslab with transfer list `dxpl`.
fn write_rows<T: Value>(ds: &hdf5::Dataset, local: &[T], width: usize, lo: usize, dxpl: i64) {
    let mem_type = hdf5::Datatype::from_type::<T>().expect("type");
    let rows = (local.len() / width) as u64;
    unsafe {
        let fspace = H5Dget_space(ds.id());
        assert!(fspace >= 0);
        let (start, count): (Vec<u64>, Vec<u64>) = if width == 1 {
            (vec![lo as u64], vec![rows])
        } else {
            (vec![lo as u64, 0], vec![rows, width as u64])
        };
        let e = H5Sselect_hyperslab(
            fspace,
            H5S_seloper_t::H5S_SELECT_SET,
            start.as_ptr(),
            std::ptr::null(),
            count.as_ptr(),
            std::ptr::null(),
        );
        assert!(e >= 0, "select hyperslab");
        let n = local.len() as u64;
        let mspace = H5Screate_simple(1, &n, std::ptr::null());
        assert!(mspace >= 0);
        let e = H5Dwrite(
            ds.id(),
            mem_type.id(),
            mspace,
            fspace,
            dxpl,
            local.as_ptr().cast(),
        );
        assert!(e >= 0, "H5Dwrite");
        H5Sclose(mspace);
        H5Sclose(fspace);
    }
}

/// (b) all ranks write their rows into one file through the MPI-IO driver.
fn parallel(world: &SimpleCommunicator, step: &Step, path: &Path, collective: bool) -> f64 {
    let size = world.size() as usize;
    let rank = world.rank() as usize;
    world.barrier();
    let t0 = Instant::now();
    let file = {
        let mut b = hdf5::File::with_options();
        b.with_fapl(|p| p.mpio(world.as_raw(), None).file_locking(false));
        b.create(path).expect("create (mpio)")
    };
    let dxpl = unsafe {
        let p = H5Pcreate(*hdf5::globals::H5P_DATASET_XFER);
        assert!(p >= 0);
        let mode = if collective {
            H5FD_mpio_xfer_t::H5FD_MPIO_COLLECTIVE
        } else {
            H5FD_mpio_xfer_t::H5FD_MPIO_INDEPENDENT
        };
        assert!(H5Pset_dxpl_mpio(p, mode) >= 0);
        p
    };
    let g = step_group(&file).expect("group");
    for (s, data) in SPECS.iter().zip(&step.local) {
        let rows = step.rows(s);
        let (lo, _) = share(rows, rank, size);
        let shape = if s.width == 1 {
            vec![rows]
        } else {
            vec![rows, s.width]
        };
        match data {
            Data::F64(v) => {
                let ds = g
                    .new_dataset::<f64>()
                    .shape(shape)
                    .create(s.name)
                    .expect("dataset");
                write_rows(&ds, v, s.width, lo, dxpl);
            }
            Data::I64(v) => {
                let ds = g
                    .new_dataset::<i64>()
                    .shape(shape)
                    .create(s.name)
                    .expect("dataset");
                write_rows(&ds, v, s.width, lo, dxpl);
            }
            Data::I32(v) => {
                let ds = g
                    .new_dataset::<i32>()
                    .shape(shape)
                    .create(s.name)
                    .expect("dataset");
                write_rows(&ds, v, s.width, lo, dxpl);
            }
        }
    }
    unsafe {
        H5Pclose(dxpl);
    }
    file.flush().expect("flush");
    drop(g);
    file.close().expect("close");
    sync_if_asked(world, path);
    let t = t0.elapsed().as_secs_f64();
    max_time(world, t)
}

/// (c) rank 0 writes `values` f64 in one dataset of a new file; the others wait.
fn bare(world: &SimpleCommunicator, values: usize, path: &Path) -> f64 {
    world.barrier();
    let mut t = 0.0;
    if world.rank() == 0 {
        let data: Vec<f64> = (0..values).map(|j| f64::at(0, j)).collect();
        let t0 = Instant::now();
        let file = serial_builder().create(path).expect("create");
        file.new_dataset::<f64>()
            .shape(values)
            .create("d")
            .expect("dataset")
            .write_raw(&data)
            .expect("write");
        file.flush().expect("flush");
        file.close().expect("close");
        sync_if_asked(world, path);
        t = t0.elapsed().as_secs_f64();
    }
    sleepy_barrier(world);
    max_time(world, t)
}

fn check_one<T: Value>(g: &hdf5::Group, s: &Spec, d: usize, rows: usize) -> usize {
    let ds = g.dataset(s.name).expect("dataset in file");
    let want_shape = if s.width == 1 {
        vec![rows]
    } else {
        vec![rows, s.width]
    };
    assert_eq!(ds.shape(), want_shape, "{}", s.name);
    let v: Vec<T> = ds.read_raw().expect("read");
    assert_eq!(v.len(), rows * s.width);
    for (j, x) in v.iter().enumerate() {
        if *x != T::at(d, j) {
            panic!("{}[{j}] = {x:?}, expected {:?}", s.name, T::at(d, j));
        }
    }
    v.len()
}

/// Rank 0 reads the whole step back and compares every value; returns the values checked.
fn check_step(step: &Step, path: &Path) -> usize {
    let file = serial_builder().open(path).expect("open for check");
    let g = file.group("steps/000001").expect("group");
    let time: f64 = g.attr("time").unwrap().read_scalar().unwrap();
    assert_eq!(time, 1.0);
    let mut n = 0;
    for (d, s) in SPECS.iter().enumerate() {
        let rows = step.rows(s);
        n += match s.kind {
            Kind::F64 => check_one::<f64>(&g, s, d, rows),
            Kind::I64 => check_one::<i64>(&g, s, d, rows),
            Kind::I32 => check_one::<i32>(&g, s, d, rows),
        };
    }
    n
}

fn check_bare(values: usize, path: &Path) -> usize {
    let file = serial_builder().open(path).expect("open for check");
    let v: Vec<f64> = file.dataset("d").unwrap().read_raw().unwrap();
    assert_eq!(v.len(), values);
    let sum: f64 = v.iter().sum();
    // Σ 0.5 j for j < n, exact in f64 at these sizes
    let want = 0.25 * (values as f64) * (values as f64 - 1.0);
    assert!(
        (sum - want).abs() <= 1e-9 * want,
        "bare sum {sum} vs {want}"
    );
    assert_eq!(v[values - 1], f64::at(0, values - 1));
    v.len()
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

const METHODS: [&str; 5] = [
    "gathered",
    "gathered_reused",
    "parallel_collective",
    "parallel_independent",
    "bare",
];

fn main() {
    let universe = mpi::initialize().expect("MPI");
    let world = universe.world();
    let rank = world.rank();
    let size = world.size() as usize;
    let reps: usize = std::env::var("REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let sizes: &[(usize, usize)] = match std::env::var("SIZES").as_deref() {
        Ok("small") => &SIZES[..1],
        _ => &SIZES[..],
    };
    // one folder for all ranks, named after rank 0's process id
    let mut pid = std::process::id();
    world.process_at_rank(0).broadcast_into(&mut pid);
    let base = std::env::var_os("PHDF5_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    let dir = base.join(format!("phdf5-bench-{pid}"));
    if rank == 0 {
        std::fs::create_dir_all(&dir).expect("temp folder");
    }
    world.barrier();
    for &(nodes, cells) in sizes {
        let step = Step::new(nodes, cells, rank as usize, size);
        let bytes = step.bytes();
        let values = bytes / 8;
        let mut times = vec![Vec::new(); METHODS.len()];
        let mut gather_times = vec![Vec::new(); 2];
        // rank 0's receive buffers for `gathered_reused`, first touched in the warm-up
        let mut reused = Vec::new();
        let sync = u8::from(std::env::var("SYNC").as_deref() == Ok("1"));
        // repetition 0 is a warm-up (first touch of the buffers, the library's set-up), not kept
        for rep in 0..=reps {
            // a different method first in each repetition, so that the write-back of the
            // previous file does not always fall on the same one
            for k in 0..METHODS.len() {
                let m = (k + rep) % METHODS.len();
                let path = dir.join(format!("{}-{nodes}-{rep}.h5", METHODS[m]));
                let mut t_gather = f64::NAN;
                let t = match m {
                    0 | 1 => {
                        let mut fresh = Vec::new();
                        let full = if m == 0 { &mut fresh } else { &mut reused };
                        let (t, g) = gathered(&world, &step, &path, full);
                        t_gather = g;
                        t
                    }
                    2 => parallel(&world, &step, &path, true),
                    3 => parallel(&world, &step, &path, false),
                    _ => bare(&world, values, &path),
                };
                if rank == 0 {
                    let checked = if m == 4 {
                        check_bare(values, &path)
                    } else {
                        check_step(&step, &path)
                    };
                    let on_disk = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
                    eprintln!(
                        "sync {sync} ranks {size} nodes {nodes} rep {rep} {:<21} {:8.1} ms{}  ({checked} values checked, file {on_disk} bytes)",
                        METHODS[m],
                        t * 1e3,
                        if m < 2 { format!(" (gather {:.1} ms)", t_gather * 1e3) } else { String::new() }
                    );
                    std::fs::remove_file(&path).expect("remove");
                    if rep > 0 {
                        times[m].push(t);
                        if m < 2 {
                            gather_times[m].push(t_gather);
                        }
                    }
                }
                sleepy_barrier(&world);
            }
        }
        if rank == 0 {
            for (m, name) in METHODS.iter().enumerate() {
                let t = &times[m];
                let min = t.iter().cloned().fold(f64::INFINITY, f64::min);
                let all: Vec<String> = t.iter().map(|x| format!("{:.1}", x * 1e3)).collect();
                let gather = if m < 2 {
                    format!(" gather_median_ms={:.1}", median(&gather_times[m]) * 1e3)
                } else {
                    String::new()
                };
                println!(
                    "RESULT sync={sync} ranks={size} nodes={nodes} cells={cells} bytes={bytes} method={name} median_ms={:.1} min_ms={:.1} all_ms={}{gather}",
                    median(t) * 1e3,
                    min * 1e3,
                    all.join(",")
                );
            }
        }
    }
    world.barrier();
    if rank == 0 {
        let _ = std::fs::remove_dir(&dir);
    }
}
