//! Contact between particles and with rigid walls (work in progress for the contact issue).
//!
//! Lifecycle (after LLNL Tribol): *search* finds candidate pairs conservatively within a stated
//! distance ([`search`]); the pairs are frozen for a Newton solve; the *kernels* compute the gap,
//! normal and slip of each pair and its residual and consistent tangent ([`kernels`]);
//! enforcement (penalty, augmented Lagrangian, Lagrange multipliers) and friction live in the
//! kernels, the driver only assembles them.
//!
//! Two node-to-segment kernels: the straight master segment ([`kernels::nts_pair`],
//! `[contact] normal = "segment"`) and a C¹ smoothed master surface ([`smooth::nts_smooth_pair`],
//! `normal = "smoothed"`), whose normal turns continuously round the corners of the particles.

pub mod driver;
pub mod kernels;
pub mod search;
pub mod smooth;

/// A boundary segment of a body: global node indices `[a, b]`, oriented so that the body lies on
/// its left (outward normal = (Δy, −Δx)/ℓ).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Segment {
    pub body: usize,
    pub nodes: [usize; 2],
}
