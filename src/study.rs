//! Studies: several runs of one case that differ in a few keys (issue 5, `mpfem study`).
//!
//! A study file (TOML) names a base case and the runs:
//!
//! ```toml
//! title = "friction"                       # optional
//! base = "../paper/5_1_1_aluminium_lateral.toml"   # relative to the study file
//! parallel = 2                             # runs at once (default: the number of cores)
//!
//! [sweep]                                  # one key over a list of values ...
//! key = "contact.friction"
//! values = [0.0, 0.1, 0.2]
//! set = { "contact.contact" = "rubbing" }  # set in every run of the sweep (optional)
//!
//! [[runs]]                                 # ... and/or runs listed one by one
//! label = "sticking"
//! set = { "contact.contact" = "cohering" }
//! # case = "other.toml"                    # a whole other case instead of `base`
//! ```
//!
//! Keys are dotted paths into the case file; a number indexes an array of tables
//! (`walls.1.velocity`). Each run's case is the base case with its keys set, parsed and
//! validated like any case (its errors name the run).
//!
//! [`run`] runs a study ([`crate::run::run`] for each of its runs, several at once), draws the
//! overlay of their pressures and writes the table of their final values.

use crate::case::Case;
use crate::plot::{PlotRequest, RunDir, StepChoice};
use crate::run::{CaseFile, Note, Reporter, RunOptions};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum StudyError {
    #[error("{path}: {msg}")]
    Input { path: PathBuf, msg: String },
}

fn input(path: &Path, msg: impl Into<String>) -> StudyError {
    StudyError::Input { path: path.to_path_buf(), msg: msg.into() }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyRaw {
    title: Option<String>,
    base: Option<String>,
    parallel: Option<i64>,
    sweep: Option<SweepRaw>,
    #[serde(default)]
    runs: Vec<RunRaw>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepRaw {
    key: String,
    values: Vec<toml::Value>,
    labels: Option<Vec<String>>,
    #[serde(default)]
    set: toml::Table,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RunRaw {
    label: String,
    case: Option<String>,
    #[serde(default)]
    set: toml::Table,
}

/// One run of a study: its label (also its folder name) and its case text.
#[derive(Clone, Debug)]
pub struct StudyRun {
    pub label: String,
    /// The case file the run starts from and the keys set on it.
    pub case_path: PathBuf,
    pub set: Vec<(String, toml::Value)>,
    /// The case text with the keys set (what the run uses; written next to its results).
    pub text: String,
}

#[derive(Clone, Debug)]
pub struct Study {
    pub title: String,
    pub parallel: Option<usize>,
    pub runs: Vec<StudyRun>,
}

/// Set `key` (dotted path, numbers index arrays) to `value` in `doc`, creating tables on the
/// way; an index past the end of an array is an error.
pub fn set_key(doc: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(format!("key \"{key}\": expected a dotted path such as contact.friction or walls.0.velocity"));
    }
    let mut root = toml::Value::Table(std::mem::take(doc));
    let result = set_in(&mut root, &parts, 0, key, value);
    if let toml::Value::Table(t) = root {
        *doc = t;
    }
    result
}

fn set_in(node: &mut toml::Value, parts: &[&str], i: usize, key: &str, value: toml::Value) -> Result<(), String> {
    let part = parts[i];
    let last = i + 1 == parts.len();
    let next = match node {
        toml::Value::Table(t) => {
            if last {
                t.insert(part.to_string(), value);
                return Ok(());
            }
            t.entry(part.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()))
        }
        toml::Value::Array(a) => {
            let idx: usize = part.parse().map_err(|_| format!("key \"{key}\": \"{part}\" indexes an array: expected a number"))?;
            let n = a.len();
            let slot = a.get_mut(idx).ok_or_else(|| format!("key \"{key}\": index {idx} past the {n} entries"))?;
            if last {
                *slot = value;
                return Ok(());
            }
            slot
        }
        _ => return Err(format!("key \"{key}\": \"{}\" is a value, not a table", parts[..i].join("."))),
    };
    set_in(next, parts, i + 1, key, value)
}

/// Read a study file and build the case text of every run.
pub fn load(path: &Path) -> Result<Study, StudyError> {
    let text = std::fs::read_to_string(path).map_err(|e| input(path, format!("cannot read the study file: {e}")))?;
    let raw: StudyRaw = toml::from_str(&text).map_err(|e| input(path, e.to_string()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let parallel = match raw.parallel {
        None => None,
        Some(n) if n >= 1 => Some(n as usize),
        Some(n) => return Err(input(path, format!("parallel: value {n}; expected a number of runs at once >= 1"))),
    };
    let base = raw.base.as_ref().map(|b| dir.join(b));
    let mut specs: Vec<(String, PathBuf, Vec<(String, toml::Value)>)> = Vec::new();
    if let Some(s) = raw.sweep {
        let Some(base) = &base else {
            return Err(input(path, "sweep: needs `base`, the case file the sweep starts from"));
        };
        if s.values.is_empty() {
            return Err(input(path, "sweep.values: empty; expected the values of sweep.key"));
        }
        if let Some(l) = &s.labels {
            if l.len() != s.values.len() {
                return Err(input(path, format!("sweep.labels: {} labels for {} values; expected one per value", l.len(), s.values.len())));
            }
        }
        for (i, v) in s.values.iter().enumerate() {
            let label = s.labels.as_ref().map_or_else(|| format!("{}={}", s.key, v), |l| l[i].clone());
            let mut set: Vec<(String, toml::Value)> = s.set.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
            set.push((s.key.clone(), v.clone()));
            specs.push((label, base.clone(), set));
        }
    }
    for (i, r) in raw.runs.iter().enumerate() {
        let case = match (&r.case, &base) {
            (Some(c), _) => dir.join(c),
            (None, Some(b)) => b.clone(),
            (None, None) => return Err(input(path, format!("runs[{i}] (\"{}\"): no `case` and no `base`; expected one of them", r.label))),
        };
        specs.push((r.label.clone(), case, r.set.iter().map(|(k, v)| (k.clone(), v.clone())).collect()));
    }
    if specs.is_empty() {
        return Err(input(path, "no runs: expected a [sweep] or [[runs]]"));
    }
    let mut runs = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for (label, case_path, set) in specs {
        if label.trim().is_empty() || label.contains(['/', '\\']) || !seen.insert(label.clone()) {
            return Err(input(path, format!("run label \"{label}\": expected a unique, non-empty name without slashes (it names the run's folder)")));
        }
        let base_text = std::fs::read_to_string(&case_path).map_err(|e| input(&case_path, format!("run \"{label}\": cannot read the case: {e}")))?;
        let mut doc: toml::Table = toml::from_str(&base_text).map_err(|e| input(&case_path, format!("run \"{label}\": {e}")))?;
        for (k, v) in &set {
            set_key(&mut doc, k, v.clone()).map_err(|e| input(path, format!("run \"{label}\": {e}")))?;
        }
        let text = toml::to_string(&doc).map_err(|e| input(path, format!("run \"{label}\": {e}")))?;
        runs.push(StudyRun { label, case_path, set, text });
    }
    Ok(Study { title: raw.title.unwrap_or_else(|| path.file_stem().map_or("study".into(), |s| s.to_string_lossy().into_owned())), parallel, runs })
}

/// How a study ended (the binary's exit code: [`StudyOutcome::exit_code`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StudyOutcome {
    /// Every run completed (exit code 0).
    Completed,
    /// The runs with these labels did not complete; the others, the plot and the table are
    /// written (exit code 1).
    Failed(Vec<String>),
    /// The study file or a run's case is not usable; nothing was run (exit code 2). The text
    /// is the one reported.
    BadInput(String),
}

impl StudyOutcome {
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Completed => 0,
            Self::Failed(_) => 1,
            Self::BadInput(_) => 2,
        }
    }
}

/// `mpfem study`: the study file at `path`, every run in its own folder `out/<label>/` (its
/// case text as `case.toml` there), at most `parallel` at once (default: the study's
/// `parallel`, else the number of cores) with one thread each, quiet; then the overlay
/// pressure plot of every run that wrote a history and the table of final values
/// ([`write_table`]). Every run's case is validated before anything runs.
pub fn run(path: &Path, out: &Path, parallel: Option<usize>, reporter: &dyn Reporter) -> StudyOutcome {
    let bad = |text: String| {
        reporter.note(Note::Error, &text);
        StudyOutcome::BadInput(text)
    };
    let study = match load(path) {
        Ok(s) => s,
        Err(e) => return bad(e.to_string()),
    };
    let mut cases = Vec::new();
    for r in &study.runs {
        let base = r.case_path.parent().unwrap_or(Path::new("."));
        match crate::case::parse(&r.text, base) {
            Ok(c) => cases.push(c),
            Err(e) => return bad(format!("{}: run \"{}\": {e}", path.display(), r.label)),
        }
    }
    if let Err(e) = std::fs::create_dir_all(out) {
        return bad(format!("cannot create {}: {e}", out.display()));
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let workers = parallel.or(study.parallel).unwrap_or(cores).clamp(1, study.runs.len());
    reporter.note(Note::Info, &format!("study \"{}\": {} run(s), {workers} at once, into {}", study.title, study.runs.len(), out.display()));
    let next = AtomicUsize::new(0);
    // (whether each run completed; None: not run)
    let completed: Vec<Mutex<Option<bool>>> = study.runs.iter().map(|_| Mutex::new(None)).collect();
    let cases: Vec<Mutex<Option<Case>>> = cases.into_iter().map(|c| Mutex::new(Some(c))).collect();
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(r) = study.runs.get(i) else { break };
                let Some(c) = cases[i].lock().ok().and_then(|mut c| c.take()) else { break };
                let dir = out.join(&r.label);
                let case_path = dir.join("case.toml");
                let written = std::fs::create_dir_all(&dir).and_then(|_| std::fs::write(&case_path, &r.text));
                let ok = match written {
                    Err(e) => {
                        reporter.note(Note::Error, &format!("run \"{}\": cannot write {}: {e}", r.label, case_path.display()));
                        false
                    }
                    Ok(()) => {
                        let opts = RunOptions { threads: Some(1), quiet: true, ..RunOptions::new(&dir) };
                        let label = format!("{} ({})", r.label, case_path.display());
                        match crate::run::run(c, &label, Some(CaseFile::describe(&case_path)), &opts, Arc::new(crate::comm::Serial), reporter) {
                            Ok(outcome) => outcome.exit_code() == 0,
                            Err(e) => {
                                reporter.note(Note::Error, &format!("run \"{}\": {}", r.label, crate::run::error_chain(&e)));
                                false
                            }
                        }
                    }
                };
                if let Ok(mut slot) = completed[i].lock() {
                    *slot = Some(ok);
                }
            });
        }
    });
    let failed: Vec<String> = study
        .runs
        .iter()
        .zip(&completed)
        .filter(|(_, c)| c.lock().ok().and_then(|c| *c) != Some(true))
        .map(|(r, _)| r.label.clone())
        .collect();
    // the overlay of every run that wrote a history, and the table
    let dirs: Vec<(String, PathBuf)> = study.runs.iter().map(|r| (r.label.clone(), out.join(&r.label))).filter(|(_, d)| d.join("history.csv").is_file()).collect();
    if !dirs.is_empty() {
        let req = PlotRequest {
            out: out.to_path_buf(),
            runs: dirs.iter().map(|(l, d)| RunDir { dir: d.clone(), label: l.clone() }).collect(),
            steps: StepChoice::Explicit(Vec::new()),
        };
        match crate::plot::plot_results(&req) {
            Ok(r) => crate::run::report_plots(&r, reporter),
            Err(e) => reporter.note(Note::Warning, &format!("study plot: {e}")),
        }
    }
    match write_table(out, &study) {
        Ok(paths) => {
            let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            reporter.note(Note::Info, &format!("wrote {}", names.join(", ")));
        }
        Err(e) => reporter.note(Note::Warning, &format!("study table: {e}")),
    }
    if failed.is_empty() {
        StudyOutcome::Completed
    } else {
        reporter.note(Note::Error, &format!("{} of {} run(s) failed: {}", failed.len(), study.runs.len(), failed.join(", ")));
        StudyOutcome::Failed(failed)
    }
}

/// `out/study.csv` and `out/study.md`: one row per run with its final values from its
/// `summary.json` (empty cells where a value is missing, status "not run" without a summary).
/// Returns the two paths.
pub fn write_table(out: &Path, study: &Study) -> std::io::Result<Vec<PathBuf>> {
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
    Ok(vec![csv_path, md_path])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_set_in_tables_and_arrays() {
        let mut doc: toml::Table = toml::from_str("[contact]\nmethod = \"penalty\"\n[[walls]]\nside = \"left\"\n[[walls]]\nside = \"right\"\n").unwrap();
        set_key(&mut doc, "contact.friction", toml::Value::Float(0.2)).unwrap();
        set_key(&mut doc, "walls.1.velocity", toml::Value::Float(5.0)).unwrap();
        set_key(&mut doc, "stop.solid_ratio", toml::Value::Float(0.9)).unwrap();
        assert_eq!(doc["contact"]["friction"].as_float(), Some(0.2));
        assert_eq!(doc["contact"]["method"].as_str(), Some("penalty"));
        assert_eq!(doc["walls"][1]["velocity"].as_float(), Some(5.0));
        assert!(doc["walls"][0].get("velocity").is_none());
        assert_eq!(doc["stop"]["solid_ratio"].as_float(), Some(0.9));
        assert!(set_key(&mut doc, "walls.5.velocity", toml::Value::Float(1.0)).unwrap_err().contains("index 5 past the 2 entries"));
        assert!(set_key(&mut doc, "walls.x", toml::Value::Float(1.0)).unwrap_err().contains("expected a number"));
        assert!(set_key(&mut doc, "contact.method.x", toml::Value::Float(1.0)).unwrap_err().contains("is a value"));
        assert!(set_key(&mut doc, "a..b", toml::Value::Float(1.0)).is_err());
    }
}
