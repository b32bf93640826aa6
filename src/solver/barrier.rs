//! The barrier contact in a running simulation (`[contact] method = "barrier"`): its terms in
//! the one pattern, the walls' prescribed motion reached through the collision-checked line
//! search, and the adaptation of the barrier stiffness.
//!
//! # The walls
//!
//! A wall jumping to its position at the end of the step would put the nodes it touches behind
//! it. Instead the walls move with the Newton iterates: at the start of a step they are where
//! the last step left them (α = 0), every Newton direction is the linearised response to
//! moving them the rest of the way (the barrier's wall terms give the right-hand side
//! H n Δw, H a wall pair's Hessian, n the wall's normal, Δw the wall's remaining advance), and
//! the line search moves the nodes and the walls together by the same fraction η of that
//! direction (α ← α + η (1 − α)), limited by the continuous collision detection of both. A
//! step has converged only when the walls have arrived (α = 1) and the residual is within its
//! tolerance. No iterate has a node on or behind a wall.
//!
//! # The pattern
//!
//! The pairs of the barrier change with every iterate. The pattern holds a block for every
//! node–edge pair closer than d̂ + h (h the smallest element size) at the start of the step,
//! and grows (incrementally, [`crate::assembly::Assembler::set_terms`]) when an iterate brings
//! a pair within d̂ that it does not hold, by every pair within d̂ + h of that iterate; wall
//! pairs use the nodes' own diagonal blocks.

use super::state::BarrierState;
use super::{NewtonFailure, Phase, Simulation};
use crate::assembly::FIXED;
use crate::contact::barrier_problem::{lag_changes, lagging, BarrierContact, BarrierEval, FrictionPair, Lagging};
use crate::contact::geometry::unit;
use crate::contact::{ContactStats, NodalContact, Wall};

/// Whether the pair Hessians are projected onto the PSD matrices in every solve (in the retry
/// of a failed step they are where the tangent is indefinite, [`Simulation::factor_descent`]).
const PROJECT: bool = false;

/// The smallest relative shift τ tried ([`Simulation::shift_until_definite`]). The shift adds
/// τ s_i to every diagonal entry, also those of the particles that nothing but the
/// tangent's regularisation holds (ρ = 1e-8 of the elements' stiffness,
/// `stabilise::BARRIER_REGULARISATION`): where τ s_i is larger
/// than a particle's own stiffness, Newton moves it by only the fraction k / (k + τ s) of the
/// way to its equilibrium an iteration. Starting the shifts at 1e-6 held the retries of
/// robustness case 12 (256 polygons) for 40–80 iterations on one loose particle each,
/// converging by 2.5 % an iteration or sliding off a saddle by 0.6 % an iteration; from 1e-10
/// the same run to solid ratio 0.82 took 10 steps and 401 iterations instead of 19 and 773
/// (docs/robustness.md, eleventh measurement).
pub(super) const SHIFT_MIN: f64 = 1e-10;

/// How many times `[solver] max_iterations` the retry of a failed step gets, descending on the
/// potential ([`Simulation::factor_descent`]): leaving a saddle by descent is progress the
/// residual does not show (it grows while the iterate slides off), and a grid that loses its
/// stability slides a long way into its new arrangement. Measured (docs/robustness.md,
/// twenty-first measurement): the 16 × 16 octagon grid's snap at solid ratio 0.883 took one
/// descent of 1,228 iterations, its relative residual wandering between 0.02 and 0.4 while
/// the pairs within d̂ went from 22,500 to 15,400 and back, and the grid then went on to 0.99
/// with the springs' work at 1e-6 of the walls'; with four times (400) every attempt at that
/// step failed and the run jammed there. An attempt that crawls against the collision-free
/// step still stops after `max_iterations` cut updates ([`NewtonFailure::ContactLimited`]).
pub const DESCENT_ITERATIONS: usize = 20;

/// The barrier contact of a simulation and its state within a step.
#[derive(Debug)]
pub(super) struct BarrierRun {
    pub contact: BarrierContact,
    /// The terms of the last evaluation.
    pub eval: BarrierEval,
    /// The node–edge pairs with a block in the pattern, sorted (`maps.pairs` in this order).
    pub pattern: Vec<(usize, usize)>,
    /// The dofs of every boundary node (`maps.nodes` in this order).
    pub node_dofs: Vec<Vec<usize>>,
    /// The walls at the start and at the end of the step.
    pub walls0: Vec<Wall>,
    pub walls1: Vec<Wall>,
    /// How far through the step the walls are (0 at its start, 1 arrived).
    pub alpha: f64,
    /// Smallest distance of the last converged step (mm).
    pub min_distance: f64,
    /// κ as built (the adaptation never goes below it or above 10⁴ times it).
    pub kappa0: f64,
    /// The smallest element size of the particles (mm).
    pub h_min: f64,
    /// Friction coefficient between particles and of each wall (0: frictionless).
    pub mu: f64,
    pub mu_walls: Vec<f64>,
    /// The lagged friction of the pairs (frozen normal forces and tangents, updated after
    /// each converged solve until they stop changing).
    pub friction: Vec<FrictionPair>,
    /// The lagged friction before the last update of this step's (empty before its second):
    /// an update back to it is a cycle ([`Simulation::update_barrier_friction`]).
    pub friction_before: Vec<FrictionPair>,
    /// Start each step with the particles carried by the walls' box
    /// ([`Simulation::box_prediction`]; on by default, off for tests of what follows it).
    pub predict: bool,
    /// Cohering particles: a node within d̂ of another particle at the end of a step (or at
    /// the start) is tied to it ([`crate::contact::barrier_problem::Tie`]), with this stiffness
    /// (N/mm; 0 without ties).
    pub tie_stiffness: f64,
    /// The size of the assembly L (mm: the largest coordinate of the reference configuration)
    /// and the round-off of the ties' forces, 8 ε k L √(number of ties) (N/mm).
    pub extent: f64,
    pub tie_floor: f64,
    /// The largest tie gap after the last multiplier update of this step (mm).
    pub tie_gap: f64,
    /// How many ties hold in the whole model (on a part: over every process; its own are
    /// `contact.ties`).
    pub n_ties: usize,
    /// Forces below this are round-off: 1e-13 K L with K the largest shear modulus or bulk
    /// penalty (incompressible particles) and L the square root of the particles' area (N/mm).
    pub stiffness_floor: f64,
    /// The smallest reference force of the relative residual, [`LOAD_FLOOR`] E L (N/mm).
    pub load_floor: f64,
    /// The contact state per node of the last converged step, for the results files
    /// ([`Simulation::barrier_nodal`]).
    pub nodal: NodalContact,
    /// Descend on the incremental potential in this step's solves: an indefinite tangent is
    /// made definite by projecting its pair Hessians onto the PSD matrices, else by a shift of
    /// its diagonal ([`Simulation::factor_descent`]); the solve gets
    /// [`DESCENT_ITERATIONS`] times the iterations. On in the retry of a step that failed without, and from then
    /// on for the rest of the run: in a rearranging packing nearly every first attempt with
    /// the exact tangent fails once one has (robustness case 12: every one from its fifth step
    /// on, 25 iterations each), and where the tangent is definite the descent's solve is
    /// Newton's own.
    pub descent: bool,
    /// The relative shift τ that last made the tangent definite in this attempt at a step
    /// (0: none yet): the next indefinite tangent's shifts start a tenth of it
    /// ([`Simulation::shift_until_definite`]).
    pub shift: f64,
    /// Whether the last tangent factored was positive definite as assembled (true also when
    /// the solver cannot tell, as LU cannot): a converged step whose tangent was definite is a
    /// minimum, and [`Simulation::leave_saddle`] has nothing to look for.
    pub definite: bool,
    /// Whether the line search turns the particles a Newton update rotates by their exact
    /// rotation (`newton::turned_point`); off only to measure what it gains.
    pub turn: bool,
    /// Whether Newton takes the update twice over at a double root (`newton::double_root`);
    /// off only to measure what it gains.
    pub double: bool,
    /// The out-of-balance force (N/mm, the residual's norm) at which the solve under way
    /// stops so that the lagged friction is updated ([`LAG_FORCING`] times the last update's
    /// largest change of μλ); 0: the solver's own tolerance ([`Simulation::solve_from`]).
    /// Newton sets it to 0 when its solve reaches that tolerance: after a solve, nonzero
    /// tells one stopped early.
    pub lag_tol: f64,
    /// The largest change of a pair's μλ in the lagged friction's last update (N/mm).
    pub lag_change: f64,
    /// Whether this step's lagging has ended in a cycle or at the last update allowed (the
    /// solve after it converges to the solver's tolerance, and no update follows).
    pub lag_ended: bool,
    /// The forcing of the solves that precede a friction update ([`LAG_FORCING`]; 0: every
    /// solve to the solver's tolerance, only to measure what it gains).
    pub lag_forcing: f64,
}

/// The stiffness of a tie relative to the softest particle's Young's modulus: k = 100 E
/// (N/mm). Each multiplier update then shrinks a tie's gap by about the ratio of the
/// particles' own stiffness at the node (of the order of E) to k, a factor 100 an update.
pub const TIE_STIFFNESS: f64 = 100.0;

/// The ties are converged when no tie's gap exceeds this fraction of the smallest element
/// size (the tied blocks of `jobs/verification/` then match one block to 1e-6).
pub const TIE_TOL: f64 = 1e-10;

/// The relative residual's reference force is never below `LOAD_FLOOR` E L, E the softest
/// particle's Young's modulus and L the square root of the particles' area: the force that
/// strains the whole assembly elastically by 1 %. Until a packing carries a load its forces
/// are round-off sized, and measured against themselves a loose particle that slides under a
/// lagged friction force or drifts towards a gap of d̂, held by nothing but the tangent's
/// regularisation, was never in equilibrium: robustness cases 03 and 06 (μ = 0.2) crawled at
/// Δt = 2e-5 s with out-of-balance forces of 5e-8 N, case 08 (asphalt discs, μ = 0.1) ran
/// 1,500–1,900 iterations a step with 4e-6 N (1e-3 E L was not enough there). With the
/// default `residual_tol` of 1e-8 the out-of-balance forces are then within 1e-10 E L, an
/// error of about 1e-10 E in a wall pressure (docs/robustness.md, twenty-fourth measurement).
pub const LOAD_FLOOR: f64 = 1e-2;

/// At most this many multiplier updates of the ties a step.
pub const MAX_TIE_UPDATES: usize = 20;

/// The slip over which the mollified friction rises to its Coulomb value, relative to the
/// smallest element size: ε = 1e-3 h (IPC's ε_v, here a slip per step).
pub const FRICTION_EPS: f64 = 1e-3;

/// The lagged friction is converged when no pair's μλ changed by more than this fraction of
/// the largest one in the last update.
pub const FRICTION_TOL: f64 = 1e-4;

/// At most this many friction updates a step.
pub const MAX_FRICTION_UPDATES: usize = 20;

/// The solves of a frictional step before the lagged friction settles stop once the
/// out-of-balance force (the residual's norm, N/mm) is below this times the last update's
/// largest change of a pair's μλ (the first solve: see [`LAG_FIRST_CHANGE`]), not at the
/// solver's tolerance; a solve that gets there with the friction settled (lagged again at its
/// iterate, no μλ would move by more than [`FRICTION_TOL`] of the largest) goes on to the
/// solver's tolerance, and so does one after an update that ends the lagging otherwise (a
/// cycle, the last update allowed). An iterate that is about to move with the next update
/// needs converging no further than that update moves the forces: a force error of that size
/// moves a pair's μλ by μ times it at most, less than the lagging's own contraction (about
/// tenfold an update, docs/robustness.md, thirty-fourth measurement). Where the lagging does
/// not contract (an update that moves the friction no less than the one before), the rest of
/// the step's solves converge, so that a cycle is told as before, by the friction coming back
/// to where it was two converged solves before. The end of a step is what it was: converged
/// to the solver's tolerance with the friction settled. Measured (docs/robustness.md,
/// thirty-sixth measurement, without that last rule and with the first solve stopped at the
/// factor times the largest μλ): the suite's frictional cases with factors of 0.01, 0.1, 0.3,
/// 1 and 3 took 5,882, 5,492, 5,361, 5,270 and 5,112 Newton iterations against 6,189
/// converging every solve; the gain levels off from 0.3 on, and 1 is the plain statement that
/// a solve is converged as far as the friction is about to move.
pub const LAG_FORCING: f64 = 1.0;

/// The change of μλ the first friction update of a step is taken to make, relative to the
/// largest μλ, for the first solve's early stop ([`LAG_FORCING`] times this times the largest
/// μλ). Measured on the robustness suite's dense frictional steps, the first update changes
/// the friction by 0.17–1.0 of the largest μλ (docs/robustness.md, thirty-fourth measurement);
/// where the friction hardly changes from step to step (a block sliding steadily on a wall) a
/// first solve stopped at the largest μλ itself made the step take 8 Newton iterations instead
/// of 6, stopped at a tenth of it 6 (`tests/contact_friction.rs`).
pub const LAG_FIRST_CHANGE: f64 = 0.1;

impl BarrierRun {
    pub fn new(contact: BarrierContact, h_min: f64, mu: f64, mu_walls: Vec<f64>, tie_stiffness: f64) -> Self {
        let node_dofs = contact.nodes.iter().map(|&(n, _)| vec![2 * n, 2 * n + 1]).collect();
        let kappa0 = contact.kappa;
        Self { contact, eval: BarrierEval::default(), pattern: Vec::new(), node_dofs, walls0: Vec::new(), walls1: Vec::new(), alpha: 1.0, min_distance: f64::INFINITY, kappa0, h_min, mu, mu_walls, friction: Vec::new(), friction_before: Vec::new(), predict: true, tie_stiffness, extent: 0.0, tie_floor: 0.0, tie_gap: f64::INFINITY, n_ties: 0, stiffness_floor: 0.0, load_floor: 0.0, nodal: NodalContact::default(), descent: false, shift: 0.0, definite: false, turn: true, double: true, lag_tol: 0.0, lag_change: 0.0, lag_ended: false, lag_forcing: LAG_FORCING }
    }

    /// The round-off of the ties' forces, after ties were made: `n_ties` of them in the whole
    /// model.
    pub fn update_tie_floor(&mut self, n_ties: usize) {
        self.n_ties = n_ties;
        self.tie_floor = 8.0 * f64::EPSILON * self.tie_stiffness * self.extent * (n_ties as f64).sqrt();
    }

    /// The pairs the pattern needs besides the barrier's: the ties', sorted into `pairs`.
    pub fn with_ties(&self, mut pairs: Vec<(usize, usize)>) -> Vec<(usize, usize)> {
        if !self.contact.ties.is_empty() {
            pairs.extend(self.contact.ties.iter().map(|t| (t.node, t.segment)));
            pairs.sort_unstable();
            pairs.dedup();
        }
        pairs
    }

    /// The walls at progress `alpha` through the step (straight between their positions at
    /// the start and the end).
    pub fn walls_at(&self, alpha: f64) -> Vec<Wall> {
        if alpha >= 1.0 || self.walls0.len() != self.walls1.len() {
            return self.walls1.clone();
        }
        self.walls0
            .iter()
            .zip(&self.walls1)
            .map(|(a, b)| Wall { point: [a.point[0] + alpha * (b.point[0] - a.point[0]), a.point[1] + alpha * (b.point[1] - a.point[1])], normal: b.normal })
            .collect()
    }

    /// The state a checkpoint keeps ([`BarrierState`]).
    pub fn state(&self) -> BarrierState {
        BarrierState { kappa: self.contact.kappa, min_distance: self.min_distance, ties: self.contact.ties.clone(), tied: self.contact.tied.clone(), descent: self.descent }
    }

    /// The largest μλ of the lagged friction (on this process's pairs).
    pub fn largest_friction(&self) -> f64 {
        self.friction.iter().fold(0.0, |m: f64, f| m.max(f.mu_lambda))
    }

    /// Whether any contact has friction.
    pub fn has_friction(&self) -> bool {
        self.mu > 0.0 || self.mu_walls.iter().any(|&m| m > 0.0)
    }

}

impl Simulation {
    /// The pattern's barrier blocks become `pairs` (sorted); the positions of every block
    /// follow when the pattern changes.
    ///
    /// On a part every process calls this (the pattern of the distributed matrix changes when
    /// any process's does, and all analyse it again together).
    pub(super) fn set_barrier_pattern(&mut self, pairs: Vec<(usize, usize)>) -> Result<(), NewtonFailure> {
        let Some(b) = self.barrier.as_mut() else { return Ok(()) };
        let same = pairs == b.pattern && b.pattern.len() == self.sys.maps.pairs.len();
        if !self.sys.any(!same) {
            return Ok(());
        }
        b.pattern = pairs;
        let dofs: Vec<Vec<usize>> = b.pattern.iter().map(|&p| b.contact.pair_dofs(p)).collect();
        let sys = &mut self.sys;
        let changed = sys.assembler.set_terms(&mut sys.kk, &dofs, &[]);
        sys.maps.pairs = sys.assembler.block_map(&sys.kk, &dofs);
        if sys.any(changed) {
            sys.r.resize(sys.kk.nrows, 0.0);
            sys.du.resize(sys.kk.nrows, 0.0);
            sys.locate_fixed_terms(&self.model, &b.node_dofs);
            sys.analyze()?;
        }
        Ok(())
    }

    /// The start of a step of size `dt` with the barrier: the walls from where they are to
    /// where they go, the pattern from the pairs within d̂ + h of the converged configuration.
    pub(super) fn prepare_barrier(&mut self, dt: f64) -> Result<(), NewtonFailure> {
        let _t = self.clock.scope(Phase::ContactSearch);
        let t = self.sol.time;
        let x_n = self.coords(&self.sol.u);
        let walls0 = self.model.wall_planes(t);
        let walls1 = self.model.wall_planes(t + dt);
        let Some(b) = self.barrier.as_mut() else { return Ok(()) };
        let h = b.h_min;
        b.walls0 = walls0;
        b.walls1 = walls1;
        b.alpha = if dt > 0.0 { 0.0 } else { 1.0 };
        b.shift = 0.0;
        let reach = b.contact.dhat + if h.is_finite() { h } else { 0.0 };
        // the ties' multipliers as the last converged step left them
        for t in &mut b.contact.ties {
            t.lambda = t.lambda0;
        }
        b.tie_gap = f64::INFINITY;
        let near = b.contact.candidates(&x_n, reach);
        let pairs = b.with_ties(near);
        self.check_ghosts(&x_n, None, reach)?;
        let Some(b) = self.barrier.as_mut() else { return Ok(()) };
        // the barrier at the converged state, with κ as the last commit left it: the friction
        // of this step is lagged there, and the springs' directions are chosen from it (the
        // last evaluation is not that state after a failed attempt: its friction pairs could
        // lie outside the pattern)
        let walls_n = b.walls0.clone();
        let evaluated = b.contact.evaluate(&x_n, &walls_n, PROJECT, &mut b.eval).map_err(|e| NewtonFailure::Contact(e.to_string()));
        self.sys.agree_part(evaluated, "the barrier met a contact at the converged state")?;
        let Some(b) = self.barrier.as_mut() else { return Ok(()) };
        b.friction = if b.has_friction() { b.eval.friction_pairs(&b.contact, &x_n, &b.walls0, b.mu, &b.mu_walls) } else { Vec::new() };
        self.set_barrier_pattern(pairs)?;
        // the springs of this step: every dof, or only the directions the barrier pairs of the
        // last converged state do not hold
        let n_bodies = self.model.bodies.len();
        let b = self.barrier.as_ref().expect("barrier");
        let sys = &self.sys;
        let held = || {
            let held = b.eval.body_support(&b.contact, &b.walls0, n_bodies);
            let Some(p) = &sys.part else { return held };
            // a part's pairs hold its bodies and its ghosts; the other processes' pairs hold
            // them too: the holds of every process, on the whole model's bodies
            let n_whole = self.model.whole_facts().n_bodies;
            let mut all = vec![0.0; 2 * n_whole];
            for (k, h) in held.iter().enumerate() {
                for c in 0..2 {
                    if h[c] {
                        all[2 * p.bodies[k] + c] = 1.0;
                    }
                }
            }
            sys.comm.sum_in_place(&mut all);
            p.bodies.iter().map(|&g| [all[2 * g] > 0.0, all[2 * g + 1] > 0.0]).collect()
        };
        self.springs.prepare(&self.model.stabilisation, &self.sol.u, &self.u_prev, dt, self.run.dt_prev, self.time.dt, held);
        Ok(())
    }

    /// On a part: that its ghosts still hold every other process's body within `reach` of
    /// one of its own at `x` (the boxes of every process's bodies, gathered). The ghosts are
    /// chosen when the part is made; a body that comes within reach of one that is not its
    /// ghost would miss pairs, so the step stops at once ([`NewtonFailure::Ghosts`]) naming
    /// them, before anything of it is done: the caller makes the parts again there. Nothing to
    /// check without a part.
    /// With `x1`, the boxes hold each body at `x` and at `x1` (a path's start and end).
    fn check_ghosts(&self, x: &[[f64; 2]], x1: Option<&[[f64; 2]]>, reach: f64) -> Result<(), NewtonFailure> {
        let Some(p) = &self.sys.part else { return Ok(()) };
        // (global body, box) of its own bodies, then every process's
        let mut at = crate::distribute::particles_at(&self.model, x);
        if let Some(x1) = x1 {
            for (a, b) in at.iter_mut().zip(crate::distribute::particles_at(&self.model, x1)) {
                a.min = [a.min[0].min(b.min[0]), a.min[1].min(b.min[1])];
                a.max = [a.max[0].max(b.max[0]), a.max[1].max(b.max[1])];
            }
        }
        let n = self.model.whole_facts().n_bodies;
        let (boxes, known) = crate::parallel::part::all_boxes(&*self.sys.comm, p.bodies.iter().copied().zip(at).take(p.own_bodies), n);
        let mut local = vec![false; n];
        for &g in &p.bodies {
            local[g] = true;
        }
        let missing = match partition::particle_graph(&boxes, partition::Adjacency::Proximity { gap: reach }) {
            Ok(graph) => p.bodies[..p.own_bodies].iter().find_map(|&a| graph.neighbors(a).iter().find(|&&c| known[c] && !local[c]).map(|&c| Ok((a, c)))),
            Err(e) => Some(Err(format!("the ghost layer's check: {e}"))),
        };
        // (every process stops alike, each naming what it found)
        let failed = self.sys.any(missing.is_some());
        match missing {
            Some(Ok((a, c))) => Err(NewtonFailure::Ghosts(format!("body {c} came within {reach:.3e} mm of body {a} of process {} but is not one of its ghosts", self.sys.comm.rank()))),
            Some(Err(e)) => Err(NewtonFailure::Part(e)),
            None if failed => Err(NewtonFailure::Ghosts("a ghost layer no longer covers its contacts on another process".into())),
            None => Ok(()),
        }
    }

    /// The barrier terms at coordinates `x` (the walls where they are in the step): evaluated,
    /// with the pattern grown first when a pair within d̂ has no block and a tangent is asked
    /// for. An iterate where a node touches an edge or a wall is an error (the line search
    /// backs off; CCD keeps it from happening).
    pub(super) fn evaluate_barrier(&mut self, x: &[[f64; 2]], tangent: bool) -> Result<(), NewtonFailure> {
        let _t = self.clock.scope(Phase::ContactAssembly);
        let Some(b) = self.barrier.as_mut() else { return Ok(()) };
        let walls = b.walls_at(b.alpha);
        let evaluated = b.contact.evaluate(x, &walls, PROJECT, &mut b.eval).map_err(|e| NewtonFailure::Contact(e.to_string()));
        // (a part: every process learns whether any met a contact, and whether any pattern grows)
        self.sys.agree_part(evaluated, "the barrier met a contact")?;
        let Some(b) = self.barrier.as_mut() else { return Ok(()) };
        if tangent {
            let c = &b.contact;
            let missing: Vec<(usize, usize)> = b.eval.edges.iter().map(|e| (e.node, e.segment)).chain(b.eval.quads.iter().map(|q| (c.edge_key(q.edge), q.segment))).filter(|p| b.pattern.binary_search(p).is_err()).collect();
            if self.sys.any(!missing.is_empty()) {
                // (with every pair within d̂ + h of this iterate, as at the start of a step, so
                // that the next iterates seldom grow it again: each growth assembles the
                // pattern anew and analyses it again, 10 % of a 256-polygon compaction when
                // only the missing pairs were added, docs/robustness.md)
                let reach = b.contact.dhat + if b.h_min.is_finite() { b.h_min } else { 0.0 };
                let mut pairs = b.pattern.clone();
                pairs.extend(missing);
                pairs.extend(b.contact.candidates(x, reach));
                pairs.sort_unstable();
                pairs.dedup();
                tracing::debug!(pairs = pairs.len(), "barrier pattern grows");
                self.set_barrier_pattern(pairs)?;
            }
        }
        Ok(())
    }

    /// The part of the incremental potential the contact knows in closed form at `u` (the
    /// barrier's energy at its last evaluation, which must be at `u`, and the lagged
    /// friction's) and its slope along `du` (every dof): for the line search, which takes
    /// their change exactly ([`super::newton`]). `None` without the barrier.
    pub(super) fn contact_potential(&self, u: &[f64], du: &[f64]) -> Option<(f64, f64)> {
        let b = self.barrier.as_ref()?;
        let (mut energy, mut slope) = (b.eval.energy, b.eval.slope(du));
        let eps = FRICTION_EPS * b.h_min;
        for fp in &b.friction {
            let t = fp.term(u, &self.sol.u, eps);
            energy += t.energy;
            slope += (0..fp.width).map(|i| t.grad[i] * du[fp.dofs[i]]).sum::<f64>();
        }
        if self.sys.part.is_some() {
            let mut v = [energy, slope];
            self.sys.comm.sum_in_place(&mut v);
            [energy, slope] = v;
        }
        Some((energy, slope))
    }

    /// Add the barrier terms of the last evaluation to the internal force and (on the process
    /// that holds the tangent) the tangent; their statistics become the contact statistics.
    pub(super) fn add_barrier(&mut self, u: &[f64], tangent: bool) {
        let _t = self.clock.scope(Phase::ContactAssembly);
        // the coordinates for the ties (none needed without them)
        let x = self.barrier.as_ref().is_some_and(|b| !b.contact.ties.is_empty()).then(|| self.coords(u));
        let Some(b) = self.barrier.as_ref() else { return };
        let sys = &mut self.sys;
        b.eval.add_gradient(&mut sys.f_int);
        // the lagged friction: its slip since the start of the step
        let eps = FRICTION_EPS * b.h_min;
        // the whole force of the particles on each wall (the statistics): the wall pairs'
        // barrier terms, and below their lagged friction
        let mut wall_load = vec![[0.0; 2]; b.eval.wall_force.len()];
        for w in &b.eval.walls {
            wall_load[w.wall][0] += w.term.grad[0];
            wall_load[w.wall][1] += w.term.grad[1];
        }
        for fp in &b.friction {
            let t = fp.term(u, &self.sol.u, eps);
            for i in 0..fp.width {
                sys.f_int[fp.dofs[i]] += t.grad[i];
            }
            // (a wall pair: its id is (node, usize::MAX − wall))
            if fp.block.is_none() {
                if let Some(load) = wall_load.get_mut(usize::MAX - fp.id.1) {
                    load[0] += t.grad[0];
                    load[1] += t.grad[1];
                }
            }
            if tangent {
                match fp.block {
                    Some(pair) => {
                        let i = b.pattern.binary_search(&pair).expect("the pattern holds every lagged pair");
                        let mut h = [0.0; 64];
                        let w = fp.width;
                        for (r, row) in t.hess[..w].iter().enumerate() {
                            h[r * w..(r + 1) * w].copy_from_slice(&row[..w]);
                        }
                        sys.maps.pairs.add(&mut sys.kk.values, i, &h[..w * w]);
                    }
                    None => {
                        let i = b.contact.nodes.binary_search_by_key(&fp.node, |&(n, _)| n).expect("a boundary node");
                        let h = [t.hess[0][0], t.hess[0][1], t.hess[1][0], t.hess[1][1]];
                        sys.maps.nodes.add(&mut sys.kk.values, i, &h);
                    }
                }
            }
        }
        // the ties
        if let Some(x) = &x {
            for tie in &b.contact.ties {
                let t = tie.term(&x, &b.contact.segments, b.tie_stiffness);
                for i in 0..6 {
                    sys.f_int[tie.dofs[i]] += t.grad[i];
                }
                if tangent {
                    let i = b.pattern.binary_search(&(tie.node, tie.segment)).expect("the pattern holds every tie");
                    sys.maps.pairs.add(&mut sys.kk.values, i, t.hess.as_flattened());
                }
            }
        }
        if tangent {
            for e in &b.eval.edges {
                let i = b.pattern.binary_search(&(e.node, e.segment)).expect("the pattern holds every pair within d̂");
                sys.maps.pairs.add(&mut sys.kk.values, i, e.term.hess.as_flattened());
            }
            for w in &b.eval.walls {
                let i = b.contact.nodes.binary_search_by_key(&w.node, |&(n, _)| n).expect("a boundary node");
                sys.maps.nodes.add(&mut sys.kk.values, i, w.term.hess.as_flattened());
            }
            for q in &b.eval.quads {
                let i = b.pattern.binary_search(&(b.contact.edge_key(q.edge), q.segment)).expect("the pattern holds every pair within d̂");
                sys.maps.pairs.add(&mut sys.kk.values, i, q.term.hess.as_flattened());
            }
        }
        self.contact_stats = ContactStats {
            wall_force: b.eval.wall_force.clone(),
            wall_load,
            max_penetration: 0.0,
            active: b.eval.edges.len() + b.eval.quads.len() + b.eval.walls.len() + b.contact.ties.len(),
            violation: 0.0,
        };
    }

    /// Add to the Newton right-hand side the linearised effect of moving the walls the rest of
    /// the way through the step (H n Δw on the nodes of the wall pairs, see the module docs).
    pub(super) fn add_wall_motion(&mut self) {
        let Some(b) = self.barrier.as_ref() else { return };
        if b.alpha >= 1.0 {
            return;
        }
        let now = b.walls_at(b.alpha);
        for w in &b.eval.walls {
            let (a, z) = (&now[w.wall], &b.walls1[w.wall]);
            let l = a.normal[0].hypot(a.normal[1]);
            let n = [a.normal[0] / l, a.normal[1] / l];
            let advance = (z.point[0] - a.point[0]) * n[0] + (z.point[1] - a.point[1]) * n[1];
            for i in 0..2 {
                let q = self.sys.assembler.eq[2 * w.node + i];
                if q != FIXED {
                    self.sys.r[q] += (w.term.hess[i][0] * n[0] + w.term.hess[i][1] * n[1]) * advance;
                }
            }
        }
    }

    /// The largest fraction of the Newton update `du` (every dof) from `u` that keeps every
    /// node off every edge of another particle and in front of the walls, which move with it
    /// to their end-of-step positions (CCD with IPC's conservative rescaling).
    pub(super) fn barrier_step_limit(&mut self, u: &[f64], du: &[f64]) -> Result<f64, NewtonFailure> {
        let moved: Vec<f64> = u.iter().zip(du).map(|(a, b)| a + b).collect();
        let alpha = self.barrier.as_ref().map_or(1.0, |b| b.alpha);
        self.collision_free_fraction(u, &moved, alpha, 1.0)
    }

    /// The largest fraction of the straight path from `u0` to `u1` (every dof), the walls
    /// moving from progress `alpha0` to `alpha1` through the step, that meets no contact (CCD
    /// with IPC's conservative rescaling; 1 when nothing meets along the whole path).
    ///
    /// On a part, the fraction of the path may also bring one of its bodies within d̂ of
    /// another process's body that is not its ghost, which its CCD cannot see: then
    /// [`NewtonFailure::Ghosts`] (the step is made again on new parts).
    pub(super) fn collision_free_fraction(&mut self, u0: &[f64], u1: &[f64], alpha0: f64, alpha1: f64) -> Result<f64, NewtonFailure> {
        let _t = self.clock.scope(Phase::ContactSearch);
        let x0 = self.coords(u0);
        let x1 = self.coords(u1);
        let Some(b) = self.barrier.as_ref() else { return Ok(1.0) };
        let dhat = b.contact.dhat;
        let fraction = self.sys.min(b.contact.collision_free_step(&x0, &x1, &b.walls_at(alpha0), &b.walls_at(alpha1)));
        if self.sys.part.is_some() {
            // (the line search goes no farther than the fraction along the path)
            let reached: Vec<[f64; 2]> = x0.iter().zip(&x1).map(|(a, z)| [a[0] + fraction * (z[0] - a[0]), a[1] + fraction * (z[1] - a[1])]).collect();
            self.check_ghosts(&x0, Some(&reached), dhat)?;
        }
        Ok(fraction)
    }

    /// After a converged solve with friction: the friction lagged again at the converged
    /// configuration `u`; true (solve again) when a followed point's μλ changed by more than
    /// [`FRICTION_TOL`] of the largest
    /// ([`crate::contact::barrier_problem::friction_residual`]), the update does not go back
    /// to the friction of two solves ago, and fewer than [`MAX_FRICTION_UPDATES`] updates were
    /// made (`updates`: 0 at the first after the step's first solve).
    ///
    /// The lagging is a fixed-point iteration on μλ. Where friction carries more of a load
    /// than the normal force that limits it, the iteration multiplies the error by less than
    /// −1, or a point slides to and fro over a vertex between two solves; then it alternates
    /// between two states for good (robustness case 06: the same two for 14 updates, twice;
    /// case 11 four times). Such a cycle is seen as the lagging coming back to where it was two
    /// solves before, to within [`FRICTION_TOL`]: the step keeps its last solve.
    pub(super) fn update_barrier_friction(&mut self, u: &[f64], updates: usize) -> bool {
        if !self.barrier.as_ref().is_some_and(|b| b.has_friction() && !b.lag_ended) {
            return false;
        }
        if updates == 0 {
            if let Some(b) = self.barrier.as_mut() {
                b.friction_before.clear();
            }
        }
        let Some((new, changes)) = self.lag_again(u, true) else { return false };
        let relative = changes[0] / changes[2].max(f64::MIN_POSITIVE);
        let Some(b) = self.barrier.as_mut() else { return false };
        match lagging(changes, FRICTION_TOL) {
            Lagging::Converged => return false,
            Lagging::Cycle => {
                tracing::debug!(change = relative, updates, "lagged friction alternates between two states: the last solve stays");
                b.lag_ended = true;
                return false;
            }
            Lagging::Again if updates >= MAX_FRICTION_UPDATES => {
                tracing::warn!(change = relative, "lagged friction not converged after the allowed updates");
                b.lag_ended = true;
                return false;
            }
            Lagging::Again => tracing::debug!(change = relative, "lagged friction updated"),
        }
        b.lag_change = changes[0];
        b.friction_before = std::mem::replace(&mut b.friction, new);
        true
    }

    /// Whether the lagged friction, lagged again at `u`, would change by no more than
    /// [`FRICTION_TOL`] of the largest μλ: a solve stopped early for a friction update that
    /// would not come goes on to the solver's tolerance instead ([`LAG_FORCING`]).
    pub(super) fn friction_settled(&mut self, u: &[f64]) -> bool {
        self.lag_again(u, false).is_none_or(|(_, changes)| matches!(lagging(changes, FRICTION_TOL), Lagging::Converged))
    }

    /// The friction lagged again at `u` and its changes from the lagged friction
    /// ([`lag_changes`], each the largest over the processes; from the friction before the last
    /// update too when `with_before`).
    fn lag_again(&mut self, u: &[f64], with_before: bool) -> Option<(Vec<FrictionPair>, [f64; 3])> {
        let x = self.coords(u);
        let b = self.barrier.as_ref()?;
        let walls = b.walls_at(b.alpha);
        let new = b.eval.friction_pairs(&b.contact, &x, &walls, b.mu, &b.mu_walls);
        let before = (with_before && !b.friction_before.is_empty()).then_some(&b.friction_before[..]);
        let changes = lag_changes(before, &b.friction, &new).map(|v| self.sys.max(v));
        Some((new, changes))
    }

    /// After a converged solve with ties: Uzawa's update of their multipliers, λ ← λ + k g;
    /// true (solve again) when a tie's gap exceeds [`TIE_TOL`] × h, the last update at least
    /// halved the largest gap, and fewer than [`MAX_TIE_UPDATES`] updates were made.
    ///
    /// The updates stall where closing a tie's gap means compressing a stiffer neighbour — a
    /// barrier pair at a small gap next to a new tie, whose stiffness 2κd̂⁴/d² exceeds the
    /// tie's 100 E by orders of magnitude: the largest gap then shrank by 2 % an update on the
    /// tied 2 × 2 discs (measured). There the ties stay penalties of 100 E for the step, with a
    /// gap of at most ~1e-4 h, and the solve is not repeated for nothing.
    pub(super) fn update_barrier_ties(&mut self, u: &[f64], updates: usize) -> bool {
        // (on a part every process decides alike: from the whole model's ties and their gaps)
        if !self.barrier.as_ref().is_some_and(|b| b.n_ties > 0) {
            return false;
        }
        let x = self.coords(u);
        let Some(b) = self.barrier.as_ref() else { return false };
        let segments = &b.contact.segments;
        let gaps: Vec<[f64; 2]> = b.contact.ties.iter().map(|t| t.gap(&x, segments)).collect();
        let worst = self.sys.max(gaps.iter().map(|g| g[0].hypot(g[1])).fold(0.0, f64::max));
        let Some(b) = self.barrier.as_mut() else { return false };
        let k = b.tie_stiffness;
        if worst <= TIE_TOL * b.h_min {
            return false;
        }
        if worst > 0.5 * b.tie_gap {
            tracing::debug!(gap = worst, last = b.tie_gap, "tie updates stall: the ties stay penalties for this step");
            return false;
        }
        b.tie_gap = worst;
        if updates >= MAX_TIE_UPDATES {
            tracing::warn!(gap = worst, tol = TIE_TOL * b.h_min, "ties not converged after the allowed updates");
            return false;
        }
        for (t, g) in b.contact.ties.iter_mut().zip(gaps) {
            t.lambda[0] += k * g[0];
            t.lambda[1] += k * g[1];
        }
        true
    }

    /// The contact state per node of the converged displacements `u` of a step (from the
    /// barrier's last evaluation, there, and the step's lagged friction and ties), for the
    /// results files:
    /// - `force`: the force of the barrier, the friction and the ties on the node (N/mm), as
    ///   the node of a pair or an end of its edge;
    /// - `pressure`, `shear`: the normal and tangential components of that force over the
    ///   node's tributary contact length ([`NodalContact::set_tractions`], current
    ///   configuration), so that Σ pressure × length over a side is the normal force it carries;
    /// - `gap`: the smallest distance the barrier acts on at the node, to an edge of another
    ///   particle or to a wall's barrier plane (which lies the wall offset behind the wall);
    ///   NaN beyond d̂ (mm, never negative);
    /// - `status`: 0 no force, 1 sliding (frictionless, or a slip of the step beyond ε_v),
    ///   2 sticking (a slip below ε_v), 3 tied;
    /// - `wall_force`: the normal force the node exerts on each wall (N/mm); summed over the
    ///   nodes, the history's wall forces.
    pub(super) fn barrier_nodal(&self, u: &[f64]) -> NodalContact {
        let n_nodes = self.model.x0.len();
        let Some(b) = self.barrier.as_ref() else { return NodalContact::default() };
        let x = self.coords(u);
        let walls = b.walls_at(b.alpha);
        let mut out = NodalContact { pressure: vec![0.0; n_nodes], shear: vec![0.0; n_nodes], gap: vec![f64::NAN; n_nodes], status: vec![0; n_nodes], force: vec![[0.0; 2]; n_nodes], wall_force: vec![vec![0.0; n_nodes]; walls.len()] };
        let mut normal = vec![[0.0f64; 2]; n_nodes];
        let gap = |g: &mut Vec<f64>, n: usize, d: f64| {
            if !(g[n] <= d) {
                g[n] = d;
            }
        };
        for e in &b.eval.edges {
            let [a, c] = b.contact.segments[e.segment].nodes;
            for (i, n) in [e.node, a, c].into_iter().enumerate() {
                normal[n][0] -= e.term.grad[2 * i];
                normal[n][1] -= e.term.grad[2 * i + 1];
            }
            gap(&mut out.gap, e.node, e.distance);
        }
        for q in &b.eval.quads {
            let [c, d] = b.contact.segments[q.edge].nodes;
            let [a, e] = b.contact.segments[q.segment].nodes;
            for (i, n) in [c, d, a, e].into_iter().enumerate() {
                normal[n][0] -= q.term.grad[2 * i];
                normal[n][1] -= q.term.grad[2 * i + 1];
            }
            gap(&mut out.gap, if q.xi < 0.5 { c } else { d }, q.distance);
        }
        for w in &b.eval.walls {
            normal[w.node][0] -= w.term.grad[0];
            normal[w.node][1] -= w.term.grad[1];
            let n = unit(walls[w.wall].normal);
            out.wall_force[w.wall][w.node] -= w.term.grad[0] * n[0] + w.term.grad[1] * n[1];
            gap(&mut out.gap, w.node, w.distance);
        }
        let eps = FRICTION_EPS * b.h_min;
        // the friction's and the ties' forces; whether each node sticks or is tied (its status
        // is decided once the forces of every process's pairs are summed)
        let mut force = normal.clone();
        let mut flags = vec![0.0; 2 * n_nodes];
        for fp in &b.friction {
            let t = fp.term(u, &self.sol.u, eps);
            for i in 0..fp.width {
                force[fp.dofs[i] / 2][fp.dofs[i] % 2] -= t.grad[i];
            }
            let slip: f64 = (0..fp.width).map(|i| fp.w[i] * (u[fp.dofs[i]] - self.sol.u[fp.dofs[i]])).sum();
            if fp.mu_lambda > 0.0 && slip.abs() < eps {
                flags[2 * fp.node] = 1.0;
            }
        }
        for tie in &b.contact.ties {
            let t = tie.term(&x, &b.contact.segments, b.tie_stiffness);
            for i in 0..6 {
                force[tie.dofs[i] / 2][tie.dofs[i] % 2] -= t.grad[i];
            }
            flags[2 * tie.node + 1] = 1.0;
        }
        if let Some(p) = &self.sys.part {
            // a node's pairs are evaluated by the processes owning their first sides: its
            // owner sums their forces, takes the smallest gap and any flag, and its ghosts get
            // the owner's values
            let nw = out.wall_force.len();
            let bs = 4 + nw;
            let mut sums: Vec<f64> = (0..n_nodes).flat_map(|n| [normal[n][0], normal[n][1], force[n][0], force[n][1]].into_iter().chain(out.wall_force.iter().map(move |w| w[n]))).collect();
            p.nodes.reverse_add(&mut sums, bs);
            p.nodes.forward(&mut sums, bs);
            let mut least: Vec<f64> = (0..n_nodes).flat_map(|n| [out.gap[n], -flags[2 * n], -flags[2 * n + 1]]).collect();
            p.nodes.reverse_with(&mut least, 3, |o, g| {
                if !g.is_nan() && !(*o <= g) {
                    *o = g;
                }
            });
            p.nodes.forward(&mut least, 3);
            for n in 0..n_nodes {
                let r = &sums[n * bs..(n + 1) * bs];
                normal[n] = [r[0], r[1]];
                force[n] = [r[2], r[3]];
                for (w, v) in out.wall_force.iter_mut().zip(&r[4..]) {
                    w[n] = *v;
                }
                out.gap[n] = least[3 * n];
                flags[2 * n] = -least[3 * n + 1];
                flags[2 * n + 1] = -least[3 * n + 2];
            }
        }
        for n in 0..n_nodes {
            if normal[n] != [0.0; 2] {
                out.status[n] = if flags[2 * n] > 0.0 { 2 } else { 1 };
            }
            if flags[2 * n + 1] > 0.0 {
                out.status[n] = 3;
            }
            out.force[n] = force[n];
        }
        out.set_tractions(&x, &b.contact.segments);
        // a node that no barrier pair touches carries no contact: a force on it is the lagged
        // friction of a pair that opened in the last solve, within the lagging's tolerance
        // (`FRICTION_TOL` of the largest μλ; seen: 0.02 N/mm on robustness-size runs). It stays
        // in `force` (the nodal forces still add up to the walls'), but the node reads open,
        // without pressure or shear: as a traction it would have no normal to be read against.
        for n in 0..n_nodes {
            if normal[n] == [0.0; 2] && out.status[n] != 3 {
                out.status[n] = 0;
                out.pressure[n] = 0.0;
                out.shear[n] = 0.0;
            }
        }
        out
    }

    /// Factor the tangent; in the barrier's retry of a failed step (`descent`), make it
    /// positive definite first where it is not. The update then descends on the incremental
    /// potential instead of heading for a saddle: where two particles' corners face each
    /// other the barrier's Hessian has a negative curvature of the order of the force over the
    /// gap, and Newton with the exact tangent circled there (robustness case 08). A tangent
    /// the Cholesky factorisation finds indefinite, or that fails to factor outright, is made
    /// definite in two stages, the second tried only when the first did not do it:
    /// 1. each barrier pair's Hessian replaced by its projection onto the PSD matrices
    ///    ([`Simulation::project_pair_hessians`]): a node facing another particle's corner
    ///    has a negative curvature of the order of its force over the gap for sliding past
    ///    it (the point–point distance's Hessian is (I − n nᵀ)/d), and the projection removes
    ///    it where it arises, while a shift large enough to cover it slows every dof (on the
    ///    2 × 2 biaxial discs with d̂/2 a shift alone took τ = 0.1, converged linearly, the
    ///    residual falling by 0.88 an iteration, and failed a step; `tests/barrier_compaction.rs`);
    /// 2. a shift of the projected tangent's diagonal (Levenberg–Marquardt,
    ///    [`Simulation::shift_until_definite`], from a tenth of the last τ that worked in this
    ///    attempt, or [`SHIFT_MIN`], up to τ = 1, definite by Gershgorin): what the elements
    ///    themselves lack, a compressed J2 or Hencky element's geometric stiffness.
    ///
    /// A tangent that is definite as it is stays exact, so Newton converges quadratically once
    /// the iterate has left the saddle (projecting in every iteration of the retry, also where
    /// the tangent is definite, raised the iterations of robustness cases 01–08 by 1.3–2.6
    /// times, twenty-fifth measurement). At a minimum the tangent is positive definite and
    /// Newton is unchanged, so is the solution. On several processes the solving one's finding
    /// is broadcast, so that all take the same shifts.
    ///
    /// Until the twenty-fifth measurement (docs/robustness.md) a small shift, τ up to 1e-4,
    /// came first and the projection second: with the stabilisation springs in the residual,
    /// projecting first had put 8.5–9.7 % of the wall work into the springs on the near-rigid
    /// ellipses of robustness case 10. Without the springs the order costs only factorisations:
    /// in the dense steps of a 256-polygon compaction nearly every tangent is indefinite, and
    /// the small shifts failed one to three factorisations before the one that held; with the
    /// projection first (and the two changes of the same measurement, the pattern's growth
    /// and the projection's size) that compaction took 909 iterations instead of 1,031, in
    /// 0.66 of the time, and the eleven cases of the suite 10,717 instead of 11,829
    /// (docs/robustness.md, twenty-fifth measurement).
    ///
    /// The descent starts with the retry of the first step that fails without it (and stays
    /// on from then, [`BarrierRun::descent`]): shifting from the first step changed which
    /// branch a symmetric assembly takes where it bifurcates (the 2 × 2 biaxial discs then
    /// stiffened earlier and missed the penalty method's pressure at 0.95 by 5.8 %,
    /// `tests/barrier_compaction.rs`, measured with the shifts starting at τ = 1e-6).
    pub(super) fn factor_descent(&mut self) -> Result<(), NewtonFailure> {
        let descent = self.barrier.as_ref().is_some_and(|b| b.descent);
        if !descent {
            let r = self.factor();
            // (a solver that cannot tell, LU or iterative, is taken as definite: no saddle
            // is looked for where the tangent is not symmetric)
            let definite = r.is_ok() && self.sys.linear.definite() != Some(false);
            self.note_definite(definite, true);
            return r;
        }
        // (each stage asks only whether the matrix it tries is definite: an LLᵀ factorisation
        // that stops at the first pivot that is not positive, without the indefinite fallback
        // of `factor`, which the descent never solves with; a factorisation that fails
        // outright is shifted as an indefinite one is)
        if self.factor_definite() {
            self.note_definite(true, false);
            return Ok(());
        }
        self.note_definite(false, false);
        self.project_pair_hessians();
        if self.factor_definite() {
            tracing::debug!("indefinite tangent made definite by projecting the pairs' Hessians");
            return Ok(());
        }
        let last = self.barrier.as_ref().map_or(0.0, |b| b.shift);
        let start = if last > 0.0 { (0.1 * last).max(SHIFT_MIN) } else { SHIFT_MIN };
        let shifted = self.shift_until_definite(start, 1.0);
        if let Some(b) = self.barrier.as_mut() {
            b.shift = shifted.unwrap_or(0.0);
        }
        if shifted.is_some() {
            return Ok(());
        }
        tracing::debug!("indefinite tangent kept: neither the projection nor a shift made it definite");
        self.factor()
    }

    /// Solve for the Newton update (right-hand side `sys.r`). An iterative solver has no
    /// factorisation to ask whether the tangent is positive definite: CG tells it by breaking
    /// down on a negative curvature ([`LinearSolver::definite`] then answers false). The
    /// tangent then gets what a Cholesky factorisation's inertia gives an indefinite one: out
    /// of the descent, the exact Newton update (solved again by a Krylov method for indefinite
    /// matrices, GMRES); in it ([`Simulation::factor_descent`]), each stage tried by solving
    /// again: the barrier pairs' Hessians projected, then the diagonal shifted. So CG with the
    /// particles' two-level preconditioner (`-pc_type mg`) takes the direct solve's path.
    ///
    /// [`LinearSolver::definite`]: crate::linalg::LinearSolver::definite
    pub(super) fn solve_update(&mut self) -> Result<(), NewtonFailure> {
        let before = self.sys.linear.definite();
        let r = self.solve_linear();
        // (only what the solve itself found: a factorisation's answer was known before it and
        // acted on; a distributed solve's breakdown is every process's, the KSP's reason is
        // collective)
        if r.is_ok() || self.barrier.is_none() || before == Some(false) || self.sys.linear.definite() != Some(false) {
            return r;
        }
        tracing::debug!("the iterative solve broke down on an indefinite tangent");
        self.note_definite(false, false);
        if !self.barrier.as_ref().is_some_and(|b| b.descent) {
            self.sys.du.iter_mut().for_each(|v| *v = 0.0);
            return self.solve_linear_with(true);
        }
        self.project_pair_hessians();
        self.factor()?;
        if self.solve_again() {
            tracing::debug!("indefinite tangent made definite by projecting the pairs' Hessians");
            return Ok(());
        }
        let last = self.barrier.as_ref().map_or(0.0, |b| b.shift);
        let start = if last > 0.0 { (0.1 * last).max(SHIFT_MIN) } else { SHIFT_MIN };
        let shifted = self.shift_until(start, 1.0, true);
        if let Some(b) = self.barrier.as_mut() {
            b.shift = shifted.unwrap_or(0.0);
        }
        match shifted {
            Some(_) => Ok(()),
            None => {
                // (the last try's failure, as the solver reports it)
                self.factor()?;
                self.sys.du.iter_mut().for_each(|v| *v = 0.0);
                self.solve_linear()
            }
        }
    }

    /// Solve with the tangent just factored, from a zero update: whether it succeeded.
    fn solve_again(&mut self) -> bool {
        self.sys.du.iter_mut().for_each(|v| *v = 0.0);
        self.solve_linear().is_ok()
    }

    /// Record whether the tangent just factored was definite; `from_root`: the answer is the
    /// solving process's alone and goes to the others.
    fn note_definite(&mut self, definite: bool, from_root: bool) {
        let mut flag = [if definite { 1.0 } else { 0.0 }];
        if from_root && self.sys.par.is_some() {
            self.sys.comm.broadcast(&mut flag);
        }
        // (a part: definite when it is so on every process)
        flag[0] = self.sys.min(flag[0]);
        if let Some(b) = self.barrier.as_mut() {
            b.definite = flag[0] > 0.5;
        }
    }

    /// Replace, in the assembled tangent, each barrier pair's Hessian by its projection onto
    /// the PSD matrices (where the tangent is assembled: the root process). The walls' pairs
    /// are left: a wall's distance is linear in the node's position, so their Hessians are
    /// positive semi-definite already.
    pub(super) fn project_pair_hessians(&mut self) {
        if !self.sys.comm.is_root() && self.sys.part.is_none() {
            return;
        }
        let _t = self.clock.scope(Phase::ContactAssembly);
        let Some(b) = self.barrier.as_ref() else { return };
        let sys = &mut self.sys;
        for e in &b.eval.edges {
            let delta = projection_change(&e.term.hess, crate::contact::barrier::project_psd_relative::<6, 4>);
            let i = b.pattern.binary_search(&(e.node, e.segment)).expect("the pattern holds every pair within d̂");
            sys.maps.pairs.add(&mut sys.kk.values, i, delta.as_flattened());
        }
        for q in &b.eval.quads {
            let delta = projection_change(&q.term.hess, |h| crate::contact::barrier::project_psd_point_on_edge(h, q.xi));
            let i = b.pattern.binary_search(&(b.contact.edge_key(q.edge), q.segment)).expect("the pattern holds every pair within d̂");
            sys.maps.pairs.add(&mut sys.kk.values, i, delta.as_flattened());
        }
    }

    /// Raise each diagonal entry of the tangent by τ s_i, s_i twice the absolute sum of its
    /// row, τ = `start`, 10 `start`, … up to `tau_max`, until the Cholesky factorisation finds
    /// it positive definite: that τ then (the shifted diagonal stays in the tangent,
    /// factored); None with the diagonal restored (and the tangent to be factored again)
    /// otherwise. At τ = 1 Gershgorin's theorem makes the matrix positive definite.
    ///
    /// The first shift of an attempt at a step starts at [`SHIFT_MIN`] and the next ones at a
    /// tenth of the last that worked (Levenberg–Marquardt's update of its damping): each τ
    /// tried costs a factorisation, and the iterations of a retry mostly need about the same
    /// τ, while a smaller one that suffices keeps the loose particles' updates whole.
    ///
    /// The row sum, not |K_ii|: on the asphalt octagons of 5.2.1 (ν = 0.5, creep) nodes facing
    /// nodes at gaps of d̂/250 have a negative curvature of the order of the contact force over
    /// the gap, 400 times the elements' stiffness, and a diagonal entry that is itself near
    /// zero; raising it by |K_ii| left the tangent indefinite at τ = 1 (and a zero pivot of the
    /// indefinite fallback failed the step outright, measured).
    pub(super) fn shift_until_definite(&mut self, start: f64, tau_max: f64) -> Option<f64> {
        self.shift_until(start, tau_max, false)
    }

    /// [`Simulation::shift_until_definite`]; `solve`: each shifted tangent is also solved
    /// with (the right-hand side in `sys.r`), and a τ holds only when that solve succeeds (an
    /// iterative solver tells that the tangent is indefinite by breaking down in the solve).
    fn shift_until(&mut self, start: f64, tau_max: f64, solve: bool) -> Option<f64> {
        let mut pos = self.sys.kk.diagonal_positions();
        // (a part shifts its own equations' diagonal; its rows hold its own terms only, so
        // their sums are a lower bound of the whole rows')
        pos.truncate(self.sys.own_eqs());
        let d0: Vec<f64> = pos.iter().map(|p| p.map_or(0.0, |p| self.sys.kk.values[p])).collect();
        // each diagonal entry is raised by τ times twice its row's absolute sum: at τ = 1 the
        // matrix is strictly diagonally dominant with a positive diagonal (Gershgorin), so
        // positive definite, also where a diagonal entry itself is near zero or negative (a
        // barrier pair's negative curvature for sliding past a corner)
        let kk = &self.sys.kk;
        let scale: Vec<f64> = match self.sys.part.as_ref().and(self.sys.linear.own_row_abs_sums()) {
            // (a part: the whole rows, as the solver merged them at the last factorisation)
            Some(sums) => sums.iter().map(|s| 2.0 * s).collect(),
            None => (0..pos.len()).map(|i| 2.0 * kk.values[kk.row_ptr[i]..kk.row_ptr[i + 1]].iter().map(|v| v.abs()).sum::<f64>()).collect(),
        };
        let mut tau = start;
        while tau <= tau_max * (1.0 + 1e-9) {
            for ((p, d), s) in pos.iter().zip(&d0).zip(&scale) {
                if let Some(p) = *p {
                    self.sys.kk.values[p] = d + tau * s;
                }
            }
            if self.factor_definite() && (!solve || self.solve_again()) {
                tracing::debug!(tau, "indefinite tangent shifted");
                return Some(tau);
            }
            tau *= 10.0;
        }
        for (p, d) in pos.iter().zip(&d0) {
            if let Some(p) = *p {
                self.sys.kk.values[p] = *d;
            }
        }
        None
    }

    /// Continue the barrier from a checkpoint's `state`, the committed solution already in
    /// place: κ, the smallest distance and the ties as they were, and the barrier evaluated
    /// again at the converged configuration with the walls where they are (as the step that
    /// converged there left it).
    pub(super) fn restore_barrier(&mut self, state: BarrierState) -> Result<(), String> {
        let n_nodes = self.model.x0.len();
        let n_segments = self.barrier.as_ref().map_or(0, |b| b.contact.segments.len());
        if let Some(t) = state.ties.iter().find(|t| t.node >= n_nodes || t.segment >= n_segments) {
            return Err(format!("barrier ties: node {} or edge {} is not in the model ({n_nodes} nodes, {n_segments} boundary edges)", t.node, t.segment));
        }
        let x = self.coords(&self.sol.u);
        let walls = self.model.wall_planes(self.sol.time);
        let Some(b) = self.barrier.as_mut() else { return Ok(()) };
        b.contact.kappa = state.kappa;
        b.min_distance = state.min_distance;
        b.contact.ties = state.ties;
        b.contact.tied = state.tied;
        b.descent = state.descent;
        let n_ties = self.sys.sum(b.contact.ties.len() as f64) as usize;
        b.update_tie_floor(n_ties);
        b.walls0.clone_from(&walls);
        b.walls1 = walls;
        b.alpha = 1.0;
        let walls = b.walls_at(1.0);
        b.contact.evaluate(&x, &walls, PROJECT, &mut b.eval).map_err(|e| format!("barrier at the checkpoint's state: {e}"))
    }

    /// Whether the walls have arrived at their end-of-step positions (always without the
    /// barrier).
    pub(super) fn walls_arrived(&self) -> bool {
        self.barrier.as_ref().is_none_or(|b| b.alpha >= 1.0)
    }

    /// After a converged step: IPC's stiffness update — when the smallest distance is below
    /// d̂/1000 and still decreasing, κ doubles (up to 10⁴ κ₀), so that gaps stay clear of the
    /// round-off of the distances without an ill-conditioned start.
    /// With cohering particles, every node now within d̂ of another particle is tied to it
    /// (its barrier force becomes the tie's multiplier), at the converged displacements `u`.
    pub(super) fn commit_barrier(&mut self, u: &[f64]) {
        if self.barrier.is_none() {
            return;
        }
        let nodal = self.barrier_nodal(u);
        if let Some(b) = self.barrier.as_mut() {
            b.nodal = nodal;
        }
        let x = self.coords(u);
        let Some(b) = self.barrier.as_mut() else { return };
        for t in &mut b.contact.ties {
            t.lambda0 = t.lambda;
        }
        if b.tie_stiffness > 0.0 {
            // (a part ties its own nodes: the whole model's new ties are every process's)
            let made = self.sys.sum(b.contact.tie_close(&x, Some(&b.eval)) as f64) as usize;
            if made > 0 {
                b.update_tie_floor(b.n_ties + made);
                tracing::debug!(made, ties = b.n_ties, "particles tied");
            }
        }
        let d = b.eval.min_distance;
        let d = if self.sys.part.is_some() { -self.sys.comm.max(-d) } else { d };
        if d < 1e-3 * b.contact.dhat && d < b.min_distance && b.contact.kappa < 1e4 * b.kappa0 {
            b.contact.kappa *= 2.0;
            tracing::debug!(kappa = b.contact.kappa, min_distance = d, "barrier stiffness doubled");
        }
        b.min_distance = d;
    }
}

/// What projecting a pair's Hessian onto the PSD matrices (by `project`) adds to it: P(H) − H.
fn projection_change<const N: usize>(hess: &[[f64; N]; N], project: impl Fn(&mut [[f64; N]; N])) -> [[f64; N]; N] {
    let mut delta = *hess;
    project(&mut delta);
    for (row, h) in delta.iter_mut().zip(hess) {
        for (v, h) in row.iter_mut().zip(h) {
            *v -= h;
        }
    }
    delta
}
