//! The verification set behind `mpfem verify`: textbook problems with known answers, each a
//! function returning rows of (case, quantity, reference, ours, error, tolerance, pass).
//! The same functions are asserted by the tests in `tests/verify_*.rs`, named after their
//! sources. Case files live in `jobs/verification/`.

use crate::analytical;
use crate::case::{self, Case, Formulation};
use crate::material::{ConstitutiveLaw, TimeIncrement};
use crate::model::Model;
use crate::solver::{Simulation, StepReport};
use nalgebra::Matrix3;
use serde::Serialize;
use std::path::Path;

/// One line of the verification table. `error` is relative unless the quantity says otherwise.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub case: String,
    pub quantity: String,
    pub reference: f64,
    pub ours: f64,
    pub error: f64,
    pub tolerance: f64,
    pub pass: bool,
    pub source: String,
}

impl Row {
    /// A row comparing `ours` with `reference` by relative error.
    pub fn relative(case: &str, quantity: &str, reference: f64, ours: f64, tolerance: f64, source: &str) -> Self {
        let error = ((ours - reference) / reference).abs();
        Self::with_error(case, quantity, reference, ours, error, tolerance, source)
    }

    /// A row whose error is computed by the caller (e.g. a maximum over many points).
    pub fn with_error(case: &str, quantity: &str, reference: f64, ours: f64, error: f64, tolerance: f64, source: &str) -> Self {
        Self {
            case: case.into(),
            quantity: quantity.into(),
            reference,
            ours,
            error,
            tolerance,
            pass: error.is_finite() && error <= tolerance,
            source: source.into(),
        }
    }

    fn failed(case: &str, quantity: &str, why: &str) -> Self {
        Self {
            case: case.into(),
            quantity: format!("{quantity} ({why})"),
            reference: f64::NAN,
            ours: f64::NAN,
            error: f64::INFINITY,
            tolerance: 0.0,
            pass: false,
            source: String::new(),
        }
    }
}

/// Parse one of the case files in `jobs/verification`.
pub fn verification_case(text: &str) -> Case {
    case::parse(text, Path::new("jobs/verification")).expect("verification case files are valid")
}

const PATCH: &str = include_str!("../jobs/verification/patch_test.toml");
const ROTATION: &str = include_str!("../jobs/verification/rigid_rotation.toml");
const COOK: &str = include_str!("../jobs/verification/cook_membrane.toml");
const CYLINDER: &str = include_str!("../jobs/verification/thick_cylinder.toml");
const INCOMPRESSIBLE: &str = include_str!("../jobs/verification/incompressible_block.toml");
const CREEP: &str = include_str!("../jobs/verification/creep_block.toml");

fn simulate(case: &Case) -> Result<(Simulation, Vec<StepReport>), String> {
    let model = Model::from_case(case).map_err(|e| e.to_string())?;
    let mut sim = Simulation::new(model, case.time.clone(), case.solver.clone()).map_err(|e| e.to_string())?;
    let mut reports = Vec::new();
    sim.run(&mut |_, r| reports.push(r.clone())).map_err(|e| e.to_string())?;
    Ok((sim, reports))
}

fn nearest_node(model: &Model, p: [f64; 2]) -> usize {
    (0..model.n_nodes())
        .min_by(|&a, &b| {
            let d = |n: usize| (model.x0[n][0] - p[0]).powi(2) + (model.x0[n][1] - p[1]).powi(2);
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0)
}

/// Patch test on a distorted 4 × 4 mesh under the homogeneous deformation
/// F = [[1.2, 0.15], [−0.05, 0.9]]: every Gauss point must carry the stress of a single
/// material point with that F (Hencky deviator + bulk pressure K ln J / J), to 1e-10.
pub fn patch_test(formulation: Formulation) -> Vec<Row> {
    patch_test_with(formulation, crate::element::ElementKind::Q1P0)
}

/// [`patch_test`] for a chosen element technology.
pub fn patch_test_with(formulation: Formulation, element: crate::element::ElementKind) -> Vec<Row> {
    let name = format!(
        "patch test ({}{})",
        if formulation == Formulation::TotalLagrangian { "TL" } else { "UL" },
        if element == crate::element::ElementKind::Q1P0Enhanced { ", enhanced" } else { "" }
    );
    let src = "Taylor, Simo & Zienkiewicz 1986; MacNeal & Harder 1985";
    let mut c = verification_case(PATCH);
    c.formulation = formulation;
    c.element = element;
    let mut model = match Model::from_case(&c) {
        Ok(m) => m,
        Err(e) => return vec![Row::failed(&name, "stress", &e.to_string())],
    };
    // distort the interior nodes (deterministic offsets, up to 0.15 mm on 0.5 mm elements)
    let boundary: std::collections::BTreeSet<usize> = model.bodies[0].mesh.node_set("boundary").unwrap_or_default().into_iter().collect();
    for n in 0..model.n_nodes() {
        if !boundary.contains(&n) {
            let k = n as f64;
            model.x0[n][0] += 0.15 * (1.7 * k).sin();
            model.x0[n][1] += 0.12 * (2.3 * k).cos();
        }
    }
    let ff = [[1.2, 0.15], [-0.05, 0.9]];
    for p in model.loading.prescribed.iter_mut() {
        let (n, c) = (p.dof / 2, p.dof % 2);
        let x = model.x0[n];
        p.value = (ff[c][0] - if c == 0 { 1.0 } else { 0.0 }) * x[0] + (ff[c][1] - if c == 1 { 1.0 } else { 0.0 }) * x[1];
    }
    let law = model.materials[0].clone();
    let mut sim = match Simulation::new(model, c.time.clone(), c.solver.clone()) {
        Ok(s) => s,
        Err(e) => return vec![Row::failed(&name, "stress", &e.to_string())],
    };
    if let Err(e) = sim.run(&mut |_, _| {}) {
        return vec![Row::failed(&name, "stress", &e.to_string())];
    }
    let f3 = Matrix3::new(ff[0][0], ff[0][1], 0.0, ff[1][0], ff[1][1], 0.0, 0.0, 0.0, 1.0);
    let jac = f3.determinant();
    let r = law.update(&f3, &Default::default(), TimeIncrement { time: 1.0, dt: 1.0 }).expect("elastic update");
    let p = law.bulk_modulus().unwrap_or(0.0) * jac.ln() / jac;
    let expected = [r.tau[0] / jac + p, r.tau[1] / jac + p, r.tau[2] / jac, r.tau[3] / jac + p];
    let scale = expected.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let mut err: f64 = 0.0;
    for e in &sim.sol.fields.sig {
        for g in e {
            for k in 0..4 {
                err = err.max((g[k] - expected[k]).abs() / scale);
            }
        }
    }
    vec![Row::with_error(&name, "max Gauss-point stress error / max |σ|", scale, scale, err, 1e-10, src)]
}

/// Rigid rotation by 90° in 9 steps of an elasto-plastic block: the stress stays zero.
pub fn rigid_rotation(formulation: Formulation) -> Vec<Row> {
    let name = format!("rigid rotation 90° ({})", if formulation == Formulation::TotalLagrangian { "TL" } else { "UL" });
    let src = "objectivity (Simo & Hughes 1998, ch. 7)";
    let mut c = verification_case(ROTATION);
    c.formulation = formulation;
    let model = match Model::from_case(&c) {
        Ok(m) => m,
        Err(e) => return vec![Row::failed(&name, "stress", &e.to_string())],
    };
    for a in model.loading.amplitudes.iter() {
        debug_assert!(matches!(a, case::Amplitude::Ramp));
    }
    let e_mod = 64100.0;
    let mut sim = match Simulation::new(model, c.time.clone(), c.solver.clone()) {
        Ok(s) => s,
        Err(e) => return vec![Row::failed(&name, "stress", &e.to_string())],
    };
    let steps = 9;
    let mut err: f64 = 0.0;
    for i in 1..=steps {
        let theta = std::f64::consts::FRAC_PI_2 * i as f64 / steps as f64;
        let (s, co) = theta.sin_cos();
        let t_next = c.time.end * i as f64 / steps as f64;
        // prescribed value × ramp amplitude(t_next) must equal (R − I) X
        let amp = t_next / c.time.end;
        for k in 0..sim.model.loading.prescribed.len() {
            let p = &sim.model.loading.prescribed[k];
            let (n, comp) = (p.dof / 2, p.dof % 2);
            let x = sim.model.x0[n];
            let u = if comp == 0 { (co - 1.0) * x[0] - s * x[1] } else { s * x[0] + (co - 1.0) * x[1] };
            sim.model.loading.prescribed[k].value = u / amp;
        }
        if let Err(e) = sim.advance(t_next - sim.sol.time) {
            return vec![Row::failed(&name, "stress", &e.to_string())];
        }
        for e in &sim.sol.fields.sig {
            for g in e {
                for v in g {
                    err = err.max(v.abs() / e_mod);
                }
            }
        }
    }
    vec![Row::with_error(&name, "max |σ| / E over all steps", 0.0, err, err, 1e-8, src)]
}

/// TL and UL on the same large-deformation elasto-plastic problem (the default job: 30 %
/// upsetting of an aluminium block with Table 1 hardening): displacements and reaction agree.
pub fn tl_equals_ul() -> Vec<Row> {
    let name = "TL = UL (default job, 30 % upsetting, Table 1)";
    let src = "Bathe 1996, ch. 6.3: TL and UL are the same linearisation";
    let mut out = Vec::new();
    let mut runs = Vec::new();
    for f in [Formulation::TotalLagrangian, Formulation::UpdatedLagrangian] {
        let mut c = case::default_case();
        c.formulation = f;
        match simulate(&c) {
            Ok(r) => runs.push(r),
            Err(e) => return vec![Row::failed(name, "displacement", &e)],
        }
    }
    let (tl, ul) = (&runs[0], &runs[1]);
    let umax = ul.0.sol.u.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let du = tl.0.sol.u.iter().zip(&ul.0.sol.u).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    out.push(Row::with_error(name, "max |u_TL − u_UL| / max |u|", umax, umax, du / umax, 1e-6, src));
    let r_tl = tl.1.last().map_or(f64::NAN, |r| r.reactions.first().map_or(f64::NAN, |v| v[1]));
    let r_ul = ul.1.last().map_or(f64::NAN, |r| r.reactions.first().map_or(f64::NAN, |v| v[1]));
    out.push(Row::relative(name, "top reaction force (N/mm)", r_ul, r_tl, 1e-6, src));
    out
}

/// Tip displacement of Cook's membrane (plane strain, linear regime) for an n × n mesh.
pub fn cook_tip(n: usize, e: f64, nu: f64, force: f64) -> Result<f64, String> {
    cook_tip_with(n, e, nu, force, None)
}

/// [`cook_tip`] with the element technology overridden (`None`: the case file's, enhanced).
pub fn cook_tip_with(n: usize, e: f64, nu: f64, force: f64, element: Option<crate::element::ElementKind>) -> Result<f64, String> {
    let mut c = verification_case(COOK);
    if let Some(k) = element {
        c.element = k;
    }
    c.bodies[0].divisions = Some([n, n]);
    let scale = 1e-5;
    c.materials[0].material = crate::material::Material::Elastic(crate::material::Elastic::new(e, nu));
    c.loads[0].kind = case::LoadKind::Force([0.0, force * scale]);
    let (sim, _) = simulate(&c)?;
    let tip = nearest_node(&sim.model, [48.0, 60.0]);
    Ok(sim.sol.u[2 * tip + 1] / scale)
}

/// Cook's membrane, compressible (E = 1, ν = 1/3, F = 1) and nearly incompressible
/// (E = 250, ν = 0.4999, F = 100): converged tip displacement within 1 % of the published
/// references, and a coarse 4 × 4 mesh within 10 % of the converged value for ν = 0.4999.
pub fn cook_membrane(fine: usize) -> Vec<Row> {
    let mut rows = Vec::new();
    let (ref_c, src_c) = analytical::cook::COMPRESSIBLE_PLANE_STRAIN;
    let (ref_i, src_i) = analytical::cook::NEARLY_INCOMPRESSIBLE_PLANE_STRAIN;
    match cook_tip(fine, 1.0, 1.0 / 3.0, 1.0) {
        Ok(v) => rows.push(Row::relative("Cook's membrane ν = 1/3", &format!("tip u_y, {fine}×{fine} mesh (mm)"), ref_c, v, 0.01, src_c)),
        Err(e) => rows.push(Row::failed("Cook's membrane ν = 1/3", "tip u_y", &e)),
    }
    match (cook_tip(fine, 250.0, 0.4999, 100.0), cook_tip(4, 250.0, 0.4999, 100.0)) {
        (Ok(v), Ok(v4)) => {
            rows.push(Row::relative("Cook's membrane ν = 0.4999", &format!("tip u_y, {fine}×{fine} mesh (mm)"), ref_i, v, 0.01, src_i));
            rows.push(Row::relative("Cook's membrane ν = 0.4999", "tip u_y, 4×4 mesh vs converged (no locking)", ref_i, v4, 0.10, src_i));
        }
        (Err(e), _) | (_, Err(e)) => rows.push(Row::failed("Cook's membrane ν = 0.4999", "tip u_y", &e)),
    }
    rows
}

/// Hill's thick-walled cylinder (incompressible, elastic–perfectly plastic, plane strain):
/// first-yield pressure, plastic-front radius against pressure, and limit pressure.
pub fn thick_cylinder() -> Vec<Row> {
    let name = "Hill thick-walled cylinder";
    let src = "Hill 1950, The Mathematical Theory of Plasticity, ch. V.3";
    let c = verification_case(CYLINDER);
    let model = match Model::from_case(&c) {
        Ok(m) => m,
        Err(e) => return vec![Row::failed(name, "pressure", &e.to_string())],
    };
    let (a, b, sy) = (100.0, 200.0, 240.0);
    let k = sy / 3f64.sqrt();
    let inner = model.bodies[0].mesh.node_set("inner").unwrap_or_default();
    let mut sim = match Simulation::new(model, c.time.clone(), c.solver.clone()) {
        Ok(s) => s,
        Err(e) => return vec![Row::failed(name, "pressure", &e.to_string())],
    };
    // centroids of the Gauss points (reference radius) for the front and first yield
    let gauss_r: Vec<[f64; 4]> = sim
        .model
        .elements
        .iter()
        .map(|el| {
            let xx0 = el.map(|n| sim.model.x0[n]);
            let mut r = [0.0; 4];
            for (q, gp) in crate::element::GAUSS.iter().enumerate() {
                let nn = crate::element::shape(gp[0], gp[1]);
                let (mut x, mut y) = (0.0, 0.0);
                for i in 0..4 {
                    x += nn[i] * xx0[i][0];
                    y += nn[i] * xx0[i][1];
                }
                r[q] = (x * x + y * y).sqrt();
            }
            r
        })
        .collect();
    let mut history = Vec::new(); // (pressure, max eq. stress at r=a extrapolated, front radius, a_cur, b_cur)
    let mut first_yield: Option<f64> = None;
    let mut front_row: Option<Row> = None;
    let _ = sim.run(&mut |s, _| {
        let x = s.coords(&s.sol.u);
        // pressure = Σ radial reactions / current inner arc length
        let mut fr = 0.0;
        for &n in &inner {
            let rr = s.nodal_reaction(n);
            let len = (x[n][0].powi(2) + x[n][1].powi(2)).sqrt();
            fr += (rr[0] * x[n][0] + rr[1] * x[n][1]) / len;
        }
        let mut arc = 0.0;
        for w in inner.windows(2) {
            let _ = w;
        }
        let mut pts: Vec<[f64; 2]> = inner.iter().map(|&n| x[n]).collect();
        pts.sort_by(|p, q| p[1].atan2(p[0]).total_cmp(&q[1].atan2(q[0])));
        for w in pts.windows(2) {
            arc += ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt();
        }
        let p = fr / arc;
        // first yield: extrapolate the von Mises stress to r = a with the elastic 1/r² law
        let mut q_a: f64 = 0.0;
        let mut r_plastic: f64 = a;
        let mut r_elastic: f64 = b;
        for (e, sig) in s.sol.fields.sig.iter().enumerate() {
            for g in 0..4 {
                let st = sig[g];
                let m = (st[0] + st[1] + st[3]) / 3.0;
                let (sx, syy, sz) = (st[0] - m, st[1] - m, st[3] - m);
                let q = (1.5 * (sx * sx + syy * syy + sz * sz + 2.0 * st[2] * st[2])).sqrt();
                let r = gauss_r[e][g];
                q_a = q_a.max(q * (r / a).powi(2));
                if s.sol.fields.states[e][g].eps_p > 0.0 {
                    r_plastic = r_plastic.max(r);
                } else {
                    r_elastic = r_elastic.min(r);
                }
            }
        }
        let yielded = s.sol.fields.states.iter().any(|st| st.iter().any(|g| g.eps_p > 0.0));
        if !yielded {
            first_yield = Some(p * sy / q_a);
        }
        let a_cur = a + s.sol.u[2 * inner[0]].hypot(s.sol.u[2 * inner[0] + 1]);
        history.push((p, yielded, 0.5 * (r_plastic + r_elastic.max(r_plastic)), a_cur));
        // plastic front once it is well inside the wall
        if front_row.is_none() && yielded && r_plastic > 140.0 && r_plastic < 170.0 {
            let c_ref = analytical::hill::front_radius(p, a, b, k);
            front_row = Some(Row::relative(name, &format!("plastic front radius at p = {p:.1} MPa (mm)"), c_ref, 0.5 * (r_plastic + r_elastic), 0.02, src));
        }
    });
    let mut rows = Vec::new();
    match first_yield {
        Some(py) => rows.push(Row::relative(name, "first-yield pressure (MPa)", analytical::hill::first_yield_pressure(a, b, k), py, 0.01, src)),
        None => rows.push(Row::failed(name, "first-yield pressure", "no elastic step")),
    }
    rows.push(front_row.unwrap_or_else(|| Row::failed(name, "plastic front radius", "front never between 140 and 170 mm")));
    match history.last() {
        Some(&(p, _, _, _)) if sim.sol.time >= c.time.end * (1.0 - 1e-9) => {
            // limit pressure on the current geometry (incompressible: b'² − a'² = b² − a²)
            let x = sim.coords(&sim.sol.u);
            let a_cur = x[inner[0]][0].hypot(x[inner[0]][1]);
            let b_cur = (b * b - a * a + a_cur * a_cur).sqrt();
            rows.push(Row::relative(name, "limit pressure 2k ln(b/a) (MPa)", analytical::hill::limit_pressure(a_cur, b_cur, k), p, 0.01, src));
        }
        _ => rows.push(Row::failed(name, "limit pressure", "run did not reach the end")),
    }
    rows
}

/// An exactly incompressible block compressed 30 %: relative area change ≤ 1e-6.
pub fn incompressible_block() -> Vec<Row> {
    let name = "incompressible block, 30 % compression";
    match simulate(&verification_case(INCOMPRESSIBLE)) {
        Ok((_, reports)) => {
            let worst = reports.iter().map(|r| r.volume_error).fold(0.0, f64::max);
            vec![Row::with_error(name, "max |A − A₀| / A₀ over all steps", 0.0, worst, worst, 1e-6, "incompressibility, ν = 0.5")]
        }
        Err(e) => vec![Row::failed(name, "area change", &e)],
    }
}

/// Run the whole verification set.
pub fn run_all() -> Vec<Row> {
    let mut rows = Vec::new();
    for f in [Formulation::TotalLagrangian, Formulation::UpdatedLagrangian] {
        rows.extend(patch_test(f));
        rows.extend(rigid_rotation(f));
    }
    rows.extend(patch_test_with(Formulation::UpdatedLagrangian, crate::element::ElementKind::Q1P0Enhanced));
    rows.extend(tl_equals_ul());
    rows.extend(cook_membrane(64));
    rows.extend(thick_cylinder());
    rows.extend(creep_block());
    rows.extend(incompressible_block());
    rows
}

/// The table as text.
pub fn format_table(rows: &[Row]) -> String {
    let mut s = format!(
        "{:<44} {:<52} {:>13} {:>13} {:>10} {:>9} {}\n",
        "case", "quantity", "reference", "ours", "error", "tolerance", "pass"
    );
    s.push_str(&"-".repeat(152));
    s.push('\n');
    for r in rows {
        s.push_str(&format!(
            "{:<44} {:<52} {:>13.6e} {:>13.6e} {:>10.2e} {:>9.1e} {}\n",
            r.case,
            r.quantity,
            r.reference,
            r.ours,
            r.error,
            r.tolerance,
            if r.pass { "PASS" } else { "FAIL" }
        ));
    }
    s
}

/// Run the creep block with time step `dt` and creep parameters `params`; returns
/// (time, log strain ln(1 + u_x/L)) per step and the shear modulus.
fn creep_run(dt: f64, params: Option<crate::material::CreepParams>, ramp: bool) -> Result<(Vec<(f64, f64)>, f64, crate::material::CreepParams), String> {
    let mut c = verification_case(CREEP);
    if ramp {
        c.loads[0].amplitude = case::Amplitude::Ramp;
    }
    c.time.dt = dt;
    c.time.dt_max = dt;
    let law = match &c.materials[0].material {
        crate::material::Material::Creep(m) => m.clone(),
        _ => return Err("creep_block.toml must use a creep material".into()),
    };
    let p = params.unwrap_or(law.params);
    c.materials[0].material = crate::material::Material::Creep(crate::material::Creep::new(law.e, law.nu, p));
    let g = c.materials[0].material.shear_modulus();
    let (_, reports) = simulate(&c)?;
    Ok((reports.iter().map(|r| (r.time, (1.0 + r.displacements[0][0]).ln())).collect(), g, p))
}

/// Plane-strain creep against the closed forms of eq. 29: constant stress with Table 2
/// (time hardening, m = 0) and with strain hardening (m = −0.5), at every step; and a stress
/// ramp σ = σ̇ t (strain hardening), where the step-frozen stress makes the scheme first order:
/// the observed order of the error at 43 s under dt halving must be ≥ 0.9.
pub fn creep_block() -> Vec<Row> {
    let name = "creep (eq. 29), plane-strain block";
    let src = "closed forms of eq. 29 (src/analytical/creep*.rs)";
    let sigma = 1.0;
    let mut rows = Vec::new();
    let sh = crate::material::CreepParams { a: 2.0e-8, n: 0.826, m: -0.5, p: 0.0, q: 0.22, temperature: 1.0, stress_scale: 1e6 };
    for (label, params) in [("Table 2, m = 0", None), ("m = −0.5", Some(sh))] {
        match creep_run(1.0, params, false) {
            Ok((hist, g, p)) => {
                let mut err: f64 = 0.0;
                for &(t, e) in &hist {
                    let ex = analytical::creep::plane_strain_uniaxial_log_strain(g, &p, sigma, t);
                    err = err.max(((e - ex) / ex).abs());
                }
                let (t, e) = *hist.last().unwrap_or(&(0.0, f64::NAN));
                let ex = analytical::creep::plane_strain_uniaxial_log_strain(g, &p, sigma, t);
                rows.push(Row::with_error(name, &format!("{label}, σ = 1 MPa: ε_xx at 43 s (max error over 1 s steps)"), ex, e, err, 0.005, src));
            }
            Err(e) => rows.push(Row::failed(name, label, &e)),
        }
    }
    // stress ramp 0 → 1 MPa over 43 s: error at the end for dt = 43/32 … 43/256
    let rate = sigma / 43.0;
    let mut errs = Vec::new();
    for k in 0..4 {
        let dt = 43.0 / (32.0 * 2f64.powi(k));
        match creep_run(dt, Some(sh), true) {
            Ok((hist, g, p)) => {
                let (t, e) = *hist.last().unwrap_or(&(0.0, f64::NAN));
                let ex = analytical::creep_ramp::plane_strain_ramp_log_strain(g, &p, rate, t);
                errs.push((dt, e, ex, ((e - ex) / ex).abs()));
            }
            Err(e) => {
                rows.push(Row::failed(name, "stress ramp", &e));
                return rows;
            }
        }
    }
    if let Some(&(dt, e, ex, err)) = errs.last() {
        // first order: 1.1 % at dt = 0.168 s, halving with dt (the 0.5 % criterion of the
        // issue is for the constant-stress closed form above, met at round-off)
        rows.push(Row::with_error(name, &format!("m = −0.5, stress ramp: ε_xx at 43 s, dt = {dt:.3} s"), ex, e, err, 0.02, src));
    }
    let n = errs.len();
    if n >= 2 {
        let order = (errs[n - 2].3 / errs[n - 1].3).log2();
        rows.push(Row::with_error(name, "stress ramp: observed order in dt (error = max(0, 1 − order))", 1.0, order, (1.0 - order).max(0.0), 0.1, src));
    }
    rows
}
