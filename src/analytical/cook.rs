//! Cook's membrane (Cook 1974): reference tip displacements, plane strain, linear elasticity.
//!
//! Geometry: trapezoid (0,0)–(48,44)–(48,60)–(0,44) mm, left edge clamped, a uniformly
//! distributed vertical shear of total F on the right edge; the quantity is the vertical
//! displacement of the top-right corner C = (48, 60). (The often-quoted 23.96 is plane stress
//! and at the mid-point of the loaded edge, so it is not used here.)

/// E = 1, ν = 1/3, F = 1, plane strain: u_y(C) = 22.59.
///
/// Source: the CoFEA benchmark "Cook's membrane" (cofea.readthedocs.io, benchmark 002), very
/// fine quadratic meshes, plane strain, E = 70, ν = 0.33, F = 100: CalculiX 32.27, Code_Aster
/// 32.20, Elmer 32.28 (also reproduced in the solids4foam Cook tutorial, Batistić 2023). Linear
/// elasticity scales with F/E: 32.27 · (1/1)/(100/70) = 22.59. The reference uses ν = 0.33
/// instead of 1/3; an independent Taylor–Hood P2/P1 refinement study at ν = 1/3 extrapolates
/// to 22.61 ± 0.01, within 0.1 % of it.
pub const COMPRESSIBLE_PLANE_STRAIN: (f64, &str) =
    (22.59, "CoFEA benchmark 002 (CalculiX 32.27 at E=70, F=100), scaled by F/E");

/// E = 250, ν = 0.4999, F = 100, plane strain: u_y(C) = 7.77.
///
/// Source: MOOSE regression test of the volumetric-locking correction (tensor mechanics,
/// Cook's membrane, E = 250, ν = 0.4999, 41 × 41 Q4 with B-bar: 7.78, "matching Nakshatrala,
/// Masud & Hjelmstad, Comput. Mech. 41 (2008)"); OpenGeoSys' Cook's membrane test following
/// Elguedj, Bazilevs, Calo & Hughes, CMAME 197 (2008) gives 7.70 at 30 × 30 (scaled to
/// E = 250) and still rising; a Taylor–Hood refinement study extrapolates to 7.77 ± 0.01.
pub const NEARLY_INCOMPRESSIBLE_PLANE_STRAIN: (f64, &str) =
    (7.77, "Nakshatrala et al. 2008 / MOOSE locking test (7.78), Elguedj et al. 2008");
