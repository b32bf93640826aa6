//! The nonlinear and linear solver choices give the same answer.
//!
//! - Modified Newton (tangent once per step, eq. 9/16 of the paper) reaches the same converged
//!   state as full Newton on the elasto-plastic default job (both converge to the residual
//!   tolerance 1e-8, so the displacements agree to ~1e-6 relative) with more iterations.
//! - LU, Cholesky and PCG (Jacobi and IC(0)) solve the same linear elastic problem (Cook's
//!   membrane, 8 × 8, linear regime) to the same tip displacement (1e-6 relative: PCG stops
//!   at a relative residual of 1e-10, Newton at 1e-10).

use mpfem::case::{self, LinearChoice, NewtonKind};
use mpfem::linalg::{LinearSolverKind, Preconditioner};
use mpfem::model::Model;
use mpfem::solver::Simulation;

fn run(c: &case::Case) -> (Vec<f64>, usize) {
    let model = Model::from_case(c).unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    let s = sim.run(&mut |_, _| {}).unwrap();
    (sim.sol.u.clone(), s.newton_iterations)
}

#[test]
fn modified_newton_matches_full_newton() {
    let full = case::default_case();
    let mut modified = case::default_case();
    modified.solver.newton = NewtonKind::Modified;
    modified.solver.max_iterations = 200;
    let (u_full, it_full) = run(&full);
    let (u_mod, it_mod) = run(&modified);
    let umax = u_full.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let diff = u_full.iter().zip(&u_mod).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(diff / umax < 1e-6, "modified vs full Newton: {}", diff / umax);
    assert!(it_mod > it_full, "modified Newton should need more iterations ({it_mod} vs {it_full})");
}

#[test]
fn linear_solvers_agree() {
    let text = std::fs::read_to_string("jobs/verification/cook_membrane.toml").unwrap();
    let base = case::parse(&text, std::path::Path::new("jobs/verification")).unwrap();
    let mut results = Vec::new();
    for (kind, pre) in [
        (LinearSolverKind::Lu, Preconditioner::Ic0),
        (LinearSolverKind::Cholesky, Preconditioner::Ic0),
        (LinearSolverKind::Pcg, Preconditioner::Jacobi),
        (LinearSolverKind::Pcg, Preconditioner::Ic0),
    ] {
        let mut c = base.clone();
        c.bodies[0].divisions = Some([8, 8]);
        c.solver.linear = LinearChoice::Fixed(kind);
        c.solver.preconditioner = pre;
        let (u, _) = run(&c);
        results.push((kind, pre, u));
    }
    let reference = &results[0].2;
    let umax = reference.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(umax > 0.0);
    for (kind, pre, u) in &results[1..] {
        let diff = u.iter().zip(reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(diff / umax < 1e-6, "{kind:?}/{pre:?} differs from LU by {}", diff / umax);
    }
}

/// `[solver] ordering = "metis"`: the Cholesky factorisation with METIS nested dissection
/// gives the same run as with AMD (a direct solve: 1e-9 relative on the displacements, the
/// orderings only change the round-off), here on the 2 × 2 frictionless disc job, whose
/// tangent is symmetric; a bad value names the key and the choices.
#[test]
fn metis_ordering_gives_the_same_run() {
    let base = case::load(std::path::Path::new("jobs/compaction/discs_2x2_lateral.toml")).unwrap();
    let mut runs = Vec::new();
    for ordering in [mpfem::linalg::FillOrdering::Amd, mpfem::linalg::FillOrdering::Metis] {
        let mut c = base.clone();
        c.stop.solid_ratio = Some(0.8);
        c.solver.linear = LinearChoice::Fixed(LinearSolverKind::Cholesky);
        c.solver.ordering = ordering;
        runs.push(run(&c).0);
    }
    let umax = runs[0].iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(umax > 1.0, "the walls must have moved: {umax}");
    let diff = runs[0].iter().zip(&runs[1]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(diff / umax < 1e-9, "METIS vs AMD: {}", diff / umax);
    let text = std::fs::read_to_string("jobs/compaction/discs_2x2_lateral.toml").unwrap();
    let e = case::parse(&text.replace("[solver]", "[solver]\nordering = \"nd\""), std::path::Path::new("jobs/compaction")).unwrap_err();
    assert_eq!(e.key, "solver.ordering");
    assert!(e.message.contains("\"nd\"") && e.message.contains("\"amd\", \"metis\""), "{e}");
}
