//! The raw serde structs of the case file, one-to-one with the TOML text: unknown keys and
//! wrong types are rejected here; [`super::validate`] turns them into the validated types.

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
    pub travel: Option<f64>,
    pub amplitude: Option<toml::Value>,
    pub contact: Option<String>,
    pub friction: Option<f64>,
}

#[derive(Deserialize, Default)]
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
    pub dhat: Option<f64>,
    pub integration: Option<String>,
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
    pub wall_pressure: Option<f64>,
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
            part: None,
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
    pub kinematics: Option<String>,
    pub plane: Option<String>,
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
    pub part: Option<String>,
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
    pub petsc_options: Option<String>,
    pub threads: Option<i64>,
    pub incompressible_penalty: Option<f64>,
    pub volume_tol: Option<f64>,
    pub max_volume_updates: Option<i64>,
    pub repartition_imbalance: Option<f64>,
}

/// An entry of `[output] probes`: a named point (reference coordinates, optionally within one
/// body) or a node of a body.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Probe {
    pub name: Option<String>,
    pub point: Option<P2>,
    pub body: Option<String>,
    pub node: Option<i64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    pub reactions: Option<Vec<String>>,
    pub displacements: Option<Vec<String>>,
    pub probes: Option<Vec<Probe>>,
    pub every: Option<i64>,
    pub checkpoint_every: Option<i64>,
    pub checkpoint_minutes: Option<f64>,
}
