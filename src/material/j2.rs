//! Finite-strain von Mises (J2) plasticity with isotropic hardening.
//!
//! Exponential map on the logarithmic elastic strain (de Souza Neto, Perić & Owen 2008, ch. 14
//! and Box 7.3/7.4; Eterovic & Bathe 1990; Weber & Anand 1990), see [`logstrain`]:
//!
//! ```text
//!   b_tr = F C_p⁻¹ Fᵀ,  ε_tr = ½ ln b_tr,  s_tr = 2G dev ε_tr,  q_tr = √(3/2) ‖s_tr‖,
//!   yield:   Φ = q_tr − σ_y(ε̄ᵖ_n) ≤ 0  →  elastic step,
//!   return:  q_tr − 3GΔγ − σ_y(ε̄ᵖ_n + Δγ) = 0   (exact: piecewise-linear table),
//!   τ′ = (1 − 3GΔγ/q_tr) s_tr,   ε̄ᵖ = ε̄ᵖ_n + Δγ,   C_p⁻¹ = F⁻¹ exp(2 ε_e) F⁻ᵀ.
//! ```
//!
//! Tangent: D = 2G(1 − 3GΔγ/q_tr) I_dev + 6G²(Δγ/q_tr − 1/(3G + H)) N̂ ⊗ N̂ (Box 7.4, H the
//! table slope on the segment holding the solution), pushed to the spatial `cc` through
//! L = ∂ ln b/∂b.
//!
//! ## Symmetry: the update is variational
//! With the history (C_p⁻¹, ε̄ᵖ_n) frozen over the step, the return above is the minimiser of
//! an incremental potential of F alone,
//!
//! ```text
//!   W(F) = min over Δγ ≥ 0 of  G ‖dev ε_tr(F) − √(3/2) Δγ N̂‖² + ∫ σ_y(ε̄) dε̄ over [ε̄ᵖ_n, ε̄ᵖ_n + Δγ],
//! ```
//!
//! (stationarity in Δγ is q_tr − 3GΔγ = σ_y(ε̄ᵖ_n + Δγ), the return map; Ortiz & Stainier
//! 1999, Miehe 2002 for the exponential map with Hencky elasticity). So τ′ is the derivative of
//! a potential and its Lie derivative `cc` is the push-forward of a second derivative: it has
//! major symmetry, although the factors D, L and l b + b lᵀ do not show it one by one. The
//! conformance battery (`tests/material_conformance.rs`, check (d)) confirms |cc_ij − cc_ji| ≤
//! 1e-10 max|cc| at plastic probes, hence `symmetric_tangent() == true`: with the barrier
//! contact J2 particles get the symmetric factorisation (`model::symmetric_tangent` says why
//! not with the other contact methods).
use super::logstrain::exponential_map_update;
use super::*;

#[derive(Clone, Debug, PartialEq)]
pub struct J2Plastic {
    pub e: f64,
    pub nu: f64,
    pub hardening: HardeningTable,
}

impl J2Plastic {
    /// Young's modulus `e` (MPa), Poisson's ratio `nu`, flow stress table σ_y(ε̄ᵖ).
    pub fn new(e: f64, nu: f64, hardening: HardeningTable) -> Self {
        Self { e, nu, hardening }
    }
}

impl ConstitutiveLaw for J2Plastic {
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
        _inc: TimeIncrement,
    ) -> Result<MatResponse, MaterialError> {
        let g = self.shear_modulus();
        let out = exponential_map_update(ff, &old.cp_inv, g, |q_tr| {
            Ok(self.hardening.return_map(3.0 * g, q_tr, old.eps_p))
        })?;
        let state = MatState {
            cp_inv: out.cp_inv,
            eps_p: old.eps_p + out.dgamma,
            eps_c: old.eps_c,
        };
        Ok(MatResponse {
            tau: out.tau,
            cc: out.cc,
            thickness: 1.0,
            state,
        })
    }
}
