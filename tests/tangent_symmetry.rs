//! The symmetric factorisation rests on a claim: `model::symmetric_tangent` says which jobs have
//! a symmetric global tangent, and those get faer's Cholesky (LLᵀ with the LDLᵀ fallbacks)
//! instead of LU. This checks the claim numerically on every kind of job that makes it (issue
//! 24): the tangent assembled at the converged end of a step in which the particles yield and
//! press on each other and on the walls, ‖K − Kᵀ‖_F / ‖K‖_F ≤ 1e-12 (round-off: the
//! element, barrier, friction and tie Hessians are each assembled from symmetric blocks, so
//! anything above round-off is a term that is not).
//!
//! The kinds: the barrier contact (the default) frictionless, with friction (μ = 0.2, lagged)
//! and cohering (ties), with J2, elastic and creep particles; and the frictionless penalty
//! method with elastic particles. The control: the penalty method with friction is declared
//! unsymmetric, and its tangent is measured so (its asymmetry far above round-off), so the
//! measure can fail.
//!
//! And the switch itself: a job that goes from LU to Cholesky gives the same wall pressures
//! to 1e-9 (relative), on a J2 quarter disc pressed by a plate with the barrier, whose tangents
//! are all definite (so both solvers take the same Newton path and only the round-off of the two
//! factorisations differs).

use mpfem::case;
use mpfem::linalg::csr::CsrMatrix;
use mpfem::model::Model;
use mpfem::solver::Simulation;
use std::collections::HashMap;
use std::path::Path;

const JOB: &str = "jobs/compaction/discs_2x2_lateral.toml";

/// ‖K − Kᵀ‖_F / ‖K‖_F over the stored entries (an entry whose transpose is not stored counts
/// whole).
fn asymmetry(k: &CsrMatrix) -> f64 {
    let mut at = HashMap::new();
    for i in 0..k.nrows {
        for p in k.row_ptr[i]..k.row_ptr[i + 1] {
            at.insert((i, k.col_idx[p]), k.values[p]);
        }
    }
    let (mut diff, mut norm) = (0.0, 0.0);
    for (&(i, j), &v) in &at {
        let t = at.get(&(j, i)).copied().unwrap_or(0.0);
        diff += (v - t) * (v - t);
        norm += v * v;
    }
    (diff / norm).sqrt()
}

/// The 2 × 2 J2 discs of `JOB` with another material, contact method and kind, run to 0.6 s
/// (solid ratio 0.80: every disc pressed by its neighbours and the walls), then the tangent of
/// the next step's converged end. Returns whether the model claims a symmetric tangent, the
/// tangent's asymmetry, the largest plastic strain and the left wall's force.
fn tangent_of(material: &str, method: &str, kind: &str, extra: &str) -> (bool, f64, f64, f64) {
    let base = std::fs::read_to_string(JOB).unwrap();
    let model_line = match material {
        "j2" => "model = \"j2\"\nyoungs_modulus = 64100.0\npoisson_ratio = 0.3\nhardening = { preset = \"aluminium_250c\" }".to_string(),
        "elastic" => "model = \"elastic\"\nyoungs_modulus = 64100.0\npoisson_ratio = 0.3".to_string(),
        // (ν = 0.3: a compressible creep, so that no volume multiplier enters)
        "creep" => "model = \"creep\"\nyoungs_modulus = 526.0\npoisson_ratio = 0.3\ncreep = { preset = \"asphalt_table2\", stress_unit = \"Pa\" }".to_string(),
        _ => unreachable!(),
    };
    let old = "model = \"j2\"\nyoungs_modulus = 64100.0\npoisson_ratio = 0.3\nhardening = { preset = \"aluminium_250c\" }";
    assert!(base.contains(old));
    let contact = match kind {
        "rubbing" => "contact = \"rubbing\"\nfriction = 0.2".to_string(),
        k => format!("contact = \"{k}\""),
    };
    let text = base
        .replace(old, &model_line)
        .replace("method = \"penalty\"", &format!("method = \"{method}\""))
        .replace("contact = \"sliding\"", &format!("{contact}{extra}"))
        .replace("end = 3.0", "end = 0.6");
    let c = case::parse(&text, Path::new("jobs/compaction")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let claim = model.symmetric_tangent();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    let mut last = None;
    sim.run(&mut |_, rep| last = rep.compaction.clone()).unwrap();
    assert!((sim.sol.time - 0.6).abs() < 1e-9, "{material} {method} {kind}: stopped at {}", sim.sol.time);
    let k = sim.tangent_after_step(0.02).unwrap_or_else(|e| panic!("{material} {method} {kind}: the step failed: {e}"));
    let eps_p = sim.sol.fields.states.iter().flatten().map(|s| s.eps_p.max(s.eps_c)).fold(0.0, f64::max);
    (claim, asymmetry(&k), eps_p, last.unwrap().force[0])
}

#[test]
fn every_job_that_claims_a_symmetric_tangent_has_one() {
    let mut lines = Vec::new();
    for (material, method, kind) in [
        ("j2", "barrier", "sliding"),
        ("j2", "barrier", "rubbing"),
        ("j2", "barrier", "cohering"),
        ("elastic", "barrier", "sliding"),
        ("elastic", "barrier", "rubbing"),
        ("creep", "barrier", "sliding"),
        ("elastic", "penalty", "sliding"),
    ] {
        let (claim, asym, flow, force) = tangent_of(material, method, kind, "");
        lines.push(format!("{material:8} {method:8} {kind:9} claims {claim}, ‖K − Kᵀ‖/‖K‖ = {asym:.2e}, largest inelastic strain {flow:.3e}, left wall {force:.1} N/mm"));
        assert!(claim, "{material} {method} {kind} should claim a symmetric tangent");
        assert!(asym <= 1e-12, "{material} {method} {kind}: ‖K − Kᵀ‖/‖K‖ = {asym:e}");
        // the step is one that loads: the walls carry the discs, the particles flow
        assert!(force > 1.0, "{material} {method} {kind}: left wall force {force}");
        if material != "elastic" {
            assert!(flow > 1e-4, "{material} {method} {kind}: largest inelastic strain {flow}");
        }
    }
    // the controls, declared unsymmetric: the penalty method's friction (the measure says
    // whether its pairs slipped in this step: stick is symmetric) and its smoothed normal
    let (claim, asym, _, _) = tangent_of("elastic", "penalty", "rubbing", "");
    lines.push(format!("elastic  penalty  rubbing   claims {claim}, ‖K − Kᵀ‖/‖K‖ = {asym:.2e}"));
    assert!(!claim);
    let (claim, asym, _, _) = tangent_of("elastic", "penalty", "sliding", "\nnormal = \"smoothed\"");
    lines.push(format!("elastic  penalty  smoothed  claims {claim}, ‖K − Kᵀ‖/‖K‖ = {asym:.2e}"));
    eprintln!("{}", lines.join("\n"));
    assert!(!claim && asym > 1e-6, "penalty, smoothed normal: claims {claim}, asymmetry {asym:e}");
}

/// The plate force of a J2 quarter disc (R = 10 mm, h = 1 mm) pressed 1 mm (10 %) with the
/// barrier, step by step, with `linear`: ux = 0 on its vertical cut and a fixed frictionless
/// wall d̂ below its horizontal cut (the quarter of `tests/symmetry.rs`), so that no rigid
/// motion is free and every tangent is definite.
fn disc_forces(linear: &str) -> (Vec<f64>, String) {
    let (h, r) = (1.0, 10.0);
    let dhat = h / 20.0;
    let text = format!(
        "[[materials]]\nname = \"alu\"\nmodel = \"j2\"\nyoungs_modulus = 64100.0\npoisson_ratio = 0.3\nhardening = {{ preset = \"aluminium_250c\" }}\n\n\
         [[bodies]]\nname = \"disc\"\nmaterial = \"alu\"\nmesh_size = {h}\nshape = {{ type = \"disc\", center = [0.0, 0.0], radius = {r}, part = \"quarter\" }}\n\n\
         [[boundary]]\nbody = \"disc\"\nset = \"axis_y\"\nux = 0.0\n\n\
         [[walls]]\nside = \"bottom\"\nposition = {}\n\n[[walls]]\nside = \"top\"\nposition = {}\ntravel = {}\n\n\
         [time]\nend = 1.0\ndt = 0.1\n\n[solver]\nlinear = \"{linear}\"\n",
        -dhat,
        r + dhat,
        1.0 + 2.0 * dhat
    );
    let c = case::parse(&text, Path::new(".")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    let name = sim.linear_solver_name().to_string();
    let mut forces = Vec::new();
    sim.run(&mut |_, rep| forces.push(rep.compaction.as_ref().unwrap().force[3])).unwrap();
    assert!(!sim.barrier_descends(), "{linear}: the descent was needed, the paths may differ");
    let flow = sim.sol.fields.states.iter().flatten().map(|s| s.eps_p).fold(0.0, f64::max);
    assert!(flow > 1e-3, "the disc yields: largest plastic strain {flow}");
    (forces, name)
}

#[test]
fn switching_from_lu_to_cholesky_keeps_the_wall_forces() {
    let (lu, lu_name) = disc_forces("lu");
    let (auto, auto_name) = disc_forces("auto");
    assert!(lu_name.to_lowercase().contains("lu") && auto_name.to_lowercase().contains("cholesky"), "{lu_name} / {auto_name}");
    assert_eq!(lu.len(), auto.len());
    let top = lu.iter().copied().fold(0.0, f64::max);
    assert!(top > 100.0, "the disc carries load: {top} N/mm");
    let worst = lu.iter().zip(&auto).map(|(a, b)| (a - b).abs() / top).fold(0.0, f64::max);
    eprintln!("{} steps, plate force up to {top:.1} N/mm; largest difference LU / Cholesky {worst:.2e} of it", lu.len());
    for (k, (a, b)) in lu.iter().zip(&auto).enumerate() {
        assert!((a - b).abs() <= 1e-9 * top, "step {}: LU {a}, Cholesky {b}", k + 1);
    }
}
