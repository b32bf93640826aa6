//! Compressed sparse row matrix with a fixed pattern and mutable values.

/// Square or rectangular CSR matrix. Column indices are sorted within each row.
/// `pattern_id` changes whenever a new pattern is built, so solvers can tell when their
/// symbolic analysis is stale.
#[derive(Clone, Debug, Default)]
pub struct CsrMatrix {
    pub nrows: usize,
    pub ncols: usize,
    pub row_ptr: Vec<usize>,
    pub col_idx: Vec<usize>,
    pub values: Vec<f64>,
    pub pattern_id: u64,
}

impl CsrMatrix {
    /// Build a pattern from per-row sorted, de-duplicated column lists; values are zero.
    pub fn from_rows(ncols: usize, rows: &[Vec<usize>]) -> Self {
        let mut row_ptr = Vec::with_capacity(rows.len() + 1);
        row_ptr.push(0);
        let mut col_idx = Vec::new();
        for r in rows {
            debug_assert!(r.windows(2).all(|w| w[0] < w[1]));
            col_idx.extend_from_slice(r);
            row_ptr.push(col_idx.len());
        }
        let nnz = col_idx.len();
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        Self {
            nrows: rows.len(),
            ncols,
            row_ptr,
            col_idx,
            values: vec![0.0; nnz],
            pattern_id: NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        }
    }

    pub fn nnz(&self) -> usize {
        self.col_idx.len()
    }

    /// Position of entry (i, j) in `values`, if it is in the pattern (binary search).
    #[inline]
    pub fn find(&self, i: usize, j: usize) -> Option<usize> {
        let s = self.row_ptr[i];
        let e = self.row_ptr[i + 1];
        self.col_idx[s..e].binary_search(&j).ok().map(|k| s + k)
    }

    /// y = A x
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        for i in 0..self.nrows {
            let mut s = 0.0;
            for k in self.row_ptr[i]..self.row_ptr[i + 1] {
                s += self.values[k] * x[self.col_idx[k]];
            }
            y[i] = s;
        }
    }

    pub fn fill_zero(&mut self) {
        self.values.iter_mut().for_each(|v| *v = 0.0);
    }

    /// Diagonal entries (zero where absent).
    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.nrows)
            .map(|i| self.find(i, i).map_or(0.0, |k| self.values[k]))
            .collect()
    }
}

impl CsrMatrix {
    /// Check the structural invariants solvers rely on: `row_ptr` has `nrows + 1`
    /// non-decreasing entries starting at 0 and ending at `nnz`, `values` has `nnz` entries, and
    /// column indices are `< ncols` and strictly increasing within each row.
    pub fn check_structure(&self) -> Result<(), String> {
        if self.row_ptr.len() != self.nrows + 1 {
            return Err(format!(
                "row_ptr has {} entries, expected nrows + 1 = {}",
                self.row_ptr.len(),
                self.nrows + 1
            ));
        }
        if self.row_ptr[0] != 0 || self.row_ptr[self.nrows] != self.col_idx.len() {
            return Err(format!(
                "row_ptr must start at 0 and end at nnz = {} (got {} .. {})",
                self.col_idx.len(),
                self.row_ptr[0],
                self.row_ptr[self.nrows]
            ));
        }
        if self.values.len() != self.col_idx.len() {
            return Err(format!(
                "values has {} entries but the pattern has {}",
                self.values.len(),
                self.col_idx.len()
            ));
        }
        for i in 0..self.nrows {
            let (s, e) = (self.row_ptr[i], self.row_ptr[i + 1]);
            if s > e {
                return Err(format!("row_ptr decreases at row {i}"));
            }
            let cols = &self.col_idx[s..e];
            if let Some(&last) = cols.last() {
                if last >= self.ncols {
                    return Err(format!("row {i} has column index {last} >= ncols = {}", self.ncols));
                }
            }
            if cols.windows(2).any(|w| w[0] >= w[1]) {
                return Err(format!("column indices of row {i} are not strictly increasing"));
            }
        }
        Ok(())
    }

    /// Position of the diagonal entry of every row (`None` where the pattern has no diagonal).
    pub fn diagonal_positions(&self) -> Vec<Option<usize>> {
        (0..self.nrows.min(self.ncols)).map(|i| self.find(i, i)).collect()
    }

    /// ‖b − A x‖₂, using `r` (length `nrows`) as workspace; on return `r = b − A x`.
    pub fn residual_into(&self, x: &[f64], b: &[f64], r: &mut [f64]) -> f64 {
        self.mul_vec(x, r);
        let mut s = 0.0;
        for (ri, bi) in r.iter_mut().zip(b) {
            *ri = bi - *ri;
            s += *ri * *ri;
        }
        s.sqrt()
    }
}

/// What a solver remembers about the sparsity pattern it analysed, to tell whether a matrix
/// handed to `factor` still has that pattern.
///
/// Matrices built by [`CsrMatrix::from_rows`] carry a unique non-zero `pattern_id`, which is
/// trusted. A `pattern_id` of 0 (e.g. a hand-made or `Default` matrix) means "unknown": the stamp
/// then keeps a copy of the pattern and compares it entry by entry.
#[derive(Clone, Debug, Default)]
pub struct PatternStamp {
    valid: bool,
    id: u64,
    nrows: usize,
    ncols: usize,
    nnz: usize,
    copy: Option<(Vec<usize>, Vec<usize>)>,
}

impl PatternStamp {
    /// Stamp of the pattern of `a`.
    pub fn of(a: &CsrMatrix) -> Self {
        Self {
            valid: true,
            id: a.pattern_id,
            nrows: a.nrows,
            ncols: a.ncols,
            nnz: a.nnz(),
            copy: (a.pattern_id == 0).then(|| (a.row_ptr.clone(), a.col_idx.clone())),
        }
    }

    /// Whether `a` has the stamped pattern.
    pub fn matches(&self, a: &CsrMatrix) -> bool {
        if !self.valid
            || self.id != a.pattern_id
            || self.nrows != a.nrows
            || self.ncols != a.ncols
            || self.nnz != a.nnz()
        {
            return false;
        }
        match &self.copy {
            None => true,
            Some((rp, ci)) => *rp == a.row_ptr && *ci == a.col_idx,
        }
    }

    /// Forget the stamped pattern (the next `matches` is false).
    pub fn clear(&mut self) {
        *self = Self::default();
    }
}
