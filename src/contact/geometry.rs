//! Pair geometry: the gap g, the projection parameter ξ and their variations for a slave node
//! against a straight master segment ([`SegmentGeometry`]), a smoothed master surface
//! ([`SmoothGeometry`], the curve itself in [`super::smooth`]) or a rigid wall
//! ([`WallGeometry`]). This is the middle layer of the contact (search → geometry →
//! enforcement): it knows nothing of penalties, multipliers or friction laws, which
//! [`super::enforce`] applies to what it computes.
//!
//! # Signs and the tangential gap
//! Master segment `1 → 2` with the master body on its LEFT: tangent t = (x₂ − x₁)/ℓ, outward
//! normal n = (t_y, −t_x); ξ = (x_s − x₁)·t/ℓ (no clipping: choosing the segment is the pair
//! selection's job); gap g = (x_s − x₁)·n, positive open, negative penetration. The tangential
//! gap from an anchor ξ_a is g_T = (ξ − ξ_a) ℓ (a wall: g_T = s − s_a with s the node's
//! coordinate along the wall, so ℓ = 1).
//!
//! # The variations a pair geometry provides ([`Linearised`])
//! With N dofs (slave first, then the master's nodes), for an enforcement whose internal force
//! is f = A(−p δg + t_T δg_T):
//! - δg (the direction of the normal force) and dg (the full gradient of g; the two differ only
//!   for the smoothed surface, whose force is taken at fixed end angles);
//! - d(δg), the geometric stiffness of the normal force;
//! - δg_T, dg_T and d(δg_T) of the tangential gap.
//!
//! The straight-segment formulas (Wriggers, *Computational Contact Mechanics*, 2nd ed.,
//! §9.1–9.3; Laursen, *Computational Contact and Impact Mechanics*, ch. 5), dofs
//! `[s_x, s_y, 1_x, 1_y, 2_x, 2_y]`, with
//! N = [n, −(1−ξ) n, −ξ n], T = [t, −(1−ξ) t, −ξ t], N₀ = [0, −n, n], D₀ = [0, −t, t]:
//! ∇g = N; ∇∇g = −(1/ℓ)[T⊗N₀ + N₀⊗T + (g/ℓ) N₀⊗N₀]; ∇g_T = G_T = T + (g/ℓ) N₀ + (ξ − ξ_a) D₀;
//! ∇∇g_T = (1/ℓ)[N⊗N₀ + N₀⊗N] − (g/ℓ²)[D₀⊗N₀ + N₀⊗D₀] + ((ξ − ξ_a)/ℓ) N₀⊗N₀.
//! A rigid flat wall has δg = n, δg_T = t and no second variations.
//!
//! The methods add their terms in a fixed order with fixed-size arrays (no allocation), so an
//! enforcement gives the same bits whichever way it is called.

use super::smooth::{self, Master, NDOF};

type V6 = [f64; 6];
type M6 = [[f64; 6]; 6];

#[inline]
fn dot2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

#[inline]
fn add_outer6(k: &mut M6, c: f64, a: &V6, b: &V6) {
    for i in 0..6 {
        let ca = c * a[i];
        for j in 0..6 {
            k[i][j] += ca * b[j];
        }
    }
}

#[inline]
fn add_outer2(k: &mut [[f64; 2]; 2], c: f64, a: [f64; 2], b: [f64; 2]) {
    for i in 0..2 {
        for j in 0..2 {
            k[i][j] += c * a[i] * b[j];
        }
    }
}

/// The geometry of a pair at one configuration, before any enforcement: what decides whether
/// the pair is in contact, and the linearisation once it is.
pub trait PairGeometry<const N: usize> {
    type Linear: Linearised<N>;
    /// Whether the pair has a geometry at all (a degenerate segment, a smoothed surface without
    /// a closest point, a wall without a normal: the pair is then inactive).
    fn valid(&self) -> bool;
    /// Signed normal gap g (mm), negative = penetration.
    fn gap(&self) -> f64;
    /// Projection parameter ξ (a wall: the tangential coordinate s, mm).
    fn xi(&self) -> f64;
    /// Outward unit normal of the master at the projection (zero for a degenerate pair).
    fn normal(&self) -> [f64; 2];
    /// The variations with the tangential gap measured from `anchor` (ξ_a, or s_a for a
    /// wall); `None` when they do not exist (the smoothed projection lost its minimum).
    fn linearise(&self, anchor: f64) -> Option<Self::Linear>;
}

/// The variations of a pair's gaps (see the module docs); every method adds to (`add_`) or
/// overwrites (`set_`) fixed-size arrays in a fixed order.
pub trait Linearised<const N: usize> {
    /// Tangential gap g_T from the anchor (mm).
    fn tangential_gap(&self) -> f64;
    /// The metric ℓ of g_T = (ξ − ξ_a) ℓ (a wall: 1).
    fn length(&self) -> f64;
    /// δg, the direction of the normal force.
    fn grad(&self) -> [f64; N];
    /// dg, the full gradient of the gap.
    fn grad_full(&self) -> [f64; N];
    /// f = c δg.
    fn set_normal_force(&self, f: &mut [f64; N], c: f64);
    /// K = a δg⊗dg − b d(δg) (a = ε_N A, b = p_N A).
    fn set_normal_tangent(&self, k: &mut [[f64; N]; N], a: f64, b: f64);
    /// f += c δg_T.
    fn add_tangential_force(&self, f: &mut [f64; N], c: f64);
    /// K += c d(δg_T).
    fn add_tangential_geometric(&self, k: &mut [[f64; N]; N], c: f64);
    /// K += c δg_T⊗dg_T (stick).
    fn add_stick(&self, k: &mut [[f64; N]; N], c: f64);
    /// K += c δg_T⊗dg (slip: the tangential traction follows the pressure).
    fn add_slip(&self, k: &mut [[f64; N]; N], c: f64);
}

// ---------------------------------------------------------------------------------------------
// Straight master segment
// ---------------------------------------------------------------------------------------------

/// Kinematics of a slave node against a master segment (see the module docs for the signs).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct NtsGeometry {
    /// Projection parameter ξ = (x_s − x₁)·t/ℓ of the closest point on the infinite master line
    /// (in [0, 1] on the segment, outside otherwise; no clipping).
    pub xi: f64,
    /// Signed normal gap g = (x_s − x̄)·n, negative = penetration (mm).
    pub gap: f64,
    /// Outward unit normal of the master body n = (t_y, −t_x).
    pub normal: [f64; 2],
    /// Unit tangent t = (x₂ − x₁)/ℓ.
    pub tangent: [f64; 2],
    /// Current master segment length ℓ (mm).
    pub length: f64,
}

/// Closest point projection of the slave node `xs` on the line through the master segment
/// `x1 → x2` (master body on the left). A degenerate segment (ℓ not positive and finite) returns
/// `gap = +∞`, `length = 0`, zero normal and tangent, `xi = 0.5`: the pair is inactive.
pub fn nts_project(xs: [f64; 2], x1: [f64; 2], x2: [f64; 2]) -> NtsGeometry {
    let d = [x2[0] - x1[0], x2[1] - x1[1]];
    let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
    if !(len > 0.0 && len.is_finite()) {
        return NtsGeometry { xi: 0.5, gap: f64::INFINITY, normal: [0.0; 2], tangent: [0.0; 2], length: 0.0 };
    }
    let t = [d[0] / len, d[1] / len];
    let n = [t[1], -t[0]];
    let r = [xs[0] - x1[0], xs[1] - x1[1]];
    NtsGeometry { xi: dot2(r, t) / len, gap: dot2(r, n), normal: n, tangent: t, length: len }
}

/// A slave node against a straight master segment: the projection, and the 6-vectors N, T,
/// N₀, D₀ of its variations (dofs `[s, 1, 2]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentGeometry {
    pub projection: NtsGeometry,
}

impl SegmentGeometry {
    pub fn new(xs: [f64; 2], x1: [f64; 2], x2: [f64; 2]) -> Self {
        Self { projection: nts_project(xs, x1, x2) }
    }
}

/// [`SegmentGeometry`] linearised about an anchor.
#[derive(Clone, Copy, Debug)]
pub struct SegmentLinear {
    gap: f64,
    xi: f64,
    xa: f64,
    l: f64,
    nn: V6,
    tt: V6,
    n0: V6,
    d0: V6,
}

impl SegmentLinear {
    /// G_T = T + (g/ℓ) N₀ + (ξ − ξ_a) D₀.
    fn gtv(&self) -> V6 {
        let (g, l) = (self.gap, self.l);
        let mut gtv = [0.0; 6];
        for i in 0..6 {
            gtv[i] = self.tt[i] + (g / l) * self.n0[i] + (self.xi - self.xa) * self.d0[i];
        }
        gtv
    }
}

impl PairGeometry<6> for SegmentGeometry {
    type Linear = SegmentLinear;
    fn valid(&self) -> bool {
        self.projection.gap.is_finite()
    }
    fn gap(&self) -> f64 {
        self.projection.gap
    }
    fn xi(&self) -> f64 {
        self.projection.xi
    }
    fn normal(&self) -> [f64; 2] {
        self.projection.normal
    }
    fn linearise(&self, anchor: f64) -> Option<SegmentLinear> {
        let NtsGeometry { xi, gap, normal: n, tangent: t, length: l } = self.projection;
        Some(SegmentLinear {
            gap,
            xi,
            xa: anchor,
            l,
            nn: [n[0], n[1], -(1.0 - xi) * n[0], -(1.0 - xi) * n[1], -xi * n[0], -xi * n[1]],
            tt: [t[0], t[1], -(1.0 - xi) * t[0], -(1.0 - xi) * t[1], -xi * t[0], -xi * t[1]],
            n0: [0.0, 0.0, -n[0], -n[1], n[0], n[1]],
            d0: [0.0, 0.0, -t[0], -t[1], t[0], t[1]],
        })
    }
}

impl Linearised<6> for SegmentLinear {
    fn tangential_gap(&self) -> f64 {
        (self.xi - self.xa) * self.l
    }
    fn length(&self) -> f64 {
        self.l
    }
    fn grad(&self) -> V6 {
        self.nn
    }
    fn grad_full(&self) -> V6 {
        self.nn
    }
    fn set_normal_force(&self, f: &mut V6, c: f64) {
        for i in 0..6 {
            f[i] = c * self.nn[i];
        }
    }
    /// K = ε_N A N⊗N + (p A/ℓ)[T⊗N₀ + N₀⊗T + (g/ℓ) N₀⊗N₀].
    fn set_normal_tangent(&self, k: &mut M6, a: f64, b: f64) {
        *k = [[0.0; 6]; 6];
        add_outer6(k, a, &self.nn, &self.nn);
        let cg = b / self.l;
        add_outer6(k, cg, &self.tt, &self.n0);
        add_outer6(k, cg, &self.n0, &self.tt);
        add_outer6(k, cg * self.gap / self.l, &self.n0, &self.n0);
    }
    fn add_tangential_force(&self, f: &mut V6, c: f64) {
        let gtv = self.gtv();
        for i in 0..6 {
            f[i] += c * gtv[i];
        }
    }
    /// K += c H_T, H_T = (1/ℓ)[N⊗N₀ + N₀⊗N] − (g/ℓ²)[D₀⊗N₀ + N₀⊗D₀] + ((ξ − ξ_a)/ℓ) N₀⊗N₀.
    fn add_tangential_geometric(&self, k: &mut M6, c: f64) {
        let (g, l) = (self.gap, self.l);
        add_outer6(k, c / l, &self.nn, &self.n0);
        add_outer6(k, c / l, &self.n0, &self.nn);
        add_outer6(k, -c * g / (l * l), &self.d0, &self.n0);
        add_outer6(k, -c * g / (l * l), &self.n0, &self.d0);
        add_outer6(k, c * (self.xi - self.xa) / l, &self.n0, &self.n0);
    }
    fn add_stick(&self, k: &mut M6, c: f64) {
        let gtv = self.gtv();
        add_outer6(k, c, &gtv, &gtv);
    }
    fn add_slip(&self, k: &mut M6, c: f64) {
        add_outer6(k, c, &self.gtv(), &self.nn);
    }
}

// ---------------------------------------------------------------------------------------------
// Smoothed master surface
// ---------------------------------------------------------------------------------------------

/// A slave node against the smoothed master surface of a segment (see [`super::smooth`]):
/// dofs `[s, 1, 2, 0, 3]` (the segment's neighbours last; an absent neighbour's entries are
/// zero).
#[derive(Clone, Copy, Debug)]
pub struct SmoothGeometry {
    xs: [f64; 2],
    master: Master,
    projection: Option<smooth::SmoothProjection>,
}

impl SmoothGeometry {
    pub fn new(xs: [f64; 2], master: &Master) -> Self {
        let projection = smooth::smooth_project(xs, master);
        if projection.is_none() {
            tracing::debug!(?xs, ?master, "smoothed contact: no closest point on the master surface, pair inactive");
        }
        Self { xs, master: *master, projection }
    }
}

/// [`SmoothGeometry`] linearised about an anchor: the variations at fixed end angles (the
/// force) and in full (the tangent) of g and g_T, from exact second-order derivatives.
#[derive(Clone, Copy, Debug)]
pub struct SmoothLinear {
    gt: f64,
    l: f64,
    gv: [f64; NDOF],
    gf: [f64; NDOF],
    gh: [[f64; NDOF]; NDOF],
    tv: [f64; NDOF],
    tf: [f64; NDOF],
    th: [[f64; NDOF]; NDOF],
}

impl PairGeometry<NDOF> for SmoothGeometry {
    type Linear = SmoothLinear;
    fn valid(&self) -> bool {
        self.projection.is_some()
    }
    fn gap(&self) -> f64 {
        self.projection.map_or(f64::INFINITY, |p| p.gap)
    }
    fn xi(&self) -> f64 {
        self.projection.map_or(0.5, |p| p.xi)
    }
    fn normal(&self) -> [f64; 2] {
        self.projection.map_or([0.0; 2], |p| p.normal)
    }
    fn linearise(&self, anchor: f64) -> Option<SmoothLinear> {
        let p = self.projection?;
        let Some(v) = smooth::variations(self.xs, &self.master, p.xi, anchor) else {
            tracing::debug!(xs = ?self.xs, master = ?self.master, "smoothed contact: projection lost its minimum, pair inactive");
            return None;
        };
        Some(SmoothLinear { gt: v.gt, l: p.length, gv: v.gv, gf: v.gf, gh: v.gh, tv: v.tv, tf: v.tf, th: v.th })
    }
}

impl Linearised<NDOF> for SmoothLinear {
    fn tangential_gap(&self) -> f64 {
        self.gt
    }
    fn length(&self) -> f64 {
        self.l
    }
    fn grad(&self) -> [f64; NDOF] {
        self.gv
    }
    fn grad_full(&self) -> [f64; NDOF] {
        self.gf
    }
    fn set_normal_force(&self, f: &mut [f64; NDOF], c: f64) {
        for i in 0..NDOF {
            f[i] = c * self.gv[i];
        }
    }
    fn set_normal_tangent(&self, k: &mut [[f64; NDOF]; NDOF], a: f64, b: f64) {
        for i in 0..NDOF {
            for j in 0..NDOF {
                k[i][j] = a * self.gv[i] * self.gf[j] - b * self.gh[i][j];
            }
        }
    }
    fn add_tangential_force(&self, f: &mut [f64; NDOF], c: f64) {
        for i in 0..NDOF {
            f[i] += c * self.tv[i];
        }
    }
    fn add_tangential_geometric(&self, k: &mut [[f64; NDOF]; NDOF], c: f64) {
        for i in 0..NDOF {
            for j in 0..NDOF {
                k[i][j] += c * self.th[i][j];
            }
        }
    }
    fn add_stick(&self, k: &mut [[f64; NDOF]; NDOF], c: f64) {
        for i in 0..NDOF {
            for j in 0..NDOF {
                k[i][j] += c * self.tv[i] * self.tf[j];
            }
        }
    }
    fn add_slip(&self, k: &mut [[f64; NDOF]; NDOF], c: f64) {
        for i in 0..NDOF {
            for j in 0..NDOF {
                k[i][j] += c * self.tv[i] * self.gf[j];
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Rigid wall
// ---------------------------------------------------------------------------------------------

/// A rigid straight wall at the current time.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Wall {
    /// A point on the wall line at the current time (mm).
    pub point: [f64; 2],
    /// Unit normal pointing INTO the domain (towards the particles); normalised by the kernel.
    pub normal: [f64; 2],
}

impl Wall {
    /// Unit tangent of the wall, t = (−n_y, n_x), chosen so that n = (t_y, −t_x) exactly as for a
    /// master segment (the wall's solid on the left of t). For a bottom wall (n = +y) t = −x;
    /// for a left wall (n = +x) t = +y.
    pub fn tangent(&self) -> [f64; 2] {
        let n = unit(self.normal);
        [-n[1], n[0]]
    }
}

/// `v` normalised (zero stays zero).
pub(crate) fn unit(v: [f64; 2]) -> [f64; 2] {
    let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
    if l > 0.0 {
        [v[0] / l, v[1] / l]
    } else {
        [0.0, 0.0]
    }
}

/// A node against a rigid wall: g = (x − point)·n, and its coordinate along the wall in the
/// wall's material frame s = x·t − d (d the wall's tangential displacement, see
/// [`super::enforce::wall_pair`]). Dofs `[x, y]` of the node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallGeometry {
    pub gap: f64,
    pub s: f64,
    pub n: [f64; 2],
    pub t: [f64; 2],
}

impl WallGeometry {
    pub fn new(x: [f64; 2], wall: &Wall, wall_displacement_tangential: f64) -> Self {
        let n = unit(wall.normal);
        let t = [-n[1], n[0]];
        let gap = dot2([x[0] - wall.point[0], x[1] - wall.point[1]], n);
        let s = dot2(x, t) - wall_displacement_tangential;
        Self { gap, s, n, t }
    }
}

/// [`WallGeometry`] about an anchor s_a.
#[derive(Clone, Copy, Debug)]
pub struct WallLinear {
    gt: f64,
    n: [f64; 2],
    t: [f64; 2],
}

impl PairGeometry<2> for WallGeometry {
    type Linear = WallLinear;
    fn valid(&self) -> bool {
        self.gap.is_finite() && self.n != [0.0, 0.0]
    }
    fn gap(&self) -> f64 {
        self.gap
    }
    fn xi(&self) -> f64 {
        self.s
    }
    fn normal(&self) -> [f64; 2] {
        self.n
    }
    fn linearise(&self, anchor: f64) -> Option<WallLinear> {
        Some(WallLinear { gt: self.s - anchor, n: self.n, t: self.t })
    }
}

impl Linearised<2> for WallLinear {
    fn tangential_gap(&self) -> f64 {
        self.gt
    }
    fn length(&self) -> f64 {
        1.0
    }
    fn grad(&self) -> [f64; 2] {
        self.n
    }
    fn grad_full(&self) -> [f64; 2] {
        self.n
    }
    fn set_normal_force(&self, f: &mut [f64; 2], c: f64) {
        *f = [c * self.n[0], c * self.n[1]];
    }
    /// A flat rigid wall has no geometric stiffness: K = ε_N A n⊗n.
    fn set_normal_tangent(&self, k: &mut [[f64; 2]; 2], a: f64, _b: f64) {
        *k = [[0.0; 2]; 2];
        add_outer2(k, a, self.n, self.n);
    }
    fn add_tangential_force(&self, f: &mut [f64; 2], c: f64) {
        f[0] += c * self.t[0];
        f[1] += c * self.t[1];
    }
    fn add_tangential_geometric(&self, _k: &mut [[f64; 2]; 2], _c: f64) {}
    fn add_stick(&self, k: &mut [[f64; 2]; 2], c: f64) {
        add_outer2(k, c, self.t, self.t);
    }
    fn add_slip(&self, k: &mut [[f64; 2]; 2], c: f64) {
        add_outer2(k, c, self.t, self.n);
    }
}
