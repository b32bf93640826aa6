//! The case file written back: a validated body as its `[[bodies]]` table (what `mpfem pack`
//! writes for the bodies its grids, packings and imports generate).

use super::{BodySpec, MaterialSpec, ShapeSpec};

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
