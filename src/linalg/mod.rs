//! Sparse linear algebra: the compressed sparse row pattern built once per topology, and the
//! linear solvers behind one trait ([`LinearSolver`]): faer sparse LU, faer sparse Cholesky
//! (LLᵀ / LDLᵀ), and preconditioned conjugate gradients.
//!
//! Every solver splits its work into `analyze` (symbolic: ordering, elimination tree, memory;
//! called once per sparsity pattern) and `factor` + `solve` (numeric; called every time the
//! values change). Parallelism is passed in as a thread count, never chosen here.

pub mod csr;
pub mod direct;
pub mod pcg;
pub mod petsc;
pub mod schwarz;

pub use csr::{BlockMap, CsrMatrix, NO_ROW};
pub use direct::FillOrdering;

use thiserror::Error;

/// Which linear solver to use. Chosen in the case file (`[solver] linear = ...`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolverKind {
    /// faer sparse LU with partial pivoting (any matrix).
    Lu,
    /// faer sparse Cholesky (symmetric; LLᵀ, falling back to LDLᵀ with Bunch–Kaufman pivoting
    /// when the matrix is not positive definite).
    Cholesky,
    /// Preconditioned conjugate gradients (symmetric positive definite matrices).
    Pcg,
    /// PETSc's distributed solvers (feature `petsc`; [`petsc`]): MUMPS by default, any KSP
    /// and PC through its options database.
    Petsc,
}

/// The linear solver a run asks for (`[solver] linear`): a fixed kind, or `Auto`, which the
/// symmetry of the tangent decides ([`LinearChoice::resolve`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LinearChoice {
    #[default]
    Auto,
    Fixed(LinearSolverKind),
}

impl LinearChoice {
    /// The solver: `Auto` is the sparse Cholesky factorisation (LLᵀ with the LDLᵀ fallbacks)
    /// when the tangent is symmetric ([`crate::model::symmetric_tangent`] decides), LU
    /// otherwise.
    pub fn resolve(self, symmetric: bool) -> LinearSolverKind {
        match self {
            LinearChoice::Fixed(k) => k,
            LinearChoice::Auto if symmetric => LinearSolverKind::Cholesky,
            LinearChoice::Auto => LinearSolverKind::Lu,
        }
    }
}

/// Preconditioner for [`LinearSolverKind::Pcg`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preconditioner {
    /// Diagonal scaling.
    Jacobi,
    /// Incomplete Cholesky with zero fill, IC(0), on the matrix pattern.
    Ic0,
    /// Two-level additive Schwarz: one exactly factorised block per particle plus a coarse
    /// space of the particles' rigid-body modes ([`schwarz::SchwarzPcg`]). Without particles
    /// (a bare matrix, [`make_solver`]) it reduces to Jacobi.
    Schwarz,
}

#[derive(Debug, Error)]
pub enum LinalgError {
    #[error("matrix is singular or not factorizable ({0})")]
    Singular(String),
    #[error("the iterative solver did not converge: relative residual {residual:.3e} after {iterations} iterations (tolerance {tol:.1e})")]
    NotConverged { iterations: usize, residual: f64, tol: f64 },
    #[error("solver used before `analyze` was called for this pattern")]
    NotAnalyzed,
    #[error("linear algebra: {0}")]
    Other(String),
}

/// Options for building a solver.
#[derive(Clone, Copy, Debug)]
pub struct SolverOptions {
    pub kind: LinearSolverKind,
    pub preconditioner: Preconditioner,
    /// Relative residual tolerance of PCG, ‖b − Ax‖ / ‖b‖.
    pub pcg_tol: f64,
    pub pcg_max_iterations: usize,
    /// Threads of the Schwarz preconditioner (1 = sequential); the direct factorisations run
    /// on one whatever this says ([`make_solver_with`]).
    pub threads: usize,
    /// Fill-reducing ordering of the sparse Cholesky factorisation (LU always uses COLAMD).
    pub ordering: direct::FillOrdering,
    /// Whether the matrices will be symmetric (the Schwarz preconditioner then runs CG,
    /// otherwise GMRES).
    pub symmetric: bool,
    /// A direct solve whose relative residual ‖b − Ax‖/‖b‖ stays above this after its
    /// iterative refinement reports the matrix singular ([`direct::Refinement::singular_tol`]).
    pub singular_tol: f64,
}

impl Default for SolverOptions {
    fn default() -> Self {
        Self {
            kind: LinearSolverKind::Lu,
            preconditioner: Preconditioner::Ic0,
            pcg_tol: 1e-10,
            pcg_max_iterations: 10_000,
            threads: 1,
            ordering: direct::FillOrdering::Amd,
            symmetric: true,
            singular_tol: direct::Refinement::default().singular_tol,
        }
    }
}

/// A sparse linear solver for `A x = b` with `A` square in CSR form.
///
/// Lifecycle: `analyze(&a)` once per sparsity pattern → (`factor(&a)` → `solve(&b, &mut x)`)*
/// for every new set of values with the same pattern. `analyze` must be called again when the
/// pattern changes (the caller tracks that; see `CsrMatrix::pattern_id`).
pub trait LinearSolver: Send {
    fn analyze(&mut self, a: &CsrMatrix) -> Result<(), LinalgError>;
    fn factor(&mut self, a: &CsrMatrix) -> Result<(), LinalgError>;
    /// Solve with the last factorisation. For PCG `x` is the initial guess on entry.
    fn solve(&mut self, a: &CsrMatrix, b: &[f64], x: &mut [f64]) -> Result<SolveStats, LinalgError>;
    /// What solves: the method (and, for PETSc, the KSP, PC and factorisation package).
    fn name(&self) -> &str;
    /// Whether the last factorisation found the matrix positive definite (a Cholesky
    /// factorisation that did not fall back to an indefinite one); None when the solver cannot
    /// tell (LU, iterative solvers). An iterative solver may answer Some(false) after a solve
    /// that broke down on a negative curvature (PETSc's CG: `KSP_DIVERGED_INDEFINITE_*`).
    fn definite(&self) -> Option<bool> {
        None
    }
    /// Factor `a` only if it is positive definite: true when it is (factored, ready to solve),
    /// false when it is not (nothing usable is held; a Cholesky solver then skips the indefinite
    /// factorisation [`LinearSolver::factor`] would fall back to). For a caller that makes an
    /// indefinite matrix definite before it solves (the barrier's descent), which needs only
    /// the answer. Solvers that cannot tell factor as usual and answer true.
    fn factor_definite(&mut self, a: &CsrMatrix) -> Result<bool, LinalgError> {
        self.factor(a)?;
        Ok(self.definite() != Some(false))
    }
    /// Solve a symmetric system that may be indefinite, with the last factorisation or
    /// preconditioner: for an iterative solver whose method needs a positive definite matrix
    /// (CG) a Krylov method that does not (GMRES, this solve only); the others solve as
    /// [`LinearSolver::solve`] does (a direct solver's LDLᵀ is exact either way).
    fn solve_indefinite(&mut self, a: &CsrMatrix, b: &[f64], x: &mut [f64]) -> Result<SolveStats, LinalgError> {
        self.solve(a, b, x)
    }
    /// A solver of a process's part of a distributed matrix: the absolute row sums
    /// Σ_j |A_ij| of the whole rows of this process's own equations, as last factored (the
    /// rows of a part hold only the process's own terms). None for the other solvers.
    fn own_row_abs_sums(&self) -> Option<Vec<f64>> {
        None
    }
}

/// `a` is square and its CSR arrays are consistent (what every `analyze` checks first).
fn check_square(a: &CsrMatrix) -> Result<(), LinalgError> {
    if a.nrows != a.ncols {
        return Err(LinalgError::Other(format!("matrix is {}×{}, expected square", a.nrows, a.ncols)));
    }
    a.check_structure().map_err(|e| LinalgError::Other(format!("invalid CSR matrix: {e}")))
}

/// `b` and `x` have the matrix dimension `n` (what every `solve` checks).
fn check_vectors(n: usize, b: &[f64], x: &[f64]) -> Result<(), LinalgError> {
    if b.len() != n || x.len() != n {
        return Err(LinalgError::Other(format!(
            "vector lengths b = {}, x = {} do not match the matrix dimension {n}",
            b.len(),
            x.len()
        )));
    }
    Ok(())
}

/// What a solve reports (iterations are 1 for direct solvers).
#[derive(Clone, Copy, Debug, Default)]
pub struct SolveStats {
    pub iterations: usize,
    pub relative_residual: f64,
}

/// Build the solver chosen in the options.
pub fn make_solver(opts: &SolverOptions) -> Box<dyn LinearSolver> {
    make_solver_with(opts, schwarz::Subdomains::default(), std::sync::Arc::new(crate::comm::Serial))
}

/// Build the solver chosen in the options, with the particles as the subdomains of the
/// Schwarz preconditioner and the processes it is distributed over (only
/// [`Preconditioner::Schwarz`] uses either).
pub fn make_solver_with(
    opts: &SolverOptions,
    subdomains: schwarz::Subdomains,
    comm: std::sync::Arc<dyn crate::comm::Collective>,
) -> Box<dyn LinearSolver> {
    let refinement = direct::Refinement { singular_tol: opts.singular_tol, ..Default::default() };
    match opts.kind {
        LinearSolverKind::Pcg if opts.preconditioner == Preconditioner::Schwarz => {
            let s = schwarz::SchwarzPcg::new(subdomains, comm, opts.pcg_tol, opts.pcg_max_iterations, opts.threads);
            Box::new(if opts.symmetric { s } else { s.unsymmetric() })
        }
        // the sparse direct factorisations and solves run on one thread whatever `threads`
        // says (the threads assemble): faer's parallel kernels were slower on this 2-core
        // machine wherever measured — 1.4–1.5 times on a 205 k-unknown tangent (`cargo bench
        // --bench solve -- solve_205k_threads`), 2.5 times on the dense steps of robustness
        // case 12 (256 polygons, 29 k unknowns, even called from inside the run's pool; from
        // outside it 4.3 times, most of it system time), the same on case 13's loose start
        // (1,024 polygons, docs/robustness.md, eleventh measurement) — and one thread makes a
        // run's path the same on any number of them
        LinearSolverKind::Lu => Box::new(direct::FaerLu::new(1).with_refinement(refinement)),
        LinearSolverKind::Cholesky => Box::new(direct::FaerCholesky::new(1).with_ordering(opts.ordering).with_refinement(refinement)),
        // every row on rank 0 (a simulation gives the rows' owners: `petsc::make`)
        LinearSolverKind::Petsc => petsc::make(None, opts.symmetric, opts.pcg_tol, opts.pcg_max_iterations, opts.singular_tol, comm.rank(), comm.size()),
        LinearSolverKind::Pcg => Box::new(pcg::Pcg::new(
            opts.preconditioner,
            opts.pcg_tol,
            opts.pcg_max_iterations,
        )),
    }
}
