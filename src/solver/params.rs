//! The solver's parameters: time stepping and the Newton and linear solver settings (the
//! case file's `[time]` and `[solver]` tables).

use crate::dynamics::Integrator;
use crate::linalg::{FillOrdering, LinearChoice, Preconditioner};

/// Time stepping (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeSpec {
    pub end: f64,
    pub dt: f64,
    pub dt_min: f64,
    pub dt_max: f64,
    pub growth: f64,
    pub cutback: f64,
    pub easy_iterations: usize,
    pub max_steps: usize,
    /// Quasi-static (default) or implicit dynamics (Newmark, HHT-α).
    pub integrator: Integrator,
}

impl TimeSpec {
    /// End time and initial step with every other field at its documented default.
    pub fn new(end: f64, dt: f64) -> Self {
        Self {
            end,
            dt,
            dt_min: (end * 1e-6).min(dt),
            dt_max: end,
            growth: 1.5,
            cutback: 0.5,
            easy_iterations: 6,
            max_steps: 100_000,
            integrator: Integrator::Static,
        }
    }
}

impl Default for TimeSpec {
    /// `end = 1`, `dt = 0.1`, the rest as documented.
    fn default() -> Self {
        Self::new(1.0, 0.1)
    }
}

/// Newton variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NewtonKind {
    /// Tangent re-formed every iteration.
    #[default]
    Full,
    /// Tangent formed once per step (eq. 9/16 of the paper).
    Modified,
}

/// Nonlinear and linear solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSpec {
    pub newton: NewtonKind,
    pub max_iterations: usize,
    pub residual_tol: f64,
    pub energy_tol: f64,
    pub line_search: bool,
    pub linear: LinearChoice,
    pub preconditioner: Preconditioner,
    pub pcg_tol: f64,
    pub pcg_max_iterations: usize,
    /// Fill-reducing ordering of the sparse Cholesky factorisation.
    pub ordering: FillOrdering,
    /// 0 = all cores.
    pub threads: usize,
    /// Augmented-Lagrangian penalty for ν = 0.5, in units of the shear modulus.
    pub incompressible_penalty: f64,
    pub volume_tol: f64,
    pub max_volume_updates: usize,
    /// Distributed runs: after a re-mesh the particles keep their processes while the load
    /// imbalance (heaviest process's element count / mean) stays at most this (≥ 1); above it
    /// the particle graph is partitioned again.
    pub repartition_imbalance: f64,
}

impl Default for SolverSpec {
    fn default() -> Self {
        Self {
            newton: NewtonKind::Full,
            max_iterations: 25,
            residual_tol: 1e-8,
            energy_tol: 1e-16,
            line_search: true,
            linear: LinearChoice::Auto,
            preconditioner: Preconditioner::Ic0,
            pcg_tol: 1e-10,
            pcg_max_iterations: 10_000,
            ordering: FillOrdering::Amd,
            threads: 0,
            incompressible_penalty: 1000.0,
            volume_tol: 1e-10,
            max_volume_updates: 30,
            repartition_imbalance: 1.05,
        }
    }
}
