//! Isotropic hardening tables. (stub: being written)
#[derive(Clone, Debug, PartialEq)]
pub struct HardeningTable { pub eps_p: Vec<f64>, pub sigma_y: Vec<f64> }
impl HardeningTable {
    pub fn perfect(sigma_y: f64) -> Self { Self { eps_p: vec![0.0], sigma_y: vec![sigma_y] } }
    pub fn from_plastic_strain(points: &[[f64; 2]]) -> Result<Self, String> { Ok(Self { eps_p: points.iter().map(|p| p[0]).collect(), sigma_y: points.iter().map(|p| p[1]).collect() }) }
    pub fn from_total_strain(_e: f64, _points: &[[f64; 2]]) -> Result<Self, String> { unimplemented!() }
}
