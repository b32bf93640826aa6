//! End-to-end runs of the `mpfem` binary: the default job writes a readable history and
//! summary; bad input exits with code 2 and names the key; a run that cannot go on exits 1 and
//! keeps every row written so far.

mod common;
use common::{mpfem, root, tmpdir};

#[test]
fn default_job_runs_and_writes_history_and_summary() {
    let out = tmpdir("default");
    let o = mpfem().args(["run", "--out"]).arg(&out).output().unwrap();
    assert!(o.status.success());
    // stderr is not a terminal here: plain progress lines instead of a bar, one per 10 % of
    // the run, the last at 100 %
    let err = String::from_utf8_lossy(&o.stderr);
    let progress: Vec<&str> = err.lines().filter(|l| l.contains(" % | t ")).collect();
    assert!((5..=12).contains(&progress.len()), "progress lines: {progress:?}");
    assert!(progress.last().is_some_and(|l| l.trim_start().starts_with("100 %") && l.contains("step")), "{progress:?}");
    let hist = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = hist.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in ["step", "time", "newton_iterations", "volume_error", "ry_block_top"] {
        assert!(header.contains(&col), "missing column {col}: {header:?}");
    }
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    let last = rows.last().unwrap();
    let t = header.iter().position(|c| *c == "time").unwrap();
    assert!((last[t] - 0.6).abs() < 1e-12, "ends at the end time");
    // plane-strain upsetting, homogeneous: force = (2/√3) σ_y · current width; Table 1
    // saturates at 130.2 MPa and the width is 20/0.7 mm (incompressible plastic flow; the
    // elastic volume change of ~1e-3 is within the 1 % tolerance)
    let ry = header.iter().position(|c| *c == "ry_block_top").unwrap();
    let expected = 2.0 / 3f64.sqrt() * 130.2 * 20.0 / 0.7;
    assert!(((-last[ry] - expected) / expected).abs() < 0.01, "top force {} vs {expected}", -last[ry]);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "completed");
    assert_eq!(summary["run"]["steps"].as_u64().unwrap() as usize, rows.len());
}

#[test]
fn check_reports_bad_input_with_exit_code_2() {
    let dir = tmpdir("bad");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[[materials]]\nname = \"m\"\nmodel = \"elastic\"\nyoungs_modulus = -5.0\npoisson_ratio = 0.3\n").unwrap();
    let o = mpfem().arg("check").arg(&bad).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("youngs_modulus") && err.contains("-5"), "{err}");
    assert!(!err.contains("panicked"));
    let o = mpfem().args(["run", "/nonexistent/case.toml"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("/nonexistent/case.toml"));
    let o = mpfem().arg("check").arg("jobs/default.toml").output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn failed_run_exits_1_and_keeps_the_history() {
    // the default job allowed only 3 steps: it stops with an error after three converged steps
    let dir = tmpdir("fail");
    let case = dir.join("fail.toml");
    let text = std::fs::read_to_string("jobs/default.toml").unwrap();
    let text = text.replace("[time]", "[time]\nmax_steps = 3");
    std::fs::write(&case, text).unwrap();
    let o = mpfem().args(["run", "--quiet"]).arg(&case).arg("--out").arg(&dir).output().unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
    let hist = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    assert_eq!(hist.lines().count(), 4, "header + the 3 converged steps are kept");
}

/// A penalty contact far too soft (`penalty = 1e-12`: the walls and discs pass into each other
/// without resistance) is a failed run naming the overlap and the key (issue 23: it reported
/// "completed (solid ratio reached)" with 11 mm of penetration, exit 0); the step that went too
/// far is in the history, its `max_penetration` above half the element size.
#[test]
fn a_contact_far_too_soft_fails_naming_the_penalty() {
    let dir = tmpdir("soft_penalty");
    let case = dir.join("soft.toml");
    let text = std::fs::read_to_string("jobs/compaction/discs_2x2_lateral.toml").unwrap();
    let soft = text.replacen("method = \"penalty\"\n", "method = \"penalty\"\npenalty = 1e-12\n", 1);
    assert_ne!(soft, text, "the job's contact table changed");
    std::fs::write(&case, soft).unwrap();
    let o = mpfem().args(["run", "--quiet", "--no-plots"]).arg(&case).arg("--out").arg(&dir).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("overlap") && err.contains("contact.penalty = 1e-12"), "{err}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
    let hist = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let header: Vec<&str> = hist.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|c| *c == "max_penetration").expect("a max_penetration column");
    let last: f64 = hist.lines().last().unwrap().split(',').nth(col).unwrap().parse().unwrap();
    assert!(last > 1.0, "the last step's penetration {last} mm: not the one that stopped the run");
}

/// A residual that is not finite names where it comes from (issue 23: E = 1e300 failed with
/// "residual history [NaN]" and no hint): the body, its material and Young's modulus.
#[test]
fn a_residual_beyond_the_floating_point_range_names_its_cause() {
    let dir = tmpdir("huge_modulus");
    let case = dir.join("huge.toml");
    let text = std::fs::read_to_string("jobs/compaction/discs_2x2_lateral.toml").unwrap();
    let huge = text.replace("model = \"j2\"", "model = \"elastic\"").replace("youngs_modulus = 64100.0", "youngs_modulus = 1e300").replace("hardening = { preset = \"aluminium_250c\" }\n", "");
    assert!(huge.contains("1e300") && !huge.contains("preset"), "the job's material changed");
    std::fs::write(&case, huge).unwrap();
    let o = mpfem().args(["run", "--quiet", "--no-plots"]).arg(&case).arg("--out").arg(&dir).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("not finite") && err.contains("Young's modulus 1e300 MPa") && err.contains("of body g0_p"), "{err}");
}

/// A log that goes to a file or a pipe (a batch job's stderr) is plain text: no colour codes
/// (before, every level and field name came wrapped in ANSI escapes).
#[test]
fn a_redirected_log_has_no_colour_codes() {
    let dir = tmpdir("plain_log");
    let case = dir.join("case.toml");
    let text = std::fs::read_to_string("jobs/default.toml").unwrap().replace("[time]", "[time]\nmax_steps = 2");
    std::fs::write(&case, text).unwrap();
    let o = mpfem().args(["-vv", "run", "--quiet", "--no-plots"]).arg(&case).arg("--out").arg(&dir).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("DEBUG"), "the debug log is on stderr: {err}");
    assert!(!err.contains('\u{1b}'), "colour codes in a redirected log: {err}");
}

/// One run per output folder (issue 23): a run takes the folder's lock (`.mpfem.lock`, the
/// system's file lock, released however the process ends); a second run into a locked folder
/// exits 2 naming the holder and writes nothing, and runs once the lock is released. Times in
/// the closing lines read as a person writes them (`t = 1 s`, not `1e0` or `1.0000000000000002`).
#[test]
fn a_second_run_into_a_locked_folder_exits_2_naming_the_first() {
    let dir = tmpdir("locked");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let case = root().join("jobs/verification/coulomb_block.toml");
    // the folder held by "another run": this test process, with its pid in the file
    let mut holder = std::fs::OpenOptions::new().read(true).write(true).create(true).truncate(true).open(out.join(".mpfem.lock")).unwrap();
    holder.lock().unwrap();
    std::io::Write::write_all(&mut holder, b"pid 4242 started at unix time 0\n").unwrap();
    let o = mpfem().args(["run", "--quiet", "--no-plots", "--out"]).arg(&out).arg(&case).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("another mpfem run is writing into") && err.contains("pid 4242"), "{err}");
    assert!(!out.join("history.csv").exists(), "the second run wrote into the locked folder");
    drop(holder);
    let o = mpfem().args(["run", "--no-plots", "--out"]).arg(&out).arg(&case).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("completed (end time) t = 1 s in 20 steps"), "{err}");
    let lock = std::fs::read_to_string(out.join(".mpfem.lock")).unwrap();
    assert!(lock.starts_with("pid ") && !lock.contains("4242"), "{lock}");
}

/// faer 0.24's indefinite sparse Cholesky fallback, the intranode Bunch–Kaufman LBLᵀ, failed an
/// index assertion on a tangent of this case — 16 × 16 frictionless elastic discs at a 1.25 mm
/// mesh (the scaling study's strong job with `MESH_SIZE=1.25`, 61,440 unknowns), whose disc
/// columns buckle in the second step. That panic ended the run with exit code 101; caught
/// (`linalg::direct::without_panics`, unit-tested there), it cost the run cut-backs. The
/// unpivoted LDLᵀ now comes before the LBLᵀ (docs/performance.md) and factors those tangents:
/// checked, the run completes its two steps without a cut-back, on LDLᵀ, with no panic and no
/// LBLᵀ in its debug log.
#[test]
fn the_tangents_that_made_faer_panic_are_factored_by_ldlt() {
    let dir = tmpdir("faer_panic");
    let case = dir.join("case.toml");
    let text = r#"title = "16 x 16 discs at 1.25 mm, cholesky"
[[materials]]
name = "alu"
model = "elastic"
youngs_modulus = 64100.0
poisson_ratio = 0.3
[[walls]]
side = "left"
position = 0.0
velocity = 64.0
[[walls]]
side = "right"
position = 160.0
velocity = 64.0
[[walls]]
side = "bottom"
position = 0.0
[[walls]]
side = "top"
position = 160.0
[[grids]]
material = "alu"
nx = 16
ny = 16
shape = "disc"
solid_ratio = 0.76
mesh_size = 1.25
[contact]
method = "penalty"
[time]
end = 0.02
dt = 0.01
dt_max = 0.01
dt_min = 1e-4
[solver]
linear = "cholesky"
[output]
every = 0
"#;
    std::fs::write(&case, text).unwrap();
    let out = mpfem().args(["run", "-vv", "--no-plots", "--threads", "1", "-o"]).arg(dir.join("out")).arg(&case).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code();
    assert!(!err.contains("panicked"), "a panic: {}", err.lines().filter(|l| l.contains("panicked")).collect::<Vec<_>>().join("\n"));
    assert_eq!(code, Some(0), "{}", err.lines().rev().take(5).collect::<Vec<_>>().join("\n"));
    assert!(err.contains("completed (end time) t = 0.02 s in 2 steps") && err.contains(" 0 cut-backs"), "{}", err.lines().rev().take(3).collect::<Vec<_>>().join("\n"));
    assert!(err.contains("factorised as LDLᵀ"), "the case no longer has an indefinite tangent: this test then checks nothing");
    assert!(!err.contains("LBLᵀ"), "the LBLᵀ was reached");
    assert!(dir.join("out/history.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Absurd sizes (issue 23, item 1): a mesh_size of 1e-12 mm or a rectangle 1e20 mm long made
/// the allocator abort (exit 134) while meshing; the element count is estimated first and a
/// mesh that cannot fit in the machine's memory is refused with exit 2 naming the body and
/// its mesh_size, by `check` and by `run`.
#[test]
fn absurd_mesh_sizes_are_refused_before_meshing() {
    let dir = tmpdir("absurd");
    let base = "[[materials]]\nname = \"m\"\nmodel = \"elastic\"\nyoungs_modulus = 1000.0\npoisson_ratio = 0.3\n\n[[bodies]]\nname = \"b\"\nmaterial = \"m\"\nmesh_size = H\nshape = { type = \"rectangle\", origin = [0.0, 0.0], size = [W, 20.0] }\n\n[time]\nend = 1.0\ndt = 0.5\n";
    for (h, w) in [("1e-12", "20.0"), ("1.0", "1e20"), ("1e-9", "20.0")] {
        let case = dir.join("case.toml");
        std::fs::write(&case, base.replace("H", h).replace("W", w)).unwrap();
        for args in [vec!["check"], vec!["run", "--quiet", "--no-plots", "--out"]] {
            let mut cmd = mpfem();
            cmd.args(&args);
            if args[0] == "run" {
                cmd.arg(dir.join("out"));
            }
            let o = cmd.arg(&case).output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "mesh_size {h}, width {w}, {args:?}: {err}");
            assert!(err.contains("bodies[0]") && err.contains("mesh_size") && err.contains("elements"), "{err}");
            assert!(!err.contains("panicked") && !err.contains("memory allocation"), "{err}");
        }
    }
}

/// A valid model that may not be what was meant is warned about by `check` and `run`, naming
/// the body or the key (issue 23, item 1: a mesh of 10⁶ elements or of scaled Jacobian 0.006
/// passed without a word): a sliver triangle whose 3° corner element has a scaled Jacobian near
/// sin 3° = 0.05 (below 0.1), and a disc meshed into more than 500,000 elements (`check` only:
/// the run would take hours). A well-shaped disc of a few hundred elements gets neither.
#[test]
fn check_and_run_warn_of_poor_and_huge_meshes() {
    let dir = tmpdir("warnings");
    let case = |name: &str, shape: &str, mesh: f64| {
        let p = dir.join(format!("{name}.toml"));
        std::fs::write(
            &p,
            format!(
                "[[materials]]\nname = \"m\"\nmodel = \"elastic\"\nyoungs_modulus = 1000.0\npoisson_ratio = 0.3\n\n\
                 [[bodies]]\nname = \"b\"\nmaterial = \"m\"\nmesh_size = {mesh}\nshape = {shape}\n\n\
                 [[walls]]\nside = \"left\"\nposition = 0.0\nvelocity = 1.0\n\n[[walls]]\nside = \"right\"\nposition = 100.0\n\n\
                 [time]\nend = 0.01\ndt = 0.01\n"
            ),
        )
        .unwrap();
        p
    };
    let sliver = case("sliver", "{ type = \"polygon\", vertices = [[10.0, 50.0], [90.0, 50.0], [90.0, 54.2]] }", 2.0);
    let huge = case("huge", "{ type = \"disc\", center = [50.0, 50.0], radius = 40.0 }", 0.06);
    let fine = case("fine", "{ type = \"disc\", center = [50.0, 50.0], radius = 40.0 }", 4.0);
    let said = |args: &[&str], p: &std::path::Path| {
        let o = mpfem().args(args).arg(p).output().unwrap();
        assert!(o.status.code().is_some_and(|c| c <= 1), "{args:?} {}: {}", p.display(), String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let out = dir.join("sliver-run");
    for (args, p) in [(vec!["check"], &sliver), (vec!["run", "--quiet", "--no-plots", "--out", out.to_str().unwrap()], &sliver)] {
        let err = said(&args, p);
        assert!(err.contains("warning") && err.contains("bodies[0] (\"b\")") && err.contains("scaled Jacobian"), "{args:?}: {err}");
    }
    let err = said(&["check"], &huge);
    assert!(err.contains("warning") && err.contains("elements (more than 500000)") && err.contains("mesh_size"), "{err}");
    let err = said(&["check"], &fine);
    assert!(!err.contains("warning"), "a well-shaped small mesh warned of: {err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A particle partly or wholly outside the die (issue "nothing lost, nothing silent", item 3)
/// is refused by `mpfem check` and `mpfem run` with exit 2, naming the body, the wall and how
/// far it reaches past it, before anything is written: a disc of radius 10 mm centred 5 mm
/// inside the left wall reaches 5 mm past it; one centred at x = −50 mm lies wholly beyond it.
/// A disc touching the wall (centred 10 mm inside it) is accepted.
#[test]
fn particles_outside_the_walls_are_refused() {
    let dir = tmpdir("outside");
    let case = |name: &str, x: f64| {
        let p = dir.join(format!("{name}.toml"));
        std::fs::write(
            &p,
            format!(
                "[[materials]]\nname = \"m\"\nmodel = \"elastic\"\nyoungs_modulus = 1000.0\npoisson_ratio = 0.3\n\n\
                 [[bodies]]\nname = \"d\"\nmaterial = \"m\"\nmesh_size = 2.0\nshape = {{ type = \"disc\", center = [{x}, 50.0], radius = 10.0 }}\n\n\
                 [[walls]]\nside = \"left\"\nposition = 0.0\nvelocity = 1.0\n\n[[walls]]\nside = \"right\"\nposition = 100.0\n\n\
                 [[walls]]\nside = \"bottom\"\nposition = 0.0\n\n[[walls]]\nside = \"top\"\nposition = 100.0\n\n\
                 [time]\nend = 0.1\ndt = 0.1\n"
            ),
        )
        .unwrap();
        p
    };
    for (name, x, what, depth) in [("partly", 5.0, "reaches beyond walls[0] (the left wall at 0 mm)", "5.0000 mm past it"), ("wholly", -50.0, "lies wholly beyond walls[0]", "60.0000 mm past it")] {
        let p = case(name, x);
        for cmd in ["check", "run"] {
            let out = dir.join(format!("{name}-{cmd}"));
            let mut c = mpfem();
            c.arg(cmd).arg(&p);
            if cmd == "run" {
                c.args(["--quiet", "--no-plots", "--out"]).arg(&out);
            }
            let o = c.output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{name} {cmd}: {err}");
            assert!(err.contains("bodies[0] (\"d\")") && err.contains(what) && err.contains(depth), "{name} {cmd}: {err}");
            assert!(!out.join("history.csv").exists(), "{name} {cmd}: a run started");
        }
    }
    let p = case("touching", 10.0);
    let o = mpfem().arg("check").arg(&p).output().unwrap();
    assert!(o.status.success(), "a disc touching the wall: {}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}
