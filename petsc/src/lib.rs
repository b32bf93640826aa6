//! A small safe wrapper of the system PETSc (the `petsc-sys` bindings): what mpfem's
//! distributed linear solve needs and nothing more.
//!
//! - [`Petsc`]: initialisation (on `MPI_COMM_WORLD`, after MPI if the caller started it) with
//!   the options database filled from a string in PETSc's command-line syntax, finalisation
//!   when dropped (which prints `-log_view` and friends);
//! - [`Vector`]: a distributed vector (each process its contiguous range);
//! - [`Matrix`]: a distributed AIJ matrix made from each process's rows in CSR form (global
//!   column numbers), whose values are replaced in place for every new set of values of the
//!   same pattern; its near-null space;
//! - [`Ksp`]: a Krylov solver with its preconditioner, given defaults in code that the options
//!   database then overrides (`-ksp_type`, `-pc_type`, `-pc_factor_mat_solver_type`, …, as
//!   every PETSc program does), the failure reasons, and the inertia of a Cholesky factor.
//!
//! Every call is collective over `PETSC_COMM_WORLD` unless it says otherwise, and must be made
//! from the thread that initialised PETSc. Errors come back as [`Error`] (PETSc's traceback
//! printing is replaced by its return-only error handler), never as a panic or an abort.

use petsc_sys as sys;
use std::ffi::{CStr, CString};
use std::fmt;
use std::ptr;
use std::sync::atomic::{AtomicBool, Ordering};

/// A PETSc call that failed: the function, PETSc's error code and its message.
#[derive(Debug, Clone, PartialEq)]
pub struct Error {
    pub call: &'static str,
    pub code: i32,
    pub message: String,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "PETSc {} failed (error {}: {})", self.call, self.code, self.message)
    }
}

impl std::error::Error for Error {}

pub type Result<T> = std::result::Result<T, Error>;

fn check(code: sys::PetscErrorCode, call: &'static str) -> Result<()> {
    if code == 0 {
        return Ok(());
    }
    // the first message of the error's traceback (what failed, in PETSc's words), else the
    // generic text of the code
    let detail = LAST_MESSAGE.lock().map(|mut m| std::mem::take(&mut *m)).unwrap_or_default();
    let mut text: *const std::os::raw::c_char = ptr::null();
    // SAFETY: PetscErrorMessage points `text` at a static string (or leaves it null)
    let generic = unsafe {
        if sys::PetscErrorMessage(code, &mut text, ptr::null_mut()) == 0 && !text.is_null() {
            CStr::from_ptr(text).to_string_lossy().into_owned()
        } else {
            "unknown error".to_string()
        }
    };
    let message = if detail.is_empty() { generic } else { format!("{generic}: {detail}") };
    Err(Error { call, code, message })
}

/// The message of the error being raised (set by [`record_error`], taken by [`check`]).
static LAST_MESSAGE: std::sync::Mutex<String> = std::sync::Mutex::new(String::new());

/// PETSc's error handler while this crate runs it: records the message where the error is
/// raised (the first call of a traceback) and returns the code, printing nothing.
unsafe extern "C" fn record_error(
    _comm: sys::MPI_Comm,
    _line: std::os::raw::c_int,
    _func: *const std::os::raw::c_char,
    _file: *const std::os::raw::c_char,
    n: sys::PetscErrorCode,
    p: sys::PetscErrorType,
    mess: *const std::os::raw::c_char,
    _ctx: *mut std::os::raw::c_void,
) -> sys::PetscErrorCode {
    if p == sys::PetscErrorType::PETSC_ERROR_INITIAL && !mess.is_null() {
        // SAFETY: PETSc passes a NUL-terminated message
        let m = unsafe { CStr::from_ptr(mess) }.to_string_lossy().trim().to_string();
        if let Ok(mut last) = LAST_MESSAGE.lock() {
            *last = m;
        }
    }
    n
}

fn cstring(s: &str, what: &'static str) -> Result<CString> {
    CString::new(s).map_err(|_| Error { call: what, code: -1, message: format!("{s:?} holds a NUL byte") })
}

/// Set once this process has initialised PETSc (through [`Petsc::initialize`] or
/// [`ensure_initialized`]); PETSc cannot be initialised again after it is finalised.
static STARTED: AtomicBool = AtomicBool::new(false);

/// Whether PETSc is initialised in this process.
pub fn is_initialized() -> bool {
    let mut flag = sys::PetscBool::PETSC_FALSE;
    // SAFETY: may be called at any time
    unsafe { sys::PetscInitialized(&mut flag) };
    flag == sys::PetscBool::PETSC_TRUE
}

fn after_initialize() -> Result<()> {
    // errors are returned with their message, not printed with a traceback on stderr (the
    // caller reports them)
    // SAFETY: PETSc is initialised; the handler has PETSc's signature and keeps no pointer
    check(unsafe { sys::PetscPushErrorHandler(Some(record_error), ptr::null_mut()) }, "PetscPushErrorHandler")
}

/// Initialise PETSc with no options if nobody has (for a library user that never made a
/// [`Petsc`]); it is then never finalised by this crate. Not after a [`Petsc`] was dropped.
pub fn ensure_initialized() -> Result<()> {
    if is_initialized() {
        return Ok(());
    }
    if STARTED.swap(true, Ordering::SeqCst) {
        return Err(Error { call: "PetscInitialize", code: -1, message: "PETSc was finalised in this process and cannot start again".into() });
    }
    // SAFETY: not initialised; MPI is initialised here if the caller has not
    check(unsafe { sys::PetscInitializeNoArguments() }, "PetscInitializeNoArguments")?;
    after_initialize()
}

/// PETSc, initialised by this value and finalised when it is dropped (which prints what
/// `-log_view` and the like ask for). Drop every [`Matrix`], [`Vector`] and [`Ksp`] first.
pub struct Petsc {
    finalize: bool,
}

impl Petsc {
    /// Initialise PETSc on `MPI_COMM_WORLD` with `options` (whitespace-separated, PETSc's
    /// command-line syntax: `-ksp_type cg -pc_type gamg -log_view`) as its command line, so
    /// that options read at initialisation (`-log_view`, `-info`) work too; the environment
    /// variable `PETSC_OPTIONS` is read as usual. If PETSc is initialised already the options
    /// are added to its database and dropping this value does not finalise it.
    pub fn initialize(options: &str) -> Result<Self> {
        if is_initialized() {
            insert_options(options)?;
            return Ok(Self { finalize: false });
        }
        if STARTED.swap(true, Ordering::SeqCst) {
            return Err(Error { call: "PetscInitialize", code: -1, message: "PETSc was finalised in this process and cannot start again".into() });
        }
        let mut args: Vec<CString> = vec![cstring("mpfem", "PetscInitialize")?];
        for a in options.split_whitespace() {
            args.push(cstring(a, "PetscInitialize")?);
        }
        // PETSc keeps the pointers to its command line until it is finalised: they live as
        // long as the process (a few bytes, once)
        let argv: &'static mut [*mut std::os::raw::c_char] = Box::leak(args.into_iter().map(CString::into_raw).chain(std::iter::once(ptr::null_mut())).collect::<Vec<_>>().into_boxed_slice());
        let mut argc = (argv.len() - 1) as std::os::raw::c_int;
        let mut argv_ptr = argv.as_mut_ptr();
        // SAFETY: argc/argv are a valid, NUL-terminated command line that outlives PETSc
        check(unsafe { sys::PetscInitialize(&mut argc, &mut argv_ptr, ptr::null(), ptr::null()) }, "PetscInitialize")?;
        after_initialize()?;
        Ok(Self { finalize: true })
    }

    /// This process's rank and the number of processes of `PETSC_COMM_WORLD`.
    pub fn rank_size() -> Result<(usize, usize)> {
        let (mut rank, mut size) = (0, 0);
        // SAFETY: PETSc (so MPI) is initialised by the caller's contract
        unsafe {
            check(sys::MPI_Comm_rank(sys::PETSC_COMM_WORLD, &mut rank), "MPI_Comm_rank")?;
            check(sys::MPI_Comm_size(sys::PETSC_COMM_WORLD, &mut size), "MPI_Comm_size")?;
        }
        Ok((rank as usize, size as usize))
    }
}

impl Drop for Petsc {
    fn drop(&mut self) {
        if self.finalize {
            // SAFETY: initialised by this value; the caller dropped every object first
            unsafe { sys::PetscFinalize() };
        }
    }
}

/// Add `options` (PETSc's command-line syntax) to the options database; later options
/// override earlier ones of the same name.
pub fn insert_options(options: &str) -> Result<()> {
    let s = cstring(options, "PetscOptionsInsertString")?;
    // SAFETY: PETSc is initialised; the string is copied
    check(unsafe { sys::PetscOptionsInsertString(ptr::null_mut(), s.as_ptr()) }, "PetscOptionsInsertString")
}

/// Whether the options database holds `name` (with its leading dash, `-ksp_type`).
pub fn has_option(name: &str) -> Result<bool> {
    let s = cstring(name, "PetscOptionsHasName")?;
    let mut flag = sys::PetscBool::PETSC_FALSE;
    // SAFETY: PETSc is initialised
    check(unsafe { sys::PetscOptionsHasName(ptr::null_mut(), ptr::null(), s.as_ptr(), &mut flag) }, "PetscOptionsHasName")?;
    Ok(flag == sys::PetscBool::PETSC_TRUE)
}

/// The value of option `name` in the options database (with its leading dash, `-pc_type`);
/// None when it is not set (or set without a value).
pub fn option_value(name: &str) -> Result<Option<String>> {
    let s = cstring(name, "PetscOptionsGetString")?;
    let mut buf = vec![0 as std::os::raw::c_char; 256];
    let mut flag = sys::PetscBool::PETSC_FALSE;
    // SAFETY: PETSc is initialised; PETSc writes at most `buf.len()` bytes, NUL-terminated
    check(unsafe { sys::PetscOptionsGetString(ptr::null_mut(), ptr::null(), s.as_ptr(), buf.as_mut_ptr(), buf.len(), &mut flag) }, "PetscOptionsGetString")?;
    if flag != sys::PetscBool::PETSC_TRUE {
        return Ok(None);
    }
    // SAFETY: NUL-terminated by PETSc
    let v = unsafe { CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned();
    Ok((!v.is_empty()).then_some(v))
}

fn petsc_int(n: usize, what: &'static str) -> Result<sys::PetscInt> {
    sys::PetscInt::try_from(n).map_err(|_| Error { call: what, code: -1, message: format!("{n} does not fit PETSc's 32-bit indices") })
}

/// A distributed vector: `local` entries on this process (a contiguous range of the global
/// numbering, the ranges in rank order).
pub struct Vector {
    v: sys::Vec,
}

impl Vector {
    /// A vector of `local` entries here (collective: the global size is the sum).
    pub fn new(local: usize) -> Result<Self> {
        let mut v: sys::Vec = ptr::null_mut();
        // SAFETY: PETSc is initialised; v is written by the call
        check(unsafe { sys::VecCreateMPI(sys::PETSC_COMM_WORLD, petsc_int(local, "VecCreateMPI")?, sys::PETSC_DETERMINE, &mut v) }, "VecCreateMPI")?;
        Ok(Self { v })
    }

    /// A vector with the row layout of `a` (its local rows here).
    pub fn like_rows(a: &Matrix) -> Result<Self> {
        let mut v: sys::Vec = ptr::null_mut();
        // SAFETY: a is a valid matrix
        check(unsafe { sys::MatCreateVecs(a.m, ptr::null_mut(), &mut v) }, "MatCreateVecs")?;
        Ok(Self { v })
    }

    /// This process's range of the vector's global entries, [start, end). Not collective.
    pub fn ownership_range(&self) -> Result<(usize, usize)> {
        let (mut lo, mut hi) = (0, 0);
        // SAFETY: valid vector
        check(unsafe { sys::VecGetOwnershipRange(self.v, &mut lo, &mut hi) }, "VecGetOwnershipRange")?;
        Ok((lo as usize, hi as usize))
    }

    /// The number of global entries. Not collective.
    pub fn global_len(&self) -> Result<usize> {
        let mut n = 0;
        // SAFETY: valid vector
        check(unsafe { sys::VecGetSize(self.v, &mut n) }, "VecGetSize")?;
        Ok(n as usize)
    }

    /// The number of entries on this process (not collective).
    pub fn local_len(&self) -> Result<usize> {
        let mut n = 0;
        // SAFETY: valid vector
        check(unsafe { sys::VecGetLocalSize(self.v, &mut n) }, "VecGetLocalSize")?;
        Ok(n as usize)
    }

    /// Overwrite this process's entries (not collective).
    pub fn set_local(&mut self, values: &[f64]) -> Result<()> {
        let n = self.local_len()?;
        if values.len() != n {
            return Err(Error { call: "VecGetArray", code: -1, message: format!("{} values for {n} local entries", values.len()) });
        }
        let mut a: *mut f64 = ptr::null_mut();
        // SAFETY: VecGetArray gives n writable entries until VecRestoreArray
        unsafe {
            check(sys::VecGetArray(self.v, &mut a), "VecGetArray")?;
            if n > 0 {
                std::slice::from_raw_parts_mut(a, n).copy_from_slice(values);
            }
            check(sys::VecRestoreArray(self.v, &mut a), "VecRestoreArray")
        }
    }

    /// This process's entries (not collective).
    pub fn local(&self) -> Result<Vec<f64>> {
        let n = self.local_len()?;
        let mut a: *const f64 = ptr::null();
        // SAFETY: VecGetArrayRead gives n readable entries until VecRestoreArrayRead
        unsafe {
            check(sys::VecGetArrayRead(self.v, &mut a), "VecGetArrayRead")?;
            let out = if n > 0 { std::slice::from_raw_parts(a, n).to_vec() } else { Vec::new() };
            check(sys::VecRestoreArrayRead(self.v, &mut a), "VecRestoreArrayRead")?;
            Ok(out)
        }
    }

    /// The Euclidean norm over every process.
    pub fn norm2(&self) -> Result<f64> {
        let mut n = 0.0;
        // SAFETY: valid vector
        check(unsafe { sys::VecNorm(self.v, sys::NormType::NORM_2, &mut n) }, "VecNorm")?;
        Ok(n)
    }

    /// The dot product with `other` over every process.
    pub fn dot(&self, other: &Vector) -> Result<f64> {
        let mut d = 0.0;
        // SAFETY: valid vectors of the same layout (PETSc checks)
        check(unsafe { sys::VecDot(self.v, other.v, &mut d) }, "VecDot")?;
        Ok(d)
    }

    /// self += alpha · x.
    pub fn axpy(&mut self, alpha: f64, x: &Vector) -> Result<()> {
        // SAFETY: valid vectors of the same layout (PETSc checks)
        check(unsafe { sys::VecAXPY(self.v, alpha, x.v) }, "VecAXPY")
    }

    /// self *= alpha.
    pub fn scale(&mut self, alpha: f64) -> Result<()> {
        // SAFETY: valid vector
        check(unsafe { sys::VecScale(self.v, alpha) }, "VecScale")
    }
}

impl Drop for Vector {
    fn drop(&mut self) {
        // SAFETY: owned handle
        unsafe { sys::VecDestroy(&mut self.v) };
    }
}

/// Gathers a distributed vector whole onto every process (a scatter made once for a layout).
pub struct GatherAll {
    ctx: sys::VecScatter,
    all: sys::Vec,
}

impl GatherAll {
    /// For vectors with the layout of `like`.
    pub fn new(like: &Vector) -> Result<Self> {
        let (mut ctx, mut all): (sys::VecScatter, sys::Vec) = (ptr::null_mut(), ptr::null_mut());
        // SAFETY: valid vector; ctx and all are written by the call
        check(unsafe { sys::VecScatterCreateToAll(like.v, &mut ctx, &mut all) }, "VecScatterCreateToAll")?;
        Ok(Self { ctx, all })
    }

    /// Every entry of `v` in the global numbering, on every process.
    pub fn gather(&mut self, v: &Vector) -> Result<Vec<f64>> {
        // SAFETY: the scatter was made for v's layout
        unsafe {
            check(sys::VecScatterBegin(self.ctx, v.v, self.all, sys::InsertMode::INSERT_VALUES, sys::ScatterMode::SCATTER_FORWARD), "VecScatterBegin")?;
            check(sys::VecScatterEnd(self.ctx, v.v, self.all, sys::InsertMode::INSERT_VALUES, sys::ScatterMode::SCATTER_FORWARD), "VecScatterEnd")?;
        }
        let whole = Vector { v: self.all };
        let out = whole.local();
        std::mem::forget(whole);
        out
    }
}

impl Drop for GatherAll {
    fn drop(&mut self) {
        // SAFETY: owned handles
        unsafe {
            sys::VecScatterDestroy(&mut self.ctx);
            sys::VecDestroy(&mut self.all);
        }
    }
}

/// A distributed AIJ matrix (`MPIAIJ`; on one process too): each process holds a contiguous
/// range of rows, the ranges in rank order.
pub struct Matrix {
    m: sys::Mat,
    nnz: usize,
}

impl Matrix {
    /// The square matrix of `n_global` rows whose rows on this process are the CSR arrays
    /// `row_ptr` (local rows + 1), `cols` (global column numbers, ascending in each row) and
    /// `values`. The local column range is the local row range. Collective.
    pub fn from_local_csr(n_global: usize, row_ptr: &[usize], cols: &[usize], values: &[f64]) -> Result<Self> {
        let n_local = row_ptr.len().saturating_sub(1);
        Self::from_local_csr_columns(n_global, n_local, n_global, row_ptr, cols, values)
    }

    /// [`Matrix::from_local_csr`] for a matrix of `n_rows` rows and `n_columns` columns,
    /// `n_local_columns` of which are this process's column range (a prolongation's: its
    /// coarse unknowns). Collective.
    pub fn from_local_csr_columns(n_rows: usize, n_local_columns: usize, n_columns: usize, row_ptr: &[usize], cols: &[usize], values: &[f64]) -> Result<Self> {
        let n_local = row_ptr.len().checked_sub(1).ok_or(Error { call: "MatCreateMPIAIJWithArrays", code: -1, message: "empty row pointer".into() })?;
        let nnz = *row_ptr.last().unwrap_or(&0);
        if cols.len() != nnz || values.len() != nnz || row_ptr[0] != 0 {
            return Err(Error { call: "MatCreateMPIAIJWithArrays", code: -1, message: format!("inconsistent CSR: row_ptr ends at {nnz}, {} columns, {} values", cols.len(), values.len()) });
        }
        if let Some(&c) = cols.iter().find(|&&c| c >= n_columns) {
            return Err(Error { call: "MatCreateMPIAIJWithArrays", code: -1, message: format!("column {c} outside the {n_columns} columns") });
        }
        let what = "MatCreateMPIAIJWithArrays";
        let rp: Vec<sys::PetscInt> = row_ptr.iter().map(|&v| petsc_int(v, what)).collect::<Result<_>>()?;
        let cj: Vec<sys::PetscInt> = cols.iter().map(|&v| petsc_int(v, what)).collect::<Result<_>>()?;
        let mut m: sys::Mat = ptr::null_mut();
        // SAFETY: consistent CSR arrays (checked above), copied by PETSc
        check(
            unsafe { sys::MatCreateMPIAIJWithArrays(sys::PETSC_COMM_WORLD, petsc_int(n_local, what)?, petsc_int(n_local_columns, what)?, petsc_int(n_rows, what)?, petsc_int(n_columns, what)?, rp.as_ptr(), cj.as_ptr(), values.as_ptr(), &mut m) },
            what,
        )?;
        Ok(Self { m, nnz })
    }

    /// Replace the values, given in the order of the CSR arrays the matrix was made from.
    /// Collective.
    pub fn update_values(&mut self, values: &[f64]) -> Result<()> {
        if values.len() != self.nnz {
            return Err(Error { call: "MatUpdateMPIAIJWithArray", code: -1, message: format!("{} values for {} entries", values.len(), self.nnz) });
        }
        // SAFETY: values has the length of the CSR the matrix was made from
        check(unsafe { sys::MatUpdateMPIAIJWithArray(self.m, values.as_ptr()) }, "MatUpdateMPIAIJWithArray")
    }

    /// Declare the matrix symmetric for as long as it lives (its factorisations may use it).
    pub fn set_symmetric(&mut self) -> Result<()> {
        // SAFETY: valid matrix
        unsafe {
            check(sys::MatSetOption(self.m, sys::MatOption::MAT_SYMMETRIC, sys::PetscBool::PETSC_TRUE), "MatSetOption(MAT_SYMMETRIC)")?;
            check(sys::MatSetOption(self.m, sys::MatOption::MAT_SYMMETRY_ETERNAL, sys::PetscBool::PETSC_TRUE), "MatSetOption(MAT_SYMMETRY_ETERNAL)")
        }
    }

    /// y = A x.
    pub fn mult(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        // SAFETY: valid handles (PETSc checks the layouts)
        check(unsafe { sys::MatMult(self.m, x.v, y.v) }, "MatMult")
    }

    /// Give the matrix a near-null space (for algebraic multigrid): the vectors, which this
    /// orthonormalises (modified Gram–Schmidt; vectors that vanish are dropped).
    pub fn set_near_null_space(&mut self, mut vectors: Vec<Vector>) -> Result<usize> {
        let mut kept: Vec<Vector> = Vec::new();
        for mut v in vectors.drain(..) {
            for q in &kept {
                let d = v.dot(q)?;
                v.axpy(-d, q)?;
            }
            let n = v.norm2()?;
            if n > 1e-12 {
                v.scale(1.0 / n)?;
                kept.push(v);
            }
        }
        let handles: Vec<sys::Vec> = kept.iter().map(|v| v.v).collect();
        let mut nsp: sys::MatNullSpace = ptr::null_mut();
        // SAFETY: orthonormal vectors of the matrix's row layout; PETSc references them
        unsafe {
            check(sys::MatNullSpaceCreate(sys::PETSC_COMM_WORLD, sys::PetscBool::PETSC_FALSE, handles.len() as sys::PetscInt, handles.as_ptr(), &mut nsp), "MatNullSpaceCreate")?;
            let r = check(sys::MatSetNearNullSpace(self.m, nsp), "MatSetNearNullSpace");
            sys::MatNullSpaceDestroy(&mut nsp);
            r?;
        }
        Ok(kept.len())
    }
}

impl Drop for Matrix {
    fn drop(&mut self) {
        // SAFETY: owned handle
        unsafe { sys::MatDestroy(&mut self.m) };
    }
}

/// What a [`Ksp::solve`] reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveInfo {
    pub iterations: usize,
    /// PETSc's `KSPConvergedReason` (positive: converged; negative: diverged).
    pub reason: i32,
}

/// A Krylov solver and its preconditioner (`KSP`, `PC`).
pub struct Ksp {
    k: sys::KSP,
}

impl Ksp {
    pub fn new() -> Result<Self> {
        let mut k: sys::KSP = ptr::null_mut();
        // SAFETY: PETSc is initialised
        check(unsafe { sys::KSPCreate(sys::PETSC_COMM_WORLD, &mut k) }, "KSPCreate")?;
        Ok(Self { k })
    }

    fn pc(&self) -> Result<sys::PC> {
        let mut pc: sys::PC = ptr::null_mut();
        // SAFETY: valid KSP
        check(unsafe { sys::KSPGetPC(self.k, &mut pc) }, "KSPGetPC")?;
        Ok(pc)
    }

    /// The defaults that the options database may then override ([`Ksp::set_from_options`]):
    /// the Krylov method (`preonly`, `cg`, `gmres`, …), the preconditioner (`lu`, `cholesky`,
    /// `gamg`, …), the factorisation package of a direct one (`mumps`, `superlu_dist`) and the
    /// relative tolerance and iteration limit of an iterative one.
    pub fn set_defaults(&mut self, ksp_type: &str, pc_type: &str, factor_package: Option<&str>, rtol: f64, max_it: usize) -> Result<()> {
        let kt = cstring(ksp_type, "KSPSetType")?;
        let pt = cstring(pc_type, "PCSetType")?;
        let pc = self.pc()?;
        // SAFETY: valid handles; the strings are copied
        unsafe {
            check(sys::KSPSetType(self.k, kt.as_ptr()), "KSPSetType")?;
            check(sys::PCSetType(pc, pt.as_ptr()), "PCSetType")?;
            if let Some(p) = factor_package {
                let p = cstring(p, "PCFactorSetMatSolverType")?;
                check(sys::PCFactorSetMatSolverType(pc, p.as_ptr()), "PCFactorSetMatSolverType")?;
            }
            check(sys::KSPSetTolerances(self.k, rtol, sys::PETSC_DEFAULT as f64, sys::PETSC_DEFAULT as f64, petsc_int(max_it, "KSPSetTolerances")?), "KSPSetTolerances")
        }
    }

    /// A two-level multigrid preconditioner (`PCMG`) whose coarse space is spanned by the
    /// columns of `prolongation` (fine rows × coarse unknowns), its coarse operator the Galerkin
    /// product Pᵀ A P (made again at every set-up), solved by MUMPS (Cholesky for a `symmetric`
    /// matrix, LU otherwise); the fine level smoothed by one Richardson iteration, damped by ½,
    /// of block Jacobi with this process's rows cut into `blocks` (their lengths, in row order;
    /// every process gives its own, an empty process `[0]`). Defaults the options database may then override
    /// (`-mg_levels_ksp_type`, `-mg_levels_pc_type`, `-mg_coarse_pc_type`, …). Call before
    /// [`Ksp::set_from_options`].
    pub fn set_two_level(&mut self, prolongation: &Matrix, blocks: &[usize], symmetric: bool) -> Result<()> {
        let pc = self.pc()?;
        let mg = cstring("mg", "PCSetType")?;
        let bjacobi = cstring("bjacobi", "PCSetType")?;
        let richardson = cstring("richardson", "KSPSetType")?;
        let preonly = cstring("preonly", "KSPSetType")?;
        let direct = cstring(if symmetric { "cholesky" } else { "lu" }, "PCSetType")?;
        let mumps = cstring("mumps", "PCFactorSetMatSolverType")?;
        let lens: Vec<sys::PetscInt> = blocks.iter().map(|&n| petsc_int(n, "PCBJacobiSetLocalBlocks")).collect::<Result<_>>()?;
        // SAFETY: valid handles; the strings and block lengths are copied by PETSc, which
        // references the prolongation
        unsafe {
            check(sys::PCSetType(pc, mg.as_ptr()), "PCSetType")?;
            check(sys::PCMGSetLevels(pc, 2, ptr::null_mut()), "PCMGSetLevels")?;
            check(sys::PCMGSetInterpolation(pc, 1, prolongation.m), "PCMGSetInterpolation")?;
            check(sys::PCMGSetGalerkin(pc, sys::PCMGGalerkinType_PC_MG_GALERKIN_BOTH), "PCMGSetGalerkin")?;
            let mut smoother: sys::KSP = ptr::null_mut();
            check(sys::PCMGGetSmoother(pc, 1, &mut smoother), "PCMGGetSmoother")?;
            let mut spc: sys::PC = ptr::null_mut();
            check(sys::KSPGetPC(smoother, &mut spc), "KSPGetPC")?;
            check(sys::KSPSetType(smoother, richardson.as_ptr()), "KSPSetType")?;
            check(sys::KSPRichardsonSetScale(smoother, 0.5), "KSPRichardsonSetScale")?;
            check(sys::KSPSetTolerances(smoother, sys::PETSC_DEFAULT as f64, sys::PETSC_DEFAULT as f64, sys::PETSC_DEFAULT as f64, 1), "KSPSetTolerances")?;
            check(sys::PCSetType(spc, bjacobi.as_ptr()), "PCSetType")?;
            check(sys::PCBJacobiSetLocalBlocks(spc, lens.len() as sys::PetscInt, lens.as_ptr()), "PCBJacobiSetLocalBlocks")?;
            let mut coarse: sys::KSP = ptr::null_mut();
            check(sys::PCMGGetCoarseSolve(pc, &mut coarse), "PCMGGetCoarseSolve")?;
            check(sys::KSPSetType(coarse, preonly.as_ptr()), "KSPSetType")?;
            let mut cpc: sys::PC = ptr::null_mut();
            check(sys::KSPGetPC(coarse, &mut cpc), "KSPGetPC")?;
            check(sys::PCSetType(cpc, direct.as_ptr()), "PCSetType")?;
            check(sys::PCFactorSetMatSolverType(cpc, mumps.as_ptr()), "PCFactorSetMatSolverType")?;
        }
        Ok(())
    }

    /// The Krylov method (`cg`, `gmres`, …) from now on, the preconditioner kept.
    pub fn set_type(&mut self, ksp_type: &str) -> Result<()> {
        let kt = cstring(ksp_type, "KSPSetType")?;
        // SAFETY: valid KSP; the string is copied
        check(unsafe { sys::KSPSetType(self.k, kt.as_ptr()) }, "KSPSetType")
    }

    /// Read the options database (`-ksp_*`, `-pc_*`, `-mat_mumps_*`, …).
    pub fn set_from_options(&mut self) -> Result<()> {
        // SAFETY: valid KSP
        check(unsafe { sys::KSPSetFromOptions(self.k) }, "KSPSetFromOptions")
    }

    /// Solve with `a` (and build the preconditioner from it); call again after its values
    /// change.
    pub fn set_operator(&mut self, a: &Matrix) -> Result<()> {
        // SAFETY: valid handles; the KSP references the matrix
        check(unsafe { sys::KSPSetOperators(self.k, a.m, a.m) }, "KSPSetOperators")
    }

    /// Build the preconditioner (factorise, for a direct one) now. Err also when PETSc
    /// records a failure of the preconditioner (a zero pivot, a singular matrix) without
    /// returning an error code.
    pub fn set_up(&mut self) -> Result<()> {
        // SAFETY: valid KSP with operators
        check(unsafe { sys::KSPSetUp(self.k) }, "KSPSetUp")?;
        let mut reason = sys::PCFailedReason::PC_NOERROR;
        // SAFETY: valid PC
        check(unsafe { sys::PCGetFailedReason(self.pc()?, &mut reason) }, "PCGetFailedReason")?;
        if reason != sys::PCFailedReason::PC_NOERROR {
            return Err(Error { call: "KSPSetUp", code: reason as i32, message: format!("the preconditioner failed: {reason:?}") });
        }
        Ok(())
    }

    /// Solve A x = b (x is the initial guess of an iterative method if it asks for one).
    pub fn solve(&mut self, b: &Vector, x: &mut Vector) -> Result<SolveInfo> {
        // SAFETY: valid handles of the operator's layout (PETSc checks)
        check(unsafe { sys::KSPSolve(self.k, b.v, x.v) }, "KSPSolve")?;
        let (mut its, mut reason) = (0, sys::KSPConvergedReason::KSP_CONVERGED_ITERATING);
        // SAFETY: valid KSP
        unsafe {
            check(sys::KSPGetIterationNumber(self.k, &mut its), "KSPGetIterationNumber")?;
            check(sys::KSPGetConvergedReason(self.k, &mut reason), "KSPGetConvergedReason")?;
        }
        Ok(SolveInfo { iterations: its as usize, reason: reason as i32 })
    }

    /// The Krylov method and the preconditioner in use (after [`Ksp::set_from_options`]), and
    /// the factorisation package of a direct preconditioner.
    pub fn types(&self) -> Result<(String, String, Option<String>)> {
        let (mut kt, mut pt): (sys::KSPType, sys::PCType) = (ptr::null(), ptr::null());
        let pc = self.pc()?;
        let mut package: sys::MatSolverType = ptr::null();
        // SAFETY: valid handles; the names are PETSc's static strings
        unsafe {
            check(sys::KSPGetType(self.k, &mut kt), "KSPGetType")?;
            check(sys::PCGetType(pc, &mut pt), "PCGetType")?;
            let name = |p: *const std::os::raw::c_char| if p.is_null() { String::new() } else { CStr::from_ptr(p).to_string_lossy().into_owned() };
            let (k, p) = (name(kt), name(pt));
            let direct = p == "lu" || p == "cholesky";
            if direct {
                check(sys::PCFactorGetMatSolverType(pc, &mut package), "PCFactorGetMatSolverType")?;
            }
            Ok((k, p, (direct && !package.is_null()).then(|| name(package))))
        }
    }

    /// The inertia of the factor of a Cholesky preconditioner (after [`Ksp::set_up`]): the
    /// numbers of negative, zero and positive eigenvalues; None when the preconditioner is not
    /// a factorisation that reports it (LU, iterative ones). MUMPS reports it with its null
    /// pivot detection on (`-mat_mumps_icntl_24 1`), and on several processes only with the
    /// root's Schur complement kept off ScaLAPACK (`-mat_mumps_icntl_13 1`).
    pub fn inertia(&self) -> Result<Option<(usize, usize, usize)>> {
        let (_, p, _) = self.types()?;
        if p != "cholesky" {
            return Ok(None);
        }
        let mut f: sys::Mat = ptr::null_mut();
        let (mut neg, mut zero, mut pos) = (0, 0, 0);
        // SAFETY: valid PC that has been set up
        unsafe {
            check(sys::PCFactorGetMatrix(self.pc()?, &mut f), "PCFactorGetMatrix")?;
            check(sys::MatGetInertia(f, &mut neg, &mut zero, &mut pos), "MatGetInertia")?;
        }
        Ok(Some((neg as usize, zero as usize, pos as usize)))
    }
}

impl Drop for Ksp {
    fn drop(&mut self) {
        // SAFETY: owned handle
        unsafe { sys::KSPDestroy(&mut self.k) };
    }
}

// SAFETY: the handles are PETSc objects used by one thread at a time (the caller's contract:
// the thread that initialised PETSc); moving them between threads does not touch them.
unsafe impl Send for Vector {}
unsafe impl Send for Matrix {}
unsafe impl Send for Ksp {}
unsafe impl Send for GatherAll {}
