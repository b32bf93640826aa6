//! PETSc as the distributed linear solver (feature `petsc`, `[solver] linear = "petsc"`):
//! `mpirun -n R mpfem run` with PETSc's solvers against the serial run with faer's.
//!
//! - MUMPS (the default): the 3 × 3 J2 discs with friction (an unsymmetric tangent: MUMPS's
//!   LU) on 1, 2, 3 and 4 ranks, and the elastic frictionless discs with the barrier (a
//!   symmetric tangent: MUMPS's LDLᵀ, whose inertia the barrier's descent asks for) on 2 and 3
//!   ranks: the wall pressures and forces equal the serial faer run's to 1e-8 relative (of the
//!   column's largest value), the tolerance for a direct distributed solve (measured:
//!   1.4e-12 and below; the Newton tolerance of the cases, 1e-11, is far below it).
//! - A checkpoint of a 2-rank PETSc run continues on 3 ranks to the uninterrupted serial faer
//!   history (1e-8).
//! - CG + GAMG (`petsc_options = "-pc_type gamg"`: CG, as the tangent is symmetric, with the
//!   rigid-body modes as GAMG's near-null space) and CG with the particles' two-level
//!   preconditioner (`-pc_type mg`) on Cook's membrane (48 × 48 elements, linear regime) on 2
//!   ranks: the corner's displacement equals faer's Cholesky to 1e-7 relative (the CG
//!   tolerance is 1e-10 of the residual, and κ of this mesh is about 1e5; measured 1e-12).
//! - The two-level CG on contact (owned + ghost parts, the barrier): see its test.
//! - An iterative solve that cannot converge fails the run cleanly (exit 1, the reason named,
//!   every rank ended), never a panic or a hang.
//!
//! Needs Open MPI's `mpirun` and PETSc (`scripts/setup.sh` installs both). The test binary
//! never starts MPI itself; its tests start `mpirun`.
#![cfg(feature = "petsc")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::{mpirun, read_csv, tmpdir};

const CASE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mpi_discs_3x3.toml");
const CASE_ELASTIC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mpi_discs_3x3_pcg.toml");
const COOK: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/jobs/verification/cook_membrane.toml");
const TOL: f64 = 1e-8;
const COMPARED: [&str; 9] = ["solid_ratio", "p_left", "p_right", "p_bottom", "p_top", "f_left", "f_right", "f_bottom", "f_top"];

/// `mpfem run case --out out` serially (no launcher) or on `ranks` ranks, with `extra`
/// arguments; its output.
fn run(case: &Path, ranks: Option<usize>, out: &Path, extra: &[&str]) -> Output {
    let mut cmd = match ranks {
        None => Command::new(env!("CARGO_BIN_EXE_mpfem")),
        Some(n) => mpirun(n),
    };
    cmd.arg("run").arg(case).arg("--out").arg(out).args(["--quiet", "--no-plots", "--threads", "1"]).args(extra);
    cmd.output().unwrap_or_else(|e| panic!("cannot start {:?} (bash scripts/setup.sh installs Open MPI): {e}", cmd.get_program()))
}

fn run_ok(case: &Path, ranks: Option<usize>, out: &Path) {
    let o = run(case, ranks, out, &[]);
    assert!(o.status.success(), "{ranks:?} ranks, {}: {:?}\nstderr: {}", case.display(), o.status, String::from_utf8_lossy(&o.stderr));
}

/// A copy of `case` in `dir` with `edit` applied (which must change it).
fn variant(dir: &Path, name: &str, case: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    let text = std::fs::read_to_string(case).expect("case");
    let new = edit(&text);
    assert_ne!(new, text, "{name}: the edit changed nothing (the case moved?)");
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, new).expect("write case");
    p
}

/// The case's `[solver]` table with `lines` added at its top.
fn with_solver(text: &str, lines: &str) -> String {
    text.replacen("[solver]\n", &format!("[solver]\n{lines}\n"), 1)
}

/// The largest difference of the compared columns from the reference, relative to each
/// column's largest |value|; asserts the same columns and steps.
fn worst_difference(reference: &Path, other: &Path, what: &str) -> f64 {
    let (h0, r0) = read_csv(&reference.join("history.csv"));
    let (h1, r1) = read_csv(&other.join("history.csv"));
    assert_eq!(h0, h1, "{what}: columns");
    assert_eq!(r0.len(), r1.len(), "{what}: {} steps, the reference {}", r1.len(), r0.len());
    let col = |n: &str| h0.iter().position(|h| h == n).unwrap_or_else(|| panic!("no column {n}"));
    assert!(r0.len() >= 3, "{what}: only {} steps", r0.len());
    assert!(r0.last().unwrap()[col("p_left")] > 1.0, "{what}: the left wall carries no pressure");
    let mut worst = 0.0f64;
    for name in COMPARED {
        let c = col(name);
        let scale = r0.iter().map(|r| r[c].abs()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        for (a, b) in r1.iter().zip(&r0) {
            assert_eq!(a[col("step")], b[col("step")], "{what}: step numbers");
            worst = worst.max((a[c] - b[c]).abs() / scale);
        }
    }
    worst
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).expect("summary.json")).expect("summary.json parses")
}

#[test]
fn mumps_on_1_to_4_ranks_matches_the_serial_faer_run() {
    let dir = tmpdir("mumps");
    // J2 with friction and the penalty method: LU
    let serial = dir.join("serial");
    run_ok(Path::new(CASE), None, &serial);
    let case = variant(&dir, "petsc", CASE, |t| with_solver(t, "linear = \"petsc\""));
    for ranks in 1..=4 {
        let out = dir.join(format!("lu{ranks}"));
        run_ok(&case, Some(ranks), &out);
        let solver = summary(&out)["run"]["linear_solver"].as_str().unwrap_or_default().to_string();
        assert_eq!(solver, "petsc preonly+lu (mumps)", "{ranks} ranks");
        let worst = worst_difference(&serial, &out, &format!("MUMPS LU on {ranks} ranks"));
        println!("MUMPS LU on {ranks} rank(s): largest relative difference from the serial faer run {worst:.2e}");
        assert!(worst <= TOL, "MUMPS LU on {ranks} ranks: {worst:.2e} > {TOL:e}");
    }
    // elastic, frictionless, the barrier: a symmetric tangent, MUMPS's LDLᵀ and its inertia
    let barrier = variant(&dir, "barrier", CASE_ELASTIC, |t| t.replace("method = \"penalty\"", "method = \"barrier\"").replace("linear = \"pcg\"\npreconditioner = \"schwarz\"\n", ""));
    let serial = dir.join("barrier-serial");
    run_ok(&barrier, None, &serial);
    assert_eq!(summary(&serial)["run"]["linear_solver"].as_str(), Some("cholesky"));
    let case = variant(&dir, "barrier-petsc", barrier.to_str().unwrap(), |t| with_solver(t, "linear = \"petsc\""));
    for ranks in [2, 3] {
        let out = dir.join(format!("ldlt{ranks}"));
        run_ok(&case, Some(ranks), &out);
        assert_eq!(summary(&out)["run"]["linear_solver"].as_str(), Some("petsc preonly+cholesky (mumps)"));
        let worst = worst_difference(&serial, &out, &format!("MUMPS LDLT on {ranks} ranks"));
        println!("MUMPS LDLT (barrier) on {ranks} ranks: largest relative difference from the serial faer run {worst:.2e}");
        assert!(worst <= TOL, "MUMPS LDLT on {ranks} ranks: {worst:.2e} > {TOL:e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_petsc_checkpoint_continues_on_another_rank_count() {
    let dir = tmpdir("restart");
    let serial = dir.join("serial");
    run_ok(Path::new(CASE), None, &serial);
    let case = variant(&dir, "petsc", CASE, |t| with_solver(t, "linear = \"petsc\"").replace("[output]\nevery = 0", "[output]\nevery = 0\ncheckpoint_every = 4\ncheckpoint_minutes = 0"));
    let two = dir.join("two");
    run_ok(&case, Some(2), &two);
    let three = dir.join("three");
    std::fs::create_dir_all(&three).unwrap();
    for f in ["history.csv", "checkpoint.h5"] {
        std::fs::copy(two.join(f), three.join(f)).unwrap();
    }
    // the checkpoint is at step 4, before the end: cut the history back to it as a stopped
    // run would have left it
    let h = std::fs::read_to_string(three.join("history.csv")).unwrap();
    let kept: Vec<&str> = h.lines().take(5).collect();
    assert!(h.lines().count() > 5, "the run has only {} steps", h.lines().count() - 1);
    std::fs::write(three.join("history.csv"), kept.join("\n") + "\n").unwrap();
    let o = run(&case, Some(3), &three, &["--restart", three.to_str().unwrap()]);
    assert!(o.status.success(), "restart on 3 ranks: {}", String::from_utf8_lossy(&o.stderr));
    let worst = worst_difference(&serial, &three, "restarted on 3 ranks");
    println!("checkpoint of 2 ranks continued on 3: largest relative difference from the serial faer run {worst:.2e}");
    assert!(worst <= TOL, "restart on 3 ranks: {worst:.2e} > {TOL:e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The displacement of Cook's membrane's corner from `probes.csv`.
fn corner_uy(dir: &Path) -> f64 {
    let (h, rows) = read_csv(&dir.join("probes.csv"));
    let c = h.iter().position(|n| n == "corner_uy").expect("corner_uy");
    rows.last().expect("a row")[c]
}

#[test]
fn cg_with_gamg_and_with_the_particles_two_levels_matches_the_direct_solve() {
    let dir = tmpdir("gamg");
    let probes = "\n[output]\nprobes = [{ name = \"corner\", point = [48.0, 60.0] }]\n";
    let direct = variant(&dir, "cook", COOK, |t| t.replace("divisions = [16, 16]", "divisions = [48, 48]") + probes);
    let reference = dir.join("faer");
    run_ok(&direct, None, &reference);
    let b = corner_uy(&reference);
    assert!(b.abs() > 1e-6, "the corner does not move: {b}");
    // (one body on 2 ranks: the two-level preconditioner's rank 1 holds no rows, no coarse
    // unknowns and one empty block)
    for (pc, name) in [("gamg", "petsc cg+gamg"), ("mg", "petsc cg+mg")] {
        let case = variant(&dir, &format!("cook-{pc}"), direct.to_str().unwrap(), |t| with_solver(t, &format!("linear = \"petsc\"\npetsc_options = \"-pc_type {pc}\"\npcg_tol = 1e-10")));
        let out = dir.join(pc);
        run_ok(&case, Some(2), &out);
        assert_eq!(summary(&out)["run"]["linear_solver"].as_str(), Some(name));
        let a = corner_uy(&out);
        let rel = (a - b).abs() / b.abs();
        println!("CG + {pc} on 2 ranks: corner u_y {a:.12e} against faer's {b:.12e} (relative {rel:.1e})");
        assert!(rel <= 1e-7, "CG + {pc}: corner u_y {a} vs {b} (relative {rel:.1e})");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The mean Krylov iterations per linear solve of the run in `out` (`summary.json`'s timing).
fn iterations_per_solve(out: &Path) -> f64 {
    let t = &summary(out)["run"]["timing"];
    let (its, solves) = (t["linear_iterations"].as_f64().expect("linear_iterations"), t["linear_solves"].as_f64().expect("linear_solves"));
    assert!(solves > 0.0, "no linear solve counted");
    its / solves
}

/// CG with the particles' two-level preconditioner (`-pc_type mg`: each particle's rigid-body
/// modes and uniform strains the coarse space, each particle's block the smoother's) on
/// owned + ghost parts, the barrier contact.
/// - The 3 × 3 J2 discs with friction 0.2, two steps (the second loaded, 33 MPa on the left
///   wall): the history equals the serial faer run's to 1e-8 relative on 2 and 3 ranks (the CG
///   tolerance is 1e-10; measured: equal to the 10 digits written). Further on the two engines
///   may part: where a tangent is nearly singular, CG's breakdown and the Cholesky
///   factorisation's pivots do not always agree on whether it is definite, and the descent then
///   projects and shifts in different iterations.
/// - The elastic 3 × 3 discs pressed from all four sides, where CG breaks down on indefinite
///   tangents (corners facing corners): the run reaches its solid ratio with the breakdowns
///   handled (the descent's projection and shifts, or the exact update by GMRES), in fewer than
///   25 CG iterations a solve on average (measured 8–13; CG with GAMG needs thousands on these
///   loose particles, docs/scaling/README.md).
#[test]
fn cg_with_the_particles_two_levels_follows_the_direct_solve_on_contact() {
    let dir = tmpdir("two-level");
    let serial_case = variant(&dir, "friction", CASE, |t| t.replace("method = \"penalty\"", "method = \"barrier\"").replace("end = 3.0", "end = 0.125"));
    let serial = dir.join("serial");
    run_ok(&serial_case, None, &serial);
    let mg_case = variant(&dir, "friction-mg", serial_case.to_str().unwrap(), |t| with_solver(t, "linear = \"petsc\"\npetsc_options = \"-pc_type mg\"\npcg_tol = 1e-10"));
    let (h0, r0) = read_csv(&serial.join("history.csv"));
    assert_eq!(r0.len(), 2, "the case moved: {} steps", r0.len());
    let p_left = h0.iter().position(|h| h == "p_left").expect("p_left");
    assert!(r0[1][p_left] > 1.0, "the second step is not loaded: {}", r0[1][p_left]);
    for ranks in [2, 3] {
        let out = dir.join(format!("mg{ranks}"));
        let o = run(&mg_case, Some(ranks), &out, &[]);
        let said = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{ranks} ranks: {said}");
        assert!(said.contains("(each its own particles and their neighbours"), "not a run on parts: {said}");
        assert_eq!(summary(&out)["run"]["linear_solver"].as_str(), Some("petsc cg+mg"));
        let (h1, r1) = read_csv(&out.join("history.csv"));
        assert_eq!((&h0, r0.len()), (&h1, r1.len()), "{ranks} ranks: columns and steps");
        let mut worst = 0.0f64;
        for name in COMPARED {
            let c = h0.iter().position(|h| h == name).expect("column");
            let scale = r0.iter().map(|r| r[c].abs()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
            for (a, b) in r1.iter().zip(&r0) {
                worst = worst.max((a[c] - b[c]).abs() / scale);
            }
        }
        let per_solve = iterations_per_solve(&out);
        println!("CG + the two levels on {ranks} ranks: {worst:.2e} from the serial faer run, {per_solve:.1} CG iterations a solve");
        assert!(worst <= TOL, "CG + the two levels on {ranks} ranks: {worst:.2e} > {TOL:e}");
        assert!(per_solve <= 25.0, "{per_solve:.1} CG iterations a solve");
    }

    // the elastic discs pressed from all four sides: CG breaks down on indefinite tangents
    let biaxial = variant(&dir, "biaxial", CASE_ELASTIC, |t| {
        t.replace("method = \"penalty\"", "method = \"barrier\"")
            .replace("linear = \"pcg\"\npreconditioner = \"schwarz\"\npcg_tol = 1e-12\n", "linear = \"petsc\"\npetsc_options = \"-pc_type mg\"\npcg_tol = 1e-10\n")
            .replace("side = \"bottom\"\nposition = 0.0\n", "side = \"bottom\"\nposition = 0.0\nvelocity = 10.0\n")
            .replace("side = \"top\"\nposition = 100.0\n", "side = \"top\"\nposition = 100.0\nvelocity = 10.0\n")
    });
    let text = std::fs::read_to_string(&biaxial).unwrap();
    assert!(text.contains("-pc_type mg") && text.matches("velocity = 10.0").count() == 4, "the case moved: {text}");
    let out = dir.join("biaxial");
    let o = Command::new("mpirun")
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_plm", "isolated")
        .env("RUST_LOG", "mpfem=debug")
        .args(["--oversubscribe", "--bind-to", "none", "-x", "RUST_LOG", "-n", "2", env!("CARGO_BIN_EXE_mpfem"), "run"])
        .arg(&biaxial)
        .arg("--out")
        .arg(&out)
        .args(["--quiet", "--no-plots", "--threads", "1"])
        .output()
        .expect("mpirun (bash scripts/setup.sh installs Open MPI)");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert_eq!(summary(&out)["run"]["stop_reason"].as_str(), Some("solid ratio reached"));
    let breakdowns = stderr.matches("the iterative solve broke down on an indefinite tangent").count();
    let per_solve = iterations_per_solve(&out);
    println!("the biaxial discs: {breakdowns} CG breakdowns handled, {per_solve:.1} CG iterations a solve");
    assert!(breakdowns >= 1, "CG never broke down: the case no longer tests it");
    assert!(per_solve <= 25.0, "{per_solve:.1} CG iterations a solve");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_iterative_solve_that_cannot_converge_fails_the_run_cleanly() {
    let dir = tmpdir("fail");
    let case = variant(&dir, "cg2", CASE, |t| with_solver(t, "linear = \"petsc\"\npetsc_options = \"-ksp_type cg -pc_type jacobi -ksp_max_it 2\""));
    let out = dir.join("out");
    let o = run(&case, Some(2), &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("did not converge"), "the reason is not named: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // what converged before is kept
    assert!(out.join("summary.json").is_file(), "no summary.json");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad input on owned + ghost parts (2 ranks with MUMPS and the barrier: a fresh run on parts
/// builds no whole model, `case::parts`) is named as the serial run names it: a particle
/// beyond a wall (the second body: found by rank 1, which meshed it, and reported by rank 0)
/// and a probe in no particle (found by no process: rank 0 builds the whole model for the
/// message) stop the run with the serial run's exit code and message line, no result written
/// and no panic.
#[test]
fn bad_input_on_parts_is_named_as_in_a_serial_run() {
    let dir = tmpdir("bad_parts");
    let parts = |t: &str| t.replace("method = \"penalty\"", "method = \"barrier\"").replace("linear = \"pcg\"", "linear = \"petsc\"");
    let cases = [
        ("beyond", "bodies[1] (\"stray\") lies wholly beyond walls[0]", variant(&dir, "beyond", CASE_ELASTIC, |t| parts(t).replace("[contact]", "[[bodies]]\nname = \"pad\"\nmaterial = \"alu\"\nmesh_size = 2.0\nshape = { type = \"disc\", center = [66.7, 66.7], radius = 3.0 }\n\n[[bodies]]\nname = \"stray\"\nmaterial = \"alu\"\nmesh_size = 1.0\nshape = { type = \"disc\", center = [-3.0, 95.0], radius = 2.0 }\n\n[contact]"))),
        ("probe", "output.probes[0].point", variant(&dir, "probe", CASE_ELASTIC, |t| parts(t).replace("[output]\nevery = 0", "[output]\nevery = 0\nprobes = [{ name = \"gap\", point = [50.0, 33.4] }]"))),
    ];
    for (name, what, case) in cases {
        let line = |o: &Output| String::from_utf8_lossy(&o.stderr).lines().find(|l| l.contains(what)).map(str::to_string);
        let serial = run(&case, None, &dir.join(format!("{name}_1")), &[]);
        let two = run(&case, Some(2), &dir.join(format!("{name}_2")), &[]);
        let stderr = String::from_utf8_lossy(&two.stderr);
        assert!(serial.status.code().is_some_and(|c| c != 0 && c != 1), "{name}: the serial run's exit code {:?}", serial.status);
        assert_eq!(two.status.code(), serial.status.code(), "{name} on 2 ranks: {stderr}");
        assert!(line(&serial).is_some(), "{name}: the serial run does not name {what}: {}", String::from_utf8_lossy(&serial.stderr));
        assert_eq!(line(&two), line(&serial), "{name}: the message on 2 ranks");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!dir.join(format!("{name}_2/history.csv")).exists(), "{name}: a history was written");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A poorly meshed particle on owned + ghost parts is warned of as in the serial run: the
/// process that meshed it (a fresh run on parts builds no whole model, `case::parts`) sends it
/// to rank 0, which prints the serial run's warning line (a sliver triangle in a pore of the
/// 3 × 3 discs, the second body, which rank 1 meshes; one step).
#[test]
fn a_poor_mesh_on_parts_is_warned_of_as_in_a_serial_run() {
    let dir = tmpdir("poor_parts");
    let case = variant(&dir, "sliver", CASE_ELASTIC, |t| {
        t.replace("method = \"penalty\"", "method = \"barrier\"").replace("linear = \"pcg\"", "linear = \"petsc\"").replace("end = 3.0", "end = 0.05").replace(
            "[contact]",
            "[[bodies]]\nname = \"pad\"\nmaterial = \"alu\"\nmesh_size = 2.0\nshape = { type = \"disc\", center = [66.7, 66.7], radius = 3.0 }\n\n[[bodies]]\nname = \"sliver\"\nmaterial = \"alu\"\nmesh_size = 2.0\nshape = { type = \"polygon\", vertices = [[30.0, 33.0], [37.0, 33.0], [37.0, 33.4]] }\n\n[contact]",
        )
    });
    let line = |o: &Output| String::from_utf8_lossy(&o.stderr).lines().find(|l| l.contains("scaled Jacobian")).map(str::to_string);
    let serial = run(&case, None, &dir.join("serial"), &[]);
    let two = run(&case, Some(2), &dir.join("two"), &[]);
    assert!(serial.status.success() && two.status.success(), "serial: {}\n2 ranks: {}", String::from_utf8_lossy(&serial.stderr), String::from_utf8_lossy(&two.stderr));
    let warned = line(&serial);
    assert!(warned.as_deref().is_some_and(|l| l.contains("bodies[1] (\"sliver\")")), "the serial run does not warn of the sliver: {}", String::from_utf8_lossy(&serial.stderr));
    assert_eq!(line(&two), warned, "the warning on 2 ranks");
    assert!(String::from_utf8_lossy(&two.stderr).contains("each its own particles and their neighbours"), "the 2-rank run is on parts: {}", String::from_utf8_lossy(&two.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}
