//! Implicit dynamics (Newmark / HHT-α, paper eq. 20–21 with M ü): verification.
//!
//! - Energy conservation of the trapezoidal rule on a suddenly loaded elastic block.
//! - The closed-form period 4L/c and peak 2 u_s of a suddenly loaded column in uniaxial
//!   strain (`mpfem::analytical::bar_wave`).
//! - HHT-α (α = −0.1) dissipates energy where the trapezoidal rule does not.
//! - A slowly applied load gives the quasi-static answer.
//!
//! Material everywhere: aluminium, E = 70 000 MPa, ν = 0.3, ρ = 2.7e-9 t/mm³ (Hencky
//! elasticity; loads of about 1 MPa keep the strains near 1e-5, so the problems are linear to
//! about 1e-5).

use mpfem::analytical::bar_wave;
use mpfem::assembly::{number_equations, Assembler, ElementFields};
use mpfem::case::{self, Case};
use mpfem::element::{Volumetric, N_ENH};
use mpfem::material::{ConstitutiveLaw, TimeIncrement};
use mpfem::model::Model;
use mpfem::solver::{Simulation, StepReport};
use std::path::Path;
use std::time::Instant;

const E: f64 = 70_000.0;
const NU: f64 = 0.3;
const RHO: f64 = 2.7e-9;

/// One elastic body `body` (rectangle `w` × `h`, `nx` × `ny` elements), the boundary and load
/// tables in `rest`, and a `[time]` table with `time` (s) and the integrator keys.
fn case_text(w: f64, h: f64, nx: usize, ny: usize, rest: &str, time: &str) -> String {
    format!(
        r#"
[[materials]]
name = "alu"
model = "elastic"
youngs_modulus = {E:e}
poisson_ratio = {NU:e}
density = {RHO:e}

[[bodies]]
name = "body"
material = "alu"
divisions = [{nx}, {ny}]
shape = {{ type = "rectangle", origin = [0.0, 0.0], size = [{w:e}, {h:e}] }}

{rest}

[time]
{time}

[output]
displacements = ["body.top"]
"#
    )
}

fn parse(text: &str) -> Case {
    case::parse(text, Path::new(".")).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Run a case; returns the reports and the displacement vector after every step.
fn run(c: &Case) -> (Vec<StepReport>, Vec<Vec<f64>>, Model) {
    let model = Model::from_case(c).unwrap();
    let mut sim = Simulation::new(model.clone(), c.time, c.solver).unwrap();
    let mut reports = Vec::new();
    let mut us = Vec::new();
    sim.run(&mut |s, r| {
        reports.push(r.clone());
        us.push(s.sol.u.clone());
    })
    .unwrap();
    (reports, us, model)
}

/// Strain energy of the discrete model at u: the line integral ∫₀¹ F_int(s u)·u ds along the
/// straight path from the undeformed state (path independent: Hencky elasticity with the
/// mean-dilatation pressure κ ln Θ / Θ is hyperelastic), by 5-point Gauss–Legendre. It uses
/// only the element internal forces, nothing of the time integrator.
struct StrainEnergy {
    assembler: Assembler,
    fields: ElementFields,
    vol: Vec<Volumetric>,
    f: Vec<f64>,
}

impl StrainEnergy {
    fn new(model: &Model) -> Self {
        let (eq, n_free) = number_equations(model.n_dofs(), model.loading.prescribed.iter().map(|p| p.dof));
        let (assembler, _) = Assembler::new(model, eq, n_free);
        let ne = model.elements.len();
        let vol = (0..ne)
            .map(|e| {
                let m = &model.materials[model.elem_material[e]];
                Volumetric {
                    kappa: m.bulk_modulus().unwrap(),
                    lambda: 0.0,
                }
            })
            .collect();
        Self {
            assembler,
            fields: ElementFields::new(ne),
            vol,
            f: vec![0.0; model.n_dofs()],
        }
    }

    fn at(&mut self, model: &Model, u: &[f64]) -> f64 {
        const GL: [(f64, f64); 5] = [
            (0.0, 0.568_888_888_888_888_9),
            (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
            (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
            (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
            (0.906_179_845_938_664, 0.236_926_885_056_189_1),
        ];
        let old = ElementFields::new(model.elements.len());
        let alpha0 = vec![[0.0; N_ENH]; model.elements.len()];
        let inc = TimeIncrement { time: 0.0, dt: 1.0 };
        let mut energy = 0.0;
        for (x, w) in GL {
            let s = 0.5 * (1.0 + x);
            let us: Vec<f64> = u.iter().map(|v| s * v).collect();
            self.assembler
                .assemble(
                    model,
                    &us,
                    &old.states,
                    &alpha0,
                    &self.vol,
                    None,
                    inc,
                    None,
                    &mut self.f,
                    &mut self.fields,
                    None,
                )
                .unwrap();
            energy += 0.5 * w * self.f.iter().zip(u).map(|(f, v)| f * v).sum::<f64>();
        }
        energy
    }
}

/// Consistent nodal forces of a constant traction on the edge set `set` (reference lengths):
/// half of t·ℓ to each node of an edge. The work of this dead load is F_ext · u.
fn traction_forces(model: &Model, t: [f64; 2]) -> Vec<f64> {
    let mut f = vec![0.0; model.n_dofs()];
    for load in &model.loading.loads {
        for e in &load.edges {
            let (a, b) = (model.x0[e[0]], model.x0[e[1]]);
            let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            for n in *e {
                for c in 0..2 {
                    f[2 * n + c] += 0.5 * t[c] * len;
                }
            }
        }
    }
    f
}

const BLOCK_BC: &str = r#"
[[boundary]]
body = "body"
set = "bottom"
ux = 0.0
uy = 0.0

[[loads]]
body = "body"
set = "top"
type = "traction"
value = [0.5, -1.0]
amplitude = "constant"
"#;
const BLOCK_TRACTION: [f64; 2] = [0.5, -1.0];

/// Energy history E_n = KE_n + SE_n − W_n of the 10 × 10 mm block (4 × 4 elements, bottom
/// clamped, traction [0.5, −1] MPa applied at t = 0 and held), 400 steps of 1e-7 s (about
/// three periods of its first mode, 4H/c_s ≈ 1.3e-5 s). Returns (E_n, W_n) per step.
fn block_energy(integrator: &str) -> Vec<(f64, f64)> {
    let c = parse(&case_text(
        10.0,
        10.0,
        4,
        4,
        BLOCK_BC,
        &format!("end = 4e-5\ndt = 1e-7\n{integrator}"),
    ));
    let (reports, us, model) = run(&c);
    assert_eq!(reports.len(), 400);
    let f_ext = traction_forces(&model, BLOCK_TRACTION);
    let mut se = StrainEnergy::new(&model);
    reports
        .iter()
        .zip(&us)
        .map(|(r, u)| {
            let w: f64 = f_ext.iter().zip(u).map(|(f, v)| f * v).sum();
            (r.kinetic_energy + se.at(&model, u) - w, w)
        })
        .collect()
}

/// Trapezoidal rule (Newmark β = 1/4, γ = 1/2), suddenly applied then held load: the
/// kinetic plus strain energy equals the work of the load at every step.
///
/// Source: for a linear system the trapezoidal rule conserves ½vᵀMv + ½uᵀKu − F·u exactly
/// (Hughes, *The Finite Element Method*, 2000, §9.3: the average-acceleration rule is
/// energy conserving); with the consistent initial acceleration a₀ = M⁻¹F the balance holds
/// from the first step. What remains is (i) the Newton tolerance (relative residual 1e-8)
/// and (ii) the geometric and material nonlinearity of Hencky elasticity at strains of
/// ~1e-5: the rule then integrates ∫F_int·du by the trapezoidal quadrature, whose error per
/// step, O(|Δu|³ ∂²F_int), is far below round-off here. The Newton residual R_n of each step
/// (‖R‖ ≤ 1e-8 ‖F‖) adds at most |Δu_n·R_n|, summed over a path of ~4 u_max per period for
/// three periods: ≲ 1e-8 · 12 ‖F‖ u_max ≈ 2.4e-7 max W. Tolerance: |E_n| ≤ 1e-6 · max W
/// (measured 2.7e-8).
#[test]
fn trapezoidal_rule_conserves_energy() {
    let t0 = Instant::now();
    let hist = block_energy("integrator = \"newmark\"");
    let w_max = hist.iter().map(|h| h.1).fold(0.0, f64::max);
    let worst = hist.iter().map(|h| h.0.abs()).fold(0.0, f64::max);
    eprintln!(
        "trapezoidal energy balance: max |KE + SE − W| / max W = {:.3e} (max W = {w_max:.4e} N·mm/mm), {:.2} s",
        worst / w_max,
        t0.elapsed().as_secs_f64()
    );
    assert!(w_max > 0.0);
    assert!(
        worst <= 1e-6 * w_max,
        "energy error {:.3e} of max W",
        worst / w_max
    );
}

/// HHT-α with α = −0.1 (γ = 0.6, β = 0.3025) on the block of
/// `trapezoidal_rule_conserves_energy`: the total energy KE + SE − W decreases (numerical
/// dissipation of the α-method, Hilber, Hughes & Taylor 1977), the trapezoidal rule keeps it
/// at 0 (≤ 1e-6 max W, previous test). At this step (ω Δt below about 0.7 for every mode of
/// the mesh: ω_max ≈ 2√2 c_p / h with c_p = √(M_c/ρ), h = 2.5 mm)
/// the α-method damps little, by design (its damping grows with ω Δt). Requirements: after
/// three periods at least 1e-4 of max W (100 × the trapezoidal tolerance) is dissipated
/// (measured 1.8e-3), and the energy at the end of each quarter of the run is below the one
/// at the end of the previous quarter (it is not monotone step by step: kinetic and strain
/// energy are exchanged within a period).
#[test]
fn hht_alpha_dissipates_energy() {
    let t0 = Instant::now();
    let hist = block_energy("integrator = \"hht\"\nhht_alpha = -0.1");
    let w_max = hist.iter().map(|h| h.1).fold(0.0, f64::max);
    let quarters: Vec<f64> = (1..=4)
        .map(|q| hist[q * hist.len() / 4 - 1].0 / w_max)
        .collect();
    let shown: Vec<String> = quarters.iter().map(|q| format!("{q:.3e}")).collect();
    eprintln!(
        "HHT α = −0.1: (KE + SE − W) / max W at the end of each quarter of the run: {}, {:.2} s",
        shown.join(", "),
        t0.elapsed().as_secs_f64()
    );
    assert!(quarters[0] < 0.0);
    for q in quarters.windows(2) {
        assert!(q[1] < q[0], "energy did not decrease: {quarters:?}");
    }
    assert!(
        quarters[3] < -1e-4,
        "dissipated only {:.3e} of max W",
        -quarters[3]
    );
}

/// The column of `suddenly_loaded_column_period_and_peak`: 10 mm wide (one element), L = 100
/// mm high (`n` elements), rollers on both sides (u_x = 0 everywhere: uniaxial strain),
/// bottom fixed, traction −P on the top with the given amplitude.
fn column(n: usize, p: f64, amplitude: &str, time: &str) -> Case {
    let bc = format!(
        r#"
[[boundary]]
body = "body"
set = "left"
ux = 0.0

[[boundary]]
body = "body"
set = "right"
ux = 0.0

[[boundary]]
body = "body"
set = "bottom"
uy = 0.0

[[loads]]
body = "body"
set = "top"
type = "traction"
value = [0.0, {:e}]
amplitude = {amplitude}
"#,
        -p
    );
    parse(&case_text(10.0, 100.0, 1, n, &bc, time))
}

/// Upward crossings of the level `level` by the sampled signal (t, y), linearly interpolated.
fn crossings(t: &[f64], y: &[f64], level: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for i in 1..t.len() {
        let (a, b) = (y[i - 1] - level, y[i] - level);
        if a < 0.0 && b >= 0.0 {
            out.push(t[i - 1] + (t[i] - t[i - 1]) * a / (a - b));
        }
    }
    out
}

/// Relative errors (period, peak, max |u − triangle| over the first period / 2 u_s) of the
/// end displacement of the suddenly loaded column with `n` elements and `per_period` steps
/// per period T = 4L/c, over three periods; prints the measured values.
fn column_errors(n: usize, per_period: usize) -> (f64, f64, f64) {
    let t0 = Instant::now();
    let (l, p) = (100.0, 1.0);
    let c = bar_wave::wave_speed(E, NU, RHO);
    let period = bar_wave::period(l, c);
    let u_s = p * l / bar_wave::constrained_modulus(E, NU);
    let dt = period / per_period as f64;
    let time = format!(
        "end = {:e}\ndt = {dt:e}\nintegrator = \"newmark\"",
        3.0 * period
    );
    let (reports, _, _) = run(&column(n, p, "\"constant\"", &time));
    let t: Vec<f64> = std::iter::once(0.0)
        .chain(reports.iter().map(|r| r.time))
        .collect();
    let tip: Vec<f64> = std::iter::once(0.0)
        .chain(reports.iter().map(|r| -r.displacements[0][1]))
        .collect();
    let up = crossings(&t, &tip, u_s);
    assert!(up.len() >= 3, "crossings {up:?}");
    let measured = (up[up.len() - 1] - up[0]) / (up.len() - 1) as f64;
    let peak = tip.iter().cloned().fold(0.0, f64::max);
    let mut shape: f64 = 0.0;
    for (ti, ui) in t.iter().zip(&tip) {
        if *ti <= period {
            shape = shape.max((ui - bar_wave::end_displacement(*ti, period, u_s)).abs());
        }
    }
    let errors = (
        measured / period - 1.0,
        peak / (2.0 * u_s) - 1.0,
        shape / (2.0 * u_s),
    );
    eprintln!(
        "column, {n} elements, T/{per_period}: T = {measured:.6e} s vs 4L/c = {period:.6e} s ({:+.3} %), peak {peak:.6e} mm \
         vs 2 u_s = {:.6e} mm ({:+.3} %), max |u − triangle| over the first period {:.3} % of 2 u_s; {} steps, {:.2} s",
        100.0 * errors.0,
        2.0 * u_s,
        100.0 * errors.1,
        100.0 * errors.2,
        reports.len(),
        t0.elapsed().as_secs_f64()
    );
    errors
}

/// A plane-strain column in uniaxial strain (rollers on its sides), fixed at the bottom,
/// under a traction P = 1 MPa applied suddenly on its free end: the end displacement is a
/// triangle wave of period T = 4L/c, c = √(M_c/ρ), M_c = E(1−ν)/((1+ν)(1−2ν)), peaking at
/// 2 u_s = 2 P L / M_c (closed form: `mpfem::analytical::bar_wave`, d'Alembert solution).
///
/// Discretisation: L = 100 mm with 20 and 40 elements, trapezoidal rule at the Courant number
/// cΔt/h = 0.4 (T/200 and T/400), three periods. Expected errors: the fundamental frequency
/// of the lumped-mass mesh is low by (π/4N)²/6 ≤ 3e-4 and the trapezoidal rule lengthens
/// its period by (ωΔt)²/12 ≤ 1e-4, so the period (mean over three periods between upward
/// crossings of u_s) must be within 0.5 %. The peak is a corner of the triangle wave (all
/// modes in phase), which dispersion rounds off: lumped mass and trapezoidal rule both give
/// ω̄ = ck(1 − O((kh)²)), a cubic phase error k³h²x that spreads the reflected step front
/// over a width ∝ (h² x)^(1/3) (an Airy-function front), so the corner is cut by
/// O((h/L)^(2/3)). Requirements: peak within 2 % (the contact issue's figure) at N = 40, and
/// the N = 20 error 1.4–2.0 × the N = 40 one (2^(2/3) = 1.59; measured N = 20, 40, 80:
/// −2.00 %, −1.25 %, −0.81 %); the whole first period within 3 % of 2 u_s of the triangle.
#[test]
fn suddenly_loaded_column_period_and_peak() {
    let (period20, peak20, _) = column_errors(20, 200);
    let (period40, peak40, shape40) = column_errors(40, 400);
    assert!(period20.abs() < 0.005 && period40.abs() < 0.005);
    assert!(peak40.abs() < 0.02);
    let rate = peak20 / peak40;
    assert!(
        (1.4..=2.0).contains(&rate),
        "peak errors {peak20:.3e} (N = 20), {peak40:.3e} (N = 40)"
    );
    assert!(shape40 < 0.03);
}

/// The quasi-static limit: the column of `suddenly_loaded_column_period_and_peak` (20
/// elements) with the load ramped from 0 to P over t_r = 50 T and then held for 5 T
/// (trapezoidal rule, Δt = T/10) follows the static solution u_s · f(t).
///
/// Bound (single mode, exact): a ramp over t_r leaves free vibrations of amplitude at most
/// 2 u_s/(ω t_r) = u_s T/(π t_r); the static end displacement is the sum of positive modal
/// parts (8/π² Σ 1/(2k−1)² = 1), so the bound holds for the column with ω₁; the discrete
/// frequency of the trapezoidal rule at ω₁Δt = 2π/10 is ω̄₁ = 2 atan(ω₁Δt/2)/Δt = 0.969 ω₁.
/// Tolerance: max over the run of |u − u_s f(t)| ≤ u_s T/(π · 0.969 · t_r) = 0.66 % of u_s.
/// The static reference is the quasi-static solver on the same mesh, which matches the
/// closed form P L / M_c to 1e-4 (Hencky at strain 1e-5: nonlinear terms of order 1e-5).
#[test]
fn slowly_applied_load_gives_the_static_answer() {
    let t0 = Instant::now();
    let (l, p, n) = (100.0, 1.0, 20);
    let period = bar_wave::period(l, bar_wave::wave_speed(E, NU, RHO));
    let t_r = 50.0 * period;
    let amp = format!("[[0.0, 0.0], [{t_r:e}, 1.0]]");
    let time = format!(
        "end = {:e}\ndt = {:e}\nintegrator = \"newmark\"",
        55.0 * period,
        period / 10.0
    );
    let (reports, _, _) = run(&column(n, p, &amp, &time));
    let stat = column(
        n,
        p,
        &amp,
        &format!(
            "end = {:e}\ndt = {:e}\ndt_max = {:e}",
            55.0 * period,
            t_r,
            t_r
        ),
    );
    let (sreports, _, _) = run(&stat);
    let u_static = -sreports.last().unwrap().displacements[0][1];
    let u_closed = p * l / bar_wave::constrained_modulus(E, NU);
    let mut worst: f64 = 0.0;
    for r in &reports {
        let f = (r.time / t_r).min(1.0);
        worst = worst.max((-r.displacements[0][1] - u_static * f).abs());
    }
    let u_end = -reports.last().unwrap().displacements[0][1];
    let bound = period / (std::f64::consts::PI * 0.969 * t_r);
    eprintln!(
        "quasi-static limit: static solver {u_static:.6e} mm vs P L / M_c {u_closed:.6e} mm ({:+.2e}); dynamic end value {u_end:.6e} mm \
         ({:+.3} %); max |u − u_s f(t)| = {:.3} % of u_s (bound {:.3} %); {} steps, {:.2} s",
        u_static / u_closed - 1.0,
        100.0 * (u_end / u_static - 1.0),
        100.0 * worst / u_static,
        100.0 * bound,
        reports.len(),
        t0.elapsed().as_secs_f64()
    );
    assert!((u_static / u_closed - 1.0).abs() < 1e-4);
    assert!(worst <= bound * u_static, "{} > {bound}", worst / u_static);
}

/// A dynamic case needs the density of every material, and a quasi-static run of a case that
/// carries densities is unchanged by them (the kinetic energy column stays 0).
#[test]
fn density_is_required_and_static_runs_report_no_kinetic_energy() {
    let text = case_text(
        10.0,
        10.0,
        2,
        2,
        BLOCK_BC,
        "end = 1e-6\ndt = 1e-7\nintegrator = \"hht\"",
    );
    let e = case::parse(&text.replace("density = 2.7e-9\n", ""), Path::new(".")).unwrap_err();
    assert_eq!(e.key, "materials[0].density");
    assert!(
        e.message.contains("\"alu\"") && e.message.contains("time.integrator"),
        "{e}"
    );
    let c = parse(&text.replace("integrator = \"hht\"", ""));
    let (reports, _, _) = run(&c);
    assert!(reports.iter().all(|r| r.kinetic_energy == 0.0));
}
