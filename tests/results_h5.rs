//! `mpfem run` writes `results.h5` and `results.xdmf`: a small compaction run (2 x 2 discs,
//! coarse mesh, stopped at solid ratio 0.741, output every 2 steps) is read back with the hdf5
//! crate; the shapes, the output steps and their times agree with `history.csv`, the last step
//! is always written, and the XDMF file is well formed with one grid per output step.

use std::path::Path;

mod common;
use common::{mpfem, run_quiet, tmpdir};

const CASE: &str = include_str!("data/discs_coarse.toml");

/// (step, time) of every row of history.csv.
fn history(dir: &Path) -> Vec<(usize, f64)> {
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let s = header.iter().position(|c| *c == "step").unwrap();
    let t = header.iter().position(|c| *c == "time").unwrap();
    lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            (v[s].parse().unwrap(), v[t].parse().unwrap())
        })
        .collect()
}

/// Check that the tags of an XML text nest properly; returns the tag names in order.
fn xml_tags(text: &str) -> Vec<String> {
    let mut stack: Vec<String> = Vec::new();
    let mut names = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find('<') {
        let j = rest[i..].find('>').expect("unterminated tag") + i;
        let tag = &rest[i + 1..j];
        rest = &rest[j + 1..];
        if tag.starts_with('?') || tag.starts_with('!') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            let open = stack.pop().expect("closing tag without an opening one");
            assert_eq!(open, name.trim(), "mismatched closing tag");
            continue;
        }
        let name = tag
            .split_whitespace()
            .next()
            .unwrap()
            .trim_end_matches('/')
            .to_string();
        names.push(name.clone());
        if !tag.ends_with('/') {
            stack.push(name);
        }
    }
    assert!(stack.is_empty(), "unclosed tags {stack:?}");
    names
}

#[test]
fn run_writes_results_h5_and_xdmf_matching_the_history() {
    let dir = tmpdir("coarse");
    let out = run_quiet(&dir, CASE);
    let case = dir.join("case.toml");

    let hist = history(&out);
    assert!(
        hist.len() >= 3,
        "too few steps for the test: {}",
        hist.len()
    );
    let last = *hist.last().unwrap();
    let expected: Vec<(usize, f64)> = hist
        .iter()
        .copied()
        .filter(|(s, _)| s % 2 == 0 || *s == last.0)
        .collect();

    let file = mpfem::h5::open(&out.join("results.h5")).unwrap();
    let steps = file.group("steps").unwrap();
    let mut names = steps.member_names().unwrap();
    names.sort();
    assert_eq!(
        names.len(),
        expected.len(),
        "output steps {names:?} vs history {expected:?}"
    );
    let mut n_nodes = 0;
    for (name, (step, time)) in names.iter().zip(&expected) {
        assert_eq!(name, &format!("{step:06}"));
        let g = steps.group(name).unwrap();
        let t: f64 = g.attr("time").unwrap().read_scalar().unwrap();
        assert!(
            (t - time).abs() <= 1e-9 * time.abs().max(1.0),
            "step {step}: time {t} vs {time}"
        );
        let s: u64 = g.attr("step").unwrap().read_scalar().unwrap();
        assert_eq!(s as usize, *step);

        let x = g.dataset("coordinates").unwrap();
        let cells = g.dataset("cells").unwrap();
        let nn = x.shape()[0];
        let ne = cells.shape()[0];
        assert_eq!(x.shape(), vec![nn, 2]);
        assert_eq!(cells.shape(), vec![ne, 4]);
        assert!(ne > 0 && nn > ne);
        n_nodes = nn;
        let c: Vec<i64> = cells.read_raw().unwrap();
        assert!(
            c.iter().all(|&n| n >= 0 && (n as usize) < nn),
            "cells are 0-based node numbers"
        );
        assert_eq!(g.dataset("displacement").unwrap().shape(), vec![nn, 3]);
        let pid: Vec<i32> = g.dataset("particle_id").unwrap().read_raw().unwrap();
        assert_eq!(pid.len(), ne);
        assert_eq!(pid.iter().copied().max(), Some(3), "four particles");
        assert_eq!(g.dataset("material_id").unwrap().shape(), vec![ne]);
        for f in mpfem::results::CELL_FIELDS {
            let v: Vec<f64> = g.dataset(f).unwrap().read_raw().unwrap();
            assert_eq!(v.len(), ne, "{f}");
            assert!(v.iter().all(|x| x.is_finite()), "{f}");
        }
        let vm: Vec<f64> = g.dataset("von_mises").unwrap().read_raw().unwrap();
        assert!(vm.iter().all(|&v| v >= 0.0));
        assert_eq!(g.dataset("wall_points").unwrap().shape(), vec![8, 2]);
        assert_eq!(g.dataset("wall_cells").unwrap().shape(), vec![4, 2]);
    }
    // the discs are compressed laterally: some plastic strain and stress at the last step
    let g = steps.group(names.last().unwrap()).unwrap();
    let vm: Vec<f64> = g.dataset("von_mises").unwrap().read_raw().unwrap();
    assert!(vm.iter().any(|&v| v > 1.0), "stress at the last step");
    // left wall at x = 10 t
    let wp: Vec<f64> = g.dataset("wall_points").unwrap().read_raw().unwrap();
    assert!(
        (wp[0] - 10.0 * last.1).abs() < 1e-9,
        "left wall at {} vs {}",
        wp[0],
        10.0 * last.1
    );
    // coordinates = reference + displacement: displacement of the first step is small but not 0
    let u: Vec<f64> = g.dataset("displacement").unwrap().read_raw().unwrap();
    assert_eq!(u.len(), 3 * n_nodes);
    assert!(u.iter().skip(2).step_by(3).all(|&z| z == 0.0));

    check_history_table_and_contact_fields(&out, &file, &names);
    check_summary(&out, &case);

    let xdmf = std::fs::read_to_string(out.join("results.xdmf")).unwrap();
    let tags = xml_tags(&xdmf);
    for f in ["velocity", "contact_force", "contact_pressure", "contact_shear", "contact_gap", "contact_status"] {
        assert!(xdmf.contains(&format!("Attribute Name=\"{f}\"")), "{f} in results.xdmf");
    }
    assert_eq!(tags[0], "Xdmf");
    assert!(xdmf.contains("GridType=\"Collection\" CollectionType=\"Temporal\""));
    let times: Vec<f64> = xdmf
        .split("<Grid Name=\"step_")
        .skip(1)
        .map(|b| {
            let v = b.split("<Time Value=\"").nth(1).unwrap();
            v[..v.find('"').unwrap()].parse().unwrap()
        })
        .collect();
    assert_eq!(times.len(), expected.len());
    for (t, (_, h)) in times.iter().zip(&expected) {
        assert!((t - h).abs() <= 1e-9 * h.abs().max(1.0));
    }
    assert!(!out.join("results.xdmf.tmp").exists());
    let walls = std::fs::read_to_string(out.join("walls.xdmf")).unwrap();
    xml_tags(&walls);
    assert_eq!(walls.matches("<Grid Name=\"walls_").count(), expected.len());
    let _ = std::fs::remove_dir_all(&dir);
}

/// summary.json: the final state is the last history row, the phases add up to the wall time,
/// the case file is identified by the SHA-256 of its text.
fn check_summary(out: &Path, case: &Path) {
    use sha2::Digest;
    let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["status"], "completed");
    assert_eq!(s["mpfem_version"], env!("CARGO_PKG_VERSION"));
    let sha: String = sha2::Sha256::digest(std::fs::read(case).unwrap()).iter().map(|x| format!("{x:02x}")).collect();
    assert_eq!(s["case"]["sha256"], sha.as_str());
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let last: Vec<f64> = text.lines().last().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    let col = |name: &str| last[header.iter().position(|c| *c == name).unwrap()];
    let f = &s["final"];
    assert_eq!(f["step"].as_f64().unwrap(), col("step"));
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-12);
    assert!(close(f["solid_ratio"].as_f64().unwrap(), col("solid_ratio")));
    assert!(s["run"]["stop_reason"] == "solid ratio reached" && col("solid_ratio") >= 0.741);
    for (k, side) in ["left", "right", "bottom", "top"].iter().enumerate() {
        assert!(close(f["pressure"][k].as_f64().unwrap(), col(&format!("p_{side}"))), "p_{side}");
        assert!(close(f["force"][k].as_f64().unwrap(), col(&format!("f_{side}"))), "f_{side}");
    }
    let vmax = f["max_particle_volume_error"].as_f64().unwrap();
    let vcol = header.iter().position(|c| *c == "volume_error_max_body").unwrap();
    let hist_max = text.lines().skip(1).map(|l| l.split(',').nth(vcol).unwrap().parse::<f64>().unwrap()).fold(0.0, f64::max);
    assert!(close(vmax, hist_max), "max particle volume error {vmax} vs history {hist_max}");
    // compaction-law fits: the pressing walls, the initial solid ratio below the first step's,
    // and a Heckel fit (3 points above 10 % of the largest pressure in this short run) whose
    // line reproduces the history's last point within its R²
    let fits = &s["fits"];
    assert_eq!(fits["pressure_of"], "left, right");
    let d0 = fits["initial_solid_ratio"].as_f64().unwrap();
    let phi_col = header.iter().position(|c| *c == "solid_ratio").unwrap();
    let phi1: f64 = text.lines().nth(1).unwrap().split(',').nth(phi_col).unwrap().parse().unwrap();
    assert!(d0 > 0.6 && d0 < phi1, "initial solid ratio {d0}, first step {phi1}");
    let h = &fits["heckel"];
    let (k, a, r2) = (h["k"].as_f64().unwrap(), h["a"].as_f64().unwrap(), h["r2"].as_f64().unwrap());
    assert!(h["points"].as_u64().unwrap() >= 3 && (0.0..=1.0).contains(&r2) && k > 0.0, "{h}");
    let p_last = 0.5 * (col("p_left") + col("p_right"));
    let heckel_last = (1.0 / (1.0 - col("solid_ratio"))).ln();
    assert!(((k * p_last + a) - heckel_last).abs() < 0.05 * heckel_last, "Heckel line {} vs {heckel_last}", k * p_last + a);
    let p = &s["phases"];
    let total = p["total"].as_f64().unwrap();
    let sum: f64 = ["contact_search", "contact_assembly", "element_assembly", "linear_solve", "output", "other"].iter().map(|k| p[k].as_f64().unwrap()).sum();
    assert!((sum - total).abs() <= 1e-9 * total, "phases {sum} vs total {total}");
    assert!(p["output"].as_f64().unwrap() > 0.0 && p["linear_solve"].as_f64().unwrap() > 0.0);
    let pct: f64 = p["percent"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).sum();
    assert!((pct - 100.0).abs() < 1e-6, "shares add up to {pct} %");
}

/// The contact node fields of an output step, their shapes checked: (nodes, pressure, gap,
/// status, force (n × 3), wall force (n × 4)).
#[allow(clippy::type_complexity)]
fn contact_fields(g: &hdf5::Group) -> (usize, Vec<f64>, Vec<f64>, Vec<i32>, Vec<f64>, Vec<f64>) {
    let nn = g.dataset("coordinates").unwrap().shape()[0];
    let p: Vec<f64> = g.dataset("contact_pressure").unwrap().read_raw().unwrap();
    let gap: Vec<f64> = g.dataset("contact_gap").unwrap().read_raw().unwrap();
    let status: Vec<i32> = g.dataset("contact_status").unwrap().read_raw().unwrap();
    let force: Vec<f64> = g.dataset("contact_force").unwrap().read_raw().unwrap();
    let wall: Vec<f64> = g.dataset("wall_force").unwrap().read_raw().unwrap();
    assert_eq!((p.len(), gap.len(), status.len(), force.len(), wall.len()), (nn, nn, nn, 3 * nn, 4 * nn));
    (nn, p, gap, status, force, wall)
}

/// `/history` repeats history.csv; the contact node fields are consistent with the wall forces
/// of the history; the velocity is the step's mean velocity.
fn check_history_table_and_contact_fields(out: &Path, file: &hdf5::File, names: &[String]) {
    // history.csv as numbers
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let csv: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    let h = file.dataset("history").unwrap();
    assert_eq!(h.shape(), vec![csv.len(), header.len()]);
    let cols: Vec<hdf5::types::VarLenUnicode> = h.attr("columns").unwrap().read_raw().unwrap();
    let cols: Vec<String> = cols.iter().map(|c| c.as_str().to_string()).collect();
    assert_eq!(cols, header, "history columns in results.h5 and history.csv");
    let table: Vec<f64> = h.read_raw().unwrap();
    let m = header.len();
    for (i, row) in csv.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            // history.csv keeps 10 significant digits: 1e-9 relative
            let w = table[i * m + j];
            assert!((w - v).abs() <= 1e-9 * v.abs() + 1e-300, "history row {i} column {}: h5 {w} vs csv {v}", header[j]);
        }
    }
    let col = |name: &str| header.iter().position(|c| c == name).unwrap();
    let (c_step, c_dt) = (col("step"), col("dt"));
    let c_force = [col("f_left"), col("f_right"), col("f_bottom"), col("f_top")];

    let steps = file.group("steps").unwrap();
    let mut active_last = 0;
    let mut u_prev: Option<(usize, Vec<f64>)> = None;
    let mut velocity_checked = false;
    for name in names {
        let g = steps.group(name).unwrap();
        let step: u64 = g.attr("step").unwrap().read_scalar().unwrap();
        let row = (0..csv.len()).find(|&i| table[i * m + c_step] == step as f64).unwrap();
        let (nn, p, gap, status, force, wall) = contact_fields(&g);
        // the node's pressure is positive exactly where it is in contact (frictionless: sliding,
        // 1), on the node of a pair and on the ends of its segment alike; a penetrating node
        // (penalty: gap < 0) is in contact
        for n in 0..nn {
            assert!((0..=1).contains(&status[n]), "status {} at node {n}", status[n]);
            assert_eq!(status[n] > 0, p[n] > 0.0, "node {n}: status {} pressure {}", status[n], p[n]);
            if gap[n] < 0.0 {
                assert!(status[n] > 0, "node {n} penetrates by {} and is open", -gap[n]);
            }
        }
        // the sum of the nodal wall forces is the wall force of the history (1e-8 relative,
        // the check; the values are summed in a different order)
        let f_hist: Vec<f64> = c_force.iter().map(|&c| table[row * m + c]).collect();
        let scale = f_hist.iter().fold(0.0f64, |a, f| a.max(f.abs()));
        for k in 0..4 {
            let sum: f64 = (0..nn).map(|n| wall[4 * n + k]).sum();
            assert!((sum - f_hist[k]).abs() <= 1e-8 * f_hist[k].abs().max(1e-300) || sum == f_hist[k], "step {step} wall {k}: nodal sum {sum} vs history {}", f_hist[k]);
        }
        // Newton's third law: particle-particle contact forces cancel, so the contact forces
        // on all nodes add up to the (frictionless) wall forces on the particles:
        // x: f_left − f_right, y: f_bottom − f_top (1e-8 of the largest wall force)
        let fx: f64 = (0..nn).map(|n| force[3 * n]).sum();
        let fy: f64 = (0..nn).map(|n| force[3 * n + 1]).sum();
        assert!((fx - (f_hist[0] - f_hist[1])).abs() <= 1e-8 * scale, "step {step}: Σ contact fx {fx} vs {}", f_hist[0] - f_hist[1]);
        assert!((fy - (f_hist[2] - f_hist[3])).abs() <= 1e-8 * scale, "step {step}: Σ contact fy {fy} vs {}", f_hist[2] - f_hist[3]);
        // the contact force on the nodes that touch a wall is that wall's push (the walls
        // push inwards: +x left, −x right, +y bottom, −y top); at solid ratio ≤ 0.741 no node
        // touching a wall touches another disc, so the sums are the history's wall forces
        for (k, (c, sign)) in [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)].into_iter().enumerate() {
            let sum: f64 = (0..nn).filter(|&n| wall[4 * n + k] > 0.0).map(|n| sign * force[3 * n + c]).sum();
            assert!((sum - f_hist[k]).abs() <= 1e-8 * scale, "step {step} wall {k}: contact force on its nodes {sum} vs history {}", f_hist[k]);
        }
        active_last = status.iter().filter(|&&s| s > 0).count();
        // velocity = (u_s − u_{s−1}) / Δt_s where two consecutive steps are in the file
        let u: Vec<f64> = g.dataset("displacement").unwrap().read_raw().unwrap();
        let v: Vec<f64> = g.dataset("velocity").unwrap().read_raw().unwrap();
        assert_eq!(v.len(), 3 * nn);
        if let Some((s_prev, up)) = &u_prev {
            if *s_prev + 1 == step as usize {
                let dt = table[row * m + c_dt];
                for i in 0..3 * nn {
                    let expect = (u[i] - up[i]) / dt;
                    assert!((v[i] - expect).abs() <= 1e-9 * (expect.abs() + 1.0), "velocity dof {i}: {} vs {expect}", v[i]);
                }
                velocity_checked = true;
            }
        }
        u_prev = Some((step as usize, u));
    }
    assert!(active_last > 0, "contacts at the last output step");
    assert!(velocity_checked, "two consecutive steps in the file (the last step follows an output step)");
}

#[test]
fn output_every_zero_writes_no_results_and_negative_is_an_error() {
    let dir = tmpdir("every");
    let case = dir.join("case.toml");
    let bad = CASE.replace("every = 2", "every = -1");
    std::fs::write(&case, bad).unwrap();
    let o = mpfem()
        .args(["check"])
        .arg(&case)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("output.every"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run killed with SIGKILL while it writes leaves a `results.h5` that opens and holds every
/// step that `results.xdmf` named at the moment of the kill.
#[test]
fn killed_run_leaves_a_readable_results_file() {
    let dir = tmpdir("kill");
    let case = dir.join("case.toml");
    let long = CASE
        .replace("every = 2", "every = 1")
        .replace("solid_ratio = 0.741\n", "solid_ratio = 0.9\n")
        .replace("dt_max = 0.1", "dt_max = 0.01")
        .replace("dt = 0.05", "dt = 0.01");
    std::fs::write(&case, long).unwrap();
    let out = dir.join("out");
    let mut child = mpfem()
        .args(["run", "--quiet", "--out"])
        .arg(&out)
        .arg(&case)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let xdmf = out.join("results.xdmf");
    let started = std::time::Instant::now();
    let count = |p: &Path| {
        std::fs::read_to_string(p).map_or(0, |t| t.matches("<Grid Name=\"step_").count())
    };
    while count(&xdmf) < 3 {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it could be killed"
        );
        assert!(
            started.elapsed().as_secs() < 60,
            "no output steps after 60 s"
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let text = std::fs::read_to_string(&xdmf).unwrap();
    xml_tags(&text);
    let named = text.matches("<Grid Name=\"step_").count();
    assert!(named >= 3);
    let file = mpfem::h5::open(&out.join("results.h5")).unwrap();
    let steps = file.group("steps").unwrap();
    for block in text.split("<Grid Name=\"step_").skip(1) {
        let name = &block[..6];
        let g = steps.group(name).unwrap();
        let x: Vec<f64> = g.dataset("coordinates").unwrap().read_raw().unwrap();
        let vm: Vec<f64> = g.dataset("von_mises").unwrap().read_raw().unwrap();
        assert!(!x.is_empty() && !vm.is_empty());
        let _: f64 = g.attr("time").unwrap().read_scalar().unwrap();
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The barrier contact writes the same node fields (`Simulation::barrier_nodal`): the coarse
/// 2 × 2 discs with the barrier and friction μ = 0.2 between the discs (frictionless walls),
/// to solid ratio 0.85, every step. At every output step: a node has a gap (a pair within d̂)
/// only where the barrier pushes it, and every gap is positive (no crossing); statuses are
/// 0 / 1 / 2 and a node with a pressure has a status; the nodal wall forces add up to the
/// history's wall forces (1e-8 relative: the same terms summed in another order); and the
/// contact forces on all nodes (barrier and friction) add up to the walls' push on the
/// particles (1e-8 of the largest wall force: the particles' forces on each other cancel,
/// Newton's third law, and the walls are frictionless). Some nodes stick at some step.
#[test]
fn barrier_run_writes_contact_fields_matching_the_history() {
    let dir = tmpdir("barrier_fields");
    let case = CASE
        .replace("method = \"penalty\"\ncontact = \"sliding\"", "method = \"barrier\"\ncontact = \"rubbing\"\nfriction = 0.2")
        .replace("solid_ratio = 0.741\n", "solid_ratio = 0.85\n")
        .replace("every = 2", "every = 1");
    assert!(case.contains("friction = 0.2") && case.contains("solid_ratio = 0.85"));
    let out = run_quiet(&dir, &case);
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    let col = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let file = mpfem::h5::open(&out.join("results.h5")).unwrap();
    let steps = file.group("steps").unwrap();
    let names = steps.member_names().unwrap();
    assert_eq!(names.len(), rows.len(), "one output step per step");
    let (mut sticking, mut touching) = (0, 0);
    for (name, row) in names.iter().zip(&rows) {
        let g = steps.group(name).unwrap();
        let (nn, p, gap, status, force, wall) = contact_fields(&g);
        for n in 0..nn {
            assert!((0..=2).contains(&status[n]), "step {name}: status {} at node {n}", status[n]);
            assert!(p[n] >= 0.0 && p[n].is_finite(), "step {name}: pressure {} at node {n}", p[n]);
            assert_eq!(p[n] > 0.0, status[n] > 0, "step {name} node {n}: pressure {} status {}", p[n], status[n]);
            if gap[n].is_finite() {
                assert!(gap[n] > 0.0, "step {name} node {n}: gap {}", gap[n]);
                assert!(status[n] > 0, "step {name} node {n}: a pair within d̂ without force");
            }
        }
        sticking += status.iter().filter(|&&s| s == 2).count();
        touching += status.iter().filter(|&&s| s > 0).count();
        let f_hist: Vec<f64> = ["f_left", "f_right", "f_bottom", "f_top"].iter().map(|c| row[col(c)]).collect();
        let scale = f_hist.iter().fold(0.0f64, |a, f| a.max(f.abs()));
        for k in 0..4 {
            let sum: f64 = (0..nn).map(|n| wall[4 * n + k]).sum();
            assert!((sum - f_hist[k]).abs() <= 1e-8 * f_hist[k].abs().max(1e-300) || sum == f_hist[k], "step {name} wall {k}: nodal sum {sum} vs history {}", f_hist[k]);
        }
        let fx: f64 = (0..nn).map(|n| force[3 * n]).sum();
        let fy: f64 = (0..nn).map(|n| force[3 * n + 1]).sum();
        assert!((fx - (f_hist[0] - f_hist[1])).abs() <= 1e-8 * scale, "step {name}: Σ contact fx {fx} vs {}", f_hist[0] - f_hist[1]);
        assert!((fy - (f_hist[2] - f_hist[3])).abs() <= 1e-8 * scale, "step {name}: Σ contact fy {fy} vs {}", f_hist[2] - f_hist[3]);
    }
    assert!(touching > 0 && sticking > 0, "{touching} nodes in contact, {sticking} sticking over the run");
    let _ = std::fs::remove_dir_all(&dir);
}
