//! faer sparse direct solvers: LU with partial pivoting ([`FaerLu`]) and Cholesky
//! ([`FaerCholesky`]: LLᵀ, falling back to an LDLᵀ or a Bunch–Kaufman LBLᵀ factorisation on the
//! same symbolic structure when the matrix is not positive definite). Both are a [`FaerDirect`]:
//! the pattern check, the workspace and the checked solve are written once; [`LuFactors`] and
//! [`CholeskyFactors`] hold what is each one's own.
//!
//! The fill-reducing ordering of the Cholesky factorisation is a [`FillOrdering`]: faer's
//! approximate minimum degree (AMD) or METIS nested dissection (from the `partition` crate). The
//! LU factorisation always uses faer's COLAMD column ordering: faer 0.24's symbolic LU takes no
//! custom column permutation.
//!
//! The Cholesky factorisation holds the matrix permuted into its fill-reducing order
//! (`Ordered`, made at the analysis), so that a numeric factorisation gathers the new values
//! into it in one pass instead of faer permuting the matrix again.
//!
//! Both keep their symbolic factorisation (fill-reducing ordering, elimination tree, supernodes)
//! and all numeric storage and scratch memory between calls: `factor` only refills values and
//! runs the numeric factorisation, as long as the pattern is unchanged
//! ([`CsrMatrix::pattern_id`]). A changed pattern triggers a new analysis automatically.
//!
//! Every `solve` checks its answer: it computes the relative residual ‖b − Ax‖/‖b‖, applies up
//! to [`Refinement::max_steps`] steps of iterative refinement when the residual is above
//! [`Refinement::target`], and reports [`LinalgError::Singular`] when the solution is not finite
//! or the residual stays above [`Refinement::singular_tol`].

use super::csr::PatternStamp;
use super::*;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::solvers::Solve;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, IntranodeLbltRef, LdltRef, LltRef,
    SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, LuSymbolicParams, NumericLu, SymbolicLu};
use faer::linalg::cholesky::llt::factor::LltError as DenseLltError;
use faer::sparse::linalg::{LuError, SupernodalThreshold};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::mat::AsMatMut;
use faer::{Conj, MatMut, Par, Side};

/// faer parallelism for a thread count (0 or 1 → sequential).
/// Run `f`, turning a panic inside it into `None`, without the panic message on stderr.
///
/// faer 0.24's indefinite sparse factorisations can fail an index assertion on some tangents
/// (seen: the intranode Bunch–Kaufman LBLᵀ of a 61 k-unknown 16 × 16 disc compaction at a
/// 1.25 mm mesh, `row < self.nrows()` with row = nrows = 2 in a 2 × 2 pivot block), which
/// ended the whole run with exit code 101. Behind this the factorisation fails like any other
/// singular one: the next fallback is tried, and the Newton step cuts back. The panic hook is
/// swapped for a silent one while `f` runs (the library does not print; the solver logs the
/// failure through `tracing`). Since the unpivoted LDLᵀ comes first, that case no longer
/// reaches the LBLᵀ (`tests/cli.rs`).
fn without_panics<T>(f: impl FnOnce() -> T) -> Option<T> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    std::panic::set_hook(hook);
    out.ok()
}

pub fn faer_par(threads: usize) -> Par {
    if threads > 1 {
        Par::rayon(threads)
    } else {
        Par::Seq
    }
}

/// Which numeric kernel family faer uses.
///
/// `Auto` (the default) is the supernodal kernels for the Cholesky factorisation and faer's
/// own choice for LU. faer's choice (`FaerChoice`) takes the supernodal kernels only where the
/// factorisation's flop count exceeds 40 times the factor's entries, and a particle packing's
/// tangent, nearly block-diagonal, mostly falls below that: faer then factors it with its
/// simplicial (up-looking) kernels, which were 1.3–2.2 times slower than the supernodal ones
/// on every packing tangent measured, from 16 to 1,024 random discs (1,540 to 102,530
/// unknowns), loose or with contacts (`cargo bench --bench structure`, docs/performance.md).
/// The others force a choice (benchmarks, tests).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FactorStructure {
    #[default]
    Auto,
    FaerChoice,
    Simplicial,
    Supernodal,
}

impl FactorStructure {
    /// The threshold for faer's analysis; `cholesky`: of a Cholesky factorisation (else LU).
    fn threshold(self, cholesky: bool) -> SupernodalThreshold {
        match self {
            FactorStructure::Auto if cholesky => SupernodalThreshold::FORCE_SUPERNODAL,
            FactorStructure::Auto | FactorStructure::FaerChoice => SupernodalThreshold::AUTO,
            FactorStructure::Simplicial => SupernodalThreshold::FORCE_SIMPLICIAL,
            FactorStructure::Supernodal => SupernodalThreshold::FORCE_SUPERNODAL,
        }
    }
}

/// Fill-reducing symmetric ordering of [`FaerCholesky`].
///
/// AMD is the default because it is the faster one here: on the SPD disc-grid tangents of
/// `benches/ordering.rs` (27 000 and 109 000 unknowns, sequential) METIS nested dissection
/// gives 6-13 % less fill, but its analysis + factorisation takes 2.9-4× as long (the METIS
/// ordering itself dominates) and even the numeric factorisation alone, the work of every
/// Newton iteration, takes 1.1-1.4× as long with faer's supernodal kernels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FillOrdering {
    /// faer's approximate minimum degree ordering.
    #[default]
    Amd,
    /// METIS nested dissection ([`partition::metis_nd`]) of the matrix graph (the pattern
    /// without its diagonal). When METIS fails the analysis falls back to AMD with a warning.
    Metis,
}

/// Owned fill-reducing permutation for faer: `fwd[k]` is the row eliminated `k`-th, `inv` its
/// inverse. `None` means "let faer compute AMD".
fn fill_permutation(a: &CsrMatrix, ordering: FillOrdering) -> Option<(Vec<usize>, Vec<usize>)> {
    match ordering {
        FillOrdering::Amd => None,
        FillOrdering::Metis => {
            let nd = partition::graph_of_pattern(a.nrows, &a.row_ptr, &a.col_idx).and_then(|g| partition::metis_nd(&g));
            match nd {
                Ok(p) => Some(p),
                Err(e) => {
                    tracing::warn!("METIS nested dissection failed ({e}); using AMD");
                    None
                }
            }
        }
    }
}

/// The symbolic Cholesky factorisation of the symmetric `a` (full pattern) in its fill-reducing
/// order P (`ordering`): B = P A Pᵀ's upper triangle ([`Ordered`]) and faer's analysis of it in
/// its own order, the same ordering and symbolic factorisation as faer's analysis of A with P.
fn ordered_symbolic(a: &CsrMatrix, ordering: FillOrdering, structure: FactorStructure) -> Result<(Ordered, SymbolicCholesky<usize>), LinalgError> {
    let (fwd, inv) = match fill_permutation(a, ordering) {
        Some(p) => p,
        None => amd_permutation(a)?,
    };
    // (faer's analysis without an ordering reads the upper triangle, whatever side it is told)
    let upper = Ordered::new(a, fwd, inv, Side::Upper);
    let params = CholeskySymbolicParams { supernodal_flop_ratio_threshold: structure.threshold(true), ..Default::default() };
    let symbolic = factorize_symbolic_cholesky(upper.symbolic(), Side::Upper, SymmetricOrdering::Identity, params)
        .map_err(|e| LinalgError::Other(format!("faer symbolic Cholesky failed: {e:?}")))?;
    Ok((upper, symbolic))
}

/// Number of nonzeros of the Cholesky factor L (diagonal included) of the symmetric matrix `a`
/// under the given ordering: the fill measure of an ordering (a simplicial symbolic analysis,
/// no numeric work).
pub fn cholesky_factor_nnz(a: &CsrMatrix, ordering: FillOrdering) -> Result<usize, LinalgError> {
    check_square(a)?;
    Ok(ordered_symbolic(a, ordering, FactorStructure::Simplicial)?.1.len_val())
}

/// Post-solve accuracy control of the direct solvers.
#[derive(Clone, Copy, Debug)]
pub struct Refinement {
    /// Maximum number of iterative-refinement steps per solve (0 disables refinement).
    pub max_steps: usize,
    /// Refine while the relative residual ‖b − Ax‖/‖b‖ is above this.
    pub target: f64,
    /// After refinement, a relative residual above this is reported as
    /// [`LinalgError::Singular`] (numerically singular or hopelessly ill-conditioned matrix).
    /// `f64::INFINITY` disables the check (non-finite solutions are still reported).
    pub singular_tol: f64,
}

impl Default for Refinement {
    fn default() -> Self {
        Self { max_steps: 2, target: 1e-12, singular_tol: 1e-6 }
    }
}

/// Convert a CSR matrix to an owned faer CSC matrix (same values, same pattern).
pub fn to_faer_csc(a: &CsrMatrix) -> SparseColMat<usize, f64> {
    let mut col_ptr = Vec::new();
    let mut row_idx = Vec::new();
    let mut pos = Vec::new();
    csr_to_csc_pattern(a, &mut col_ptr, &mut row_idx, &mut pos);
    let values = pos.iter().map(|&k| a.values[k]).collect();
    let sym = SymbolicSparseColMat::new_checked(a.nrows, a.ncols, col_ptr, None, row_idx);
    SparseColMat::new(sym, values)
}

/// Solve `A x = b` with the plainest faer calls: CSR → CSC conversion, then
/// `SparseColMat::sp_lu` (symbolic + numeric) and `Solve::solve_in_place`, all with faer's global
/// parallelism setting. Reference for benchmarks. Panics if faer reports an error.
pub fn bare_faer_lu_solve(a: &CsrMatrix, b: &[f64]) -> Vec<f64> {
    let csc = to_faer_csc(a);
    let lu = csc.sp_lu().expect("faer sparse LU failed");
    let mut x = b.to_vec();
    let n = x.len();
    lu.solve_in_place(MatMut::from_column_major_slice_mut(&mut x, n, 1));
    x
}

/// Solve `A x = b` (A symmetric positive definite) with the plainest faer calls:
/// `SparseColMat::sp_cholesky(Side::Lower)` on the CSC form and `Solve::solve_in_place`, with
/// faer's global parallelism setting. Reference for benchmarks. Panics if faer reports an error.
pub fn bare_faer_cholesky_solve(a: &CsrMatrix, b: &[f64]) -> Vec<f64> {
    let csc = to_faer_csc(a);
    let llt = csc.sp_cholesky(Side::Lower).expect("faer sparse Cholesky failed");
    let mut x = b.to_vec();
    let n = x.len();
    llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut x, n, 1));
    x
}

/// CSC pattern of `a` plus, for each CSC entry, its position in `a.values`. Row indices come out
/// sorted within each column. Reuses the vectors' capacity.
fn csr_to_csc_pattern(a: &CsrMatrix, col_ptr: &mut Vec<usize>, row_idx: &mut Vec<usize>, pos: &mut Vec<usize>) {
    let nnz = a.nnz();
    col_ptr.clear();
    col_ptr.resize(a.ncols + 1, 0);
    for &j in &a.col_idx {
        col_ptr[j + 1] += 1;
    }
    for j in 0..a.ncols {
        col_ptr[j + 1] += col_ptr[j];
    }
    row_idx.clear();
    row_idx.resize(nnz, 0);
    pos.clear();
    pos.resize(nnz, 0);
    // `next[j]` = next free slot of column j (allocated once per pattern).
    let mut next: Vec<usize> = col_ptr[..a.ncols].to_vec();
    for i in 0..a.nrows {
        for k in a.row_ptr[i]..a.row_ptr[i + 1] {
            let j = a.col_idx[k];
            let slot = next[j];
            next[j] += 1;
            row_idx[slot] = i;
            pos[slot] = k;
        }
    }
}

fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Solve with a factorisation (`solve_in_place` overwrites its argument with A⁻¹·arg), then check
/// and refine. `r` and `d` are work vectors of length n.
#[allow(clippy::too_many_arguments)]
fn solve_checked(
    a: &CsrMatrix,
    b: &[f64],
    x: &mut [f64],
    r: &mut [f64],
    d: &mut [f64],
    cfg: &Refinement,
    refinements: &mut usize,
    mut solve_in_place: impl FnMut(&mut [f64]),
) -> Result<SolveStats, LinalgError> {
    *refinements = 0;
    let bnorm = norm2(b);
    if bnorm == 0.0 {
        x.fill(0.0);
        return Ok(SolveStats { iterations: 1, relative_residual: 0.0 });
    }
    if !bnorm.is_finite() {
        return Err(LinalgError::Other("right-hand side is not finite".into()));
    }
    x.copy_from_slice(b);
    solve_in_place(x);
    if !x.iter().all(|v| v.is_finite()) {
        return Err(LinalgError::Singular(
            "the factorisation produced a non-finite solution (zero pivot: matrix numerically singular)".into(),
        ));
    }
    let mut rel = a.residual_into(x, b, r) / bnorm;
    while rel > cfg.target && *refinements < cfg.max_steps {
        d.copy_from_slice(r);
        solve_in_place(d);
        if !d.iter().all(|v| v.is_finite()) {
            break;
        }
        for (xi, di) in x.iter_mut().zip(d.iter()) {
            *xi += di;
        }
        // r is overwritten; keep the old residual norm to decide whether the step helped.
        let new_rel = a.residual_into(x, b, r) / bnorm;
        if new_rel.is_nan() || new_rel >= rel {
            // No improvement: undo the step (restores x and r) and stop.
            for (xi, di) in x.iter_mut().zip(d.iter()) {
                *xi -= di;
            }
            rel = a.residual_into(x, b, r) / bnorm;
            break;
        }
        rel = new_rel;
        *refinements += 1;
    }
    if rel > cfg.target {
        tracing::debug!(relative_residual = rel, refinements = *refinements, "direct solve above the refinement target");
    }
    if rel.is_nan() || rel > cfg.singular_tol {
        return Err(LinalgError::Singular(format!(
            "relative residual {rel:.3e} after the direct solve exceeds {:.1e} \
             (matrix numerically singular or severely ill-conditioned)",
            cfg.singular_tol
        )));
    }
    Ok(SolveStats { iterations: 1, relative_residual: rel })
}

// ---------------------------------------------------------------------------------------------
// What LU and Cholesky share
// ---------------------------------------------------------------------------------------------

/// The part of a faer direct solver that is its own: its symbolic analysis, numeric
/// factorisation and triangular solves. [`FaerDirect`] does the rest.
trait Factorisation {
    /// [`LinearSolver::name`].
    const NAME: &'static str;
    /// What the messages call the factorisation.
    const LABEL: &'static str;
    /// Drop the symbolic analysis and the numeric factorisation.
    fn forget(&mut self);
    /// Symbolic analysis of the square matrix `a` (checked); returns the scratch memory the
    /// numeric factorisation and the solves need with parallelism `par`.
    fn analyse(&mut self, a: &CsrMatrix, structure: FactorStructure, par: Par) -> Result<StackReq, LinalgError>;
    /// Numeric factorisation of the n×n matrix `a`, whose pattern is the analysed one (after a
    /// successful `analyse`).
    fn factor(&mut self, a: &CsrMatrix, n: usize, par: Par, mem: &mut MemBuffer) -> Result<(), LinalgError>;
    /// Overwrite `rhs` with A⁻¹·rhs (after a successful `factor`).
    fn solve_in_place(&self, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack);
    /// Whether the last factorisation found the matrix positive definite (None: it cannot
    /// tell).
    fn definite(&self) -> Option<bool> {
        None
    }
    /// [`LinearSolver::factor_definite`]: by default the factorisation and its answer.
    fn factor_definite(&mut self, a: &CsrMatrix, n: usize, par: Par, mem: &mut MemBuffer) -> Result<bool, LinalgError> {
        self.factor(a, n, par, mem)?;
        Ok(self.definite() != Some(false))
    }
}

/// A faer sparse direct solver: the factorisation `F` ([`LuFactors`] or [`CholeskyFactors`])
/// and what both kinds share: the thread count, the kernel structure, the refinement settings,
/// whether an analysis and a factorisation are held, the pattern stamp that decides whether the
/// analysis still holds, the counters, faer's workspace (sized at the analysis) and the work
/// vectors of the refinement.
pub struct FaerDirect<F> {
    threads: usize,
    par: Par,
    structure: FactorStructure,
    refine: Refinement,
    analysed: bool,
    factored: bool,
    stamp: PatternStamp,
    analyses: usize,
    refinements: usize,
    n: usize,
    mem: MemBuffer,
    r: Vec<f64>,
    d: Vec<f64>,
    fact: F,
}

impl<F: Default> FaerDirect<F> {
    /// `threads` > 1 runs the numeric factorisation and solves with `Par::rayon(threads)`.
    pub fn new(threads: usize) -> Self {
        Self {
            threads,
            par: faer_par(threads),
            structure: FactorStructure::Auto,
            refine: Refinement::default(),
            analysed: false,
            factored: false,
            stamp: PatternStamp::default(),
            analyses: 0,
            refinements: 0,
            n: 0,
            mem: MemBuffer::new(StackReq::empty()),
            r: Vec::new(),
            d: Vec::new(),
            fact: F::default(),
        }
    }
}

impl<F> FaerDirect<F> {
    /// Force simplicial / supernodal kernels (takes effect at the next analysis).
    pub fn with_structure(mut self, s: FactorStructure) -> Self {
        self.structure = s;
        self.stamp.clear();
        self
    }

    /// Replace the post-solve refinement / singularity-check settings.
    pub fn with_refinement(mut self, r: Refinement) -> Self {
        self.refine = r;
        self
    }

    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Number of symbolic analyses performed so far.
    pub fn analyses(&self) -> usize {
        self.analyses
    }

    /// Iterative-refinement steps taken by the last solve.
    pub fn last_refinements(&self) -> usize {
        self.refinements
    }
}

impl<F: Factorisation + Send> LinearSolver for FaerDirect<F> {
    fn analyze(&mut self, a: &CsrMatrix) -> Result<(), LinalgError> {
        if self.analysed && self.stamp.matches(a) {
            return Ok(());
        }
        self.stamp.clear();
        self.analysed = false;
        self.factored = false;
        self.fact.forget();
        check_square(a)?;
        let n = a.nrows;
        self.n = n;
        let req = self.fact.analyse(a, self.structure, self.par)?;
        let Ok(mem) = MemBuffer::try_new(req) else {
            self.fact.forget();
            return Err(LinalgError::Other(format!("out of memory for the {} workspace", F::LABEL)));
        };
        self.mem = mem;
        self.r.resize(n, 0.0);
        self.d.resize(n, 0.0);
        self.analysed = true;
        self.stamp = PatternStamp::of(a);
        self.analyses += 1;
        Ok(())
    }

    fn factor(&mut self, a: &CsrMatrix) -> Result<(), LinalgError> {
        self.analyze(a)?; // nothing to do when the pattern is the analysed one
        self.factored = false;
        self.fact.factor(a, self.n, self.par, &mut self.mem)?;
        self.factored = true;
        Ok(())
    }

    fn factor_definite(&mut self, a: &CsrMatrix) -> Result<bool, LinalgError> {
        self.analyze(a)?;
        self.factored = false;
        let definite = self.fact.factor_definite(a, self.n, self.par, &mut self.mem)?;
        self.factored = definite;
        Ok(definite)
    }

    fn solve(&mut self, a: &CsrMatrix, b: &[f64], x: &mut [f64]) -> Result<SolveStats, LinalgError> {
        if !self.analysed {
            return Err(LinalgError::NotAnalyzed);
        }
        if !self.factored {
            return Err(LinalgError::Other(format!("{} solve called without a successful factorisation", F::LABEL)));
        }
        if a.nrows != self.n || a.ncols != self.n {
            return Err(LinalgError::NotAnalyzed);
        }
        check_vectors(self.n, b, x)?;
        let n = self.n;
        let par = self.par;
        let fact = &self.fact;
        let mem = &mut self.mem;
        solve_checked(a, b, x, &mut self.r, &mut self.d, &self.refine, &mut self.refinements, |v| {
            fact.solve_in_place(MatMut::from_column_major_slice_mut(v, n, 1), par, MemStack::new(mem));
        })
    }

    fn name(&self) -> &'static str {
        F::NAME
    }

    fn definite(&self) -> Option<bool> {
        if self.factored {
            self.fact.definite()
        } else {
            None
        }
    }
}

// ---------------------------------------------------------------------------------------------
// LU
// ---------------------------------------------------------------------------------------------

/// faer sparse LU with partial (row) pivoting and a COLAMD fill-reducing column ordering.
///
/// `analyze` converts the CSR pattern to CSC once (remembering where every CSC value comes from,
/// so `factor` refills values in O(nnz) without allocating) and runs faer's symbolic LU.
pub type FaerLu = FaerDirect<LuFactors>;

/// What [`FaerLu`] holds of its own: the CSC copy of the matrix and faer's symbolic and numeric
/// LU.
#[derive(Default)]
pub struct LuFactors {
    symbolic: Option<SymbolicLu<usize>>,
    numeric: NumericLu<usize, f64>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    csc_pos: Vec<usize>,
    csc_values: Vec<f64>,
}

impl LuFactors {
    fn csc_symbolic(&self, n: usize) -> SymbolicSparseColMatRef<'_, usize> {
        // Invariants were checked when the pattern was converted in `analyse`.
        SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx)
    }
}

impl Factorisation for LuFactors {
    const NAME: &'static str = "lu";
    const LABEL: &'static str = "LU";

    fn forget(&mut self) {
        self.symbolic = None;
    }

    fn analyse(&mut self, a: &CsrMatrix, structure: FactorStructure, par: Par) -> Result<StackReq, LinalgError> {
        csr_to_csc_pattern(a, &mut self.col_ptr, &mut self.row_idx, &mut self.csc_pos);
        self.csc_values.clear();
        self.csc_values.resize(a.nnz(), 0.0);
        let params = LuSymbolicParams { supernodal_flop_ratio_threshold: structure.threshold(false), ..Default::default() };
        let symbolic = factorize_symbolic_lu(self.csc_symbolic(a.nrows), params)
            .map_err(|e| LinalgError::Other(format!("faer symbolic LU failed: {e:?}")))?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]);
        self.symbolic = Some(symbolic);
        self.numeric = NumericLu::new();
        Ok(req)
    }

    fn factor(&mut self, a: &CsrMatrix, n: usize, par: Par, mem: &mut MemBuffer) -> Result<(), LinalgError> {
        for (v, &k) in self.csc_values.iter_mut().zip(&self.csc_pos) {
            *v = a.values[k];
        }
        if let Some(k) = self.csc_values.iter().position(|v| !v.is_finite()) {
            return Err(LinalgError::Other(format!("matrix entry {} is not finite", self.csc_pos[k])));
        }
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let mat = SparseColMatRef::new(sym, &self.csc_values);
        let symbolic = self.symbolic.as_ref().expect("analysed");
        match symbolic.factorize_numeric_lu(&mut self.numeric, mat, par, MemStack::new(mem), Default::default()) {
            Ok(_) => Ok(()),
            Err(LuError::SymbolicSingular { index }) => Err(LinalgError::Singular(format!(
                "LU: no pivot available at elimination step {index} (structurally singular matrix)"
            ))),
            Err(LuError::Generic(e)) => Err(LinalgError::Other(format!("faer numeric LU failed: {e:?}"))),
        }
    }

    fn solve_in_place(&self, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        let symbolic = self.symbolic.as_ref().expect("factored");
        LuRef::new_unchecked(symbolic, &self.numeric).solve_in_place_with_conj(Conj::No, rhs, par, stack);
    }
}

// ---------------------------------------------------------------------------------------------
// Cholesky
// ---------------------------------------------------------------------------------------------

/// Which factorisation [`FaerCholesky`] currently holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CholeskyKind {
    /// A = LLᵀ (positive definite).
    Llt,
    /// A = LDLᵀ without pivoting (indefinite fallback, simplicial structure or when LBLᵀ failed).
    Ldlt,
    /// A = P L B Lᵀ Pᵀ with Bunch–Kaufman pivoting inside supernodes (indefinite fallback,
    /// supernodal structure).
    Lblt,
}

/// faer sparse Cholesky with a choice of fill-reducing ordering ([`FillOrdering`], AMD by
/// default).
///
/// The CSR matrix must be symmetric with a structurally symmetric (full) pattern; only the
/// entries `a[i][j]` with `j ≥ i` (the upper triangle of the CSR rows, which is the lower
/// triangle of the CSC view faer sees) are read — no copy is made.
///
/// The numeric factorisation tries LLᵀ; when a pivot is not positive it falls back on the same
/// symbolic structure to an unpivoted LDLᵀ and then (supernodal structure) to faer's intranode
/// Bunch–Kaufman LBLᵀ; if all fail the result is [`LinalgError::Singular`].
pub type FaerCholesky = FaerDirect<CholeskyFactors>;

/// What [`FaerCholesky`] holds of its own: the ordering, faer's symbolic factorisation, the
/// factor values and the pivoting data of LBLᵀ.
#[derive(Default)]
pub struct CholeskyFactors {
    ordering: FillOrdering,
    symbolic: Option<SymbolicCholesky<usize>>,
    kind: Option<CholeskyKind>,
    l_values: Vec<f64>,
    subdiag: Vec<f64>,
    perm_fwd: Vec<usize>,
    perm_inv: Vec<usize>,
    ordered: Ordered,
}

/// The triangle of a symmetric CSR matrix A in its fill-reducing order, B = P A Pᵀ, as the
/// CSC arrays faer factors, with the map that gathers its values from A's: made at the
/// analysis, so that a numeric factorisation reads B as it stands. Given A and its
/// permutation, faer would build B again at every numeric factorisation (counting its columns
/// and scattering A's entries: 8.8 % of the 1,024 random discs' run, docs/performance.md);
/// the gather is one pass over B's values.
struct Ordered {
    /// B's row i is A's row `fwd[i]`; A's row j is B's row `inv[j]`.
    fwd: Vec<usize>,
    inv: Vec<usize>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// B's k-th value is A's value `gather[k]`.
    gather: Vec<usize>,
    values: Vec<f64>,
    /// The triangle held: `Lower` (rows i ≥ j in column j) for faer's supernodal kernels,
    /// `Upper` for its simplicial ones (each reads its own side without a copy).
    side: Side,
}

impl Default for Ordered {
    fn default() -> Self {
        Self { fwd: Vec::new(), inv: Vec::new(), col_ptr: vec![0], row_idx: Vec::new(), gather: Vec::new(), values: Vec::new(), side: Side::Lower }
    }
}

impl Ordered {
    /// B's triangle `side` of the symmetric `a` (full pattern) under the permutation
    /// (`fwd`, `inv`); its values are gathered by [`Ordered::gather`]. Each entry is read
    /// from the CSR upper triangle of `a` (its row ≤ its column), as faer reads `a`'s CSC
    /// lower triangle: an assembled tangent is symmetric to round-off only, and this keeps
    /// the factors those of faer's own permutation, bit for bit.
    fn new(a: &CsrMatrix, fwd: Vec<usize>, inv: Vec<usize>, side: Side) -> Self {
        let n = a.nrows;
        // B's (row, column) of A's upper entry (r, c), r ≤ c, in the triangle held
        let place = |r: usize, c: usize| {
            let (i, j) = (inv[r], inv[c]);
            if (side == Side::Lower) == (i >= j) {
                (i, j)
            } else {
                (j, i)
            }
        };
        let mut col_ptr = vec![0usize; n + 1];
        for r in 0..n {
            for &c in &a.col_idx[a.row_ptr[r]..a.row_ptr[r + 1]] {
                if c >= r {
                    col_ptr[place(r, c).1 + 1] += 1;
                }
            }
        }
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        let nnz = col_ptr[n];
        let (mut row_idx, mut gather) = (vec![0usize; nnz], vec![0usize; nnz]);
        let mut next = col_ptr.clone();
        for r in 0..n {
            for k in a.row_ptr[r]..a.row_ptr[r + 1] {
                let c = a.col_idx[k];
                if c >= r {
                    let (i, j) = place(r, c);
                    row_idx[next[j]] = i;
                    gather[next[j]] = k;
                    next[j] += 1;
                }
            }
        }
        // (faer's invariants of a column-major pattern, checked here once)
        let _ = SymbolicSparseColMatRef::new_unsorted_checked(n, n, &col_ptr, None, &row_idx);
        Self { fwd, inv, col_ptr, row_idx, gather, values: vec![0.0; nnz], side }
    }

    /// B's values from `a`'s (the matrix of the analysis, new values): whether they are all
    /// finite (what faer reads of `a`; checked in the same pass).
    fn gather(&mut self, a: &CsrMatrix) -> bool {
        let mut finite = true;
        for (v, &k) in self.values.iter_mut().zip(&self.gather) {
            *v = a.values[k];
            finite &= v.is_finite();
        }
        finite
    }

    /// B's pattern as faer reads it. Checked once, where it is made ([`Ordered::new`]); a check
    /// at every factorisation was a pass over the pattern each time (0.9 % of the 1,024 random
    /// discs' run).
    fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        let n = self.fwd.len();
        // SAFETY: `Ordered::new` made these arrays and checked them with
        // `new_unsorted_checked`; nothing changes them afterwards (only `values`)
        unsafe { SymbolicSparseColMatRef::new_unchecked(n, n, &self.col_ptr, None, &self.row_idx) }
    }
}

/// faer's approximate minimum degree ordering of the symmetric `a` (full pattern), as faer's
/// own analysis computes it with `SymmetricOrdering::Amd`: (forward, inverse).
fn amd_permutation(a: &CsrMatrix) -> Result<(Vec<usize>, Vec<usize>), LinalgError> {
    let n = a.nrows;
    let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
    let mut mem = MemBuffer::try_new(faer::sparse::linalg::amd::order_maybe_unsorted_scratch::<usize>(n, a.nnz()))
        .map_err(|_| LinalgError::Other("out of memory for the AMD ordering".into()))?;
    faer::sparse::linalg::amd::order_maybe_unsorted(&mut fwd, &mut inv, csr_as_csc(a), CholeskySymbolicParams::default().amd_params, MemStack::new(&mut mem))
        .map_err(|e| LinalgError::Other(format!("faer AMD ordering failed: {e:?}")))?;
    Ok((fwd, inv))
}

impl FaerDirect<CholeskyFactors> {
    /// Choose the fill-reducing ordering (takes effect at the next analysis).
    pub fn with_ordering(mut self, o: FillOrdering) -> Self {
        self.fact.ordering = o;
        self.stamp.clear();
        self
    }

    pub fn ordering(&self) -> FillOrdering {
        self.fact.ordering
    }

    /// Length of the factor's value storage of the current analysis (nonzeros of L for the
    /// simplicial structure; the supernodal structure also stores the zeros of its dense
    /// blocks).
    pub fn factor_len(&self) -> Option<usize> {
        self.fact.symbolic.as_ref().map(|s| s.len_val())
    }

    /// The factorisation currently held (`None` before a successful `factor`).
    pub fn kind(&self) -> Option<CholeskyKind> {
        self.fact.kind
    }

    /// Whether faer chose (or was forced to) supernodal kernels for the current analysis.
    pub fn is_supernodal(&self) -> Option<bool> {
        self.fact.symbolic.as_ref().map(|s| matches!(s.raw(), SymbolicCholeskyRaw::Supernodal(_)))
    }
}

impl CholeskyFactors {
    /// The LLᵀ factorisation of `a`: None when it succeeded (the factors are held), else the
    /// index of the first pivot that was not positive (nothing usable is held).
    fn llt(&mut self, a: &CsrMatrix, par: Par, mem: &mut MemBuffer) -> Result<Option<usize>, LinalgError> {
        self.kind = None;
        if !self.ordered.gather(a) {
            let k = a.values.iter().position(|v| !v.is_finite()).unwrap_or(0);
            return Err(LinalgError::Other(format!("matrix entry {k} is not finite")));
        }
        let symbolic = self.symbolic.as_ref().expect("analysed");
        let mat = SparseColMatRef::new(self.ordered.symbolic(), &self.ordered.values);
        let llt = symbolic.factorize_numeric_llt(&mut self.l_values, mat, self.ordered.side, Default::default(), par, MemStack::new(mem), Default::default());
        match llt {
            Ok(_) => {
                self.kind = Some(CholeskyKind::Llt);
                Ok(None)
            }
            Err(DenseLltError::NonPositivePivot { index }) => Ok(Some(index)),
        }
    }
}

/// The CSR arrays of `a` seen as a CSC matrix (that is Aᵀ = A for a symmetric matrix).
fn csr_as_csc(a: &CsrMatrix) -> SymbolicSparseColMatRef<'_, usize> {
    SymbolicSparseColMatRef::new_checked(a.nrows, a.ncols, &a.row_ptr, None, &a.col_idx)
}

impl Factorisation for CholeskyFactors {
    const NAME: &'static str = "cholesky";
    const LABEL: &'static str = "Cholesky";

    fn forget(&mut self) {
        self.symbolic = None;
        self.kind = None;
    }

    fn analyse(&mut self, a: &CsrMatrix, structure: FactorStructure, par: Par) -> Result<StackReq, LinalgError> {
        let n = a.nrows;
        // B = P A Pᵀ made here (`Ordered`) and analysed in its own order (so the same factors
        // as faer's of A with P); the supernodal kernels read B's lower triangle
        let (upper, symbolic) = ordered_symbolic(a, self.ordering, structure)?;
        self.ordered = match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(_) => Ordered::new(a, upper.fwd, upper.inv, Side::Lower),
            SymbolicCholeskyRaw::Simplicial(_) => upper,
        };
        tracing::debug!(n, nnz = a.nnz(), factor = symbolic.len_val(), supernodal = matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)), "Cholesky analysed");
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
            symbolic.factorize_numeric_intranode_lblt_scratch::<f64>(par, Default::default()),
            // (a solve's right-hand side in B's order, `solve_in_place`, and faer's own scratch)
            faer::linalg::temp_mat_scratch::<f64>(n, 1).and(symbolic.solve_in_place_scratch::<f64>(1, par)),
        ]);
        self.l_values.clear();
        self.l_values.resize(symbolic.len_val(), 0.0);
        self.subdiag.resize(n, 0.0);
        self.perm_fwd.clear();
        self.perm_fwd.extend(0..n);
        self.perm_inv.clear();
        self.perm_inv.extend(0..n);
        self.symbolic = Some(symbolic);
        Ok(req)
    }

    fn factor_definite(&mut self, a: &CsrMatrix, _n: usize, par: Par, mem: &mut MemBuffer) -> Result<bool, LinalgError> {
        Ok(self.llt(a, par, mem)?.is_none())
    }

    fn factor(&mut self, a: &CsrMatrix, _n: usize, par: Par, mem: &mut MemBuffer) -> Result<(), LinalgError> {
        let Some(llt_pivot) = self.llt(a, par, mem)? else { return Ok(()) };
        let symbolic = self.symbolic.as_ref().expect("analysed");
        // (B's values, gathered by `llt`)
        let side = self.ordered.side;
        let mat = SparseColMatRef::new(self.ordered.symbolic(), &self.ordered.values);

        // Not positive definite: LDLᵀ without pivoting on the same structure first, then (on the
        // supernodal structure, the only one where faer offers it) Bunch–Kaufman LBLᵀ with its
        // pivots chosen inside each supernode. The LDLᵀ first: on the penalty contact tangents
        // of 3 × 3 elastic discs (tests/data/mpi_discs_3x3_pcg.toml with the direct solver) the
        // LBLᵀ solves left relative residuals of 2e-6 to 1e-3 that refinement did not lower,
        // and the run cut back 12 times to the LDLᵀ's none (its solves at 1e-12).
        let ldlt = without_panics(|| {
            symbolic
                .factorize_numeric_ldlt(&mut self.l_values, mat, side, Default::default(), par, MemStack::new(mem), Default::default())
                .map(|_| ())
        });
        let ldlt_failure = match ldlt {
            Some(Ok(())) if self.l_values.iter().all(|v| v.is_finite()) => {
                tracing::debug!(pivot = llt_pivot, "Cholesky: not positive definite, factorised as LDLᵀ without pivoting");
                self.kind = Some(CholeskyKind::Ldlt);
                return Ok(());
            }
            Some(Ok(())) => "the LDLᵀ fallback produced non-finite values".to_string(),
            Some(Err(e)) => format!("the LDLᵀ fallback failed ({e:?})"),
            None => "the LDLᵀ fallback failed inside faer".to_string(),
        };
        if matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)) {
            let done = without_panics(|| {
                symbolic.factorize_numeric_intranode_lblt(
                    &mut self.l_values,
                    &mut self.subdiag,
                    &mut self.perm_fwd,
                    &mut self.perm_inv,
                    mat,
                    side,
                    par,
                    MemStack::new(mem),
                    Default::default(),
                );
            });
            if done.is_none() {
                tracing::debug!("faer's intranode LBLᵀ panicked on this matrix");
            }
            if done.is_some() && self.l_values.iter().chain(&self.subdiag).all(|v| v.is_finite()) {
                tracing::debug!(pivot = llt_pivot, "Cholesky: not positive definite, LDLᵀ failed, factorised as LBLᵀ");
                self.kind = Some(CholeskyKind::Lblt);
                return Ok(());
            }
        }
        Err(LinalgError::Singular(format!(
            "Cholesky: matrix not positive definite (LLᵀ pivot {llt_pivot} ≤ 0) and {ldlt_failure}; \
             the matrix is singular or needs pivoting across supernodes — use the LU solver"
        )))
    }

    fn definite(&self) -> Option<bool> {
        self.kind.map(|k| k == CholeskyKind::Llt)
    }

    fn solve_in_place(&self, mut rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        let symbolic = self.symbolic.as_ref().expect("factored");
        let l_values = &self.l_values;
        // the factors are B's = P A Pᵀ's: A x = b is B (P x) = P b, P b in the workspace (sized
        // at the analysis for the one column every solve has)
        let fwd = &self.ordered.fwd;
        let (mut y, stack) = faer::linalg::temp_mat_zeroed::<f64, _, _>(rhs.nrows(), rhs.ncols(), stack);
        let mut y = y.as_mat_mut();
        for j in 0..rhs.ncols() {
            for (i, &f) in fwd.iter().enumerate() {
                y[(i, j)] = rhs[(f, j)];
            }
        }
        let y_mut = y.as_mut();
        match self.kind.expect("factored") {
            CholeskyKind::Llt => LltRef::new(symbolic, l_values).solve_in_place_with_conj(Conj::No, y_mut, par, stack),
            CholeskyKind::Ldlt => LdltRef::new(symbolic, l_values).solve_in_place_with_conj(Conj::No, y_mut, par, stack),
            CholeskyKind::Lblt => {
                let perm = PermRef::new_checked(&self.perm_fwd, &self.perm_inv, y_mut.nrows());
                IntranodeLbltRef::new(symbolic, l_values, &self.subdiag, perm).solve_in_place_with_conj(Conj::No, y_mut, par, stack)
            }
        }
        for j in 0..rhs.ncols() {
            for (i, &f) in fwd.iter().enumerate() {
                rhs[(f, j)] = y[(i, j)];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::without_panics;

    /// A panic inside a factorisation (here an index out of bounds, as faer's was) becomes a
    /// failure, `None`; a call that returns gives its value.
    #[test]
    fn a_panic_becomes_none() {
        let v: Vec<usize> = vec![1, 2];
        let k = v.len() + 1;
        assert_eq!(without_panics(|| v[k]), None);
        assert_eq!(without_panics(|| v[1]), Some(2));
    }
}
