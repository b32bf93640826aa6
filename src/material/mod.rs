//! Constitutive laws behind one small interface.
//!
//! ## Contract
//! Every law is isochoric–volumetric split. The **element** owns the volumetric response
//! (mean dilatation: Cauchy pressure from the element area ratio Θ and the bulk modulus K that
//! the law reports, or an augmented-Lagrangian constraint Θ = 1 when the law is incompressible,
//! ν = 0.5). The **law** owns the deviatoric response: given the deformation gradient F at the
//! end of the step (plane strain, F₃₃ = 1) and its committed state at the start of the step, it
//! returns
//! - the deviatoric Kirchhoff stress τ′ = dev τ, depending only on the isochoric part
//!   J^{-1/3} F (our laws are von Mises type, so inelastic flow is isochoric), in the order
//!   `[xx, yy, xy, zz]`, MPa;
//! - the spatial tangent `cc` (Voigt 3×3, rows τ′ `[xx, yy, xy]`, columns the rate of
//!   deformation `[d_xx, d_yy, 2 d_xy]`) defined by the Lie (Oldroyd) derivative
//!   L_v τ′ = ∂τ′/∂l : l − l τ′ − τ′ lᵀ = cc : d for every velocity gradient l; for our
//!   isotropic laws the spin part drops out (objectivity);
//! - the updated state, to be committed by the caller only after the global Newton solve has
//!   converged (the old state is never modified: cut-back just discards the new one).
//!
//! Elastic response: Hencky (logarithmic) isotropic elasticity, τ′ = 2G dev(ln V_e) where
//! V_e is the elastic left stretch. The inelastic laws use the exponential map on the
//! logarithmic elastic strain (Weber–Anand / Eterovic–Bathe; de Souza Neto et al., 2008,
//! ch. 14), which keeps the return maps of small-strain J2 and creep exact in log strains.

pub mod creep;
pub mod elastic;
pub mod hardening;
pub mod j2;
pub mod logstrain;
pub mod plane_stress;

use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use creep::{Creep, CreepParams};
pub use elastic::Elastic;
pub use hardening::HardeningTable;
pub use j2::J2Plastic;

/// History variables at one quadrature point.
///
/// `cp_inv` is the inverse plastic right Cauchy–Green tensor C_p⁻¹ (reference configuration,
/// `[xx, yy, xy, zz]`), identity for a virgin material; the trial elastic left Cauchy–Green
/// tensor is b_e = F C_p⁻¹ Fᵀ. It carries the combined (plastic + creep) inelastic deformation.
/// After a re-mesh in a deformed configuration (reference := current, F := I) it holds the
/// elastic left Cauchy–Green tensor b_e of before, for every law including the elastic one
/// ([`crate::remesh::state`]); the Kirchhoff stresses of the laws stay per unit volume of the
/// original configuration (the element divides them by its initial volume ratio j₀, see
/// [`crate::element`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MatState {
    pub cp_inv: [f64; 4],
    /// Equivalent (accumulated, von Mises) plastic strain ε̄ᵖ.
    pub eps_p: f64,
    /// Equivalent (accumulated, von Mises) creep strain ε̄ᶜ.
    pub eps_c: f64,
}

impl Default for MatState {
    fn default() -> Self {
        Self { cp_inv: [1.0, 1.0, 0.0, 1.0], eps_p: 0.0, eps_c: 0.0 }
    }
}

/// The time increment a law is updated over: from `time - dt` to `time` (s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeIncrement {
    pub time: f64,
    pub dt: f64,
}

/// Result of a stress update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatResponse {
    /// Deviatoric Kirchhoff stress τ′ `[xx, yy, xy, zz]` (MPa).
    pub tau: [f64; 4],
    /// Spatial tangent c (3×3 Voigt, see module docs), MPa.
    pub cc: [[f64; 3]; 3],
    /// The through-thickness stretch λ₃ = F₃₃ the response is for: 1 in plane strain; in
    /// plane stress ([`plane_stress::PlaneStress`]) the one that makes σ₃₃ vanish.
    pub thickness: f64,
    /// Updated state (uncommitted).
    pub state: MatState,
}

#[derive(Debug, Error, Clone, PartialEq)]
pub enum MaterialError {
    #[error("inverted or degenerate deformation (det F = {0:.3e})")]
    InvertedElement(f64),
    #[error("local return map did not converge (residual {residual:.3e} after {iterations} iterations)")]
    ReturnMapFailed { iterations: usize, residual: f64 },
    #[error("initial volume ratio j0 = {0:.3e} of the element must be positive and finite")]
    InvalidVolumeRatio(f64),
}

/// One constitutive law (see the module docs for the exact contract).
pub trait ConstitutiveLaw: Send + Sync {
    /// Young's modulus E (MPa) and Poisson's ratio ν of the (isotropic) elastic response.
    fn elastic_constants(&self) -> (f64, f64);
    /// Small-strain shear modulus G (MPa).
    fn shear_modulus(&self) -> f64 {
        let (e, nu) = self.elastic_constants();
        lame_from_e_nu(e, nu).0
    }
    /// Bulk modulus K (MPa), or `None` when the law is incompressible (ν = 0.5).
    fn bulk_modulus(&self) -> Option<f64> {
        let (e, nu) = self.elastic_constants();
        lame_from_e_nu(e, nu).1
    }
    /// Whether the consistent tangent `cc` has major symmetry (lets the driver pick a
    /// symmetric factorisation).
    fn symmetric_tangent(&self) -> bool;
    /// Stress, tangent and new state at the end of the increment for deformation gradient `ff`
    /// (plane strain: only the in-plane 2×2 block differs from the identity), starting from the
    /// committed state `old`.
    fn update(&self, ff: &Matrix3<f64>, old: &MatState, inc: TimeIncrement) -> Result<MatResponse, MaterialError>;
}

/// The laws mpfem knows, as one enum so a body's material is a plain value.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    Elastic(Elastic),
    J2(J2Plastic),
    Creep(Creep),
}

impl Material {
    /// Young's modulus E (MPa): the stiffness scale of the default contact penalty 10 E/h and
    /// of the stabilisation springs.
    pub fn youngs_modulus(&self) -> f64 {
        self.law().elastic_constants().0
    }

    fn law(&self) -> &dyn ConstitutiveLaw {
        match self {
            Material::Elastic(m) => m,
            Material::J2(m) => m,
            Material::Creep(m) => m,
        }
    }
}

impl ConstitutiveLaw for Material {
    fn elastic_constants(&self) -> (f64, f64) {
        self.law().elastic_constants()
    }
    fn symmetric_tangent(&self) -> bool {
        self.law().symmetric_tangent()
    }
    fn update(&self, ff: &Matrix3<f64>, old: &MatState, inc: TimeIncrement) -> Result<MatResponse, MaterialError> {
        self.law().update(ff, old, inc)
    }
}

/// Shear and bulk moduli from Young's modulus E and Poisson's ratio ν (bulk `None` at ν = 0.5).
pub fn lame_from_e_nu(e: f64, nu: f64) -> (f64, Option<f64>) {
    let g = e / (2.0 * (1.0 + nu));
    let k = if nu >= 0.5 { None } else { Some(e / (3.0 * (1.0 - 2.0 * nu))) };
    (g, k)
}
