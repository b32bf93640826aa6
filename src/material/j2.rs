//! Finite-strain J2 plasticity. (stub: being written)
use super::*;
#[derive(Clone, Debug, PartialEq)]
pub struct J2Plastic { pub e: f64, pub nu: f64, pub hardening: HardeningTable }
impl J2Plastic { pub fn new(e: f64, nu: f64, hardening: HardeningTable) -> Self { Self { e, nu, hardening } } }
impl ConstitutiveLaw for J2Plastic {
    fn shear_modulus(&self) -> f64 { lame_from_e_nu(self.e, self.nu).0 }
    fn bulk_modulus(&self) -> Option<f64> { lame_from_e_nu(self.e, self.nu).1 }
    fn symmetric_tangent(&self) -> bool { false }
    fn update(&self, _ff: &Matrix3<f64>, _old: &MatState, _inc: TimeIncrement) -> Result<MatResponse, MaterialError> { unimplemented!() }
}
