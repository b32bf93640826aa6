//! Preconditioned conjugate gradients for symmetric positive definite matrices, with a Jacobi
//! (diagonal) or an IC(0) (incomplete Cholesky, zero fill) preconditioner.
//!
//! `analyze` builds the pattern-dependent structures (diagonal positions, the lower-triangle
//! pattern of the IC(0) factor and its map into the matrix values) and sizes every work vector;
//! `factor` computes the preconditioner values; `solve` iterates without allocating.

use super::csr::PatternStamp;
use super::*;

const NONE: usize = usize::MAX;

/// IC(0) diagonal shifts tried, in order, when a pivot is not positive: the factorised matrix is
/// A + α·diag(A).
const IC0_SHIFTS: [f64; 7] = [1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3];

/// Preconditioned conjugate gradients (see the module documentation).
///
/// The matrix must be symmetric positive definite with a structurally symmetric pattern that
/// contains the diagonal. IC(0) reads the lower triangle (`j ≤ i`) of the CSR rows.
pub struct Pcg {
    preconditioner: Preconditioner,
    tol: f64,
    max_iterations: usize,
    state: CgState,
    /// Position of the diagonal entry of each row in `a.values`.
    diag_pos: Vec<usize>,
    /// Jacobi: 1 / a_ii.
    inv_diag: Vec<f64>,
    /// IC(0) factor L (lower triangular, CSR, diagonal last in each row).
    l_row_ptr: Vec<usize>,
    l_col: Vec<usize>,
    /// Position in `a.values` of each entry of L.
    l_src: Vec<usize>,
    l_val: Vec<f64>,
    /// Scatter map used by the IC(0) factorisation (all `NONE` between rows).
    marker: Vec<usize>,
    ic_shift: f64,
}

impl Pcg {
    pub fn new(preconditioner: Preconditioner, tol: f64, max_iterations: usize) -> Self {
        Self {
            preconditioner,
            tol,
            max_iterations,
            state: CgState::default(),
            diag_pos: Vec::new(),
            inv_diag: Vec::new(),
            l_row_ptr: Vec::new(),
            l_col: Vec::new(),
            l_src: Vec::new(),
            l_val: Vec::new(),
            marker: Vec::new(),
            ic_shift: 0.0,
        }
    }

    pub fn preconditioner(&self) -> Preconditioner {
        self.preconditioner
    }

    pub fn tolerance(&self) -> f64 {
        self.tol
    }

    pub fn max_iterations(&self) -> usize {
        self.max_iterations
    }

    /// Number of pattern analyses performed so far.
    pub fn analyses(&self) -> usize {
        self.state.analyses
    }

    /// Diagonal shift α used by the last IC(0) factorisation (the preconditioner is the IC(0)
    /// factor of A + α·diag(A)); 0 when no shift was needed or for Jacobi.
    pub fn ic_shift(&self) -> f64 {
        self.ic_shift
    }

    /// One attempt at IC(0) of A + alpha·diag(A). On a non-positive pivot returns its row.
    fn ic0_try(&mut self, a: &CsrMatrix, alpha: f64) -> Result<(), usize> {
        let n = self.state.n;
        let (rp, col, src, val, marker) =
            (&self.l_row_ptr, &self.l_col, &self.l_src, &mut self.l_val, &mut self.marker);
        for i in 0..n {
            let (s, e) = (rp[i], rp[i + 1]);
            let dpos = e - 1; // diagonal is last
            for q in s..e {
                marker[col[q]] = q;
            }
            // Off-diagonal entries L[i][k], k < i, in increasing k.
            for q in s..dpos {
                let k = col[q];
                let mut v = a.values[src[q]];
                let (ks, ke) = (rp[k], rp[k + 1] - 1);
                for t in ks..ke {
                    let m = marker[col[t]];
                    if m != NONE {
                        // col[t] < k, so L[i][col[t]] (position m < q) is already final.
                        v -= val[m] * val[t];
                    }
                }
                val[q] = v / val[ke];
            }
            let mut d = a.values[src[dpos]] * (1.0 + alpha);
            for q in s..dpos {
                d -= val[q] * val[q];
            }
            for q in s..e {
                marker[col[q]] = NONE;
            }
            if !d.is_finite() || d <= 0.0 {
                return Err(i);
            }
            val[dpos] = d.sqrt();
        }
        Ok(())
    }

    /// z = M⁻¹ r.
    fn apply_preconditioner(
        preconditioner: Preconditioner,
        inv_diag: &[f64],
        l_row_ptr: &[usize],
        l_col: &[usize],
        l_val: &[f64],
        r: &[f64],
        z: &mut [f64],
    ) {
        match preconditioner {
            Preconditioner::Jacobi | Preconditioner::Schwarz => {
                for ((zi, ri), di) in z.iter_mut().zip(r).zip(inv_diag) {
                    *zi = ri * di;
                }
            }
            Preconditioner::Ic0 => {
                let n = r.len();
                // L y = r
                for i in 0..n {
                    let (s, dpos) = (l_row_ptr[i], l_row_ptr[i + 1] - 1);
                    let mut v = r[i];
                    for q in s..dpos {
                        v -= l_val[q] * z[l_col[q]];
                    }
                    z[i] = v / l_val[dpos];
                }
                // Lᵀ z = y (column sweep over the rows of L)
                for i in (0..n).rev() {
                    let (s, dpos) = (l_row_ptr[i], l_row_ptr[i + 1] - 1);
                    let zi = z[i] / l_val[dpos];
                    z[i] = zi;
                    for q in s..dpos {
                        z[l_col[q]] -= l_val[q] * zi;
                    }
                }
            }
        }
    }
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Work vectors of [`cg`].
#[derive(Default)]
pub(crate) struct CgVectors {
    pub(crate) r: Vec<f64>,
    pub(crate) z: Vec<f64>,
    pub(crate) p: Vec<f64>,
    pub(crate) ap: Vec<f64>,
}

/// What the conjugate-gradient solvers ([`Pcg`], [`super::schwarz::SchwarzPcg`]) keep between
/// calls besides their preconditioner: the analysed pattern and the number of analyses, the
/// dimension, whether the preconditioner is set up for the current values, and the work vectors.
#[derive(Default)]
pub(crate) struct CgState {
    pub(crate) stamp: PatternStamp,
    pub(crate) analyses: usize,
    pub(crate) n: usize,
    pub(crate) factored: bool,
    pub(crate) work: CgVectors,
}

impl CgState {
    /// Whether the pattern of `a` is the analysed one.
    pub(crate) fn is_analysed_for(&self, a: &CsrMatrix) -> bool {
        self.analyses > 0 && self.stamp.matches(a)
    }

    /// Start an analysis of `a`: forget the pattern and the preconditioner, check that `a` is
    /// square and well formed; returns its dimension.
    pub(crate) fn begin_analysis(&mut self, a: &CsrMatrix) -> Result<usize, LinalgError> {
        self.stamp.clear();
        self.factored = false;
        check_square(a)?;
        self.n = a.nrows;
        Ok(self.n)
    }

    /// End a successful analysis of `a`: the work vectors sized (zero), the pattern stamped and
    /// counted.
    pub(crate) fn finish_analysis(&mut self, a: &CsrMatrix) {
        let w = &mut self.work;
        for v in [&mut w.r, &mut w.z, &mut w.p, &mut w.ap] {
            v.clear();
            v.resize(self.n, 0.0);
        }
        self.stamp = PatternStamp::of(a);
        self.analyses += 1;
    }

    /// ‖b‖ after checking the vector lengths; `None` when b = 0 (`x` is then set to the exact
    /// solution 0), an error when b is not finite.
    pub(crate) fn rhs_norm(&self, b: &[f64], x: &mut [f64]) -> Result<Option<f64>, LinalgError> {
        check_vectors(self.n, b, x)?;
        let bnorm = dot(b, b).sqrt();
        if bnorm == 0.0 {
            x.fill(0.0);
            return Ok(None);
        }
        if !bnorm.is_finite() {
            return Err(LinalgError::Other("right-hand side is not finite".into()));
        }
        Ok(Some(bnorm))
    }
}

/// The product with the matrix and the preconditioner, as [`cg`] uses them.
pub(crate) trait CgOperator {
    /// y = A x
    fn mul(&mut self, x: &[f64], y: &mut [f64]);
    /// z = M⁻¹ r
    fn precondition(&mut self, r: &[f64], z: &mut [f64]) -> Result<(), LinalgError>;
}

/// Preconditioned conjugate gradients on `A x = b` from the initial guess in `x` (`bnorm` =
/// ‖b‖ > 0), with the work vectors `[r, z, p, ap]`. When the recursive residual reaches `tol`
/// the true one is computed; if it misses, the iteration restarts from it. A breakdown (pᵀAp ≤
/// 0 or rᵀM⁻¹r ≤ 0: the matrix or the preconditioner is not positive definite) is
/// [`LinalgError::Singular`], with its iteration in `broke_at`; running out of iterations is
/// [`LinalgError::NotConverged`] with the true residual of the last iterate.
#[allow(clippy::too_many_arguments)]
pub(crate) fn cg(
    op: &mut dyn CgOperator,
    b: &[f64],
    bnorm: f64,
    x: &mut [f64],
    tol: f64,
    max_iterations: usize,
    [r, z, p, ap]: [&mut [f64]; 4],
    broke_at: &mut usize,
) -> Result<SolveStats, LinalgError> {
    let n = b.len();
    let true_residual = |op: &mut dyn CgOperator, x: &[f64], r: &mut [f64], ap: &mut [f64]| {
        op.mul(x, ap);
        for i in 0..n {
            r[i] = b[i] - ap[i];
        }
        dot(r, r).sqrt() / bnorm
    };
    let mut rel = true_residual(op, x, r, ap);
    if rel <= tol {
        return Ok(SolveStats { iterations: 0, relative_residual: rel });
    }
    op.precondition(r, z)?;
    p.copy_from_slice(z);
    let mut rz = dot(r, z);
    let mut it = 0;
    while it < max_iterations {
        it += 1;
        op.mul(p, ap);
        let pap = dot(p, ap);
        if !pap.is_finite() || pap <= 0.0 {
            *broke_at = it;
            return Err(LinalgError::Singular(format!("PCG breakdown at iteration {it}: pᵀAp = {pap:e} (matrix not positive definite)")));
        }
        let alpha = rz / pap;
        let mut rr = 0.0;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
            rr += r[i] * r[i];
        }
        rel = rr.sqrt() / bnorm;
        if rel <= tol {
            // confirm with the true residual (the recursive one drifts in floating point); if it
            // does not hold, restart from the true residual
            rel = true_residual(op, x, r, ap);
            if rel <= tol {
                return Ok(SolveStats { iterations: it, relative_residual: rel });
            }
            op.precondition(r, z)?;
            p.copy_from_slice(z);
            rz = dot(r, z);
            continue;
        }
        op.precondition(r, z)?;
        let rz_new = dot(r, z);
        if !rz_new.is_finite() || rz_new <= 0.0 {
            *broke_at = it;
            return Err(LinalgError::Singular(format!(
                "PCG breakdown at iteration {it}: rᵀM⁻¹r = {rz_new:e} (preconditioner not positive definite)"
            )));
        }
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    rel = true_residual(op, x, r, ap);
    Err(LinalgError::NotConverged { iterations: it, residual: rel, tol })
}

impl LinearSolver for Pcg {
    fn analyze(&mut self, a: &CsrMatrix) -> Result<(), LinalgError> {
        if self.state.is_analysed_for(a) {
            return Ok(());
        }
        let n = self.state.begin_analysis(a)?;
        self.diag_pos.clear();
        for i in 0..n {
            match a.find(i, i) {
                Some(k) => self.diag_pos.push(k),
                None => {
                    return Err(LinalgError::Singular(format!(
                        "PCG: row {i} has no diagonal entry in the pattern"
                    )))
                }
            }
        }
        self.inv_diag.clear();
        self.l_row_ptr.clear();
        self.l_col.clear();
        self.l_src.clear();
        self.l_val.clear();
        self.marker.clear();
        match self.preconditioner {
            Preconditioner::Jacobi | Preconditioner::Schwarz => self.inv_diag.resize(n, 0.0),
            Preconditioner::Ic0 => {
                // Lower triangle of each row: sorted columns up to and including the diagonal.
                self.l_row_ptr.reserve(n + 1);
                self.l_row_ptr.push(0);
                for i in 0..n {
                    for k in a.row_ptr[i]..=self.diag_pos[i] {
                        self.l_col.push(a.col_idx[k]);
                        self.l_src.push(k);
                    }
                    self.l_row_ptr.push(self.l_col.len());
                }
                self.l_val.resize(self.l_col.len(), 0.0);
                self.marker.resize(n, NONE);
            }
        }
        self.state.finish_analysis(a);
        Ok(())
    }

    fn factor(&mut self, a: &CsrMatrix) -> Result<(), LinalgError> {
        self.analyze(a)?; // nothing to do when the pattern is the analysed one
        self.state.factored = false;
        self.ic_shift = 0.0;
        for (i, &k) in self.diag_pos.iter().enumerate() {
            let d = a.values[k];
            if !d.is_finite() || d <= 0.0 {
                return Err(LinalgError::Singular(format!(
                    "PCG: diagonal entry {i} is {d:e}; the matrix is not symmetric positive definite"
                )));
            }
        }
        match self.preconditioner {
            Preconditioner::Jacobi | Preconditioner::Schwarz => {
                for (inv, &k) in self.inv_diag.iter_mut().zip(&self.diag_pos) {
                    *inv = 1.0 / a.values[k];
                }
            }
            Preconditioner::Ic0 => {
                if let Err(mut row) = self.ic0_try(a, 0.0) {
                    let mut ok = false;
                    for alpha in IC0_SHIFTS {
                        match self.ic0_try(a, alpha) {
                            Ok(()) => {
                                self.ic_shift = alpha;
                                ok = true;
                                break;
                            }
                            Err(r) => row = r,
                        }
                    }
                    if !ok {
                        return Err(LinalgError::Singular(format!(
                            "IC(0): non-positive pivot at row {row} even with a diagonal shift of {:e}·diag(A)",
                            IC0_SHIFTS[IC0_SHIFTS.len() - 1]
                        )));
                    }
                }
            }
        }
        self.state.factored = true;
        Ok(())
    }

    fn solve(&mut self, a: &CsrMatrix, b: &[f64], x: &mut [f64]) -> Result<SolveStats, LinalgError> {
        if self.state.analyses == 0 || a.nrows != self.state.n || a.ncols != self.state.n {
            return Err(LinalgError::NotAnalyzed);
        }
        if !self.state.factored {
            return Err(LinalgError::Other("PCG solve called without a successful factor".into()));
        }
        let Some(bnorm) = self.state.rhs_norm(b, x)? else {
            return Ok(SolveStats { iterations: 0, relative_residual: 0.0 });
        };
        if !x.iter().all(|v| v.is_finite()) {
            x.fill(0.0);
        }
        struct Op<'a> {
            a: &'a CsrMatrix,
            pre: Preconditioner,
            inv_diag: &'a [f64],
            l_row_ptr: &'a [usize],
            l_col: &'a [usize],
            l_val: &'a [f64],
        }
        impl CgOperator for Op<'_> {
            fn mul(&mut self, x: &[f64], y: &mut [f64]) {
                self.a.mul_vec(x, y);
            }
            fn precondition(&mut self, r: &[f64], z: &mut [f64]) -> Result<(), LinalgError> {
                Pcg::apply_preconditioner(self.pre, self.inv_diag, self.l_row_ptr, self.l_col, self.l_val, r, z);
                Ok(())
            }
        }
        let (tol, max_iterations) = (self.tol, self.max_iterations);
        let Self { preconditioner, inv_diag, l_row_ptr, l_col, l_val, state, .. } = self;
        let mut op = Op { a, pre: *preconditioner, inv_diag, l_row_ptr, l_col, l_val };
        let CgVectors { r, z, p, ap } = &mut state.work;
        cg(&mut op, b, bnorm, x, tol, max_iterations, [r, z, p, ap], &mut 0)
    }

    fn name(&self) -> &'static str {
        "pcg"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tridiag(n: usize, diag: f64) -> CsrMatrix {
        let rows: Vec<Vec<usize>> = (0..n)
            .map(|i| (i.saturating_sub(1)..(i + 2).min(n)).collect())
            .collect();
        let mut a = CsrMatrix::from_rows(n, &rows);
        for i in 0..n {
            for k in a.row_ptr[i]..a.row_ptr[i + 1] {
                a.values[k] = if a.col_idx[k] == i { diag } else { -1.0 };
            }
        }
        a
    }

    #[test]
    fn linalg_ic0_of_tridiagonal_is_exact() {
        // IC(0) of a tridiagonal matrix has no dropped fill: it is the exact Cholesky factor,
        // so PCG converges in one iteration.
        let a = tridiag(30, 2.5);
        let b: Vec<f64> = (0..30).map(|i| (i as f64).sin() + 1.0).collect();
        let mut s = Pcg::new(Preconditioner::Ic0, 1e-12, 100);
        s.analyze(&a).unwrap();
        s.factor(&a).unwrap();
        let mut x = vec![0.0; 30];
        let st = s.solve(&a, &b, &mut x).unwrap();
        assert_eq!(st.iterations, 1);
        assert!(st.relative_residual <= 1e-12);
        assert_eq!(s.ic_shift(), 0.0);
    }

    #[test]
    fn linalg_ic0_shift_on_kershaw_matrix() {
        // Kershaw's 4×4 SPD matrix: IC(0) without a shift meets a negative pivot.
        let rows: Vec<Vec<usize>> = vec![vec![0, 1, 3], vec![0, 1, 2], vec![1, 2, 3], vec![0, 2, 3]];
        let mut a = CsrMatrix::from_rows(4, &rows);
        let dense = [[3.0, -2.0, 0.0, 2.0], [-2.0, 3.0, -2.0, 0.0], [0.0, -2.0, 3.0, -2.0], [2.0, 0.0, -2.0, 3.0]];
        for i in 0..4 {
            for k in a.row_ptr[i]..a.row_ptr[i + 1] {
                a.values[k] = dense[i][a.col_idx[k]];
            }
        }
        let mut s = Pcg::new(Preconditioner::Ic0, 1e-10, 100);
        s.analyze(&a).unwrap();
        s.factor(&a).unwrap();
        assert!(s.ic_shift() > 0.0, "Kershaw's matrix needs a shift");
        let b = vec![1.0, 2.0, 3.0, 4.0];
        let mut x = vec![0.0; 4];
        let st = s.solve(&a, &b, &mut x).unwrap();
        assert!(st.relative_residual <= 1e-10);
        assert_eq!(s.analyses(), 1);
    }
}
