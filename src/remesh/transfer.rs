//! Transfer of quadrature-point and nodal fields from an old mesh to a new mesh of the same
//! region.
//!
//! ## Quadrature-point fields: L2 projection, then interpolation
//! 1. The old Gauss-point values f_q define a function known only at the quadrature points.
//!    Its global L2 projection onto the bilinear nodal functions of the old mesh solves
//!    `M f̂ = b`, `M_ab = Σ_e Σ_q N_a N_b det J |_q`, `b_a = Σ_e Σ_q N_a det J f |_q`, with the
//!    element's own 2×2 Gauss rule in the current coordinates. That rule integrates N_a N_b det J
//!    exactly (degree ≤ 3 in each of ξ, η), so M is the exact consistent mass matrix; it is
//!    symmetric positive definite and solved by faer's sparse Cholesky ([`FaerCholesky`]), one
//!    factorisation for all components.
//! 2. The nodal field f̂ is interpolated at the new points with the old shape functions of the
//!    element that holds each point ([`PointLocator`]; points outside the old mesh: nearest
//!    element, clamped coordinates, see [`super::locate`]).
//!
//! Properties (each a test):
//! - **Linear fields are transferred exactly** (to round-off): the coordinates x, y are in the
//!   isoparametric span, so for f = a + b·x the data f_q = Σ_b N_b(ξ_q) f(x_b) and the projection
//!   returns f̂_b = f(x_b) exactly; interpolation reproduces f. This holds for new points inside
//!   the old mesh (outside: the clamped constant extension errs by ≤ |∇f| × distance).
//! - **Constants are kept** everywhere, also outside (partition of unity).
//! - **Smooth fields converge at second order** in the mesh size (L2 projection onto Q1 is
//!   O(h²) in L2 and, on quasi-uniform meshes, pointwise; interpolation at the new points adds an
//!   O(h²) term): measured rates 1.98, 1.99 in the relative L2 norm and 1.69, 1.86 in the max
//!   norm for h, h/2, h/4 (test `smooth_field_converges`).
//! - Not monotone: near a jump of the data (e.g. the border of a plastic zone) the projection
//!   over- and undershoots by about 20 % of the jump (Gibbs-like; measured 16–24 % on distorted
//!   rectangle meshes), the price of the O(h²) accuracy. [`super::state`] clamps the inelastic
//!   strains at zero and transfers the elastic strain in logarithmic form, so no transferred
//!   state is inadmissible, but the stress near a plastic-zone border is smeared.
//!
//! ## Lumped alternative
//! [`FieldTransfer::quadrature_field_lumped`] uses the row-sum lumped mass matrix instead: every
//! nodal value is a weighted average of the nearby Gauss-point data, so the result stays within
//! the bounds of the data (tested on the jump), constants are exact, but the accuracy drops to
//! first order (measured max-norm rates 1.09, 1.04; L2 rates 1.41, 1.50; errors 7–14 times
//! those of the consistent projection). Use it for fields that must stay in a range.
//!
//! ## Nodal fields
//! [`FieldTransfer::nodal_field`] interpolates an old nodal field at the new nodes (exact for
//! bilinear-representable fields, O(h²) for smooth ones).
// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::locate::{Location, PointLocator};
use super::{check_mesh, RemeshError};
use crate::element::{shape, shape_derivs, GAUSS};
use crate::linalg::direct::FaerCholesky;
use crate::linalg::{CsrMatrix, LinearSolver};
use crate::mesh::quality::scaled_jacobian;
use crate::mesh::Mesh;

/// Values at the quadrature points of a mesh: point `4 e + q` (element e, Gauss point q of
/// [`GAUSS`]) has the components `values[(4 e + q) n_comp ..][..n_comp]`.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadField {
    pub n_comp: usize,
    pub values: Vec<f64>,
}

/// Values at the nodes of a mesh: node n has the components `values[n n_comp ..][..n_comp]`.
#[derive(Clone, Debug, PartialEq)]
pub struct NodalField {
    pub n_comp: usize,
    pub values: Vec<f64>,
}

impl QuadField {
    /// A zero field with `n_comp` components on the quadrature points of `n_elements` elements.
    pub fn zeros(n_elements: usize, n_comp: usize) -> Self {
        Self { n_comp, values: vec![0.0; 4 * n_elements * n_comp] }
    }

    /// Number of points (4 per element).
    pub fn n_points(&self) -> usize {
        self.values.len().checked_div(self.n_comp).unwrap_or(0)
    }

    /// Components at point i.
    pub fn point(&self, i: usize) -> &[f64] {
        &self.values[i * self.n_comp..(i + 1) * self.n_comp]
    }

    /// Mutable components at point i.
    pub fn point_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.values[i * self.n_comp..(i + 1) * self.n_comp]
    }

    /// A field sampled from a function of the point position.
    pub fn from_fn(points: &[[f64; 2]], n_comp: usize, f: impl Fn([f64; 2], &mut [f64])) -> Self {
        let mut out = Self { n_comp, values: vec![0.0; points.len() * n_comp] };
        for (i, &p) in points.iter().enumerate() {
            f(p, out.point_mut(i));
        }
        out
    }
}

impl NodalField {
    /// Components at node n.
    pub fn node(&self, n: usize) -> &[f64] {
        &self.values[n * self.n_comp..(n + 1) * self.n_comp]
    }

    /// A field sampled from a function of the node position.
    pub fn from_fn(coords: &[[f64; 2]], n_comp: usize, f: impl Fn([f64; 2], &mut [f64])) -> Self {
        let mut values = vec![0.0; coords.len() * n_comp];
        for (i, &p) in coords.iter().enumerate() {
            f(p, &mut values[i * n_comp..(i + 1) * n_comp]);
        }
        Self { n_comp, values }
    }
}

/// Positions of the quadrature points of `mesh` in the coordinates `coords`, numbered `4 e + q`.
///
/// # Errors
/// Invalid mesh input (see [`RemeshError`]).
pub fn quadrature_points(mesh: &Mesh, coords: &[[f64; 2]]) -> Result<Vec<[f64; 2]>, RemeshError> {
    check_mesh(mesh, coords)?;
    let mut pts = Vec::with_capacity(4 * mesh.n_elements());
    for el in &mesh.elements {
        for gp in &GAUSS {
            let n = shape(gp[0], gp[1]);
            let mut x = [0.0; 2];
            for a in 0..4 {
                x[0] += n[a] * coords[el[a]][0];
                x[1] += n[a] * coords[el[a]][1];
            }
            pts.push(x);
        }
    }
    Ok(pts)
}

/// det J of the bilinear map at the four Gauss points of the quad `p`.
fn gauss_jacobians(p: &[[f64; 2]; 4]) -> [f64; 4] {
    std::array::from_fn(|q| {
        let dn = shape_derivs(GAUSS[q][0], GAUSS[q][1]);
        let mut j = [[0.0; 2]; 2];
        for a in 0..4 {
            for i in 0..2 {
                for k in 0..2 {
                    j[i][k] += p[a][i] * dn[a][k];
                }
            }
        }
        j[0][0] * j[1][1] - j[0][1] * j[1][0]
    })
}

/// Global L2 projection of quadrature-point fields onto the nodes of one mesh (consistent mass
/// matrix, factorised once; see the module docs).
pub struct L2Projector {
    elements: Vec<[usize; 4]>,
    n_nodes: usize,
    /// det J at the Gauss points of every element.
    det_j: Vec<[f64; 4]>,
    mass: CsrMatrix,
    solver: FaerCholesky,
}

impl std::fmt::Debug for L2Projector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("L2Projector").field("n_nodes", &self.n_nodes).field("n_elements", &self.elements.len()).finish()
    }
}

impl L2Projector {
    /// Assemble and factorise the mass matrix of `mesh` in the coordinates `coords`. Nodes that
    /// belong to no element get a unit diagonal (their projected value is 0; no interpolation
    /// ever reads them).
    ///
    /// # Errors
    /// Invalid mesh input, an element with a non-positive scaled Jacobian, or a failed
    /// factorisation.
    pub fn new(mesh: &Mesh, coords: &[[f64; 2]]) -> Result<Self, RemeshError> {
        check_mesh(mesh, coords)?;
        let n = coords.len();
        let mut det_j = Vec::with_capacity(mesh.n_elements());
        for (e, el) in mesh.elements.iter().enumerate() {
            let p = el.map(|k| coords[k]);
            let sj = scaled_jacobian(p);
            if !(sj > 0.0) {
                return Err(RemeshError::InvalidElement { element: e, scaled_jacobian: sj });
            }
            det_j.push(gauss_jacobians(&p));
        }
        let mut rows: Vec<Vec<usize>> = vec![Vec::new(); n];
        for el in &mesh.elements {
            for &a in el {
                rows[a].extend_from_slice(el);
            }
        }
        let mut orphans = Vec::new();
        for (i, r) in rows.iter_mut().enumerate() {
            if r.is_empty() {
                r.push(i);
                orphans.push(i);
            }
            r.sort_unstable();
            r.dedup();
        }
        let mut mass = CsrMatrix::from_rows(n, &rows);
        let nq: [[f64; 4]; 4] = std::array::from_fn(|q| shape(GAUSS[q][0], GAUSS[q][1]));
        for (el, dj) in mesh.elements.iter().zip(&det_j) {
            for a in 0..4 {
                for b in 0..4 {
                    let m: f64 = (0..4).map(|q| nq[q][a] * nq[q][b] * dj[q]).sum();
                    // entries exist by construction of the pattern
                    if let Some(k) = mass.find(el[a], el[b]) {
                        mass.values[k] += m;
                    }
                }
            }
        }
        for &i in &orphans {
            if let Some(k) = mass.find(i, i) {
                mass.values[k] = 1.0;
            }
        }
        if !orphans.is_empty() {
            tracing::debug!(n = orphans.len(), "L2 projection: nodes without elements get the value 0");
        }
        let mut solver = FaerCholesky::new(1);
        solver.analyze(&mass).map_err(|e| RemeshError::Projection(e.to_string()))?;
        solver.factor(&mass).map_err(|e| RemeshError::Projection(e.to_string()))?;
        Ok(Self { elements: mesh.elements.clone(), n_nodes: n, det_j, mass, solver })
    }

    /// Project a quadrature-point field (4 points per element of the mesh given to
    /// [`L2Projector::new`]) onto the nodes.
    ///
    /// # Errors
    /// A field of the wrong size, with no components or with non-finite values, or a failed
    /// solve.
    pub fn project(&mut self, field: &QuadField) -> Result<NodalField, RemeshError> {
        check_field(field, 4 * self.elements.len(), "quadrature-point field")?;
        let nc = field.n_comp;
        let nq: [[f64; 4]; 4] = std::array::from_fn(|q| shape(GAUSS[q][0], GAUSS[q][1]));
        let mut out = NodalField { n_comp: nc, values: vec![0.0; self.n_nodes * nc] };
        let mut b = vec![0.0; self.n_nodes];
        let mut x = vec![0.0; self.n_nodes];
        for c in 0..nc {
            b.iter_mut().for_each(|v| *v = 0.0);
            for (e, (el, dj)) in self.elements.iter().zip(&self.det_j).enumerate() {
                for q in 0..4 {
                    let f = field.values[(4 * e + q) * nc + c] * dj[q];
                    for a in 0..4 {
                        b[el[a]] += nq[q][a] * f;
                    }
                }
            }
            if b.iter().all(|&v| v == 0.0) {
                x.iter_mut().for_each(|v| *v = 0.0);
            } else {
                self.solver.solve(&self.mass, &b, &mut x).map_err(|e| RemeshError::Projection(e.to_string()))?;
            }
            for (i, &v) in x.iter().enumerate() {
                out.values[i * nc + c] = v;
            }
        }
        Ok(out)
    }
}

impl L2Projector {
    /// Projection with the row-sum lumped mass matrix: f̂_a = Σ N_a f det J / Σ N_a det J over
    /// the Gauss points of the elements around node a. Every nodal value is a convex
    /// combination of the data (N_a ≥ 0 at the Gauss points, det J > 0), so bounds are kept
    /// (no overshoot at jumps, see the module docs), constants are exact, but linear fields are
    /// not reproduced on distorted meshes and at the boundary (first order there).
    ///
    /// # Errors
    /// A field of the wrong size, with no components or with non-finite values.
    pub fn project_lumped(&self, field: &QuadField) -> Result<NodalField, RemeshError> {
        check_field(field, 4 * self.elements.len(), "quadrature-point field")?;
        let nc = field.n_comp;
        let nq: [[f64; 4]; 4] = std::array::from_fn(|q| shape(GAUSS[q][0], GAUSS[q][1]));
        let mut num = vec![0.0; self.n_nodes * nc];
        let mut den = vec![0.0; self.n_nodes];
        for (e, (el, dj)) in self.elements.iter().zip(&self.det_j).enumerate() {
            for q in 0..4 {
                for a in 0..4 {
                    let w = nq[q][a] * dj[q];
                    den[el[a]] += w;
                    for c in 0..nc {
                        num[el[a] * nc + c] += w * field.values[(4 * e + q) * nc + c];
                    }
                }
            }
        }
        for (i, &d) in den.iter().enumerate() {
            for c in 0..nc {
                // orphan nodes (d = 0) keep 0
                num[i * nc + c] = if d > 0.0 { num[i * nc + c] / d } else { 0.0 };
            }
        }
        Ok(NodalField { n_comp: nc, values: num })
    }
}

fn check_field(values_n_comp: &impl FieldLike, n_points: usize, what: &'static str) -> Result<(), RemeshError> {
    let (nc, values) = values_n_comp.parts();
    if nc == 0 {
        return Err(RemeshError::NoComponents);
    }
    if values.len() != n_points * nc {
        return Err(RemeshError::SizeMismatch { what, expected: n_points * nc, got: values.len() });
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(RemeshError::NonFinite { what: "field value", index: i });
    }
    Ok(())
}

trait FieldLike {
    fn parts(&self) -> (usize, &[f64]);
}

impl FieldLike for QuadField {
    fn parts(&self) -> (usize, &[f64]) {
        (self.n_comp, &self.values)
    }
}

impl FieldLike for NodalField {
    fn parts(&self) -> (usize, &[f64]) {
        (self.n_comp, &self.values)
    }
}

/// How the points of the new mesh were found in the old one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TransferStats {
    /// Number of located points.
    pub n_points: usize,
    /// Points outside the old mesh (assigned to the nearest element, clamped coordinates).
    pub n_outside: usize,
    /// Largest distance of an outside point from the old mesh (mm; 0 if none).
    pub max_distance: f64,
}

impl TransferStats {
    fn of(locs: &[Location]) -> Self {
        let outside = locs.iter().filter(|l| !l.is_inside());
        Self {
            n_points: locs.len(),
            n_outside: outside.clone().count(),
            max_distance: outside.map(|l| l.distance).fold(0.0, f64::max),
        }
    }
}

/// Interpolate a nodal field of the old mesh at located points.
fn interpolate(old_elements: &[[usize; 4]], locs: &[Location], field: &NodalField) -> Vec<f64> {
    let nc = field.n_comp;
    let mut out = vec![0.0; locs.len() * nc];
    for (i, l) in locs.iter().enumerate() {
        let n = l.shape();
        let el = old_elements[l.element];
        for c in 0..nc {
            out[i * nc + c] = (0..4).map(|a| n[a] * field.values[el[a] * nc + c]).sum();
        }
    }
    out
}

/// Everything needed to move fields from one old mesh to one new mesh: the old mesh's L2
/// projector and the locations of the new quadrature points and nodes in the old mesh.
#[derive(Debug)]
pub struct FieldTransfer {
    projector: L2Projector,
    old_elements: Vec<[usize; 4]>,
    n_old_nodes: usize,
    gp_locations: Vec<Location>,
    node_locations: Vec<Location>,
}

impl FieldTransfer {
    /// Prepare the transfer from `old_mesh` in `old_coords` (its current configuration) to
    /// `new_mesh` in `new_coords`.
    ///
    /// # Errors
    /// Invalid mesh input, an invalid old element, or a failed mass-matrix factorisation.
    pub fn new(old_mesh: &Mesh, old_coords: &[[f64; 2]], new_mesh: &Mesh, new_coords: &[[f64; 2]]) -> Result<Self, RemeshError> {
        let locator = PointLocator::new(old_mesh, old_coords)?;
        let projector = L2Projector::new(old_mesh, old_coords)?;
        let gp = quadrature_points(new_mesh, new_coords)?;
        let gp_locations = locator.locate_all(&gp)?;
        let node_locations = locator.locate_all(new_coords)?;
        let t = Self { projector, old_elements: old_mesh.elements.clone(), n_old_nodes: old_coords.len(), gp_locations, node_locations };
        let (sg, sn) = (t.quadrature_stats(), t.node_stats());
        if sg.n_outside > 0 || sn.n_outside > 0 {
            tracing::debug!(
                gauss_outside = sg.n_outside,
                gauss_max_distance = sg.max_distance,
                nodes_outside = sn.n_outside,
                nodes_max_distance = sn.max_distance,
                "field transfer: points of the new mesh outside the old mesh (clamped to the nearest element)"
            );
        }
        Ok(t)
    }

    /// Location statistics of the new quadrature points.
    pub fn quadrature_stats(&self) -> TransferStats {
        TransferStats::of(&self.gp_locations)
    }

    /// Location statistics of the new nodes.
    pub fn node_stats(&self) -> TransferStats {
        TransferStats::of(&self.node_locations)
    }

    /// Locations of the new quadrature points (`4 e + q`) in the old mesh.
    pub fn quadrature_locations(&self) -> &[Location] {
        &self.gp_locations
    }

    /// Locations of the new nodes in the old mesh.
    pub fn node_locations(&self) -> &[Location] {
        &self.node_locations
    }

    /// Transfer a quadrature-point field of the old mesh to the quadrature points of the new
    /// mesh (L2 projection onto the old nodes, then interpolation).
    ///
    /// # Errors
    /// A field of the wrong size, without components or with non-finite values.
    pub fn quadrature_field(&mut self, old: &QuadField) -> Result<QuadField, RemeshError> {
        let nodal = self.projector.project(old)?;
        Ok(QuadField { n_comp: old.n_comp, values: interpolate(&self.old_elements, &self.gp_locations, &nodal) })
    }

    /// As [`FieldTransfer::quadrature_field`] with the lumped projection
    /// ([`L2Projector::project_lumped`]): bounded (no over- or undershoot, for fields that must
    /// stay in a range, e.g. a damage variable), constants exact, only first order.
    ///
    /// # Errors
    /// As [`FieldTransfer::quadrature_field`].
    pub fn quadrature_field_lumped(&self, old: &QuadField) -> Result<QuadField, RemeshError> {
        let nodal = self.projector.project_lumped(old)?;
        Ok(QuadField { n_comp: old.n_comp, values: interpolate(&self.old_elements, &self.gp_locations, &nodal) })
    }

    /// The L2 projection of an old quadrature-point field onto the old nodes (the intermediate
    /// nodal field of [`FieldTransfer::quadrature_field`]).
    ///
    /// # Errors
    /// As [`FieldTransfer::quadrature_field`].
    pub fn project_to_old_nodes(&mut self, old: &QuadField) -> Result<NodalField, RemeshError> {
        self.projector.project(old)
    }

    /// Interpolate a nodal field of the old mesh at the new nodes.
    ///
    /// # Errors
    /// A field of the wrong size, without components or with non-finite values.
    pub fn nodal_field(&self, old: &NodalField) -> Result<NodalField, RemeshError> {
        check_field(old, self.n_old_nodes, "nodal field")?;
        Ok(NodalField { n_comp: old.n_comp, values: interpolate(&self.old_elements, &self.node_locations, old) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;
    use crate::remesh::test_support::*;

    fn linear(p: [f64; 2], out: &mut [f64]) {
        out[0] = 3.0 - 2.0 * p[0] + 5.0 * p[1];
        out[1] = -1.0 + 0.5 * p[0] - 0.25 * p[1];
    }

    /// Max |a − b| over max |b|.
    fn rel_max_err(a: &[f64], b: &[f64]) -> f64 {
        let e = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        e / b.iter().map(|v| v.abs()).fold(0.0, f64::max)
    }

    /// Two distorted rectangle meshes (12×7 and 21×9, different bubbles) with the same deformed
    /// boundary: a linear field moves exactly. Tolerance 1e-10 relative: only the round-off of
    /// the assembly, the direct solve of the (well-conditioned) mass matrix and the
    /// interpolation remains.
    #[test]
    fn linear_field_exact_between_rectangle_meshes() {
        let old = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 12, 7);
        let new = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 21, 9);
        let xo = deform_rectangle(&old, 2.0, 1.0, 0.12);
        let xn = deform_rectangle(&new, 2.0, 1.0, -0.08);
        let mut t = FieldTransfer::new(&old, &xo, &new, &xn).unwrap();
        assert_eq!(t.quadrature_stats().n_outside, 0);
        let f_old = QuadField::from_fn(&quadrature_points(&old, &xo).unwrap(), 2, linear);
        let f_new = t.quadrature_field(&f_old).unwrap();
        let exact = QuadField::from_fn(&quadrature_points(&new, &xn).unwrap(), 2, linear);
        let err = rel_max_err(&f_new.values, &exact.values);
        assert!(err < 1e-10, "linear field error {err:e}");
        // the intermediate nodal field is the field itself at the old nodes
        let nodal = t.project_to_old_nodes(&f_old).unwrap();
        let at_nodes = NodalField::from_fn(&xo, 2, linear);
        assert!(rel_max_err(&nodal.values, &at_nodes.values) < 1e-10);
        // nodal transfer: new boundary nodes lie on the old boundary edges (to round-off)
        let nn = t.nodal_field(&at_nodes).unwrap();
        let exact_n = NodalField::from_fn(&xn, 2, linear);
        assert!(t.node_stats().max_distance < 1e-12, "{:?}", t.node_stats());
        assert!(rel_max_err(&nn.values, &exact_n.values) < 1e-10);
    }

    /// Move the nodes of `new` (a disc mesh of radius r about the origin) radially so that its
    /// boundary nodes lie on the boundary polygon of `old` (another disc mesh of radius r):
    /// what a mesher of the old boundary polyline does. The scale factor r_poly(θ)/r is applied
    /// to every node by its angle, so interior nodes follow smoothly.
    fn fit_into(new: &Mesh, old: &Mesh) -> Vec<[f64; 2]> {
        let r = old.nodes.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
        new.nodes
            .iter()
            .map(|&p| {
                let rho = p[0].hypot(p[1]);
                if rho == 0.0 {
                    return p;
                }
                let d = [p[0] / rho, p[1] / rho];
                // ray from the origin along d against the boundary edges a → b
                let mut s = 1.0;
                for &[a, b] in &old.boundary {
                    let (pa, pb) = (old.nodes[a], old.nodes[b]);
                    let e = [pb[0] - pa[0], pb[1] - pa[1]];
                    let den = d[0] * e[1] - d[1] * e[0];
                    if den.abs() < 1e-300 {
                        continue;
                    }
                    let t = (pa[0] * e[1] - pa[1] * e[0]) / den; // ray parameter
                    let u = (pa[0] * d[1] - pa[1] * d[0]) / den; // edge parameter
                    if t > 0.0 && (-1e-12..=1.0 + 1e-12).contains(&u) {
                        s = t / r;
                        break;
                    }
                }
                [p[0] * s, p[1] * s]
            })
            .collect()
    }

    /// Disc meshes of two densities, the old one distorted by a bubble + affine map, the new
    /// one fitted into the old boundary polygon and mapped by the affine part, so that the new mesh lies inside the old one
    /// (its boundary nodes on the old boundary, convex region): linear fields are exact
    /// (1e-10 relative, as above).
    #[test]
    fn linear_field_exact_between_disc_meshes() {
        let old = shapes::disc([0.0, 0.0], 1.0, 0.1);
        let new0 = shapes::disc([0.0, 0.0], 1.0, 0.17);
        let fitted = Mesh { nodes: fit_into(&new0, &old), ..new0.clone() };
        let xo = deform_disc(&old, 1.0, 0.2);
        // the new mesh is built in the current configuration: the affine image of the fitted
        // mesh, whose boundary nodes then lie on the old deformed boundary polygon (the old
        // boundary nodes are on the circle, where the bubble vanishes)
        let xn: Vec<[f64; 2]> = fitted.nodes.iter().map(|&p| affine(p)).collect();
        let mut t = FieldTransfer::new(&old, &xo, &fitted, &xn).unwrap();
        assert_eq!(t.quadrature_stats().n_outside, 0);
        assert!(t.node_stats().max_distance < 1e-12, "{:?}", t.node_stats());
        let f_old = QuadField::from_fn(&quadrature_points(&old, &xo).unwrap(), 2, linear);
        let f_new = t.quadrature_field(&f_old).unwrap();
        let exact = QuadField::from_fn(&quadrature_points(&fitted, &xn).unwrap(), 2, linear);
        let err = rel_max_err(&f_new.values, &exact.values);
        assert!(err < 1e-10, "linear field error {err:e}");
        let nn = t.nodal_field(&NodalField::from_fn(&xo, 2, linear)).unwrap();
        assert!(rel_max_err(&nn.values, &NodalField::from_fn(&xn, 2, linear).values) < 1e-10);
    }

    /// Without fitting, the new boundary nodes lie on the circle, outside the old inscribed
    /// polygon: those points are clamped. Constants still transfer to 1e-12 (partition of
    /// unity; relative to the value 7.5), and a linear field errs only at outside points, by at
    /// most |∇f| × distance (+1e-12 round-off).
    #[test]
    fn outside_points_constant_kept_linear_bounded() {
        let old = shapes::disc([0.0, 0.0], 1.0, 0.1);
        let new = shapes::disc([0.0, 0.0], 1.0, 0.13);
        let xo = deform_disc(&old, 1.0, 0.2);
        let xn = deform_disc(&new, 1.0, 0.2);
        let mut t = FieldTransfer::new(&old, &xo, &new, &xn).unwrap();
        let s = t.node_stats();
        assert!(s.n_outside > 0 && s.max_distance > 0.0 && s.max_distance < 0.01, "{s:?}");

        let gp_old = quadrature_points(&old, &xo).unwrap();
        let c_old = QuadField::from_fn(&gp_old, 3, |_, o| o.copy_from_slice(&[7.5, -2.0, 0.0]));
        let c_new = t.quadrature_field(&c_old).unwrap();
        for i in 0..c_new.n_points() {
            let v = c_new.point(i);
            assert!((v[0] - 7.5).abs() < 1e-12 && (v[1] + 2.0).abs() < 1e-12 && v[2].abs() < 1e-12, "{v:?}");
        }
        let cn = t.nodal_field(&NodalField::from_fn(&xo, 1, |_, o| o[0] = 7.5)).unwrap();
        assert!(cn.values.iter().all(|v| (v - 7.5).abs() < 1e-12));

        let grad = (2.0f64.powi(2) + 5.0f64.powi(2)).sqrt();
        let nn = t.nodal_field(&NodalField::from_fn(&xo, 2, linear)).unwrap();
        let exact = NodalField::from_fn(&xn, 2, linear);
        for (i, l) in t.node_locations().iter().enumerate() {
            let e = (nn.node(i)[0] - exact.node(i)[0]).abs();
            assert!(e <= grad * l.distance + 1e-12, "node {i}: error {e:e}, distance {:e}", l.distance);
        }
    }

    fn smooth(p: [f64; 2], out: &mut [f64]) {
        out[0] = (2.0 * p[0]).sin() * (3.0 * p[1]).cos() + 0.5 * p[0] * p[0];
    }

    /// Relative L2 (det J-weighted over the new Gauss points) and max errors of the transfer of
    /// `smooth` between distorted rectangle meshes of k·(8×4) (old) and k·(11×6) (new).
    fn smooth_errors(k: usize, lumped: bool) -> (f64, f64) {
        let old = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 8 * k, 4 * k);
        let new = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 11 * k, 6 * k);
        let xo = deform_rectangle(&old, 2.0, 1.0, 0.12);
        let xn = deform_rectangle(&new, 2.0, 1.0, -0.08);
        let mut t = FieldTransfer::new(&old, &xo, &new, &xn).unwrap();
        let f_old = QuadField::from_fn(&quadrature_points(&old, &xo).unwrap(), 1, smooth);
        let f_new = if lumped { t.quadrature_field_lumped(&f_old).unwrap() } else { t.quadrature_field(&f_old).unwrap() };
        let gp = quadrature_points(&new, &xn).unwrap();
        let exact = QuadField::from_fn(&gp, 1, smooth);
        let (mut e2, mut n2) = (0.0, 0.0);
        for (e, el) in new.elements.iter().enumerate() {
            let dj = gauss_jacobians(&el.map(|n| xn[n]));
            for (q, w) in dj.iter().enumerate() {
                let i = 4 * e + q;
                e2 += w * (f_new.values[i] - exact.values[i]).powi(2);
                n2 += w * exact.values[i].powi(2);
            }
        }
        ((e2 / n2).sqrt(), rel_max_err(&f_new.values, &exact.values))
    }

    /// Smooth field f = sin 2x cos 3y + x²/2 (deformed coordinates), meshes h, h/2, h/4
    /// (old 8×4, 16×8, 32×16; new 11×6, 22×12, 44×24, both distorted). Measured:
    ///
    /// | mesh | rel. L2 error | ratio | rate | rel. max error | ratio | rate |
    /// |------|---------------|-------|------|----------------|-------|------|
    /// | h    | 9.08e-3       |       |      | 1.30e-2        |       |      |
    /// | h/2  | 2.30e-3       | 3.96  | 1.98 | 4.05e-3        | 3.22  | 1.69 |
    /// | h/4  | 5.78e-4       | 3.97  | 1.99 | 1.11e-3        | 3.64  | 1.86 |
    ///
    /// Second order; the max error sits at the boundary (the L2 projection's boundary nodes)
    /// and approaches its asymptotic rate more slowly. Asserted: L2 rates ≥ 1.9, max rates
    /// ≥ 1.5 (first order is the requirement; the computation is deterministic, the margins
    /// only absorb last-digit differences between platforms).
    #[test]
    fn smooth_field_converges() {
        let e: Vec<(f64, f64)> = [1, 2, 4].iter().map(|&k| smooth_errors(k, false)).collect();
        let rate = |a: f64, b: f64| (a / b).log2();
        let r_l2 = [rate(e[0].0, e[1].0), rate(e[1].0, e[2].0)];
        let r_max = [rate(e[0].1, e[1].1), rate(e[1].1, e[2].1)];
        tracing::info!(?e, ?r_l2, ?r_max, "smooth transfer convergence");
        assert!(r_l2.iter().all(|&r| r >= 1.9) && r_max.iter().all(|&r| r >= 1.5), "errors {e:?}, L2 rates {r_l2:?}, max rates {r_max:?}");
        assert!(e[2].0 < 1e-3, "{e:?}");
    }

    /// Data with a jump (1 left of x = 1.13, 0 right of it, in deformed coordinates) on the
    /// distorted rectangle meshes of `smooth_errors`: the consistent projection over- and
    /// undershoots (measured max 1.19, 1.16, 1.23 and min −0.21, −0.24, −0.17 for k = 1, 2, 4:
    /// asserted beyond 1.1 and −0.1, and within ±0.3), the lumped one stays in [0, 1]
    /// (to 1e-12: its values are convex combinations of the data).
    /// The same study with the lumped projection: first order, as expected of a one-sided
    /// average at the boundary. Measured:
    ///
    /// | mesh | rel. L2 error | rate | rel. max error | rate |
    /// |------|---------------|------|----------------|------|
    /// | h    | 6.18e-2       |      | 1.16e-1        |      |
    /// | h/2  | 2.32e-2       | 1.41 | 5.49e-2        | 1.09 |
    /// | h/4  | 8.18e-3       | 1.50 | 2.66e-2        | 1.04 |
    ///
    /// Asserted: L2 rates ≥ 1.3, max rates ≥ 0.9 (deterministic values).
    #[test]
    fn smooth_field_converges_lumped() {
        let e: Vec<(f64, f64)> = [1, 2, 4].iter().map(|&k| smooth_errors(k, true)).collect();
        let rate = |a: f64, b: f64| (a / b).log2();
        let r_l2 = [rate(e[0].0, e[1].0), rate(e[1].0, e[2].0)];
        let r_max = [rate(e[0].1, e[1].1), rate(e[1].1, e[2].1)];
        assert!(r_l2.iter().all(|&r| r >= 1.3) && r_max.iter().all(|&r| r >= 0.9), "errors {e:?}, L2 rates {r_l2:?}, max rates {r_max:?}");
    }

    #[test]
    fn jump_overshoot_consistent_not_lumped() {
        for k in [1, 2, 4] {
            let old = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 8 * k, 4 * k);
            let new = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 11 * k, 6 * k);
            let xo = deform_rectangle(&old, 2.0, 1.0, 0.12);
            let xn = deform_rectangle(&new, 2.0, 1.0, -0.08);
            let mut t = FieldTransfer::new(&old, &xo, &new, &xn).unwrap();
            let f_old = QuadField::from_fn(&quadrature_points(&old, &xo).unwrap(), 1, |p, o| o[0] = if p[0] < 1.13 { 1.0 } else { 0.0 });
            let range = |v: &[f64]| (v.iter().cloned().fold(f64::INFINITY, f64::min), v.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
            let (lo, hi) = range(&t.quadrature_field(&f_old).unwrap().values);
            assert!(hi > 1.1 && hi < 1.3 && lo < -0.1 && lo > -0.3, "k = {k}: [{lo}, {hi}]");
            let (lo, hi) = range(&t.quadrature_field_lumped(&f_old).unwrap().values);
            assert!(lo >= -1e-12 && hi <= 1.0 + 1e-12, "k = {k}: lumped [{lo}, {hi}]");
            assert!(lo < 0.01 && hi > 0.99, "the jump is still resolved: [{lo}, {hi}]");
        }
    }

    #[test]
    fn degenerate_input() {
        let m = shapes::rectangle([0.0, 0.0], 1.0, 1.0, 2, 2);
        let mut t = FieldTransfer::new(&m, &m.nodes, &m, &m.nodes).unwrap();
        assert_eq!(t.quadrature_field(&QuadField { n_comp: 0, values: vec![] }), Err(RemeshError::NoComponents));
        assert!(matches!(t.quadrature_field(&QuadField::zeros(3, 1)), Err(RemeshError::SizeMismatch { .. })));
        let mut f = QuadField::zeros(4, 2);
        f.values[5] = f64::NAN;
        assert!(matches!(t.quadrature_field(&f), Err(RemeshError::NonFinite { .. })));
        assert!(t.nodal_field(&NodalField { n_comp: 1, values: vec![0.0; 3] }).is_err());
        // zero field: zero out, no solve
        let z = t.quadrature_field(&QuadField::zeros(4, 2)).unwrap();
        assert!(z.values.iter().all(|&v| v == 0.0));
        // an orphan node does not break the projection
        let mut mo = m.clone();
        mo.nodes.push([5.0, 5.0]);
        let xo = mo.nodes.clone();
        let mut p = L2Projector::new(&mo, &xo).unwrap();
        let one = QuadField { n_comp: 1, values: vec![1.0; 16] };
        let n = p.project(&one).unwrap();
        assert!(n.values[..9].iter().all(|v| (v - 1.0).abs() < 1e-12) && n.values[9] == 0.0);
        // inverted old element
        let mut x = m.nodes.clone();
        x[4] = [1.2, 1.2];
        assert!(matches!(L2Projector::new(&m, &x), Err(RemeshError::InvalidElement { .. })));
    }
}
