//! All-quadrilateral meshes of simple (possibly non-convex) polygons.
//!
//! [`simple_polygon`] meshes any simple polygon (no two sides cross or touch, except neighbours
//! at their shared vertex) with a target element size `h` (mm):
//!
//! 1. the outline is resampled ([`resample_outline`]) so that no side is longer than `2h`; every
//!    input vertex is kept and the new points lie on the input sides, so the meshed region is
//!    exactly the input polygon (its area equals the polygon's area to round-off);
//! 2. a constrained Delaunay triangulation of the resampled outline is refined (the `spade`
//!    crate: Ruppert-type refinement with a minimum angle of [`MIN_TRIANGLE_ANGLE_DEG`] and a
//!    largest triangle area of `2√3 h²`, twice an equilateral triangle of side `2h`, which gives
//!    triangles of side about `2h`); refinement may split outline sides further, always at
//!    points on the side;
//! 3. every triangle is split into three quadrilaterals through its centroid and its edge
//!    midpoints, so the quadrilaterals have edges of about `h` (half the triangle edges; the
//!    mean element edge comes out at 0.8–0.95 `h`, finer near sharp corners) and the boundary
//!    nodes are the resampled outline points plus the midpoints between them (boundary edges
//!    at most `h`).
//!
//! Quality: a triangle whose angles are all at least 30° gives three quadrilaterals with a
//! scaled Jacobian of at least [`MIN_SCALED_JACOBIAN`] (0.37, the sine of the smallest corner
//! angle; equilateral triangles give 0.87). The refinement reaches the angle limit everywhere
//! except next to input corners sharper than the limit, where the quadrilateral at the tip has
//! the tip's angle (scaled Jacobian about the sine of the corner angle).
//!
//! The same split is available for any triangulation as [`triangles_to_quads`] (used for
//! triangles read from gmsh files).

use super::shapes::MeshError;
use super::Mesh;
use std::collections::HashMap;

type P = [f64; 2];

/// Minimum triangle angle requested from the Delaunay refinement (degrees).
pub const MIN_TRIANGLE_ANGLE_DEG: f64 = 30.0;

/// Smallest scaled Jacobian of the three quadrilaterals of a triangle whose angles are all at
/// least [`MIN_TRIANGLE_ANGLE_DEG`] (worst case over such triangles, computed numerically:
/// 0.3712); meshes from [`simple_polygon`] reach it unless the polygon has corners sharper than
/// about 35°.
pub const MIN_SCALED_JACOBIAN: f64 = 0.37;

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: P, b: P) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// `(b - a) × (c - a)`: positive when `a, b, c` turn counter-clockwise.
pub(crate) fn orient(a: P, b: P, c: P) -> f64 {
    cross(sub(b, a), sub(c, a))
}

/// Half the diagonal of the bounding box of `pts` (0 for no points).
pub(crate) fn size_of(pts: &[P]) -> f64 {
    let [lo, hi] = super::bounding_box(pts);
    if pts.is_empty() {
        0.0
    } else {
        0.5 * (hi[0] - lo[0]).hypot(hi[1] - lo[1])
    }
}

/// Whether the closed segments `a0 a1` and `b0 b1` share a point, with orientation values
/// within `eps` counted as collinear.
pub(crate) fn segments_touch(a0: P, a1: P, b0: P, b1: P, eps: f64) -> bool {
    let sign = |v: f64| if v > eps { 1 } else if v < -eps { -1 } else { 0 };
    let d1 = sign(orient(b0, b1, a0));
    let d2 = sign(orient(b0, b1, a1));
    let d3 = sign(orient(a0, a1, b0));
    let d4 = sign(orient(a0, a1, b1));
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let within = |p: P, q: P, r: P| {
        // r on the line p q: within the bounding box (slightly enlarged)
        let t = eps.sqrt();
        r[0] >= p[0].min(q[0]) - t && r[0] <= p[0].max(q[0]) + t && r[1] >= p[1].min(q[1]) - t && r[1] <= p[1].max(q[1]) + t
    };
    (d1 == 0 && within(b0, b1, a0))
        || (d2 == 0 && within(b0, b1, a1))
        || (d3 == 0 && within(a0, a1, b0))
        || (d4 == 0 && within(a0, a1, b1))
}

/// Checks that `vertices` form a simple polygon (either orientation) and returns its signed
/// area (positive when counter-clockwise).
///
/// # Errors
/// [`MeshError`] for fewer than 3 vertices, a non-finite coordinate, a zero-length side, zero
/// area, or two sides that cross or touch (other than neighbours at their shared vertex; a
/// neighbour folding back onto its predecessor counts as touching).
pub fn check_simple_polygon(vertices: &[[f64; 2]]) -> Result<f64, MeshError> {
    let n = vertices.len();
    if n < 3 {
        return Err(MeshError::TooFewVertices(n));
    }
    if let Some(k) = vertices.iter().position(|v| !(v[0].is_finite() && v[1].is_finite())) {
        return Err(MeshError::NonFiniteVertex(k));
    }
    let size = size_of(vertices).max(f64::MIN_POSITIVE);
    for k in 0..n {
        let (a, b) = (vertices[k], vertices[(k + 1) % n]);
        if (a[0] - b[0]).hypot(a[1] - b[1]) <= 1e-12 * size {
            return Err(MeshError::DegenerateSide(k));
        }
    }
    let area = super::polygon_area(vertices.iter().copied());
    if area.abs() <= 1e-12 * size * size {
        return Err(MeshError::ZeroArea);
    }
    // orientation values of points on a line are zero up to this (relative to the size)
    let eps = 1e-12 * size * size;
    // neighbours: a side folding back onto the previous one (a spike of zero angle)
    for k in 0..n {
        let (a, b, c) = (vertices[(k + n - 1) % n], vertices[k], vertices[(k + 1) % n]);
        let (u, v) = (sub(a, b), sub(c, b));
        if orient(a, b, c).abs() <= eps && u[0] * v[0] + u[1] * v[1] > 0.0 {
            return Err(MeshError::SelfIntersecting((k + n - 1) % n, k));
        }
    }
    // every other pair of sides, pruned by a sweep over the sides' x ranges
    let mut sides: Vec<(usize, f64, f64)> = (0..n)
        .map(|k| {
            let (a, b) = (vertices[k], vertices[(k + 1) % n]);
            (k, a[0].min(b[0]), a[0].max(b[0]))
        })
        .collect();
    sides.sort_by(|p, q| p.1.total_cmp(&q.1));
    let tol = 1e-9 * size;
    for (s, &(i, _, xmax)) in sides.iter().enumerate() {
        for &(j, xmin, _) in &sides[s + 1..] {
            if xmin > xmax + tol {
                break;
            }
            let adjacent = (i + 1) % n == j || (j + 1) % n == i;
            if adjacent {
                continue;
            }
            let (a0, a1) = (vertices[i], vertices[(i + 1) % n]);
            let (b0, b1) = (vertices[j], vertices[(j + 1) % n]);
            if segments_touch(a0, a1, b0, b1, eps) {
                return Err(MeshError::SelfIntersecting(i.min(j), i.max(j)));
            }
        }
    }
    Ok(area)
}

/// The outline with every side longer than `max_side` split into equal parts no longer than
/// `max_side`; every input vertex is kept, in order. `max_side` must be positive.
pub fn resample_outline(vertices: &[[f64; 2]], max_side: f64) -> Vec<[f64; 2]> {
    let n = vertices.len();
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let (a, b) = (vertices[k], vertices[(k + 1) % n]);
        out.push(a);
        let m = super::shapes::divisions_for((b[0] - a[0]).hypot(b[1] - a[1]), max_side);
        for i in 1..m {
            let t = i as f64 / m as f64;
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    out
}

/// All-quadrilateral mesh of a simple polygon (counter-clockwise or clockwise) with target
/// element size `h` (see the module docs for the method and the quality bound).
///
/// The mesh has counter-clockwise elements, one closed boundary loop (counter-clockwise, body on
/// the left) through every input vertex in order, and the edge set `"boundary"`.
///
/// # Errors
/// [`MeshError`] for invalid input (see [`check_simple_polygon`]), `h` not positive and finite,
/// or a failure of the triangulation.
pub fn simple_polygon(vertices: &[[f64; 2]], h: f64) -> Result<Mesh, MeshError> {
    polygon_mesh(vertices, h, false)
}

/// [`simple_polygon`] whose refinement never splits a side of the (resampled) outline, so
/// that the boundary nodes are the resampled outline points and the midpoints between them,
/// and nothing else (the re-meshing of a deformed particle places those midpoints itself;
/// see [`crate::remesh::remesh_particle_keeping`]). Next to a long side between short ones the
/// triangles may then stay below the angle limit.
///
/// # Errors
/// As [`simple_polygon`].
pub fn simple_polygon_keeping_sides(vertices: &[[f64; 2]], h: f64) -> Result<Mesh, MeshError> {
    polygon_mesh(vertices, h, true)
}

fn polygon_mesh(vertices: &[[f64; 2]], h: f64, keep_sides: bool) -> Result<Mesh, MeshError> {
    if !(h > 0.0 && h.is_finite()) {
        return Err(MeshError::InvalidSize(h));
    }
    let area = check_simple_polygon(vertices)?;
    let ccw: Vec<P> = if area > 0.0 { vertices.to_vec() } else { vertices.iter().rev().copied().collect() };
    let outline = resample_outline(&ccw, 2.0 * h);
    let (nodes, triangles) = refined_triangulation(&outline, h, keep_sides)?;
    Ok(triangles_to_quads(nodes, &triangles))
}

/// Constrained Delaunay triangulation of the counter-clockwise `outline`, refined to triangles
/// of side about `2h`; returns the nodes used and the counter-clockwise triangles inside.
fn refined_triangulation(outline: &[P], h: f64, keep_sides: bool) -> Result<(Vec<P>, Vec<[usize; 3]>), MeshError> {
    use spade::{AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation};
    let n = outline.len();
    let pts: Vec<Point2<f64>> = outline.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let edges: Vec<[usize; 2]> = (0..n).map(|k| [k, (k + 1) % n]).collect();
    let mut conflicts = 0usize;
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(pts, edges, |_| conflicts += 1)
        .map_err(|e| MeshError::Triangulation(format!("{e:?}")))?;
    if conflicts > 0 || cdt.num_vertices() != n {
        return Err(MeshError::Triangulation(format!(
            "{conflicts} conflicting outline side(s), {} of {n} outline points kept",
            cdt.num_vertices()
        )));
    }
    // twice the area of an equilateral triangle of side 2h: the refinement splits a triangle
    // above the limit into pieces of a third to a half of it, so triangles come out at about
    // side 2h (with the limit at the area of side 2h itself they come out near side 1.3h)
    let max_area = 2.0 * 3f64.sqrt() * h * h;
    let area = super::polygon_area(outline.iter().copied()).abs();
    let budget = 20 * ((area / max_area).ceil() as usize) + 10 * n + 1000;
    let params = RefinementParameters::<f64>::new()
        .exclude_outer_faces(true)
        .with_angle_limit(AngleLimit::from_deg(MIN_TRIANGLE_ANGLE_DEG))
        .with_max_allowed_area(max_area)
        .with_max_additional_vertices(budget);
    let params = if keep_sides { params.keep_constraint_edges() } else { params };
    let result = cdt.refine(params);
    if !result.refinement_complete {
        tracing::warn!(
            "polygon mesher: Delaunay refinement stopped after {budget} added points (h = {h} mm); some triangles may be coarse or poorly shaped"
        );
    }
    let excluded: std::collections::HashSet<_> = result.excluded_faces.into_iter().collect();
    let mut index: HashMap<usize, usize> = HashMap::new();
    let mut nodes: Vec<P> = Vec::new();
    // the outline points keep their indices (and their exact coordinates)
    for v in cdt.vertices().take(n) {
        let p = v.position();
        index.insert(v.fix().index(), nodes.len());
        nodes.push([p.x, p.y]);
    }
    let mut triangles = Vec::new();
    for f in cdt.inner_faces() {
        if excluded.contains(&f.fix()) {
            continue;
        }
        let mut t = [0usize; 3];
        for (k, v) in f.vertices().iter().enumerate() {
            let id = v.fix().index();
            t[k] = *index.entry(id).or_insert_with(|| {
                let p = v.position();
                nodes.push([p.x, p.y]);
                nodes.len() - 1
            });
        }
        if orient(nodes[t[0]], nodes[t[1]], nodes[t[2]]) < 0.0 {
            t.swap(1, 2);
        }
        triangles.push(t);
    }
    if triangles.is_empty() {
        return Err(MeshError::Triangulation("no triangle inside the outline".into()));
    }
    Ok((nodes, triangles))
}

/// Splits every triangle into three quadrilaterals through its centroid and its edge
/// midpoints (vertex, midpoint of the next edge, centroid, midpoint of the previous edge) and
/// returns the conforming quadrilateral mesh ([`Mesh::from_quads`]). Triangles are made
/// counter-clockwise first; nodes not used by any triangle are dropped. Midpoints of shared
/// edges are shared, so a conforming triangulation gives a conforming mesh.
pub fn triangles_to_quads(nodes: Vec<[f64; 2]>, triangles: &[[usize; 3]]) -> Mesh {
    let mut used = vec![usize::MAX; nodes.len()];
    let mut out: Vec<P> = Vec::new();
    for t in triangles {
        for &v in t {
            if used[v] == usize::MAX {
                used[v] = out.len();
                out.push(nodes[v]);
            }
        }
    }
    let mut mid: HashMap<[usize; 2], usize> = HashMap::new();
    let mut elements = Vec::with_capacity(3 * triangles.len());
    for t in triangles {
        let mut t = t.map(|v| used[v]);
        if orient(out[t[0]], out[t[1]], out[t[2]]) < 0.0 {
            t.swap(1, 2);
        }
        let mut m = [0usize; 3];
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            m[k] = *mid.entry([a.min(b), a.max(b)]).or_insert_with(|| {
                let (p, q) = (out[a], out[b]);
                out.push([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]);
                out.len() - 1
            });
        }
        let (p0, p1, p2) = (out[t[0]], out[t[1]], out[t[2]]);
        let g = out.len();
        out.push([(p0[0] + p1[0] + p2[0]) / 3.0, (p0[1] + p1[1] + p2[1]) / 3.0]);
        for k in 0..3 {
            elements.push([t[k], m[k], g, m[(k + 2) % 3]]);
        }
    }
    Mesh::from_quads(out, elements)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simple_polygon_checks() {
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!((check_simple_polygon(&sq).unwrap() - 1.0).abs() < 1e-15);
        let bow = [[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 1.0]];
        assert!(matches!(check_simple_polygon(&bow), Err(MeshError::SelfIntersecting(0, 2))));
        // a vertex touching a non-adjacent side
        let pinch = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [1.0, 0.0], [0.0, 2.0]];
        assert!(matches!(check_simple_polygon(&pinch), Err(MeshError::SelfIntersecting(..))));
        assert!(matches!(check_simple_polygon(&sq[..2]), Err(MeshError::TooFewVertices(2))));
        assert!(matches!(check_simple_polygon(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]), Err(MeshError::ZeroArea)));
        assert!(matches!(check_simple_polygon(&[[0.0, 0.0], [f64::NAN, 0.0], [0.0, 1.0]]), Err(MeshError::NonFiniteVertex(1))));
        assert!(matches!(simple_polygon(&sq, 0.0), Err(MeshError::InvalidSize(_))));
    }

    #[test]
    fn resampling_keeps_vertices() {
        let r = resample_outline(&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.25]], 0.3);
        assert_eq!(r.len(), 4 + 1 + 4);
        assert_eq!(r[0], [0.0, 0.0]);
        assert_eq!(r[4], [1.0, 0.0]);
        assert_eq!(r[5], [1.0, 0.25]);
    }

    #[test]
    fn one_triangle_gives_three_quads() {
        let m = triangles_to_quads(vec![[0.0, 0.0], [0.0, 1.0], [1.0, 0.0], [5.0, 5.0]], &[[0, 1, 2]]);
        assert_eq!(m.n_elements(), 3);
        assert_eq!(m.n_nodes(), 7);
        assert!((m.area(&m.nodes) - 0.5).abs() < 1e-15);
        assert_eq!(m.boundary.len(), 6);
        assert_eq!(m.boundary_loops().len(), 1);
    }
}
