//! Hertz line contact (plane strain): an elastic cylinder of radius R pressed onto a rigid flat
//! by a force P' per unit length.
//!
//! Source: K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, chapter 4
//! (normal contact of elastic solids: Hertz theory), §4.3 "two-dimensional contact of
//! cylindrical bodies" (pp. 99–104; the half-width and the peak pressure are his eqs. (4.43)
//! and (4.45) in the 1985 edition). With the contact modulus 1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂
//! and a rigid flat (E₂ → ∞), E* = E/(1 − ν²), and for the cylinder against a flat the relative
//! radius is R itself:
//!
//! * half-width of the contact strip a = √(4 P' R / (π E*)),
//! * pressure p(x) = p₀ √(1 − x²/a²) for |x| ≤ a (elliptical), 0 outside,
//! * peak pressure p₀ = 2 P' / (π a) = √(P' E* / (π R)) (the load is the area of the half
//!   ellipse, P' = π a p₀ / 2).
//!
//! Assumptions of the closed form: linear elasticity, frictionless contact, a ≪ R (each body a
//! half-space near the contact). The strip's width depends only on the local curvature and the
//! load, so it also holds for each contact of a disc squeezed between two flats (the diametral
//! compression only changes the approach of the centres, not a or p₀). Units: mm, N/mm, MPa.

use std::f64::consts::PI;

/// Plane-strain Hertz contact of an elastic cylinder (radius `radius`, Young's modulus
/// `youngs_modulus`, Poisson's ratio `poisson_ratio`) on a rigid flat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HertzCylinder {
    /// Cylinder radius R (mm).
    pub radius: f64,
    /// Young's modulus E (MPa).
    pub youngs_modulus: f64,
    /// Poisson's ratio ν.
    pub poisson_ratio: f64,
}

impl HertzCylinder {
    pub fn new(radius: f64, youngs_modulus: f64, poisson_ratio: f64) -> Self {
        Self {
            radius,
            youngs_modulus,
            poisson_ratio,
        }
    }

    /// Plane-strain contact modulus against a rigid flat, E* = E / (1 − ν²) (MPa).
    pub fn contact_modulus(&self) -> f64 {
        self.youngs_modulus / (1.0 - self.poisson_ratio * self.poisson_ratio)
    }

    /// Half-width a = √(4 P' R / (π E*)) of the contact strip under the force `force` per unit
    /// length P' (N/mm); mm.
    pub fn half_width(&self, force: f64) -> f64 {
        (4.0 * force * self.radius / (PI * self.contact_modulus())).sqrt()
    }

    /// Peak pressure p₀ = 2 P' / (π a) (MPa).
    pub fn peak_pressure(&self, force: f64) -> f64 {
        2.0 * force / (PI * self.half_width(force))
    }

    /// Peak pressure from its second expression p₀ = √(P' E* / (π R)) (MPa); equal to
    /// [`HertzCylinder::peak_pressure`].
    pub fn peak_pressure_direct(&self, force: f64) -> f64 {
        (force * self.contact_modulus() / (PI * self.radius)).sqrt()
    }

    /// Contact pressure p(x) = p₀ √(1 − x²/a²) at the distance `x` from the centre of the strip
    /// (0 outside it); MPa.
    pub fn pressure(&self, force: f64, x: f64) -> f64 {
        let a = self.half_width(force);
        let s = 1.0 - (x / a) * (x / a);
        if s > 0.0 {
            self.peak_pressure(force) * s.sqrt()
        } else {
            0.0
        }
    }

    /// Force per unit length P' = π E* a² / (4 R) that produces the half-width `a` (N/mm).
    pub fn force_for_half_width(&self, a: f64) -> f64 {
        PI * self.contact_modulus() * a * a / (4.0 * self.radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel() -> HertzCylinder {
        HertzCylinder::new(10.0, 200_000.0, 0.3)
    }

    #[test]
    fn both_expressions_of_the_peak_pressure_agree() {
        let h = steel();
        for force in [1.0, 250.0, 17_000.0] {
            let (p1, p2) = (h.peak_pressure(force), h.peak_pressure_direct(force));
            assert!((p1 / p2 - 1.0).abs() < 1e-14, "{p1} vs {p2}");
        }
    }

    #[test]
    fn the_pressure_integrates_to_the_load() {
        let h = steel();
        let force = 5000.0;
        let a = h.half_width(force);
        // x = a sin θ removes the square-root end singularity of the integrand's derivative:
        // ∫ p dx = ∫ p₀ cos²θ a dθ over [−π/2, π/2], Simpson with 200 panels
        let n = 200;
        let d = PI / n as f64;
        let f = |k: usize| {
            let th = -0.5 * PI + d * k as f64;
            h.pressure(force, a * th.sin()) * a * th.cos()
        };
        let mut s = f(0) + f(n);
        for k in 1..n {
            s += if k % 2 == 1 { 4.0 } else { 2.0 } * f(k);
        }
        let total = s * d / 3.0;
        assert!((total / force - 1.0).abs() < 1e-10, "{total} vs {force}");
    }

    #[test]
    fn pressure_profile_is_elliptical_and_vanishes_outside() {
        let h = steel();
        let force = 1000.0;
        let a = h.half_width(force);
        assert_eq!(h.pressure(force, 0.0), h.peak_pressure(force));
        assert!((h.pressure(force, 0.6 * a) / h.peak_pressure(force) - 0.8).abs() < 1e-12);
        assert_eq!(h.pressure(force, a), 0.0);
        assert_eq!(h.pressure(force, -1.5 * a), 0.0);
    }

    #[test]
    fn half_width_scales_as_the_square_root_of_the_load_and_inverts() {
        let h = steel();
        let (a1, a4) = (h.half_width(100.0), h.half_width(400.0));
        assert!((a4 / a1 - 2.0).abs() < 1e-14);
        assert!((h.force_for_half_width(a1) / 100.0 - 1.0).abs() < 1e-14);
        // E* of steel: 200000 / 0.91
        assert!((h.contact_modulus() - 200_000.0 / 0.91).abs() < 1e-9);
        // a hand value: P' = 1000 N/mm, R = 10 mm → a² = 4·1000·10 / (π · 219780.2) = 0.057932 mm²,
        // a = 0.240692 mm
        assert!(
            (h.half_width(1000.0) - 0.240_692).abs() < 1e-6,
            "{}",
            h.half_width(1000.0)
        );
    }
}
