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
