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
//!
//! The case file stops at the model: [`crate::model::Model::from_case`] (module `build`) turns
//! a validated case into the model and the parameter structs each part of the physics owns
//! (the element's [`Formulation`], the [`crate::loading::Loading`], the contact's
//! [`crate::contact::ContactParams`], the [`crate::stabilise::StabilisationParams`], the
//! solver's [`TimeSpec`] and [`SolverSpec`]); no module of the physics imports this one. The
//! generators (`[[grids]]`, `[[packings]]`, `[[imports]]`) are validated in module `expand` and
//! run by [`crate::packing`] and [`crate::mesh::import`]; writing a case back (`mpfem pack`) is
//! [`crate::pack`]'s.

use std::path::{Path, PathBuf};

use thiserror::Error;

mod build;
mod expand;
pub mod parts;
mod raw;
mod validate;

pub use build::mesh_body;
use validate::{toml_error, Cx, Locator};

pub use crate::contact::{ContactMethod, ContactNormal, ContactParams};
pub use crate::element::Formulation;
pub use crate::linalg::LinearChoice;
pub use crate::loading::{Amplitude, LoadKind, WallSide};
pub use crate::model::StopSpec;
pub use crate::remesh::RemeshSpec;
pub use crate::solver::{NewtonKind, SolverSpec, TimeSpec};
pub use crate::stabilise::{StabilisationKind, StabilisationParams, Stabilise};

use crate::linalg::LinearSolverKind;
use crate::material::Material;

/// The built-in default job (plane-strain upsetting of an aluminium block).
pub const DEFAULT_JOB: &str = include_str!("../../jobs/default.toml");

/// Largest accepted `divisions` entry (a guard against absurd meshes).
pub const MAX_DIVISIONS: i64 = 100_000;

/// Default density, t/mm³.
pub const DEFAULT_DENSITY: f64 = 1e-9;

/// Largest `count` of a `[[packings]]` entry: the scaling estimates' largest assembly (10⁵).
/// (The cells are built from each seed's neighbours; pushing discs apart costs about
/// count^1.5 a sweep.)
pub const MAX_PACKING_COUNT: usize = 100_000;
/// Most particles a `[[grids]]` entry may hold (nx × ny): ten times the largest assembly the
/// scaling estimates consider (10⁵); beyond, the grid's own bookkeeping would not fit a node.
pub const MAX_GRID_PARTICLES: usize = 1_000_000;
/// Most sides of a grid's polygon particles.
pub const MAX_POLYGON_SIDES: usize = 1000;

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
    /// Plane stress (`[model] plane = "stress"`) instead of plane strain.
    pub plane_stress: bool,
    /// Element technology (`[model] element`).
    pub element: crate::element::ElementKind,
    pub materials: Vec<MaterialSpec>,
    pub bodies: Vec<BodySpec>,
    pub boundary: Vec<DirichletSpec>,
    pub loads: Vec<LoadSpec>,
    pub time: TimeSpec,
    pub solver: SolverSpec,
    /// PETSc's options for `[solver] linear = "petsc"` (its command-line syntax; empty: none).
    pub petsc_options: String,
    pub output: OutputSpec,
    /// Rigid walls (empty: no walls).
    pub walls: Vec<WallSpec>,
    /// Contact settings (used when there are walls or several bodies): the `[contact]` table,
    /// and each wall's contact kind (`walls`, in the order of [`Case::walls`]).
    pub contact: ContactParams,
    /// The stabilisation springs (the springs' keys of `[contact]`).
    pub stabilisation: StabilisationParams,
    pub stop: StopSpec,
    /// Adaptive re-meshing of the particles (`[remesh]`).
    pub remesh: RemeshSpec,
    /// Directory of the case file; relative paths in the file are resolved against it.
    pub base_dir: PathBuf,
}

/// A rigid straight wall: `position` (x of a left/right wall, y of a bottom/top wall, mm, at
/// t = 0) moving towards the particles at `velocity` (mm/s, positive inward), or by `travel`
/// (mm) times an amplitude (see [`crate::loading`]). Its contact kind with the particles is
/// `contact.walls[i]` ([`Case::contact`]).
#[derive(Clone, Debug, PartialEq)]
pub struct WallSpec {
    pub side: WallSide,
    pub position: f64,
    /// Constant inward speed (mm/s); 0 when the wall moves by `travel`.
    pub velocity: f64,
    /// Inward travel (mm) and its amplitude, instead of a constant speed.
    pub travel: Option<(f64, Amplitude)>,
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
    /// A half or a quarter of a disc (`disc`, equal semi-axes) or an ellipse, for symmetry
    /// models ([`crate::mesh::shapes::ellipse_part`]).
    EllipsePart {
        center: [f64; 2],
        semi_axes: [f64; 2],
        angle_deg: f64,
        part: crate::mesh::shapes::EllipsePart,
        disc: bool,
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
            ShapeSpec::EllipsePart { disc: true, .. } => "disc",
            ShapeSpec::EllipsePart { disc: false, .. } => "ellipse",
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
            ShapeSpec::EllipsePart { part: crate::mesh::shapes::EllipsePart::Half, .. } => &["outer", "axis_x", "boundary"],
            ShapeSpec::EllipsePart { part: crate::mesh::shapes::EllipsePart::Quarter, .. } => &["outer", "axis_x", "axis_y", "boundary"],
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
            ShapeSpec::EllipsePart { center, semi_axes, angle_deg, part, .. } => {
                // the part's outline: its centre and 64 points along its arc
                let (t0, span) = match part {
                    crate::mesh::shapes::EllipsePart::Half => (0.0, std::f64::consts::PI),
                    crate::mesh::shapes::EllipsePart::Quarter => (0.0, std::f64::consts::FRAC_PI_2),
                };
                let (cs, sn) = (angle_deg.to_radians().cos(), angle_deg.to_radians().sin());
                let mut v: Vec<[f64; 2]> = (0..=64)
                    .map(|i| {
                        let t = t0 + span * i as f64 / 64.0;
                        let (x, y) = (semi_axes[0] * t.cos(), semi_axes[1] * t.sin());
                        [center[0] + cs * x - sn * y, center[1] + sn * x + cs * y]
                    })
                    .collect();
                if *part == crate::mesh::shapes::EllipsePart::Quarter {
                    v.push(*center);
                }
                Convex::Polygon(v)
            }
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
            | ShapeSpec::EllipsePart { center, .. }
            | ShapeSpec::AnnulusSector { center, .. } => Some(*center),
            _ => None,
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

/// A load on an edge set.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadSpec {
    /// Index into [`Case::bodies`].
    pub body: usize,
    pub set: String,
    pub kind: LoadKind,
    pub amplitude: Amplitude,
}

/// Extra columns of `history.csv`: `(body index, edge set name)`, and how often the field
/// results (`results.h5` / `results.xdmf`) are written.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputSpec {
    /// Reaction force columns `rx_BODY_SET`, `ry_BODY_SET`.
    pub reactions: Vec<(usize, String)>,
    /// Mean displacement columns `ux_BODY_SET`, `uy_BODY_SET`.
    pub displacements: Vec<(usize, String)>,
    /// Named points whose state goes to `probes.csv` every step.
    pub probes: Vec<ProbeSpec>,
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

/// An entry of `[output] probes` (validated; located in the mesh by `Model::from_case`).
#[derive(Clone, Debug, PartialEq)]
pub struct ProbeSpec {
    /// The prefix of its columns in `probes.csv` (letters, digits, `_` and `-`; unique).
    pub name: String,
    pub at: ProbeSpecAt,
}

/// Where a probe is.
#[derive(Clone, Debug, PartialEq)]
pub enum ProbeSpecAt {
    /// A material point at reference coordinates `point` (mm), inside body `body` when given
    /// (a point on an interface then belongs to that body), else the first body that holds it.
    Point { point: [f64; 2], body: Option<usize> },
    /// Node `node` (the body's own numbering, from 0) of body `body`.
    Node { body: usize, node: usize },
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self { reactions: Vec::new(), displacements: Vec::new(), probes: Vec::new(), every: 1, checkpoint_every: 0, checkpoint_minutes: 30.0 }
    }
}

impl Case {
    /// The linear solver to use: `[solver] linear`, with `"auto"` resolved by the symmetry of
    /// the model's tangent ([`crate::model::symmetric_tangent`], the one place that decides it).
    pub fn linear_kind(&self) -> LinearSolverKind {
        let follower = self.loads.iter().any(|l| matches!(l.kind, LoadKind::Pressure(_)));
        let contact = &self.contact;
        let has_contact = !self.walls.is_empty() || self.bodies.len() > 1;
        let materials = self.bodies.iter().filter_map(|b| self.materials.get(b.material)).map(|m| &m.material);
        let symmetric = crate::model::symmetric_tangent(materials, follower, has_contact.then_some((contact, self.bodies.len())));
        self.solver.linear.resolve(symmetric)
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
