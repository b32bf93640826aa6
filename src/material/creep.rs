//! Visco-plastic creep, eq. 29 of the paper. (stub: being written)
use super::*;
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CreepParams { pub a: f64, pub n: f64, pub m: f64, pub p: f64, pub q: f64, pub temperature: f64, pub stress_scale: f64 }
#[derive(Clone, Debug, PartialEq)]
pub struct Creep { pub e: f64, pub nu: f64, pub params: CreepParams }
impl Creep { pub fn new(e: f64, nu: f64, params: CreepParams) -> Self { Self { e, nu, params } } }
impl ConstitutiveLaw for Creep {
    fn shear_modulus(&self) -> f64 { lame_from_e_nu(self.e, self.nu).0 }
    fn bulk_modulus(&self) -> Option<f64> { lame_from_e_nu(self.e, self.nu).1 }
    fn symmetric_tangent(&self) -> bool { false }
    fn update(&self, _ff: &Matrix3<f64>, _old: &MatState, _inc: TimeIncrement) -> Result<MatResponse, MaterialError> { unimplemented!() }
}
