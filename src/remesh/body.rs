//! The element history of one particle carried from its old mesh to a new one: what the
//! solver keeps per element ([`BodyState`]: material states at the four Gauss points, the
//! initial volume ratio j₀ and the augmented-Lagrangian pressure λ_e) computed for the new mesh,
//! which is built in the current configuration (its reference = current, displacement 0).
//!
//! - **Material states**: written as the transferable components of [`super::state`] (the
//!   logarithmic elastic strain ½ ln b_e, ε̄ᵖ, ε̄ᶜ) with the old total deformation gradient,
//!   moved by the consistent L2 projection ([`FieldTransfer::quadrature_field`]) and read back
//!   with C_p⁻¹ := b_e.
//! - **j₀**: the old element's total volume ratio j₀ v_e/V_e (v_e current, V_e reference
//!   area), as ln(j₀ v_e/V_e) at its four points, moved by the bounded lumped projection
//!   ([`FieldTransfer::quadrature_field_lumped`]: element-wise constant data jump from element
//!   to element, where the consistent projection overshoots) and averaged over the four points
//!   of each new element (P0), then exponentiated.
//! - **λ_e**: like ln j₀ (lumped, element average).
//!
//! For a homogeneous deformation everything is reproduced to round-off (the test below); for
//! a non-uniform one the accuracy is that of the transfer (second order for the states, see
//! [`super::transfer`]).

use super::{area_check, states_from_field, states_to_field, AreaCheck, FieldTransfer, NodalField, QuadField, RemeshError, TransferStats};
use crate::material::MatState;
use crate::mesh::Mesh;

/// Per-element history of one particle, in the solver's layout.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyState {
    pub states: Vec<[MatState; 4]>,
    /// Initial volume ratio per element (1 for a mesh built stress-free).
    pub j0: Vec<f64>,
    /// Augmented-Lagrangian element pressure λ_e (MPa); zeros for compressible bodies.
    pub lambda: Vec<f64>,
}

/// The transferred history and what the transfer saw.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyTransfer {
    pub state: BodyState,
    /// How many new Gauss points fell outside the old mesh, and how far.
    pub quadrature: TransferStats,
    /// Old (current configuration) and new areas.
    pub area: AreaCheck,
    /// The nodal fields given to [`transfer_body`], interpolated at the new nodes (same order).
    pub nodal: Vec<NodalField>,
}

/// Carry `old_state` of a particle meshed by `old` (reference coordinates `x0_old`, current
/// `x_old`) over to `new` (nodes in the current configuration), and the nodal fields `nodal`
/// of the old nodes (displacement increments, velocities) to the new nodes, with one point
/// location and one projector for all of them.
///
/// # Errors
/// Inconsistent sizes (states, j₀ or λ not one per old element), invalid meshes or
/// coordinates, an inverted old element, an inadmissible old state.
pub fn transfer_body(old: &Mesh, x0_old: &[[f64; 2]], x_old: &[[f64; 2]], old_state: &BodyState, nodal: &[NodalField], new: &Mesh) -> Result<BodyTransfer, RemeshError> {
    let ne = old.elements.len();
    for (what, got) in [("old states", old_state.states.len()), ("old j0", old_state.j0.len()), ("old lambda", old_state.lambda.len())] {
        if got != ne {
            return Err(RemeshError::SizeMismatch { what, expected: ne, got });
        }
    }
    let mut transfer = FieldTransfer::new(old, x_old, new, &new.nodes)?;
    let states = states_from_field(&transfer.quadrature_field(&states_to_field(old, x0_old, x_old, &old_state.states)?)?)?;
    // ln(total volume ratio) and λ per old element, at its four points
    let mut elem = QuadField::zeros(ne, 2);
    for (e, el) in old.elements.iter().enumerate() {
        let big_v = crate::mesh::polygon_area(el.iter().map(|&n| x0_old[n]));
        let v = crate::mesh::polygon_area(el.iter().map(|&n| x_old[n]));
        let theta = old_state.j0[e] * v / big_v;
        if !(theta > 0.0 && theta.is_finite()) {
            return Err(RemeshError::InvertedDeformation { det: theta });
        }
        for q in 0..4 {
            elem.point_mut(4 * e + q).copy_from_slice(&[theta.ln(), old_state.lambda[e]]);
        }
    }
    let moved = transfer.quadrature_field_lumped(&elem)?;
    let n_new = new.elements.len();
    let mut j0 = vec![0.0; n_new];
    let mut lambda = vec![0.0; n_new];
    for e in 0..n_new {
        let (mut ln_t, mut lam) = (0.0, 0.0);
        for q in 0..4 {
            let p = moved.point(4 * e + q);
            ln_t += 0.25 * p[0];
            lam += 0.25 * p[1];
        }
        j0[e] = ln_t.exp();
        lambda[e] = lam;
    }
    let nodal = nodal.iter().map(|f| transfer.nodal_field(f)).collect::<Result<Vec<_>, _>>()?;
    let area = area_check(old, x_old, new, &new.nodes)?;
    Ok(BodyTransfer { state: BodyState { states, j0, lambda }, quadrature: transfer.quadrature_stats(), area, nodal })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;

    /// A disc deformed homogeneously (x = F X, det F = 0.78) carrying a homogeneous plastic
    /// state (C_p⁻¹ ≠ I, ε̄ᵖ = 0.05, ε̄ᶜ = 0.01), j₀ = 1.1 and λ = 3 MPa, re-meshed on its
    /// deformed boundary: every new Gauss point gets C_p⁻¹ = F C_p⁻¹_old Fᵀ (the old b_e), the
    /// same ε̄ᵖ, ε̄ᶜ, every new element j₀ = 1.1 det F and λ = 3, to 1e-10 (round-off of the
    /// projections and of exp/ln); the area is kept to 1e-12 (same boundary polygon).
    #[test]
    fn homogeneous_history_is_carried_over_exactly() {
        let old = shapes::disc([5.0, -2.0], 10.0, 2.0);
        let f = [[1.1, 0.3], [-0.1, 0.72]];
        let det = f[0][0] * f[1][1] - f[0][1] * f[1][0];
        let x_old: Vec<[f64; 2]> = old.nodes.iter().map(|p| [f[0][0] * p[0] + f[0][1] * p[1], f[1][0] * p[0] + f[1][1] * p[1]]).collect();
        let cp = [1.05, 0.96, 0.02, 0.99]; // [xx, yy, xy, zz], SPD
        let st = MatState { cp_inv: cp, eps_p: 0.05, eps_c: 0.01 };
        let ne = old.elements.len();
        let old_state = BodyState { states: vec![[st; 4]; ne], j0: vec![1.1; ne], lambda: vec![3.0; ne] };
        let new = super::super::remesh_particle(&old, &x_old, 1.5).unwrap();
        let out = transfer_body(&old, &old.nodes, &x_old, &old_state, &[], &new).unwrap();
        assert!(out.area.relative_change.abs() < 1e-12, "{:?}", out.area);
        // b_e = F C_p⁻¹ Fᵀ (in-plane block), zz unchanged (F₃₃ = 1)
        let c = [[cp[0], cp[2]], [cp[2], cp[1]]];
        let mut b = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                for k in 0..2 {
                    for l in 0..2 {
                        b[i][j] += f[i][k] * c[k][l] * f[j][l];
                    }
                }
            }
        }
        let expect = [b[0][0], b[1][1], b[0][1], cp[3]];
        let mut worst: f64 = 0.0;
        for s in out.state.states.iter().flatten() {
            for k in 0..4 {
                worst = worst.max((s.cp_inv[k] - expect[k]).abs());
            }
            worst = worst.max((s.eps_p - 0.05).abs()).max((s.eps_c - 0.01).abs());
        }
        assert!(worst < 1e-10, "states differ by {worst:.3e}");
        let wj = out.state.j0.iter().map(|j| (j - 1.1 * det).abs()).fold(0.0, f64::max);
        let wl = out.state.lambda.iter().map(|l| (l - 3.0).abs()).fold(0.0, f64::max);
        assert!(wj < 1e-10 && wl < 1e-10, "j0 {wj:.3e}, lambda {wl:.3e}");
        assert_eq!(out.state.states.len(), new.elements.len());
    }

    /// Wrong sizes are errors, not panics.
    #[test]
    fn size_mismatch_is_an_error() {
        let old = shapes::disc([0.0, 0.0], 5.0, 1.0);
        let ne = old.elements.len();
        let bad = BodyState { states: vec![[MatState::default(); 4]; ne], j0: vec![1.0; ne - 1], lambda: vec![0.0; ne] };
        let e = transfer_body(&old, &old.nodes, &old.nodes, &bad, &[], &old).unwrap_err();
        assert!(matches!(e, RemeshError::SizeMismatch { what: "old j0", .. }), "{e}");
    }
}
