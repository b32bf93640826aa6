//! The material history written as transferable quadrature-point fields, and back.
//!
//! The history of a Gauss point is [`MatState`]: C_p⁻¹ in the *reference* configuration of the
//! old mesh, ε̄ᵖ and ε̄ᶜ. The new mesh is built in the current configuration, which becomes its
//! reference configuration (new F = I at the start). A reference-frame tensor cannot be
//! interpolated between two meshes with different reference frames, so the state is pushed
//! forward first: with F the old total deformation gradient at the Gauss point,
//!
//! ```text
//!   b_e = F C_p⁻¹ Fᵀ            (spatial elastic left Cauchy–Green tensor)
//! ```
//!
//! and on the new mesh `C_p⁻¹ := b_e`, because then the law's trial tensor F C_p⁻¹ Fᵀ with
//! F = I is the same b_e and gives the same deviatoric Kirchhoff stress τ′ = 2G dev(½ ln b_e)
//! (for the elastic–plastic and creep laws; see the module docs of [`super`] for the elastic
//! law, which ignores C_p⁻¹).
//!
//! ## Components (6 per Gauss point, [`STATE_COMPONENTS`])
//! `[ε_xx, ε_yy, ε_xy, ε_zz, ε̄ᵖ, ε̄ᶜ]` with ε = ½ ln b_e the logarithmic elastic strain
//! (tensor components). The logarithm is transferred instead of b_e itself because any
//! interpolated or projected symmetric ε gives a positive definite b_e = exp(2ε), whereas an L2
//! projection of b_e can overshoot into indefinite tensors near steep gradients; the elastic
//! volume change ln det b_e / 2 = tr ε is then transferred linearly. For homogeneous states
//! both choices are exact. The equivalent strains are clamped at 0 after the transfer (the
//! projection may undershoot slightly near the border of a plastic zone).
// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::transfer::QuadField;
use super::{check_mesh, RemeshError};
use crate::element::{shape_derivs, GAUSS};
use crate::material::logstrain::{check_deformation, hencky_strain, left_cauchy_green, Spectral};
use crate::material::MatState;
use crate::mesh::Mesh;
use nalgebra::Matrix3;

/// Number of transferable components of a material state.
pub const STATE_COMPONENTS: usize = 6;

/// Deformation gradient F = ∂x/∂X of the bilinear element at natural coordinates `xi`, from
/// the reference corners `x0` and the current corners `x` (F = J J₀⁻¹ with J = ∂x/∂ξ,
/// J₀ = ∂X/∂ξ).
///
/// # Errors
/// [`RemeshError::InvertedDeformation`] when det J₀ ≤ 0 or det F ≤ 0 (or not finite).
pub fn deformation_gradient(x0: &[[f64; 2]; 4], x: &[[f64; 2]; 4], xi: [f64; 2]) -> Result<[[f64; 2]; 2], RemeshError> {
    let dn = shape_derivs(xi[0], xi[1]);
    let mut j0 = [[0.0; 2]; 2];
    let mut j = [[0.0; 2]; 2];
    for a in 0..4 {
        for i in 0..2 {
            for k in 0..2 {
                j0[i][k] += x0[a][i] * dn[a][k];
                j[i][k] += x[a][i] * dn[a][k];
            }
        }
    }
    let det0 = j0[0][0] * j0[1][1] - j0[0][1] * j0[1][0];
    if !(det0 > 0.0 && det0.is_finite()) {
        return Err(RemeshError::InvertedDeformation { det: det0 });
    }
    let inv0 = [[j0[1][1] / det0, -j0[0][1] / det0], [-j0[1][0] / det0, j0[0][0] / det0]];
    let f: [[f64; 2]; 2] = std::array::from_fn(|i| std::array::from_fn(|k| j[i][0] * inv0[0][k] + j[i][1] * inv0[1][k]));
    let det = f[0][0] * f[1][1] - f[0][1] * f[1][0];
    if !(det > 0.0 && det.is_finite()) {
        return Err(RemeshError::InvertedDeformation { det });
    }
    Ok(f)
}

fn matrix3(f: &[[f64; 2]; 2]) -> Matrix3<f64> {
    Matrix3::new(f[0][0], f[0][1], 0.0, f[1][0], f[1][1], 0.0, 0.0, 0.0, 1.0)
}

/// The transferable components `[ε_xx, ε_yy, ε_xy, ε_zz, ε̄ᵖ, ε̄ᶜ]` (see the module docs) of a
/// state `state` at a point with total deformation gradient `f` (in-plane block; F₃₃ = 1).
///
/// # Errors
/// det F ≤ 0 or non-finite F ([`RemeshError::InvertedDeformation`]); a C_p⁻¹ that gives a
/// b_e that is not positive definite, or non-finite state values
/// ([`RemeshError::InvalidState`], index 0).
pub fn state_to_components(f: &[[f64; 2]; 2], state: &MatState) -> Result<[f64; STATE_COMPONENTS], RemeshError> {
    let ff = matrix3(f);
    check_deformation(&ff).map_err(|_| RemeshError::InvertedDeformation { det: f[0][0] * f[1][1] - f[0][1] * f[1][0] })?;
    if !(state.cp_inv.iter().all(|v| v.is_finite()) && state.eps_p.is_finite() && state.eps_c.is_finite()) {
        return Err(RemeshError::InvalidState { index: 0, reason: "non-finite history".into() });
    }
    let be = left_cauchy_green(&ff, &state.cp_inv);
    let sp = Spectral::of(&be);
    if !(sp.lam[1] > 0.0 && sp.lam[2] > 0.0) {
        return Err(RemeshError::InvalidState {
            index: 0,
            reason: format!("b_e = F C_p⁻¹ Fᵀ is not positive definite (eigenvalues {:?})", sp.lam),
        });
    }
    let eps = hencky_strain(&be);
    Ok([eps[0], eps[1], eps[2], eps[3], state.eps_p, state.eps_c])
}

/// The state on the new mesh (reference = current configuration) from transferred components:
/// C_p⁻¹ = b_e = exp(2ε), ε̄ᵖ and ε̄ᶜ clamped at 0.
///
/// # Errors
/// Not exactly [`STATE_COMPONENTS`] components, or non-finite values
/// ([`RemeshError::InvalidState`], index 0).
pub fn state_from_components(c: &[f64]) -> Result<MatState, RemeshError> {
    if c.len() != STATE_COMPONENTS {
        return Err(RemeshError::SizeMismatch { what: "state components", expected: STATE_COMPONENTS, got: c.len() });
    }
    if !c.iter().all(|v| v.is_finite()) {
        return Err(RemeshError::InvalidState { index: 0, reason: "non-finite component".into() });
    }
    let sp = Spectral::of(&[c[0], c[1], c[2], c[3]]);
    let be = sp.compose([(2.0 * sp.lam[0]).exp(), (2.0 * sp.lam[1]).exp(), (2.0 * sp.lam[2]).exp()]);
    if !be.iter().all(|v| v.is_finite()) {
        return Err(RemeshError::InvalidState { index: 0, reason: "elastic strain too large for exp".into() });
    }
    Ok(MatState { cp_inv: be, eps_p: c[4].max(0.0), eps_c: c[5].max(0.0) })
}

fn at_point(e: RemeshError, index: usize) -> RemeshError {
    match e {
        RemeshError::InvalidState { reason, .. } => RemeshError::InvalidState { index, reason },
        RemeshError::InvertedDeformation { det } => RemeshError::InvalidState { index, reason: format!("inverted deformation (det = {det:.3e})") },
        other => other,
    }
}

/// The transferable field of the states of an old mesh: `states[e][q]` at Gauss point q of
/// element e, with F from the reference coordinates `x0` and current coordinates `x`.
///
/// # Errors
/// Invalid mesh input (checked for both coordinate sets), a wrong number of states, or a point
/// whose F or state is inadmissible ([`RemeshError::InvalidState`] with the point index 4e + q).
pub fn states_to_field(mesh: &Mesh, x0: &[[f64; 2]], x: &[[f64; 2]], states: &[[MatState; 4]]) -> Result<QuadField, RemeshError> {
    check_mesh(mesh, x0)?;
    check_mesh(mesh, x)?;
    if states.len() != mesh.n_elements() {
        return Err(RemeshError::SizeMismatch { what: "element states", expected: mesh.n_elements(), got: states.len() });
    }
    let mut field = QuadField::zeros(mesh.n_elements(), STATE_COMPONENTS);
    for (e, el) in mesh.elements.iter().enumerate() {
        let (p0, p) = (el.map(|n| x0[n]), el.map(|n| x[n]));
        for (q, gp) in GAUSS.iter().enumerate() {
            let i = 4 * e + q;
            let f = deformation_gradient(&p0, &p, *gp).map_err(|err| at_point(err, i))?;
            let c = state_to_components(&f, &states[e][q]).map_err(|err| at_point(err, i))?;
            field.point_mut(i).copy_from_slice(&c);
        }
    }
    Ok(field)
}

/// The states of the new mesh from a transferred field ([`STATE_COMPONENTS`] components,
/// 4 points per element).
///
/// # Errors
/// A field with another component count or a point count not a multiple of 4, or a
/// non-finite value ([`RemeshError::InvalidState`] with the point index).
pub fn states_from_field(field: &QuadField) -> Result<Vec<[MatState; 4]>, RemeshError> {
    if field.n_comp != STATE_COMPONENTS {
        return Err(RemeshError::SizeMismatch { what: "state field components", expected: STATE_COMPONENTS, got: field.n_comp });
    }
    if field.values.len() % (4 * STATE_COMPONENTS) != 0 {
        return Err(RemeshError::SizeMismatch {
            what: "state field values",
            expected: field.values.len().div_ceil(4 * STATE_COMPONENTS) * 4 * STATE_COMPONENTS,
            got: field.values.len(),
        });
    }
    let ne = field.values.len() / (4 * STATE_COMPONENTS);
    let mut out = vec![[MatState::default(); 4]; ne];
    for (e, s) in out.iter_mut().enumerate() {
        for (q, sq) in s.iter_mut().enumerate() {
            let i = 4 * e + q;
            *sq = state_from_components(field.point(i)).map_err(|err| at_point(err, i))?;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{ConstitutiveLaw, HardeningTable, J2Plastic, TimeIncrement};
    use crate::mesh::shapes;
    use crate::remesh::transfer::FieldTransfer;

    const INC: TimeIncrement = TimeIncrement { time: 1.0, dt: 1.0 };

    fn law() -> J2Plastic {
        let h = HardeningTable::from_plastic_strain(&[[0.0, 100.0], [0.1, 150.0], [1.0, 200.0]]).unwrap();
        J2Plastic::new(70_000.0, 0.3, h)
    }

    /// F1: a large isochoric-ish shear + compression (plastic); F2: partly unloaded from F1
    /// (elastic from the state of F1).
    fn f1() -> [[f64; 2]; 2] {
        [[0.8, 0.35], [0.05, 1.15]]
    }
    fn f2() -> [[f64; 2]; 2] {
        let a = f1();
        // back by 0.1 % towards F1 scaled: a small elastic unloading
        [[a[0][0] * 1.0008, a[0][1] * 0.999], [a[1][0], a[1][1] * 0.9995]]
    }

    /// A plastic state, and the stress at F2 computed by the law from the old reference frame.
    fn loaded() -> (MatState, [f64; 4]) {
        let l = law();
        let s1 = l.update(&matrix3(&f1()), &MatState::default(), INC).unwrap().state;
        assert!(s1.eps_p > 0.1, "the loading is plastic: {s1:?}");
        let r2 = l.update(&matrix3(&f2()), &s1, INC).unwrap();
        assert_eq!(r2.state.eps_p, s1.eps_p, "F2 is an elastic unloading");
        (MatState { eps_c: 0.0123, ..s1 }, r2.tau)
    }

    fn rel(a: &[f64; 4], b: &[f64; 4]) -> f64 {
        let n = b.iter().map(|v| v.abs()).fold(0.0, f64::max);
        a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max) / n
    }

    /// One point: (F2, state) → components → new state with F = I gives the same Kirchhoff
    /// stress, through the J2 law itself (its elastic branch evaluates τ′ = 2G dev(½ ln b_e)
    /// with b_e = F C_p⁻¹ Fᵀ). Tolerance 1e-10 relative: ln/exp and two closed-form
    /// eigen-decompositions of tensors with eigenvalues of order 1 lose only a few ulps.
    #[test]
    fn kirchhoff_stress_reproduced_at_a_point() {
        let (s, tau_old) = loaded();
        let c = state_to_components(&f2(), &s).unwrap();
        let s_new = state_from_components(&c).unwrap();
        let r = law().update(&Matrix3::identity(), &s_new, INC).unwrap();
        assert!(rel(&r.tau, &tau_old) < 1e-10, "{:?} vs {:?}", r.tau, tau_old);
        assert_eq!(r.state.eps_p, s.eps_p, "still elastic on the new mesh");
        assert_eq!((s_new.eps_p, s_new.eps_c), (s.eps_p, s.eps_c));
        // the new C_p⁻¹ is b_e of the old point
        let be = left_cauchy_green(&matrix3(&f2()), &s.cp_inv);
        assert!(rel(&s_new.cp_inv, &be) < 1e-12);
        // and a virgin state at F = I stays virgin (identity, zero strains)
        let v = state_from_components(&state_to_components(&[[1.0, 0.0], [0.0, 1.0]], &MatState::default()).unwrap()).unwrap();
        assert_eq!(v, MatState::default());
    }

    /// A homogeneous deformation F2 of a disc mesh with the same plastic state at every Gauss
    /// point, transferred to another disc mesh built in the current configuration (the
    /// affine image of a disc mesh of another density; its boundary nodes lie outside the old
    /// polygon, where the clamping still keeps constants): the Kirchhoff stress at every new
    /// Gauss point equals the old one to 1e-10 relative (constant fields pass the L2
    /// projection and interpolation to round-off, see the transfer tests).
    #[test]
    fn homogeneous_state_transferred_between_meshes() {
        let (s, tau_old) = loaded();
        let old = shapes::disc([0.0, 0.0], 1.0, 0.15);
        let f = f2();
        let c = [0.3, -0.1];
        let move_ = |p: &[f64; 2]| [f[0][0] * p[0] + f[0][1] * p[1] + c[0], f[1][0] * p[0] + f[1][1] * p[1] + c[1]];
        let x_old: Vec<[f64; 2]> = old.nodes.iter().map(move_).collect();
        let new = shapes::disc([0.0, 0.0], 1.0, 0.11);
        let x_new: Vec<[f64; 2]> = new.nodes.iter().map(move_).collect();
        // F recovered from the nodal coordinates at every Gauss point
        for el in &old.elements {
            let g = deformation_gradient(&el.map(|n| old.nodes[n]), &el.map(|n| x_old[n]), GAUSS[2]).unwrap();
            for i in 0..2 {
                for k in 0..2 {
                    assert!((g[i][k] - f[i][k]).abs() < 1e-12);
                }
            }
        }
        let states = vec![[s; 4]; old.n_elements()];
        let field = states_to_field(&old, &old.nodes, &x_old, &states).unwrap();
        let mut t = FieldTransfer::new(&old, &x_old, &new, &x_new).unwrap();
        assert!(t.node_stats().n_outside > 0, "the test covers clamped points");
        let moved = t.quadrature_field(&field).unwrap();
        let new_states = states_from_field(&moved).unwrap();
        assert_eq!(new_states.len(), new.n_elements());
        let l = law();
        let mut worst: f64 = 0.0;
        for st in new_states.iter().flatten() {
            let r = l.update(&Matrix3::identity(), st, INC).unwrap();
            worst = worst.max(rel(&r.tau, &tau_old));
            assert!((st.eps_p - s.eps_p).abs() < 1e-12 && (st.eps_c - s.eps_c).abs() < 1e-12);
        }
        assert!(worst < 1e-10, "worst relative stress difference {worst:e}");
    }

    #[test]
    fn degenerate_input() {
        let s = MatState::default();
        assert!(matches!(state_to_components(&[[1.0, 0.0], [0.0, -1.0]], &s), Err(RemeshError::InvertedDeformation { .. })));
        let bad = MatState { cp_inv: [1.0, -1.0, 0.0, 1.0], ..s };
        assert!(matches!(state_to_components(&[[1.0, 0.0], [0.0, 1.0]], &bad), Err(RemeshError::InvalidState { .. })));
        let nan = MatState { eps_p: f64::NAN, ..s };
        assert!(state_to_components(&[[1.0, 0.0], [0.0, 1.0]], &nan).is_err());
        assert!(state_from_components(&[0.0; 5]).is_err());
        assert!(state_from_components(&[0.0, 0.0, f64::INFINITY, 0.0, 0.0, 0.0]).is_err());
        assert!(state_from_components(&[1e3, 0.0, 0.0, 0.0, 0.0, 0.0]).is_err(), "exp overflow");
        // negative equivalent strains (projection undershoot) are clamped
        let c = state_from_components(&[0.0, 0.0, 0.0, 0.0, -1e-6, -2e-6]).unwrap();
        assert_eq!((c.eps_p, c.eps_c), (0.0, 0.0));
        // element map degenerate
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let flat = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 0.0]];
        assert!(deformation_gradient(&flat, &sq, [0.0, 0.0]).is_err());
        assert!(deformation_gradient(&sq, &flat, [0.0, 0.0]).is_err());
        // states_to_field reports the point
        let m = shapes::rectangle([0.0, 0.0], 1.0, 1.0, 1, 1);
        let mut x = m.nodes.clone();
        x.iter_mut().for_each(|p| p[0] = -p[0]); // mirrored: det F = −1 everywhere
        let err = states_to_field(&m, &m.nodes, &x, &[[s; 4]]).unwrap_err();
        assert!(matches!(err, RemeshError::InvalidState { index: 0, .. }), "{err:?}");
        assert!(states_to_field(&m, &m.nodes, &m.nodes, &[]).is_err());
        assert!(states_from_field(&QuadField::zeros(1, 5)).is_err());
        assert!(states_from_field(&QuadField { n_comp: 6, values: vec![0.0; 30] }).is_err());
    }
}
