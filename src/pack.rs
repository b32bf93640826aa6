//! `mpfem pack`: a case's particle grids, random packings and imported particles expanded into
//! the bodies they generate, written as a case file of their own (`packed.toml`) with a
//! preview picture (`packing.png`).

use crate::case::{self, BodySpec, Case, MaterialSpec, ShapeSpec};
use crate::plot::PlotError;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The packed case could not be written.
#[derive(Debug, Error)]
pub enum PackError {
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot parse {}", path.display())]
    Parse {
        path: PathBuf,
        #[source]
        source: toml::de::Error,
    },
    #[error("cannot resolve {}", path.display())]
    Resolve {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write the packed case as TOML")]
    Toml(#[source] toml::ser::Error),
    #[error("cannot create {}", path.display())]
    CreateDir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// What [`write_packing`] wrote.
#[derive(Debug)]
pub struct PackReport {
    /// Bodies of the case (the particles, grids, packings and imports expanded).
    pub particles: usize,
    /// Total particle area (mm²).
    pub area: f64,
    /// Particle area over the die's area, when the case has all four walls.
    pub solid_ratio: Option<f64>,
    /// The packed case file.
    pub packed: PathBuf,
    /// The preview picture, or why it was not drawn (the packed case is written either way).
    pub png: PathBuf,
    pub preview: Result<(), PlotError>,
}

/// Write `out/packed.toml` — the case file at `case_path` (`c` is it, loaded) with every
/// `[[grids]]`, `[[packings]]` and `[[imports]]` entry replaced by the `[[bodies]]` it
/// generates, hardening tables by absolute path — and the preview `out/packing.png`.
///
/// # Errors
/// [`PackError`] when the case file cannot be read again or the packed case not written.
pub fn write_packing(case_path: &Path, c: &Case, out: &Path) -> Result<PackReport, PackError> {
    let text = std::fs::read_to_string(case_path).map_err(|source| PackError::Read { path: case_path.to_path_buf(), source })?;
    let mut table: toml::Table = text.parse().map_err(|source| PackError::Parse { path: case_path.to_path_buf(), source })?;
    table.remove("grids");
    table.remove("packings");
    table.remove("imports");
    // the written case lives elsewhere: hardening tables given by a relative path are pointed
    // at the original file
    let base = case_path.parent().unwrap_or(Path::new("."));
    if let Some(toml::Value::Array(materials)) = table.get_mut("materials") {
        for m in materials {
            if let Some(f) = m.get_mut("hardening").and_then(|h| h.get_mut("file")) {
                if let Some(rel) = f.as_str().map(Path::new).filter(|p| p.is_relative()) {
                    let abs = std::path::absolute(base.join(rel)).map_err(|source| PackError::Resolve { path: rel.to_path_buf(), source })?;
                    *f = toml::Value::String(abs.display().to_string());
                }
            }
        }
    }
    let bodies: Vec<toml::Value> = c.bodies.iter().map(|b| toml::Value::Table(body_table(b, &c.materials))).collect();
    table.insert("bodies".into(), toml::Value::Array(bodies));
    let body = toml::to_string(&table).map_err(PackError::Toml)?;
    std::fs::create_dir_all(out).map_err(|source| PackError::CreateDir { path: out.to_path_buf(), source })?;
    let packed = out.join("packed.toml");
    let header = format!(
        "# Written by `mpfem pack` from {}: the case with its [[grids]], [[packings]] and [[imports]]\n# replaced by the [[bodies]] they generate (hardening table and gmsh files by absolute path).\n\n",
        case_path.display()
    );
    std::fs::write(&packed, header + &body).map_err(|source| PackError::Write { path: packed.clone(), source })?;

    let die = case::die_of(&c.walls);
    let area: f64 = c.bodies.iter().filter_map(|b| b.shape.particle()).map(|s| s.area()).sum();
    let solid_ratio = die.map(|d| area / ((d[1] - d[0]) * (d[3] - d[2])));
    let particles: Vec<crate::plot::PreviewParticle> = c
        .bodies
        .iter()
        .filter_map(|b| b.shape.particle().map(|s| crate::plot::PreviewParticle { outline: s.outline(96), material: b.material }))
        .collect();
    let names: Vec<String> = c.materials.iter().map(|m| m.name.clone()).collect();
    let mut title = vec![if c.title.is_empty() { case_path.display().to_string() } else { c.title.clone() }];
    title.push(match solid_ratio {
        Some(r) => format!("{} particles, solid ratio {r:.4}", c.bodies.len()),
        None => format!("{} particles", c.bodies.len()),
    });
    let png = out.join("packing.png");
    let preview = crate::plot::packing_png(&particles, &names, die, &title, &png);
    Ok(PackReport { particles: c.bodies.len(), area, solid_ratio, packed, png, preview })
}

/// A validated body as a `[[bodies]]` table of the case file (material by name), such that
/// parsing it gives this body back.
pub fn body_table(body: &BodySpec, materials: &[MaterialSpec]) -> toml::Table {
    let mut t = toml::Table::new();
    t.insert("name".into(), body.name.clone().into());
    let material = materials.get(body.material).map_or_else(String::new, |m| m.name.clone());
    t.insert("material".into(), material.into());
    // a gmsh body's element size comes from its mesh (mesh_size is not allowed there)
    if !matches!(body.shape, ShapeSpec::Gmsh { .. }) {
        t.insert("mesh_size".into(), body.mesh_size.into());
    }
    if let Some([a, b]) = body.divisions {
        t.insert("divisions".into(), toml::Value::Array(vec![(a as i64).into(), (b as i64).into()]));
    }
    t.insert("shape".into(), toml::Value::Table(shape_table(&body.shape)));
    t
}

/// The `shape = { type = ..., ... }` table of the case file.
pub fn shape_table(shape: &ShapeSpec) -> toml::Table {
    let pair = |p: [f64; 2]| toml::Value::Array(vec![p[0].into(), p[1].into()]);
    let mut t = toml::Table::new();
    t.insert("type".into(), shape.type_name().into());
    match shape {
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
        ShapeSpec::EllipsePart { center, semi_axes, angle_deg, part, disc } => {
            t.insert("center".into(), pair(*center));
            if *disc {
                t.insert("radius".into(), semi_axes[0].into());
            } else {
                t.insert("semi_axes".into(), pair(*semi_axes));
            }
            t.insert("angle".into(), (*angle_deg).into());
            t.insert("part".into(), match part {
                crate::mesh::shapes::EllipsePart::Half => "half",
                crate::mesh::shapes::EllipsePart::Quarter => "quarter",
            }.into());
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
