//! Time stepping and the nonlinear solution: full or modified Newton–Raphson (the paper's
//! eq. 9 / 16), backtracking line search, residual and energy convergence tests, adaptive time
//! steps with cut-back and growth, and the augmented-Lagrangian (Uzawa) loop that enforces
//! incompressibility element by element for ν = 0.5.
//!
//! Lifecycle of a step t_n → t_{n+1} = t_n + Δt:
//! 1. prescribed displacements and loads are evaluated at t_{n+1}; free displacements are
//!    predicted by extrapolating the last converged increment;
//! 2. Newton iterations `K Δu = F_ext − F_int` until ‖R‖ ≤ tol_R · reference force and
//!    |Δu·R| ≤ tol_E · |Δu₀·R₀|; material states are evaluated from the committed ones and never
//!    changed inside the iterations;
//! 3. for incompressible bodies the multipliers are updated (λ_e ← p_e) and step 2 repeats
//!    until max |Θ_e − 1| ≤ `volume_tol`;
//! 4. on success the states are committed and the step may grow; on failure (no convergence,
//!    inverted element, failed return map, failed linear solve) everything of the step is
//!    discarded and it is retried with Δt · cutback, down to `dt_min`.

use crate::assembly::{number_equations, AssemblyError, Assembler, ElementFields, FIXED};
use crate::case::{StabilisationKind, Stabilise};
use crate::contact::driver::{wall_position, ContactProblem, ContactStats};
use crate::case::{LinearChoice, LoadKind, NewtonKind, SolverSpec, TimeSpec};
use crate::dynamics::Dynamics;
use crate::element::Volumetric;
use crate::linalg::{make_solver_with, CsrMatrix, LinalgError, LinearSolver, LinearSolverKind, SolverOptions};
use crate::material::{ConstitutiveLaw, TimeIncrement};
use crate::model::Model;
use crate::parallel::{Collective, Distribution, PartitionStats, Serial};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Instant;
use thiserror::Error;

/// Why one Newton solve failed (drives the cut-back).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum NewtonFailure {
    #[error("no convergence in {iterations} iterations (residual history {residuals:?})")]
    NotConverged { iterations: usize, residuals: Vec<f64> },
    #[error("diverged at iteration {iteration} (residual history {residuals:?})")]
    Diverged { iteration: usize, residuals: Vec<f64> },
    #[error("{0}")]
    Element(#[from] AssemblyError),
    #[error("linear solver: {0}")]
    Linear(String),
}

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
}

/// One converged step, as reported to observers and written to the history.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StepReport {
    pub step: usize,
    pub time: f64,
    pub dt: f64,
    /// Newton iterations of this step (all augmented-Lagrangian rounds together).
    pub newton_iterations: usize,
    /// Augmented-Lagrangian multiplier updates of this step.
    pub volume_updates: usize,
    pub cutbacks: usize,
    /// Final residual norm relative to the reference force.
    pub residual: f64,
    /// |A(t) − A(0)| / A(0) over all bodies.
    pub volume_error: f64,
    /// Largest per-body |A(t) − A(0)| / A(0).
    pub volume_error_max_body: f64,
    /// Largest element |Θ − 1| over incompressible bodies (0 if none).
    pub max_element_volume_change: f64,
    /// Reaction force (N/mm) on each reaction group of the model.
    pub reactions: Vec<[f64; 2]>,
    /// Mean displacement (mm) of each displacement group of the model.
    pub displacements: Vec<[f64; 2]>,
    /// Compaction quantities, when the model has walls or several bodies.
    pub compaction: Option<Compaction>,
    /// Kinetic energy ½ vᵀ M v (N·mm/mm); 0 in a quasi-static analysis.
    pub kinetic_energy: f64,
    /// Particles re-meshed during this step (a retry after an inverted element) and after it
    /// (quality limits crossed); the state written for the step is the re-meshed one.
    pub remeshes: usize,
}

/// Compaction quantities of a step (walls that do not exist report 0).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Compaction {
    /// Total particle area / area enclosed by the walls (0 without four walls).
    pub solid_ratio: f64,
    /// Wall pressure = normal wall force / current wall length (MPa): left, right, bottom, top.
    pub pressure: [f64; 4],
    /// Normal wall force per unit thickness (N/mm): left, right, bottom, top.
    pub force: [f64; 4],
    pub max_penetration: f64,
    pub active_contacts: usize,
    /// Energy dissipated by the stabilisation springs since the start (N·mm/mm).
    pub stabilisation_energy: f64,
    /// Work of the walls on the particles since the start (N·mm/mm).
    pub external_work: f64,
}

/// What a finished run reports.
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    pub steps: usize,
    pub newton_iterations: usize,
    pub cutbacks: usize,
    /// Particle re-meshes over the run.
    pub remeshes: usize,
    pub final_time: f64,
    pub wall_time_s: f64,
    pub linear_solver: String,
    pub n_dofs: usize,
    pub n_free: usize,
    pub n_elements: usize,
    pub last: Option<StepReport>,
    /// Why the run ended: "end time", "solid ratio reached", "jammed", or the reason an
    /// observer gave for stopping the run after a step (e.g. "interrupted by SIGTERM").
    pub stop_reason: String,
    /// Whether the run was stopped by its observer before its end (see
    /// [`Simulation::run_controlled`]).
    pub interrupted: bool,
    /// Wall time spent per phase (s).
    pub timing: Timing,
    /// The partition over the processes: ranks, current imbalance and edge cut, repartitions
    /// (see [`crate::parallel::PartitionStats`]).
    pub partition: PartitionStats,
}

/// Accumulated wall time per phase of the solution (s).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Timing {
    /// Element kernels and their scatter (residual and tangent).
    pub element_assembly: f64,
    /// Contact search (pair selection, pattern rebuilds).
    pub contact_search: f64,
    /// Contact kernels and stabilisation added to the residual and tangent.
    pub contact_assembly: f64,
    /// Numeric factorisations and solves (symbolic analyses included).
    pub linear_solve: f64,
    /// Re-meshing: the new meshes, the transfer of the state and the rebuilt solver (the
    /// re-equilibration that follows is counted in the phases above, and in
    /// `reequilibration`).
    pub remesh: f64,
    /// The re-equilibrations after re-meshes (already counted in the assembly and solve
    /// phases).
    pub reequilibration: f64,
    /// Linear solves, and the iterations they took (1 per solve for the direct solvers).
    #[serde(default)]
    pub linear_solves: usize,
    #[serde(default)]
    pub linear_iterations: usize,
}

/// The converged solution at the end of the last committed step.
#[derive(Clone, Debug)]
pub struct Solution {
    pub time: f64,
    /// Nodal displacements (mm), dof `2 n + c`.
    pub u: Vec<f64>,
    pub fields: ElementFields,
    /// Augmented-Lagrangian multipliers per element (MPa).
    pub lambda: Vec<f64>,
    /// Initial volume ratio j₀ per element: the volume ratio that the element's reference
    /// configuration already carries with respect to the original (stress-free-volume) one.
    /// 1 for a mesh built in the undeformed configuration; set by a re-mesh in a deformed
    /// configuration (see the module docs of [`crate::element`]). Constant between re-meshes.
    pub j0: Vec<f64>,
}

/// The small part of a simulation's state between two steps (counters, energies, the next
/// step size, the contact histories ...): with [`SimState`]'s arrays, everything a run needs to
/// continue bit for bit on the same model. Serialised into a checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SimScalars {
    pub time: f64,
    pub step: usize,
    /// The last converged step size (the predictor's and the inertial anchor's Δt_{n−1}).
    pub dt_prev: f64,
    /// The step size the next step tries.
    pub next_dt: f64,
    pub total_iterations: usize,
    pub total_cutbacks: usize,
    pub total_remeshes: usize,
    pub stab_all: bool,
    pub stab_viscous: bool,
    pub stab_energy: f64,
    pub work_ext: f64,
    pub last_wall_force: Vec<f64>,
    /// Initial body areas (the volume error's reference, kept over re-meshes).
    pub area0_body: Vec<f64>,
    pub area0_total: f64,
    pub force_floor: f64,
    pub timing: Timing,
    pub remesh_baseline: Vec<Option<crate::remesh::QualityCheck>>,
    pub last_report: Option<StepReport>,
    /// Repartitions, kept partitions, moved particles and partitioning time of the run so far
    /// (absent from older checkpoints: zero).
    #[serde(default)]
    pub partition: PartitionTotals,
    pub contact: Option<crate::contact::driver::ContactState>,
}

/// The state of a simulation between two steps that is not rebuilt from its model
/// ([`Simulation::state`], [`Simulation::set_state`]).
#[derive(Clone, Debug)]
pub struct SimState {
    pub scalars: SimScalars,
    /// The committed solution (time, u, element fields, multipliers, j₀).
    pub sol: Solution,
    /// u_{n−1}: the predictor's and the inertial stabilisation's previous displacement.
    pub u_prev: Vec<f64>,
    /// Newmark state u, v, a, g of an implicit dynamic analysis.
    pub dynamics: Option<[Vec<f64>; 4]>,
}

/// The counts of [`PartitionStats`] that add up over a run (and over its restarts, whatever
/// the number of processes), kept in a checkpoint.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct PartitionTotals {
    pub repartitions: usize,
    pub kept: usize,
    pub moved: usize,
    pub time_s: f64,
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

/// The simulation driver: owns the model, the solution and the solver workspaces.
pub struct Simulation {
    pub model: Model,
    pub time: TimeSpec,
    pub spec: SolverSpec,
    pub sol: Solution,
    assembler: Assembler,
    kk: CsrMatrix,
    linear: Box<dyn LinearSolver>,
    linear_name: String,
    /// Newmark / HHT-α state of an implicit dynamic analysis (None: quasi-static).
    dynamics: Option<Dynamics>,
    pool: Option<rayon::ThreadPool>,
    /// Volumetric data per element (κ and whether it is an incompressible body).
    kappa: Vec<f64>,
    incompressible: Vec<bool>,
    area0_body: Vec<f64>,
    area0_total: f64,
    force_floor: f64,
    // work buffers
    trial_fields: ElementFields,
    f_int: Vec<f64>,
    f_ext: Vec<f64>,
    r: Vec<f64>,
    du: Vec<f64>,
    u_prev: Vec<f64>,
    dt_prev: f64,
    step: usize,
    total_iterations: usize,
    total_cutbacks: usize,
    /// Contact with walls and between bodies (None: nothing can touch).
    pub contact: Option<ContactProblem>,
    /// Stabilisation spring per dof (N/mm²) acting in the current step, zero without contact.
    stab_k: Vec<f64>,
    /// Stabilisation spring per dof when it acts everywhere (ζ E a / h²).
    stab_base: Vec<f64>,
    /// Body of every node.
    node_body: Vec<usize>,
    /// Stabilise every dof in the current step (a retry after a failure).
    stab_all: bool,
    /// Factor of the stabilisation springs in this step (`stiffen_on_cutback`; 1 otherwise).
    stab_scale: f64,
    /// Anchor the springs at the last converged position in the current step, whatever
    /// `stabilisation_kind` says (a retry after a failure with the inertial anchor).
    stab_viscous: bool,
    /// Where the stabilisation springs of the current step are anchored.
    stab_anchor: Vec<f64>,
    /// Tangent-only regularisation per dof (N/mm²).
    reg_k: Vec<f64>,
    contact_stats: ContactStats,
    stab_energy: f64,
    work_ext: f64,
    last_wall_force: Vec<f64>,
    f_elem_norm: f64,
    pub timing: Timing,
    /// Particle re-meshes so far.
    total_remeshes: usize,
    /// Part of a transferred state's out-of-balance force still held back while a
    /// re-equilibration releases it (added to F_int; empty otherwise), per dof (N/mm).
    eq_offset: Vec<f64>,
    /// Per body: the quality of its last new mesh when that mesh itself crossed the limits
    /// (it is then re-meshed again only once it has become clearly worse).
    remesh_baseline: Vec<Option<crate::remesh::QualityCheck>>,
    /// The step size the next step of [`Simulation::run`] tries (s): the adaptive step after
    /// the last converged one.
    next_dt: f64,
    /// The report of the last converged step of a run (for the jam test and the summary).
    last_report: Option<StepReport>,
    /// The processes of the run ([`Serial`] for one).
    comm: Arc<dyn Collective>,
    /// What this process owns in a run on several processes (None: one process, the serial
    /// code path), see [`crate::parallel`].
    par: Option<Distribution>,
    /// The partition's figures (one process: 1 rank, imbalance 1, no cut, no repartitions).
    partition: PartitionStats,
    /// Whether every process takes part in the linear solves (the Schwarz PCG on several
    /// processes); otherwise rank 0 solves and broadcasts the update.
    distributed_solve: bool,
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

    /// [`Simulation::new_with`]; with `previous` (the owners of the bodies in the simulation
    /// this one replaces, when any process owned them, and its partition figures) the owners
    /// are kept unless their imbalance on the new model is above `[solver]
    /// repartition_imbalance` (see [`Distribution::build`]).
    fn build(model: Model, time: TimeSpec, spec: SolverSpec, comm: Arc<dyn Collective>, previous: Option<(Option<&[usize]>, &PartitionStats)>) -> Result<Self, SolveError> {
        let mut partition = previous.map_or_else(PartitionStats::default, |p| p.1.clone());
        let par = Distribution::build(&model, comm.clone(), previous.and_then(|p| p.0), spec.repartition_imbalance, &mut partition);
        let n_dofs = model.n_dofs();
        let (eq, n_free) = number_equations(n_dofs, model.prescribed.iter().map(|p| p.dof));
        let mut contact = ContactProblem::new(&model, model.walls.clone(), model.contact.clone());
        let (mut assembler, kk) = match contact.as_mut() {
            Some(c) => {
                c.select_pairs(&model.x0);
                Assembler::with_multipliers(&model, eq, n_free, &c.couplings(), &c.multiplier_dofs())
            }
            None => Assembler::new(&model, eq, n_free),
        };
        if let Some(p) = &par {
            assembler.retain_elements(&p.owned_elements);
        }
        // stabilisation springs ζ E a / h² on every dof of a contact problem
        let mut stab_k = vec![0.0; n_dofs];
        if let Some(c) = &contact {
            for (e, el) in model.elements.iter().enumerate() {
                let b = model.elem_body[e];
                let a = crate::mesh::polygon_area(el.iter().map(|&n| model.x0[n])) / 4.0;
                let k = c.body_e[b] * a / (c.body_h[b] * c.body_h[b]);
                for &n in el {
                    stab_k[2 * n] += k;
                    stab_k[2 * n + 1] += k;
                }
            }
        }
        // base nodal stiffness E a / h² → stabilisation ζ·base (residual and tangent) and
        // regularisation ρ·base (tangent only)
        let reg_k: Vec<f64> = stab_k.iter().map(|k| k * model.contact.regularisation).collect();
        stab_k.iter_mut().for_each(|k| *k *= model.contact.stabilisation);
        let mut node_body = vec![0; model.n_nodes()];
        for (b, body) in model.bodies.iter().enumerate() {
            node_body[body.node_offset..body.node_offset + body.mesh.nodes.len()].fill(b);
        }
        let n_walls = model.walls.len();
        let kind = match spec.linear {
            LinearChoice::Fixed(k) => k,
            LinearChoice::Auto => {
                if model.symmetric_tangent() {
                    LinearSolverKind::Cholesky
                } else {
                    LinearSolverKind::Lu
                }
            }
        };
        let threads = if spec.threads == 0 {
            std::thread::available_parallelism().map_or(1, |n| n.get())
        } else {
            spec.threads
        };
        let pool = if threads > 1 {
            Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .map_err(|e| LinalgError::Other(format!("cannot start {threads} threads: {e}")))?,
            )
        } else {
            None
        };
        let opts = SolverOptions {
            kind,
            preconditioner: spec.preconditioner,
            pcg_tol: spec.pcg_tol,
            pcg_max_iterations: spec.pcg_max_iterations,
            threads,
            ordering: spec.ordering,
            symmetric: model.symmetric_tangent(),
        };
        // the particles are the subdomains of the Schwarz preconditioner, distributed like the
        // elements; with it every process takes part in the solve, otherwise rank 0 alone solves
        let distributed_solve = par.is_some() && kind == LinearSolverKind::Pcg && spec.preconditioner == crate::linalg::Preconditioner::Schwarz;
        let mut subdomains = crate::linalg::schwarz::Subdomains::default();
        if kind == LinearSolverKind::Pcg && spec.preconditioner == crate::linalg::Preconditioner::Schwarz {
            let ranges: Vec<_> = model.bodies.iter().map(|b| b.node_offset..b.node_offset + b.mesh.nodes.len()).collect();
            let eq = &assembler.eq;
            subdomains = crate::linalg::schwarz::Subdomains::from_particles(&ranges, &model.x0, |d| (eq[d] != FIXED).then_some(eq[d]));
            if let Some(p) = &par {
                subdomains = subdomains.with_owners(&p.body_owner, comm.rank());
            }
        }
        let mut linear = make_solver_with(&opts, subdomains, comm.clone());
        // (a failure on the solving process fails every process)
        let analyzed = if n_free > 0 && (comm.is_root() || distributed_solve) { linear.analyze(&kk) } else { Ok(()) };
        if par.is_some() && comm.max(if analyzed.is_err() { 1.0 } else { 0.0 }) > 0.0 {
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
            match m.bulk_modulus() {
                Some(k) => kappa[e] = k,
                None => {
                    kappa[e] = spec.incompressible_penalty * m.shear_modulus();
                    incompressible[e] = true;
                }
            }
        }
        let area0_body = model.body_areas(&model.x0);
        let area0_total: f64 = area0_body.iter().sum();
        // forces below this are round-off: G · L · 1e-13 with L = √(total area)
        let force_floor = 1e-13 * g_max * area0_total.abs().sqrt();
        let sol = Solution { time: 0.0, u: vec![0.0; n_dofs], fields: ElementFields::new(ne), lambda: vec![0.0; ne], j0: vec![1.0; ne] };
        let dynamics = Dynamics::from_model(time.integrator, &model);
        let mut sim = Self {
            trial_fields: ElementFields::new(ne),
            f_int: vec![0.0; n_dofs],
            f_ext: vec![0.0; n_dofs],
            r: vec![0.0; kk.nrows],
            du: vec![0.0; kk.nrows],
            u_prev: vec![0.0; n_dofs],
            dt_prev: 0.0,
            model,
            time,
            spec,
            sol,
            assembler,
            kk,
            linear,
            linear_name,
            dynamics,
            pool,
            kappa,
            incompressible,
            area0_body,
            area0_total,
            force_floor,
            step: 0,
            total_iterations: 0,
            total_cutbacks: 0,
            contact,
            stab_base: stab_k.clone(),
            stab_k,
            node_body,
            stab_all: false,
            stab_scale: 1.0,
            stab_anchor: vec![0.0; n_dofs],
            stab_viscous: false,
            reg_k,
            contact_stats: ContactStats::default(),
            stab_energy: 0.0,
            work_ext: 0.0,
            last_wall_force: vec![0.0; n_walls],
            f_elem_norm: 0.0,
            timing: Timing::default(),
            total_remeshes: 0,
            eq_offset: Vec::new(),
            remesh_baseline: Vec::new(),
            next_dt: time.dt.min(time.dt_max),
            last_report: None,
            comm,
            par,
            partition,
            distributed_solve,
        };
        sim.remesh_baseline = vec![None; sim.model.bodies.len()];
        sim.start_dynamics()?;
        Ok(sim)
    }

    /// Initial state of an implicit dynamic analysis (nothing when quasi-static): v_0 = 0 and
    /// the acceleration consistent with F_ext(t_0) − F_int(u_0), see [`Dynamics::start`].
    fn start_dynamics(&mut self) -> Result<(), SolveError> {
        let Some(mut dy) = self.dynamics.take() else { return Ok(()) };
        let u0 = self.sol.u.clone();
        let vol = self.volumetric(&self.sol.lambda);
        let inc = TimeIncrement { time: self.sol.time, dt: self.time.dt };
        self.evaluate(&u0, inc, &vol, false).map_err(|e| SolveError::StepFailed {
            time: self.sol.time,
            dt: 0.0,
            dt_min: self.time.dt_min,
            cause: e.into(),
        })?;
        dy.start(&u0, &self.f_int, &self.f_ext, &self.assembler.eq);
        self.dynamics = Some(dy);
        Ok(())
    }

    /// The state between two steps (after a converged step, or before the first), for a
    /// checkpoint: with the same model, [`Simulation::set_state`] on a new simulation continues
    /// the run bit for bit.
    pub fn state(&self) -> SimState {
        SimState {
            scalars: SimScalars {
                time: self.sol.time,
                step: self.step,
                dt_prev: self.dt_prev,
                next_dt: self.next_dt,
                total_iterations: self.total_iterations,
                total_cutbacks: self.total_cutbacks,
                total_remeshes: self.total_remeshes,
                stab_all: self.stab_all,
                stab_viscous: self.stab_viscous,
                stab_energy: self.stab_energy,
                work_ext: self.work_ext,
                last_wall_force: self.last_wall_force.clone(),
                area0_body: self.area0_body.clone(),
                area0_total: self.area0_total,
                force_floor: self.force_floor,
                timing: self.timing.clone(),
                remesh_baseline: self.remesh_baseline.clone(),
                last_report: self.last_report.clone(),
                contact: self.contact.as_ref().map(|c| c.state()),
                partition: PartitionTotals { repartitions: self.partition.repartitions, kept: self.partition.kept, moved: self.partition.moved, time_s: self.partition.time_s },
            },
            sol: self.sol.clone(),
            u_prev: self.u_prev.clone(),
            dynamics: self.dynamics.as_ref().map(|d| [d.u.clone(), d.v.clone(), d.a.clone(), d.g.clone()]),
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
        check("body areas", s.area0_body.len(), nb)?;
        check("re-mesh baselines", s.remesh_baseline.len(), nb)?;
        check("wall forces", s.last_wall_force.len(), self.last_wall_force.len())?;
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
        self.step = s.step;
        self.dt_prev = s.dt_prev;
        self.next_dt = s.next_dt;
        self.total_iterations = s.total_iterations;
        self.total_cutbacks = s.total_cutbacks;
        self.total_remeshes = s.total_remeshes;
        self.stab_all = s.stab_all;
        self.stab_viscous = s.stab_viscous;
        self.stab_energy = s.stab_energy;
        self.work_ext = s.work_ext;
        self.last_wall_force = s.last_wall_force;
        self.area0_body = s.area0_body;
        self.area0_total = s.area0_total;
        self.force_floor = s.force_floor;
        self.timing = s.timing;
        self.remesh_baseline = s.remesh_baseline;
        self.last_report = s.last_report;
        // the run's counts so far; the current partition (on this run's processes) is this one's
        self.partition.repartitions = s.partition.repartitions;
        self.partition.kept = s.partition.kept;
        self.partition.moved = s.partition.moved;
        self.partition.time_s += s.partition.time_s;
        Ok(())
    }

    /// The step counter (converged steps so far).
    pub fn step(&self) -> usize {
        self.step
    }

    /// The report of the last converged step of [`Simulation::run`] (kept in a checkpoint).
    pub fn last_report(&self) -> Option<&StepReport> {
        self.last_report.as_ref()
    }

    /// The stabilisation spring of every dof when it acts, ζ E a / h² (N/mm², before the
    /// `stiffen_on_cutback` factor; zero without contact): h is the particle's
    /// [`crate::model::Body::contact_h`], so a re-mesh does not change a particle's total.
    pub fn stabilisation_springs(&self) -> &[f64] {
        &self.stab_base
    }

    pub fn n_free(&self) -> usize {
        self.assembler.n_free
    }

    /// Re-mesh body `b` in its current configuration with elements of size about `h` (mm)
    /// and carry the solution over ([`crate::remesh`]): the new mesh keeps every boundary point
    /// of the old one (area and contact surface unchanged), its reference configuration is the
    /// current one (u = 0 on its nodes, the last step's increment moved by nodal transfer so
    /// that the inertial stabilisation keeps its anchor), and the material states, initial
    /// volume ratios and element pressures are transferred ([`crate::remesh::transfer_body`]).
    /// Everything else is rebuilt for the new numbering; the other bodies keep their solution.
    /// The run's counters, energies and initial areas (for the volume error) are kept.
    /// The contact history of every pair (stick anchors, augmented-Lagrangian and Lagrange
    /// multipliers, wall histories) and the tributary lengths of the kept contact zones are
    /// carried to the new numbering ([`ContactProblem::carry_history`]).
    ///
    /// # Errors
    /// [`SolveError::Remesh`] for an implicit dynamic analysis (velocities and accelerations
    /// are not transferred), a body held by boundary conditions, loads or output groups, or a
    /// boundary the mesher refuses.
    pub fn remesh_body(&mut self, b: usize, h: f64) -> Result<crate::remesh::BodyTransfer, SolveError> {
        let hold = self.contact_nodes(b);
        self.remesh_body_holding(b, h, &hold)
    }

    /// The boundary nodes of body `b` (numbered within the body) in contact, as slave or
    /// master, at the last evaluation of the committed state.
    fn contact_nodes(&self, b: usize) -> Vec<usize> {
        let Some(body) = self.model.bodies.get(b) else { return Vec::new() };
        let (n0, nn) = (body.node_offset, body.mesh.n_nodes());
        match self.contact.as_ref() {
            Some(c) => (0..nn)
                .filter(|&k| {
                    let g = n0 + k;
                    c.nodal.status.get(g).is_some_and(|&s| s > 0) || c.nodal.force.get(g).is_some_and(|f| f[0] != 0.0 || f[1] != 0.0)
                })
                .collect(),
            None => Vec::new(),
        }
    }

    /// [`Self::remesh_body`] with the boundary nodes `hold` (numbered within the body) kept
    /// where they are (see [`crate::remesh::remesh_particle_keeping`]).
    fn remesh_body_holding(&mut self, b: usize, h: f64, hold: &[usize]) -> Result<crate::remesh::BodyTransfer, SolveError> {
        let fail = |reason: String| SolveError::Remesh { body: b, reason };
        if self.dynamics.is_some() {
            return Err(fail("implicit dynamics: velocities and accelerations are not transferred".into()));
        }
        let body = self.model.bodies.get(b).ok_or_else(|| fail("no such body".into()))?;
        let (n0, nn) = (body.node_offset, body.mesh.n_nodes());
        let (e0, ne) = (body.elem_offset, body.mesh.n_elements());
        let x = self.coords(&self.sol.u);
        let (xb0, xb) = (&self.model.x0[n0..n0 + nn], &x[n0..n0 + nn]);
        let new_mesh = crate::remesh::remesh_particle_keeping(&body.mesh, xb, h, hold).map_err(|e| fail(e.to_string()))?;
        // An incompressible body carries its element pressures p = λ + κ (Θ − 1) whole in λ,
        // with j₀ := 1 on the new mesh (Θ = 1 there): with κ = `incompressible_penalty` · G the
        // part κ (Θ − 1) would turn the smoothing of the element volume ratios Θ (equal to 1
        // within `volume_tol`, with the element-to-element scatter of Q1/P0) into pressure
        // errors of the order of the stresses themselves (measured: the re-equilibration
        // started at a relative residual of 1.0 and took 24 iterations on one asphalt octagon).
        let incompressible = (e0..e0 + ne).all(|e| self.incompressible[e]);
        let pressure_like = if incompressible { &self.sol.fields.pressure } else { &self.sol.lambda };
        let old_state = crate::remesh::BodyState {
            states: self.sol.fields.states[e0..e0 + ne].to_vec(),
            j0: self.sol.j0[e0..e0 + ne].to_vec(),
            lambda: pressure_like[e0..e0 + ne].to_vec(),
        };
        // the last step's increment u_n − u_{n−1} of the body goes to the new nodes too
        let incr = crate::remesh::NodalField { n_comp: 2, values: (2 * n0..2 * (n0 + nn)).map(|d| self.sol.u[d] - self.u_prev[d]).collect() };
        let mut moved = crate::remesh::transfer_body(&body.mesh, xb0, xb, &old_state, &[incr], &new_mesh).map_err(|e| fail(e.to_string()))?;
        let incr_new = moved.nodal.pop().ok_or_else(|| fail("the increment was not transferred".into()))?;
        if incompressible {
            moved.state.j0.iter_mut().for_each(|j| *j = 1.0);
        }
        // the old boundary nodes the new mesh keeps where they are, bit for bit (the held
        // contact zones): old node of the body → its number in the new mesh
        let bits = |p: [f64; 2]| p.map(f64::to_bits);
        let new_boundary: HashMap<[u64; 2], usize> = new_mesh.boundary.iter().flatten().map(|&k| (bits(new_mesh.nodes[k]), k)).collect();
        let kept: Vec<Option<usize>> = xb.iter().map(|&p| new_boundary.get(&bits(p)).copied()).collect();
        let model = self.model.with_body_mesh(b, new_mesh).map_err(|e| fail(e.to_string()))?;
        // the owners are kept unless the new element counts unbalance them too much
        let owners = self.par.as_ref().map(|p| p.body_owner.as_slice());
        let mut next = Simulation::build(model, self.time, self.spec, self.comm.clone(), Some((owners, &self.partition)))?;
        // the solution: other bodies renumbered, the re-meshed body from the transfer
        for (c, (ob, nb)) in self.model.bodies.iter().zip(&next.model.bodies).enumerate() {
            if c == b {
                for k in 0..nb.mesh.n_nodes() {
                    for d in 0..2 {
                        next.u_prev[2 * (nb.node_offset + k) + d] = -incr_new.values[2 * k + d];
                    }
                }
                let r = nb.elem_offset..nb.elem_offset + nb.mesh.n_elements();
                next.sol.fields.states[r.clone()].copy_from_slice(&moved.state.states);
                next.sol.j0[r.clone()].copy_from_slice(&moved.state.j0);
                next.sol.lambda[r].copy_from_slice(&moved.state.lambda);
                continue;
            }
            let (src, dst, n) = (2 * ob.node_offset, 2 * nb.node_offset, 2 * ob.mesh.n_nodes());
            next.sol.u[dst..dst + n].copy_from_slice(&self.sol.u[src..src + n]);
            next.u_prev[dst..dst + n].copy_from_slice(&self.u_prev[src..src + n]);
            let (src, dst, n) = (ob.elem_offset, nb.elem_offset, ob.mesh.n_elements());
            next.sol.fields.states[dst..dst + n].copy_from_slice(&self.sol.fields.states[src..src + n]);
            next.sol.fields.sig[dst..dst + n].copy_from_slice(&self.sol.fields.sig[src..src + n]);
            next.sol.j0[dst..dst + n].copy_from_slice(&self.sol.j0[src..src + n]);
            next.sol.lambda[dst..dst + n].copy_from_slice(&self.sol.lambda[src..src + n]);
        }
        // (the default contact penalty 10 E/h and the stabilisation springs ζ E a/h² keep the
        // particle's own h, `Body::contact_h`, which `with_body_mesh` keeps)
        let x_new = next.coords(&next.sol.u);
        if let (Some(old), Some(new)) = (self.contact.as_ref(), next.contact.as_mut()) {
            // the contact history of the whole assembly (stick anchors, multipliers, wall
            // histories) goes to the new numbering, not only the re-meshed body's
            let mut node_map = vec![None; self.model.x0.len()];
            for (c, (ob, nb)) in self.model.bodies.iter().zip(&next.model.bodies).enumerate() {
                for k in 0..ob.mesh.n_nodes() {
                    node_map[ob.node_offset + k] = if c == b { kept[k].map(|m| nb.node_offset + m) } else { Some(nb.node_offset + k) };
                }
            }
            let carried = new.carry_history(old, &node_map, [&self.model.x0, &x], [&next.model.x0, &x_new]);
            tracing::debug!(body = b, ?carried, "contact history carried over the re-mesh");
        }
        next.sol.time = self.sol.time;
        next.dt_prev = self.dt_prev;
        next.step = self.step;
        next.total_iterations = self.total_iterations;
        next.total_cutbacks = self.total_cutbacks;
        next.stab_energy = self.stab_energy;
        next.work_ext = self.work_ext;
        next.last_wall_force.clone_from(&self.last_wall_force);
        next.area0_body.clone_from(&self.area0_body);
        next.area0_total = self.area0_total;
        next.force_floor = self.force_floor;
        next.timing = self.timing.clone();
        next.total_remeshes = self.total_remeshes;
        next.remesh_baseline.clone_from(&self.remesh_baseline);
        next.next_dt = self.next_dt;
        next.last_report.clone_from(&self.last_report);
        *self = next;
        Ok(moved)
    }

    /// After a converged step (`[remesh] enabled`): re-mesh every particle whose mesh, in the
    /// current configuration, crosses the quality limits (the worst first), then re-equilibrate
    /// once. Particles held by boundary conditions, loads or output groups are never
    /// re-meshed. Returns the number of particles re-meshed.
    fn remesh_after_step(&mut self) -> usize {
        if !self.model.remesh.enabled {
            return 0;
        }
        let limits = self.model.remesh.limits;
        let x = self.coords(&self.sol.u);
        // (smallest scaled Jacobian, body) of every particle that asks for a new mesh
        let mut worst: Vec<(f64, usize)> = Vec::new();
        for (b, body) in self.model.bodies.iter().enumerate() {
            if self.model.remesh_constraint(b).is_some() {
                continue;
            }
            let xb = &x[body.node_offset..body.node_offset + body.mesh.n_nodes()];
            match crate::remesh::check_quality(&body.mesh, xb, &limits) {
                Ok(q) if q.needs_remesh => {
                    let worse = match &self.remesh_baseline[b] {
                        None => true,
                        Some(base) => {
                            q.scaled_jacobian.value < 0.9 * base.scaled_jacobian.value
                                || q.aspect_ratio.value > 1.1 * base.aspect_ratio.value
                                || q.min_angle_deg.value < 0.9 * base.min_angle_deg.value
                        }
                    };
                    if worse {
                        tracing::debug!(body = b, violated = ?q.violated, scaled_jacobian = q.scaled_jacobian.value, aspect_ratio = q.aspect_ratio.value, min_angle = q.min_angle_deg.value, "quality limits crossed");
                        worst.push((q.scaled_jacobian.value, b));
                    }
                }
                Ok(_) => {}
                Err(e) => tracing::warn!(body = b, %e, "quality check failed"),
            }
        }
        // every particle that asks for it, the worst first, then one re-equilibration: on a
        // regular grid the particles cross the limits together, and re-meshing one of them
        // while its neighbours keep their distorted corner elements perturbs those elements at
        // the brink of inversion (measured on the 16 octagons of 5.2.1 at φ 0.906: the next
        // step then failed at every step size, 25 Newton iterations stalling on the corner
        // elements of the other particles)
        worst.sort_by(|a, b| a.0.total_cmp(&b.0));
        let bodies: Vec<usize> = worst.iter().map(|&(_, b)| b).collect();
        self.remesh_and_rebalance_all(&bodies)
    }

    /// Whether body `b`'s mesh in the last converged state is within a factor 2 of the quality
    /// limits (scaled Jacobian below twice its limit, aspect ratio above half its limit or
    /// smallest angle below twice its limit): only then is an inverted element answered by a
    /// re-mesh rather than a cut-back.
    fn mesh_is_poor(&self, b: usize) -> bool {
        let body = &self.model.bodies[b];
        let x = self.coords(&self.sol.u);
        let xb = &x[body.node_offset..body.node_offset + body.mesh.n_nodes()];
        let l = self.model.remesh.limits;
        let relaxed = crate::remesh::QualityLimits {
            min_scaled_jacobian: (2.0 * l.min_scaled_jacobian).min(0.99),
            max_aspect_ratio: (0.5 * l.max_aspect_ratio).max(1.01),
            min_angle_deg: (2.0 * l.min_angle_deg).min(89.0),
        };
        crate::remesh::check_quality(&body.mesh, xb, &relaxed).is_ok_and(|q| q.needs_remesh)
    }

    /// Re-mesh body `b` in the current state (at `[remesh] mesh_size` or its own mesh size),
    /// then re-equilibrate the transferred state at the same time and wall positions. A body
    /// whose re-mesh fails keeps its mesh (a warning says why); a failed re-equilibration leaves
    /// the transferred state for the next step to balance. Returns whether it was re-meshed.
    fn remesh_and_rebalance(&mut self, b: usize) -> bool {
        self.remesh_and_rebalance_all(&[b]) > 0
    }

    /// [`Self::remesh_and_rebalance`] for several bodies: each is re-meshed, then the state is
    /// re-equilibrated once. Returns how many were re-meshed.
    fn remesh_and_rebalance_all(&mut self, bodies: &[usize]) -> usize {
        let mut done = 0;
        // the contact nodes of every body before the first rebuild (a rebuilt contact problem
        // starts without them; a body's own node numbers do not change when another one is
        // re-meshed)
        let holds: Vec<Vec<usize>> = bodies.iter().map(|&b| self.contact_nodes(b)).collect();
        for (&b, hold) in bodies.iter().zip(&holds) {
            if self.total_remeshes >= self.model.remesh.max_remeshes {
                tracing::warn!(max = self.model.remesh.max_remeshes, "the largest number of re-meshes (remesh.max_remeshes) is reached: no more re-meshing");
                break;
            }
            let h = self.model.remesh.mesh_size.unwrap_or(self.model.bodies[b].mesh_size);
            let t0 = Instant::now();
            let moved = self.remesh_body_holding(b, h, hold);
            // (the rebuild's set-up is not counted in any other phase)
            self.timing.remesh += t0.elapsed().as_secs_f64();
            let moved = match moved {
                Ok(m) => m,
                Err(e) => {
                    tracing::warn!(body = b, %e, "re-meshing failed: the particle keeps its mesh");
                    continue;
                }
            };
            self.total_remeshes += 1;
            done += 1;
            let body = &self.model.bodies[b];
            let q = crate::remesh::check_quality(&body.mesh, &body.mesh.nodes, &self.model.remesh.limits).ok().filter(|q| q.needs_remesh);
            if let Some(q) = &q {
                tracing::warn!(body = b, violated = ?q.violated, "the new mesh itself crosses the quality limits (boundary points are kept); re-meshed again only once it is worse");
            }
            self.remesh_baseline[b] = q;
            tracing::info!(time = self.sol.time, body = b, name = %body.name, elements = body.mesh.n_elements(), area_change = moved.area.relative_change, "particle re-meshed");
        }
        if done == 0 {
            return 0;
        }
        let t0 = Instant::now();
        match self.equilibrate() {
            Ok(its) => tracing::debug!(iterations = its, "re-equilibrated after re-meshing"),
            Err(e) => tracing::warn!(%e, "re-equilibration after re-meshing failed: the next step starts from the transferred state"),
        }
        self.timing.reequilibration += t0.elapsed().as_secs_f64();
        done
    }

    /// Bring the state back into equilibrium at the current time and wall positions (after a
    /// re-mesh: the transferred stresses are not exactly balanced on the new mesh). A Newton
    /// solve with Δt = 0 (no creep, the springs anchored where they are), committed in place:
    /// time, step counter and the last increment (for the next prediction) are kept. Returns
    /// the Newton iterations.
    pub fn equilibrate(&mut self) -> Result<usize, NewtonFailure> {
        if self.dynamics.is_some() {
            return Err(NewtonFailure::Linear("re-equilibration is for quasi-static analyses".into()));
        }
        let inc = TimeIncrement { time: self.sol.time, dt: 0.0 };
        let snapshot = self.contact.as_ref().map(|c| c.snapshot());
        let (stab_all, stab_viscous) = (self.stab_all, self.stab_viscous);
        self.stab_viscous = true;
        let result = self.prepare_contact(0.0).and_then(|()| self.release_imbalance(inc));
        self.eq_offset.clear();
        self.stab_all = stab_all;
        self.stab_viscous = stab_viscous;
        let trial = match result {
            Ok(t) => t,
            Err(e) => {
                if let (Some(c), Some(snap)) = (self.contact.as_mut(), snapshot) {
                    c.restore(snap);
                }
                return Err(e);
            }
        };
        let stab: f64 = self.stab_k.iter().enumerate().map(|(d, k)| k * (trial.u[d] - self.stab_anchor[d]) * (trial.u[d] - self.sol.u[d])).sum();
        self.stab_energy += stab;
        if let Some(c) = self.contact.as_mut() {
            c.commit();
        }
        for d in 0..self.u_prev.len() {
            self.u_prev[d] += trial.u[d] - self.sol.u[d];
        }
        self.sol.u = trial.u;
        self.sol.lambda = trial.lambda;
        std::mem::swap(&mut self.sol.fields, &mut self.trial_fields);
        self.total_iterations += trial.iterations;
        Ok(trial.iterations)
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
    fn release_imbalance(&mut self, inc: TimeIncrement) -> Result<Trial, NewtonFailure> {
        let u0 = self.sol.u.clone();
        let vol = self.volumetric(&self.sol.lambda.clone());
        self.eq_offset.clear();
        let rel0 = self.evaluate(&u0, inc, &vol, false)? / self.reference_force();
        let r0: Vec<f64> = self.f_ext.iter().zip(&self.f_int).map(|(e, i)| e - i).collect();
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
            self.eq_offset = r0.iter().map(|r| (1.0 - s_try) * r).collect();
            let mut u_try = u.clone();
            let attempt = if s_try >= 1.0 {
                self.eq_offset.clear();
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

    /// Whether every process takes part in the linear solves (the Schwarz PCG on several
    /// processes) rather than rank 0 alone.
    pub fn solves_distributed(&self) -> bool {
        self.distributed_solve
    }

    /// The partition of the bodies over the processes: ranks, imbalance, edge cut and the
    /// repartitions so far (one process: 1, 1, 0, 0).
    pub fn partition(&self) -> &PartitionStats {
        &self.partition
    }

    pub fn linear_solver_name(&self) -> &str {
        &self.linear_name
    }

    /// Nodal velocities of the last committed step (mm/s, dof `2 n + c`): the Newmark
    /// velocity with inertia, otherwise the step's mean velocity (u_n − u_{n−1})/Δt (zero
    /// before the first step).
    pub fn velocity(&self) -> Vec<f64> {
        if let Some(dy) = self.dynamics.as_ref() {
            return dy.v.clone();
        }
        if self.step == 0 || !(self.dt_prev > 0.0) {
            return vec![0.0; self.sol.u.len()];
        }
        self.sol.u.iter().zip(&self.u_prev).map(|(a, b)| (a - b) / self.dt_prev).collect()
    }

    /// Solid ratio of the initial configuration (particle area / die area at t = 0), when four
    /// walls close a die.
    pub fn initial_solid_ratio(&self) -> Option<f64> {
        let [x0, x1, y0, y1] = self.contact.as_ref()?.die(0.0)?;
        let die = (x1 - x0) * (y1 - y0);
        (die > 0.0).then(|| self.area0_total / die)
    }

    /// Contact state per node of the last committed step (None without contact).
    pub fn nodal_contact(&self) -> Option<&crate::contact::driver::NodalContact> {
        self.contact.as_ref().map(|c| &c.nodal)
    }

    /// Current nodal coordinates x = X + u.
    pub fn coords(&self, u: &[f64]) -> Vec<[f64; 2]> {
        self.model.x0.iter().enumerate().map(|(n, p)| [p[0] + u[2 * n], p[1] + u[2 * n + 1]]).collect()
    }

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
        while self.sol.time < t_end * (1.0 - 1e-12) {
            if self.step >= self.time.max_steps {
                return Err(SolveError::TooManySteps(self.time.max_steps));
            }
            let dt = self.next_dt;
            let remaining = t_end - self.sol.time;
            let dt_try = if remaining <= dt * 1.01 { remaining } else { dt };
            let report = match self.advance(dt_try) {
                Ok(r) => r,
                Err(SolveError::StepFailed { time, dt, cause, .. }) if self.model.stop.jam && self.is_jammed(self.last_report.as_ref()) => {
                    tracing::warn!(time, dt, %cause, "the walls cannot advance any more: jammed");
                    stop_reason = "jammed".to_string();
                    break;
                }
                Err(e) => return Err(e),
            };
            self.next_dt = if report.cutbacks == 0 && report.newton_iterations <= self.time.easy_iterations {
                (report.dt * self.time.growth).min(self.time.dt_max)
            } else {
                report.dt
            };
            self.last_report = Some(report.clone());
            let flow = observer(self, &report);
            let reached = match (&report.compaction, self.model.stop.solid_ratio) {
                (Some(c), Some(target)) => c.solid_ratio >= target,
                _ => false,
            };
            if reached {
                stop_reason = "solid ratio reached".to_string();
                break;
            }
            if let ControlFlow::Break(reason) = flow {
                stop_reason = reason;
                interrupted = true;
                break;
            }
        }
        Ok(RunSummary {
            steps: self.step,
            newton_iterations: self.total_iterations,
            cutbacks: self.total_cutbacks,
            remeshes: self.total_remeshes,
            final_time: self.sol.time,
            wall_time_s: start.elapsed().as_secs_f64(),
            linear_solver: self.linear_name.clone(),
            n_dofs: self.model.n_dofs(),
            n_free: self.assembler.n_free,
            n_elements: self.model.elements.len(),
            last: self.last_report.clone(),
            stop_reason,
            interrupted,
            timing: self.timing.clone(),
            partition: self.partition.clone(),
        })
    }

    /// A failed step counts as a jam (the walls cannot advance any more) only when the last
    /// converged state is dense (solid ratio ≥ `[stop] jam_solid_ratio`, 0.9 by default) and
    /// every moving wall carries load;
    /// otherwise the failure is a convergence failure and is reported as an error.
    fn is_jammed(&self, last: Option<&StepReport>) -> bool {
        let Some(c) = last.and_then(|r| r.compaction.as_ref()) else { return false };
        let moving_loaded = self.model.walls.iter().all(|w| {
            let k = w.side.index();
            w.velocity == 0.0 || c.force[k] > 0.0
        });
        !self.model.walls.is_empty() && c.solid_ratio >= self.model.stop.jam_solid_ratio && moving_loaded
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
        loop {
            if let (Some(c), Some(snap)) = (self.contact.as_mut(), snapshot.as_ref()) {
                c.restore(snap.clone());
            }
            let result = self.try_step(dt_try);
            let stabilised = self.contact.is_some() && self.model.contact.stabilisation > 0.0;
            let partial = stabilised && !self.stab_all && self.model.contact.stabilise == Stabilise::Unsupported;
            let inertial = stabilised && !self.stab_viscous && self.model.contact.viscous_retry && self.model.contact.stabilisation_kind == StabilisationKind::Inertial;
            let inverted = match &result {
                Err(NewtonFailure::Element(e)) if self.model.remesh.enabled && !remesh_tried => self.model.elem_body.get(e.element).copied(),
                _ => None,
            };
            if let Some(b) = inverted {
                // an element inverted: re-mesh its particle (in the last converged state) and
                // retry the same step before any cut-back, when its mesh there is already
                // poor (a new mesh of a good mesh does not help: the step was too large)
                remesh_tried = true;
                if self.model.remesh_constraint(b).is_none() && self.mesh_is_poor(b) {
                    tracing::info!(time = self.sol.time, dt = dt_try, body = b, "an element inverted: re-meshing the particle and retrying the step");
                    if self.remesh_and_rebalance(b) {
                        remeshes += 1;
                        snapshot = self.contact.as_ref().map(|c| c.snapshot());
                        continue;
                    }
                }
            }
            match result {
                Ok(trial) => {
                    self.stab_all = false;
                    self.stab_viscous = false;
                    let mut report = self.commit(dt_try, trial, cutbacks);
                    remeshes += self.remesh_after_step();
                    report.remeshes = remeshes;
                    return Ok(report);
                }
                Err(cause) if partial => {
                    // retry the same step with every dof stabilised before cutting back
                    tracing::debug!(time = self.sol.time, dt = dt_try, %cause, "step failed with partial stabilisation, retrying with all");
                    self.stab_all = true;
                    cutbacks += 1;
                    self.total_cutbacks += 1;
                }
                Err(cause) if inertial => {
                    // retry the same step with the springs anchored where the step starts: a
                    // particle that hits another at rest must change its velocity at once, which
                    // the inertial anchor resists and the viscous one does not
                    tracing::debug!(time = self.sol.time, dt = dt_try, %cause, "step failed with inertial stabilisation, retrying viscous");
                    self.stab_viscous = true;
                    cutbacks += 1;
                    self.total_cutbacks += 1;
                }
                Err(cause) => {
                    // (a retry's wider or viscous springs stay on for the cut-back steps)
                    cutbacks += 1;
                    self.total_cutbacks += 1;
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

    /// Reaction on node `n` after the last converged step: F_int − F_ext (N/mm).
    pub fn nodal_reaction(&self, n: usize) -> [f64; 2] {
        [self.f_int[2 * n] - self.f_ext[2 * n], self.f_int[2 * n + 1] - self.f_ext[2 * n + 1]]
    }

    /// External force vector at time t on configuration `x` (all dofs), and, when `kk` is
    /// given, subtract its derivative (follower pressure) from the tangent.
    fn external_forces(&mut self, t: f64, x: &[[f64; 2]], with_tangent: bool) {
        let f = &mut self.f_ext;
        f.iter_mut().for_each(|v| *v = 0.0);
        for load in &self.model.loads {
            let amp = self.model.amplitudes[load.amplitude].at(t, self.model.t_end);
            for e in &load.edges {
                let (a, b) = (e[0], e[1]);
                match &load.kind {
                    LoadKind::Traction(tr) | LoadKind::Force(tr) => {
                        let scale = if matches!(load.kind, LoadKind::Force(_)) { 1.0 / load.length0 } else { 1.0 };
                        let (pa, pb) = (self.model.x0[a], self.model.x0[b]);
                        let len = ((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2)).sqrt();
                        for c in 0..2 {
                            let v = 0.5 * amp * scale * tr[c] * len;
                            f[2 * a + c] += v;
                            f[2 * b + c] += v;
                        }
                    }
                    LoadKind::Pressure(p) => {
                        // force on each node: −p/2 · (outward normal × length) = −p/2 (Δy, −Δx)
                        let p = p * amp;
                        let (xa, xb) = (x[a], x[b]);
                        let fx = -0.5 * p * (xb[1] - xa[1]);
                        let fy = 0.5 * p * (xb[0] - xa[0]);
                        for n in [a, b] {
                            f[2 * n] += fx;
                            f[2 * n + 1] += fy;
                        }
                        if with_tangent {
                            // K −= ∂f_ext/∂x:  ∂fx/∂y_b = −p/2, ∂fx/∂y_a = p/2, ∂fy/∂x_b = p/2, ∂fy/∂x_a = −p/2
                            let eq = &self.assembler.eq;
                            for n in [a, b] {
                                for (row, col, d) in [
                                    (2 * n, 2 * b + 1, -0.5 * p),
                                    (2 * n, 2 * a + 1, 0.5 * p),
                                    (2 * n + 1, 2 * b, 0.5 * p),
                                    (2 * n + 1, 2 * a, -0.5 * p),
                                ] {
                                    if eq[row] != FIXED && eq[col] != FIXED {
                                        if let Some(k) = self.kk.find(eq[row], eq[col]) {
                                            self.kk.values[k] -= d;
                                        }
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    fn volumetric(&self, lambda: &[f64]) -> Vec<Volumetric> {
        self.kappa.iter().zip(lambda).map(|(&kappa, &lambda)| Volumetric { kappa, lambda }).collect()
    }

    /// Assemble at displacement `u`: fills `f_int`, `f_ext`, the free residual `r` and (if
    /// asked) the tangent. Returns ‖r‖.
    fn evaluate(&mut self, u: &[f64], inc: TimeIncrement, vol: &[Volumetric], tangent: bool) -> Result<f64, AssemblyError> {
        let x = self.coords(u);
        // on several processes the element tangent is summed onto rank 0 right after the
        // element assembly; the rest (loads, contact, springs, inertia) rank 0 alone adds
        let root_tangent = tangent && self.comm.is_root();
        let kk = if tangent { Some(&mut self.kk) } else { None };
        let t0 = Instant::now();
        let assembled = self.assembler.assemble_j0(
            &self.model,
            u,
            &self.sol.fields.states,
            &self.sol.fields.alpha,
            vol,
            Some(&self.sol.j0),
            inc,
            kk,
            &mut self.f_int,
            &mut self.trial_fields,
            self.pool.as_ref(),
        );
        match &self.par {
            Some(p) => {
                p.agree(assembled)?;
                // every dof and every tangent entry of the elements belongs to one body, so only
                // its owner adds to it: the sums are exact, and rank 0 then adds the rest in the
                // serial order (the run is bit-identical to the serial one)
                p.comm.sum_in_place(&mut self.f_int);
                if tangent {
                    p.comm.sum_to_root(&mut self.kk.values);
                }
            }
            None => assembled?,
        }
        self.timing.element_assembly += t0.elapsed().as_secs_f64();
        self.external_forces(inc.time, &x, root_tangent);
        // element forces alone: with contact they balance the contact forces, which makes them
        // the force scale of a problem driven by walls (no external force, no reaction)
        self.f_elem_norm = self.f_int.iter().map(|v| v * v).sum::<f64>().sqrt();
        let t1 = Instant::now();
        if let Some(c) = self.contact.as_mut() {
            let kk = if root_tangent { Some((&mut self.kk, self.assembler.eq.as_slice(), self.assembler.n_free)) } else { None };
            // (each process evaluates the pairs of its own particles' slave nodes)
            let ex: &dyn crate::contact::driver::PairExchange = match &self.par {
                Some(p) => p,
                None => &crate::contact::driver::EveryPair,
            };
            self.contact_stats = c.add(&x, inc.time, &mut self.f_int, kk, tangent, ex);
            // stabilisation springs (in residual and tangent, dissipate energy) and the
            // tangent-only regularisation (changes the Newton path, not the solution)
            // (a dof the contacts hold has no spring in the residual but keeps it in the
            // tangent, where it only steadies the iterations)
            for (d, (&k, &kr)) in self.stab_k.iter().zip(&self.reg_k).enumerate() {
                if k > 0.0 {
                    self.f_int[d] += k * (u[d] - self.stab_anchor[d]);
                }
                let q = self.assembler.eq[d];
                let kt = self.stab_scale * self.stab_base[d] + kr;
                if root_tangent && q != FIXED && kt > 0.0 {
                    if let Some(pos) = self.kk.find(q, q) {
                        self.kk.values[pos] += kt;
                    }
                }
            }
        }
        self.timing.contact_assembly += t1.elapsed().as_secs_f64();
        // implicit dynamics: inertia (HHT-weighted) in F_int, M/((1+α)βΔt²) on the diagonal
        if let Some(dy) = self.dynamics.as_ref() {
            dy.add_inertia(u, inc.dt, &self.assembler.eq, &mut self.f_int, root_tangent.then_some(&mut self.kk));
        }
        if !self.eq_offset.is_empty() {
            for (f, o) in self.f_int.iter_mut().zip(&self.eq_offset) {
                *f += o;
            }
        }
        let mut norm2 = 0.0;
        for (d, &q) in self.assembler.eq.iter().enumerate() {
            if q != FIXED {
                let v = self.f_ext[d] - self.f_int[d];
                self.r[q] = v;
                norm2 += v * v;
            }
        }
        // Lagrange-multiplier rows (scaled to forces, see `Multipliers::rows`)
        if let Some(c) = self.contact.as_ref() {
            let n_free = self.assembler.n_free;
            for (k, &f) in c.lm.rows.iter().enumerate() {
                self.r[n_free + k] = -f;
                norm2 += f * f;
            }
        }
        Ok(norm2.sqrt())
    }

    /// Reference force for the relative residual: the larger of ‖F_ext‖ and ‖F_int‖ over all
    /// dofs (which includes the reactions), never below round-off.
    fn reference_force(&self) -> f64 {
        let n = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        n(&self.f_ext).max(n(&self.f_int)).max(self.f_elem_norm).max(self.force_floor)
    }

    /// Whether this process takes part in the linear solves (rank 0, or every process with
    /// the distributed Schwarz PCG).
    fn solves_here(&self) -> bool {
        self.comm.is_root() || self.distributed_solve
    }

    fn factor(&mut self) -> Result<(), NewtonFailure> {
        let t0 = Instant::now();
        if self.distributed_solve {
            // rank 0 holds the whole tangent (elements summed, contact added): every process
            // needs the rows of its particles
            self.comm.broadcast(&mut self.kk.values);
        }
        let r = if self.solves_here() { self.linear.factor(&self.kk).map_err(|e| NewtonFailure::Linear(e.to_string())) } else { Ok(()) };
        let r = self.agree_linear(r, "factorisation");
        self.timing.linear_solve += t0.elapsed().as_secs_f64();
        r
    }

    /// Solve `kk du = r` (rank 0 solves, the others receive `du`).
    fn solve_linear(&mut self) -> Result<(), NewtonFailure> {
        let r = if self.solves_here() {
            match self.linear.solve(&self.kk, &self.r, &mut self.du) {
                Ok(st) => {
                    self.timing.linear_solves += 1;
                    self.timing.linear_iterations += st.iterations;
                    Ok(())
                }
                Err(e) => Err(NewtonFailure::Linear(e.to_string())),
            }
        } else {
            Ok(())
        };
        let r = self.agree_linear(r, "linear solve");
        // (the distributed solve leaves the same update on every process)
        if r.is_ok() && self.par.is_some() && !self.distributed_solve {
            self.comm.broadcast(&mut self.du);
        }
        r
    }

    fn agree_linear(&self, r: Result<(), NewtonFailure>, what: &str) -> Result<(), NewtonFailure> {
        agree_linear(self.par.as_ref(), r, what)
    }

    /// Contact pairs for a solve that ends at `sol.time + dt` (frozen during its Newton
    /// iterations; the pattern is rebuilt when they change), where the stabilisation springs
    /// are anchored and how stiff they are. `dt = 0` is a re-equilibration in place: the springs
    /// are then anchored at the last converged position.
    fn prepare_contact(&mut self, dt: f64) -> Result<(), NewtonFailure> {
        // contact pairs for this step, frozen during its Newton iterations
        let t_search = Instant::now();
        if let Some(c) = self.contact.as_mut() {
            let x_n = self.model.x0.iter().enumerate().map(|(n, p)| [p[0] + self.sol.u[2 * n], p[1] + self.sol.u[2 * n + 1]]).collect::<Vec<_>>();
            c.time = self.sol.time;
            c.wall_reach = c.walls.iter().map(|w| w.velocity.abs() * dt).fold(0.0, f64::max);
            if c.select_pairs(&x_n) {
                let (assembler, kk) = Assembler::with_multipliers(&self.model, self.assembler.eq.clone(), self.assembler.n_free, &c.couplings(), &c.multiplier_dofs());
                self.assembler = assembler;
                self.r.resize(kk.nrows, 0.0);
                self.du.resize(kk.nrows, 0.0);
                self.kk = kk;
                if let Some(p) = &self.par {
                    self.assembler.retain_elements(&p.owned_elements);
                }
                if self.assembler.n_free > 0 {
                    let r = if self.comm.is_root() || self.distributed_solve { self.linear.analyze(&self.kk).map_err(|e| NewtonFailure::Linear(e.to_string())) } else { Ok(()) };
                    agree_linear(self.par.as_ref(), r, "symbolic analysis")?;
                }
            }
            // anchor of the springs: the last converged position, or its extrapolation
            let inertial = self.model.contact.stabilisation_kind == StabilisationKind::Inertial && !self.stab_viscous;
            let s = if inertial && self.dt_prev > 0.0 { dt / self.dt_prev } else { 0.0 };
            for d in 0..self.stab_anchor.len() {
                self.stab_anchor[d] = self.sol.u[d] + s * (self.sol.u[d] - self.u_prev[d]);
            }
            // a step cut below the case's Δt: springs of a fixed mass (k ∝ 1/Δt²) or dashpot
            // (k ∝ 1/Δt) instead of fixed springs
            self.stab_scale = 1.0;
            if self.model.contact.stiffen_on_cutback && dt > 0.0 && dt < self.time.dt {
                let ratio = self.time.dt / dt;
                self.stab_scale = if inertial { ratio * ratio } else { ratio };
            }
            // stabilisation of this step: every dof, or only the directions the contacts of
            // the last converged state do not hold
            let scale = self.stab_scale;
            if self.stab_all || self.model.contact.stabilise == Stabilise::All {
                for (k, b) in self.stab_k.iter_mut().zip(&self.stab_base) {
                    *k = scale * b;
                }
            } else {
                let held = c.body_support(&x_n, self.model.bodies.len());
                for (d, k) in self.stab_k.iter_mut().enumerate() {
                    *k = if held[self.node_body[d / 2]][d % 2] { 0.0 } else { scale * self.stab_base[d] };
                }
            }
        }
        self.timing.contact_search += t_search.elapsed().as_secs_f64();
        Ok(())
    }

    /// Attempt one step of size dt from the committed solution. On success the trial
    /// displacement is in `self.sol.u` (not yet committed) — see `commit`.
    fn try_step(&mut self, dt: f64) -> Result<Trial, NewtonFailure> {
        let t = self.sol.time + dt;
        let inc = TimeIncrement { time: t, dt };
        self.prepare_contact(dt)?;
        // prediction
        let mut u = self.sol.u.clone();
        if self.dt_prev > 0.0 {
            let s = dt / self.dt_prev;
            for (d, &q) in self.assembler.eq.iter().enumerate() {
                if q != FIXED {
                    u[d] += s * (self.sol.u[d] - self.u_prev[d]);
                }
            }
        }
        for p in &self.model.prescribed {
            u[p.dof] = p.value * self.model.amplitude(p.amplitude, t);
        }
        if let Some(dy) = self.dynamics.as_ref() {
            dy.predict(&mut u, dt, &self.assembler.eq); // Newmark predictor (a_{n+1} = 0)
        }
        if self.dt_prev == 0.0 && self.dynamics.is_none() {
            // no increment to extrapolate (first step): linearised prediction instead
            if let Err(e) = self.tangent_predictor(&mut u, inc) {
                tracing::debug!(%e, "tangent predictor skipped");
                u.copy_from_slice(&self.sol.u);
                for p in &self.model.prescribed {
                    u[p.dof] = p.value * self.model.amplitude(p.amplitude, t);
                }
            }
        }
        let restart = self.dt_prev > 0.0;
        self.solve_from(u, inc, restart)
    }

    /// Newton from `u` (prescribed dofs already at their values of `inc.time`), with the
    /// augmented-Lagrangian updates of the incompressible bodies and of the contact. With
    /// `restart`, a first guess that inverts an element is replaced once by the last converged
    /// solution.
    fn solve_from(&mut self, mut u: Vec<f64>, inc: TimeIncrement, restart: bool) -> Result<Trial, NewtonFailure> {
        let t = inc.time;
        let mut lambda = self.sol.lambda.clone();
        let mut iterations = 0;
        let mut updates = 0;
        let mut first = true;
        loop {
            let vol = self.volumetric(&lambda);
            let (its, res) = match self.newton(&mut u, inc, &vol) {
                Ok(v) => v,
                Err(NewtonFailure::Element(e)) if first && restart => {
                    // the extrapolated guess inverted an element: restart from the last solution
                    tracing::debug!(%e, "prediction rejected");
                    first = false;
                    u.copy_from_slice(&self.sol.u);
                    for p in &self.model.prescribed {
                        u[p.dof] = p.value * self.model.amplitude(p.amplitude, t);
                    }
                    continue;
                }
                Err(e) => return Err(e),
            };
            first = false;
            iterations += its;
            // the fields of the other processes' elements (for the updates below and the commit)
            if let Some(p) = &self.par {
                p.sync_fields(&mut self.trial_fields);
            }
            // augmented Lagrangian on the element area of incompressible bodies
            let mut worst: f64 = 0.0;
            for e in 0..self.incompressible.len() {
                if self.incompressible[e] {
                    worst = worst.max((self.trial_fields.theta[e] - 1.0).abs());
                }
            }
            let contact_update = self.contact.as_ref().is_some_and(|c| c.needs_augmentation(&self.contact_stats))
                && updates < self.model.contact.max_augmentations;
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
                    lambda[e] = self.trial_fields.pressure[e];
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
    fn tangent_predictor(&mut self, u: &mut [f64], inc: TimeIncrement) -> Result<(), NewtonFailure> {
        let n_free = self.assembler.n_free;
        if n_free == 0 {
            return Ok(());
        }
        let u_n = self.sol.u.clone();
        let du_c: Vec<f64> = u.iter().zip(&u_n).map(|(a, b)| a - b).collect();
        let vol = self.volumetric(&self.sol.lambda.clone());
        // K and F_int at u_n (with the loads of t_{n+1})
        self.evaluate(&u_n, inc, &vol, true)?;
        let f0 = self.f_int.clone();
        let r0 = self.r.clone(); // F_ext(t_{n+1}) − F_int(u_n) on free dofs
        self.factor()?;
        let eps = 1e-6;
        let u_eps: Vec<f64> = u_n.iter().zip(&du_c).map(|(a, d)| a + eps * d).collect();
        self.evaluate(&u_eps, inc, &vol, false)?;
        for (d, &q) in self.assembler.eq.iter().enumerate() {
            if q != FIXED {
                self.r[q] = r0[q] - (self.f_int[d] - f0[d]) / eps;
            }
        }
        self.du.iter_mut().for_each(|v| *v = 0.0);
        self.solve_linear()?;
        for (d, &q) in self.assembler.eq.iter().enumerate() {
            if q != FIXED {
                u[d] = u_n[d] + self.du[q];
            }
        }
        Ok(())
    }

    /// Newton–Raphson at fixed multipliers. Returns (iterations, final relative residual).
    fn newton(&mut self, u: &mut [f64], inc: TimeIncrement, vol: &[Volumetric]) -> Result<(usize, f64), NewtonFailure> {
        let full = matches!(self.spec.newton, NewtonKind::Full);
        let n_free = self.assembler.n_free;
        let mut residuals = Vec::new();
        let mut rnorm = self.evaluate(u, inc, vol, true)?;
        if n_free == 0 {
            return Ok((0, 0.0));
        }
        self.factor()?;
        let mut e0 = 0.0;
        let mut e_last = f64::INFINITY;
        let mut du_full = vec![0.0; u.len()];
        for k in 0..=self.spec.max_iterations {
            let reference = self.reference_force();
            let rel = rnorm / reference;
            residuals.push(rel);
            if tracing::enabled!(tracing::Level::DEBUG) {
                // where the largest out-of-balance force sits, to tell a stalled contact zone
                // from a global non-convergence
                let (mut worst_dof, mut worst) = (0, 0.0f64);
                for (d, &q) in self.assembler.eq.iter().enumerate() {
                    if q != FIXED && self.r[q].abs() > worst {
                        (worst_dof, worst) = (d, self.r[q].abs());
                    }
                }
                let node = worst_dof / 2;
                let x = self.model.x0.get(node).map_or([f64::NAN; 2], |p| [p[0] + u[2 * node], p[1] + u[2 * node + 1]]);
                tracing::debug!(iteration = k, residual = rel, energy = e_last, active = self.contact_stats.active, worst_force = worst, worst_node = node, body = self.node_body.get(node).copied().unwrap_or(0), x = ?x, "newton");
                if tracing::enabled!(tracing::Level::TRACE) {
                    if let Some(c) = &self.contact {
                        for line in c.describe_node(node, &self.coords(u)) {
                            tracing::trace!(node, "{line}");
                        }
                    }
                }
            }
            if !rnorm.is_finite() || (k > 2 && rel > 1e8 * residuals[0].max(1e-300)) {
                return Err(NewtonFailure::Diverged { iteration: k, residuals });
            }
            let residual_ok = rnorm <= self.spec.residual_tol * reference || rnorm <= self.force_floor;
            let energy_ok = k > 0 && e_last <= self.spec.energy_tol * e0;
            // the energy test is relative to the first iteration of this solve, which is
            // itself at round-off when a step starts almost in equilibrium: a residual a
            // hundred times below its tolerance is then accepted on its own
            // (or once the residual, already within its tolerance, stops decreasing: the
            // round-off floor of the assembly has been reached)
            let tiny = rel <= 0.01 * self.spec.residual_tol || rnorm <= self.force_floor;
            let floor_reached = k >= 1 && rel >= 0.5 * residuals[k - 1];
            if residual_ok && (k == 0 || energy_ok || tiny || floor_reached) {
                return Ok((k, rel));
            }
            if k == self.spec.max_iterations {
                break;
            }
            // solve K Δu = R
            self.du.iter_mut().for_each(|v| *v = 0.0);
            let t0 = Instant::now();
            let solved = self.solve_linear();
            self.timing.linear_solve += t0.elapsed().as_secs_f64();
            solved?;
            let energy = self.du.iter().zip(&self.r).map(|(a, b)| a * b).sum::<f64>().abs();
            if k == 0 {
                e0 = energy.max(f64::MIN_POSITIVE);
            }
            e_last = energy;
            for (d, &q) in self.assembler.eq.iter().enumerate() {
                du_full[d] = if q != FIXED { self.du[q] } else { 0.0 };
            }
            // line search: backtrack while the residual grows or an element fails
            let u0: Vec<f64> = u.to_vec();
            let line_search = self.spec.line_search;
            if let Some(c) = self.contact.as_mut() {
                c.lm.mark();
            }
            let mut eta = 1.0;
            let r_old = rnorm;
            let mut accepted = false;
            for _ in 0..6 {
                for d in 0..u.len() {
                    u[d] = u0[d] + eta * du_full[d];
                }
                if let Some(c) = self.contact.as_mut() {
                    c.lm.step(&self.du[n_free..], eta);
                }
                match self.evaluate(u, inc, vol, full) {
                    Ok(rn) => {
                        // accept when the residual norm or the energy |Δu·R(η)| decreased
                        let s: f64 = self.du.iter().zip(&self.r).map(|(a, b)| a * b).sum::<f64>().abs();
                        let better = rn.is_finite() && (rn < r_old || s < 0.9 * energy);
                        if !line_search || better || eta < 0.06 {
                            rnorm = rn;
                            accepted = rn.is_finite();
                            break;
                        }
                        eta *= 0.5;
                    }
                    Err(e) if eta < 0.06 => return Err(e.into()),
                    Err(_) => eta *= 0.5,
                }
            }
            if !accepted {
                // keep the smallest step tried; its residual drives the next iteration
                rnorm = self.evaluate(u, inc, vol, full)?;
            }
            if full {
                self.factor()?;
            }
        }
        Err(NewtonFailure::NotConverged { iterations: self.spec.max_iterations, residuals })
    }

    /// Commit a converged step: states, displacements, multipliers, time; build its report.
    fn commit(&mut self, dt: f64, trial: Trial, cutbacks: usize) -> StepReport {
        // work done against the stabilisation springs over the step (their force at the end of
        // the step times the increment)
        let stab: f64 = self.stab_k.iter().enumerate().map(|(d, k)| k * (trial.u[d] - self.stab_anchor[d]) * (trial.u[d] - self.sol.u[d])).sum();
        self.stab_energy += stab;
        if let Some(c) = self.contact.as_mut() {
            c.commit();
        }
        self.u_prev.copy_from_slice(&self.sol.u);
        self.sol.u = trial.u;
        self.sol.lambda = trial.lambda;
        std::mem::swap(&mut self.sol.fields, &mut self.trial_fields);
        if let Some(dy) = self.dynamics.as_mut() {
            dy.commit(&self.sol.u, dt, &self.f_int, &self.f_ext);
        }
        self.sol.time += dt;
        self.dt_prev = dt;
        self.step += 1;
        self.total_iterations += trial.iterations;
        let x = self.coords(&self.sol.u);
        let areas = self.model.body_areas(&x);
        let total: f64 = areas.iter().sum();
        let volume_error = ((total - self.area0_total) / self.area0_total).abs();
        let volume_error_max_body = areas
            .iter()
            .zip(&self.area0_body)
            .map(|(a, a0)| ((a - a0) / a0).abs())
            .fold(0.0, f64::max);
        let reactions = self
            .model
            .reaction_groups
            .iter()
            .map(|g| {
                let mut r = [0.0; 2];
                for &n in &g.nodes {
                    for c in 0..2 {
                        r[c] += self.f_int[2 * n + c] - self.f_ext[2 * n + c];
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
                let k = g.nodes.len().max(1) as f64;
                [m[0] / k, m[1] / k]
            })
            .collect();
        let compaction = self.contact.as_ref().map(|c| {
            let t = self.sol.time;
            let mut out = Compaction {
                max_penetration: self.contact_stats.max_penetration,
                active_contacts: self.contact_stats.active,
                ..Default::default()
            };
            for (w, spec) in c.walls.iter().enumerate() {
                let f = self.contact_stats.wall_force.get(w).copied().unwrap_or(0.0);
                let moved = (wall_position(spec, t) - wall_position(spec, t - dt)).abs();
                self.work_ext += 0.5 * (f + self.last_wall_force[w]) * moved;
                self.last_wall_force[w] = f;
                let k = spec.side.index();
                let len = c.wall_length(w, t, &x);
                out.force[k] += f;
                out.pressure[k] += if len > 0.0 { f / len } else { 0.0 };
            }
            if let Some([x0, x1, y0, y1]) = c.die(t) {
                out.solid_ratio = total / ((x1 - x0) * (y1 - y0));
            }
            out.stabilisation_energy = self.stab_energy;
            out.external_work = self.work_ext;
            out
        });
        StepReport {
            compaction,
            step: self.step,
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
            kinetic_energy: self.dynamics.as_ref().map_or(0.0, |dy| dy.kinetic_energy()),
            remeshes: 0,
        }
    }
}

/// A linear-algebra result of rank 0 (the only one that factors and solves), known to every
/// process of a run on several processes (`par`); unchanged on one.
fn agree_linear(par: Option<&Distribution>, r: Result<(), NewtonFailure>, what: &str) -> Result<(), NewtonFailure> {
    let Some(p) = par else { return r };
    // the other processes wait here while rank 0 factorises and solves: asleep, so that their
    // cores are free for other work (a blocking collective spins on them; with more ranks than
    // cores it took the core of a rank that was working)
    p.comm.idle_barrier();
    let mut failed = [if r.is_err() { 1.0 } else { 0.0 }];
    p.comm.broadcast(&mut failed);
    match r {
        Err(e) => Err(e),
        Ok(()) if failed[0] > 0.0 => Err(NewtonFailure::Linear(format!("{what} failed on rank 0"))),
        Ok(()) => Ok(()),
    }
}
