//! PETSc as the distributed linear solver engine (`[solver] linear = "petsc"`, feature
//! `petsc`): every process takes part in each solve; the options database tunes it as every
//! PETSc program is tuned (`[solver] petsc_options`, or `PETSC_OPTIONS`).
//!
//! The tangent comes to this solver in one of two ways ([`Rows`]). Whole on every process (the
//! replicated model of the distributed runs, [`crate::parallel`]): each process hands PETSc
//! only its own rows: the
//! global PETSc numbering puts the rows of each process's particles in one contiguous range,
//! in rank order (the particles' owners after the METIS partition; the multiplier rows on rank
//! 0), and the matrix is a distributed AIJ made once per sparsity pattern from those rows and
//! refilled in place for every new tangent. The update is gathered whole onto every process.
//! Or as a process's part ([`PartRows`]): the rows of its own equations and of its ghosts',
//! numbered locally (its own first); the ghost rows — the contact terms its pairs add to
//! other processes' equations — go to their owners, who add them to their own rows in rank
//! order (the pattern once per sparsity pattern, the values at every factorisation), and the
//! update comes back on the process's own equations and, through the forward scatter, its
//! ghosts'.
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
//! multigrid. `-pc_type mg` (without `-pc_mg_levels`) is the particles' two-level
//! preconditioner (`CoarseSpace`: each particle's rigid-body modes and uniform strains
//! the coarse space, its block the smoother's), the one that converges on loose particles; an
//! iterative solve that breaks down on an indefinite matrix answers `definite() == Some(false)`
//! and [`LinearSolver::solve_indefinite`] solves it again by GMRES. A direct solve whose residual ‖b − A x‖/‖b‖ stays above the solver's singular
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
    /// The particle of each row (any numbering that tells particles apart; [`NO_PARTICLE`] for
    /// a multiplier row): the coarse space of the two-level preconditioner (`-pc_type mg`).
    pub particle: Vec<usize>,
}

/// [`RowLayout::particle`] and [`PartRows::particle`] of a row that belongs to no particle.
pub const NO_PARTICLE: usize = usize::MAX;

/// A process's part of the system ([`Rows::Part`]): the map of its equations (its own first,
/// then its ghosts') and where each equation's dof is.
#[derive(Clone)]
pub struct PartRows {
    pub map: std::sync::Arc<crate::comm::IndexMap>,
    /// The reference position and the direction (0: x, 1: y) of each local equation's dof.
    pub dof: Vec<Option<([f64; 2], usize)>>,
    /// The particle of each local equation ([`RowLayout::particle`]).
    pub particle: Vec<usize>,
}

/// How the rows of the systems reach the solver (see the module docs).
#[derive(Clone)]
pub enum Rows {
    /// The whole matrix on every process; these rows are each process's own.
    Whole(RowLayout),
    /// Each process's part: its own rows and its ghosts', in local numbers.
    Part(PartRows),
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
    make_rows(layout.map(Rows::Whole), symmetric, rtol, max_iterations, singular_tol, rank, size)
}

/// [`make`] for rows given either way ([`Rows`]; None: the whole matrix, every row on rank 0).
/// With [`Rows::Part`] the matrix, right-hand side and update of every call are the process's
/// part (local equations, its own first): the right-hand side's own entries must be complete
/// (its ghosts' are not read), and the update comes back on every local equation.
pub fn make_rows(rows: Option<Rows>, symmetric: bool, rtol: f64, max_iterations: usize, singular_tol: f64, rank: usize, size: usize) -> Box<dyn LinearSolver> {
    #[cfg(feature = "petsc")]
    {
        Box::new(imp::PetscSolver::new(rows, symmetric, rtol, max_iterations, singular_tol, rank, size))
    }
    #[cfg(not(feature = "petsc"))]
    {
        let _ = (rows, symmetric, rtol, max_iterations, singular_tol, rank, size);
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

    /// Where the values of the rows handed to PETSc come from.
    enum Sources {
        /// The whole matrix: PETSc's number of every row, this process's rows (mpfem numbers)
        /// in PETSc's order, and for every entry of the local CSR handed to PETSc its position
        /// in the tangent's values.
        Whole { global: Vec<usize>, local_rows: Vec<usize>, source: Vec<usize> },
        /// A part: the position in the part's values of each entry of its own rows (every one
        /// has its own position: an own row's columns are distinct); per
        /// process, the positions of the values of the ghost rows it owns, in the order they are
        /// sent, and the entries the values received from it go to.
        Part { map: std::sync::Arc<crate::comm::IndexMap>, own: Vec<usize>, send: Vec<Vec<usize>>, recv: Vec<Vec<usize>>, row_ptr: Vec<usize> },
    }

    /// A row's dof (reference position and direction; None: a multiplier) and its particle.
    type RowDof = (Option<([f64; 2], usize)>, usize);

    /// The PETSc objects of one sparsity pattern.
    struct Pattern {
        pattern_id: u64,
        sources: Sources,
        values: Vec<f64>,
        a: Matrix,
        ksp: Ksp,
        b: Vector,
        x: Vector,
        ax: Vector,
        /// The update gathered whole (the whole matrix's rows only).
        gather: Option<GatherAll>,
        direct: bool,
        name: String,
        inertia_warned: bool,
    }

    pub(super) struct PetscSolver {
        rows: Option<Rows>,
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
        pub(super) fn new(rows: Option<Rows>, symmetric: bool, rtol: f64, max_iterations: usize, singular_tol: f64, rank: usize, size: usize) -> Self {
            Self { rows, symmetric, rtol, max_iterations, singular_tol, rank, size, pattern: None, definite: None }
        }

        fn build(&self, a: &CsrMatrix) -> Result<Pattern, LinalgError> {
            petsc::ensure_initialized().map_err(err)?;
            let (r, s) = petsc::Petsc::rank_size().map_err(err)?;
            if (r, s) != (self.rank, self.size) {
                return Err(LinalgError::Other(format!("PETSc runs on {s} process(es) (this is its rank {r}) but the run on {} (rank {})", self.size, self.rank)));
            }
            let (mut m, sources, dofs) = match &self.rows {
                Some(Rows::Part(part)) => self.part_rows(a, part)?,
                whole => self.whole_rows(a, match whole {
                    Some(Rows::Whole(l)) => Some(l),
                    _ => None,
                })?,
            };
            if self.symmetric {
                m.set_symmetric().map_err(err)?;
            }
            // the rigid-body modes of the plane, for algebraic multigrid
            let mut modes = Vec::with_capacity(3);
            for mode in 0..3 {
                let v: Vec<f64> = dofs
                    .iter()
                    .map(|(d, _)| d.map_or(0.0, |(p, c)| affine_mode(mode, p, c)))
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
            let krylov = if self.symmetric { "cg" } else { "gmres" };
            // `-pc_type mg` without levels of the user's: the particles' two-level preconditioner
            let two_level = petsc::option_value("-pc_type").map_err(err)?.as_deref() == Some("mg") && !petsc::has_option("-pc_mg_levels").map_err(err)?;
            if two_level {
                ksp.set_defaults(krylov, "mg", None, self.rtol, self.max_iterations).map_err(err)?;
                let space = CoarseSpace::of_rows(&dofs);
                let counter = petsc::Vector::new(space.n_coarse).map_err(err)?;
                let (start, _) = counter.ownership_range().map_err(err)?;
                let n_coarse = counter.global_len().map_err(err)?;
                let cols: Vec<usize> = space.cols.iter().map(|c| c + start).collect();
                let rows = Vector::like_rows(&m).map_err(err)?.global_len().map_err(err)?;
                let p = Matrix::from_local_csr_columns(rows, space.n_coarse, n_coarse, &space.row_ptr, &cols, &space.values).map_err(err)?;
                // each particle's block solved exactly by the smoother (its zero pivots, a loose
                // particle's rigid-body modes, shifted: those are the coarse space's), and the
                // coarse operator's null pivots (a particle that nothing holds yet) detected
                // and left out, with room for the delayed pivots an indefinite coarse
                // operator brings (MUMPS ran out of its estimated workspace, INFOG(1) = −9, on
                // 256 discs), unless the options say otherwise
                for o in ["-mg_levels_sub_pc_type lu", "-mg_levels_sub_pc_factor_shift_type nonzero", "-mg_coarse_mat_mumps_icntl_24 1", "-mg_coarse_mat_mumps_icntl_14 200"] {
                    if !petsc::has_option(o.split(' ').next().unwrap_or(o)).map_err(err)? {
                        petsc::insert_options(o).map_err(err)?;
                    }
                }
                ksp.set_two_level(&p, &space.blocks, self.symmetric).map_err(err)?;
            } else {
                // room for the delayed pivots of an indefinite tangent (a saddle, the descent's
                // probe) unless the options say otherwise: with MUMPS's own margin of its
                // estimated workspace its factorisation ran out of it (INFOG(1) = −9, PETSc's
                // PC_FACTOR_OUTMEMORY) on 4 ranks of tests/mpi_parts_run.rs's 3 × 3 discs in one
                // run of the CI, at every step size down to `dt_min`; the margin changes no result
                if !petsc::has_option("-mat_mumps_icntl_14").map_err(err)? {
                    petsc::insert_options("-mat_mumps_icntl_14 100").map_err(err)?;
                }
                ksp.set_defaults("preonly", pc, Some("mumps"), self.rtol, self.max_iterations).map_err(err)?;
            }
            ksp.set_operator(&m).map_err(err)?;
            ksp.set_from_options().map_err(err)?;
            let (mut k, mut p, mut package) = ksp.types().map_err(err)?;
            if k == "preonly" && p != "lu" && p != "cholesky" && !petsc::has_option("-ksp_type").map_err(err)? {
                // an iterative preconditioner (`-pc_type gamg`) alone: its Krylov method, CG for
                // a symmetric tangent, GMRES otherwise (one application is not a solve)
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
            let gather = if matches!(sources, Sources::Whole { .. }) { Some(GatherAll::new(&x).map_err(err)?) } else { None };
            let values = vec![0.0; sources_len(&sources)];
            Ok(Pattern { pattern_id: a.pattern_id, sources, values, a: m, ksp, b, x, ax, gather, direct, name, inertia_warned: false })
        }

        /// The matrix of this process's rows of the whole matrix `a`, the sources of its values,
        /// and its rows' dofs.
        fn whole_rows(&self, a: &CsrMatrix, layout: Option<&RowLayout>) -> Result<(Matrix, Sources, Vec<RowDof>), LinalgError> {
            let n = a.nrows;
            let whole = RowLayout { owner: vec![0; n], dof: vec![None; n], particle: vec![NO_PARTICLE; n] };
            let layout = layout.unwrap_or(&whole);
            if layout.owner.len() != n || layout.dof.len() != n || layout.particle.len() != n {
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
            let m = Matrix::from_local_csr(n, &row_ptr, &cols, &values).map_err(err)?;
            let dofs = local_rows.iter().map(|&i| (layout.dof[i], layout.particle[i])).collect();
            Ok((m, Sources::Whole { global, local_rows, source }, dofs))
        }

        /// The matrix of this process's own rows of a part `a` (local equations, its own first,
        /// then its ghosts'): its own rows and the ghost rows the other processes send it, merged
        /// (the pattern goes to the owners here, once per pattern).
        fn part_rows(&self, a: &CsrMatrix, part: &PartRows) -> Result<(Matrix, Sources, Vec<RowDof>), LinalgError> {
            let map = &part.map;
            let (n_own, n_local) = (map.n_owned(), map.n_local());
            if a.nrows != n_local || part.dof.len() != n_local || part.particle.len() != n_local {
                return Err(LinalgError::Other(format!("the part has {n_local} equations and {} dofs, the matrix {} rows", part.dof.len(), a.nrows)));
            }
            let start = map.start();
            // the ghost rows' patterns to their owners: [row, count, columns…] per row, global
            let mut out = vec![Vec::new(); self.size];
            let mut send = vec![Vec::new(); self.size];
            for i in n_own..n_local {
                let o = map.ghost_owners()[i - n_own];
                let (lo, hi) = (a.row_ptr[i], a.row_ptr[i + 1]);
                out[o].push(map.global(i) as f64);
                out[o].push((hi - lo) as f64);
                for k in lo..hi {
                    out[o].push(map.global(a.col_idx[k]) as f64);
                    send[o].push(k);
                }
            }
            let got = map.comm().exchange(&out);
            drop(out);
            // the entries the other processes send for this process's rows, grouped by row:
            // (column, source), the source numbering a's own entries first (k) and then the
            // received ones, process by process in the order sent — so that sorting a row's
            // entries by (column, source) puts the sources of an entry in the order its value
            // is summed in (the own one first). Counted first, so that nothing grows.
            let n_a = a.row_ptr[n_own];
            let mut recv_ptr = vec![0usize; n_own + 1];
            let mut offset = Vec::with_capacity(got.len() + 1);
            offset.push(n_a);
            for (q, buf) in got.iter().enumerate() {
                let (mut at, mut n) = (0, 0);
                while at + 1 < buf.len() {
                    let (row, count) = (buf[at] as usize, buf[at + 1] as usize);
                    if !(start..start + n_own).contains(&row) || at + 2 + count > buf.len() {
                        return Err(LinalgError::Other(format!("process {q} sent row {row}, which is not one of this process's {start}..{}", start + n_own)));
                    }
                    recv_ptr[row - start + 1] += count;
                    n += count;
                    at += 2 + count;
                }
                if at != buf.len() {
                    return Err(LinalgError::Other(format!("process {q} sent a cut row pattern")));
                }
                offset.push(offset[q] + n);
            }
            for r in 0..n_own {
                recv_ptr[r + 1] += recv_ptr[r];
            }
            let mut recv_items = vec![(0usize, 0usize); recv_ptr[n_own]];
            let mut fill = recv_ptr.clone();
            for (q, buf) in got.iter().enumerate() {
                let (mut at, mut index) = (0, 0);
                while at < buf.len() {
                    let (row, count) = (buf[at] as usize - start, buf[at + 1] as usize);
                    for c in &buf[at + 2..at + 2 + count] {
                        recv_items[fill[row]] = (*c as usize, offset[q] + index);
                        fill[row] += 1;
                        index += 1;
                    }
                    at += 2 + count;
                }
            }
            drop(fill);
            let mut row_ptr = vec![0usize; n_own + 1];
            let mut cols = Vec::with_capacity(n_a + recv_items.len());
            let mut own = vec![usize::MAX; n_a];
            let mut recv: Vec<Vec<usize>> = got.iter().map(|_| Vec::new()).collect();
            let mut received: Vec<Vec<(usize, usize)>> = got.iter().map(|b| Vec::with_capacity(b.len())).collect();
            drop(got);
            // row by row: its own entries (global columns) and the received ones, sorted
            let mut row_entries: Vec<(usize, usize)> = Vec::new();
            for i in 0..n_own {
                row_entries.clear();
                row_entries.extend((a.row_ptr[i]..a.row_ptr[i + 1]).map(|k| (map.global(a.col_idx[k]), k)));
                row_entries.extend_from_slice(&recv_items[recv_ptr[i]..recv_ptr[i + 1]]);
                row_entries.sort_unstable();
                let mut last = None;
                for &(col, from) in &row_entries {
                    // (the same entry again is one more source of its value)
                    if last != Some(col) {
                        cols.push(col);
                        row_ptr[i + 1] += 1;
                        last = Some(col);
                    }
                    let e = cols.len() - 1;
                    if from < n_a {
                        own[from] = e;
                    } else {
                        let q = offset.partition_point(|&o| o <= from) - 1;
                        received[q].push((from - offset[q], e));
                    }
                }
            }
            drop(recv_items);
            for r in 0..n_own {
                row_ptr[r + 1] += row_ptr[r];
            }
            for (q, list) in received.iter_mut().enumerate() {
                list.sort_unstable();
                recv[q] = list.iter().map(|&(_, e)| e).collect();
            }
            let mut values = vec![0.0; cols.len()];
            for (&e, &v) in own.iter().zip(&a.values) {
                values[e] += v;
            }
            let m = Matrix::from_local_csr(map.n_global(), &row_ptr, &cols, &values).map_err(err)?;
            let dofs = part.dof[..n_own].iter().copied().zip(part.particle[..n_own].iter().copied()).collect();
            Ok((m, Sources::Part { map: map.clone(), own, send, recv, row_ptr }, dofs))
        }
    }

    /// The value at position `p` in direction `comp` (0: x, 1: y) of the affine displacement
    /// field `mode`: 0, 1 the translations, 2 the rotation about the origin, 3, 4 the normal
    /// strains along x and y, 5 the shear strain. The first three are the rigid-body modes.
    fn affine_mode(mode: usize, p: [f64; 2], comp: usize) -> f64 {
        match (mode, comp) {
            (0, 0) | (1, 1) => 1.0,
            (2, 0) => -p[1],
            (3, 0) | (2, 1) | (5, 1) => p[0],
            (4, 1) | (5, 0) => p[1],
            _ => 0.0,
        }
    }

    /// The coarse space of the two-level preconditioner on this process's rows: each
    /// particle's rigid-body modes (two translations, a rotation about its centre) and uniform
    /// strains (three), orthonormalised on the particle's rows (modes that vanish there, a
    /// particle with fewer free dofs, are dropped). The particles are a process's own, whole,
    /// so the prolongation has no entries off the process.
    pub(super) struct CoarseSpace {
        /// The prolongation's rows (this process's rows) in CSR, columns local to the process.
        pub row_ptr: Vec<usize>,
        pub cols: Vec<usize>,
        pub values: Vec<f64>,
        /// This process's coarse unknowns.
        pub n_coarse: usize,
        /// The smoother's blocks: the lengths of the runs of rows of one particle (a
        /// multiplier row is a run of its own) when every particle's rows are one run; one
        /// block of all the process's rows otherwise.
        pub blocks: Vec<usize>,
    }

    impl CoarseSpace {
        pub(super) fn of_rows(rows: &[RowDof]) -> Self {
            let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
            let mut index = std::collections::HashMap::new();
            for (i, (dof, particle)) in rows.iter().enumerate() {
                if dof.is_some() && *particle != NO_PARTICLE {
                    let g = *index.entry(*particle).or_insert_with(|| {
                        groups.push((*particle, Vec::new()));
                        groups.len() - 1
                    });
                    groups[g].1.push(i);
                }
            }
            // per row: (column, value)
            let mut entries: Vec<Vec<(usize, f64)>> = vec![Vec::new(); rows.len()];
            let mut n_coarse = 0;
            for (_, members) in &groups {
                let pos = |i: usize| rows[i].0.map_or([0.0; 2], |d| d.0);
                let n = members.len() as f64;
                let c = members.iter().fold([0.0; 2], |s, &i| [s[0] + pos(i)[0] / n, s[1] + pos(i)[1] / n]);
                let size = members.iter().map(|&i| (pos(i)[0] - c[0]).hypot(pos(i)[1] - c[1])).fold(0.0, f64::max);
                let size = if size > 0.0 { size } else { 1.0 };
                let mut kept: Vec<Vec<f64>> = Vec::new();
                for mode in 0..6 {
                    let mut v: Vec<f64> = members
                        .iter()
                        .map(|&i| {
                            let (p, comp) = rows[i].0.unwrap_or(([0.0; 2], 0));
                            affine_mode(mode, [(p[0] - c[0]) / size, (p[1] - c[1]) / size], comp)
                        })
                        .collect();
                    let before = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                    for q in &kept {
                        let d: f64 = v.iter().zip(q).map(|(a, b)| a * b).sum();
                        v.iter_mut().zip(q).for_each(|(a, b)| *a -= d * b);
                    }
                    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                    if before > 0.0 && norm > 1e-8 * before {
                        v.iter_mut().for_each(|a| *a /= norm);
                        kept.push(v);
                    }
                }
                for (j, q) in kept.iter().enumerate() {
                    for (&i, &value) in members.iter().zip(q) {
                        if value != 0.0 {
                            entries[i].push((n_coarse + j, value));
                        }
                    }
                }
                n_coarse += kept.len();
            }
            let mut row_ptr = vec![0];
            let (mut cols, mut values) = (Vec::new(), Vec::new());
            for e in &entries {
                cols.extend(e.iter().map(|x| x.0));
                values.extend(e.iter().map(|x| x.1));
                row_ptr.push(cols.len());
            }
            // the runs of rows of one particle
            let mut runs: Vec<(usize, usize)> = Vec::new();
            for (_, particle) in rows {
                match runs.last_mut() {
                    Some((p, len)) if *p == *particle && *particle != NO_PARTICLE => *len += 1,
                    _ => runs.push((*particle, 1)),
                }
            }
            let mut seen = std::collections::HashSet::new();
            let one_run_each = runs.iter().all(|(p, _)| *p == NO_PARTICLE || seen.insert(*p));
            // (otherwise one block of all its rows, an empty one on a process without rows:
            // every process sets its blocks, or block Jacobi's set-up waits for them)
            let blocks = if one_run_each && !runs.is_empty() { runs.iter().map(|r| r.1).collect() } else { vec![rows.len()] };
            Self { row_ptr, cols, values, n_coarse, blocks }
        }
    }

    /// PETSc's name of a KSP's reason to stop that is a failure.
    fn reason_name(reason: i32) -> String {
        match reason {
            -2 => "KSP_DIVERGED_NULL".into(),
            -3 => "KSP_DIVERGED_ITS (the iteration limit)".into(),
            -4 => "KSP_DIVERGED_DTOL (the residual grew)".into(),
            -5 => "KSP_DIVERGED_BREAKDOWN".into(),
            -7 => "KSP_DIVERGED_NONSYMMETRIC".into(),
            -8 => "KSP_DIVERGED_INDEFINITE_PC (an indefinite preconditioner)".into(),
            -9 => "KSP_DIVERGED_NANORINF (NaN or infinity)".into(),
            -10 => "KSP_DIVERGED_INDEFINITE_MAT (an indefinite matrix)".into(),
            -11 => "KSP_DIVERGED_PC_FAILED (the preconditioner's set-up failed)".into(),
            r => format!("KSP reason {r}"),
        }
    }

    fn sources_len(s: &Sources) -> usize {
        match s {
            Sources::Whole { source, .. } => source.len(),
            Sources::Part { own, recv, .. } => own.iter().chain(recv.iter().flatten()).map(|e| e + 1).max().unwrap_or(0),
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
            if p.pattern_id != a.pattern_id {
                return Err(LinalgError::NotAnalyzed);
            }
            match &p.sources {
                Sources::Whole { source, .. } => {
                    if source.last().is_some_and(|&k| k >= a.values.len()) {
                        return Err(LinalgError::NotAnalyzed);
                    }
                    for (v, &k) in p.values.iter_mut().zip(source) {
                        *v = a.values[k];
                    }
                }
                Sources::Part { map, own, send, recv, .. } => {
                    // the ghost rows' values to their owners; the own rows' values, then what
                    // every process sent, in rank order
                    let out: Vec<Vec<f64>> = send.iter().map(|ks| ks.iter().map(|&k| a.values[k]).collect()).collect();
                    let got = map.comm().exchange(&out);
                    p.values.iter_mut().for_each(|v| *v = 0.0);
                    if own.len() > a.values.len() {
                        return Err(LinalgError::NotAnalyzed);
                    }
                    for (&e, &v) in own.iter().zip(&a.values) {
                        p.values[e] += v;
                    }
                    for (es, vals) in recv.iter().zip(&got) {
                        for (&e, &v) in es.iter().zip(vals) {
                            p.values[e] += v;
                        }
                    }
                }
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
            let local: Vec<f64> = match &p.sources {
                Sources::Whole { local_rows, .. } => local_rows.iter().map(|&i| b[i]).collect(),
                Sources::Part { map, .. } => b[..map.n_owned()].to_vec(),
            };
            p.b.set_local(&local).map_err(err)?;
            let info = p.ksp.solve(&p.b, &mut p.x).map_err(err)?;
            // ‖b − A x‖ / ‖b‖ over every process
            p.a.mult(&p.x, &mut p.ax).map_err(err)?;
            p.ax.axpy(-1.0, &p.b).map_err(err)?;
            let (res, bn) = (p.ax.norm2().map_err(err)?, p.b.norm2().map_err(err)?);
            let rel = if bn > 0.0 { res / bn } else { res };
            // (a breakdown once the true residual is below the tolerance is round-off in the
            // last iteration's curvature: the update is the converged one)
            let converged_anyway = !p.direct && rel.is_finite() && rel <= self.rtol;
            if (info.reason < 0 && !converged_anyway) || !rel.is_finite() {
                // CG's breakdown on a negative curvature of the matrix or of the preconditioner
                // (KSP_DIVERGED_INDEFINITE_PC, _MAT), or its residual growing 10⁵ times or a
                // zero curvature (_DTOL, _BREAKDOWN, what a preconditioner made from an
                // indefinite matrix also does): how an iterative solve tells that the matrix is
                // not positive definite
                let indefinite = !p.direct && [-4, -5, -8, -10].contains(&info.reason);
                let e = if p.direct {
                    LinalgError::Singular(format!("{}: KSP diverged (reason {}), relative residual {rel:.3e}", p.name, info.reason))
                } else if info.reason == -3 {
                    LinalgError::NotConverged { iterations: info.iterations, residual: rel, tol: self.rtol }
                } else {
                    LinalgError::Other(format!("{}: the iterative solver did not converge: {} after {} iterations, relative residual {rel:.3e} (tolerance {:.1e})", p.name, reason_name(info.reason), info.iterations, self.rtol))
                };
                if indefinite {
                    self.definite = Some(false);
                }
                return Err(e);
            }
            if p.direct && rel > self.singular_tol {
                return Err(LinalgError::Singular(format!("{}: relative residual {rel:.3e} after the direct solve", p.name)));
            }
            match &p.sources {
                Sources::Whole { global, .. } => {
                    let all = p.gather.as_mut().ok_or(LinalgError::NotAnalyzed)?.gather(&p.x).map_err(err)?;
                    for (xi, &g) in x.iter_mut().zip(global) {
                        *xi = all[g];
                    }
                }
                Sources::Part { map, .. } => {
                    let own = p.x.local().map_err(err)?;
                    x[..own.len()].copy_from_slice(&own);
                    map.forward(x, 1);
                }
            }
            Ok(SolveStats { iterations: info.iterations.max(1), relative_residual: rel })
        }

        fn solve_indefinite(&mut self, a: &CsrMatrix, b: &[f64], x: &mut [f64]) -> Result<SolveStats, LinalgError> {
            let p = self.pattern.as_mut().ok_or(LinalgError::NotAnalyzed)?;
            let (k, _, _) = p.ksp.types().map_err(err)?;
            if p.direct || k != "cg" {
                return self.solve(a, b, x);
            }
            p.ksp.set_type("gmres").map_err(err)?;
            let r = self.solve(a, b, x);
            let back = self.pattern.as_mut().ok_or(LinalgError::NotAnalyzed)?.ksp.set_type("cg").map_err(err);
            let r = r?;
            back?;
            Ok(r)
        }

        fn name(&self) -> &str {
            self.pattern.as_ref().map_or("petsc", |p| p.name.as_str())
        }

        fn definite(&self) -> Option<bool> {
            self.definite
        }

        fn own_row_abs_sums(&self) -> Option<Vec<f64>> {
            match &self.pattern.as_ref()?.sources {
                Sources::Part { row_ptr, .. } => {
                    let values = &self.pattern.as_ref()?.values;
                    Some(row_ptr.windows(2).map(|w| values[w[0]..w[1]].iter().map(|v| v.abs()).sum()).collect())
                }
                Sources::Whole { .. } => None,
            }
        }
    }
}
