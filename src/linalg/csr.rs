//! Compressed sparse row matrix with a fixed pattern and mutable values.

/// A new pattern identity (never 0, which marks a hand-made pattern).
fn next_pattern_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

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
        Self { nrows: rows.len(), ncols, row_ptr, col_idx, values: vec![0.0; nnz], pattern_id: next_pattern_id() }
    }

    /// A square pattern of `n` rows from its row pointers and (per row sorted, distinct)
    /// column indices; values are zero, and the pattern gets a new `pattern_id`.
    pub fn from_parts(n: usize, row_ptr: Vec<usize>, col_idx: Vec<usize>) -> Self {
        debug_assert_eq!(row_ptr.len(), n + 1);
        let nnz = col_idx.len();
        Self { nrows: n, ncols: n, row_ptr, col_idx, values: vec![0.0; nnz], pattern_id: next_pattern_id() }
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

/// Marks a constrained row or column in [`BlockMap::locate`] (no entry).
pub const NO_ROW: usize = usize::MAX;

/// The positions in a CSR pattern of a list of square local blocks: block `i` couples its
/// rows `rows_i` (equation numbers, [`NO_ROW`] for a constrained dof) with themselves, and its
/// `w_i × w_i` entries, row-major, sit at `w_i²` positions found once per pattern (binary
/// search), so adding a block costs `w_i²` indexed additions and no search. The non-element
/// terms of the global system (contact pairs, wall pairs, springs, inertia, multiplier rows,
/// follower loads) are added through these maps.
#[derive(Clone, Debug, Default)]
pub struct BlockMap {
    /// Block i's positions are `pos[offsets[i]..offsets[i + 1]]` (its width squared of them).
    offsets: Vec<usize>,
    pos: Vec<u32>,
}

impl BlockMap {
    /// A constrained entry, or one outside the pattern.
    pub const ABSENT: u32 = u32::MAX;

    /// The positions of every block in `m` (entries not in the pattern are [`Self::ABSENT`]).
    pub fn locate<'a>(m: &CsrMatrix, blocks: impl IntoIterator<Item = &'a [usize]>) -> Self {
        let mut offsets = vec![0];
        let mut pos = Vec::new();
        for rows in blocks {
            for &r in rows {
                for &c in rows {
                    let p = if r == NO_ROW || c == NO_ROW { None } else { m.find(r, c) };
                    pos.push(p.map_or(Self::ABSENT, |p| p as u32));
                }
            }
            offsets.push(pos.len());
        }
        Self { offsets, pos }
    }

    /// Number of blocks.
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Width of block `i`.
    pub fn width(&self, i: usize) -> usize {
        ((self.offsets[i + 1] - self.offsets[i]) as f64).sqrt() as usize
    }

    /// Add the row-major block `k` (its width squared of entries) of block `i` to `values`,
    /// skipping constrained entries.
    #[inline]
    pub fn add(&self, values: &mut [f64], i: usize, k: &[f64]) {
        for (&p, &v) in self.pos[self.offsets[i]..self.offsets[i + 1]].iter().zip(k) {
            if p != Self::ABSENT {
                values[p as usize] += v;
            }
        }
    }

    /// Add `v` to entry (a, b) of block `i` (local row and column), unless constrained.
    #[inline]
    pub fn add_entry(&self, values: &mut [f64], i: usize, a: usize, b: usize, v: f64) {
        let w = self.width(i);
        let p = self.pos[self.offsets[i] + a * w + b];
        if p != Self::ABSENT {
            values[p as usize] += v;
        }
    }

    /// Whether entry (a, b) of block `i` is in the pattern (not constrained).
    pub fn has_entry(&self, i: usize, a: usize, b: usize) -> bool {
        let w = self.width(i);
        self.pos[self.offsets[i] + a * w + b] != Self::ABSENT
    }
}
