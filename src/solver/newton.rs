//! The Newton solve of a step: full or modified Newton–Raphson with a backtracking line
//! search on the residual and the energy, the convergence tests, the loops of the
//! augmented-Lagrangian updates (incompressible elements and contact multipliers) around it,
//! the linearised predictor of a first step, the barrier's double step at a double root, and
//! the release of an out-of-balance force in increments (a re-meshed state).

use super::{NewtonFailure, Simulation, Trial};
use crate::assembly::FIXED;
use crate::element::Volumetric;
use crate::material::TimeIncrement;
use crate::solver::NewtonKind;

/// The curvature constant c₂ of the barrier's line search (strong Wolfe): the slope of the
/// potential at the end of an accepted step is at most c₂ times its slope at the start.
const WOLFE_CURVATURE: f64 = 0.9;
/// The sufficient-decrease constant c₁ of the barrier's line search (Armijo).
const ARMIJO: f64 = 1e-4;

/// The contact's part E_c of the incremental potential (the barrier and the lagged friction)
/// and its slope ∇E_c·Δu at the start of a line search (`energy0`, `slope0`) and at the step
/// tried. The trapezoidal rule is exact for a quadratic only; the barrier's Hessian jumps
/// where a closest point passes an edge's end and grows like 1/d² towards contact, and the
/// friction's is μλ/ε_v in stick and zero in slip, so across such a change its estimate can
/// call an ascent a descent. Both energies are known in closed form, so the line search
/// takes their change exactly.
#[derive(Clone, Copy, Debug)]
struct BarrierLine {
    energy0: f64,
    slope0: f64,
    energy: f64,
    slope: f64,
}

/// Whether a step η along a Newton update decreases the incremental potential Π enough (the
/// barrier's line search once the walls have arrived): with g0 = −Π′(0) = R(u₀)·Δu and
/// `slope` = −Π′(η) = R(u₀ + ηΔu)·Δu (R = −∇Π), Armijo's sufficient decrease on the change of
/// Π estimated by the trapezoidal rule, −½η(g0 + slope) ≤ −c₁ η g0 (with `barrier`, the
/// barrier's part of Π exactly and the rest by the trapezoidal rule), and the far side of the
/// strong Wolfe curvature condition, −slope ≤ c₂ g0. The curvature condition rejects a step
/// that lands as steeply uphill as it left, an overshoot across a valley which the trapezoidal
/// estimate rates as no change at all: accepting it let Newton jump back and forth between
/// the valley's sides where the Hessian jumps (a node passing an edge's end, a friction pair
/// between stick and slip), a cycle of period two that held the residual at 1e-3 for 20
/// iterations (robustness case 02, measured).
fn barrier_descent(eta: f64, g0: f64, slope: f64, barrier: Option<BarrierLine>) -> bool {
    let change = potential_change(eta, g0, slope, barrier);
    g0 > 0.0 && change <= -ARMIJO * eta * g0 && slope >= -WOLFE_CURVATURE * g0
}

/// The change of the incremental potential along a step η as the line search estimates it:
/// with `barrier`, the contact's part exactly and the trapezoidal rule on the rest only;
/// without, the trapezoidal rule on the whole (see [`barrier_descent`] for the slopes).
fn potential_change(eta: f64, g0: f64, slope: f64, barrier: Option<BarrierLine>) -> f64 {
    match barrier {
        Some(b) => (b.energy - b.energy0) - 0.5 * eta * ((g0 + b.slope0) + (slope + b.slope)),
        None => -0.5 * eta * (g0 + slope),
    }
}

/// Whether the change of the incremental potential along a step η, as [`barrier_descent`]
/// estimates it, is below the round-off of the barrier's energy (a relative 1e-10 of it):
/// near convergence the barrier's own change is a difference of two large sums and says
/// nothing, and a step that does not raise the residual is taken on that instead.
fn within_round_off(eta: f64, g0: f64, slope: f64, barrier: Option<BarrierLine>) -> bool {
    barrier.is_some_and(|b| potential_change(eta, g0, slope, barrier).abs() <= 1e-10 * b.energy0.abs().max(b.energy.abs()))
}

/// The factor of the update tried first at a double root ([`double_root`]).
const DOUBLE_STEP: f64 = 2.0;

/// Whether a Newton update Δu_k (`dd` = Δu_k·Δu_k) is half the last one Δu_{k−1}, both taken
/// whole with the walls arrived (`dp` = Δu_k·Δu_{k−1}, `pp` = Δu_{k−1}·Δu_{k−1}): nearly the
/// same direction (a cosine of at least 0.95) and 0.35–0.65 of its length. That is Newton at a
/// double root, where the error halves each iteration, and the update twice over lands on the
/// root (Newton's step for a root of multiplicity m is m times the plain one).
///
/// The barrier makes such roots wherever a particle rests on nothing but the barrier: a loose
/// particle that a wall or a neighbour pushes, with nothing behind it, is in equilibrium only
/// where the barrier's force is zero, at the gap d̂, and IPC's barrier
/// −κ(d − d̂)² ln(d/d̂) ≈ κ d̂ s³ (s = 1 − d/d̂) has a force of order s² and a stiffness of
/// order s there. Measured on robustness case 01 (16 polygons, loose): every step before the
/// packing carried load took 16–17 iterations, the residual quartering and the update halving
/// from the third on.
fn double_root(dd: f64, dp: f64, pp: f64) -> bool {
    if !(pp > 0.0 && dd > 0.0) {
        return false;
    }
    let c = dp / pp;
    // |Δu_k − c Δu_{k−1}|² = dd − c² pp: the part of the update off the last one's line
    (0.35..=0.65).contains(&c) && dd - c * c * pp <= 0.1 * dd
}

/// Whether the relative residuals of the last three iterations fell by a quarter twice in a
/// row (0.2–0.3 of the one before): the residual's signature of a double root (a force of
/// order s² at an error s that halves), seen where a few particles' loose motion that does not
/// change the residual keeps the updates from halving as a whole.
fn quartered(residuals: &[f64]) -> bool {
    let n = residuals.len();
    n >= 3 && (0.2..=0.3).contains(&(residuals[n - 1] / residuals[n - 2])) && (0.2..=0.3).contains(&(residuals[n - 2] / residuals[n - 3]))
}

/// How far through the step the walls are at a step η of a Newton update that started with
/// them at `alpha0` (they move with the update the same fraction of the rest of their way),
/// snapped to 1 (arrived) within round-off.
fn wall_progress(alpha0: f64, eta: f64) -> f64 {
    let a = alpha0 + eta * (1.0 - alpha0);
    if a >= 1.0 - 1e-12 {
        1.0
    } else {
        a
    }
}

/// The rigid rotation a Newton update makes of one particle: the update's best-fit rotation
/// θ about the particle's centroid c (least squares over its nodes).
#[derive(Clone, Copy, Debug)]
struct BodyTurn {
    nodes: (usize, usize),
    centre: [f64; 2],
    theta: f64,
}

/// Below this best-fit rotation (rad) an update is taken along a straight line: the
/// linearised rotation's change of area, θ², is then at round-off.
const TURN_MIN: f64 = 1e-6;

/// The particle a Newton update moves furthest (see `Simulation::largest_update`).
struct LargestUpdate {
    body: usize,
    /// the largest nodal update (mm)
    largest: f64,
    /// the particle's mean translation (mm)
    translation: f64,
    /// its best-fit turn (rad)
    turn: f64,
    /// the largest nodal update less the translation and the linearised turn (mm)
    deformation: f64,
}

/// The centroid c of nodes at `x0` + `u` (dofs interleaved) and the rotation θ about it that
/// fits the update `du` best in the least-squares sense: θ = Σ r × Δu / Σ |r|² (the mean
/// translation drops out since Σ r = 0).
fn best_fit_turn(x0: &[[f64; 2]], u: &[f64], du: &[f64]) -> ([f64; 2], f64) {
    let n = x0.len() as f64;
    let mut c = [0.0; 2];
    for (k, p) in x0.iter().enumerate() {
        for i in 0..2 {
            c[i] += p[i] + u[2 * k + i];
        }
    }
    let c = [c[0] / n, c[1] / n];
    let (mut num, mut den) = (0.0, 0.0);
    for (k, p) in x0.iter().enumerate() {
        let r = [p[0] + u[2 * k] - c[0], p[1] + u[2 * k + 1] - c[1]];
        num += r[0] * du[2 * k + 1] - r[1] * du[2 * k];
        den += r[0] * r[0] + r[1] * r[1];
    }
    (c, if den > 0.0 { num / den } else { 0.0 })
}

/// A particle's update `du` from `u` (its nodes at `x0`, dofs interleaved) split into its
/// mean translation t, its best-fit turn θ about the centroid ([`best_fit_turn`]) and the
/// largest nodal remainder |Δu − t − θ J r|, its deformation (J the quarter turn, r the node's
/// position from the centroid).
fn rigid_split(x0: &[[f64; 2]], u: &[f64], du: &[f64]) -> ([f64; 2], f64, f64) {
    let n = x0.len().max(1) as f64;
    let (c, turn) = best_fit_turn(x0, u, du);
    let t = [du.iter().step_by(2).sum::<f64>() / n, du.iter().skip(1).step_by(2).sum::<f64>() / n];
    let deformation = x0
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let r = [p[0] + u[2 * k] - c[0], p[1] + u[2 * k + 1] - c[1]];
            (du[2 * k] - t[0] + turn * r[1]).hypot(du[2 * k + 1] - t[1] - turn * r[0])
        })
        .fold(0.0f64, f64::max);
    (t, turn, deformation)
}

/// The point η of a Newton update Δu from u₀ in which every turning particle turns by ηθ
/// exactly (a finite rotation about its centroid) and the rest of its update, Δu less the
/// linearised rotation θ × r, is taken along a straight line:
/// `u(η) = u₀ + η (Δu − θ J r) + (R(ηθ) − I) r`, with r the node's position from the centroid
/// at u₀ and J the quarter turn. Its tangent `u′(η) = Δu − θ J r + θ J R(ηθ) r` equals Δu at
/// η = 0. Writes u(η) to `u` and u′(η) to `tangent` (every dof).
fn turned_point(x0: &[[f64; 2]], u0: &[f64], du: &[f64], turns: &[BodyTurn], eta: f64, u: &mut [f64], tangent: &mut [f64]) {
    for d in 0..u.len() {
        u[d] = u0[d] + eta * du[d];
        tangent[d] = du[d];
    }
    for t in turns {
        let (s, c) = (eta * t.theta).sin_cos();
        for n in t.nodes.0..t.nodes.1 {
            let r = [x0[n][0] + u0[2 * n] - t.centre[0], x0[n][1] + u0[2 * n + 1] - t.centre[1]];
            // linearised rotation θ J r and the exact one R(ηθ) r
            let lin = [-t.theta * r[1], t.theta * r[0]];
            let rot = [c * r[0] - s * r[1], s * r[0] + c * r[1]];
            for i in 0..2 {
                let d = 2 * n + i;
                u[d] = u0[d] + eta * (du[d] - lin[i]) + (rot[i] - r[i]);
            }
            tangent[2 * n] = du[2 * n] - lin[0] - t.theta * rot[1];
            tangent[2 * n + 1] = du[2 * n + 1] - lin[1] + t.theta * rot[0];
        }
    }
}

impl Simulation {
    /// Newton from `u` (prescribed dofs already at their values of `inc.time`), with the
    /// augmented-Lagrangian updates of the incompressible bodies and of the contact. With
    /// `restart`, a first guess that inverts an element is replaced once by the last converged
    /// solution.
    pub(super) fn solve_from(&mut self, mut u: Vec<f64>, inc: TimeIncrement, restart: bool) -> Result<Trial, NewtonFailure> {
        let t = inc.time;
        let mut lambda = self.sol.lambda.clone();
        let mut iterations = 0;
        let mut updates = 0;
        let mut first = true;
        // the out-of-balance force (N/mm) at which this solve stops for a friction update (0:
        // the solver's tolerance; see [`super::barrier::LAG_FORCING`])
        let forcing = self.barrier.as_ref().map_or(0.0, |b| b.lag_forcing);
        let largest = self.barrier.as_ref().filter(|b| b.has_friction()).map_or(0.0, |b| b.largest_friction());
        let mut loose = forcing * super::barrier::LAG_FIRST_CHANGE * self.sys.max(largest);
        // whether the lagged friction has contracted at every update of this step so far, and
        // the last update's largest change of μλ (N/mm)
        let mut settling = true;
        let mut last_change = f64::INFINITY;
        if let Some(b) = self.barrier.as_mut() {
            b.lag_ended = false;
        }
        loop {
            let vol = self.volumetric(&lambda);
            if let Some(b) = self.barrier.as_mut() {
                b.lag_tol = loose;
            }
            let result = self.newton(&mut u, inc, &vol);
            if let Some(b) = self.barrier.as_mut() {
                // (a solve that reached the solver's tolerance, the friction settled or not)
                if b.lag_tol == 0.0 {
                    loose = 0.0;
                }
                b.lag_tol = 0.0;
            }
            let (its, res) = match result {
                Ok(v) => v,
                Err(NewtonFailure::Element(e)) if first && restart => {
                    // the extrapolated guess inverted an element: restart from the last solution
                    tracing::debug!(%e, "prediction rejected");
                    first = false;
                    u.copy_from_slice(&self.sol.u);
                    self.model.loading.apply_prescribed(&mut u, t);
                    continue;
                }
                Err(e) => return Err(e),
            };
            first = false;
            iterations += its;
            // the fields of the other processes' elements (for the updates below and the commit)
            if let Some(p) = &self.sys.par {
                p.sync_fields(&mut self.sys.trial_fields);
            }
            // augmented Lagrangian on the element area of incompressible bodies
            let mut worst: f64 = 0.0;
            for e in 0..self.incompressible.len() {
                // (a part: its own elements, the others' are theirs)
                if self.incompressible[e] && self.sys.part.as_ref().is_none_or(|p| self.model.elem_body[e] < p.own_bodies) {
                    worst = worst.max((self.sys.trial_fields.theta[e] - 1.0).abs());
                }
            }
            let worst = self.sys.max(worst);
            let augment = self.contact.as_ref().is_some_and(|c| c.needs_augmentation(&self.contact_stats)) && updates < self.model.contact.max_augmentations;
            let friction = !augment && self.update_barrier_friction(&u, updates);
            let contact_update = augment || friction || self.update_barrier_ties(&u, updates);
            if !contact_update && loose > 0.0 {
                // the friction has settled on a solve stopped early: the last solve, from
                // there, to the solver's tolerance (the friction checked again after it)
                loose = 0.0;
                continue;
            }
            // (the early stops rest on the lagging's contraction: after an update that moved
            // the friction no less than the one before, the rest of the step's solves converge,
            // so that a cycle of the lagging is told as with converged solves, by its coming
            // back to the friction of two solves before)
            loose = 0.0;
            if let Some(b) = self.barrier.as_ref().filter(|_| friction) {
                settling &= b.lag_change < last_change;
                last_change = b.lag_change;
                if settling {
                    loose = forcing * b.lag_change;
                }
            }
            if contact_update {
                if let Some(c) = self.contact.as_mut() {
                    c.augment();
                }
            }
            if !contact_update && (worst <= self.spec.volume_tol || updates >= self.spec.max_volume_updates) {
                if worst > self.spec.volume_tol {
                    tracing::warn!(worst, tol = self.spec.volume_tol, "volume constraint not met after the allowed updates");
                }
                return Ok(Trial { u, lambda, worst, iterations, updates, residual: res });
            }
            for e in 0..self.incompressible.len() {
                if self.incompressible[e] {
                    lambda[e] = self.sys.trial_fields.pressure[e];
                }
            }
            updates += 1;
        }
    }

    /// Linearised step prediction from the committed state: with K the tangent at u_n,
    /// `K_ff Δu_f = F_ext(t_{n+1}) − F_int(u_n) − K_fc Δu_c`, where the coupling to the
    /// prescribed increments Δu_c is the directional derivative of F_int along Δu_c (a forward
    /// difference with a step of 1e-6 Δu_c: accurate to ~1e-6, plenty for a predictor).
    /// On entry `u` holds u_n on free dofs and the new prescribed values; on success the free
    /// dofs hold the prediction.
    pub(super) fn tangent_predictor(&mut self, u: &mut [f64], inc: TimeIncrement) -> Result<(), NewtonFailure> {
        let n_free = self.sys.assembler.n_free;
        if n_free == 0 {
            return Ok(());
        }
        let u_n = self.sol.u.clone();
        let du_c: Vec<f64> = u.iter().zip(&u_n).map(|(a, b)| a - b).collect();
        let vol = self.volumetric(&self.sol.lambda.clone());
        // K and F_int at u_n (with the loads of t_{n+1})
        self.evaluate(&u_n, inc, &vol, true)?;
        let f0 = self.sys.f_int.clone();
        let r0 = self.sys.r.clone(); // F_ext(t_{n+1}) − F_int(u_n) on free dofs
        self.factor()?;
        let eps = 1e-6;
        let u_eps: Vec<f64> = u_n.iter().zip(&du_c).map(|(a, d)| a + eps * d).collect();
        self.evaluate(&u_eps, inc, &vol, false)?;
        for (d, &q) in self.sys.assembler.eq.iter().enumerate() {
            if q != FIXED {
                self.sys.r[q] = r0[q] - (self.sys.f_int[d] - f0[d]) / eps;
            }
        }
        self.sys.du.iter_mut().for_each(|v| *v = 0.0);
        self.solve_update()?;
        for (d, &q) in self.sys.assembler.eq.iter().enumerate() {
            if q != FIXED {
                u[d] = u_n[d] + self.sys.du[q];
            }
        }
        Ok(())
    }

    /// Newton–Raphson at fixed multipliers. Returns (iterations, final relative residual).
    pub(super) fn newton(&mut self, u: &mut [f64], inc: TimeIncrement, vol: &[Volumetric]) -> Result<(usize, f64), NewtonFailure> {
        let full = matches!(self.spec.newton, NewtonKind::Full);
        let n_free = self.sys.assembler.n_free;
        let mut residuals = Vec::new();
        let mut rnorm = self.evaluate(u, inc, vol, true)?;
        // (a part: the free equations of every process)
        if self.sys.part.as_ref().map_or(n_free, |p| p.eqs.n_global()) == 0 {
            return Ok((0, 0.0));
        }
        self.factor_descent()?;
        let mut e0 = 0.0;
        let mut e_last = f64::INFINITY;
        let mut du_full = vec![0.0; u.len()];
        // the largest nodal change of the last whole Newton update (mm; before the line search)
        let mut last_update = f64::INFINITY;
        // the retry of a failed barrier step descends on the potential, and leaving a saddle
        // that way is progress the residual does not show (it grows while the iterate slides
        // off): it gets more iterations
        let max_iterations = if self.barrier.as_ref().is_some_and(|b| b.descent) { super::barrier::DESCENT_ITERATIONS * self.spec.max_iterations } else { self.spec.max_iterations };
        // how many updates in a row the collision-free step has cut below half
        let mut limited = 0;
        // how many updates in a row were taken whole with the walls arrived, and the last of
        // them (equation numbering), to tell a double root (see [`double_root`])
        let mut whole = 0;
        let mut last_whole: Vec<f64> = Vec::new();
        for k in 0..=max_iterations {
            // a stop asked for (a signal) abandons the step here, within one iteration
            self.check_interrupt()?;
            let reference = self.reference_force();
            let rel = rnorm / reference;
            residuals.push(rel);
            if tracing::enabled!(tracing::Level::DEBUG) {
                // where the largest out-of-balance force sits, to tell a stalled contact zone
                // from a global non-convergence
                let (mut worst_dof, mut worst) = (0, 0.0f64);
                for (d, &q) in self.sys.assembler.eq.iter().enumerate() {
                    if q != FIXED && self.sys.r[q].abs() > worst {
                        (worst_dof, worst) = (d, self.sys.r[q].abs());
                    }
                }
                let node = worst_dof / 2;
                let x = self.model.x0.get(node).map_or([f64::NAN; 2], |p| [p[0] + u[2 * node], p[1] + u[2 * node + 1]]);
                tracing::debug!(iteration = k, residual = rel, energy = e_last, active = self.contact_stats.active, worst_force = worst, worst_node = node, body = self.springs.node_body.get(node).copied().unwrap_or(0), x = ?x, "newton");
                if tracing::enabled!(tracing::Level::TRACE) {
                    if let Some(c) = &self.contact {
                        for line in c.describe_node(node, &self.coords(u)) {
                            tracing::trace!(node, "{line}");
                        }
                    }
                }
            }
            // (with the barrier the walls reach the particles during the solve: a residual of
            // zero at its start is no scale for divergence)
            let first = if self.barrier.is_some() { residuals.iter().copied().fold(0.0, f64::max) } else { residuals[0] };
            if !rnorm.is_finite() {
                return Err(NewtonFailure::NotFinite { iteration: k, cause: self.non_finite_cause() });
            }
            if k > 2 && rel > 1e8 * first.max(1e-300) {
                return Err(NewtonFailure::Diverged { iteration: k, residuals });
            }
            let floor = self.force_floor();
            let residual_ok = rnorm <= self.spec.residual_tol * reference || rnorm <= floor;
            let energy_ok = k > 0 && e_last <= self.spec.energy_tol * e0;
            // the energy test is relative to the first iteration of this solve, which is
            // itself at round-off when a step starts almost in equilibrium: a residual a
            // hundred times below its tolerance is then accepted on its own
            // (or once the residual, already within its tolerance, stops decreasing: the
            // round-off floor of the assembly has been reached)
            let tiny = rel <= 0.01 * self.spec.residual_tol || rnorm <= floor;
            let floor_reached = k >= 1 && rel >= 0.5 * residuals[k - 1];
            if residual_ok && (k == 0 || energy_ok || tiny || floor_reached) && self.walls_arrived() {
                self.converged_to_tolerance();
                return Ok((k, rel));
            }
            // a solve the lagged friction is to move on from stops well below that move
            // (and where the friction would not move, the solve goes on to the solver's
            // tolerance at once, with the tangent it has factored)
            if self.barrier.as_ref().is_some_and(|b| rnorm <= b.lag_tol) && self.walls_arrived() {
                if !self.friction_settled(u) {
                    return Ok((k, rel));
                }
                self.converged_to_tolerance();
            }
            // with the barrier, IPC's test on the Newton step as well: a residual within a
            // hundred times its tolerance and a whole Newton update below 1e-6 h. The barrier's
            // point–edge distance is C¹ only (its Hessian jumps where the closest point passes
            // an edge's end), and on a regular grid nodes face nodes exactly there: Newton
            // then circles the solution at a residual of 1e-8–1e-7 with updates of 1e-7 mm
            // (seen on the asphalt octagons of 5.2.1, h ≈ 10 mm)
            if let Some(b) = self.barrier.as_ref() {
                if k >= 2 && b.alpha >= 1.0 && rel <= 100.0 * self.spec.residual_tol && last_update <= 1e-6 * b.h_min {
                    self.converged_to_tolerance();
                    return Ok((k, rel));
                }
            }
            if k == max_iterations {
                break;
            }
            // solve K Δu = R (with the barrier, R includes the walls' remaining motion)
            self.sys.du.iter_mut().for_each(|v| *v = 0.0);
            let r_true = self.barrier.is_some().then(|| self.sys.r.clone());
            self.add_wall_motion();
            self.solve_update()?;
            let halved = (whole >= 1 && double_root(self.sys.dot(&self.sys.du, &self.sys.du), self.sys.dot(&self.sys.du, &last_whole), self.sys.dot(&last_whole, &last_whole)))
                || (whole >= 2 && quartered(&residuals));
            let energy = self.sys.dot(&self.sys.du, &self.sys.r).abs();
            // with the barrier: the slope of the incremental potential along the update is
            // −R(u)·Δu (R = −∇Π), positive g0 = R·Δu for a descent direction
            let g0 = r_true.as_ref().map_or(0.0, |r| self.sys.dot(&self.sys.du, r));
            if k == 0 {
                e0 = energy.max(f64::MIN_POSITIVE);
            }
            e_last = energy;
            for (d, &q) in self.sys.assembler.eq.iter().enumerate() {
                du_full[d] = if q != FIXED { self.sys.du[q] } else { 0.0 };
            }
            if tracing::enabled!(tracing::Level::DEBUG) {
                // which particle the update moves most, and how: rigidly (a loose particle
                // with little to hold it) or by deforming (docs/robustness.md, thirty-second
                // measurement)
                if let Some(m) = self.largest_update(&u[..], &du_full) {
                    tracing::debug!(body = m.body, largest = m.largest, translation = m.translation, turn = m.turn, deformation = m.deformation, "largest update");
                }
            }
            // line search: backtrack while the residual grows or an element fails
            let u0: Vec<f64> = u.to_vec();
            let line_search = self.spec.line_search;
            if let Some(c) = self.contact.as_mut() {
                c.lm.mark();
            }
            // with the barrier the step starts at the largest collision-free fraction of the
            // update (the walls moving with it) and may back off further
            let barrier = self.barrier.is_some();
            // particles the update turns are turned exactly along the line search (a
            // linearised rotation θ × r changes a particle's area by θ², against its bulk
            // stiffness); `tangent` is the path's direction at the point tried (the update
            // itself where nothing turns)
            let turns = if self.barrier.as_ref().is_some_and(|b| b.turn) { self.body_turns(&u0, &du_full) } else { Vec::new() };
            // (a part: whether a particle turns on any process, so that all take the same path
            // through the line search; a process without turns takes straight lines on it)
            let turning = self.sys.any(!turns.is_empty());
            let mut tangent = du_full.clone();
            let (eta_max, alpha0, tries) = match self.barrier.as_ref() {
                Some(b) => {
                    let alpha0 = b.alpha;
                    let limit = if !turning {
                        self.barrier_step_limit(&u0, &du_full)?
                    } else {
                        let mut u1 = u0.clone();
                        turned_point(&self.model.x0, &u0, &du_full, &turns, 1.0, &mut u1, &mut tangent);
                        let chord: Vec<f64> = u1.iter().zip(&u0).map(|(a, b)| a - b).collect();
                        self.barrier_step_limit(&u0, &chord)?
                    };
                    (limit, alpha0, 12)
                }
                None => (1.0, 1.0, 6),
            };
            // The descent's retry gets several times the iterations to leave a saddle, progress
            // the residual does not show; an attempt whose last `max_iterations` updates were
            // all cut below half by the collision-free step is not leaving a saddle: its
            // updates aim through contacts the tangent does not hold yet (pairs beyond d̂ when
            // it was computed), the time step bringing particles together faster than the solve
            // takes them on, and a shorter step is the remedy. Measured (docs/robustness.md,
            // nineteenth measurement): on the 1,024-octagon grid such attempts ran 340 updates
            // in a row at 0.1–0.25 of themselves without converging, 7 minutes a try; the
            // longest such run in the 12,329 iterations of robustness case 08 was 13. Stopping
            // after 25 made paper job 5.2.1 jam at 0.971 (its grid cut back into a snap), so the
            // count is `max_iterations`: the first attempt loses at most its last update (when
            // every one of its updates was cut), and the retry's extra iterations are refused.
            limited = if eta_max < 0.5 { limited + 1 } else { 0 };
            if limited >= self.spec.max_iterations {
                tracing::debug!(iteration = k, limited, "the collision-free step keeps cutting the updates: the step is cut back");
                return Err(NewtonFailure::ContactLimited { iteration: k, limited, residuals });
            }
            // the barrier's energy and slope along the update at its start
            let line0 = self.contact_potential(&u0, &du_full);
            let mut eta = eta_max;
            // at a double root the update twice over is tried first, when its whole path is
            // collision-free
            // (a turned point's chord is checked where it is tried)
            let doubled = halved && self.barrier.as_ref().is_some_and(|b| b.double) && alpha0 >= 1.0 && eta_max >= 1.0 && {
                let twice: Vec<f64> = du_full.iter().map(|d| 2.0 * d).collect();
                turning || self.barrier_step_limit(&u0, &twice)? >= 1.0
            };
            if doubled {
                eta = DOUBLE_STEP;
            }
            // the smallest step accepted anyway, and the one below which an evaluation that
            // fails fails the solve (the barrier backs off further)
            let (accept_below, fail_below) = if barrier { (0.06 * eta_max * 1e-2, 0.06 * eta_max * 1e-3) } else { (0.06, 0.06) };
            let r_old = rnorm;
            let mut accepted = false;
            // whether the last point tried was left unevaluated (its path crossed a contact)
            let mut crossed = false;
            for _ in 0..tries + usize::from(doubled) {
                if !turning {
                    for d in 0..u.len() {
                        u[d] = u0[d] + eta * du_full[d];
                    }
                } else {
                    turned_point(&self.model.x0, &u0, &du_full, &turns, eta, u, &mut tangent);
                    crossed = self.collision_free_fraction(&u0, u, alpha0, wall_progress(alpha0, eta))? < 1.0;
                    if crossed {
                        tracing::debug!(eta, turns = turns.len(), "the turned point's chord meets a contact: backed off");
                        eta = if eta > 1.0 { eta_max } else { 0.5 * eta };
                        continue;
                    }
                }
                if let Some(c) = self.contact.as_mut() {
                    c.lm.step(&self.sys.du[n_free..], eta);
                }
                if let Some(b) = self.barrier.as_mut() {
                    b.alpha = wall_progress(alpha0, eta);
                }
                match self.evaluate(u, inc, vol, full) {
                    Ok(rn) => {
                        // accept when the residual norm or the energy |Δu·R(η)| decreased
                        let s: f64 = self.sys.dot(&self.sys.du, &self.sys.r).abs();
                        // With the barrier, while the walls still move with the step, a
                        // residual that does not grow is enough (a free motion has a zero
                        // residual). Once they have arrived, a descent direction (g0 > 0) must
                        // lower the potential: a step that lowers the residual norm but raises
                        // the potential let Newton cycle with period two, the residual
                        // alternating between two values for 20 iterations (robustness case
                        // 11, 64 polygons with μ = 0.2: it got to 0.944 instead of 0.906 in
                        // the same time without it, docs/robustness.md). The residual decides
                        // only where the potential cannot: an update that is no descent
                        // direction (an indefinite tangent; the step's retry shifts it,
                        // `factor_descent`) and a change of the potential below round-off.
                        let better = rn.is_finite()
                            && if barrier {
                                let slope: f64 = if !turning {
                                    self.sys.dot(&self.sys.du, &self.sys.r)
                                } else {
                                    let own = self.sys.own_dofs();
                                    self.sys.sum(self.sys.assembler.eq[..own].iter().zip(&tangent).filter(|(&q, _)| q != FIXED).map(|(&q, t)| t * self.sys.r[q]).sum())
                                };
                                let line = line0.zip(self.contact_potential(u, &tangent)).map(|((energy0, slope0), (energy, slope))| BarrierLine { energy0, slope0, energy, slope });
                                if eta > 1.0 {
                                    // (the double step: a descent on the potential, nothing less)
                                    barrier_descent(eta, g0, slope, line)
                                } else {
                                    alpha0 < 1.0 || barrier_descent(eta, g0, slope, line) || (rn <= r_old && (g0 <= 0.0 || within_round_off(eta, g0, slope, line)))
                                }
                            } else {
                                rn < r_old || s < 0.9 * energy
                            };
                        if better || (eta <= 1.0 && (!line_search || eta < accept_below)) {
                            rnorm = rn;
                            accepted = rn.is_finite();
                            break;
                        }
                        eta = if eta > 1.0 { eta_max } else { 0.5 * eta };
                    }
                    Err(e) if eta < fail_below => return Err(e),
                    Err(_) => eta = if eta > 1.0 { eta_max } else { 0.5 * eta },
                }
            }
            if accepted && eta == 1.0 && alpha0 >= 1.0 && barrier {
                last_whole.clone_from(&self.sys.du);
                whole += 1;
            } else {
                whole = 0;
            }
            if eta > 1.0 {
                tracing::debug!(iteration = k, "double root: the update taken twice");
            }
            last_update = self.sys.max(du_full.iter().fold(0.0f64, |m, v| m.max(v.abs())));
            if let Some(b) = self.barrier.as_ref() {
                tracing::debug!(eta, eta_max, alpha = b.alpha, accepted, g0, min_distance = b.eval.min_distance, last_update, "barrier line search");
            }
            if !accepted && crossed {
                // the smallest step tried was not evaluated: stay where the update started
                u.copy_from_slice(&u0);
                if let Some(b) = self.barrier.as_mut() {
                    b.alpha = alpha0;
                }
            }
            if !accepted {
                // keep the smallest step tried; its residual drives the next iteration
                rnorm = self.evaluate(u, inc, vol, full)?;
            }
            if full {
                self.factor_descent()?;
            }
        }
        Err(NewtonFailure::NotConverged { iterations: max_iterations, residuals })
    }

    /// Mark the solve under way as one converged to the solver's tolerance, not stopped
    /// early for a friction update (`BarrierRun::lag_tol` back to 0).
    fn converged_to_tolerance(&mut self) {
        if let Some(b) = self.barrier.as_mut() {
            b.lag_tol = 0.0;
        }
    }

    /// The out-of-balance force R₀ = F_ext − F_int(u₀) of a transferred state, released in
    /// increments: Newton solves R(u) = (1 − s) R₀ for s rising from 0 (where u₀ is the
    /// solution) to 1 (equilibrium), the last one with the volume and contact updates. Each
    /// increment starts next to its solution, so that a large imbalance (transferred stresses
    /// that do not match the contact forces of a new boundary discretisation, measured: a
    /// relative residual of 0.15 on an asphalt octagon among its neighbours) is not answered
    /// by one Newton step that inverts elements or jumps between contact states. The increment
    /// Δs starts at 1 (one solve: a re-meshed disc re-balances in 10 iterations, against 21
    /// in increments of 1/4), halves on a failure (down to 1/256) and doubles after an easy
    /// one. The contact pairs stay those selected at the transferred state (selecting them
    /// again between increments made the octagon's release stall at s = 0.54, measured).
    pub(super) fn release_imbalance(&mut self, inc: TimeIncrement) -> Result<Trial, NewtonFailure> {
        let u0 = self.sol.u.clone();
        let vol = self.volumetric(&self.sol.lambda.clone());
        self.sys.eq_offset.clear();
        let rel0 = self.evaluate(&u0, inc, &vol, false)? / self.reference_force();
        let r0: Vec<f64> = self.sys.f_ext.iter().zip(&self.sys.f_int).map(|(e, i)| e - i).collect();
        if rel0 <= 10.0 * self.spec.residual_tol {
            // nearly balanced already: one solve
            return self.solve_from(u0, inc, false);
        }
        let mut u = u0;
        let mut s = 0.0;
        let mut ds: f64 = 1.0;
        let mut iterations = 0;
        let mut increments = 0;
        while s < 1.0 {
            let s_try = (s + ds).min(1.0);
            self.sys.eq_offset = r0.iter().map(|r| (1.0 - s_try) * r).collect();
            let mut u_try = u.clone();
            let attempt = if s_try >= 1.0 {
                self.sys.eq_offset.clear();
                self.solve_from(u_try.clone(), inc, false).map(|t| {
                    let its = t.iterations;
                    u_try.clone_from(&t.u);
                    (its, Some(t))
                })
            } else {
                self.newton(&mut u_try, inc, &vol).map(|(its, _)| (its, None))
            };
            increments += 1;
            match attempt {
                Ok((its, trial)) => {
                    iterations += its;
                    tracing::debug!(s = s_try, iterations = its, "imbalance released");
                    if let Some(mut t) = trial {
                        t.iterations = iterations;
                        tracing::debug!(increments, iterations, initial_residual = rel0, "re-equilibrated in increments");
                        return Ok(t);
                    }
                    u = u_try;
                    s = s_try;
                    if its <= self.time.easy_iterations {
                        ds = (2.0 * ds).min(1.0);
                    }
                }
                Err(e) => {
                    ds *= 0.5;
                    tracing::debug!(s = s_try, next = ds, %e, "release increment failed, halving");
                    if ds < 1.0 / 256.0 {
                        return Err(e);
                    }
                }
            }
        }
        unreachable!("the loop returns at s = 1")
    }

    /// The particle whose nodes a Newton update `du` (every dof) from `u` moves furthest, and
    /// that motion split into the particle's mean translation, its best-fit turn about its
    /// centroid (rad) and the largest nodal remainder (the deformation), all in mm but the
    /// turn. For the debug log only.
    fn largest_update(&self, u: &[f64], du: &[f64]) -> Option<LargestUpdate> {
        let nodal = |k: usize| du[2 * k].hypot(du[2 * k + 1]);
        let (body, b, largest) = self
            .model
            .bodies
            .iter()
            .enumerate()
            .map(|(i, b)| (i, b, (b.node_offset..b.node_offset + b.mesh.nodes.len()).map(nodal).fold(0.0f64, f64::max)))
            .max_by(|x, y| x.2.total_cmp(&y.2))?;
        let (lo, hi) = (b.node_offset, b.node_offset + b.mesh.nodes.len());
        let (t, turn, deformation) = rigid_split(&self.model.x0[lo..hi], &u[2 * lo..2 * hi], &du[2 * lo..2 * hi]);
        Some(LargestUpdate { body, largest, translation: t[0].hypot(t[1]), turn, deformation })
    }

    /// The particles a Newton update `du` (every dof) from `u` turns by more than
    /// [`TURN_MIN`], with their centroids and best-fit rotations; particles with a prescribed
    /// dof are left straight.
    fn body_turns(&self, u: &[f64], du: &[f64]) -> Vec<BodyTurn> {
        let mut turns = Vec::new();
        for b in &self.model.bodies {
            let (lo, hi) = (b.node_offset, b.node_offset + b.mesh.nodes.len());
            if hi <= lo || (2 * lo..2 * hi).any(|d| self.sys.assembler.eq[d] == FIXED) {
                continue;
            }
            let (c, theta) = best_fit_turn(&self.model.x0[lo..hi], &u[2 * lo..2 * hi], &du[2 * lo..2 * hi]);
            if theta.abs() > TURN_MIN {
                turns.push(BodyTurn { nodes: (lo, hi), centre: c, theta });
            }
        }
        turns
    }

    /// The residual norm below which forces are round-off: the run's floor (from the
    /// particles' shear modulus and size; with the barrier, the bulk penalty of incompressible
    /// particles counts too), or with the barrier's ties the round-off of their forces
    /// k g, where g is a difference of coordinates of up to the assembly's size L: 8 ε k L per
    /// tie, summed in quadrature (1e-6 N with 70 ties of 100 E = 6.4e6 N/mm over 100 mm, more
    /// than the loads of a loose tied network hold at a relative 1e-8, measured).
    /// Where a residual that is not finite comes from, in words: the dof whose internal
    /// force (elements, contact, springs) or external force is NaN, or else the largest in
    /// magnitude (a sum of squares past the floating-point range), named by its body, that
    /// body's material and Young's modulus, or the loads.
    fn non_finite_cause(&self) -> String {
        let (f_int, f_ext) = (&self.sys.f_int, &self.sys.f_ext);
        let worst = |f: &[f64]| f.iter().enumerate().fold(None, |w: Option<(usize, f64)>, (d, &v)| {
            let m = if v.is_nan() { f64::INFINITY } else { v.abs() };
            match w {
                Some((_, b)) if b >= m => w,
                _ => Some((d, m)),
            }
        });
        let (Some((di, mi)), Some((de, me))) = (worst(f_int), worst(f_ext)) else { return "no forces".into() };
        let (dof, external) = if me > mi { (de, true) } else { (di, false) };
        let f = if external { f_ext[dof] } else { f_int[dof] };
        let node = dof / 2;
        let body = self.model.bodies.iter().position(|b| (b.node_offset..b.node_offset + b.mesh.n_nodes()).contains(&node));
        let about = body.and_then(|b| self.model.bodies.get(b)).map_or_else(String::new, |b| {
            let e = self.model.materials.get(b.material).map_or(f64::NAN, |m| m.youngs_modulus());
            format!(" of body {} (materials[{}], Young's modulus {e:e} MPa)", b.name, b.material)
        });
        if external {
            format!("the external force at node {node}{about} is {f:e} N/mm: look at the loads (their values and amplitudes)")
        } else {
            format!("the internal force at node {node}{about} is {f:e} N/mm: look at that material's constants, the contact's penalty or stiffness, and the loads")
        }
    }

    pub(super) fn force_floor(&self) -> f64 {
        let barrier = self.barrier.as_ref().map_or(0.0, |b| b.tie_floor.max(b.stiffness_floor));
        self.run.force_floor.max(barrier)
    }

    pub(super) fn volumetric(&self, lambda: &[f64]) -> Vec<Volumetric> {
        self.kappa.iter().zip(lambda).map(|(&kappa, &lambda)| Volumetric { kappa, lambda }).collect()
    }

    /// Reference force for the relative residual: the larger of ‖F_ext‖ and ‖F_int‖ over all
    /// dofs (which includes the reactions), never below round-off (with the barrier, never
    /// below the load floor 1e-2 E L of an assembly that carries nothing yet, `barrier::LOAD_FLOOR`).
    pub(super) fn reference_force(&self) -> f64 {
        let n = |v: &[f64]| self.sys.norm_dofs(v);
        let load = self.barrier.as_ref().map_or(0.0, |b| b.load_floor);
        n(&self.sys.f_ext).max(n(&self.sys.f_int)).max(self.sys.f_elem_norm).max(self.run.force_floor).max(load)
    }
}

#[cfg(test)]
mod tests {
    use super::{barrier_descent, best_fit_turn, double_root, quartered, rigid_split, turned_point, within_round_off, BarrierLine, BodyTurn};

    /// Π(η) = ½ c (η − η*)² along a Newton update whose curvature is off (η* the true
    /// minimiser): −Π′(η) = c (η* − η), g0 = c η*. Closed form, exact to round-off.
    fn slope(c: f64, eta_star: f64, eta: f64) -> f64 {
        c * (eta_star - eta)
    }

    /// A ring of 12 nodes of radius 5 about (3, −2) and its centre node, displaced by `u`.
    fn ring() -> (Vec<[f64; 2]>, Vec<f64>) {
        let mut x0: Vec<[f64; 2]> = (0..12).map(|k| {
            let a = k as f64 * std::f64::consts::PI / 6.0;
            [3.0 + 5.0 * a.cos(), -2.0 + 5.0 * a.sin()]
        }).collect();
        x0.push([3.0, -2.0]);
        // a small non-rigid displacement, so that u₀ is not the reference configuration
        let u0: Vec<f64> = (0..2 * x0.len()).map(|d| 1e-2 * ((d * 7 % 5) as f64 - 2.0)).collect();
        (x0, u0)
    }

    fn position(x0: &[[f64; 2]], u: &[f64], n: usize) -> [f64; 2] {
        [x0[n][0] + u[2 * n], x0[n][1] + u[2 * n + 1]]
    }

    #[test]
    fn an_update_splits_into_its_translation_turn_and_deformation() {
        let (x0, u0) = ring();
        let (c, _) = best_fit_turn(&x0, &u0, &vec![0.0; u0.len()]);
        // Δu = t + θ J r on every node, and a bump b on the centre node (index 12): it moves the
        // mean by b/13 and leaves 12 b/13 at the centre; it turns the fit by r₁₂ × b / Σ|r|²
        // only, r₁₂ the centre's offset from the centroid (u₀'s perturbation, of order 1e-2 mm)
        let (theta, t, b) = (0.2, [0.4, -0.9], [0.3, 0.4]);
        let mut du: Vec<f64> = (0..x0.len()).flat_map(|n| {
            let p = position(&x0, &u0, n);
            let r = [p[0] - c[0], p[1] - c[1]];
            [t[0] - theta * r[1], t[1] + theta * r[0]]
        }).collect();
        let (t0, turn0, def0) = rigid_split(&x0, &u0, &du);
        assert!((t0[0] - t[0]).abs() < 1e-14 && (t0[1] - t[1]).abs() < 1e-14 && (turn0 - theta).abs() < 1e-14 && def0 < 1e-14, "{t0:?} {turn0} {def0}");
        du[24] += b[0];
        du[25] += b[1];
        let (t1, turn1, def1) = rigid_split(&x0, &u0, &du);
        assert!((t1[0] - t[0] - b[0] / 13.0).abs() < 1e-14 && (t1[1] - t[1] - b[1] / 13.0).abs() < 1e-14, "{t1:?}");
        // (Σ|r|² = 300 mm²: the turn moves by about 0.5 × 1e-2 / 300, below 1e-4, and the
        // deformation by that times 5 mm at most)
        assert!((turn1 - theta).abs() < 1e-4, "{turn1}");
        assert!((def1 - 0.5 * 12.0 / 13.0).abs() < 1e-3, "{def1}");
    }

    #[test]
    fn the_best_fit_turn_of_a_linearised_rotation_is_its_angle() {
        let (x0, u0) = ring();
        let (c, _) = best_fit_turn(&x0, &u0, &vec![0.0; u0.len()]);
        // Δu = t + θ J r: θ comes back to round-off, whatever the translation t
        let (theta, t) = (0.3, [0.7, -1.1]);
        let du: Vec<f64> = (0..x0.len()).flat_map(|n| {
            let p = position(&x0, &u0, n);
            let r = [p[0] - c[0], p[1] - c[1]];
            [t[0] - theta * r[1], t[1] + theta * r[0]]
        }).collect();
        let (c1, fit) = best_fit_turn(&x0, &u0, &du);
        assert_eq!(c, c1);
        assert!((fit - theta).abs() < 1e-14, "{fit}");
        // a uniform stretch Δu = ε r (with a translation) turns nothing
        let du: Vec<f64> = (0..x0.len()).flat_map(|n| {
            let p = position(&x0, &u0, n);
            [t[0] + 0.1 * (p[0] - c[0]), t[1] + 0.1 * (p[1] - c[1])]
        }).collect();
        assert!(best_fit_turn(&x0, &u0, &du).1.abs() < 1e-15);
    }

    #[test]
    fn a_turned_update_is_a_rigid_rotation_with_the_update_as_tangent() {
        let (x0, u0) = ring();
        let (c, _) = best_fit_turn(&x0, &u0, &vec![0.0; u0.len()]);
        let (theta, t) = (0.4, [0.5, 0.25]);
        let rigid: Vec<f64> = (0..x0.len()).flat_map(|n| {
            let p = position(&x0, &u0, n);
            [t[0] - theta * (p[1] - c[1]), t[1] + theta * (p[0] - c[0])]
        }).collect();
        let turns = [BodyTurn { nodes: (0, x0.len()), centre: c, theta }];
        let (mut u, mut tangent) = (vec![0.0; u0.len()], vec![0.0; u0.len()]);
        // η = 0: the start, the tangent the update itself
        turned_point(&x0, &u0, &rigid, &turns, 0.0, &mut u, &mut tangent);
        assert_eq!(u, u0);
        assert_eq!(tangent, rigid);
        // η = 0.7 of a linearised rigid rotation: every distance kept (a linear step would
        // stretch them by √(1 + (0.7θ)²) − 1 = 3.8 %), the centroid moved by 0.7 t and turned
        // by 0.7 θ exactly
        let eta = 0.7;
        turned_point(&x0, &u0, &rigid, &turns, eta, &mut u, &mut tangent);
        for a in 0..x0.len() {
            for b in 0..a {
                let d = |v: &[f64]| {
                    let (p, q) = (position(&x0, v, a), position(&x0, v, b));
                    (p[0] - q[0]).hypot(p[1] - q[1])
                };
                assert!((d(&u) / d(&u0) - 1.0).abs() < 1e-14, "nodes {a}, {b}");
            }
        }
        let (c2, _) = best_fit_turn(&x0, &u, &vec![0.0; u.len()]);
        assert!((c2[0] - c[0] - eta * t[0]).abs() < 1e-13 && (c2[1] - c[1] - eta * t[1]).abs() < 1e-13);
        let p0 = position(&x0, &u0, 0);
        let p = position(&x0, &u, 0);
        let angle = (p[1] - c2[1]).atan2(p[0] - c2[0]) - (p0[1] - c[1]).atan2(p0[0] - c[0]);
        assert!((angle - eta * theta).abs() < 1e-14, "{angle}");
        // with a deformation on top, the tangent is the path's derivative: central differences
        // of step 1e-5 are exact to O(1e-10) here (the path is smooth, its third derivative of
        // order θ³ r)
        let du: Vec<f64> = rigid.iter().enumerate().map(|(d, v)| v + 0.05 * ((d * 3 % 7) as f64 - 3.0)).collect();
        let h = 1e-5;
        let (mut up, mut um, mut scratch) = (vec![0.0; u0.len()], vec![0.0; u0.len()], vec![0.0; u0.len()]);
        turned_point(&x0, &u0, &du, &turns, eta + h, &mut up, &mut scratch);
        turned_point(&x0, &u0, &du, &turns, eta - h, &mut um, &mut scratch);
        turned_point(&x0, &u0, &du, &turns, eta, &mut u, &mut tangent);
        for d in 0..u.len() {
            let fd = (up[d] - um[d]) / (2.0 * h);
            assert!((fd - tangent[d]).abs() < 1e-9, "dof {d}: {fd} against {}", tangent[d]);
        }
    }

    /// One loose rubber-like elastic disc (R = 10 mm, ν = 0.45, E = 10 MPa) in a die whose
    /// walls stay 40 mm away, which turned by 0.25 rad about its centre in the step before: its
    /// inertial springs (ζ = 1e-8 set in the case, which also leaves the tangent without the
    /// barrier's default regularisation), anchored at u_n extrapolated (here 2 u_n), pull it on. Nothing else
    /// acts, so the solution is the rigid motion nearest the anchors with the springs as
    /// weights (the weighted Procrustes fit, closed form), to the ratio ζ of the springs to
    /// the disc's stiffness. Returns the Newton iterations, the largest distance of the
    /// solution from that rigid motion (mm) and its angle and the fit's (rad).
    fn turn_a_loose_disc(turn: bool) -> (usize, f64, f64, f64) {
        let text = r#"
title = "a loose disc"
[[materials]]
name = "rubber"
model = "elastic"
youngs_modulus = 10.0
poisson_ratio = 0.45
[[walls]]
side = "left"
position = 0.0
[[walls]]
side = "right"
position = 100.0
[[walls]]
side = "bottom"
position = 0.0
[[walls]]
side = "top"
position = 100.0
velocity = 1.0
[[bodies]]
name = "disc"
material = "rubber"
mesh_size = 2.0
shape = { type = "disc", center = [50.0, 50.0], radius = 10.0 }
[contact]
stabilisation = 1e-8
[time]
end = 1.0
dt = 0.1
"#;
        let c = crate::case::parse(text, std::path::Path::new(".")).unwrap();
        let model = crate::model::Model::from_case(&c).unwrap();
        let mut sim = crate::solver::Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
        sim.barrier.as_mut().expect("the barrier is the default").turn = turn;
        let (s, co) = 0.25f64.sin_cos();
        for (n, p) in sim.model.x0.iter().enumerate() {
            let r = [p[0] - 50.0, p[1] - 50.0];
            sim.sol.u[2 * n] = co * r[0] - s * r[1] - r[0];
            sim.sol.u[2 * n + 1] = s * r[0] + co * r[1] - r[1];
        }
        sim.run.dt_prev = 0.1;
        let trial = sim.try_step(0.1).expect("the step converges");
        // weighted Procrustes: centroids and angle of points y against the reference x0
        let k: Vec<f64> = (0..sim.model.x0.len()).map(|n| sim.springs.k[2 * n]).collect();
        let x0 = &sim.model.x0;
        let fit = |y: &dyn Fn(usize) -> [f64; 2]| {
            let w: f64 = k.iter().sum();
            let mut c0 = [0.0; 2];
            let mut c1 = [0.0; 2];
            for n in 0..x0.len() {
                for i in 0..2 {
                    c0[i] += k[n] * x0[n][i] / w;
                    c1[i] += k[n] * y(n)[i] / w;
                }
            }
            let (mut sn, mut cs) = (0.0, 0.0);
            for n in 0..x0.len() {
                let (a, b) = ([x0[n][0] - c0[0], x0[n][1] - c0[1]], [y(n)[0] - c1[0], y(n)[1] - c1[1]]);
                sn += k[n] * (a[0] * b[1] - a[1] * b[0]);
                cs += k[n] * (a[0] * b[0] + a[1] * b[1]);
            }
            (c0, c1, sn.atan2(cs))
        };
        let anchor = |n: usize| [x0[n][0] + 2.0 * sim.sol.u[2 * n], x0[n][1] + 2.0 * sim.sol.u[2 * n + 1]];
        let solved = |n: usize| [x0[n][0] + trial.u[2 * n], x0[n][1] + trial.u[2 * n + 1]];
        let (c0, c1, phi) = fit(&anchor);
        let (_, _, angle) = fit(&solved);
        let (s, co) = phi.sin_cos();
        let off = (0..x0.len()).map(|n| {
            let r = [x0[n][0] - c0[0], x0[n][1] - c0[1]];
            let y = solved(n);
            (c1[0] + co * r[0] - s * r[1] - y[0]).hypot(c1[1] + s * r[0] + co * r[1] - y[1])
        }).fold(0.0, f64::max);
        (trial.iterations, off, angle, phi)
    }

    #[test]
    fn a_double_root_is_told_by_its_halving_updates_or_quartering_residuals() {
        // an update half the last along the same line, and a few percent off it
        assert!(double_root(0.25, 0.5, 1.0));
        assert!(double_root(0.25 + 0.02, 0.5, 1.0));
        // the same length, a quarter, or at right angles: not a double root
        assert!(!double_root(1.0, 1.0, 1.0) && !double_root(1.0 / 16.0, 0.25, 1.0) && !double_root(0.25, 0.0, 1.0));
        assert!(!double_root(0.0, 0.0, 1.0) && !double_root(0.25, 0.5, 0.0));
        assert!(quartered(&[1.0, 0.26, 0.06]) && quartered(&[5.0, 1.0, 0.26, 0.06]));
        assert!(!quartered(&[1.0, 0.5, 0.25]) && !quartered(&[1.0, 0.25, 0.01]) && !quartered(&[0.25, 0.06]));
    }

    /// One elastic disc (R = 10 mm, E = 1,000 MPa) pushed along by the left wall of a die
    /// whose other walls are far: nothing holds it but the barrier, so it rests at the gap d̂
    /// from the wall, where the barrier's force is of order s² and its stiffness of order s
    /// (a double root). Returns the Newton iterations of the steps after the first contact.
    fn push_a_loose_disc(double: bool) -> Vec<usize> {
        let text = r#"
[[materials]]
name = "m"
model = "elastic"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[walls]]
side = "left"
position = 0.0
velocity = 10.0
[[walls]]
side = "right"
position = 100.0
[[walls]]
side = "bottom"
position = -30.0
[[walls]]
side = "top"
position = 30.0
[[bodies]]
name = "disc"
material = "m"
mesh_size = 2.0
shape = { type = "disc", center = [11.0, 0.0], radius = 10.0 }
[time]
end = 1.0
dt = 0.1
dt_max = 0.1
"#;
        let c = crate::case::parse(text, std::path::Path::new(".")).unwrap();
        let model = crate::model::Model::from_case(&c).unwrap();
        let mut sim = crate::solver::Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
        sim.barrier.as_mut().expect("the barrier is the default").double = double;
        // (from the last converged state: the box prediction would carry the disc along)
        sim.set_barrier_box_prediction(false);
        let mut its = Vec::new();
        sim.run(&mut |_, r| its.push(r.newton_iterations)).unwrap();
        // (the wall reaches the disc in the first step; after it the disc is pushed)
        let gap = sim.barrier_gap();
        assert!(its.len() == 10, "{its:?} {gap:?}");
        its[2..].to_vec()
    }

    /// Measured: 17 iterations a step without the double step (the error halving from the
    /// third on), 5 with it.
    #[test]
    fn a_pushed_loose_disc_takes_a_few_iterations() {
        let plain = push_a_loose_disc(false);
        let double = push_a_loose_disc(true);
        eprintln!("iterations a step: {plain:?} plain, {double:?} with the double step");
        assert!(plain.iter().all(|&k| k >= 12), "{plain:?}");
        assert!(double.iter().all(|&k| k <= 8), "{double:?}");
    }

    /// A loose disc (R = 5 mm) at (30, 60) in a 100 × 100 mm die whose left and top walls move
    /// in at 10 mm/s: each 0.1 s step the box prediction carries its centre to the affine image
    /// of the box, x' = l₁ + (x − l₀)(h₁ − l₁)/(h₀ − l₀) on each axis (to 1e-9 mm: the middle
    /// of its nodes' bounding box, each node translated by the same amount), and Newton has
    /// nothing left to do but let the walls arrive (at most one update a step). Without the
    /// prediction it stays where it is.
    #[test]
    fn a_loose_disc_is_carried_with_the_box() {
        let text = r#"
[[materials]]
name = "m"
model = "elastic"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[walls]]
side = "left"
position = 0.0
velocity = 10.0
[[walls]]
side = "right"
position = 100.0
[[walls]]
side = "bottom"
position = 0.0
[[walls]]
side = "top"
position = 100.0
velocity = 10.0
[[bodies]]
name = "disc"
material = "m"
mesh_size = 2.0
shape = { type = "disc", center = [30.0, 60.0], radius = 5.0 }
[time]
end = 0.3
dt = 0.1
dt_max = 0.1
"#;
        let centre = |predict: bool| {
            let c = crate::case::parse(text, std::path::Path::new(".")).unwrap();
            let model = crate::model::Model::from_case(&c).unwrap();
            let mut sim = crate::solver::Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
            sim.set_barrier_box_prediction(predict);
            let mut its = Vec::new();
            sim.run(&mut |_, r| its.push(r.newton_iterations)).unwrap();
            let mid = |y: &dyn Fn(usize) -> [f64; 2]| -> [f64; 2] {
                std::array::from_fn(|a| {
                    let v: Vec<f64> = (0..sim.model.x0.len()).map(|k| y(k)[a]).collect();
                    0.5 * (v.iter().copied().fold(f64::INFINITY, f64::min) + v.iter().copied().fold(f64::NEG_INFINITY, f64::max))
                })
            };
            let c = mid(&|k| [sim.model.x0[k][0] + sim.sol.u[2 * k], sim.model.x0[k][1] + sim.sol.u[2 * k + 1]]);
            let c0 = mid(&|k| sim.model.x0[k]);
            (c, c0, its)
        };
        let (c, c0, its) = centre(true);
        // three steps of 1 mm: the left wall 0 → 3, the top 100 → 97
        let mut want = c0;
        for k in 0..3 {
            let (l0, l1) = (k as f64, k as f64 + 1.0);
            want[0] = l1 + (want[0] - l0) * (100.0 - l1) / (100.0 - l0);
            let (h0, h1) = (100.0 - k as f64, 99.0 - k as f64);
            want[1] = (want[1] - 0.0) * h1 / h0;
        }
        assert_eq!(its.len(), 3, "{its:?}");
        assert!(its.iter().all(|&k| k <= 1), "iterations a step: {its:?}");
        assert!((c[0] - want[0]).abs() < 1e-9 && (c[1] - want[1]).abs() < 1e-9, "centre {c:?}, the box's image {want:?}");
        let (c, c0, _) = centre(false);
        assert!((c[0] - c0[0]).abs() < 1e-9 && (c[1] - c0[1]).abs() < 1e-9, "without the prediction the disc stays: {c:?} from {c0:?}");
    }

    #[test]
    fn a_loose_disc_turns_in_a_few_iterations() {
        let (its, off, angle, phi) = turn_a_loose_disc(true);
        let (its_straight, off_straight, _, _) = turn_a_loose_disc(false);
        eprintln!("turned: {its} iterations, off {off:e} mm, angle {angle} against {phi}; straight: {its_straight} iterations, off {off_straight:e}");
        assert!((angle - phi).abs() < 1e-6 && off < 1e-5, "turned: angle {angle} against {phi}, {off} mm off the rigid motion");
        assert!(off_straight < 1e-5);
        // measured: 3 turned, 27 straight (each straight update turns the disc by a linearised
        // rotation, which stretches it by θ²/2 against its bulk modulus)
        assert!(its <= 5 && its_straight >= 5 * its, "{its} iterations turned, {its_straight} straight");
    }

    #[test]
    fn an_overshoot_across_the_valley_is_rejected_and_its_half_accepted() {
        let (c, eta_star) = (3.0, 0.5);
        let g0 = slope(c, eta_star, 0.0);
        // η = 1 lands on the far side as steep as it left: Π(1) = Π(0), no decrease
        assert!(!barrier_descent(1.0, g0, slope(c, eta_star, 1.0), None));
        // the backtracked η = 1/2 is the minimiser
        assert!(barrier_descent(0.5, g0, slope(c, eta_star, 0.5), None));
    }

    #[test]
    fn a_barrier_rise_the_trapezoidal_rule_misses_is_rejected() {
        // Π = E_b + Π_nb along the update, Π_nb = −η (R_nb·Δu = 1 everywhere) and E_b the
        // smooth step 1.5(3η² − 2η³) (flat at both ends): Π(1) − Π(0) = 1.5 − 1 = +0.5, an
        // ascent. The trapezoidal rule on Π's slope alone (1 at both ends) sees −1.
        let g0 = 1.0;
        let slope = 1.0;
        assert!(barrier_descent(1.0, g0, slope, None));
        let line = BarrierLine { energy0: 0.0, slope0: 0.0, energy: 1.5, slope: 0.0 };
        assert!(!barrier_descent(1.0, g0, slope, Some(line)));
        // a rise of 0.9 leaves a decrease of 0.1, which passes Armijo's test
        let line = BarrierLine { energy: 0.9, ..line };
        assert!(barrier_descent(1.0, g0, slope, Some(line)));
    }

    #[test]
    fn a_short_step_downhill_is_accepted_and_an_ascent_is_not() {
        let (c, eta_star) = (2.0, 4.0);
        let g0 = slope(c, eta_star, 0.0);
        assert!(barrier_descent(1.0, g0, slope(c, eta_star, 1.0), None));
        // a direction uphill (g0 < 0) is never a descent
        assert!(!barrier_descent(1.0, -g0, -slope(c, eta_star, 1.0), None));
        // an overshoot that still lowers Π but lands steeper than c₂ g0 uphill is rejected:
        // η* = 0.45, η = 1: −Π′(1) = −0.55 against g0 = 0.45, a ratio of −1.22
        let (c, eta_star) = (1.0, 0.45);
        let g0 = slope(c, eta_star, 0.0);
        assert!(!barrier_descent(1.0, g0, slope(c, eta_star, 1.0), None));
        // and one that lands at 0.8 of the start's slope uphill is accepted: η* = 1/1.8
        let eta_star = 1.0 / 1.8;
        let g0 = slope(c, eta_star, 0.0);
        assert!(barrier_descent(1.0, g0, slope(c, eta_star, 1.0), None));
    }

    #[test]
    fn a_change_below_the_barriers_round_off_is_told_apart() {
        // a barrier energy of 1e6 with slopes that cancel: the change of Π along η = 1 is
        // (E − E0) − ½ (g0 + s0 + s + s1) = E − E0 with g0 + s0 = −(s + s1)
        let line = |de: f64| BarrierLine { energy0: 1e6, slope0: 2.0, energy: 1e6 + de, slope: -1.0 };
        let (g0, slope) = (-1.0, -0.0);
        // 1e-5 is 1e-11 of the energy: round-off, the residual decides
        assert!(within_round_off(1.0, g0, slope, Some(line(1e-5))));
        assert!(within_round_off(1.0, g0, slope, Some(line(-1e-5))));
        // 1e-3 is 1e-9 of it: a real change, the potential decides
        assert!(!within_round_off(1.0, g0, slope, Some(line(1e-3))));
        // without the barrier there is no round-off scale
        assert!(!within_round_off(1.0, g0, slope, None));
    }
}
