//! The verification set of `mpfem verify`, one test per source. Each row carries its own
//! reference, tolerance and citation (see `src/verify.rs` and `src/analytical/`); a test passes
//! when every row of its case passes.

use mpfem::case::Formulation;
use mpfem::verify::{self, Row};

fn assert_rows(rows: &[Row]) {
    assert!(!rows.is_empty(), "a verification case produced no rows");
    let table = verify::format_table(rows);
    for r in rows {
        assert!(r.pass, "verification row failed:\n{table}");
    }
}

/// Taylor, Simo & Zienkiewicz (1986) / MacNeal & Harder (1985): a distorted patch under a
/// homogeneous finite deformation reproduces the uniform stress to 1e-10 (TL and UL).
#[test]
fn patch_test_taylor_simo_zienkiewicz_tl_and_ul() {
    assert_rows(&verify::patch_test(Formulation::TotalLagrangian));
    assert_rows(&verify::patch_test(Formulation::UpdatedLagrangian));
    assert_rows(&verify::patch_test_with(Formulation::UpdatedLagrangian, mpfem::element::ElementKind::Q1P0Enhanced));
}

/// Objectivity: 90° rigid rotation in 9 steps of an elasto-plastic block keeps σ = 0 to 1e-8 E.
#[test]
fn objectivity_rigid_rotation_90_degrees() {
    assert_rows(&verify::rigid_rotation(Formulation::TotalLagrangian));
    assert_rows(&verify::rigid_rotation(Formulation::UpdatedLagrangian));
}

/// Bathe (1996) ch. 6.3: TL and UL are the same linearisation; the default job (30 %
/// upsetting, Table 1 hardening) gives the same displacements and force to 1e-6.
#[test]
fn bathe_total_and_updated_lagrangian_agree() {
    assert_rows(&verify::tl_equals_ul());
}

/// Cook (1974) membrane, plane strain, linear regime, Q1/P0 with enhanced bending modes: tip
/// displacement within 1 % of the published references (CoFEA benchmark 002; Nakshatrala et
/// al. 2008 / MOOSE) on a 64 × 64 mesh, compressible and ν = 0.4999, and within 10 % of the
/// converged value on a coarse 4 × 4 mesh at ν = 0.4999 (no locking).
#[test]
fn cook_membrane_1974_tip_displacement() {
    assert_rows(&verify::cook_membrane(64));
}

/// Refinement study, ν = 0.4999, enhanced element: the tip displacement approaches the
/// reference (7.77) monotonically from 8 × 8 on and the 32 × 32 value is within 1 %.
#[test]
fn cook_membrane_refinement_converges() {
    let (reference, _) = mpfem::analytical::cook::NEARLY_INCOMPRESSIBLE_PLANE_STRAIN;
    let v: Vec<f64> = [8, 16, 32].iter().map(|&n| verify::cook_tip(n, 250.0, 0.4999, 100.0).unwrap()).collect();
    assert!(v[0] < v[1] && v[1] < v[2], "not monotone: {v:?}");
    assert!(((v[2] - reference) / reference).abs() < 0.01, "32x32: {v:?}");
}

/// The plain Q1/P0 element is free of volumetric locking: at ν = 0.4999 on 4 × 4 it reaches
/// 84 % of the converged tip displacement (a locking element gives well under half), and on
/// 64 × 64 it is within 1 % of the reference. Its coarse-mesh deficit is bending stiffness, which
/// the enhanced modes remove (test above).
#[test]
fn cook_membrane_plain_q1p0_does_not_lock() {
    let (reference, _) = mpfem::analytical::cook::NEARLY_INCOMPRESSIBLE_PLANE_STRAIN;
    let q1p0 = Some(mpfem::element::ElementKind::Q1P0);
    let v4 = verify::cook_tip_with(4, 250.0, 0.4999, 100.0, q1p0).unwrap();
    let v64 = verify::cook_tip_with(64, 250.0, 0.4999, 100.0, q1p0).unwrap();
    assert!(v4 / reference > 0.84, "4x4: {v4}");
    assert!(((v64 - reference) / reference).abs() < 0.01, "64x64: {v64}");
}

/// Hill (1950) thick-walled cylinder, incompressible elastic–perfectly plastic, plane strain:
/// first-yield and limit pressures within 1 %, plastic-front radius within 2 %.
#[test]
fn hill_1950_thick_walled_cylinder() {
    assert_rows(&verify::thick_cylinder());
}

/// Eq. 29 of the paper (creep): constant stress (m = 0 with Table 2, and m = −0.5) within
/// 0.5 % at every step, and first-order convergence in dt under a stress ramp.
#[test]
fn creep_eq29_closed_forms_and_convergence() {
    assert_rows(&verify::creep_block());
}

/// An exactly incompressible block (ν = 0.5) compressed 30 %: |ΔA|/A ≤ 1e-6.
#[test]
fn incompressible_block_keeps_its_area() {
    assert_rows(&verify::incompressible_block());
}
