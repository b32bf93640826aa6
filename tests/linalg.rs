//! Integration tests of the sparse linear solvers (`mpfem::linalg`).
//!
//! Accuracy target: a relative residual ‖b − Ax‖/‖b‖ ≤ 1e-10 for every solver. The direct solvers
//! are backward stable, so on these well-conditioned test matrices (condition numbers ≲ 1e4)
//! they reach ~1e-15; 1e-10 leaves a wide margin for platform/BLAS differences while still
//! catching any wrong permutation, transposition or stale factor (those give O(1) residuals).
//! PCG is run with tolerance 1e-10 and reports the *true* residual of the returned iterate.
//! The error against the known solution x* is bounded by cond(A)·residual, hence the looser
//! 1e-7 checks on ‖x − x*‖/‖x*‖.

use mpfem::linalg::direct::{
    bare_faer_cholesky_solve, bare_faer_lu_solve, to_faer_csc, CholeskyKind, FactorStructure, FaerCholesky, FaerLu,
};
use mpfem::linalg::pcg::Pcg;
use mpfem::linalg::*;

const RES_TOL: f64 = 1e-10;
const ERR_TOL: f64 = 1e-7;

/// Build a CSR matrix from a per-row list of (column, value) pairs (columns in any order).
fn csr_from_entries(n: usize, entries: &[Vec<(usize, f64)>]) -> CsrMatrix {
    let rows: Vec<Vec<usize>> = entries
        .iter()
        .map(|r| {
            let mut c: Vec<usize> = r.iter().map(|e| e.0).collect();
            c.sort_unstable();
            c.dedup();
            c
        })
        .collect();
    let mut a = CsrMatrix::from_rows(n, &rows);
    for (i, r) in entries.iter().enumerate() {
        for &(j, v) in r {
            let k = a.find(i, j).unwrap();
            a.values[k] += v;
        }
    }
    a
}

/// 2D convection–diffusion on an m×m grid with Dirichlet boundary (eliminated), unit spacing:
/// −Δu + (cx, cy)·∇u with central differences. cx = cy = 0 gives the SPD 5-point Laplacian.
fn conv_diff(m: usize, cx: f64, cy: f64, shift: f64) -> CsrMatrix {
    let n = m * m;
    let id = |i: usize, j: usize| i * m + j;
    let mut entries = vec![Vec::new(); n];
    for i in 0..m {
        for j in 0..m {
            let r = id(i, j);
            entries[r].push((r, 4.0 - shift));
            if i > 0 {
                entries[r].push((id(i - 1, j), -1.0 - cy / 2.0));
            }
            if i + 1 < m {
                entries[r].push((id(i + 1, j), -1.0 + cy / 2.0));
            }
            if j > 0 {
                entries[r].push((id(i, j - 1), -1.0 - cx / 2.0));
            }
            if j + 1 < m {
                entries[r].push((id(i, j + 1), -1.0 + cx / 2.0));
            }
        }
    }
    csr_from_entries(n, &entries)
}

fn laplacian(m: usize) -> CsrMatrix {
    conv_diff(m, 0.0, 0.0, 0.0)
}

fn x_star(n: usize) -> Vec<f64> {
    (0..n).map(|i| 1.0 + (0.37 * i as f64).sin() + 0.001 * i as f64).collect()
}

fn rhs_of(a: &CsrMatrix, x: &[f64]) -> Vec<f64> {
    let mut b = vec![0.0; a.nrows];
    a.mul_vec(x, &mut b);
    b
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn rel_residual(a: &CsrMatrix, x: &[f64], b: &[f64]) -> f64 {
    let ax = rhs_of(a, x);
    let r: Vec<f64> = ax.iter().zip(b).map(|(p, q)| q - p).collect();
    norm(&r) / norm(b)
}

fn rel_err(x: &[f64], y: &[f64]) -> f64 {
    let d: Vec<f64> = x.iter().zip(y).map(|(p, q)| p - q).collect();
    norm(&d) / norm(y)
}

/// analyze + factor + solve from a zero initial guess.
fn run(s: &mut dyn LinearSolver, a: &CsrMatrix, b: &[f64]) -> Result<(Vec<f64>, SolveStats), LinalgError> {
    s.analyze(a)?;
    s.factor(a)?;
    let mut x = vec![0.0; a.nrows];
    let st = s.solve(a, b, &mut x)?;
    Ok((x, st))
}

fn check_solution(a: &CsrMatrix, x: &[f64], xs: &[f64], b: &[f64], st: &SolveStats, what: &str) {
    let res = rel_residual(a, x, b);
    assert!(res <= RES_TOL, "{what}: relative residual {res:e} > {RES_TOL:e}");
    assert!(st.relative_residual <= RES_TOL, "{what}: reported residual {:e}", st.relative_residual);
    // The reported residual is the true one (up to rounding).
    assert!((st.relative_residual - res).abs() <= 1e-12, "{what}: reported {:e} vs {res:e}", st.relative_residual);
    let err = rel_err(x, xs);
    assert!(err <= ERR_TOL, "{what}: error against x* {err:e}");
}

#[test]
fn lu_solves_laplacian() {
    let a = laplacian(50);
    let xs = x_star(a.nrows);
    let b = rhs_of(&a, &xs);
    let mut s = FaerLu::new(1);
    let (x, st) = run(&mut s, &a, &b).unwrap();
    check_solution(&a, &x, &xs, &b, &st, "LU");
    assert_eq!(st.iterations, 1);
    assert_eq!(s.analyses(), 1);
}

#[test]
fn lu_solves_nonsymmetric_convection_diffusion() {
    // Strong convection (cell Péclet 1.6 / 0.8): clearly nonsymmetric, not an M-matrix.
    let a = conv_diff(50, 3.2, -1.6, 0.0);
    let k01 = a.find(0, 1).unwrap();
    let k10 = a.find(1, 0).unwrap();
    assert!((a.values[k01] - a.values[k10]).abs() > 1.0, "matrix must be nonsymmetric");
    let xs = x_star(a.nrows);
    let b = rhs_of(&a, &xs);
    for structure in [FactorStructure::Auto, FactorStructure::FaerChoice, FactorStructure::Simplicial, FactorStructure::Supernodal] {
        let mut s = FaerLu::new(1).with_structure(structure);
        let (x, st) = run(&mut s, &a, &b).unwrap();
        check_solution(&a, &x, &xs, &b, &st, &format!("LU {structure:?} (nonsymmetric)"));
    }
}

#[test]
fn cholesky_solves_laplacian() {
    let a = laplacian(50);
    let xs = x_star(a.nrows);
    let b = rhs_of(&a, &xs);
    for structure in [FactorStructure::Auto, FactorStructure::FaerChoice, FactorStructure::Simplicial, FactorStructure::Supernodal] {
        let mut s = FaerCholesky::new(1).with_structure(structure);
        let (x, st) = run(&mut s, &a, &b).unwrap();
        check_solution(&a, &x, &xs, &b, &st, &format!("Cholesky {structure:?}"));
        assert_eq!(s.kind(), Some(CholeskyKind::Llt));
        assert_eq!(s.analyses(), 1);
        // the default is the supernodal kernels (faer's own choice would take the simplicial
        // ones for this matrix: its fill is small)
        match structure {
            FactorStructure::Auto | FactorStructure::Supernodal => assert_eq!(s.is_supernodal(), Some(true), "{structure:?}"),
            FactorStructure::FaerChoice | FactorStructure::Simplicial => assert_eq!(s.is_supernodal(), Some(false), "{structure:?}"),
        }
    }
}

#[test]
fn pcg_jacobi_and_ic0_solve_laplacian_ic0_needs_fewer_iterations() {
    let a = laplacian(50);
    let xs = x_star(a.nrows);
    let b = rhs_of(&a, &xs);
    let mut its = Vec::new();
    for pre in [Preconditioner::Jacobi, Preconditioner::Ic0] {
        let mut s = Pcg::new(pre, 1e-10, 2000);
        let (x, st) = run(&mut s, &a, &b).unwrap();
        check_solution(&a, &x, &xs, &b, &st, &format!("PCG {pre:?}"));
        assert!(st.iterations > 1);
        assert_eq!(s.ic_shift(), 0.0, "the Laplacian needs no IC(0) shift");
        its.push(st.iterations);
    }
    assert!(its[1] < its[0], "IC(0) took {} iterations, Jacobi {}", its[1], its[0]);
}

#[test]
fn make_solver_builds_every_kind() {
    let a = laplacian(20);
    let xs = x_star(a.nrows);
    let b = rhs_of(&a, &xs);
    for kind in [LinearSolverKind::Lu, LinearSolverKind::Cholesky, LinearSolverKind::Pcg] {
        for preconditioner in [Preconditioner::Jacobi, Preconditioner::Ic0] {
            let opts = SolverOptions { kind, preconditioner, ..Default::default() };
            let mut s = make_solver(&opts);
            let (x, st) = run(s.as_mut(), &a, &b).unwrap();
            check_solution(&a, &x, &xs, &b, &st, s.name());
        }
    }
}

/// Same pattern, new values: scale and make the diagonal heavier.
fn revalue(a: &CsrMatrix, seed: f64) -> CsrMatrix {
    let mut a2 = a.clone();
    for i in 0..a2.nrows {
        for k in a2.row_ptr[i]..a2.row_ptr[i + 1] {
            let j = a2.col_idx[k];
            a2.values[k] *= 1.5;
            if i == j {
                a2.values[k] += seed * (1.0 + (i % 7) as f64);
            }
        }
    }
    a2
}

#[test]
fn symbolic_analysis_is_reused_for_new_values_and_redone_for_new_patterns() {
    let a = laplacian(30);
    let xs = x_star(a.nrows);
    fn exercise<S: LinearSolver>(mut s: S, analyses: impl Fn(&S) -> usize, a: &CsrMatrix, xs: &[f64]) {
        let name = s.name().to_string();
        s.analyze(a).unwrap();
        assert_eq!(analyses(&s), 1);
        // analyze again with the same pattern: no new symbolic work.
        s.analyze(a).unwrap();
        assert_eq!(analyses(&s), 1, "{name}: analyze repeated for an unchanged pattern");
        for (step, seed) in [0.0, 0.3, 2.0, 0.01].into_iter().enumerate() {
            let a2 = revalue(a, seed);
            assert_eq!(a2.pattern_id, a.pattern_id);
            let b = rhs_of(&a2, xs);
            s.factor(&a2).unwrap();
            let mut x = vec![0.0; a.nrows];
            let st = s.solve(&a2, &b, &mut x).unwrap();
            check_solution(&a2, &x, xs, &b, &st, &format!("{name} refactor {step}"));
            assert_eq!(analyses(&s), 1, "{name}: symbolic analysis redone for new values");
        }
        // A new pattern id (same structure, rebuilt) triggers a new analysis inside factor.
        let rebuilt = {
            let rows: Vec<Vec<usize>> =
                (0..a.nrows).map(|i| a.col_idx[a.row_ptr[i]..a.row_ptr[i + 1]].to_vec()).collect();
            let mut r = CsrMatrix::from_rows(a.ncols, &rows);
            r.values.copy_from_slice(&a.values);
            r
        };
        assert_ne!(rebuilt.pattern_id, a.pattern_id);
        let b = rhs_of(&rebuilt, xs);
        s.factor(&rebuilt).unwrap();
        let mut x = vec![0.0; a.nrows];
        let st = s.solve(&rebuilt, &b, &mut x).unwrap();
        check_solution(&rebuilt, &x, xs, &b, &st, &format!("{name} new pattern id"));
        assert_eq!(analyses(&s), 2, "{name}: new pattern id must trigger re-analysis");
        // A genuinely different pattern and size (explicit analyze).
        let small = laplacian(17);
        let xs2 = x_star(small.nrows);
        let b2 = rhs_of(&small, &xs2);
        s.analyze(&small).unwrap();
        s.factor(&small).unwrap();
        let mut x2 = vec![0.0; small.nrows];
        let st = s.solve(&small, &b2, &mut x2).unwrap();
        check_solution(&small, &x2, &xs2, &b2, &st, &format!("{name} new pattern"));
        assert_eq!(analyses(&s), 3);
        // Going back to the first matrix without calling analyze: factor re-analyses.
        let b = rhs_of(a, xs);
        s.factor(a).unwrap();
        let mut x = vec![0.0; a.nrows];
        let st = s.solve(a, &b, &mut x).unwrap();
        check_solution(a, &x, xs, &b, &st, &format!("{name} back to first pattern"));
        assert_eq!(analyses(&s), 4);
    }

    exercise(FaerLu::new(1), FaerLu::analyses, &a, &xs);
    exercise(FaerCholesky::new(1), FaerCholesky::analyses, &a, &xs);
    exercise(Pcg::new(Preconditioner::Jacobi, 1e-10, 2000), Pcg::analyses, &a, &xs);
    exercise(Pcg::new(Preconditioner::Ic0, 1e-10, 2000), Pcg::analyses, &a, &xs);
}

#[test]
fn pattern_id_zero_matrices_are_compared_by_structure() {
    // A hand-made matrix with pattern_id 0: the solvers must compare the pattern itself.
    let mut a = laplacian(12);
    a.pattern_id = 0;
    let xs = x_star(a.nrows);
    let b = rhs_of(&a, &xs);
    let mut s = FaerLu::new(1);
    let (x, st) = run(&mut s, &a, &b).unwrap();
    check_solution(&a, &x, &xs, &b, &st, "LU id 0");
    let a2 = revalue(&a, 0.5);
    let b2 = rhs_of(&a2, &xs);
    s.factor(&a2).unwrap();
    let mut x2 = vec![0.0; a.nrows];
    let st = s.solve(&a2, &b2, &mut x2).unwrap();
    check_solution(&a2, &x2, &xs, &b2, &st, "LU id 0 revalued");
    assert_eq!(s.analyses(), 1);
    // Different structure, still id 0 and same nnz count is impossible here; use another size.
    let mut c = conv_diff(12, 1.0, 0.5, 0.0);
    c.pattern_id = 0;
    // Same dimension and same pattern as `a` (5-point stencil) → no re-analysis needed.
    s.factor(&c).unwrap();
    assert_eq!(s.analyses(), 1);
    // Drop one off-diagonal pair: same dimension, different pattern, id 0 → re-analysis.
    let mut entries: Vec<Vec<(usize, f64)>> = (0..a.nrows)
        .map(|i| (a.row_ptr[i]..a.row_ptr[i + 1]).map(|k| (a.col_idx[k], a.values[k])).collect())
        .collect();
    entries[0].retain(|e| e.0 != 1);
    entries[1].retain(|e| e.0 != 0);
    let mut d = csr_from_entries(a.nrows, &entries);
    d.pattern_id = 0;
    let bd = rhs_of(&d, &xs);
    s.factor(&d).unwrap();
    let mut xd = vec![0.0; a.nrows];
    let st = s.solve(&d, &bd, &mut xd).unwrap();
    check_solution(&d, &xd, &xs, &bd, &st, "LU id 0 new structure");
    assert_eq!(s.analyses(), 2);
}

#[test]
fn cholesky_on_indefinite_symmetric_matrix_uses_ldlt() {
    // Shifted Laplacian (Helmholtz-like): eigenvalues 4 − 2cos(iπ/31) − 2cos(jπ/31) − σ straddle 0.
    let a = conv_diff(30, 0.0, 0.0, 1.2345);
    let xs = x_star(a.nrows);
    let b = rhs_of(&a, &xs);
    for structure in [FactorStructure::Auto, FactorStructure::FaerChoice, FactorStructure::Simplicial, FactorStructure::Supernodal] {
        let mut s = FaerCholesky::new(1).with_structure(structure);
        // (no zero pivot: LDLᵀ without pivoting holds, on either structure)
        let (x, st) = run(&mut s, &a, &b).unwrap_or_else(|e| panic!("{structure:?}: {e}"));
        check_solution(&a, &x, &xs, &b, &st, &format!("indefinite Cholesky {structure:?}"));
        assert_eq!(s.kind(), Some(CholeskyKind::Ldlt), "{structure:?}");
    }
}

/// `LinearSolver::definite` (what the barrier's Newton uses to decide on shifting an
/// indefinite tangent): a Cholesky factorisation of the Laplacian (eigenvalues > 0) reports
/// positive definite; of the shifted Laplacian above (eigenvalues on both sides of 0), not;
/// LU and PCG cannot tell; nothing is reported before a factorisation.
#[test]
fn cholesky_reports_whether_the_matrix_is_definite() {
    let spd = laplacian(20);
    let indefinite = conv_diff(30, 0.0, 0.0, 1.2345);
    for structure in [FactorStructure::Simplicial, FactorStructure::Supernodal] {
        let mut s = FaerCholesky::new(1).with_structure(structure);
        assert_eq!(s.definite(), None, "before any factorisation");
        s.analyze(&spd).unwrap();
        s.factor(&spd).unwrap();
        assert_eq!(s.definite(), Some(true), "Laplacian, {structure:?}");
        s.analyze(&indefinite).unwrap();
        if s.factor(&indefinite).is_ok() {
            assert_eq!(s.definite(), Some(false), "shifted Laplacian, {structure:?}");
        }
    }
    let mut lu = FaerLu::new(1);
    lu.factor(&spd).unwrap();
    assert_eq!(lu.definite(), None);
    let mut pcg = Pcg::new(Preconditioner::Jacobi, 1e-10, 2000);
    pcg.analyze(&spd).unwrap();
    pcg.factor(&spd).unwrap();
    assert_eq!(pcg.definite(), None);
}

/// `LinearSolver::factor_definite` (the probe of the barrier's descent): on the Laplacian it
/// factors and the solve is exact (to the residual tolerance of this file); on the shifted
/// Laplacian (eigenvalues on both sides of 0) it answers false and holds no factorisation, so
/// a solve is refused instead of using a stale or indefinite one; the plain `factor` of the same
/// matrix still falls back to an indefinite factorisation. Solvers that cannot tell (LU) factor
/// and answer true.
#[test]
fn factor_definite_factors_definite_matrices_only() {
    let spd = laplacian(20);
    let xs = x_star(spd.nrows);
    let b = rhs_of(&spd, &xs);
    let indefinite = conv_diff(20, 0.0, 0.0, 1.2345);
    for structure in [FactorStructure::Simplicial, FactorStructure::Supernodal] {
        let mut s = FaerCholesky::new(1).with_structure(structure);
        assert!(s.factor_definite(&spd).unwrap(), "Laplacian, {structure:?}");
        assert_eq!(s.definite(), Some(true));
        let mut x = vec![0.0; spd.nrows];
        let st = s.solve(&spd, &b, &mut x).unwrap();
        check_solution(&spd, &x, &xs, &b, &st, &format!("factor_definite, {structure:?}"));
        // the same pattern with indefinite values: refused, and nothing to solve with
        assert!(!s.factor_definite(&indefinite).unwrap(), "shifted Laplacian, {structure:?}");
        assert_eq!(s.definite(), None, "no factorisation held after a refused probe");
        assert!(s.solve(&indefinite, &b, &mut x).is_err(), "a solve after a refused probe is an error");
        if s.factor(&indefinite).is_ok() {
            assert_eq!(s.definite(), Some(false), "the plain factorisation falls back, {structure:?}");
        }
    }
    let mut lu = FaerLu::new(1);
    assert!(lu.factor_definite(&indefinite).unwrap(), "LU cannot tell: it factors and answers true");
    let mut x = vec![0.0; spd.nrows];
    let bi = rhs_of(&indefinite, &xs);
    let st = lu.solve(&indefinite, &bi, &mut x).unwrap();
    check_solution(&indefinite, &x, &xs, &bi, &st, "LU after factor_definite");
}

#[test]
fn cholesky_on_saddle_point_matrix_does_not_panic() {
    // [[K, Bᵀ], [B, 0]]: zero diagonal block, needs pivoting. Either a correct answer or Singular.
    let m = 10;
    let k = laplacian(m);
    let nk = k.nrows;
    let nc = m; // constraints: u(row 0, j) − u(row 1, j) = 0
    let n = nk + nc;
    let mut entries: Vec<Vec<(usize, f64)>> =
        (0..nk).map(|i| (k.row_ptr[i]..k.row_ptr[i + 1]).map(|p| (k.col_idx[p], k.values[p])).collect()).collect();
    entries.resize(n, Vec::new());
    for c in 0..nc {
        let (u0, u1, row) = (c, m + c, nk + c);
        entries[row].push((u0, 1.0));
        entries[row].push((u1, -1.0));
        entries[u0].push((row, 1.0));
        entries[u1].push((row, -1.0));
        entries[row].push((row, 0.0)); // explicit zero diagonal in the pattern
    }
    let a = csr_from_entries(n, &entries);
    let xs = x_star(n);
    let b = rhs_of(&a, &xs);
    for structure in [FactorStructure::Auto, FactorStructure::FaerChoice, FactorStructure::Simplicial, FactorStructure::Supernodal] {
        let mut s = FaerCholesky::new(1).with_structure(structure);
        match run(&mut s, &a, &b) {
            Ok((x, st)) => check_solution(&a, &x, &xs, &b, &st, &format!("saddle Cholesky {structure:?}")),
            Err(LinalgError::Singular(_)) => {}
            Err(e) => panic!("unexpected error {e}"),
        }
    }
    // LU handles it.
    let mut lu = FaerLu::new(1);
    let (x, st) = run(&mut lu, &a, &b).unwrap();
    check_solution(&a, &x, &xs, &b, &st, "saddle LU");
}

#[test]
fn two_threads_match_one_thread() {
    let spd = laplacian(60);
    let nonsym = conv_diff(60, 1.0, 2.0, 0.0);
    let xs = x_star(spd.nrows);
    for structure in [FactorStructure::Auto, FactorStructure::Supernodal] {
        let b = rhs_of(&nonsym, &xs);
        let (x1, _) = run(&mut FaerLu::new(1).with_structure(structure), &nonsym, &b).unwrap();
        let (x2, st2) = run(&mut FaerLu::new(2).with_structure(structure), &nonsym, &b).unwrap();
        check_solution(&nonsym, &x2, &xs, &b, &st2, "LU 2 threads");
        let d = rel_err(&x2, &x1);
        assert!(d <= 1e-12, "LU {structure:?}: threads 2 vs 1 differ by {d:e}");

        let b = rhs_of(&spd, &xs);
        let (x1, _) = run(&mut FaerCholesky::new(1).with_structure(structure), &spd, &b).unwrap();
        let (x2, st2) = run(&mut FaerCholesky::new(2).with_structure(structure), &spd, &b).unwrap();
        check_solution(&spd, &x2, &xs, &b, &st2, "Cholesky 2 threads");
        let d = rel_err(&x2, &x1);
        assert!(d <= 1e-12, "Cholesky {structure:?}: threads 2 vs 1 differ by {d:e}");
    }
    // Through the options (which factorise on one thread whatever `threads` says: the run's
    // threads assemble, `linalg::make_solver_with`).
    let b = rhs_of(&spd, &xs);
    let opts = SolverOptions { kind: LinearSolverKind::Cholesky, threads: 2, ..Default::default() };
    let (x, st) = run(make_solver(&opts).as_mut(), &spd, &b).unwrap();
    check_solution(&spd, &x, &xs, &b, &st, "make_solver threads 2");
}

#[test]
fn singular_matrices_give_errors_not_panics() {
    // (a) Structurally singular: an empty row/column (only a zero diagonal kept in the pattern).
    let mut a = laplacian(10);
    for i in 0..a.nrows {
        for k in a.row_ptr[i]..a.row_ptr[i + 1] {
            if i == 7 || a.col_idx[k] == 7 {
                a.values[k] = 0.0;
            }
        }
    }
    // (b) Numerically singular 2×2 with a full pattern: [[1, 1], [1, 1]].
    let ones = csr_from_entries(2, &[vec![(0, 1.0), (1, 1.0)], vec![(0, 1.0), (1, 1.0)]]);
    // (c) Pure-Neumann Laplacian (rows sum to zero, null space = constants) with an inconsistent b.
    let m = 12;
    let mut neumann = laplacian(m);
    for i in 0..neumann.nrows {
        let mut off = 0.0;
        let mut dk = 0;
        for k in neumann.row_ptr[i]..neumann.row_ptr[i + 1] {
            if neumann.col_idx[k] == i {
                dk = k;
            } else {
                off += neumann.values[k];
            }
        }
        neumann.values[dk] = -off;
    }
    let cases: Vec<(&str, &CsrMatrix)> = vec![("zero row", &a), ("ones", &ones), ("neumann", &neumann)];
    for (what, m) in cases {
        let b: Vec<f64> = (0..m.nrows).map(|i| 1.0 + i as f64).collect();
        let solvers: Vec<Box<dyn LinearSolver>> = vec![
            Box::new(FaerLu::new(1)),
            Box::new(FaerLu::new(1).with_structure(FactorStructure::Supernodal)),
            Box::new(FaerCholesky::new(1)),
            Box::new(FaerCholesky::new(1).with_structure(FactorStructure::Supernodal)),
            Box::new(Pcg::new(Preconditioner::Jacobi, 1e-10, 500)),
            Box::new(Pcg::new(Preconditioner::Ic0, 1e-10, 500)),
        ];
        for mut s in solvers {
            let r = run(s.as_mut(), m, &b);
            assert!(r.is_err(), "{what}: {} returned Ok({:?})", s.name(), r.map(|r| r.1));
        }
    }
}

#[test]
fn pcg_zero_rhs_initial_guess_and_non_convergence() {
    let a = laplacian(30);
    let xs = x_star(a.nrows);
    let b = rhs_of(&a, &xs);
    let mut s = Pcg::new(Preconditioner::Ic0, 1e-10, 1000);
    s.analyze(&a).unwrap();
    s.factor(&a).unwrap();
    // b = 0 → x = 0 immediately, whatever the initial guess.
    let mut x = vec![3.0; a.nrows];
    let st = s.solve(&a, &vec![0.0; a.nrows], &mut x).unwrap();
    assert_eq!(st.iterations, 0);
    assert!(x.iter().all(|&v| v == 0.0));
    // Exact initial guess → zero iterations.
    let mut x = xs.clone();
    let st = s.solve(&a, &b, &mut x).unwrap();
    assert_eq!(st.iterations, 0);
    // A good initial guess needs fewer iterations than a zero one.
    let mut x0 = vec![0.0; a.nrows];
    let cold = s.solve(&a, &b, &mut x0).unwrap().iterations;
    let mut xg: Vec<f64> = xs.iter().map(|v| v * (1.0 + 1e-6)).collect();
    let warm = s.solve(&a, &b, &mut xg).unwrap().iterations;
    assert!(warm < cold, "warm {warm} vs cold {cold}");
    // Too few iterations → NotConverged with the iteration count and the true residual.
    let mut t = Pcg::new(Preconditioner::Jacobi, 1e-10, 3);
    t.analyze(&a).unwrap();
    t.factor(&a).unwrap();
    let mut x = vec![0.0; a.nrows];
    match t.solve(&a, &b, &mut x) {
        Err(LinalgError::NotConverged { iterations, residual, tol }) => {
            assert_eq!(iterations, 3);
            assert_eq!(tol, 1e-10);
            assert!((residual - rel_residual(&a, &x, &b)).abs() < 1e-12);
            assert!(residual > 1e-10);
        }
        other => panic!("expected NotConverged, got {other:?}"),
    }
}

#[test]
fn direct_solvers_zero_rhs_and_misuse() {
    let a = laplacian(8);
    let mut lu = FaerLu::new(1);
    let mut x = vec![0.0; a.nrows];
    assert!(matches!(lu.solve(&a, &vec![1.0; a.nrows], &mut x), Err(LinalgError::NotAnalyzed)));
    lu.analyze(&a).unwrap();
    assert!(lu.solve(&a, &vec![1.0; a.nrows], &mut x).is_err(), "solve before factor must fail");
    lu.factor(&a).unwrap();
    let mut x = vec![5.0; a.nrows];
    let st = lu.solve(&a, &vec![0.0; a.nrows], &mut x).unwrap();
    assert_eq!(st.relative_residual, 0.0);
    assert!(x.iter().all(|&v| v == 0.0));
    assert!(lu.solve(&a, &[1.0, 2.0], &mut x).is_err(), "wrong b length must fail");
    let mut ch = FaerCholesky::new(1);
    assert!(matches!(ch.solve(&a, &vec![1.0; a.nrows], &mut x), Err(LinalgError::NotAnalyzed)));
    let mut rect = CsrMatrix::from_rows(3, &[vec![0, 1], vec![2]]);
    rect.values = vec![1.0, 2.0, 3.0];
    assert!(lu.analyze(&rect).is_err());
    assert!(ch.analyze(&rect).is_err());
}

#[test]
fn wrappers_agree_with_bare_faer_calls() {
    let spd = laplacian(40);
    let nonsym = conv_diff(40, 2.0, 1.0, 0.0);
    let xs = x_star(spd.nrows);

    let csc = to_faer_csc(&nonsym);
    assert_eq!(csc.nrows(), nonsym.nrows);
    assert_eq!(csc.compute_nnz(), nonsym.nnz());
    // Spot-check the transposition: entry (0, 1) of the CSR matrix is row 0 of column 1.
    let col1_rows = csc.symbolic().row_idx_of_col_raw(1);
    let col1_vals = csc.val_of_col(1);
    let p = col1_rows.iter().position(|&r| r == 0).unwrap();
    assert_eq!(col1_vals[p], nonsym.values[nonsym.find(0, 1).unwrap()]);

    let b = rhs_of(&nonsym, &xs);
    let bare = bare_faer_lu_solve(&nonsym, &b);
    assert!(rel_residual(&nonsym, &bare, &b) <= RES_TOL);
    let (x, _) = run(&mut FaerLu::new(1), &nonsym, &b).unwrap();
    assert!(rel_err(&x, &bare) <= 1e-12);

    let b = rhs_of(&spd, &xs);
    let bare = bare_faer_cholesky_solve(&spd, &b);
    assert!(rel_residual(&spd, &bare, &b) <= RES_TOL);
    let (x, _) = run(&mut FaerCholesky::new(1), &spd, &b).unwrap();
    assert!(rel_err(&x, &bare) <= 1e-12);
}

#[test]
fn metis_nested_dissection_ordering_matches_amd() {
    // SPD 5-point Laplacian on a 40 × 40 grid (1600 unknowns): METIS's nested-dissection order
    // is a permutation of the unknowns, and the Cholesky solve with it gives the same answer as
    // with AMD (1e-10 relative; both are ~1e-15 from the exact solution on this
    // well-conditioned matrix). On a grid, nested dissection fills no worse than AMD give or
    // take 30 % (asymptotically both are O(n log n)).
    use mpfem::linalg::direct::{cholesky_factor_nnz, FillOrdering};
    let a = laplacian(40);
    let n = a.nrows;
    let g = partition::graph_of_pattern(n, &a.row_ptr, &a.col_idx).unwrap();
    assert_eq!(g.n_edges(), 2 * 40 * 39);
    let (perm, iperm) = partition::metis_nd(&g).unwrap();
    let mut seen = vec![false; n];
    for (k, &v) in perm.iter().enumerate() {
        assert!(!seen[v], "vertex {v} twice");
        seen[v] = true;
        assert_eq!(iperm[v], k);
    }
    let xs = x_star(n);
    let b = rhs_of(&a, &xs);
    let solve = |o: FillOrdering| {
        let mut s = FaerCholesky::new(1).with_ordering(o);
        assert_eq!(s.ordering(), o);
        s.analyze(&a).unwrap();
        s.factor(&a).unwrap();
        assert_eq!(s.kind(), Some(CholeskyKind::Llt));
        let mut x = vec![0.0; n];
        let st = s.solve(&a, &b, &mut x).unwrap();
        assert!(st.relative_residual < RES_TOL);
        x
    };
    let x_amd = solve(FillOrdering::Amd);
    let x_nd = solve(FillOrdering::Metis);
    let diff = x_amd.iter().zip(&x_nd).map(|(p, q)| (p - q).powi(2)).sum::<f64>().sqrt();
    let norm = x_amd.iter().map(|p| p * p).sum::<f64>().sqrt();
    assert!(diff <= 1e-10 * norm, "METIS and AMD solutions differ by {:.2e}", diff / norm);
    let (f_amd, f_nd) = (
        cholesky_factor_nnz(&a, FillOrdering::Amd).unwrap(),
        cholesky_factor_nnz(&a, FillOrdering::Metis).unwrap(),
    );
    assert!(f_nd >= n && f_amd >= n);
    assert!(10 * f_nd <= 13 * f_amd, "fill: METIS {f_nd}, AMD {f_amd}");
    // The indefinite fallback runs on the METIS structure too (the shifted Laplacian of
    // `cholesky_on_indefinite_symmetric_matrix_uses_ldlt_or_reports_singular`): a correct answer
    // from LDLᵀ / LBLᵀ, or Singular — never a panic or a wrong answer.
    let a = conv_diff(30, 0.0, 0.0, 1.2345);
    let xs = x_star(a.nrows);
    let b = rhs_of(&a, &xs);
    let mut s = FaerCholesky::new(1).with_ordering(FillOrdering::Metis);
    match run(&mut s, &a, &b) {
        Ok((x, st)) => {
            check_solution(&a, &x, &xs, &b, &st, "indefinite Cholesky, METIS ordering");
            assert!(matches!(s.kind(), Some(CholeskyKind::Ldlt | CholeskyKind::Lblt)), "{:?}", s.kind());
        }
        Err(LinalgError::Singular(_)) => {}
        Err(e) => panic!("unexpected error {e}"),
    }
}

/// `SolverOptions::singular_tol` decides when a direct solve that refinement cannot bring to
/// round-off is called singular. A 2 × 2 positive definite matrix with eigenvalues 1 and 1e-12
/// (eigenvectors at 45°) and a right-hand side along its soft eigenvector: the solution is
/// 1e12 times the right-hand side, and forming b − Ax cancels digits, so the relative residual
/// of an exact-as-floating-point solve is far above round-off (about 1e-5, a closed-form
/// consequence of ε‖A‖‖x‖/‖b‖ ≈ 1e-16 · 1e12). With the linear algebra's default limit (1e-6)
/// that is an error; with the limit the Newton solves use (1e-3,
/// `mpfem::solver::NEWTON_SOLVE_TOL`) the same solve is returned, and its answer is the exact
/// solution to the accuracy the conditioning allows (1e-3 relative).
#[test]
fn the_singular_limit_of_a_direct_solve_is_an_option() {
    let lam = 1e-12;
    let a = csr_from_entries(2, &[vec![(0, 0.5 * (1.0 + lam)), (1, 0.5 * (1.0 - lam))], vec![(0, 0.5 * (1.0 - lam)), (1, 0.5 * (1.0 + lam))]]);
    let c = 0.5f64.sqrt();
    let b = [-c, c];
    for kind in [LinearSolverKind::Cholesky, LinearSolverKind::Lu] {
        let loose = SolverOptions { kind, singular_tol: mpfem::solver::NEWTON_SOLVE_TOL, ..Default::default() };
        let (x, st) = run(make_solver(&loose).as_mut(), &a, &b).unwrap_or_else(|e| panic!("{kind:?} with the Newton limit: {e}"));
        assert!(st.relative_residual > 1e-6 && st.relative_residual <= 1e-3, "{kind:?}: relative residual {:e} (the check would be vacuous below 1e-6)", st.relative_residual);
        let exact = [-c / lam, c / lam];
        for i in 0..2 {
            assert!((x[i] / exact[i] - 1.0).abs() < 1e-3, "{kind:?}: x[{i}] = {} against {}", x[i], exact[i]);
        }
        let strict = SolverOptions { kind, ..Default::default() };
        assert!(matches!(run(make_solver(&strict).as_mut(), &a, &b), Err(LinalgError::Singular(_))), "{kind:?}: the default limit of 1e-6 must report the same solve singular");
    }
}

/// Where LDLᵀ without pivoting meets a zero pivot (a tridiagonal matrix with a zero diagonal:
/// symmetric, indefinite, nonsingular for an even size), the supernodal structure falls back
/// on faer's Bunch–Kaufman LBLᵀ, whose 2 × 2 pivots solve it to round-off; the simplicial
/// structure has no such fallback and says the matrix needs the LU solver.
#[test]
fn a_zero_pivot_is_factored_by_lblt_on_the_supernodal_structure() {
    let n = 200;
    let entries: Vec<Vec<(usize, f64)>> = (0..n)
        .map(|i| {
            let mut row = vec![(i, 0.0)];
            if i > 0 {
                row.push((i - 1, 1.0));
            }
            if i + 1 < n {
                row.push((i + 1, 1.0));
            }
            row
        })
        .collect();
    let a = csr_from_entries(n, &entries);
    let xs = x_star(n);
    let b = rhs_of(&a, &xs);
    for structure in [FactorStructure::Auto, FactorStructure::Supernodal] {
        let mut s = FaerCholesky::new(1).with_structure(structure);
        let (x, st) = run(&mut s, &a, &b).unwrap_or_else(|e| panic!("{structure:?}: {e}"));
        check_solution(&a, &x, &xs, &b, &st, &format!("zero-diagonal tridiagonal, {structure:?}"));
        assert_eq!(s.kind(), Some(CholeskyKind::Lblt), "{structure:?}");
        assert_eq!(s.definite(), Some(false));
    }
    let mut s = FaerCholesky::new(1).with_structure(FactorStructure::Simplicial);
    match run(&mut s, &a, &b) {
        Err(LinalgError::Singular(m)) => assert!(m.contains("LU solver"), "{m}"),
        other => panic!("simplicial: expected a singular-matrix error, got {:?}", other.map(|(_, st)| st.relative_residual)),
    }
}

/// A matrix with an entry that is not finite is refused by the Cholesky factorisation with an
/// error naming an entry, on either structure (faer is never handed NaN).
#[test]
fn cholesky_refuses_a_matrix_entry_that_is_not_finite() {
    for structure in [FactorStructure::Simplicial, FactorStructure::Supernodal] {
        let mut a = laplacian(10);
        let mut s = FaerCholesky::new(1).with_structure(structure);
        s.analyze(&a).unwrap();
        s.factor(&a).unwrap();
        let p = a.find(3, 4).expect("an off-diagonal entry");
        let q = a.find(4, 3).expect("its transpose");
        a.values[p] = f64::NAN;
        a.values[q] = f64::NAN;
        let e = s.factor(&a).expect_err("a NaN entry");
        assert!(e.to_string().contains("not finite"), "{structure:?}: {e}");
    }
}
