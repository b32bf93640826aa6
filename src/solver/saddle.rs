//! Leaving a saddle (barrier contact): a converged step whose tangent is not positive definite
//! in the particles themselves sits on an equilibrium that is not a minimum of the incremental
//! potential — a regular grid that has passed the point where its symmetric path loses
//! stability. The gradient there has no component along the mode that breaks the symmetry,
//! so Newton and the descent both stay on the unstable path, which then snaps through much
//! later, when round-off has grown (the asphalt octagon grids of the 6.2 study: a snap at
//! solid ratio 0.9545 that released 13 % of the walls' work into the stabilisation springs and
//! jammed the run, docs/robustness.md, fifteenth and sixteenth measurements).
//!
//! After every converged step whose last tangent was not definite as assembled:
//! 1. the tangent at the converged state is assembled again with each barrier pair's Hessian
//!    projected onto the PSD matrices — the barrier's own negative curvature (a node sliding
//!    past a vertex of another particle, of the order of the pair's force over its gap) is
//!    a property of the sharp corners of the discretised boundaries, not an instability of the
//!    particles: departing along it scrambled a loose grid of octagons at its first contact
//!    (measured) — and factored if it is positive definite: then the state is a minimum;
//! 2. otherwise the tangent is shifted until definite (as the descent shifts it) and inverse
//!    iteration with that factorisation gives a direction v with vᵀKv < 0 on the unshifted
//!    tangent; a curvature vᵀKv / Σ|K_ii|v_i² above −[`CURVATURE_TOL`] is round-off, and the
//!    state is kept;
//! 3. the state is moved along v by [`AMPLITUDE`] times the smallest element size at the
//!    node that moves most (less if the continuous collision detection says so) and the step
//!    is solved again from there, descending (`BarrierRun::descent`, on from then as after a
//!    failed step); up to [`MAX_DEPARTURES`] times a step. A departure whose solve fails leaves
//!    the step with its converged saddle: the step never fails for it.
//!
//! Where the tangent is definite (every step of a loose or random packing whose particles are
//! not unstable) none of this costs anything: the flag comes from the step's own last
//! factorisation. Not with friction or ties (their lagged terms would follow the departure's
//! iterates, and a departure that fails could not give them back), nor where the solver
//! cannot tell a definite tangent (LU, iterative solvers).

use super::{NewtonFailure, Simulation, Trial};
use crate::assembly::FIXED;
use crate::material::TimeIncrement;

/// At most this many departures from a saddle a step.
const MAX_DEPARTURES: usize = 3;

/// Inverse iterations for a direction of negative curvature (it stops earlier once the
/// Rayleigh quotient is negative and changes by less than 1e-3 of itself).
const INVERSE_ITERATIONS: usize = 40;

/// A relative curvature vᵀKv / Σ|K_ii|v_i² above −1e-8 counts as round-off. On the 4 × 4
/// asphalt octagons (6.2 study from 0.65) the first negative curvature of the particles
/// came at solid ratio 0.80 with −1.4e-7, growing to −1.2e-6 over the next six steps.
pub const CURVATURE_TOL: f64 = 1e-8;

/// The largest nodal move of a departure, relative to the smallest element size.
pub const AMPLITUDE: f64 = 1e-2;

impl Simulation {
    /// See the module docs. Returns the trial the step ends on (the given one when it is a
    /// minimum or no departure converged).
    ///
    /// # Errors
    /// [`NewtonFailure::Ghosts`] when a departure meets a body a part does not hold (the step
    /// is made again on new parts).
    pub(super) fn leave_saddle(&mut self, mut trial: Trial, inc: TimeIncrement) -> Result<Trial, NewtonFailure> {
        let n_free = self.sys.assembler.n_free;
        // (with friction or ties the departure's solve would update their lagged terms, which
        // a departure that fails could not give back: there the step keeps its state)
        if n_free == 0 || self.barrier.as_ref().is_none_or(|b| b.definite || b.has_friction() || b.tie_stiffness > 0.0) {
            return Ok(trial);
        }
        let mut moved = false;
        for departure in 0..MAX_DEPARTURES {
            let vol = self.volumetric(&trial.lambda);
            if self.evaluate(&trial.u, inc, &vol, true).is_err() {
                break;
            }
            self.project_pair_hessians();
            if self.factor_definite() {
                break;
            }
            let Some(v) = self.negative_curvature(departure) else { break };
            let h = self.barrier.as_ref().map_or(1.0, |b| b.h_min);
            let mut dir = vec![0.0; trial.u.len()];
            for (d, &q) in self.sys.assembler.eq.iter().enumerate() {
                if q != FIXED {
                    dir[d] = v[q];
                }
            }
            let big = self.sys.max(dir.chunks(2).map(|c| (c[0] * c[0] + c[1] * c[1]).sqrt()).fold(0.0, f64::max));
            if big <= 0.0 || !big.is_finite() {
                break;
            }
            let s = AMPLITUDE * h / big;
            dir.iter_mut().for_each(|v| *v *= s);
            let eta = self.barrier_step_limit(&trial.u, &dir)?.min(1.0);
            let start: Vec<f64> = trial.u.iter().zip(&dir).map(|(a, b)| a + eta * b).collect();
            if let Some(b) = self.barrier.as_mut() {
                b.descent = true;
            }
            match self.solve_from(start, inc, false) {
                Ok(mut t) => {
                    let change = t.u.iter().zip(&trial.u).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                    tracing::debug!(time = inc.time, departure, iterations = t.iterations, change, eta, "saddle left and minimised again");
                    t.iterations += trial.iterations;
                    t.updates += trial.updates;
                    trial = t;
                    moved = true;
                    self.run.saddle_departures += 1;
                    if self.barrier.as_ref().is_some_and(|b| b.definite) {
                        break;
                    }
                }
                Err(e @ NewtonFailure::Ghosts(_)) => return Err(e),
                Err(e) => {
                    tracing::debug!(time = inc.time, departure, %e, "the departure from a saddle did not converge; the step keeps its converged state");
                    break;
                }
            }
        }
        // the element fields, the barrier's evaluation and the contact state at the trial's
        // displacements, as the commit takes them
        let vol = self.volumetric(&trial.lambda);
        if self.evaluate(&trial.u, inc, &vol, false).is_err() {
            tracing::warn!(moved, "the converged state of a step could not be evaluated again");
        }
        Ok(trial)
    }

    /// A direction of negative curvature of the tangent in `kk` (not definite): the tangent
    /// shifted until definite, then inverse iteration with that factorisation from a fixed
    /// pseudo-random start; the Rayleigh quotients on the unshifted tangent. None when no
    /// shift made it definite or the curvature found is round-off ([`CURVATURE_TOL`]). The
    /// solving process's tangent decides; on several processes its quotients are broadcast.
    fn negative_curvature(&mut self, departure: usize) -> Option<Vec<f64>> {
        // the unshifted tangent, for the Rayleigh quotients
        let k_exact = self.sys.kk.clone();
        let mut diag: Vec<f64> = k_exact.diagonal();
        if let Some(p) = &self.sys.part {
            // the whole diagonal of its own equations: every process's terms
            p.eqs.reverse_add(&mut diag, 1);
        }
        let tau = self.shift_until_definite(super::barrier::SHIFT_MIN, 1.0)?;
        let n = self.sys.r.len();
        let n_free = self.sys.assembler.n_free;
        let mut x = vec![0.0; n];
        let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        match &self.sys.part {
            None => x.iter_mut().take(n_free).for_each(|v| *v = next()),
            Some(p) => {
                // the whole model's start, each equation's value read at its whole equation
                let whole: Vec<f64> = (0..p.eqs.n_global()).map(|_| next()).collect();
                for (v, &q) in x.iter_mut().zip(&p.eq_whole) {
                    *v = whole.get(q).copied().unwrap_or(0.0);
                }
            }
        }
        // (a part: its own equations' sums, and xᵀKx from every process's own terms, its
        // ghosts' included: K is the sum of the parts')
        let own = self.sys.own_eqs();
        let mut kx = vec![0.0; n];
        let (mut rq, mut rel) = (0.0, 0.0);
        let mut its = 0;
        for it in 0..INVERSE_ITERATIONS {
            its = it + 1;
            let norm = self.sys.sum(x[..own].iter().map(|v| v * v).sum::<f64>()).sqrt();
            if !(norm > 0.0) || !norm.is_finite() {
                return None;
            }
            x.iter_mut().for_each(|v| *v /= norm);
            self.sys.r.copy_from_slice(&x);
            self.sys.du.iter_mut().for_each(|v| *v = 0.0);
            self.solve_linear().ok()?;
            x.copy_from_slice(&self.sys.du);
            k_exact.mul_vec(&x, &mut kx);
            let xx: f64 = self.sys.sum(x[..own].iter().map(|v| v * v).sum());
            let xkx: f64 = self.sys.sum(x.iter().zip(&kx).map(|(a, b)| a * b).sum());
            let xdx: f64 = self.sys.sum(x[..own].iter().zip(&diag).map(|(a, d)| a * a * d.abs()).sum());
            let mut q = [xkx / xx, xkx / xdx];
            if self.sys.par.is_some() {
                self.sys.comm.broadcast(&mut q);
            }
            let settled = q[0] < 0.0 && (q[0] - rq).abs() <= 1e-3 * q[0].abs();
            (rq, rel) = (q[0], q[1]);
            if settled {
                break;
            }
        }
        tracing::debug!(departure, tau, its, rq, rel, "saddle: direction of negative curvature");
        (rel.is_finite() && rel < -CURVATURE_TOL).then_some(x)
    }
}
