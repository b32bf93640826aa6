//! # mpfem — multi-particle finite elements for the compaction of 2D granular assemblies
//!
//! Units everywhere: length mm, force N, stress MPa (N/mm²), time s, mass t, density t/mm³.
//! The model is plane strain; forces on a 2D body are per unit thickness (N/mm).
//!
//! ## Notation (one convention for the whole crate)
//! Names follow Bathe's notation used by the source paper:
//! - `xx0` / `x0`: reference (time 0) coordinates X; `x`: current coordinates; `u = x - X`.
//! - `ff`: deformation gradient F = ∂x/∂X (3×3, plane strain F₃₃ = 1); `jac`: J = det F.
//! - `tau`: Kirchhoff stress τ = J σ; `sig`: Cauchy stress σ; `ss`: 2nd Piola–Kirchhoff S.
//! - `cc`: spatial tangent c (Lie derivative of τ with respect to the rate of deformation d),
//!   `dd`: material tangent D = ∂S/∂E (Bathe's ₀D); `kk`: stiffness K; `rr`: residual R.
//! - Voigt order for in-plane symmetric tensors: `[xx, yy, xy]`; stresses also carry `zz` as a
//!   fourth entry `[xx, yy, xy, zz]` where the out-of-plane component matters.
//! - Element node order is counter-clockwise; degrees of freedom are `2*node + component`.
//!
//! Physics code (element, material, contact kernels) never sees threads or MPI: parallelism is
//! passed in by the caller (see [`assembly`]). The library never prints; it logs with `tracing`.

pub mod analytical;
pub mod assembly;
#[doc(hidden)]
pub mod bench_support;
pub mod case;
pub mod checkpoint;
pub mod comm;
pub mod contact;
pub mod distribute;
pub mod dynamics;
pub mod element;
pub mod fits;
pub mod h5;
pub mod linalg;
pub mod loading;
pub mod material;
pub mod mesh;
pub mod model;
pub mod output;
pub mod pack;
pub mod results;
pub mod packing;
pub mod parallel;
pub mod plot;
pub mod remesh;
pub mod run;
pub mod solver;
pub mod stabilise;
pub mod study;
pub mod verify;
