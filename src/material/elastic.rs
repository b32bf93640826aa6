//! Hencky (logarithmic) isotropic elasticity. (stub: being written)
use super::*;
#[derive(Clone, Debug, PartialEq)]
pub struct Elastic { pub e: f64, pub nu: f64 }
impl Elastic { pub fn new(e: f64, nu: f64) -> Self { Self { e, nu } } }
impl ConstitutiveLaw for Elastic {
    fn shear_modulus(&self) -> f64 { lame_from_e_nu(self.e, self.nu).0 }
    fn bulk_modulus(&self) -> Option<f64> { lame_from_e_nu(self.e, self.nu).1 }
    fn symmetric_tangent(&self) -> bool { true }
    fn update(&self, _ff: &Matrix3<f64>, _old: &MatState, _inc: TimeIncrement) -> Result<MatResponse, MaterialError> { unimplemented!() }
}
