//! Visco-plastic creep, eq. 29 of the paper (time- and strain-hardening power law).
//!
//! ## Law
//! ```text
//!   dε̄ᶜ/dt = A (s q)ⁿ (ε̄ᶜ)ᵐ Tᵖ · q_t t^(q_t − 1)
//! ```
//! with q the von Mises equivalent Kirchhoff stress in MPa, s = `stress_scale` the factor that
//! converts MPa into the stress unit the constants were fitted in (1 for MPa, 10⁶ for Pa),
//! T = `temperature`, q_t = field `q` (time exponent), m the strain-hardening exponent
//! (m = 0: pure time hardening). The flow is deviatoric along N = (3/2) s/q, carried by the
//! same exponential map as J2 plasticity ([`logstrain`]).
//!
//! ## Integration (implicit in the stress, exact in the strain dependence)
//! At fixed q the law is separable, (ε̄ᶜ)^(−m) dε̄ᶜ = A (s q)ⁿ Tᵖ d(t^(q_t)). The update
//! integrates this exactly over the step with q frozen at its end-of-step value (backward Euler
//! in the stress only; t_n = `inc.time − inc.dt`, clamped at 0):
//! ```text
//!   φ(Δε̄ᶜ) := [(ε̄ᶜ_n + Δε̄ᶜ)^(1−m) − (ε̄ᶜ_n)^(1−m)] / (1 − m) = C qⁿ,
//!   q = q_tr − 3G Δε̄ᶜ,   C = A sⁿ Tᵖ (t_{n+1}^{q_t} − t_n^{q_t}).
//! ```
//! For m = 0, φ(x) = x and this is the plain backward-Euler update Δε̄ᶜ = C qⁿ. Why not backward
//! Euler in the strain as well (Δε̄ᶜ = C qⁿ (ε̄ᶜ_n + Δε̄ᶜ)ᵐ)? For m ≠ 0 the rate ∝ (ε̄ᶜ)ᵐ is
//! singular (m < 0) or degenerate (m > 0) at ε̄ᶜ = 0: that scheme's first step from a virgin
//! state under constant stress gives (1 − m)^(−1/(1−m)) times the exact ε̄ᶜ (0.76, i.e. 24 %
//! low, for m = −0.5) for every dt, and with q_t < 1 and uniform steps its observed order in dt
//! drops to about q_t. The separable
//! form is exact for constant stress at any dt (the increments of φ telescope to the closed form
//! of `analytical::creep`) and first order in the step for varying stress.
//!
//! The scalar equation is solved as R(x) = φ(x) − C (q_tr − 3Gx)ⁿ = 0 on x ∈ (0, q_tr/(3G)):
//! for m < 1 and n > 0, φ is strictly increasing (φ′(x) = (ε̄ᶜ_n + x)^(−m) > 0) and the second
//! term strictly decreasing, R(0) = −C q_trⁿ < 0 < R(q_tr/3G), so there is exactly one root,
//! found by Newton's method safeguarded by bisection on the bracket, started from the
//! no-relaxation root φ⁻¹(C q_trⁿ) (an upper bound). φ and φ⁻¹ are evaluated with
//! ln_1p/exp_m1 so that x ≪ ε̄ᶜ_n loses no digits. The root is finite and positive also at the
//! singular start m < 0, ε̄ᶜ_n = 0 (φ(x) = x^(1−m)/(1 − m)), and the spurious root x = 0 of
//! 0 < m < 1 at ε̄ᶜ_n = 0 does not occur. m ≥ 1 is rejected ([`CreepParams::validate`]): from
//! a virgin state the creep strain would then stay zero forever (unique solution of the ODE).
//!
//! ## Accuracy
//! Exact (to roundoff) under constant stress for every m < 1, q_t, dt and initial creep strain;
//! first order in the step of the time factor t^(q_t) when the stress varies
//! (tests/material_point.rs: constant-stress errors at roundoff for 43 steps of 1 s with
//! Table 2's q_t = 0.22 and m = −0.5; observed order ≈ 1 under a linear stress ramp).
//!
//! ## Tangent
//! As J2 (de Souza Neto et al. 2008, Box 7.4) with the effective slope H = dq/dΔε̄ᶜ of the
//! discrete creep relation at fixed history and time, from differentiating φ(Δε̄ᶜ) = C qⁿ:
//! φ′ = n C qⁿ⁻¹ H, i.e. (with C qⁿ = φ at the root)
//! ```text
//!   H = q (ε̄ᶜ_n + Δε̄ᶜ)^(−m) / (n φ(Δε̄ᶜ)),
//!   D = 2G (1 − 3GΔε̄ᶜ/q_tr) I_dev + 6G² (Δε̄ᶜ/q_tr − 1/(3G + H)) N̂ ⊗ N̂.
//! ```
//! For m = 0 this is H = q/(n Δε̄ᶜ).
//!
//! ## Symmetry: the update is variational
//! Within a step the history ε̄ᶜ_n and the time factor C are fixed, so the return's stress is a
//! function of the increment alone, q = k(x) := (φ(x)/C)^(1/n), increasing in x. The return
//! q_tr − 3Gx = k(x) is then the stationarity condition of the convex incremental potential
//! (q_tr − 3Gx)²/(6G) + ∫₀ˣ k, for every m < 1 (not only m = 0), exactly as for J2 with
//! σ_y replaced by k ([`super::j2`]). τ′ derives from a potential of F and `cc` has major
//! symmetry (check (d) of `tests/material_conformance.rs`, 1e-10), hence
//! `symmetric_tangent() == true`.
// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
use super::logstrain::exponential_map_update;
use super::*;

/// Parameters of the creep law (eq. 29), see the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CreepParams {
    /// Coefficient A (in the stress unit selected by `stress_scale`).
    pub a: f64,
    /// Stress exponent n > 0.
    pub n: f64,
    /// Strain-hardening exponent m < 1.
    pub m: f64,
    /// Temperature exponent p.
    pub p: f64,
    /// Time exponent q_t > 0 (the paper's q).
    pub q: f64,
    /// Temperature T (in the unit the constants were fitted in).
    pub temperature: f64,
    /// Factor converting MPa into the stress unit of A (1 for MPa, 10⁶ for Pa).
    pub stress_scale: f64,
}

impl CreepParams {
    /// The paper's Table 2 (asphalt): A = 5.15·10⁻⁸, m = 0, n = 0.826, p = 0, q = 0.22, with
    /// T = 1 (irrelevant since p = 0). Goes with E = 526 MPa and ν = 0.5 (incompressible),
    /// see [`ASPHALT_E`] and [`ASPHALT_NU`].
    ///
    /// The source prints A as "0.5.15 × 10⁻⁸"; we read 5.15·10⁻⁸ (see `DESIGN.md`). The paper
    /// does not state the stress unit of A: with stresses in MPa (`stress_scale = 1`) the creep
    /// strain after 43 s at 100 MPa is about 5·10⁻⁶, with stresses in Pa
    /// (`stress_scale = 1e6`, consistent with the paper's SI-sized 1 m model) it is about 0.5 and
    /// creep dominates, as the paper's text implies. The caller chooses explicitly.
    pub fn asphalt_table2(stress_scale: f64) -> Self {
        Self {
            a: 5.15e-8,
            n: 0.826,
            m: 0.0,
            p: 0.0,
            q: 0.22,
            temperature: 1.0,
            stress_scale,
        }
    }

    /// Checks A ≥ 0, n > 0, m < 1, q_t > 0, T > 0, stress_scale > 0 and finite p.
    pub fn validate(&self) -> Result<(), String> {
        let fin = [
            self.a,
            self.n,
            self.m,
            self.p,
            self.q,
            self.temperature,
            self.stress_scale,
        ];
        if fin.iter().any(|v| !v.is_finite()) {
            return Err(format!("creep parameters must be finite: {self:?}"));
        }
        if self.a < 0.0 {
            return Err(format!(
                "creep coefficient A = {} must not be negative",
                self.a
            ));
        }
        if !(self.n > 0.0) {
            return Err(format!(
                "creep stress exponent n = {} must be positive",
                self.n
            ));
        }
        if !(self.m < 1.0) {
            return Err(format!(
                "creep strain exponent m = {} must be < 1 (for m ≥ 1 creep never starts from zero creep strain)",
                self.m
            ));
        }
        if !(self.q > 0.0) {
            return Err(format!(
                "creep time exponent q = {} must be positive",
                self.q
            ));
        }
        if !(self.temperature > 0.0) {
            return Err(format!(
                "creep temperature T = {} must be positive",
                self.temperature
            ));
        }
        if !(self.stress_scale > 0.0) {
            return Err(format!(
                "creep stress_scale = {} must be positive",
                self.stress_scale
            ));
        }
        Ok(())
    }

    /// C = A sⁿ Tᵖ (t_{n+1}^{q_t} − t_n^{q_t}) for the increment (times clamped at 0).
    pub fn step_factor(&self, inc: TimeIncrement) -> f64 {
        let t1 = inc.time.max(0.0);
        let t0 = (inc.time - inc.dt).max(0.0).min(t1);
        let dtime = t1.powf(self.q) - t0.powf(self.q);
        self.a * self.stress_scale.powf(self.n) * self.temperature.powf(self.p) * dtime
    }
}

/// Young's modulus that goes with [`CreepParams::asphalt_table2`] (MPa, Table 2).
pub const ASPHALT_E: f64 = 526.0;
/// Poisson's ratio that goes with [`CreepParams::asphalt_table2`] (Table 2: incompressible).
pub const ASPHALT_NU: f64 = 0.5;

#[derive(Clone, Debug, PartialEq)]
pub struct Creep {
    pub e: f64,
    pub nu: f64,
    pub params: CreepParams,
}

impl Creep {
    /// Young's modulus `e` (MPa), Poisson's ratio `nu`, creep parameters.
    ///
    /// # Panics
    /// If `params` fail [`CreepParams::validate`] (e.g. m ≥ 1); use [`Creep::try_new`] to get
    /// the message as an error instead.
    pub fn new(e: f64, nu: f64, params: CreepParams) -> Self {
        match Self::try_new(e, nu, params) {
            Ok(c) => c,
            Err(msg) => panic!("invalid creep law: {msg}"),
        }
    }

    /// As [`Creep::new`], returning an error for invalid parameters.
    pub fn try_new(e: f64, nu: f64, params: CreepParams) -> Result<Self, String> {
        params.validate()?;
        Ok(Self { e, nu, params })
    }

    /// Solves the discrete creep relation φ(Δε̄ᶜ) = C qⁿ (module docs) for x = Δε̄ᶜ given the
    /// trial equivalent stress, the committed creep strain and the step factor C.
    /// Returns (Δε̄ᶜ, H = dq/dΔε̄ᶜ); (0, ∞) when nothing creeps.
    pub fn return_map(
        &self,
        g: f64,
        q_tr: f64,
        eps_n: f64,
        c: f64,
    ) -> Result<(f64, f64), MaterialError> {
        if !(q_tr > 0.0) || !(c > 0.0) {
            return Ok((0.0, f64::INFINITY));
        }
        let m = self.params.m;
        let n = self.params.n;
        let eps_n = eps_n.max(0.0);
        let three_g = 3.0 * g;
        let x_max = q_tr / three_g;
        // R(x) = φ(x) − C qⁿ and R'(x), for 0 < x < x_max.
        let resid = |x: f64| {
            let qq = q_tr - three_g * x;
            let cqn = c * qq.powf(n);
            let r = creep_phi(m, eps_n, x) - cqn;
            let dr = (eps_n + x).powf(-m) + three_g * n * cqn / qq;
            (r, dr)
        };
        // Start from the root without stress relaxation (an upper bound: R(x) ≥ φ(x) − C q_trⁿ).
        let x_est = creep_phi_inv(m, eps_n, c * q_tr.powf(n));
        let (mut lo, mut hi) = (0.0, x_max);
        let mut x = if x_est > 0.0 && x_est < 0.5 * x_max {
            x_est
        } else {
            0.5 * x_max
        };
        let mut last_r = f64::NAN;
        let mut converged = false;
        for _ in 0..300 {
            let (r, dr) = resid(x);
            last_r = r;
            if r == 0.0 {
                converged = true;
                break;
            }
            if r < 0.0 {
                lo = x;
            } else {
                hi = x;
            }
            let dx = r / dr;
            let xn = x - dx;
            if dx.abs() <= 1e-13 * x {
                // Converged (quadratic: the error of xn is far below the step). Near the root
                // the Newton step may round onto the bracket end; keep x then.
                if xn >= lo && xn <= hi {
                    x = xn;
                }
                converged = true;
                break;
            }
            x = if xn > lo && xn < hi {
                xn
            } else {
                0.5 * (lo + hi)
            };
            if hi - lo <= 4.0 * f64::EPSILON * hi {
                converged = true;
                break;
            }
        }
        if !converged || !x.is_finite() {
            return Err(MaterialError::ReturnMapFailed {
                iterations: 300,
                residual: last_r.abs(),
            });
        }
        let qq = q_tr - three_g * x;
        let h = qq * (eps_n + x).powf(-m) / (n * creep_phi(m, eps_n, x));
        Ok((x, h))
    }
}

/// φ(x) = [(ε̄₀ + x)^(1−m) − ε̄₀^(1−m)] / (1 − m) for ε̄₀ = `eps0` ≥ 0, x ≥ 0, m < 1 (the exact
/// integral of dε̄/ε̄ᵐ, module docs), without cancellation for x ≪ ε̄₀. φ(x) = x for m = 0.
pub fn creep_phi(m: f64, eps0: f64, x: f64) -> f64 {
    let a = 1.0 - m;
    if m == 0.0 {
        x
    } else if eps0 > 0.0 {
        eps0.powf(a) * (a * (x / eps0).ln_1p()).exp_m1() / a
    } else {
        x.powf(a) / a
    }
}

/// Inverse of [`creep_phi`] in x: the creep strain increment x ≥ 0 with φ(x) = `y` ≥ 0,
/// x = (ε̄₀^(1−m) + (1 − m) y)^(1/(1−m)) − ε̄₀.
pub fn creep_phi_inv(m: f64, eps0: f64, y: f64) -> f64 {
    let a = 1.0 - m;
    if m == 0.0 {
        y
    } else if eps0 > 0.0 {
        eps0 * ((a * y / eps0.powf(a)).ln_1p() / a).exp_m1()
    } else {
        (a * y).powf(1.0 / a)
    }
}

impl ConstitutiveLaw for Creep {
    fn elastic_constants(&self) -> (f64, f64) {
        (self.e, self.nu)
    }
    fn symmetric_tangent(&self) -> bool {
        true
    }
    fn update(
        &self,
        ff: &Matrix3<f64>,
        old: &MatState,
        inc: TimeIncrement,
    ) -> Result<MatResponse, MaterialError> {
        let g = self.shear_modulus();
        let c = self.params.step_factor(inc);
        let out = exponential_map_update(ff, &old.cp_inv, g, |q_tr| {
            self.return_map(g, q_tr, old.eps_c, c)
        })?;
        let state = MatState {
            cp_inv: out.cp_inv,
            eps_p: old.eps_p,
            eps_c: old.eps_c + out.dgamma,
        };
        Ok(MatResponse {
            tau: out.tau,
            cc: out.cc,
            thickness: 1.0,
            state,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scalar return solves the discrete relation φ(Δε̄ᶜ) = C qⁿ to roundoff (1e-12 relative
    /// in Δε̄ᶜ plus the rounding of q = q_tr − 3GΔε̄ᶜ) over a wide range of step factors,
    /// stresses, histories and exponents (including the singular start m < 0, ε̄ᶜ_n = 0).
    #[test]
    fn return_map_solves_discrete_relation() {
        for &m in &[-0.5, 0.0, 0.5] {
            for &n in &[0.826, 1.0, 3.0] {
                let law = Creep::new(
                    526.0,
                    0.5,
                    CreepParams {
                        m,
                        n,
                        ..CreepParams::asphalt_table2(1.0)
                    },
                );
                let g = law.shear_modulus();
                for &c in &[1e-14, 1e-8, 1e-3, 1.0, 1e3] {
                    for &q_tr in &[1e-6, 1.0, 100.0, 1e4] {
                        for &eps_n in &[0.0, 1e-6, 0.3] {
                            let (x, h) = law.return_map(g, q_tr, eps_n, c).unwrap();
                            assert!(x > 0.0 && x < q_tr / (3.0 * g) && h > 0.0);
                            let q = q_tr - 3.0 * g * x;
                            // x that solves the relation exactly at this q (closed form).
                            let a = 1.0 - m;
                            let x_rhs = (eps_n.powf(a) + a * c * q.powf(n)).powf(1.0 / a) - eps_n;
                            let x_acc = creep_phi_inv(m, eps_n, c * q.powf(n));
                            // The naive closed form cancels for x ≪ ε̄ᶜ_n; it must agree with
                            // the accurate φ⁻¹ to its own rounding.
                            assert!(
                                (x_rhs - x_acc).abs() <= 1e-12 * x_acc + 8.0 * f64::EPSILON * eps_n
                            );
                            // q = q_tr − 3Gx carries an absolute rounding error ~ u·q_tr, which
                            // moves x_acc by dx/dq · u q_tr; a step that relaxes the stress
                            // completely (q ≤ 1e-12 q_tr) has x = q_tr/3G to roundoff and is not
                            // checked further.
                            let dxdq = n * c * q.powf(n - 1.0) / (eps_n + x).powf(-m);
                            let noise = dxdq * 8.0 * f64::EPSILON * q_tr;
                            let relaxed = q <= 1e-12 * q_tr;
                            assert!(
                                relaxed || (x - x_acc).abs() <= 1e-12 * x + noise,
                                "m={m} n={n} c={c} q={q_tr} e={eps_n}: {x} vs {x_acc}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// Constant stress with no relaxation (q fixed): the increments of φ telescope, so a
    /// sequence of steps reproduces the one-step result to roundoff.
    #[test]
    fn phi_telescopes() {
        for &m in &[-0.5, 0.0, 0.5] {
            let mut e = 0.0;
            for _ in 0..50 {
                e += creep_phi_inv(m, e, 0.02);
            }
            let one = creep_phi_inv(m, 0.0, 1.0);
            assert!((e - one).abs() <= 1e-13 * one, "m={m}: {e} vs {one}");
            assert!((creep_phi(m, 0.0, one) - 1.0).abs() <= 1e-14);
        }
    }
}
