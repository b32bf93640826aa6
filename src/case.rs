//! The TOML case file: schema (serde), validation and the validated [`Case`].
//!
//! The schema is documented key by key in `docs/case-file.md`; the built-in default job
//! ([`DEFAULT_JOB`], `jobs/default.toml`) is a complete, commented example.
//!
//! Parsing happens in two stages:
//! 1. the text is deserialised into private raw structs (module `raw`) that mirror the file
//!    one-to-one and reject unknown keys and wrong types (`#[serde(deny_unknown_fields)]`);
//!    syntax and type errors are reported with the key path, line and column;
//! 2. the raw structs are validated (ranges, finiteness, required keys, cross references,
//!    duplicated names, files) and converted into the public types below, applying the
//!    documented defaults.
//!
//! Every failure is one [`CaseError`]: the dotted key path (`materials[1].poisson_ratio`) and a
//! message that states the offending value and what was expected. Nothing here panics on any
//! input and nothing is printed.

use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::linalg::{LinearSolverKind, Preconditioner};
use crate::material::creep::CreepParams;
use crate::material::{ConstitutiveLaw, Creep, Elastic, HardeningTable, J2Plastic, Material};

/// The built-in default job (plane-strain upsetting of an aluminium block).
pub const DEFAULT_JOB: &str = include_str!("../jobs/default.toml");

/// Largest accepted `divisions` entry (a guard against absurd meshes).
pub const MAX_DIVISIONS: i64 = 100_000;

/// Default density, t/mm³.
pub const DEFAULT_DENSITY: f64 = 1e-9;

/// Largest `count` of a `[[packings]]` entry (the cells are built in O(count²)).
pub const MAX_PACKING_COUNT: usize = 5000;

/// Default Lloyd relaxation steps of a `[[packings]]` entry.
pub const DEFAULT_LLOYD: usize = 10;

/// The die `[x0, x1, y0, y1]` (mm) closed by a left, a right, a bottom and a top wall at their
/// initial positions; `None` unless all four are present.
pub fn die_of(walls: &[WallSpec]) -> Option<[f64; 4]> {
    let pos = |side: WallSide| walls.iter().find(|w| w.side == side).map(|w| w.position);
    Some([pos(WallSide::Left)?, pos(WallSide::Right)?, pos(WallSide::Bottom)?, pos(WallSide::Top)?])
}


// ---------------------------------------------------------------------------------------------
// Error
// ---------------------------------------------------------------------------------------------

/// A case-file error: the dotted key path and a message naming the value and the expectation.
///
/// `Display` prints `KEY: MESSAGE` (or just `MESSAGE` when the error is not tied to a key).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{}", self.render())]
pub struct CaseError {
    /// Dotted key path, e.g. `materials[1].poisson_ratio`; a file path for I/O errors; may be
    /// empty for syntax errors that are not inside any key.
    pub key: String,
    pub message: String,
}

impl CaseError {
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            message: message.into(),
        }
    }

    fn render(&self) -> String {
        if self.key.is_empty() {
            self.message.clone()
        } else {
            format!("{}: {}", self.key, self.message)
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Validated types
// ---------------------------------------------------------------------------------------------

/// A validated case.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    pub title: String,
    pub formulation: Formulation,
    /// Element technology (`[model] element`).
    pub element: crate::element::ElementKind,
    pub materials: Vec<MaterialSpec>,
    pub bodies: Vec<BodySpec>,
    pub boundary: Vec<DirichletSpec>,
    pub loads: Vec<LoadSpec>,
    pub time: TimeSpec,
    pub solver: SolverSpec,
    pub output: OutputSpec,
    /// Rigid walls (empty: no walls).
    pub walls: Vec<WallSpec>,
    /// Contact settings (used when there are walls or several bodies).
    pub contact: ContactSpec,
    pub stop: StopSpec,
    /// Adaptive re-meshing of the particles (`[remesh]`).
    pub remesh: RemeshSpec,
    /// Directory of the case file; relative paths in the file are resolved against it.
    pub base_dir: PathBuf,
}

/// Which incremental formulation the element uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Formulation {
    /// Total Lagrangian (reference configuration), paper eq. 5–11.
    TotalLagrangian,
    /// Updated Lagrangian (current configuration), paper eq. 12–17.
    #[default]
    UpdatedLagrangian,
}

/// Which side of the die a rigid wall closes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WallSide {
    Left,
    Right,
    Bottom,
    Top,
}

impl WallSide {
    /// Position of the side in the history's wall columns: left 0, right 1, bottom 2, top 3.
    pub fn index(self) -> usize {
        match self {
            WallSide::Left => 0,
            WallSide::Right => 1,
            WallSide::Bottom => 2,
            WallSide::Top => 3,
        }
    }
}

/// A rigid straight wall: `position` (x of a left/right wall, y of a bottom/top wall, mm, at
/// t = 0) moving towards the particles at `velocity` (mm/s, positive inward).
#[derive(Clone, Debug, PartialEq)]
pub struct WallSpec {
    pub side: WallSide,
    pub position: f64,
    pub velocity: f64,
    pub kind: crate::contact::kernels::ContactKind,
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
}

/// Scope of the contact stabilisation springs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Stabilise {
    /// Only the directions (x, y) in which a body is not held by its contacts at the start of
    /// the step (it has no contact pushing it each way); a step that fails is retried with every
    /// dof stabilised before it is cut back.
    Unsupported,
    /// Every free dof of every body, every step.
    #[default]
    All,
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
    /// [`crate::contact::smooth`]). The 4 × 4 octagon jobs (5.2.1, 5.2.2) reach solid ratio
    /// 0.99 instead of jamming at 0.92/0.96, but the 20 ellipses of 5.1.3 (biaxial) fail at
    /// solid ratio 0.80, which `segment` completes.
    Smoothed,
}

/// Anchor of the contact stabilisation springs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum StabilisationKind {
    /// Anchored at the position extrapolated from the last two converged steps,
    /// u_n + (Δt/Δt_prev)(u_n − u_{n−1}): the springs resist changes of velocity only (like a
    /// nodal mass k Δt²), so particles that move steadily lose no energy to them. The default:
    /// on the 2 × 2 jobs it takes 0.002–0.03 % of the wall work (viscous: 0.5–0.8 %).
    #[default]
    Inertial,
    /// Anchored at the last converged position: the springs resist any motion (a dashpot of
    /// viscosity k Δt); a particle that is let go stops at once.
    Viscous,
}

/// The `[contact]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactSpec {
    pub method: ContactMethod,
    /// Contact kind between particles.
    pub kind: crate::contact::kernels::ContactKind,
    /// Normal and tangential penalty (MPa/mm); `None` = 10 E_min / h per pair.
    pub penalty: Option<f64>,
    /// Augmented Lagrangian: stop when the largest penetration <= this x the element size.
    pub penetration_tol: f64,
    pub max_augmentations: usize,
    /// zeta: every free node is tied to its last converged position by a spring
    /// zeta * E * a / h^2 (a tributary area, h element size), which keeps particles that touch
    /// nothing solvable.
    pub stabilisation: f64,
    /// Which bodies and directions the stabilisation springs act on.
    pub stabilise: Stabilise,
    /// Where the stabilisation springs are anchored.
    pub stabilisation_kind: StabilisationKind,
    /// Retry a step that fails with the inertial anchor at the same size with the viscous one
    /// before cutting back.
    pub viscous_retry: bool,
    /// On a step smaller than `[time] dt` the springs stiffen as a fixed nodal mass (inertial
    /// anchor: by (dt/Δt)²) or a fixed dashpot (viscous anchor: by dt/Δt) would, so that a
    /// cut-back in general ends where the springs outweigh a loss of stability of the particles
    /// (a snap-through between two interlocked corners, a buckling column).
    pub stiffen_on_cutback: bool,
    /// rho: a spring rho * E * a / h^2 added to the tangent only (not to the residual): it
    /// steadies the Newton iterations of weakly held particles without changing the solution
    /// or dissipating energy.
    pub regularisation: f64,
    /// Search distance (mm); `None` = one element size.
    pub search_distance: Option<f64>,
    /// Lagrange multipliers: an active constraint is g + r λ / c = 0 (c the default penalty),
    /// a perturbed Lagrangian that keeps the system regular where two candidates constrain the
    /// same gap (a node facing a node, symmetric ties). 0 = exact constraints.
    pub lagrange_regularisation: f64,
    /// Contact normal of the node-to-segment pairs: straight segments or a smoothed surface.
    pub normal: ContactNormal,
}

impl Default for ContactSpec {
    fn default() -> Self {
        Self {
            method: ContactMethod::Penalty,
            kind: crate::contact::kernels::ContactKind::Sliding,
            penalty: None,
            penetration_tol: 0.01,
            max_augmentations: 20,
            stabilisation: 1e-5,
            stabilise: Stabilise::All,
            stabilisation_kind: StabilisationKind::Inertial,
            viscous_retry: false,
            stiffen_on_cutback: false,
            regularisation: 0.0,
            search_distance: None,
            lagrange_regularisation: 1e-4,
            normal: ContactNormal::default(),
        }
    }
}

/// The `[stop]` table: end the run early.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct StopSpec {
    /// Stop once the solid ratio reaches this value.
    pub solid_ratio: Option<f64>,
    /// End the run normally (status "jammed") when the walls cannot advance any more (a step
    /// fails below dt_min), instead of failing.
    pub jam: bool,
    /// A failed step counts as a jam only at or above this solid ratio (default 0.9).
    pub jam_solid_ratio: f64,
}

/// The `[remesh]` table: adaptive re-meshing of deformed particles (see [`crate::remesh`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RemeshSpec {
    /// Re-mesh a particle whose mesh crosses the quality limits after a converged step, and
    /// re-mesh and retry a step that inverts an element.
    pub enabled: bool,
    /// The quality limits (scaled Jacobian, aspect ratio, smallest corner angle).
    pub limits: crate::remesh::QualityLimits,
    /// Target element size of the new meshes (mm); `None`: each body's own `mesh_size`.
    pub mesh_size: Option<f64>,
    /// Largest number of re-meshes in one run (all particles together); past it the run goes
    /// on without re-meshing.
    pub max_remeshes: usize,
}

impl Default for RemeshSpec {
    fn default() -> Self {
        Self { enabled: false, limits: crate::remesh::QualityLimits::default(), mesh_size: None, max_remeshes: 10_000 }
    }
}

/// A named material.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialSpec {
    pub name: String,
    /// t/mm³.
    pub density: f64,
    pub material: Material,
}

/// A body: one shape meshed with one material.
#[derive(Debug, Clone, PartialEq)]
pub struct BodySpec {
    pub name: String,
    /// Index into [`Case::materials`].
    pub material: usize,
    pub shape: ShapeSpec,
    /// Target element edge length h (mm).
    pub mesh_size: f64,
    /// Structured divisions `[n along x or radius, n along y or circumference]` (rectangle,
    /// cook, annulus sector only); overrides `mesh_size` there.
    pub divisions: Option<[usize; 2]>,
}

impl BodySpec {
    /// The body as a `[[bodies]]` table of the case file (material by name), such that
    /// parsing it gives this body back.
    pub fn to_toml(&self, materials: &[MaterialSpec]) -> toml::Table {
        let mut t = toml::Table::new();
        t.insert("name".into(), self.name.clone().into());
        let material = materials.get(self.material).map_or_else(String::new, |m| m.name.clone());
        t.insert("material".into(), material.into());
        // a gmsh body's element size comes from its mesh (mesh_size is not allowed there)
        if !matches!(self.shape, ShapeSpec::Gmsh { .. }) {
            t.insert("mesh_size".into(), self.mesh_size.into());
        }
        if let Some([a, b]) = self.divisions {
            t.insert("divisions".into(), toml::Value::Array(vec![(a as i64).into(), (b as i64).into()]));
        }
        t.insert("shape".into(), toml::Value::Table(self.shape.to_toml()));
        t
    }
}

impl ShapeSpec {
    /// The `shape = { type = ..., ... }` table of the case file.
    pub fn to_toml(&self) -> toml::Table {
        let pair = |p: [f64; 2]| toml::Value::Array(vec![p[0].into(), p[1].into()]);
        let mut t = toml::Table::new();
        t.insert("type".into(), self.type_name().into());
        match self {
            ShapeSpec::Rectangle { origin, size } => {
                t.insert("origin".into(), pair(*origin));
                t.insert("size".into(), pair(*size));
            }
            ShapeSpec::Disc { center, radius } => {
                t.insert("center".into(), pair(*center));
                t.insert("radius".into(), (*radius).into());
            }
            ShapeSpec::Ellipse { center, semi_axes, angle_deg } => {
                t.insert("center".into(), pair(*center));
                t.insert("semi_axes".into(), pair(*semi_axes));
                t.insert("angle".into(), (*angle_deg).into());
            }
            ShapeSpec::Polygon { vertices } => {
                t.insert("vertices".into(), toml::Value::Array(vertices.iter().map(|v| pair(*v)).collect()));
            }
            ShapeSpec::Cook => {}
            ShapeSpec::AnnulusSector { center, inner_radius, outer_radius, angles_deg } => {
                t.insert("center".into(), pair(*center));
                t.insert("inner_radius".into(), (*inner_radius).into());
                t.insert("outer_radius".into(), (*outer_radius).into());
                t.insert("angles".into(), pair(*angles_deg));
            }
            ShapeSpec::Outline { vertices } => {
                t.insert("vertices".into(), toml::Value::Array(vertices.iter().map(|v| pair(*v)).collect()));
            }
            ShapeSpec::Gmsh { file, group, scale, offset, .. } => {
                // absolute (see Cx::gmsh_shape), so the table stays valid wherever it is written
                t.insert("file".into(), file.display().to_string().into());
                t.insert("group".into(), group.clone().into());
                t.insert("scale".into(), (*scale).into());
                t.insert("offset".into(), pair(*offset));
            }
        }
        t
    }
}

/// Geometry of a body (mm, degrees).
#[derive(Debug, Clone, PartialEq)]
pub enum ShapeSpec {
    Rectangle {
        origin: [f64; 2],
        size: [f64; 2],
    },
    Disc {
        center: [f64; 2],
        radius: f64,
    },
    Ellipse {
        center: [f64; 2],
        semi_axes: [f64; 2],
        angle_deg: f64,
    },
    Polygon {
        vertices: Vec<[f64; 2]>,
    },
    /// The standard Cook membrane: trapezoid (0,0), (48,44), (48,60), (0,44).
    Cook,
    AnnulusSector {
        center: [f64; 2],
        inner_radius: f64,
        outer_radius: f64,
        angles_deg: [f64; 2],
    },
    /// Any simple polygon (possibly non-convex), meshed by
    /// [`crate::mesh::polygon::simple_polygon`].
    Outline {
        vertices: Vec<[f64; 2]>,
    },
    /// One 2D physical group of a gmsh file (see [`crate::mesh::import`]), scaled by `scale`
    /// about the origin and then shifted by `offset`; `mesh` is the group's mesh so placed.
    Gmsh {
        /// The file, resolved against the case file's directory (absolute).
        file: PathBuf,
        /// The group's physical name, or its tag (decimal) when it has no name.
        group: String,
        scale: f64,
        offset: [f64; 2],
        mesh: std::sync::Arc<crate::mesh::Mesh>,
    },
}

impl ShapeSpec {
    /// The lower-case name used in the case file (`type = ...`).
    pub fn type_name(&self) -> &'static str {
        match self {
            ShapeSpec::Rectangle { .. } => "rectangle",
            ShapeSpec::Disc { .. } => "disc",
            ShapeSpec::Ellipse { .. } => "ellipse",
            ShapeSpec::Polygon { .. } => "polygon",
            ShapeSpec::Cook => "cook",
            ShapeSpec::AnnulusSector { .. } => "annulus_sector",
            ShapeSpec::Outline { .. } => "outline",
            ShapeSpec::Gmsh { .. } => "gmsh",
        }
    }

    /// Names of the edge sets the mesher provides for this shape.
    pub fn edge_set_names(&self) -> Vec<String> {
        let names: &[&str] = match self {
            ShapeSpec::Rectangle { .. } | ShapeSpec::Cook => {
                &["left", "right", "bottom", "top", "boundary"]
            }
            ShapeSpec::Disc { .. } | ShapeSpec::Ellipse { .. } => &["outer", "boundary"],
            ShapeSpec::Outline { .. } | ShapeSpec::Gmsh { .. } => &["boundary"],
            ShapeSpec::AnnulusSector { .. } => &["inner", "outer", "start", "end", "boundary"],
            ShapeSpec::Polygon { vertices } => {
                let mut v = vec!["boundary".to_string()];
                v.extend((0..vertices.len()).map(|i| format!("side{i}")));
                return v;
            }
        };
        names.iter().map(|s| s.to_string()).collect()
    }

    /// The convex outline used by the overlap check; `None` for the shapes that are not convex
    /// (annulus sector, outline, gmsh; see [`ShapeSpec::particle`]). A polygon stands for the
    /// convex hull of its vertices.
    pub fn convex(&self) -> Option<crate::packing::overlap::Convex> {
        use crate::packing::overlap::Convex;
        Some(match self {
            ShapeSpec::Disc { center, radius } => Convex::Disc { center: *center, radius: *radius },
            ShapeSpec::Ellipse { center, semi_axes, angle_deg } => Convex::Ellipse { center: *center, semi_axes: *semi_axes, angle_deg: *angle_deg },
            ShapeSpec::Polygon { vertices } => Convex::Polygon(vertices.clone()),
            ShapeSpec::Rectangle { origin: o, size: s } => Convex::Polygon(vec![*o, [o[0] + s[0], o[1]], [o[0] + s[0], o[1] + s[1]], [o[0], o[1] + s[1]]]),
            ShapeSpec::Cook => Convex::Polygon(vec![[0.0, 0.0], [48.0, 44.0], [48.0, 60.0], [0.0, 44.0]]),
            ShapeSpec::AnnulusSector { .. } | ShapeSpec::Outline { .. } | ShapeSpec::Gmsh { .. } => return None,
        })
    }

    /// The particle outline used by the overlap check: [`ShapeSpec::convex`] for the convex
    /// shapes, the polygon of an outline, and the outer boundary loop of a gmsh mesh (holes are
    /// ignored); `None` for an annulus sector (not checked).
    pub fn particle(&self) -> Option<crate::packing::overlap::Particle> {
        use crate::packing::overlap::Particle;
        match self {
            ShapeSpec::Outline { vertices } => Some(Particle::Simple(vertices.clone())),
            ShapeSpec::Gmsh { mesh, .. } => {
                let outer = mesh
                    .boundary_loops()
                    .into_iter()
                    .map(|l| l.iter().map(|&i| mesh.nodes[i]).collect::<Vec<_>>())
                    .max_by(|a, b| crate::mesh::polygon_area(a.iter().copied()).total_cmp(&crate::mesh::polygon_area(b.iter().copied())))?;
                Some(Particle::Simple(outer))
            }
            _ => self.convex().map(Particle::Convex),
        }
    }

    /// Centre for radial displacements (disc, ellipse, annulus sector); `None` otherwise.
    pub fn center(&self) -> Option<[f64; 2]> {
        match self {
            ShapeSpec::Disc { center, .. }
            | ShapeSpec::Ellipse { center, .. }
            | ShapeSpec::AnnulusSector { center, .. } => Some(*center),
            _ => None,
        }
    }
}

/// Time variation of a prescribed value: the value is multiplied by `at(t, t_end)`.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Amplitude {
    /// 0 at t = 0, 1 at t = t_end, linear in between (held at 1 after t_end).
    #[default]
    Ramp,
    /// 1 at all times.
    Constant,
    /// Piecewise linear through `[t, f]` points (times strictly increasing), constant outside.
    Table(Vec<[f64; 2]>),
}

impl Amplitude {
    /// Amplitude factor at time `t` of an analysis that ends at `t_end`.
    pub fn at(&self, t: f64, t_end: f64) -> f64 {
        match self {
            Amplitude::Ramp => {
                if t_end > 0.0 {
                    (t / t_end).clamp(0.0, 1.0)
                } else {
                    1.0
                }
            }
            Amplitude::Constant => 1.0,
            Amplitude::Table(pts) => {
                let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
                    return 0.0;
                };
                if t <= first[0] {
                    return first[1];
                }
                if t >= last[0] {
                    return last[1];
                }
                for w in pts.windows(2) {
                    let (a, b) = (w[0], w[1]);
                    if t <= b[0] {
                        let dt = b[0] - a[0];
                        if dt <= 0.0 {
                            return b[1];
                        }
                        return a[1] + (b[1] - a[1]) * (t - a[0]) / dt;
                    }
                }
                last[1]
            }
        }
    }
}

/// Prescribed displacements on an edge set (mm, times the amplitude).
#[derive(Debug, Clone, PartialEq)]
pub struct DirichletSpec {
    /// Index into [`Case::bodies`].
    pub body: usize,
    pub set: String,
    pub ux: Option<f64>,
    pub uy: Option<f64>,
    /// Radial displacement about the shape's [`ShapeSpec::center`].
    pub radial: Option<f64>,
    pub amplitude: Amplitude,
}

/// Kind and value of a load on an edge set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoadKind {
    /// Dead traction per reference length `[tx, ty]`, MPa.
    Traction([f64; 2]),
    /// Follower pressure normal to the current edge, MPa (positive pushes into the body).
    Pressure(f64),
    /// Total force `[Fx, Fy]` (N per unit thickness) spread uniformly over the set's
    /// reference length.
    Force([f64; 2]),
}

/// A load on an edge set.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadSpec {
    /// Index into [`Case::bodies`].
    pub body: usize,
    pub set: String,
    pub kind: LoadKind,
    pub amplitude: Amplitude,
}

/// Time stepping (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeSpec {
    pub end: f64,
    pub dt: f64,
    pub dt_min: f64,
    pub dt_max: f64,
    pub growth: f64,
    pub cutback: f64,
    pub easy_iterations: usize,
    pub max_steps: usize,
    /// Quasi-static (default) or implicit dynamics (Newmark, HHT-α).
    pub integrator: crate::dynamics::Integrator,
}

impl TimeSpec {
    /// End time and initial step with every other field at its documented default.
    pub fn new(end: f64, dt: f64) -> Self {
        Self {
            end,
            dt,
            dt_min: (end * 1e-6).min(dt),
            dt_max: end,
            growth: 1.5,
            cutback: 0.5,
            easy_iterations: 6,
            max_steps: 100_000,
            integrator: crate::dynamics::Integrator::Static,
        }
    }
}

impl Default for TimeSpec {
    /// `end = 1`, `dt = 0.1`, the rest as documented.
    fn default() -> Self {
        Self::new(1.0, 0.1)
    }
}

/// Newton variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NewtonKind {
    /// Tangent re-formed every iteration.
    #[default]
    Full,
    /// Tangent formed once per step (eq. 9/16 of the paper).
    Modified,
}

/// Linear solver choice; `Auto` is resolved by [`Case::auto_linear_kind`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LinearChoice {
    #[default]
    Auto,
    Fixed(LinearSolverKind),
}

/// Nonlinear and linear solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSpec {
    pub newton: NewtonKind,
    pub max_iterations: usize,
    pub residual_tol: f64,
    pub energy_tol: f64,
    pub line_search: bool,
    pub linear: LinearChoice,
    pub preconditioner: Preconditioner,
    pub pcg_tol: f64,
    pub pcg_max_iterations: usize,
    /// Fill-reducing ordering of the sparse Cholesky factorisation.
    pub ordering: crate::linalg::FillOrdering,
    /// 0 = all cores.
    pub threads: usize,
    /// Augmented-Lagrangian penalty for ν = 0.5, in units of the shear modulus.
    pub incompressible_penalty: f64,
    pub volume_tol: f64,
    pub max_volume_updates: usize,
    /// Distributed runs: after a re-mesh the particles keep their processes while the load
    /// imbalance (heaviest process's element count / mean) stays at most this (≥ 1); above it
    /// the particle graph is partitioned again.
    pub repartition_imbalance: f64,
}

impl Default for SolverSpec {
    fn default() -> Self {
        Self {
            newton: NewtonKind::Full,
            max_iterations: 25,
            residual_tol: 1e-8,
            energy_tol: 1e-16,
            line_search: true,
            linear: LinearChoice::Auto,
            preconditioner: Preconditioner::Ic0,
            pcg_tol: 1e-10,
            pcg_max_iterations: 10_000,
            ordering: crate::linalg::FillOrdering::Amd,
            threads: 0,
            incompressible_penalty: 1000.0,
            volume_tol: 1e-10,
            max_volume_updates: 30,
            repartition_imbalance: 1.05,
        }
    }
}

/// Extra columns of `history.csv`: `(body index, edge set name)`, and how often the field
/// results (`results.h5` / `results.xdmf`) are written.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputSpec {
    /// Reaction force columns `rx_BODY_SET`, `ry_BODY_SET`.
    pub reactions: Vec<(usize, String)>,
    /// Mean displacement columns `ux_BODY_SET`, `uy_BODY_SET`.
    pub displacements: Vec<(usize, String)>,
    /// Write the field results every `every` converged steps (and always the last one);
    /// 0 writes no field results. Default 1.
    pub every: usize,
    /// Write a restart checkpoint (`checkpoint.h5`) every `checkpoint_every` converged steps;
    /// 0 (the default): not by step count.
    pub checkpoint_every: usize,
    /// Write a restart checkpoint when this much wall-clock time (minutes) has passed since the
    /// last one (or the start); 0: not by time. Default 30.
    pub checkpoint_minutes: f64,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self { reactions: Vec::new(), displacements: Vec::new(), every: 1, checkpoint_every: 0, checkpoint_minutes: 30.0 }
    }
}

impl Case {
    /// The linear solver `linear = "auto"` stands for: Cholesky when every material used by a
    /// body has a symmetric tangent, no load is a follower pressure and the contact is
    /// frictionless penalty with the segment normal, LU otherwise.
    pub fn auto_linear_kind(&self) -> LinearSolverKind {
        let symmetric = self
            .bodies
            .iter()
            .filter_map(|b| self.materials.get(b.material))
            .all(|m| m.material.symmetric_tangent());
        let follower = self
            .loads
            .iter()
            .any(|l| matches!(l.kind, LoadKind::Pressure(_)));
        use crate::contact::kernels::ContactKind;
        let contact = !self.walls.is_empty() || self.bodies.len() > 1;
        let friction = contact
            && (!matches!(self.contact.kind, ContactKind::Sliding) || self.walls.iter().any(|w| !matches!(w.kind, ContactKind::Sliding)));
        let lagrange = contact && self.contact.method == ContactMethod::Lagrange;
        // the smoothed contact normal has a non-symmetric tangent (crate::contact::smooth)
        let smoothed = self.bodies.len() > 1 && self.contact.normal == ContactNormal::Smoothed;
        if symmetric && !follower && !friction && !lagrange && !smoothed {
            LinearSolverKind::Cholesky
        } else {
            LinearSolverKind::Lu
        }
    }

    /// The linear solver to use (resolving `Auto`).
    pub fn linear_kind(&self) -> LinearSolverKind {
        match self.solver.linear {
            LinearChoice::Auto => self.auto_linear_kind(),
            LinearChoice::Fixed(k) => k,
        }
    }

    /// Index of the body called `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Index of the material called `name`.
    pub fn material_index(&self, name: &str) -> Option<usize> {
        self.materials.iter().position(|m| m.name == name)
    }
}

// ---------------------------------------------------------------------------------------------
// Entry points
// ---------------------------------------------------------------------------------------------

/// Read and validate the case file at `path` (relative paths inside are resolved against the
/// file's directory).
pub fn load(path: &Path) -> Result<Case, CaseError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        CaseError::new(
            "",
            format!("cannot read case file \"{}\": {e}", path.display()),
        )
    })?;
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    parse(&text, &base_dir)
}

/// Parse and validate case-file text; `base_dir` resolves relative paths (hardening files).
pub fn parse(text: &str, base_dir: &Path) -> Result<Case, CaseError> {
    let root = toml::de::DeTable::parse(text).map_err(|e| toml_error(text, None, &e))?;
    let loc = Locator::new(text, root.get_ref());
    let raw: raw::Case = toml::from_str(text).map_err(|e| toml_error(text, Some(&loc), &e))?;
    let cx = Cx {
        loc: &loc,
        base_dir,
        msh_cache: Default::default(),
    };
    cx.case(raw)
}

/// The built-in default job ([`DEFAULT_JOB`]); its validity is checked by a test.
pub fn default_case() -> Case {
    match parse(DEFAULT_JOB, Path::new(".")) {
        Ok(c) => c,
        Err(e) => panic!("the built-in default job is invalid: {e}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Raw serde structs (one-to-one with the file)
// ---------------------------------------------------------------------------------------------

mod raw {
    use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};
    use serde::Deserialize;
    use std::marker::PhantomData;

    /// Exactly two values `[a, b]` (serde's `[T; 2]` would silently ignore extra elements).
    #[derive(Clone, Copy)]
    pub struct Pair<T>(pub [T; 2]);

    impl<'de, T: Deserialize<'de>> Deserialize<'de> for Pair<T> {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct V<T>(PhantomData<T>);
            impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
                type Value = Pair<T>;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("an array of exactly two numbers")
                }
                fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Pair<T>, A::Error> {
                    let a: T = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(0, &self))?;
                    let b: T = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(1, &self))?;
                    let mut n = 2;
                    while seq.next_element::<IgnoredAny>()?.is_some() {
                        n += 1;
                    }
                    if n != 2 {
                        return Err(de::Error::invalid_length(n, &self));
                    }
                    Ok(Pair([a, b]))
                }
            }
            d.deserialize_seq(V(PhantomData))
        }
    }

    pub type P2 = Pair<f64>;

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Case {
        pub title: Option<String>,
        pub model: Option<Model>,
        pub materials: Option<Vec<Material>>,
        pub bodies: Option<Vec<Body>>,
        pub boundary: Option<Vec<Boundary>>,
        pub loads: Option<Vec<Load>>,
        pub time: Option<Time>,
        pub solver: Option<Solver>,
        pub output: Option<Output>,
        pub walls: Option<Vec<WallRaw>>,
        pub contact: Option<ContactRaw>,
        pub grids: Option<Vec<GridRaw>>,
        pub packings: Option<Vec<PackingRaw>>,
        pub imports: Option<Vec<ImportRaw>>,
        pub stop: Option<StopRaw>,
        pub remesh: Option<RemeshRaw>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct RemeshRaw {
        pub enabled: Option<bool>,
        pub min_scaled_jacobian: Option<f64>,
        pub max_aspect_ratio: Option<f64>,
        pub min_angle: Option<f64>,
        pub mesh_size: Option<f64>,
        pub max_remeshes: Option<i64>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct ImportRaw {
        pub file: Option<String>,
        pub material: Option<String>,
        pub materials: Option<Vec<String>>,
        pub fractions: Option<Vec<f64>>,
        pub seed: Option<i64>,
        pub mesh_size: Option<f64>,
        pub scale: Option<f64>,
        pub offset: Option<P2>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct PackingRaw {
        pub kind: Option<String>,
        pub count: Option<i64>,
        pub seed: Option<i64>,
        pub solid_ratio: Option<f64>,
        pub material: Option<String>,
        pub materials: Option<Vec<String>>,
        pub fractions: Option<Vec<f64>>,
        pub sizes: Option<SizesRaw>,
        pub lloyd: Option<i64>,
        pub aspect: Option<f64>,
        pub mesh_size: Option<f64>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct SizesRaw {
        pub distribution: Option<String>,
        pub ratio: Option<f64>,
        pub sigma: Option<f64>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct WallRaw {
        pub side: Option<String>,
        pub position: Option<f64>,
        pub velocity: Option<f64>,
        pub contact: Option<String>,
        pub friction: Option<f64>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct ContactRaw {
        pub method: Option<String>,
        pub contact: Option<String>,
        pub friction: Option<f64>,
        pub penalty: Option<f64>,
        pub penetration_tol: Option<f64>,
        pub max_augmentations: Option<i64>,
        pub stabilisation: Option<f64>,
        pub stabilise: Option<String>,
        pub stabilisation_kind: Option<String>,
        pub viscous_retry: Option<bool>,
        pub stiffen_on_cutback: Option<bool>,
        pub regularisation: Option<f64>,
        pub search_distance: Option<f64>,
        pub lagrange_regularisation: Option<f64>,
        pub normal: Option<String>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct GridRaw {
        pub material: Option<String>,
        pub nx: Option<i64>,
        pub ny: Option<i64>,
        pub shape: Option<String>,
        pub sides: Option<i64>,
        pub orientation: Option<String>,
        pub arrangement: Option<String>,
        pub materials: Option<Vec<String>>,
        pub fractions: Option<Vec<f64>>,
        pub pattern: Option<String>,
        pub seed: Option<i64>,
        pub solid_ratio: Option<f64>,
        pub mesh_size: Option<f64>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct StopRaw {
        pub solid_ratio: Option<f64>,
        pub jam: Option<bool>,
        pub jam_solid_ratio: Option<f64>,
    }

    impl Shape {
        fn empty(kind: &str) -> Self {
            Self {
                kind: Some(kind.into()),
                origin: None,
                size: None,
                center: None,
                radius: None,
                semi_axes: None,
                angle: None,
                vertices: None,
                inner_radius: None,
                outer_radius: None,
                angles: None,
                file: None,
                group: None,
                scale: None,
                offset: None,
            }
        }
        pub fn outline(vertices: Vec<[f64; 2]>) -> Self {
            Self { vertices: Some(vertices.into_iter().map(Pair).collect()), ..Self::empty("outline") }
        }
        pub fn gmsh(file: String, group: String, scale: f64, offset: [f64; 2]) -> Self {
            Self { file: Some(file), group: Some(group), scale: Some(scale), offset: Some(Pair(offset)), ..Self::empty("gmsh") }
        }
        pub fn disc(center: [f64; 2], radius: f64) -> Self {
            Self { center: Some(Pair(center)), radius: Some(radius), ..Self::empty("disc") }
        }
        pub fn polygon(vertices: Vec<[f64; 2]>) -> Self {
            Self { vertices: Some(vertices.into_iter().map(Pair).collect()), ..Self::empty("polygon") }
        }
        pub fn from_convex(c: crate::packing::overlap::Convex) -> Self {
            use crate::packing::overlap::Convex;
            match c {
                Convex::Disc { center, radius } => Self::disc(center, radius),
                Convex::Polygon(v) => Self::polygon(v),
                Convex::Ellipse { center, semi_axes, angle_deg } => Self {
                    center: Some(Pair(center)),
                    semi_axes: Some(Pair(semi_axes)),
                    angle: Some(angle_deg),
                    ..Self::empty("ellipse")
                },
            }
        }
    }

    impl Body {
        pub fn generated(name: String, material: String, mesh_size: f64, shape: Shape) -> Self {
            Self { name: Some(name), material: Some(material), mesh_size: Some(mesh_size), divisions: None, shape: Some(shape) }
        }
        /// A body whose element size comes from its (imported) mesh.
        pub fn imported(name: String, material: String, shape: Shape) -> Self {
            Self { name: Some(name), material: Some(material), mesh_size: None, divisions: None, shape: Some(shape) }
        }
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Model {
        pub formulation: Option<String>,
        pub element: Option<String>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Material {
        pub name: Option<String>,
        pub model: Option<String>,
        pub youngs_modulus: Option<f64>,
        pub poisson_ratio: Option<f64>,
        pub density: Option<f64>,
        pub yield_stress: Option<f64>,
        pub hardening: Option<Hardening>,
        pub creep: Option<Creep>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Hardening {
        pub strain: Option<String>,
        pub points: Option<Vec<P2>>,
        pub file: Option<String>,
        pub preset: Option<String>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Creep {
        #[serde(rename = "A", alias = "a")]
        pub a: Option<f64>,
        pub n: Option<f64>,
        pub m: Option<f64>,
        pub p: Option<f64>,
        pub q: Option<f64>,
        pub temperature: Option<f64>,
        pub stress_unit: Option<String>,
        pub preset: Option<String>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Body {
        pub name: Option<String>,
        pub material: Option<String>,
        pub mesh_size: Option<f64>,
        pub divisions: Option<Pair<i64>>,
        pub shape: Option<Shape>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Shape {
        #[serde(rename = "type")]
        pub kind: Option<String>,
        pub origin: Option<P2>,
        pub size: Option<P2>,
        pub center: Option<P2>,
        pub radius: Option<f64>,
        pub semi_axes: Option<P2>,
        pub angle: Option<f64>,
        pub vertices: Option<Vec<P2>>,
        pub inner_radius: Option<f64>,
        pub outer_radius: Option<f64>,
        pub angles: Option<P2>,
        pub file: Option<String>,
        pub group: Option<String>,
        pub scale: Option<f64>,
        pub offset: Option<P2>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Boundary {
        pub body: Option<String>,
        pub set: Option<String>,
        pub ux: Option<f64>,
        pub uy: Option<f64>,
        pub radial: Option<f64>,
        pub amplitude: Option<toml::Value>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Load {
        pub body: Option<String>,
        pub set: Option<String>,
        #[serde(rename = "type")]
        pub kind: Option<String>,
        pub value: Option<toml::Value>,
        pub amplitude: Option<toml::Value>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Time {
        pub end: Option<f64>,
        pub dt: Option<f64>,
        pub dt_min: Option<f64>,
        pub dt_max: Option<f64>,
        pub growth: Option<f64>,
        pub cutback: Option<f64>,
        pub easy_iterations: Option<i64>,
        pub max_steps: Option<i64>,
        pub integrator: Option<String>,
        pub hht_alpha: Option<f64>,
        pub newmark_beta: Option<f64>,
        pub newmark_gamma: Option<f64>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Solver {
        pub newton: Option<String>,
        pub max_iterations: Option<i64>,
        pub residual_tol: Option<f64>,
        pub energy_tol: Option<f64>,
        pub line_search: Option<bool>,
        pub linear: Option<String>,
        pub preconditioner: Option<String>,
        pub ordering: Option<String>,
        pub pcg_tol: Option<f64>,
        pub pcg_max_iterations: Option<i64>,
        pub threads: Option<i64>,
        pub incompressible_penalty: Option<f64>,
        pub volume_tol: Option<f64>,
        pub max_volume_updates: Option<i64>,
        pub repartition_imbalance: Option<f64>,
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Output {
        pub reactions: Option<Vec<String>>,
        pub displacements: Option<Vec<String>>,
        pub every: Option<i64>,
        pub checkpoint_every: Option<i64>,
        pub checkpoint_minutes: Option<f64>,
    }
}

// ---------------------------------------------------------------------------------------------
// Source locations: key path <-> byte span, line/column
// ---------------------------------------------------------------------------------------------

struct Locator<'a> {
    text: &'a str,
    /// Every key and value of the document with its dotted path.
    entries: Vec<(String, Range<usize>)>,
    /// First byte of each path (the key for table entries, the value for array items).
    first: HashMap<String, usize>,
}

impl<'a> Locator<'a> {
    fn new(text: &'a str, root: &toml::de::DeTable<'_>) -> Self {
        let mut loc = Locator {
            text,
            entries: Vec::new(),
            first: HashMap::new(),
        };
        loc.walk_table(root, "");
        loc
    }

    fn walk_table(&mut self, table: &toml::de::DeTable<'_>, prefix: &str) {
        for (k, v) in table.iter() {
            let path = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            let ks = k.span();
            self.first.entry(path.clone()).or_insert(ks.start);
            self.entries.push((path.clone(), ks));
            self.walk_value(v.get_ref(), v.span(), &path);
        }
    }

    fn walk_value(&mut self, v: &toml::de::DeValue<'_>, span: Range<usize>, path: &str) {
        self.entries.push((path.to_string(), span.clone()));
        self.first.entry(path.to_string()).or_insert(span.start);
        match v {
            toml::de::DeValue::Table(t) => self.walk_table(t, path),
            toml::de::DeValue::Array(a) => {
                for (i, item) in a.iter().enumerate() {
                    self.walk_value(item.get_ref(), item.span(), &format!("{path}[{i}]"));
                }
            }
            _ => {}
        }
    }

    /// The innermost key or value whose span contains byte `pos`.
    fn path_at(&self, pos: usize) -> Option<String> {
        self.entries
            .iter()
            .filter(|(_, r)| (r.start <= pos && pos < r.end) || (r.start == pos && r.end == pos))
            .min_by_key(|(_, r)| r.end - r.start)
            .map(|(p, _)| p.clone())
    }

    /// Line of `path` or of its nearest ancestor present in the file.
    fn line_of(&self, path: &str) -> Option<usize> {
        let mut p = path;
        loop {
            if let Some(&pos) = self.first.get(p) {
                return Some(line_col(self.text, pos).0);
            }
            let cut = p.rfind(['.', '['])?;
            p = &p[..cut];
            if p.is_empty() {
                return None;
            }
        }
    }
}

/// 1-based line and column (in characters) of byte `pos`.
fn line_col(text: &str, pos: usize) -> (usize, usize) {
    let mut pos = pos.min(text.len());
    while !text.is_char_boundary(pos) {
        pos -= 1;
    }
    let before = &text[..pos];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = text[line_start..pos].chars().count() + 1;
    (line, col)
}

fn toml_error(text: &str, loc: Option<&Locator>, e: &toml::de::Error) -> CaseError {
    let msg = e.message().trim().replace('\n', "; ");
    match e.span() {
        Some(span) => {
            let (line, col) = line_col(text, span.start);
            let key = loc.and_then(|l| l.path_at(span.start)).unwrap_or_default();
            CaseError::new(key, format!("line {line}, column {col}: {msg}"))
        }
        None => CaseError::new("", format!("invalid case file: {msg}")),
    }
}

// ---------------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------------

struct Cx<'a> {
    loc: &'a Locator<'a>,
    base_dir: &'a Path,
    /// gmsh files read so far (a file with many particles is parsed once).
    msh_cache: std::cell::RefCell<HashMap<PathBuf, std::rc::Rc<Vec<crate::mesh::import::MshParticle>>>>,
}

fn join_names<'s>(names: impl IntoIterator<Item = &'s str>) -> String {
    let v: Vec<&str> = names.into_iter().collect();
    if v.is_empty() {
        "none".to_string()
    } else {
        v.join(", ")
    }
}

fn value_num(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    }
}

fn describe(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("{s:?}"),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::Float(f) => format!("{f:?}"),
        toml::Value::Boolean(b) => b.to_string(),
        toml::Value::Datetime(d) => d.to_string(),
        toml::Value::Array(a) => {
            let mut s = String::from("[");
            for (i, x) in a.iter().enumerate() {
                if i > 0 {
                    s.push_str(", ");
                }
                s.push_str(&describe(x));
            }
            s.push(']');
            s
        }
        toml::Value::Table(_) => "a table".to_string(),
    }
}

/// Allowed characters in body names (they appear in `body.set` and in CSV column names).
fn valid_body_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

impl Cx<'_> {
    /// An error at `key`, with the line of the key (or its nearest ancestor) appended.
    fn err(&self, key: &str, msg: impl Into<String>) -> CaseError {
        let mut message = msg.into();
        if let Some(line) = self.loc.line_of(key) {
            let _ = write!(message, " (line {line})");
        }
        CaseError::new(key, message)
    }

    fn missing(&self, key: &str, expected: &str) -> CaseError {
        self.err(key, format!("missing; expected {expected}"))
    }

    fn req<T>(&self, v: Option<T>, key: &str, expected: &str) -> Result<T, CaseError> {
        v.ok_or_else(|| self.missing(key, expected))
    }

    /// A finite number satisfying `ok`.
    fn num(&self, key: &str, v: f64, ok: bool, expected: &str) -> Result<f64, CaseError> {
        if !v.is_finite() {
            return Err(self.err(
                key,
                format!("value {v:?} is not a finite number; expected {expected}"),
            ));
        }
        if !ok {
            return Err(self.err(key, format!("value {v:?}; expected {expected}")));
        }
        Ok(v)
    }

    fn positive(&self, key: &str, v: f64, what: &str) -> Result<f64, CaseError> {
        self.num(key, v, v > 0.0, &format!("{what} > 0"))
    }

    fn finite(&self, key: &str, v: f64, what: &str) -> Result<f64, CaseError> {
        self.num(key, v, true, what)
    }

    fn finite2(&self, key: &str, v: [f64; 2], what: &str) -> Result<[f64; 2], CaseError> {
        for (i, x) in v.iter().enumerate() {
            self.finite(&format!("{key}[{i}]"), *x, what)?;
        }
        Ok(v)
    }

    fn count(&self, key: &str, v: i64, min: i64) -> Result<usize, CaseError> {
        if v < min {
            return Err(self.err(key, format!("value {v}; expected an integer >= {min}")));
        }
        usize::try_from(v).map_err(|_| self.err(key, format!("value {v} is too large")))
    }

    fn choice<'v>(&self, key: &str, v: &str, allowed: &[&'v str]) -> Result<&'v str, CaseError> {
        allowed.iter().find(|a| **a == v).copied().ok_or_else(|| {
            let list: Vec<String> = allowed.iter().map(|a| format!("\"{a}\"")).collect();
            self.err(
                key,
                format!("value \"{v}\"; expected one of {}", list.join(", ")),
            )
        })
    }

    // ---- whole case ---------------------------------------------------------------------

    fn case(&self, r: raw::Case) -> Result<Case, CaseError> {
        let title = r.title.unwrap_or_default();
        let element = match r.model.as_ref().and_then(|m| m.element.clone()) {
            None => crate::element::ElementKind::Q1P0,
            Some(e) => match e.as_str() {
                "q1p0" => crate::element::ElementKind::Q1P0,
                "q1p0_enhanced" => crate::element::ElementKind::Q1P0Enhanced,
                _ => {
                    return Err(self.err(
                        "model.element",
                        format!("value \"{e}\"; expected \"q1p0\" (mean dilatation) or \"q1p0_enhanced\" (mean dilatation + enhanced bending modes)"),
                    ))
                }
            },
        };
        let formulation = match r.model.and_then(|m| m.formulation) {
            None => Formulation::UpdatedLagrangian,
            Some(f) => match f.as_str() {
                "updated_lagrangian" | "ul" => Formulation::UpdatedLagrangian,
                "total_lagrangian" | "tl" => Formulation::TotalLagrangian,
                _ => {
                    return Err(self.err(
                        "model.formulation",
                        format!(
                            "value \"{f}\"; expected \"updated_lagrangian\" (or \"ul\") or \"total_lagrangian\" (or \"tl\")"
                        ),
                    ))
                }
            },
        };

        let raw_materials = r.materials.unwrap_or_default();
        // a density must be given explicitly when the analysis is dynamic (checked below)
        let density_given: Vec<bool> = raw_materials.iter().map(|m| m.density.is_some()).collect();
        if raw_materials.is_empty() {
            return Err(self.err(
                "materials",
                "no material defined; expected at least one [[materials]] table with name, model, youngs_modulus and poisson_ratio",
            ));
        }
        let mut materials = Vec::with_capacity(raw_materials.len());
        for (i, m) in raw_materials.into_iter().enumerate() {
            let key = format!("materials[{i}]");
            let spec = self.material(&key, m)?;
            if materials.iter().any(|x: &MaterialSpec| x.name == spec.name) {
                return Err(self.err(
                    &format!("{key}.name"),
                    format!(
                        "value \"{}\": duplicated material name; expected names to be unique",
                        spec.name
                    ),
                ));
            }
            materials.push(spec);
        }

        let raw_walls = r.walls.unwrap_or_default();
        let mut walls = Vec::with_capacity(raw_walls.len());
        for (i, w) in raw_walls.into_iter().enumerate() {
            walls.push(self.wall(&format!("walls[{i}]"), w)?);
        }
        let contact = self.contact(r.contact)?;
        if contact.method == ContactMethod::Lagrange {
            use crate::contact::kernels::ContactKind;
            if !matches!(contact.kind, ContactKind::Sliding) {
                return Err(self.err(
                    "contact.method",
                    "value \"lagrange\": Lagrange multipliers are implemented for frictionless contact only; expected contact.contact = \"sliding\" or method = \"augmented_lagrangian\" (which also ties and rubs)",
                ));
            }
            if let Some(i) = walls.iter().position(|w| !matches!(w.kind, ContactKind::Sliding)) {
                return Err(self.err(
                    &format!("walls[{i}].contact"),
                    "Lagrange multipliers (contact.method = \"lagrange\") are implemented for frictionless contact only; expected \"sliding\" or method = \"augmented_lagrangian\"",
                ));
            }
        }
        let stop = match r.stop {
            None => StopSpec { solid_ratio: None, jam: true, jam_solid_ratio: 0.9 },
            Some(st) => StopSpec {
                solid_ratio: match st.solid_ratio {
                    Some(v) => Some(self.num("stop.solid_ratio", v, v > 0.0 && v <= 1.0, "a solid ratio in (0, 1]")?),
                    None => None,
                },
                jam: st.jam.unwrap_or(true),
                jam_solid_ratio: match st.jam_solid_ratio {
                    Some(v) => self.num("stop.jam_solid_ratio", v, v > 0.0 && v <= 1.0, "a solid ratio in (0, 1]")?,
                    None => 0.9,
                },
            },
        };
        let mut raw_bodies = r.bodies.unwrap_or_default();
        for (i, g) in r.grids.unwrap_or_default().into_iter().enumerate() {
            raw_bodies.extend(self.grid(&format!("grids[{i}]"), g, &walls, &materials)?);
        }
        for (i, p) in r.packings.unwrap_or_default().into_iter().enumerate() {
            raw_bodies.extend(self.packing(&format!("packings[{i}]"), i, p, &walls, &materials)?);
        }
        for (i, imp) in r.imports.unwrap_or_default().into_iter().enumerate() {
            raw_bodies.extend(self.import(&format!("imports[{i}]"), i, imp, &materials)?);
        }
        if raw_bodies.is_empty() {
            return Err(self.err(
                "bodies",
                "no body defined; expected at least one [[bodies]] table with name, material, mesh_size and shape (or [[grids]], [[packings]], [[imports]])",
            ));
        }
        let mut bodies: Vec<BodySpec> = Vec::with_capacity(raw_bodies.len());
        for (i, b) in raw_bodies.into_iter().enumerate() {
            let key = format!("bodies[{i}]");
            let spec = self.body(&key, b, &materials)?;
            if bodies.iter().any(|x| x.name == spec.name) {
                return Err(self.err(
                    &format!("{key}.name"),
                    format!(
                        "value \"{}\": duplicated body name; expected names to be unique",
                        spec.name
                    ),
                ));
            }
            bodies.push(spec);
        }
        self.check_overlaps(&bodies)?;

        let mut boundary = Vec::new();
        for (i, b) in r.boundary.unwrap_or_default().into_iter().enumerate() {
            boundary.push(self.dirichlet(&format!("boundary[{i}]"), b, &bodies)?);
        }
        let mut loads = Vec::new();
        for (i, l) in r.loads.unwrap_or_default().into_iter().enumerate() {
            loads.push(self.load(&format!("loads[{i}]"), l, &bodies)?);
        }

        let time = match r.time {
            Some(t) => self.time(t)?,
            None => {
                return Err(self.err(
                    "time",
                    "missing; expected a [time] table with at least `end` and `dt` (s)",
                ))
            }
        };
        if time.integrator.is_dynamic() {
            if let Some(i) = density_given.iter().position(|given| !given) {
                return Err(self.err(
                    &format!("materials[{i}].density"),
                    format!(
                        "missing for material \"{}\"; expected a density > 0 (t/mm^3): the dynamic integrator (time.integrator) needs the mass of every material",
                        materials[i].name
                    ),
                ));
            }
        }
        let solver = self.solver(r.solver)?;
        if contact.method == ContactMethod::Lagrange {
            if let LinearChoice::Fixed(k) = solver.linear {
                if k != LinearSolverKind::Lu {
                    return Err(self.err(
                        "solver.linear",
                        format!("value {k:?}: contact.method = \"lagrange\" gives an indefinite system; expected \"lu\" or \"auto\""),
                    ));
                }
            }
        }
        let output = self.output(r.output, &bodies)?;

        let remesh = match r.remesh {
            None => RemeshSpec::default(),
            Some(m) => self.remesh(m, &time)?,
        };
        Ok(Case {
            title,
            formulation,
            element,
            materials,
            bodies,
            boundary,
            loads,
            time,
            solver,
            output,
            walls,
            contact,
            stop,
            remesh,
            base_dir: self.base_dir.to_path_buf(),
        })
    }

    fn remesh(&self, m: raw::RemeshRaw, time: &TimeSpec) -> Result<RemeshSpec, CaseError> {
        let mut spec = RemeshSpec { enabled: m.enabled.unwrap_or(true), ..RemeshSpec::default() };
        if let Some(v) = m.min_scaled_jacobian {
            spec.limits.min_scaled_jacobian = self.num("remesh.min_scaled_jacobian", v, v > 0.0 && v < 1.0, "a scaled Jacobian in (0, 1)")?;
        }
        if let Some(v) = m.max_aspect_ratio {
            spec.limits.max_aspect_ratio = self.num("remesh.max_aspect_ratio", v, v > 1.0, "an aspect ratio > 1")?;
        }
        if let Some(v) = m.min_angle {
            spec.limits.min_angle_deg = self.num("remesh.min_angle", v, v > 0.0 && v < 90.0, "an angle in degrees in (0, 90)")?;
        }
        if let Some(v) = m.mesh_size {
            spec.mesh_size = Some(self.positive("remesh.mesh_size", v, "an element size (mm)")?);
        }
        if let Some(v) = m.max_remeshes {
            spec.max_remeshes = self.count("remesh.max_remeshes", v, 0)?;
        }
        if spec.enabled && time.integrator.is_dynamic() {
            return Err(self.err(
                "remesh.enabled",
                "value true with an implicit dynamic analysis (time.integrator): velocities and accelerations are not transferred to a new mesh; expected enabled = false or a quasi-static analysis",
            ));
        }
        Ok(spec)
    }

    // ---- materials ----------------------------------------------------------------------

    fn material(&self, key: &str, m: raw::Material) -> Result<MaterialSpec, CaseError> {
        let name = self.req(
            m.name,
            &format!("{key}.name"),
            "a unique, non-empty material name",
        )?;
        if name.trim().is_empty() {
            return Err(self.err(
                &format!("{key}.name"),
                "empty name; expected a unique, non-empty material name",
            ));
        }
        let model_key = format!("{key}.model");
        let model = self.req(m.model, &model_key, "\"elastic\", \"j2\" or \"creep\"")?;
        let model = self.choice(&model_key, &model, &["elastic", "j2", "creep"])?;

        let e_key = format!("{key}.youngs_modulus");
        let e = self.req(m.youngs_modulus, &e_key, "Young's modulus E > 0 (MPa)")?;
        let e = self.positive(&e_key, e, "Young's modulus E (MPa)")?;
        let nu_key = format!("{key}.poisson_ratio");
        let nu = self.req(m.poisson_ratio, &nu_key, "a Poisson's ratio in [0, 0.5]")?;
        let nu = self.num(
            &nu_key,
            nu,
            (0.0..=0.5).contains(&nu),
            "a Poisson's ratio in [0, 0.5]",
        )?;
        let density = match m.density {
            None => DEFAULT_DENSITY,
            Some(d) => self.positive(&format!("{key}.density"), d, "a density (t/mm^3)")?,
        };

        if model != "j2" {
            if m.yield_stress.is_some() {
                return Err(self.err(
                    &format!("{key}.yield_stress"),
                    format!("not allowed for model \"{model}\"; expected only with model = \"j2\""),
                ));
            }
            if m.hardening.is_some() {
                return Err(self.err(
                    &format!("{key}.hardening"),
                    format!("not allowed for model \"{model}\"; expected only with model = \"j2\""),
                ));
            }
        }
        if model != "creep" && m.creep.is_some() {
            return Err(self.err(
                &format!("{key}.creep"),
                format!("not allowed for model \"{model}\"; expected only with model = \"creep\""),
            ));
        }

        let material = match model {
            "elastic" => Material::Elastic(Elastic::new(e, nu)),
            "j2" => {
                let table = match (m.yield_stress, m.hardening) {
                    (Some(_), Some(_)) => {
                        return Err(self.err(
                            &format!("{key}.hardening"),
                            "given together with yield_stress; expected exactly one of yield_stress (perfect plasticity) or hardening (table)",
                        ))
                    }
                    (None, None) => {
                        return Err(self.err(
                            key,
                            "model \"j2\" needs its yield behaviour; expected exactly one of yield_stress = <MPa> or hardening = { ... }",
                        ))
                    }
                    (Some(sy), None) => {
                        let sy = self.positive(&format!("{key}.yield_stress"), sy, "a yield stress (MPa)")?;
                        HardeningTable::perfect(sy)
                    }
                    (None, Some(h)) => self.hardening(&format!("{key}.hardening"), h, e)?,
                };
                Material::J2(J2Plastic::new(e, nu, table))
            }
            _ => {
                let c = self.req(
                    m.creep,
                    &format!("{key}.creep"),
                    "a creep table, e.g. creep = { preset = \"asphalt_table2\", stress_unit = \"Pa\" }",
                )?;
                Material::Creep(Creep::new(e, nu, self.creep(&format!("{key}.creep"), c)?))
            }
        };
        Ok(MaterialSpec {
            name,
            density,
            material,
        })
    }

    fn hardening(&self, key: &str, h: raw::Hardening, e: f64) -> Result<HardeningTable, CaseError> {
        let sources = [h.points.is_some(), h.file.is_some(), h.preset.is_some()]
            .iter()
            .filter(|x| **x)
            .count();
        if sources != 1 {
            return Err(self.err(
                key,
                format!(
                    "{} of points, file, preset given; expected exactly one (points = [[strain, stress], ...], file = \"table.csv\" or preset = \"aluminium_250c\")",
                    sources
                ),
            ));
        }
        if let Some(preset) = h.preset {
            let pkey = format!("{key}.preset");
            self.choice(&pkey, &preset, &["aluminium_250c"])?;
            if h.strain.is_some() {
                return Err(self.err(
                    &format!("{key}.strain"),
                    "not allowed with preset (the preset defines its strain measure); expected only with points or file",
                ));
            }
            return HardeningTable::from_total_strain(
                e,
                &crate::material::hardening::aluminium_250c(),
            )
            .map_err(|msg| self.err(key, format!("preset \"aluminium_250c\" rejected: {msg}")));
        }
        let skey = format!("{key}.strain");
        let strain = self.req(
            h.strain,
            &skey,
            "the strain measure of the table: \"total\" (strain includes the elastic part) or \"plastic\"",
        )?;
        let strain = self.choice(&skey, &strain, &["total", "plastic"])?;

        let (points, pkey) = if let Some(points) = h.points {
            (
                points.into_iter().map(|p| p.0).collect(),
                format!("{key}.points"),
            )
        } else {
            let file = h.file.unwrap_or_default();
            let fkey = format!("{key}.file");
            let path = self.base_dir.join(&file);
            let text = std::fs::read_to_string(&path).map_err(|err| {
                self.err(
                    &fkey,
                    format!("cannot read hardening table \"{}\": {err}", path.display()),
                )
            })?;
            let pts = read_two_columns(&text)
                .map_err(|msg| self.err(&fkey, format!("in \"{}\": {msg}", path.display())))?;
            (pts, fkey)
        };
        self.check_table(&pkey, &points, strain)?;
        let table = if strain == "total" {
            HardeningTable::from_total_strain(e, &points)
        } else {
            HardeningTable::from_plastic_strain(&points)
        };
        table.map_err(|msg| self.err(key, format!("invalid hardening table: {msg}")))
    }

    /// Checks shared by both strain measures: finite, strain >= 0 and strictly increasing,
    /// stress >= 0 and non-decreasing (softening is not supported).
    fn check_table(&self, key: &str, pts: &[[f64; 2]], strain: &str) -> Result<(), CaseError> {
        if pts.is_empty() {
            return Err(self.err(
                key,
                "empty table; expected at least one [strain, stress] point",
            ));
        }
        for (i, p) in pts.iter().enumerate() {
            let k = format!("{key}[{i}]");
            if !p[0].is_finite() || !p[1].is_finite() {
                return Err(self.err(
                    &k,
                    format!(
                        "value [{:?}, {:?}]; expected finite numbers [strain, stress (MPa)]",
                        p[0], p[1]
                    ),
                ));
            }
            if p[0] < 0.0 || p[1] < 0.0 {
                return Err(self.err(
                    &k,
                    format!(
                        "value [{:?}, {:?}]; expected strain >= 0 and stress >= 0",
                        p[0], p[1]
                    ),
                ));
            }
            if i > 0 {
                let q = pts[i - 1];
                if p[0] <= q[0] {
                    return Err(self.err(
                        &k,
                        format!(
                            "{strain} strain {:?} after {:?}; expected a table with strictly increasing strain",
                            p[0], q[0]
                        ),
                    ));
                }
                if p[1] < q[1] {
                    return Err(self.err(
                        &k,
                        format!(
                            "stress {:?} MPa after {:?} MPa; expected a non-decreasing (hardening) stress, softening is not supported",
                            p[1], q[1]
                        ),
                    ));
                }
            }
        }
        if strain == "plastic" && pts[0][1] <= 0.0 {
            return Err(self.err(
                &format!("{key}[0]"),
                format!("initial yield stress {:?}; expected the first point's stress (the initial yield stress) > 0", pts[0][1]),
            ));
        }
        Ok(())
    }

    fn creep(&self, key: &str, c: raw::Creep) -> Result<CreepParams, CaseError> {
        let ukey = format!("{key}.stress_unit");
        let unit = c.stress_unit.ok_or_else(|| {
            self.err(
                &ukey,
                "missing; expected \"Pa\", \"kPa\", \"MPa\" or \"GPa\": the stress unit the creep coefficient A was fitted in. \
                 The paper does not state it, and because the creep rate goes as A·(s·σ)^n with s the unit factor, the choice changes the creep rate \
                 by orders of magnitude (a factor 10^(6n) between \"Pa\" and \"MPa\"), so there is no safe default",
            )
        })?;
        let stress_scale = match self.choice(&ukey, &unit, &["Pa", "kPa", "MPa", "GPa"])? {
            "Pa" => 1e6,
            "kPa" => 1e3,
            "MPa" => 1.0,
            _ => 1e-3,
        };
        let base = match &c.preset {
            Some(p) => {
                self.choice(&format!("{key}.preset"), p, &["asphalt_table2"])?;
                Some(CreepParams::asphalt_table2(1.0))
            }
            None => None,
        };
        let need = |v: Option<f64>,
                    name: &str,
                    preset: Option<f64>,
                    what: &str|
         -> Result<f64, CaseError> {
            match v.or(preset) {
                Some(x) => Ok(x),
                None => Err(self.missing(&format!("{key}.{name}"), what)),
            }
        };
        let a = need(
            c.a,
            "A",
            base.map(|b| b.a),
            "the creep coefficient A > 0 (or preset = \"asphalt_table2\")",
        )?;
        let n = need(
            c.n,
            "n",
            base.map(|b| b.n),
            "the stress exponent n > 0 (or preset = \"asphalt_table2\")",
        )?;
        let q = need(
            c.q,
            "q",
            base.map(|b| b.q),
            "the time exponent q > 0 (or preset = \"asphalt_table2\")",
        )?;
        let temperature = need(
            c.temperature,
            "temperature",
            base.map(|b| b.temperature),
            "a temperature T > 0 (or preset = \"asphalt_table2\")",
        )?;
        let m = c.m.or(base.map(|b| b.m)).unwrap_or(0.0);
        let p = c.p.or(base.map(|b| b.p)).unwrap_or(0.0);
        let a = self.positive(&format!("{key}.A"), a, "the creep coefficient A")?;
        let n = self.positive(&format!("{key}.n"), n, "the stress exponent n")?;
        let m = self.num(
            &format!("{key}.m"),
            m,
            m < 1.0,
            "the strain-hardening exponent m < 1",
        )?;
        let p = self.finite(&format!("{key}.p"), p, "a finite temperature exponent p")?;
        let q = self.positive(&format!("{key}.q"), q, "the time exponent q")?;
        let temperature = self.positive(
            &format!("{key}.temperature"),
            temperature,
            "a temperature T",
        )?;
        Ok(CreepParams {
            a,
            n,
            m,
            p,
            q,
            temperature,
            stress_scale,
        })
    }

    // ---- bodies -------------------------------------------------------------------------

    fn body(
        &self,
        key: &str,
        b: raw::Body,
        materials: &[MaterialSpec],
    ) -> Result<BodySpec, CaseError> {
        let nkey = format!("{key}.name");
        let name = self.req(
            b.name,
            &nkey,
            "a unique body name of letters, digits, '_' and '-'",
        )?;
        if !valid_body_name(&name) {
            return Err(self.err(
                &nkey,
                format!("value \"{name}\"; expected a non-empty name of ASCII letters, digits, '_' and '-' (it is used in \"body.set\" references and CSV column names)"),
            ));
        }
        let mkey = format!("{key}.material");
        let mat_name = self.req(b.material, &mkey, "the name of a material")?;
        let material = materials
            .iter()
            .position(|m| m.name == mat_name)
            .ok_or_else(|| {
                self.err(
                    &mkey,
                    format!(
                        "value \"{mat_name}\": no material named \"{mat_name}\" (known: {})",
                        join_names(materials.iter().map(|m| m.name.as_str()))
                    ),
                )
            })?;
        let shape = match b.shape {
            Some(s) => self.shape(&format!("{key}.shape"), s)?,
            None => {
                return Err(self.missing(
                    &format!("{key}.shape"),
                    "a shape, e.g. shape = { type = \"rectangle\", origin = [0.0, 0.0], size = [20.0, 20.0] }",
                ))
            }
        };
        let dkey = format!("{key}.divisions");
        let divisions = match b.divisions {
            None => None,
            Some(raw::Pair(d)) => {
                if !matches!(
                    shape,
                    ShapeSpec::Rectangle { .. } | ShapeSpec::Cook | ShapeSpec::AnnulusSector { .. }
                ) {
                    return Err(self.err(
                        &dkey,
                        format!(
                            "not allowed for shape type \"{}\"; expected divisions only for rectangle, cook and annulus_sector (use mesh_size)",
                            shape.type_name()
                        ),
                    ));
                }
                let mut out = [0usize; 2];
                for (i, v) in d.iter().enumerate() {
                    if !(1..=MAX_DIVISIONS).contains(v) {
                        return Err(self.err(
                            &format!("{dkey}[{i}]"),
                            format!(
                                "value {v}; expected a number of divisions in [1, {MAX_DIVISIONS}]"
                            ),
                        ));
                    }
                    out[i] = usize::try_from(*v).map_err(|_| {
                        self.err(&format!("{dkey}[{i}]"), format!("value {v} is too large"))
                    })?;
                }
                Some(out)
            }
        };
        let hkey = format!("{key}.mesh_size");
        if let ShapeSpec::Gmsh { mesh, .. } = &shape {
            if let Some(h) = b.mesh_size {
                return Err(self.err(
                    &hkey,
                    format!("value {h:?}: not allowed for shape type \"gmsh\" (the elements come from the file); expected no mesh_size"),
                ));
            }
            // the element size of the imported mesh: the side of a square of its mean element area
            let n = mesh.n_elements().max(1) as f64;
            let mesh_size = (mesh.area(&mesh.nodes).abs() / n).sqrt();
            return Ok(BodySpec { name, material, shape, mesh_size, divisions });
        }
        let mesh_size = match (b.mesh_size, divisions) {
            (Some(h), _) => self.positive(&hkey, h, "a target element edge length h (mm)")?,
            (None, Some(d)) => implied_mesh_size(&shape, d),
            (None, None) => {
                return Err(self.missing(
                    &hkey,
                    "a target element edge length h > 0 (mm), or divisions = [nx, ny]",
                ))
            }
        };
        Ok(BodySpec {
            name,
            material,
            shape,
            mesh_size,
            divisions,
        })
    }

    fn shape(&self, key: &str, s: raw::Shape) -> Result<ShapeSpec, CaseError> {
        let tkey = format!("{key}.type");
        let kind = self.req(
            s.kind.clone(),
            &tkey,
            "\"rectangle\", \"disc\", \"ellipse\", \"polygon\", \"outline\", \"gmsh\", \"cook\" or \"annulus_sector\"",
        )?;
        let kind = self.choice(
            &tkey,
            &kind,
            &[
                "rectangle",
                "disc",
                "ellipse",
                "polygon",
                "outline",
                "gmsh",
                "cook",
                "annulus_sector",
            ],
        )?;
        let allowed: &[&str] = match kind {
            "rectangle" => &["origin", "size"],
            "disc" => &["center", "radius"],
            "ellipse" => &["center", "semi_axes", "angle"],
            "polygon" | "outline" => &["vertices"],
            "gmsh" => &["file", "group", "scale", "offset"],
            "cook" => &[],
            _ => &["center", "inner_radius", "outer_radius", "angles"],
        };
        let present = [
            ("origin", s.origin.is_some()),
            ("size", s.size.is_some()),
            ("center", s.center.is_some()),
            ("radius", s.radius.is_some()),
            ("semi_axes", s.semi_axes.is_some()),
            ("angle", s.angle.is_some()),
            ("vertices", s.vertices.is_some()),
            ("inner_radius", s.inner_radius.is_some()),
            ("outer_radius", s.outer_radius.is_some()),
            ("angles", s.angles.is_some()),
            ("file", s.file.is_some()),
            ("group", s.group.is_some()),
            ("scale", s.scale.is_some()),
            ("offset", s.offset.is_some()),
        ];
        for (field, is) in present {
            if is && !allowed.contains(&field) {
                return Err(self.err(
                    &format!("{key}.{field}"),
                    format!(
                        "not a parameter of shape type \"{kind}\"; expected only: {}",
                        if allowed.is_empty() {
                            "type".to_string()
                        } else {
                            format!("type, {}", allowed.join(", "))
                        }
                    ),
                ));
            }
        }
        let center = |cx: &Self| -> Result<[f64; 2], CaseError> {
            cx.finite2(
                &format!("{key}.center"),
                s.center.map_or([0.0, 0.0], |p| p.0),
                "a finite centre coordinate (mm)",
            )
        };
        Ok(match kind {
            "rectangle" => {
                let origin = self.finite2(
                    &format!("{key}.origin"),
                    s.origin.map_or([0.0, 0.0], |p| p.0),
                    "a finite coordinate (mm)",
                )?;
                let skey = format!("{key}.size");
                let size = self.req(
                    s.size.map(|p| p.0),
                    &skey,
                    "size = [width, height] > 0 (mm)",
                )?;
                for (i, v) in size.iter().enumerate() {
                    self.positive(&format!("{skey}[{i}]"), *v, "a side length (mm)")?;
                }
                ShapeSpec::Rectangle { origin, size }
            }
            "disc" => {
                let center = center(self)?;
                let rkey = format!("{key}.radius");
                let r = self.req(s.radius, &rkey, "a radius > 0 (mm)")?;
                let radius = self.positive(&rkey, r, "a radius (mm)")?;
                ShapeSpec::Disc { center, radius }
            }
            "ellipse" => {
                let center = center(self)?;
                let akey = format!("{key}.semi_axes");
                let semi_axes = self.req(
                    s.semi_axes.map(|p| p.0),
                    &akey,
                    "semi_axes = [a, b] > 0 (mm)",
                )?;
                for (i, v) in semi_axes.iter().enumerate() {
                    self.positive(&format!("{akey}[{i}]"), *v, "a semi-axis (mm)")?;
                }
                let angle_deg = self.finite(
                    &format!("{key}.angle"),
                    s.angle.unwrap_or(0.0),
                    "a finite angle (degrees)",
                )?;
                ShapeSpec::Ellipse {
                    center,
                    semi_axes,
                    angle_deg,
                }
            }
            "polygon" => {
                let vkey = format!("{key}.vertices");
                let vertices: Vec<[f64; 2]> = self
                    .req(
                        s.vertices,
                        &vkey,
                        "at least 3 vertices [[x0, y0], [x1, y1], ...] (mm)",
                    )?
                    .into_iter()
                    .map(|p| p.0)
                    .collect();
                if vertices.len() < 3 {
                    return Err(self.err(
                        &vkey,
                        format!("{} vertices; expected at least 3", vertices.len()),
                    ));
                }
                for (i, v) in vertices.iter().enumerate() {
                    self.finite2(
                        &format!("{vkey}[{i}]"),
                        *v,
                        "a finite vertex coordinate (mm)",
                    )?;
                }
                let n = vertices.len();
                let area2: f64 = (0..n)
                    .map(|i| {
                        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                        a[0] * b[1] - b[0] * a[1]
                    })
                    .sum();
                let scale = vertices
                    .iter()
                    .fold(0.0f64, |m, v| m.max(v[0].abs()).max(v[1].abs()))
                    .max(1e-300);
                if area2.abs() <= 1e-12 * scale * scale {
                    return Err(self.err(
                        &vkey,
                        "the polygon has zero area; expected vertices of a convex polygon",
                    ));
                }
                ShapeSpec::Polygon { vertices }
            }
            "cook" => ShapeSpec::Cook,
            "outline" => {
                let vkey = format!("{key}.vertices");
                let vertices: Vec<[f64; 2]> = self
                    .req(s.vertices, &vkey, "at least 3 vertices [[x0, y0], [x1, y1], ...] (mm) of a simple polygon")?
                    .into_iter()
                    .map(|p| p.0)
                    .collect();
                for (i, v) in vertices.iter().enumerate() {
                    self.finite2(&format!("{vkey}[{i}]"), *v, "a finite vertex coordinate (mm)")?;
                }
                crate::mesh::polygon::check_simple_polygon(&vertices)
                    .map_err(|e| self.err(&vkey, format!("{} vertices: {e}; expected a simple polygon (sides that neither cross nor touch)", vertices.len())))?;
                ShapeSpec::Outline { vertices }
            }
            "gmsh" => self.gmsh_shape(key, s)?,
            _ => {
                let center = center(self)?;
                let ikey = format!("{key}.inner_radius");
                let okey = format!("{key}.outer_radius");
                let ri = self.req(s.inner_radius, &ikey, "an inner radius > 0 (mm)")?;
                let ri = self.positive(&ikey, ri, "an inner radius (mm)")?;
                let ro = self.req(s.outer_radius, &okey, "an outer radius > inner_radius (mm)")?;
                let ro = self.num(
                    &okey,
                    ro,
                    ro > ri,
                    &format!("an outer radius > inner_radius = {ri:?} (mm)"),
                )?;
                let gkey = format!("{key}.angles");
                let angles = self.req(
                    s.angles.map(|p| p.0),
                    &gkey,
                    "angles = [start, end] in degrees",
                )?;
                let angles = self.finite2(&gkey, angles, "finite angles (degrees)")?;
                let span = angles[1] - angles[0];
                if !(span > 0.0 && span <= 360.0) {
                    return Err(self.err(
                        &gkey,
                        format!("value [{:?}, {:?}]; expected start < end and end - start <= 360 degrees (360 = full ring)", angles[0], angles[1]),
                    ));
                }
                ShapeSpec::AnnulusSector {
                    center,
                    inner_radius: ri,
                    outer_radius: ro,
                    angles_deg: angles,
                }
            }
        })
    }

    /// Resolve `body` / `set` references of a boundary condition or a load.
    fn body_set(
        &self,
        key: &str,
        body: Option<String>,
        set: Option<String>,
        bodies: &[BodySpec],
    ) -> Result<(usize, String), CaseError> {
        let bkey = format!("{key}.body");
        let name = self.req(body, &bkey, "the name of a body")?;
        let bi = self.find_body(&bkey, &name, bodies)?;
        let skey = format!("{key}.set");
        let set = self.req(
            set,
            &skey,
            &format!(
                "an edge set of body \"{name}\" ({})",
                bodies[bi].shape.edge_set_names().join(", ")
            ),
        )?;
        self.check_set(&skey, &bodies[bi], &set)?;
        Ok((bi, set))
    }

    fn find_body(&self, key: &str, name: &str, bodies: &[BodySpec]) -> Result<usize, CaseError> {
        bodies.iter().position(|b| b.name == name).ok_or_else(|| {
            self.err(
                key,
                format!(
                    "value \"{name}\": no body named \"{name}\" (known: {})",
                    join_names(bodies.iter().map(|b| b.name.as_str()))
                ),
            )
        })
    }

    fn contact_kind(&self, key: &str, kind: Option<String>, friction: Option<f64>) -> Result<crate::contact::kernels::ContactKind, CaseError> {
        use crate::contact::kernels::ContactKind;
        let kind = kind.unwrap_or_else(|| "sliding".into());
        let fkey = key.rsplit_once('.').map_or("friction".to_string(), |(p, _)| format!("{p}.friction"));
        let mu = match friction {
            Some(v) => self.num(&fkey, v, v >= 0.0, "a Coulomb friction coefficient >= 0")?,
            None => 0.0,
        };
        Ok(match self.choice(key, &kind, &["sliding", "rubbing", "cohering"])? {
            "rubbing" => {
                if friction.is_none() {
                    return Err(self.missing(&fkey, "a friction coefficient mu >= 0 for contact = \"rubbing\""));
                }
                ContactKind::Rubbing { mu }
            }
            "cohering" => ContactKind::Cohering,
            _ => {
                if mu > 0.0 {
                    return Err(self.err(&fkey, format!("value {mu}: friction needs contact = \"rubbing\"")));
                }
                ContactKind::Sliding
            }
        })
    }

    fn wall(&self, key: &str, w: raw::WallRaw) -> Result<WallSpec, CaseError> {
        let side_s = self.req(w.side, &format!("{key}.side"), "one of \"left\", \"right\", \"bottom\", \"top\"")?;
        let side = match self.choice(&format!("{key}.side"), &side_s, &["left", "right", "bottom", "top"])? {
            "left" => WallSide::Left,
            "right" => WallSide::Right,
            "bottom" => WallSide::Bottom,
            _ => WallSide::Top,
        };
        let position = self.finite(
            &format!("{key}.position"),
            self.req(w.position, &format!("{key}.position"), "the wall's x (left/right) or y (bottom/top) at t = 0, mm")?,
            "a position in mm",
        )?;
        let velocity = self.finite(&format!("{key}.velocity"), w.velocity.unwrap_or(0.0), "a velocity in mm/s (positive inward)")?;
        let kind = self.contact_kind(&format!("{key}.contact"), w.contact, w.friction)?;
        Ok(WallSpec { side, position, velocity, kind })
    }

    fn contact(&self, c: Option<raw::ContactRaw>) -> Result<ContactSpec, CaseError> {
        let mut spec = ContactSpec::default();
        let Some(c) = c else { return Ok(spec) };
        if let Some(m) = c.method {
            spec.method = match self.choice("contact.method", &m, &["penalty", "augmented_lagrangian", "lagrange"])? {
                "penalty" => ContactMethod::Penalty,
                "lagrange" => ContactMethod::Lagrange,
                _ => ContactMethod::AugmentedLagrangian,
            };
        }
        spec.kind = self.contact_kind("contact.contact", c.contact, c.friction)?;
        if let Some(v) = c.penalty {
            spec.penalty = if v == 0.0 { None } else { Some(self.positive("contact.penalty", v, "a penalty in MPa/mm (0 = automatic)")?) };
        }
        if let Some(v) = c.penetration_tol {
            spec.penetration_tol = self.positive("contact.penetration_tol", v, "a penetration tolerance relative to the element size")?;
        }
        if let Some(v) = c.max_augmentations {
            spec.max_augmentations = self.count("contact.max_augmentations", v, 1)?;
        }
        if let Some(v) = c.stabilisation {
            spec.stabilisation = self.num("contact.stabilisation", v, v >= 0.0, "a stabilisation factor >= 0")?;
        }
        if let Some(v) = c.stabilise {
            spec.stabilise = match self.choice("contact.stabilise", &v, &["unsupported", "all"])? {
                "all" => Stabilise::All,
                _ => Stabilise::Unsupported,
            };
        }
        if let Some(v) = c.stabilisation_kind {
            spec.stabilisation_kind = match self.choice("contact.stabilisation_kind", &v, &["inertial", "viscous"])? {
                "viscous" => StabilisationKind::Viscous,
                _ => StabilisationKind::Inertial,
            };
        }
        if let Some(v) = c.viscous_retry {
            if v && spec.stabilisation_kind != StabilisationKind::Inertial {
                return Err(self.err("contact.viscous_retry", "value true: the springs are viscous already; expected viscous_retry only with stabilisation_kind = \"inertial\""));
            }
            spec.viscous_retry = v;
        }
        if let Some(v) = c.stiffen_on_cutback {
            spec.stiffen_on_cutback = v;
        }
        if let Some(v) = c.regularisation {
            spec.regularisation = self.num("contact.regularisation", v, v >= 0.0, "a regularisation factor >= 0")?;
        }
        if let Some(v) = c.lagrange_regularisation {
            spec.lagrange_regularisation =
                self.num("contact.lagrange_regularisation", v, (0.0..1.0).contains(&v), "a regularisation factor r with 0 <= r < 1 (0 = exact constraints)")?;
        }
        if let Some(v) = c.normal {
            spec.normal = match self.choice("contact.normal", &v, &["segment", "smoothed"])? {
                "smoothed" => ContactNormal::Smoothed,
                _ => ContactNormal::Segment,
            };
        }
        if let Some(v) = c.search_distance {
            spec.search_distance = if v == 0.0 { None } else { Some(self.positive("contact.search_distance", v, "a distance in mm (0 = one element size)")?) };
        }
        Ok(spec)
    }

    /// Particles (bodies) must not overlap: the first overlapping pair is an error at the
    /// later body, naming both (see [`crate::packing::overlap`]; touching is allowed, annulus
    /// sectors are not checked).
    fn check_overlaps(&self, bodies: &[BodySpec]) -> Result<(), CaseError> {
        if bodies.len() < 2 {
            return Ok(());
        }
        let shapes: Vec<_> = bodies.iter().map(|b| b.shape.particle()).collect();
        let Some(o) = crate::packing::overlap::overlapping_particles(&shapes, 1e-9).into_iter().next() else {
            return Ok(());
        };
        let (a, b) = (&bodies[o.first], &bodies[o.second]);
        let depth = if o.depth.is_finite() { format!(" by {:.4} mm", o.depth) } else { String::new() };
        Err(self.err(
            &format!("bodies[{}]", o.second),
            format!(
                "body \"{}\" ({}) overlaps body \"{}\" (bodies[{}], {}){depth}; expected particles that do not overlap (touching is allowed): move or shrink one of them",
                b.name,
                b.shape.type_name(),
                a.name,
                o.first,
                a.shape.type_name()
            ),
        ))
    }

    /// The die `[x0, x1, y0, y1]` closed by the four walls, for the generator at `key`.
    fn die(&self, key: &str, what: &str, walls: &[WallSpec]) -> Result<[f64; 4], CaseError> {
        let [x0, x1, y0, y1] = die_of(walls).ok_or_else(|| self.err(key, format!("a {what} fills the die, which needs all four [[walls]] (left, right, bottom, top)")))?;
        if !(x1 > x0 && y1 > y0) {
            return Err(self.err("walls", format!("the die [{x0}, {x1}] x [{y0}, {y1}] mm is empty; expected left < right and bottom < top")));
        }
        Ok([x0, x1, y0, y1])
    }

    /// The materials of a generator: `material = "a"` or `materials = ["a", "b"]`, each a known
    /// material; `(name, key)` pairs.
    fn material_list(&self, key: &str, material: Option<String>, list: Option<Vec<String>>, materials: &[MaterialSpec]) -> Result<Vec<(String, String)>, CaseError> {
        let k = |field: &str| format!("{key}.{field}");
        let names: Vec<(String, String)> = match (material, list) {
            (Some(m), None) => vec![(m, k("material"))],
            (None, Some(ms)) if !ms.is_empty() => ms.into_iter().enumerate().map(|(i, m)| (m, format!("{key}.materials[{i}]"))).collect(),
            (None, Some(_)) => return Err(self.err(&k("materials"), "empty list; expected at least one material name")),
            (Some(_), Some(_)) => return Err(self.err(&k("materials"), "given together with material; expected material = \"name\" or materials = [\"a\", \"b\", ...], not both")),
            (None, None) => return Err(self.missing(&k("material"), "material = \"name\" or materials = [\"a\", \"b\", ...] (with fractions)")),
        };
        for (name, nkey) in &names {
            if !materials.iter().any(|m| &m.name == name) {
                return Err(self.err(nkey, format!("value \"{name}\": no material named \"{name}\" (known: {})", join_names(materials.iter().map(|m| m.name.as_str())))));
            }
        }
        Ok(names)
    }

    /// `fractions` of a generator with `n` materials (default: equal shares).
    fn fractions(&self, key: &str, fractions: Option<Vec<f64>>, n: usize) -> Result<Vec<f64>, CaseError> {
        let Some(f) = fractions else { return Ok(vec![1.0; n]) };
        if f.len() != n {
            return Err(self.err(&format!("{key}.fractions"), format!("{} value(s) for {n} material(s); expected one fraction per material", f.len())));
        }
        for (i, v) in f.iter().enumerate() {
            self.positive(&format!("{key}.fractions[{i}]"), *v, "a fraction (relative share of the particles)")?;
        }
        Ok(f)
    }

    /// Expand a `[[packings]]` entry into raw bodies named `r{i}_p{k}` inside the die.
    fn packing(&self, key: &str, index: usize, p: raw::PackingRaw, walls: &[WallSpec], materials: &[MaterialSpec]) -> Result<Vec<raw::Body>, CaseError> {
        use crate::packing::random::{self, RandomSpec, Sizes};
        let k = |field: &str| format!("{key}.{field}");
        let [x0, x1, y0, y1] = self.die(key, "random packing", walls)?;
        let kind = self.req(p.kind, &k("kind"), "\"voronoi_polygons\", \"voronoi_ellipses\" or \"discs\"")?;
        let kind = self.choice(&k("kind"), &kind, &["voronoi_polygons", "voronoi_ellipses", "discs"])?;
        let aspect = match p.aspect {
            None => 1.0,
            Some(_) if kind == "discs" => return Err(self.err(&k("aspect"), "not a parameter of kind \"discs\"; expected only with voronoi_polygons or voronoi_ellipses")),
            Some(v) => self.num(&k("aspect"), v, (0.1..=10.0).contains(&v), "an elongation of the cells along x in [0.1, 10] (1 = roundish)")?,
        };
        let count = self.count(&k("count"), self.req(p.count, &k("count"), "the number of particles (>= 1)")?, 1)?;
        if count > MAX_PACKING_COUNT {
            return Err(self.err(&k("count"), format!("value {count}; expected at most {MAX_PACKING_COUNT} particles")));
        }
        let seed = match p.seed {
            None => 0,
            Some(v) => self.count(&k("seed"), v, 0)? as u64,
        };
        let phi = self.req(p.solid_ratio, &k("solid_ratio"), "the initial solid ratio in (0, 1)")?;
        let phi = self.num(&k("solid_ratio"), phi, phi > 0.0 && phi < 1.0, "a solid ratio in (0, 1)")?;
        let h = self.positive(&k("mesh_size"), self.req(p.mesh_size, &k("mesh_size"), "an element size in mm")?, "an element size in mm")?;
        let lloyd = match p.lloyd {
            None => DEFAULT_LLOYD,
            Some(v) => {
                let n = self.count(&k("lloyd"), v, 0)?;
                if n > 1000 {
                    return Err(self.err(&k("lloyd"), format!("value {n}; expected at most 1000 relaxation steps")));
                }
                n
            }
        };
        let names = self.material_list(key, p.material, p.materials, materials)?;
        let fractions = self.fractions(key, p.fractions, names.len())?;
        let sizes = match p.sizes {
            None => Sizes::Equal,
            Some(sz) => {
                let dkey = k("sizes.distribution");
                let dist = self.req(sz.distribution, &dkey, "\"equal\", \"uniform\" or \"lognormal\"")?;
                let dist = self.choice(&dkey, &dist, &["equal", "uniform", "lognormal"])?;
                let ratio = |cx: &Self| -> Result<f64, CaseError> {
                    let rkey = k("sizes.ratio");
                    let r = cx.req(sz.ratio, &rkey, "the largest / smallest radius ratio (> 1)")?;
                    cx.num(&rkey, r, r > 1.0 && r <= 100.0, "a largest / smallest radius ratio in (1, 100]")
                };
                match dist {
                    "equal" => {
                        for (name, is) in [("ratio", sz.ratio.is_some()), ("sigma", sz.sigma.is_some())] {
                            if is {
                                return Err(self.err(&k(&format!("sizes.{name}")), "not a parameter of distribution \"equal\"; expected only with \"uniform\" (ratio) or \"lognormal\" (sigma, ratio)"));
                            }
                        }
                        Sizes::Equal
                    }
                    "uniform" => {
                        if sz.sigma.is_some() {
                            return Err(self.err(&k("sizes.sigma"), "not a parameter of distribution \"uniform\"; expected only ratio"));
                        }
                        Sizes::Uniform { ratio: ratio(self)? }
                    }
                    _ => {
                        let skey = k("sizes.sigma");
                        let sigma = self.req(sz.sigma, &skey, "the standard deviation of ln(radius) (> 0)")?;
                        let sigma = self.num(&skey, sigma, sigma > 0.0 && sigma <= 2.0, "a standard deviation of ln(radius) in (0, 2]")?;
                        Sizes::LogNormal { sigma, ratio: ratio(self)? }
                    }
                }
            }
        };
        let spec = RandomSpec { count, seed, solid_ratio: phi, sizes, lloyd, aspect, fractions };
        let die = random::Die { x: [x0, x1], y: [y0, y1] };
        let packing = match kind {
            "voronoi_polygons" => random::voronoi_polygons(die, &spec),
            "voronoi_ellipses" => random::voronoi_ellipses(die, &spec),
            _ => random::random_discs(die, &spec),
        }
        .map_err(|e| {
            let at = match e.param {
                "die" => "walls".to_string(),
                "count" | "solid_ratio" | "sizes" | "fractions" | "aspect" => k(e.param),
                _ => key.to_string(),
            };
            self.err(&at, e.message)
        })?;
        Ok(packing
            .particles
            .into_iter()
            .enumerate()
            .map(|(j, part)| {
                let material = names[part.material].0.clone();
                raw::Body::generated(format!("r{index}_p{j}"), material, h, raw::Shape::from_convex(part.shape))
            })
            .collect())
    }

    /// The particles of a gmsh file (read once per file).
    fn msh(&self, key: &str, path: &Path) -> Result<std::rc::Rc<Vec<crate::mesh::import::MshParticle>>, CaseError> {
        if let Some(m) = self.msh_cache.borrow().get(path) {
            return Ok(m.clone());
        }
        let bytes = std::fs::read(path).map_err(|e| self.err(key, format!("cannot read gmsh file \"{}\": {e}", path.display())))?;
        let parts = crate::mesh::import::read_msh(&bytes).map_err(|e| self.err(key, format!("in gmsh file \"{}\": {e}", path.display())))?;
        let parts = std::rc::Rc::new(parts);
        self.msh_cache.borrow_mut().insert(path.to_path_buf(), parts.clone());
        Ok(parts)
    }

    /// `scale` (default 1) and `offset` (default [0, 0]) of an import or a gmsh shape.
    fn placement(&self, key: &str, scale: Option<f64>, offset: Option<raw::P2>) -> Result<(f64, [f64; 2]), CaseError> {
        let scale = match scale {
            None => 1.0,
            Some(v) => self.positive(&format!("{key}.scale"), v, "a scale factor")?,
        };
        let offset = self.finite2(&format!("{key}.offset"), offset.map_or([0.0, 0.0], |p| p.0), "a finite shift (mm)")?;
        Ok((scale, offset))
    }

    /// `shape = { type = "gmsh", file, group, scale, offset }`.
    fn gmsh_shape(&self, key: &str, s: raw::Shape) -> Result<ShapeSpec, CaseError> {
        let fkey = format!("{key}.file");
        let file = self.req(s.file, &fkey, "the path of a gmsh .msh file (relative to the case file)")?;
        // absolute, so that a case written elsewhere (mpfem pack) refers to the same file
        let path = self.base_dir.join(&file);
        let path = std::path::absolute(&path).unwrap_or(path);
        let parts = self.msh(&fkey, &path)?;
        let (scale, offset) = self.placement(key, s.scale, s.offset)?;
        let label = |p: &crate::mesh::import::MshParticle| p.name.clone().unwrap_or_else(|| p.tag.to_string());
        let known = || {
            let tags: Vec<String> = parts.iter().map(|p| p.tag.to_string()).collect();
            format!("{}; tags {}", join_names(parts.iter().filter_map(|p| p.name.as_deref())), tags.join(", "))
        };
        let gkey = format!("{key}.group");
        let part = match s.group {
            Some(g) => parts
                .iter()
                .find(|p| p.name.as_deref() == Some(g.as_str()))
                .or_else(|| parts.iter().find(|p| p.tag.to_string() == g))
                .ok_or_else(|| self.err(&gkey, format!("value \"{g}\": gmsh file \"{}\" has no 2D physical group named or tagged \"{g}\" (names: {})", path.display(), known())))?,
            None if parts.len() == 1 => &parts[0],
            None => return Err(self.missing(&gkey, &format!("the physical group (name or tag) of the particle: gmsh file \"{}\" has {} (names: {})", path.display(), parts.len(), known()))),
        };
        let mut mesh = part.mesh.clone();
        for p in &mut mesh.nodes {
            *p = [scale * p[0] + offset[0], scale * p[1] + offset[1]];
        }
        Ok(ShapeSpec::Gmsh { file: path, group: label(part), scale, offset, mesh: std::sync::Arc::new(mesh) })
    }

    /// Expand an `[[imports]]` entry into raw bodies: the particles of an outline CSV file
    /// (named `i{index}_p{k}`, k the particle's block in the file) or of a gmsh file (named by
    /// their physical name, or `i{index}_g{tag}` without one).
    fn import(&self, key: &str, index: usize, imp: raw::ImportRaw, materials: &[MaterialSpec]) -> Result<Vec<raw::Body>, CaseError> {
        let k = |field: &str| format!("{key}.{field}");
        let file = self.req(imp.file, &k("file"), "the path of an outline CSV file (.csv) or a gmsh file (.msh), relative to the case file")?;
        let path = self.base_dir.join(&file);
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
        let ext = match ext.as_str() {
            "csv" | "msh" => ext,
            _ => return Err(self.err(&k("file"), format!("value \"{file}\": unknown file type; expected a .csv outline file or a .msh gmsh file"))),
        };
        let names = self.material_list(key, imp.material, imp.materials, materials)?;
        let fractions = self.fractions(key, imp.fractions, names.len())?;
        let seed = match imp.seed {
            None => 0,
            Some(v) => self.count(&k("seed"), v, 0)? as u64,
        };
        let (scale, offset) = self.placement(key, imp.scale, imp.offset)?;
        let material_of = |count: usize| -> Vec<String> {
            crate::packing::random::mixture(seed, count, &fractions).into_iter().map(|m| names[m.min(names.len() - 1)].0.clone()).collect()
        };
        if ext == "csv" {
            let h = self.req(imp.mesh_size, &k("mesh_size"), "an element size in mm (the outlines are meshed with it)")?;
            let h = self.positive(&k("mesh_size"), h, "an element size in mm")?;
            let text = std::fs::read_to_string(&path).map_err(|e| self.err(&k("file"), format!("cannot read outline file \"{}\": {e}", path.display())))?;
            let outlines = crate::mesh::import::read_outlines_csv(&text).map_err(|e| self.err(&k("file"), format!("in \"{}\", {e}", path.display())))?;
            let mats = material_of(outlines.len());
            return Ok(outlines
                .into_iter()
                .zip(mats)
                .enumerate()
                .map(|(j, (o, m))| {
                    let v = o.vertices.iter().map(|p| [scale * p[0] + offset[0], scale * p[1] + offset[1]]).collect();
                    raw::Body::generated(format!("i{index}_p{j}"), m, h, raw::Shape::outline(v))
                })
                .collect());
        }
        if let Some(h) = imp.mesh_size {
            return Err(self.err(&k("mesh_size"), format!("value {h:?}: not allowed for a gmsh file (the elements come from the file); expected no mesh_size")));
        }
        let parts = self.msh(&k("file"), &path)?;
        let mats = material_of(parts.len());
        let mut out = Vec::with_capacity(parts.len());
        for (p, m) in parts.iter().zip(mats) {
            let (name, group) = match &p.name {
                Some(n) if valid_body_name(n) => (n.clone(), n.clone()),
                Some(_) => {
                    return Err(self.err(
                        &k("file"),
                        format!("in gmsh file \"{}\": {}: the name is not a valid body name; expected ASCII letters, digits, '_' and '-' (rename the physical group)", path.display(), p.describe()),
                    ))
                }
                None => (format!("i{index}_g{}", p.tag), p.tag.to_string()),
            };
            out.push(raw::Body::imported(name, m, raw::Shape::gmsh(file.clone(), group, scale, offset)));
        }
        Ok(out)
    }

    /// Expand a `[[grids]]` entry into raw bodies named `g{i}_p{k}` inside the die of the walls.
    fn grid(&self, key: &str, g: raw::GridRaw, walls: &[WallSpec], materials: &[MaterialSpec]) -> Result<Vec<raw::Body>, CaseError> {
        let [x0, x1, y0, y1] = self.die(key, "particle grid", walls)?;
        let names = self.material_list(key, g.material, g.materials, materials)?;
        let nx = self.count(&format!("{key}.nx"), self.req(g.nx, &format!("{key}.nx"), "particles along x (>= 1)")?, 1)?;
        let ny = self.count(&format!("{key}.ny"), self.req(g.ny, &format!("{key}.ny"), "particles along y (>= 1)")?, 1)?;
        let shape = g.shape.unwrap_or_else(|| "disc".into());
        let sides = match self.choice(&format!("{key}.shape"), &shape, &["disc", "ellipse", "polygon"])? {
            "disc" => 0,
            "ellipse" => usize::MAX,
            _ => self.count(&format!("{key}.sides"), g.sides.unwrap_or(6), 3)?,
        };
        let phi = self.req(g.solid_ratio, &format!("{key}.solid_ratio"), "the initial solid ratio in (0, 1)")?;
        let phi = self.num(&format!("{key}.solid_ratio"), phi, phi > 0.0 && phi < 1.0, "a solid ratio in (0, 1)")?;
        let h = self.positive(&format!("{key}.mesh_size"), self.req(g.mesh_size, &format!("{key}.mesh_size"), "an element size in mm")?, "an element size in mm")?;
        let arrangement = match g.arrangement.as_deref() {
            None => crate::packing::Arrangement::Square,
            Some(a) => match self.choice(&format!("{key}.arrangement"), a, &["square", "hexagonal"])? {
                "hexagonal" => {
                    if nx < 2 {
                        return Err(self.err(&format!("{key}.nx"), format!("value {nx}; a hexagonal grid needs nx >= 2 (its odd rows hold nx - 1 particles)")));
                    }
                    crate::packing::Arrangement::Hexagonal
                }
                _ => crate::packing::Arrangement::Square,
            },
        };
        let cells = crate::packing::grid_cells(nx, ny, arrangement);
        let assigned: Vec<usize> = match g.pattern {
            Some(pat) => {
                let pkey = format!("{key}.pattern");
                let pat = self.choice(&pkey, &pat, &["checkerboard", "rows", "columns"])?;
                for (field, given) in [("fractions", g.fractions.is_some()), ("seed", g.seed.is_some())] {
                    if given {
                        return Err(self.err(&format!("{key}.{field}"), "not allowed with pattern; expected either a pattern or fractions (with a seed)"));
                    }
                }
                let m = names.len();
                cells
                    .iter()
                    .map(|&(i, j)| match pat {
                        "checkerboard" => (i + j) % m,
                        "rows" => j % m,
                        _ => i % m,
                    })
                    .collect()
            }
            None => {
                let fractions = self.fractions(key, g.fractions, names.len())?;
                let seed = match g.seed {
                    None => 0,
                    Some(v) => self.count(&format!("{key}.seed"), v, 0)? as u64,
                };
                crate::packing::random::mixture(seed, cells.len(), &fractions)
            }
        };
        let material = |k: usize| names[assigned.get(k).copied().unwrap_or(0)].0.clone();
        let ix = key.trim_start_matches("grids[").trim_end_matches(']');
        let angle0 = match g.orientation.as_deref() {
            None => std::f64::consts::FRAC_PI_2,
            Some(o) => {
                let okey = format!("{key}.orientation");
                if sides == 0 || sides == usize::MAX {
                    return Err(self.err(&okey, format!("value \"{o}\": not allowed for shape \"{shape}\"; expected orientation only with shape = \"polygon\"")));
                }
                match self.choice(&okey, o, &["vertex", "flat"])? {
                    "flat" => std::f64::consts::PI / sides as f64,
                    _ => std::f64::consts::FRAC_PI_2,
                }
            }
        };
        if sides == usize::MAX {
            let places = crate::packing::arranged_grid_ellipses(nx, ny, x1 - x0, y1 - y0, phi, arrangement).map_err(|m| self.err(&format!("{key}.solid_ratio"), m))?;
            return Ok(places
                .iter()
                .enumerate()
                .map(|(k, (c, ab))| {
                    let mut shape = raw::Shape::disc([x0 + c[0], y0 + c[1]], 0.0);
                    shape.kind = Some("ellipse".into());
                    shape.radius = None;
                    shape.semi_axes = Some(raw::Pair(*ab));
                    shape.angle = Some(0.0);
                    raw::Body::generated(format!("g{ix}_p{k}"), material(k), h, shape)
                })
                .collect());
        }
        let places = crate::packing::oriented_grid(nx, ny, x1 - x0, y1 - y0, phi, sides, arrangement, angle0).map_err(|m| self.err(&format!("{key}.solid_ratio"), m))?;
        Ok(places
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let c = [x0 + p.center[0], y0 + p.center[1]];
                let shape = if sides == 0 {
                    raw::Shape::disc(c, p.radius)
                } else {
                    raw::Shape::polygon(crate::packing::regular_polygon(c, p.radius, sides, angle0))
                };
                raw::Body::generated(format!("g{ix}_p{k}"), material(k), h, shape)
            })
            .collect())
    }

    fn check_set(&self, key: &str, body: &BodySpec, set: &str) -> Result<(), CaseError> {
        let names = body.shape.edge_set_names();
        if names.iter().any(|n| n == set) {
            Ok(())
        } else {
            Err(self.err(
                key,
                format!(
                    "value \"{set}\": body \"{}\" ({}) has no edge set \"{set}\" (known: {})",
                    body.name,
                    body.shape.type_name(),
                    names.join(", ")
                ),
            ))
        }
    }

    fn amplitude(&self, key: &str, v: Option<toml::Value>) -> Result<Amplitude, CaseError> {
        const EXPECTED: &str = "\"ramp\", \"constant\" or a table [[t0, f0], [t1, f1], ...] with strictly increasing times";
        let Some(v) = v else {
            return Ok(Amplitude::Ramp);
        };
        match &v {
            toml::Value::String(s) => match s.as_str() {
                "ramp" => Ok(Amplitude::Ramp),
                "constant" => Ok(Amplitude::Constant),
                _ => Err(self.err(key, format!("value \"{s}\"; expected {EXPECTED}"))),
            },
            toml::Value::Array(items) => {
                if items.is_empty() {
                    return Err(self.err(key, format!("empty table; expected {EXPECTED}")));
                }
                let mut pts: Vec<[f64; 2]> = Vec::with_capacity(items.len());
                for (i, item) in items.iter().enumerate() {
                    let ikey = format!("{key}[{i}]");
                    let pair = match item {
                        toml::Value::Array(p) if p.len() == 2 => {
                            match (value_num(&p[0]), value_num(&p[1])) {
                                (Some(t), Some(f)) => [t, f],
                                _ => return Err(self.err(
                                    &ikey,
                                    format!(
                                        "value {}; expected a pair of numbers [time (s), factor]",
                                        describe(item)
                                    ),
                                )),
                            }
                        }
                        _ => {
                            return Err(self.err(
                                &ikey,
                                format!(
                                    "value {}; expected a pair of numbers [time (s), factor]",
                                    describe(item)
                                ),
                            ))
                        }
                    };
                    self.finite2(&ikey, pair, "finite [time (s), factor]")?;
                    if let Some(prev) = pts.last() {
                        if pair[0] <= prev[0] {
                            return Err(self.err(
                                &ikey,
                                format!(
                                    "time {:?} after {:?}; expected strictly increasing times",
                                    pair[0], prev[0]
                                ),
                            ));
                        }
                    }
                    pts.push(pair);
                }
                Ok(Amplitude::Table(pts))
            }
            other => Err(self.err(
                key,
                format!("value {}; expected {EXPECTED}", describe(other)),
            )),
        }
    }

    fn dirichlet(
        &self,
        key: &str,
        b: raw::Boundary,
        bodies: &[BodySpec],
    ) -> Result<DirichletSpec, CaseError> {
        let (body, set) = self.body_set(key, b.body, b.set, bodies)?;
        let ux =
            b.ux.map(|v| self.finite(&format!("{key}.ux"), v, "a finite displacement (mm)"))
                .transpose()?;
        let uy =
            b.uy.map(|v| self.finite(&format!("{key}.uy"), v, "a finite displacement (mm)"))
                .transpose()?;
        let radial = b
            .radial
            .map(|v| {
                self.finite(
                    &format!("{key}.radial"),
                    v,
                    "a finite radial displacement (mm)",
                )
            })
            .transpose()?;
        if ux.is_none() && uy.is_none() && radial.is_none() {
            return Err(self.err(
                key,
                "no displacement given; expected at least one of ux, uy (mm) or radial (mm)",
            ));
        }
        if radial.is_some() {
            if ux.is_some() || uy.is_some() {
                return Err(self.err(
                    &format!("{key}.radial"),
                    "given together with ux/uy; expected either radial or ux/uy in one [[boundary]] entry",
                ));
            }
            let shape = &bodies[body].shape;
            if shape.center().is_none() {
                return Err(self.err(
                    &format!("{key}.radial"),
                    format!(
                        "not available for shape type \"{}\"; expected radial only on disc, ellipse or annulus_sector bodies",
                        shape.type_name()
                    ),
                ));
            }
        }
        let amplitude = self.amplitude(&format!("{key}.amplitude"), b.amplitude)?;
        Ok(DirichletSpec {
            body,
            set,
            ux,
            uy,
            radial,
            amplitude,
        })
    }

    fn load(&self, key: &str, l: raw::Load, bodies: &[BodySpec]) -> Result<LoadSpec, CaseError> {
        let (body, set) = self.body_set(key, l.body, l.set, bodies)?;
        let tkey = format!("{key}.type");
        let kind = self.req(l.kind, &tkey, "\"traction\", \"pressure\" or \"force\"")?;
        let kind = self.choice(&tkey, &kind, &["traction", "pressure", "force"])?;
        let vkey = format!("{key}.value");
        let v = self.req(
            l.value,
            &vkey,
            if kind == "pressure" {
                "a pressure p (MPa)"
            } else {
                "a vector [x, y]"
            },
        )?;
        let vector = |what: &str| -> Result<[f64; 2], CaseError> {
            match &v {
                toml::Value::Array(a) if a.len() == 2 => match (value_num(&a[0]), value_num(&a[1]))
                {
                    (Some(x), Some(y)) => self.finite2(&vkey, [x, y], &format!("a finite {what}")),
                    _ => Err(self.err(
                        &vkey,
                        format!(
                            "value {}; expected {what} as two numbers [x, y]",
                            describe(&v)
                        ),
                    )),
                },
                _ => Err(self.err(
                    &vkey,
                    format!(
                        "value {}; expected {what} as two numbers [x, y]",
                        describe(&v)
                    ),
                )),
            }
        };
        let kind = match kind {
            "traction" => LoadKind::Traction(vector("traction [tx, ty] (MPa)")?),
            "force" => LoadKind::Force(vector("force [Fx, Fy] (N/mm)")?),
            _ => match value_num(&v) {
                Some(p) => LoadKind::Pressure(self.finite(&vkey, p, "a finite pressure (MPa)")?),
                None => {
                    return Err(self.err(
                        &vkey,
                        format!(
                            "value {}; expected a single number, the pressure p (MPa)",
                            describe(&v)
                        ),
                    ))
                }
            },
        };
        let amplitude = self.amplitude(&format!("{key}.amplitude"), l.amplitude)?;
        Ok(LoadSpec {
            body,
            set,
            kind,
            amplitude,
        })
    }

    // ---- time, solver, output -----------------------------------------------------------

    fn time(&self, t: raw::Time) -> Result<TimeSpec, CaseError> {
        let end = self.req(t.end, "time.end", "the end time > 0 (s)")?;
        let end = self.positive("time.end", end, "the end time (s)")?;
        let dt = self.req(t.dt, "time.dt", "the initial time step, 0 < dt <= end (s)")?;
        let dt = self.num(
            "time.dt",
            dt,
            dt > 0.0 && dt <= end,
            &format!("an initial time step 0 < dt <= end = {end:?} (s)"),
        )?;
        let mut s = TimeSpec::new(end, dt);
        if let Some(v) = t.dt_min {
            s.dt_min = self.num(
                "time.dt_min",
                v,
                v > 0.0 && v <= dt,
                &format!("a minimum step 0 < dt_min <= dt = {dt:?} (s)"),
            )?;
        }
        if let Some(v) = t.dt_max {
            s.dt_max = self.num(
                "time.dt_max",
                v,
                v >= dt,
                &format!("a maximum step dt_max >= dt = {dt:?} (s)"),
            )?;
        }
        if let Some(v) = t.growth {
            s.growth = self.num("time.growth", v, v >= 1.0, "a step growth factor >= 1")?;
        }
        if let Some(v) = t.cutback {
            s.cutback = self.num(
                "time.cutback",
                v,
                v > 0.0 && v < 1.0,
                "a cut-back factor in (0, 1)",
            )?;
        }
        if let Some(v) = t.easy_iterations {
            s.easy_iterations = self.count("time.easy_iterations", v, 1)?;
        }
        if let Some(v) = t.max_steps {
            s.max_steps = self.count("time.max_steps", v, 1)?;
        }
        s.integrator = self.integrator(&t)?;
        // accuracy of a dynamic analysis is set by the step, not by the Newton iterations:
        // unless asked otherwise the step does not grow
        if s.integrator.is_dynamic() && t.dt_max.is_none() {
            s.dt_max = dt;
        }
        Ok(s)
    }

    /// `[time] integrator` and its parameters.
    fn integrator(&self, t: &raw::Time) -> Result<crate::dynamics::Integrator, CaseError> {
        use crate::dynamics::Integrator;
        let kind = match &t.integrator {
            None => "static",
            Some(v) => self.choice("time.integrator", v, &["static", "newmark", "hht"])?,
        };
        let only = |key: &str, given: bool, with: &str| -> Result<(), CaseError> {
            if given && kind != with {
                return Err(self.err(
                    key,
                    format!("not allowed with integrator = \"{kind}\"; expected only with integrator = \"{with}\""),
                ));
            }
            Ok(())
        };
        only("time.hht_alpha", t.hht_alpha.is_some(), "hht")?;
        only("time.newmark_beta", t.newmark_beta.is_some(), "newmark")?;
        only("time.newmark_gamma", t.newmark_gamma.is_some(), "newmark")?;
        Ok(match kind {
            "newmark" => {
                let gamma = match t.newmark_gamma {
                    None => 0.5,
                    Some(g) => self.num(
                        "time.newmark_gamma",
                        g,
                        (0.5..=1.0).contains(&g),
                        "a Newmark gamma in [0.5, 1] (unconditional stability needs gamma >= 0.5)",
                    )?,
                };
                let beta = match t.newmark_beta {
                    None => 0.25 * (gamma + 0.5) * (gamma + 0.5),
                    Some(b) => self.num(
                        "time.newmark_beta",
                        b,
                        b >= 0.5 * gamma && b <= 1.0,
                        &format!("a Newmark beta in [gamma/2, 1] = [{:?}, 1] (unconditional stability needs 2 beta >= gamma)", 0.5 * gamma),
                    )?,
                };
                Integrator::Newmark { beta, gamma }
            }
            "hht" => {
                let alpha = match t.hht_alpha {
                    None => -0.05,
                    Some(a) => self.num(
                        "time.hht_alpha",
                        a,
                        (-1.0 / 3.0..=0.0).contains(&a),
                        "an HHT alpha in [-1/3, 0]",
                    )?,
                };
                Integrator::Hht { alpha }
            }
            _ => Integrator::Static,
        })
    }

    fn solver(&self, r: Option<raw::Solver>) -> Result<SolverSpec, CaseError> {
        let mut s = SolverSpec::default();
        let Some(r) = r else { return Ok(s) };
        if let Some(v) = &r.newton {
            s.newton = match self.choice("solver.newton", v, &["full", "modified"])? {
                "full" => NewtonKind::Full,
                _ => NewtonKind::Modified,
            };
        }
        s.max_iterations = match r.max_iterations {
            Some(v) => self.count("solver.max_iterations", v, 1)?,
            None if s.newton == NewtonKind::Modified => 60,
            None => 25,
        };
        if let Some(v) = r.residual_tol {
            s.residual_tol =
                self.positive("solver.residual_tol", v, "a relative residual tolerance")?;
        }
        if let Some(v) = r.energy_tol {
            s.energy_tol = self.positive("solver.energy_tol", v, "a relative energy tolerance")?;
        }
        if let Some(v) = r.line_search {
            s.line_search = v;
        }
        if let Some(v) = &r.linear {
            s.linear = match self.choice("solver.linear", v, &["auto", "lu", "cholesky", "pcg"])? {
                "auto" => LinearChoice::Auto,
                "lu" => LinearChoice::Fixed(LinearSolverKind::Lu),
                "cholesky" => LinearChoice::Fixed(LinearSolverKind::Cholesky),
                _ => LinearChoice::Fixed(LinearSolverKind::Pcg),
            };
        }
        if let Some(v) = &r.preconditioner {
            s.preconditioner = match self.choice("solver.preconditioner", v, &["ic0", "jacobi", "schwarz"])? {
                "ic0" => Preconditioner::Ic0,
                "schwarz" => Preconditioner::Schwarz,
                _ => Preconditioner::Jacobi,
            };
        }
        if let Some(v) = &r.ordering {
            s.ordering = match self.choice("solver.ordering", v, &["amd", "metis"])? {
                "amd" => crate::linalg::FillOrdering::Amd,
                _ => crate::linalg::FillOrdering::Metis,
            };
        }
        if let Some(v) = r.pcg_tol {
            s.pcg_tol = self.positive("solver.pcg_tol", v, "a PCG relative tolerance")?;
        }
        if let Some(v) = r.pcg_max_iterations {
            s.pcg_max_iterations = self.count("solver.pcg_max_iterations", v, 1)?;
        }
        if let Some(v) = r.threads {
            s.threads = self.count("solver.threads", v, 0)?;
        }
        if let Some(v) = r.incompressible_penalty {
            s.incompressible_penalty = self.positive(
                "solver.incompressible_penalty",
                v,
                "a penalty (in units of the shear modulus)",
            )?;
        }
        if let Some(v) = r.volume_tol {
            s.volume_tol = self.positive("solver.volume_tol", v, "a volume tolerance")?;
        }
        if let Some(v) = r.max_volume_updates {
            s.max_volume_updates = self.count("solver.max_volume_updates", v, 1)?;
        }
        if let Some(v) = r.repartition_imbalance {
            s.repartition_imbalance = self.num(
                "solver.repartition_imbalance",
                v,
                v >= 1.0,
                "a load imbalance (heaviest process's element count / mean) >= 1",
            )?;
        }
        Ok(s)
    }

    fn output(&self, r: Option<raw::Output>, bodies: &[BodySpec]) -> Result<OutputSpec, CaseError> {
        let mut out = OutputSpec::default();
        let Some(r) = r else { return Ok(out) };
        out.reactions =
            self.output_list("output.reactions", r.reactions.unwrap_or_default(), bodies)?;
        out.displacements = self.output_list(
            "output.displacements",
            r.displacements.unwrap_or_default(),
            bodies,
        )?;
        if let Some(v) = r.every {
            out.every = self.count("output.every", v, 0)?;
        }
        if let Some(v) = r.checkpoint_every {
            out.checkpoint_every = self.count("output.checkpoint_every", v, 0)?;
        }
        if let Some(v) = r.checkpoint_minutes {
            out.checkpoint_minutes = self.num("output.checkpoint_minutes", v, v >= 0.0, "a wall-clock time in minutes >= 0 (0 = no checkpoint by time)")?;
        }
        Ok(out)
    }

    fn output_list(
        &self,
        key: &str,
        items: Vec<String>,
        bodies: &[BodySpec],
    ) -> Result<Vec<(usize, String)>, CaseError> {
        let mut seen = HashSet::new();
        let mut out = Vec::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            let ikey = format!("{key}[{i}]");
            let Some((body, set)) = item.rsplit_once('.') else {
                return Err(self.err(
                    &ikey,
                    format!("value \"{item}\"; expected \"body.set\", e.g. \"block.top\""),
                ));
            };
            let bi = self.find_body(&ikey, body, bodies)?;
            self.check_set(&ikey, &bodies[bi], set)?;
            if !seen.insert(item.as_str()) {
                return Err(self.err(
                    &ikey,
                    format!("value \"{item}\" is listed twice; expected each entry once"),
                ));
            }
            out.push((bi, set.to_string()));
        }
        Ok(out)
    }
}

/// A representative element size when only `divisions` are given.
fn implied_mesh_size(shape: &ShapeSpec, d: [usize; 2]) -> f64 {
    let (a, b) = match shape {
        ShapeSpec::Rectangle { size, .. } => (size[0], size[1]),
        ShapeSpec::Cook => (48.0, 44.0),
        ShapeSpec::AnnulusSector {
            inner_radius,
            outer_radius,
            angles_deg,
            ..
        } => (
            outer_radius - inner_radius,
            outer_radius * (angles_deg[1] - angles_deg[0]).to_radians(),
        ),
        _ => (1.0, 1.0),
    };
    (a / d[0].max(1) as f64).max(b / d[1].max(1) as f64)
}

/// Read a two-column numeric table (`strain, stress`): separators `,` `;` tab or spaces,
/// `#` starts a comment, one header line before the data is allowed.
fn read_two_columns(text: &str) -> Result<Vec<[f64; 2]>, String> {
    let mut pts = Vec::new();
    let mut header_seen = false;
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line
            .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .collect();
        let nums: Option<Vec<f64>> = fields.iter().map(|f| f.parse::<f64>().ok()).collect();
        match nums {
            Some(v) if v.len() == 2 => pts.push([v[0], v[1]]),
            None if pts.is_empty() && !header_seen => header_seen = true,
            _ => {
                return Err(format!(
                    "line {}: \"{line}\"; expected two numbers per line (strain, stress in MPa)",
                    i + 1
                ))
            }
        }
    }
    if pts.is_empty() {
        return Err("no data; expected lines of two numbers (strain, stress in MPa)".to_string());
    }
    Ok(pts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplitude_values() {
        assert_eq!(Amplitude::Ramp.at(0.5, 2.0), 0.25);
        assert_eq!(Amplitude::Ramp.at(3.0, 2.0), 1.0);
        assert_eq!(Amplitude::Constant.at(0.0, 2.0), 1.0);
        let t = Amplitude::Table(vec![[0.0, 0.0], [1.0, 2.0], [2.0, 2.0]]);
        assert_eq!(t.at(-1.0, 2.0), 0.0);
        assert_eq!(t.at(0.5, 2.0), 1.0);
        assert_eq!(t.at(5.0, 2.0), 2.0);
    }

    #[test]
    fn edge_sets() {
        let p = ShapeSpec::Polygon {
            vertices: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        };
        assert_eq!(p.edge_set_names(), ["boundary", "side0", "side1", "side2"]);
        assert_eq!(
            ShapeSpec::Cook.edge_set_names(),
            ["left", "right", "bottom", "top", "boundary"]
        );
        assert_eq!(ShapeSpec::Cook.center(), None);
    }

    #[test]
    fn two_column_reader() {
        let pts =
            read_two_columns("# comment\nstrain,stress\n0, 1\n0.1;2 # x\n\n0.2\t3\n").unwrap();
        assert_eq!(pts, vec![[0.0, 1.0], [0.1, 2.0], [0.2, 3.0]]);
        assert!(read_two_columns("a,b\n1,2\nx,y\n")
            .unwrap_err()
            .contains("line 3"));
        assert!(read_two_columns("# nothing\n").is_err());
    }

    #[test]
    fn line_and_column() {
        assert_eq!(line_col("ab\ncd", 4), (2, 2));
        assert_eq!(line_col("", 10), (1, 1));
    }
}
