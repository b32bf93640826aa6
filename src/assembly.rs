//! The one assembler of the global system: the degree-of-freedom numbering, the one sparsity
//! pattern every force term adds into, and the scatter of the local contributions.
//!
//! Every term of the system is a list of local contributions with its own connectivity (the
//! dofs it touches) and fixed-size scratch: the element kernels (8 dofs), the contact pairs (6
//! or 10), the wall pairs (2), the stabilisation springs and the inertia (1: the diagonal),
//! the follower loads (4), the Lagrange multiplier rows (the pair's dofs and the multiplier).
//! The pattern is the elements' couplings plus those of the terms whose connectivity changes
//! (contact pairs, multipliers); a change of pairs updates it incrementally
//! ([`Assembler::set_terms`]: the element couplings are merged with the new ones and the
//! element scatter remapped, nothing is rebuilt from the mesh). The positions of every other
//! term's entries are found once per pattern ([`BlockMap`]), so adding a contribution never
//! searches.
//!
//! Elements are coloured once per topology so that no two elements of one colour share a node.
//! Colours are processed one after the other; inside a colour the elements are evaluated and
//! scattered in parallel (rayon, on a pool the caller passes in, or sequentially) without any
//! write conflict. Every matrix or vector entry therefore receives its contributions in colour
//! order, whatever the thread count: 1 and N threads give bit-identical results. The other
//! terms are cheap next to the elements and are added after them, in a fixed order (see
//! [`crate::solver`]), which keeps a run on any number of processes bit-identical to the serial
//! one.

use crate::element::{self, ElementKind, ElementOut, Volumetric, N_ENH};
use crate::linalg::{BlockMap, CsrMatrix, NO_ROW};
use crate::material::{MatState, MaterialError, TimeIncrement};
use crate::model::Model;
use rayon::prelude::*;
use thiserror::Error;

/// Marker for a constrained degree of freedom in the equation map.
pub const FIXED: usize = NO_ROW;


#[derive(Debug, Error, Clone, PartialEq)]
#[error("element {element}: {source}")]
pub struct AssemblyError {
    pub element: usize,
    #[source]
    pub source: MaterialError,
}

/// Equation numbers: `eq[dof]` is the row of a free dof in the reduced system, or [`FIXED`].
pub fn number_equations(n_dofs: usize, fixed: impl IntoIterator<Item = usize>) -> (Vec<usize>, usize) {
    let mut eq = vec![0usize; n_dofs];
    for d in fixed {
        eq[d] = FIXED;
    }
    let mut n = 0;
    for e in eq.iter_mut() {
        if *e != FIXED {
            *e = n;
            n += 1;
        }
    }
    (eq, n)
}

/// Per-element results kept after an assembly (Gauss-point stress and new states).
#[derive(Clone, Debug, Default)]
pub struct ElementFields {
    pub states: Vec<[MatState; 4]>,
    /// Cauchy stress per Gauss point `[xx, yy, xy, zz]` (MPa).
    pub sig: Vec<[[f64; 4]; 4]>,
    /// Element pressure (MPa) and area ratio Θ (with respect to the original configuration:
    /// the element's initial volume ratio j₀ included, see [`crate::element`]).
    pub pressure: Vec<f64>,
    pub theta: Vec<f64>,
    /// Enhanced-mode parameters per element (Q1/P0 enhanced only).
    pub alpha: Vec<[f64; N_ENH]>,
}

impl ElementFields {
    pub fn new(n_elements: usize) -> Self {
        Self {
            states: vec![[MatState::default(); 4]; n_elements],
            sig: vec![[[0.0; 4]; 4]; n_elements],
            pressure: vec![0.0; n_elements],
            theta: vec![1.0; n_elements],
            alpha: vec![[0.0; N_ENH]; n_elements],
        }
    }

    /// The fields of `pressure.len()` elements from their records as a checkpoint stores them
    /// (per element: `states` 4 Gauss points × `cp_inv[4], eps_p, eps_c`, `sig` 4 × 4, `alpha`
    /// [`N_ENH`]).
    pub fn from_records(states: &[f64], sig: &[f64], alpha: &[f64], pressure: Vec<f64>, theta: Vec<f64>) -> Self {
        let ne = pressure.len();
        let mut f = Self::new(ne);
        for el in 0..ne {
            for gp in 0..4 {
                let q = &states[24 * el + 6 * gp..24 * el + 6 * gp + 6];
                f.states[el][gp] = MatState { cp_inv: [q[0], q[1], q[2], q[3]], eps_p: q[4], eps_c: q[5] };
                f.sig[el][gp].copy_from_slice(&sig[16 * el + 4 * gp..16 * el + 4 * gp + 4]);
            }
            f.alpha[el].copy_from_slice(&alpha[N_ENH * el..N_ENH * (el + 1)]);
        }
        f.pressure = pressure;
        f.theta = theta;
        f
    }
}

/// The assembly plan of one model topology and the current pattern of its terms.
pub struct Assembler {
    /// Global dofs of each element.
    pub elem_dofs: Vec<[usize; 8]>,
    /// Position of each element-matrix entry in the element-only pattern (`u32::MAX` if
    /// constrained) ...
    scatter_base: Vec<[u32; 64]>,
    /// ... and in the current pattern.
    scatter: Vec<[u32; 64]>,
    /// Equation map.
    pub eq: Vec<usize>,
    pub n_free: usize,
    /// Element colours: no two elements of one colour share a node.
    pub colors: Vec<Vec<usize>>,
    /// The element-only pattern (row pointers and columns of the free rows).
    base_rows: Vec<usize>,
    base_cols: Vec<usize>,
    /// The entries the current terms add to the element pattern, sorted, and the number of
    /// multiplier rows.
    extra: Vec<(usize, usize)>,
    n_multipliers: usize,
}
/// Greedy colouring of the elements so that elements sharing a node get different colours.
pub fn color_elements(elements: &[[usize; 4]], n_nodes: usize) -> Vec<Vec<usize>> {
    let mut node_colors: Vec<u64> = vec![0; n_nodes]; // bit c set: a colour-c element touches the node
    let mut colors: Vec<Vec<usize>> = Vec::new();
    let mut wide: Vec<Vec<usize>> = vec![Vec::new(); n_nodes]; // colours ≥ 64 (rare)
    for (e, el) in elements.iter().enumerate() {
        let mut used = 0u64;
        for &n in el {
            used |= node_colors[n];
        }
        let c = if used != u64::MAX {
            (!used).trailing_zeros() as usize
        } else {
            (64..).find(|c| el.iter().all(|&n| !wide[n].contains(c))).unwrap_or(64)
        };
        for &n in el {
            if c < 64 {
                node_colors[n] |= 1 << c;
            } else {
                wide[n].push(c);
            }
        }
        if colors.len() <= c {
            colors.resize_with(c + 1, Vec::new);
        }
        colors[c].push(e);
    }
    colors
}

/// Raw shared pointer for the conflict-free parallel scatter of one colour.
#[derive(Clone, Copy)]
struct SharedMut<T>(*mut T);
// SAFETY: only used inside one colour, whose elements touch pairwise disjoint entries.
unsafe impl<T> Send for SharedMut<T> {}
unsafe impl<T> Sync for SharedMut<T> {}

impl Assembler {
    /// The assembly plan of `model` with the equation numbering `eq` (`n_free` free rows), and
    /// the element-only pattern.
    pub fn new(model: &Model, eq: Vec<usize>, n_free: usize) -> (Self, CsrMatrix) {
        let elem_dofs: Vec<[usize; 8]> = model
            .elements
            .iter()
            .map(|el| {
                let mut d = [0; 8];
                for a in 0..4 {
                    d[2 * a] = 2 * el[a];
                    d[2 * a + 1] = 2 * el[a] + 1;
                }
                d
            })
            .collect();
        let mut rows: Vec<Vec<usize>> = vec![Vec::new(); n_free];
        for d in &elem_dofs {
            for &i in d {
                if eq[i] == FIXED {
                    continue;
                }
                for &j in d {
                    if eq[j] != FIXED {
                        rows[eq[i]].push(eq[j]);
                    }
                }
            }
        }
        for r in rows.iter_mut() {
            r.sort_unstable();
            r.dedup();
        }
        let kk = CsrMatrix::from_rows(rows.len(), &rows);
        let scatter_base: Vec<[u32; 64]> = elem_dofs
            .iter()
            .map(|d| {
                let mut s = [u32::MAX; 64];
                for i in 0..8 {
                    for j in 0..8 {
                        if eq[d[i]] != FIXED && eq[d[j]] != FIXED {
                            s[8 * i + j] = kk.find(eq[d[i]], eq[d[j]]).expect("entry in pattern") as u32;
                        }
                    }
                }
                s
            })
            .collect();
        let colors = color_elements(&model.elements, model.n_nodes());
        let assembler = Self {
            elem_dofs,
            scatter: scatter_base.clone(),
            scatter_base,
            eq,
            n_free,
            colors,
            base_rows: kk.row_ptr.clone(),
            base_cols: kk.col_idx.clone(),
            extra: Vec::new(),
            n_multipliers: 0,
        };
        (assembler, kk)
    }

    /// The pattern of the elements plus the terms whose connectivity changes: every block of
    /// `blocks` couples all its dofs (the contact pairs), and Lagrange multiplier k, the
    /// equation `n_free + k`, couples with the dofs `multipliers[k]` both ways and has a
    /// diagonal entry. When these couplings differ from the current ones, `kk` becomes the new
    /// pattern (a new `pattern_id`, values zero, `n_free + multipliers.len()` rows): the
    /// element couplings are merged with the new ones row by row and the element scatter is
    /// remapped, in O(entries), without going back to the mesh. Returns whether the pattern
    /// changed.
    pub fn set_terms(&mut self, kk: &mut CsrMatrix, blocks: &[Vec<usize>], multipliers: &[Vec<usize>]) -> bool {
        let eq = &self.eq;
        // (entries the elements couple already are not kept, so that the same pattern always
        // has the same list; the list is sorted and
        // de-duplicated whenever it has doubled, so that it never holds many more entries than
        // the distinct ones: a block list repeats most entries many times)
        let in_base = |r: usize, c: usize| r < self.n_free && self.base_cols[self.base_rows[r]..self.base_rows[r + 1]].binary_search(&c).is_ok();
        let mut extra: Vec<(usize, usize)> = Vec::new();
        let mut compacted = 0;
        for dofs in blocks {
            for &i in dofs {
                if eq[i] == FIXED {
                    continue;
                }
                for &j in dofs {
                    if eq[j] != FIXED && !in_base(eq[i], eq[j]) {
                        extra.push((eq[i], eq[j]));
                    }
                }
            }
            if extra.len() > 2 * compacted + 4096 {
                extra.sort_unstable();
                extra.dedup();
                compacted = extra.len();
            }
        }
        for (k, dofs) in multipliers.iter().enumerate() {
            let m = self.n_free + k;
            extra.push((m, m));
            for &i in dofs {
                if eq[i] != FIXED {
                    extra.push((eq[i], m));
                    extra.push((m, eq[i]));
                }
            }
        }
        extra.sort_unstable();
        extra.dedup();
        if extra == self.extra && multipliers.len() == self.n_multipliers && kk.nrows == self.n_free + multipliers.len() {
            return false;
        }
        let n_rows = self.n_free + multipliers.len();
        let (mut row_ptr, mut col_idx) = (Vec::with_capacity(n_rows + 1), Vec::with_capacity(self.base_cols.len() + extra.len()));
        let mut base_to_full = vec![0u32; self.base_cols.len()];
        row_ptr.push(0);
        let mut e = 0;
        for r in 0..n_rows {
            let (bs, be) = if r < self.n_free { (self.base_rows[r], self.base_rows[r + 1]) } else { (0, 0) };
            let mut b = bs;
            loop {
                let next_extra = extra.get(e).filter(|x| x.0 == r).map(|x| x.1);
                let next_base = (b < be).then(|| self.base_cols[b]);
                match (next_base, next_extra) {
                    (None, None) => break,
                    (Some(c), x) if x.is_none_or(|x| c < x) => {
                        base_to_full[b] = col_idx.len() as u32;
                        col_idx.push(c);
                        b += 1;
                    }
                    (_, Some(x)) => {
                        col_idx.push(x);
                        e += 1;
                    }
                    (Some(_), None) => unreachable!("covered by the second arm"),
                }
            }
            row_ptr.push(col_idx.len());
        }
        *kk = CsrMatrix::from_parts(n_rows, row_ptr, col_idx);
        for (s, base) in self.scatter.iter_mut().zip(&self.scatter_base) {
            for (p, &q) in s.iter_mut().zip(base) {
                *p = if q == u32::MAX { u32::MAX } else { base_to_full[q as usize] };
            }
        }
        self.extra = extra;
        self.n_multipliers = multipliers.len();
        true
    }

    /// The positions in `kk` of blocks over the global dofs `blocks` (constrained dofs have
    /// none).
    pub fn block_map(&self, kk: &CsrMatrix, blocks: &[Vec<usize>]) -> BlockMap {
        let rows: Vec<Vec<usize>> = blocks.iter().map(|b| b.iter().map(|&d| self.eq[d]).collect()).collect();
        BlockMap::locate(kk, rows.iter().map(Vec::as_slice))
    }

    /// The positions in `kk` of the multiplier blocks: block k over the dofs `multipliers[k]`
    /// and, last, the multiplier's own equation `n_free + k`.
    pub fn multiplier_map(&self, kk: &CsrMatrix, multipliers: &[Vec<usize>]) -> BlockMap {
        let rows: Vec<Vec<usize>> = multipliers.iter().enumerate().map(|(k, b)| b.iter().map(|&d| self.eq[d]).chain([self.n_free + k]).collect()).collect();
        BlockMap::locate(kk, rows.iter().map(Vec::as_slice))
    }

    /// The position in `kk` of the diagonal entry of every dof (a 1 × 1 block per dof; none for
    /// a constrained one).
    pub fn diagonal_map(&self, kk: &CsrMatrix) -> BlockMap {
        let rows: Vec<[usize; 1]> = self.eq.iter().map(|&q| [q]).collect();
        BlockMap::locate(kk, rows.iter().map(|r| r.as_slice()))
    }

    /// Evaluate only the elements `e` with `keep[e]` from now on (a process of a distributed
    /// run assembles the elements it owns; the others leave their entries of the force, the
    /// tangent and the element fields alone). Kept elements keep their colour order.
    pub fn retain_elements(&mut self, keep: &[bool]) {
        for color in &mut self.colors {
            color.retain(|&e| keep.get(e).copied().unwrap_or(false));
        }
        self.colors.retain(|c| !c.is_empty());
    }

    /// Assemble the internal force `f_int` (all dofs, N/mm) and, if `kk` is given, the tangent
    /// on the free dofs, for nodal displacements `u` (dof `2 n + c`), committed states `old`,
    /// enhanced modes `alpha0`, the element volumetric data `vol` and the initial volume ratio
    /// j₀ of every element (`j0[e]`, see the module docs of [`crate::element`]; `None`: the
    /// reference configuration of every element is the original one, j₀ = 1). Gauss-point
    /// results go to `fields`.
    ///
    /// # Errors
    /// The first element (in the assembly order) whose kernel fails; an element without an
    /// entry in `j0`, or with a j₀ that is not positive and finite, fails with
    /// [`MaterialError::InvalidVolumeRatio`].
    #[allow(clippy::too_many_arguments)]
    pub fn assemble(
        &mut self,
        model: &Model,
        u: &[f64],
        old: &[[MatState; 4]],
        alpha0: &[[f64; N_ENH]],
        vol: &[Volumetric],
        j0: Option<&[f64]>,
        inc: TimeIncrement,
        mut kk: Option<&mut CsrMatrix>,
        f_int: &mut [f64],
        fields: &mut ElementFields,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<(), AssemblyError> {
        // (on the pool's threads when there is one: the tangent's values are tens of MB, and
        // zeroing them on one thread was the serial part that held 2 threads below 1.85×)
        match (pool, kk.as_deref_mut()) {
            (Some(p), Some(k)) => p.install(|| {
                k.values.par_chunks_mut(1 << 14).for_each(|c| c.fill(0.0));
                f_int.par_chunks_mut(1 << 14).for_each(|c| c.fill(0.0));
            }),
            (None, Some(k)) => {
                k.fill_zero();
                f_int.fill(0.0);
            }
            (_, None) => f_int.fill(0.0),
        }
        let tangent = kk.is_some();
        let f_ptr = SharedMut(f_int.as_mut_ptr());
        let k_ptr = SharedMut(kk.map_or(std::ptr::null_mut(), |k| k.values.as_mut_ptr()));
        let states = SharedMut(fields.states.as_mut_ptr());
        let sig = SharedMut(fields.sig.as_mut_ptr());
        let pressure = SharedMut(fields.pressure.as_mut_ptr());
        let theta = SharedMut(fields.theta.as_mut_ptr());
        let alpha = SharedMut(fields.alpha.as_mut_ptr());
        let elem_dofs = &self.elem_dofs;
        let scatter = &self.scatter;
        let work = |&e: &usize| -> Result<(), AssemblyError> {
            let (f_ptr, k_ptr, states, sig, pressure, theta, alpha) = (f_ptr, k_ptr, states, sig, pressure, theta, alpha);
            let mut out = ElementOut::default();
            let el = &model.elements[e];
            let xx0 = el.map(|n| model.x0[n]);
            let ue = el.map(|n| [u[2 * n], u[2 * n + 1]]);
            let material = &model.materials[model.elem_material[e]];
            let ps;
            let law: &dyn crate::material::ConstitutiveLaw = if model.plane_stress {
                ps = crate::material::plane_stress::PlaneStress { law: material };
                &ps
            } else {
                material
            };
            // a missing entry is reported as an invalid (NaN) ratio of this element
            let j0e = j0.map_or(Some(1.0), |v| v.get(e).copied()).unwrap_or(f64::NAN);
            match model.element {
                ElementKind::Q1P0 => element::evaluate(model.formulation, element::ElementInput { law, xx0: &xx0, uu: &ue, old: &old[e], inc, vol: vol[e], j0: j0e, tangent }, &mut out),
                ElementKind::Q1P0Enhanced => {
                    let mut a = alpha0[e];
                    let r = element::evaluate_enhanced(element::ElementInput { law, xx0: &xx0, uu: &ue, old: &old[e], inc, vol: vol[e], j0: j0e, tangent }, &mut a, &mut out);
                    out.alpha = a;
                    r
                }
            }
            .map_err(|source| AssemblyError { element: e, source })?;
            // SAFETY: the elements of one colour share no node, hence no dof, no matrix entry
            // and no element slot; colours are processed one after the other.
            unsafe {
                let dofs = &elem_dofs[e];
                for a in 0..8 {
                    *f_ptr.0.add(dofs[a]) += out.f_int[a];
                }
                if tangent {
                    let s = &scatter[e];
                    for a in 0..8 {
                        for b in 0..8 {
                            let pos = s[8 * a + b];
                            if pos != u32::MAX {
                                *k_ptr.0.add(pos as usize) += out.kk[a][b];
                            }
                        }
                    }
                }
                let g = &out.gauss;
                *states.0.add(e) = [g[0].state, g[1].state, g[2].state, g[3].state];
                *sig.0.add(e) = [g[0].sig, g[1].sig, g[2].sig, g[3].sig];
                *pressure.0.add(e) = out.pressure;
                *theta.0.add(e) = out.theta;
                *alpha.0.add(e) = out.alpha;
            }
            Ok(())
        };
        for color in &self.colors {
            match pool {
                Some(p) => p.install(|| color.par_iter().with_min_len(64).try_for_each(work))?,
                None => color.iter().try_for_each(work)?,
            }
        }
        Ok(())
    }
}
