//! Running a case from start to end (or on from a checkpoint): what `mpfem run` does, as a
//! library call a test can make.
//!
//! [`run`] reads the checkpoint to continue from and refuses a case that is not the one it was
//! written with (its SHA-256 differs) unless told to go on; splits the work over the MPI ranks
//! (rank 0 writes, the others solve along); writes `history.csv`, `results.h5`/`.xdmf`, a
//! checkpoint every `[output] checkpoint_every` steps, every `checkpoint_minutes` and after the
//! step in which the stop flag was set; fits the pressure–density curve; writes
//! `summary.json`; draws the plots. It returns a [`RunOutcome`] (completed, interrupted with or
//! without a checkpoint, failed, bad input) and never prints: every line for the user goes to a
//! [`Reporter`] the caller implements (the binary prints them, a progress bar on a terminal).
//!
//! ```text
//!  Case ─► checkpoint? ─► Model ─► Simulation ──step──► history, results, checkpoint ─► summary ─► plots
//!                                               │
//!                                               └─► Reporter::step (progress), stop flag read
//! ```

use crate::case::Case;
use crate::checkpoint::CheckpointFile;
use crate::fits::CurvePoint;
use crate::model::Model;
use crate::output::{write_summary, FinalState, HistoryWriter, Phases, ProbeWriter, SummaryFile};
use crate::comm::Collective;
use crate::plot::{PlotReport, PlotRequest};
use crate::results::{ResultsError, ResultsWriter};
use crate::solver::{RunSummary, SimState, Simulation, SolveError, StepReport};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use thiserror::Error;

/// What kind of line a [`Reporter::note`] is (the binary prefixes `mpfem: `, `warning: `,
/// `error: `).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Note {
    /// What the run does or did: its start, a restart, a checkpoint, how it ended.
    Info,
    /// Something went wrong that does not stop the run (a checkpoint or a plot not written).
    Warning,
    /// Why the run did not start or did not finish.
    Error,
}

/// Where a run's lines for the user go. Called on rank 0 only (the other ranks are silent),
/// from the study's worker threads at once (hence `Sync`).
pub trait Reporter: Sync {
    /// One line for the user, without its prefix and newline.
    fn note(&self, kind: Note, text: &str);
    /// The time steps begin (after the start line); not called for a quiet run.
    fn steps_begin(&self) {}
    /// After every converged step, before the stop flag is read (so a flag set here stops the
    /// run after this step); not called for a quiet run.
    fn step(&self, _progress: &Progress) {}
    /// The time steps are over (before the closing lines); not called for a quiet run.
    fn steps_end(&self) {}
}

/// A reporter that drops everything.
pub struct Silent;

impl Reporter for Silent {
    fn note(&self, _kind: Note, _text: &str) {}
}

/// How far a run is after a converged step ([`Reporter::step`]).
#[derive(Clone, Copy, Debug)]
pub struct Progress<'a> {
    pub report: &'a StepReport,
    /// The fraction of the run done, in [0, 1] ([`progress`]).
    pub done: f64,
    /// The solid ratio now and the one the run stops at (`[stop] solid_ratio`), if any.
    pub solid_ratio: Option<f64>,
    pub target: Option<f64>,
    /// Wall-clock seconds since this process started the run.
    pub elapsed_s: f64,
}

impl Progress<'_> {
    /// `solid ratio 0.8123 → 0.95 | t 1.2000e-1 s | step 12 | dt 1.00e-2 | 4 it`.
    pub fn line(&self) -> String {
        let r = self.report;
        let density = match (self.solid_ratio, self.target) {
            (Some(p), Some(t)) => format!("solid ratio {p:.4} → {t} | "),
            (Some(p), None) => format!("solid ratio {p:.4} | "),
            _ => String::new(),
        };
        format!("{density}t {} s | step {} | dt {} s | {} it", seconds(r.time), r.step, seconds(r.dt), r.newton_iterations)
    }
}

/// How a run is controlled from outside its case.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Output folder for history.csv, summary.json, results.h5, results.xdmf, checkpoint.h5.
    pub out: PathBuf,
    /// Threads for the assembly (overrides `[solver] threads`; 0 = all cores; the sparse direct
    /// factorisations run on one).
    pub threads: Option<usize>,
    /// No progress: [`Reporter::steps_begin`], [`Reporter::step`], [`Reporter::steps_end`]
    /// are not called (the other lines are).
    pub quiet: bool,
    /// Draw the plots at the end (pressure.png/.svg, snapshot_step_N.png).
    pub plots: bool,
    /// Continue from the checkpoint in this folder (its checkpoint.h5, or the file itself).
    pub restart: Option<PathBuf>,
    /// Restart even when the case is not the one the checkpoint was written with.
    pub allow_case_change: bool,
    /// Read after every step: non-zero (the binary stores the number of the signal received)
    /// writes a checkpoint and stops the run ("interrupted by SIGTERM").
    pub stop: Option<Arc<AtomicUsize>>,
}

impl RunOptions {
    /// Into `out`, with plots, progress, no restart, no stop flag.
    pub fn new(out: impl Into<PathBuf>) -> Self {
        Self { out: out.into(), threads: None, quiet: false, plots: true, restart: None, allow_case_change: false, stop: None }
    }
}

/// How a run ended (the binary's exit code: [`RunOutcome::exit_code`]).
#[derive(Debug)]
pub enum RunOutcome {
    /// It reached its end (end time, target solid ratio, jammed): exit code 0.
    Completed(RunSummary),
    /// The stop flag stopped it after a step. `checkpoint`: that step's checkpoint was written
    /// and `--restart` continues the run (exit code 3), or it could not be (exit code 1). (On
    /// ranks other than 0, which write nothing, always true.)
    Interrupted { summary: RunSummary, checkpoint: bool },
    /// A step could not be solved; the results up to the last converged step are written
    /// (exit code 1).
    Failed(SolveError),
    /// An output file could not be written (a full disk, a folder gone or read-only): the run
    /// stopped after the step whose output failed, every row and step written before it
    /// readable (exit code 1). The text names the file and the cause.
    OutputFailed { summary: RunSummary, error: String },
    /// The case, the checkpoint or the two together are not usable; nothing was run (exit code
    /// 2). The text is the one reported.
    BadInput(String),
}

impl RunOutcome {
    /// 0 completed, 1 failed (or interrupted without its checkpoint), 2 bad input, 3
    /// interrupted with a checkpoint.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Completed(_) => 0,
            Self::Interrupted { checkpoint: true, .. } => 3,
            Self::Interrupted { checkpoint: false, .. } | Self::Failed(_) | Self::OutputFailed { .. } => 1,
            Self::BadInput(_) => 2,
        }
    }
}

/// The output could not be written (or the simulation not set up): the run stops at once.
/// With MPI, on rank 0 alone (the caller ends the other ranks).
#[derive(Debug, Error)]
pub enum RunError {
    #[error("cannot create output directory {}", dir.display())]
    OutputDir {
        dir: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot copy {} into {}", file.display(), to.display())]
    CopyRunFile {
        file: PathBuf,
        to: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot {} {}/history.csv", if *continued { "continue" } else { "write" }, dir.display())]
    History {
        dir: PathBuf,
        continued: bool,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot {} {}/probes.csv", if *continued { "continue" } else { "write" }, dir.display())]
    Probes {
        dir: PathBuf,
        continued: bool,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot {} the results in {}", if *continued { "continue" } else { "write" }, dir.display())]
    Results {
        dir: PathBuf,
        continued: bool,
        #[source]
        source: ResultsError,
    },
    #[error("cannot write {}/summary.json", dir.display())]
    Summary {
        dir: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Solver(#[from] SolveError),
}

/// An error and its causes on one line, `error: cause: cause of the cause`.
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text += &format!(": {c}");
        cause = c.source();
    }
    text
}

/// What `mpfem check` tells of a case without running it: the size of its model and the
/// quality of its meshes (over every body).
#[derive(Clone, Debug)]
pub struct CaseCheck {
    pub n_nodes: usize,
    pub n_elements: usize,
    pub n_prescribed: usize,
    pub n_loads: usize,
    /// Smallest scaled Jacobian of any element (≤ 0: inverted).
    pub min_scaled_jacobian: f64,
    /// Largest longest-over-shortest edge ratio of any element.
    pub max_aspect_ratio: f64,
    pub n_inverted: usize,
    /// The bodies with inverted elements: (index in `bodies`, name, how many).
    pub inverted_bodies: Vec<(usize, String, usize)>,
    /// The particles beyond a wall at the start ([`Model::outside_walls`]): one message each.
    pub outside_walls: Vec<String>,
    /// What the model may run into without being wrong ([`model_warnings`]): one message each.
    pub warnings: Vec<String>,
}

/// Above this many elements `check` and `run` warn that the run is large (hours a step on one
/// core, gigabytes of memory: `docs/scaling/` has the measured rates).
pub const LARGE_MODEL_ELEMENTS: usize = 500_000;

/// Below this smallest scaled Jacobian of a particle's mesh `check` and `run` warn (1 is a
/// square; the re-mesher's default limit is 0.2): so distorted an element stiffens, locks or
/// inverts early.
pub const POOR_SCALED_JACOBIAN: f64 = 0.1;

/// The warnings of a model that is valid but may not be what was meant: more than
/// [`LARGE_MODEL_ELEMENTS`] elements, or a particle whose mesh has an element of scaled Jacobian
/// below [`POOR_SCALED_JACOBIAN`] (not inverted: that is an error). Each names the keys to change.
pub fn model_warnings(m: &Model) -> Vec<String> {
    size_and_mesh_warnings(m.elements.len(), m.poor_meshes(POOR_SCALED_JACOBIAN).into_iter().map(|(i, q)| (i, m.bodies[i].name.clone(), q)))
}

/// [`model_warnings`] of a model of `n_elements` elements whose bodies `poor` (index, name,
/// smallest scaled Jacobian, [`Model::poor_meshes`]) are poorly meshed.
fn size_and_mesh_warnings(n_elements: usize, poor: impl Iterator<Item = (usize, String, f64)>) -> Vec<String> {
    let mut w = Vec::new();
    if n_elements > LARGE_MODEL_ELEMENTS {
        w.push(format!("the model has {n_elements} elements (more than {LARGE_MODEL_ELEMENTS}): expect hours a step on one core and gigabytes of memory; a coarser mesh_size (or fewer divisions) makes it smaller"));
    }
    for (i, name, q) in poor {
        w.push(format!("bodies[{i}] (\"{name}\"): its mesh has an element of scaled Jacobian {q:.3} (below {POOR_SCALED_JACOBIAN}), which stiffens, locks or inverts early; a smaller mesh_size or other divisions mesh it better"));
    }
    w
}

/// Build the model of case `c` and measure its meshes ([`crate::mesh::quality::quality`]).
///
/// # Errors
/// The model's error when the case does not make one.
pub fn check(c: &Case) -> Result<CaseCheck, crate::model::ModelError> {
    let m = Model::from_case(c)?;
    let mut k = CaseCheck {
        n_nodes: m.n_nodes(),
        n_elements: m.elements.len(),
        n_prescribed: m.loading.prescribed.len(),
        n_loads: m.loading.loads.len(),
        min_scaled_jacobian: f64::INFINITY,
        max_aspect_ratio: 0.0,
        n_inverted: 0,
        inverted_bodies: Vec::new(),
        outside_walls: m.outside_walls(),
        warnings: model_warnings(&m),
    };
    for (i, b) in m.bodies.iter().enumerate() {
        let q = crate::mesh::quality::quality(&b.mesh, &b.mesh.nodes);
        k.min_scaled_jacobian = k.min_scaled_jacobian.min(q.min_scaled_jacobian);
        k.max_aspect_ratio = k.max_aspect_ratio.max(q.max_aspect_ratio);
        k.n_inverted += q.n_inverted;
        if q.n_inverted > 0 {
            k.inverted_bodies.push((i, b.name.clone(), q.n_inverted));
        }
    }
    Ok(k)
}

/// Which case file a run used: its path and the SHA-256 of its text (the version of the case
/// that produced the results), for `summary.json` and the checkpoint.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CaseFile {
    pub path: String,
    pub sha256: String,
}

impl CaseFile {
    /// `path` and the SHA-256 of its bytes (empty when it cannot be read).
    pub fn describe(path: &Path) -> Self {
        use sha2::Digest;
        let sha256 = std::fs::read(path)
            .map(|b| sha2::Sha256::digest(&b).iter().map(|x| format!("{x:02x}")).collect())
            .unwrap_or_default();
        Self { path: path.display().to_string(), sha256 }
    }
}

/// The SHA-256 a checkpoint records for the case (the built-in default job has no file).
pub fn case_hash(case_file: Option<&CaseFile>) -> String {
    case_file.map_or_else(|| format!("built-in default job of mpfem {}", env!("CARGO_PKG_VERSION")), |c| c.sha256.clone())
}

/// The run's own state kept in a checkpoint (what the summary needs besides the solver).
/// Serialised by field name: the names are those of the checkpoints written before (as the
/// binary's `CliState`), which must still restart.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct RunState {
    pub phi0: Option<f64>,
    pub max_body_volume_error: f64,
    pub curve: Vec<CurvePoint>,
    /// Wall-clock time of the run so far (s), over its restarts.
    pub wall_time_s: f64,
    /// Time spent writing history.csv so far (s).
    pub history_s: f64,
    /// The checkpoints the run was continued from (for summary.json).
    pub restarts: Vec<serde_json::Value>,
}

/// How far a run is, in [0, 1]: the larger of the time fraction and, with a target solid
/// ratio, the fraction of the way from the initial to the target solid ratio
/// (`solid = (φ₀, φ, φ_target)`).
pub fn progress(time: f64, t_end: f64, solid: Option<(f64, f64, f64)>) -> f64 {
    let by_time = if t_end > 0.0 { time / t_end } else { 0.0 };
    let by_density = match solid {
        Some((phi0, phi, target)) if target > phi0 => (phi - phi0) / (target - phi0),
        _ => 0.0,
    };
    by_time.max(by_density).clamp(0.0, 1.0)
}

/// Copy the files a restarted run continues (history.csv, probes.csv, results.h5) from the checkpoint's
/// folder into another output folder (nothing when they are the same folder).
pub fn copy_run_files(from: &Path, to: &Path) -> Result<(), RunError> {
    let same = match (from.canonicalize(), to.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if same {
        return Ok(());
    }
    for name in ["history.csv", "probes.csv", "results.h5"] {
        let (src, dst) = (from.join(name), to.join(name));
        // (never a file onto itself, which would empty it)
        let same_file = matches!((src.canonicalize(), dst.canonicalize()), (Ok(a), Ok(b)) if a == b);
        if src.is_file() && !same_file {
            std::fs::copy(&src, &dst).map_err(|source| RunError::CopyRunFile { file: src.clone(), to: to.to_path_buf(), source })?;
        }
    }
    Ok(())
}

/// Write the checkpoint of `state` on `model`, whose last converged step is `at` (step,
/// time), and say so: false when it could not be written (a warning says why; the previous
/// one stays).
fn checkpoint_now(out: &Path, model: &Model, sim: &SimState, sha: &str, state: &RunState, at: (usize, f64), reporter: &dyn Reporter) -> bool {
    match crate::checkpoint::write_state(out, model, sim, sha, state) {
        Ok(p) => {
            reporter.note(Note::Info, &format!("checkpoint at step {}, t = {} s: {}", at.0, seconds(at.1), p.display()));
            true
        }
        Err(e) => {
            reporter.note(Note::Warning, &e.to_string());
            false
        }
    }
}

/// The name of the signal whose number the stop flag holds.
fn signal_name(sig: usize) -> String {
    match sig as i32 {
        signal_hook::consts::SIGTERM => "SIGTERM".into(),
        signal_hook::consts::SIGINT => "SIGINT".into(),
        s => format!("signal {s}"),
    }
}

/// Report `text` as an error (on rank 0) and return it as [`RunOutcome::BadInput`].
/// A time for a message: nine decimals at most, without trailing zeros (a step sum such as
/// 1.3450000000000002 reads 1.345).
pub fn seconds(t: f64) -> String {
    let s = format!("{t:.9}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.') } else { &s };
    if s == "-0" { "0".to_string() } else { s.to_string() }
}

/// Why an output folder could not be locked.
enum LockError {
    /// Another process holds it (the message names it).
    Busy(String),
    Io(RunError),
}

/// The advisory lock of the output folder `out` (created if needed): `out/.mpfem.lock`, locked
/// with the operating system's file lock (released when the process ends, however it ends, so
/// a killed run leaves no stale lock) and holding the process id and the start time for the
/// message a second run gets. On a file system without locks the run goes on with a warning.
fn lock_output(out: &Path) -> Result<Option<std::fs::File>, LockError> {
    use std::io::{Read, Seek, Write};
    std::fs::create_dir_all(out).map_err(|source| LockError::Io(RunError::OutputDir { dir: out.to_path_buf(), source }))?;
    let path = out.join(".mpfem.lock");
    let mut f = std::fs::OpenOptions::new().read(true).write(true).create(true).truncate(false).open(&path).map_err(|source| LockError::Io(RunError::OutputDir { dir: out.to_path_buf(), source }))?;
    match f.try_lock() {
        Ok(()) => {
            let stamp = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
            let _ = f.set_len(0).and_then(|_| f.rewind()).and_then(|_| writeln!(f, "pid {} started at unix time {stamp}", std::process::id())).and_then(|_| f.flush());
            Ok(Some(f))
        }
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut who = String::new();
            let _ = f.read_to_string(&mut who);
            let who = who.trim();
            Err(LockError::Busy(format!(
                "another mpfem run is writing into {} ({}); wait for it to end or choose another --out",
                out.display(),
                if who.is_empty() { "its process id is not recorded yet" } else { who }
            )))
        }
        Err(std::fs::TryLockError::Error(e)) => {
            tracing::warn!(path = %path.display(), %e, "cannot lock the output folder (no file locks on this file system?): two runs into it would mix their files");
            Ok(None)
        }
    }
}

fn bad_input(root: bool, reporter: &dyn Reporter, text: String) -> RunOutcome {
    if root {
        reporter.note(Note::Error, &text);
    }
    RunOutcome::BadInput(text)
}

/// The lines for a [`PlotReport`]'s pictures.
pub fn report_plots(r: &PlotReport, reporter: &dyn Reporter) {
    if r.written.is_empty() {
        reporter.note(Note::Info, "no plots written");
    } else {
        let names: Vec<String> = r.written.iter().map(|p| p.display().to_string()).collect();
        reporter.note(Note::Info, &format!("wrote plots {}", names.join(", ")));
    }
}

/// The plots at the end of a run, from whatever the run wrote; failures are warnings.
fn plots_after_run(out: &Path, reporter: &dyn Reporter) {
    let req = PlotRequest::of_folders(&[out.to_path_buf()], &[], None, None);
    match crate::plot::plot_results(&req) {
        Ok(r) => {
            for s in &r.skipped {
                reporter.note(Note::Info, s);
            }
            report_plots(&r, reporter)
        }
        Err(e) => reporter.note(Note::Warning, &format!("plots: {e} (the results are written; `mpfem plot {}` redraws them)", out.display())),
    }
}

/// Run case `c` into `opts.out` (or on from `opts.restart`), on every rank of `comm`.
///
/// `label` names the case in the lines reported (its path, or what it is); `case_file` is the
/// file it was read from (its SHA-256 goes into the checkpoints and summary.json; `None` for
/// the built-in default job). Rank 0 writes and reports; the other ranks solve along and stop
/// after the same step.
///
/// # Errors
/// [`RunError`] when the output cannot be written or the simulation not set up: nothing more
/// is written, and with MPI the other ranks are not told (the caller ends them).
pub fn run(mut c: Case, label: &str, case_file: Option<CaseFile>, opts: &RunOptions, comm: Arc<dyn Collective>, reporter: &dyn Reporter) -> Result<RunOutcome, RunError> {
    let out = opts.out.as_path();
    let root = comm.is_root();
    if let Some(t) = opts.threads {
        c.solver.threads = t;
    }
    if comm.size() > 1 && c.solver.threads == 0 {
        // "every core" is shared by the ranks of a node (rank 0's gathered factorisation stays
        // at its share: faer's sparse factorisations ran 1.4-1.5 times slower on 2 threads than
        // on 1 here, `cargo bench --bench solve -- solve_205k_threads`)
        let local = std::env::var("OMPI_COMM_WORLD_LOCAL_SIZE").or_else(|_| std::env::var("MPI_LOCALNRANKS")).ok().and_then(|v| v.parse::<usize>().ok()).unwrap_or(comm.size());
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        c.solver.threads = (cores / local.max(1)).max(1);
    }
    // the checkpoint to continue from, read before anything is written
    let checkpoint = match &opts.restart {
        None => None,
        Some(p) => match CheckpointFile::open(p) {
            Ok(ck) => Some(ck),
            Err(e) => return Ok(bad_input(root, reporter, format!("cannot restart: {e}"))),
        },
    };
    let sha = case_hash(case_file.as_ref());
    if let Some(ck) = &checkpoint {
        if ck.case_sha256 != sha {
            let case = case_file.as_ref().map_or_else(|| "the built-in default job".to_string(), |c| format!("the case file {}", c.path));
            if !opts.allow_case_change {
                let text = format!(
                    "cannot restart: {case} (sha256 {sha}) is not the one the checkpoint {} was written with (sha256 {}); pass --allow-case-change to restart anyway",
                    ck.path.display(),
                    ck.case_sha256
                );
                return Ok(bad_input(root, reporter, text));
            }
            if root {
                let text = format!(
                    "{case} (sha256 {sha}) is not the one the checkpoint {} was written with (sha256 {}); restarting anyway (--allow-case-change)",
                    ck.path.display(),
                    ck.case_sha256
                );
                reporter.note(Note::Warning, &text);
            }
        }
    }
    // one run per output folder: rank 0 holds its lock for the whole run, and every rank
    // learns whether it got it (the others would otherwise wait for rank 0 in their solve)
    let lock = if root { Some(lock_output(out)) } else { None };
    let mut locked = [match &lock {
        Some(Err(_)) => 0.0,
        _ => 1.0,
    }];
    comm.broadcast(&mut locked);
    if locked[0] == 0.0 {
        let text = match lock {
            Some(Err(LockError::Busy(text))) => text,
            Some(Err(LockError::Io(e))) => return Err(e),
            _ => format!("another mpfem run is writing into {}", out.display()),
        };
        return Ok(bad_input(root, reporter, text));
    }
    // PETSc on every rank for the whole run, with the case's options (its solvers, in the
    // simulation, are dropped before it finalises)
    let _petsc = if c.solver.linear == crate::linalg::LinearChoice::Fixed(crate::linalg::LinearSolverKind::Petsc) {
        match crate::linalg::petsc::start(&c.petsc_options) {
            Ok(p) => Some(p),
            Err(e) => return Ok(bad_input(root, reporter, format!("solver.linear = \"petsc\": cannot start PETSc with solver.petsc_options = {:?}: {e}", c.petsc_options))),
        }
    } else {
        None
    };
    // with PETSc on several processes each holds its own particles and their neighbours
    // (owned + ghost parts, `Simulation::new_part`); a model a part does not take yet runs
    // replicated, every process holding all of it, as before. (Decided on the case's bodies
    // without their meshes: a fresh run on parts never builds the whole model, `case::parts`.)
    let mut parts = false;
    if _petsc.is_some() && comm.size() > 1 {
        let refusal = match c.bodies.len() < comm.size() {
            true => Some("fewer bodies than processes"),
            false => Model::from_case_holding(&c, Some(&[]), &[]).map_or(Some("a case whose model cannot be made"), |skeleton| Simulation::part_refusal(&skeleton)),
        };
        match refusal {
            None => parts = true,
            Some(what) if root => reporter.note(Note::Info, &format!("every MPI rank holds the whole model: a distributed part does not take {what} yet")),
            Some(_) => {}
        }
    }
    if !root {
        return match parts {
            true => run_part_rank(&c, comm, checkpoint),
            false => run_rank(&c, comm, checkpoint),
        };
    }
    // (held until the run returns)
    let _lock = lock;
    let formulation = format!("{:?}", c.formulation);
    let n_bodies = c.bodies.len();
    let title = c.title.clone();
    let started = Instant::now();
    let ranks = comm.size();
    let whole_model = || Model::from_case(&c).map_err(|e| format!("{label}: {e}"));
    // (on parts, rank 0 holds the model of the bodies it needs for the output until the
    // output files are made — the whole model on a restart —; then only its frame, into which
    // the meshes are gathered at the output steps. `part_reach`: the ghosts' reach of the
    // parts, kept to grow them again)
    let (mut sim, resumed, mut whole, part_reach) = match checkpoint {
        None if parts => match part_start(&c, &comm, None) {
            Ok(FreshPart { sim, held, reach, poor }) => {
                for w in size_and_mesh_warnings(sim.model.whole_facts().n_elements, poor.into_iter()) {
                    reporter.note(Note::Warning, &format!("{label}: {w}"));
                }
                (sim, None, held, Some(reach))
            }
            Err(e) => return Ok(bad_input(true, reporter, e.message(label))),
        },
        None => {
            let model = match whole_model() {
                Ok(m) => m,
                Err(e) => return Ok(bad_input(true, reporter, e)),
            };
            // a particle beyond a wall at the start would be pushed through it or lost (a
            // fresh run; a restart continues the checkpoint's configuration)
            if let Some(m) = model.outside_walls().into_iter().next() {
                return Ok(bad_input(true, reporter, format!("{label}: {m}")));
            }
            for w in model_warnings(&model) {
                reporter.note(Note::Warning, &format!("{label}: {w}"));
            }
            (Simulation::new_with(model, c.time, c.solver, Arc::clone(&comm))?, None, None, None)
        }
        Some(ck) => {
            let (step, time, path) = (ck.step, ck.time, ck.path.clone());
            let state: RunState = match ck.run_state() {
                Ok(s) => s,
                Err(e) => return Ok(bad_input(true, reporter, format!("cannot restart: {e}"))),
            };
            let from = match path.parent() {
                Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
                _ => PathBuf::from("."),
            };
            // (on parts each process reads its own of the checkpoint; otherwise all of it, onto
            // the whole model)
            let (sim, whole, reach) = if parts {
                match part_start(&c, &comm, Some(&ck)) {
                    Ok(FreshPart { sim, held, reach, .. }) => (sim, held, Some(reach)),
                    Err(e) => return Ok(bad_input(true, reporter, e.message(label))),
                }
            } else {
                let model = match whole_model() {
                    Ok(m) => m,
                    Err(e) => return Ok(bad_input(true, reporter, e)),
                };
                match ck.read().and_then(|ck| ck.restore_with(model, c.time, c.solver, Arc::clone(&comm))) {
                    Ok(sim) => (sim, None, None),
                    Err(e) => return Ok(bad_input(true, reporter, format!("cannot restart: {e}"))),
                }
            };
            copy_run_files(&from, out)?;
            reporter.note(Note::Info, &format!("restarting from {} at step {step}, t = {} s", path.display(), seconds(time)));
            (sim, Some((step, time, path, state)), whole, reach)
        }
    };
    // the model the output is written on: the whole one (a part's is its process's share)
    let shown = whole.as_ref().unwrap_or(&sim.model);
    let columns = crate::output::history_columns(shown);
    let every = c.output.every;
    // (the space of the final summary, held from the start)
    crate::output::reserve_summary(out, &title).map_err(|source| RunError::Summary { dir: out.to_path_buf(), source })?;
    let (mut history, mut results) = match &resumed {
        None => (
            HistoryWriter::create(out, shown).map_err(|source| RunError::History { dir: out.to_path_buf(), continued: false, source })?,
            match every {
                0 => None,
                every => Some(ResultsWriter::create(out, every, &columns).map_err(|source| RunError::Results { dir: out.to_path_buf(), continued: false, source })?),
            },
        ),
        Some((step, ..)) => (
            HistoryWriter::open_append(out, shown, *step).map_err(|source| RunError::History { dir: out.to_path_buf(), continued: true, source })?,
            match every {
                0 => None,
                every => Some(ResultsWriter::open_append(out, every, &columns, *step).map_err(|source| RunError::Results { dir: out.to_path_buf(), continued: true, source })?),
            },
        ),
    };
    // (the history's path, and the probes' beside it, for the closing lines)
    let history_files = if shown.probes.is_empty() { history.path.display().to_string() } else { format!("{}, {}", history.path.display(), out.join("probes.csv").display()) };
    let mut probes = match &resumed {
        None => ProbeWriter::create(out, shown),
        Some((step, ..)) => ProbeWriter::open_append(out, shown, *step),
    }
    .map_err(|source| RunError::Probes { dir: out.to_path_buf(), continued: resumed.is_some(), source })?;
    // pictures of an earlier run in the same folder would not match the new results
    crate::plot::remove_old_plots(out);
    let on_ranks = match ranks {
        1 => String::new(),
        _ if parts => format!(", {ranks} MPI ranks (each its own particles and their neighbours, solve distributed)"),
        _ if sim.solves_distributed() => format!(", {ranks} MPI ranks (solve distributed)"),
        _ => format!(", {ranks} MPI ranks (solve on rank 0)"),
    };
    let start = format!(
        "{label}: \"{title}\" — {n_bodies} body(ies), {} elements, {} free dofs, linear solver {}{on_ranks}, end time {} s",
        sim.model.whole_facts().n_elements,
        sim.n_free_whole(),
        sim.linear_solver_name(),
        c.time.end
    );
    reporter.note(Note::Info, &start);

    let t_end = c.time.end;
    let target = c.stop.solid_ratio;
    if !opts.quiet {
        reporter.steps_begin();
    }
    let mut earlier = RunState::default();
    if let Some((step, time, path, state)) = resumed {
        earlier = state;
        earlier.restarts.push(serde_json::json!({ "checkpoint": path.display().to_string(), "step": step, "time": time }));
    }
    let mut phi0: Option<f64> = earlier.phi0;
    let mut max_body_volume_error = earlier.max_body_volume_error;
    let mut history_s = earlier.history_s;
    let wall_before = earlier.wall_time_s;
    let restarts = earlier.restarts.clone();
    // the pressure–density curve for the compaction-law fits: the mean pressure of the moving
    // walls (of every loaded wall when none moves)
    let pressing = shown.loading.pressing_sides();
    let has_probes = !shown.probes.is_empty();
    // (on parts: the whole model without its meshes, for the output; no rank holds the whole
    // mesh from here on)
    let frame = whole.take().and_then(|w| w.frame());
    let mut curve: Vec<CurvePoint> = std::mem::take(&mut earlier.curve);
    // checkpoints: every `checkpoint_every` steps, every `checkpoint_minutes`, and after the
    // step in which the stop flag was set
    let ckpt_every = c.output.checkpoint_every;
    let ckpt_interval = (c.output.checkpoint_minutes > 0.0).then(|| Duration::try_from_secs_f64(60.0 * c.output.checkpoint_minutes).ok()).flatten();
    let mut last_ckpt = Instant::now();
    let mut ckpt_s = 0.0;
    // (step of the last checkpoint written, whether the last attempt failed)
    let mut ckpt_written: Option<usize> = None;
    let mut ckpt_failed = false;
    let mut io_error: Option<std::io::Error> = None;
    // (on parts: the gathered meshes did not make the whole model)
    let mut model_error: Option<String> = None;
    let mut results_error: Option<ResultsError> = None;
    // (the first output that could not be written: the run stops there)
    let mut output_failed: Option<String> = None;
    // (after a restart: the checkpoint's last step, so that a run restarted at its end still
    // writes its last step and final state)
    let mut last_report: Option<StepReport> = sim.last_report().cloned();
    // a signal abandons the step under way within one Newton iteration (every rank looks at
    // rank 0's flag there; without one, a flag nobody sets, so that all ranks check alike)
    let stop_flag = opts.stop.clone().unwrap_or_default();
    sim.set_interrupt(Arc::clone(&stop_flag));
    let run_started = Instant::now();
    let mut observer = |s: &Simulation, r: &StepReport| {
        last_report = Some(r.clone());
        max_body_volume_error = max_body_volume_error.max(r.volume_error_max_body);
        if let Some(c) = &r.compaction {
            let loaded: Vec<f64> = if pressing.is_empty() {
                c.pressure.iter().copied().filter(|p| *p > 0.0).collect()
            } else {
                pressing.iter().map(|&k| c.pressure[k]).collect()
            };
            if !loaded.is_empty() && c.solid_ratio > 0.0 {
                curve.push(CurvePoint { solid_ratio: c.solid_ratio, pressure: loaded.iter().sum::<f64>() / loaded.len() as f64 });
            }
        }
        let t_out = Instant::now();
        if let Err(e) = history.write(r) {
            io_error.get_or_insert(e);
        }
        // (a file removed under the run takes writes that go nowhere)
        if io_error.is_none() && !history.path.exists() {
            io_error = Some(std::io::Error::new(std::io::ErrorKind::NotFound, format!("{} was removed, or its folder", history.path.display())));
        }
        history_s += t_out.elapsed().as_secs_f64();
        let phi = r.compaction.as_ref().map(|c| c.solid_ratio);
        if phi0.is_none() {
            // the first step's solid ratio stands in for the initial one (the first
            // increment is small)
            phi0 = phi;
        }
        let solid = match (phi0, phi, target) {
            (Some(a), Some(b), Some(t)) => Some((a, b, t)),
            _ => None,
        };
        if !opts.quiet {
            let done = progress(r.time, t_end, solid);
            reporter.step(&Progress { report: r, done, solid_ratio: phi, target, elapsed_s: started.elapsed().as_secs_f64() });
        }
        // every rank stops after the same step, and checkpoints it together: rank 0's flags
        // decide (see `run_rank`, `run_part_rank`)
        let due = (ckpt_every > 0 && r.step % ckpt_every == 0) || ckpt_interval.is_some_and(|d| last_ckpt.elapsed() >= d);
        let (signal, due) = step_flags(&*comm, opts.stop.as_ref().map_or(0, |f| f.load(Ordering::SeqCst)), due);
        // a part's state gathered onto the whole model, when something is written from it
        let mut gathered = if parts && part_output_due(r.step, every, has_probes, signal, due) { s.gather(signal != 0 || due) } else { None };
        // (and the whole model of its bodies' meshes, for this step's writing only)
        let assembled = assemble_whole(&frame, gathered.as_mut()).map_err(|e| model_error.get_or_insert(e).clone()).ok().flatten();
        let snap = match (&gathered, &assembled) {
            (Some(g), Some(w)) => Some(g.snapshot(w)),
            _ if parts => None,
            _ => Some(s.snapshot()),
        };
        let t_out = Instant::now();
        if let (Some(p), Some(snap)) = (probes.as_mut(), &snap) {
            if let Err(e) = p.write(snap, r) {
                io_error.get_or_insert(e);
            }
        }
        history_s += t_out.elapsed().as_secs_f64();
        if let (Some(w), None) = (results.as_mut(), &results_error) {
            let written = match &snap {
                Some(snap) => w.observe(snap, r).map(|_| ()),
                None => w.append_history(r),
            };
            if let Err(e) = written {
                results_error = Some(e);
            }
        }
        if signal != 0 || due {
            let t0 = Instant::now();
            let state = RunState {
                phi0,
                max_body_volume_error,
                curve: curve.clone(),
                wall_time_s: wall_before + started.elapsed().as_secs_f64(),
                history_s,
                restarts: restarts.clone(),
            };
            ckpt_failed = !match (&gathered, &assembled) {
                // (gathered complete: a checkpoint was due)
                (Some(g), Some(w)) => checkpoint_now(out, w, &g.state, &sha, &state, (r.step, r.time), reporter),
                _ if parts => false,
                _ => checkpoint_now(out, &s.model, &s.state(), &sha, &state, (r.step, r.time), reporter),
            };
            if !ckpt_failed {
                ckpt_written = Some(r.step);
            }
            last_ckpt = Instant::now();
            ckpt_s += t0.elapsed().as_secs_f64();
        }
        // a failed write stops the run at once, every rank alike (rank 0's word)
        let failure = io_error
            .as_ref()
            .map(|e| format!("history.csv or probes.csv: {e}"))
            .or_else(|| model_error.clone())
            .or_else(|| results_error.as_ref().map(|e| format!("results: {e}")))
            .or_else(|| ckpt_failed.then(|| "checkpoint.h5 could not be written".to_string()));
        if step_flags(&*comm, usize::from(failure.is_some()), false).0 != 0 {
            let why = failure.unwrap_or_else(|| "an output file on rank 0".into());
            output_failed.get_or_insert_with(|| why.clone());
            return ControlFlow::Break(format!("output failed: {why}"));
        }
        if signal != 0 {
            return ControlFlow::Break(format!("interrupted by {}", signal_name(signal)));
        }
        ControlFlow::Continue(())
    };
    // (on parts: made again, and the run goes on, where the particles moved out of their ghosts)
    let mut remade = None;
    let mut result = loop {
        let mut segment = sim.run_controlled(&mut observer);
        if !go_on_with_new_parts(&mut sim, &mut segment, part_reach, &c, &stop_flag, &mut remade) {
            break segment;
        }
    };
    if let Ok(s) = result.as_mut() {
        s.wall_time_s = wall_before + run_started.elapsed().as_secs_f64();
        if s.interrupted && s.stop_reason == crate::solver::STOP_ABANDONED {
            // the signal came during a step, which was abandoned: the checkpoint of the last
            // converged state, which the observer did not see with the signal
            let signal = stop_flag.load(Ordering::SeqCst);
            s.stop_reason = format!("interrupted by {} (the step under way abandoned)", signal_name(signal));
            let t0 = Instant::now();
            let state = RunState { phi0, max_body_volume_error, curve: curve.clone(), wall_time_s: wall_before + started.elapsed().as_secs_f64(), history_s, restarts: restarts.clone() };
            let mut gathered = parts.then(|| sim.gather(true)).flatten();
            ckpt_failed = !match (assemble_whole(&frame, gathered.as_mut()), &gathered) {
                (Ok(Some(w)), Some(g)) => checkpoint_now(out, &w, &g.state, &sha, &state, (s.steps, s.final_time), reporter),
                (Err(e), _) => {
                    reporter.note(Note::Warning, &e);
                    false
                }
                _ if parts => false,
                _ => checkpoint_now(out, &sim.model, &sim.state(), &sha, &state, (s.steps, s.final_time), reporter),
            };
            if !ckpt_failed {
                ckpt_written = Some(s.steps);
            }
            ckpt_s += t0.elapsed().as_secs_f64();
        }
    }
    if !opts.quiet {
        reporter.steps_end();
    }
    if let (Some(e), None) = (io_error, &output_failed) {
        reporter.note(Note::Warning, &format!("history.csv: {e}"));
    }
    // the last converged step is always in the results, also when the run failed after it
    // (a part's state gathered whatever happened to the writer: every rank takes part)
    let mut gathered = (parts && every > 0).then(|| sim.gather(false)).flatten();
    let assembled = assemble_whole(&frame, gathered.as_mut());
    if let (Some(w), None, None) = (results.as_mut(), &results_error, &output_failed) {
        let snap = match (&gathered, &assembled) {
            (Some(g), Ok(Some(m))) => Some(g.snapshot(m)),
            _ if parts => None,
            _ => Some(sim.snapshot()),
        };
        match snap {
            Some(snap) => {
                if let Err(e) = w.finish(&snap, last_report.as_ref()) {
                    results_error = Some(e);
                }
            }
            None => reporter.note(Note::Warning, &format!("results: the last step's state did not reach rank 0{}", assembled.as_ref().err().map(|e| format!(" ({e})")).unwrap_or_default())),
        }
    }
    drop((gathered, assembled));
    if let (Some(e), None) = (&results_error, &output_failed) {
        reporter.note(Note::Warning, &format!("results: {e}; the steps written before are readable"));
    }
    let (status, error, summary) = match &result {
        Ok(s) if output_failed.is_some() => ("failed", output_failed.clone().map(|e| format!("output failed: {e}")), Some(s)),
        Ok(s) if s.interrupted => ("interrupted", None, Some(s)),
        Ok(s) => ("completed", None, Some(s)),
        Err(e) => ("failed", Some(e.to_string()), None),
    };
    let last_step = summary.and_then(|s| s.last.as_ref());
    let wall_time_s = wall_before + started.elapsed().as_secs_f64();
    let peak_memory_mb = peak_memory(&*comm);
    let output_s = history_s + ckpt_s + results.as_ref().map_or(0.0, |w| w.elapsed_s);
    let file = SummaryFile {
        mpfem_version: env!("CARGO_PKG_VERSION"),
        title: &title,
        case: case_file.as_ref().map(|c| serde_json::json!({ "path": c.path, "sha256": c.sha256 })),
        status,
        restarts,
        error,
        formulation,
        n_bodies,
        // the meshes the run ended on: a restart's (its re-meshed particles come from the
        // checkpoint, whatever the case says) and every re-mesh's
        n_nodes: sim.model.whole_facts().n_nodes,
        n_elements: sim.model.whole_facts().n_elements,
        wall_time_s,
        peak_memory_mb,
        final_state: last_report.as_ref().map(|r| FinalState::of(r, max_body_volume_error)),
        phases: Phases::split(&sim.timing(), output_s, wall_time_s),
        fits: sim.initial_solid_ratio().filter(|_| !curve.is_empty()).map(|d0| {
            let names = crate::plot::WALLS;
            let of = if pressing.is_empty() { "every loaded wall".to_string() } else { pressing.iter().map(|&k| names[k]).collect::<Vec<_>>().join(", ") };
            crate::fits::fit(&curve, d0, of)
        }),
        run: summary,
        last_step,
    };
    // (a summary that cannot be written fails the run as any other output: exit code 1)
    let summary_path = match write_summary(out, &file) {
        Ok(p) => p,
        Err(e) => {
            let why = format!("{}: {e}", out.join("summary.json").display());
            if output_failed.is_some() {
                reporter.note(Note::Error, &format!("{why} (not written either)"));
            } else {
                output_failed = Some(why);
            }
            out.join("summary.json")
        }
    };
    let outcome = match result {
        Ok(s) if output_failed.is_some() => {
            let error = output_failed.unwrap_or_default();
            reporter.note(Note::Error, &format!("the run stopped at t = {} s after step {}: an output file could not be written: {error}", seconds(s.final_time), s.steps));
            reporter.note(Note::Info, &format!("every row and output step written before it is readable in {}; free space or choose another --out, then restart from the last checkpoint (if one was written) or run again", out.display()));
            RunOutcome::OutputFailed { summary: s, error }
        }
        Ok(s) if s.interrupted => {
            let checkpoint = ckpt_written == Some(s.steps) && !ckpt_failed;
            reporter.note(Note::Info, &format!("{} at t = {} s after {} steps; results up to it are in {}", s.stop_reason, seconds(s.final_time), s.steps, out.display()));
            if checkpoint {
                let again = match &case_file {
                    Some(cf) => format!("mpfem run {} --out {} --restart {}", cf.path, out.display(), out.display()),
                    None => format!("mpfem run --out {} --restart {}", out.display(), out.display()),
                };
                reporter.note(Note::Info, &format!("continue with: {again}"));
            } else {
                reporter.note(Note::Error, "the checkpoint of the last step could not be written");
            }
            RunOutcome::Interrupted { summary: s, checkpoint }
        }
        Ok(s) => {
            let text = format!(
                "completed ({}) t = {} s in {} steps, {} Newton iterations, {} cut-backs, {:.2} s wall; volume error {:.2e}",
                s.stop_reason,
                seconds(s.final_time),
                s.steps,
                s.newton_iterations,
                s.cutbacks,
                s.wall_time_s,
                s.last.as_ref().map_or(0.0, |r| r.volume_error)
            );
            reporter.note(Note::Info, &text);
            let text = match &results {
                Some(w) => format!(
                    "wrote {}, {}, {} ({} output steps, {:.2} s) and {}",
                    history_files,
                    summary_path.display(),
                    w.h5_path.display(),
                    w.n_written(),
                    w.elapsed_s,
                    w.xdmf_path.display()
                ),
                None => format!("wrote {} and {}", history_files, summary_path.display()),
            };
            reporter.note(Note::Info, &text);
            RunOutcome::Completed(s)
        }
        Err(e) => {
            reporter.note(Note::Error, &format!("the run stopped at t = {} s: {e}", seconds(sim.sol.time)));
            let text = match &results {
                Some(w) => format!(
                    "results up to the last converged step are in {}, {}, {} and {}",
                    history_files,
                    summary_path.display(),
                    w.h5_path.display(),
                    w.xdmf_path.display()
                ),
                None => format!("results up to the last converged step are in {} and {}", history_files, summary_path.display()),
            };
            reporter.note(Note::Info, &text);
            RunOutcome::Failed(e)
        }
    };
    // the results file is closed before the plots read it
    drop(results);
    drop(history);
    // (a run stopped with its checkpoint ends at once: the batch system's grace period is short)
    if opts.plots && outcome.exit_code() != 3 {
        plots_after_run(out, reporter);
    }
    Ok(outcome)
}

/// Ranks 1..N of an MPI run: the same solve on the same model (from the same checkpoint on a
/// restart), no output (rank 0 writes the results and reports); the stop after the stop flag
/// is rank 0's decision, broadcast after every step.
fn run_rank(c: &Case, comm: Arc<dyn Collective>, checkpoint: Option<CheckpointFile>) -> Result<RunOutcome, RunError> {
    let model = match Model::from_case(c) {
        Ok(m) => m,
        Err(e) => return Ok(RunOutcome::BadInput(e.to_string())),
    };
    let mut sim = match checkpoint {
        None => Simulation::new_with(model, c.time, c.solver, Arc::clone(&comm))?,
        Some(ck) => match ck.read().and_then(|ck| ck.restore_with(model, c.time, c.solver, Arc::clone(&comm))) {
            Ok(s) => s,
            Err(e) => return Ok(RunOutcome::BadInput(e.to_string())),
        },
    };
    // (rank 0's flag decides, also within a step: this one is never set)
    sim.set_interrupt(Arc::default());
    let result = sim.run_controlled(&mut |_, _| {
        let (signal, _) = step_flags(&*comm, 0, false);
        root_verdict(&*comm, signal)
    });
    peak_memory(&*comm);
    Ok(match result {
        Ok(s) if s.interrupted && s.stop_reason == OUTPUT_FAILED_ON_ROOT => RunOutcome::OutputFailed { error: s.stop_reason.clone(), summary: s },
        Ok(s) if s.interrupted => RunOutcome::Interrupted { summary: s, checkpoint: true },
        Ok(s) => RunOutcome::Completed(s),
        Err(e) => RunOutcome::Failed(e),
    })
}

/// The stop reason of ranks 1.. when rank 0 could not write an output file.
const OUTPUT_FAILED_ON_ROOT: &str = "output failed on rank 0";

/// Every process's peak resident memory (MB, `VmHWM` of `/proc/self/status`), on rank 0 in
/// rank order (empty elsewhere, and where the system does not tell). Collective.
fn peak_memory(comm: &dyn Collective) -> Vec<f64> {
    let all = comm.gather_varcount_to_root(&[own_peak_memory()]);
    if all.iter().all(|v| v.is_finite()) {
        all
    } else {
        Vec::new()
    }
}

/// This process's peak resident memory so far (MB, `VmHWM` of `/proc/self/status`; NaN where
/// the system does not tell).
fn own_peak_memory() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1)).and_then(|v| v.parse::<f64>().ok()))
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// After a converged step: rank 0's stop signal (0: none) and whether a checkpoint is due, the
/// same on every process (broadcast from rank 0; the other ranks pass 0 and false).
fn step_flags(comm: &dyn Collective, signal: usize, due: bool) -> (usize, bool) {
    if comm.size() == 1 {
        return (signal, due);
    }
    let mut flags = [signal as f64, if due { 1.0 } else { 0.0 }];
    comm.broadcast(&mut flags);
    (flags[0] as usize, flags[1] != 0.0)
}

/// On ranks 1.., after a step's output: rank 0's word on it (its second [`step_flags`], after
/// its writes: whether one failed), and the stop `signal` of its first. Collective.
///
/// (Two broadcasts a step, not one: the first decides what is gathered for the writes, the
/// second tells how the writes went; 16 bytes each.)
fn root_verdict(comm: &dyn Collective, signal: usize) -> ControlFlow<String> {
    if step_flags(comm, 0, false).0 != 0 {
        // (rank 0's output failed: it stops, and so do the others)
        ControlFlow::Break(OUTPUT_FAILED_ON_ROOT.into())
    } else if signal != 0 {
        ControlFlow::Break("interrupted on rank 0".into())
    } else {
        ControlFlow::Continue(())
    }
}

/// Whether a distributed run's parts gather their state after step `step` (every process
/// decides alike): for the probes, the results' output steps (`every`), a checkpoint, a stop.
fn part_output_due(step: usize, every: usize, probes: bool, signal: usize, checkpoint: bool) -> bool {
    probes || (every > 0 && step % every == 0) || signal != 0 || checkpoint
}

/// On rank 0 of a run on parts: the whole model of `gathered`'s bodies (taken out of it) in
/// `frame` ([`crate::model::ModelFrame::assemble`]), for one step's writing. `None` without a
/// frame or without a gathered state (the other ranks, the steps that write nothing of it).
///
/// # Errors
/// Bodies the frame does not take (the step's output is not written).
fn assemble_whole(frame: &Option<crate::model::ModelFrame>, gathered: Option<&mut crate::solver::Gathered>) -> Result<Option<Model>, String> {
    let (Some(f), Some(g)) = (frame, gathered) else { return Ok(None) };
    f.assemble(std::mem::take(&mut g.bodies)).map(Some).map_err(|e| format!("the whole model for the output: {e}"))
}

/// What [`part_start`] makes.
struct FreshPart {
    sim: Simulation,
    /// (rank 0) the model of the bodies it holds ([`crate::case::parts::PartStart::held`])
    held: Option<Model>,
    /// The ghosts' reach.
    reach: f64,
    /// (rank 0) the poorly meshed bodies: index, name, smallest scaled Jacobian.
    poor: Vec<(usize, String, f64)>,
}

/// This process's simulation of a run on parts, made without the whole model
/// ([`crate::case::parts::start_part_from`]): fresh, or at the checkpoint `from` (of which
/// each process reads its share's meshes and its part's rows); on rank 0 also the model of
/// the bodies it holds (for the output's columns and frame), and on every process the ghosts'
/// reach and (rank 0, a fresh run) the poorly meshed bodies. Collective. A case that does not
/// make a model is named by the whole model's own message on rank 0 ([`Model::from_case`],
/// built then for that alone); a checkpoint that does not fit, by "cannot restart: …".
fn part_start(c: &Case, comm: &Arc<dyn Collective>, from: Option<&CheckpointFile>) -> Result<FreshPart, PartStartError> {
    use crate::case::parts::{start_part_from, StartError};
    let t = Instant::now();
    match start_part_from(c, Arc::clone(comm), POOR_SCALED_JACOBIAN, from) {
        Ok(s) => {
            let reach = s.part.reach;
            tracing::info!(
                seconds = t.elapsed().as_secs_f64(),
                own_bodies = s.part.n_owned_bodies,
                ghost_bodies = s.part.bodies.len() - s.part.n_owned_bodies,
                nodes = s.part.model.n_nodes(),
                peak_memory_mb = own_peak_memory(),
                restart = from.is_some(),
                "this process's part is made from the case (no process built the whole model)"
            );
            let sim = match from {
                None => Simulation::new_part(s.part, c.time, c.solver).map_err(|e| PartStartError::Case(e.to_string()))?,
                Some(ck) => {
                    let mut sim = Simulation::new_part_for_state(s.part, c.time, c.solver).map_err(|e| PartStartError::Case(e.to_string()))?;
                    // (collective: every process learns whether one could not take its state)
                    let set = sim.set_whole_state_from(ck.scalars.clone(), ck).map_err(|e| PartStartError::Restart(format!("cannot restart: {}: {e}", ck.path.display())));
                    let failed = comm.max(if set.is_err() { 1.0 } else { 0.0 }) > 0.0;
                    match (set, failed) {
                        (Err(e), _) => return Err(e),
                        (Ok(()), true) => return Err(PartStartError::Restart("cannot restart: another process could not take its part of the checkpoint's state".into())),
                        (Ok(()), false) => sim,
                    }
                }
            };
            Ok(FreshPart { sim, held: s.held, reach, poor: s.poor })
        }
        Err(StartError::Model(seen)) if comm.is_root() => Err(PartStartError::Case(Model::from_case(c).err().map(|e| e.to_string()).or(seen).unwrap_or_else(|| "a process could not build its part of the model".into()))),
        Err(e @ StartError::Restart(_)) => Err(PartStartError::Restart(format!("cannot restart: {e}"))),
        Err(e) => Err(PartStartError::Case(e.to_string())),
    }
}

/// Why [`part_start`] made no part: the case (its message, which the caller prefixes with the
/// case's label) or the checkpoint of a restart ("cannot restart: …", whole).
enum PartStartError {
    Case(String),
    Restart(String),
}

impl PartStartError {
    /// The line for the user, the case named by `label`.
    fn message(self, label: &str) -> String {
        match self {
            Self::Case(e) => format!("{label}: {e}"),
            Self::Restart(e) => e,
        }
    }
}

/// Ranks 1..N of a run on parts ([`run`] on rank 0): the same part of the same model, the same
/// collective steps of the output after every step (the flags of rank 0, the gathers), no
/// output of their own. Returns what the run did; rank 0 says why a setup failed.
fn run_part_rank(c: &Case, comm: Arc<dyn Collective>, checkpoint: Option<CheckpointFile>) -> Result<RunOutcome, RunError> {
    let (every, probes) = (c.output.every, !c.output.probes.is_empty());
    // (a restart: this process's share and part of the checkpoint, as on rank 0)
    let (sim, reach) = match checkpoint {
        Some(ck) if ck.run_state::<RunState>().is_err() => return Ok(RunOutcome::BadInput("cannot restart: the checkpoint's run record".into())),
        ck => match part_start(c, &comm, ck.as_ref()) {
            Ok(FreshPart { sim, reach, .. }) => (Ok(sim), reach),
            // (rank 0 says why)
            Err(e) => (Err(e.message("this process's part")), 0.0),
        },
    };
    let mut sim = match sim {
        Ok(s) => s,
        Err(e) => return Ok(RunOutcome::BadInput(e)),
    };
    // (rank 0's flag decides, also within a step: this one is never set)
    sim.set_interrupt(Arc::default());
    let mut observer = |s: &Simulation, r: &StepReport| {
        let (signal, due) = step_flags(&*comm, 0, false);
        if part_output_due(r.step, every, probes, signal, due) {
            s.gather(signal != 0 || due);
        }
        root_verdict(&*comm, signal)
    };
    let never = Arc::default();
    let mut remade = None;
    let result = loop {
        let mut segment = sim.run_controlled(&mut observer);
        if !go_on_with_new_parts(&mut sim, &mut segment, Some(reach), c, &never, &mut remade) {
            break segment;
        }
    };
    // the gathers of rank 0's last checkpoint and output step, in its order
    if matches!(&result, Ok(s) if s.interrupted && s.stop_reason == crate::solver::STOP_ABANDONED) {
        sim.gather(true);
    }
    if every > 0 {
        sim.gather(false);
    }
    peak_memory(&*comm);
    Ok(match result {
        Ok(s) if s.interrupted && s.stop_reason == OUTPUT_FAILED_ON_ROOT => RunOutcome::OutputFailed { error: s.stop_reason.clone(), summary: s },
        Ok(s) if s.interrupted => RunOutcome::Interrupted { summary: s, checkpoint: true },
        Ok(s) => RunOutcome::Completed(s),
        Err(e) => RunOutcome::Failed(e),
    })
}

/// After a run's segment on parts (`reach`: the ghosts' reach the parts were first made with,
/// None when the run is not on parts): when it stopped because a part's ghosts no longer hold
/// every body within the contact reach of its own (the particles moved), grow every part again
/// at the last converged state ([`Simulation::regrown`]: each process keeps its own bodies and
/// gets its new ghosts from their owners; nobody gathers the whole model or state) — and say
/// to go on (true). False for any other end, and when the parts cannot be grown again
/// (`result` then says why). Collective on parts.
///
/// `remade` is the step at which the parts were last grown again and the ghosts' reach then:
/// grown again at the same step (an iterate moved the particles farther than the reach), the
/// reach doubles; at a later step it is `reach` again.
fn go_on_with_new_parts(sim: &mut Simulation, result: &mut Result<RunSummary, SolveError>, reach: Option<f64>, c: &Case, stop: &Arc<AtomicUsize>, remade: &mut Option<(usize, f64)>) -> bool {
    use crate::solver::NewtonFailure;
    let (Some(reach0), Err(SolveError::StepFailed { time, dt, dt_min, cause: NewtonFailure::Ghosts(why) })) = (reach, &*result) else { return false };
    let (time, dt, dt_min) = (*time, *dt, *dt_min);
    let step = sim.step();
    let reach = match *remade {
        Some((at, reach)) if at == step => 2.0 * reach,
        _ => reach0,
    };
    *remade = Some((step, reach));
    tracing::info!(time, step, reach, %why, "the parts are grown again: the particles moved out of their ghost layers");
    match sim.regrown(c.time.clone(), c.solver.clone(), reach) {
        Ok(mut s) => {
            s.set_interrupt(Arc::clone(stop));
            *sim = s;
            true
        }
        Err(e) => {
            *result = Err(SolveError::StepFailed { time, dt, dt_min, cause: NewtonFailure::Part(format!("the parts could not be grown again ({why}): {e}")) });
            false
        }
    }
}
