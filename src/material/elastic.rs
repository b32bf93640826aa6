//! Hencky (logarithmic) isotropic elasticity.
//!
//! ```text
//!   τ′ = 2G dev(½ ln b),   b = F C_p⁻¹ Fᵀ,   G = E / (2(1 + ν)),
//! ```
//!
//! the deviatoric Kirchhoff stress of the stored energy W = G ‖dev ε‖² with the Hencky strain
//! ε = ½ ln b (the volumetric part K/2 (ln J)² belongs to the element, see the module docs of
//! [`crate::material`]). The law creates no history: the state is returned unchanged. Its
//! C_p⁻¹ is the identity for a body meshed in its stress-free configuration (then b = F Fᵀ,
//! bit for bit); after a re-mesh in a deformed configuration it holds the pushed-forward
//! elastic left Cauchy–Green tensor b_e of before ([`crate::remesh::state`]), so the stress
//! carries over.
//!
//! Tangent: `cc` = 2G I_dev : ½ L : (l b + b lᵀ) − l τ′ − τ′ lᵀ, built by
//! [`logstrain::spatial_tangent`] (L = ∂ ln b/∂b, derivative
//! of an isotropic tensor function). Because τ′ derives from a potential, `cc` has major
//! symmetry. Exact for large strains; it reduces to linear isotropic elasticity for small ones.
use super::logstrain::exponential_map_update;
use super::*;

#[derive(Clone, Debug, PartialEq)]
pub struct Elastic {
    pub e: f64,
    pub nu: f64,
}

impl Elastic {
    /// Young's modulus `e` (MPa) and Poisson's ratio `nu` (ν = 0.5: incompressible).
    pub fn new(e: f64, nu: f64) -> Self {
        Self { e, nu }
    }
}

impl ConstitutiveLaw for Elastic {
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
        let out = exponential_map_update(ff, &old.cp_inv, self.shear_modulus(), |_| {
            Ok((0.0, f64::INFINITY))
        })?;
        Ok(MatResponse {
            tau: out.tau,
            cc: out.cc,
            thickness: 1.0,
            state: *old,
        })
    }
}
