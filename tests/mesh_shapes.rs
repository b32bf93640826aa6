//! Integration tests of the all-quadrilateral mesh generators (`mesh::shapes`) and the quality
//! measures (`mesh::quality`).
//!
//! Tolerances: areas of straight-sided domains and polygonal areas are compared to 1e-12
//! relative, because the generators place boundary nodes on the straight sides (curves) up to
//! floating-point rounding only, and a sum of a few thousand shoelace terms loses at most a few
//! hundred ulps (~1e-13 relative). Node-on-curve checks use 1e-12 relative for the same reason
//! (one `cos`/`sin`/multiply-add per coordinate).

use mpfem::mesh::quality::{self, QualityReport};
use mpfem::mesh::shapes::{self, MeshError};
use mpfem::mesh::{polygon_area, Mesh};
use std::collections::{HashMap, HashSet};
use std::f64::consts::PI;

fn rel_close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs())
}

/// Structural checks every generated mesh must pass:
/// - every element has positive area (counter-clockwise) and positive scaled Jacobian;
/// - every node is used and no two nodes coincide;
/// - conformity: every undirected edge is used by one or two elements, an edge used twice is
///   traversed in opposite directions (consistent orientation), and `boundary` is exactly the
///   set of directed edges used once (so it is oriented with the body on its left);
/// - the boundary is closed: each boundary node starts exactly one and ends exactly one edge;
/// - `edge_sets["boundary"] == boundary`, every edge set is a duplicate-free subset of it;
/// - the sum of the shoelace terms over `boundary` equals the mesh area (1e-12 relative).
fn check_mesh(m: &Mesh) {
    assert!(m.n_elements() > 0);
    for e in 0..m.n_elements() {
        let a = m.element_area(e, &m.nodes);
        assert!(a > 0.0, "element {e} has area {a}");
    }
    let q = quality::quality(m, &m.nodes);
    assert_eq!(q.n_inverted, 0, "inverted elements: {q:?}");

    let mut used = vec![false; m.n_nodes()];
    for el in &m.elements {
        for &n in el {
            used[n] = true;
        }
    }
    assert!(used.iter().all(|&u| u), "unused nodes");
    let size = bbox_size(&m.nodes);
    let mut order: Vec<usize> = (0..m.n_nodes()).collect();
    order.sort_by(|&a, &b| m.nodes[a][0].total_cmp(&m.nodes[b][0]));
    for (k, &a) in order.iter().enumerate() {
        for &b in &order[k + 1..] {
            if m.nodes[b][0] - m.nodes[a][0] > 1e-9 * size {
                break;
            }
            let d = (m.nodes[a][0] - m.nodes[b][0]).hypot(m.nodes[a][1] - m.nodes[b][1]);
            assert!(d > 1e-9 * size, "nodes {a} and {b} coincide");
        }
    }

    let mut directed: HashMap<[usize; 2], usize> = HashMap::new();
    for el in &m.elements {
        for k in 0..4 {
            *directed.entry([el[k], el[(k + 1) % 4]]).or_insert(0) += 1;
        }
    }
    let mut once: HashSet<[usize; 2]> = HashSet::new();
    for (&[a, b], &c) in &directed {
        assert_eq!(
            c, 1,
            "directed edge {a}->{b} used {c} times (inconsistent orientation)"
        );
        if !directed.contains_key(&[b, a]) {
            once.insert([a, b]);
        }
    }
    let bset: HashSet<[usize; 2]> = m.boundary.iter().copied().collect();
    assert_eq!(bset.len(), m.boundary.len(), "duplicate boundary edges");
    assert_eq!(bset, once, "boundary != edges used by exactly one element");
    let mut starts: HashMap<usize, usize> = HashMap::new();
    let mut ends: HashMap<usize, usize> = HashMap::new();
    for &[a, b] in &m.boundary {
        *starts.entry(a).or_insert(0) += 1;
        *ends.entry(b).or_insert(0) += 1;
    }
    assert_eq!(starts.len(), m.boundary.len());
    for (n, c) in &starts {
        assert_eq!(
            (*c, ends.get(n).copied()),
            (1, Some(1)),
            "boundary not closed at {n}"
        );
    }

    assert_eq!(m.edge_sets.get("boundary"), Some(&m.boundary));
    for (name, set) in &m.edge_sets {
        let s: HashSet<[usize; 2]> = set.iter().copied().collect();
        assert_eq!(s.len(), set.len(), "duplicates in edge set {name}");
        assert!(s.is_subset(&bset), "edge set {name} not on the boundary");
    }

    let area = m.area(&m.nodes);
    let shoelace: f64 = m
        .boundary
        .iter()
        .map(|&[a, b]| {
            let (p, q) = (m.nodes[a], m.nodes[b]);
            0.5 * (p[0] * q[1] - q[0] * p[1])
        })
        .sum();
    assert!(
        rel_close(area, shoelace, 1e-12),
        "area {area} != boundary shoelace {shoelace}"
    );
}

fn bbox_size(pts: &[[f64; 2]]) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in pts {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (hi[0] - lo[0]).max(hi[1] - lo[1])
}

fn set_nodes(m: &Mesh, name: &str) -> Vec<[f64; 2]> {
    m.node_set(name)
        .unwrap_or_else(|| panic!("no edge set {name}"))
        .into_iter()
        .map(|n| m.nodes[n])
        .collect()
}

fn boundary_nodes(m: &Mesh) -> Vec<[f64; 2]> {
    set_nodes(m, "boundary")
}

fn hexagon(r: f64) -> Vec<[f64; 2]> {
    (0..6)
        .map(|k| {
            let t = k as f64 * PI / 3.0;
            [1.0 + r * t.cos(), -2.0 + r * t.sin()]
        })
        .collect()
}

const TRIANGLE: [[f64; 2]; 3] = [[0.0, 0.0], [3.0, 0.0], [1.0, 2.0]];
const PENTAGON: [[f64; 2]; 5] = [[0.0, 0.0], [4.0, -0.5], [5.0, 2.0], [2.5, 4.0], [-0.5, 2.5]];

#[test]
fn divisions_for_rounds_up_and_ignores_rounding_noise() {
    assert_eq!(shapes::divisions_for(1.0, 0.3), 4);
    assert_eq!(shapes::divisions_for(3.0, 0.3), 10); // 3.0/0.3 = 10.000000000000002
    assert_eq!(shapes::divisions_for(0.1, 1.0), 1);
    assert_eq!(shapes::divisions_for(0.0, 1.0), 1);
    assert_eq!(shapes::divisions_for(1.0, 0.0), 1);
}

#[test]
fn rectangle_area_sets_and_numbering() {
    let (w, hgt, nx, ny) = (3.0, 2.0, 6, 4);
    let m = shapes::rectangle([1.0, -1.0], w, hgt, nx, ny);
    check_mesh(&m);
    assert_eq!(m.n_elements(), nx * ny);
    assert_eq!(m.n_nodes(), (nx + 1) * (ny + 1));
    // Exact up to rounding of the shoelace sums: 1e-12 relative.
    assert!(rel_close(m.area(&m.nodes), w * hgt, 1e-12));
    for (name, count) in [("left", ny), ("right", ny), ("bottom", nx), ("top", nx)] {
        assert_eq!(m.edge_sets[name].len(), count, "{name}");
    }
    // Sides built from the corner coordinates: constant coordinates are exact.
    assert!(set_nodes(&m, "left").iter().all(|p| p[0] == 1.0));
    assert!(set_nodes(&m, "right").iter().all(|p| p[0] == 4.0));
    assert!(set_nodes(&m, "bottom").iter().all(|p| p[1] == -1.0));
    assert!(set_nodes(&m, "top").iter().all(|p| p[1] == 1.0));
    let q = quality::quality(&m, &m.nodes);
    assert!((q.min_scaled_jacobian - 1.0).abs() < 1e-12);
}

#[test]
fn cook_membrane_area_and_sets() {
    let corners = [[0.0, 0.0], [48.0, 44.0], [48.0, 60.0], [0.0, 44.0]];
    let exact = polygon_area(corners);
    assert!((exact - 1440.0).abs() < 1e-12); // 48 × (44 + 16) / 2
    for (nx, ny) in [(1, 1), (4, 4), (16, 16), (32, 8)] {
        let m = shapes::cook_membrane(nx, ny);
        check_mesh(&m);
        assert_eq!(m.n_elements(), nx * ny);
        // Straight sides, nodes on them up to rounding: 1e-12 relative.
        assert!(rel_close(m.area(&m.nodes), exact, 1e-12), "{nx}x{ny}");
        assert!(set_nodes(&m, "left").iter().all(|p| p[0] == 0.0));
        assert!(set_nodes(&m, "right").iter().all(|p| p[0] == 48.0));
        assert_eq!(m.edge_sets["left"].len(), ny);
        assert_eq!(m.edge_sets["right"].len(), ny);
        assert_eq!(m.edge_sets["bottom"].len(), nx);
        assert_eq!(m.edge_sets["top"].len(), nx);
    }
}

#[test]
fn polygon_meshes_have_exactly_the_polygon_area() {
    let polys: Vec<Vec<[f64; 2]>> = vec![hexagon(2.0), TRIANGLE.to_vec(), PENTAGON.to_vec()];
    for poly in &polys {
        let exact = polygon_area(poly.iter().copied());
        for h in [2.0, 0.5, 0.2, 0.1] {
            let m = shapes::convex_polygon(poly, h).unwrap();
            check_mesh(&m);
            // Boundary nodes lie on the straight sides up to rounding: 1e-12 relative.
            assert!(
                rel_close(m.area(&m.nodes), exact, 1e-12),
                "area {} vs {exact} (h = {h})",
                m.area(&m.nodes)
            );
            // Clockwise input gives the same area (reversed internally).
            let rev: Vec<[f64; 2]> = poly.iter().rev().copied().collect();
            let mr = shapes::convex_polygon(&rev, h).unwrap();
            check_mesh(&mr);
            assert!(rel_close(mr.area(&mr.nodes), exact, 1e-12));
        }
    }
}

/// `side{k}` holds the edges on the segment from input vertex k to k + 1: each edge's nodes lie
/// on that segment (distance 1e-12 × size, rounding) and the edges add up to its length.
fn check_polygon_sides(poly: &[[f64; 2]], m: &Mesh) {
    let n = poly.len();
    let size = bbox_size(poly);
    let mut total = 0;
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = d[0].hypot(d[1]);
        let set = &m.edge_sets[&format!("side{k}")];
        total += set.len();
        let mut sum = 0.0;
        for &[p, q] in set {
            for node in [p, q] {
                let x = m.nodes[node];
                let r = [x[0] - a[0], x[1] - a[1]];
                let dist_line = (d[0] * r[1] - d[1] * r[0]).abs() / len;
                let t = (d[0] * r[0] + d[1] * r[1]) / (len * len);
                assert!(dist_line <= 1e-12 * size, "node off side {k}");
                assert!((-1e-12..=1.0 + 1e-12).contains(&t), "node beyond side {k}");
            }
            sum += (m.nodes[q][0] - m.nodes[p][0]).hypot(m.nodes[q][1] - m.nodes[p][1]);
        }
        assert!(rel_close(sum, len, 1e-12), "side {k}: {sum} vs {len}");
    }
    assert_eq!(total, m.boundary.len(), "sides cover the boundary");
}

#[test]
fn polygon_side_sets_follow_input_numbering() {
    for poly in [hexagon(1.0), TRIANGLE.to_vec(), PENTAGON.to_vec()] {
        let m = shapes::convex_polygon(&poly, 0.3).unwrap();
        check_polygon_sides(&poly, &m);
        // Clockwise input: side k is still the segment from input vertex k to k + 1.
        let rev: Vec<[f64; 2]> = poly.iter().rev().copied().collect();
        let mr = shapes::convex_polygon(&rev, 0.3).unwrap();
        check_polygon_sides(&rev, &mr);
    }
    // A nearly flat (179°) corner is accepted and stays valid.
    let almost = [
        [0.0, 0.0],
        [1.0, -0.0087],
        [2.0, 0.0],
        [2.0, 2.0],
        [0.0, 2.0],
    ];
    let m = shapes::convex_polygon(&almost, 0.25).unwrap();
    check_mesh(&m);
    check_polygon_sides(&almost, &m);
}

#[test]
fn disc_area_matches_inscribed_polygon() {
    let (c, r) = ([3.0, -1.0], 2.5);
    for h in [5.0, 1.0, 0.3, 0.1] {
        let m = shapes::disc(c, r, h);
        check_mesh(&m);
        let nb = m.boundary.len();
        assert!(nb >= 8, "at least 8 boundary segments, got {nb}");
        assert_eq!(m.edge_sets["outer"], m.boundary);
        // Boundary nodes on the circle: 1e-12 relative (one cos/sin each).
        for p in boundary_nodes(&m) {
            let d = (p[0] - c[0]).hypot(p[1] - c[1]);
            assert!((d - r).abs() <= 1e-12 * r, "node at radius {d}");
        }
        // The mesh is exactly the boundary polygon (1e-12, rounding only) ...
        let area = m.area(&m.nodes);
        let chain: Vec<[f64; 2]> = m.boundary.iter().map(|e| m.nodes[e[0]]).collect();
        assert!(rel_close(area, polygon_area(chain), 1e-12));
        // ... which is the inscribed polygon with nb equal chords:
        // π r² − A = r²(π − (nb/2) sin(2π/nb)), to 1e-12 of π r².
        let inscribed = 0.5 * nb as f64 * r * r * (2.0 * PI / nb as f64).sin();
        assert!(rel_close(area, inscribed, 1e-12), "{area} vs {inscribed}");
        assert!(area < PI * r * r);
        // Chords no longer than h (equal arcs of length ≤ h).
        for &[a, b] in &m.boundary {
            let (p, q) = (m.nodes[a], m.nodes[b]);
            assert!((p[0] - q[0]).hypot(p[1] - q[1]) <= h * (1.0 + 1e-12));
        }
    }
}

/// Coordinates of `p` in the ellipse frame (un-rotated, centred).
fn ellipse_frame(p: [f64; 2], c: [f64; 2], angle_deg: f64) -> [f64; 2] {
    let (s, co) = angle_deg.to_radians().sin_cos();
    let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
    [co * dx + s * dy, -s * dx + co * dy]
}

#[test]
fn ellipse_boundary_on_curve_and_area() {
    let c = [-2.0, 5.0];
    for (ab, angle) in [([2.0, 1.0], 30.0), ([1.0, 3.0], -75.0), ([1.5, 1.5], 10.0)] {
        let [a, b] = ab;
        for h in [0.5, 0.2, 0.1] {
            let m = shapes::ellipse(c, ab, angle, h);
            check_mesh(&m);
            assert_eq!(m.edge_sets["outer"], m.boundary);
            // On the ellipse: (x/a)² + (y/b)² = 1 to 1e-12 (rounding of cos/sin and the
            // rotation, both ~1e-16 relative).
            let mut params = Vec::new();
            for &[n0, _] in &m.boundary {
                let q = ellipse_frame(m.nodes[n0], c, angle);
                let f = (q[0] / a).powi(2) + (q[1] / b).powi(2);
                assert!((f - 1.0).abs() < 1e-12, "node off the ellipse: {f}");
                params.push((q[1] / b).atan2(q[0] / a));
            }
            // The boundary polygon with nodes at parameters t_i has area
            // (ab/2) Σ sin(Δt_i) (affine image of a polygon inscribed in the unit circle), and
            // π a b − A = (ab/2) Σ (Δt_i − sin Δt_i) ≥ 0. Compared to 1e-12 relative.
            let nb = params.len();
            let mut poly_area = 0.0;
            let mut dt_sum = 0.0;
            for i in 0..nb {
                let mut dt = params[(i + 1) % nb] - params[i];
                if dt < 0.0 {
                    dt += 2.0 * PI;
                }
                dt_sum += dt;
                poly_area += 0.5 * a * b * dt.sin();
            }
            assert!((dt_sum - 2.0 * PI).abs() < 1e-9, "boundary winds once");
            let area = m.area(&m.nodes);
            assert!(rel_close(area, poly_area, 1e-12), "{area} vs {poly_area}");
            assert!(area < PI * a * b);
            // Inscribed-polygon bound with the largest parameter step: deficit ≤
            // π a b (1 − sin(Δt_max)/Δt_max).
            let dt_max = (0..nb)
                .map(|i| (params[(i + 1) % nb] - params[i]).rem_euclid(2.0 * PI))
                .fold(0.0, f64::max);
            let bound = PI * a * b * (1.0 - dt_max.sin() / dt_max);
            assert!(PI * a * b - area <= bound * (1.0 + 1e-9));
        }
    }
}

#[test]
fn annulus_sector_geometry_and_sets() {
    let (c, r_in, r_out) = ([1.0, 2.0], 10.0, 20.0);
    for (t0, t1, nr, nc) in [(0.0, 90.0, 4, 8), (30.0, 200.0, 3, 17), (0.0, 360.0, 2, 24)] {
        let m = shapes::annulus_sector(c, r_in, r_out, t0, t1, nr, nc);
        check_mesh(&m);
        assert_eq!(m.n_elements(), nr * nc);
        // Mesh area = inner polygon removed from outer polygon, nc chords of angle Δθ each:
        // (nc/2) sin(Δθ) (r_out² − r_in²); rounding only, 1e-12.
        let dth = (t1 - t0).to_radians() / nc as f64;
        let poly = 0.5 * nc as f64 * dth.sin() * (r_out * r_out - r_in * r_in);
        assert!(rel_close(m.area(&m.nodes), poly, 1e-12));
        let radius = |p: [f64; 2]| (p[0] - c[0]).hypot(p[1] - c[1]);
        for p in set_nodes(&m, "inner") {
            assert!((radius(p) - r_in).abs() <= 1e-12 * r_in);
        }
        for p in set_nodes(&m, "outer") {
            assert!((radius(p) - r_out).abs() <= 1e-12 * r_out);
        }
        assert_eq!(m.edge_sets["inner"].len(), nc);
        assert_eq!(m.edge_sets["outer"].len(), nc);
        let full = t1 - t0 == 360.0;
        for (name, t) in [("start", t0), ("end", t1)] {
            let set = &m.edge_sets[name];
            assert_eq!(set.len(), if full { 0 } else { nr }, "{name}");
            let dir = [t.to_radians().cos(), t.to_radians().sin()];
            for p in set_nodes(&m, name) {
                let r = [p[0] - c[0], p[1] - c[1]];
                assert!((dir[0] * r[1] - dir[1] * r[0]).abs() <= 1e-12 * r_out);
            }
        }
        // The inner arc is traversed clockwise (body on the left): negative shoelace sum.
        let s: f64 = m.edge_sets["inner"]
            .iter()
            .map(|&[a, b]| {
                let (p, q) = (m.nodes[a], m.nodes[b]);
                let (p, q) = ([p[0] - c[0], p[1] - c[1]], [q[0] - c[0], q[1] - c[1]]);
                p[0] * q[1] - q[0] * p[1]
            })
            .sum();
        assert!(s < 0.0);
    }
}

#[test]
fn quality_is_good_for_discs_ellipses_and_polygons() {
    // Requirement: min scaled Jacobian > 0.3 (the O-grid gives ≈ 0.82–0.85 for discs; ellipses
    // up to 3:1 and the test polygons stay above 0.6).
    let mut cases: Vec<(String, Mesh)> = Vec::new();
    for h in [1.0, 0.3, 0.1, 0.04] {
        cases.push((format!("disc h={h}"), shapes::disc([0.0, 0.0], 1.0, h)));
        cases.push((
            format!("ellipse 2:1 h={h}"),
            shapes::ellipse([0.0, 0.0], [2.0, 1.0], 20.0, h),
        ));
        cases.push((
            format!("ellipse 1:3 h={h}"),
            shapes::ellipse([0.0, 0.0], [1.0, 3.0], 0.0, h),
        ));
        cases.push((
            format!("hexagon h={h}"),
            shapes::convex_polygon(&hexagon(1.0), h).unwrap(),
        ));
        cases.push((
            format!("triangle h={h}"),
            shapes::convex_polygon(&TRIANGLE, h).unwrap(),
        ));
        cases.push((
            format!("pentagon h={h}"),
            shapes::convex_polygon(&PENTAGON, h).unwrap(),
        ));
    }
    for (name, m) in &cases {
        let q: QualityReport = quality::quality(m, &m.nodes);
        assert_eq!(q.n_elements, m.n_elements());
        assert!(q.min_scaled_jacobian > 0.3, "{name}: {q:?}");
        assert!(
            q.min_angle_deg > 17.0 && q.max_angle_deg < 163.0,
            "{name}: {q:?}"
        );
        let per_element = quality::element_quality(m, &m.nodes);
        let min = per_element.iter().cloned().fold(f64::INFINITY, f64::min);
        assert_eq!(min, q.min_scaled_jacobian);
    }
}

#[test]
fn refinement_scales_element_count_like_inverse_h_squared() {
    // Halving h should multiply the element count by about 4; allow [3, 5] because division
    // counts are rounded up per block.
    let count = |h: f64| -> [usize; 4] {
        [
            shapes::disc([0.0, 0.0], 1.0, h).n_elements(),
            shapes::ellipse([0.0, 0.0], [2.0, 1.0], 45.0, h).n_elements(),
            shapes::convex_polygon(&PENTAGON, h).unwrap().n_elements(),
            shapes::convex_polygon(&TRIANGLE, h).unwrap().n_elements(),
        ]
    };
    for h in [0.2, 0.1] {
        let (c1, c2) = (count(h), count(h / 2.0));
        for k in 0..4 {
            let ratio = c2[k] as f64 / c1[k] as f64;
            assert!(
                (3.0..=5.0).contains(&ratio),
                "case {k}, h {h}: ratio {ratio}"
            );
        }
    }
    // Element size about h: element count within a factor 2.5 of area / h².
    let h = 0.05;
    let n = shapes::disc([0.0, 0.0], 1.0, h).n_elements() as f64;
    let ideal = PI / (h * h);
    assert!(n > ideal / 2.5 && n < 2.5 * ideal, "{n} vs {ideal}");
    let n = shapes::convex_polygon(&PENTAGON, h).unwrap().n_elements() as f64;
    let ideal = polygon_area(PENTAGON) / (h * h);
    assert!(n > ideal / 2.5 && n < 2.5 * ideal, "{n} vs {ideal}");
}

#[test]
fn convex_polygon_rejects_bad_input() {
    let e = |v: &[[f64; 2]], h: f64| shapes::convex_polygon(v, h).unwrap_err();
    assert_eq!(
        e(&[[0.0, 0.0], [1.0, 0.0]], 0.1),
        MeshError::TooFewVertices(2)
    );
    // Non-convex "arrow": reflex corner at vertex 2.
    let arrow = [[0.0, 0.0], [2.0, 0.0], [1.0, 0.5], [2.0, 2.0], [0.0, 2.0]];
    assert_eq!(e(&arrow, 0.1), MeshError::NotConvex(2));
    // Self-intersecting pentagram: all turns to the left but twice around.
    let star: Vec<[f64; 2]> = (0..5)
        .map(|k| {
            let t = (2 * k) as f64 * 2.0 * PI / 5.0;
            [t.cos(), t.sin()]
        })
        .collect();
    assert!(matches!(e(&star, 0.1), MeshError::NotConvex(_)));
    // A 180° corner (collinear consecutive vertices) at vertex 1.
    let square5 = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
    assert_eq!(e(&square5, 0.1), MeshError::NotConvex(1));
    // Degenerate: collinear vertices, repeated vertex.
    assert_eq!(
        e(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]], 0.1),
        MeshError::ZeroArea
    );
    assert_eq!(
        e(&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]], 0.1),
        MeshError::DegenerateSide(1)
    );
    assert_eq!(
        e(&[[0.0, 0.0], [1.0, 0.0], [f64::NAN, 1.0]], 0.1),
        MeshError::NonFiniteVertex(2)
    );
    // Bad element size.
    assert_eq!(e(&TRIANGLE, 0.0), MeshError::InvalidSize(0.0));
    assert!(matches!(e(&TRIANGLE, -1.0), MeshError::InvalidSize(_)));
    // Messages are readable.
    assert!(MeshError::NotConvex(2)
        .to_string()
        .contains("not strictly convex"));
    assert!(MeshError::ZeroArea.to_string().contains("zero area"));
}

#[test]
fn quality_measures_on_simple_elements() {
    let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    assert!((quality::scaled_jacobian(sq) - 1.0).abs() < 1e-15);
    // Parallelogram with 45° corners: sin 45°.
    let par = [[0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [1.0, 1.0]];
    assert!((quality::scaled_jacobian(par) - 0.5f64.sqrt()).abs() < 1e-15);
    // Mirrored mesh: every element inverted.
    let m = shapes::rectangle([0.0, 0.0], 2.0, 1.0, 4, 1);
    let mirrored: Vec<[f64; 2]> = m.nodes.iter().map(|p| [-p[0], p[1]]).collect();
    let q = quality::quality(&m, &mirrored);
    assert_eq!(q.n_inverted, 4);
    assert!(q.min_scaled_jacobian < 0.0);
    let q = quality::quality(&m, &m.nodes);
    assert_eq!(q.n_inverted, 0);
    assert!((q.max_aspect_ratio - 2.0).abs() < 1e-12); // 0.5 × 1 elements
    assert!((q.min_angle_deg - 90.0).abs() < 1e-9 && (q.max_angle_deg - 90.0).abs() < 1e-9);
    // Serializes (used in run reports).
    let json = serde_json::to_string(&q).unwrap();
    assert!(json.contains("min_scaled_jacobian"));
}
