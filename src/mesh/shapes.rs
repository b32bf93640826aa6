//! All-quadrilateral mesh generators.
//!
//! Every generator returns a conforming mesh of four-node quadrilaterals with counter-clockwise
//! node order and positive area, the full boundary in [`Mesh::boundary`] (body on the left of
//! each edge, outer boundary counter-clockwise, edges chained head to tail) and named edge sets
//! in [`Mesh::edge_sets`] (same orientation, always including `"boundary"`).
//!
//! All meshes are built from *patches*: logically rectangular blocks whose four sides are given
//! as point lists; interior nodes come from discrete transfinite (Coons) interpolation of the
//! sides, so nodes given on curved sides (circle, ellipse) stay exactly there. Shared patch
//! sides are generated once and handed to both patches, and nodes are merged (within 1e-9 of the
//! body size) when patches are assembled, so the meshes conform.
//!
//! Element sizes: the generators pick division counts with [`divisions_for`] so that element
//! edges are close to the target size `h` (mm); O-grid cores (discs, ellipses) come out somewhat
//! finer than `h` because the core shares its division count with a longer arc.

use super::Mesh;
use std::collections::{BTreeMap, HashMap};
use std::f64::consts::{FRAC_PI_2, PI};

/// Invalid input to a mesh generator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("a polygon needs at least 3 vertices, got {0}")]
    TooFewVertices(usize),
    #[error("polygon vertex {0} has a non-finite coordinate")]
    NonFiniteVertex(usize),
    #[error("polygon side {0} has zero length (vertices {0} and the next one coincide)")]
    DegenerateSide(usize),
    #[error("polygon has zero area (all vertices collinear)")]
    ZeroArea,
    #[error("polygon is not strictly convex (reflex or 180° corner at vertex {0}, or self-intersecting)")]
    NotConvex(usize),
    #[error("target element size h must be positive and finite, got {0}")]
    InvalidSize(f64),
    #[error("polygon is not simple: side {0} (from vertex {0}) and side {1} (from vertex {1}) intersect or touch")]
    SelfIntersecting(usize, usize),
    #[error("triangulation failed: {0}")]
    Triangulation(String),
}

/// Number of divisions of a length `length` for a target element size `h`:
/// `max(1, ceil(length / h))`, where a ratio within 1e-9 (relative) above an integer counts as
/// that integer, so that e.g. `divisions_for(3.0, 0.3) == 10` despite rounding.
/// Non-finite or non-positive input gives 1.
pub fn divisions_for(length: f64, h: f64) -> usize {
    let r = length / h;
    if !(r.is_finite() && r > 0.0) {
        return 1;
    }
    let n = (r * (1.0 - 1e-9)).ceil();
    if n < 1.0 {
        1
    } else {
        n as usize
    }
}

// ---------------------------------------------------------------------------------------------
// Small vector helpers

type P = [f64; 2];

fn add(a: P, b: P) -> P {
    [a[0] + b[0], a[1] + b[1]]
}

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}

fn scale(s: f64, a: P) -> P {
    [s * a[0], s * a[1]]
}

fn cross(a: P, b: P) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dist(a: P, b: P) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// `n + 1` equally spaced points on the segment `a → b`, endpoints exactly `a` and `b`.
fn line(a: P, b: P, n: usize) -> Vec<P> {
    let d = sub(b, a);
    let mut v: Vec<P> = (0..=n)
        .map(|k| add(a, scale(k as f64 / n as f64, d)))
        .collect();
    v[0] = a;
    v[n] = b;
    v
}

// ---------------------------------------------------------------------------------------------
// Patch assembly

/// The four sides of a logically rectangular patch with corners `c00, c10, c11, c01`
/// (counter-clockwise): `bottom` runs `c00 → c10`, `right` `c10 → c11`, `top` `c01 → c11`,
/// `left` `c00 → c01`. Opposite sides have equal point counts.
struct Sides {
    bottom: Vec<P>,
    right: Vec<P>,
    top: Vec<P>,
    left: Vec<P>,
}

impl Sides {
    /// Node grid `g[j][i]` (`i` along bottom/top, `j` along left/right): side points on the
    /// sides, discrete transfinite interpolation inside.
    fn grid(&self) -> Vec<Vec<P>> {
        let nu = self.bottom.len() - 1;
        let nv = self.left.len() - 1;
        assert!(
            nu >= 1 && nv >= 1,
            "patch needs at least one division per direction"
        );
        assert_eq!(
            self.top.len(),
            nu + 1,
            "patch: top and bottom differ in point count"
        );
        assert_eq!(
            self.right.len(),
            nv + 1,
            "patch: left and right differ in point count"
        );
        let (c00, c10, c01, c11) = (self.bottom[0], self.bottom[nu], self.top[0], self.top[nu]);
        let mut g = vec![vec![[0.0; 2]; nu + 1]; nv + 1];
        for (j, row) in g.iter_mut().enumerate() {
            for (i, p) in row.iter_mut().enumerate() {
                *p = if j == 0 {
                    self.bottom[i]
                } else if j == nv {
                    self.top[i]
                } else if i == 0 {
                    self.left[j]
                } else if i == nu {
                    self.right[j]
                } else {
                    let u = i as f64 / nu as f64;
                    let v = j as f64 / nv as f64;
                    let mut q = [0.0; 2];
                    for d in 0..2 {
                        q[d] = (1.0 - v) * self.bottom[i][d]
                            + v * self.top[i][d]
                            + (1.0 - u) * self.left[j][d]
                            + u * self.right[j][d]
                            - ((1.0 - u) * (1.0 - v) * c00[d]
                                + u * (1.0 - v) * c10[d]
                                + (1.0 - u) * v * c01[d]
                                + u * v * c11[d]);
                    }
                    q
                };
            }
        }
        g
    }
}

/// Collects patches into one mesh, merging coincident nodes.
struct Builder {
    nodes: Vec<P>,
    elements: Vec<[usize; 4]>,
    tagged: Vec<(String, [usize; 2])>,
    cells: HashMap<(i64, i64), Vec<usize>>,
    tol: f64,
}

impl Builder {
    /// `tol`: nodes closer than this (in max-norm) are merged.
    fn new(tol: f64) -> Self {
        Builder {
            nodes: Vec::new(),
            elements: Vec::new(),
            tagged: Vec::new(),
            cells: HashMap::new(),
            tol,
        }
    }

    fn cell(&self, p: P) -> (i64, i64) {
        (
            (p[0] / self.tol).floor() as i64,
            (p[1] / self.tol).floor() as i64,
        )
    }

    fn node(&mut self, p: P) -> usize {
        let (cx, cy) = self.cell(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(list) = self.cells.get(&(cx + dx, cy + dy)) {
                    for &n in list {
                        let q = self.nodes[n];
                        if (q[0] - p[0]).abs() <= self.tol && (q[1] - p[1]).abs() <= self.tol {
                            return n;
                        }
                    }
                }
            }
        }
        let n = self.nodes.len();
        self.nodes.push(p);
        self.cells.entry((cx, cy)).or_default().push(n);
        n
    }

    /// Adds a node grid `g[j][i]` as `(rows-1) × (cols-1)` elements; `tags` name the
    /// bottom, right, top and left sides (edges get the element's orientation).
    fn grid_patch(&mut self, g: &[Vec<P>], tags: [Option<&str>; 4]) {
        let nv = g.len() - 1;
        let nu = g[0].len() - 1;
        let idx: Vec<Vec<usize>> = g
            .iter()
            .map(|row| row.iter().map(|&p| self.node(p)).collect())
            .collect();
        for j in 0..nv {
            for i in 0..nu {
                self.elements
                    .push([idx[j][i], idx[j][i + 1], idx[j + 1][i + 1], idx[j + 1][i]]);
            }
        }
        let mut tag = |name: Option<&str>, edges: Vec<[usize; 2]>| {
            if let Some(name) = name {
                for e in edges {
                    self.tagged.push((name.to_string(), e));
                }
            }
        };
        tag(
            tags[0],
            (0..nu).map(|i| [idx[0][i], idx[0][i + 1]]).collect(),
        );
        tag(
            tags[1],
            (0..nv).map(|j| [idx[j][nu], idx[j + 1][nu]]).collect(),
        );
        tag(
            tags[2],
            (0..nu).map(|i| [idx[nv][i + 1], idx[nv][i]]).collect(),
        );
        tag(
            tags[3],
            (0..nv).map(|j| [idx[j + 1][0], idx[j][0]]).collect(),
        );
    }

    fn patch(&mut self, sides: &Sides, tags: [Option<&str>; 4]) {
        let g = sides.grid();
        self.grid_patch(&g, tags);
    }

    /// Finds the boundary (edges used by one element), keeps tagged edges that lie on it, and
    /// orders every edge set head to tail.
    fn finish(self) -> Mesh {
        let mut count: HashMap<[usize; 2], usize> = HashMap::new();
        for el in &self.elements {
            for k in 0..4 {
                let (a, b) = (el[k], el[(k + 1) % 4]);
                *count.entry([a.min(b), a.max(b)]).or_insert(0) += 1;
            }
        }
        let mut boundary = Vec::new();
        for el in &self.elements {
            for k in 0..4 {
                let (a, b) = (el[k], el[(k + 1) % 4]);
                if count[&[a.min(b), a.max(b)]] == 1 {
                    boundary.push([a, b]);
                }
            }
        }
        let on_boundary: std::collections::HashSet<[usize; 2]> = boundary.iter().copied().collect();
        let boundary = chain(boundary);
        let mut sets: BTreeMap<String, Vec<[usize; 2]>> = BTreeMap::new();
        for (name, e) in self.tagged {
            let list = sets.entry(name).or_default();
            if on_boundary.contains(&e) && !list.contains(&e) {
                list.push(e);
            }
        }
        let mut edge_sets: BTreeMap<String, Vec<[usize; 2]>> =
            sets.into_iter().map(|(k, v)| (k, chain(v))).collect();
        edge_sets.insert("boundary".to_string(), boundary.clone());
        Mesh {
            nodes: self.nodes,
            elements: self.elements,
            boundary,
            edge_sets,
        }
    }
}

/// Orders directed edges into head-to-tail chains: open chains first (each from its free
/// start), then closed loops, each loop starting at its smallest start node.
pub(crate) fn chain(edges: Vec<[usize; 2]>) -> Vec<[usize; 2]> {
    let mut by_start: HashMap<usize, Vec<usize>> = HashMap::new();
    let mut ends: std::collections::HashSet<usize> = std::collections::HashSet::new();
    for (k, e) in edges.iter().enumerate() {
        by_start.entry(e[0]).or_default().push(k);
        ends.insert(e[1]);
    }
    let mut used = vec![false; edges.len()];
    let mut out = Vec::with_capacity(edges.len());
    let mut starts: Vec<usize> = (0..edges.len())
        .filter(|&k| !ends.contains(&edges[k][0]))
        .collect();
    let mut rest: Vec<usize> = (0..edges.len()).collect();
    rest.sort_by_key(|&k| (edges[k][0], k));
    starts.extend(rest);
    for s in starts {
        let mut k = s;
        while !used[k] {
            used[k] = true;
            out.push(edges[k]);
            match by_start
                .get(&edges[k][1])
                .and_then(|l| l.iter().copied().find(|&q| !used[q]))
            {
                Some(q) => k = q,
                None => break,
            }
        }
    }
    out
}

fn merge_tol(points: &[P]) -> f64 {
    let [lo, hi] = super::bounding_box(points);
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE);
    1e-9 * size
}

// ---------------------------------------------------------------------------------------------
// Rectangles and Cook's membrane

/// Structured `nx × ny` mesh of the rectangle `[x0, x0 + width] × [y0, y0 + height]` with
/// `origin = [x0, y0]`. Edge sets `"left"` (x = x0), `"right"`, `"bottom"` (y = y0), `"top"`,
/// `"boundary"`. Nodes are numbered row by row from the bottom left.
///
/// # Panics
/// If `nx` or `ny` is 0 or `width`/`height` is not positive and finite.
pub fn rectangle(origin: [f64; 2], width: f64, height: f64, nx: usize, ny: usize) -> Mesh {
    assert!(
        nx >= 1 && ny >= 1,
        "rectangle: nx and ny must be at least 1"
    );
    assert!(
        width > 0.0 && height > 0.0 && width.is_finite() && height.is_finite(),
        "rectangle: width and height must be positive"
    );
    let [x0, y0] = origin;
    let (x1, y1) = (x0 + width, y0 + height);
    quad_block([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], nx, ny)
}

/// Bilinear `nx × ny` mesh of a convex quadrilateral with corners `c = [c00, c10, c11, c01]`
/// (counter-clockwise), sides tagged bottom/right/top/left.
fn quad_block(c: [P; 4], nx: usize, ny: usize) -> Mesh {
    let sides = Sides {
        bottom: line(c[0], c[1], nx),
        right: line(c[1], c[2], ny),
        top: line(c[3], c[2], nx),
        left: line(c[0], c[3], ny),
    };
    let mut b = Builder::new(merge_tol(&c));
    b.patch(
        &sides,
        [Some("bottom"), Some("right"), Some("top"), Some("left")],
    );
    b.finish()
}

/// Cook's membrane: the trapezoid with corners (0,0), (48,44), (48,60), (0,44) mm, meshed as
/// the bilinear image of an `nx × ny` grid (`nx` divisions along x, `ny` along the vertical
/// edges). Edge sets `"left"` (x = 0, clamped in the benchmark), `"right"` (x = 48, loaded),
/// `"bottom"`, `"top"`, `"boundary"`.
///
/// # Panics
/// If `nx` or `ny` is 0.
pub fn cook_membrane(nx: usize, ny: usize) -> Mesh {
    assert!(
        nx >= 1 && ny >= 1,
        "cook_membrane: nx and ny must be at least 1"
    );
    quad_block(
        [[0.0, 0.0], [48.0, 44.0], [48.0, 60.0], [0.0, 44.0]],
        nx,
        ny,
    )
}

// ---------------------------------------------------------------------------------------------
// Discs and ellipses (O-grid)

/// Core half-width of the O-grid in the unit disc (the core corners sit at radius `C·√2`).
const OGRID_CORE: f64 = 0.5;
/// `t* = atan((b/a)^e)`: e = 0 keeps the corners at t = π/4, e = 1 puts them where the normal
/// is at 45°.
const OGRID_CORNER_EXPONENT: f64 = 1.0;
/// Outward bulge of the core sides at their midpoints, as a fraction of `OGRID_CORE`
/// (parabolic profile). Opens the core corners and closes the block corners toward 90°.
const OGRID_BULGE: f64 = 0.12;

/// Parameters `t` (ellipse `(a cos t, b sin t)`) of `n + 1` points on the arc
/// `t ∈ [mid - w, mid + w]`, equally spaced in arc length, returned as offsets `t - mid`
/// (ascending, exactly antisymmetric, endpoints exactly ∓w).
fn arc_offsets(a: f64, b: f64, mid: f64, w: f64, n: usize) -> Vec<f64> {
    let mut q: Vec<f64> = if a == b {
        (0..=n)
            .map(|k| -w + 2.0 * w * k as f64 / n as f64)
            .collect()
    } else {
        // Cumulative arc length on a fine grid (trapezoidal rule), inverted linearly.
        let m = 64 * n + 256;
        let speed = |t: f64| (a * t.sin()).hypot(b * t.cos());
        let ts: Vec<f64> = (0..=m)
            .map(|k| mid - w + 2.0 * w * k as f64 / m as f64)
            .collect();
        let mut s = vec![0.0; m + 1];
        for k in 1..=m {
            s[k] = s[k - 1] + 0.5 * (speed(ts[k - 1]) + speed(ts[k])) * (ts[k] - ts[k - 1]);
        }
        let total = s[m];
        let mut out = Vec::with_capacity(n + 1);
        let mut seg = 0;
        for k in 0..=n {
            let target = total * k as f64 / n as f64;
            while seg + 1 < m && s[seg + 1] < target {
                seg += 1;
            }
            let w = ((target - s[seg]) / (s[seg + 1] - s[seg])).clamp(0.0, 1.0);
            out.push(ts[seg] + w * (ts[seg + 1] - ts[seg]) - mid);
        }
        out
    };
    for k in 0..=n / 2 {
        let v = 0.5 * (q[k] - q[n - k]);
        q[k] = v;
        q[n - k] = -v;
    }
    q[0] = -w;
    q[n] = w;
    q
}

/// Arc length of the ellipse `(a cos t, b sin t)` for `t ∈ [t0, t1]` (Simpson, 200 panels).
fn ellipse_arc_length(a: f64, b: f64, t0: f64, t1: f64) -> f64 {
    let n = 200;
    let hh = (t1 - t0) / n as f64;
    let f = |t: f64| (a * t.sin()).hypot(b * t.cos());
    let mut s = f(t0) + f(t1);
    for k in 1..n {
        s += if k % 2 == 1 { 4.0 } else { 2.0 } * f(t0 + hh * k as f64);
    }
    s * hh / 3.0
}

/// Parameter `t*` of the first O-grid block corner on the ellipse `(a cos t, b sin t)`:
/// π/4 for a circle, moving toward the end of the longer axis for elongated ellipses.
fn corner_parameter(a: f64, b: f64) -> f64 {
    (b / a).powf(OGRID_CORNER_EXPONENT).atan()
}

/// O-grid of the ellipse with semi-axes `a` (along the rotated x axis) and `b`, rotated by
/// `angle` (radians) about `center`: a core block plus four curved blocks, built in the unit
/// disc and mapped by `(x, y) ↦ center + R(angle)·(a x, b y)`.
fn ogrid(center: P, a: f64, b: f64, angle: f64, h: f64, even: bool) -> Mesh {
    let (cs, sn) = (angle.cos(), angle.sin());
    let map = |p: P| -> P {
        let (x, y) = (a * p[0], b * p[1]);
        [center[0] + cs * x - sn * y, center[1] + sn * x + cs * y]
    };
    // Block corners on the boundary at parameters ±t*, π ± t*. For a circle t* = π/4; for an
    // ellipse t* moves toward the ends of the long axis so that the radial lines meet the
    // boundary at angles closer to 90°.
    let ts = corner_parameter(a, b);
    let (ct, st) = (ts.cos(), ts.sin());
    // Circumferential divisions of the right/left arcs (nr) and the top/bottom arcs (nt).
    // (even counts put grid lines on both axes: the mesh then splits into halves and quarters)
    let round = |n: usize| if even { n + n % 2 } else { n };
    let nr = round(divisions_for(ellipse_arc_length(a, b, -ts, ts), h).max(2));
    let nt = round(divisions_for(ellipse_arc_length(a, b, ts, PI - ts), h).max(2));
    // Core: a rectangle whose corner sits inside the boundary corner P(t*), offset along the
    // boundary normal there (45° in physical space for the default t*), by g (for a circle of
    // radius r: g = (1 - c√2) r, core corners at (±c r, ±c r)). Its sides are bulged outward by
    // beta × their (physical) half-length. Everything below is in unit-disc coordinates.
    let (px, py) = (a * ct, b * st);
    let nrm = {
        let (nx, ny) = (ct / a, st / b);
        let l = nx.hypot(ny);
        [nx / l, ny / l]
    };
    let g = (1.0 - OGRID_CORE * std::f64::consts::SQRT_2) * std::f64::consts::SQRT_2 * px.min(py);
    let (xc, yc) = (px - g * nrm[0], py - g * nrm[1]); // physical core corner
    let (cx, cy) = (xc / a, yc / b);
    let beta = OGRID_BULGE;
    let (bx, by) = (beta * yc / a, beta * xc / b); // bulge amplitudes (unit-disc units)
                                                   // Radial divisions from the mean core-to-boundary gap (side midpoints and corners).
    let gap_right = a * (1.0 - cx - bx);
    let gap_top = b * (1.0 - cy - by);
    let m = divisions_for((gap_right + gap_top + g) / 3.0, h);

    let sr = arc_offsets(a, b, 0.0, ts, nr); // right arc offsets about t = 0
    let wt = FRAC_PI_2 - ts;
    let qt = arc_offsets(a, b, FRAC_PI_2, wt, nt); // top arc offsets about t = π/2
    let bulge_x = |y: f64| cx + bx * (1.0 - (y / cy) * (y / cy));
    let bulge_y = |x: f64| cy + by * (1.0 - (x / cx) * (x / cx));
    let on = |t: f64| -> P { [t.cos(), t.sin()] };
    // Arc corners (unit disc), counter-clockwise from t = t*.
    let arc_corner = [[ct, st], [-ct, st], [-ct, -st], [ct, -st]];
    let core_corner = [[cx, cy], [-cx, cy], [-cx, -cy], [cx, -cy]];
    let with_ends = |mut v: Vec<P>, first: P, last: P| {
        let n = v.len() - 1;
        v[0] = first;
        v[n] = last;
        v
    };
    // Arcs, counter-clockwise; block k spans arc_corner[k-1] → arc_corner[k].
    let arc_right = with_ends(
        sr.iter().map(|&s| on(s)).collect(),
        arc_corner[3],
        arc_corner[0],
    );
    let arc_top = with_ends(
        qt.iter().map(|&q| on(FRAC_PI_2 + q)).collect(),
        arc_corner[0],
        arc_corner[1],
    );
    let arc_left = with_ends(
        sr.iter().map(|&s| on(PI + s)).collect(),
        arc_corner[1],
        arc_corner[2],
    );
    let arc_bottom = with_ends(
        qt.iter().map(|&q| on(1.5 * PI + q)).collect(),
        arc_corner[2],
        arc_corner[3],
    );
    // Core sides, counter-clockwise partners of the arcs (same parameter fractions).
    let core_right: Vec<P> = sr
        .iter()
        .map(|&s| {
            let y = cy * (s / ts);
            [bulge_x(y), y]
        })
        .collect();
    let core_top: Vec<P> = qt
        .iter()
        .map(|&q| {
            let x = -cx * (q / wt);
            [x, bulge_y(x)]
        })
        .collect();
    let core_left: Vec<P> = sr
        .iter()
        .map(|&s| {
            let y = -cy * (s / ts);
            [-bulge_x(y), y]
        })
        .collect();
    let core_bottom: Vec<P> = qt
        .iter()
        .map(|&q| {
            let x = cx * (q / wt);
            [x, -bulge_y(x)]
        })
        .collect();
    let core_right = with_ends(core_right, core_corner[3], core_corner[0]);
    let core_top = with_ends(core_top, core_corner[0], core_corner[1]);
    let core_left = with_ends(core_left, core_corner[1], core_corner[2]);
    let core_bottom = with_ends(core_bottom, core_corner[2], core_corner[3]);
    // Radial lines from core corner k to arc corner k.
    let radial: Vec<Vec<P>> = (0..4)
        .map(|k| line(core_corner[k], arc_corner[k], m))
        .collect();

    let mp = |v: &[P]| -> Vec<P> { v.iter().map(|&p| map(p)).collect() };
    let rev = |v: &[P]| -> Vec<P> { v.iter().rev().copied().collect() };
    let mut bld = Builder::new(1e-9 * a.max(b));
    // Core: u along x, v along y.
    bld.patch(
        &Sides {
            bottom: mp(&core_bottom),
            right: mp(&core_right),
            top: mp(&rev(&core_top)),
            left: mp(&rev(&core_left)),
        },
        [None; 4],
    );
    // Curved blocks: u outward (core side → arc), v counter-clockwise.
    let blocks = [
        (&core_right, &arc_right, 3usize, 0usize),
        (&core_top, &arc_top, 0, 1),
        (&core_left, &arc_left, 1, 2),
        (&core_bottom, &arc_bottom, 2, 3),
    ];
    for (core_side, arc, k0, k1) in blocks {
        bld.patch(
            &Sides {
                bottom: mp(&radial[k0]),
                right: mp(arc),
                top: mp(&radial[k1]),
                left: mp(core_side),
            },
            [None, Some("outer"), None, None],
        );
    }
    bld.finish()
}

/// O-grid mesh of the disc of radius `radius` about `center`: a (slightly bulged) square core
/// block plus four curved blocks. All boundary nodes lie exactly on the circle (up to rounding
/// of `cos`/`sin`), at least 8 boundary segments, element edges about `h` on the circle and
/// somewhat finer in the core. Edge sets `"outer"` and `"boundary"` (the same edges).
///
/// # Panics
/// If `radius` or `h` is not positive and finite.
pub fn disc(center: [f64; 2], radius: f64, h: f64) -> Mesh {
    assert!(
        radius > 0.0 && radius.is_finite(),
        "disc: radius must be positive"
    );
    assert!(h > 0.0 && h.is_finite(), "disc: h must be positive");
    ogrid(center, radius, radius, 0.0, h, false)
}

/// O-grid mesh of the ellipse with semi-axes `semi_axes = [a, b]` (`a` along the x axis before
/// rotation) rotated by `angle_deg` (counter-clockwise, degrees) about `center`. Boundary nodes
/// lie exactly on the ellipse, spaced equally in arc length within each quarter. Edge sets
/// `"outer"` and `"boundary"`.
///
/// The block corners sit where the boundary normal is at 45° to the axes, so the radial block
/// edges meet the boundary nearly at right angles (min scaled Jacobian ≈ 0.83 at 2:1, ≈ 0.67
/// at 3:1, ≈ 0.34 at 5:1). The O-grid shares one radial division count all around, so for
/// elongated ellipses the element aspect ratio grows roughly like `a/b`.
///
/// # Panics
/// If a semi-axis or `h` is not positive and finite.
pub fn ellipse(center: [f64; 2], semi_axes: [f64; 2], angle_deg: f64, h: f64) -> Mesh {
    let [a, b] = semi_axes;
    assert!(
        a > 0.0 && b > 0.0 && a.is_finite() && b.is_finite(),
        "ellipse: semi-axes must be positive"
    );
    assert!(h > 0.0 && h.is_finite(), "ellipse: h must be positive");
    assert!(angle_deg.is_finite(), "ellipse: angle must be finite");
    ogrid(center, a, b, angle_deg.to_radians(), h, false)
}

/// A half or a quarter of an ellipse (or disc), for symmetry models.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EllipsePart {
    /// y′ ≥ 0 in the shape's own axes (x′ along its first semi-axis).
    Half,
    /// x′ ≥ 0 and y′ ≥ 0.
    Quarter,
}

/// The half or quarter (`part`, in the shape's own axes before the rotation by `angle_deg`) of
/// the O-grid mesh of an ellipse (a disc with equal semi-axes): the full mesh with an even
/// number of divisions on each arc, whose grid lines then run along both axes, cut along them.
/// Its nodes on the cuts lie exactly on the axes. Edge sets `"outer"` (the arc), `"axis_x"`
/// (the flat side on the shape's own x axis), `"axis_y"` (a quarter's flat side on its own y
/// axis) and `"boundary"`; the cuts are where a symmetry condition or a mirror wall goes.
///
/// # Panics
/// As [`ellipse`].
pub fn ellipse_part(center: [f64; 2], semi_axes: [f64; 2], angle_deg: f64, part: EllipsePart, h: f64) -> Mesh {
    let [a, b] = semi_axes;
    assert!(a > 0.0 && b > 0.0 && a.is_finite() && b.is_finite(), "ellipse_part: semi-axes must be positive");
    assert!(h > 0.0 && h.is_finite(), "ellipse_part: h must be positive");
    assert!(angle_deg.is_finite(), "ellipse_part: angle must be finite");
    let t = angle_deg.to_radians();
    let full = ogrid(center, a, b, t, h, true);
    let (cs, sn) = (t.cos(), t.sin());
    // own axes: x′ = R(−θ)(x − c)
    let own = |p: P| -> P {
        let (dx, dy) = (p[0] - center[0], p[1] - center[1]);
        [cs * dx + sn * dy, -sn * dx + cs * dy]
    };
    let world = |q: P| -> P { [center[0] + cs * q[0] - sn * q[1], center[1] + sn * q[0] + cs * q[1]] };
    let tol = 1e-9 * a.max(b);
    let keep = |q: P| q[1] > 0.0 && (part == EllipsePart::Half || q[0] > 0.0);
    let mut map = vec![usize::MAX; full.nodes.len()];
    let (mut nodes, mut elements) = (Vec::new(), Vec::new());
    for el in &full.elements {
        let c = el.iter().fold([0.0; 2], |s, &n| [s[0] + 0.25 * full.nodes[n][0], s[1] + 0.25 * full.nodes[n][1]]);
        if !keep(own(c)) {
            continue;
        }
        elements.push(el.map(|n| {
            if map[n] == usize::MAX {
                map[n] = nodes.len();
                // a node on a cut goes exactly onto it
                let mut q = own(full.nodes[n]);
                for v in &mut q {
                    if v.abs() <= tol {
                        *v = 0.0;
                    }
                }
                nodes.push(if q[0] == 0.0 || q[1] == 0.0 { world(q) } else { full.nodes[n] });
            }
            map[n]
        }));
    }
    let mut mesh = Mesh::from_quads(nodes, elements);
    let on = |n: usize, k: usize| own(mesh.nodes[n])[k].abs() <= tol;
    let (mut outer, mut axis_x, mut axis_y) = (Vec::new(), Vec::new(), Vec::new());
    for &[p, q] in &mesh.boundary {
        if on(p, 1) && on(q, 1) {
            axis_x.push([p, q]);
        } else if part == EllipsePart::Quarter && on(p, 0) && on(q, 0) {
            axis_y.push([p, q]);
        } else {
            outer.push([p, q]);
        }
    }
    mesh.edge_sets.insert("outer".into(), outer);
    mesh.edge_sets.insert("axis_x".into(), axis_x);
    if part == EllipsePart::Quarter {
        mesh.edge_sets.insert("axis_y".into(), axis_y);
    }
    mesh
}

// ---------------------------------------------------------------------------------------------
// Annulus sectors

/// Structured polar mesh of the annulus sector `r_in <= r <= r_out`,
/// `theta0_deg <= θ <= theta1_deg` (degrees, counter-clockwise from the x axis) about `center`:
/// `n_radial` divisions in r (equal), `n_circ` in θ (equal). Nodes on the arcs lie exactly on the
/// circles (up to rounding of `cos`/`sin`). Edge sets `"inner"` (r = r_in), `"outer"`
/// (r = r_out), `"start"` (θ = theta0), `"end"` (θ = theta1), `"boundary"`. A full ring
/// (`theta1 - theta0 = 360`) is closed up; its `"start"`/`"end"` sets are then empty.
///
/// # Panics
/// Unless `0 < r_in < r_out`, `theta0 < theta1 <= theta0 + 360`, `n_radial, n_circ >= 1` and each
/// element spans less than 180°.
pub fn annulus_sector(
    center: [f64; 2],
    r_in: f64,
    r_out: f64,
    theta0_deg: f64,
    theta1_deg: f64,
    n_radial: usize,
    n_circ: usize,
) -> Mesh {
    assert!(
        r_in > 0.0 && r_in < r_out && r_out.is_finite(),
        "annulus_sector: need 0 < r_in < r_out"
    );
    let span = theta1_deg - theta0_deg;
    assert!(
        span > 0.0 && span <= 360.0,
        "annulus_sector: need theta0 < theta1 <= theta0 + 360"
    );
    assert!(
        n_radial >= 1 && n_circ >= 1,
        "annulus_sector: need at least one division each way"
    );
    assert!(
        span / (n_circ as f64) < 180.0,
        "annulus_sector: each element must span less than 180°"
    );
    let (t0, t1) = (theta0_deg.to_radians(), theta1_deg.to_radians());
    // g[j][i]: i radial (u), j circumferential (v) → counter-clockwise elements.
    let g: Vec<Vec<P>> = (0..=n_circ)
        .map(|j| {
            let t = if j == n_circ {
                t1
            } else {
                t0 + (t1 - t0) * j as f64 / n_circ as f64
            };
            let (c, s) = (t.cos(), t.sin());
            (0..=n_radial)
                .map(|i| {
                    let r = if i == n_radial {
                        r_out
                    } else {
                        r_in + (r_out - r_in) * i as f64 / n_radial as f64
                    };
                    [center[0] + r * c, center[1] + r * s]
                })
                .collect()
        })
        .collect();
    let mut b = Builder::new(1e-9 * r_out);
    b.grid_patch(
        &g,
        [Some("start"), Some("outer"), Some("end"), Some("inner")],
    );
    b.finish()
}

// ---------------------------------------------------------------------------------------------
// Convex polygons

/// All-quadrilateral mesh of a convex polygon with target element size `h`.
///
/// The polygon (counter-clockwise or clockwise; clockwise input is reversed) is split into one
/// quadrilateral per vertex — vertex, midpoint of the next side, area centroid, midpoint of the
/// previous side — and each of these is subdivided by transfinite interpolation. Division
/// counts live on the spokes (centroid → side midpoint); side `k` gets the counts of the two
/// neighbouring spokes, so the mesh conforms and the boundary nodes lie on the polygon sides.
/// Corner angles of the coarse quadrilaterals are the polygon's angles, 90°-ish at the side
/// midpoints and about 360°/n at the centroid, so quality is good for polygons with up to about
/// ten sides and no very sharp corners (min scaled Jacobian ≈ sine of the smallest such angle).
///
/// Edge sets: `"boundary"` and `"side{k}"` for the side from input vertex `k` to input vertex
/// `k + 1` (mod n), whatever the input orientation; edges are oriented with the body on the left.
///
/// Corners must be strictly convex: a 180° corner (collinear consecutive vertices) is rejected,
/// because the coarse quadrilateral there would have a flat corner; merge such sides first.
///
/// # Errors
/// [`MeshError`] for fewer than 3 vertices, non-finite coordinates, a zero-length side, zero
/// area, a reflex or 180° corner or a self-intersecting polygon, or `h` not positive and
/// finite.
pub fn convex_polygon(vertices: &[[f64; 2]], h: f64) -> Result<Mesh, MeshError> {
    let n = vertices.len();
    if n < 3 {
        return Err(MeshError::TooFewVertices(n));
    }
    if !(h > 0.0 && h.is_finite()) {
        return Err(MeshError::InvalidSize(h));
    }
    if let Some(k) = vertices
        .iter()
        .position(|v| !(v[0].is_finite() && v[1].is_finite()))
    {
        return Err(MeshError::NonFiniteVertex(k));
    }
    let size = {
        let [lo, hi] = super::bounding_box(vertices);
        (hi[0] - lo[0]).hypot(hi[1] - lo[1])
    };
    for k in 0..n {
        if dist(vertices[k], vertices[(k + 1) % n]) <= 1e-12 * size {
            return Err(MeshError::DegenerateSide(k));
        }
    }
    let area = super::polygon_area(vertices.iter().copied());
    if area.abs() <= 1e-12 * size * size {
        return Err(MeshError::ZeroArea);
    }
    // Counter-clockwise working copy w; input index of w[i], and input side of CCW side i.
    let ccw = area > 0.0;
    let w: Vec<P> = if ccw {
        vertices.to_vec()
    } else {
        vertices.iter().rev().copied().collect()
    };
    let input_vertex = |i: usize| if ccw { i } else { n - 1 - i };
    let input_side = |i: usize| if ccw { i } else { (2 * n - 2 - i) % n };
    // Strict convexity: every turn to the left (a 180° corner would give an element with a
    // flat corner), and the turning angles add up to one full turn (not self-intersecting).
    let mut turning = 0.0;
    for i in 0..n {
        let e0 = sub(w[i], w[(i + n - 1) % n]);
        let e1 = sub(w[(i + 1) % n], w[i]);
        let cr = cross(e0, e1);
        let scale_ = e0[0].hypot(e0[1]) * e1[0].hypot(e1[1]);
        if cr <= 1e-12 * scale_ {
            return Err(MeshError::NotConvex(input_vertex(i)));
        }
        turning += cr.atan2(e0[0] * e1[0] + e0[1] * e1[1]);
    }
    if (turning - 2.0 * PI).abs() > 1e-6 {
        return Err(MeshError::NotConvex(input_vertex(0)));
    }
    // Area centroid (inside a convex polygon).
    let g = {
        let (mut gx, mut gy, mut a2) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let (p, q) = (w[i], w[(i + 1) % n]);
            let c = cross(p, q);
            a2 += c;
            gx += (p[0] + q[0]) * c;
            gy += (p[1] + q[1]) * c;
        }
        [gx / (3.0 * a2), gy / (3.0 * a2)]
    };
    let mid: Vec<P> = (0..n)
        .map(|i| scale(0.5, add(w[i], w[(i + 1) % n])))
        .collect();
    let len: Vec<f64> = (0..n).map(|i| dist(w[i], w[(i + 1) % n])).collect();
    // Spoke i (centroid → mid[i]) has s[i] divisions; so do the half-sides it is opposite to:
    // w[i+1] → mid[i+1] and mid[i-1] → w[i].
    let s: Vec<usize> = (0..n)
        .map(|i| {
            let target =
                (dist(g, mid[i]) + 0.5 * len[(i + 1) % n] + 0.5 * len[(i + n - 1) % n]) / 3.0;
            divisions_for(target, h)
        })
        .collect();
    // Spokes, each generated once (mid[i] → g) and shared by its two quadrilaterals.
    let spokes: Vec<Vec<P>> = (0..n).map(|i| line(mid[i], g, s[i])).collect();
    let side_names: Vec<String> = (0..n).map(|i| format!("side{}", input_side(i))).collect();
    let mut b = Builder::new(1e-9 * size);
    for i in 0..n {
        let ip = (i + n - 1) % n; // previous side
                                  // Corners: c00 = w[i], c10 = mid[i], c11 = g, c01 = mid[ip].
        let sides = Sides {
            bottom: line(w[i], mid[i], s[ip]),
            right: spokes[i].clone(),
            top: spokes[ip].clone(),
            left: line(w[i], mid[ip], s[i]),
        };
        b.patch(
            &sides,
            [
                Some(side_names[i].as_str()),
                None,
                None,
                Some(side_names[ip].as_str()),
            ],
        );
    }
    Ok(b.finish())
}
