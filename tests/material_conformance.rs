//! Conformance battery for every constitutive law behind `ConstitutiveLaw` (the contract in
//! `src/material/mod.rs`). One generic function, [`battery`], is applied to each law:
//!
//! (a) zero stress at F = I and at a rigid rotation F = R (virgin state); tolerance 1e-12·G
//!     (exact up to roundoff: ln I = 0).
//! (b) the spatial tangent `cc` against central finite differences of τ′ for F → F ± ε l F
//!     (history fixed) over the three symmetric basis l's and a skew l, checking
//!     cc : sym(l) = A − l τ′ − τ′ lᵀ with A = (τ′(F + εlF) − τ′(F − εlF))/(2ε), at several
//!     deformed states after a committed inelastic history (C_p⁻¹ ≠ I), including states that
//!     are plastic/creeping in the probed step. ε = 1e-6: the central-difference truncation
//!     error is O(ε²)·|∂³τ| ≈ 1e-12·G and the roundoff error O(u·|τ|/ε) ≈ 1e-16·G/1e-6 = 1e-10·G,
//!     both far below the tolerance: max entry error ≤ 1e-6 · max|cc|.
//!     (Source of the definition: the Lie derivative contract in `src/material/mod.rs`.)
//! (c) objectivity: τ′(QF) = Q τ′(F) Qᵀ and the same new history, for Q = 30°, 90°, −135°,
//!     with the same committed state; relative tolerance 1e-10 (roundoff only).
//! (d) when `symmetric_tangent()` is true, |cc_ij − cc_ji| ≤ 1e-10 · max|cc| (roundoff only).
//! (e) inverted or degenerate F (det F ≤ 0, or non-finite) gives
//!     `Err(MaterialError::InvertedElement)`, not a panic.
use mpfem::material::creep::{ASPHALT_E, ASPHALT_NU};
use mpfem::material::hardening::{aluminium_250c, ALUMINIUM_250C_E, ALUMINIUM_250C_NU};
use mpfem::material::*;
use nalgebra::Matrix3;

fn f2(a: f64, b: f64, c: f64, d: f64) -> Matrix3<f64> {
    Matrix3::new(a, b, 0.0, c, d, 0.0, 0.0, 0.0, 1.0)
}

fn rot(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    f2(c, -s, s, c)
}

fn tau_m(t: &[f64; 4]) -> Matrix3<f64> {
    Matrix3::new(t[0], t[2], 0.0, t[2], t[1], 0.0, 0.0, 0.0, t[3])
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Expect {
    Elastic,
    Inelastic,
    Any,
}

struct Case {
    name: &'static str,
    law: Material,
    dt: f64,
    /// Deformation gradients of the committed steps that build the history.
    history: Vec<Matrix3<f64>>,
    /// Probe deformation gradients (evaluated from the committed history) and what the step is.
    probes: Vec<(Matrix3<f64>, Expect)>,
}

fn inelastic(old: &MatState, new: &MatState) -> bool {
    new.eps_p > old.eps_p || new.eps_c > old.eps_c
}

fn max_abs3(m: &[[f64; 3]; 3]) -> f64 {
    m.iter().flatten().fold(0.0f64, |a, &b| a.max(b.abs()))
}

/// The generic battery (a)–(e); see the module docs for what and why.
fn battery(case: &Case) {
    let law = &case.law;
    let g = law.shear_modulus();
    let name = case.name;

    // (a) zero stress at F = I and at a rigid rotation, virgin state.
    let virgin = MatState::default();
    let inc0 = TimeIncrement {
        time: case.dt,
        dt: case.dt,
    };
    for ff in [Matrix3::identity(), rot(37.0), rot(90.0)] {
        let r = law.update(&ff, &virgin, inc0).unwrap();
        let m = r.tau.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        assert!(m <= 1e-12 * g, "{name}: stress {m:e} at a rigid motion");
        assert_eq!(r.state.eps_p, 0.0);
        assert_eq!(r.state.eps_c, 0.0);
    }

    // Committed history.
    let mut state = MatState::default();
    let mut time = 0.0;
    for ff in &case.history {
        time += case.dt;
        let r = law
            .update(ff, &state, TimeIncrement { time, dt: case.dt })
            .unwrap();
        state = r.state;
    }
    let has_history = state.eps_p > 0.0 || state.eps_c > 0.0;
    if has_history {
        let d = (0..4)
            .map(|i| (state.cp_inv[i] - MatState::default().cp_inv[i]).abs())
            .fold(0.0, f64::max);
        assert!(d > 1e-3, "{name}: history did not change C_p⁻¹");
    }
    let inc = TimeIncrement {
        time: time + case.dt,
        dt: case.dt,
    };

    let basis: [[[f64; 3]; 3]; 4] = [
        [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
        [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]],
        [[0.0, 0.5, 0.0], [0.5, 0.0, 0.0], [0.0, 0.0, 0.0]],
        [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]], // skew: must give zero
    ];
    let eps = 1e-6;
    let mut worst_fd: f64 = 0.0;
    for (ip, (ff, expect)) in case.probes.iter().enumerate() {
        let r = law.update(ff, &state, inc).unwrap();
        match expect {
            Expect::Inelastic => assert!(
                inelastic(&state, &r.state),
                "{name}: probe {ip} expected inelastic"
            ),
            Expect::Elastic => assert!(
                !inelastic(&state, &r.state),
                "{name}: probe {ip} expected elastic"
            ),
            Expect::Any => {}
        }
        let scale = max_abs3(&r.cc);
        let t = tau_m(&r.tau);

        // (b) tangent vs central finite differences of τ′.
        for (il, lb) in basis.iter().enumerate() {
            let l = Matrix3::from_fn(|i, j| lb[i][j]);
            let tp = law
                .update(&((Matrix3::identity() + l * eps) * ff), &state, inc)
                .unwrap()
                .tau;
            let tm = law
                .update(&((Matrix3::identity() - l * eps) * ff), &state, inc)
                .unwrap()
                .tau;
            let a = (tau_m(&tp) - tau_m(&tm)) / (2.0 * eps);
            let lie = a - l * t - t * l.transpose();
            let d = [l[(0, 0)], l[(1, 1)], l[(0, 1)] + l[(1, 0)]];
            let want = [(0, 0), (1, 1), (0, 1)];
            for (row, &(i, j)) in want.iter().enumerate() {
                let an: f64 = (0..3).map(|k| r.cc[row][k] * d[k]).sum();
                let err = (lie[(i, j)] - an).abs() / scale;
                worst_fd = worst_fd.max(err);
                assert!(
                    err <= 1e-6,
                    "{name}: probe {ip}, l #{il}, row {row}: FD {} vs cc {} (rel err {err:e})",
                    lie[(i, j)],
                    an
                );
            }
        }

        // (c) objectivity, same committed state.
        let tmax = r.tau.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        assert!(tmax > 0.0);
        for deg in [30.0, 90.0, -135.0] {
            let q = rot(deg);
            let rq = law.update(&(q * ff), &state, inc).unwrap();
            let rotated = q * t * q.transpose();
            let err = (tau_m(&rq.tau) - rotated).abs().max() / tmax;
            assert!(
                err <= 1e-10,
                "{name}: probe {ip}, Q = {deg}°: objectivity error {err:e}"
            );
            let cmax = r.state.cp_inv.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
            for k in 0..4 {
                assert!(
                    (rq.state.cp_inv[k] - r.state.cp_inv[k]).abs() <= 1e-10 * cmax,
                    "{name}: history not objective"
                );
            }
            assert!(
                (rq.state.eps_p - r.state.eps_p).abs()
                    <= 1e-10 * r.state.eps_p.abs().max(1e-300) + 1e-300
            );
            assert!((rq.state.eps_c - r.state.eps_c).abs() <= 1e-10 * r.state.eps_c.abs());
        }

        // (d) symmetry.
        if law.symmetric_tangent() {
            for i in 0..3 {
                for j in 0..3 {
                    let err = (r.cc[i][j] - r.cc[j][i]).abs() / scale;
                    assert!(
                        err <= 1e-10,
                        "{name}: probe {ip}: cc not symmetric ({i},{j}): {err:e}"
                    );
                }
            }
        }
    }
    assert!(worst_fd < 1e-6);
    eprintln!(
        "{name}: worst tangent FD error {worst_fd:.2e} (history eps_p {:.3e}, eps_c {:.3e})",
        state.eps_p, state.eps_c
    );

    // (e) inverted / degenerate F.
    for ff in [
        f2(-1.0, 0.0, 0.0, 1.0),
        f2(1.0, 2.0, 1.0, 2.0),
        f2(0.5, 1.0, 1.0, 0.5),
        f2(f64::NAN, 0.0, 0.0, 1.0),
    ] {
        match law.update(&ff, &state, inc) {
            Err(MaterialError::InvertedElement(_)) => {}
            other => panic!("{name}: inverted F gave {other:?}"),
        }
    }
}

/// Deformation path shared by the laws: shear + stretch, committed twice.
fn history() -> Vec<Matrix3<f64>> {
    vec![f2(1.08, 0.12, -0.03, 0.95), f2(1.15, 0.25, -0.05, 0.9)]
}

/// Probes: further loading, reversed loading, a volume change, large stretch, near identity.
fn probes(expect_loading: Expect) -> Vec<(Matrix3<f64>, Expect)> {
    vec![
        (f2(1.2, 0.3, -0.06, 0.88), expect_loading),
        (f2(0.8, -0.2, 0.1, 1.15), expect_loading),
        (f2(1.3, 0.1, 0.05, 1.1), expect_loading),
        (f2(1.9, 0.4, 0.2, 0.6), expect_loading),
        (f2(1.001, 0.002, 0.0, 0.999), Expect::Any),
    ]
}

#[test]
fn elastic_compressible() {
    battery(&Case {
        name: "elastic nu=0.3",
        law: Material::Elastic(Elastic::new(64100.0, 0.3)),
        dt: 1.0,
        history: history(),
        probes: probes(Expect::Elastic),
    });
}

#[test]
fn elastic_incompressible() {
    battery(&Case {
        name: "elastic nu=0.5",
        law: Material::Elastic(Elastic::new(526.0, 0.5)),
        dt: 1.0,
        history: history(),
        probes: probes(Expect::Elastic),
    });
}

#[test]
fn j2_table1() {
    let table = HardeningTable::from_total_strain(ALUMINIUM_250C_E, &aluminium_250c()).unwrap();
    battery(&Case {
        name: "J2 Table 1",
        law: Material::J2(J2Plastic::new(ALUMINIUM_250C_E, ALUMINIUM_250C_NU, table)),
        dt: 1.0,
        history: history(),
        probes: probes(Expect::Inelastic),
    });
}

#[test]
fn j2_small_hardening_history() {
    // History that ends inside the hardening part of Table 1 (ε̄ᵖ between breakpoints).
    let table = HardeningTable::from_total_strain(ALUMINIUM_250C_E, &aluminium_250c()).unwrap();
    battery(&Case {
        name: "J2 Table 1 (small strains)",
        law: Material::J2(J2Plastic::new(ALUMINIUM_250C_E, ALUMINIUM_250C_NU, table)),
        dt: 1.0,
        history: vec![f2(1.002, 0.0, 0.0, 0.998)],
        probes: vec![
            (f2(1.003, 0.0004, 0.0, 0.997), Expect::Inelastic),
            (f2(1.0025, 0.0, 0.001, 0.998), Expect::Any),
            (f2(1.0015, 0.0, 0.0, 0.9985), Expect::Elastic),
        ],
    });
}

#[test]
fn j2_perfectly_plastic() {
    battery(&Case {
        name: "J2 perfect",
        law: Material::J2(J2Plastic::new(
            200000.0,
            0.3,
            HardeningTable::perfect(250.0),
        )),
        dt: 1.0,
        history: history(),
        probes: probes(Expect::Inelastic),
    });
}

#[test]
fn creep_asphalt_time_hardening() {
    battery(&Case {
        name: "creep asphalt (Pa)",
        law: Material::Creep(Creep::new(
            ASPHALT_E,
            ASPHALT_NU,
            CreepParams::asphalt_table2(1e6),
        )),
        dt: 0.5,
        history: history(),
        probes: probes(Expect::Inelastic),
    });
}

#[test]
fn creep_strain_hardening() {
    let params = CreepParams {
        m: -0.5,
        ..CreepParams::asphalt_table2(1e6)
    };
    battery(&Case {
        name: "creep m=-0.5",
        law: Material::Creep(Creep::new(ASPHALT_E, ASPHALT_NU, params)),
        dt: 0.5,
        history: history(),
        probes: probes(Expect::Inelastic),
    });
}

/// Table 1 of the paper (aluminium, 250 °C, E = 64.1 GPa) converted from total to plastic
/// strain: the initial yield is 70.5 MPa at ε̄ᵖ = 0 (the first point lies on the elastic line
/// within 1.6e-7), the other plastic strains are ε − σ/E (to 1e-12 absolute).
#[test]
fn table1_conversion() {
    let pts = aluminium_250c();
    let t = HardeningTable::from_total_strain(ALUMINIUM_250C_E, &pts).unwrap();
    assert_eq!(t.eps_p.len(), 4);
    assert_eq!(t.eps_p[0], 0.0);
    assert_eq!(t.sigma_y[0], 70.5);
    assert_eq!(t.initial_yield(), 70.5);
    for k in 1..4 {
        let [e, s] = pts[k + 1];
        assert!((t.eps_p[k] - (e - s / ALUMINIUM_250C_E)).abs() <= 1e-12);
        assert_eq!(t.sigma_y[k], s);
    }
    // perfectly plastic after the last point
    assert_eq!(t.eval(1.0), (130.2, 0.0));
    // a flat-out invalid table names the point
    let err =
        HardeningTable::from_total_strain(64100.0, &[[0.0, 0.0], [0.0011, 70.5], [0.001, 80.0]])
            .unwrap_err();
    assert!(err.contains("point 2"), "{err}");
}
