//! ParaView opens the results: `pvpython` (Debian's `paraview` package, headless under
//! `xvfb-run`) opens `./results.xdmf` of a small compaction run, checks the time steps against
//! `history.csv` and the field names, colours by von Mises stress at the last step and saves a
//! PNG. Skipped (with a message) only when `pvpython` is not installed and `CI` is not set;
//! under CI a missing `pvpython` fails the test.

use std::path::Path;
use std::process::Command;

mod common;
use common::{run_quiet, tmpdir};

const CASE: &str = include_str!("data/discs_coarse.toml");

const SCRIPT: &str = r#"
import os, sys
from paraview.simple import *
expected = [float(t) for t in sys.argv[1].split(",")]
r = OpenDataFile("./results.xdmf")
if r is None:
    sys.exit("pvpython: cannot open ./results.xdmf")
r.UpdatePipelineInformation()
times = list(r.TimestepValues)
if len(times) != len(expected) or any(abs(a - b) > 1e-9 * max(1.0, abs(b)) for a, b in zip(times, expected)):
    sys.exit("pvpython: time steps %r, expected %r" % (times, expected))
r.UpdatePipeline(times[-1])
cells = set(r.CellData.keys())
points = set(r.PointData.keys())
need = {"stress_xx", "stress_yy", "stress_xy", "stress_zz", "von_mises", "pressure",
        "eq_plastic_strain", "eq_creep_strain", "particle_id", "material_id"}
need_points = {"displacement", "velocity", "contact_force", "contact_pressure", "contact_shear", "contact_gap", "contact_status"}
if not need <= cells or not need_points <= points:
    sys.exit("pvpython: missing arrays: cells %r, points %r" % (sorted(need - cells), sorted(need_points - points)))
plo, phi = r.PointData["contact_pressure"].GetRange()
if not (plo >= 0.0 and phi > 0.0):
    sys.exit("pvpython: contact_pressure range %r at the last step" % ((plo, phi),))
lo, hi = r.CellData["von_mises"].GetRange()
if not (0.0 <= lo < hi):
    sys.exit("pvpython: von_mises range %r at the last step" % ((lo, hi),))
view = GetActiveViewOrCreate("RenderView")
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = times[-1]
d = Show(r, view)
ColorBy(d, ("CELLS", "von_mises"))
d.RescaleTransferFunctionToDataRange(False, True)
d.SetScalarBarVisibility(view, True)
view.InteractionMode = "2D"
ResetCamera(view)
SaveScreenshot("./von_mises.png", view, ImageResolution=[800, 600])
if not os.path.exists("./von_mises.png") or os.path.getsize("./von_mises.png") == 0:
    sys.exit("pvpython: no PNG written")
print("pvpython: %d time steps, von_mises %.6g..%.6g MPa, von_mises.png written" % (len(times), lo, hi))
"#;

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|p| p.join(program).is_file()))
}

/// Times of the history rows that are output steps (every 2 steps and the last one).
fn output_times(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let s = header.iter().position(|c| *c == "step").unwrap();
    let t = header.iter().position(|c| *c == "time").unwrap();
    let rows: Vec<(usize, String)> = lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            (v[s].parse().unwrap(), v[t].to_string())
        })
        .collect();
    let last = rows.last().map(|r| r.0);
    rows.into_iter()
        .filter(|(s, _)| s % 2 == 0 || Some(*s) == last)
        .map(|(_, t)| t)
        .collect()
}

#[test]
fn paraview_opens_results_xdmf() {
    let ci = std::env::var_os("CI").is_some_and(|v| !v.is_empty());
    if !on_path("pvpython") || !on_path("xvfb-run") {
        assert!(!ci, "CI is set but pvpython or xvfb-run is missing: run scripts/setup.sh (it installs paraview, python3-paraview, xvfb, xauth)");
        eprintln!("SKIPPED paraview_opens_results_xdmf: pvpython or xvfb-run not installed (scripts/setup.sh installs them)");
        return;
    }
    let dir = tmpdir("run");
    let out = run_quiet(&dir, CASE);
    let times = output_times(&out);
    assert!(times.len() >= 2);
    std::fs::write(out.join("check_results.py"), SCRIPT).unwrap();
    // xvfb-run sometimes hands pvpython a display whose X server does not accept the
    // connection yet ("bad X server connection", seen in ~2 of 10 cold starts on Debian 12):
    // that is the harness, not ParaView reading our files, so retry it (at most 3 attempts)
    let mut attempt = 0;
    let o = loop {
        attempt += 1;
        let o = Command::new("xvfb-run")
            .args(["-a", "-e", "xvfb.log", "pvpython", "check_results.py"])
            .arg(times.join(","))
            .current_dir(&out)
            .output()
            .unwrap();
        let x_failed = String::from_utf8_lossy(&o.stderr).contains("bad X server connection");
        if !(x_failed && attempt < 3) {
            break o;
        }
        eprintln!("pvpython: the virtual X server refused the connection (attempt {attempt}), retrying");
        std::thread::sleep(std::time::Duration::from_secs(1));
    };
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success(),
        "pvpython failed ({}):\n{stdout}\n{stderr}",
        o.status
    );
    assert!(
        stdout.contains("von_mises.png written"),
        "{stdout}\n{stderr}"
    );
    let png = std::fs::read(out.join("von_mises.png")).unwrap();
    assert!(png.len() > 1000 && png.starts_with(b"\x89PNG"), "not a PNG");
    let _ = std::fs::remove_dir_all(&dir);
}
