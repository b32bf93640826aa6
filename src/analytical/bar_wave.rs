//! A suddenly loaded elastic bar in uniaxial strain: the d'Alembert solution of the 1D wave
//! equation (e.g. K. F. Graff, *Wave Motion in Elastic Solids*, 1975, ch. 2; Timoshenko &
//! Goodier, *Theory of Elasticity*, the longitudinal impact of bars).
//!
//! A column of height L, fixed at y = 0, free at y = L, held on rollers at its sides so that
//! only u_y(y, t) is non-zero (uniaxial strain, plane strain), is at rest when a traction P
//! is applied at t = 0 on its free end and then held. The constrained (P-wave) modulus and
//! the wave speed are
//! ```text
//!   M_c = E (1 − ν) / ((1 + ν)(1 − 2ν)),   c = √(M_c / ρ).
//! ```
//! The front of the stress wave −P leaves the loaded end with particle velocity P/(ρ c),
//! reflects at the fixed end (stress doubled, velocity zero) and returns at t = 2L/c, which
//! reverses the end velocity. The end displacement is therefore a triangle wave: it grows
//! linearly from 0 to 2 u_s at t = 2L/c and returns linearly to 0 at t = 4L/c, with
//! ```text
//!   u_s = P L / M_c (the static end displacement),  period T = 4 L / c,  peak 2 u_s.
//! ```

/// Constrained (uniaxial-strain) modulus M_c = E(1 − ν)/((1 + ν)(1 − 2ν)) (MPa).
pub fn constrained_modulus(e: f64, nu: f64) -> f64 {
    e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))
}

/// Speed of the uniaxial-strain wave c = √(M_c/ρ) (mm/s for MPa and t/mm³).
pub fn wave_speed(e: f64, nu: f64, rho: f64) -> f64 {
    (constrained_modulus(e, nu) / rho).sqrt()
}

/// Period of the free-end displacement, T = 4 L / c (s).
pub fn period(length: f64, c: f64) -> f64 {
    4.0 * length / c
}

/// End displacement at time t ≥ 0 (same sign as the static one `u_static` = P L / M_c):
/// the triangle wave 2 u_s · tri(t / T) with tri rising from 0 to 1 on [0, 1/2] and back.
pub fn end_displacement(t: f64, period: f64, u_static: f64) -> f64 {
    let s = (t / period).rem_euclid(1.0);
    2.0 * u_static * if s <= 0.5 { 2.0 * s } else { 2.0 * (1.0 - s) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_wave() {
        assert_eq!(end_displacement(0.0, 2.0, 1.0), 0.0);
        assert!((end_displacement(1.0, 2.0, 1.0) - 2.0).abs() < 1e-15);
        assert!((end_displacement(2.5, 2.0, 1.0) - 1.0).abs() < 1e-15);
        // ν = 0: M_c = E
        assert_eq!(constrained_modulus(3.0, 0.0), 3.0);
    }
}
