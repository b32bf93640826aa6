//! PETSc as the distributed linear solver engine (`[solver] linear = "petsc"`, feature
//! `petsc`): every process takes part in each solve; the options database tunes it as every
//! PETSc program is tuned (`[solver] petsc_options`, or `PETSC_OPTIONS`).
//!
//! The tangent comes to this solver whole on every process (the replicated model of the
//! distributed runs, [`crate::parallel`]); each process hands PETSc only its own rows: the
//! global PETSc numbering puts the rows of each process's particles in one contiguous range,
//! in rank order (the particles' owners after the METIS partition; the multiplier rows on rank
//! 0), and the matrix is a distributed AIJ made once per sparsity pattern from those rows and
//! refilled in place for every new tangent. The update is gathered whole onto every process.
//!
//! Defaults, which the options database overrides: MUMPS's distributed direct solve, its LDLᵀ
//! for a symmetric tangent (whose inertia tells the barrier's descent whether the tangent is
//! positive definite: MUMPS's null-pivot detection and centralised root, ICNTL 24 and 13, are
//! switched on for it unless the options set them) and its LU otherwise. An iterative
//! preconditioner given without a Krylov method (`-pc_type gamg` alone) runs in CG for a
//! symmetric tangent, GMRES otherwise; an iterative solve gets the relative tolerance and
//! iteration limit of `[solver] pcg_tol`, `pcg_max_iterations` and the rigid-body modes of
//! the plane (two translations, one rotation about the origin; restricted to an aggregate
//! inside one particle they are that particle's own) as the near-null space of algebraic
//! multigrid. A direct solve whose residual ‖b − A x‖/‖b‖ stays above the solver's singular
//! tolerance reports the matrix singular, as the faer solvers do.

use super::{CsrMatrix, LinalgError, LinearSolver, SolveStats};

/// What the solver needs to know of each row of the systems it will solve.
#[derive(Clone, Debug)]
pub struct RowLayout {
    /// The process that owns each row (its particle's owner; 0 for the multiplier rows).
    pub owner: Vec<usize>,
    /// The reference position and the direction (0: x, 1: y) of each row's dof; None for a
    /// multiplier row. The rigid-body modes of the near-null space are built from these.
    pub dof: Vec<Option<([f64; 2], usize)>>,
}

/// The PETSc environment of a run: PETSc initialised with the run's options (so that options
/// read at initialisation, `-log_view`, work) and finalised when this is dropped, after every
/// solver of the run. Hold it for the whole run.
pub struct Environment {
    #[cfg(feature = "petsc")]
    _petsc: petsc::Petsc,
}

/// Start PETSc with `options` (PETSc's command-line syntax). Every process calls this.
pub fn start(options: &str) -> Result<Environment, LinalgError> {
    #[cfg(feature = "petsc")]
    {
        let p = petsc::Petsc::initialize(options).map_err(|e| LinalgError::Other(e.to_string()))?;
        Ok(Environment { _petsc: p })
    }
    #[cfg(not(feature = "petsc"))]
    {
        let _ = options;
        Err(LinalgError::Other(NOT_BUILT.into()))
    }
}

/// Why a `linear = "petsc"` run cannot start in a build without the `petsc` feature.
pub const NOT_BUILT: &str = "this mpfem was built without PETSc (rebuild with `cargo build --release --features petsc` after `bash scripts/setup.sh`)";

/// The PETSc solver for the rows of `layout` (None: every row on rank 0), on the processes of
/// `PETSC_COMM_WORLD`, which must be the run's (`rank` of `size`: checked, with PETSc's
/// initialisation if nobody made an [`Environment`], by the first `analyze`). Without the
/// `petsc` feature its `analyze` fails with [`NOT_BUILT`].
pub fn make(layout: Option<RowLayout>, symmetric: bool, rtol: f64, max_iterations: usize, singular_tol: f64, rank: usize, size: usize) -> Box<dyn LinearSolver> {
    #[cfg(feature = "petsc")]
    {
        Box::new(imp::PetscSolver::new(layout, symmetric, rtol, max_iterations, singular_tol, rank, size))
    }
    #[cfg(not(feature = "petsc"))]
    {
        let _ = (layout, symmetric, rtol, max_iterations, singular_tol, rank, size);
        Box::new(NotBuilt)
    }
}

/// The solver of a build without PETSc: every call fails with [`NOT_BUILT`].
#[cfg(not(feature = "petsc"))]
struct NotBuilt;

#[cfg(not(feature = "petsc"))]
impl LinearSolver for NotBuilt {
    fn analyze(&mut self, _a: &CsrMatrix) -> Result<(), LinalgError> {
        Err(LinalgError::Other(NOT_BUILT.into()))
    }
    fn factor(&mut self, _a: &CsrMatrix) -> Result<(), LinalgError> {
        Err(LinalgError::Other(NOT_BUILT.into()))
    }
    fn solve(&mut self, _a: &CsrMatrix, _b: &[f64], _x: &mut [f64]) -> Result<SolveStats, LinalgError> {
        Err(LinalgError::Other(NOT_BUILT.into()))
    }
    fn name(&self) -> &str {
        "petsc (not built)"
    }
}

#[cfg(feature = "petsc")]
mod imp {
    use super::super::{check_square, check_vectors};
    use super::*;
    use petsc::{GatherAll, Ksp, Matrix, Vector};

    fn err(e: petsc::Error) -> LinalgError {
        LinalgError::Other(e.to_string())
    }

    /// The PETSc objects of one sparsity pattern.
    struct Pattern {
        pattern_id: u64,
        /// PETSc's number of every row.
        global: Vec<usize>,
        /// This process's rows (mpfem numbers), in PETSc's order.
        local_rows: Vec<usize>,
        /// For every entry of the local CSR handed to PETSc, its position in the tangent's
        /// values.
        source: Vec<usize>,
        values: Vec<f64>,
        a: Matrix,
        ksp: Ksp,
        b: Vector,
        x: Vector,
        ax: Vector,
        gather: GatherAll,
        direct: bool,
        name: String,
        inertia_warned: bool,
    }

    pub(super) struct PetscSolver {
        layout: Option<RowLayout>,
        symmetric: bool,
        rtol: f64,
        max_iterations: usize,
        singular_tol: f64,
        rank: usize,
        size: usize,
        pattern: Option<Pattern>,
        definite: Option<bool>,
    }

    impl PetscSolver {
        pub(super) fn new(layout: Option<RowLayout>, symmetric: bool, rtol: f64, max_iterations: usize, singular_tol: f64, rank: usize, size: usize) -> Self {
            Self { layout, symmetric, rtol, max_iterations, singular_tol, rank, size, pattern: None, definite: None }
        }

        fn build(&self, a: &CsrMatrix) -> Result<Pattern, LinalgError> {
            petsc::ensure_initialized().map_err(err)?;
            let (r, s) = petsc::Petsc::rank_size().map_err(err)?;
            if (r, s) != (self.rank, self.size) {
                return Err(LinalgError::Other(format!("PETSc runs on {s} process(es) (this is its rank {r}) but the run on {} (rank {})", self.size, self.rank)));
            }
            let n = a.nrows;
            let whole = RowLayout { owner: vec![0; n], dof: vec![None; n] };
            let layout = self.layout.as_ref().unwrap_or(&whole);
            if layout.owner.len() != n || layout.dof.len() != n {
                return Err(LinalgError::Other(format!("the row layout has {} rows, the matrix {n}", layout.owner.len())));
            }
            if let Some(&o) = layout.owner.iter().find(|&&o| o >= self.size) {
                return Err(LinalgError::Other(format!("a row owned by process {o} of {}", self.size)));
            }
            // PETSc's numbering: each process's rows in one range, in rank order, each range in
            // mpfem's order
            let mut count = vec![0usize; self.size];
            for &o in &layout.owner {
                count[o] += 1;
            }
            let mut next: Vec<usize> = count.iter().scan(0, |s, &c| {
                let start = *s;
                *s += c;
                Some(start)
            }).collect();
            let mut global = vec![0usize; n];
            let mut local_rows = Vec::with_capacity(count[self.rank]);
            for (i, &o) in layout.owner.iter().enumerate() {
                global[i] = next[o];
                next[o] += 1;
                if o == self.rank {
                    local_rows.push(i);
                }
            }
            // this process's rows in CSR with PETSc's column numbers, ascending in each row
            let mut row_ptr = Vec::with_capacity(local_rows.len() + 1);
            row_ptr.push(0);
            let (mut cols, mut source) = (Vec::new(), Vec::new());
            let mut row: Vec<(usize, usize)> = Vec::new();
            for &i in &local_rows {
                row.clear();
                row.extend((a.row_ptr[i]..a.row_ptr[i + 1]).map(|k| (global[a.col_idx[k]], k)));
                row.sort_unstable();
                cols.extend(row.iter().map(|e| e.0));
                source.extend(row.iter().map(|e| e.1));
                row_ptr.push(cols.len());
            }
            let values: Vec<f64> = source.iter().map(|&k| a.values[k]).collect();
            let mut m = Matrix::from_local_csr(n, &row_ptr, &cols, &values).map_err(err)?;
            if self.symmetric {
                m.set_symmetric().map_err(err)?;
            }
            // the rigid-body modes of the plane, for algebraic multigrid
            let mut modes = Vec::with_capacity(3);
            for mode in 0..3 {
                let v: Vec<f64> = local_rows
                    .iter()
                    .map(|&i| match layout.dof[i] {
                        None => 0.0,
                        Some((p, c)) => match (mode, c) {
                            (0, 0) | (1, 1) => 1.0,
                            (2, 0) => -p[1],
                            (2, _) => p[0],
                            _ => 0.0,
                        },
                    })
                    .collect();
                let mut vec = Vector::like_rows(&m).map_err(err)?;
                vec.set_local(&v).map_err(err)?;
                modes.push(vec);
            }
            m.set_near_null_space(modes).map_err(err)?;
            // MUMPS reports the inertia of its LDLᵀ (on several processes) only with these
            let symmetric_direct = ["-mat_mumps_icntl_13", "-mat_mumps_icntl_24"];
            for o in symmetric_direct {
                if self.symmetric && !petsc::has_option(o).map_err(err)? {
                    petsc::insert_options(&format!("{o} 1")).map_err(err)?;
                }
            }
            let mut ksp = Ksp::new().map_err(err)?;
            let pc = if self.symmetric { "cholesky" } else { "lu" };
            ksp.set_defaults("preonly", pc, Some("mumps"), self.rtol, self.max_iterations).map_err(err)?;
            ksp.set_operator(&m).map_err(err)?;
            ksp.set_from_options().map_err(err)?;
            let (mut k, mut p, mut package) = ksp.types().map_err(err)?;
            if k == "preonly" && p != "lu" && p != "cholesky" && !petsc::has_option("-ksp_type").map_err(err)? {
                // an iterative preconditioner (`-pc_type gamg`) alone: its Krylov method, CG for
                // a symmetric tangent, GMRES otherwise (one application is not a solve)
                let krylov = if self.symmetric { "cg" } else { "gmres" };
                ksp.set_defaults(krylov, &p, None, self.rtol, self.max_iterations).map_err(err)?;
                ksp.set_from_options().map_err(err)?;
                (k, p, package) = ksp.types().map_err(err)?;
            }
            let direct = k == "preonly";
            let name = match package {
                Some(pkg) => format!("petsc {k}+{p} ({pkg})"),
                None => format!("petsc {k}+{p}"),
            };
            let b = Vector::like_rows(&m).map_err(err)?;
            let x = Vector::like_rows(&m).map_err(err)?;
            let ax = Vector::like_rows(&m).map_err(err)?;
            let gather = GatherAll::new(&x).map_err(err)?;
            Ok(Pattern { pattern_id: a.pattern_id, global, local_rows, source, values, a: m, ksp, b, x, ax, gather, direct, name, inertia_warned: false })
        }
    }

    impl LinearSolver for PetscSolver {
        fn analyze(&mut self, a: &CsrMatrix) -> Result<(), LinalgError> {
            check_square(a)?;
            // (the objects of the old pattern go first)
            self.pattern = None;
            self.pattern = Some(self.build(a)?);
            self.definite = None;
            Ok(())
        }

        fn factor(&mut self, a: &CsrMatrix) -> Result<(), LinalgError> {
            let p = self.pattern.as_mut().ok_or(LinalgError::NotAnalyzed)?;
            if p.pattern_id != a.pattern_id || p.source.last().is_some_and(|&k| k >= a.values.len()) {
                return Err(LinalgError::NotAnalyzed);
            }
            for (v, &k) in p.values.iter_mut().zip(&p.source) {
                *v = a.values[k];
            }
            self.definite = None;
            p.a.update_values(&p.values).map_err(err)?;
            p.ksp.set_operator(&p.a).map_err(err)?;
            p.ksp.set_up().map_err(|e| LinalgError::Singular(e.to_string()))?;
            // (options that keep MUMPS from reporting the inertia, `-mat_mumps_icntl_24 0`,
            // leave the definiteness unknown, as with LU, rather than failing every solve)
            match p.ksp.inertia() {
                Ok(Some((neg, zero, _))) => self.definite = Some(neg == 0 && zero == 0),
                Ok(None) => {}
                Err(e) if !p.inertia_warned => {
                    tracing::warn!(%e, "the factorisation's inertia is not available: whether the tangent is positive definite is not known");
                    p.inertia_warned = true;
                }
                Err(_) => {}
            }
            Ok(())
        }

        fn solve(&mut self, a: &CsrMatrix, b: &[f64], x: &mut [f64]) -> Result<SolveStats, LinalgError> {
            check_vectors(a.nrows, b, x)?;
            let p = self.pattern.as_mut().ok_or(LinalgError::NotAnalyzed)?;
            let local: Vec<f64> = p.local_rows.iter().map(|&i| b[i]).collect();
            p.b.set_local(&local).map_err(err)?;
            let info = p.ksp.solve(&p.b, &mut p.x).map_err(err)?;
            // ‖b − A x‖ / ‖b‖ over every process
            p.a.mult(&p.x, &mut p.ax).map_err(err)?;
            p.ax.axpy(-1.0, &p.b).map_err(err)?;
            let (res, bn) = (p.ax.norm2().map_err(err)?, p.b.norm2().map_err(err)?);
            let rel = if bn > 0.0 { res / bn } else { res };
            if info.reason < 0 || !rel.is_finite() {
                return Err(if p.direct {
                    LinalgError::Singular(format!("{}: KSP diverged (reason {}), relative residual {rel:.3e}", p.name, info.reason))
                } else {
                    LinalgError::NotConverged { iterations: info.iterations, residual: rel, tol: self.rtol }
                });
            }
            if p.direct && rel > self.singular_tol {
                return Err(LinalgError::Singular(format!("{}: relative residual {rel:.3e} after the direct solve", p.name)));
            }
            let all = p.gather.gather(&p.x).map_err(err)?;
            for (xi, &g) in x.iter_mut().zip(&p.global) {
                *xi = all[g];
            }
            Ok(SolveStats { iterations: info.iterations.max(1), relative_residual: rel })
        }

        fn name(&self) -> &str {
            self.pattern.as_ref().map_or("petsc", |p| p.name.as_str())
        }

        fn definite(&self) -> Option<bool> {
            self.definite
        }
    }
}
