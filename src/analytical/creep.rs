//! Closed forms for the creep law of eq. 29 of the paper (material point, constant stress).
//!
//! ## Equivalent creep strain under constant equivalent stress
//! With q constant, eq. 29 reads dε̄/dt = K ε̄ᵐ q_t t^(q_t−1), K = A (s q)ⁿ Tᵖ. Separating
//! variables, ε̄^(−m) dε̄ = K d(t^(q_t)); integrating from ε̄(0) = 0 (needs m < 1):
//! ε̄^(1−m)/(1 − m) = K t^(q_t), hence
//! ```text
//!   ε̄ᶜ(t) = [(1 − m) A (s q)ⁿ Tᵖ t^(q_t)]^(1/(1−m)).
//! ```
//! Check: for m = 0 this is K t^(q_t), whose derivative K q_t t^(q_t−1) is eq. 29.
//! From a pre-strained state ε̄ᶜ(0) = ε̄₀ the same integration gives
//! ε̄ᶜ(t) = [ε̄₀^(1−m) + (1 − m) K t^(q_t)]^(1/(1−m)).
//!
//! These constant-stress forms are what the material update (`material::creep`) reproduces to
//! roundoff at any step size: it integrates the separable ODE exactly over each step with q
//! frozen at its end-of-step value.
//!
//! ## Linear stress ramp
//! With q(t) = q₁ t/t₁ (a stress ramp reaching q₁ at t₁) the law is still separable:
//! ε̄^(−m) dε̄ = K₁ (t/t₁)ⁿ q_t t^(q_t−1) dt, K₁ = A (s q₁)ⁿ Tᵖ, and from ε̄ᶜ(0) = 0
//! ```text
//!   ε̄ᶜ(t) = [(1 − m) K₁ q_t/(n + q_t) · t^(q_t) (t/t₁)ⁿ]^(1/(1−m)).
//! ```
//! Check: for m = 0, d/dt [K₁ q_t/(n + q_t) t^(n+q_t)/t₁ⁿ] = K₁ q_t t^(q_t−1) (t/t₁)ⁿ, eq. 29 at
//! q = q₁ t/t₁. The material update freezes q at the end of each step, so it is first order
//! here; tests/material_point.rs uses this case for the convergence-order study.
//!
//! ## Plane-strain uniaxial creep of an incompressible material point
//! F = diag(λ, 1/λ, 1), total Kirchhoff stress τ_xx = σ, τ_yy = 0 (the pressure p makes
//! τ_yy = 0), so τ′_xx − τ′_yy = σ. Logarithmic strains are additive along the fixed principal
//! axes: ε = ε_e + ε_c. The creep flow direction is (3/2) s/q; initially ε_c = 0 and ε_e,zz = 0
//! (plane strain, isochoric), so s_zz = 2G dev(ε_e)_zz = 0 and it stays 0. Then
//! s = diag(σ/2, −σ/2, 0), q = √(3/2 · 2 (σ/2)²) = (√3/2) σ, the elastic log strain is
//! ε_e,xx = s_xx/(2G) = σ/(4G) and the creep log strain is ε_c,xx = (3/2)(σ/2)/q · ε̄ᶜ = (√3/2) ε̄ᶜ:
//! ```text
//!   ln λ = ε_xx(t) = σ/(4G) + (√3/2) ε̄ᶜ(t)   with q = (√3/2) σ.
//! ```
//! The same holds for a time-varying σ(t) of fixed sign (the flow direction does not change),
//! with σ = σ(t) and ε̄ᶜ(t) from q(t) = (√3/2)|σ(t)|, e.g. the linear ramp above.
//! Source: eq. 29 of the compaction paper (`/work/shared/seeds/000_e93b1aa71ee83dbe.txt`, §5.2);
//! derivation above (standard power-law creep, e.g. Kraus, *Creep Analysis*, 1980).
use crate::material::CreepParams;

/// ε̄ᶜ(t) under constant von Mises stress `q` (MPa), from ε̄ᶜ(0) = 0 (module docs).
pub fn equivalent_creep_strain(p: &CreepParams, q: f64, t: f64) -> f64 {
    let k = p.a * (p.stress_scale * q).powf(p.n) * p.temperature.powf(p.p);
    ((1.0 - p.m) * k * t.max(0.0).powf(p.q)).powf(1.0 / (1.0 - p.m))
}

/// ε̄ᶜ(t) under constant `q` from the initial creep strain ε̄ᶜ(0) = `eps0` ≥ 0 (module docs).
pub fn equivalent_creep_strain_from(p: &CreepParams, q: f64, t: f64, eps0: f64) -> f64 {
    let k = p.a * (p.stress_scale * q).powf(p.n) * p.temperature.powf(p.p);
    (eps0.powf(1.0 - p.m) + (1.0 - p.m) * k * t.max(0.0).powf(p.q)).powf(1.0 / (1.0 - p.m))
}

/// As [`plane_strain_uniaxial_log_strain`] from a pre-strained state with creep strain
/// `eps0` accumulated under the same stress direction (creep log strain (√3/2) ε̄₀ along x).
pub fn plane_strain_uniaxial_log_strain_from(
    g: f64,
    p: &CreepParams,
    sigma: f64,
    t: f64,
    eps0: f64,
) -> f64 {
    let q = 0.5 * 3f64.sqrt() * sigma.abs();
    sigma / (4.0 * g)
        + sigma.signum() * 0.5 * 3f64.sqrt() * equivalent_creep_strain_from(p, q, t, eps0)
}

/// Log strain ε_xx = ln λ at time `t` of the incompressible plane-strain point under constant
/// Kirchhoff stress τ_xx = `sigma` (τ_yy = 0), shear modulus `g` (module docs).
pub fn plane_strain_uniaxial_log_strain(g: f64, p: &CreepParams, sigma: f64, t: f64) -> f64 {
    let q = 0.5 * 3f64.sqrt() * sigma.abs();
    sigma / (4.0 * g) + sigma.signum() * 0.5 * 3f64.sqrt() * equivalent_creep_strain(p, q, t)
}

/// ε̄ᶜ(t) under the linear ramp q(τ) = `q_end` τ/`t_end` from ε̄ᶜ(0) = 0 (module docs).
pub fn equivalent_creep_strain_ramp(p: &CreepParams, q_end: f64, t_end: f64, t: f64) -> f64 {
    let k1 = p.a * (p.stress_scale * q_end).powf(p.n) * p.temperature.powf(p.p);
    let t = t.max(0.0);
    let integral = k1 * p.q / (p.n + p.q) * t.powf(p.q) * (t / t_end).powf(p.n);
    ((1.0 - p.m) * integral).powf(1.0 / (1.0 - p.m))
}

/// Log strain ε_xx = ln λ at time `t` of the incompressible plane-strain point under the
/// linear Kirchhoff stress ramp τ_xx = `sigma_end` t/`t_end` (τ_yy = 0), shear modulus `g`.
pub fn plane_strain_uniaxial_log_strain_ramp(
    g: f64,
    p: &CreepParams,
    sigma_end: f64,
    t_end: f64,
    t: f64,
) -> f64 {
    let q_end = 0.5 * 3f64.sqrt() * sigma_end.abs();
    let sigma = sigma_end * t / t_end;
    sigma / (4.0 * g)
        + sigma_end.signum() * 0.5 * 3f64.sqrt() * equivalent_creep_strain_ramp(p, q_end, t_end, t)
}
