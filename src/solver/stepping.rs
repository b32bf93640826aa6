//! The time-stepping loop: the step size control (growth after easy steps, cut-back after a
//! failure, down to `dt_min`), the retries before a cut-back (every dof stabilised, viscous
//! springs, a re-mesh of a poor particle), the jam test, the predictor of a step, and the
//! commit of a converged one with its report.

use super::{Compaction, NewtonFailure, Phase, RunSummary, Simulation, SolveError, StepReport, Trial};
use crate::assembly::FIXED;
use crate::loading::WallSide;
use crate::material::TimeIncrement;
use crate::stabilise::{StabilisationKind, Stabilise};
use std::ops::ControlFlow;
use std::time::Instant;

/// The largest contact penetration a run on the node-to-segment contact takes, as a fraction
/// of the smallest element size ([`Simulation::check_penetration`]).
pub const PENETRATION_LIMIT: f64 = 0.5;

impl Simulation {
    /// Run from the current time to the end time, calling `observer` after every converged
    /// step. On error the last committed solution stays in `self.sol`.
    pub fn run(&mut self, observer: &mut dyn FnMut(&Simulation, &StepReport)) -> Result<RunSummary, SolveError> {
        self.run_controlled(&mut |s, r| {
            observer(s, r);
            ControlFlow::Continue(())
        })
    }

    /// [`Simulation::run`] with an observer that may stop the run after the step it is shown
    /// (`ControlFlow::Break(reason)`: the summary's `stop_reason`, `interrupted` set). The
    /// observer sees the simulation in a state that continues bit for bit (the step size of the
    /// next step included), so it can write a checkpoint ([`crate::checkpoint`]).
    pub fn run_controlled(&mut self, observer: &mut dyn FnMut(&Simulation, &StepReport) -> ControlFlow<String>) -> Result<RunSummary, SolveError> {
        let start = Instant::now();
        let t_end = self.time.end;
        let mut stop_reason = "end time".to_string();
        let mut interrupted = false;
        // (a state that already meets `[stop]` — a run continued after its last step, a
        // restart from its final checkpoint — takes no step past it)
        let met = self.run.last_report.as_ref().and_then(|r| self.stop_met(r));
        if let Some(reason) = &met {
            stop_reason.clone_from(reason);
        }
        while met.is_none() && self.sol.time < t_end * (1.0 - 1e-12) {
            if self.run.step >= self.time.max_steps {
                return Err(SolveError::TooManySteps(self.time.max_steps));
            }
            let dt = self.run.next_dt;
            let remaining = t_end - self.sol.time;
            let dt_try = self.land_on_target(if remaining <= dt * 1.01 { remaining } else { dt });
            let report = match self.advance(dt_try) {
                Ok(r) => r,
                Err(SolveError::StepFailed { cause: NewtonFailure::Interrupted, .. }) => {
                    stop_reason = super::STOP_ABANDONED.to_string();
                    interrupted = true;
                    break;
                }
                // (a part whose ghosts no longer cover its contacts is not jammed: the caller
                // makes the parts again and goes on)
                Err(SolveError::StepFailed { time, dt, cause, .. }) if self.model.stop.jam && !matches!(cause, NewtonFailure::Ghosts(_) | NewtonFailure::Part(_)) && self.is_jammed(self.run.last_report.as_ref()) => {
                    tracing::warn!(time, dt, %cause, "the walls cannot advance any more: jammed");
                    stop_reason = "jammed".to_string();
                    break;
                }
                Err(e) => return Err(e),
            };
            self.run.next_dt = if self.run.last_step_easy {
                (report.dt * self.time.growth).min(self.time.dt_max)
            } else {
                report.dt
            };
            self.run.last_report = Some(report.clone());
            let flow = observer(self, &report);
            // (a contact so soft that the particles pass into each other is a failed run, not
            // a completed one: shown the step, then stopped)
            self.check_penetration(&report)?;
            if let Some(reason) = self.stop_met(&report) {
                stop_reason = reason;
                break;
            }
            if let ControlFlow::Break(reason) = flow {
                stop_reason = reason;
                interrupted = true;
                break;
            }
        }
        Ok(RunSummary {
            steps: self.run.step,
            newton_iterations: self.run.total_iterations,
            cutbacks: self.run.total_cutbacks,
            remeshes: self.run.total_remeshes,
            saddle_departures: self.run.saddle_departures,
            final_time: self.sol.time,
            wall_time_s: start.elapsed().as_secs_f64(),
            linear_solver: self.sys.linear_name.clone(),
            // (a part: the whole model's counts)
            n_dofs: 2 * self.model.whole_facts().n_nodes,
            n_free: match &self.sys.part {
                Some(p) => self.sys.sum(p.own_eqs as f64) as usize,
                None => self.sys.assembler.n_free,
            },
            n_elements: self.model.whole_facts().n_elements,
            last: self.run.last_report.clone(),
            stop_reason,
            interrupted,
            timing: self.clock.timing(),
            partition: self.sys.partition.clone(),
        })
    }

    /// That the node-to-segment contact's largest penetration after step `report` is at most
    /// [`PENETRATION_LIMIT`] × the smallest element size h: beyond, the particles pass into
    /// each other and the walls (a penalty far too soft), and the run stops naming it. The
    /// barrier keeps every gap open: nothing to check.
    ///
    /// # Errors
    /// [`SolveError::Contact`] naming the penetration, the limit and the contact's settings.
    fn check_penetration(&self, report: &StepReport) -> Result<(), SolveError> {
        let Some(c) = &report.compaction else { return Ok(()) };
        let h = self.model.whole_facts().h_min;
        if self.model.contact.method == crate::contact::ContactMethod::Barrier || !h.is_finite() || c.max_penetration <= PENETRATION_LIMIT * h {
            return Ok(());
        }
        let penalty = self.model.contact.penalty.map_or_else(|| "the default 10 E / h".to_string(), |k| format!("contact.penalty = {k:e} MPa/mm"));
        Err(SolveError::Contact(format!(
            "after step {} (t = {:.6e} s) the particles overlap by {:.3e} mm, more than {PENETRATION_LIMIT} of the smallest element size ({h:.3e} mm): the contact is far too soft ({penalty}, method = \"{}\"); raise contact.penalty or use the barrier contact (the default method)",
            report.step,
            report.time,
            c.max_penetration,
            match self.model.contact.method {
                crate::contact::ContactMethod::Penalty => "penalty",
                crate::contact::ContactMethod::AugmentedLagrangian => "augmented_lagrangian",
                crate::contact::ContactMethod::Lagrange => "lagrange",
                crate::contact::ContactMethod::Barrier => "barrier",
            }
        )))
    }

    /// Whether the state of step `report` meets `[stop]` (its solid ratio or its pressing walls'
    /// pressure), and the summary's reason.
    fn stop_met(&self, report: &StepReport) -> Option<String> {
        let c = report.compaction.as_ref()?;
        if self.model.stop.solid_ratio.is_some_and(|target| c.solid_ratio >= target) {
            return Some("solid ratio reached".into());
        }
        if self.model.stop.wall_pressure.is_some_and(|target| self.pressing_pressure(c) >= target) {
            return Some("wall pressure reached".into());
        }
        None
    }

    /// The step `dt`, shortened so that it ends where the walls close the die to the stop solid
    /// ratio (`[stop] solid_ratio`) when it would go beyond it: the run stops at the state the
    /// user asked for, not up to a whole (large) step past it, and the last point of the
    /// pressure–density curve is not an extrapolation. The particles' area is taken as at the
    /// last converged step (the walls' motion is prescribed, so the die's area at any time is
    /// known); where it shrinks a little during the step, the run ends one short step later.
    /// Unchanged without a stop solid ratio, without four walls or before the first step.
    pub(super) fn land_on_target(&self, dt: f64) -> f64 {
        const LANDING_MARGIN: f64 = 1e-4;
        let (Some(target), Some(c)) = (self.model.stop.solid_ratio, self.run.last_report.as_ref().and_then(|r| r.compaction.as_ref())) else {
            return dt;
        };
        let area = |t: f64| self.model.loading.die_area(t);
        let t0 = self.sol.time;
        let (Some(a0), Some(a1)) = (area(t0), area(t0 + dt)) else { return dt };
        // aimed a little beyond the target (1e-4 of solid ratio), so that the round-off of the
        // particles' area, or a small elastic shrinking of it, does not leave the run a sliver
        // of a step short
        let solid = c.solid_ratio * a0;
        let aim = target + LANDING_MARGIN;
        let reaches = |a: f64| a > 0.0 && solid >= aim * a;
        if solid >= target * a0 || !reaches(a1) {
            return dt;
        }
        // bisection on the step for the time the die's area falls to solid / aim (the
        // walls may follow an amplitude table, so no closed form); the upper end reaches it
        let (mut lo, mut hi) = (0.0, dt);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if area(t0 + mid).is_some_and(reaches) {
                hi = mid;
            } else {
                lo = mid;
            }
            if hi - lo <= 1e-12 * dt {
                break;
            }
        }
        hi.max(self.time.dt_min).min(dt)
    }

    /// The mean pressure of the pressing walls (those that move) in `c` (MPa): what
    /// `[stop] wall_pressure` is compared with, the same mean as the pressure–density curve
    /// of `summary.json`.
    pub fn pressing_pressure(&self, c: &Compaction) -> f64 {
        let sides = self.model.loading.pressing_sides();
        if sides.is_empty() {
            return 0.0;
        }
        sides.iter().map(|&s| c.pressure[s]).sum::<f64>() / sides.len() as f64
    }

    /// A failed step counts as a jam (the walls cannot advance any more) only when the last
    /// converged state is dense (solid ratio ≥ `[stop] jam_solid_ratio`, 0.9 by default) and
    /// every moving wall carries load;
    /// otherwise the failure is a convergence failure and is reported as an error.
    fn is_jammed(&self, last: Option<&StepReport>) -> bool {
        let Some(c) = last.and_then(|r| r.compaction.as_ref()) else { return false };
        let walls = &self.model.loading;
        let moving_loaded = walls.walls.iter().enumerate().all(|(w, wall)| !walls.wall_moves(w) || c.force[wall.side.index()] > 0.0);
        !walls.walls.is_empty() && c.solid_ratio >= self.model.stop.jam_solid_ratio && moving_loaded
    }

    /// One converged step of size `dt`, or smaller after cut-backs (the report says which).
    pub fn advance(&mut self, dt: f64) -> Result<StepReport, SolveError> {
        let mut dt_try = dt;
        let mut cutbacks = 0;
        let mut snapshot = self.contact.as_ref().map(|c| c.snapshot());
        // particles re-meshed in this step: the retry after an inverted element (once per
        // step), then those whose mesh crosses the quality limits after the step
        let mut remeshes = 0;
        let mut remesh_tried = false;
        // whether the step starts descending on the potential (after a step that needed it)
        let sticky = self.barrier.as_ref().is_some_and(|b| b.descent);
        // (what an abandoned step puts back: the springs' retry switches, the cut-back count)
        let (springs0, cutbacks0, departures0) = ((self.springs.all, self.springs.viscous), self.run.total_cutbacks, self.run.saddle_departures);
        loop {
            if let (Some(c), Some(snap)) = (self.contact.as_mut(), snapshot.as_ref()) {
                c.restore(snap.clone());
            }
            let result = self.try_step(dt_try);
            let stab = &self.model.stabilisation;
            let stabilised = self.contact.is_some() && stab.factor > 0.0;
            let partial = stabilised && !self.springs.all && stab.scope == Stabilise::Unsupported;
            let inertial = stabilised && !self.springs.viscous && stab.viscous_retry && stab.kind == StabilisationKind::Inertial;
            let inverted = match &result {
                Err(NewtonFailure::Element(e)) if self.model.remesh.enabled && !remesh_tried => Some(e.element),
                _ => None,
            };
            if let Some(e) = inverted {
                // an element inverted: re-mesh its particle (in the last converged state) and
                // retry the same step before any cut-back, when its mesh there is already
                // poor (a new mesh of a good mesh does not help: the step was too large; on
                // a part the element is the whole model's, and its owner decides)
                remesh_tried = true;
                let body = match self.sys.part.is_some() {
                    true => self.part_body_to_remesh(e),
                    false => self.model.elem_body.get(e).copied().filter(|&b| self.model.remesh_constraint(b).is_none() && self.mesh_is_poor(b)),
                };
                if let Some(b) = body {
                    tracing::info!(time = self.sol.time, dt = dt_try, body = b, "an element inverted: re-meshing the particle and retrying the step");
                    if self.remesh_and_rebalance(b) {
                        remeshes += 1;
                        snapshot = self.contact.as_ref().map(|c| c.snapshot());
                        continue;
                    }
                }
            }
            let descent_retry = self.barrier.as_ref().is_some_and(|b| !b.descent) && !matches!(result, Err(NewtonFailure::Element(_)));
            if let Err(cause @ (NewtonFailure::Interrupted | NewtonFailure::Part(_) | NewtonFailure::Ghosts(_))) = result {
                // abandoned: the last converged state as the step found it (the contact
                // histories, the descent's switch, the springs, the counts), to be
                // checkpointed (a stop) or taken onto new parts (a part's ghosts no longer
                // cover its contacts: no retry or cut-back changes them)
                if let (Some(c), Some(snap)) = (self.contact.as_mut(), snapshot) {
                    c.restore(snap);
                }
                if let Some(b) = self.barrier.as_mut() {
                    b.descent = sticky;
                }
                (self.springs.all, self.springs.viscous) = springs0;
                self.run.total_cutbacks = cutbacks0;
                self.run.saddle_departures = departures0;
                if matches!(cause, NewtonFailure::Interrupted) {
                    tracing::info!(time = self.sol.time, dt = dt_try, "step abandoned: a stop was asked for");
                }
                return Err(SolveError::StepFailed { time: self.sol.time, dt: dt_try, dt_min: self.time.dt_min, cause });
            }
            match result {
                Ok(trial) => {
                    self.springs.all = false;
                    self.springs.viscous = false;
                    // (with the barrier, the descent stays on for the steps after one that
                    // needed it: `BarrierRun::descent`)
                    let descended = self.barrier.as_ref().is_some_and(|b| b.descent);
                    let easy = self.step_easy(&trial, cutbacks, descended && dt_try == dt && cutbacks == usize::from(!sticky));
                    let mut report = self.commit(dt_try, trial, cutbacks);
                    self.run.last_step_easy = easy;
                    remeshes += self.remesh_after_step();
                    report.remeshes = remeshes;
                    return Ok(report);
                }
                Err(cause) if descent_retry => {
                    // with the barrier, retry the same step with the indefinite tangents
                    // shifted to positive definite ones before cutting back
                    tracing::debug!(time = self.sol.time, dt = dt_try, %cause, "step failed, retrying with definite tangents");
                    if let Some(b) = self.barrier.as_mut() {
                        b.descent = true;
                    }
                    cutbacks += 1;
                    self.run.total_cutbacks += 1;
                }
                Err(cause) if partial => {
                    // retry the same step with every dof stabilised before cutting back
                    tracing::debug!(time = self.sol.time, dt = dt_try, %cause, "step failed with partial stabilisation, retrying with all");
                    self.springs.all = true;
                    cutbacks += 1;
                    self.run.total_cutbacks += 1;
                }
                Err(cause) if inertial => {
                    // retry the same step with the springs anchored where the step starts: a
                    // particle that hits another at rest must change its velocity at once, which
                    // the inertial anchor resists and the viscous one does not
                    tracing::debug!(time = self.sol.time, dt = dt_try, %cause, "step failed with inertial stabilisation, retrying viscous");
                    self.springs.viscous = true;
                    cutbacks += 1;
                    self.run.total_cutbacks += 1;
                }
                Err(cause) => {
                    // (a retry's wider or viscous springs stay on for the cut-back steps)
                    cutbacks += 1;
                    self.run.total_cutbacks += 1;
                    let next = dt_try * self.time.cutback;
                    tracing::warn!(time = self.sol.time, dt = dt_try, next, %cause, "step failed, cutting back");
                    if next < self.time.dt_min {
                        return Err(SolveError::StepFailed { time: self.sol.time, dt: dt_try, dt_min: self.time.dt_min, cause });
                    }
                    dt_try = next;
                }
            }
        }
    }

    /// Whether a converged step is easy, so that the next one may grow (by `[time] growth`):
    /// it converged at the size it was tried without a retry, in at most `[time]
    /// easy_iterations` Newton iterations.
    ///
    /// With the barrier, every step that converged at the size it was tried is easy, whatever
    /// its iterations: without a retry, or descending on the potential (`descended_at_size`:
    /// from its start, the descent being on since an earlier step, or in the retry after its
    /// first attempt failed; the size was not what failed). A barrier solve's iterations do not
    /// say how hard its step was: in a rearranging packing most of them settle the loose
    /// particles against near-d̂ gaps, about as many in a small step as in a large one, so a
    /// step held small costs more iterations for the same compaction. Measured on robustness
    /// case 12 (256 polygons, docs/robustness.md, twenty-third measurement), Newton iterations to
    /// solid ratio 0.92: steps fixed at 0.005 s, 27–45 a step and 2,239 to 0.84 alone; held at
    /// 0.015 s by the old rule (grown only after steps of at most 24 iterations, which the dense
    /// phase never has), 60–280 a step and 3,158; at 0.05 s, 90–205 a step and 1,634.
    fn step_easy(&self, trial: &Trial, cutbacks: usize, descended_at_size: bool) -> bool {
        if self.barrier.is_some() {
            return cutbacks == 0 || descended_at_size;
        }
        cutbacks == 0 && trial.iterations <= self.time.easy_iterations
    }

    /// Contact pairs for a solve that ends at `sol.time + dt` (frozen during its Newton
    /// iterations; the pattern follows when they change), where the stabilisation springs
    /// are anchored and how stiff they are. `dt = 0` is a re-equilibration in place: the springs
    /// are then anchored at the last converged position.
    pub(super) fn prepare_contact(&mut self, dt: f64) -> Result<(), NewtonFailure> {
        if self.barrier.is_some() {
            return self.prepare_barrier(dt);
        }
        let _t = self.clock.scope(Phase::ContactSearch);
        let Some(c) = self.contact.as_mut() else { return Ok(()) };
        let x_n = self.model.x0.iter().enumerate().map(|(n, p)| [p[0] + self.sol.u[2 * n], p[1] + self.sol.u[2 * n + 1]]).collect::<Vec<_>>();
        c.wall_reach = self.model.loading.wall_reach(self.sol.time, dt);
        let walls_n = self.model.wall_planes(self.sol.time);
        if c.select_pairs(&x_n, &walls_n) {
            // the pattern follows the pairs (incrementally); the positions of the pair and
            // multiplier blocks follow them in any case
            let sys = &mut self.sys;
            let (pair_dofs, multiplier_dofs) = (c.pair_dof_lists(), c.multiplier_dofs());
            let changed = sys.assembler.set_terms(&mut sys.kk, &pair_dofs, &multiplier_dofs);
            sys.maps.pairs = sys.assembler.block_map(&sys.kk, &pair_dofs);
            sys.maps.multipliers = sys.assembler.multiplier_map(&sys.kk, &multiplier_dofs);
            if changed {
                sys.r.resize(sys.kk.nrows, 0.0);
                sys.du.resize(sys.kk.nrows, 0.0);
                sys.locate_fixed_terms(&self.model, &c.node_dof_lists());
                sys.analyze()?;
            }
        }
        // the springs of this step: every dof, or only the directions the contacts of the last
        // converged state do not hold
        let n_bodies = self.model.bodies.len();
        let held = || c.body_support(&x_n, &walls_n, n_bodies);
        self.springs.prepare(&self.model.stabilisation, &self.sol.u, &self.u_prev, dt, self.run.dt_prev, self.time.dt, held);
        Ok(())
    }

    /// The barrier's prediction of the step from `t0` to `t1`: every particle translated with
    /// the box its walls make, as far as the motion is collision-free (IPC's conservative CCD,
    /// the walls where the step starts). Along an axis with a wall on each side, a particle's
    /// centre c (the middle of its bounding box) goes to l₁ + (c − l₀)(h₁ − l₁)/(h₀ − l₀), l and
    /// h the two walls' positions at t0 and t1 ([`crate::loading::Loading::wall_position`]);
    /// along any other axis it stays. On `u` (every dof, the step's start); the walls then
    /// move with Newton's line search as before.
    ///
    /// A particle that nothing touches is in equilibrium wherever it is; Newton left it where
    /// it was, and each update of a packing then aimed its particles through gaps the tangent
    /// does not see. Carried with the box, a loose packing's particles keep their places
    /// relative to each other, and a loaded one starts nearer its compacted state
    /// (docs/robustness.md, thirtieth measurement: a loose step costs about one iteration, the
    /// suite's median 21 → 18 a step, the 1,024 random discs' ten steps 735 → 628).
    pub(super) fn box_prediction(&mut self, u: &mut [f64], t0: f64, t1: f64) -> Result<(), NewtonFailure> {
        let Some(alpha0) = self.barrier.as_ref().map(|b| b.alpha) else { return Ok(()) };
        // per axis: (l₀, l₁, the stretch); none where the walls do not bound it
        let loading = &self.model.loading;
        let map = |lo: WallSide, hi: WallSide| {
            let (l, h) = (loading.wall_on(lo)?, loading.wall_on(hi)?);
            let (l0, h0, l1, h1) = (loading.wall_position(l, t0), loading.wall_position(h, t0), loading.wall_position(l, t1), loading.wall_position(h, t1));
            (h0 > l0 && h1 > l1).then(|| (l0, l1, (h1 - l1) / (h0 - l0)))
        };
        let maps = [map(WallSide::Left, WallSide::Right), map(WallSide::Bottom, WallSide::Top)];
        if maps.iter().all(|m| m.is_none_or(|(l0, l1, s)| l0 == l1 && s == 1.0)) {
            return Ok(());
        }
        // each particle's centre (the middle of its nodes' bounding box: the same on every
        // process of a part, whatever order its nodes are numbered in) and its translation
        let x = self.coords(u);
        let body = &self.springs.node_body;
        let mut boxes = vec![[f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY]; self.model.bodies.len()];
        for (n, p) in x.iter().enumerate() {
            let b = &mut boxes[body[n]];
            b[0] = b[0].min(p[0]);
            b[1] = b[1].min(p[1]);
            b[2] = b[2].max(p[0]);
            b[3] = b[3].max(p[1]);
        }
        let shift: Vec<[f64; 2]> = boxes
            .iter()
            .map(|b| {
                let c = [0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3])];
                std::array::from_fn(|a| if c[a].is_finite() { maps[a].map_or(0.0, |(l0, l1, stretch)| l1 + (c[a] - l0) * stretch - c[a]) } else { 0.0 })
            })
            .collect();
        let u0 = u.to_vec();
        let mut u1 = u0.clone();
        for (d, &q) in self.sys.assembler.eq.iter().enumerate() {
            if q != FIXED {
                u1[d] += shift[body[d / 2]][d % 2];
            }
        }
        // (the walls stay: they move with Newton's line search, which takes a first update
        // whatever it does to the potential while they travel)
        let f = self.collision_free_fraction(&u0, &u1, alpha0, alpha0)?;
        for d in 0..u.len() {
            u[d] = u0[d] + f * (u1[d] - u0[d]);
        }
        tracing::debug!(fraction = f, "box prediction");
        Ok(())
    }

    /// Attempt one step of size dt from the committed solution. On success the trial
    /// displacement is in `self.sol.u` (not yet committed) — see `commit`.
    pub(super) fn try_step(&mut self, dt: f64) -> Result<Trial, NewtonFailure> {
        let t = self.sol.time + dt;
        let inc = TimeIncrement { time: t, dt };
        self.prepare_contact(dt)?;
        // prediction (with the barrier: each particle carried with the box of the walls, as far
        // as that is collision-free, `box_prediction`; an extrapolating predictor was measured
        // and rejected, docs/robustness.md, twenty-seventh measurement)
        let mut u = self.sol.u.clone();
        let barrier = self.barrier.is_some();
        if self.run.dt_prev > 0.0 && !barrier {
            let s = dt / self.run.dt_prev;
            for (d, &q) in self.sys.assembler.eq.iter().enumerate() {
                if q != FIXED {
                    u[d] += s * (self.sol.u[d] - self.u_prev[d]);
                }
            }
        }
        self.model.loading.apply_prescribed(&mut u, t);
        if let Some(dy) = self.dynamics.as_ref() {
            dy.predict(&mut u, dt, &self.sys.assembler.eq); // Newmark predictor (a_{n+1} = 0)
        }
        if self.run.dt_prev == 0.0 && self.dynamics.is_none() && !barrier {
            // no increment to extrapolate (first step): linearised prediction instead
            if let Err(e) = self.tangent_predictor(&mut u, inc) {
                tracing::debug!(%e, "tangent predictor skipped");
                u.copy_from_slice(&self.sol.u);
                self.model.loading.apply_prescribed(&mut u, t);
            }
        }
        if self.dynamics.is_none() && self.barrier.as_ref().is_some_and(|b| b.predict) {
            self.box_prediction(&mut u, self.sol.time, t)?;
        }
        let restart = self.run.dt_prev > 0.0;
        let trial = self.solve_from(u, inc, restart)?;
        self.leave_saddle(trial, inc)
    }

    /// The tangent of a step's converged end, for verification: a step of `dt` tried from the
    /// committed state as [`Simulation::advance`] tries it first (no retry, no cut-back), and
    /// the assembled tangent (the free equations, both triangles) evaluated exactly at its
    /// converged displacements, with nothing projected or shifted. The step is not committed:
    /// the state stays the last converged one, but the trial's contact and pattern remain,
    /// so the simulation is for inspection only afterwards.
    ///
    /// # Errors
    /// The step's failure, when it does not converge.
    pub fn tangent_after_step(&mut self, dt: f64) -> Result<crate::linalg::csr::CsrMatrix, NewtonFailure> {
        let trial = self.try_step(dt)?;
        let inc = TimeIncrement { time: self.sol.time + dt, dt };
        let vol = self.volumetric(&trial.lambda);
        self.evaluate(&trial.u, inc, &vol, true)?;
        Ok(self.sys.kk.clone())
    }

    /// Commit a converged step: states, displacements, multipliers, time; build its report.
    pub(super) fn commit(&mut self, dt: f64, trial: Trial, cutbacks: usize) -> StepReport {
        // work done against the stabilisation springs over the step (their force at the end of
        // the step times the increment)
        self.springs.energy += self.sys.sum(self.springs.work(&trial.u, &self.sol.u));
        if self.contact.is_some() {
            let x = self.coords(&trial.u);
            if let Some(c) = self.contact.as_mut() {
                c.commit(&x);
            }
        }
        self.commit_barrier(&trial.u);
        self.u_prev.copy_from_slice(&self.sol.u);
        self.sol.u = trial.u;
        self.sol.lambda = trial.lambda;
        std::mem::swap(&mut self.sol.fields, &mut self.sys.trial_fields);
        if let Some(dy) = self.dynamics.as_mut() {
            dy.commit(&self.sol.u, dt, &self.sys.f_int, &self.sys.f_ext);
        }
        self.sol.time += dt;
        self.run.dt_prev = dt;
        self.run.step += 1;
        self.run.total_iterations += trial.iterations;
        let x = self.coords(&self.sol.u);
        let areas = self.model.body_areas(&x);
        // (a part: its own bodies, and the sums and extremes over the processes)
        let own_bodies = self.sys.part.as_ref().map_or(areas.len(), |p| p.own_bodies);
        let total: f64 = self.sys.sum(areas[..own_bodies].iter().sum());
        let volume_error = ((total - self.run.area0_total) / self.run.area0_total).abs();
        let volume_error_max_body = self.sys.max(
            areas[..own_bodies]
                .iter()
                .zip(&self.run.area0_body)
                .map(|(a, a0)| ((a - a0) / a0).abs())
                .fold(0.0, f64::max),
        );
        let reactions: Vec<[f64; 2]> = self
            .model
            .reaction_groups
            .iter()
            .map(|g| {
                let mut r = [0.0; 2];
                for &n in &g.nodes {
                    for c in 0..2 {
                        r[c] += self.sys.f_int[2 * n + c] - self.sys.f_ext[2 * n + c];
                    }
                }
                r
            })
            .collect();
        let displacements = self
            .model
            .displacement_groups
            .iter()
            .map(|g| {
                let mut m = [0.0; 2];
                for &n in &g.nodes {
                    for c in 0..2 {
                        m[c] += self.sol.u[2 * n + c];
                    }
                }
                let k = self.sys.sum(g.nodes.len() as f64).max(1.0);
                [self.sys.sum(m[0]) / k, self.sys.sum(m[1]) / k]
            })
            .collect();
        let reactions: Vec<[f64; 2]> = reactions.into_iter().map(|r: [f64; 2]| [self.sys.sum(r[0]), self.sys.sum(r[1])]).collect();
        if self.sys.part.is_some() {
            // the walls' loads and the contacts of every process
            let stats = &mut self.contact_stats;
            self.sys.comm.sum_in_place(&mut stats.wall_force);
            let mut load: Vec<f64> = stats.wall_load.iter().flatten().copied().collect();
            self.sys.comm.sum_in_place(&mut load);
            for (l, v) in stats.wall_load.iter_mut().zip(load.chunks_exact(2)) {
                *l = [v[0], v[1]];
            }
            stats.active = self.sys.sum(stats.active as f64) as usize;
        }
        // the boundary nodes of a contact problem (penalty-type or barrier)
        let boundary: Option<Vec<usize>> = match (&self.contact, &self.barrier) {
            (Some(c), _) => Some(c.boundary.slaves.iter().map(|&(n, _)| n).collect()),
            (None, Some(b)) => Some(b.contact.nodes.iter().map(|&(n, _)| n).collect()),
            (None, None) => None,
        };
        let compaction = boundary.map(|nodes| {
            let t = self.sol.time;
            let mut out = Compaction {
                max_penetration: self.contact_stats.max_penetration,
                active_contacts: self.contact_stats.active,
                ..Default::default()
            };
            let loading = &self.model.loading;
            for (w, wall) in loading.walls.iter().enumerate() {
                let f = self.contact_stats.wall_force.get(w).copied().unwrap_or(0.0);
                let moved = (loading.wall_position(w, t) - loading.wall_position(w, t - dt)).abs();
                self.run.work_ext += 0.5 * (f + self.run.last_wall_force[w]) * moved;
                self.run.last_wall_force[w] = f;
                let k = wall.side.index();
                let len = loading.wall_length(w, t, nodes.iter().map(|&n| x[n]));
                out.force[k] += f;
                // the load's component along the wall (y on a left or right wall, x on a
                // bottom or top one)
                let along = usize::from(matches!(wall.side, WallSide::Left | WallSide::Right));
                out.shear[k] += self.contact_stats.wall_load.get(w).map_or(0.0, |l| l[along]);
                out.travel[k] = loading.wall_travel(w, t);
                out.pressure[k] += if len > 0.0 { f / len } else { 0.0 };
            }
            if let Some(die) = loading.die_area(t) {
                out.solid_ratio = total / die;
            }
            out.stabilisation_energy = self.springs.energy;
            out.external_work = self.run.work_ext;
            out
        });
        StepReport {
            compaction,
            step: self.run.step,
            time: self.sol.time,
            dt,
            newton_iterations: trial.iterations,
            volume_updates: trial.updates,
            cutbacks,
            residual: trial.residual,
            volume_error,
            volume_error_max_body,
            max_element_volume_change: trial.worst,
            reactions,
            displacements,
            // (a part: its own dofs', summed over the processes)
            kinetic_energy: self.dynamics.as_ref().map_or(0.0, |dy| self.sys.sum(dy.kinetic_energy(self.sys.own_dofs()))),
            remeshes: 0,
        }
    }
}
