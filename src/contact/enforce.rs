//! Enforcement: the contact laws applied to a pair's geometry ([`super::geometry`]) — the
//! normal law of the penalty and augmented-Lagrangian methods, Coulomb friction and ties, the
//! Uzawa update, and the force and tangent of a Lagrange multiplier. The top layer of the
//! contact (search → geometry → enforcement): the kernels here read only a geometry record
//! and a pair history, never a mesh or a node number.
//!
//! # Conventions (signs)
//!
//! * **Pressure** p_N ≥ 0 in compression (MPa). The augmented-Lagrangian multiplier λ_N
//!   ([`PairHistory::lambda_n`]) uses the **same sign**: λ_N ≥ 0 is a compressive pressure, and
//!   p_N = max(0, λ_N − ε_N g) (bilateral for [`ContactKind::Cohering`]: p_N = λ_N − ε_N g, which
//!   may be negative = tension).
//! * **Tangential gap** (elastic slip from the stick anchor, measured with the current metric)
//!   g_T = (ξ − ξ_a) ℓ, and the **shear** (tangential traction, MPa) conjugate to it:
//!   t_T = λ_T + ε_T g_T in stick, t_T = μ p_N sign(t_T^trial) in slip. Positive t_T resists a
//!   positive g_T (the slave moved along +t from the anchor).
//! * **Residual convention**: the kernels return the contact contribution to the INTERNAL force,
//!   f_c, so that the driver forms R = F_ext − F_int − f_c and adds K_c = ∂f_c/∂x to the tangent.
//!   With A the tributary length of the slave node (force = pressure · A, N/mm):
//!
//!   f_c = A (−p_N δg + t_T δg_T),
//!
//!   i.e. the contact force on the slave node is A (p_N n − t_T t) (pushes it out of the master
//!   body) and the master nodes receive the reaction. Without friction f_c = ∂Π/∂x of the
//!   penalty potential Π = A(λ_N(−g) + ½ ε_N g²) on the active set, so the frictionless tangent
//!   is symmetric (straight segments and walls); in slip it is not (Coulomb is non-associative).
//!
//! Differentiating f_c: K_c = A [−δg⊗dp_N − p_N d(δg) + δg_T⊗dt_T + t_T d(δg_T)], with
//! dp_N = −ε_N dg (active) and dt_T = ε_T dg_T (stick) or dt_T = μ sign dp_N (slip).
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
//! With augmentation ([`augment`]) the driver, after a converged Newton solve, sets λ_N ← p_N,
//! λ_T ← t_T (Uzawa) and solves again; it stops when the largest violation (penetration, and the
//! elastic stick slip) is below a tolerance. Each update reduces the penetration by the factor
//! k/(k + ε_N A) for a pair of local structural stiffness k, so moderate penalties converge in a
//! few updates to a small penetration.
//!
//! # Lagrange multipliers
//!
//! With `method = "lagrange"` the pressure λ is an unknown of the system: the pair's force is
//! −λ A δg (the penalty kernel with ε = 0 and λ as its multiplier gives it, with the geometric
//! stiffness −λ A d(δg)) and its constraint row is A dg (see [`lagrange_row`] and
//! [`super::problem::Multipliers`]).

use super::geometry::{Linearised, PairGeometry, SegmentGeometry, SmoothGeometry, Wall, WallGeometry};
use super::smooth::{Master, NDOF};
use serde::{Deserialize, Serialize};

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
    /// the tangential coordinate s_a (mm) of the anchor in the wall's own frame (see
    /// [`wall_pair`]). Meaningful only when `active`.
    pub xi_stick: f64,
    /// Augmented-Lagrangian normal multiplier λ_N, a pressure in MPa, **≥ 0 in compression**
    /// (same sign as [`PairResult::pressure`]; negative only for a cohering pair in tension).
    pub lambda_n: f64,
    /// Augmented-Lagrangian tangential multiplier λ_T, a shear traction in MPa, same sign as
    /// [`PairResult::shear`].
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

/// What an enforcement gives for one pair, over the geometry's N dofs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairResult<const N: usize> {
    /// Contact contribution to the internal force, f_c = A(−p_N δg + t_T δg_T) (N/mm).
    pub f: [f64; N],
    /// K_c = ∂f_c/∂x (N/mm²); row i, column j = ∂f_i/∂x_j. Non-symmetric in slip (and for the
    /// smoothed surface).
    pub k: [[f64; N]; N],
    /// Normal gap g (mm), negative = penetration (+∞ without a geometry).
    pub gap: f64,
    /// Projection parameter ξ (a wall: the tangential coordinate s, mm).
    pub xi: f64,
    /// The master's outward normal at the projection.
    pub normal: [f64; 2],
    /// δg and dg of an active pair (see [`Linearised::grad`]); zero otherwise.
    pub grad: [f64; N],
    pub grad_full: [f64; N],
    /// Contact pressure p_N (MPa), ≥ 0 in compression (negative only for cohering in tension).
    pub pressure: f64,
    /// Shear traction t_T (MPa) conjugate to g_T.
    pub shear: f64,
    /// Coulomb slip occurred (return mapping active).
    pub slip: bool,
    /// The pair carries force (p_N > 0, or cohering).
    pub active: bool,
    /// History to commit if this state is accepted without augmentation.
    pub new_history: PairHistory,
}

impl<const N: usize> PairResult<N> {
    /// An inactive pair at gap `gap`, parameter `xi`: no force, its history reset at ξ.
    fn inactive(gap: f64, xi: f64, normal: [f64; 2]) -> Self {
        Self {
            f: [0.0; N],
            k: [[0.0; N]; N],
            gap,
            xi,
            normal,
            grad: [0.0; N],
            grad_full: [0.0; N],
            pressure: 0.0,
            shear: 0.0,
            slip: false,
            active: false,
            new_history: PairHistory { xi_stick: xi, lambda_n: 0.0, lambda_t: 0.0, active: false },
        }
    }
}

/// Which tangential law applies (decides dt_T): none, stick (dt_T = ε_T dg_T), or slip with
/// the signed coefficient μ·sign(t_trial) (dt_T = μ sign dp_N).
pub(crate) enum TangLaw {
    None,
    Stick,
    Slip(f64),
}

/// `v > 0` (false for NaN).
#[inline]
fn positive(v: f64) -> bool {
    v > 0.0
}

/// The friction law: (t_T, law) given the trial traction t = λ_T + ε_T g_T and the pressure
/// p_N; `fresh` (no anchor yet) means no tangential force.
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

/// The penalty / augmented-Lagrangian laws on a pair of any geometry, `area` the slave node's
/// tributary length (mm; forces are pressure · area, N/mm):
/// * normal: p_N = max(0, λ_N − ε_N g) (`Sliding`, `Rubbing`), p_N = λ_N − ε_N g (`Cohering`);
///   unilateral pairs with p_N ≤ 0 are inactive (f = 0, K = 0) — with λ_N = 0 that is g ≥ 0;
/// * tangential (`Rubbing`, `Cohering`, only if `old.active`): g_T from the anchor ξ_a =
///   `old.xi_stick`; trial t = λ_T + ε_T g_T; `Rubbing` sticks if |t| ≤ μ p_N, else slips with
///   t_T = μ p_N sign(t) and the anchor moved by the return mapping
///   ξ_a' = ξ − (t_T − λ_T)/(ε_T ℓ); `Cohering` always sticks.
pub fn evaluate<const N: usize, G: PairGeometry<N>>(geo: &G, area: f64, kind: ContactKind, params: &PenaltyParams, old: &PairHistory) -> PairResult<N> {
    let (gap, xi, normal) = (geo.gap(), geo.xi(), geo.normal());
    let inactive = || PairResult::inactive(gap, xi, normal);
    if !geo.valid() {
        return inactive();
    }
    let cohering = matches!(kind, ContactKind::Cohering);
    let p = old.lambda_n - params.eps_n * gap;
    if !cohering && !positive(p) {
        return inactive();
    }
    let fresh = !old.active || !positive(params.eps_t);
    let anchor0 = if fresh { xi } else { old.xi_stick };
    let Some(lin) = geo.linearise(anchor0) else {
        return inactive();
    };
    let l = lin.length();
    let t_trial = old.lambda_t + params.eps_t * lin.tangential_gap();
    let (tau, law) = friction_law(kind, fresh, t_trial, p);
    let mut anchor = anchor0;
    let lambda_t = if fresh { 0.0 } else { old.lambda_t };

    let mut out = inactive();
    lin.set_normal_force(&mut out.f, -p * area);
    lin.set_normal_tangent(&mut out.k, params.eps_n * area, p * area);
    match law {
        TangLaw::None => {
            if !fresh && !cohering {
                // frictionless: keep tracking the current projection
                anchor = xi;
            }
        }
        TangLaw::Stick | TangLaw::Slip(_) => {
            lin.add_tangential_force(&mut out.f, tau * area);
            lin.add_tangential_geometric(&mut out.k, tau * area);
            match law {
                TangLaw::Stick => lin.add_stick(&mut out.k, params.eps_t * area),
                TangLaw::Slip(smu) => {
                    // dt_T = μ sign dp_N = −μ sign ε_N dg (non-symmetric)
                    lin.add_slip(&mut out.k, -smu * params.eps_n * area);
                    anchor = xi - (tau - lambda_t) / (params.eps_t * l);
                    out.slip = true;
                }
                TangLaw::None => {}
            }
        }
    }
    out.grad = lin.grad();
    out.grad_full = lin.grad_full();
    out.pressure = p;
    out.shear = tau;
    out.active = true;
    out.new_history = PairHistory { xi_stick: anchor, lambda_n: old.lambda_n, lambda_t, active: true };
    out
}

/// A slave node `xs` against the straight master segment `x1 → x2` (master body on the left),
/// dofs `[s_x, s_y, 1_x, 1_y, 2_x, 2_y]` ([`evaluate`] on a [`SegmentGeometry`]).
pub fn segment_pair(xs: [f64; 2], x1: [f64; 2], x2: [f64; 2], area: f64, kind: ContactKind, params: &PenaltyParams, old: &PairHistory) -> PairResult<6> {
    evaluate(&SegmentGeometry::new(xs, x1, x2), area, kind, params, old)
}

/// A slave node `xs` against the smoothed master surface `m`, dofs
/// `[s_x, s_y, 1_x, 1_y, 2_x, 2_y, 0_x, 0_y, 3_x, 3_y]` (an absent neighbour's entries are zero;
/// [`evaluate`] on a [`SmoothGeometry`]).
pub fn smooth_pair(xs: [f64; 2], m: &Master, area: f64, kind: ContactKind, params: &PenaltyParams, old: &PairHistory) -> PairResult<NDOF> {
    evaluate(&SmoothGeometry::new(xs, m), area, kind, params, old)
}

/// A node `x` against a rigid wall, dofs `[x, y]` ([`evaluate`] on a [`WallGeometry`]): the
/// tangential coordinate is s = x·t − d in the wall's material frame, with t =
/// [`Wall::tangent`] and d = `wall_displacement_tangential` the wall's tangential displacement
/// along t from a fixed reference (only its change since the anchor was set matters); g_T =
/// s − s_a. A flat rigid wall has no geometric stiffness; the slip return mapping is
/// s_a' = s − (t_T − λ_T)/ε_T.
pub fn wall_pair(x: [f64; 2], wall: &Wall, wall_displacement_tangential: f64, area: f64, kind: ContactKind, params: &PenaltyParams, old: &PairHistory) -> PairResult<2> {
    evaluate(&WallGeometry::new(x, wall, wall_displacement_tangential), area, kind, params, old)
}

/// Uzawa update of a pair after a converged solve: λ_N ← p_N, λ_T ← t_T.
///
/// In stick (and for cohering pairs) the anchor is kept, so repeated updates drive both the
/// penetration −g and the elastic slip g_T to zero; in slip the anchor moves to the current
/// projection ξ, so λ_T alone reproduces the slip traction there. An inactive pair is reset
/// (λ = 0, not active). The driver loops "solve → augment" until the largest violation is
/// below its tolerance, then commits the step.
pub fn augment<const N: usize>(out: &PairResult<N>) -> PairHistory {
    if !out.active {
        return PairHistory { xi_stick: out.xi, lambda_n: 0.0, lambda_t: 0.0, active: false };
    }
    PairHistory { xi_stick: if out.slip { out.xi } else { out.new_history.xi_stick }, lambda_n: out.pressure, lambda_t: out.shear, active: true }
}

/// Constraint violation of one active pair (mm): the penetration (for a tie, the normal gap
/// either way), and for tied or sticking pairs the elastic tangential slip |t_T − λ_T| / ε_T.
/// The augmented Lagrangian drives the largest one below its tolerance.
pub fn violation(kind: ContactKind, gap: f64, shear: f64, slip: bool, old: &PairHistory, eps_t: f64) -> f64 {
    let normal = if matches!(kind, ContactKind::Cohering) { gap.abs() } else { (-gap).max(0.0) };
    let tangential = match kind {
        ContactKind::Sliding => 0.0,
        _ if slip || !old.active || !(eps_t > 0.0) => 0.0,
        _ => ((shear - old.lambda_t) / eps_t).abs(),
    };
    normal.max(tangential)
}

/// A Lagrange multiplier's constraint row: with the pressure λ (MPa), the scale c (MPa/mm, the
/// default penalty) and the regularisation r, the complementarity φ = min(λ, c g) = 0 is
/// written per evaluation as (the system's unknown being λ/c, rows scaled by c):
/// - active (λ − c g > 0): row c·F = −c A (g + r λ / c), its derivatives −c A dg (by x) and
///   −r c A (by λ/c): the perturbed Lagrangian g + r λ/c = 0;
/// - inactive: row c·F = −A λ, derivative −c A (by λ/c): drives λ to zero.
///
/// Returns (active, row value, its derivative by the unknown λ/c).
pub fn lagrange_row(lambda: f64, gap: f64, area: f64, c: f64, r: f64) -> (bool, f64, f64) {
    let active = lambda - c * gap > 0.0;
    let row = if active { -c * area * gap - r * area * lambda } else { -area * lambda };
    let diagonal = if active { -r * c * area } else { -c * area };
    (active, row, diagonal)
}
