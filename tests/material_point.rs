//! Material-point tests: plane-strain, incompressible uniaxial loading against closed forms.
//!
//! Driver: F = diag(λ, 1/λ, 1); the total Kirchhoff stress is τ = τ′ + p I with the pressure p
//! chosen so that τ_yy = 0, hence τ_xx = τ′_xx − τ′_yy. For a prescribed τ_xx the stretch is
//! found by scalar Newton on e = ln λ with the law's own tangent: for l = diag(1, −1, 0) (the
//! rate of ln λ), A = cc : l + l τ′ + τ′ lᵀ, so
//! dτ_xx/de = cc₀₀ − cc₀₁ − cc₁₀ + cc₁₁ + 2(τ′_xx + τ′_yy).
//! Closed forms: `mpfem::analytical::creep` (eq. 29 of the paper) and `mpfem::analytical::j2`.
use mpfem::analytical::{creep as acreep, j2 as aj2};
use mpfem::material::creep::{ASPHALT_E, ASPHALT_NU};
use mpfem::material::hardening::{aluminium_250c, ALUMINIUM_250C_E, ALUMINIUM_250C_NU};
use mpfem::material::*;
use nalgebra::Matrix3;

fn ff(e: f64) -> Matrix3<f64> {
    Matrix3::new(e.exp(), 0.0, 0.0, 0.0, (-e).exp(), 0.0, 0.0, 0.0, 1.0)
}

fn tau_xx(r: &MatResponse) -> f64 {
    r.tau[0] - r.tau[1]
}

fn dtau_de(r: &MatResponse) -> f64 {
    r.cc[0][0] - r.cc[0][1] - r.cc[1][0] + r.cc[1][1] + 2.0 * (r.tau[0] + r.tau[1])
}

/// Solves τ_xx(e) = sigma from the committed `state` by Newton with the law's tangent.
/// Returns (e, response, iterations). Tolerance |τ_xx − σ| ≤ 1e-11·max(|σ|, 1 MPa).
fn solve_stress(
    law: &dyn ConstitutiveLaw,
    state: &MatState,
    inc: TimeIncrement,
    sigma: f64,
    e0: f64,
) -> (f64, MatResponse, usize) {
    let mut e = e0;
    for it in 0..50 {
        let r = law.update(&ff(e), state, inc).unwrap();
        let res = tau_xx(&r) - sigma;
        if res.abs() <= 1e-11 * sigma.abs().max(1.0) {
            return (e, r, it);
        }
        e -= res / dtau_de(&r);
    }
    panic!("material-point Newton did not converge");
}

/// Creep under constant τ_xx = σ from t = 0 to `t_end` in `nsteps` equal steps; returns the
/// times, ln λ and ε̄ᶜ after every step, and the largest Newton iteration count.
fn creep_run(
    law: &Creep,
    sigma: f64,
    t_end: f64,
    nsteps: usize,
) -> (Vec<f64>, Vec<f64>, Vec<f64>, usize) {
    let dt = t_end / nsteps as f64;
    let mut state = MatState::default();
    let mut e = 0.0;
    let (mut ts, mut es, mut ecs) = (vec![], vec![], vec![]);
    let mut max_it = 0;
    for k in 1..=nsteps {
        let inc = TimeIncrement {
            time: k as f64 * dt,
            dt,
        };
        let (e1, r, it) = solve_stress(law, &state, inc, sigma, e);
        max_it = max_it.max(it);
        e = e1;
        state = r.state;
        ts.push(inc.time);
        es.push(e);
        ecs.push(state.eps_c);
    }
    (ts, es, ecs, max_it)
}

/// Time hardening (m = 0), Table 2 asphalt with A in Pa units (stress_scale 1e6), σ = 1 MPa,
/// 43 s in 118 steps (the paper's lateral compaction run, §5.2.1). Tolerance 0.5 % on ln λ at
/// every step against σ/(4G) + (√3/2) ε̄ᶜ(t) (analytical::creep). With m = 0 and constant
/// stress the scheme (exact time factor) is exact, so the observed error is at roundoff level.
#[test]
fn creep_time_hardening_table2() {
    let p = CreepParams::asphalt_table2(1e6);
    let law = Creep::new(ASPHALT_E, ASPHALT_NU, p);
    let g = law.shear_modulus();
    let sigma = 1.0;
    let (ts, es, ecs, max_it) = creep_run(&law, sigma, 43.0, 118);
    let mut worst: f64 = 0.0;
    for k in 0..ts.len() {
        let exact = acreep::plane_strain_uniaxial_log_strain(g, &p, sigma, ts[k]);
        let rel = (es[k] - exact).abs() / exact;
        worst = worst.max(rel);
        assert!(
            rel <= 5e-3,
            "t = {}: ln λ = {} vs {} ({rel:e})",
            ts[k],
            es[k],
            exact
        );
        let q = 0.5 * 3f64.sqrt() * sigma;
        let ec = acreep::equivalent_creep_strain(&p, q, ts[k]);
        assert!((ecs[k] - ec).abs() <= 5e-3 * ec);
    }
    assert!(
        max_it <= 10,
        "Newton iterations {max_it}: tangent not consistent?"
    );
    eprintln!("time hardening: worst relative error {worst:.2e}, final ln λ = {:.5}, max Newton its {max_it}", es.last().unwrap());
}

/// Strain hardening m = −0.5 (other constants from Table 2, stress_scale 1e6, q_t = 1 so the
/// step in the time factor t^(q_t) is uniform — see `creep_convergence_order` for q_t = 0.22),
/// σ = 1 MPa, 43 s. Closed form ε̄ᶜ = [(1−m) K t]^(1/(1−m)) (analytical::creep). The implicit
/// scheme is first order; with 4000 steps (dt = 10.75 ms) the relative error of ln λ is
/// within the 0.5 % tolerance at every step from t = 4.3 s (10 % of the run) to the end.
/// The first steps of the singular-rate start (ε̄̇ᶜ ∝ (ε̄ᶜ)^(−½) at ε̄ᶜ = 0) carry a relative
/// error that does not shrink with dt (step 1: Δε̄ᶜ^(3/2) = KΔt instead of (3/2)KΔt, so ≈ 24 % of
/// ε̄ᶜ) and decays roughly like 1/k with the step number k, so "every step" cannot hold at any
/// fixed dt; the early errors are printed for the record.
#[test]
fn creep_strain_hardening_fine_step() {
    let p = CreepParams {
        m: -0.5,
        q: 1.0,
        ..CreepParams::asphalt_table2(1e6)
    };
    let law = Creep::new(ASPHALT_E, ASPHALT_NU, p);
    let g = law.shear_modulus();
    let sigma = 1.0;
    let n = 4000;
    let (ts, es, _, max_it) = creep_run(&law, sigma, 43.0, n);
    let mut worst: f64 = 0.0;
    for k in 0..n {
        let exact = acreep::plane_strain_uniaxial_log_strain(g, &p, sigma, ts[k]);
        let rel = (es[k] - exact).abs() / exact;
        if [0, 1, 3, 9, 39, 79, 199, 399, 999, 3999].contains(&k) {
            eprintln!(
                "strain hardening, step {:4} (t = {:7.4} s): relative error {rel:.3e}",
                k + 1,
                ts[k]
            );
        }
        if k + 1 < n / 10 {
            continue;
        }
        worst = worst.max(rel);
        assert!(
            rel <= 5e-3,
            "t = {}: ln λ = {} vs {} ({rel:e})",
            ts[k],
            es[k],
            exact
        );
    }
    assert!(max_it <= 10);
    eprintln!(
        "strain hardening: worst relative error (t ≥ 4.3 s) {worst:.2e}, final ln λ = {:.5}",
        es.last().unwrap()
    );
}

/// Creep run from a pre-strained state with creep strain `eps0` along the loading direction:
/// C_p⁻¹ = exp(−2 ε_c) with ε_c = (√3/2) ε̄₀ diag(1, −1, 0).
fn creep_run_from(law: &Creep, sigma: f64, t_end: f64, nsteps: usize, eps0: f64) -> f64 {
    let dt = t_end / nsteps as f64;
    let ec = 0.5 * 3f64.sqrt() * eps0;
    let mut state = MatState {
        cp_inv: [(-2.0 * ec).exp(), (2.0 * ec).exp(), 0.0, 1.0],
        eps_p: 0.0,
        eps_c: eps0,
    };
    let mut e = ec;
    for k in 1..=nsteps {
        let inc = TimeIncrement {
            time: k as f64 * dt,
            dt,
        };
        let (e1, r, _) = solve_stress(law, &state, inc, sigma, e);
        e = e1;
        state = r.state;
    }
    e
}

fn order_study(p: CreepParams, label: &str, steps: [usize; 4], eps0: f64) -> Vec<f64> {
    let law = Creep::new(ASPHALT_E, ASPHALT_NU, p);
    let g = law.shear_modulus();
    let sigma = 1.0;
    let t_end = 43.0;
    let exact = acreep::plane_strain_uniaxial_log_strain_from(g, &p, sigma, t_end, eps0);
    let errs: Vec<f64> = steps
        .iter()
        .map(|&n| (creep_run_from(&law, sigma, t_end, n, eps0) - exact).abs())
        .collect();
    let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    let shown: Vec<String> = errs.iter().map(|e| format!("{e:.3e}")).collect();
    eprintln!(
        "{label}: steps {steps:?}, errors of ln λ at t_end {shown:?}, observed orders {orders:.3?}"
    );
    orders
}

/// Convergence order in dt of the implicit creep update for m ≠ 0 (m = −0.5, q_t = 1, Table 2
/// otherwise, σ = 1 MPa): error of ln λ at t_end = 43 s for four step sizes dt, dt/2, dt/4,
/// dt/8. Backward Euler is first order; we assert an observed order ≥ 0.9 for every halving.
/// - From the virgin state (ε̄ᶜ = 0) the rate ∝ (ε̄ᶜ)^(−½) is singular at the start; the local
///   errors of the early steps add up to an error ~ dt·ln(t_end/dt), whose observed order
///   tends to 1 only logarithmically (measured ≈ 0.86–0.88 for dt = 43/100 … 43/800, ≈ 0.90 for
///   43/1600 … 43/12800), so this case uses dt = 43/3200 … 43/25600.
/// - From a pre-strained state ε̄ᶜ₀ = 0.05 the rate is regular and the first order is clean
///   already at dt = 43/100 … 43/800.
#[test]
fn creep_convergence_order() {
    let p = CreepParams {
        m: -0.5,
        q: 1.0,
        ..CreepParams::asphalt_table2(1e6)
    };
    for o in order_study(
        p,
        "m = -0.5, q_t = 1, virgin",
        [3200, 6400, 12800, 25600],
        0.0,
    ) {
        assert!(o >= 0.9, "observed order {o}");
    }
    for o in order_study(
        p,
        "m = -0.5, q_t = 1, pre-strained 0.05",
        [100, 200, 400, 800],
        0.05,
    ) {
        assert!(o >= 0.9, "observed order {o}");
    }
    // Informative only: with the paper's time exponent q_t = 0.22 and uniform dt, the first
    // step covers dt^0.22 of the time factor t^0.22, which lowers the observed order in dt.
    let p22 = CreepParams {
        m: -0.5,
        ..CreepParams::asphalt_table2(1e6)
    };
    let _ = order_study(
        p22,
        "m = -0.5, q_t = 0.22, virgin (not asserted)",
        [100, 200, 400, 800],
        0.0,
    );
}

/// Monotonic plane-strain tension and compression, strain controlled, perfectly plastic:
/// τ_xx = 4G ln λ up to yield, then the plateau 2σ_y/√3 (analytical::j2). The return map is
/// exact for radial paths, so the tolerance is 1e-9 relative.
#[test]
fn j2_perfect_plateau() {
    let (e_mod, sy) = (200000.0, 250.0);
    let law = J2Plastic::new(e_mod, 0.3, HardeningTable::perfect(sy));
    let g = law.shear_modulus();
    for sign in [1.0, -1.0] {
        let mut state = MatState::default();
        for k in 1..=100 {
            let e = sign * 0.0005 * k as f64;
            let r = law
                .update(
                    &ff(e),
                    &state,
                    TimeIncrement {
                        time: k as f64,
                        dt: 1.0,
                    },
                )
                .unwrap();
            state = r.state;
            let exact = aj2::plane_strain_uniaxial_linear(g, sy, 0.0, e);
            assert!(
                (tau_xx(&r) - exact).abs() <= 1e-9 * exact.abs(),
                "e = {e}: {} vs {exact}",
                tau_xx(&r)
            );
            assert!(
                r.tau[3].abs() <= 1e-9 * sy,
                "out-of-plane deviator must stay zero"
            );
        }
        let plateau = aj2::plane_strain_yield_stress(sy);
        let r = law
            .update(
                &ff(sign * 0.05),
                &state,
                TimeIncrement {
                    time: 101.0,
                    dt: 1.0,
                },
            )
            .unwrap();
        assert!((tau_xx(&r) - sign * plateau).abs() <= 1e-10 * plateau);
        // ε̄ᵖ = (2/√3)(e − e_y) on the plateau
        let ey = sy / (2.0 * 3f64.sqrt() * g);
        assert!((state.eps_p - 2.0 / 3f64.sqrt() * (0.05 - ey)).abs() <= 1e-10);
    }
}

/// Linear hardening σ_y = 250 + 1000 ε̄ᵖ (table up to ε̄ᵖ = 1): strain-controlled tension to
/// ln λ = 0.2 in 40 steps and in 1 step (the return is exact for radial paths), against the
/// closed form (analytical::j2); tolerance 1e-9 relative.
#[test]
fn j2_linear_hardening() {
    let table = HardeningTable::from_plastic_strain(&[[0.0, 250.0], [1.0, 1250.0]]).unwrap();
    let law = J2Plastic::new(200000.0, 0.3, table);
    let g = law.shear_modulus();
    for nsteps in [40usize, 1] {
        let mut state = MatState::default();
        let mut last = 0.0;
        for k in 1..=nsteps {
            let e = 0.2 * k as f64 / nsteps as f64;
            let r = law
                .update(
                    &ff(e),
                    &state,
                    TimeIncrement {
                        time: k as f64,
                        dt: 1.0,
                    },
                )
                .unwrap();
            state = r.state;
            let exact = aj2::plane_strain_uniaxial_linear(g, 250.0, 1000.0, e);
            assert!(
                (tau_xx(&r) - exact).abs() <= 1e-9 * exact.abs(),
                "e = {e}: {} vs {exact}",
                tau_xx(&r)
            );
            last = tau_xx(&r);
        }
        assert!(last > aj2::plane_strain_yield_stress(250.0));
    }
}

/// Table 1 (aluminium, 250 °C), stress controlled with the Newton driver: τ_xx ramps to 145 MPa
/// (below the plateau 2·130.2/√3 = 150.3 MPa) in 29 steps; ln λ and ε̄ᵖ against the table
/// closed form (analytical::j2), tolerance 1e-9 relative; Newton converges in ≤ 10 iterations.
#[test]
fn j2_table1_stress_controlled() {
    let table = HardeningTable::from_total_strain(ALUMINIUM_250C_E, &aluminium_250c()).unwrap();
    let law = J2Plastic::new(ALUMINIUM_250C_E, ALUMINIUM_250C_NU, table.clone());
    let g = law.shear_modulus();
    let mut state = MatState::default();
    let mut e = 0.0;
    for k in 1..=29 {
        let sigma = 5.0 * k as f64;
        let (e1, r, it) = solve_stress(
            &law,
            &state,
            TimeIncrement {
                time: k as f64,
                dt: 1.0,
            },
            sigma,
            e,
        );
        assert!(it <= 10);
        e = e1;
        state = r.state;
        let (tau_exact, ep_exact) = aj2::plane_strain_uniaxial_table(g, &table, e);
        assert!(
            (sigma - tau_exact).abs() <= 1e-9 * sigma,
            "σ = {sigma}: closed form at ln λ = {e} gives {tau_exact}"
        );
        assert!((state.eps_p - ep_exact).abs() <= 1e-9 * ep_exact.max(1e-6));
    }
    // first yield at 2·70.5/√3 = 81.4 MPa
    let y = aj2::plane_strain_yield_stress(70.5);
    assert!((y - 81.406).abs() < 1e-3);
}
