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
//! (continue it with `--restart`), 130 a second SIGTERM/SIGINT ended the run at once.

use anyhow::Context;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mpfem::case::{self, Case};
use mpfem::model::Model;
use mpfem::output::{write_summary, FinalState, HistoryWriter, Phases, SummaryFile};
use mpfem::plot::{PlotRequest, RunDir, StepChoice, StepSpec};
use mpfem::results::ResultsWriter;
use mpfem::parallel::Collective;
use mpfem::solver::Simulation;
use std::sync::Arc;
use std::io::IsTerminal;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser)]
#[command(name = "mpfem", version, about = "Multi-particle finite elements: large-deformation plane-strain solver for the compaction of deformable particles (units: mm, N, MPa, s)")]
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
        /// Threads for assembly and factorisation (overrides [solver] threads; 0 = all cores).
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
    /// Validate a case file without running it.
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
    let comm = mpfem::parallel::launch();
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
    tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).with_target(false).init();

    match cli.command {
        Command::Check { case } => match case::load(&case) {
            Ok(c) => match Model::from_case(&c) {
                Ok(m) => {
                    let (mut min_sj, mut max_ar, mut inverted) = (f64::INFINITY, 0.0f64, 0usize);
                    for b in &m.bodies {
                        let q = mpfem::mesh::quality::quality(&b.mesh, &b.mesh.nodes);
                        min_sj = min_sj.min(q.min_scaled_jacobian);
                        max_ar = max_ar.max(q.max_aspect_ratio);
                        inverted += q.n_inverted;
                    }
                    println!(
                        "{}: OK — \"{}\": {} material(s), {} body(ies), {} nodes, {} elements, {} prescribed dofs, {} load(s), end time {} s",
                        case.display(),
                        c.title,
                        c.materials.len(),
                        c.bodies.len(),
                        m.n_nodes(),
                        m.elements.len(),
                        m.loading.prescribed.len(),
                        m.loading.loads.len(),
                        c.time.end
                    );
                    println!("mesh quality: min scaled Jacobian {min_sj:.3}, max aspect ratio {max_ar:.2}, {inverted} inverted element(s)");
                    if inverted > 0 {
                        eprintln!("error: {}: the mesh has {inverted} inverted element(s)", case.display());
                        return ExitCode::from(2);
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {}: {e}", case.display());
                    ExitCode::from(2)
                }
            },
            Err(e) => {
                eprintln!("error: {}: {e}", case.display());
                ExitCode::from(2)
            }
        },
        Command::Plot { dir, compare, label, steps, out } => plot(dir, compare, label, steps, out),
        Command::Pack { case, out } => pack(&case, &out),
        Command::Study { study, out, parallel } => run_study(&study, &out, parallel),
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
            let signal = match catch_signals() {
                Ok(s) => Some(s),
                Err(e) => {
                    eprintln!("warning: cannot catch SIGTERM/SIGINT ({e}): a signal ends the run without a checkpoint");
                    None
                }
            };
            let control = RunControl { signal, restart, allow_case_change };
            match run(c, &label, case_file, &out, threads, quiet, !no_plots, &control, comm.clone()) {
                Ok(code) => code,
                Err(e) => {
                    eprintln!("error: {e:#}");
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

/// `mpfem pack`: expand the case's grids, packings and imports into bodies, write them as a case file
/// and a preview.
/// `mpfem study`: every run in its own folder, at most `parallel` at once (one thread each),
/// then the overlay plot and the table of final values.
fn run_study(path: &Path, out: &Path, parallel: Option<usize>) -> ExitCode {
    let study = match mpfem::study::load(path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    // every run's case is validated before anything runs
    let mut cases = Vec::new();
    for r in &study.runs {
        let base = r.case_path.parent().unwrap_or(Path::new("."));
        match case::parse(&r.text, base) {
            Ok(c) => cases.push(c),
            Err(e) => {
                eprintln!("error: {}: run \"{}\": {e}", path.display(), r.label);
                return ExitCode::from(2);
            }
        }
    }
    if let Err(e) = std::fs::create_dir_all(out) {
        eprintln!("error: cannot create {}: {e}", out.display());
        return ExitCode::from(2);
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let workers = parallel.or(study.parallel).unwrap_or(cores).clamp(1, study.runs.len());
    eprintln!("mpfem: study \"{}\": {} run(s), {workers} at once, into {}", study.title, study.runs.len(), out.display());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let codes: Vec<std::sync::Mutex<Option<u8>>> = study.runs.iter().map(|_| std::sync::Mutex::new(None)).collect();
    let cases: Vec<std::sync::Mutex<Option<Case>>> = cases.into_iter().map(|c| std::sync::Mutex::new(Some(c))).collect();
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                let Some(r) = study.runs.get(i) else { break };
                let Some(c) = cases[i].lock().ok().and_then(|mut c| c.take()) else { break };
                let dir = out.join(&r.label);
                let case_path = dir.join("case.toml");
                let written = std::fs::create_dir_all(&dir).and_then(|_| std::fs::write(&case_path, &r.text));
                let code = match written {
                    Err(e) => {
                        eprintln!("error: run \"{}\": cannot write {}: {e}", r.label, case_path.display());
                        2
                    }
                    Ok(()) => match run(c, &format!("{} ({})", r.label, case_path.display()), Some(CaseFile::describe(&case_path)), &dir, Some(1), true, true, &RunControl::default(), Arc::new(mpfem::parallel::Serial)) {
                        Ok(code) if code == ExitCode::SUCCESS => 0,
                        Ok(_) => 1,
                        Err(e) => {
                            eprintln!("error: run \"{}\": {e:#}", r.label);
                            1
                        }
                    },
                };
                if let Ok(mut slot) = codes[i].lock() {
                    *slot = Some(code);
                }
            });
        }
    });
    let failed: Vec<&str> = study
        .runs
        .iter()
        .zip(&codes)
        .filter(|(_, c)| c.lock().ok().and_then(|c| *c) != Some(0))
        .map(|(r, _)| r.label.as_str())
        .collect();
    // the overlay of every run that wrote a history, and the table
    let dirs: Vec<(String, PathBuf)> = study.runs.iter().map(|r| (r.label.clone(), out.join(&r.label))).filter(|(_, d)| d.join("history.csv").is_file()).collect();
    if !dirs.is_empty() {
        let req = PlotRequest {
            out: out.to_path_buf(),
            runs: dirs.iter().map(|(l, d)| RunDir { dir: d.clone(), label: l.clone() }).collect(),
            steps: StepChoice::Explicit(Vec::new()),
        };
        match mpfem::plot::plot_results(&req) {
            Ok(r) => report_plots(&r),
            Err(e) => eprintln!("warning: study plot: {e}"),
        }
    }
    match write_study_table(out, &study) {
        Ok(paths) => eprintln!("mpfem: wrote {}", paths.join(", ")),
        Err(e) => eprintln!("warning: study table: {e}"),
    }
    if failed.is_empty() {
        ExitCode::SUCCESS
    } else {
        eprintln!("error: {} of {} run(s) failed: {}", failed.len(), study.runs.len(), failed.join(", "));
        ExitCode::from(1)
    }
}

/// OUT/study.csv and OUT/study.md: one row per run with its final values from summary.json.
fn write_study_table(out: &Path, study: &mpfem::study::Study) -> std::io::Result<Vec<String>> {
    let head = ["label", "status", "stop_reason", "steps", "solid_ratio", "p_left", "p_right", "p_bottom", "p_top", "volume_error", "max_particle_volume_error", "heckel_k", "kawakita_a", "kawakita_b", "wall_time_s"];
    let mut rows: Vec<Vec<String>> = Vec::new();
    for r in &study.runs {
        let s: serde_json::Value = std::fs::read_to_string(out.join(&r.label).join("summary.json"))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or(serde_json::Value::Null);
        let num = |v: &serde_json::Value| v.as_f64().map_or(String::new(), |x| format!("{x:.6e}"));
        let f = &s["final"];
        let text = |v: &serde_json::Value| v.as_str().unwrap_or("").to_string();
        let mut row = vec![
            r.label.clone(),
            s["status"].as_str().unwrap_or("not run").to_string(),
            text(&s["run"]["stop_reason"]),
            s["run"]["steps"].as_u64().map_or(String::new(), |n| n.to_string()),
            num(&f["solid_ratio"]),
        ];
        for k in 0..4 {
            row.push(num(&f["pressure"][k]));
        }
        row.push(num(&f["volume_error"]));
        row.push(num(&f["max_particle_volume_error"]));
        row.push(num(&s["fits"]["heckel"]["k"]));
        row.push(num(&s["fits"]["kawakita"]["a"]));
        row.push(num(&s["fits"]["kawakita"]["b"]));
        row.push(num(&s["wall_time_s"]));
        rows.push(row);
    }
    let csv_path = out.join("study.csv");
    let quote = |c: &String| if c.contains([',', '"']) { format!("\"{}\"", c.replace('"', "\"\"")) } else { c.clone() };
    let mut csv = head.join(",") + "\n";
    for r in &rows {
        csv += &(r.iter().map(quote).collect::<Vec<_>>().join(",") + "\n");
    }
    std::fs::write(&csv_path, csv)?;
    let md_path = out.join("study.md");
    let mut md = format!("# {}\n\n| {} |\n|{}|\n", study.title, head.join(" | "), vec!["---"; head.len()].join("|"));
    for r in &rows {
        md += &format!("| {} |\n", r.join(" | "));
    }
    std::fs::write(&md_path, md)?;
    Ok(vec![csv_path.display().to_string(), md_path.display().to_string()])
}

fn pack(case_path: &Path, out: &Path) -> ExitCode {
    let c = match case::load(case_path) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {}: {e}", case_path.display());
            return ExitCode::from(2);
        }
    };
    match write_packing(case_path, &c, out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn write_packing(case_path: &Path, c: &Case, out: &Path) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(case_path).with_context(|| format!("cannot read {}", case_path.display()))?;
    let mut table: toml::Table = text.parse().with_context(|| format!("cannot parse {}", case_path.display()))?;
    table.remove("grids");
    table.remove("packings");
    table.remove("imports");
    // the written case lives elsewhere: hardening tables given by a relative path are pointed
    // at the original file
    let base = case_path.parent().unwrap_or(Path::new("."));
    if let Some(toml::Value::Array(materials)) = table.get_mut("materials") {
        for m in materials {
            if let Some(f) = m.get_mut("hardening").and_then(|h| h.get_mut("file")) {
                if let Some(rel) = f.as_str().map(Path::new).filter(|p| p.is_relative()) {
                    let abs = std::path::absolute(base.join(rel)).with_context(|| format!("cannot resolve {}", rel.display()))?;
                    *f = toml::Value::String(abs.display().to_string());
                }
            }
        }
    }
    let bodies: Vec<toml::Value> = c.bodies.iter().map(|b| toml::Value::Table(b.to_toml(&c.materials))).collect();
    table.insert("bodies".into(), toml::Value::Array(bodies));
    let body = toml::to_string(&table).context("cannot write the packed case as TOML")?;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let packed = out.join("packed.toml");
    let header = format!(
        "# Written by `mpfem pack` from {}: the case with its [[grids]], [[packings]] and [[imports]]\n# replaced by the [[bodies]] they generate (hardening table and gmsh files by absolute path).\n\n",
        case_path.display()
    );
    std::fs::write(&packed, header + &body).with_context(|| format!("cannot write {}", packed.display()))?;

    let die = case::die_of(&c.walls);
    let area: f64 = c.bodies.iter().filter_map(|b| b.shape.particle()).map(|s| s.area()).sum();
    let ratio = die.map(|d| area / ((d[1] - d[0]) * (d[3] - d[2])));
    let particles: Vec<mpfem::plot::PreviewParticle> = c
        .bodies
        .iter()
        .filter_map(|b| b.shape.particle().map(|s| mpfem::plot::PreviewParticle { outline: s.outline(96), material: b.material }))
        .collect();
    let names: Vec<String> = c.materials.iter().map(|m| m.name.clone()).collect();
    let mut title = vec![if c.title.is_empty() { case_path.display().to_string() } else { c.title.clone() }];
    title.push(match ratio {
        Some(r) => format!("{} particles, solid ratio {r:.4}", c.bodies.len()),
        None => format!("{} particles", c.bodies.len()),
    });
    let png = out.join("packing.png");
    let preview = mpfem::plot::packing_png(&particles, &names, die, &title, &png);
    match ratio {
        Some(r) => println!("{}: {} particles, solid ratio {r:.6} (particle area {area:.6} mm^2)", case_path.display(), c.bodies.len()),
        None => println!("{}: {} particles (no die: the case has not all four walls)", case_path.display(), c.bodies.len()),
    }
    println!("wrote {}", packed.display());
    match preview {
        Ok(()) => println!("wrote {}", png.display()),
        // the packing is written; a missing font only costs the picture
        Err(e) => eprintln!("warning: no preview: {e}"),
    }
    Ok(())
}

/// Which case file a run used: its path and the SHA-256 of its text (the version of the case
/// that produced the results), for `summary.json`.
#[derive(serde::Serialize)]
struct CaseFile {
    path: String,
    sha256: String,
}

impl CaseFile {
    fn describe(path: &Path) -> Self {
        use sha2::Digest;
        let sha256 = std::fs::read(path)
            .map(|b| sha2::Sha256::digest(&b).iter().map(|x| format!("{x:02x}")).collect())
            .unwrap_or_default();
        Self { path: path.display().to_string(), sha256 }
    }
}

/// How far a run is, in [0, 1]: the larger of the time fraction and, with a target solid
/// ratio, the fraction of the way from the initial to the target solid ratio.
fn progress(time: f64, t_end: f64, solid: Option<(f64, f64, f64)>) -> f64 {
    let by_time = if t_end > 0.0 { time / t_end } else { 0.0 };
    let by_density = match solid {
        Some((phi0, phi, target)) if target > phi0 => (phi - phi0) / (target - phi0),
        _ => 0.0,
    };
    by_time.max(by_density).clamp(0.0, 1.0)
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
    let runs: Vec<RunDir> = dirs
        .iter()
        .enumerate()
        .map(|(i, d)| RunDir { dir: d.clone(), label: labels.get(i).cloned().unwrap_or_else(|| mpfem::plot::default_label(d)) })
        .collect();
    let req = PlotRequest {
        out: out.unwrap_or_else(|| dirs[0].clone()),
        runs,
        steps: match steps {
            Some(s) => StepChoice::Explicit(s),
            None => StepChoice::Spread(mpfem::plot::DEFAULT_SNAPSHOTS),
        },
    };
    match mpfem::plot::plot_results(&req) {
        Ok(r) => {
            for s in &r.skipped {
                eprintln!("mpfem: {s}");
            }
            report_plots(&r);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(if e.is_input() { 2 } else { 1 })
        }
    }
}

fn report_plots(r: &mpfem::plot::PlotReport) {
    if r.written.is_empty() {
        eprintln!("mpfem: no plots written");
    } else {
        let names: Vec<String> = r.written.iter().map(|p| p.display().to_string()).collect();
        eprintln!("mpfem: wrote plots {}", names.join(", "));
    }
}

/// The plots at the end of `mpfem run`, from whatever the run wrote; failures are warnings.
fn plots_after_run(out: &Path) {
    let label = mpfem::plot::default_label(out);
    let req = PlotRequest {
        runs: vec![RunDir { dir: out.to_path_buf(), label }],
        out: out.to_path_buf(),
        steps: StepChoice::Spread(mpfem::plot::DEFAULT_SNAPSHOTS),
    };
    match mpfem::plot::plot_results(&req) {
        Ok(r) => {
            for s in &r.skipped {
                eprintln!("mpfem: {s}");
            }
            report_plots(&r)
        }
        Err(e) => eprintln!("warning: plots: {e} (the results are written; `mpfem plot {}` redraws them)", out.display()),
    }
}

/// How `mpfem run` is controlled from outside the case: the signal that asks it to stop (set by
/// [`catch_signals`]), the checkpoint to continue from.
#[derive(Default)]
struct RunControl {
    /// The number of the first SIGTERM/SIGINT received (0: none).
    signal: Option<Arc<AtomicUsize>>,
    restart: Option<PathBuf>,
    allow_case_change: bool,
}

/// SIGTERM (Slurm's pre-emption and time-limit signal) and SIGINT (Ctrl-C) set a flag that the
/// run reads after each converged step: it then writes a checkpoint, closes its results and
/// exits with code 3. A second signal ends the process at once (exit code 130).
fn catch_signals() -> std::io::Result<Arc<AtomicUsize>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let which = Arc::new(AtomicUsize::new(0));
    let once = Arc::new(std::sync::atomic::AtomicBool::new(false));
    for sig in [SIGTERM, SIGINT] {
        // (registered first: it sees the flag of an earlier signal before this one sets it)
        signal_hook::flag::register_conditional_shutdown(sig, 130, Arc::clone(&once))?;
        signal_hook::flag::register(sig, Arc::clone(&once))?;
        signal_hook::flag::register_usize(sig, Arc::clone(&which), sig as usize)?;
    }
    Ok(which)
}

fn signal_name(sig: usize) -> String {
    match sig as i32 {
        signal_hook::consts::SIGTERM => "SIGTERM".into(),
        signal_hook::consts::SIGINT => "SIGINT".into(),
        s => format!("signal {s}"),
    }
}

/// The CLI's own run state kept in a checkpoint (what the summary needs besides the solver).
#[derive(serde::Serialize, serde::Deserialize, Default)]
struct CliState {
    phi0: Option<f64>,
    max_body_volume_error: f64,
    curve: Vec<mpfem::fits::CurvePoint>,
    /// Wall-clock time of the run so far (s), over its restarts.
    wall_time_s: f64,
    /// Time spent writing history.csv so far (s).
    history_s: f64,
    /// The checkpoints the run was continued from (for summary.json).
    restarts: Vec<serde_json::Value>,
}

/// The SHA-256 a checkpoint records for the case (the built-in default job has no file).
fn case_hash(case_file: Option<&CaseFile>) -> String {
    case_file.map_or_else(|| format!("built-in default job of mpfem {}", env!("CARGO_PKG_VERSION")), |c| c.sha256.clone())
}

/// Copy the files a restarted run continues (history.csv, results.h5) from the checkpoint's
/// folder into another output folder.
fn copy_run_files(from: &Path, to: &Path) -> anyhow::Result<()> {
    let same = match (from.canonicalize(), to.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if same {
        return Ok(());
    }
    for name in ["history.csv", "results.h5"] {
        let (src, dst) = (from.join(name), to.join(name));
        // (never a file onto itself, which would empty it)
        let same_file = matches!((src.canonicalize(), dst.canonicalize()), (Ok(a), Ok(b)) if a == b);
        if src.is_file() && !same_file {
            std::fs::copy(&src, &dst).with_context(|| format!("cannot copy {} into {}", src.display(), to.display()))?;
        }
    }
    Ok(())
}

/// `mpirun -n N mpfem run`, ranks 1..N: the same solve on the same model (from the same
/// checkpoint on a restart), no output (rank 0 writes the results and reports); the stop
/// after a signal is rank 0's decision, broadcast after every step. The exit code is the run's.
fn run_rank(c: &Case, comm: Arc<dyn Collective>, checkpoint: Option<mpfem::checkpoint::Checkpoint>) -> anyhow::Result<ExitCode> {
    let model = match Model::from_case(c) {
        Ok(m) => m,
        Err(_) => return Ok(ExitCode::from(2)),
    };
    let mut sim = match checkpoint {
        None => Simulation::new_with(model, c.time, c.solver, Arc::clone(&comm))?,
        Some(ck) => match ck.restore_with(model, c.time, c.solver, Arc::clone(&comm)) {
            Ok(s) => s,
            Err(_) => return Ok(ExitCode::from(2)),
        },
    };
    let result = sim.run_controlled(&mut |_, _| {
        let mut stop = [0.0];
        comm.broadcast(&mut stop);
        if stop[0] != 0.0 {
            ControlFlow::Break("interrupted on rank 0".into())
        } else {
            ControlFlow::Continue(())
        }
    });
    Ok(match result {
        Ok(s) if s.interrupted => ExitCode::from(3),
        Ok(_) => ExitCode::SUCCESS,
        Err(_) => ExitCode::from(1),
    })
}

#[allow(clippy::too_many_arguments)]
fn run(mut c: Case, label: &str, case_file: Option<CaseFile>, out: &Path, threads: Option<usize>, quiet: bool, plots: bool, control: &RunControl, comm: Arc<dyn Collective>) -> anyhow::Result<ExitCode> {
    if let Some(t) = threads {
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
    let checkpoint = match &control.restart {
        None => None,
        Some(p) => match mpfem::checkpoint::Checkpoint::read(p) {
            Ok(ck) => Some(ck),
            Err(e) => {
                if comm.is_root() {
                    eprintln!("error: cannot restart: {e}");
                }
                return Ok(ExitCode::from(2));
            }
        },
    };
    let sha = case_hash(case_file.as_ref());
    if let Some(ck) = &checkpoint {
        if ck.case_sha256 != sha {
            let case = case_file.as_ref().map_or_else(|| "the built-in default job".to_string(), |c| format!("the case file {}", c.path));
            if !comm.is_root() {
                if !control.allow_case_change {
                    return Ok(ExitCode::from(2));
                }
            } else if control.allow_case_change {
                eprintln!("warning: {case} (sha256 {sha}) is not the one the checkpoint {} was written with (sha256 {}); restarting anyway (--allow-case-change)", ck.path.display(), ck.case_sha256);
            } else {
                eprintln!(
                    "error: cannot restart: {case} (sha256 {sha}) is not the one the checkpoint {} was written with (sha256 {}); pass --allow-case-change to restart anyway",
                    ck.path.display(),
                    ck.case_sha256
                );
                return Ok(ExitCode::from(2));
            }
        }
    }
    if !comm.is_root() {
        return run_rank(&c, comm, checkpoint);
    }
    std::fs::create_dir_all(out).with_context(|| format!("cannot create output directory {}", out.display()))?;
    let model = match Model::from_case(&c) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {label}: {e}");
            return Ok(ExitCode::from(2));
        }
    };
    let formulation = format!("{:?}", c.formulation);
    let n_nodes = model.n_nodes();
    let n_elements = model.elements.len();
    let n_bodies = model.bodies.len();
    let title = c.title.clone();
    let started = Instant::now();
    let ranks = comm.size();
    let (mut sim, resumed) = match checkpoint {
        None => (Simulation::new_with(model, c.time, c.solver, Arc::clone(&comm))?, None),
        Some(ck) => {
            let (step, time, path) = (ck.step, ck.time, ck.path.clone());
            let state: CliState = match ck.run_state() {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("error: cannot restart: {e}");
                    return Ok(ExitCode::from(2));
                }
            };
            let from = match path.parent() {
                Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
                _ => PathBuf::from("."),
            };
            let sim = match ck.restore_with(model, c.time, c.solver, Arc::clone(&comm)) {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("error: cannot restart: {e}");
                    return Ok(ExitCode::from(2));
                }
            };
            copy_run_files(&from, out)?;
            eprintln!("mpfem: restarting from {} at step {step}, t = {time} s", path.display());
            (sim, Some((step, time, path, state)))
        }
    };
    let columns = mpfem::output::history_columns(&sim.model);
    let (mut history, mut results) = match &resumed {
        None => (
            HistoryWriter::create(out, &sim.model).with_context(|| format!("cannot write {}/history.csv", out.display()))?,
            match c.output.every {
                0 => None,
                every => Some(ResultsWriter::create(out, every, &columns).with_context(|| format!("cannot write the results in {}", out.display()))?),
            },
        ),
        Some((step, ..)) => (
            HistoryWriter::open_append(out, &sim.model, *step).with_context(|| format!("cannot continue {}/history.csv", out.display()))?,
            match c.output.every {
                0 => None,
                every => Some(ResultsWriter::open_append(out, every, &columns, *step).with_context(|| format!("cannot continue the results in {}", out.display()))?),
            },
        ),
    };
    // pictures of an earlier run in the same folder would not match the new results
    mpfem::plot::remove_old_plots(out);
    let on_ranks = match ranks {
        1 => String::new(),
        _ if sim.solves_distributed() => format!(", {ranks} MPI ranks (solve distributed)"),
        _ => format!(", {ranks} MPI ranks (solve on rank 0)"),
    };
    eprintln!(
        "mpfem: {label}: \"{title}\" — {n_bodies} body(ies), {n_elements} elements, {} free dofs, linear solver {}{on_ranks}, end time {} s",
        sim.n_free(),
        sim.linear_solver_name(),
        c.time.end
    );

    let t_end = c.time.end;
    let target = c.stop.solid_ratio;
    let tty = std::io::stderr().is_terminal();
    let bar = if quiet || !tty {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {percent:>3}% ETA {eta} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b.enable_steady_tick(std::time::Duration::from_millis(250));
        b
    };
    // without a terminal (batch jobs, CI): a plain line every 10 % of the run and at least
    // every minute
    let mut next_note = 0.1;
    let mut last_note = Instant::now();
    let mut earlier = CliState::default();
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
    let loading = &sim.model.loading;
    let pressing: Vec<usize> = loading.walls.iter().enumerate().filter(|&(w, _)| loading.wall_moves(w)).map(|(_, wall)| wall.side.index()).collect();
    let mut curve: Vec<mpfem::fits::CurvePoint> = std::mem::take(&mut earlier.curve);
    // checkpoints: every `checkpoint_every` steps, every `checkpoint_minutes`, and after the
    // step in which a signal arrived
    let ckpt_every = c.output.checkpoint_every;
    let ckpt_interval = (c.output.checkpoint_minutes > 0.0).then(|| std::time::Duration::try_from_secs_f64(60.0 * c.output.checkpoint_minutes).ok()).flatten();
    let mut last_ckpt = Instant::now();
    let mut ckpt_s = 0.0;
    // (step of the last checkpoint written, whether the last attempt failed)
    let mut ckpt_written: Option<usize> = None;
    let mut ckpt_failed = false;
    let mut io_error: Option<std::io::Error> = None;
    let mut results_error: Option<mpfem::results::ResultsError> = None;
    // (after a restart: the checkpoint's last step, so that a run restarted at its end still
    // writes its last step and final state)
    let mut last_report: Option<mpfem::solver::StepReport> = sim.last_report().cloned();
    let mut result = sim.run_controlled(&mut |s, r| {
        last_report = Some(r.clone());
        max_body_volume_error = max_body_volume_error.max(r.volume_error_max_body);
        if let Some(c) = &r.compaction {
            let loaded: Vec<f64> = if pressing.is_empty() {
                c.pressure.iter().copied().filter(|p| *p > 0.0).collect()
            } else {
                pressing.iter().map(|&k| c.pressure[k]).collect()
            };
            if !loaded.is_empty() && c.solid_ratio > 0.0 {
                curve.push(mpfem::fits::CurvePoint { solid_ratio: c.solid_ratio, pressure: loaded.iter().sum::<f64>() / loaded.len() as f64 });
            }
        }
        let t_out = Instant::now();
        if let Err(e) = history.write(r) {
            io_error.get_or_insert(e);
        }
        history_s += t_out.elapsed().as_secs_f64();
        if let (Some(w), None) = (results.as_mut(), &results_error) {
            if let Err(e) = w.observe(s, r) {
                results_error = Some(e);
            }
        }
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
        let done = progress(r.time, t_end, solid);
        let density = match (phi, target) {
            (Some(p), Some(t)) => format!("solid ratio {p:.4} → {t} | "),
            (Some(p), None) => format!("solid ratio {p:.4} | "),
            _ => String::new(),
        };
        let line = format!("{density}t {:.4e} s | step {} | dt {:.2e} | {} it", r.time, r.step, r.dt, r.newton_iterations);
        bar.set_position((1000.0 * done) as u64);
        bar.set_message(line.clone());
        if !tty && !quiet && (done >= next_note || last_note.elapsed().as_secs() >= 60) {
            eprintln!("  {:3.0} % | {line} | volume error {:.2e} | {:.0} s", 100.0 * done, r.volume_error, started.elapsed().as_secs_f64());
            while next_note <= done {
                next_note += 0.1;
            }
            last_note = Instant::now();
        }
        let signal = control.signal.as_ref().map_or(0, |f| f.load(Ordering::SeqCst));
        if comm.size() > 1 {
            // every rank stops after the same step: rank 0's flag decides (see `run_rank`)
            let mut stop = [signal as f64];
            comm.broadcast(&mut stop);
        }
        let due = (ckpt_every > 0 && r.step % ckpt_every == 0) || ckpt_interval.is_some_and(|d| last_ckpt.elapsed() >= d);
        if signal != 0 || due {
            let t0 = Instant::now();
            let state = CliState {
                phi0,
                max_body_volume_error,
                curve: curve.clone(),
                wall_time_s: wall_before + started.elapsed().as_secs_f64(),
                history_s,
                restarts: restarts.clone(),
            };
            match mpfem::checkpoint::write(out, s, &sha, &state) {
                Ok(p) => {
                    bar.suspend(|| eprintln!("mpfem: checkpoint at step {}, t = {:.6e} s: {}", r.step, r.time, p.display()));
                    ckpt_written = Some(r.step);
                    ckpt_failed = false;
                }
                Err(e) => {
                    bar.suspend(|| eprintln!("warning: {e}"));
                    ckpt_failed = true;
                }
            }
            last_ckpt = Instant::now();
            ckpt_s += t0.elapsed().as_secs_f64();
        }
        if signal != 0 {
            return ControlFlow::Break(format!("interrupted by {}", signal_name(signal)));
        }
        ControlFlow::Continue(())
    });
    if let Ok(s) = result.as_mut() {
        s.wall_time_s += wall_before;
    }
    bar.finish_and_clear();
    if let Some(e) = io_error {
        eprintln!("warning: history.csv: {e}");
    }
    // the last converged step is always in the results, also when the run failed after it
    if let (Some(w), None) = (results.as_mut(), &results_error) {
        if let Err(e) = w.finish(&sim, last_report.as_ref()) {
            results_error = Some(e);
        }
    }
    if let Some(e) = &results_error {
        eprintln!("warning: results: {e}; the steps written before are readable");
    }
    let (status, error, summary) = match &result {
        Ok(s) if s.interrupted => ("interrupted", None, Some(s)),
        Ok(s) => ("completed", None, Some(s)),
        Err(e) => ("failed", Some(e.to_string()), None),
    };
    let last_step = summary.and_then(|s| s.last.as_ref());
    let wall_time_s = wall_before + started.elapsed().as_secs_f64();
    let output_s = history_s + ckpt_s + results.as_ref().map_or(0.0, |w| w.elapsed_s);
    let t = &sim.timing();
    let file = SummaryFile {
        mpfem_version: env!("CARGO_PKG_VERSION"),
        title: &title,
        case: case_file.as_ref().map(|c| serde_json::json!({ "path": c.path, "sha256": c.sha256 })),
        status,
        restarts,
        error: error.clone(),
        formulation,
        n_bodies,
        n_nodes,
        n_elements,
        wall_time_s,
        final_state: last_report.as_ref().map(|r| FinalState::of(r, max_body_volume_error)),
        phases: Phases::split(t, output_s, wall_time_s),
        fits: sim.initial_solid_ratio().filter(|_| !curve.is_empty()).map(|d0| {
            let names = mpfem::plot::WALLS;
            let of = if pressing.is_empty() { "every loaded wall".to_string() } else { pressing.iter().map(|&k| names[k]).collect::<Vec<_>>().join(", ") };
            mpfem::fits::fit(&curve, d0, of)
        }),
        run: summary,
        last_step,
    };
    let summary_path = write_summary(out, &file).with_context(|| format!("cannot write {}/summary.json", out.display()))?;
    let code = match result {
        Ok(s) if s.interrupted => {
            let again = match (&case_file, ckpt_written == Some(s.steps) && !ckpt_failed) {
                (_, false) => None,
                (Some(cf), true) => Some(format!("mpfem run {} --out {} --restart {}", cf.path, out.display(), out.display())),
                (None, true) => Some(format!("mpfem run --out {} --restart {}", out.display(), out.display())),
            };
            eprintln!("mpfem: {} at t = {} s after {} steps; results up to it are in {}", s.stop_reason, s.final_time, s.steps, out.display());
            match again {
                Some(cmd) => {
                    eprintln!("mpfem: continue with: {cmd}");
                    ExitCode::from(3)
                }
                None => {
                    eprintln!("error: the checkpoint of the last step could not be written");
                    ExitCode::from(1)
                }
            }
        }
        Ok(s) => {
            eprintln!(
                "mpfem: completed ({}) t = {} s in {} steps, {} Newton iterations, {} cut-backs, {:.2} s wall; volume error {:.2e}",
                s.stop_reason,
                s.final_time,
                s.steps,
                s.newton_iterations,
                s.cutbacks,
                s.wall_time_s,
                s.last.as_ref().map_or(0.0, |r| r.volume_error)
            );
            match &results {
                Some(w) => eprintln!(
                    "mpfem: wrote {}, {}, {} ({} output steps, {:.2} s) and {}",
                    history.path.display(),
                    summary_path.display(),
                    w.h5_path.display(),
                    w.n_written(),
                    w.elapsed_s,
                    w.xdmf_path.display()
                ),
                None => eprintln!("mpfem: wrote {} and {}", history.path.display(), summary_path.display()),
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: the run stopped at t = {} s: {e}", sim.sol.time);
            match &results {
                Some(w) => eprintln!(
                    "mpfem: results up to the last converged step are in {}, {}, {} and {}",
                    history.path.display(),
                    summary_path.display(),
                    w.h5_path.display(),
                    w.xdmf_path.display()
                ),
                None => eprintln!("mpfem: results up to the last converged step are in {} and {}", history.path.display(), summary_path.display()),
            }
            ExitCode::from(1)
        }
    };
    // the results file is closed before the plots read it
    drop(results);
    drop(history);
    // (a run stopped by a signal exits at once: the batch system's grace period is short)
    if plots && code != ExitCode::from(3) {
        plots_after_run(out);
    }
    Ok(code)
}
