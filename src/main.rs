//! `mpfem`: the command-line front end.
//!
//! ```text
//! mpfem run [CASE.toml] [--out DIR]   run a case (no case: the built-in default job)
//! mpfem check CASE.toml               validate a case without running it
//! mpfem pack CASE.toml [--out DIR]    expand grids, packings, imports: DIR/packed.toml, packing.png
//! mpfem verify                        run the verification set and print the table
//! mpfem plot DIR [--compare DIR2 ...]  redraw the plots of a results folder
//! mpfem study STUDY.toml [--out DIR]  several runs of a case side by side: one plot, one table
//! ```
//! Exit codes: 0 success, 1 the run or a verification failed (or `plot` could not draw),
//! 2 bad input (case file, paths, steps, a missing or unreadable checkpoint, a case that is not
//! the checkpoint's), 3 `run` stopped by SIGTERM or SIGINT after writing its checkpoint
//! (continue it with `--restart`), 130 a second SIGTERM/SIGINT (a second or more after the
//! first) ended the run at once.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mpfem::case;
use mpfem::plot::{PlotRequest, StepSpec};
use mpfem::run::{error_chain, CaseFile, Note, Progress, Reporter, RunOptions};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::AtomicUsize;
use std::sync::{Arc, Mutex};
use std::time::Instant;

#[derive(Parser)]
#[command(name = "mpfem", version, about = "Multi-particle finite elements: large-deformation plane-strain (or plane-stress) solver for the compaction of deformable particles (units: mm, N, MPa, s)")]
struct Cli {
    /// More log output (-v info, -vv debug); RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a case file (or the built-in default job when no case is given).
    Run {
        /// The TOML case file; omit to run the built-in default job (jobs/default.toml).
        case: Option<PathBuf>,
        /// Output directory for history.csv, summary.json, results.h5 and results.xdmf.
        #[arg(short, long, default_value = "out")]
        out: PathBuf,
        /// Threads for the assembly (overrides [solver] threads; 0 = all cores; the sparse direct factorisations run on one).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar.
        #[arg(short, long)]
        quiet: bool,
        /// Do not draw the plots (pressure.png/.svg, snapshot_step_N.png) at the end of the run.
        #[arg(long)]
        no_plots: bool,
        /// Continue the run from the checkpoint in this folder (its checkpoint.h5, or the file
        /// itself); history.csv and results.h5 of the output folder keep the steps up to the
        /// checkpoint and go on from there.
        #[arg(long, value_name = "DIR")]
        restart: Option<PathBuf>,
        /// Restart even when the case file is not the one the checkpoint was written with
        /// (its SHA-256 differs); the model must still match.
        #[arg(long, requires = "restart")]
        allow_case_change: bool,
    },
    /// Redraw the plots of a results folder: wall pressure against solid ratio
    /// (pressure.png, pressure.svg) and snapshots coloured by von Mises stress
    /// (snapshot_step_N.png); with --compare, the pressures of several runs in one plot
    /// (pressure_compare.png, pressure_compare.svg).
    Plot {
        /// The results folder written by `mpfem run --out DIR`.
        dir: PathBuf,
        /// More results folders whose pressures are overlaid on DIR's (repeatable).
        #[arg(long, value_name = "DIR2")]
        compare: Vec<PathBuf>,
        /// Legend label of each run, in the order DIR, DIR2, ... (repeatable; default: the
        /// folder names).
        #[arg(long)]
        label: Vec<String>,
        /// Output steps to draw as snapshots, comma separated: step numbers of history.csv,
        /// `first`, `last` (default: about 4 spread over the output steps, the last included).
        #[arg(long, value_delimiter = ',', value_parser = parse_step)]
        steps: Option<Vec<StepSpec>>,
        /// Where to write the pictures (default: DIR).
        #[arg(short, long)]
        out: Option<PathBuf>,
    },
    /// Expand the particle grids, random packings and imported particles of a case: write
    /// DIR/packed.toml (the case with every [[grids]], [[packings]] and [[imports]] entry
    /// replaced by its [[bodies]]) and
    /// DIR/packing.png (a preview), and print the particle count and the solid ratio.
    Pack {
        /// The TOML case file.
        case: PathBuf,
        /// Output directory.
        #[arg(short, long, default_value = "pack")]
        out: PathBuf,
    },
    /// Run a study: the runs of a study file (a base case with a few keys changed, swept or
    /// listed) side by side, each into OUT/<label>/, then one pressure plot of all of them
    /// (OUT/pressure_compare.png, .svg) and a table of their final values (OUT/study.csv,
    /// OUT/study.md). Exit 1 if a run failed (the others and the table are still written).
    Study {
        /// The study file (TOML; see docs/case-file.md, "Studies").
        study: PathBuf,
        /// Output directory.
        #[arg(short, long, default_value = "study")]
        out: PathBuf,
        /// Runs at once (overrides the study's `parallel`; default: the number of cores).
        #[arg(long)]
        parallel: Option<usize>,
    },
    /// Validate a case file (or every run of a study file) without running it.
    Check {
        case: PathBuf,
    },
    /// Run the verification set (patch test, objectivity, TL = UL, Cook's membrane, Hill's
    /// cylinder, creep, incompressible block) and print the table; non-zero exit if a row fails.
    Verify {
        /// Write the table as JSON to this file as well.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

/// Rust ignores SIGPIPE, so printing into a closed pipe (`mpfem check CASE | head -1`) would
/// panic; restore the default: the process ends quietly, as other command-line tools do.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to its default at start-up, before any thread
    // exists, has no preconditions
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn main() -> ExitCode {
    restore_sigpipe();
    let cli = Cli::parse();
    // MPI, when the `mpi` feature is on and an MPI launcher started this process (finalised
    // when `comm` is dropped at the end of `main`); otherwise one serial process
    let comm = mpfem::comm::launch();
    let level = match cli.verbose {
        // ranks other than 0 are silent: rank 0 talks to the user and writes the results
        _ if !comm.is_root() => "off",
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let filter = match comm.is_root() {
        true => tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level)),
        false => tracing_subscriber::EnvFilter::new(level),
    };
    // colour codes only on a terminal: a log redirected to a file (a batch job's stderr) stays
    // plain text; NO_COLOR (no-color.org) turns them off on a terminal too
    let ansi = std::io::IsTerminal::is_terminal(&std::io::stderr()) && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty());
    tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).with_target(false).with_ansi(ansi).init();

    match cli.command {
        Command::Check { case } => check(&case),
        Command::Plot { dir, compare, label, steps, out } => plot(dir, compare, label, steps, out),
        Command::Pack { case, out } => pack(&case, &out),
        Command::Study { study, out, parallel } => ExitCode::from(mpfem::study::run(&study, &out, parallel, &Console::new()).exit_code()),
        Command::Run { case, out, threads, quiet, no_plots, restart, allow_case_change } => {
            let (c, label) = match &case {
                Some(p) => match case::load(p) {
                    Ok(c) => (c, p.display().to_string()),
                    Err(e) => {
                        eprintln!("error: {}: {e}", p.display());
                        return ExitCode::from(2);
                    }
                },
                None => (case::default_case(), "built-in default job (jobs/default.toml)".to_string()),
            };
            let case_file = case.as_ref().map(|p| CaseFile::describe(p));
            let stop = match catch_signals() {
                Ok(s) => Some(s),
                Err(e) => {
                    eprintln!("warning: cannot catch SIGTERM/SIGINT ({e}): a signal ends the run without a checkpoint");
                    None
                }
            };
            let opts = RunOptions { out, threads, quiet, plots: !no_plots, restart, allow_case_change, stop };
            match mpfem::run::run(c, &label, case_file, &opts, comm.clone(), &Console::new()) {
                Ok(outcome) => ExitCode::from(outcome.exit_code()),
                Err(e) => {
                    eprintln!("error: {}", error_chain(&e));
                    // (an output folder rank 0 alone cannot write: the other ranks would wait)
                    comm.abort_all(2);
                    ExitCode::from(2)
                }
            }
        }
        Command::Verify { json } => {
            let rows = mpfem::verify::run_all();
            print!("{}", mpfem::verify::format_table(&rows));
            if let Some(p) = json {
                if let Err(e) = std::fs::write(&p, serde_json::to_string_pretty(&rows).unwrap_or_default()) {
                    eprintln!("error: cannot write {}: {e}", p.display());
                    return ExitCode::from(2);
                }
            }
            let failed = rows.iter().filter(|r| !r.pass).count();
            if failed == 0 {
                println!("verify: all {} rows pass", rows.len());
                ExitCode::SUCCESS
            } else {
                println!("verify: {failed} of {} rows FAIL", rows.len());
                ExitCode::from(1)
            }
        }
    }
}

/// Whether `path` is a study file (top-level `sweep`, `runs` or `base`) rather than a case.
fn is_study(path: &Path) -> bool {
    std::fs::read_to_string(path).ok().and_then(|t| t.parse::<toml::Table>().ok()).is_some_and(|t| ["sweep", "runs", "base"].iter().any(|k| t.contains_key(*k)))
}

/// `mpfem check STUDY.toml`: every run the study would make, checked as `mpfem check` checks a
/// case (one line each); exit 2 when the study file or any run is invalid.
fn check_study(path: &Path) -> ExitCode {
    let study = match mpfem::study::load(path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let mut failed = 0;
    for r in &study.runs {
        let dir = r.case_path.parent().unwrap_or(Path::new("."));
        let checked = case::parse(&r.text, dir).map_err(|e| e.to_string()).and_then(|c| mpfem::run::check(&c).map_err(|e| e.to_string()));
        match checked {
            Ok(k) if k.n_inverted == 0 => println!("{}: run \"{}\": OK — {} nodes, {} elements, min scaled Jacobian {:.3}", path.display(), r.label, k.n_nodes, k.n_elements, k.min_scaled_jacobian),
            Ok(k) => {
                eprintln!("error: {}: run \"{}\" ({}): the mesh has {} inverted element(s)", path.display(), r.label, r.case_path.display(), k.n_inverted);
                failed += 1;
            }
            Err(e) => {
                eprintln!("error: {}: run \"{}\" ({}): {e}", path.display(), r.label, r.case_path.display());
                failed += 1;
            }
        }
    }
    if failed > 0 {
        eprintln!("error: {}: {failed} of {} run(s) invalid", path.display(), study.runs.len());
        return ExitCode::from(2);
    }
    println!("{}: OK — study \"{}\", {} run(s)", path.display(), study.title, study.runs.len());
    ExitCode::SUCCESS
}

/// `mpfem check`: exit 0 when the case makes a model without inverted elements, else 2; a study
/// file has each of its runs checked.
fn check(case: &Path) -> ExitCode {
    if is_study(case) {
        return check_study(case);
    }
    let checked = case::load(case).map_err(|e| e.to_string()).and_then(|c| mpfem::run::check(&c).map(|k| (c, k)).map_err(|e| e.to_string()));
    let (c, k) = match checked {
        Ok(ck) => ck,
        Err(e) => {
            eprintln!("error: {}: {e}", case.display());
            return ExitCode::from(2);
        }
    };
    if !k.outside_walls.is_empty() {
        for m in &k.outside_walls {
            eprintln!("error: {}: {m}", case.display());
        }
        return ExitCode::from(2);
    }
    if k.n_inverted > 0 {
        for (i, name, n) in &k.inverted_bodies {
            eprintln!("error: {}: bodies[{i}] (\"{name}\"): its mesh has {n} inverted element(s); expected a shape and mesh_size / divisions that mesh it (a self-touching outline, or divisions too few for a curved side)", case.display());
        }
        return ExitCode::from(2);
    }
    println!(
        "{}: OK — \"{}\": {} material(s), {} body(ies), {} nodes, {} elements, {} prescribed dofs, {} load(s), end time {} s",
        case.display(),
        c.title,
        c.materials.len(),
        c.bodies.len(),
        k.n_nodes,
        k.n_elements,
        k.n_prescribed,
        k.n_loads,
        c.time.end
    );
    println!("mesh quality: min scaled Jacobian {:.3}, max aspect ratio {:.2}, {} inverted element(s)", k.min_scaled_jacobian, k.max_aspect_ratio, k.n_inverted);
    for w in &k.warnings {
        eprintln!("warning: {}: {w}", case.display());
    }
    ExitCode::SUCCESS
}

/// `mpfem pack`: expand the case's grids, packings and imports into bodies, write them as a
/// case file and a preview.
fn pack(case_path: &Path, out: &Path) -> ExitCode {
    let c = match case::load(case_path) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {}: {e}", case_path.display());
            return ExitCode::from(2);
        }
    };
    let p = match mpfem::pack::write_packing(case_path, &c, out) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {}", error_chain(&e));
            return ExitCode::from(2);
        }
    };
    match p.solid_ratio {
        Some(r) => println!("{}: {} particles, solid ratio {r:.6} (particle area {:.6} mm^2)", case_path.display(), p.particles, p.area),
        None => println!("{}: {} particles (no die: the case has not all four walls)", case_path.display(), p.particles),
    }
    println!("wrote {}", p.packed.display());
    match &p.preview {
        Ok(()) => println!("wrote {}", p.png.display()),
        // the packing is written; a missing font only costs the picture
        Err(e) => eprintln!("warning: no preview: {e}"),
    }
    ExitCode::SUCCESS
}

fn parse_step(s: &str) -> Result<StepSpec, String> {
    s.parse()
}

/// `mpfem plot`: exit 0 when drawn, 2 on bad input (folders, files, steps, labels), 1 when the
/// drawing itself fails.
fn plot(dir: PathBuf, compare: Vec<PathBuf>, labels: Vec<String>, steps: Option<Vec<StepSpec>>, out: Option<PathBuf>) -> ExitCode {
    let dirs: Vec<PathBuf> = std::iter::once(dir).chain(compare).collect();
    if !labels.is_empty() && labels.len() != dirs.len() {
        eprintln!("error: --label given {} time(s) for {} run(s): expected one label per results folder (DIR, then each --compare)", labels.len(), dirs.len());
        return ExitCode::from(2);
    }
    let req = PlotRequest::of_folders(&dirs, &labels, steps, out);
    match mpfem::plot::plot_results(&req) {
        Ok(r) => {
            let console = Console::new();
            for s in &r.skipped {
                console.note(Note::Info, s);
            }
            mpfem::run::report_plots(&r, &console);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(if e.is_input() { 2 } else { 1 })
        }
    }
}

/// The command line's [`Reporter`]: lines on stderr (`mpfem: `, `warning: `, `error: `); the
/// progress as a bar on a terminal, else (batch jobs, CI) a plain line every 10 % of the run
/// and at least every minute.
struct Console {
    tty: bool,
    bar: Mutex<Option<ProgressBar>>,
    /// (the fraction of the run at which the next plain line is due, when the last one was written)
    plain: Mutex<(f64, Instant)>,
}

impl Console {
    fn new() -> Self {
        Self { tty: std::io::stderr().is_terminal(), bar: Mutex::new(None), plain: Mutex::new((0.1, Instant::now())) }
    }

    fn bar(&self) -> Option<ProgressBar> {
        self.bar.lock().ok().and_then(|b| b.clone())
    }
}

impl Reporter for Console {
    fn note(&self, kind: Note, text: &str) {
        let prefix = match kind {
            Note::Info => "mpfem",
            Note::Warning => "warning",
            Note::Error => "error",
        };
        match self.bar() {
            Some(b) => b.suspend(|| eprintln!("{prefix}: {text}")),
            None => eprintln!("{prefix}: {text}"),
        }
    }

    fn steps_begin(&self) {
        if self.tty {
            let b = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
            b.set_style(
                ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {percent:>3}% ETA {eta} {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            b.enable_steady_tick(std::time::Duration::from_millis(250));
            if let Ok(mut slot) = self.bar.lock() {
                *slot = Some(b);
            }
        } else if let Ok(mut plain) = self.plain.lock() {
            *plain = (0.1, Instant::now());
        }
    }

    fn step(&self, p: &Progress) {
        let line = p.line();
        if let Some(b) = self.bar() {
            b.set_position((1000.0 * p.done) as u64);
            b.set_message(line);
        } else if let (false, Ok(mut plain)) = (self.tty, self.plain.lock()) {
            let (next, last) = &mut *plain;
            if p.done >= *next || last.elapsed().as_secs() >= 60 {
                eprintln!("  {:3.0} % | {line} | volume error {:.2e} | {:.0} s", 100.0 * p.done, p.report.volume_error, p.elapsed_s);
                while *next <= p.done {
                    *next += 0.1;
                }
                *last = Instant::now();
            }
        }
    }

    fn steps_end(&self) {
        if let Some(b) = self.bar.lock().ok().and_then(|mut b| b.take()) {
            b.finish_and_clear();
        }
    }
}

/// SIGTERM (Slurm's pre-emption and time-limit signal) and SIGINT (Ctrl-C) set a flag that the
/// run reads before every Newton iteration and after each converged step: it then abandons the
/// step under way, writes a checkpoint of the last converged one, closes its results and exits
/// with code 3. A second signal at least [`SECOND_SIGNAL_AFTER_MS`] after the first ends
/// the process at once (exit code 130); one sooner is the same request delivered twice:
/// `timeout` sends its signal to the command and then to the command's whole process group,
/// and a batch system may signal the job's shell and every process in it. Measured: a
/// 1,024-particle run under `timeout` was ended at once, without its checkpoint, by the pair.
fn catch_signals() -> std::io::Result<Arc<AtomicUsize>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    use std::sync::atomic::{AtomicU64, Ordering};
    let which = Arc::new(AtomicUsize::new(0));
    // the time of the first signal (ms on the monotonic clock, + 1; 0 = none yet)
    let first = Arc::new(AtomicU64::new(0));
    for sig in [SIGTERM, SIGINT] {
        let (which, first) = (Arc::clone(&which), Arc::clone(&first));
        let handler = move || {
            let now = monotonic_ms() + 1;
            match first.compare_exchange(0, now, Ordering::SeqCst, Ordering::SeqCst) {
                Ok(_) => which.store(sig as usize, Ordering::SeqCst),
                Err(t) if now.saturating_sub(t) >= SECOND_SIGNAL_AFTER_MS => signal_hook::low_level::exit(130),
                Err(_) => {}
            }
        };
        // SAFETY: the handler only reads the monotonic clock (clock_gettime is
        // async-signal-safe), does atomic operations and may call _exit
        unsafe { signal_hook::low_level::register(sig, handler) }?;
    }
    Ok(which)
}

/// A second SIGTERM/SIGINT sooner than this after the first is taken as the same request.
const SECOND_SIGNAL_AFTER_MS: u64 = 1000;

/// Milliseconds on the monotonic clock (async-signal-safe: `clock_gettime`).
fn monotonic_ms() -> u64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: a valid pointer to a timespec; CLOCK_MONOTONIC always exists on Linux
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1000 + ts.tv_nsec as u64 / 1_000_000
}
