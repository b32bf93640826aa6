//! Preconditioned conjugate gradients. (stub: being written)
use super::*;
pub struct Pcg;
impl Pcg { pub fn new(_p: Preconditioner, _tol: f64, _maxit: usize) -> Self { Pcg } }
impl LinearSolver for Pcg {
    fn analyze(&mut self, _a: &CsrMatrix) -> Result<(), LinalgError> { unimplemented!() }
    fn factor(&mut self, _a: &CsrMatrix) -> Result<(), LinalgError> { unimplemented!() }
    fn solve(&mut self, _a: &CsrMatrix, _b: &[f64], _x: &mut [f64]) -> Result<SolveStats, LinalgError> { unimplemented!() }
    fn name(&self) -> &'static str { "pcg" }
}
