//! The solution of a model in time: the state it acts on, the time-stepping loop, and the
//! Newton solve of each step, in the paper's terms (full or modified Newton–Raphson, eq. 9 /
//! 16; adaptive time steps; the augmented-Lagrangian loop that enforces incompressibility
//! element by element for ν = 0.5).
//!
//! Lifecycle of a step t_n → t_{n+1} = t_n + Δt ([`Simulation::advance`], `stepping`):
//! 1. the contact pairs are selected on the converged configuration and frozen for the step,
//!    the stabilisation springs anchored; prescribed displacements, walls and loads are
//!    evaluated at t_{n+1} ([`crate::loading`]); free displacements are predicted by
//!    extrapolating the last converged increment;
//! 2. Newton iterations `K Δu = F_ext − F_int` (`newton`) until ‖R‖ ≤ tol_R · reference force
//!    and |Δu·R| ≤ tol_E · |Δu₀·R₀|, each residual and tangent formed by the one assembler from
//!    every force term (`Simulation::evaluate`, `system`); material states are evaluated from
//!    the committed ones and never changed inside the iterations;
//! 3. for incompressible bodies the multipliers are updated (λ_e ← p_e), for the augmented
//!    Lagrangian contact the pair multipliers, and step 2 repeats until max |Θ_e − 1| ≤
//!    `volume_tol` and the contact violation is within its tolerance;
//! 4. on success the states are committed and the step may grow; on failure (no convergence,
//!    inverted element, failed return map, failed linear solve) everything of the step is
//!    discarded and it is retried with Δt · cutback, down to `dt_min` (after a retry with
//!    every dof stabilised or the springs viscous, and a re-mesh of a poor particle, when
//!    asked for).
//!
//! The modules: `params` (the case's `[time]` and `[solver]`), `state` (the solution and the
//! run's counters, and what a checkpoint keeps), `report` (step reports, run summary, phase
//! timers), `system` (the global system and the evaluation of every term), `newton` (Newton,
//! line search, the multiplier loops, the predictor, the release of an imbalance), `stepping`
//! (the time loop, cut-back, commit), `remeshing` (re-meshing a running simulation).

mod barrier;
mod migrate;
mod newton;
mod params;
mod remesh_parts;
mod remeshing;
mod report;
mod saddle;
mod snapshot;
mod state;
mod stepping;
mod system;

pub use barrier::DESCENT_ITERATIONS;
pub use params::{NewtonKind, SolverSpec, TimeSpec};
pub use report::{Clock, Compaction, Phase, PhaseScope, RunSummary, StepReport, Timing};
pub use snapshot::{Gathered, Snapshot, WholeRows};
pub use state::{BarrierState, PartitionTotals, RunState, SimScalars, SimState, Solution};

use crate::assembly::{number_equations, AssemblyError, Assembler, ElementFields, FIXED};
use crate::comm::{Collective, Serial};
use crate::contact::{ContactEvals, ContactProblem, ContactStats};
use crate::dynamics::Dynamics;
use crate::linalg::{make_solver_with, LinalgError, LinearSolverKind, SolverOptions};
use crate::material::ConstitutiveLaw;
use crate::model::Model;
use crate::parallel::{Distribution, PartitionStats};
use crate::stabilise::Springs;
use std::sync::Arc;
use system::{System, TermMaps};
use thiserror::Error;

/// The largest relative residual ‖R − K Δu‖/‖R‖ of a direct solve for a Newton update of the
/// barrier contact before the tangent is called singular and the step fails (the linear
/// algebra's own default, which the other contact methods keep, is 1e-6). A Newton update
/// needs no more: an inexact Newton method whose updates solve their systems to a relative
/// residual η < 1 still converges, linearly at the rate η near the
/// solution (Dembo, Eisenstat and Steihaug, SIAM J. Numer. Anal. 19, 1982), and the line
/// search checks that each update descends. Measured: the tangents of the dense packings are
/// ill-conditioned (loose particles held by springs of 1e-8 of the elements' stiffness and by
/// barrier pairs near d̂), their solves end at 1e-6–4e-6 after the refinement, and with the old
/// limit such a solve failed its step and cut it back (robustness case 12 at solid ratio 0.81,
/// its step then held at half its size to the end; docs/robustness.md, twenty-third
/// measurement). A singular tangent's solve is not finite or leaves a residual of order one.
pub const NEWTON_SOLVE_TOL: f64 = 1e-3;

/// Why one Newton solve failed (drives the cut-back).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum NewtonFailure {
    #[error("no convergence in {iterations} iterations (residual history {residuals:?})")]
    NotConverged { iterations: usize, residuals: Vec<f64> },
    #[error("diverged at iteration {iteration} (residual history {residuals:?})")]
    Diverged { iteration: usize, residuals: Vec<f64> },
    /// The residual is not a finite number (NaN, or beyond the floating-point range): `cause`
    /// names where its largest or first non-finite force sits.
    #[error("the residual is not finite at iteration {iteration}: {cause}")]
    NotFinite { iteration: usize, cause: String },
    /// The barrier's collision-free step cut each of the last `max_iterations` updates below
    /// half of itself (in the descent's retry, which may run longer): the step is too long for
    /// the contacts it makes.
    #[error("the collision-free step limited {limited} Newton updates in a row below half of themselves by iteration {iteration}: the step makes contacts faster than they converge (residual history {residuals:?})")]
    ContactLimited { iteration: usize, limited: usize, residuals: Vec<f64> },
    #[error("{0}")]
    Element(#[from] AssemblyError),
    #[error("linear solver: {0}")]
    Linear(String),
    /// An iterate the contact cannot take (the barrier: boundaries touching).
    #[error("contact: {0}")]
    Contact(String),
    /// A stop was asked for ([`Simulation::set_interrupt`]) during the iterations: the step is
    /// abandoned.
    #[error("interrupted")]
    Interrupted,
    /// A distributed part can no longer go on as it is (its ghosts no longer cover its
    /// contacts): no shorter step helps, the run stops (on every process alike).
    #[error("distributed part: {0}")]
    Part(String),
    /// A distributed part's ghosts no longer hold every other process's body within the
    /// contact reach of its own (the particles moved): the caller makes the parts again at
    /// the last converged state ([`Simulation::gather_all`]) and goes on.
    #[error("distributed part: {0}")]
    Ghosts(String),
}

/// The stop reason [`Simulation::run_controlled`] gives when a stop asked for during a step
/// ([`Simulation::set_interrupt`]) abandoned it: the caller checkpoints the last converged
/// state and may say why in its own words.
pub const STOP_ABANDONED: &str = "interrupted during a step (abandoned)";

/// A run that could not go on.
#[derive(Debug, Error)]
pub enum SolveError {
    #[error("step from t = {time:.6e} s failed with dt = {dt:.3e} s (below dt_min = {dt_min:.3e} s): {cause}")]
    StepFailed { time: f64, dt: f64, dt_min: f64, cause: NewtonFailure },
    #[error("maximum number of steps ({0}) reached before the end time")]
    TooManySteps(usize),
    #[error("linear solver setup: {0}")]
    Linear(#[from] LinalgError),
    #[error("re-meshing body {body}: {reason}")]
    Remesh { body: usize, reason: String },
    #[error("contact: {0}")]
    Contact(String),
}

/// A converged but uncommitted step.
struct Trial {
    u: Vec<f64>,
    lambda: Vec<f64>,
    worst: f64,
    iterations: usize,
    updates: usize,
    residual: f64,
}

/// The simulation of a model: its solution and run state, the global system, and the force
/// terms besides the elements (contact, stabilisation springs, inertia).
pub struct Simulation {
    pub model: Model,
    pub time: TimeSpec,
    pub spec: SolverSpec,
    /// The committed solution.
    pub sol: Solution,
    /// Counters, energies and the step-size control between steps.
    run: RunState,
    /// u_{n−1}: the predictor's and the inertial stabilisation's previous displacement.
    u_prev: Vec<f64>,
    /// The global system: assembler, pattern, matrix, vectors, linear solver, processes.
    sys: System,
    /// Volumetric data per element: the bulk modulus κ (or the augmented-Lagrangian penalty of
    /// an incompressible body) and whether the element's body is incompressible.
    kappa: Vec<f64>,
    incompressible: Vec<bool>,
    /// Contact with walls and between bodies (None: nothing can touch), the statistics of its
    /// last evaluation and the buffer of its evaluations.
    pub contact: Option<ContactProblem>,
    contact_stats: ContactStats,
    contact_evals: ContactEvals,
    /// The barrier contact (`[contact] method = "barrier"`; then `contact` is None).
    barrier: Option<barrier::BarrierRun>,
    /// The stabilisation springs of a contact problem.
    springs: Springs,
    /// Newmark / HHT-α state of an implicit dynamic analysis (None: quasi-static).
    dynamics: Option<Dynamics>,
    /// Wall time per phase.
    clock: Clock,
    /// The stop flag looked at before every Newton iteration ([`Simulation::set_interrupt`]).
    interrupt: Option<Arc<std::sync::atomic::AtomicUsize>>,
}

impl Simulation {
    /// Build the driver. `threads` = 0 uses every core; 1 assembles sequentially.
    pub fn new(model: Model, time: TimeSpec, spec: SolverSpec) -> Result<Self, SolveError> {
        Self::new_with(model, time, spec, Arc::new(Serial))
    }

    /// As [`Simulation::new`], on the processes of `comm`: every process builds the same
    /// model and calls this; each assembles the elements of the particles it owns, rank 0
    /// solves the linear systems (see [`crate::parallel`]). With one process this is
    /// [`Simulation::new`].
    pub fn new_with(model: Model, time: TimeSpec, spec: SolverSpec, comm: Arc<dyn Collective>) -> Result<Self, SolveError> {
        Self::build(model, time, spec, comm, None)
    }

    /// [`Simulation::new_with`] for a state set right after it ([`Simulation::set_state`]: a
    /// restart): its reference configuration is not checked as a start (a particle re-meshed
    /// before the checkpoint has its configuration then as its reference, beside the others'
    /// original ones); the barrier is checked at the state set.
    pub fn new_for_state(model: Model, time: TimeSpec, spec: SolverSpec, comm: Arc<dyn Collective>) -> Result<Self, SolveError> {
        Self::build_with(model, time, spec, comm, None, None, true)
    }

    /// [`Simulation::new_part`] for a state set right after it ([`Simulation::set_whole_state`]:
    /// a restart on parts; see [`Simulation::new_for_state`]).
    pub fn new_part_for_state(part: crate::parallel::part::RankPart, time: TimeSpec, spec: SolverSpec) -> Result<Self, SolveError> {
        Self::part_simulation(part, time, spec, true)
    }

    /// [`Simulation::new_with`]; with `previous` (the owners of the bodies in the simulation
    /// this one replaces, when any process owned them, and its partition figures) the owners
    /// are kept unless their imbalance on the new model is above `[solver]
    /// repartition_imbalance` (see [`Distribution::build`]).
    fn build(model: Model, time: TimeSpec, spec: SolverSpec, comm: Arc<dyn Collective>, previous: Option<(Option<&[usize]>, &PartitionStats)>) -> Result<Self, SolveError> {
        // (a rebuild for a re-mesh starts from the running state, set after it)
        let rebuild = previous.is_some();
        Self::build_with(model, time, spec, comm, previous, None, rebuild)
    }

    /// What of `model` a distributed part ([`Simulation::new_part`]) does not take
    /// yet, None when it takes them all.
    pub fn part_refusal(model: &Model) -> Option<&'static str> {
        if !model.has_contact() {
            Some("a model without contact (one body, no walls)")
        } else if model.contact.method != crate::contact::ContactMethod::Barrier {
            Some("a contact method other than the barrier")
        } else {
            None
        }
    }

    /// The simulation of this process's part of a distributed model (the owned + ghost state,
    /// [`crate::parallel::part::RankPart`]): it holds the meshes and states of its own
    /// particles and of its ghosts only, evaluates the elements of its own particles and the
    /// barrier pairs whose first side is on one of them, and solves with PETSc over the
    /// processes (see [`crate::parallel`]). Every process of the part's map calls this.
    ///
    /// For now a part takes the barrier contact (frictionless, with friction or cohering),
    /// quasi-statics (with re-meshing) or implicit dynamics; anything else is refused by name.
    ///
    /// # Errors
    /// What the part cannot take (above), or what [`Simulation::new`] refuses.
    pub fn new_part(part: crate::parallel::part::RankPart, time: TimeSpec, spec: SolverSpec) -> Result<Self, SolveError> {
        Self::part_simulation(part, time, spec, false)
    }

    /// [`Simulation::new_part`]; with `rebuild` the part is made for a running state (set after
    /// it: a part grown again or re-meshed), whose reference configuration is not checked as a
    /// start (a re-meshed particle's is its configuration when it was re-meshed).
    pub(super) fn part_simulation(part: crate::parallel::part::RankPart, time: TimeSpec, spec: SolverSpec, rebuild: bool) -> Result<Self, SolveError> {
        let model = &part.model;
        let unsupported = Self::part_refusal(model);
        if let Some(what) = unsupported {
            return Err(SolveError::Contact(format!("a distributed part does not take {what} yet")));
        }
        let (eq, _) = number_equations(model.n_dofs(), model.loading.prescribed.iter().map(|p| p.dof));
        let comm = part.nodes.comm_arc();
        let eqs = part.equation_map(&eq).map_err(|e| SolveError::Linear(LinalgError::Other(e.to_string())))?;
        let crate::parallel::part::RankPart { model, bodies, n_owned_bodies, nodes, whole_eq, whole, layout, reach } = part;
        let own_dofs = 2 * nodes.n_owned();
        let own_eqs = eqs.n_owned();
        // the whole model's equation of each of the part's equations
        let mut eq_whole = vec![0; eqs.n_local()];
        for (d, &q) in eq.iter().enumerate() {
            if q != FIXED {
                eq_whole[q] = whole_eq.get(d).copied().unwrap_or(FIXED);
            }
        }
        let sys = system::PartSys { nodes, eqs: Arc::new(eqs), own_dofs, own_eqs, bodies, own_bodies: n_owned_bodies, eq_whole, layout, whole, reach };
        Self::build_with(model, time, spec, comm, None, Some(sys), rebuild)
    }

    fn build_with(model: Model, time: TimeSpec, spec: SolverSpec, comm: Arc<dyn Collective>, previous: Option<(Option<&[usize]>, &PartitionStats)>, part: Option<system::PartSys>, rebuild: bool) -> Result<Self, SolveError> {
        let mut partition = previous.map_or_else(PartitionStats::default, |p| p.1.clone());
        let par = if let Some(p) = &part {
            // (a part: its owners change only when it is repartitioned, `migrate.rs`; the
            // imbalance follows the re-meshes)
            partition.ranks = comm.size();
            partition.imbalance = p.layout.imbalance(comm.size());
            partition.edge_cut = p.layout.edge_cut;
            None
        } else {
            Distribution::build(&model, comm.clone(), previous.and_then(|p| p.0), spec.repartition_imbalance, &mut partition)
        };
        // (a part: whether each of its bodies is its own)
        let own_body: Vec<bool> = (0..model.bodies.len()).map(|b| part.as_ref().is_none_or(|p| b < p.own_bodies)).collect();
        let n_dofs = model.n_dofs();
        let (eq, n_free) = number_equations(n_dofs, model.loading.prescribed.iter().map(|p| p.dof));
        let mut contact = model.contact_problem();
        let (mut assembler, mut kk) = Assembler::new(&model, eq, n_free);
        let (mut pair_dofs, mut multiplier_dofs, mut node_dofs) = (Vec::new(), Vec::new(), Vec::new());
        if let Some(c) = contact.as_mut() {
            c.select_pairs(&model.x0, &model.wall_planes(0.0));
            (pair_dofs, multiplier_dofs, node_dofs) = (c.pair_dof_lists(), c.multiplier_dofs(), c.node_dof_lists());
            assembler.set_terms(&mut kk, &pair_dofs, &multiplier_dofs);
        }
        // (the whole model's figures, also when this is a process's part of it)
        let whole = model.whole_facts();
        let h = whole.h_min;
        let mu_of = |k: &crate::contact::ContactKind| match k {
            crate::contact::ContactKind::Rubbing { mu } => mu.max(0.0),
            _ => 0.0,
        };
        // each particle's Young's modulus, and the softest
        let body_e: Vec<f64> = model.bodies.iter().map(|b| model.materials[b.material].youngs_modulus()).collect();
        let e_min = whole.e_min;
        // cohering particles with the barrier: ties of stiffness 100 E (softest particle)
        let tie_stiffness = if matches!(model.contact.kind, crate::contact::ContactKind::Cohering) {
            barrier::TIE_STIFFNESS * e_min
        } else {
            0.0
        };
        let mut barrier = model.barrier_contact().map(|c| barrier::BarrierRun::new(c, h, mu_of(&model.contact.kind), model.contact.walls.iter().map(mu_of).collect(), tie_stiffness));
        if let (Some(b), Some(_)) = (barrier.as_mut(), part.as_ref()) {
            // a part evaluates the pairs whose first side is its own
            b.contact.evaluate_only(own_body.clone());
        }
        if let Some(b) = barrier.as_mut() {
            // cohering particles that touch (or nearly) at the start are tied at once
            if tie_stiffness > 0.0 {
                b.extent = whole.extent;
                let mut n = [b.contact.tie_close(&model.x0, None) as f64];
                if part.is_some() {
                    // (a part ties its own nodes: the whole model's ties are every process's)
                    comm.sum_in_place(&mut n);
                }
                b.update_tie_floor(n[0] as usize);
            }
            // the pattern of the pairs within d̂ + h of the reference configuration
            let near = b.contact.candidates(&model.x0, b.contact.dhat + h);
            b.pattern = b.with_ties(near);
            pair_dofs = b.pattern.iter().map(|&p| b.contact.pair_dofs(p)).collect();
            node_dofs = b.node_dofs.clone();
            assembler.set_terms(&mut kk, &pair_dofs, &[]);
            b.walls1 = model.wall_planes(0.0);
            b.walls0 = b.walls1.clone();
            // the barrier starts from boundaries apart: where two touch it is infinite (a
            // rebuild's state is checked when it is set, [`Simulation::restore_barrier`])
            let mut eval = crate::contact::barrier_problem::BarrierEval::default();
            let start = if rebuild { Ok(()) } else { b.contact.evaluate(&model.x0, &b.walls0, false, &mut eval) };
            if part.is_some() && comm.max(if start.is_err() { 1.0 } else { 0.0 }) > 0.0 && start.is_ok() {
                return Err(SolveError::Contact("the barrier contact found touching particles at the start on another process".into()));
            }
            if let Err(e) = start {
                return Err(SolveError::Contact(format!(
                    "{e} at the start: the barrier contact (contact.method = \"barrier\", the default) needs the particles apart from each other at the start (walls may touch them); expected a gap between particles, `contact = \"cohering\"` (touching particles are tied), or contact.method = \"penalty\" or \"augmented_lagrangian\""
                )));
            }
        }
        if let Some(p) = &par {
            assembler.retain_elements(&p.owned_elements);
        }
        if part.is_some() {
            let own: Vec<bool> = model.elem_body.iter().map(|&b| own_body[b]).collect();
            assembler.retain_elements(&own);
        }
        let maps = TermMaps { pairs: assembler.block_map(&kk, &pair_dofs), multipliers: assembler.multiplier_map(&kk, &multiplier_dofs), ..Default::default() };
        // stabilisation springs ζ E a / h² on every dof of a contact problem
        let body_h: Vec<f64> = model.bodies.iter().map(|b| b.contact_h).collect();
        let body_nodes: Vec<_> = model.bodies.iter().map(|b| b.node_offset..b.node_offset + b.mesh.nodes.len()).collect();
        // (a part's springs on its own particles: a ghost's are its owner's)
        let spring_elements: Vec<usize> = (0..model.elements.len()).filter(|&e| own_body[model.elem_body[e]]).collect();
        let springs = if part.is_some() {
            let els: Vec<[usize; 4]> = spring_elements.iter().map(|&e| model.elements[e]).collect();
            let eb: Vec<usize> = spring_elements.iter().map(|&e| model.elem_body[e]).collect();
            Springs::new(&model.x0, &els, &eb, &body_e, &body_h, &body_nodes, &model.stabilisation, contact.is_some() || barrier.is_some())
        } else {
            Springs::new(&model.x0, &model.elements, &model.elem_body, &body_e, &body_h, &body_nodes, &model.stabilisation, contact.is_some() || barrier.is_some())
        };
        let n_walls = model.loading.walls.len();
        let symmetric = model.symmetric_tangent();
        let kind = spec.linear.resolve(symmetric);
        let threads = if spec.threads == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { spec.threads };
        let pool = if threads > 1 {
            Some(rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| LinalgError::Other(format!("cannot start {threads} threads: {e}")))?)
        } else {
            None
        };
        // (the barrier's Newton updates only; the other contact methods keep the linear
        // algebra's limit, their runs unchanged)
        let singular_tol = if barrier.is_some() { NEWTON_SOLVE_TOL } else { crate::linalg::direct::Refinement::default().singular_tol };
        let opts = SolverOptions { kind, preconditioner: spec.preconditioner, pcg_tol: spec.pcg_tol, pcg_max_iterations: spec.pcg_max_iterations, threads, ordering: spec.ordering, symmetric, singular_tol };
        // the particles are the subdomains of the Schwarz preconditioner, distributed like the
        // elements; with it every process takes part in the solve, otherwise rank 0 alone solves
        let schwarz = kind == LinearSolverKind::Pcg && spec.preconditioner == crate::linalg::Preconditioner::Schwarz;
        // (PETSc: every process solves its own rows)
        let petsc = kind == LinearSolverKind::Petsc;
        let distributed_solve = (par.is_some() && (schwarz || petsc)) || part.is_some();
        let mut subdomains = crate::linalg::schwarz::Subdomains::default();
        if schwarz {
            let eq = &assembler.eq;
            subdomains = crate::linalg::schwarz::Subdomains::from_particles(&body_nodes, &model.x0, |d| (eq[d] != FIXED).then_some(eq[d]));
            if let Some(p) = &par {
                subdomains = subdomains.with_owners(&p.body_owner, comm.rank());
            }
        }
        let mut linear = if let Some(p) = &part {
            // a part's rows: its own and its ghosts' equations, PETSc over the processes
            let mut dof = vec![None; kk.nrows];
            let mut particle = vec![crate::linalg::petsc::NO_PARTICLE; kk.nrows];
            for (b, body) in model.bodies.iter().enumerate() {
                for node in body.node_offset..body.node_offset + body.mesh.nodes.len() {
                    for c in 0..2 {
                        let q = assembler.eq[2 * node + c];
                        if q != FIXED {
                            dof[q] = Some((model.x0[node], c));
                            particle[q] = b;
                        }
                    }
                }
            }
            let rows = crate::linalg::petsc::Rows::Part(crate::linalg::petsc::PartRows { map: p.eqs.clone(), dof, particle });
            crate::linalg::petsc::make_rows(Some(rows), symmetric, spec.pcg_tol, spec.pcg_max_iterations, singular_tol, comm.rank(), comm.size())
        } else if petsc {
            // each row to its particle's owner (the multiplier rows to rank 0), with its dof's
            // reference position and direction for the rigid-body modes
            let n_rows = kk.nrows;
            let mut layout = crate::linalg::petsc::RowLayout { owner: vec![0; n_rows], dof: vec![None; n_rows], particle: vec![crate::linalg::petsc::NO_PARTICLE; n_rows] };
            for (b, body) in model.bodies.iter().enumerate() {
                let owner = par.as_ref().map_or(0, |p| p.body_owner[b]);
                for node in body.node_offset..body.node_offset + body.mesh.nodes.len() {
                    for c in 0..2 {
                        let q = assembler.eq[2 * node + c];
                        if q != FIXED {
                            layout.owner[q] = owner;
                            layout.dof[q] = Some((model.x0[node], c));
                            layout.particle[q] = b;
                        }
                    }
                }
            }
            crate::linalg::petsc::make(Some(layout), symmetric, spec.pcg_tol, spec.pcg_max_iterations, singular_tol, comm.rank(), comm.size())
        } else {
            make_solver_with(&opts, subdomains, comm.clone())
        };
        // (a failure on the solving process fails every process)
        let n_free_all = part.as_ref().map_or(n_free, |p| p.eqs.n_global());
        let analyzed = if n_free_all > 0 && (comm.is_root() || distributed_solve) { linear.analyze(&kk) } else { Ok(()) };
        if (par.is_some() || part.is_some()) && comm.max(if analyzed.is_err() { 1.0 } else { 0.0 }) > 0.0 {
            analyzed?;
            return Err(LinalgError::Other("symbolic analysis failed on rank 0".into()).into());
        }
        analyzed?;
        let linear_name = linear.name().to_string();
        let ne = model.elements.len();
        let mut kappa = vec![0.0; ne];
        let mut incompressible = vec![false; ne];
        let mut g_max: f64 = 0.0;
        for e in 0..ne {
            let m = &model.materials[model.elem_material[e]];
            g_max = g_max.max(m.shear_modulus());
            // (plane stress: the volumetric response is the law's, in the thickness condition;
            // the element carries no mean-dilatation pressure)
            match m.bulk_modulus() {
                _ if model.plane_stress => {}
                Some(k) => kappa[e] = k,
                None => {
                    kappa[e] = spec.incompressible_penalty * m.shear_modulus();
                    incompressible[e] = true;
                }
            }
        }
        let area0_body = model.body_areas(&model.x0);
        let mut area0_total: f64 = area0_body.iter().zip(&own_body).filter(|(_, &o)| o).map(|(a, _)| a).sum();
        if part.is_some() {
            // (the whole model's figures, the same on every process)
            area0_total = comm.all_gather_varcount(&[area0_total]).iter().sum();
            g_max = comm.max(g_max);
        }
        // forces below this are round-off: G · L · 1e-13 with L = √(total area)
        let force_floor = 1e-13 * g_max * area0_total.abs().sqrt();
        if let Some(b) = barrier.as_mut() {
            // with the barrier the floor counts the bulk penalty of an incompressible particle
            // too (its round-off held the near-rigid ellipses of the paper's section 4,
            // ν = 0.5, at a relative residual of 3e-5 with updates of 1e-14 mm, measured); the
            // other methods, and compressible particles, keep G (their results unchanged)
            let mut k_max = kappa.iter().zip(&incompressible).filter(|(_, &i)| i).map(|(&k, _)| k).fold(g_max, f64::max);
            if part.is_some() {
                k_max = comm.max(k_max);
            }
            b.stiffness_floor = 1e-13 * k_max * area0_total.abs().sqrt();
            b.load_floor = if e_min.is_finite() { barrier::LOAD_FLOOR * e_min * area0_total.abs().sqrt() } else { 0.0 };
        }
        let sol = Solution { time: 0.0, u: vec![0.0; n_dofs], fields: ElementFields::new(ne), lambda: vec![0.0; ne], j0: vec![1.0; ne] };
        let dynamics = Dynamics::from_model(time.integrator, &model);
        let n_rows = kk.nrows;
        let mut sys = System {
            assembler,
            kk,
            maps,
            r: vec![0.0; n_rows],
            du: vec![0.0; n_rows],
            f_int: vec![0.0; n_dofs],
            f_ext: vec![0.0; n_dofs],
            f_elem_norm: 0.0,
            trial_fields: ElementFields::new(ne),
            eq_offset: Vec::new(),
            linear,
            linear_name,
            pool,
            comm,
            par,
            partition,
            distributed_solve,
            part,
        };
        sys.locate_fixed_terms(&model, &node_dofs);
        let run = RunState {
            step: 0,
            dt_prev: 0.0,
            next_dt: time.dt.min(time.dt_max),
            total_iterations: 0,
            total_cutbacks: 0,
            total_remeshes: 0,
            area0_body,
            area0_total,
            force_floor,
            work_ext: 0.0,
            last_wall_force: vec![0.0; n_walls],
            remesh_baseline: vec![None; model.bodies.len()],
            last_report: None,
            last_step_easy: false,
            saddle_departures: 0,
        };
        let mut sim = Self {
            model,
            time,
            spec,
            sol,
            run,
            u_prev: vec![0.0; n_dofs],
            sys,
            kappa,
            incompressible,
            contact,
            contact_stats: ContactStats::default(),
            contact_evals: ContactEvals::default(),
            barrier,
            springs,
            dynamics,
            clock: Clock::default(),
            interrupt: None,
        };
        sim.start_dynamics()?;
        Ok(sim)
    }

    /// Initial state of an implicit dynamic analysis (nothing when quasi-static): v_0 = 0 and
    /// the acceleration consistent with F_ext(t_0) − F_int(u_0), see [`Dynamics::start`].
    fn start_dynamics(&mut self) -> Result<(), SolveError> {
        let Some(mut dy) = self.dynamics.take() else { return Ok(()) };
        let u0 = self.sol.u.clone();
        let vol = self.volumetric(&self.sol.lambda);
        let inc = crate::material::TimeIncrement { time: self.sol.time, dt: self.time.dt };
        self.evaluate(&u0, inc, &vol, false).map_err(|e| SolveError::StepFailed { time: self.sol.time, dt: 0.0, dt_min: self.time.dt_min, cause: e.into() })?;
        dy.start(&u0, &self.sys.f_int, &self.sys.f_ext, &self.sys.assembler.eq);
        self.dynamics = Some(dy);
        Ok(())
    }

    /// The state between two steps (after a converged step, or before the first), for a
    /// checkpoint: with the same model, [`Simulation::set_state`] on a new simulation continues
    /// the run bit for bit.
    pub fn state(&self) -> SimState {
        SimState {
            scalars: self.scalars(),
            sol: self.sol.clone(),
            u_prev: self.u_prev.clone(),
            dynamics: self.dynamics.as_ref().map(|d| [d.u.clone(), d.v.clone(), d.a.clone(), d.g.clone()]),
        }
    }

    /// The scalars of [`Simulation::state`].
    pub(super) fn scalars(&self) -> SimScalars {
        SimScalars {
            time: self.sol.time,
            run: self.run.clone(),
            stab_all: self.springs.all,
            stab_viscous: self.springs.viscous,
            stab_energy: self.springs.energy,
            timing: self.clock.timing(),
            contact: self.contact.as_ref().map(|c| c.state()),
            barrier: self.barrier.as_ref().map(|b| b.state()),
            partition: PartitionTotals { repartitions: self.sys.partition.repartitions, kept: self.sys.partition.kept, moved: self.sys.partition.moved, time_s: self.sys.partition.time_s },
        }
    }

    /// Continue from `state` ([`Simulation::state`] of a simulation of the same model, e.g.
    /// read from a checkpoint).
    ///
    /// # Errors
    /// A message naming what does not fit this simulation's model (sizes of the arrays,
    /// bodies, walls, contact, dynamics).
    pub fn set_state(&mut self, state: SimState) -> Result<(), String> {
        let SimState { scalars: s, sol, u_prev, dynamics } = state;
        let (n_dofs, ne, nb) = (self.model.n_dofs(), self.model.elements.len(), self.model.bodies.len());
        let check = |what: &str, got: usize, want: usize| if got == want { Ok(()) } else { Err(format!("{what}: {got} in the checkpoint, {want} in the model")) };
        check("displacement dofs", sol.u.len(), n_dofs)?;
        check("previous displacement dofs", u_prev.len(), n_dofs)?;
        check("element multipliers", sol.lambda.len(), ne)?;
        check("element initial volume ratios", sol.j0.len(), ne)?;
        check("element material states", sol.fields.states.len(), ne)?;
        check("element stresses", sol.fields.sig.len(), ne)?;
        check("element pressures", sol.fields.pressure.len(), ne)?;
        check("element volume ratios", sol.fields.theta.len(), ne)?;
        check("element enhanced modes", sol.fields.alpha.len(), ne)?;
        check("body areas", s.run.area0_body.len(), nb)?;
        check("re-mesh baselines", s.run.remesh_baseline.len(), nb)?;
        check("wall forces", s.run.last_wall_force.len(), self.run.last_wall_force.len())?;
        match (self.contact.as_mut(), s.contact) {
            (Some(c), Some(cs)) => c.set_state(cs)?,
            (None, None) => {}
            (have, _) => return Err(format!("contact: the model {} contact, the checkpoint {}", if have.is_some() { "has" } else { "has no" }, if have.is_some() { "has none" } else { "has" })),
        }
        match (self.dynamics.as_mut(), dynamics) {
            (Some(d), Some([u, v, a, g])) => {
                for (what, x) in [("dynamic displacements", &u), ("velocities", &v), ("accelerations", &a), ("dynamic forces", &g)] {
                    check(what, x.len(), d.u.len())?;
                }
                (d.u, d.v, d.a, d.g) = (u, v, a, g);
            }
            (None, None) => {}
            (have, _) => return Err(format!("the analysis is {} but the checkpoint's is not", if have.is_some() { "dynamic" } else { "quasi-static" })),
        }
        self.sol = sol;
        self.sol.time = s.time;
        self.u_prev = u_prev;
        self.run = s.run;
        self.springs.all = s.stab_all;
        self.springs.viscous = s.stab_viscous;
        self.springs.energy = s.stab_energy;
        self.clock.set(s.timing);
        // the run's counts so far; the current partition (on this run's processes) is this one's
        self.sys.partition.repartitions = s.partition.repartitions;
        self.sys.partition.kept = s.partition.kept;
        self.sys.partition.moved = s.partition.moved;
        self.sys.partition.time_s += s.partition.time_s;
        match (self.barrier.is_some(), s.barrier) {
            (true, Some(bs)) => self.restore_barrier(bs)?,
            (false, None) => {}
            (true, None) => return Err("contact: the model has the barrier contact, the checkpoint has no barrier state (it was written by another contact method or an older mpfem)".into()),
            (false, Some(_)) => return Err("contact: the checkpoint has a barrier contact state, the model has no barrier contact".into()),
        }
        Ok(())
    }

    /// Switch the barrier's double step at double roots off or on (on by default; nothing to
    /// switch without the barrier). For benchmarks and tests that measure what it gains; no
    /// case key reaches it.
    pub fn set_barrier_double_step(&mut self, on: bool) {
        if let Some(b) = self.barrier.as_mut() {
            b.double = on;
        }
    }

    /// The forcing of the solves before a friction update (`LAG_FORCING` of solver/barrier.rs by
    /// default; 0: every solve converged to the solver's tolerance; nothing to set without the
    /// barrier). For tests and benchmarks that measure what it gains; no case key reaches it.
    pub fn set_barrier_lag_forcing(&mut self, forcing: f64) {
        if let Some(b) = self.barrier.as_mut() {
            b.lag_forcing = forcing;
        }
    }

    /// Switch the barrier's box prediction of each step off or on (on by default; nothing to
    /// switch without the barrier). For tests and benchmarks that measure what Newton does
    /// from the last converged state; no case key reaches it.
    pub fn set_barrier_box_prediction(&mut self, on: bool) {
        if let Some(b) = self.barrier.as_mut() {
            b.predict = on;
        }
    }

    /// The step counter (converged steps so far).
    pub fn step(&self) -> usize {
        self.run.step
    }

    /// The step size the next step of [`Simulation::run`] tries (s; shortened only to end on
    /// the end time or the stop solid ratio): after a converged step, what the step-size
    /// control chose.
    pub fn next_dt(&self) -> f64 {
        self.run.next_dt
    }

    /// The report of the last converged step of [`Simulation::run`] (kept in a checkpoint).
    pub fn last_report(&self) -> Option<&StepReport> {
        self.run.last_report.as_ref()
    }

    /// The stabilisation spring of every dof when it acts, ζ E a / h² (N/mm², before the
    /// `stiffen_on_cutback` factor; zero without contact): h is the particle's
    /// [`crate::model::Body::contact_h`], so a re-mesh does not change a particle's total.
    pub fn stabilisation_springs(&self) -> &[f64] {
        &self.springs.base
    }

    pub fn n_free(&self) -> usize {
        self.sys.assembler.n_free
    }

    /// The whole model's free equations: [`Simulation::n_free`], or on parts those of every
    /// process together.
    pub fn n_free_whole(&self) -> usize {
        self.sys.part.as_ref().map_or(self.sys.assembler.n_free, |p| p.eqs.n_global())
    }

    /// Whether every process takes part in the linear solves (the Schwarz PCG on several
    /// processes) rather than rank 0 alone.
    pub fn solves_distributed(&self) -> bool {
        self.sys.distributed_solve
    }

    /// The partition of the bodies over the processes: ranks, imbalance, edge cut and the
    /// repartitions so far (one process: 1, 1, 0, 0).
    pub fn partition(&self) -> &PartitionStats {
        &self.sys.partition
    }

    pub fn linear_solver_name(&self) -> &str {
        &self.sys.linear_name
    }

    /// Nodal velocities of the last committed step (mm/s, dof `2 n + c`): the Newmark
    /// velocity with inertia, otherwise the step's mean velocity (u_n − u_{n−1})/Δt (zero
    /// before the first step).
    pub fn velocity(&self) -> Vec<f64> {
        self.snapshot().velocity()
    }

    /// Solid ratio of the initial configuration (particle area / die area at t = 0), when four
    /// walls close a die.
    pub fn initial_solid_ratio(&self) -> Option<f64> {
        self.contact.as_ref()?;
        let die = self.model.loading.die_area(0.0)?;
        (die > 0.0).then(|| self.run.area0_total / die)
    }

    /// The barrier contact's force on every dof at its last evaluation — the converged state
    /// after a step — as a contribution to the internal force (N/mm; the force on a node is
    /// its negative); None without the barrier.
    pub fn barrier_forces(&self) -> Option<Vec<f64>> {
        let b = self.barrier.as_ref()?;
        let mut f = vec![0.0; self.model.n_dofs()];
        b.eval.add_gradient(&mut f);
        Some(f)
    }

    /// The barrier's smallest distance and activation distance d̂ at its last evaluation (mm);
    /// None without the barrier.
    pub fn barrier_gap(&self) -> Option<(f64, f64)> {
        self.barrier.as_ref().map(|b| (b.eval.min_distance, b.contact.dhat))
    }

    /// With the barrier: whether the next step starts descending on the incremental
    /// potential (on for good once a step has needed the retry that does,
    /// `BarrierRun::descent`). False without the barrier.
    pub fn barrier_descends(&self) -> bool {
        self.barrier.as_ref().is_some_and(|b| b.descent)
    }

    /// With the barrier's ties (cohering particles): how many ties hold, and the largest gap
    /// of a tie in the committed state (mm; see [`crate::contact::barrier_problem::Tie`]).
    /// None without the barrier.
    /// On a part: over every process (collective).
    pub fn barrier_ties(&self) -> Option<(usize, f64)> {
        let b = self.barrier.as_ref()?;
        let x = self.coords(&self.sol.u);
        let gap = b.contact.ties.iter().map(|t| t.gap(&x, &b.contact.segments)).map(|g| g[0].hypot(g[1])).fold(0.0, f64::max);
        Some((self.sys.sum(b.contact.ties.len() as f64) as usize, self.sys.max(gap)))
    }

    /// With the barrier: how many boundary nodes of the committed state lie inside another
    /// particle or behind a wall (zero by construction; see
    /// [`crate::contact::barrier_problem::BarrierContact::crossings`]). None without it.
    pub fn barrier_crossings(&self) -> Option<usize> {
        let b = self.barrier.as_ref()?;
        Some(b.contact.crossings(&self.coords(&self.sol.u), &self.model.wall_planes(self.sol.time)))
    }

    /// Contact state per node of the last committed step (None without contact).
    pub fn nodal_contact(&self) -> Option<&crate::contact::NodalContact> {
        match (&self.contact, &self.barrier) {
            (Some(c), _) => Some(&c.nodal),
            (None, Some(b)) => Some(&b.nodal),
            (None, None) => None,
        }
    }

    /// Current nodal coordinates x = X + u.
    pub fn coords(&self, u: &[f64]) -> Vec<[f64; 2]> {
        self.model.x0.iter().enumerate().map(|(n, p)| [p[0] + u[2 * n], p[1] + u[2 * n + 1]]).collect()
    }

    /// Reaction on node `n` after the last converged step: F_int − F_ext (N/mm).
    pub fn nodal_reaction(&self, n: usize) -> [f64; 2] {
        [self.sys.f_int[2 * n] - self.sys.f_ext[2 * n], self.sys.f_int[2 * n + 1] - self.sys.f_ext[2 * n + 1]]
    }

    /// Wall time per phase so far.
    pub fn timing(&self) -> Timing {
        self.clock.timing()
    }

    /// The run's phase timers (a caller may time its own phases, e.g. the output).
    pub fn clock(&self) -> &Clock {
        &self.clock
    }
}

impl Simulation {
    /// Look at `flag` before every Newton iteration: when it is not zero the step under way
    /// is abandoned at once (the last converged state kept, as after a failed attempt) and
    /// [`Simulation::run_controlled`] returns with `interrupted` set, without calling its
    /// observer for that step. So a stop asked for by a signal takes effect within one Newton
    /// iteration, not at the end of a step that may be cutting back for minutes. On several
    /// processes every process must set a flag (rank 0's decides: it is broadcast at every
    /// check, so that all abandon the same iteration).
    pub fn set_interrupt(&mut self, flag: Arc<std::sync::atomic::AtomicUsize>) {
        self.interrupt = Some(flag);
    }

    /// Whether a stop was asked for (rank 0's flag, on every process).
    pub(super) fn check_interrupt(&self) -> Result<(), NewtonFailure> {
        let Some(flag) = &self.interrupt else { return Ok(()) };
        let mut asked = [flag.load(std::sync::atomic::Ordering::SeqCst) as f64];
        if self.sys.par.is_some() || self.sys.part.is_some() {
            self.sys.comm.broadcast(&mut asked);
        }
        if asked[0] != 0.0 {
            Err(NewtonFailure::Interrupted)
        } else {
            Ok(())
        }
    }
}
