//! Point location in a quadrilateral mesh: which element holds a point, and at which natural
//! coordinates (ξ, η).
//!
//! ## Search structure
//! A uniform grid of buckets over the bounding box of the mesh, with about one bucket per
//! element (bucket size √(box area / elements), at most 4 × elements buckets). Every element is
//! entered in the buckets its bounding box overlaps; the lists are stored compressed (one index
//! array and offsets), so the build is O(elements) for meshes of bounded element size ratio and
//! a query tests the O(1) elements of one bucket.
//!
//! ## Inversion of the bilinear map
//! x(ξ) = Σ N_a(ξ) x_a is inverted by Newton's method from the element centre,
//! ξ ← ξ − J(ξ)⁻¹ (x(ξ) − p), until the step is below 10⁻¹⁴ or stalls at round-off (see
//! [`invert_bilinear`]). A point is inside when the converged
//! |ξ|, |η| ≤ 1 + 10⁻¹⁰ (the excess is clamped away).
//!
//! ## Points outside the mesh
//! A point in no element (the new boundary differs from the old one by round-off or by
//! resampling) is assigned to the **nearest element** (smallest Euclidean distance to the
//! element's boundary polygon, found by a ring search over the buckets, exact) with the natural
//! coordinates of the **closest point of that element**: that point lies on an edge, which the
//! bilinear map parametrises linearly, so its (ξ, η) is exact and lies on the boundary of
//! [−1, 1]² ("clamped" coordinates). [`Location::distance`] is the distance to that point
//! (0 for points inside). Interpolating there is a constant extension normal to the boundary:
//! it keeps constants and bounds, and errs by at most |∇f| × distance for a smooth f.
//!
//! The locator requires every element to be valid (scaled Jacobian > 0 in the given
//! coordinates, which makes the bilinear map one-to-one); otherwise the constructor returns
//! [`RemeshError::InvalidElement`].
// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{check_mesh, RemeshError};
use crate::element::{shape, shape_derivs};
use crate::mesh::quality::scaled_jacobian;
use crate::mesh::Mesh;

/// Where a point lies in a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Location {
    /// Element index.
    pub element: usize,
    /// Natural coordinates (ξ, η) in [−1, 1]².
    pub xi: [f64; 2],
    /// Distance (mm) from the point to the element: 0 inside, > 0 for a point outside the mesh
    /// assigned to its nearest element (see the module docs).
    pub distance: f64,
}

impl Location {
    /// Whether the point was found inside an element.
    pub fn is_inside(&self) -> bool {
        self.distance == 0.0
    }

    /// Shape function values at the location.
    pub fn shape(&self) -> [f64; 4] {
        shape(self.xi[0], self.xi[1])
    }
}

/// Tolerance on the natural coordinates for "inside" (see the module docs).
const XI_TOL: f64 = 1e-10;
/// Newton step size at which the inversion has converged.
const NEWTON_TOL: f64 = 1e-14;
const NEWTON_MAX_ITER: usize = 30;

/// Uniform-grid point locator for one mesh in given nodal coordinates (see the module docs).
#[derive(Clone, Debug)]
pub struct PointLocator {
    /// Corner coordinates of every element.
    corners: Vec<[[f64; 2]; 4]>,
    lo: [f64; 2],
    cell: [f64; 2],
    nx: usize,
    ny: usize,
    /// Bucket b holds `items[start[b]..start[b + 1]]`.
    start: Vec<usize>,
    items: Vec<usize>,
}

impl PointLocator {
    /// Build the bucket grid for `mesh` with nodal coordinates `coords`.
    ///
    /// # Errors
    /// An empty mesh, wrong coordinate count, bad node index, non-finite coordinates, or an
    /// element with a non-positive scaled Jacobian.
    pub fn new(mesh: &Mesh, coords: &[[f64; 2]]) -> Result<Self, RemeshError> {
        check_mesh(mesh, coords)?;
        let corners: Vec<[[f64; 2]; 4]> = mesh.elements.iter().map(|el| el.map(|n| coords[n])).collect();
        for (e, p) in corners.iter().enumerate() {
            let sj = scaled_jacobian(*p);
            if !(sj > 0.0) {
                return Err(RemeshError::InvalidElement { element: e, scaled_jacobian: sj });
            }
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in corners.iter().flatten() {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let ne = corners.len();
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        // valid elements have positive area, so w, h > 0
        let s = (w * h / ne as f64).sqrt();
        let max_cells = 4 * ne + 16;
        let nx = ((w / s).ceil() as usize).clamp(1, max_cells);
        let ny = ((h / s).ceil() as usize).clamp(1, (max_cells / nx).max(1));
        let cell = [w / nx as f64, h / ny as f64];
        let mut loc = Self { corners, lo, cell, nx, ny, start: vec![0; nx * ny + 1], items: Vec::new() };
        // two passes: count, then fill (compressed bucket lists)
        let ranges: Vec<[usize; 4]> = loc.corners.iter().map(|p| loc.cell_range(p)).collect();
        for r in &ranges {
            for j in r[2]..=r[3] {
                for i in r[0]..=r[1] {
                    loc.start[j * nx + i + 1] += 1;
                }
            }
        }
        for b in 0..nx * ny {
            loc.start[b + 1] += loc.start[b];
        }
        let mut next = loc.start.clone();
        loc.items = vec![0; loc.start[nx * ny]];
        for (e, r) in ranges.iter().enumerate() {
            for j in r[2]..=r[3] {
                for i in r[0]..=r[1] {
                    let b = j * nx + i;
                    loc.items[next[b]] = e;
                    next[b] += 1;
                }
            }
        }
        Ok(loc)
    }

    /// Number of elements of the located mesh.
    pub fn n_elements(&self) -> usize {
        self.corners.len()
    }

    /// Cell index along axis k of a coordinate, clamped to the grid.
    fn cell_of(&self, v: f64, k: usize) -> usize {
        let n = if k == 0 { self.nx } else { self.ny };
        let t = ((v - self.lo[k]) / self.cell[k]).floor();
        if t.is_nan() || t < 0.0 {
            0
        } else {
            (t as usize).min(n - 1)
        }
    }

    /// Cell ranges `[i0, i1, j0, j1]` (inclusive) overlapped by the bounding box of a quad,
    /// widened by a relative 1e-9 so that points on a bucket border find the element.
    fn cell_range(&self, p: &[[f64; 2]; 4]) -> [usize; 4] {
        let [lo, hi] = crate::mesh::bounding_box(p);
        let pad = [1e-9 * self.cell[0], 1e-9 * self.cell[1]];
        [
            self.cell_of(lo[0] - pad[0], 0),
            self.cell_of(hi[0] + pad[0], 0),
            self.cell_of(lo[1] - pad[1], 1),
            self.cell_of(hi[1] + pad[1], 1),
        ]
    }

    fn bucket(&self, i: usize, j: usize) -> &[usize] {
        let b = j * self.nx + i;
        &self.items[self.start[b]..self.start[b + 1]]
    }

    /// Locate `p` (see the module docs): the element holding it with its natural coordinates,
    /// or, outside the mesh, the nearest element with the coordinates of its closest point.
    ///
    /// # Errors
    /// A non-finite point.
    pub fn locate(&self, p: [f64; 2]) -> Result<Location, RemeshError> {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(RemeshError::NonFinite { what: "point", index: 0 });
        }
        let (ci, cj) = (self.cell_of(p[0], 0), self.cell_of(p[1], 1));
        for &e in self.bucket(ci, cj) {
            if let Some(xi) = invert_if_inside(&self.corners[e], p) {
                return Ok(Location { element: e, xi, distance: 0.0 });
            }
        }
        Ok(self.nearest(p, ci, cj))
    }

    /// Locate many points.
    ///
    /// # Errors
    /// A non-finite point (its index is reported).
    pub fn locate_all(&self, points: &[[f64; 2]]) -> Result<Vec<Location>, RemeshError> {
        points
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                self.locate(p).map_err(|e| match e {
                    RemeshError::NonFinite { what, .. } => RemeshError::NonFinite { what, index: i },
                    other => other,
                })
            })
            .collect()
    }

    /// Ring search for the nearest element of a point in no element, starting at cell
    /// (ci, cj): after the rings 0..=r have been scanned, every element closer than
    /// r × min(cell size) has been seen (the point lies in, or projects onto, cell (ci, cj)),
    /// so the search stops when that bound passes the best distance.
    fn nearest(&self, p: [f64; 2], ci: usize, cj: usize) -> Location {
        let mut best = Location { element: 0, xi: [0.0; 2], distance: f64::INFINITY };
        let step = self.cell[0].min(self.cell[1]);
        let r_max = self.nx.max(self.ny);
        for r in 0..=r_max {
            let (i0, i1) = (ci.saturating_sub(r), (ci + r).min(self.nx - 1));
            let (j0, j1) = (cj.saturating_sub(r), (cj + r).min(self.ny - 1));
            for j in j0..=j1 {
                // only the cells of ring r (Chebyshev distance r from the start cell): whole
                // rows at the top and bottom of the ring, the two side cells in between
                let full_row = j.abs_diff(cj) == r;
                let sides = [ci.checked_sub(r), Some(ci + r).filter(|&i| i < self.nx)];
                let row: Vec<usize> = if full_row {
                    (i0..=i1).collect()
                } else {
                    sides.iter().flatten().copied().collect()
                };
                for i in row {
                    for &e in self.bucket(i, j) {
                        let (d, xi) = closest_point(&self.corners[e], p);
                        if d < best.distance || (d == best.distance && e < best.element) {
                            best = Location { element: e, xi, distance: d };
                        }
                    }
                }
            }
            if best.distance <= r as f64 * step {
                break;
            }
        }
        if best.distance == 0.0 {
            // inside the polygon of an element although the Newton inversion did not accept
            // it (a point on an edge to round-off): keep it inside with its edge coordinates
            tracing::trace!(?p, element = best.element, "point on an element edge, located by the edge projection");
        }
        best
    }
}

/// x(ξ) for the corners `p`.
fn map(p: &[[f64; 2]; 4], xi: [f64; 2]) -> [f64; 2] {
    let n = shape(xi[0], xi[1]);
    let mut x = [0.0; 2];
    for a in 0..4 {
        x[0] += n[a] * p[a][0];
        x[1] += n[a] * p[a][1];
    }
    x
}

/// Newton inversion of the bilinear map of the quad `p` at the point `x` from the element
/// centre. Returns the natural coordinates when Newton converged, whether or not they lie in
/// [−1, 1]²; `None` on divergence (|ξ| > 10, a singular Jacobian, or no convergence in 30
/// iterations — points far outside an element).
///
/// The corners and the point are first shifted by the element centroid, so that the residual
/// x(ξ) − p is computed with a round-off relative to the element size rather than to the
/// distance from the origin. Converged: a step ≤ 10⁻¹⁴, or a step below 10⁻⁸ that no longer
/// halves (quadratic convergence stalled at round-off, for very distorted elements).
pub fn invert_bilinear(p: &[[f64; 2]; 4], x: [f64; 2]) -> Option<[f64; 2]> {
    let c = [0.25 * (p[0][0] + p[1][0] + p[2][0] + p[3][0]), 0.25 * (p[0][1] + p[1][1] + p[2][1] + p[3][1])];
    let q: [[f64; 2]; 4] = p.map(|v| [v[0] - c[0], v[1] - c[1]]);
    let x = [x[0] - c[0], x[1] - c[1]];
    let mut xi = [0.0f64; 2];
    let mut prev = f64::INFINITY;
    for _ in 0..NEWTON_MAX_ITER {
        let y = map(&q, xi);
        let r = [y[0] - x[0], y[1] - x[1]];
        let dn = shape_derivs(xi[0], xi[1]);
        let mut j = [[0.0; 2]; 2];
        for a in 0..4 {
            for i in 0..2 {
                for k in 0..2 {
                    j[i][k] += q[a][i] * dn[a][k];
                }
            }
        }
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if !(det.abs() > 0.0) || !det.is_finite() {
            return None;
        }
        let d = [(j[1][1] * r[0] - j[0][1] * r[1]) / det, (-j[1][0] * r[0] + j[0][0] * r[1]) / det];
        xi[0] -= d[0];
        xi[1] -= d[1];
        if !(xi[0].abs() <= 10.0 && xi[1].abs() <= 10.0) {
            return None;
        }
        let step = d[0].abs().max(d[1].abs());
        if step <= NEWTON_TOL || (step <= 1e-8 && step > 0.5 * prev) {
            return Some(xi);
        }
        prev = step;
    }
    None
}

/// Natural coordinates of `x` in the quad `p` if it lies inside (to [`XI_TOL`]), clamped to
/// [−1, 1]².
fn invert_if_inside(p: &[[f64; 2]; 4], x: [f64; 2]) -> Option<[f64; 2]> {
    // cheap bounding-box rejection (with a relative margin for points on an edge)
    let [lo, hi] = crate::mesh::bounding_box(p);
    let pad = 1e-9 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if x[0] < lo[0] - pad || x[0] > hi[0] + pad || x[1] < lo[1] - pad || x[1] > hi[1] + pad {
        return None;
    }
    let xi = invert_bilinear(p, x)?;
    if xi[0].abs() <= 1.0 + XI_TOL && xi[1].abs() <= 1.0 + XI_TOL {
        Some([xi[0].clamp(-1.0, 1.0), xi[1].clamp(-1.0, 1.0)])
    } else {
        None
    }
}

/// Distance from `x` to the quad `p` (0 when inside its polygon) and the natural coordinates
/// of the closest point: for a point outside, the closest point on the closest edge, whose
/// edge parameter t ∈ [0, 1] maps to (ξ, η) exactly (edge a → a+1 of the counter-clockwise
/// element: η = −1, ξ = 1, η = 1, ξ = −1 in turn).
fn closest_point(p: &[[f64; 2]; 4], x: [f64; 2]) -> (f64, [f64; 2]) {
    let mut inside = true;
    let mut best = (f64::INFINITY, [0.0; 2]);
    for a in 0..4 {
        let b = (a + 1) % 4;
        let e = [p[b][0] - p[a][0], p[b][1] - p[a][1]];
        let w = [x[0] - p[a][0], x[1] - p[a][1]];
        if e[0] * w[1] - e[1] * w[0] < 0.0 {
            inside = false; // right of a counter-clockwise edge
        }
        let l2 = e[0] * e[0] + e[1] * e[1];
        let t = if l2 > 0.0 { ((e[0] * w[0] + e[1] * w[1]) / l2).clamp(0.0, 1.0) } else { 0.0 };
        let d = (w[0] - t * e[0]).hypot(w[1] - t * e[1]);
        if d < best.0 {
            let s = 2.0 * t - 1.0;
            let xi = match a {
                0 => [s, -1.0],
                1 => [1.0, s],
                2 => [-s, 1.0],
                _ => [-1.0, -s],
            };
            best = (d, xi);
        }
    }
    if inside {
        // a valid element is convex; use the Newton inversion when it converges
        let xi = invert_bilinear(p, x).map(|v| [v[0].clamp(-1.0, 1.0), v[1].clamp(-1.0, 1.0)]).unwrap_or(best.1);
        return (0.0, xi);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;
    use rand_chacha::rand_core::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn uniform(rng: &mut ChaCha8Rng, a: f64, b: f64) -> f64 {
        let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        a + (b - a) * u
    }

    /// Random convex quads (corners of a unit square moved by up to 0.35 in each direction,
    /// kept if the scaled Jacobian is above 0.05) and random natural coordinates: Newton
    /// recovers (ξ, η) to 1e-12. The map is evaluated in floating point, so the recovered
    /// coordinates can differ by the conditioning of J times the round-off of x (|x| ≤ 2, J of
    /// order 1/sj ≤ 20: ~1e-14).
    #[test]
    fn newton_recovers_natural_coordinates() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut n_quads = 0;
        let mut worst: f64 = 0.0;
        while n_quads < 200 {
            let base = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
            let p: [[f64; 2]; 4] = std::array::from_fn(|a| [base[a][0] + uniform(&mut rng, -0.35, 0.35), base[a][1] + uniform(&mut rng, -0.35, 0.35)]);
            if scaled_jacobian(p) < 0.05 {
                continue;
            }
            n_quads += 1;
            for _ in 0..20 {
                let xi = [uniform(&mut rng, -1.0, 1.0), uniform(&mut rng, -1.0, 1.0)];
                let x = map(&p, xi);
                let got = invert_bilinear(&p, x).expect("converges inside a valid quad");
                worst = worst.max((got[0] - xi[0]).abs().max((got[1] - xi[1]).abs()));
            }
        }
        assert!(worst < 1e-12, "worst natural-coordinate error {worst:e}");
    }

    /// The same through the bucket grid on a distorted disc mesh: random points generated
    /// from random (element, ξ, η) are found in that element (or a neighbour sharing the
    /// point, for points on an edge) with the same position to 1e-12 mm.
    #[test]
    fn locator_finds_random_points_in_distorted_mesh() {
        let m = shapes::disc([0.0, 0.0], 2.0, 0.25);
        let x = crate::remesh::test_support::deform_disc(&m, 2.0, 0.3);
        let loc = PointLocator::new(&m, &x).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..2000 {
            let e = (rng.next_u64() % m.n_elements() as u64) as usize;
            let xi = [uniform(&mut rng, -1.0, 1.0), uniform(&mut rng, -1.0, 1.0)];
            let p = m.elements[e].map(|n| x[n]);
            let pt = map(&p, xi);
            let l = loc.locate(pt).unwrap();
            assert!(l.is_inside());
            if l.element == e {
                assert!((l.xi[0] - xi[0]).abs() < 1e-12 && (l.xi[1] - xi[1]).abs() < 1e-12, "{l:?} vs {xi:?}");
            }
            let q = map(&m.elements[l.element].map(|n| x[n]), l.xi);
            assert!((q[0] - pt[0]).abs() < 1e-12 && (q[1] - pt[1]).abs() < 1e-12);
        }
        // every node is found (corners: on edges shared by up to four elements)
        for (i, &pt) in x.iter().enumerate() {
            let l = loc.locate(pt).unwrap();
            assert!(l.is_inside(), "node {i}");
            assert!(m.elements[l.element].contains(&i), "node {i} in element {}", l.element);
        }
    }

    /// Small elements far from the origin (h = 0.05 mm at 280 mm): the inversion works in
    /// coordinates relative to the element centroid, so every point is found inside and (ξ, η)
    /// is recovered to the precision the absolute point coordinates carry
    /// (ε · 280 / 0.05 ≈ 1e-12, times the Jacobian conditioning; tolerance 1e-10). A Newton test
    /// with an absolute step tolerance failed here (the step stalls at ~2e-14).
    #[test]
    fn locator_far_from_origin() {
        let m = shapes::rectangle([250.0, -120.0], 2.0, 1.0, 40, 20);
        let x: Vec<[f64; 2]> = crate::remesh::test_support::deform_rectangle(
            &Mesh { nodes: m.nodes.iter().map(|p| [p[0] - 250.0, p[1] + 120.0]).collect(), ..m.clone() },
            2.0,
            1.0,
            0.1,
        )
        .iter()
        .map(|p| [p[0] + 250.0, p[1] - 120.0])
        .collect();
        let loc = PointLocator::new(&m, &x).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..2000 {
            let e = (rng.next_u64() % m.n_elements() as u64) as usize;
            let xi = [uniform(&mut rng, -1.0, 1.0), uniform(&mut rng, -1.0, 1.0)];
            let pt = map(&m.elements[e].map(|n| x[n]), xi);
            let l = loc.locate(pt).unwrap();
            assert!(l.is_inside(), "{l:?}");
            if l.element == e {
                assert!((l.xi[0] - xi[0]).abs() < 1e-10 && (l.xi[1] - xi[1]).abs() < 1e-10, "{l:?} vs {xi:?}");
            }
        }
    }

    /// Points outside the mesh: nearest element and the natural coordinates of the closest
    /// point, checked against a brute-force search over all elements (distance to 1e-14).
    #[test]
    fn points_outside_go_to_nearest_element() {
        let m = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 8, 4);
        let x = crate::remesh::test_support::deform_rectangle(&m, 2.0, 1.0, 0.1);
        let loc = PointLocator::new(&m, &x).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut n_out = 0;
        for _ in 0..500 {
            let pt = [uniform(&mut rng, -1.0, 4.0), uniform(&mut rng, -1.5, 1.5)];
            let l = loc.locate(pt).unwrap();
            // brute force
            let (mut bd, mut be) = (f64::INFINITY, 0);
            for (e, el) in m.elements.iter().enumerate() {
                let (d, _) = closest_point(&el.map(|n| x[n]), pt);
                if d < bd {
                    bd = d;
                    be = e;
                }
            }
            assert!((l.distance - bd).abs() < 1e-14, "{l:?} vs {bd} in {be}");
            if l.distance > 0.0 {
                n_out += 1;
                assert!(l.xi[0].abs() == 1.0 || l.xi[1].abs() == 1.0, "clamped coordinates on the element boundary");
                // the location maps to a point at exactly that distance
                let q = map(&m.elements[l.element].map(|n| x[n]), l.xi);
                assert!(((q[0] - pt[0]).hypot(q[1] - pt[1]) - l.distance).abs() < 1e-12);
            }
        }
        assert!(n_out > 100, "the sample has points outside: {n_out}");
        // a point just outside (1e-9 mm) an edge: distance 1e-9, coordinates on that edge
        let mid = [0.5 * (x[0][0] + x[1][0]), 0.5 * (x[0][1] + x[1][1])];
        let e0 = [x[1][0] - x[0][0], x[1][1] - x[0][1]];
        let l0 = e0[0].hypot(e0[1]);
        let out = [mid[0] + 1e-9 * e0[1] / l0, mid[1] - 1e-9 * e0[0] / l0];
        let l = loc.locate(out).unwrap();
        assert_eq!(l.element, 0);
        assert!((l.distance - 1e-9).abs() < 1e-14);
        assert!((l.xi[0] - 0.0).abs() < 1e-6 && l.xi[1] == -1.0, "{l:?}");
    }

    /// The build is O(elements): about one bucket per element and each element in a bounded
    /// number of buckets. Measured: distorted 200×100 rectangle mesh, 20000 elements, 20124
    /// buckets, 4.36 entries per element, at most 9 elements per bucket; distorted disc mesh,
    /// 12561 elements, 12635 buckets, 4.43 entries per element, at most 10 per bucket.
    /// Asserted: ≤ 5 entries per element, ≤ 4 buckets per element + 16, ≤ 12 per bucket.
    #[test]
    fn bucket_grid_is_linear() {
        let r = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 200, 100);
        let xr = crate::remesh::test_support::deform_rectangle(&r, 2.0, 1.0, 0.12);
        let d = shapes::disc([0.0, 0.0], 1.0, 0.02);
        let xd = crate::remesh::test_support::deform_disc(&d, 1.0, 0.2);
        for (m, x) in [(&r, &xr), (&d, &xd)] {
            let loc = PointLocator::new(m, x).unwrap();
            let ne = m.n_elements();
            let n_buckets = loc.nx * loc.ny;
            let max_load = (0..n_buckets).map(|b| loc.start[b + 1] - loc.start[b]).max().unwrap();
            assert!(loc.items.len() <= 5 * ne, "{} entries for {ne} elements", loc.items.len());
            assert!(n_buckets <= 4 * ne + 16);
            assert!(max_load <= 12, "max bucket load {max_load}");
        }
    }

    #[test]
    fn degenerate_input() {
        let m = shapes::rectangle([0.0, 0.0], 1.0, 1.0, 2, 2);
        assert!(matches!(PointLocator::new(&Mesh::default(), &[]), Err(RemeshError::EmptyMesh)));
        let mut x = m.nodes.clone();
        x[4] = [1.2, 1.2]; // centre node beyond the far corner: element 0 is a dart
        assert!(matches!(PointLocator::new(&m, &x), Err(RemeshError::InvalidElement { .. })));
        let loc = PointLocator::new(&m, &m.nodes).unwrap();
        assert!(loc.locate([f64::NAN, 0.0]).is_err());
        assert!(loc.locate_all(&[[0.1, 0.1], [0.0, f64::INFINITY]]).is_err());
        // far away points are still located (nearest corner element)
        let l = loc.locate([100.0, 100.0]).unwrap();
        assert_eq!(m.elements[l.element], m.elements[3]);
        assert_eq!(l.xi, [1.0, 1.0]);
    }
}
