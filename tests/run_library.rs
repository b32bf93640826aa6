//! The run orchestration called as a library, without the binary (`mpfem::run::run`): a run
//! stopped through its stop flag after step 2 writes the checkpoint of step 2 and returns
//! "interrupted"; continued from it through the library, its history.csv is byte for byte the
//! uninterrupted run's; a restart with a case whose SHA-256 is not the checkpoint's is refused
//! as bad input (nothing written) unless `allow_case_change`; every line goes to the reporter.
//!
//! The case: tests/data/mpi_discs_3x3.toml, 3 × 3 discs with Coulomb friction 0.2 between
//! them (stick anchors in the pair histories, so a restart that lost them would show), from
//! solid ratio 0.76 to 0.80.

use mpfem::comm::Serial;
use mpfem::run::{CaseFile, Note, Progress, Reporter, RunOptions, RunOutcome, RunState};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mpfem-runlib-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The test case's text written into `dir` with `extra` appended.
fn case_in(dir: &Path, extra: &str) -> PathBuf {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mpi_discs_3x3.toml")).unwrap();
    let path = dir.join("case.toml");
    std::fs::write(&path, format!("{text}{extra}")).unwrap();
    path
}

/// Keeps every line and step; sets `stop` (to SIGTERM's number) after step `stop_after`.
#[derive(Default)]
struct Recorder {
    notes: Mutex<Vec<(Note, String)>>,
    steps: Mutex<Vec<(usize, f64)>>,
    begun: AtomicUsize,
    ended: AtomicUsize,
    stop: Option<(usize, Arc<AtomicUsize>)>,
}

impl Recorder {
    fn stopping_after(step: usize, flag: &Arc<AtomicUsize>) -> Self {
        Self { stop: Some((step, Arc::clone(flag))), ..Self::default() }
    }

    fn notes(&self, kind: Note) -> Vec<String> {
        self.notes.lock().unwrap().iter().filter(|(k, _)| *k == kind).map(|(_, t)| t.clone()).collect()
    }

    fn steps(&self) -> Vec<usize> {
        self.steps.lock().unwrap().iter().map(|s| s.0).collect()
    }
}

impl Reporter for Recorder {
    fn note(&self, kind: Note, text: &str) {
        self.notes.lock().unwrap().push((kind, text.to_string()));
    }
    fn steps_begin(&self) {
        self.begun.fetch_add(1, Ordering::SeqCst);
    }
    fn step(&self, p: &Progress) {
        self.steps.lock().unwrap().push((p.report.step, p.done));
        if let Some((after, flag)) = &self.stop {
            if p.report.step == *after {
                flag.store(libc::SIGTERM as usize, Ordering::SeqCst);
            }
        }
    }
    fn steps_end(&self) {
        self.ended.fetch_add(1, Ordering::SeqCst);
    }
}

/// Run the case file at `case` with `opts` through the library, on one process.
fn run(case: &Path, opts: &RunOptions, reporter: &Recorder) -> RunOutcome {
    let c = mpfem::case::load(case).unwrap();
    mpfem::run::run(c, &case.display().to_string(), Some(CaseFile::describe(case)), opts, Arc::new(Serial), reporter).unwrap()
}

fn options(out: &Path) -> RunOptions {
    RunOptions { plots: false, ..RunOptions::new(out) }
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&read(&dir.join("summary.json"))).unwrap()
}

/// The uninterrupted run into `dir/a`: its step count and history.csv.
fn uninterrupted(dir: &Path, case: &Path) -> (usize, String) {
    let a = dir.join("a");
    let rec = Recorder::default();
    let steps = match run(case, &options(&a), &rec) {
        RunOutcome::Completed(s) => {
            assert_eq!(s.stop_reason, "solid ratio reached");
            s.steps
        }
        other => panic!("the uninterrupted run: {other:?}"),
    };
    assert!(steps > 3, "{steps} steps: too few to stop after step 2 and go on");
    // one progress report per step, the last at the end of the run
    assert_eq!(rec.steps(), (1..=steps).collect::<Vec<_>>());
    assert_eq!(rec.steps.lock().unwrap().last().unwrap().1, 1.0);
    assert_eq!((rec.begun.load(Ordering::SeqCst), rec.ended.load(Ordering::SeqCst)), (1, 1));
    let info = rec.notes(Note::Info);
    assert!(info[0].starts_with(&format!("{}: \"3 x 3 discs, coarse, MPI ranks test\" — 9 body(ies), ", case.display())), "{info:?}");
    assert!(info.iter().any(|l| l.starts_with("completed (solid ratio reached) t = ") && l.contains(&format!(" in {steps} steps"))), "{info:?}");
    assert!(rec.notes(Note::Warning).is_empty() && rec.notes(Note::Error).is_empty());
    let history = read(&a.join("history.csv"));
    assert_eq!(history.lines().count(), steps + 1, "header and one row per step");
    assert_eq!(summary(&a)["status"], "completed");
    (steps, history)
}

#[test]
fn a_run_stopped_by_its_flag_restarts_through_the_library_to_the_same_history() {
    let dir = tmpdir("stop");
    let case = case_in(&dir, "");
    let (steps, history) = uninterrupted(&dir, &case);

    // stopped after step 2: the checkpoint of step 2, "interrupted", exit code 3
    let b = dir.join("b");
    let flag = Arc::new(AtomicUsize::new(0));
    let rec = Recorder::stopping_after(2, &flag);
    let opts = RunOptions { stop: Some(Arc::clone(&flag)), ..options(&b) };
    match run(&case, &opts, &rec) {
        RunOutcome::Interrupted { summary, checkpoint } => {
            assert!(checkpoint);
            assert_eq!(summary.steps, 2);
            assert_eq!(summary.stop_reason, "interrupted by SIGTERM");
        }
        other => panic!("expected interrupted, got {other:?}"),
    }
    assert_eq!(rec.steps(), [1, 2], "no step after the flag");
    let info = rec.notes(Note::Info);
    assert!(info.iter().any(|l| l.starts_with("checkpoint at step 2, t = ") && l.ends_with(&b.join("checkpoint.h5").display().to_string())), "{info:?}");
    assert!(info.iter().any(|l| l.starts_with("interrupted by SIGTERM at t = ") && l.contains("after 2 steps")), "{info:?}");
    let again = format!("continue with: mpfem run {} --out {} --restart {}", case.display(), b.display(), b.display());
    assert!(info.contains(&again), "{info:?}");
    let ck = mpfem::checkpoint::Checkpoint::read(&b).unwrap();
    assert_eq!(ck.step, 2);
    assert_eq!(ck.case_sha256, CaseFile::describe(&case).sha256);
    let state: RunState = ck.run_state().unwrap();
    assert!(state.phi0.is_some_and(|p| p > 0.75 && p < 0.80), "{:?}", state.phi0);
    assert_eq!(state.curve.len(), 2, "one pressure–density point per step");
    assert!(state.restarts.is_empty());
    let part = read(&b.join("history.csv"));
    assert_eq!(part.lines().count(), 3);
    assert!(history.starts_with(&part), "the interrupted history is the uninterrupted one's beginning");
    let s = summary(&b);
    assert_eq!((s["status"].as_str(), s["run"]["interrupted"].as_bool()), (Some("interrupted"), Some(true)));

    // continued from it in place: the uninterrupted run's history, byte for byte
    let rec = Recorder::default();
    let opts = RunOptions { restart: Some(b.clone()), ..options(&b) };
    match run(&case, &opts, &rec) {
        RunOutcome::Completed(s) => assert_eq!(s.steps, steps),
        other => panic!("the restart: {other:?}"),
    }
    assert_eq!(rec.steps(), (3..=steps).collect::<Vec<_>>(), "the restart goes on from step 3");
    let info = rec.notes(Note::Info);
    assert!(info.iter().any(|l| l.starts_with("restarting from ") && l.contains("at step 2, t = ")), "{info:?}");
    assert_eq!(read(&b.join("history.csv")), history, "history.csv after the restart");
    let (sa, sb) = (summary(&dir.join("a")), summary(&b));
    assert_eq!(sb["status"], "completed");
    assert_eq!(sb["restarts"][0]["step"], 2);
    for key in ["final", "fits", "last_step"] {
        assert_eq!(sa[key], sb[key], "summary.json {key}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_restart_with_another_case_is_bad_input_unless_allowed() {
    let dir = tmpdir("sha");
    let case = case_in(&dir, "");
    let (_, history) = uninterrupted(&dir, &case);
    let c = dir.join("c");
    let flag = Arc::new(AtomicUsize::new(0));
    let opts = RunOptions { stop: Some(Arc::clone(&flag)), ..options(&c) };
    let outcome = run(&case, &opts, &Recorder::stopping_after(1, &flag));
    assert_eq!(outcome.exit_code(), 3, "{outcome:?}");
    let before = read(&c.join("history.csv"));
    assert_eq!(before.lines().count(), 2);

    // the same model from a case file whose text (so its SHA-256) differs
    let changed = dir.join("changed");
    std::fs::create_dir_all(&changed).unwrap();
    let other = case_in(&changed, "# a comment changes the file, not the model\n");
    let (old, new) = (CaseFile::describe(&case).sha256, CaseFile::describe(&other).sha256);
    assert_ne!(old, new);
    let rec = Recorder::default();
    let opts = RunOptions { restart: Some(c.clone()), ..options(&c) };
    let text = match run(&other, &opts, &rec) {
        RunOutcome::BadInput(text) => text,
        outcome => panic!("expected bad input, got {outcome:?}"),
    };
    assert_eq!(RunOutcome::BadInput(text.clone()).exit_code(), 2);
    let expect = format!(
        "cannot restart: the case file {} (sha256 {new}) is not the one the checkpoint {} was written with (sha256 {old}); pass --allow-case-change to restart anyway",
        other.display(),
        c.join("checkpoint.h5").display()
    );
    assert_eq!(text, expect);
    assert_eq!(rec.notes(Note::Error), [expect], "reported once, as an error");
    assert!(rec.steps().is_empty() && rec.notes(Note::Info).is_empty(), "nothing run");
    assert_eq!(read(&c.join("history.csv")), before, "nothing written");
    assert_eq!(mpfem::checkpoint::Checkpoint::read(&c).unwrap().step, 1);

    // allowed: a warning naming both, and the run completes as the uninterrupted one
    let rec = Recorder::default();
    let opts = RunOptions { allow_case_change: true, ..opts };
    let outcome = run(&other, &opts, &rec);
    assert_eq!(outcome.exit_code(), 0, "{outcome:?}");
    let warnings = rec.notes(Note::Warning);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains(&old) && warnings[0].contains(&new) && warnings[0].ends_with("restarting anyway (--allow-case-change)"), "{warnings:?}");
    assert_eq!(read(&c.join("history.csv")), history);
    assert_eq!(summary(&c)["case"]["sha256"].as_str(), Some(new.as_str()));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A missing checkpoint is bad input too, before anything is created.
#[test]
fn a_missing_checkpoint_is_bad_input() {
    let dir = tmpdir("missing");
    let case = case_in(&dir, "");
    let out = dir.join("out");
    let rec = Recorder::default();
    let opts = RunOptions { restart: Some(dir.join("nowhere")), ..options(&out) };
    match run(&case, &opts, &rec) {
        RunOutcome::BadInput(text) => {
            assert!(text.starts_with("cannot restart: ") && text.contains("nowhere") && text.contains("no checkpoint"), "{text}");
            assert_eq!(rec.notes(Note::Error), [text]);
        }
        other => panic!("expected bad input, got {other:?}"),
    }
    assert!(!out.exists(), "no output folder for a run that did not start");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The run state in a checkpoint is stored by field name: these are the names of the
/// checkpoints written before the orchestration moved into the library (the binary's
/// `CliState`), which must still restart.
#[test]
fn the_run_state_keeps_its_field_names() {
    let v = serde_json::to_value(RunState::default()).unwrap();
    let mut keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(keys, ["curve", "history_s", "max_body_volume_error", "phi0", "restarts", "wall_time_s"]);
    let old = r#"{"phi0":0.76,"max_body_volume_error":1e-4,"curve":[{"solid_ratio":0.77,"pressure":2.5}],"wall_time_s":3.0,"history_s":0.1,"restarts":[{"step":4}]}"#;
    let s: RunState = serde_json::from_str(old).unwrap();
    assert_eq!((s.phi0, s.max_body_volume_error, s.wall_time_s, s.history_s), (Some(0.76), 1e-4, 3.0, 0.1));
    assert_eq!((s.curve[0].solid_ratio, s.curve[0].pressure), (0.77, 2.5));
    assert_eq!(s.restarts[0]["step"], 4);
}
