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
//! ([`RemeshSpec`]) the solver calls it after every converged step for the worst
//! free particle that crosses the quality limits (one per step), and once per step for the particle of an inverted
//! element when its mesh is already near the limits; then
//! [`crate::solver::Simulation::equilibrate`] balances the transferred state in place
//! (Δt = 0: 6 Newton iterations in the mid-run test). The history's `remeshes` column counts
//! them; results.h5 writes each step's own mesh. The new boundary keeps the old points of the
//! contact zones at their old spacing ([`remesh_particle_keeping`]). Still missing: contact
//! history (stick points, multipliers), which starts afresh after a re-mesh.
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

use std::collections::HashMap;
use crate::mesh::Mesh;
use thiserror::Error;

pub use body::{transfer_body, BodyState, BodyTransfer};
pub use locate::{Location, PointLocator};
pub use monitor::{check_quality, QualityCheck, QualityLimits, QualityMeasure, Worst};

/// The `[remesh]` table: adaptive re-meshing of deformed particles (see [`crate::remesh`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RemeshSpec {
    /// Re-mesh a particle whose mesh crosses the quality limits after a converged step, and
    /// re-mesh and retry a step that inverts an element.
    pub enabled: bool,
    /// The quality limits (scaled Jacobian, aspect ratio, smallest corner angle).
    pub limits: QualityLimits,
    /// Target element size of the new meshes (mm); `None`: each body's own `mesh_size`.
    pub mesh_size: Option<f64>,
    /// Largest number of re-meshes in one run (all particles together); past it the run goes
    /// on without re-meshing.
    pub max_remeshes: usize,
}

impl Default for RemeshSpec {
    fn default() -> Self {
        Self { enabled: false, limits: QualityLimits::default(), mesh_size: None, max_remeshes: 10_000 }
    }
}
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
/// neighbours along the boundary kept exactly where they are: the nodes in contact, whose
/// positions set the penetrations and with them the contact forces (a penalty contact
/// penetrates by p/ε, a fraction of a millimetre on the asphalt jobs; moving a contact face by
/// the coarsening tolerance 0.05 `h` = 1.25 mm there changed the contact forces by 20 %).
///
/// The mesher ([`crate::mesh::polygon::simple_polygon`]) splits triangles into quadrilaterals
/// and so adds the midpoint of every side of the polygon it is given. The polygon is built so
/// that the new boundary has about the old density, not twice it:
/// 1. free stretches are coarsened to a spacing of about `2h` ([`coarsen_outline_keeping`]:
///    corners, strongly curved stretches and held nodes keep their points); the coarsened
///    polygon's free points are offset along their vertex normals by the one distance that
///    gives the old area back ([`restore_area_keeping`]), so they move by at most the
///    coarsening tolerance (0.05 `h`) plus that offset;
/// 2. in runs of old points kept as they are (held, or on a curved stretch the coarsening left
///    alone) every other point is dropped ([`thin_kept_runs`]) and the mesher's midpoint of the
///    side that replaces it is moved back onto it ([`snap_midpoints`], with the points of a
///    side the refinement split moved onto the two old sides); the mesh size at the boundary
///    is raised to half the longest such side so that the mesher keeps them whole;
/// 3. the interior nodes are smoothed ([`smooth_interior`]).
///
/// A held stretch thus keeps every old point, bit for bit, and no point is added between two
/// of them (measured on an asphalt octagon of the 5.2.1 job held all round: 48 boundary nodes
/// and 162 elements from 48 and 72; 96 and 588 before the thinning), and the particle's area
/// is unchanged to round-off (1e-12). Should that fail (no free point left to restore the
/// area with, a side the mesher split elsewhere than at its midpoint, a moved node that would
/// invert an element, a polygon the mesher refuses), the old outline is thinned as a whole
/// (every old point kept, at the old spacing), and as a last resort meshed as it is (every
/// old point a vertex: twice the density).
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
    let full = || {
        let mut new = crate::mesh::polygon::simple_polygon(&outline, h).map_err(|e| RemeshError::Mesher(e.to_string()))?;
        smooth_interior(&mut new, SMOOTHING_SWEEPS);
        Ok(new)
    };
    // 1. the outline coarsened to about 2h, with every other held point left to the mesher's
    //    side midpoints (the old density there); 2. should that fail (no free point left to
    //    restore the area with, or the mesher splits a side in a way the midpoint cannot be put
    //    back), every old point, every other one a polygon vertex (the old boundary exactly, at
    //    its old spacing); 3. every old point a polygon vertex (the mesher's midpoints double
    //    the boundary density).
    let every: Vec<bool> = vec![true; m];
    for attempt in 0..2 {
        let (kept, pinned) = if attempt == 0 {
            let kept = coarsen_outline_keeping(&outline, &keep, 2.0 * h, 0.05 * h, CORNER_DEG);
            // a free point the coarsening kept together with both its neighbours (a curved
            // stretch, finer than 2h only within the tolerance) is an old point on old sides:
            // pinned too, so that it is thinned as the held ones are
            let mut is_kept = vec![false; m];
            kept.iter().for_each(|&i| is_kept[i] = true);
            let pinned: Vec<bool> = (0..m).map(|i| keep[i] || (is_kept[i] && is_kept[(i + 1) % m] && is_kept[(i + m - 1) % m])).collect();
            (kept, pinned)
        } else {
            ((0..m).collect(), every.clone())
        };
        let (kept, snaps) = thin_kept_runs(&outline, &pinned, &kept, THIN_MAX_SIDE * h);
        let coarse: Vec<[f64; 2]> = kept.iter().map(|&i| outline[i]).collect();
        let fixed: Vec<bool> = kept.iter().map(|&i| pinned[i]).collect();
        // a point put back on the midpoint of side k adds the triangle (a, s, b) to the area
        let snapped_area: f64 = snaps.iter().map(|&(k, i)| signed_area(&[coarse[k], outline[i], coarse[(k + 1) % coarse.len()]])).sum();
        let Some(coarse) = restore_area_keeping(&coarse, &fixed, area - snapped_area) else {
            tracing::debug!(attempt, "no free boundary point to restore the area with");
            continue;
        };
        // the mesher resamples sides longer than twice its size: a side whose midpoint is to
        // land on a dropped point stays whole (the boundary size is raised to half the longest
        // of them, at most 1.5 h, and the interior follows it)
        let longest = snaps.iter().map(|&(k, _)| {
            let (a, b) = (coarse[k], coarse[(k + 1) % coarse.len()]);
            (b[0] - a[0]).hypot(b[1] - a[1])
        });
        let hb = longest.fold(h, |hb, l| hb.max(0.5 * l * (1.0 + 1e-9)));
        let mut new = match crate::mesh::polygon::simple_polygon_keeping_sides(&coarse, hb) {
            Ok(m) => m,
            Err(e) => {
                // the coarse polygon may touch itself where the old one nearly did
                tracing::debug!(%e, attempt, "outline refused by the mesher");
                continue;
            }
        };
        if snaps.is_empty() || snap_midpoints(&mut new, &coarse, &snaps.iter().map(|&(k, i)| (k, outline[i])).collect::<Vec<_>>()) {
            smooth_interior(&mut new, SMOOTHING_SWEEPS);
            return Ok(new);
        }
        tracing::debug!(attempt, "a side midpoint could not be put back on its old boundary point");
    }
    tracing::debug!("meshing the full outline");
    full()
}

/// Longest side (in units of the target size h) that a dropped point of [`thin_kept_runs`]
/// may leave: the old spacing is kept where it is up to 1.5 h; longer old sides are
/// refined by the mesher.
pub const THIN_MAX_SIDE: f64 = 3.0;

/// Sweeps of [`smooth_interior`] given to a new particle mesh.
pub const SMOOTHING_SWEEPS: usize = 8;

/// Smart Laplacian smoothing of the interior nodes of `mesh` (the boundary is not touched, so
/// neither is the area): in each of `sweeps` sweeps every interior node moves to the mean of
/// its neighbours along element edges when that raises the smallest scaled Jacobian of the
/// elements around it, and stays otherwise. The mesher's quadrilaterals (three per triangle)
/// are kinked where triangles of different sizes meet, and a side midpoint put back on a
/// dented boundary squeezes the elements next to it; the smoothing evens both out.
pub fn smooth_interior(mesh: &mut Mesh, sweeps: usize) {
    use crate::mesh::quality::scaled_jacobian;
    let n = mesh.n_nodes();
    let mut on_boundary = vec![false; n];
    for e in &mesh.boundary {
        on_boundary[e[0]] = true;
        on_boundary[e[1]] = true;
    }
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (e, el) in mesh.elements.iter().enumerate() {
        for c in 0..4 {
            let (v, w) = (el[c], el[(c + 1) % 4]);
            around[v].push(e);
            if !neighbours[v].contains(&w) {
                neighbours[v].push(w);
            }
            if !neighbours[w].contains(&v) {
                neighbours[w].push(v);
            }
        }
    }
    let worst = |nodes: &[[f64; 2]], els: &[usize]| els.iter().map(|&e| scaled_jacobian(mesh.elements[e].map(|v| nodes[v]))).fold(f64::INFINITY, f64::min);
    let mut nodes = mesh.nodes.clone();
    for _ in 0..sweeps {
        let mut moved = false;
        for v in 0..n {
            if on_boundary[v] || neighbours[v].is_empty() {
                continue;
            }
            let k = neighbours[v].len() as f64;
            let mean = neighbours[v].iter().fold([0.0, 0.0], |m, &w| [m[0] + nodes[w][0] / k, m[1] + nodes[w][1] / k]);
            let before = worst(&nodes, &around[v]);
            let old = nodes[v];
            nodes[v] = mean;
            if worst(&nodes, &around[v]) > before {
                moved = true;
            } else {
                nodes[v] = old;
            }
        }
        if !moved {
            break;
        }
    }
    mesh.nodes = nodes;
}

/// Thins the runs of held points in `kept` (indices into the closed outline `p`, in order):
/// of three kept points that are neighbours on the outline and all held (`keep`), the middle
/// one is dropped when the side that replaces it is at most `max_side` long and the point lies
/// near the middle of that side (projection within its middle half, at most a quarter of the
/// side off it); alternately, so that no two dropped points are neighbours. The mesher puts a
/// midpoint on every side, and [`snap_midpoints`] moves it onto the dropped point: the held
/// stretch keeps every old point, exactly where it was, and its old spacing (not half of it).
/// Returns the thinned indices and, for each dropped point, `(k, i)`: side k of the thinned
/// polygon (from its point k to k + 1) takes outline point i.
fn thin_kept_runs(p: &[[f64; 2]], keep: &[bool], kept: &[usize], max_side: f64) -> (Vec<usize>, Vec<(usize, usize)>) {
    let (n, m) = (p.len(), kept.len());
    let mut drop = vec![false; m];
    if m >= 6 {
        let next = |i: usize| (i + 1) % n;
        let droppable = |k: usize| {
            let (a, i, b) = (kept[(k + m - 1) % m], kept[k], kept[(k + 1) % m]);
            if !(keep[a] && keep[i] && keep[b] && next(a) == i && next(i) == b) {
                return false;
            }
            let (pa, pi, pb) = (p[a], p[i], p[b]);
            let d = [pb[0] - pa[0], pb[1] - pa[1]];
            let l2 = d[0] * d[0] + d[1] * d[1];
            if !(l2 > 0.0) || l2.sqrt() > max_side {
                return false;
            }
            let r = [pi[0] - pa[0], pi[1] - pa[1]];
            let t = (r[0] * d[0] + r[1] * d[1]) / l2;
            let off = (r[0] * d[1] - r[1] * d[0]).abs() / l2;
            (0.25..=0.75).contains(&t) && off <= 0.25
        };
        for k in 0..m {
            let prev_dropped = drop[(k + m - 1) % m];
            let next_dropped = k + 1 == m && drop[0];
            if !prev_dropped && !next_dropped && droppable(k) {
                drop[k] = true;
            }
        }
        if drop.iter().filter(|&&d| !d).count() < 4 {
            drop.fill(false);
        }
    }
    let mut thinned = Vec::with_capacity(m);
    let mut snaps = Vec::new();
    for k in 0..m {
        if drop[k] {
            // side from the last kept point; the first point of the polygon is never dropped
            // after a dropped last one (see above), so `thinned` is not empty unless k = 0
            snaps.push((thinned.len().wrapping_sub(1), kept[k]));
        } else {
            thinned.push(kept[k]);
        }
    }
    let t = thinned.len();
    for s in &mut snaps {
        // a point dropped at k = 0 lies on the closing side (from the last point to the first)
        if s.0 == usize::MAX {
            s.0 = t - 1;
        }
    }
    (thinned, snaps)
}

/// Puts the dropped point `s` of each side `k` of `polygon` (from `polygon[k]` = a to
/// `polygon[k + 1]` = b) back on the boundary of `mesh`: the boundary nodes between a and b,
/// all on the chord a–b, are moved by their chord parameter t onto the old outline a–s–b
/// (t ≤ ½ onto a–s, the rest onto s–b), so the mesher's midpoint (t = ½) lands on s, and
/// the further points of a side the refinement split land on the old sides a–s and s–b.
/// False, with `mesh` unchanged, when a side has no node at its midpoint, or a moved node
/// would turn one of its elements inside out.
fn snap_midpoints(mesh: &mut Mesh, polygon: &[[f64; 2]], snaps: &[(usize, [f64; 2])]) -> bool {
    let loops = mesh.boundary_loops();
    if loops.len() != 1 {
        return false;
    }
    let lp = &loops[0];
    let at: HashMap<[u64; 2], usize> = lp.iter().enumerate().map(|(pos, &v)| (mesh.nodes[v].map(f64::to_bits), pos)).collect();
    let nl = lp.len();
    let mut moved = mesh.nodes.clone();
    let mut touched = Vec::new();
    for &(k, s) in snaps {
        let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
        let (Some(&pa), Some(&pb)) = (at.get(&a.map(f64::to_bits)), at.get(&b.map(f64::to_bits))) else {
            tracing::debug!(side = k, "snap: a side's end is not a boundary node of the new mesh");
            return false;
        };
        // the nodes strictly between a and b, going the short way round the loop
        let (fwd, bwd) = ((pb + nl - pa) % nl, (pa + nl - pb) % nl);
        let between: Vec<usize> = if fwd <= bwd { (1..fwd).map(|i| lp[(pa + i) % nl]).collect() } else { (1..bwd).map(|i| lp[(pa + nl - i) % nl]).collect() };
        let d = [b[0] - a[0], b[1] - a[1]];
        let l2 = d[0] * d[0] + d[1] * d[1];
        let mut hit_mid = false;
        for &v in &between {
            let p = mesh.nodes[v];
            let t = ((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2;
            moved[v] = if (t - 0.5).abs() <= 1e-9 {
                hit_mid = true;
                s
            } else if t < 0.5 {
                let u = 2.0 * t;
                [a[0] + u * (s[0] - a[0]), a[1] + u * (s[1] - a[1])]
            } else {
                let u = 2.0 * t - 1.0;
                [s[0] + u * (b[0] - s[0]), s[1] + u * (b[1] - s[1])]
            };
            touched.push(v);
        }
        if !hit_mid {
            tracing::debug!(side = k, nodes = between.len(), "snap: no node at the side's midpoint");
            return false;
        }
    }
    let touched: std::collections::HashSet<usize> = touched.into_iter().collect();
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    for el in &mesh.elements {
        if el.iter().any(|v| touched.contains(v)) {
            let q = el.map(|v| moved[v]);
            if (0..4).any(|c| orient(q[c], q[(c + 1) % 4], q[(c + 3) % 4]) <= 0.0) {
                tracing::debug!("snap: a moved node turns an element inside out");
                return false;
            }
        }
    }
    mesh.nodes = moved;
    true
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
    // a deficit of round-off (a polygon that already has the area) needs no point to move
    if n < 3 || deficit.abs() <= 1e-13 * area.abs() {
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
