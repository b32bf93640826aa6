//! The case file builds the model: every body meshed in one global numbering, the loading
//! (walls, prescribed displacements, loads, amplitudes) and the parameter structs of each part
//! of the physics. This is where the case file stops.

use super::{BodySpec, Case, ProbeSpecAt, ShapeSpec};
use crate::loading::{Amplitude, EdgeLoad, Loading, PrescribedDof, WallMotion, WallTravel};
use crate::mesh::{shapes, Mesh};
use crate::model::{Body, Model, ModelError, NodeGroup, Probe, ProbeAt};

/// Memory a mesh element surely takes at least in a run (bytes): its nodes, Gauss-point states
/// and its share of the sparse tangent and its factor. A compaction with contact takes about
/// 30 kB an element (the 1,024-polygon case: 1.23 GB for 42,195 elements), a lone elastic body
/// a few; the guard below refuses only what cannot fit even at this floor.
pub const MIN_BYTES_PER_ELEMENT: f64 = 2e3;

/// The machine's memory (bytes; `None` when it cannot be read).
fn machine_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kb: f64 = text.lines().find(|l| l.starts_with("MemTotal:"))?.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

/// About how many elements `b` meshes into (an upper estimate for the curved shapes, whose
/// O-grids and polygon meshes take up to twice area / h²), before any allocation.
pub fn estimated_elements(b: &BodySpec) -> f64 {
    let h = b.mesh_size;
    let div = |i: usize, len: f64| b.divisions.map_or_else(|| shapes::divisions_for(len.abs(), h) as f64, |d| d[i] as f64);
    let area = |a: f64| 2.0 * (a.abs() / (h * h)).max(1.0);
    match &b.shape {
        ShapeSpec::Rectangle { size, .. } => div(0, size[0]) * div(1, size[1]),
        ShapeSpec::Cook => div(0, 48.0) * div(1, 44.0),
        ShapeSpec::Disc { radius, .. } => area(std::f64::consts::PI * radius * radius),
        ShapeSpec::Ellipse { semi_axes, .. } | ShapeSpec::EllipsePart { semi_axes, .. } => area(std::f64::consts::PI * semi_axes[0] * semi_axes[1]),
        ShapeSpec::Polygon { vertices } | ShapeSpec::Outline { vertices } => area(crate::mesh::polygon_area(vertices.iter().copied())),
        ShapeSpec::Gmsh { mesh, .. } => mesh.elements.len() as f64,
        ShapeSpec::AnnulusSector { inner_radius, outer_radius, angles_deg, .. } => {
            let arc = 0.5 * (inner_radius + outer_radius) * (angles_deg[1] - angles_deg[0]).abs().to_radians();
            div(0, outer_radius - inner_radius) * div(1, arc)
        }
    }
}

/// Mesh one body's shape at its mesh size / divisions. A shape whose mesh could not fit in the
/// machine's memory (at [`MIN_BYTES_PER_ELEMENT`]), or whose element count is not a number, is
/// refused before anything is allocated.
pub fn mesh_body(b: &BodySpec) -> Result<Mesh, String> {
    let n = estimated_elements(b);
    let memory = machine_memory().unwrap_or(f64::INFINITY);
    if !n.is_finite() || n > 1e12 || n * MIN_BYTES_PER_ELEMENT > memory {
        return Err(format!(
            "mesh_size = {} (divisions {:?}) makes about {n:.3e} elements, which need at least {:.3e} bytes against this machine's {:.3e}; expected a coarser mesh_size or a smaller shape",
            b.mesh_size,
            b.divisions,
            n * MIN_BYTES_PER_ELEMENT,
            memory
        ));
    }
    let h = b.mesh_size;
    let div = |i: usize, len: f64| b.divisions.map_or_else(|| shapes::divisions_for(len, h), |d| d[i]);
    Ok(match &b.shape {
        ShapeSpec::Rectangle { origin, size } => {
            shapes::rectangle(*origin, size[0], size[1], div(0, size[0]), div(1, size[1]))
        }
        ShapeSpec::Cook => shapes::cook_membrane(div(0, 48.0), div(1, 44.0)),
        ShapeSpec::Disc { center, radius } => shapes::disc(*center, *radius, h),
        ShapeSpec::Ellipse { center, semi_axes, angle_deg } => shapes::ellipse(*center, *semi_axes, *angle_deg, h),
        ShapeSpec::EllipsePart { center, semi_axes, angle_deg, part, .. } => shapes::ellipse_part(*center, *semi_axes, *angle_deg, *part, h),
        ShapeSpec::Polygon { vertices } => shapes::convex_polygon(vertices, h).map_err(|e| e.to_string())?,
        ShapeSpec::Outline { vertices } => crate::mesh::polygon::simple_polygon(vertices, h).map_err(|e| e.to_string())?,
        ShapeSpec::Gmsh { mesh, .. } => (**mesh).clone(),
        ShapeSpec::AnnulusSector { center, inner_radius, outer_radius, angles_deg } => {
            let arc = 0.5 * (inner_radius + outer_radius) * (angles_deg[1] - angles_deg[0]).abs().to_radians();
            shapes::annulus_sector(
                *center,
                *inner_radius,
                *outer_radius,
                angles_deg[0],
                angles_deg[1],
                div(0, outer_radius - inner_radius),
                div(1, arc),
            )
        }
    })
}

impl Model {
    /// The model of a validated case.
    ///
    /// # Errors
    /// A body whose shape cannot be meshed, an edge set that does not exist.
    pub fn from_case(case: &Case) -> Result<Self, ModelError> {
        Self::from_case_holding(case, None, &[])
    }

    /// The model of a validated case in which only the bodies `held` marks (one flag a body;
    /// `None`: every body) are meshed: the others keep their names, materials and mesh sizes
    /// but no nodes or elements, their prescribed displacements, loads and output groups are
    /// empty, and the probes in them are left out. What a process of a distributed run builds
    /// of the case ([`crate::case::parts`]), so that none holds the whole mesh. The amplitudes,
    /// walls and parameters are the whole model's, and the numbering is that of the held
    /// bodies one after the other. `pins` places point probes in a body: (probe, body), the
    /// body the whole model would find the point in (the first body holding it).
    ///
    /// # Errors
    /// As [`Model::from_case`], for the held bodies (a point probe that no held body holds is
    /// left out, not an error, when not every body is held).
    pub fn from_case_holding(case: &Case, held: Option<&[bool]>, pins: &[(usize, usize)]) -> Result<Self, ModelError> {
        let present = |b: usize| held.is_none_or(|h| h.get(b).copied().unwrap_or(false));
        let mut bodies = Vec::with_capacity(case.bodies.len());
        let mut x0 = Vec::new();
        let mut elements = Vec::new();
        let mut elem_material = Vec::new();
        let mut elem_body = Vec::new();
        for (ib, b) in case.bodies.iter().enumerate() {
            let mesh = match present(ib) {
                true => mesh_body(b).map_err(|message| ModelError::Mesh { body: ib, name: b.name.clone(), message })?,
                false => Mesh::default(),
            };
            let node_offset = x0.len();
            let elem_offset = elements.len();
            x0.extend_from_slice(&mesh.nodes);
            for e in &mesh.elements {
                elements.push(e.map(|n| n + node_offset));
                elem_material.push(b.material);
                elem_body.push(ib);
            }
            let contact_h = if present(ib) { Body::mean_element_size(&mesh) } else { f64::INFINITY };
            bodies.push(Body { name: b.name.clone(), mesh, material: b.material, node_offset, elem_offset, mesh_size: b.mesh_size, contact_h });
        }

        let mut amplitudes: Vec<Amplitude> = Vec::new();
        let mut amp_index = |a: &Amplitude| -> usize {
            amplitudes.push(a.clone());
            amplitudes.len() - 1
        };

        let global_set = |key: &str, body: usize, set: &str| -> Result<(Vec<usize>, Vec<[usize; 2]>), ModelError> {
            if !present(body) {
                return Ok((Vec::new(), Vec::new()));
            }
            let b = &bodies[body];
            let edges = b.mesh.edge_sets.get(set).ok_or_else(|| ModelError::MissingSet {
                key: key.to_string(),
                body: b.name.clone(),
                set: set.to_string(),
            })?;
            let nodes = b.mesh.node_set(set).unwrap_or_default().into_iter().map(|n| n + b.node_offset).collect();
            let edges = edges.iter().map(|e| e.map(|n| n + b.node_offset)).collect();
            Ok((nodes, edges))
        };

        let mut prescribed: Vec<PrescribedDof> = Vec::new();
        for (i, d) in case.boundary.iter().enumerate() {
            let key = format!("boundary[{i}].set");
            let (nodes, _) = global_set(&key, d.body, &d.set)?;
            let amp = amp_index(&d.amplitude);
            let center = case.bodies[d.body].shape.center().unwrap_or([0.0, 0.0]);
            for &n in &nodes {
                let mut set_dof = |dof: usize, value: f64| {
                    if let Some(p) = prescribed.iter_mut().find(|p| p.dof == dof) {
                        p.value = value;
                        p.amplitude = amp;
                    } else {
                        prescribed.push(PrescribedDof { dof, value, amplitude: amp });
                    }
                };
                if let Some(r) = d.radial {
                    let dx = x0[n][0] - center[0];
                    let dy = x0[n][1] - center[1];
                    let len = (dx * dx + dy * dy).sqrt().max(f64::MIN_POSITIVE);
                    set_dof(2 * n, r * dx / len);
                    set_dof(2 * n + 1, r * dy / len);
                }
                if let Some(ux) = d.ux {
                    set_dof(2 * n, ux);
                }
                if let Some(uy) = d.uy {
                    set_dof(2 * n + 1, uy);
                }
            }
        }
        prescribed.sort_by_key(|p| p.dof);

        let mut loads = Vec::new();
        for (i, l) in case.loads.iter().enumerate() {
            let key = format!("loads[{i}].set");
            let (_, edges) = global_set(&key, l.body, &l.set)?;
            let length0 = edges
                .iter()
                .map(|e| {
                    let (a, b) = (x0[e[0]], x0[e[1]]);
                    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
                })
                .sum();
            loads.push(EdgeLoad { edges, kind: l.kind.clone(), amplitude: amp_index(&l.amplitude), length0 });
        }

        let group = |(body, set): &(usize, String), prefix: &str| -> Result<NodeGroup, ModelError> {
            let (nodes, _) = global_set(&format!("output.{prefix}"), *body, set)?;
            Ok(NodeGroup { label: format!("{}_{}", bodies[*body].name, set), nodes })
        };
        let reaction_groups = case.output.reactions.iter().map(|g| group(g, "reactions")).collect::<Result<_, _>>()?;
        let displacement_groups =
            case.output.displacements.iter().map(|g| group(g, "displacements")).collect::<Result<_, _>>()?;

        // the probes, located in the reference meshes
        let mut probes = Vec::with_capacity(case.output.probes.len());
        for (i, p) in case.output.probes.iter().enumerate() {
            let at = match p.at {
                ProbeSpecAt::Point { point, body } => {
                    let body = pins.iter().find(|&&(k, _)| k == i).map(|&(_, b)| b).or(body);
                    let found = match body {
                        Some(b) if !present(b) => continue,
                        _ => crate::model::locate(&x0, &elements, &elem_body, point, body),
                    };
                    if found.is_none() && held.is_some() {
                        continue;
                    }
                    let (element, xi) = found.ok_or_else(|| ModelError::Probe {
                        key: format!("output.probes[{i}].point"),
                        message: format!(
                            "value [{}, {}]; expected a point inside {} in the reference configuration",
                            point[0],
                            point[1],
                            body.map_or("a particle".to_string(), |b| format!("body \"{}\"", bodies[b].name))
                        ),
                    })?;
                    ProbeAt::Point { element, xi }
                }
                ProbeSpecAt::Node { body, node } => {
                    if !present(body) {
                        continue;
                    }
                    let n = bodies[body].mesh.n_nodes();
                    if node >= n {
                        return Err(ModelError::Probe { key: format!("output.probes[{i}].node"), message: format!("value {node}; expected a node of body \"{}\", 0 to {}", bodies[body].name, n - 1) });
                    }
                    let global = bodies[body].node_offset + node;
                    ProbeAt::Node { node: global, corners: crate::model::node_corners(&elements, global) }
                }
            };
            probes.push(Probe { name: p.name.clone(), at });
        }

        let walls = case
            .walls
            .iter()
            .map(|w| WallMotion {
                side: w.side,
                position: w.position,
                travel: match &w.travel {
                    None => WallTravel::Velocity(w.velocity),
                    Some((travel, a)) => WallTravel::Amplitude { travel: *travel, amplitude: amp_index(a) },
                },
            })
            .collect();
        let loading = Loading { walls, prescribed, loads, amplitudes, t_end: case.time.end };
        Ok(Self {
            title: case.title.clone(),
            formulation: case.formulation,
            plane_stress: case.plane_stress,
            element: case.element,
            loading,
            contact: case.contact.clone(),
            stabilisation: case.stabilisation.clone(),
            stop: case.stop.clone(),
            remesh: case.remesh.clone(),
            materials: case.materials.iter().map(|m| m.material.clone()).collect(),
            densities: case.materials.iter().map(|m| m.density).collect(),
            bodies,
            x0,
            elements,
            elem_material,
            elem_body,
            reaction_groups,
            displacement_groups,
            whole: None,
            probes,
        })
    }
}
