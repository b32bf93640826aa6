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

/// Radial displacement of the outer surface at pressure p ≤ p_L (mm), small strain, shear
/// modulus g = E/3. Incompressibility makes u = B/r in the whole wall; in the elastic zone
/// σ_θ − σ_r = 4 g B / r² and σ_r(b) = 0, so that the elastic wall has p = 2 g B (1/a² − 1/b²),
/// and with a plastic front at c the yield condition σ_θ − σ_r = 2k at r = c gives
/// B = k c² / (2g). Then u_b = B / b.
pub fn outer_displacement(p: f64, a: f64, b: f64, k: f64, g: f64) -> f64 {
    let bb = if p <= first_yield_pressure(a, b, k) {
        p / (2.0 * g * (1.0 / (a * a) - 1.0 / (b * b)))
    } else {
        let c = front_radius(p, a, b, k);
        k * c * c / (2.0 * g)
    };
    bb / b
}

/// The inverse of [`outer_displacement`]: the pressure at which the outer surface has moved
/// by u_b (MPa; p_L once the front has reached b).
pub fn pressure_for_outer_displacement(ub: f64, a: f64, b: f64, k: f64, g: f64) -> f64 {
    let bb = ub * b;
    if bb <= k * a * a / (2.0 * g) {
        2.0 * g * bb * (1.0 / (a * a) - 1.0 / (b * b))
    } else {
        pressure_for_front((2.0 * g * bb / k).sqrt().min(b), a, b, k)
    }
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

    /// u_b is continuous at first yield (the elastic and the elastic–plastic forms meet, 1e-9)
    /// and grows with p; at the limit the front is at b, so u_b = k b / (2g).
    #[test]
    fn outer_displacement_is_continuous_and_reaches_the_limit_form() {
        let (a, b, k, g) = (100.0, 200.0, 240.0 / 3f64.sqrt(), 70_000.0);
        let py = first_yield_pressure(a, b, k);
        let (below, above) = (outer_displacement(py * (1.0 - 1e-12), a, b, k, g), outer_displacement(py * (1.0 + 1e-12), a, b, k, g));
        assert!((below - above).abs() <= 1e-9 * below, "{below} vs {above}");
        assert!((below - k * a * a / (2.0 * g * b)).abs() <= 1e-9 * below);
        let pl = limit_pressure(a, b, k);
        // (p(c) is flat at c = b, dp/dc = 2k (1/c − c/b²) = 0: the front there is found to the
        // square root of the rounding, 1e-8 relative)
        assert!((outer_displacement(pl, a, b, k, g) - k * b / (2.0 * g)).abs() <= 1e-6 * k * b / g);
        let mut last = 0.0;
        for i in 1..=20 {
            let p = pl * i as f64 / 20.0;
            let u = outer_displacement(p, a, b, k, g);
            assert!(u > last);
            last = u;
            assert!((pressure_for_outer_displacement(u, a, b, k, g) - p).abs() <= 1e-9 * pl, "inverse at p = {p}");
        }
    }
}
