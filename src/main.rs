//! `mpfem`: the command-line front end.
//!
//! ```text
//! mpfem run [CASE.toml] [--out DIR]   run a case (no case: the built-in default job)
//! mpfem check CASE.toml               validate a case without running it
//! mpfem verify                        run the verification set and print the table
//! ```
//! Exit codes: 0 success, 1 the run or a verification failed, 2 bad input (case file, paths).

use anyhow::Context;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mpfem::case::{self, Case};
use mpfem::model::Model;
use mpfem::output::{write_summary, HistoryWriter, SummaryFile};
use mpfem::results::ResultsWriter;
use mpfem::solver::Simulation;
use std::io::IsTerminal;
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    let level = match cli.verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
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
                        m.prescribed.len(),
                        m.loads.len(),
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
        Command::Run { case, out, threads, quiet } => {
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
            match run(c, &label, &out, threads, quiet) {
                Ok(code) => code,
                Err(e) => {
                    eprintln!("error: {e:#}");
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

fn run(mut c: Case, label: &str, out: &Path, threads: Option<usize>, quiet: bool) -> anyhow::Result<ExitCode> {
    if let Some(t) = threads {
        c.solver.threads = t;
    }
    std::fs::create_dir_all(out).with_context(|| format!("cannot create output directory {}", out.display()))?;
    let model = match Model::from_case(&c) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {label}: {e}");
            return Ok(ExitCode::from(2));
        }
    };
    let mut history = HistoryWriter::create(out, &model).with_context(|| format!("cannot write {}/history.csv", out.display()))?;
    let mut results = match c.output.every {
        0 => None,
        every => Some(ResultsWriter::create(out, every, &mpfem::output::history_columns(&model)).with_context(|| format!("cannot write the results in {}", out.display()))?),
    };
    let formulation = format!("{:?}", c.formulation);
    let n_nodes = model.n_nodes();
    let n_elements = model.elements.len();
    let n_bodies = model.bodies.len();
    let title = c.title.clone();
    let started = Instant::now();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone())?;
    eprintln!(
        "mpfem: {label}: \"{title}\" — {n_bodies} body(ies), {n_elements} elements, {} free dofs, linear solver {}, end time {} s",
        sim.n_free(),
        sim.linear_solver_name(),
        c.time.end
    );

    let t_end = c.time.end;
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} t = {msg}").unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    };
    let tty = std::io::stderr().is_terminal();
    let mut next_note = 0.1;
    let mut io_error: Option<std::io::Error> = None;
    let mut results_error: Option<mpfem::results::ResultsError> = None;
    let mut last_report: Option<mpfem::solver::StepReport> = None;
    let result = sim.run(&mut |s, r| {
        last_report = Some(r.clone());
        if let Err(e) = history.write(r) {
            io_error.get_or_insert(e);
        }
        if let (Some(w), None) = (results.as_mut(), &results_error) {
            if let Err(e) = w.observe(s, r) {
                results_error = Some(e);
            }
        }
        bar.set_position((1000.0 * r.time / t_end) as u64);
        bar.set_message(format!("{:.4e} s, step {}, dt {:.2e}, {} it", r.time, r.step, r.dt, r.newton_iterations));
        if !tty && !quiet && r.time >= next_note * t_end {
            eprintln!("  t = {:.4e} s ({:.0} %), step {}, {} Newton iterations, volume error {:.2e}", r.time, 100.0 * r.time / t_end, r.step, r.newton_iterations, r.volume_error);
            next_note += 0.1;
        }
    });
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
        Ok(s) => ("completed", None, Some(s)),
        Err(e) => ("failed", Some(e.to_string()), None),
    };
    let last_step = summary.and_then(|s| s.last.as_ref());
    let file = SummaryFile {
        mpfem_version: env!("CARGO_PKG_VERSION"),
        title: &title,
        status,
        error: error.clone(),
        formulation,
        n_bodies,
        n_nodes,
        n_elements,
        wall_time_s: started.elapsed().as_secs_f64(),
        run: summary,
        last_step,
    };
    let summary_path = write_summary(out, &file).with_context(|| format!("cannot write {}/summary.json", out.display()))?;
    match result {
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
            Ok(ExitCode::SUCCESS)
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
            Ok(ExitCode::from(1))
        }
    }
}
