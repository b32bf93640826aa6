//! Degree-of-freedom numbering, the sparsity pattern (built once per topology) and the
//! parallel assembly of internal forces and tangent stiffness.
//!
//! Elements are evaluated in parallel (rayon, on a pool the caller passes in, or sequentially)
//! in fixed-size chunks, then scattered into the global matrix in element order. The order of
//! every floating-point sum is therefore independent of the thread count: 1 and N threads give
//! bit-identical results.

use crate::element::{self, ElementKind, ElementOut, Volumetric, N_ENH};
use crate::linalg::CsrMatrix;
use crate::material::{MatState, MaterialError, TimeIncrement};
use crate::model::Model;
use rayon::prelude::*;
use thiserror::Error;

/// Marker for a constrained degree of freedom in the equation map.
pub const FIXED: usize = usize::MAX;

/// Elements evaluated in parallel before each sequential scatter.
const CHUNK: usize = 2048;

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
    /// Element pressure (MPa) and area ratio Θ.
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
}

/// Assembly plan for one model topology.
pub struct Assembler {
    /// Global dofs of each element.
    pub elem_dofs: Vec<[usize; 8]>,
    /// Position of each element-matrix entry in the CSR values (`u32::MAX` if constrained).
    scatter: Vec<[u32; 64]>,
    /// Equation map.
    pub eq: Vec<usize>,
    pub n_free: usize,
    scratch: Vec<ElementOut>,
}

impl Assembler {
    /// Build the equation numbering and the free–free sparsity pattern.
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
        let kk = CsrMatrix::from_rows(n_free, &rows);
        let scatter = elem_dofs
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
        let scratch = vec![ElementOut::default(); CHUNK.min(model.elements.len().max(1))];
        (Self { elem_dofs, scatter, eq, n_free, scratch }, kk)
    }

    /// Assemble the internal force `f_int` (all dofs, N/mm) and, if `kk` is given, the tangent
    /// on the free dofs, for nodal displacements `u` (dof `2 n + c`), committed states `old` and the element
    /// volumetric data `vol`. Gauss-point results go to `fields`.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble(
        &mut self,
        model: &Model,
        u: &[f64],
        old: &[[MatState; 4]],
        alpha0: &[[f64; N_ENH]],
        vol: &[Volumetric],
        inc: TimeIncrement,
        mut kk: Option<&mut CsrMatrix>,
        f_int: &mut [f64],
        fields: &mut ElementFields,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<(), AssemblyError> {
        f_int.iter_mut().for_each(|v| *v = 0.0);
        if let Some(k) = kk.as_deref_mut() {
            k.fill_zero();
        }
        let tangent = kk.is_some();
        let ne = model.elements.len();
        let mut start = 0;
        while start < ne {
            let end = (start + CHUNK).min(ne);
            let len = end - start;
            let work = |(i, out): (usize, &mut ElementOut)| -> Result<(), AssemblyError> {
                let e = start + i;
                let el = &model.elements[e];
                let xx0 = el.map(|n| model.x0[n]);
                let ue = el.map(|n| [u[2 * n], u[2 * n + 1]]);
                let law = &model.materials[model.elem_material[e]];
                match model.element {
                    ElementKind::Q1P0 => element::evaluate(model.formulation, law, &xx0, &ue, &old[e], inc, vol[e], tangent, out),
                    ElementKind::Q1P0Enhanced => {
                        let mut a = alpha0[e];
                        let r = element::evaluate_enhanced(law, &xx0, &ue, &old[e], inc, vol[e], tangent, &mut a, out);
                        out.alpha = a;
                        r
                    }
                }
                .map_err(|source| AssemblyError { element: e, source })
            };
            let scratch = &mut self.scratch[..len];
            match pool {
                Some(p) => p.install(|| scratch.par_iter_mut().enumerate().try_for_each(work))?,
                None => scratch.iter_mut().enumerate().try_for_each(work)?,
            }
            // sequential scatter in element order (deterministic sums)
            for (i, out) in scratch.iter().enumerate() {
                let e = start + i;
                let dofs = &self.elem_dofs[e];
                for a in 0..8 {
                    f_int[dofs[a]] += out.f_int[a];
                }
                if let Some(k) = kk.as_deref_mut() {
                    let s = &self.scatter[e];
                    for a in 0..8 {
                        for b in 0..8 {
                            let pos = s[8 * a + b];
                            if pos != u32::MAX {
                                k.values[pos as usize] += out.kk[a][b];
                            }
                        }
                    }
                }
                fields.states[e] = [out.gauss[0].state, out.gauss[1].state, out.gauss[2].state, out.gauss[3].state];
                fields.sig[e] = [out.gauss[0].sig, out.gauss[1].sig, out.gauss[2].sig, out.gauss[3].sig];
                fields.pressure[e] = out.pressure;
                fields.theta[e] = out.theta;
                fields.alpha[e] = out.alpha;
            }
            start = end;
        }
        Ok(())
    }
}
