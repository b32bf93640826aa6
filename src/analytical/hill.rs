//! Thick-walled cylinder under internal pressure, plane strain, incompressible
//! elastic–perfectly plastic von Mises material (Hill 1950, *The Mathematical Theory of
//! Plasticity*, ch. V.3; also Chakrabarty, *Theory of Plasticity*, §5.3).
//!
//! With inner radius a, outer radius b and shear yield stress k = σ_y/√3 (von Mises in plane
//! strain with ν = 1/2):
//! - first yield at the bore: p_y = k (1 − a²/b²);
//! - elastic–plastic, front at radius c: p = k (1 − c²/b² + 2 ln(c/a));
//! - limit (fully plastic, c = b): p_L = 2k ln(b/a).

/// First-yield pressure k (1 − a²/b²) (MPa).
pub fn first_yield_pressure(a: f64, b: f64, k: f64) -> f64 {
    k * (1.0 - a * a / (b * b))
}

/// Pressure for a plastic front at radius c, a ≤ c ≤ b (MPa).
pub fn pressure_for_front(c: f64, a: f64, b: f64, k: f64) -> f64 {
    k * (1.0 - c * c / (b * b) + 2.0 * (c / a).ln())
}

/// Limit pressure 2k ln(b/a) (MPa).
pub fn limit_pressure(a: f64, b: f64, k: f64) -> f64 {
    2.0 * k * (b / a).ln()
}

/// Plastic front radius for a pressure p_y ≤ p ≤ p_L (inverse of [`pressure_for_front`],
/// which increases monotonically in c on [a, b]; solved by bisection to 1e-12 relative).
pub fn front_radius(p: f64, a: f64, b: f64, k: f64) -> f64 {
    let (mut lo, mut hi) = (a, b);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if pressure_for_front(mid, a, b, k) < p {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-12 * b {
            break;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_inverts_pressure_and_meets_the_limits() {
        let (a, b, k) = (100.0, 200.0, 240.0 / 3f64.sqrt());
        // c = a gives first yield, c = b the limit pressure (closed forms above)
        assert!((pressure_for_front(a, a, b, k) - first_yield_pressure(a, b, k)).abs() < 1e-12 * k);
        assert!((pressure_for_front(b, a, b, k) - limit_pressure(a, b, k)).abs() < 1e-12 * k);
        let c = front_radius(pressure_for_front(150.0, a, b, k), a, b, k);
        assert!((c - 150.0).abs() < 1e-9);
    }
}
