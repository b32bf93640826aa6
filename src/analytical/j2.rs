//! Closed forms for von Mises plasticity in plane-strain uniaxial loading of an incompressible
//! material point (F = diag(λ, 1/λ, 1), τ_yy = 0 through the pressure).
//!
//! With e = ln λ, the log strain is diag(e, −e, 0); by the argument of
//! [`crate::analytical::creep`] the out-of-plane deviator stays zero, so s = diag(s, −s, 0),
//! q = √3 |s| and the total stress is τ_xx = τ′_xx − τ′_yy = 2s.
//! - Elastic: s = 2G e, so τ_xx = 4G e.
//! - Yield (q = σ_y): τ_xx = 2σ_y/√3 (the plane-strain von Mises "2k" with k = σ_y/√3),
//!   at e_y = σ_y/(2√3 G).
//! - Plastic: the plastic log strain is ε_p,xx = (3/2)(s/q) ε̄ᵖ = (√3/2) ε̄ᵖ and
//!   e = σ_y(ε̄ᵖ)/(2√3 G) + (√3/2) ε̄ᵖ. For linear hardening σ_y = σ₀ + H ε̄ᵖ:
//!   σ_y = (2√3 G H e + 3G σ₀)/(3G + H) (e ≥ e_y), τ_xx = 2σ_y/√3; H = 0 gives the plateau.
//!
//! Source: von Mises plane-strain yield (Hill, *The Mathematical Theory of Plasticity*, 1950,
//! ch. VI; de Souza Neto, Perić & Owen 2008, §6.4); the large-strain result is exact because
//! with fixed principal axes the exponential map makes the log-strain return identical to the
//! small-strain one.
use crate::material::HardeningTable;

/// Total τ_xx at first yield (plane strain, incompressible): 2σ_y/√3.
pub fn plane_strain_yield_stress(sigma_y: f64) -> f64 {
    2.0 * sigma_y / 3f64.sqrt()
}

/// τ_xx(e) for linear hardening σ_y = σ₀ + H ε̄ᵖ under monotonic loading, e = ln λ (either sign).
pub fn plane_strain_uniaxial_linear(g: f64, sigma0: f64, h: f64, e: f64) -> f64 {
    let s3 = 3f64.sqrt();
    let ea = e.abs();
    let sy = if ea <= sigma0 / (2.0 * s3 * g) {
        2.0 * s3 * g * ea
    } else {
        (2.0 * s3 * g * h * ea + 3.0 * g * sigma0) / (3.0 * g + h)
    };
    e.signum() * 2.0 * sy / s3
}

/// τ_xx(e) and ε̄ᵖ(e) for a piecewise-linear table under monotonic loading from a virgin state:
/// solves e = σ_y(ε̄ᵖ)/(2√3G) + (√3/2) ε̄ᵖ segment by segment (the right side is increasing).
pub fn plane_strain_uniaxial_table(g: f64, table: &HardeningTable, e: f64) -> (f64, f64) {
    let s3 = 3f64.sqrt();
    let ea = e.abs();
    let strain_at = |ep: f64, sy: f64| sy / (2.0 * s3 * g) + 0.5 * s3 * ep;
    if ea <= strain_at(0.0, table.sigma_y[0]) {
        return (e.signum() * 4.0 * g * ea, 0.0);
    }
    let nseg = table.eps_p.len();
    for k in 0..nseg {
        let h = table.slope(k);
        let last = k + 1 == nseg;
        if last || ea <= strain_at(table.eps_p[k + 1], table.sigma_y[k + 1]) {
            // e = (σ_k + h (ε̄ − ε̄_k))/(2√3G) + (√3/2) ε̄  → linear in ε̄
            let ep = (ea - (table.sigma_y[k] - h * table.eps_p[k]) / (2.0 * s3 * g))
                / (h / (2.0 * s3 * g) + 0.5 * s3);
            let sy = table.sigma_y[k] + h * (ep - table.eps_p[k]);
            return (e.signum() * 2.0 * sy / s3, ep);
        }
    }
    unreachable!("the last segment is unbounded")
}
