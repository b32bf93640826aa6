//! The element's consistent linearisation and the parallel assembly.
//!
//! - tangent = ∂f_int/∂x by central finite differences (TL and UL; elastic, J2 in the plastic
//!   range, and the incompressible augmented-Lagrangian volumetric part), relative error ≤ 1e-6
//!   with a perturbation of 1e-7 mm on 1 mm elements (truncation ~h², round-off ~1e-16/h);
//! - assembly on 1 and 2 threads gives bit-identical forces and matrices (the scatter runs in
//!   element order, so no sum depends on the thread count).

use mpfem::bench_support::{assembly_fixture, Law};
use mpfem::case::Formulation;
use mpfem::element::{evaluate, evaluate_enhanced, ElementInput, ElementOut, Volumetric};
use mpfem::material::{ConstitutiveLaw, Elastic, HardeningTable, J2Plastic, MatState, Material, TimeIncrement};

fn fd_check(formulation: Formulation, law: &Material, vol: Volumetric, uu: [[f64; 2]; 4]) -> f64 {
    let xx0 = [[0.0, 0.0], [1.0, 0.1], [1.1, 1.0], [-0.1, 0.9]];
    let old = [MatState::default(); 4];
    let inc = TimeIncrement { time: 1.0, dt: 1.0 };
    let input = ElementInput { law, xx0: &xx0, uu: &uu, old: &old, inc, vol, j0: 1.0, tangent: true };
    let mut out = ElementOut::default();
    evaluate(formulation, input, &mut out).expect("element");
    let kk = out.kk;
    let h = 1e-7;
    let mut worst: f64 = 0.0;
    let scale = kk.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
    for j in 0..8 {
        let (a, c) = (j / 2, j % 2);
        let mut up = uu;
        up[a][c] += h;
        let mut dn = uu;
        dn[a][c] -= h;
        let mut op = ElementOut::default();
        let mut om = ElementOut::default();
        evaluate(formulation, ElementInput { uu: &up, tangent: false, ..input }, &mut op).expect("element +h");
        evaluate(formulation, ElementInput { uu: &dn, tangent: false, ..input }, &mut om).expect("element -h");
        for i in 0..8 {
            let fd = (op.f_int[i] - om.f_int[i]) / (2.0 * h);
            worst = worst.max((fd - kk[i][j]).abs() / scale);
        }
    }
    worst
}

#[test]
fn element_tangent_matches_finite_differences() {
    // a large, non-homogeneous deformation (stretch, shear and some rotation)
    let uu = [[0.0, 0.0], [0.12, 0.05], [0.02, 0.15], [-0.08, 0.03]];
    let small = uu.map(|p| [p[0] * 0.02, p[1] * 0.02]);
    let e = 64100.0;
    let elastic = Material::Elastic(Elastic::new(e, 0.3));
    let j2 = Material::J2(J2Plastic::new(
        e,
        0.3,
        HardeningTable::from_total_strain(e, &mpfem::material::hardening::aluminium_250c()).unwrap(),
    ));
    let incompressible = Material::Elastic(Elastic::new(526.0, 0.5));
    for f in [Formulation::TotalLagrangian, Formulation::UpdatedLagrangian] {
        let k = elastic.bulk_modulus().unwrap();
        let err = fd_check(f, &elastic, Volumetric { kappa: k, lambda: 0.0 }, uu);
        assert!(err < 1e-6, "{f:?} elastic: {err:e}");
        let err = fd_check(f, &j2, Volumetric { kappa: k, lambda: 0.0 }, small);
        assert!(err < 1e-6, "{f:?} J2 (plastic): {err:e}");
        let g = incompressible.shear_modulus();
        let err = fd_check(f, &incompressible, Volumetric { kappa: 1e3 * g, lambda: 7.5 }, uu);
        assert!(err < 1e-6, "{f:?} incompressible: {err:e}");
    }
}

#[test]
fn assembly_is_identical_on_one_and_two_threads() {
    for law in [Law::Elastic, Law::J2] {
        let mut one = assembly_fixture(40, law, 1);
        let mut two = assembly_fixture(40, law, 2);
        one.assemble();
        two.assemble();
        assert_eq!(one.f_int, two.f_int, "{law:?}: internal forces differ");
        assert_eq!(one.kk.values, two.kk.values, "{law:?}: tangents differ");
        assert!(one.f_int.iter().any(|v| v.abs() > 1.0), "the fixture must be loaded");
    }
}

/// The condensed tangent of the enhanced element (α eliminated at element level) is the exact
/// derivative of its internal force: central differences, 1e-6 relative.
#[test]
fn enhanced_element_condensed_tangent_matches_finite_differences() {
    let xx0 = [[0.0, 0.0], [1.0, 0.1], [1.1, 1.0], [-0.1, 0.9]];
    let uu = [[0.0, 0.0], [0.12, 0.05], [0.02, 0.15], [-0.08, 0.03]];
    let old = [MatState::default(); 4];
    let inc = TimeIncrement { time: 1.0, dt: 1.0 };
    let e = 64100.0;
    let j2 = Material::J2(J2Plastic::new(e, 0.3, HardeningTable::perfect(130.0)));
    for (law, uu) in [(Material::Elastic(Elastic::new(e, 0.3)), uu), (j2, uu.map(|p| [0.02 * p[0], 0.02 * p[1]]))] {
        let vol = Volumetric { kappa: law.bulk_modulus().unwrap(), lambda: 0.0 };
        let input = ElementInput { law: &law, xx0: &xx0, uu: &uu, old: &old, inc, vol, j0: 1.0, tangent: true };
        let mut out = ElementOut::default();
        let mut alpha = [0.0; 4];
        evaluate_enhanced(input, &mut alpha, &mut out).unwrap();
        assert!(alpha.iter().any(|a| a.abs() > 1e-8), "the enhanced modes must be active: {alpha:?}");
        let scale = out.kk.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
        let h = 1e-7;
        let mut worst: f64 = 0.0;
        for j in 0..8 {
            let (a, c) = (j / 2, j % 2);
            let (mut up, mut dn) = (uu, uu);
            up[a][c] += h;
            dn[a][c] -= h;
            let (mut op, mut om) = (ElementOut::default(), ElementOut::default());
            let (mut ap, mut am) = (alpha, alpha);
            evaluate_enhanced(ElementInput { uu: &up, tangent: false, ..input }, &mut ap, &mut op).unwrap();
            evaluate_enhanced(ElementInput { uu: &dn, tangent: false, ..input }, &mut am, &mut om).unwrap();
            for i in 0..8 {
                let fd = (op.f_int[i] - om.f_int[i]) / (2.0 * h);
                worst = worst.max((fd - out.kk[i][j]).abs() / scale);
            }
        }
        assert!(worst < 1e-6, "{law:?}: {worst:e}");
    }
}

/// The element colouring is valid: no two elements of one colour share a node, every element
/// has exactly one colour, and a structured quad mesh needs only 4 colours.
#[test]
fn element_colouring_is_conflict_free() {
    let mesh = mpfem::mesh::shapes::rectangle([0.0, 0.0], 10.0, 7.0, 10, 7);
    let colors = mpfem::assembly::color_elements(&mesh.elements, mesh.nodes.len());
    assert_eq!(colors.len(), 4);
    let mut seen = vec![0; mesh.elements.len()];
    for c in &colors {
        let mut touched = vec![false; mesh.nodes.len()];
        for &e in c {
            seen[e] += 1;
            for &n in &mesh.elements[e] {
                assert!(!touched[n], "two elements of one colour share node {n}");
                touched[n] = true;
            }
        }
    }
    assert!(seen.iter().all(|&k| k == 1));
    let disc = mpfem::mesh::shapes::disc([0.0, 0.0], 5.0, 0.7);
    let colors = mpfem::assembly::color_elements(&disc.elements, disc.nodes.len());
    for c in &colors {
        let mut touched = vec![false; disc.nodes.len()];
        for &e in c {
            for &n in &disc.elements[e] {
                assert!(!touched[n]);
                touched[n] = true;
            }
        }
    }
}
