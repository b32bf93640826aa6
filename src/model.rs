//! The discrete model built from a validated case: meshes of every body in one global node
//! numbering, materials per element, prescribed displacements and loads as lists of degrees of
//! freedom and boundary edges.

use crate::case::{Amplitude, BodySpec, Case, Formulation, LoadKind, ShapeSpec};
use crate::material::{ConstitutiveLaw, Material};
use crate::mesh::{shapes, Mesh};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ModelError {
    #[error("bodies[{body}] ({name}): cannot mesh the shape: {message}")]
    Mesh { body: usize, name: String, message: String },
    #[error("{key}: edge set \"{set}\" does not exist on body \"{body}\"")]
    MissingSet { key: String, body: String, set: String },
    #[error("body {body} cannot be re-meshed: {what} refer to its nodes")]
    RemeshConstrained { body: String, what: &'static str },
    #[error("no body {0}")]
    NoBody(usize),
}

/// One meshed body.
#[derive(Clone, Debug)]
pub struct Body {
    pub name: String,
    pub mesh: Mesh,
    pub material: usize,
    /// Global index of the body's node 0.
    pub node_offset: usize,
    /// Global index of the body's element 0.
    pub elem_offset: usize,
    /// Target element edge length of the body's mesh (mm): the case's `mesh_size`, used again
    /// when the body is re-meshed.
    pub mesh_size: f64,
    /// The particle's mean element size √(A / n_e) of the mesh it was built with (mm): the
    /// length h of its default contact penalty 10 E/h and of its stabilisation springs
    /// ζ E a / h². A property of the particle, kept when it is re-meshed (a finer new mesh
    /// must not stiffen its contacts or springs: measured 1.9 times on an asphalt octagon).
    pub contact_h: f64,
}

impl Body {
    /// √(A / n_e) of `mesh` in its own coordinates (mm).
    pub fn mean_element_size(mesh: &Mesh) -> f64 {
        (mesh.area(&mesh.nodes) / mesh.n_elements().max(1) as f64).sqrt()
    }
}

/// A prescribed displacement component: `u[dof] = value · amplitude(t)`.
#[derive(Clone, Debug, PartialEq)]
pub struct PrescribedDof {
    pub dof: usize,
    pub value: f64,
    pub amplitude: usize,
}

/// A distributed load on a list of boundary edges (global node indices, body on the left).
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeLoad {
    pub edges: Vec<[usize; 2]>,
    pub kind: LoadKind,
    pub amplitude: usize,
    /// Reference length of the edge set (mm), used by `LoadKind::Force`.
    pub length0: f64,
}

/// A named set of nodes whose reactions or mean displacements go to the history.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeGroup {
    pub label: String,
    pub nodes: Vec<usize>,
}

#[derive(Clone, Debug)]
pub struct Model {
    pub title: String,
    pub formulation: Formulation,
    /// Element technology of every element.
    pub element: crate::element::ElementKind,
    /// Rigid walls, contact settings and early-stop criteria of a compaction.
    pub walls: Vec<crate::case::WallSpec>,
    pub contact: crate::case::ContactSpec,
    pub stop: crate::case::StopSpec,
    pub remesh: crate::case::RemeshSpec,
    pub materials: Vec<Material>,
    /// Mass density of each material (t/mm³), used by the implicit dynamics.
    pub densities: Vec<f64>,
    pub bodies: Vec<Body>,
    /// Reference coordinates of all nodes (mm).
    pub x0: Vec<[f64; 2]>,
    /// All elements, global node indices, counter-clockwise.
    pub elements: Vec<[usize; 4]>,
    pub elem_material: Vec<usize>,
    pub elem_body: Vec<usize>,
    pub prescribed: Vec<PrescribedDof>,
    pub loads: Vec<EdgeLoad>,
    pub amplitudes: Vec<Amplitude>,
    pub reaction_groups: Vec<NodeGroup>,
    pub displacement_groups: Vec<NodeGroup>,
    /// End time of the run (s): amplitudes "ramp" go from 0 to 1 over [0, t_end].
    pub t_end: f64,
}

/// Mesh one body's shape at its mesh size / divisions.
pub fn mesh_body(b: &BodySpec) -> Result<Mesh, String> {
    let h = b.mesh_size;
    let div = |i: usize, len: f64| b.divisions.map_or_else(|| shapes::divisions_for(len, h), |d| d[i]);
    Ok(match &b.shape {
        ShapeSpec::Rectangle { origin, size } => {
            shapes::rectangle(*origin, size[0], size[1], div(0, size[0]), div(1, size[1]))
        }
        ShapeSpec::Cook => shapes::cook_membrane(div(0, 48.0), div(1, 44.0)),
        ShapeSpec::Disc { center, radius } => shapes::disc(*center, *radius, h),
        ShapeSpec::Ellipse { center, semi_axes, angle_deg } => shapes::ellipse(*center, *semi_axes, *angle_deg, h),
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
    pub fn from_case(case: &Case) -> Result<Self, ModelError> {
        let mut bodies = Vec::with_capacity(case.bodies.len());
        let mut x0 = Vec::new();
        let mut elements = Vec::new();
        let mut elem_material = Vec::new();
        let mut elem_body = Vec::new();
        for (ib, b) in case.bodies.iter().enumerate() {
            let mesh = mesh_body(b).map_err(|message| ModelError::Mesh { body: ib, name: b.name.clone(), message })?;
            let node_offset = x0.len();
            let elem_offset = elements.len();
            x0.extend_from_slice(&mesh.nodes);
            for e in &mesh.elements {
                elements.push(e.map(|n| n + node_offset));
                elem_material.push(b.material);
                elem_body.push(ib);
            }
            let contact_h = Body::mean_element_size(&mesh);
            bodies.push(Body { name: b.name.clone(), mesh, material: b.material, node_offset, elem_offset, mesh_size: b.mesh_size, contact_h });
        }

        let mut amplitudes: Vec<Amplitude> = Vec::new();
        let mut amp_index = |a: &Amplitude| -> usize {
            amplitudes.push(a.clone());
            amplitudes.len() - 1
        };

        let global_set = |key: &str, body: usize, set: &str| -> Result<(Vec<usize>, Vec<[usize; 2]>), ModelError> {
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

        Ok(Self {
            title: case.title.clone(),
            formulation: case.formulation,
            element: case.element,
            walls: case.walls.clone(),
            contact: case.contact.clone(),
            stop: case.stop.clone(),
            remesh: case.remesh.clone(),
            materials: case.materials.iter().map(|m| m.material.clone()).collect(),
            densities: case.materials.iter().map(|m| m.density).collect(),
            bodies,
            x0,
            elements,
            elem_material,
            elem_body,
            prescribed,
            loads,
            amplitudes,
            reaction_groups,
            displacement_groups,
            t_end: case.time.end,
        })
    }

    pub fn n_nodes(&self) -> usize {
        self.x0.len()
    }

    pub fn n_dofs(&self) -> usize {
        2 * self.x0.len()
    }

    /// Amplitude factor of amplitude `i` at time `t`.
    pub fn amplitude(&self, i: usize, t: f64) -> f64 {
        self.amplitudes[i].at(t, self.t_end)
    }

    /// True when every material has a symmetric tangent, no load is a follower pressure and
    /// all contact is frictionless with the segment normal (the smoothed one has a
    /// non-symmetric tangent, see [`crate::contact::smooth`]), so the global tangent is
    /// symmetric.
    pub fn symmetric_tangent(&self) -> bool {
        use crate::contact::kernels::ContactKind;
        let frictionless = |k: &ContactKind| matches!(k, ContactKind::Sliding);
        let contact = !self.walls.is_empty() || self.bodies.len() > 1;
        self.materials.iter().all(|m| m.symmetric_tangent())
            && self.loads.iter().all(|l| !matches!(l.kind, LoadKind::Pressure(_)))
            && (!contact || (frictionless(&self.contact.kind) && self.walls.iter().all(|w| frictionless(&w.kind))))
            && (!contact || self.contact.method != crate::case::ContactMethod::Lagrange)
            && (self.bodies.len() < 2 || self.contact.normal != crate::case::ContactNormal::Smoothed)
    }

    /// Why body `b` cannot be re-meshed (its nodes are named by prescribed displacements,
    /// loads or output groups, whose node lists would lose their meaning), or `None` when it
    /// can (also for a body index out of range: [`Model::with_body_mesh`] reports that).
    pub fn remesh_constraint(&self, b: usize) -> Option<&'static str> {
        let body = self.bodies.get(b)?;
        let (lo, hi) = (body.node_offset, body.node_offset + body.mesh.n_nodes());
        let inside = |n: usize| (lo..hi).contains(&n);
        if self.prescribed.iter().any(|p| inside(p.dof / 2)) {
            return Some("prescribed displacements");
        }
        if self.loads.iter().any(|l| l.edges.iter().flatten().any(|&n| inside(n))) {
            return Some("loads");
        }
        if self.reaction_groups.iter().chain(&self.displacement_groups).any(|g| g.nodes.iter().any(|&n| inside(n))) {
            return Some("output groups");
        }
        None
    }

    /// The model with body `b` meshed by `mesh` instead (a re-mesh: `mesh.nodes` are the new
    /// reference coordinates, normally the body's current configuration). The other bodies keep
    /// their meshes and reference coordinates; the global numbering is rebuilt, so node n of
    /// body c moves from `self.bodies[c].node_offset + n` to `new.bodies[c].node_offset + n`
    /// (and the same for elements), and prescribed dofs, loads and output groups are renumbered.
    ///
    /// # Errors
    /// [`ModelError::NoBody`] for a body index out of range, and
    /// [`ModelError::RemeshConstrained`] when prescribed displacements, loads or output groups
    /// refer to nodes of body `b` (they are defined on its old boundary edge sets).
    pub fn with_body_mesh(&self, b: usize, mesh: Mesh) -> Result<Model, ModelError> {
        let old = self.bodies.get(b).ok_or(ModelError::NoBody(b))?;
        if let Some(what) = self.remesh_constraint(b) {
            return Err(ModelError::RemeshConstrained { body: old.name.clone(), what });
        }
        let mut new = self.clone();
        new.bodies[b].mesh = mesh;
        let (mut x0, mut elements, mut elem_material, mut elem_body) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        // old global node -> new global node, for the nodes of the other bodies
        let mut renumber = vec![usize::MAX; self.x0.len()];
        for (ib, body) in new.bodies.iter_mut().enumerate() {
            let (node_offset, elem_offset) = (x0.len(), elements.len());
            if ib == b {
                x0.extend_from_slice(&body.mesh.nodes);
            } else {
                let n = body.mesh.n_nodes();
                x0.extend_from_slice(&self.x0[body.node_offset..body.node_offset + n]);
                for k in 0..n {
                    renumber[body.node_offset + k] = node_offset + k;
                }
            }
            for e in &body.mesh.elements {
                elements.push(e.map(|n| n + node_offset));
                elem_material.push(body.material);
                elem_body.push(ib);
            }
            body.node_offset = node_offset;
            body.elem_offset = elem_offset;
        }
        for p in &mut new.prescribed {
            p.dof = 2 * renumber[p.dof / 2] + p.dof % 2;
        }
        for l in &mut new.loads {
            for e in &mut l.edges {
                *e = e.map(|n| renumber[n]);
            }
        }
        for g in new.reaction_groups.iter_mut().chain(new.displacement_groups.iter_mut()) {
            for n in &mut g.nodes {
                *n = renumber[*n];
            }
        }
        new.x0 = x0;
        new.elements = elements;
        new.elem_material = elem_material;
        new.elem_body = elem_body;
        Ok(new)
    }

    /// Reference area of each body (mm²).
    pub fn body_areas(&self, coords: &[[f64; 2]]) -> Vec<f64> {
        let mut a = vec![0.0; self.bodies.len()];
        for (e, el) in self.elements.iter().enumerate() {
            a[self.elem_body[e]] += crate::mesh::polygon_area(el.iter().map(|&n| coords[n]));
        }
        a
    }
}
