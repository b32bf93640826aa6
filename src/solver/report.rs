//! What a run reports: each converged step ([`StepReport`], a row of `history.csv`), the
//! compaction quantities of a step, the summary of a run, and the wall time per phase, with the
//! scoped phase timers ([`Clock::scope`], one guard per phase, as deal.II's
//! `TimerOutput::Scope`).

use crate::parallel::PartitionStats;
use serde::{Deserialize, Serialize};
use std::sync::{Arc, Mutex};
use std::time::Instant;

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
    /// Tangential (friction) force of the particles on each wall per unit thickness (N/mm),
    /// along the global axis the wall lies on: y for the left and right walls, x for the bottom
    /// and top ones (so that a die's equilibrium reads f_left − f_right = shear_bottom +
    /// shear_top and f_bottom − f_top = shear_left + shear_right). 0 without friction.
    #[serde(default)]
    pub shear: [f64; 4],
    /// Inward travel of each wall from its position at t = 0 (mm).
    #[serde(default)]
    pub travel: [f64; 4],
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
    /// Converged steps moved off a saddle and minimised again (barrier contact,
    /// [`super::Simulation::leave_saddle`]).
    pub saddle_departures: usize,
    pub final_time: f64,
    pub wall_time_s: f64,
    pub linear_solver: String,
    pub n_dofs: usize,
    pub n_free: usize,
    pub n_elements: usize,
    pub last: Option<StepReport>,
    /// Why the run ended: "end time", "solid ratio reached", "wall pressure reached", "jammed", or the reason an
    /// observer gave for stopping the run after a step (e.g. "interrupted by SIGTERM").
    pub stop_reason: String,
    /// Whether the run was stopped by its observer before its end (see
    /// [`super::Simulation::run_controlled`]).
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
    /// Numeric factorisations, those that found the matrix indefinite (or failed) included:
    /// a Newton iteration whose tangent is made definite takes several.
    #[serde(default)]
    pub factorisations: usize,
}

/// A phase of the solution whose wall time [`Timing`] keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    ElementAssembly,
    ContactSearch,
    ContactAssembly,
    LinearSolve,
    Remesh,
    Reequilibration,
}

/// The run's phase timers: clones share one [`Timing`], and [`Clock::scope`] times a phase
/// until the guard it returns is dropped (so the phase is timed however it is left, by an
/// error included). The clock is shared rather than borrowed, so a timed scope never holds
/// the simulation it measures.
#[derive(Clone, Debug, Default)]
pub struct Clock(Arc<Mutex<Timing>>);

/// A phase being timed (see [`Clock::scope`]).
#[must_use = "the phase is timed until this guard is dropped"]
pub struct PhaseScope {
    clock: Clock,
    phase: Phase,
    start: Instant,
}

impl Drop for PhaseScope {
    fn drop(&mut self) {
        let s = self.start.elapsed().as_secs_f64();
        self.clock.update(|t| *t.phase_mut(self.phase) += s);
    }
}

impl Timing {
    fn phase_mut(&mut self, p: Phase) -> &mut f64 {
        match p {
            Phase::ElementAssembly => &mut self.element_assembly,
            Phase::ContactSearch => &mut self.contact_search,
            Phase::ContactAssembly => &mut self.contact_assembly,
            Phase::LinearSolve => &mut self.linear_solve,
            Phase::Remesh => &mut self.remesh,
            Phase::Reequilibration => &mut self.reequilibration,
        }
    }
}

impl Clock {
    /// Time `phase` from now until the returned guard is dropped.
    pub fn scope(&self, phase: Phase) -> PhaseScope {
        PhaseScope { clock: self.clone(), phase, start: Instant::now() }
    }

    /// The times so far.
    pub fn timing(&self) -> Timing {
        self.0.lock().map(|t| t.clone()).unwrap_or_default()
    }

    /// Replace the times (a restart continues the counts of its checkpoint).
    pub fn set(&self, timing: Timing) {
        self.update(|t| *t = timing);
    }

    /// Count a linear solve of `iterations` iterations.
    pub fn count_solve(&self, iterations: usize) {
        self.update(|t| {
            t.linear_solves += 1;
            t.linear_iterations += iterations;
        });
    }

    /// Count a numeric factorisation.
    pub fn count_factorisation(&self) {
        self.update(|t| t.factorisations += 1);
    }

    fn update(&self, f: impl FnOnce(&mut Timing)) {
        // (a poisoned clock only loses times)
        if let Ok(mut t) = self.0.lock() {
            f(&mut t);
        }
    }
}
