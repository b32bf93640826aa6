//! Creep of eq. 29 under a von Mises stress that grows linearly in time, q(t) = k t.
//!
//! Eq. 29 with q = k t is separable: ε̄⁻ᵐ dε̄ = A (s k)ⁿ Tᵖ q_t t^(n + q_t − 1) dt, so from
//! ε̄(0) = 0 (m < 1)
//! ```text
//!   ε̄ᶜ(t) = [ (1 − m) A (s k)ⁿ Tᵖ q_t t^(n + q_t) / (n + q_t) ]^(1/(1−m)).
//! ```
//! Check: for m = 0 its derivative is A (s k t)ⁿ Tᵖ q_t t^(q_t − 1), eq. 29 with q = k t.
//! In the plane-strain incompressible block of `analytical::creep` (s_zz = 0, q = (√3/2) σ) a
//! Cauchy stress σ(t) = σ̇ t gives k = (√3/2) σ̇ and the log strain
//! ε_xx = σ(t)/(4G) + (√3/2) ε̄ᶜ(t). A time integrator that freezes the stress over a step is
//! first-order accurate on this problem, which makes it the convergence test of the scheme.
use crate::material::CreepParams;

/// ε̄ᶜ(t) for q(t) = k t (module docs).
pub fn equivalent_creep_strain_ramp(p: &CreepParams, k: f64, t: f64) -> f64 {
    let e = p.n + p.q;
    let c = (1.0 - p.m) * p.a * (p.stress_scale * k).powf(p.n) * p.temperature.powf(p.p) * p.q / e;
    (c * t.max(0.0).powf(e)).powf(1.0 / (1.0 - p.m))
}

/// Log strain ε_xx of the plane-strain block under Cauchy stress σ(t) = `rate` · t (MPa/s).
pub fn plane_strain_ramp_log_strain(g: f64, p: &CreepParams, rate: f64, t: f64) -> f64 {
    let k = 0.5 * 3f64.sqrt() * rate;
    rate * t / (4.0 * g) + 0.5 * 3f64.sqrt() * equivalent_creep_strain_ramp(p, k, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form satisfies eq. 29 (central difference of ε̄ against the rate, 1e-6).
    #[test]
    fn ramp_closed_form_satisfies_eq29() {
        let p = CreepParams { a: 2e-8, n: 0.826, m: -0.5, p: 0.0, q: 0.22, temperature: 1.0, stress_scale: 1e6 };
        let k = 0.05;
        for &t in &[1.0, 7.0, 30.0] {
            let h = 1e-4 * t;
            let de = (equivalent_creep_strain_ramp(&p, k, t + h) - equivalent_creep_strain_ramp(&p, k, t - h)) / (2.0 * h);
            let e = equivalent_creep_strain_ramp(&p, k, t);
            let rate = p.a * (p.stress_scale * k * t).powf(p.n) * e.powf(p.m) * p.q * t.powf(p.q - 1.0);
            assert!(((de - rate) / rate).abs() < 1e-6, "t = {t}: {de} vs {rate}");
        }
    }
}
