//! Overlap tests between particles: convex ones (discs, ellipses, convex polygons) and, in
//! general, any simple polygons ([`simple_polygons_overlap`], [`overlapping_particles`]).
//!
//! Two discs overlap when the distance of their centres is below the sum of their radii (exact).
//! Any other pair is first measured with GJK (parry2d) on exact support maps: a disc, a rotated
//! ellipse (support point `c + R A² Rᵀd / |A Rᵀd|`) and the convex hull of a polygon's
//! vertices. Where GJK finds the shapes intersecting, the penetration depth is the smallest
//! overlap of their projections, min over unit d of h_A(d) + h_B(−d) (h the support function):
//! exact over the side normals for two polygons and over the side normals and vertex
//! directions for a disc and a polygon, and, with an ellipse, the best of 512 directions
//! refined by golden-section search (the EPA of parry2d does not converge on curved shapes).
//! The result is the signed distance between the two shapes: positive when apart, negative
//! (minus the penetration depth) when they overlap. Touching is not overlapping: pairs are reported only
//! when they penetrate by more than a tolerance relative to their size.

use parry2d_f64::math::{Pose, Vector};
use parry2d_f64::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry2d_f64::shape::SupportMap;

/// A convex particle outline in world coordinates (mm).
#[derive(Clone, Debug, PartialEq)]
pub enum Convex {
    Disc { center: [f64; 2], radius: f64 },
    /// Semi-axes `[a, b]` along the axes rotated by `angle_deg` (counter-clockwise).
    Ellipse { center: [f64; 2], semi_axes: [f64; 2], angle_deg: f64 },
    /// The convex hull of these vertices.
    Polygon(Vec<[f64; 2]>),
}

impl Convex {
    /// Axis-aligned bounding box `[xmin, xmax, ymin, ymax]`.
    pub fn aabb(&self) -> [f64; 4] {
        match self {
            Convex::Disc { center: c, radius: r } => [c[0] - r, c[0] + r, c[1] - r, c[1] + r],
            Convex::Ellipse { center: c, semi_axes: [a, b], angle_deg } => {
                let (s, co) = angle_deg.to_radians().sin_cos();
                let hx = ((a * co).powi(2) + (b * s).powi(2)).sqrt();
                let hy = ((a * s).powi(2) + (b * co).powi(2)).sqrt();
                [c[0] - hx, c[0] + hx, c[1] - hy, c[1] + hy]
            }
            Convex::Polygon(v) => v.iter().fold(
                [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY],
                |b, p| [b[0].min(p[0]), b[1].max(p[0]), b[2].min(p[1]), b[3].max(p[1])],
            ),
        }
    }

    /// Area (mm²); for a polygon the area of its vertex loop.
    pub fn area(&self) -> f64 {
        match self {
            Convex::Disc { radius, .. } => std::f64::consts::PI * radius * radius,
            Convex::Ellipse { semi_axes, .. } => std::f64::consts::PI * semi_axes[0] * semi_axes[1],
            Convex::Polygon(v) => crate::mesh::polygon_area(v.iter().copied()).abs(),
        }
    }

    /// Points along the outline (polygons: their vertices; discs and ellipses: `n` points).
    pub fn outline(&self, n: usize) -> Vec<[f64; 2]> {
        let n = n.max(8);
        match self {
            Convex::Disc { center: c, radius: r } => (0..n)
                .map(|k| {
                    let t = std::f64::consts::TAU * k as f64 / n as f64;
                    [c[0] + r * t.cos(), c[1] + r * t.sin()]
                })
                .collect(),
            Convex::Ellipse { center: c, semi_axes: [a, b], angle_deg } => {
                let (s, co) = angle_deg.to_radians().sin_cos();
                (0..n)
                    .map(|k| {
                        let t = std::f64::consts::TAU * k as f64 / n as f64;
                        let (x, y) = (a * t.cos(), b * t.sin());
                        [c[0] + co * x - s * y, c[1] + s * x + co * y]
                    })
                    .collect()
            }
            Convex::Polygon(v) => v.clone(),
        }
    }
}

impl SupportMap for Convex {
    fn local_support_point(&self, dir: Vector) -> Vector {
        match self {
            Convex::Disc { center, radius } => {
                let n = dir.length();
                let c = Vector::new(center[0], center[1]);
                if n > 0.0 && n.is_finite() {
                    c + dir * (*radius / n)
                } else {
                    c + Vector::new(*radius, 0.0)
                }
            }
            Convex::Ellipse { center, semi_axes: [a, b], angle_deg } => {
                let (s, co) = angle_deg.to_radians().sin_cos();
                // direction in the ellipse's axes
                let (dx, dy) = (co * dir.x + s * dir.y, -s * dir.x + co * dir.y);
                let n = (a * dx).hypot(b * dy);
                let (px, py) = if n > 0.0 && n.is_finite() { (a * a * dx / n, b * b * dy / n) } else { (*a, 0.0) };
                Vector::new(center[0] + co * px - s * py, center[1] + s * px + co * py)
            }
            Convex::Polygon(v) => {
                let best = v
                    .iter()
                    .max_by(|p, q| (p[0] * dir.x + p[1] * dir.y).total_cmp(&(q[0] * dir.x + q[1] * dir.y)))
                    .copied()
                    .unwrap_or([0.0, 0.0]);
                Vector::new(best[0], best[1])
            }
        }
    }
}

/// Signed distance between two convex particles (mm): the gap when they are apart, minus the
/// penetration depth when they overlap. `None` only when the depth is not a finite number
/// (non-finite input; treat it as an overlap).
pub fn signed_distance(a: &Convex, b: &Convex) -> Option<f64> {
    if let (Convex::Disc { center: c1, radius: r1 }, Convex::Disc { center: c2, radius: r2 }) = (a, b) {
        return Some((c1[0] - c2[0]).hypot(c1[1] - c2[1]) - r1 - r2);
    }
    let pos = Pose::IDENTITY;
    let (ca, cb) = (centre_of(a), centre_of(b));
    let dir = (cb - ca).try_normalize().unwrap_or(Vector::X);
    let mut simplex = VoronoiSimplex::new();
    simplex.reset(CsoPoint::from_shapes(&pos, a, b, dir));
    match gjk::closest_points(&pos, a, b, f64::MAX, true, &mut simplex) {
        GJKResult::ClosestPoints(p1, p2, _) => Some((p2 - p1).length()),
        GJKResult::Intersection => {
            let depth = penetration_depth(a, b);
            depth.is_finite().then_some(-depth)
        }
        // with an unbounded search distance these mean "apart"
        GJKResult::Proximity(_) | GJKResult::NoIntersection(_) => Some(f64::INFINITY),
    }
}

/// Overlap of the projections of `a` and `b` on the unit direction at angle `t`.
fn projection_overlap(a: &Convex, b: &Convex, t: f64) -> f64 {
    let d = Vector::new(t.cos(), t.sin());
    a.local_support_point(d).dot(d) + b.local_support_point(-d).dot(-d)
}

/// Directions that are candidates for the smallest projection overlap of a polygon: its side
/// normals; of a disc against a polygon: also the directions from the vertices to the centre.
fn candidate_angles(s: &Convex, other: &Convex, out: &mut Vec<f64>) {
    if let Convex::Polygon(v) = s {
        let k = v.len();
        for i in 0..k {
            let (p, q) = (v[i], v[(i + 1) % k]);
            let t = (q[1] - p[1]).atan2(q[0] - p[0]);
            // both normals: the vertex order may be either way round
            out.push(t - std::f64::consts::FRAC_PI_2);
            out.push(t + std::f64::consts::FRAC_PI_2);
            if let Convex::Disc { center: c, .. } = other {
                let t = (c[1] - p[1]).atan2(c[0] - p[0]);
                out.push(t);
                out.push(t + std::f64::consts::PI);
            }
        }
    }
}

/// min over unit d of h_A(d) + h_B(−d): the penetration depth of two intersecting convex
/// shapes (the length of the shortest translation that separates them).
fn penetration_depth(a: &Convex, b: &Convex) -> f64 {
    let f = |t: f64| projection_overlap(a, b, t);
    let mut cands = Vec::new();
    candidate_angles(a, b, &mut cands);
    candidate_angles(b, a, &mut cands);
    let mut best = cands.iter().map(|&t| f(t)).fold(f64::INFINITY, f64::min);
    let ellipse = |s: &Convex| matches!(s, Convex::Ellipse { .. });
    // two discs never get here; a disc and a polygon are exact over the candidates
    if ellipse(a) || ellipse(b) || cands.is_empty() {
        const N: usize = 512;
        let step = std::f64::consts::TAU / N as f64;
        let mut samples: Vec<(f64, f64)> = (0..N).map(|k| (f(k as f64 * step), k as f64 * step)).collect();
        samples.sort_by(|p, q| p.0.total_cmp(&q.0));
        // refine around the four best samples (the minimum of a smooth function is bracketed
        // by the neighbours of the best sample)
        for &(v, t) in samples.iter().take(4) {
            best = best.min(v);
            let (mut lo, mut hi) = (t - step, t + step);
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
            let (mut f1, mut f2) = (f(x1), f(x2));
            for _ in 0..60 {
                if f1 < f2 {
                    hi = x2;
                    (x2, f2) = (x1, f1);
                    x1 = hi - g * (hi - lo);
                    f1 = f(x1);
                } else {
                    lo = x1;
                    (x1, f1) = (x2, f2);
                    x2 = lo + g * (hi - lo);
                    f2 = f(x2);
                }
            }
            best = best.min(f1).min(f2);
        }
    }
    best
}

fn centre_of(s: &Convex) -> Vector {
    let b = s.aabb();
    Vector::new(0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]))
}

/// One overlapping pair: indices into the slice given to [`overlapping_pairs`] and the
/// penetration depth (mm; `NaN` when it could not be measured).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overlap {
    pub first: usize,
    pub second: usize,
    pub depth: f64,
}

/// Every pair of particles that overlap by more than `rel_tol` × the size of the smaller one
/// (touching pairs are not reported), in order of `(first, second)`, `first < second`. `None`
/// entries (shapes that are not checked) are skipped. A sweep along x over the bounding boxes
/// keeps the number of exact tests near the number of neighbours.
pub fn overlapping_pairs(shapes: &[Option<Convex>], rel_tol: f64) -> Vec<Overlap> {
    let particles: Vec<Option<Particle>> = shapes.iter().map(|s| s.clone().map(Particle::Convex)).collect();
    overlapping_particles(&particles, rel_tol)
}

/// [`overlapping_pairs`] for particles that may be any simple polygon: two convex particles are
/// measured as there (exact signed distance); any pair with a [`Particle::Simple`] goes through
/// [`simple_polygons_overlap`] (a disc or an ellipse as the inscribed polygon of
/// [`CURVED_OUTLINE_POINTS`] points, so that overlaps shallower than about 5e-6 of its radius
/// are not seen).
pub fn overlapping_particles(shapes: &[Option<Particle>], rel_tol: f64) -> Vec<Overlap> {
    let mut items: Vec<(usize, [f64; 4])> = shapes
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.as_ref().map(|s| (i, s.aabb())))
        .filter(|(_, b)| b.iter().all(|x| x.is_finite()))
        .collect();
    items.sort_by(|p, q| p.1[0].total_cmp(&q.1[0]));
    let mut out = Vec::new();
    for (k, (i, bi)) in items.iter().enumerate() {
        for (j, bj) in &items[k + 1..] {
            if bj[0] > bi[1] {
                break;
            }
            if bj[2] > bi[3] || bj[3] < bi[2] {
                continue;
            }
            let (Some(a), Some(b)) = (&shapes[*i], &shapes[*j]) else { continue };
            let tol = rel_tol * a.size().min(b.size());
            let (first, second) = if i < j { (*i, *j) } else { (*j, *i) };
            if let (Particle::Convex(a), Particle::Convex(b)) = (a, b) {
                match signed_distance(a, b) {
                    Some(d) if d >= -tol => {}
                    Some(d) => out.push(Overlap { first, second, depth: -d }),
                    None => out.push(Overlap { first, second, depth: f64::NAN }),
                }
            } else if let Some(depth) = simple_polygons_overlap(&a.polygon(), &b.polygon(), tol) {
                out.push(Overlap { first, second, depth });
            }
        }
    }
    out.sort_by_key(|o| (o.first, o.second));
    out
}

/// Points of the inscribed polygon standing for a disc or an ellipse in the general test.
pub const CURVED_OUTLINE_POINTS: usize = 1024;

/// A particle outline for the overlap check: convex (exact tests) or any simple polygon.
#[derive(Clone, Debug, PartialEq)]
pub enum Particle {
    Convex(Convex),
    /// A simple polygon (either orientation), e.g. a user's grain outline.
    Simple(Vec<[f64; 2]>),
}

impl Particle {
    /// Axis-aligned bounding box `[xmin, xmax, ymin, ymax]`.
    pub fn aabb(&self) -> [f64; 4] {
        match self {
            Particle::Convex(c) => c.aabb(),
            Particle::Simple(v) => Convex::Polygon(v.clone()).aabb(),
        }
    }

    /// Area (mm²).
    pub fn area(&self) -> f64 {
        match self {
            Particle::Convex(c) => c.area(),
            Particle::Simple(v) => crate::mesh::polygon_area(v.iter().copied()).abs(),
        }
    }

    /// Points along the outline (polygons: their vertices; discs and ellipses: `n` points).
    pub fn outline(&self, n: usize) -> Vec<[f64; 2]> {
        match self {
            Particle::Convex(c) => c.outline(n),
            Particle::Simple(v) => v.clone(),
        }
    }

    /// The outline as a polygon for [`simple_polygons_overlap`].
    fn polygon(&self) -> Vec<[f64; 2]> {
        match self {
            Particle::Convex(c @ (Convex::Disc { .. } | Convex::Ellipse { .. })) => c.outline(CURVED_OUTLINE_POINTS),
            _ => self.outline(0),
        }
    }

    fn size(&self) -> f64 {
        let b = self.aabb();
        0.5 * (b[1] - b[0]).hypot(b[3] - b[2])
    }
}

type P = [f64; 2];

/// Signed distance of `p` from the line through `a` and `b` (positive on the left).
fn line_distance(a: P, b: P, p: P) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l = dx.hypot(dy);
    if l > 0.0 {
        (dx * (p[1] - a[1]) - dy * (p[0] - a[0])) / l
    } else {
        (p[0] - a[0]).hypot(p[1] - a[1])
    }
}

fn segment_distance(a: P, b: P, p: P) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    let t = if l2 > 0.0 { (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (p[0] - a[0] - t * d[0]).hypot(p[1] - a[1] - t * d[1])
}

/// How deep `p` lies inside the polygon: the distance to its outline, positive inside and
/// negative outside (even–odd rule).
pub fn depth_inside(p: P, poly: &[P]) -> f64 {
    let n = poly.len();
    let mut inside = false;
    let mut d = f64::INFINITY;
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
        d = d.min(segment_distance(a, b, p));
    }
    if inside {
        d
    } else {
        -d
    }
}

/// A point strictly inside a simple polygon: in the corner at its lowest-leftmost vertex (a
/// convex corner), the centroid of the corner's triangle when no other vertex lies in it,
/// otherwise halfway to the vertex in it farthest from the corner's chord.
fn interior_point(poly: &[P]) -> Option<P> {
    let n = poly.len();
    if n < 3 {
        return None;
    }
    let k = (0..n).min_by(|&i, &j| poly[i][0].total_cmp(&poly[j][0]).then(poly[i][1].total_cmp(&poly[j][1])))?;
    let (u, v, w) = (poly[(k + n - 1) % n], poly[k], poly[(k + 1) % n]);
    let ccw = line_distance(u, v, w) > 0.0;
    let inside_tri = |p: P| {
        let s = |a: P, b: P| line_distance(a, b, p) * if ccw { 1.0 } else { -1.0 };
        s(u, v) > 0.0 && s(v, w) > 0.0 && s(w, u) > 0.0
    };
    let far = (0..n)
        .filter(|&i| i != k && i != (k + 1) % n && i != (k + n - 1) % n && inside_tri(poly[i]))
        .max_by(|&i, &j| line_distance(w, u, poly[i]).abs().total_cmp(&line_distance(w, u, poly[j]).abs()));
    Some(match far {
        Some(i) => [0.5 * (v[0] + poly[i][0]), 0.5 * (v[1] + poly[i][1])],
        None => [(u[0] + v[0] + w[0]) / 3.0, (u[1] + v[1] + w[1]) / 3.0],
    })
}

/// Parameters `t` in (0, 1) along `a0 → a1` where the outline `other` meets the segment (its
/// sides crossing or touching it, its vertices within `tol` of it).
fn meeting_points(a0: P, a1: P, other: &[P], tol: f64, out: &mut Vec<f64>) {
    let d = [a1[0] - a0[0], a1[1] - a0[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    if l2 <= 0.0 {
        return;
    }
    let lo = [a0[0].min(a1[0]) - tol, a0[1].min(a1[1]) - tol];
    let hi = [a0[0].max(a1[0]) + tol, a0[1].max(a1[1]) + tol];
    let m = other.len();
    let param = |p: P| ((p[0] - a0[0]) * d[0] + (p[1] - a0[1]) * d[1]) / l2;
    for k in 0..m {
        let (b0, b1) = (other[k], other[(k + 1) % m]);
        if b0[0].max(b1[0]) < lo[0] || b0[0].min(b1[0]) > hi[0] || b0[1].max(b1[1]) < lo[1] || b0[1].min(b1[1]) > hi[1] {
            continue;
        }
        if segment_distance(a0, a1, b0) <= tol {
            out.push(param(b0));
        }
        let e = [b1[0] - b0[0], b1[1] - b0[1]];
        let den = d[0] * e[1] - d[1] * e[0];
        if den.abs() > 1e-14 * l2.sqrt() * e[0].hypot(e[1]) {
            let w = [b0[0] - a0[0], b0[1] - a0[1]];
            let t = (w[0] * e[1] - w[1] * e[0]) / den;
            let s = (w[0] * d[1] - w[1] * d[0]) / den;
            if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
                out.push(t);
            }
        }
    }
}

/// Whether two simple polygons (either orientation) overlap by more than `tol` (mm):
/// `Some(depth)` with `depth` the deepest penetration seen at the test points (a lower bound of
/// the penetration depth), `None` when they are apart or only touch.
///
/// They overlap when two sides properly cross (each side's ends more than `tol` on either side
/// of the other's line), or when a point of one outline lies more than `tol` inside the other.
/// The points tested are the midpoints of the pieces into which each side is cut where the
/// other outline meets it (which covers the vertices inside the other polygon and sides that
/// run inside it between two touching points), and one interior point of each polygon (for
/// two polygons with the same outline). Touching (a shared vertex, a vertex on a side, sides
/// along each other) is not an overlap.
pub fn simple_polygons_overlap(a: &[P], b: &[P], tol: f64) -> Option<f64> {
    if a.len() < 3 || b.len() < 3 {
        return None;
    }
    let tol = tol.max(0.0);
    let (ba, bb) = (Convex::Polygon(a.to_vec()).aabb(), Convex::Polygon(b.to_vec()).aabb());
    if ba[0] > bb[1] + tol || bb[0] > ba[1] + tol || ba[2] > bb[3] + tol || bb[2] > ba[3] + tol {
        return None;
    }
    let mut deepest: Option<f64> = None;
    let mut seen = |d: f64| {
        if d > tol {
            deepest = Some(deepest.map_or(d, |x: f64| x.max(d)));
        }
    };
    // proper crossings
    let (n, m) = (a.len(), b.len());
    for i in 0..n {
        let (a0, a1) = (a[i], a[(i + 1) % n]);
        for k in 0..m {
            let (b0, b1) = (b[k], b[(k + 1) % m]);
            let (s0, s1) = (line_distance(b0, b1, a0), line_distance(b0, b1, a1));
            let (t0, t1) = (line_distance(a0, a1, b0), line_distance(a0, a1, b1));
            if s0.abs() > tol && s1.abs() > tol && t0.abs() > tol && t1.abs() > tol && s0 * s1 < 0.0 && t0 * t1 < 0.0 {
                seen(s0.abs().min(s1.abs()).min(t0.abs()).min(t1.abs()));
            }
        }
    }
    // points of each outline inside the other
    let mut ts = Vec::new();
    for (p, q) in [(a, b), (b, a)] {
        let n = p.len();
        for i in 0..n {
            let (p0, p1) = (p[i], p[(i + 1) % n]);
            ts.clear();
            ts.extend([0.0, 1.0]);
            meeting_points(p0, p1, q, tol, &mut ts);
            ts.retain(|t| t.is_finite());
            ts.iter_mut().for_each(|t| *t = t.clamp(0.0, 1.0));
            ts.sort_by(f64::total_cmp);
            for w in ts.windows(2) {
                if w[1] - w[0] <= 0.0 {
                    continue;
                }
                let t = 0.5 * (w[0] + w[1]);
                let x = [p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1])];
                seen(depth_inside(x, q));
            }
            seen(depth_inside(p0, q));
        }
        if let Some(x) = interior_point(p) {
            seen(depth_inside(x, q).min(depth_inside(x, p)));
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(c: [f64; 2], h: f64) -> Convex {
        Convex::Polygon(vec![[c[0] - h, c[1] - h], [c[0] + h, c[1] - h], [c[0] + h, c[1] + h], [c[0] - h, c[1] + h]])
    }

    #[test]
    fn discs_are_exact() {
        let a = Convex::Disc { center: [0.0, 0.0], radius: 1.0 };
        let b = Convex::Disc { center: [3.0, 4.0], radius: 2.0 };
        assert_eq!(signed_distance(&a, &b), Some(2.0));
        let c = Convex::Disc { center: [2.0, 0.0], radius: 1.5 };
        assert!((signed_distance(&a, &c).unwrap() + 0.5).abs() < 1e-15);
    }

    #[test]
    fn polygons_and_ellipses() {
        let a = square([0.0, 0.0], 1.0);
        // apart by 0.5 along x
        let d = signed_distance(&a, &square([2.5, 0.3], 1.0)).unwrap();
        assert!((d - 0.5).abs() < 1e-9, "{d}");
        // overlapping by 0.25 along x
        let d = signed_distance(&a, &square([1.75, 0.1], 1.0)).unwrap();
        assert!((d + 0.25).abs() < 1e-9, "{d}");
        // an ellipse with semi-axes 2 x 0.5 rotated by 90 degrees reaches y = 2
        let e = Convex::Ellipse { center: [0.0, 3.0], semi_axes: [2.0, 0.5], angle_deg: 90.0 };
        let d = signed_distance(&a, &e).unwrap();
        assert!((d - 0.0).abs() < 1e-6, "{d}");
        let e2 = Convex::Ellipse { center: [0.0, 2.9], semi_axes: [2.0, 0.5], angle_deg: 90.0 };
        assert!(signed_distance(&a, &e2).unwrap() < -0.09);
        let disc = Convex::Disc { center: [0.0, 5.5], radius: 0.5 };
        let d = signed_distance(&e, &disc).unwrap();
        assert!((d - 0.0).abs() < 1e-6, "{d}");
    }

    #[test]
    fn simple_polygons() {
        let l = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [1.0, 1.0], [1.0, 4.0], [0.0, 4.0]];
        let shift = |p: &[[f64; 2]], d: [f64; 2]| p.iter().map(|v| [v[0] + d[0], v[1] + d[1]]).collect::<Vec<_>>();
        // in the notch of the L: apart
        let sq = vec![[1.5, 1.5], [3.0, 1.5], [3.0, 3.0], [1.5, 3.0]];
        assert_eq!(simple_polygons_overlap(&l, &sq, 1e-9), None);
        // touching along the inner sides of the notch
        let sq2 = vec![[1.0, 1.0], [3.0, 1.0], [3.0, 3.0], [1.0, 3.0]];
        assert_eq!(simple_polygons_overlap(&l, &sq2, 1e-9), None);
        // sides crossing
        let sq3 = shift(&sq2, [-0.5, 0.0]);
        assert!(simple_polygons_overlap(&l, &sq3, 1e-9).unwrap() > 0.4);
        // the same outline, and one inside the other without crossings
        assert!(simple_polygons_overlap(&l, &l, 1e-9).is_some());
        let small = vec![[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]];
        assert!(simple_polygons_overlap(&l, &small, 1e-9).is_some());
        assert!(simple_polygons_overlap(&small, &l, 1e-9).is_some());
        // half-overlapping squares whose vertices all lie on the other's sides
        let a = vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        let b = vec![[1.0, 0.0], [3.0, 0.0], [3.0, 2.0], [1.0, 2.0]];
        assert!(simple_polygons_overlap(&a, &b, 1e-9).is_some());
        // a disc in the notch and one in the corner of the L
        let p = |c: Convex| Some(Particle::Convex(c));
        let shapes = vec![
            Some(Particle::Simple(l.clone())),
            p(Convex::Disc { center: [2.5, 2.5], radius: 1.0 }),
            p(Convex::Disc { center: [0.5, 0.5], radius: 0.3 }),
            Some(Particle::Simple(shift(&l, [4.0, 0.0]))), // touches the first along x = 4
        ];
        let o = overlapping_particles(&shapes, 1e-9);
        assert_eq!(o.len(), 1);
        assert_eq!((o[0].first, o[0].second), (0, 2));
    }

    #[test]
    fn pairs_are_found_and_touching_is_allowed() {
        let shapes = vec![
            Some(square([0.0, 0.0], 1.0)),
            Some(square([2.0, 0.0], 1.0)), // touches 0
            None,
            Some(Convex::Disc { center: [3.5, 0.0], radius: 1.0 }), // overlaps 1 by 0.5
            Some(Convex::Disc { center: [10.0, 0.0], radius: 1.0 }),
        ];
        let o = overlapping_pairs(&shapes, 1e-9);
        assert_eq!(o.len(), 1);
        assert_eq!((o[0].first, o[0].second), (1, 3));
        assert!((o[0].depth - 0.5).abs() < 1e-6);
    }
}
