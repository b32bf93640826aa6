//! The wrapper against closed-form answers, on one process (PETSc starts MPI itself):
//! - the 1D Dirichlet Laplacian tridiag(−1, 2, −1) of order n solved with MUMPS's Cholesky,
//!   MUMPS's LU and CG + GAMG for a manufactured solution (b = A x*): x* to 1e-10 relative
//!   for the direct solves, to 1e-6 for CG at rtol 1e-9 (κ(A) ≈ 4n²/π² ≈ 4e3 here);
//! - the inertia of A − s I from MUMPS's LDLᵀ: its eigenvalues are 2 − 2 cos(kπ/(n+1)),
//!   k = 1..n, so the count below s is known exactly;
//! - a singular matrix (a zero row and column): its zero eigenvalue counted by the LDLᵀ,
//!   and its LU an error, not a panic;
//! - the near-null space of the constant: one vector kept, the zero vector dropped.
//!
//! One test function: PETSc starts once per process.

use petsc::{GatherAll, Ksp, Matrix, Petsc, Vector};

const N: usize = 200;

/// The rows of tridiag(−1, d, −1) of order n (ascending columns).
fn tridiagonal(n: usize, d: f64) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let (mut rp, mut cols, mut vals) = (vec![0], Vec::new(), Vec::new());
    for i in 0..n {
        if i > 0 {
            cols.push(i - 1);
            vals.push(-1.0);
        }
        cols.push(i);
        vals.push(d);
        if i + 1 < n {
            cols.push(i + 1);
            vals.push(-1.0);
        }
        rp.push(cols.len());
    }
    (rp, cols, vals)
}

fn mul(rp: &[usize], cols: &[usize], vals: &[f64], x: &[f64]) -> Vec<f64> {
    (0..rp.len() - 1).map(|i| (rp[i]..rp[i + 1]).map(|k| vals[k] * x[cols[k]]).sum()).collect()
}

fn solve_with(a: &Matrix, b: &[f64], ksp_type: &str, pc_type: &str, package: Option<&str>) -> (Vec<f64>, Ksp) {
    let mut ksp = Ksp::new().unwrap();
    ksp.set_defaults(ksp_type, pc_type, package, 1e-9, 10_000).unwrap();
    ksp.set_operator(a).unwrap();
    ksp.set_from_options().unwrap();
    ksp.set_up().unwrap();
    let mut bv = Vector::like_rows(a).unwrap();
    bv.set_local(b).unwrap();
    let mut xv = Vector::like_rows(a).unwrap();
    let info = ksp.solve(&bv, &mut xv).unwrap();
    assert!(info.reason > 0, "{ksp_type}+{pc_type}: diverged, reason {}", info.reason);
    let mut g = GatherAll::new(&xv).unwrap();
    (g.gather(&xv).unwrap(), ksp)
}

fn rel_err(x: &[f64], y: &[f64]) -> f64 {
    let d: f64 = x.iter().zip(y).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
    d / y.iter().map(|v| v * v).sum::<f64>().sqrt()
}

#[test]
fn petsc_solves_and_reports_inertia() {
    let env = Petsc::initialize("-mat_mumps_icntl_13 1 -mat_mumps_icntl_24 1").expect("PETSc starts");
    assert_eq!(Petsc::rank_size().unwrap(), (0, 1));
    let (rp, cols, vals) = tridiagonal(N, 2.0);
    let x_true: Vec<f64> = (0..N).map(|i| ((i as f64) * 0.37).sin() + 0.1 * i as f64).collect();
    let b = mul(&rp, &cols, &vals, &x_true);
    {
        let mut a = Matrix::from_local_csr(N, &rp, &cols, &vals).unwrap();
        a.set_symmetric().unwrap();
        for (kt, pt, pkg, tol) in [("preonly", "cholesky", Some("mumps"), 1e-10), ("preonly", "lu", Some("mumps"), 1e-10), ("cg", "gamg", None, 1e-6)] {
            let (x, ksp) = solve_with(&a, &b, kt, pt, pkg);
            let e = rel_err(&x, &x_true);
            assert!(e < tol, "{kt}+{pt}: relative error {e:.2e} (tolerance {tol:.0e})");
            let (k, p, package) = ksp.types().unwrap();
            assert_eq!((k.as_str(), p.as_str(), package.as_deref()), (kt, pt, pkg));
            // a positive definite matrix: all eigenvalues positive for the LDLᵀ, no inertia
            // from the others
            let inertia = ksp.inertia().unwrap();
            if pt == "cholesky" {
                assert_eq!(inertia, Some((0, 0, N)));
            } else {
                assert_eq!(inertia, None);
            }
        }
        // the constant vector orthonormalised, the zero vector dropped
        let mut ones = Vector::like_rows(&a).unwrap();
        ones.set_local(&vec![3.0; N]).unwrap();
        let zero = Vector::like_rows(&a).unwrap();
        assert_eq!(a.set_near_null_space(vec![ones, zero]).unwrap(), 1);

        // new values on the same pattern: A − s I with s = 0.9 (between eigenvalues; at s = 1, k = 67 is a zero eigenvalue), whose
        // eigenvalues 2 − 2 cos(kπ/(n+1)) − s are negative for k < (n+1)/3
        let s = 0.9;
        let (_, _, vals_s) = tridiagonal(N, 2.0 - s);
        a.update_values(&vals_s).unwrap();
        let mut ksp = Ksp::new().unwrap();
        ksp.set_defaults("preonly", "cholesky", Some("mumps"), 1e-9, 1).unwrap();
        ksp.set_operator(&a).unwrap();
        ksp.set_from_options().unwrap();
        ksp.set_up().unwrap();
        let negative = (1..=N).filter(|&k| 2.0 - 2.0 * (k as f64 * std::f64::consts::PI / (N as f64 + 1.0)).cos() - s < 0.0).count();
        assert!(negative > 10);
        assert_eq!(ksp.inertia().unwrap(), Some((negative, 0, N - negative)));
        // wrong lengths are errors
        assert!(a.update_values(&vals_s[1..]).is_err());

        // a singular matrix (the last row and column zero): eigenvalues those of the
        // tridiagonal of order n − 1 (all positive) and one zero; with null-pivot detection
        // MUMPS's LDLᵀ counts it, and without, its LU fails (an error, not a panic)
        let mut vz = vals.clone();
        let last = rp[N - 1];
        for v in &mut vz[last..] {
            *v = 0.0;
        }
        vz[last - 1] = 0.0;
        let az = Matrix::from_local_csr(N, &rp, &cols, &vz).unwrap();
        let mut ksp = Ksp::new().unwrap();
        ksp.set_defaults("preonly", "cholesky", Some("mumps"), 1e-9, 1).unwrap();
        ksp.set_operator(&az).unwrap();
        ksp.set_from_options().unwrap();
        ksp.set_up().unwrap();
        assert_eq!(ksp.inertia().unwrap(), Some((0, 1, N - 1)));
        petsc::insert_options("-mat_mumps_icntl_24 0").unwrap();
        assert!(petsc::has_option("-mat_mumps_icntl_24").unwrap());
        let mut ksp = Ksp::new().unwrap();
        ksp.set_defaults("preonly", "lu", Some("mumps"), 1e-9, 1).unwrap();
        ksp.set_operator(&az).unwrap();
        ksp.set_from_options().unwrap();
        let r = ksp.set_up();
        let e = r.expect_err("a singular matrix factorised by LU");
        assert!(e.to_string().contains("KSPSetUp"), "{e}");
    }
    drop(env);
}
