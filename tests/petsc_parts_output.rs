//! `mpirun -n R mpfem run` on owned + ghost parts (`[solver] linear = "petsc"`, the barrier
//! contact: each rank holds its own particles and their neighbours; issue 21): what it writes
//! against the serial run with faer on the whole model.
//!
//! - 2 ranks, the 3 × 3 elastic discs with the barrier (0.76 → 0.80, 7 steps, results every 2
//!   steps, a checkpoint every 4): every `history.csv` column but the Newton residual (a
//!   round-off figure of the linear solver: MUMPS's and faer's differ) equals the serial run's
//!   to 1e-8 of the column's largest |value| (the tolerance for a direct distributed
//!   solve; measured 1e-12 and below), and every dataset of every output step of `results.h5`
//!   — coordinates, cells, stresses, the contact's nodal pressure, gap, status and forces,
//!   the walls — too (the same NaN pattern of the gaps): rank 0 gathers the parts onto the
//!   whole model's numbering.
//! - The 2-rank checkpoint continues on 3 ranks, and the serial run's checkpoint on 2 ranks, to
//!   the uninterrupted serial history (1e-8): a restart takes each process's share of the
//!   checkpoint's whole state, whatever the rank count that wrote it.
//! - 2 × 2 discs from solid ratio 0.45 (no disc within the ghosts' reach of another process's
//!   at the start) pressed laterally to 0.62 on 2 ranks: the discs come within the contact
//!   reach of bodies that are not their ghosts, the step is made again on new parts (at least
//!   once, `summary.json`'s `run.partition.repartitions`), and the history equals the serial
//!   run's to 1e-8 (measured 1e-10: the parts miss no contact). The same from a 3 × 3 grid
//!   with the jam test from solid ratio 0.5 (`[stop] jam_solid_ratio`): the parts are made
//!   again at steps whose walls carry load, which must not end the run as a jam (it did —
//!   stop reason "jammed" — in this case and in the 64-polygon robustness case on 2 ranks,
//!   before the jam test left that failure alone); its history is not
//!   compared (the loose 3 × 3 grid takes another branch with faer's round-off than with
//!   MUMPS's, serially too).
//!
//! - Implicit dynamics (HHT-α, discs heavy enough that the kinetic energy reaches a tenth of
//!   the walls' work and more): the 3 × 3 discs on 2 ranks against the serial run, history
//!   (1e-8 of each column but the residual and the volume errors, which are compared to 1e-10
//!   absolute: a volume error of 1e-5 reads the round-off of the displacements 1e4 times
//!   larger relative to itself), `results.h5` with the velocities (1e-8), and the 2-rank
//!   checkpoint (with u, v, a and the HHT forces of every node) continued on 3 ranks; then the
//!   loose 3 × 3 grid, whose parts are grown again mid-run carrying the dynamics to the new
//!   ghosts, to the same tolerances.
//!
//! - Cohering discs (`contact = "cohering"`: 36 nodes tied from step 4): 2 ranks against the
//!   serial run (history and `results.h5` from step 2, the tied status included, 1e-8; the
//!   volume errors 1e-10 absolute), and the 2-rank checkpoint (its ties gathered into the
//!   whole model's numbering of nodes and edges) continued on 3 ranks, and the serial one on 2.
//!
//! - Re-meshing (`[remesh]` with `min_scaled_jacobian = 0.828`, just below the discs' first
//!   meshes' 0.832: all nine discs are re-meshed at step 3, each by its owner): 2 ranks against
//!   the serial run (history and `results.h5`, whose steps after the re-mesh carry the new
//!   meshes, 1e-8), the 2-rank checkpoint written after the re-mesh (with the new meshes'
//!   quality, the re-mesh baselines) continued on 3 ranks, and
//!   the serial one on 2 ranks and serially (a checkpoint's re-meshed particles have their
//!   configuration when re-meshed as their reference, beside the others' original one).
//!
//! Needs Open MPI's `mpirun` and PETSc (`scripts/setup.sh` installs both).
#![cfg(feature = "petsc")]

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::{mpfem, mpirun, read_csv, tmpdir};

const CASE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mpi_discs_3x3_pcg.toml");
const TOL: f64 = 1e-8;

/// `mpfem run case --out out` serially or on `ranks` ranks, with `extra` arguments.
fn run(case: &Path, ranks: Option<usize>, out: &Path, extra: &[&str]) -> Output {
    let mut cmd = match ranks {
        None => mpfem(),
        Some(n) => mpirun(n),
    };
    cmd.arg("run").arg(case).arg("--out").arg(out).args(["--no-plots", "--threads", "1"]).args(extra);
    let o = cmd.output().unwrap_or_else(|e| panic!("cannot start {:?} (bash scripts/setup.sh installs Open MPI): {e}", cmd.get_program()));
    assert!(o.status.success(), "{ranks:?} ranks, {}: {:?}\nstderr: {}", case.display(), o.status, String::from_utf8_lossy(&o.stderr));
    o
}

/// The largest difference of `b` from `a` relative to `a`'s largest |value| (NaN where both
/// are NaN counts as equal; a NaN in one only is infinitely far).
fn relative(a: &[f64], b: &[f64]) -> f64 {
    relative_at_least(a, b, 1e-300)
}

/// [`relative`] with the scale at least `floor`.
fn relative_at_least(a: &[f64], b: &[f64], floor: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a.iter().filter(|v| v.is_finite()).fold(0.0f64, |m, v| m.max(v.abs())).max(floor);
    a.iter()
        .zip(b)
        .map(|(x, y)| match (x.is_nan(), y.is_nan()) {
            (true, true) => 0.0,
            (false, false) => (x - y).abs() / scale,
            _ => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}

/// The worst relative difference over the history columns but the residual; asserts the same
/// columns and steps.
fn history_difference(reference: &Path, other: &Path, what: &str) -> f64 {
    history_difference_but(reference, other, what, &[])
}

/// [`history_difference`] with the columns `absolute` compared to [`VOLUME_TOL`] absolute.
fn history_difference_but(reference: &Path, other: &Path, what: &str, absolute: &[&str]) -> f64 {
    history_difference_except(reference, other, what, absolute, &[])
}

/// [`history_difference_but`] without the columns `skipped`.
fn history_difference_except(reference: &Path, other: &Path, what: &str, absolute: &[&str], skipped: &[&str]) -> f64 {
    let (h0, r0) = read_csv(&reference.join("history.csv"));
    let (h1, r1) = read_csv(&other.join("history.csv"));
    assert_eq!(h0, h1, "{what}: columns");
    assert_eq!(r0.len(), r1.len(), "{what}: {} steps, the reference {}", r1.len(), r0.len());
    let mut worst = 0.0f64;
    for (c, name) in h0.iter().enumerate() {
        if name == "residual" || skipped.contains(&name.as_str()) {
            continue;
        }
        let a: Vec<f64> = r0.iter().map(|r| r[c]).collect();
        let b: Vec<f64> = r1.iter().map(|r| r[c]).collect();
        if absolute.contains(&name.as_str()) {
            let d = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(d <= VOLUME_TOL, "{what}: history column {name} differs by {d:.2e} > {VOLUME_TOL:e} (absolute)");
            continue;
        }
        let d = relative(&a, &b);
        assert!(d <= TOL, "{what}: history column {name} differs by {d:.2e} > {TOL:e}");
        worst = worst.max(d);
    }
    worst
}

/// The worst relative difference of the columns of two `probes.csv` (each column on the scale
/// of its largest |value|), asserting the same columns and steps and each column within
/// [`TOL`].
fn probes_difference(reference: &Path, other: &Path) -> f64 {
    let (h0, r0) = read_csv(&reference.join("probes.csv"));
    let (h1, r1) = read_csv(&other.join("probes.csv"));
    assert_eq!(h0, h1, "probes.csv: columns");
    assert!(h0.len() > 2 && r0.len() > 2 && r0.len() == r1.len(), "probes.csv: {} and {} steps", r0.len(), r1.len());
    let mut worst = 0.0f64;
    for (c, name) in h0.iter().enumerate() {
        let a: Vec<f64> = r0.iter().map(|r| r[c]).collect();
        let b: Vec<f64> = r1.iter().map(|r| r[c]).collect();
        let d = relative(&a, &b);
        assert!(d <= TOL, "probes.csv column {name} differs by {d:.2e} > {TOL:e}");
        worst = worst.max(d);
    }
    worst
}

/// Every dataset of every output step of two `results.h5`, read as numbers: the worst
/// relative difference (asserting the same steps and datasets), and how many were compared.
fn results_difference(reference: &Path, other: &Path) -> (f64, usize) {
    let (fa, fb) = (hdf5::File::open(reference.join("results.h5")).expect("results.h5"), hdf5::File::open(other.join("results.h5")).expect("results.h5"));
    let (sa, sb) = (fa.group("steps").expect("/steps"), fb.group("steps").expect("/steps"));
    let steps = sa.member_names().expect("steps");
    assert_eq!(steps, sb.member_names().expect("steps"), "output steps");
    // every step's Δt (the reference's history)
    let (h, rows) = read_csv(&reference.join("history.csv"));
    let col = h.iter().position(|c| c == "dt").expect("a dt column");
    let dts: Vec<f64> = rows.iter().map(|r| r[col]).collect();
    assert!(steps.len() >= 3, "only {} output steps", steps.len());
    let (mut worst, mut n) = (0.0f64, 0);
    for s in &steps {
        let (ga, gb) = (sa.group(s).expect("step"), sb.group(s).expect("step"));
        let names = ga.member_names().expect("datasets");
        assert_eq!(names, gb.member_names().expect("datasets"), "step {s}: datasets");
        // (the shear traction is compared on the scale of the pressure: where the contact
        // is frictionless it is round-off of the pressure's size; the velocity, the step's
        // increment over its Δt, on the scale of the displacement over Δt: the last step,
        // shortened to land on the target, has a Δt a hundred times below the others)
        let largest = |name: &str| -> f64 {
            let v: Vec<f64> = ga.dataset(name).and_then(|d| d.read_raw()).unwrap_or_default();
            v.iter().filter(|v| v.is_finite()).fold(1e-300f64, |m, v| m.max(v.abs()))
        };
        let pressure = largest("contact_pressure");
        let step: usize = s.parse().expect("a step number");
        let dt = dts.get(step.wrapping_sub(1)).copied().unwrap_or(f64::INFINITY);
        let velocity = largest("displacement") / dt;
        for d in &names {
            let (da, db) = (ga.dataset(d).expect("dataset"), gb.dataset(d).expect("dataset"));
            assert_eq!(da.shape(), db.shape(), "step {s}: {d}: shape");
            let (a, b): (Vec<f64>, Vec<f64>) = (da.read_raw().expect("numbers"), db.read_raw().expect("numbers"));
            let floor = match d.as_str() {
                "contact_shear" => pressure,
                "velocity" => velocity,
                _ => 1e-300,
            };
            let diff = relative_at_least(&a, &b, floor);
            assert!(diff <= TOL, "results.h5 step {s}: {d} differs by {diff:.2e} > {TOL:e}");
            worst = worst.max(diff);
            n += 1;
        }
    }
    (worst, n)
}

/// The history up to the checkpoint at step `step` in a fresh folder with the checkpoint (as
/// a stopped run leaves them).
fn stopped_at(from: &Path, to: &Path, step: usize) {
    std::fs::create_dir_all(to).unwrap();
    std::fs::copy(from.join("checkpoint.h5"), to.join("checkpoint.h5")).unwrap();
    let h = std::fs::read_to_string(from.join("history.csv")).unwrap();
    assert!(h.lines().count() > step + 1, "the run has only {} steps", h.lines().count() - 1);
    let kept: Vec<&str> = h.lines().take(step + 1).collect();
    std::fs::write(to.join("history.csv"), kept.join("\n") + "\n").unwrap();
}

/// The step of the last checkpoint of the run in `out`, made every `every` steps: asserts that
/// the run went on after it (a run that ends on a checkpoint leaves nothing to continue, and
/// its step count moves with the solver's paths: choose another `checkpoint_every` then).
fn last_checkpoint(out: &Path, every: usize) -> usize {
    let steps = std::fs::read_to_string(out.join("history.csv")).unwrap().lines().count() - 1;
    let k = steps / every * every;
    assert!(k >= 1 && k < steps, "the run in {} has {steps} steps: its last checkpoint (every {every}) is at its end or missing", out.display());
    k
}

/// The checkpoint of the run in `from` (written at `step`, its last) continued in `to` with
/// `case` on `ranks` ranks (serially with None), with `--allow-case-change` when `changed`
/// (a checkpoint written with another case).
fn restarted(from: &Path, step: usize, to: &Path, case: &Path, ranks: Option<usize>, changed: bool) {
    stopped_at(from, to, step);
    let restart = to.to_str().unwrap();
    let args: Vec<&str> = if changed { vec!["--quiet", "--allow-case-change", "--restart", restart] } else { vec!["--quiet", "--restart", restart] };
    run(case, ranks, to, &args);
}

/// The MPI tests' 3 × 3 case with the barrier and faer (`edit` applied to it) written as
/// `serial.toml` in `dir`, and the same with `linear = "petsc"` as `parts.toml`; asserts that
/// each of `made` is in the edited case.
fn serial_and_parts(dir: &Path, edit: impl Fn(String) -> String, made: &[&str]) -> (PathBuf, PathBuf) {
    let text = std::fs::read_to_string(CASE).expect("case").replace("method = \"penalty\"", "method = \"barrier\"").replace("linear = \"pcg\"\npreconditioner = \"schwarz\"\n", "");
    let serial_text = edit(text);
    for m in made.iter().chain(&["method = \"barrier\""]) {
        assert!(serial_text.contains(m), "the case moved: {m} not made");
    }
    assert!(!serial_text.contains("schwarz"), "the case moved: its solver table");
    let (serial, parts) = (dir.join("serial.toml"), dir.join("parts.toml"));
    std::fs::write(&serial, &serial_text).unwrap();
    std::fs::write(&parts, serial_text.replacen("[solver]\n", "[solver]\nlinear = \"petsc\"\n", 1)).unwrap();
    (serial, parts)
}

#[test]
fn parts_write_the_serial_results_and_restart_on_other_rank_counts() {
    let dir = tmpdir("parts");
    // (with probes in discs of both ranks, a point and a node, and a displacement group)
    let output = "[output]\nevery = 2\ncheckpoint_every = 3\ncheckpoint_minutes = 0\nprobes = [{ name = \"q\", point = [83.0, 84.0] }, { name = \"n\", body = \"g0_p0\", node = 2 }]\ndisplacements = [\"g0_p4.boundary\"]";
    let (serial_case, parts_case) = serial_and_parts(&dir, |t| t.replace("[output]\nevery = 0", output), &["every = 2", "probes", "g0_p4.boundary"]);

    let serial = dir.join("serial");
    run(&serial_case, None, &serial, &["--quiet"]);
    let two = dir.join("two");
    let o = run(&parts_case, Some(2), &two, &[]);
    let said = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(said.contains("2 MPI ranks (each its own particles and their neighbours"), "not a run on parts: {said}");
    let worst = history_difference(&serial, &two, "2 ranks");
    let (results, n) = results_difference(&serial, &two);
    // (rank 0 keeps no mesh between the writes: the probes are read on the whole model made of
    // the meshes gathered at each step)
    let probes = probes_difference(&serial, &two);
    println!("parts on 2 ranks: history {worst:.2e}, results.h5 {results:.2e} over {n} datasets, probes.csv {probes:.2e}, from the serial faer run");

    // the 2-rank checkpoint (its last, every 3 steps) on 3 ranks
    let three = dir.join("three");
    restarted(&two, last_checkpoint(&two, 3), &three, &parts_case, Some(3), false);
    let worst = history_difference(&serial, &three, "2 ranks' checkpoint on 3");
    println!("the 2-rank checkpoint continued on 3 ranks: {worst:.2e} from the serial run");
    // the serial run's last checkpoint (the whole model) on 2 ranks' parts
    let from_serial = dir.join("from-serial");
    restarted(&serial, last_checkpoint(&serial, 3), &from_serial, &parts_case, Some(2), true);
    let worst = history_difference(&serial, &from_serial, "the serial checkpoint on 2 ranks");
    println!("the serial checkpoint continued on 2 ranks: {worst:.2e} from the serial run");
    let _ = std::fs::remove_dir_all(&dir);
}

/// How often the run in `out` made its parts again (`summary.json`'s
/// `run.partition.repartitions`), asserting at least once and that it reached its solid ratio.
fn made_again_to_target(out: &Path, what: &str) -> u64 {
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).expect("summary.json")).expect("summary.json parses");
    assert_eq!(summary["run"]["stop_reason"].as_str(), Some("solid ratio reached"), "{what}: {}", summary["run"]);
    let remade = summary["run"]["partition"]["repartitions"].as_u64().expect("run.partition.repartitions");
    assert!(remade >= 1, "{what}: the parts were never made again: the case no longer tests it");
    remade
}

#[test]
fn parts_are_made_again_when_the_particles_move_out_of_their_ghosts() {
    let dir = tmpdir("remade");
    let (serial_case, parts_case) = serial_and_parts(
        &dir,
        |t| t.replace("nx = 3\nny = 3\n", "nx = 2\nny = 2\n").replace("solid_ratio = 0.76\nmesh_size = 5.0", "solid_ratio = 0.45\nmesh_size = 2.5").replace("[stop]\nsolid_ratio = 0.80", "[stop]\nsolid_ratio = 0.62"),
        &["nx = 2\nny = 2", "solid_ratio = 0.45", "solid_ratio = 0.62"],
    );
    let serial = dir.join("serial");
    run(&serial_case, None, &serial, &["--quiet"]);
    let two = dir.join("two");
    run(&parts_case, Some(2), &two, &["--quiet"]);
    let remade = made_again_to_target(&two, "2 x 2");
    // (every column but the Newton iterations to 1e-8: these loose frictionless discs have a
    // neutral vertical mode until they touch the fixed walls, along which the linear solver's
    // round-off moves them by 1e-7 mm, and the iterations of one step depend on it — step 14:
    // 19 with faer on one process, 15 with MUMPS on one, 14 on two, measured with the barrier's
    // double step, 2026-12-07 — while the wall pressures agree to 1e-10. The iterations of the
    // whole run must agree within 5 %.)
    let worst = history_difference_except(&serial, &two, "parts made again", &[], &["newton_iterations"]);
    let total = |out: &Path| {
        let (head, rows) = read_csv(&out.join("history.csv"));
        let c = head.iter().position(|h| h == "newton_iterations").expect("newton_iterations");
        rows.iter().map(|r| r[c]).sum::<f64>()
    };
    let (its_serial, its_two) = (total(&serial), total(&two));
    assert!((its_two - its_serial).abs() <= 0.05 * its_serial, "Newton iterations: {its_two} on parts, {its_serial} serial");
    println!("parts made again {remade} times on 2 ranks: history {worst:.2e} from the serial run");

    // 3 x 3 discs, the jam test from 0.5: made again at loaded steps, not jammed
    let jam_text = std::fs::read_to_string(&parts_case).unwrap().replace("nx = 2\nny = 2\n", "nx = 3\nny = 3\n").replace("[stop]\nsolid_ratio = 0.62", "[stop]\nsolid_ratio = 0.62\njam_solid_ratio = 0.5");
    assert!(jam_text.contains("nx = 3\nny = 3") && jam_text.contains("jam_solid_ratio = 0.5"), "the case moved");
    let jam_case = dir.join("jam.toml");
    std::fs::write(&jam_case, jam_text).unwrap();
    let jam = dir.join("jam");
    run(&jam_case, Some(2), &jam, &["--quiet"]);
    let remade = made_again_to_target(&jam, "3 x 3");
    println!("3 x 3 from 0.45, jam test from 0.5: parts made again {remade} times, solid ratio reached");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The volume errors' tolerance (absolute: they are fractions of each body's area).
const VOLUME_TOL: f64 = 1e-10;

/// The history columns compared to [`VOLUME_TOL`] absolute.
const VOLUMES: [&str; 2] = ["volume_error", "volume_error_max_body"];

/// The case `text` with heavy discs (ρ = 0.01 t/mm³: their inertia is of the order of the
/// contact forces at these steps) and the HHT-α integrator.
fn dynamic(text: String) -> String {
    text.replacen("poisson_ratio = 0.3\n", "poisson_ratio = 0.3\ndensity = 0.01\n", 1).replacen("[time]\n", "[time]\nintegrator = \"hht\"\n", 1)
}

/// The largest kinetic energy of a run and the walls' largest work (history columns).
fn kinetic_and_work(out: &Path) -> (f64, f64) {
    let (h, rows) = read_csv(&out.join("history.csv"));
    let col = |name: &str| h.iter().position(|c| c == name).unwrap_or_else(|| panic!("no column {name}"));
    let (k, w) = (col("kinetic_energy"), col("external_work"));
    rows.iter().fold((0.0f64, 0.0f64), |(a, b), r| (a.max(r[k]), b.max(r[w].abs())))
}

#[test]
fn implicit_dynamics_on_parts_follows_the_serial_run() {
    let dir = tmpdir("dynamic");
    let (serial_case, parts_case) = serial_and_parts(&dir, |t| dynamic(t).replace("[output]\nevery = 0", "[output]\nevery = 1\ncheckpoint_every = 3\ncheckpoint_minutes = 0"), &["density = 0.01", "integrator = \"hht\"", "every = 1"]);
    let serial = dir.join("serial");
    run(&serial_case, None, &serial, &["--quiet"]);
    let (kinetic, work) = kinetic_and_work(&serial);
    assert!(kinetic > 0.1 * work, "the inertia does not matter: kinetic energy {kinetic:e} against the walls' work {work:e}");
    let two = dir.join("two");
    let o = run(&parts_case, Some(2), &two, &[]);
    let said = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(said.contains("2 MPI ranks (each its own particles and their neighbours"), "not a run on parts: {said}");
    let worst = history_difference_but(&serial, &two, "dynamics on 2 ranks", &VOLUMES);
    let (results, n) = results_difference(&serial, &two);
    println!("dynamics on parts, 2 ranks: history {worst:.2e}, results.h5 {results:.2e} over {n} datasets (kinetic energy up to {kinetic:.3e}, walls' work {work:.3e})");
    // the 2-rank checkpoint (step 3 of 4: u, v, a, g of every node) on 3 ranks
    let three = dir.join("three");
    restarted(&two, 3, &three, &parts_case, Some(3), false);
    let worst = history_difference_but(&serial, &three, "the dynamic 2-rank checkpoint on 3", &VOLUMES);
    println!("the dynamic 2-rank checkpoint continued on 3 ranks: {worst:.2e} from the serial run");

    // the loose 3 x 3 grid: the parts grown again with the dynamics
    let loose = |t: String| dynamic(t).replace("solid_ratio = 0.76\nmesh_size = 5.0", "solid_ratio = 0.45\nmesh_size = 2.5").replace("[stop]\nsolid_ratio = 0.80", "[stop]\nsolid_ratio = 0.62\njam_solid_ratio = 0.5");
    let (serial_case, parts_case) = serial_and_parts(&dir, loose, &["solid_ratio = 0.45", "jam_solid_ratio = 0.5", "density = 0.01"]);
    let serial = dir.join("loose-serial");
    run(&serial_case, None, &serial, &["--quiet"]);
    let two = dir.join("loose-two");
    run(&parts_case, Some(2), &two, &["--quiet"]);
    let remade = made_again_to_target(&two, "dynamic 3 x 3");
    let worst = history_difference_but(&serial, &two, "dynamic parts grown again", &VOLUMES);
    println!("dynamic loose 3 x 3 on 2 ranks, parts grown again {remade} times: history {worst:.2e} from the serial run");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cohering_parts_write_and_restart_their_ties() {
    let dir = tmpdir("cohering");
    let edit = |t: String| t.replace("contact = \"sliding\"", "contact = \"cohering\"").replace("[output]\nevery = 0", "[output]\nevery = 2\ncheckpoint_every = 5\ncheckpoint_minutes = 0");
    let (serial_case, parts_case) = serial_and_parts(&dir, edit, &["contact = \"cohering\"", "every = 2"]);
    let serial = dir.join("serial");
    run(&serial_case, None, &serial, &["--quiet"]);
    let two = dir.join("two");
    run(&parts_case, Some(2), &two, &["--quiet"]);
    let worst = history_difference_but(&serial, &two, "cohering on 2 ranks", &VOLUMES);
    let (results, n) = results_difference(&serial, &two);
    let file = hdf5::File::open(two.join("results.h5")).expect("results.h5");
    let steps = file.group("steps").expect("/steps");
    let last = steps.member_names().expect("steps").pop().expect("a step");
    let status: Vec<f64> = steps.group(&last).and_then(|g| g.dataset("contact_status")).and_then(|d| d.read_raw()).expect("contact_status");
    let tied = status.iter().filter(|&&s| s == 3.0).count();
    assert!(tied > 0, "no tied node at the last step: the case no longer tests the ties");
    println!("cohering on 2 ranks: {tied} tied nodes, history {worst:.2e}, results.h5 {results:.2e} over {n} datasets");
    // the 2-rank checkpoint (step 5 of 8, ties in the whole model's numbering) on 3 ranks
    let three = dir.join("three");
    restarted(&two, 5, &three, &parts_case, Some(3), false);
    let worst = history_difference_but(&serial, &three, "the cohering 2-rank checkpoint on 3", &VOLUMES);
    let from_serial = dir.join("from-serial");
    restarted(&serial, 5, &from_serial, &parts_case, Some(2), true);
    let worst_serial = history_difference_but(&serial, &from_serial, "the cohering serial checkpoint on 2 ranks", &VOLUMES);
    println!("cohering checkpoints continued: 2 ranks' on 3 {worst:.2e}, the serial one on 2 {worst_serial:.2e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn remeshing_parts_write_the_serial_results_and_restart() {
    let dir = tmpdir("remesh");
    let edit = |t: String| t.replace("[output]\nevery = 0", "[remesh]\nmin_scaled_jacobian = 0.828\n\n[output]\nevery = 2\ncheckpoint_every = 5\ncheckpoint_minutes = 0");
    let (serial_case, parts_case) = serial_and_parts(&dir, edit, &["min_scaled_jacobian = 0.828", "every = 2"]);
    let serial = dir.join("serial");
    run(&serial_case, None, &serial, &["--quiet"]);
    let (h, rows) = read_csv(&serial.join("history.csv"));
    let col = h.iter().position(|c| c == "remeshes").expect("a remeshes column");
    let remeshes: f64 = rows.iter().map(|r| r[col]).sum();
    let first = rows.iter().position(|r| r[col] > 0.0).expect("a re-mesh") + 1;
    assert!(remeshes >= 9.0 && first < 5 && rows.len() < 10, "{remeshes} re-meshes, the first at step {first}, {} steps: the checkpoint at step 5, the last, no longer follows them", rows.len());
    let two = dir.join("two");
    run(&parts_case, Some(2), &two, &["--quiet"]);
    let worst = history_difference(&serial, &two, "re-meshing on 2 ranks");
    let (results, n) = results_difference(&serial, &two);
    // the output's meshes are the new ones after the re-mesh
    let file = hdf5::File::open(two.join("results.h5")).expect("results.h5");
    let cells = |s: &str| file.dataset(&format!("steps/{s}/cells")).expect("cells").shape()[0];
    assert_ne!(cells("000002"), cells("000004"), "the output after the re-mesh has the old mesh");
    println!("re-meshing on 2 ranks: {remeshes} re-meshes, {} then {} elements; history {worst:.2e}, results.h5 {results:.2e} over {n} datasets", cells("000002"), cells("000004"));
    // the parts' partition as summary.json reports it: nine discs of equal element counts (all
    // re-meshed alike) on 2 ranks, five on one, and close pairs split between them
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(two.join("summary.json")).expect("summary.json")).expect("json");
    let p = &summary["run"]["partition"];
    let (imbalance, cut) = (p["imbalance"].as_f64().expect("imbalance"), p["edge_cut"].as_u64().expect("edge cut"));
    assert!((imbalance - 10.0 / 9.0).abs() < 1e-12 && cut > 0, "run.partition on the parts: {p}");
    // the 2-rank checkpoint after the re-mesh (step 5, with the new meshes' quality as their
    // re-mesh baselines: without them the restart re-meshed three discs again) on 3 ranks; the
    // serial one on 2, and serially
    let three = dir.join("three");
    restarted(&two, 5, &three, &parts_case, Some(3), false);
    let on_three = history_difference(&serial, &three, "the re-meshed 2-rank checkpoint on 3");
    let from_serial = dir.join("from-serial");
    restarted(&serial, 5, &from_serial, &parts_case, Some(2), true);
    let on_two = history_difference(&serial, &from_serial, "the re-meshed serial checkpoint on 2 ranks");
    let again = dir.join("serial-again");
    restarted(&serial, 5, &again, &serial_case, None, false);
    let serially = history_difference(&serial, &again, "the re-meshed serial checkpoint serially");
    println!("re-meshed checkpoints continued: 2 ranks' on 3 {on_three:.2e}, the serial one on 2 {on_two:.2e}, serially {serially:.2e}");
    let _ = std::fs::remove_dir_all(&dir);
}
