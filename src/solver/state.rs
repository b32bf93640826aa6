//! The state of a simulation between two steps: the committed solution, the run's counters,
//! energies and step-size control, and what a checkpoint keeps of them.

use super::report::{StepReport, Timing};
use crate::assembly::ElementFields;
use serde::{Deserialize, Serialize};

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
    /// Counters, step sizes, energies, references (their keys sit at this level of the
    /// checkpoint's map, as before they were grouped).
    #[serde(flatten)]
    pub run: RunState,
    pub stab_all: bool,
    pub stab_viscous: bool,
    pub stab_energy: f64,
    pub timing: Timing,
    /// Repartitions, kept partitions, moved particles and partitioning time of the run so far
    /// (absent from older checkpoints: zero).
    #[serde(default)]
    pub partition: PartitionTotals,
    pub contact: Option<crate::contact::ContactState>,
    /// The barrier contact's state (absent from older checkpoints and without the barrier).
    #[serde(default)]
    pub barrier: Option<BarrierState>,
}

/// What of the barrier contact changes over a run and is not rebuilt from the model: κ after
/// its doublings, the smallest distance of the last converged step (the next doubling
/// compares with it), the ties of cohering particles with their multipliers, and whether the
/// steps descend on the potential from their start (after a step that needed it). The last
/// evaluation of the barrier, from which the next step lags its friction and picks the
/// springs' directions, is recomputed at the converged state on a restart.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BarrierState {
    pub kappa: f64,
    pub min_distance: f64,
    pub ties: Vec<crate::contact::barrier_problem::Tie>,
    pub tied: Vec<(usize, usize)>,
    /// Whether the next step starts descending on the potential (absent from older
    /// checkpoints: no).
    #[serde(default)]
    pub descent: bool,
}

/// The state of a simulation between two steps that is not rebuilt from its model
/// ([`super::Simulation::state`], [`super::Simulation::set_state`]).
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

/// The counts of [`crate::parallel::PartitionStats`] that add up over a run (and over its restarts, whatever
/// the number of processes), kept in a checkpoint.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct PartitionTotals {
    pub repartitions: usize,
    pub kept: usize,
    pub moved: usize,
    pub time_s: f64,
}

/// The run's state between steps besides the solution: the step counter and size control,
/// the totals, the energies and the references of the volume error.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunState {
    pub step: usize,
    /// The last converged step size (the predictor's and the inertial anchor's Δt_{n−1}).
    pub dt_prev: f64,
    /// The step size the next step of [`super::Simulation::run`] tries (s).
    pub next_dt: f64,
    pub total_iterations: usize,
    pub total_cutbacks: usize,
    /// Particle re-meshes so far.
    pub total_remeshes: usize,
    /// Work of the walls on the particles since the start, and the wall forces of the last
    /// step (N·mm/mm, N/mm).
    pub work_ext: f64,
    pub last_wall_force: Vec<f64>,
    /// Initial body areas (the volume error's reference, kept over re-meshes).
    pub area0_body: Vec<f64>,
    pub area0_total: f64,
    /// Forces below this are round-off.
    pub force_floor: f64,
    /// Per body: the quality of its last new mesh when that mesh itself crossed the limits
    /// (it is then re-meshed again only once it has become clearly worse).
    pub remesh_baseline: Vec<Option<crate::remesh::QualityCheck>>,
    /// The report of the last converged step (for the jam test and the summary).
    pub last_report: Option<StepReport>,
    /// Whether the last converged step was easy (the next one may grow).
    #[serde(default)]
    pub last_step_easy: bool,
    /// Converged steps moved off a saddle and minimised again so far
    /// ([`super::Simulation::leave_saddle`]).
    #[serde(default)]
    pub saddle_departures: usize,
}
