//! Restart checkpoints: `checkpoint.h5`, everything a run needs to continue bit for bit after
//! a converged step — the solver state ([`crate::solver::SimState`]), each body's current mesh
//! (re-meshing replaces meshes mid-run, so a restart cannot rebuild the model from the case
//! alone) and a record of the caller's own run state (the CLI's pressure–density curve, say).
//!
//! ## Layout of `checkpoint.h5`
//! Every array is global (whole-model numbering, independent of how a run is split over
//! processes), f64 written and read as IEEE doubles (exact).
//! - root attributes: `format_version` (u32, [`FORMAT_VERSION`]), `mpfem_version` and
//!   `case_sha256` (strings: the version that wrote it, the SHA-256 of the case file's text),
//!   `step` (u64) and `time` (f64, s) of the last converged step;
//! - `/solution`: `u` and `u_prev` (n_dofs: displacements of the last two converged steps,
//!   mm), `lambda`, `j0`, `pressure`, `theta` (n_elements), `states` (n_elements × 4 Gauss
//!   points × 6: the material state `cp_inv[4], eps_p, eps_c`), `sig` (n_elements × 4 × 4,
//!   Cauchy stress per Gauss point, MPa), `alpha` (n_elements × enhanced modes);
//! - `/dynamics` (implicit dynamic analyses only): `u`, `v`, `a`, `g` (n_dofs);
//! - `/meshes/NNNNNN` per body: `nodes` (n × 2, mm, the mesh's reference coordinates),
//!   `elements` (n × 4, u64), `boundary` (n × 2, u64) and `edge_sets/NAME` (n × 2, u64);
//! - `scalars` (u8): CBOR of [`crate::solver::SimScalars`] (counters, energies, next step size,
//!   timing, contact pair histories, the barrier contact's κ, smallest distance and ties, the
//!   last step's report);
//! - `run` (u8): CBOR of the caller's record ([`Checkpoint::run_state`]).
//!
//! Since format version 2 the file starts with a 512-byte user block (which HDF5 skips) holding
//! `mpfem checkpoint sha256 ` and the SHA-256 of every byte after the block: a restart checks
//! it before HDF5 reads anything (HDF5 may crash on a damaged file rather than report it).
//! Every dataset carries an attribute `sha256`, the SHA-256 of its
//! values as little-endian bytes in storage order, and the root an attribute `header_sha256`
//! over the other root attributes (`format_version|mpfem_version|case_sha256|step|time bits`,
//! time as the hexadecimal of its IEEE bits). A restart checks every one, and the meshes'
//! node numbers against their node counts, before anything of the checkpoint is used: a
//! changed or damaged file is refused (exit 2) naming the dataset, never restarted into a
//! different run. Version 1 files (no checksums) are still read, with a warning.
//!
//! The file is written as `checkpoint.h5.tmp`, flushed and synced to disk, then renamed over
//! `checkpoint.h5`: a run killed while it writes leaves the previous checkpoint intact.
//!
//! A serial run or a replicated model reads all of it ([`Checkpoint::read`]). A run on parts
//! opens it lazily ([`CheckpointFile::open`]: the seal over every byte, the header, the
//! scalars) and each process reads its share's meshes and its part's rows of the arrays
//! ([`CheckpointFile::mesh`], [`WholeRows`]), so that no process holds the whole state.

use crate::solver::{SolverSpec, TimeSpec};
use crate::mesh::Mesh;
use crate::model::Model;
use crate::solver::{SimScalars, SimState, Simulation, Solution, WholeRows};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Name of the checkpoint file in a run's output directory.
pub const FILE_NAME: &str = "checkpoint.h5";
/// Version of the layout; a checkpoint of another version is refused.
pub const FORMAT_VERSION: u32 = 2;
/// The oldest layout still read (without checksums to verify).
const OLDEST_VERSION: u32 = 1;
/// The user block at the start of a checkpoint (format 2 on), which HDF5 does not read: it
/// holds [`SEAL`] and the SHA-256 of every byte after it, checked before HDF5 opens the file
/// (HDF5 itself may crash on a damaged file rather than report it).
const USERBLOCK: u64 = 512;
const SEAL: &[u8] = b"mpfem checkpoint sha256 ";

/// Write the whole-file checksum of the checkpoint at `path` (made with a [`USERBLOCK`]) into
/// its user block: [`SEAL`], the SHA-256 of the bytes after the block in hexadecimal, a new
/// line. Public for tests that edit a checkpoint on purpose.
///
/// # Errors
/// The I/O error when the file cannot be read or written.
pub fn seal(path: &Path) -> std::io::Result<()> {
    use std::io::{Seek, SeekFrom, Write};
    let mut head = SEAL.to_vec();
    head.extend_from_slice(body_sha256(path)?.as_bytes());
    head.push(b'\n');
    let mut f = std::fs::OpenOptions::new().write(true).open(path)?;
    f.seek(SeekFrom::Start(0))?;
    f.write_all(&head)?;
    f.sync_all()
}

/// The SHA-256 (hexadecimal) of the bytes of the file at `path` after its [`USERBLOCK`], read
/// in pieces (a checkpoint of a large run is not held in memory whole).
///
/// # Errors
/// The I/O error when the file cannot be read, or is shorter than its user block.
fn body_sha256(path: &Path) -> std::io::Result<String> {
    use sha2::Digest;
    use std::io::{Read, Seek, SeekFrom};
    let mut f = std::fs::File::open(path)?;
    if f.metadata()?.len() < USERBLOCK {
        return Err(std::io::Error::other("shorter than its user block"));
    }
    f.seek(SeekFrom::Start(USERBLOCK))?;
    let mut hasher = sha2::Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hasher.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

/// Whether the file carries a seal (false: a checkpoint of format 1, or one whose seal is
/// gone); Err naming the mismatch when its bytes are not the ones sealed.
fn check_seal(path: &Path) -> Result<bool, String> {
    use std::io::Read;
    let mut head = Vec::with_capacity(SEAL.len() + 64);
    std::fs::File::open(path).and_then(|f| f.take((SEAL.len() + 64) as u64).read_to_end(&mut head)).map_err(|e| e.to_string())?;
    if !head.starts_with(SEAL) {
        return Ok(false);
    }
    let stored = std::str::from_utf8(&head[SEAL.len()..]).unwrap_or("");
    let actual = body_sha256(path).map_err(|e| e.to_string())?;
    if stored != actual {
        return Err(format!("checksum mismatch of the whole file (SHA-256 {actual}, sealed {stored}): the file was changed or damaged after it was written"));
    }
    Ok(true)
}

/// What can go wrong with a checkpoint.
#[derive(Debug, Error)]
pub enum CheckpointError {
    #[error("{}: no checkpoint there (a run writes one with [output] checkpoint_every or checkpoint_minutes, and when it is stopped by SIGTERM or SIGINT)", path.display())]
    Missing { path: PathBuf },
    #[error("{}: not a readable checkpoint: {reason}", path.display())]
    Corrupt { path: PathBuf, reason: String },
    #[error("{}: cannot write the checkpoint: {reason}", path.display())]
    Write { path: PathBuf, reason: String },
    #[error("{}: the checkpoint does not fit the model of the case: {reason}", path.display())]
    Mismatch { path: PathBuf, reason: String },
}

/// What names a checkpoint: its file, layout, writer, case and step, and the caller's record
/// ([`CheckpointHead::run_state`]). Both ways of reading one ([`Checkpoint`],
/// [`CheckpointFile`]) dereference to it.
#[derive(Clone, Debug)]
pub struct CheckpointHead {
    pub path: PathBuf,
    /// The layout's version ([`FORMAT_VERSION`], or an older one still read).
    pub format_version: u32,
    pub mpfem_version: String,
    pub case_sha256: String,
    pub step: usize,
    pub time: f64,
    run: Vec<u8>,
}

impl CheckpointHead {
    /// The caller's record written with the checkpoint ([`write`]'s `run`).
    ///
    /// # Errors
    /// [`CheckpointError::Corrupt`] when it is not a `T`.
    pub fn run_state<T: DeserializeOwned>(&self) -> Result<T, CheckpointError> {
        ciborium::from_reader(self.run.as_slice()).map_err(|e| CheckpointError::Corrupt { path: self.path.clone(), reason: format!("run: {e}") })
    }
}

/// A checkpoint read back whole ([`Checkpoint::read`]).
#[derive(Clone, Debug)]
pub struct Checkpoint {
    pub head: CheckpointHead,
    /// Each body's mesh at the checkpoint.
    pub meshes: Vec<Mesh>,
    pub state: SimState,
}

impl std::ops::Deref for Checkpoint {
    type Target = CheckpointHead;
    fn deref(&self) -> &CheckpointHead {
        &self.head
    }
}

fn h5err(path: &Path) -> impl Fn(hdf5::Error) -> CheckpointError + '_ {
    move |e| CheckpointError::Write { path: path.to_path_buf(), reason: e.to_string() }
}

fn cbor<T: Serialize>(v: &T) -> Result<Vec<u8>, String> {
    let mut buf = Vec::new();
    ciborium::into_writer(v, &mut buf).map_err(|e| e.to_string())?;
    Ok(buf)
}

/// The SHA-256, in hexadecimal, of values as little-endian bytes in their order.
fn digest<T: Copy, const W: usize>(v: &[T], bytes: impl Fn(T) -> [u8; W]) -> String {
    use sha2::Digest;
    let mut h = sha2::Sha256::new();
    for &x in v {
        h.update(bytes(x));
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

fn digest_f64(v: &[f64]) -> String {
    digest(v, f64::to_le_bytes)
}

fn digest_u64(v: &[u64]) -> String {
    digest(v, u64::to_le_bytes)
}

fn digest_u8(v: &[u8]) -> String {
    digest(v, |b: u8| [b])
}

/// The checksum of the root attributes other than itself.
fn header_digest(version: u32, mpfem_version: &str, case_sha256: &str, step: u64, time: f64) -> String {
    let text = format!("{version}|{mpfem_version}|{case_sha256}|{step}|{:016x}", time.to_bits());
    digest_u8(text.as_bytes())
}

fn flat_usize<const N: usize>(v: &[[usize; N]]) -> Vec<u64> {
    v.iter().flat_map(|a| a.iter().map(|&x| x as u64)).collect()
}

/// Write `DIR/checkpoint.h5` for the state of `sim` (call between steps, e.g. from the
/// observer of [`Simulation::run_controlled`]) with `case_sha256` (the case file's SHA-256,
/// checked on restart) and the caller's record `run`. Returns the path written.
///
/// # Errors
/// [`CheckpointError::Write`] when the file cannot be written; the previous checkpoint is
/// then still in place.
pub fn write<T: Serialize>(dir: &Path, sim: &Simulation, case_sha256: &str, run: &T) -> Result<PathBuf, CheckpointError> {
    write_state(dir, &sim.model, &sim.state(), case_sha256, run)
}

/// [`write`] for `state` on `model` (a distributed run's state gathered onto the whole model
/// it was made from, [`Simulation::gather`]).
///
/// # Errors
/// As [`write`].
pub fn write_state<T: Serialize>(dir: &Path, model: &Model, state: &SimState, case_sha256: &str, run: &T) -> Result<PathBuf, CheckpointError> {
    let path = dir.join(FILE_NAME);
    let tmp = dir.join(format!("{FILE_NAME}.tmp"));
    let werr = |reason: String| CheckpointError::Write { path: path.clone(), reason };
    let scalars = cbor(&state.scalars).map_err(&werr)?;
    let run = cbor(run).map_err(&werr)?;
    {
        let f = crate::h5::create_with_userblock(&tmp, USERBLOCK).map_err(h5err(&tmp))?;
        write_h5(&f, model, state, case_sha256, &scalars, &run).map_err(h5err(&tmp))?;
        f.flush().map_err(h5err(&tmp))?;
        f.close().map_err(h5err(&tmp))?;
    }
    let io = |e: std::io::Error| CheckpointError::Write { path: path.clone(), reason: e.to_string() };
    seal(&tmp).map_err(io)?;
    std::fs::File::open(&tmp).and_then(|f| f.sync_all()).map_err(io)?;
    std::fs::rename(&tmp, &path).map_err(io)?;
    // the rename itself is durable once the directory is synced (best effort)
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(path)
}

fn write_h5(f: &hdf5::File, model: &Model, st: &SimState, case_sha256: &str, scalars: &[u8], run: &[u8]) -> hdf5::Result<()> {
    use hdf5::types::VarLenUnicode;
    let text = |s: &str| -> hdf5::Result<VarLenUnicode> { s.parse().map_err(|e| hdf5::Error::from(format!("{e}"))) };
    let step = st.scalars.run.step as u64;
    f.new_attr::<u32>().create("format_version")?.write_scalar(&FORMAT_VERSION)?;
    f.new_attr::<VarLenUnicode>().create("mpfem_version")?.write_scalar(&text(env!("CARGO_PKG_VERSION"))?)?;
    f.new_attr::<VarLenUnicode>().create("case_sha256")?.write_scalar(&text(case_sha256)?)?;
    f.new_attr::<u64>().create("step")?.write_scalar(&step)?;
    f.new_attr::<f64>().create("time")?.write_scalar(&st.scalars.time)?;
    let header = header_digest(FORMAT_VERSION, env!("CARGO_PKG_VERSION"), case_sha256, step, st.scalars.time);
    f.new_attr::<VarLenUnicode>().create("header_sha256")?.write_scalar(&text(&header)?)?;
    // every dataset with the checksum of its values
    let sum = |d: &hdf5::Dataset, hex: String| -> hdf5::Result<()> { d.new_attr::<VarLenUnicode>().create("sha256")?.write_scalar(&text(&hex)?) };
    let put_u8 = |g: &hdf5::Group, name: &str, v: &[u8]| -> hdf5::Result<()> {
        let d = g.new_dataset::<u8>().shape(v.len()).create(name)?;
        d.write_raw(v)?;
        sum(&d, digest_u8(v))
    };
    let put_f64 = |g: &hdf5::Group, name: &str, shape: Vec<usize>, v: &[f64]| -> hdf5::Result<()> {
        let d = g.new_dataset::<f64>().shape(shape).create(name)?;
        d.write_raw(v)?;
        sum(&d, digest_f64(v))
    };
    let put_u64 = |g: &hdf5::Group, name: &str, shape: Vec<usize>, v: &[u64]| -> hdf5::Result<()> {
        let d = g.new_dataset::<u64>().shape(shape).create(name)?;
        d.write_raw(v)?;
        sum(&d, digest_u64(v))
    };
    let root = f.group("/")?;
    put_u8(&root, "scalars", scalars)?;
    put_u8(&root, "run", run)?;

    let sol = &st.sol;
    let ne = sol.lambda.len();
    let g = f.create_group("solution")?;
    put_f64(&g, "u", vec![sol.u.len()], &sol.u)?;
    put_f64(&g, "u_prev", vec![st.u_prev.len()], &st.u_prev)?;
    for (name, v) in [("lambda", &sol.lambda), ("j0", &sol.j0), ("pressure", &sol.fields.pressure), ("theta", &sol.fields.theta)] {
        put_f64(&g, name, vec![v.len()], v)?;
    }
    let states: Vec<f64> = sol.fields.states.iter().flat_map(|gp| gp.iter().flat_map(|q| [q.cp_inv[0], q.cp_inv[1], q.cp_inv[2], q.cp_inv[3], q.eps_p, q.eps_c])).collect();
    put_f64(&g, "states", vec![ne, 4, 6], &states)?;
    let sig: Vec<f64> = sol.fields.sig.iter().flat_map(|gp| gp.iter().flatten().copied()).collect();
    put_f64(&g, "sig", vec![ne, 4, 4], &sig)?;
    let n_enh = sol.fields.alpha.first().map_or(0, |a| a.len());
    let alpha: Vec<f64> = sol.fields.alpha.iter().flatten().copied().collect();
    put_f64(&g, "alpha", vec![ne, n_enh], &alpha)?;
    if let Some(dy) = &st.dynamics {
        let g = f.create_group("dynamics")?;
        for (name, v) in ["u", "v", "a", "g"].iter().zip(dy) {
            put_f64(&g, name, vec![v.len()], v)?;
        }
    }
    let meshes = f.create_group("meshes")?;
    for (b, body) in model.bodies.iter().enumerate() {
        let m = &body.mesh;
        let g = meshes.create_group(&format!("{b:06}"))?;
        g.new_attr::<VarLenUnicode>().create("name")?.write_scalar(&text(&body.name)?)?;
        let nodes: Vec<f64> = m.nodes.iter().flatten().copied().collect();
        put_f64(&g, "nodes", vec![m.nodes.len(), 2], &nodes)?;
        put_u64(&g, "elements", vec![m.elements.len(), 4], &flat_usize(&m.elements))?;
        put_u64(&g, "boundary", vec![m.boundary.len(), 2], &flat_usize(&m.boundary))?;
        let sets = g.create_group("edge_sets")?;
        for (name, edges) in &m.edge_sets {
            put_u64(&sets, name.as_str(), vec![edges.len(), 2], &flat_usize(edges))?;
        }
    }
    Ok(())
}

/// The checkpoint file named by `path`: `path/checkpoint.h5` for a directory (or a path that
/// does not exist and does not end in `.h5`), otherwise `path` itself.
pub fn file_of(path: &Path) -> PathBuf {
    let h5 = path.extension().is_some_and(|e| e == "h5");
    if path.is_dir() || (!path.exists() && !h5) {
        path.join(FILE_NAME)
    } else {
        path.to_path_buf()
    }
}

fn pairs<const N: usize>(v: Vec<u64>, what: &str) -> Result<Vec<[usize; N]>, String> {
    if v.len() % N != 0 {
        return Err(format!("{what}: {} values, not a multiple of {N}", v.len()));
    }
    Ok(v.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i] as usize)).collect())
}

impl Checkpoint {
    /// Read a checkpoint (a file, or a directory holding `checkpoint.h5`).
    ///
    /// # Errors
    /// [`CheckpointError::Missing`] when there is no such file, [`CheckpointError::Corrupt`]
    /// when it is not a complete checkpoint of this format version.
    pub fn read(path: &Path) -> Result<Self, CheckpointError> {
        CheckpointFile::open(path)?.read()
    }

    fn read_h5(f: &hdf5::File, path: &Path) -> Result<Self, String> {
        let head = Header::read(f, path)?;
        let checked = |name: &str, d: &hdf5::Dataset, actual: String| head.checked(name, d, actual);
        let f64s = |name: &str| -> Result<Vec<f64>, String> {
            let d = f.dataset(name).map_err(e(name))?;
            let v = d.read_raw::<f64>().map_err(e(name))?;
            checked(name, &d, digest_f64(&v))?;
            Ok(v)
        };
        let scalars: SimScalars = ciborium::from_reader(head.bytes(f, "scalars")?.as_slice()).map_err(|err| format!("scalars: {err}"))?;
        let run = head.bytes(f, "run")?;

        let u = f64s("solution/u")?;
        let u_prev = f64s("solution/u_prev")?;
        let lambda = f64s("solution/lambda")?;
        let ne = lambda.len();
        let per_element = |name: &str, width: usize| -> Result<Vec<f64>, String> {
            let v = f64s(name)?;
            if v.len() != ne * width {
                return Err(format!("{name}: {} values for {ne} elements of {width}", v.len()));
            }
            Ok(v)
        };
        let j0 = per_element("solution/j0", 1)?;
        let pressure = per_element("solution/pressure", 1)?;
        let theta = per_element("solution/theta", 1)?;
        let states = per_element("solution/states", 24)?;
        let sig = per_element("solution/sig", 16)?;
        let alpha = per_element("solution/alpha", crate::element::N_ENH)?;
        let fields = crate::assembly::ElementFields::from_records(&states, &sig, &alpha, pressure, theta);
        let dynamics = if f.link_exists("dynamics") {
            Some([f64s("dynamics/u")?, f64s("dynamics/v")?, f64s("dynamics/a")?, f64s("dynamics/g")?])
        } else {
            None
        };
        let mut meshes = Vec::new();
        let mut names = f.group("meshes").and_then(|g| g.member_names()).map_err(e("meshes"))?;
        names.sort();
        for name in names {
            meshes.push(read_mesh(f, &format!("meshes/{name}"), &checked)?);
        }
        let sol = Solution { time: scalars.time, u, fields, lambda, j0 };
        Ok(Self { head: head.named(path, run), meshes, state: SimState { scalars, sol, u_prev, dynamics } })
    }

    /// The model at the checkpoint: `base` (the model of the case) with the meshes of the
    /// bodies that were re-meshed before it.
    ///
    /// # Errors
    /// [`CheckpointError::Mismatch`] when the bodies differ in number or a mesh cannot be set.
    pub fn model(&self, base: Model) -> Result<Model, CheckpointError> {
        let mismatch = |reason: String| CheckpointError::Mismatch { path: self.path.clone(), reason };
        if self.meshes.len() != base.bodies.len() {
            return Err(mismatch(format!("{} bodies in the checkpoint, {} in the case", self.meshes.len(), base.bodies.len())));
        }
        let mut model = base;
        for (b, mesh) in self.meshes.iter().enumerate() {
            if !same_mesh(&model.bodies[b].mesh, mesh) {
                tracing::debug!(body = b, elements = mesh.n_elements(), "restart: the body has its re-meshed mesh");
                model = model.with_body_mesh(b, mesh.clone()).map_err(|e| mismatch(e.to_string()))?;
            }
        }
        Ok(model)
    }

    /// The simulation at the checkpoint, on the model of the case `base` ([`Checkpoint::model`])
    /// with the case's time and solver settings.
    ///
    /// # Errors
    /// [`CheckpointError::Mismatch`] when the checkpoint does not fit the model.
    pub fn restore(self, base: Model, time: TimeSpec, spec: SolverSpec) -> Result<Simulation, CheckpointError> {
        self.restore_with(base, time, spec, std::sync::Arc::new(crate::comm::Serial))
    }

    /// [`Checkpoint::restore`] on the processes `comm` (every rank reads the same global
    /// state; the rank count may differ from the one that wrote it).
    ///
    /// # Errors
    /// As [`Checkpoint::restore`].
    pub fn restore_with(self, base: Model, time: TimeSpec, spec: SolverSpec, comm: std::sync::Arc<dyn crate::comm::Collective>) -> Result<Simulation, CheckpointError> {
        let model = self.model(base)?;
        let path = self.path.clone();
        let mismatch = |reason: String| CheckpointError::Mismatch { path: path.clone(), reason };
        let mut sim = Simulation::new_for_state(model, time, spec, comm).map_err(|e| mismatch(e.to_string()))?;
        sim.set_state(self.state).map_err(mismatch)?;
        Ok(sim)
    }
}

/// A checkpoint opened for reading in pieces: its header, solver scalars and the caller's
/// record are read, the file's seal checked; the meshes and the arrays are read only where
/// asked ([`CheckpointFile::mesh`], and by rows through [`WholeRows`]), so that a process of a
/// run on parts reads its own bodies and rows and never holds the whole state
/// ([`crate::case::parts`]). [`CheckpointFile::read`] reads all of it (a serial run or a
/// replicated model).
pub struct CheckpointFile {
    pub head: CheckpointHead,
    /// The solver's scalars (counters, contact histories, the barrier's ties: whole-model
    /// numbering).
    pub scalars: SimScalars,
    /// Each body's group under `meshes/`, in body order.
    bodies: Vec<String>,
    file: hdf5::File,
}

impl std::fmt::Debug for CheckpointFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CheckpointFile").field("path", &self.path).field("step", &self.step).field("time", &self.time).field("bodies", &self.bodies.len()).finish_non_exhaustive()
    }
}

/// Values read at once from one array of a checkpoint (8 MB of doubles).
const ROW_BLOCK_VALUES: usize = 1 << 20;

impl CheckpointFile {
    /// Open the checkpoint at `path` (a file, or a directory holding `checkpoint.h5`): the
    /// whole file against its seal, the header, the scalars and the caller's record.
    ///
    /// # Errors
    /// As [`Checkpoint::read`].
    pub fn open(path: &Path) -> Result<Self, CheckpointError> {
        let path = file_of(path);
        if !path.is_file() {
            return Err(CheckpointError::Missing { path });
        }
        let corrupt = |reason: String| CheckpointError::Corrupt { path: path.clone(), reason };
        let sealed = check_seal(&path).map_err(corrupt)?;
        let file = crate::h5::open(&path).map_err(|e| corrupt(e.to_string()))?;
        let head = Header::read(&file, &path).map_err(corrupt)?;
        if head.version >= 2 && !sealed {
            return Err(corrupt("no whole-file checksum at its start (a format 2 checkpoint carries one): the file was changed after it was written".into()));
        }
        let scalars: SimScalars = ciborium::from_reader(head.bytes(&file, "scalars").map_err(corrupt)?.as_slice()).map_err(|err| corrupt(format!("scalars: {err}")))?;
        let run = head.bytes(&file, "run").map_err(corrupt)?;
        let mut bodies = file.group("meshes").and_then(|g| g.member_names()).map_err(|err| corrupt(format!("meshes: {err}")))?;
        bodies.sort();
        Ok(Self { head: head.named(&path, run), scalars, bodies, file })
    }

    /// All of the checkpoint (each dataset checked against its checksum).
    ///
    /// # Errors
    /// As [`Checkpoint::read`].
    pub fn read(&self) -> Result<Checkpoint, CheckpointError> {
        Checkpoint::read_h5(&self.file, &self.path).map_err(|reason| CheckpointError::Corrupt { path: self.path.clone(), reason })
    }

    /// How many bodies the checkpoint has meshes of.
    pub fn n_bodies(&self) -> usize {
        self.bodies.len()
    }

    /// Body `b`'s mesh at the checkpoint (its node numbers checked against its node count).
    ///
    /// # Errors
    /// [`CheckpointError::Corrupt`] when there is no such body or its mesh cannot be read.
    pub fn mesh(&self, b: usize) -> Result<Mesh, CheckpointError> {
        let corrupt = |reason: String| CheckpointError::Corrupt { path: self.path.clone(), reason };
        let name = self.bodies.get(b).ok_or_else(|| corrupt(format!("body {b}: the checkpoint has meshes of {} bodies", self.bodies.len())))?;
        // (the bytes were checked against the file's seal; a version 1 file has no checksums)
        read_mesh(&self.file, &format!("meshes/{name}"), &|_: &str, _: &hdf5::Dataset, _: String| Ok(())).map_err(corrupt)
    }
}

impl std::ops::Deref for CheckpointFile {
    type Target = CheckpointHead;
    fn deref(&self) -> &CheckpointHead {
        &self.head
    }
}

impl WholeRows for CheckpointFile {
    fn values(&self, name: &str) -> Option<usize> {
        let d = self.file.dataset(name).ok()?;
        Some(d.shape().iter().product())
    }

    /// Read in blocks of at most [`ROW_BLOCK_VALUES`] values, each spanning requested rows
    /// only (what lies between them in a block is read and dropped).
    fn rows(&self, name: &str, width: usize, rows: &[usize]) -> Result<Vec<f64>, String> {
        use hdf5::{Hyperslab, SliceOrIndex};
        let e = |err: hdf5::Error| format!("{name}: {err}");
        let d = self.file.dataset(name).map_err(e)?;
        let shape = d.shape();
        let total: usize = shape.iter().product();
        let inner: usize = shape.iter().skip(1).product();
        if width == 0 {
            return Ok(Vec::new());
        }
        if shape.is_empty() || inner == 0 || width % inner != 0 || total % width != 0 {
            return Err(format!("{name}: an array of shape {shape:?} is not read by rows of {width} values"));
        }
        let (n, k) = (total / width, width / inner);
        if let Some(&r) = rows.iter().find(|&&r| r >= n) {
            return Err(format!("{name}: row {r} of {n} rows"));
        }
        let mut order: Vec<usize> = (0..rows.len()).collect();
        order.sort_by_key(|&i| rows[i]);
        let per_block = (ROW_BLOCK_VALUES / width).max(1);
        let mut out = vec![0.0; width * rows.len()];
        let mut at = 0;
        while at < order.len() {
            let lo = rows[order[at]];
            let mut end = at;
            while end < order.len() && rows[order[end]] < lo + per_block {
                end += 1;
            }
            let hi = rows[order[end - 1]] + 1;
            let mut slab = vec![SliceOrIndex::from(lo * k..hi * k)];
            slab.extend((1..shape.len()).map(|_| SliceOrIndex::from(..)));
            let block: Vec<f64> = d.read_slice::<f64, _, ndarray::IxDyn>(Hyperslab::from(slab)).map_err(e)?.iter().copied().collect();
            for &i in &order[at..end] {
                let r = rows[i] - lo;
                out[width * i..width * (i + 1)].copy_from_slice(&block[width * r..width * (r + 1)]);
            }
            at = end;
        }
        Ok(out)
    }
}

/// The root attributes of a checkpoint, checked against their checksum (version 2 on).
struct Header {
    version: u32,
    mpfem_version: String,
    case_sha256: String,
    step: u64,
    time: f64,
}

const CHANGED: &str = "checksum mismatch: the file was changed or damaged after it was written";

impl Header {
    fn read(f: &hdf5::File, path: &Path) -> Result<Self, String> {
        use hdf5::types::VarLenUnicode;
        let version: u32 = f.attr("format_version").and_then(|a| a.read_scalar()).map_err(e("format_version"))?;
        if !(OLDEST_VERSION..=FORMAT_VERSION).contains(&version) {
            return Err(format!("format version {version}; this mpfem reads versions {OLDEST_VERSION} to {FORMAT_VERSION}"));
        }
        if version < 2 {
            tracing::warn!(path = %path.display(), version, "an old checkpoint without checksums: its contents cannot be verified");
        }
        let string = |name: &str| -> Result<String, String> { f.attr(name).and_then(|a| a.read_scalar::<VarLenUnicode>()).map(|s| s.as_str().to_string()).map_err(e(name)) };
        let mpfem_version = string("mpfem_version")?;
        let case_sha256 = string("case_sha256")?;
        let step: u64 = f.attr("step").and_then(|a| a.read_scalar()).map_err(e("step"))?;
        let time: f64 = f.attr("time").and_then(|a| a.read_scalar()).map_err(e("time"))?;
        if version >= 2 && string("header_sha256")? != header_digest(version, &mpfem_version, &case_sha256, step, time) {
            return Err(format!("the root attributes (format_version, mpfem_version, case_sha256, step, time): {CHANGED}"));
        }
        if !time.is_finite() || time < 0.0 {
            return Err(format!("time: {time}; expected a finite time ≥ 0"));
        }
        Ok(Self { version, mpfem_version, case_sha256, step, time })
    }

    /// The head of the checkpoint at `path` with this header and the caller's record `run`.
    fn named(self, path: &Path, run: Vec<u8>) -> CheckpointHead {
        CheckpointHead { path: path.to_path_buf(), format_version: self.version, mpfem_version: self.mpfem_version, case_sha256: self.case_sha256, step: self.step as usize, time: self.time, run }
    }

    /// A dataset's values checked against its checksum (version 2 on).
    fn checked(&self, name: &str, d: &hdf5::Dataset, actual: String) -> Result<(), String> {
        use hdf5::types::VarLenUnicode;
        if self.version < 2 {
            return Ok(());
        }
        let stored = d.attr("sha256").and_then(|a| a.read_scalar::<VarLenUnicode>()).map_err(|err| format!("{name}: no checksum ({err})"))?;
        if stored.as_str() == actual {
            Ok(())
        } else {
            Err(format!("{name}: {CHANGED}"))
        }
    }

    fn bytes(&self, f: &hdf5::File, name: &str) -> Result<Vec<u8>, String> {
        let d = f.dataset(name).map_err(e(name))?;
        let v = d.read_raw::<u8>().map_err(e(name))?;
        self.checked(name, &d, digest_u8(&v))?;
        Ok(v)
    }
}

fn e(what: &str) -> impl Fn(hdf5::Error) -> String + '_ {
    move |err| format!("{what}: {err}")
}

/// The mesh of group `p` (`meshes/NNNNNN`), each dataset passed to `checked` with its
/// values' checksum; its node numbers checked against its node count and its coordinates
/// finite (nothing later indexes out of it).
fn read_mesh(f: &hdf5::File, p: &str, checked: &dyn Fn(&str, &hdf5::Dataset, String) -> Result<(), String>) -> Result<Mesh, String> {
    let f64s = |name: &str| -> Result<Vec<f64>, String> {
        let d = f.dataset(name).map_err(e(name))?;
        let v = d.read_raw::<f64>().map_err(e(name))?;
        checked(name, &d, digest_f64(&v))?;
        Ok(v)
    };
    let u64s = |name: &str| -> Result<Vec<u64>, String> {
        let d = f.dataset(name).map_err(e(name))?;
        let v = d.read_raw::<u64>().map_err(e(name))?;
        checked(name, &d, digest_u64(&v))?;
        Ok(v)
    };
    let nodes = f64s(&format!("{p}/nodes"))?;
    if nodes.len() % 2 != 0 {
        return Err(format!("{p}/nodes: odd number of coordinates"));
    }
    let mut edge_sets = BTreeMap::new();
    let sets = f.group(&format!("{p}/edge_sets")).map_err(e(p))?;
    for s in sets.member_names().map_err(e(p))? {
        edge_sets.insert(s.clone(), pairs::<2>(u64s(&format!("{p}/edge_sets/{s}"))?, &s)?);
    }
    let mesh = Mesh {
        nodes: nodes.chunks_exact(2).map(|c| [c[0], c[1]]).collect(),
        elements: pairs::<4>(u64s(&format!("{p}/elements"))?, p)?,
        boundary: pairs::<2>(u64s(&format!("{p}/boundary"))?, p)?,
        edge_sets,
    };
    let n = mesh.nodes.len();
    if let Some(k) = mesh.nodes.iter().position(|q| !q[0].is_finite() || !q[1].is_finite()) {
        return Err(format!("{p}/nodes: node {k} has coordinates {:?}", mesh.nodes[k]));
    }
    let bad = |what: &str, list: &[usize]| list.iter().find(|&&v| v >= n).map(|v| format!("{p}/{what}: node {v} of a mesh of {n} nodes"));
    if let Some(m) = bad("elements", mesh.elements.as_flattened()) {
        return Err(m);
    }
    if let Some(m) = bad("boundary", mesh.boundary.as_flattened()) {
        return Err(m);
    }
    for (s, edges) in &mesh.edge_sets {
        if let Some(m) = bad(&format!("edge_sets/{s}"), edges.as_flattened()) {
            return Err(m);
        }
    }
    Ok(mesh)
}

/// Whether two meshes are the same, bit for bit.
pub fn same_mesh(a: &Mesh, b: &Mesh) -> bool {
    a.nodes.len() == b.nodes.len()
        && a.nodes.iter().zip(&b.nodes).all(|(p, q)| p[0].to_bits() == q[0].to_bits() && p[1].to_bits() == q[1].to_bits())
        && a.elements == b.elements
        && a.boundary == b.boundary
}
