//! Contact between particles and with rigid walls, in three layers (the shape of LLNL
//! Tribol's search / geom / physics and of MOOSE's `PenetrationLocator` → `PenetrationInfo` →
//! constraint):
//!
//! 1. **search** ([`search`]): candidate node-to-segment pairs, conservative within a stated
//!    distance (a parry2d bounding-volume hierarchy);
//! 2. **pairs and geometry** ([`pairs`], [`geometry`], [`smooth`], [`boundary`]): the pairs
//!    frozen for a step with their histories (trial, commit, backup, restore, the carry over a
//!    re-mesh), and the geometry record of a pair — gap, projection and their variations —
//!    for a straight master segment, a C¹ smoothed master surface or a rigid wall;
//! 3. **enforcement** ([`enforce`]): penalty, augmented Lagrangian and Lagrange multipliers
//!    with Coulomb friction and ties, as kernels that read only a geometry record and a pair
//!    history.
//!
//! [`problem::ContactProblem`] ties them together for a model: it evaluates the pairs a
//! process owns, and adds every process's evaluations in the serial order into the force, the
//! tangent (through the assembler's block maps), the statistics and the nodal results. It never
//! sees a process or a thread: the exchange of evaluations is the caller's
//! ([`crate::parallel`]).

pub mod barrier;
pub mod barrier_problem;
pub mod boundary;
pub mod enforce;
pub mod geometry;
pub mod pairs;
pub mod problem;
pub mod search;
pub mod smooth;

pub use boundary::ContactBody;
pub use enforce::{ContactKind, PairHistory, PenaltyParams};
pub use geometry::Wall;
pub use problem::{ContactEvals, ContactProblem, ContactState, ContactStats, ContactTangent, NodalContact};

/// A boundary segment of a body: global node indices `[a, b]`, oriented so that the body lies on
/// its left (outward normal = (Δy, −Δx)/ℓ).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Segment {
    pub body: usize,
    pub nodes: [usize; 2],
}

/// How contact constraints are enforced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactMethod {
    /// Penalty (paper eq. 26–28).
    Penalty,
    /// Penalty plus Uzawa updates of the multipliers until the penetration is below tolerance.
    AugmentedLagrangian,
    /// Lagrange multipliers (paper eq. 22–25): one unknown contact force per candidate pair,
    /// zero penetration, an indefinite system solved by LU. Frictionless contact only.
    Lagrange,
    /// Incremental Potential Contact: a smoothly clamped log barrier on the distance of every
    /// boundary node to every boundary edge of another particle and to every wall closer than
    /// d̂ ([`barrier`], [`barrier_problem`]), with a line search that never lets an iterate
    /// cross; lagged, mollified Coulomb friction; ties for cohering particles. The default.
    Barrier,
}

/// Normal of the node-to-segment pairs between particles (`[contact] normal`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ContactNormal {
    /// The normal of the closest straight master segment: it turns at once by the corner's
    /// angle when a slave node slides round a master corner. The default: the smoothed normal
    /// is better on the 4 × 4 octagon jobs but not (yet) on every job (see
    /// [`ContactNormal::Smoothed`]).
    #[default]
    Segment,
    /// A C¹ cubic Hermite master surface through the nodes with averaged nodal tangents
    /// (corners sharper than 80° stay sharp, nearly flat nodes are left alone): the closest
    /// point, gap and normal move continuously round the corners (see
    /// [`smooth`]). The 4 × 4 octagon jobs (5.2.1, 5.2.2) reach solid ratio
    /// 0.99 instead of jamming at 0.92/0.96, but the 20 ellipses of 5.1.3 (biaxial) fail at
    /// solid ratio 0.80, which `segment` completes.
    Smoothed,
}

/// Where the barrier between particles is evaluated (`[contact] integration`, barrier only).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BarrierIntegration {
    /// Gauss points along every boundary edge against the other particles' edges, the nodes'
    /// own terms reaching d̂/10: a uniform gap carries a uniform pressure (the contact patch
    /// test to 0.48 %; see [`barrier_problem`]).
    #[default]
    Edges,
    /// The boundary nodes against the other particles' edges, as in IPC: the ends of a
    /// contact and the nodes facing a non-matching mesh carry equal forces (the patch test
    /// off by 31 % at Gauss points); the 1,024-octagon grid of creeping asphalt reaches 0.99
    /// with it in 26 minutes, with [`BarrierIntegration::Edges`] it passes its snap through
    /// long descents and was at 0.881 after 54 (docs/robustness.md, twentieth and twenty-first
    /// measurements).
    Nodes,
}

/// The contact parameters of a model (from the case's `[contact]` table and the walls'
/// `contact` / `friction` keys).
#[derive(Clone, Debug, PartialEq)]
pub struct ContactParams {
    pub method: ContactMethod,
    /// Contact kind between particles.
    pub kind: ContactKind,
    /// Contact kind of each rigid wall with the particles, in the model's wall order.
    pub walls: Vec<ContactKind>,
    /// Normal and tangential penalty (MPa/mm); `None` = 10 E_min / h per pair.
    pub penalty: Option<f64>,
    /// Augmented Lagrangian: stop when the largest penetration <= this x the element size.
    pub penetration_tol: f64,
    pub max_augmentations: usize,
    /// Search distance (mm); `None` = one element size.
    pub search_distance: Option<f64>,
    /// Lagrange multipliers: an active constraint is g + r λ / c = 0 (c the default penalty),
    /// a perturbed Lagrangian that keeps the system regular where two candidates constrain the
    /// same gap (a node facing a node, symmetric ties). 0 = exact constraints.
    pub lagrange_regularisation: f64,
    /// Contact normal of the node-to-segment pairs: straight segments or a smoothed surface.
    pub normal: ContactNormal,
    /// Barrier: the activation distance d̂ (mm); `None` = 1/20 of the smallest element size
    /// ([`barrier_problem::default_dhat`]).
    pub dhat: Option<f64>,
    /// Barrier: evaluated on Gauss points of the edges or on the nodes.
    pub integration: BarrierIntegration,
}

impl Default for ContactParams {
    fn default() -> Self {
        Self {
            method: ContactMethod::Barrier,
            kind: ContactKind::Sliding,
            walls: Vec::new(),
            penalty: None,
            penetration_tol: 0.01,
            max_augmentations: 20,
            search_distance: None,
            lagrange_regularisation: 1e-4,
            normal: ContactNormal::default(),
            dhat: None,
            integration: BarrierIntegration::default(),
        }
    }
}
