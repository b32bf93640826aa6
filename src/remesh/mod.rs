//! Building blocks for the adaptive re-meshing of deformed particles: when to re-mesh
//! ([`monitor`]), where the points of a new mesh lie in the old one ([`locate`]), how
//! quadrature-point and nodal fields move from the old to the new mesh ([`transfer`]), and how
//! the material history is written as transferable fields ([`state`]).
//!
//! The mesher of the new particle mesh (the deformed boundary polygon meshed with
//! quadrilaterals) lives in [`crate::mesh`]; everything here works for any pair of
//! [`Mesh`]es of (nearly) the same region.
//!
//! ## Conventions
//! - A mesh is always passed with the nodal coordinates it is to be read in (`coords`, same
//!   length as `mesh.nodes`): the *old* mesh in its current (deformed) configuration, the *new*
//!   mesh in its own nodes (built in the current configuration, so for the new mesh
//!   reference = current).
//! - Quadrature points are those of the element, [`crate::element::GAUSS`] (2×2 Gauss, weights
//!   1), numbered `4 e + q` in the order of `GAUSS`; the position of point q of element e is
//!   `Σ_a N_a(ξ_q) x_a` with [`crate::element::shape`].
//! - A field with `n` components per point is one flat `Vec<f64>` with the components of a
//!   point next to each other ([`QuadField`], [`NodalField`]).
//!
//! ## The transfer (see [`transfer`] for the details and the measured accuracy)
//! 1. Old quadrature-point values are projected onto the old nodes by the global L2 projection
//!    with the consistent mass matrix of the bilinear shape functions (faer sparse Cholesky).
//! 2. The nodal field is interpolated with the old shape functions at the new points, located
//!    in the old mesh by a uniform bucket grid and a Newton inversion of the bilinear map.
//! 3. New points outside the old mesh (the new boundary differs from the old one by round-off or
//!    by boundary resampling, e.g. a chord across a concave old boundary vertex) take the value
//!    at the closest point of the nearest old element ("clamped" natural coordinates). This
//!    keeps bounds and constants but is only first-order accurate there: a linear field is not
//!    reproduced exactly at such points (error ≤ |∇f| × distance). [`TransferStats`] reports how
//!    many points were outside and how far.
//!
//! ## Integration into the solver
//! [`body::transfer_body`] does items 3, 5 and 6 below for one particle (material states, j₀,
//! λ_e), tested exact for a homogeneous history, and
//! [`crate::solver::Simulation::remesh_body`] re-meshes a body of a running simulation with it
//! (tested mid-run: wall forces within 1 %). With `[remesh]` in the case
//! ([`crate::case::RemeshSpec`]) the solver calls it after every converged step for the worst
//! free particle that crosses the quality limits (one per step), and once per step for the particle of an inverted
//! element when its mesh is already near the limits; then
//! [`crate::solver::Simulation::equilibrate`] balances the transferred state in place
//! (Δt = 0: 6 Newton iterations in the mid-run test). The history's `remeshes` column counts
//! them; results.h5 writes each step's own mesh. Still missing: contact history (stick points,
//! multipliers) and a boundary resampling that does not add the midpoints of the kept boundary
//! edges at every re-mesh (see the closing notes of the re-meshing issue).
//!
//! The list of what a re-mesh carries over, item by item:
//! At a re-mesh of body b at the end of a committed step (the solver is not modified by this
//! module; this is the list of what it has to carry over):
//! 1. **Trigger**: [`monitor::check_quality`] on the body's mesh with the current coordinates
//!    `x = X + u`, after each committed step (cheap: O(elements)). Per body b of the model:
//!    `mesh = model.bodies[b].mesh` (local numbering), `X = model.x0[off..off + n]` and
//!    `x = X + u` on the same range (`off = node_offset`, `n = mesh.n_nodes()`), states
//!    `sol.fields.states[eoff..eoff + ne]` (`eoff = elem_offset`).
//! 2. **Geometry**: the new mesh is built from the current boundary polyline of the body; the
//!    new reference coordinates are the current ones; u := 0 for the new nodes; velocities and
//!    accelerations of the dynamic analysis are nodal fields: [`FieldTransfer::nodal_field`].
//!    [`area_check`] confirms that the body area was kept.
//! 3. **Material history** (`sol.fields.states`, `[MatState; 4]` per element): with F the old
//!    total deformation gradient at each old Gauss point ([`state::deformation_gradient`]),
//!    write `(F, MatState)` as the six components of [`state::state_to_components`] (the
//!    logarithmic elastic strain ½ ln(F C_p⁻¹ Fᵀ), ε̄ᵖ, ε̄ᶜ) with [`state::states_to_field`],
//!    transfer them with [`FieldTransfer::quadrature_field`], and read the new states with
//!    [`state::states_from_field`] (C_p⁻¹ := b_e, because the new F = I). The deviatoric
//!    Kirchhoff stress is then reproduced: to 1e-10 for a homogeneous deformation, with
//!    second-order convergence for a non-uniform one (`tests/remesh.rs`).
//! 4. **Elastic law** (done): [`crate::material::Elastic`] starts from `old.cp_inv`
//!    (b = F C_p⁻¹ Fᵀ), so the pushed-forward C_p⁻¹ := b_e carries its stress; identical
//!    results while `cp_inv` stays the identity, as it does for an elastic body that was never
//!    re-meshed.
//! 5. **Volumetric state (Q1/P0)** (the element side is done): the element pressure comes from
//!    Θ = j₀ v_e/V_e with V_e the reference area and j₀ the per-element initial volume ratio
//!    `sol.j0` ([`crate::solver::Solution::j0`], 1 by default); on the new mesh v_e = V_e, so
//!    j₀ := Θ_old keeps the pressure. j₀ also divides the laws' deviatoric Kirchhoff stress
//!    (the laws' stresses are per unit original volume; see the module docs of
//!    [`crate::element`]): without it the deviatoric Cauchy stress of a re-meshed element
//!    would be J_old times too large. J₀ is transferred as a field: ln Θ_old, constant per
//!    old element, repeated at its four Gauss points, transferred with
//!    [`FieldTransfer::quadrature_field_lumped`] and averaged over the four Gauss points of
//!    each new element (P0). The lumped (bounded) projection is preferred for these
//!    element-wise constant data, which jump from element to element: the consistent
//!    projection overshoots at jumps (see [`transfer`]). With the states of item 3 and j₀ the
//!    Cauchy stress, pressure and internal force of a homogeneously deformed element are
//!    reproduced to 1e-10, and a further increment gives the same result as on the old mesh
//!    (`tests/rereference.rs`). Still to do at the re-mesh: the mass of an implicit dynamic
//!    analysis (density per unit new reference area ρ/j₀) and the solver's volume-error
//!    report, which compares with the areas at start-up.
//! 6. **Augmented-Lagrangian multipliers** λ_e (`sol.lambda`, incompressible bodies): a pressure
//!    per element, transferred like ln Θ (Gauss-point field, then element average). After the
//!    transfer the first step runs its Uzawa updates as usual, from the transferred λ_e.
//! 7. **Enhanced modes** α (Q1/E4, `sol.fields.alpha`): element-internal parameters, not
//!    transferable; reset to 0 (they are re-solved element by element at the next evaluation).
//! 8. **Stresses for output** (`sol.fields.sig`): recomputed by the first assembly on the new
//!    mesh; not transferred.
//! 9. **Contact history**: keyed by node and master segment (node-to-segment pairs, sticking
//!    anchors ξ_stick, normal/tangential multipliers) and by wall and node. The new boundary
//!    nodes are located on the old boundary polyline: for each new boundary node, the old
//!    boundary edge it lies on (closest old boundary edge) gives its pair history by
//!    interpolating the two old nodes' histories (multipliers and gaps linearly; sticking
//!    anchors are re-projected from the current position of the master point); pairs whose
//!    master segment belonged to the re-meshed body are re-searched from scratch (the search is
//!    frozen per step anyway). Frictionless contact needs no history beyond the multipliers,
//!    which are re-established by the augmentation loop of the first step. The contact problem's
//!    segments, slave lists, nodal areas and Lagrange multiplier candidates must be rebuilt,
//!    which also changes the sparsity pattern (new analysis of the linear solver).
//! 10. **Model bookkeeping**: node and element offsets of all later bodies, prescribed dofs,
//!     loads and node groups referring to the body, the assembler (equation numbers, colours,
//!     pattern) and the work vectors are rebuilt, as at start-up.
//! 11. **Re-equilibration**: the transferred state is smooth but not in equilibrium on the new
//!     mesh (projection error, smeared plastic-zone borders). The driver should run one
//!     Newton solve at the committed load and time (dt = 0, no creep increment) before the
//!     next step, and log the size of the residual it removed.
// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod body;
pub mod locate;
pub mod monitor;
pub mod state;
pub mod transfer;

use crate::mesh::Mesh;
use thiserror::Error;

pub use body::{transfer_body, BodyState, BodyTransfer};
pub use locate::{Location, PointLocator};
pub use monitor::{check_quality, QualityCheck, QualityLimits, QualityMeasure, Worst};
pub use state::{deformation_gradient, state_from_components, state_to_components, states_from_field, states_to_field, STATE_COMPONENTS};
pub use transfer::{quadrature_points, FieldTransfer, L2Projector, NodalField, QuadField, TransferStats};

/// Why a re-meshing building block could not do its work.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RemeshError {
    #[error("the mesh has no elements")]
    EmptyMesh,
    #[error("{what}: expected {expected} entries, got {got}")]
    SizeMismatch { what: &'static str, expected: usize, got: usize },
    #[error("element {element} refers to node {node}, but there are only {n_nodes} nodes")]
    BadNodeIndex { element: usize, node: usize, n_nodes: usize },
    #[error("{what} {index} is not finite")]
    NonFinite { what: &'static str, index: usize },
    #[error("element {element} is inverted or degenerate in the given coordinates (scaled Jacobian {scaled_jacobian:.3e})")]
    InvalidElement { element: usize, scaled_jacobian: f64 },
    #[error("a field needs at least one component per point")]
    NoComponents,
    #[error("the L2 projection failed: {0}")]
    Projection(String),
    #[error("inverted or degenerate element map or deformation (det = {det:.3e})")]
    InvertedDeformation { det: f64 },
    #[error("material state {index}: {reason}")]
    InvalidState { index: usize, reason: String },
    #[error("the particle's boundary has {0} loops; expected one (a particle without holes)")]
    BoundaryLoops(usize),
    #[error("meshing the deformed boundary failed: {0}")]
    Mesher(String),
}

/// Checks shared by the building blocks: at least one element, one coordinate pair per node,
/// node indices in range and finite coordinates.
pub(crate) fn check_mesh(mesh: &Mesh, coords: &[[f64; 2]]) -> Result<(), RemeshError> {
    if mesh.elements.is_empty() {
        return Err(RemeshError::EmptyMesh);
    }
    if coords.len() != mesh.nodes.len() {
        return Err(RemeshError::SizeMismatch { what: "nodal coordinates", expected: mesh.nodes.len(), got: coords.len() });
    }
    let n_nodes = coords.len();
    for (e, el) in mesh.elements.iter().enumerate() {
        if let Some(&node) = el.iter().find(|&&n| n >= n_nodes) {
            return Err(RemeshError::BadNodeIndex { element: e, node, n_nodes });
        }
    }
    if let Some(i) = coords.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
        return Err(RemeshError::NonFinite { what: "node", index: i });
    }
    Ok(())
}

/// Total areas of an old and a new mesh of one body (mm², shoelace formula, exact for the
/// bilinear elements).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaCheck {
    pub old_area: f64,
    pub new_area: f64,
    /// (new − old) / old.
    pub relative_change: f64,
}

/// Areas of the old mesh (in `old_coords`) and the new mesh (in `new_coords`). When the new
/// mesh keeps the old boundary polyline the two agree to round-off; resampling the boundary
/// changes the area by the segments cut off or added.
///
/// # Errors
/// Invalid mesh input (see [`RemeshError`]) or a non-positive old area.
pub fn area_check(old_mesh: &Mesh, old_coords: &[[f64; 2]], new_mesh: &Mesh, new_coords: &[[f64; 2]]) -> Result<AreaCheck, RemeshError> {
    check_mesh(old_mesh, old_coords)?;
    check_mesh(new_mesh, new_coords)?;
    let old_area = old_mesh.area(old_coords);
    let new_area = new_mesh.area(new_coords);
    if !(old_area > 0.0) {
        return Err(RemeshError::InvalidElement { element: 0, scaled_jacobian: old_area });
    }
    Ok(AreaCheck { old_area, new_area, relative_change: (new_area - old_area) / old_area })
}

#[cfg(test)]
pub(crate) mod test_support {
    //! Meshes for the tests: generator meshes moved by a smooth displacement that emulates a
    //! deformed particle.
    use crate::mesh::Mesh;

    /// Current coordinates x = A X + c + bubble(X), with the bubble vanishing on the boundary
    /// of the rectangle `[0, w] × [0, h]`: the boundary stays the image of the rectangle under
    /// the affine map, which is the same polygon for every mesh of the rectangle.
    pub fn deform_rectangle(mesh: &Mesh, w: f64, h: f64, amp: f64) -> Vec<[f64; 2]> {
        use std::f64::consts::PI;
        mesh.nodes
            .iter()
            .map(|&[x, y]| {
                let b = (PI * x / w).sin() * (PI * y / h).sin();
                let bx = amp * b * (2.0 * PI * y / h).cos();
                let by = amp * b * (PI * x / w).cos();
                let (u, v) = (x + bx, y + by);
                affine([u, v])
            })
            .collect()
    }

    /// The affine part used by the deformation helpers: a shear and a compression.
    pub fn affine(p: [f64; 2]) -> [f64; 2] {
        [1.1 * p[0] + 0.25 * p[1] + 0.3, -0.05 * p[0] + 0.8 * p[1] - 0.2]
    }

    /// Smooth displacement of a disc mesh of radius `r` about the origin with a bubble that
    /// vanishes on the circle, followed by the affine map.
    pub fn deform_disc(mesh: &Mesh, r: f64, amp: f64) -> Vec<[f64; 2]> {
        mesh.nodes
            .iter()
            .map(|&[x, y]| {
                let b = 1.0 - (x * x + y * y) / (r * r);
                let u = x + amp * b * (y / r);
                let v = y + amp * b * (x / r) * (x / r);
                affine([u, v])
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::*;
    use super::*;
    use crate::mesh::shapes;

    /// Two rectangle meshes of different density, both with the same deformed boundary: the
    /// areas agree to round-off (1e-12 relative: shoelace sums of a few hundred terms of size
    /// ≤ 1).
    #[test]
    fn area_kept_with_same_boundary() {
        let old = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 12, 7);
        let new = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 21, 9);
        let xo = deform_rectangle(&old, 2.0, 1.0, 0.15);
        let xn: Vec<[f64; 2]> = new.nodes.iter().map(|&p| affine(p)).collect();
        let a = area_check(&old, &xo, &new, &xn).unwrap();
        assert!(a.relative_change.abs() < 1e-12, "{a:?}");
        // the affine map has det = 1.1 * 0.8 + 0.25 * 0.05 = 0.8925
        assert!((a.old_area - 2.0 * 0.8925).abs() < 1e-12);
    }

    /// Discs of two densities: the inscribed polygons differ, the finer one is larger and both
    /// are below π r² by O(h²).
    #[test]
    fn area_of_resampled_boundary_differs() {
        let coarse = shapes::disc([0.0, 0.0], 1.0, 0.4);
        let fine = shapes::disc([0.0, 0.0], 1.0, 0.1);
        let a = area_check(&coarse, &coarse.nodes, &fine, &fine.nodes).unwrap();
        assert!(a.relative_change > 0.0 && a.relative_change < 0.05, "{a:?}");
        assert!(a.new_area < std::f64::consts::PI);
    }

    #[test]
    fn degenerate_input_is_an_error() {
        let m = shapes::rectangle([0.0, 0.0], 1.0, 1.0, 2, 2);
        let empty = Mesh::default();
        assert_eq!(area_check(&empty, &[], &m, &m.nodes), Err(RemeshError::EmptyMesh));
        assert!(matches!(area_check(&m, &m.nodes[1..], &m, &m.nodes), Err(RemeshError::SizeMismatch { .. })));
        let mut bad = m.nodes.clone();
        bad[3][1] = f64::NAN;
        assert!(matches!(area_check(&m, &bad, &m, &m.nodes), Err(RemeshError::NonFinite { .. })));
        let mut m2 = m.clone();
        m2.elements[0][2] = 99;
        assert!(matches!(area_check(&m2, &m2.nodes, &m, &m.nodes), Err(RemeshError::BadNodeIndex { .. })));
    }
}

/// A new mesh of a deformed particle, built on its current boundary (every boundary node at
/// its current position `coords`, in the order of the boundary loop) with quadrilaterals of
/// size about `h` by [`crate::mesh::polygon::simple_polygon`]. The new mesh's nodes are in the
/// current configuration (its reference = current). See [`remesh_particle_keeping`], which
/// this is with no point held.
///
/// # Errors
/// As [`remesh_particle_keeping`].
pub fn remesh_particle(mesh: &Mesh, coords: &[[f64; 2]], h: f64) -> Result<Mesh, RemeshError> {
    remesh_particle_keeping(mesh, coords, h, &[])
}

/// [`remesh_particle`] with the boundary nodes `hold` (node numbers of `mesh`) and their
/// neighbours along the boundary kept exactly where they are: the nodes in contact, whose positions set the penetrations and with them
/// the contact forces (a penalty contact penetrates by p/ε, a fraction of a millimetre on the
/// asphalt jobs; moving a contact face by the coarsening tolerance 0.05 `h` = 1.25 mm there
/// changed the contact forces by 20 %).
///
/// The boundary is first coarsened to a spacing of about `2h` ([`coarsen_outline_keeping`]:
/// corners, strongly curved stretches and held nodes keep their points), because the mesher
/// adds the midpoint of every side; without it each re-mesh would double the boundary points.
/// The coarsened polygon's free points are then offset along their vertex normals by the one
/// distance that gives it the old area back ([`restore_area_keeping`]), so the particle's area
/// is unchanged to round-off (1e-12) while its free boundary moves by at most the coarsening
/// tolerance (0.05 `h`) plus that offset, and a held stretch not at all (the mesher's side
/// midpoints between two held nodes lie on the old boundary). When every point is held, or the
/// coarsened polygon is refused, the whole outline is meshed as it is.
///
/// # Errors
/// The checks of the other building blocks, a boundary with more or fewer than one loop, or a
/// boundary polygon the mesher refuses (self-intersecting after an inverted element, say).
pub fn remesh_particle_keeping(mesh: &Mesh, coords: &[[f64; 2]], h: f64, hold: &[usize]) -> Result<Mesh, RemeshError> {
    check_mesh(mesh, coords)?;
    let loops = mesh.boundary_loops();
    if loops.len() != 1 {
        return Err(RemeshError::BoundaryLoops(loops.len()));
    }
    let held: std::collections::HashSet<usize> = hold.iter().copied().collect();
    let outline: Vec<[f64; 2]> = loops[0].iter().map(|&n| coords[n]).collect();
    // the held nodes and their neighbours along the boundary: the sides next to a contact
    // zone carry the pairs at its edge
    let m = loops[0].len();
    let hit: Vec<bool> = loops[0].iter().map(|n| held.contains(n)).collect();
    let keep: Vec<bool> = (0..m).map(|i| hit[i] || hit[(i + 1) % m] || hit[(i + m - 1) % m]).collect();
    let area = signed_area(&outline);
    let kept = coarsen_outline_keeping(&outline, &keep, 2.0 * h, 0.05 * h, CORNER_DEG);
    let coarse: Vec<[f64; 2]> = kept.iter().map(|&i| outline[i]).collect();
    let fixed: Vec<bool> = kept.iter().map(|&i| keep[i]).collect();
    let restored = restore_area_keeping(&coarse, &fixed, area);
    let full = || crate::mesh::polygon::simple_polygon(&outline, h).map_err(|e| RemeshError::Mesher(e.to_string()));
    let Some(coarse) = restored else {
        tracing::debug!("no free boundary point to restore the area with: meshing the full outline");
        return full();
    };
    match crate::mesh::polygon::simple_polygon(&coarse, h) {
        Ok(m) => Ok(m),
        Err(e) => {
            // the coarse polygon may touch itself where the old one nearly did: mesh the old one
            tracing::debug!(%e, "coarsened outline refused, meshing the full outline");
            full()
        }
    }
}

/// A boundary point whose sides turn by more than this (degrees) is a corner, always kept by
/// [`coarsen_outline`].
pub const CORNER_DEG: f64 = 25.0;

/// Signed area of a closed polygon (positive when counter-clockwise), mm².
pub fn signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|i| {
        let (a, b) = (p[i], p[(i + 1) % n]);
        a[0] * b[1] - a[1] * b[0]
    }).sum::<f64>()
}

/// The closed outline `p` with points dropped so that the kept ones are about `spacing` apart
/// along the outline: a point is dropped only when it is not a corner (its sides turn by at
/// most `corner_deg`) and lies within `tol` of the chord between the kept points around it.
/// Greedy from a corner (or from point 0 when there is none): from each kept point the next is
/// the farthest one within `spacing` of arc length whose skipped points all qualify.
pub fn coarsen_outline(p: &[[f64; 2]], spacing: f64, tol: f64, corner_deg: f64) -> Vec<[f64; 2]> {
    coarsen_outline_keeping(p, &[], spacing, tol, corner_deg).into_iter().map(|i| p[i]).collect()
}

/// [`coarsen_outline`] that also keeps every point `i` with `keep[i]` (an empty `keep` holds
/// none), and returns the indices of the kept points in `p`, in order.
pub fn coarsen_outline_keeping(p: &[[f64; 2]], keep: &[bool], spacing: f64, tol: f64, corner_deg: f64) -> Vec<usize> {
    let n = p.len();
    let all = || (0..n).collect::<Vec<usize>>();
    if n < 4 || !(spacing > 0.0) {
        return all();
    }
    let len = |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]).hypot(b[1] - a[1]);
    let cos_corner = corner_deg.to_radians().cos();
    let corner: Vec<bool> = (0..n)
        .map(|i| {
            let (a, b, c) = (p[(i + n - 1) % n], p[i], p[(i + 1) % n]);
            let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
            let (lu, lv) = (u[0].hypot(u[1]), v[0].hypot(v[1]));
            keep.get(i).copied().unwrap_or(false) || lu == 0.0 || lv == 0.0 || (u[0] * v[0] + u[1] * v[1]) / (lu * lv) < cos_corner
        })
        .collect();
    let start = corner.iter().position(|&c| c).unwrap_or(0);
    let idx = |k: usize| (start + k) % n;
    let at = |k: usize| p[idx(k)];
    let is_corner = |k: usize| corner[idx(k)];
    // distance from q to the chord a–b
    let off_chord = |q: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l = dx.hypot(dy);
        if l == 0.0 {
            return len(q, a);
        }
        ((q[0] - a[0]) * dy - (q[1] - a[1]) * dx).abs() / l
    };
    let mut kept = vec![idx(0)];
    let mut k = 0;
    while k < n {
        let mut arc = 0.0;
        let mut best = k + 1;
        let mut j = k + 1;
        while j <= n {
            arc += len(at(j - 1), at(j));
            if arc > spacing * (1.0 + 1e-9) && j > k + 1 {
                break;
            }
            let ok = (k + 1..j).all(|m| !is_corner(m) && off_chord(at(m), at(k), at(j)) <= tol);
            if !ok {
                break;
            }
            best = j;
            if j < n && is_corner(j) {
                break;
            }
            j += 1;
        }
        if best >= n {
            break;
        }
        kept.push(idx(best));
        k = best;
    }
    if kept.len() < 3 {
        return all();
    }
    kept
}

/// The polygon `p` offset along its vertex normals (the normalised sum of the outward normals
/// of the two sides at each vertex) by the one distance δ that makes its signed area `area`:
/// the area of the offset polygon is a quadratic in δ, solved in closed form (the root nearer
/// zero). Returns `p` unchanged when it already has the area or no root exists.
pub fn restore_area(p: &[[f64; 2]], area: f64) -> Vec<[f64; 2]> {
    restore_area_keeping(p, &[], area).unwrap_or_else(|| p.to_vec())
}

/// [`restore_area`] with the points `i` with `fixed[i]` left in place (an empty `fixed` fixes
/// none): only the free points move along their normals, and the area is still a quadratic
/// in δ. None when the area is to change but no point is free to change it (or no root
/// exists).
pub fn restore_area_keeping(p: &[[f64; 2]], fixed: &[bool], area: f64) -> Option<Vec<[f64; 2]>> {
    let n = p.len();
    let a0 = signed_area(p);
    let deficit = area - a0;
    if n < 3 || deficit == 0.0 {
        return Some(p.to_vec());
    }
    // outward normal of side i (p_i → p_{i+1}) of a counter-clockwise polygon is (dy, −dx)/l;
    // a clockwise polygon has the opposite sign (the area is negative)
    let sign = if a0 >= 0.0 { 1.0 } else { -1.0 };
    let side_normal = |i: usize| {
        let (a, b) = (p[i], p[(i + 1) % n]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l = dx.hypot(dy).max(f64::MIN_POSITIVE);
        [sign * dy / l, -sign * dx / l]
    };
    let normals: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            if fixed.get(i).copied().unwrap_or(false) {
                return [0.0, 0.0];
            }
            let (a, b) = (side_normal((i + n - 1) % n), side_normal(i));
            let s = [a[0] + b[0], a[1] + b[1]];
            let l = s[0].hypot(s[1]);
            if l > 1e-12 { [s[0] / l, s[1] / l] } else { b }
        })
        .collect();
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    // A(δ) = A₀ + B δ + C δ²
    let (mut b, mut c) = (0.0, 0.0);
    for i in 0..n {
        let j = (i + 1) % n;
        b += 0.5 * (cross(p[i], normals[j]) + cross(normals[i], p[j]));
        c += 0.5 * cross(normals[i], normals[j]);
    }
    if b == 0.0 {
        return None;
    }
    let delta = if c.abs() * deficit.abs() < 1e-12 * b * b {
        deficit / b
    } else {
        let disc = b * b + 4.0 * c * deficit;
        if disc < 0.0 {
            return None;
        }
        // the root nearer zero, in the cancellation-free form
        2.0 * deficit / (b + b.signum() * disc.sqrt())
    };
    Some(p.iter().zip(&normals).map(|(q, m)| [q[0] + delta * m[0], q[1] + delta * m[1]]).collect())
}


#[cfg(test)]
mod outline_tests {
    use super::*;

    /// A 10 × 10 square with 40 points per side (spacing 0.25), counter-clockwise.
    fn fine_square() -> Vec<[f64; 2]> {
        let mut p = Vec::new();
        let corners = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            for i in 0..40 {
                let t = i as f64 / 40.0;
                p.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        p
    }

    /// Straight sides lose their inner points down to the spacing (here 1.0: 10 sides of 1.0 a
    /// side, exactly, since the points are equally spaced), the four corners stay, and nothing
    /// moves (the area is exact, so no offset).
    #[test]
    fn coarsening_a_square_keeps_its_corners() {
        let p = fine_square();
        let c = coarsen_outline(&p, 1.0, 0.01, CORNER_DEG);
        assert_eq!(c.len(), 40, "{c:?}");
        for corner in [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]] {
            assert!(c.iter().any(|q| q == &corner), "corner {corner:?} dropped");
        }
        assert!((signed_area(&c) - 100.0).abs() < 1e-12);
        assert_eq!(restore_area(&c, 100.0), c);
    }

    /// A circle of radius 10 as a 256-gon coarsened to spacing 2 loses area (chords); the
    /// offset gives it back to 1e-12 relative, with every point moved by the same δ, which is
    /// (lost area)/(perimeter) to first order (within 1 %). Clockwise input works the same.
    #[test]
    fn coarsened_circle_gets_its_area_back() {
        let p: Vec<[f64; 2]> = (0..256)
            .map(|k| {
                let t = 2.0 * std::f64::consts::PI * k as f64 / 256.0;
                [10.0 * t.cos(), 10.0 * t.sin()]
            })
            .collect();
        for poly in [p.clone(), p.iter().rev().copied().collect::<Vec<_>>()] {
            let a = signed_area(&poly);
            let c = coarsen_outline(&poly, 2.0, 0.1, CORNER_DEG);
            assert!(c.len() >= 31 && c.len() <= 40, "{} points", c.len());
            let lost = a - signed_area(&c);
            assert!(lost.abs() > 0.1, "coarsening must lose some area: {lost}");
            let r = restore_area(&c, a);
            assert!(((signed_area(&r) - a) / a).abs() < 1e-12, "{} vs {a}", signed_area(&r));
            let moved: Vec<f64> = r.iter().zip(&c).map(|(x, y)| (x[0] - y[0]).hypot(x[1] - y[1])).collect();
            let perimeter: f64 = (0..c.len()).map(|i| {
                let (x, y) = (c[i], c[(i + 1) % c.len()]);
                (y[0] - x[0]).hypot(y[1] - x[1])
            }).sum();
            let expected = lost.abs() / perimeter;
            for m in &moved {
                assert!((m - expected).abs() < 0.01 * expected, "moved {m} vs {expected}");
            }
        }
    }

    /// Held points survive the coarsening even on a straight side (where every other point of
    /// the side goes), and the area offset moves only the free points: the held ones stay
    /// bit for bit, the area comes back to 1e-12 relative (a 256-gon coarsened to spacing 2,
    /// with a quarter of its points held). With every point held there is nothing to offset
    /// with: None.
    #[test]
    fn held_points_stay_where_they_are() {
        let p = fine_square();
        let keep: Vec<bool> = (0..p.len()).map(|i| (5..15).contains(&i)).collect();
        let kept = coarsen_outline_keeping(&p, &keep, 2.0, 0.01, CORNER_DEG);
        for i in 5..15 {
            assert!(kept.contains(&i), "held point {i} dropped: {kept:?}");
        }
        assert!(kept.len() < 40, "the free sides are still coarsened: {} points", kept.len());

        let circle: Vec<[f64; 2]> = (0..256)
            .map(|k| {
                let t = 2.0 * std::f64::consts::PI * k as f64 / 256.0;
                [10.0 * t.cos(), 10.0 * t.sin()]
            })
            .collect();
        let a = signed_area(&circle);
        let keep: Vec<bool> = (0..256).map(|i| i < 64).collect();
        let kept = coarsen_outline_keeping(&circle, &keep, 2.0, 0.1, CORNER_DEG);
        let c: Vec<[f64; 2]> = kept.iter().map(|&i| circle[i]).collect();
        let fixed: Vec<bool> = kept.iter().map(|&i| keep[i]).collect();
        assert_eq!(fixed.iter().filter(|&&f| f).count(), 64);
        let r = restore_area_keeping(&c, &fixed, a).unwrap();
        assert!(((signed_area(&r) - a) / a).abs() < 1e-12, "{} vs {a}", signed_area(&r));
        for ((q, o), f) in r.iter().zip(&c).zip(&fixed) {
            if *f {
                assert_eq!(q, o, "a held point moved");
            } else {
                assert!((q[0] - o[0]).hypot(q[1] - o[1]) > 0.0, "a free point did not move");
            }
        }
        let all = vec![true; c.len()];
        assert!(restore_area_keeping(&c, &all, a).is_none());
    }
}
