//! faer sparse direct solvers. (stub: being written)
use super::*;
pub struct FaerLu;
impl FaerLu { pub fn new(_threads: usize) -> Self { FaerLu } }
impl LinearSolver for FaerLu {
    fn analyze(&mut self, _a: &CsrMatrix) -> Result<(), LinalgError> { unimplemented!() }
    fn factor(&mut self, _a: &CsrMatrix) -> Result<(), LinalgError> { unimplemented!() }
    fn solve(&mut self, _a: &CsrMatrix, _b: &[f64], _x: &mut [f64]) -> Result<SolveStats, LinalgError> { unimplemented!() }
    fn name(&self) -> &'static str { "lu" }
}
pub struct FaerCholesky;
impl FaerCholesky { pub fn new(_threads: usize) -> Self { FaerCholesky } }
impl LinearSolver for FaerCholesky {
    fn analyze(&mut self, _a: &CsrMatrix) -> Result<(), LinalgError> { unimplemented!() }
    fn factor(&mut self, _a: &CsrMatrix) -> Result<(), LinalgError> { unimplemented!() }
    fn solve(&mut self, _a: &CsrMatrix, _b: &[f64], _x: &mut [f64]) -> Result<SolveStats, LinalgError> { unimplemented!() }
    fn name(&self) -> &'static str { "cholesky" }
}
