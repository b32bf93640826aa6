//! Random packings in a rectangular die at an exact initial solid ratio, seeded and
//! reproducible (ChaCha8 stream from the seed; the same seed gives the same packing on every
//! platform up to the last bit of the libm functions used: `sqrt`, `ln`, `cos`).
//!
//! - [`voronoi_polygons`]: convex polygons. Seeds drawn uniformly in the die are moved a few
//!   times to the centroids of their cells (Lloyd relaxation, so the cells are roundish); the
//!   cells are the power diagram of the seeds clipped to the die (the plain Voronoi diagram
//!   when all particles have the same size; with a size distribution each seed carries the
//!   weight r², so cell sizes follow the drawn radii approximately). Each cell is simplified
//!   (a vertex is dropped where a side is shorter than [`MIN_SIDE`] × √area, or the corner is
//!   flatter than [`MAX_CORNER_DEG`], and the tip of a corner sharper than [`MIN_CORNER_DEG`]
//!   is cut off; both keep a cell inside itself, and keep the particle meshable), then
//!   every cell is shrunk about its centroid by the same factor s = √(φ · die area / Σ cell
//!   areas): areas scale with s², so the solid ratio is φ to round-off, and the shrunk cells
//!   lie strictly inside their disjoint cells. Any φ in (0, Σ cell areas / die area) is
//!   reachable (above 0.97: simplification trims a percent or two).
//! - [`random_discs`]: discs with radii drawn from the size distribution and scaled by one
//!   factor so that their total area is φ × die area exactly. They start at the centroids of
//!   the Lloyd-relaxed power cells (weights r²), grow from half their size to full size in
//!   50 stages, and at each stage are pushed apart pair by pair
//!   (Gauss–Seidel sweeps, each overlapping pair separated along its centre line, the larger
//!   disc moving less, discs kept inside the die) until every pair is at least a quarter of
//!   the clearance [`DISC_GAP`] × mean radius apart (and every disc the whole clearance
//!   inside the die). Random discs jam well below the polygons: in a square die about
//!   0.72–0.76 with 16 particles (16 equal discs cannot beat the 4 × 4 grid, π/4), 0.77 with
//!   100 and 0.80 with 300, whatever the size distribution. A target
//!   that cannot be reached within [`MAX_SWEEPS`] sweeps is an error.
//!
//! - [`voronoi_ellipses`]: ellipses from the same relaxed cells (not simplified): each cell's
//!   inertia ellipse (the ellipse with the cell's centroid and second moments of area) scaled
//!   to the largest copy inside the cell (exact: an ellipse (c, M) lies in the half-plane
//!   n·x <= b while n·c + √(nᵀMn) <= b), then all shrunk about their centres by the one
//!   factor that gives φ exactly. With `aspect` > 1 the cells, and so the ellipses, are
//!   elongated along x. The inscribed ellipses cover about 0.72–0.77 of the die (9 to 100
//!   particles, any aspect), which bounds the reachable φ.
//!
//! Materials are assigned by fraction: the counts are rounded by largest remainder (each
//! within one particle of fraction × count, and adding up to the count) and shuffled over the
//! particles with the same random stream.

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thiserror::Error;

use super::overlap::Convex;

/// A cell side shorter than this × √(cell area) is merged away before shrinking.
pub const MIN_SIDE: f64 = 0.25;
/// A cell corner with an interior angle above this (degrees) is dropped before shrinking.
pub const MAX_CORNER_DEG: f64 = 165.0;
/// A cell corner sharper than this (degrees) has its tip cut off before shrinking.
pub const MIN_CORNER_DEG: f64 = 40.0;
/// Clearance between discs (and between a disc and the die) aimed at by [`random_discs`], as a
/// fraction of the mean radius; at least a quarter of it is guaranteed between discs.
pub const DISC_GAP: f64 = 0.01;
/// Largest number of push-apart sweeps of [`random_discs`] at the final size.
pub const MAX_SWEEPS: usize = 20_000;
/// Growth stages of [`random_discs`] (from half size) and push-apart sweeps at most per stage.
const GROWTH_STAGES: usize = 50;
const STAGE_SWEEPS: usize = 200;

/// A packing failure: the parameter at fault (`count`, `solid_ratio`, `sizes`, `fractions`,
/// `die`) and a message naming the value and what was expected.
#[derive(Clone, Debug, PartialEq, Error)]
#[error("{param}: {message}")]
pub struct PackError {
    pub param: &'static str,
    pub message: String,
}

fn fail(param: &'static str, message: impl Into<String>) -> PackError {
    PackError { param, message: message.into() }
}

/// The rectangle `[x0, x1] × [y0, y1]` (mm) enclosed by the walls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Die {
    pub x: [f64; 2],
    pub y: [f64; 2],
}

impl Die {
    pub fn area(&self) -> f64 {
        (self.x[1] - self.x[0]) * (self.y[1] - self.y[0])
    }
    fn width(&self) -> f64 {
        self.x[1] - self.x[0]
    }
    fn height(&self) -> f64 {
        self.y[1] - self.y[0]
    }
}

/// Relative particle sizes (the absolute size follows from the count and the solid ratio).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Sizes {
    /// All particles the same size.
    #[default]
    Equal,
    /// Radius uniform in [r, ratio · r].
    Uniform { ratio: f64 },
    /// ln(radius) normal with standard deviation `sigma`, truncated to radii within a factor
    /// `ratio` (largest / smallest ≤ ratio, symmetric about the median in log scale).
    LogNormal { sigma: f64, ratio: f64 },
}

/// What to generate.
#[derive(Clone, Debug, PartialEq)]
pub struct RandomSpec {
    pub count: usize,
    pub seed: u64,
    /// Target solid ratio φ = particle area / die area.
    pub solid_ratio: f64,
    pub sizes: Sizes,
    /// Lloyd relaxation steps.
    pub lloyd: usize,
    /// Cells (polygons, ellipses) elongated along x by this factor (1 = roundish): the
    /// tessellation is built in the die scaled by 1/√aspect along x and √aspect along y and
    /// mapped back. Not used by [`random_discs`].
    pub aspect: f64,
    /// Material fractions (one per material, positive; normalised).
    pub fractions: Vec<f64>,
}

/// One generated particle: its outline and the index of its material in
/// [`RandomSpec::fractions`].
#[derive(Clone, Debug, PartialEq)]
pub struct Particle {
    pub shape: Convex,
    pub material: usize,
}

/// A generated packing.
#[derive(Clone, Debug, PartialEq)]
pub struct Packing {
    pub die: Die,
    pub particles: Vec<Particle>,
}

impl Packing {
    /// Total particle area / die area.
    pub fn solid_ratio(&self) -> f64 {
        self.particles.iter().map(|p| p.shape.area()).sum::<f64>() / self.die.area()
    }
}

// ---------------------------------------------------------------------------------------------
// Random numbers

struct Stream(ChaCha8Rng);

impl Stream {
    fn new(seed: u64) -> Self {
        Self(ChaCha8Rng::seed_from_u64(seed))
    }
    /// Uniform in [0, 1) with 53 random bits.
    fn unit(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Uniform integer in 0..n (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.0.next_u64() % n as u64) as usize
    }
    /// Standard normal (Box–Muller).
    fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.unit(); // (0, 1]
        let u2 = self.unit();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

fn check_spec(die: &Die, spec: &RandomSpec) -> Result<(), PackError> {
    if !(die.width() > 0.0 && die.height() > 0.0 && die.area().is_finite()) {
        return Err(fail("die", format!("[{}, {}] x [{}, {}] mm; expected left < right and bottom < top", die.x[0], die.x[1], die.y[0], die.y[1])));
    }
    if spec.count == 0 {
        return Err(fail("count", "0; expected at least one particle"));
    }
    if !(spec.solid_ratio > 0.0 && spec.solid_ratio < 1.0) {
        return Err(fail("solid_ratio", format!("{}; expected a value in (0, 1)", spec.solid_ratio)));
    }
    if !(spec.aspect.is_finite() && spec.aspect > 0.0) {
        return Err(fail("aspect", format!("{}; expected an elongation > 0 (1 = roundish cells)", spec.aspect)));
    }
    if spec.fractions.is_empty() || spec.fractions.iter().any(|f| !(f.is_finite() && *f > 0.0)) {
        return Err(fail("fractions", format!("{:?}; expected one positive fraction per material", spec.fractions)));
    }
    match spec.sizes {
        Sizes::Equal => {}
        Sizes::Uniform { ratio } => {
            if !(ratio.is_finite() && ratio >= 1.0) {
                return Err(fail("sizes", format!("ratio = {ratio}; expected a largest / smallest radius ratio >= 1")));
            }
        }
        Sizes::LogNormal { sigma, ratio } => {
            if !(sigma.is_finite() && sigma >= 0.0) {
                return Err(fail("sizes", format!("sigma = {sigma}; expected a standard deviation of ln(radius) >= 0")));
            }
            if !(ratio.is_finite() && ratio > 1.0) {
                return Err(fail("sizes", format!("ratio = {ratio}; expected a largest / smallest radius ratio > 1 (the truncation of the lognormal)")));
            }
        }
    }
    Ok(())
}

/// Relative radii (median about 1).
fn draw_radii(rng: &mut Stream, n: usize, sizes: Sizes) -> Vec<f64> {
    (0..n)
        .map(|_| match sizes {
            Sizes::Equal => 1.0,
            Sizes::Uniform { ratio } => 1.0 + (ratio - 1.0) * rng.unit(),
            Sizes::LogNormal { sigma, ratio } => {
                let half = 0.5 * ratio.ln();
                // truncated by rejection; a normal lands in ±half with probability > 1e-3 for
                // any accepted sigma within a few thousand draws, else clamp
                for _ in 0..10_000 {
                    let z = sigma * rng.normal();
                    if z.abs() <= half {
                        return z.exp();
                    }
                }
                1.0
            }
        })
        .collect()
}

/// Material counts by largest remainder: each within one of `fraction × count`, summing to
/// `count` (ties go to the earlier material).
pub fn material_counts(count: usize, fractions: &[f64]) -> Vec<usize> {
    let total: f64 = fractions.iter().sum();
    if fractions.is_empty() || total.is_nan() || total <= 0.0 {
        return Vec::new();
    }
    let exact: Vec<f64> = fractions.iter().map(|f| f / total * count as f64).collect();
    let mut counts: Vec<usize> = exact.iter().map(|e| e.floor() as usize).collect();
    let mut order: Vec<usize> = (0..fractions.len()).collect();
    order.sort_by(|&a, &b| (exact[b] - exact[b].floor()).total_cmp(&(exact[a] - exact[a].floor())).then(a.cmp(&b)));
    let mut left = count.saturating_sub(counts.iter().sum());
    for &m in order.iter().cycle() {
        if left == 0 {
            break;
        }
        counts[m] += 1;
        left -= 1;
    }
    counts
}

/// Material of each of `count` particles by `fractions`: the counts of [`material_counts`]
/// shuffled by a random stream of `seed` (Fisher–Yates), reproducibly.
pub fn mixture(seed: u64, count: usize, fractions: &[f64]) -> Vec<usize> {
    assign_materials(&mut Stream::new(seed), count, fractions)
}

/// Material of each particle: the counts of [`material_counts`], shuffled (Fisher–Yates).
fn assign_materials(rng: &mut Stream, count: usize, fractions: &[f64]) -> Vec<usize> {
    let mut v: Vec<usize> = material_counts(count, fractions).iter().enumerate().flat_map(|(m, &k)| std::iter::repeat_n(m, k)).collect();
    for i in (1..v.len()).rev() {
        let j = rng.below(i + 1);
        v.swap(i, j);
    }
    v
}

// ---------------------------------------------------------------------------------------------
// Power diagram by half-plane clipping

type P = [f64; 2];

/// Keep the part of the convex polygon `poly` where `n · x <= c`.
fn clip(poly: &[P], n: P, c: f64) -> Vec<P> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    let k = poly.len();
    for i in 0..k {
        let (a, b) = (poly[i], poly[(i + 1) % k]);
        let (fa, fb) = (n[0] * a[0] + n[1] * a[1] - c, n[0] * b[0] + n[1] * b[1] - c);
        if fa <= 0.0 {
            out.push(a);
        }
        if (fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0) {
            let t = fa / (fa - fb);
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    out
}

/// The power cell of every seed (weights `w` ≥ 0), clipped to the die; counter-clockwise. A
/// cell may be empty (a light seed next to heavy ones).
///
/// Each cell starts as the die and is clipped by the other seeds' half-planes, nearest seed
/// first (ties by index). The seeds are taken from a bucket grid in rings of doubling radius ρ:
/// once the cell lies within R of its seed and (ρ² − max w) / 2ρ > 1.01 R, no farther seed's
/// half-plane reaches it (the plane of a seed at distance d > ρ lies at least
/// (d² − max w) / 2d > R from the seed, and that grows with d), so the cell is complete. The
/// clips made, and their order, are those of clipping by every other seed in order of distance,
/// so the cells are the same to the bit; a cell costs its neighbours, not all the seeds.
fn power_cells(die: &Die, seeds: &[P], w: &[f64]) -> Vec<Vec<P>> {
    let rect = vec![[die.x[0], die.y[0]], [die.x[1], die.y[0]], [die.x[1], die.y[1]], [die.x[0], die.y[1]]];
    let w_max = w.iter().fold(0.0f64, |m, &x| m.max(x));
    let grid = Buckets::new(die, seeds);
    let far = die.width().hypot(die.height());
    (0..seeds.len())
        .map(|i| {
            let p = seeds[i];
            let mut cell = rect.clone();
            let (mut inner, mut rho) = (-1.0f64, grid.size);
            loop {
                let mut ring: Vec<(f64, usize)> = grid.near(p, rho).filter(|&j| j != i).map(|j| (dist2(p, seeds[j]), j)).filter(|&(d, _)| d > inner && d <= rho * rho).collect();
                ring.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                for (_, j) in ring {
                    if cell.is_empty() {
                        break;
                    }
                    let q = seeds[j];
                    // |x - p|² - w_i <= |x - q|² - w_j  <=>  2 (q - p) · x <= |q|² - |p|² - w_j + w_i
                    let n = [2.0 * (q[0] - p[0]), 2.0 * (q[1] - p[1])];
                    let c = q[0] * q[0] + q[1] * q[1] - p[0] * p[0] - p[1] * p[1] - w[j] + w[i];
                    if n[0] == 0.0 && n[1] == 0.0 {
                        continue; // coincident seeds: the next relaxation separates them
                    }
                    // a half-plane that contains every vertex changes nothing
                    if cell.iter().all(|v| n[0] * v[0] + n[1] * v[1] <= c) {
                        continue;
                    }
                    cell = clip(&cell, n, c);
                }
                let r = cell.iter().fold(0.0f64, |m, &v| m.max(dist2(p, v))).sqrt();
                if cell.is_empty() || rho > 2.0 * far || (rho * rho - w_max) / (2.0 * rho) > 1.01 * r {
                    break;
                }
                (inner, rho) = (rho * rho, 2.0 * rho);
            }
            cell
        })
        .collect()
}

/// The seeds sorted into a grid of buckets over the die, about one seed a bucket (at most
/// one row or column a seed along either side: a die far narrower than a seed's share of it
/// gets one column).
struct Buckets {
    x0: P,
    /// A seed's share of the die, √(area / count): the first ring's radius.
    size: f64,
    /// A bucket's sides.
    side: P,
    cols: usize,
    rows: usize,
    /// The seeds of each bucket (row-major).
    seeds: Vec<Vec<usize>>,
}

impl Buckets {
    fn new(die: &Die, seeds: &[P]) -> Self {
        let n = seeds.len().max(1);
        let size = (die.area() / n as f64).sqrt();
        let count = |length: f64| ((length / size).round() as usize).clamp(1, n);
        let (cols, rows) = (count(die.width()), count(die.height()));
        let side = [die.width() / cols as f64, die.height() / rows as f64];
        let mut b = Self { x0: [die.x[0], die.y[0]], size, side, cols, rows, seeds: vec![Vec::new(); cols * rows] };
        for (i, &q) in seeds.iter().enumerate() {
            let (c, r) = b.cell(q);
            b.seeds[r * cols + c].push(i);
        }
        b
    }

    /// The bucket holding point `q` (clamped to the grid).
    fn cell(&self, q: P) -> (usize, usize) {
        let at = |v: f64, side: f64, n: usize| ((v / side).floor().max(0.0) as usize).min(n - 1);
        (at(q[0] - self.x0[0], self.side[0], self.cols), at(q[1] - self.x0[1], self.side[1], self.rows))
    }

    /// The seeds of every bucket that meets the square of half-side `rho` about `p` (a
    /// superset of the seeds within `rho` of `p`).
    fn near(&self, p: P, rho: f64) -> impl Iterator<Item = usize> + '_ {
        let (c0, r0) = self.cell([p[0] - rho, p[1] - rho]);
        let (c1, r1) = self.cell([p[0] + rho, p[1] + rho]);
        (r0..=r1).flat_map(move |r| (c0..=c1).flat_map(move |c| self.seeds[r * self.cols + c].iter().copied()))
    }
}

fn dist2(a: P, b: P) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

/// Area (signed, positive counter-clockwise) and area centroid of a polygon.
fn area_centroid(poly: &[P]) -> (f64, P) {
    let k = poly.len();
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    // relative to the first vertex to limit cancellation
    let o = poly.first().copied().unwrap_or([0.0, 0.0]);
    for i in 0..k {
        let (p, q) = (poly[i], poly[(i + 1) % k]);
        let (px, py, qx, qy) = (p[0] - o[0], p[1] - o[1], q[0] - o[0], q[1] - o[1]);
        let cr = px * qy - qx * py;
        a += cr;
        cx += (px + qx) * cr;
        cy += (py + qy) * cr;
    }
    a *= 0.5;
    if a.abs() > 0.0 {
        (a, [o[0] + cx / (6.0 * a), o[1] + cy / (6.0 * a)])
    } else {
        (0.0, o)
    }
}

/// Lloyd-relaxed seeds and their final power cells; seeds whose cell vanished are redrawn.
fn relaxed_cells(rng: &mut Stream, die: &Die, w: &[f64], lloyd: usize) -> Result<(Vec<P>, Vec<Vec<P>>), PackError> {
    let n = w.len();
    let draw = |rng: &mut Stream| [die.x[0] + die.width() * rng.unit(), die.y[0] + die.height() * rng.unit()];
    let mut seeds: Vec<P> = (0..n).map(|_| draw(rng)).collect();
    let mut cells = power_cells(die, &seeds, w);
    let mut step = 0;
    loop {
        let empty: Vec<usize> = (0..n).filter(|&i| area_centroid(&cells[i]).0 <= 0.0).collect();
        if step >= lloyd && empty.is_empty() {
            break;
        }
        if step >= lloyd + 50 {
            return Err(fail("sizes", format!("{} power cell(s) stay empty after {step} relaxation steps; expected a narrower size distribution", empty.len())));
        }
        for (i, s) in seeds.iter_mut().enumerate() {
            let (a, c) = area_centroid(&cells[i]);
            *s = if a > 0.0 { c } else { draw(rng) };
        }
        cells = power_cells(die, &seeds, w);
        step += 1;
    }
    Ok((seeds, cells))
}

/// [`relaxed_cells`] of a die stretched by `aspect` along x (the cells are built in the die
/// mapped by x / √aspect, y · √aspect, which keeps areas, and mapped back).
fn stretched_cells(rng: &mut Stream, die: &Die, w: &[f64], lloyd: usize, aspect: f64) -> Result<(Vec<P>, Vec<Vec<P>>), PackError> {
    let k = aspect.sqrt();
    let sdie = Die { x: [die.x[0] / k, die.x[1] / k], y: [die.y[0] * k, die.y[1] * k] };
    let (seeds, cells) = relaxed_cells(rng, &sdie, w, lloyd)?;
    let back = |p: &P| [p[0] * k, p[1] / k];
    Ok((seeds.iter().map(back).collect(), cells.iter().map(|c| c.iter().map(back).collect()).collect()))
}

/// Drop vertices that make short sides or flat corners (never below 3 vertices). Every
/// dropped vertex removes a triangle, so the result lies inside the input.
fn simplify(poly: &mut Vec<P>) {
    let cos_max = MAX_CORNER_DEG.to_radians().cos();
    loop {
        let k = poly.len();
        if k <= 3 {
            return;
        }
        let (area, _) = area_centroid(poly);
        let min_side = MIN_SIDE * area.abs().sqrt();
        // the cheapest vertex (smallest cut triangle) among the offending ones
        let cut = |i: usize| {
            let (a, b, c) = (poly[(i + k - 1) % k], poly[i], poly[(i + 1) % k]);
            0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs()
        };
        let mut worst: Option<(f64, usize)> = None;
        for i in 0..k {
            let (a, b, c) = (poly[(i + k - 1) % k], poly[i], poly[(i + 1) % k]);
            let (u, v) = ([a[0] - b[0], a[1] - b[1]], [c[0] - b[0], c[1] - b[1]]);
            let (lu, lv) = (u[0].hypot(u[1]), v[0].hypot(v[1]));
            let flat = lu * lv > 0.0 && (u[0] * v[0] + u[1] * v[1]) / (lu * lv) < cos_max;
            let short = lv < min_side || lu < min_side;
            if flat || short || lu == 0.0 || lv == 0.0 {
                let t = cut(i);
                if worst.is_none_or(|(best, _)| t < best) {
                    worst = Some((t, i));
                }
            }
        }
        match worst {
            Some((_, i)) => {
                poly.remove(i);
            }
            None => return,
        }
    }
}

/// Cut the tip of every corner sharper than [`MIN_CORNER_DEG`]: the corner is replaced by two
/// points on its sides at 0.3 × the shorter side from it, whose corners are 90° + half the
/// old angle. The result lies inside the input.
fn blunt(poly: &mut Vec<P>) {
    let cos_min = MIN_CORNER_DEG.to_radians().cos();
    let mut out = Vec::with_capacity(poly.len() + 4);
    let k = poly.len();
    for i in 0..k {
        let (a, b, c) = (poly[(i + k - 1) % k], poly[i], poly[(i + 1) % k]);
        let (u, v) = ([a[0] - b[0], a[1] - b[1]], [c[0] - b[0], c[1] - b[1]]);
        let (lu, lv) = (u[0].hypot(u[1]), v[0].hypot(v[1]));
        if lu > 0.0 && lv > 0.0 && (u[0] * v[0] + u[1] * v[1]) / (lu * lv) > cos_min {
            let l = 0.3 * lu.min(lv);
            out.push([b[0] + u[0] * l / lu, b[1] + u[1] * l / lu]);
            out.push([b[0] + v[0] * l / lv, b[1] + v[1] * l / lv]);
        } else {
            out.push(b);
        }
    }
    *poly = out;
}

/// Random convex polygons at the exact solid ratio (see the module docs).
pub fn voronoi_polygons(die: Die, spec: &RandomSpec) -> Result<Packing, PackError> {
    check_spec(&die, spec)?;
    let mut rng = Stream::new(spec.seed);
    let radii = draw_radii(&mut rng, spec.count, spec.sizes);
    let w = weights(&die, &radii);
    let (_, mut cells) = stretched_cells(&mut rng, &die, &w, spec.lloyd, spec.aspect)?;
    for c in &mut cells {
        simplify(c);
        blunt(c);
    }
    let areas: Vec<(f64, P)> = cells.iter().map(|c| area_centroid(c)).collect();
    let total: f64 = areas.iter().map(|a| a.0).sum();
    let target = spec.solid_ratio * die.area();
    let s = (target / total).sqrt();
    if s.is_nan() || s >= 1.0 {
        return Err(fail("solid_ratio", format!("{}; the simplified cells cover {:.4} of the die, expected a solid ratio below that", spec.solid_ratio, total / die.area())));
    }
    let materials = assign_materials(&mut rng, spec.count, &spec.fractions);
    let particles = cells
        .iter()
        .zip(&areas)
        .zip(materials)
        .map(|((cell, &(_, c)), material)| Particle {
            shape: Convex::Polygon(cell.iter().map(|v| [c[0] + s * (v[0] - c[0]), c[1] + s * (v[1] - c[1])]).collect()),
            material,
        })
        .collect();
    tracing::debug!(count = spec.count, seed = spec.seed, shrink = s, "packing: voronoi polygons");
    Ok(Packing { die, particles })
}

/// Random ellipses at the exact solid ratio (see the module docs).
pub fn voronoi_ellipses(die: Die, spec: &RandomSpec) -> Result<Packing, PackError> {
    check_spec(&die, spec)?;
    let mut rng = Stream::new(spec.seed);
    let radii = draw_radii(&mut rng, spec.count, spec.sizes);
    let w = weights(&die, &radii);
    let (_, cells) = stretched_cells(&mut rng, &die, &w, spec.lloyd, spec.aspect)?;
    // the largest copy of each cell's inertia ellipse that fits in the cell: (centre, M) with
    // the ellipse {x : (x - c)ᵀ M⁻¹ (x - c) <= 1}
    let mut shapes = Vec::with_capacity(cells.len());
    for cell in &cells {
        let (a, c) = area_centroid(cell);
        if a <= 0.0 {
            return Err(fail("count", format!("{}: a cell has no area; expected fewer particles", spec.count)));
        }
        let m = inertia_ellipse(cell, c, a);
        let k = cell.len();
        let t = (0..k)
            .map(|i| {
                let (p, q) = (cell[i], cell[(i + 1) % k]);
                // outward unit normal of the counter-clockwise side p -> q
                let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
                let l = dx.hypot(dy);
                if l == 0.0 {
                    return f64::INFINITY;
                }
                let n = [dy / l, -dx / l];
                let room = n[0] * (p[0] - c[0]) + n[1] * (p[1] - c[1]);
                let reach = (n[0] * n[0] * m[0] + 2.0 * n[0] * n[1] * m[1] + n[1] * n[1] * m[2]).sqrt();
                room / reach
            })
            .fold(f64::INFINITY, f64::min);
        let m = [t * t * m[0], t * t * m[1], t * t * m[2]];
        shapes.push((c, m));
    }
    let total: f64 = shapes.iter().map(|(_, m)| std::f64::consts::PI * (m[0] * m[2] - m[1] * m[1]).max(0.0).sqrt()).sum();
    let s = (spec.solid_ratio * die.area() / total).sqrt();
    if s.is_nan() || s >= 1.0 {
        return Err(fail("solid_ratio", format!("{}; the ellipses inscribed in the cells cover {:.4} of the die, expected a solid ratio below that", spec.solid_ratio, total / die.area())));
    }
    let materials = assign_materials(&mut rng, spec.count, &spec.fractions);
    let particles = shapes
        .into_iter()
        .zip(materials)
        .map(|((center, m), material)| {
            // principal axes of M: semi-axes √λ, the major axis at angle θ
            let (h, d) = (0.5 * (m[0] + m[2]), (0.25 * (m[0] - m[2]).powi(2) + m[1] * m[1]).sqrt());
            let theta = 0.5 * (2.0 * m[1]).atan2(m[0] - m[2]);
            let semi_axes = [s * (h + d).sqrt(), s * (h - d).max(0.0).sqrt()];
            Particle { shape: Convex::Ellipse { center, semi_axes, angle_deg: theta.to_degrees() }, material }
        })
        .collect();
    tracing::debug!(count = spec.count, seed = spec.seed, shrink = s, "packing: voronoi ellipses");
    Ok(Packing { die, particles })
}

/// `[Mxx, Mxy, Myy]` = 4 × the covariance of the polygon (area `a`, centroid `c`): the ellipse
/// with the polygon's second moments of area.
fn inertia_ellipse(poly: &[P], c: P, a: f64) -> [f64; 3] {
    let k = poly.len();
    let (mut ixx, mut ixy, mut iyy) = (0.0, 0.0, 0.0);
    for i in 0..k {
        let (p, q) = (poly[i], poly[(i + 1) % k]);
        let (x0, y0, x1, y1) = (p[0] - c[0], p[1] - c[1], q[0] - c[0], q[1] - c[1]);
        let cr = x0 * y1 - x1 * y0;
        ixx += cr * (x0 * x0 + x0 * x1 + x1 * x1);
        iyy += cr * (y0 * y0 + y0 * y1 + y1 * y1);
        ixy += cr * (x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0);
    }
    [4.0 * ixx / (12.0 * a), 4.0 * ixy / (24.0 * a), 4.0 * iyy / (12.0 * a)]
}

/// Power weights r² scaled so that discs of radius √w would cover half the die.
fn weights(die: &Die, radii: &[f64]) -> Vec<f64> {
    let sum: f64 = radii.iter().map(|r| r * r).sum();
    let k = 0.5 * die.area() / (std::f64::consts::PI * sum);
    radii.iter().map(|r| k * r * r).collect()
}

/// Random discs at the exact solid ratio (see the module docs).
pub fn random_discs(die: Die, spec: &RandomSpec) -> Result<Packing, PackError> {
    check_spec(&die, spec)?;
    let mut rng = Stream::new(spec.seed);
    let rel = draw_radii(&mut rng, spec.count, spec.sizes);
    let sum: f64 = rel.iter().map(|r| r * r).sum();
    let lambda = (spec.solid_ratio * die.area() / (std::f64::consts::PI * sum)).sqrt();
    let radii: Vec<f64> = rel.iter().map(|r| lambda * r).collect();
    let mean = radii.iter().sum::<f64>() / radii.len() as f64;
    let gap = DISC_GAP * mean;
    let rmax = radii.iter().fold(0.0f64, |m, &r| m.max(r));
    if 2.0 * (rmax + gap) > die.width().min(die.height()) {
        return Err(fail("solid_ratio", format!("{}: the largest disc (radius {rmax:.4} mm) does not fit in the die; expected a lower solid ratio or more particles", spec.solid_ratio)));
    }
    let w: Vec<f64> = weights(&die, &rel);
    let (mut pos, _) = relaxed_cells(&mut rng, &die, &w, spec.lloyd)?;
    // grow the discs from half their size in stages, separating them at each stage: the
    // assembly organises itself while there is room
    for stage in 0..GROWTH_STAGES {
        let f = 0.5 + 0.5 * stage as f64 / GROWTH_STAGES as f64;
        let r: Vec<f64> = radii.iter().map(|r| f * r).collect();
        let _ = separate(&die, &mut pos, &r, gap, STAGE_SWEEPS);
    }
    let sweeps = separate(&die, &mut pos, &radii, gap, MAX_SWEEPS).ok_or_else(|| {
        fail(
            "solid_ratio",
            format!("{}: {} discs could not be pushed apart within {MAX_SWEEPS} sweeps; expected a lower solid ratio (random discs reach about 0.72-0.76 with 16 particles, 0.77 with 100, 0.80 with 300; voronoi_polygons reach any)", spec.solid_ratio, spec.count),
        )
    })?;
    let materials = assign_materials(&mut rng, spec.count, &spec.fractions);
    let particles = pos
        .iter()
        .zip(&radii)
        .zip(materials)
        .map(|((&center, &radius), material)| Particle { shape: Convex::Disc { center, radius }, material })
        .collect();
    tracing::debug!(count = spec.count, seed = spec.seed, sweeps, "packing: random discs");
    Ok(Packing { die, particles })
}

/// Push discs apart until every pair is at least `gap / 4` apart (aiming at `gap`), every disc
/// `gap` inside the die; returns the number of sweeps, `None` if `max_sweeps` were not
/// enough.
fn separate(die: &Die, pos: &mut [P], r: &[f64], gap: f64, max_sweeps: usize) -> Option<usize> {
    let n = pos.len();
    let rmax = r.iter().fold(0.0f64, |m, &x| m.max(x));
    let inside = |p: &mut P, ri: f64| {
        let m = ri + gap;
        p[0] = p[0].clamp(die.x[0] + m, die.x[1] - m);
        p[1] = p[1].clamp(die.y[0] + m, die.y[1] - m);
    };
    for (p, &ri) in pos.iter_mut().zip(r) {
        inside(p, ri);
    }
    let mut order: Vec<usize> = (0..n).collect();
    for sweep in 0..max_sweeps {
        order.sort_by(|&a, &b| pos[a][0].total_cmp(&pos[b][0]));
        let mut worst = 0.0f64;
        for a in 0..n {
            let i = order[a];
            for &j in &order[a + 1..] {
                if pos[j][0] - pos[i][0] > r[i] + rmax + gap {
                    break;
                }
                let want = r[i] + r[j] + gap;
                let (dx, dy) = (pos[j][0] - pos[i][0], pos[j][1] - pos[i][1]);
                if dy.abs() >= want {
                    continue;
                }
                let d = dx.hypot(dy);
                if d >= want {
                    continue;
                }
                worst = worst.max(r[i] + r[j] + 0.25 * gap - d);
                let (ux, uy) = if d > 0.0 {
                    (dx / d, dy / d)
                } else {
                    let t = 2.399_963_229_728_653 * (i + j) as f64; // golden angle
                    (t.cos(), t.sin())
                };
                let (ai, aj) = (r[i] * r[i], r[j] * r[j]);
                let delta = want - d;
                let (si, sj) = (delta * aj / (ai + aj), delta * ai / (ai + aj));
                pos[i][0] -= si * ux;
                pos[i][1] -= si * uy;
                pos[j][0] += sj * ux;
                pos[j][1] += sj * uy;
                inside(&mut pos[i], r[i]);
                inside(&mut pos[j], r[j]);
            }
        }
        if worst <= 0.0 && min_clearance(pos, r) >= 0.25 * gap {
            return Some(sweep);
        }
    }
    None
}

/// Smallest distance between two disc outlines (mm); infinite for fewer than two discs.
pub fn min_clearance(pos: &[P], r: &[f64]) -> f64 {
    let rmax = r.iter().fold(0.0f64, |m, &x| m.max(x));
    let mut order: Vec<usize> = (0..pos.len()).collect();
    order.sort_by(|&a, &b| pos[a][0].total_cmp(&pos[b][0]));
    let mut best = f64::INFINITY;
    for (a, &i) in order.iter().enumerate() {
        for &j in &order[a + 1..] {
            if pos[j][0] - pos[i][0] - r[i] - rmax > best {
                break;
            }
            best = best.min(dist2(pos[i], pos[j]).sqrt() - r[i] - r[j]);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The power cells by clipping each cell with every other seed, nearest first: the
    /// definition [`power_cells`] shortens.
    fn power_cells_by_all(die: &Die, seeds: &[P], w: &[f64]) -> Vec<Vec<P>> {
        let rect = vec![[die.x[0], die.y[0]], [die.x[1], die.y[0]], [die.x[1], die.y[1]], [die.x[0], die.y[1]]];
        (0..seeds.len())
            .map(|i| {
                let p = seeds[i];
                let mut others: Vec<usize> = (0..seeds.len()).filter(|&j| j != i).collect();
                others.sort_by(|&a, &b| dist2(p, seeds[a]).total_cmp(&dist2(p, seeds[b])));
                let mut cell = rect.clone();
                for j in others {
                    let q = seeds[j];
                    let n = [2.0 * (q[0] - p[0]), 2.0 * (q[1] - p[1])];
                    let c = q[0] * q[0] + q[1] * q[1] - p[0] * p[0] - p[1] * p[1] - w[j] + w[i];
                    if cell.is_empty() || (n[0] == 0.0 && n[1] == 0.0) || cell.iter().all(|v| n[0] * v[0] + n[1] * v[1] <= c) {
                        continue;
                    }
                    cell = clip(&cell, n, c);
                }
                cell
            })
            .collect()
    }

    /// The power cells from the bucket grid's rings are those of clipping by every seed, to the
    /// bit: equal and unequal weights (radius ratios 1, 2 and 4, so some cells vanish), narrow
    /// dies (one a thousandth of a millimetre wide: a few buckets, found by the case fuzz), a
    /// seed on a corner and two coincident seeds; and their areas add up to the
    /// die's (to 1e-9 relative: a partition of the die, the coincident seeds' cell once).
    #[test]
    fn power_cells_from_rings_are_those_of_every_seed() {
        let mut empty = 0;
        let dies = [(1.0, Die { x: [0.0, 100.0], y: [0.0, 100.0] }), (2.0, Die { x: [-30.0, 70.0], y: [5.0, 45.0] }), (4.0, Die { x: [0.0, 300.0], y: [0.0, 20.0] }), (2.0, Die { x: [0.0, 1e-3], y: [0.0, 100.0] })];
        for (k, (ratio, die)) in dies.into_iter().enumerate() {
            let mut rng = Stream::new(7 + k as u64);
            let n = 600;
            let mut seeds: Vec<P> = (0..n).map(|_| [die.x[0] + die.width() * rng.unit(), die.y[0] + die.height() * rng.unit()]).collect();
            seeds[1] = [die.x[0], die.y[0]];
            seeds[3] = seeds[2];
            let radii = draw_radii(&mut rng, n, Sizes::Uniform { ratio });
            let w = weights(&die, &radii);
            // (a die far narrower than a seed's share gets one column, not millions of buckets)
            let buckets = Buckets::new(&die, &seeds);
            assert!(buckets.cols * buckets.rows <= 3 * n + 1, "die {k}: {} × {} buckets for {n} seeds", buckets.cols, buckets.rows);
            let fast = power_cells(&die, &seeds, &w);
            let all = power_cells_by_all(&die, &seeds, &w);
            for (i, (a, b)) in fast.iter().zip(&all).enumerate() {
                assert!(a.len() == b.len() && a.iter().zip(b).all(|(u, v)| u[0].to_bits() == v[0].to_bits() && u[1].to_bits() == v[1].to_bits()), "die {k}, cell {i}: {a:?} against {b:?}");
            }
            // (the coincident seeds 2 and 3 each get the cell of the heavier: counted once)
            let lighter = if w[2] >= w[3] { 3 } else { 2 };
            let area: f64 = fast.iter().enumerate().filter(|&(i, _)| i != lighter).map(|(_, c)| area_centroid(c).0).sum();
            assert!((area - die.area()).abs() <= 1e-9 * die.area(), "die {k}: the cells cover {area}, the die {}", die.area());
            empty += fast.iter().filter(|c| area_centroid(c).0 <= 0.0).count();
        }
        assert!(empty > 0, "some cell vanished (the heavy weights' case is tested)");
    }

    #[test]
    fn counts_by_largest_remainder() {
        assert_eq!(material_counts(10, &[0.5, 0.5]), vec![5, 5]);
        assert_eq!(material_counts(10, &[1.0, 1.0, 1.0]), vec![4, 3, 3]);
        assert_eq!(material_counts(7, &[0.2, 0.8]), vec![1, 6]);
        assert_eq!(material_counts(3, &[1.0]), vec![3]);
    }

    #[test]
    fn clipping_a_square() {
        let sq = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let half = clip(&sq, [1.0, 0.0], 0.5);
        let (a, c) = area_centroid(&half);
        assert!((a - 0.5).abs() < 1e-15 && (c[0] - 0.25).abs() < 1e-15 && (c[1] - 0.5).abs() < 1e-15);
    }

    #[test]
    fn simplify_drops_short_sides_and_stays_inside() {
        let mut p = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 0.98], [0.99, 1.0], [0.0, 1.0]];
        simplify(&mut p);
        assert_eq!(p.len(), 4);
    }
}
