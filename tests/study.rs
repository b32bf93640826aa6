//! `mpfem study`: a sweep and a listed run over the small 2 x 2 case (tests/data/discs_coarse.toml),
//! each in its own folder; the table repeats each run's summary.json and the overlay plot has
//! every run's curves; bad study files exit 2 naming what is wrong.

use std::path::Path;

mod common;
use common::{mpfem, root, tmpdir};

fn study(dir: &Path, text: &str) -> std::process::Output {
    let file = dir.join("study.toml");
    std::fs::write(&file, text).unwrap();
    mpfem()
        .args(["study", "--parallel", "2", "--out"])
        .arg(dir.join("out"))
        .arg(&file)
        .output()
        .unwrap()
}

#[test]
fn a_sweep_and_a_listed_run_give_folders_a_table_and_one_plot() {
    let dir = tmpdir("ok");
    let base = root().join("tests/data/discs_coarse.toml");
    let text = format!(
        r#"
title = "coarse study"
base = "{}"

[sweep]
key = "stop.solid_ratio"
values = [0.72, 0.74]
labels = ["phi072", "phi074"]

[[runs]]
label = "rubbing"
set = {{ "contact.contact" = "rubbing", "contact.friction" = 0.2, "output.every" = 0 }}
"#,
        base.display()
    );
    let o = study(&dir, &text);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let out = dir.join("out");
    let mut finals = Vec::new();
    for (label, target) in [("phi072", 0.72), ("phi074", 0.74), ("rubbing", 0.741)] {
        let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join(label).join("summary.json")).unwrap()).unwrap();
        assert_eq!(s["status"], "completed", "{label}");
        assert_eq!(s["run"]["stop_reason"], "solid ratio reached", "{label}");
        let phi = s["final"]["solid_ratio"].as_f64().unwrap();
        assert!(phi >= target, "{label}: {phi} < {target}");
        finals.push((label, phi, s["run"]["steps"].as_u64().unwrap()));
        // the run's case is the base with the keys set
        let case: toml::Table = toml::from_str(&std::fs::read_to_string(out.join(label).join("case.toml")).unwrap()).unwrap();
        assert_eq!(case["stop"]["solid_ratio"].as_float(), Some(target), "{label}");
    }
    assert!(finals[0].2 < finals[1].2, "the lower target stops earlier: {finals:?}");
    let rubbing: toml::Table = toml::from_str(&std::fs::read_to_string(out.join("rubbing/case.toml")).unwrap()).unwrap();
    assert_eq!(rubbing["contact"]["contact"].as_str(), Some("rubbing"));
    assert_eq!(rubbing["contact"]["friction"].as_float(), Some(0.2));
    assert!(!out.join("rubbing/results.h5").exists(), "output.every = 0 was set for this run");

    // the table: one row per run, the final solid ratio of its summary
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = head.iter().position(|c| *c == "solid_ratio").unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 3);
    for (row, (label, phi, _)) in rows.iter().zip(&finals) {
        assert_eq!(row[0], *label);
        assert_eq!(row[1], "completed");
        let v: f64 = row[col].parse().unwrap();
        assert!((v - phi).abs() <= 1e-6 * phi, "{label}: table {v} vs summary {phi}");
    }
    assert!(std::fs::read_to_string(out.join("study.md")).unwrap().starts_with("# coarse study"));
    // one overlay with the left and right walls of each of the three runs
    let svg = std::fs::read_to_string(out.join("pressure_compare.svg")).unwrap();
    for label in ["phi072", "phi074", "rubbing"] {
        for wall in ["left wall", "right wall"] {
            assert!(svg.contains(&format!("{label}: {wall}")), "no legend entry {label}: {wall}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_study_files_exit_2_naming_the_problem() {
    let dir = tmpdir("bad");
    let base = root().join("tests/data/discs_coarse.toml");
    let cases = [
        (format!("base = \"{}\"\nwhat = 1\n[[runs]]\nlabel = \"a\"\n", base.display()), "unknown field `what`"),
        (format!("base = \"{}\"\n", base.display()), "no runs"),
        (format!("base = \"{}\"\n[[runs]]\nlabel = \"a\"\nset = {{ \"walls.9.velocity\" = 1.0 }}\n", base.display()), "index 9 past the 4 entries"),
        (format!("base = \"{}\"\n[[runs]]\nlabel = \"a\"\nset = {{ \"contact.friction\" = -1.0 }}\n", base.display()), "run \"a\""),
        (format!("base = \"{}\"\n[[runs]]\nlabel = \"a\"\n[[runs]]\nlabel = \"a\"\n", base.display()), "unique"),
        ("[[runs]]\nlabel = \"a\"\n".to_string(), "no `case` and no `base`"),
    ];
    for (text, expect) in cases {
        let o = study(&dir, &text);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{text}\n{err}");
        assert!(err.contains(expect), "expected `{expect}` in: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every study shipped in jobs/studies loads, and every one of its runs is a valid case.
#[test]
fn shipped_studies_load_and_their_cases_are_valid() {
    let dir = root().join("jobs/studies");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let s = mpfem::study::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(!s.runs.is_empty());
        for r in &s.runs {
            let base = r.case_path.parent().unwrap();
            mpfem::case::parse(&r.text, base).unwrap_or_else(|e| panic!("{}: run {}: {e}", path.display(), r.label));
        }
        n += 1;
    }
    assert!(n >= 3, "studies found: {n}");
}

/// `mpfem check STUDY.toml` (issue 23) checks every run the study would make, one line each:
/// exit 0 when all are valid, else 2 naming the run and the key of the bad one.
#[test]
fn check_validates_every_run_of_a_study() {
    let dir = tmpdir("check");
    let base = root().join("tests/data/discs_coarse.toml");
    let text = |bad: &str| {
        format!(
            "title = \"checked\"\nbase = \"{}\"\n\n[[runs]]\nlabel = \"plain\"\n\n[[runs]]\nlabel = \"rubbing\"\nset = {{ \"contact.contact\" = \"rubbing\", \"contact.friction\" = {bad} }}\n",
            base.display()
        )
    };
    let file = dir.join("study.toml");
    std::fs::write(&file, text("0.2")).unwrap();
    let o = mpfem().arg("check").arg(&file).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out} {}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("run \"plain\": OK") && out.contains("run \"rubbing\": OK") && out.contains("2 run(s)"), "{out}");
    std::fs::write(&file, text("-0.2")).unwrap();
    let o = mpfem().arg("check").arg(&file).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("run \"rubbing\"") && err.contains("contact.friction") && err.contains("1 of 2 run(s) invalid"), "{err}");
}
