//! Contact pair kernels: gap, normal, slip, contact force and consistent tangent of one
//! node-to-segment pair or one node-to-rigid-wall pair.
//!
//! The kernels are pure functions of the current coordinates and of the pair history of the last
//! converged state; they never allocate (fixed-size arrays only), never print and never panic on
//! bad geometry (a degenerate segment gives an inactive pair).
//!
//! # Conventions (signs)
//!
//! * **Master segment** `1 → 2` with the master body on its LEFT (see
//!   [`Segment`](super::Segment)): tangent t = (x₂ − x₁)/ℓ, ℓ = |x₂ − x₁|, outward normal
//!   n = (t_y, −t_x) = (Δy, −Δx)/ℓ.
//! * **Projection** of the slave node x_s on the (infinite) master line:
//!   ξ = (x_s − x₁)·t/ℓ, x̄ = x₁ + ξ (x₂ − x₁) (ξ ∈ [0, 1] on the segment; the kernels do not clip,
//!   choosing the segment is the driver's job).
//! * **Normal gap** g = (x_s − x̄)·n = (x_s − x₁)·n: positive = open, **negative = penetration**.
//! * **Pressure** p_N ≥ 0 in compression (MPa). The augmented-Lagrangian multiplier λ_N
//!   ([`PairHistory::lambda_n`]) uses the **same sign**: λ_N ≥ 0 is a compressive pressure, and
//!   p_N = max(0, λ_N − ε_N g) (bilateral for [`ContactKind::Cohering`]: p_N = λ_N − ε_N g, which
//!   may be negative = tension).
//! * **Tangential gap** (elastic slip from the stick anchor ξ_a, measured with the current metric)
//!   g_T = (ξ − ξ_a) ℓ, and the **shear** (tangential traction, MPa) conjugate to it:
//!   t_T = λ_T + ε_T g_T in stick, t_T = μ p_N sign(t_T^trial) in slip. Positive t_T resists a
//!   positive g_T (the slave moved along +t from the anchor).
//! * **Residual convention**: the kernels return the contact contribution to the INTERNAL force,
//!   f_c, so that the driver forms R = F_ext − F_int − f_c and adds K_c = ∂f_c/∂x to the tangent.
//!   With A the tributary length of the slave node (force = pressure · A, N/mm):
//!
//!   f_c = A (−p_N ∇g + t_T ∇g_T),
//!
//!   i.e. the contact force acting on the slave node is A (p_N n − t_T t) (pushes it out of the
//!   master body) and the master nodes receive the reaction, split (1 − ξ, ξ).
//!   Without friction f_c = ∂Π/∂x of the penalty potential Π = A(λ_N(−g) + ½ ε_N g²) on the active
//!   set, so the frictionless tangent is symmetric; in slip it is not (Coulomb is non-associative).
//!
//! # Node-to-segment linearisation (Wriggers, *Computational Contact Mechanics*, 2nd ed., §9.1–9.3
//! for the 2D node-to-segment element; Laursen, *Computational Contact and Impact Mechanics*, ch. 5)
//!
//! Dof order `[s_x, s_y, 1_x, 1_y, 2_x, 2_y]`. With δd = δx₂ − δx₁ define the 6-vectors
//!
//! * N  = [ n, −(1−ξ) n, −ξ n ]   (∇g),
//! * T  = [ t, −(1−ξ) t, −ξ t ],
//! * N₀ = [ 0, −n, n ]            (so n·δd = N₀·δx),
//! * D₀ = [ 0, −t, t ]            (∇ℓ, since δℓ = t·δd).
//!
//! In 2D δt = n (n·δd)/ℓ and δn = −t (n·δd)/ℓ, which give
//!
//! * ∇g = N (the terms from δn and δξ cancel because x̄ is the closest point),
//! * ∇ξ = (T + (g/ℓ) N₀)/ℓ,
//! * ∇∇g = −(1/ℓ)[T⊗N₀ + N₀⊗T + (g/ℓ) N₀⊗N₀]   (Wriggers' geometric NTS matrix),
//! * ∇g_T = G_T = T + (g/ℓ) N₀ + (ξ − ξ_a) D₀,
//! * ∇∇g_T = H_T = (1/ℓ)[N⊗N₀ + N₀⊗N] − (g/ℓ²)[D₀⊗N₀ + N₀⊗D₀] + ((ξ − ξ_a)/ℓ) N₀⊗N₀.
//!
//! Differentiating f_c = A(−p_N N + t_T G_T):
//!
//! K_c = A [ −N⊗∇p_N − p_N ∇∇g + G_T⊗∇t_T + t_T H_T ],  with ∇p_N = −ε_N N (active) and
//! ∇t_T = ε_T G_T (stick) or ∇t_T = μ sign(t_T^trial) ∇p_N = −μ sign ε_N N (slip).
//! The first two terms are the "gap" (material) stiffness ε_N A N⊗N and the geometric stiffness
//! (p_N A/ℓ)[T⊗N₀ + N₀⊗T + (g/ℓ) N₀⊗N₀]; the slip term A G_T⊗(−μ sign ε_N N) is the
//! non-symmetric part.
//!
//! # Friction history and Uzawa augmentation
//!
//! The pair history stores the stick anchor ξ_a, the multipliers λ_N, λ_T and whether the pair was
//! active at the last converged state. If the pair was NOT active (first contact), the anchor is
//! the current projection, so g_T ≡ 0 and there is no tangential force or stiffness for that step
//! (friction/tying starts at the next step). A driver that wants the tie/stick to start at the
//! projection of the start of the step seeds `xi_stick` with it and sets `active = true`.
//!
//! Slip is a return mapping: the anchor is moved to ξ_a' = ξ − (t_T − λ_T)/(ε_T ℓ), so that the
//! trial law evaluated at the current configuration with the new anchor gives exactly the slip
//! traction. Committing a converged step without augmentation means history ← `new_history`.
//!
//! With augmentation ([`augment`], [`augment_wall`]) the driver, after a converged Newton solve,
//! sets λ_N ← p_N, λ_T ← t_T (Uzawa) and solves again; it stops when the largest penetration
//! (−g over the active pairs, and the elastic stick slip |g_T|) is below a tolerance. Each update
//! reduces the penetration by the factor k/(k + ε_N A) for a pair of local structural stiffness k,
//! so moderate penalties converge in a few updates to a small penetration.

use serde::{Deserialize, Serialize};

type V6 = [f64; 6];
type M6 = [[f64; 6]; 6];

/// `v > 0` (false for NaN).
#[inline]
fn positive(v: f64) -> bool {
    v > 0.0
}

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
/// `gap = +∞`, `length = 0`, zero normal and tangent, `xi = 0.5`: the kernels treat it as inactive.
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

/// The paper's three contact types.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ContactKind {
    /// Frictionless, unilateral.
    Sliding,
    /// Coulomb friction with coefficient μ, unilateral (μ ≤ 0 behaves as `Sliding`).
    Rubbing { mu: f64 },
    /// Tied: sticks in both tangential directions and resists separation (bilateral normal law,
    /// tension allowed).
    Cohering,
}

/// History of one contact pair at the last converged (or last augmented) state.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct PairHistory {
    /// Stick anchor. Node-to-segment: the master parameter ξ_a (dimensionless). Node-to-wall:
    /// the tangential coordinate s_a (mm) of the anchor in the wall's own frame (see [`node_wall`]).
    /// Meaningful only when `active`.
    pub xi_stick: f64,
    /// Augmented-Lagrangian normal multiplier λ_N, a pressure in MPa, **≥ 0 in compression**
    /// (same sign as [`PairOut::pressure`]; negative only for a cohering pair in tension).
    pub lambda_n: f64,
    /// Augmented-Lagrangian tangential multiplier λ_T, a shear traction in MPa, same sign as
    /// [`PairOut::shear`].
    pub lambda_t: f64,
    /// Whether the pair was in contact (or tied) at that state.
    pub active: bool,
}

/// Penalty parameters (MPa/mm): pressure per mm of penetration, shear per mm of elastic slip.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PenaltyParams {
    /// ε_N, normal pressure per mm of penetration (MPa/mm).
    pub eps_n: f64,
    /// ε_T, tangential traction per mm of elastic (stick) slip (MPa/mm).
    pub eps_t: f64,
}

/// Default penalties from the softer body's Young's modulus `e_min` (MPa) and the element size
/// `h` (mm): ε_N = ε_T = 10 E/h.
///
/// Rationale: a contact layer of stiffness E/h per unit area is as stiff as one element row of
/// the softer body; ten times that keeps the penetration at g ≈ p h/(10 E), i.e. the penetration
/// strain p/(10E) is a tenth of the bulk strain p/E under the same pressure, while the condition
/// number of the tangent grows only by ≈ 10. Larger factors reduce penetration linearly but
/// worsen conditioning; use [`augment`] (Uzawa) instead to drive the penetration to a tolerance.
/// The same value for ε_T makes the reversible stick slip ≈ t_T h/(10 E).
pub fn default_penalty(e_min: f64, h: f64) -> PenaltyParams {
    let eps = 10.0 * e_min / h;
    PenaltyParams { eps_n: eps, eps_t: eps }
}

/// Output of [`nts_pair`]. Dofs `[s_x, s_y, 1_x, 1_y, 2_x, 2_y]`.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct PairOut {
    /// Contact contribution to the internal force, f_c = A(−p_N ∇g + t_T ∇g_T) (N/mm).
    pub f: [f64; 6],
    /// K_c = ∂f_c/∂x (N/mm²); row i, column j = ∂f_i/∂x_j. Non-symmetric in slip.
    pub k: [[f64; 6]; 6],
    /// Normal gap g (mm), negative = penetration.
    pub gap: f64,
    /// Projection parameter ξ of the slave node on the master line.
    pub xi: f64,
    /// Contact pressure p_N (MPa), ≥ 0 in compression (negative only for cohering in tension).
    pub pressure: f64,
    /// Shear traction t_T (MPa) conjugate to g_T (see the module docs).
    pub shear: f64,
    /// Coulomb slip occurred (return mapping active).
    pub slip: bool,
    /// The pair carries force (p_N > 0, or cohering).
    pub active: bool,
    /// History to commit if this state is accepted without augmentation.
    pub new_history: PairHistory,
}

/// Which tangential law applies (decides ∇t_T): none, stick (∇t_T = ε_T ∇g_T), or slip with
/// the signed coefficient μ·sign(t_trial) (∇t_T = μ sign ∇p_N).
pub(crate) enum TangLaw {
    None,
    Stick,
    Slip(f64),
}

/// Friction law shared by both kernels: returns (t_T, law) given the trial traction
/// t = λ_T + ε_T g_T and the pressure p_N; `fresh` (no anchor yet) means no tangential force.
pub(crate) fn friction_law(kind: ContactKind, fresh: bool, t_trial: f64, p: f64) -> (f64, TangLaw) {
    match kind {
        ContactKind::Sliding => (0.0, TangLaw::None),
        ContactKind::Rubbing { mu } if !positive(mu) => (0.0, TangLaw::None),
        _ if fresh => (0.0, TangLaw::None),
        ContactKind::Cohering => (t_trial, TangLaw::Stick),
        ContactKind::Rubbing { mu } => {
            let lim = mu * p;
            if t_trial.abs() <= lim {
                (t_trial, TangLaw::Stick)
            } else {
                let s = if t_trial > 0.0 { 1.0 } else { -1.0 };
                (s * lim, TangLaw::Slip(s * mu))
            }
        }
    }
}

/// Node-to-segment pair: slave node `xs`, master segment `x1 → x2` (master body on the left).
///
/// Laws (see the module docs for signs and the tangent):
/// * normal: p_N = max(0, λ_N − ε_N g) (`Sliding`, `Rubbing`), p_N = λ_N − ε_N g (`Cohering`);
///   unilateral pairs with p_N ≤ 0 are inactive (f = 0, K = 0) — with λ_N = 0 that is g ≥ 0;
/// * tangential (`Rubbing`, `Cohering`, only if `old.active`): g_T = (ξ − ξ_a) ℓ with the anchor
///   ξ_a = `old.xi_stick` and the current length ℓ; trial t = λ_T + ε_T g_T; `Rubbing` sticks if
///   |t| ≤ μ p_N, else slips with t_T = μ p_N sign(t) and the anchor moved by the return mapping
///   ξ_a' = ξ − (t_T − λ_T)/(ε_T ℓ); `Cohering` always sticks.
///
/// `area` is the slave node's tributary length (mm); forces are pressure · area (N/mm).
#[allow(clippy::too_many_arguments)]
pub fn nts_pair(
    xs: [f64; 2],
    x1: [f64; 2],
    x2: [f64; 2],
    area: f64,
    kind: ContactKind,
    params: &PenaltyParams,
    old: &PairHistory,
    out: &mut PairOut,
) {
    let geo = nts_project(xs, x1, x2);
    out.f = [0.0; 6];
    out.k = [[0.0; 6]; 6];
    out.gap = geo.gap;
    out.xi = geo.xi;
    out.pressure = 0.0;
    out.shear = 0.0;
    out.slip = false;
    out.active = false;
    let inactive_history = PairHistory { xi_stick: geo.xi, lambda_n: 0.0, lambda_t: 0.0, active: false };
    if !geo.gap.is_finite() {
        out.new_history = inactive_history;
        return;
    }
    let cohering = matches!(kind, ContactKind::Cohering);
    let g = geo.gap;
    let p = old.lambda_n - params.eps_n * g;
    if !cohering && !positive(p) {
        out.new_history = inactive_history;
        return;
    }

    let (n, t, l, xi) = (geo.normal, geo.tangent, geo.length, geo.xi);
    let nn: V6 = [n[0], n[1], -(1.0 - xi) * n[0], -(1.0 - xi) * n[1], -xi * n[0], -xi * n[1]];
    let tt: V6 = [t[0], t[1], -(1.0 - xi) * t[0], -(1.0 - xi) * t[1], -xi * t[0], -xi * t[1]];
    let n0: V6 = [0.0, 0.0, -n[0], -n[1], n[0], n[1]];
    let d0: V6 = [0.0, 0.0, -t[0], -t[1], t[0], t[1]];

    // Normal part: f = −p A N; K = ε_N A N⊗N + (p A/ℓ)[T⊗N₀ + N₀⊗T + (g/ℓ) N₀⊗N₀].
    let mut f = [0.0; 6];
    for i in 0..6 {
        f[i] = -p * area * nn[i];
    }
    let mut k = [[0.0; 6]; 6];
    add_outer6(&mut k, params.eps_n * area, &nn, &nn);
    let cg = p * area / l;
    add_outer6(&mut k, cg, &tt, &n0);
    add_outer6(&mut k, cg, &n0, &tt);
    add_outer6(&mut k, cg * g / l, &n0, &n0);

    // Tangential part.
    let fresh = !old.active || !positive(params.eps_t);
    let xa = old.xi_stick;
    let gt = (xi - xa) * l;
    let t_trial = old.lambda_t + params.eps_t * gt;
    let (tau, law) = friction_law(kind, fresh, t_trial, p);
    let mut anchor = if fresh { xi } else { xa };
    let lambda_t = if fresh { 0.0 } else { old.lambda_t };
    match law {
        TangLaw::None => {
            if !fresh && !matches!(kind, ContactKind::Cohering) {
                // Frictionless: keep tracking the current projection.
                anchor = xi;
            }
        }
        TangLaw::Stick | TangLaw::Slip(_) => {
            // G_T = T + (g/ℓ) N₀ + (ξ − ξ_a) D₀
            let mut gtv = [0.0; 6];
            for i in 0..6 {
                gtv[i] = tt[i] + (g / l) * n0[i] + (xi - xa) * d0[i];
            }
            for i in 0..6 {
                f[i] += tau * area * gtv[i];
            }
            // t_T H_T, H_T = (1/ℓ)[N⊗N₀ + N₀⊗N] − (g/ℓ²)[D₀⊗N₀ + N₀⊗D₀] + ((ξ−ξ_a)/ℓ) N₀⊗N₀
            let c = tau * area;
            add_outer6(&mut k, c / l, &nn, &n0);
            add_outer6(&mut k, c / l, &n0, &nn);
            add_outer6(&mut k, -c * g / (l * l), &d0, &n0);
            add_outer6(&mut k, -c * g / (l * l), &n0, &d0);
            add_outer6(&mut k, c * (xi - xa) / l, &n0, &n0);
            match law {
                TangLaw::Stick => add_outer6(&mut k, params.eps_t * area, &gtv, &gtv),
                TangLaw::Slip(smu) => {
                    // ∇t_T = μ sign ∇p_N = −μ sign ε_N N (non-symmetric)
                    add_outer6(&mut k, -smu * params.eps_n * area, &gtv, &nn);
                    anchor = xi - (tau - lambda_t) / (params.eps_t * l);
                    out.slip = true;
                }
                TangLaw::None => {}
            }
        }
    }

    out.f = f;
    out.k = k;
    out.pressure = p;
    out.shear = tau;
    out.active = true;
    out.new_history = PairHistory { xi_stick: anchor, lambda_n: old.lambda_n, lambda_t, active: true };
}

/// Uzawa update of a node-to-segment pair after a converged solve: λ_N ← p_N, λ_T ← t_T.
///
/// In stick (and for cohering pairs) the anchor is kept, so repeated updates drive both the
/// penetration −g and the elastic slip g_T to zero; in slip the anchor moves to the current
/// projection ξ, so λ_T alone reproduces the slip traction there. An inactive pair is reset
/// (λ = 0, not active). The driver loops "solve → augment" until max(−g) over the active pairs
/// (and |g_T| of the sticking ones) is below its penetration tolerance, then commits the step.
/// The update depends only on `out`; `old` is the history the solve used (kept for symmetry with
/// the kernels and for drivers that compare the two).
pub fn augment(old: &PairHistory, out: &PairOut) -> PairHistory {
    let _ = old;
    if !out.active {
        return PairHistory { xi_stick: out.xi, lambda_n: 0.0, lambda_t: 0.0, active: false };
    }
    PairHistory {
        xi_stick: if out.slip { out.xi } else { out.new_history.xi_stick },
        lambda_n: out.pressure,
        lambda_t: out.shear,
        active: true,
    }
}

/// A rigid straight wall at the current time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wall {
    /// A point on the wall line at the current time (mm).
    pub point: [f64; 2],
    /// Unit normal pointing INTO the domain (towards the particles); normalised by the kernel.
    pub normal: [f64; 2],
}

impl Wall {
    /// Unit tangent of the wall, t = (−n_y, n_x), chosen so that n = (t_y, −t_x) exactly as for a
    /// master [`Segment`](super::Segment) (the wall's solid on the left of t). For a bottom wall
    /// (n = +y) t = −x; for a left wall (n = +x) t = +y.
    pub fn tangent(&self) -> [f64; 2] {
        let n = unit(self.normal);
        [-n[1], n[0]]
    }
}

fn unit(v: [f64; 2]) -> [f64; 2] {
    let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
    if l > 0.0 {
        [v[0] / l, v[1] / l]
    } else {
        [0.0, 0.0]
    }
}

/// Output of [`node_wall`]. Dofs `[x, y]` of the node.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct WallOut {
    /// Contact contribution to the internal force, f_c = A(−p_N n + t_T t) (N/mm).
    pub f: [f64; 2],
    /// K_c = ∂f_c/∂x (N/mm²).
    pub k: [[f64; 2]; 2],
    /// Normal gap g = (x − point)·n (mm), negative = penetration.
    pub gap: f64,
    /// Tangential coordinate of the node in the wall's frame, s = x·t − d (mm).
    pub s: f64,
    /// Pressure p_N (MPa), ≥ 0 in compression.
    pub pressure: f64,
    /// Shear traction t_T (MPa), conjugate to g_T = s − s_a.
    pub shear: f64,
    pub slip: bool,
    pub active: bool,
    pub new_history: PairHistory,
}

/// Node-to-rigid-wall pair. Same laws as [`nts_pair`] with the wall as master:
///
/// * g = (x − point)·n (n unit, into the domain), p_N = max(0, λ_N − ε_N g) (bilateral for
///   `Cohering`);
/// * tangential coordinate in the wall's material frame s = x·t − d, with t = [`Wall::tangent`]
///   and d = `wall_displacement_tangential`, the wall's tangential displacement along t measured
///   from a fixed reference (the driver may pass the cumulative value since the start of the
///   analysis: only its change since the anchor was set matters, because the anchor s_a is stored
///   in the same wall frame); g_T = s − s_a with s_a = `old.xi_stick` (mm);
/// * f_c = A(−p_N n + t_T t), K_c = ε_N A n⊗n + A t⊗∇t_T with ∇t_T = ε_T t (stick) or
///   −μ sign ε_N n (slip, non-symmetric). A flat rigid wall has no geometric stiffness.
/// * slip return mapping: s_a' = s − (t_T − λ_T)/ε_T.
#[allow(clippy::too_many_arguments)]
pub fn node_wall(
    x: [f64; 2],
    wall: &Wall,
    wall_displacement_tangential: f64,
    area: f64,
    kind: ContactKind,
    params: &PenaltyParams,
    old: &PairHistory,
    out: &mut WallOut,
) {
    let n = unit(wall.normal);
    let t = [-n[1], n[0]];
    let g = dot2([x[0] - wall.point[0], x[1] - wall.point[1]], n);
    let s = dot2(x, t) - wall_displacement_tangential;
    out.f = [0.0; 2];
    out.k = [[0.0; 2]; 2];
    out.gap = g;
    out.s = s;
    out.pressure = 0.0;
    out.shear = 0.0;
    out.slip = false;
    out.active = false;
    let inactive_history = PairHistory { xi_stick: s, lambda_n: 0.0, lambda_t: 0.0, active: false };
    let cohering = matches!(kind, ContactKind::Cohering);
    let p = old.lambda_n - params.eps_n * g;
    if !g.is_finite() || n == [0.0, 0.0] || (!cohering && !positive(p)) {
        out.new_history = inactive_history;
        return;
    }
    let mut f = [-p * area * n[0], -p * area * n[1]];
    let mut k = [[0.0; 2]; 2];
    add_outer2(&mut k, params.eps_n * area, n, n);

    let fresh = !old.active || !positive(params.eps_t);
    let sa = old.xi_stick;
    let t_trial = old.lambda_t + params.eps_t * (s - sa);
    let (tau, law) = friction_law(kind, fresh, t_trial, p);
    let mut anchor = if fresh { s } else { sa };
    let lambda_t = if fresh { 0.0 } else { old.lambda_t };
    match law {
        TangLaw::None => {
            if !fresh && !cohering {
                anchor = s;
            }
        }
        TangLaw::Stick => {
            f[0] += tau * area * t[0];
            f[1] += tau * area * t[1];
            add_outer2(&mut k, params.eps_t * area, t, t);
        }
        TangLaw::Slip(smu) => {
            f[0] += tau * area * t[0];
            f[1] += tau * area * t[1];
            add_outer2(&mut k, -smu * params.eps_n * area, t, n);
            anchor = s - (tau - lambda_t) / params.eps_t;
            out.slip = true;
        }
    }
    out.f = f;
    out.k = k;
    out.pressure = p;
    out.shear = tau;
    out.active = true;
    out.new_history = PairHistory { xi_stick: anchor, lambda_n: old.lambda_n, lambda_t, active: true };
}

/// Uzawa update of a node-to-wall pair (see [`augment`]): λ_N ← p_N, λ_T ← t_T; the anchor is kept
/// in stick and moved to the current s in slip; inactive pairs are reset.
pub fn augment_wall(old: &PairHistory, out: &WallOut) -> PairHistory {
    let _ = old;
    if !out.active {
        return PairHistory { xi_stick: out.s, lambda_n: 0.0, lambda_t: 0.0, active: false };
    }
    PairHistory {
        xi_stick: if out.slip { out.s } else { out.new_history.xi_stick },
        lambda_n: out.pressure,
        lambda_t: out.shear,
        active: true,
    }
}
