//! The discrete model: meshes of every body in one global node numbering, materials per
//! element, the prescribed motion and loads ([`Loading`]), and the parameters of each part
//! of the physics (contact, stabilisation, re-meshing, the stop criteria). The case file
//! builds it ([`crate::case`], `Model::from_case`); nothing here knows the case file.

use crate::contact::{ContactBody, ContactProblem};
use crate::contact::{ContactKind, Wall};
use crate::contact::{ContactMethod, ContactNormal, ContactParams};
use crate::element::{ElementKind, Formulation};
use crate::loading::{LoadKind, Loading};
use crate::material::{ConstitutiveLaw, Material};
use crate::mesh::Mesh;
use crate::remesh::RemeshSpec;
use crate::stabilise::StabilisationParams;
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
    #[error("{key}: {message}")]
    Probe { key: String, message: String },
}

/// One meshed body.
#[derive(Clone, Debug, PartialEq)]
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

/// A point whose state goes to `probes.csv` every step (`[output] probes`).
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    pub name: String,
    pub at: ProbeAt,
}

/// Where a probe is, in the global numbering.
#[derive(Clone, Debug, PartialEq)]
pub enum ProbeAt {
    /// A material point: the element that holds it in the reference configuration and its
    /// local coordinates (ξ, η) there.
    Point { element: usize, xi: [f64; 2] },
    /// A node, with every element at it and the node's corner (0–3) in each.
    Node { node: usize, corners: Vec<(usize, usize)> },
}

/// A named set of nodes whose reactions or mean displacements go to the history.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeGroup {
    pub label: String,
    pub nodes: Vec<usize>,
}

/// The `[stop]` table: end the run early.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct StopSpec {
    /// Stop once the solid ratio reaches this value.
    pub solid_ratio: Option<f64>,
    /// Stop once the mean pressure of the pressing (moving) walls reaches this value (MPa).
    pub wall_pressure: Option<f64>,
    /// End the run normally (status "jammed") when the walls cannot advance any more (a step
    /// fails below dt_min), instead of failing.
    pub jam: bool,
    /// A failed step counts as a jam only at or above this solid ratio (default 0.9).
    pub jam_solid_ratio: f64,
}

#[derive(Clone, Debug)]
pub struct Model {
    pub title: String,
    pub formulation: Formulation,
    /// Plane stress instead of plane strain (`[model] plane = "stress"`): every law through
    /// [`crate::material::plane_stress::PlaneStress`], no mean-dilatation pressure.
    pub plane_stress: bool,
    /// Element technology of every element.
    pub element: ElementKind,
    /// Walls, prescribed displacements, loads and their amplitudes.
    pub loading: Loading,
    /// Contact between the bodies and with the walls.
    pub contact: ContactParams,
    /// The stabilisation springs of a contact problem.
    pub stabilisation: StabilisationParams,
    /// Early-stop criteria of a compaction.
    pub stop: StopSpec,
    pub remesh: RemeshSpec,
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
    pub reaction_groups: Vec<NodeGroup>,
    pub displacement_groups: Vec<NodeGroup>,
    /// The points of `probes.csv`.
    pub probes: Vec<Probe>,
    /// When this model is one process's part of a distributed model ([`Model::part`]): the
    /// facts of the whole model its physics depends on. `None` for a whole model.
    pub whole: Option<WholeModel>,
}

/// Where the nodes and elements of a part of a model ([`Model::part`]) are in the whole model.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PartMap {
    /// The whole model's node for each node of the part.
    pub node: Vec<usize>,
    /// The whole model's element for each element of the part.
    pub element: Vec<usize>,
}

/// One body as a process's part takes it for a ghost ([`Model::with_ghosts`]): the body (its
/// offsets are set where it is put), its reference coordinates and its prescribed dofs,
/// numbered from its node 0 (`2 n + c`). What its owner sends a process that needs it as a
/// new ghost.
#[derive(Clone, Debug, PartialEq)]
pub struct GhostBody {
    pub body: Body,
    pub x0: Vec<[f64; 2]>,
    pub prescribed: Vec<crate::loading::PrescribedDof>,
}

/// A node or an element of a body: the body and its index in the body's own numbering.
pub type BodyLocal = (usize, usize);

/// A whole model without its meshes ([`Model::frame`]): its parameters (walls, amplitudes,
/// materials, contact), and its loads, output groups and probes with their nodes and
/// elements in their bodies' own numbering. What rank 0 of a run on owned + ghost parts keeps
/// for the output: at an output step the bodies' current meshes are gathered from their
/// owners and put into it ([`ModelFrame::assemble`]), and dropped after the writing. The
/// bodies that loads, groups and probes name keep their meshes (they are never re-meshed,
/// [`Model::remesh_constraint`]), so their own numbers stay true whatever else is re-meshed.
#[derive(Clone, Debug)]
pub struct ModelFrame {
    /// Everything but the meshes and what refers to nodes.
    params: Model,
    n_bodies: usize,
    /// Each load without its edges, and its edges' nodes.
    loads: Vec<(crate::loading::EdgeLoad, Vec<[BodyLocal; 2]>)>,
    reaction_groups: Vec<(String, Vec<BodyLocal>)>,
    displacement_groups: Vec<(String, Vec<BodyLocal>)>,
    probes: Vec<(String, LocalProbe)>,
}

/// A probe's place in its body's own numbering ([`ProbeAt`]).
#[derive(Clone, Debug)]
enum LocalProbe {
    Point { element: BodyLocal, xi: [f64; 2] },
    Node { node: BodyLocal, corners: Vec<(BodyLocal, usize)> },
}

impl ModelFrame {
    /// The bodies of the frame.
    pub fn n_bodies(&self) -> usize {
        self.n_bodies
    }

    /// The whole model with `bodies` (every body in order, each with its current mesh, its
    /// reference coordinates and its prescribed dofs, as [`Model::ghost_body`] gives them),
    /// numbered one after the other, the loads, groups and probes put on their nodes.
    ///
    /// # Errors
    /// Another number of bodies than the frame's ([`ModelError::NoBody`] naming the count),
    /// or a body named by a load, group or probe without the node or element it names.
    pub fn assemble(&self, bodies: Vec<GhostBody>) -> Result<Model, ModelError> {
        if bodies.len() != self.n_bodies {
            return Err(ModelError::NoBody(bodies.len()));
        }
        let mut m = self.params.with_ghosts(0, bodies)?;
        let missing = |b: usize| ModelError::Probe { key: format!("bodies[{b}]"), message: "a load, output group or probe names a node or element its mesh no longer has".into() };
        let node = |(b, i): BodyLocal| -> Result<usize, ModelError> {
            let body = &m.bodies[b];
            if i < body.mesh.n_nodes() {
                Ok(body.node_offset + i)
            } else {
                Err(missing(b))
            }
        };
        let element = |(b, j): BodyLocal| -> Result<usize, ModelError> {
            let body = &m.bodies[b];
            if j < body.mesh.n_elements() {
                Ok(body.elem_offset + j)
            } else {
                Err(missing(b))
            }
        };
        let loads = self
            .loads
            .iter()
            .map(|(l, edges)| Ok(crate::loading::EdgeLoad { edges: edges.iter().map(|&[a, b]| Ok([node(a)?, node(b)?])).collect::<Result<_, ModelError>>()?, ..l.clone() }))
            .collect::<Result<Vec<_>, ModelError>>()?;
        let groups = |gs: &[(String, Vec<BodyLocal>)]| gs.iter().map(|(label, nodes)| Ok(NodeGroup { label: label.clone(), nodes: nodes.iter().map(|&n| node(n)).collect::<Result<_, ModelError>>()? })).collect::<Result<Vec<_>, ModelError>>();
        let (reaction_groups, displacement_groups) = (groups(&self.reaction_groups)?, groups(&self.displacement_groups)?);
        let probes = self
            .probes
            .iter()
            .map(|(name, at)| {
                let at = match at {
                    LocalProbe::Point { element: e, xi } => ProbeAt::Point { element: element(*e)?, xi: *xi },
                    LocalProbe::Node { node: n, corners } => ProbeAt::Node { node: node(*n)?, corners: corners.iter().map(|&(e, a)| Ok((element(e)?, a))).collect::<Result<_, ModelError>>()? },
                };
                Ok(Probe { name: name.clone(), at })
            })
            .collect::<Result<Vec<_>, ModelError>>()?;
        m.loading.loads = loads;
        m.reaction_groups = reaction_groups;
        m.displacement_groups = displacement_groups;
        m.probes = probes;
        Ok(m)
    }
}

/// What a part of a model ([`Model::part`]) keeps of the whole one: the figures that set
/// parameters of the physics for every body alike (the barrier's d̂ and κ, the ties'
/// stiffness), which its own bodies alone would give differently on each process.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WholeModel {
    /// Bodies, nodes and elements of the whole model.
    pub n_bodies: usize,
    pub n_nodes: usize,
    pub n_elements: usize,
    /// Smallest contact length h of its bodies (mm, [`Body::contact_h`]).
    pub h_min: f64,
    /// Smallest Young's modulus of its bodies (MPa).
    pub e_min: f64,
    /// Largest coordinate magnitude of its reference configuration (mm).
    pub extent: f64,
}

/// Whether the global tangent is symmetric: every material's consistent tangent is, no load
/// is a follower pressure, and, when bodies can touch (`contact`: the contact parameters and
/// the number of bodies), the contact is the barrier (its barrier, lagged friction and ties
/// are potentials: their Hessians are symmetric, checked against finite differences in
/// `tests/contact_conformance.rs` and [`crate::contact::barrier_problem`]), or is frictionless
/// everywhere, not enforced by Lagrange multipliers and uses the segment normal between
/// particles (the smoothed normal's tangent is not symmetric, see [`crate::contact::smooth`]).
/// The one place that decides it, and with it Cholesky against LU
/// ([`crate::linalg::LinearChoice::resolve`]).
///
/// The J2 and creep particles' tangents are symmetric too (their updates are variational, see
/// [`crate::material::j2`]), but they count as such only with the barrier. Without it they keep
/// LU, as measured on the penalty method's frictionless 2 × 2 J2 jobs
/// (`tests/compaction_jobs.rs`): their contact tangent is indefinite, so the symmetric solver
/// falls back to an LDLᵀ without pivoting, and the columns of discs, whose rotations are held
/// only by the weak springs, then lost their mirror symmetry to 7e-4 of the largest
/// displacement (opposite walls 1.4e-5 apart), against 1e-7 with LU's pivoting. With the
/// barrier the same J2 particles took 2.4 times less time per Newton iteration than with LU
/// (robustness cases 01 and 11, docs/robustness.md).
pub fn symmetric_tangent<'a>(materials: impl IntoIterator<Item = &'a Material>, follower_loads: bool, contact: Option<(&ContactParams, usize)>) -> bool {
    let frictionless = |k: &ContactKind| matches!(k, ContactKind::Sliding);
    let barrier = contact.is_some_and(|(c, _)| c.method == ContactMethod::Barrier);
    let contact_ok = contact.is_none_or(|(c, n_bodies)| {
        barrier || (frictionless(&c.kind) && c.walls.iter().all(frictionless) && c.method != ContactMethod::Lagrange && (n_bodies < 2 || c.normal != ContactNormal::Smoothed))
    });
    let material_ok = |m: &Material| m.symmetric_tangent() && (barrier || matches!(m, Material::Elastic(_)));
    materials.into_iter().all(material_ok) && !follower_loads && contact_ok
}

impl Model {
    pub fn n_nodes(&self) -> usize {
        self.x0.len()
    }

    pub fn n_dofs(&self) -> usize {
        2 * self.x0.len()
    }

    /// The whole model's facts ([`WholeModel`]): this model's own for a whole model, those of
    /// the model it is a part of otherwise.
    pub fn whole_facts(&self) -> WholeModel {
        self.whole.unwrap_or_else(|| WholeModel {
            n_bodies: self.bodies.len(),
            n_nodes: self.x0.len(),
            n_elements: self.elements.len(),
            h_min: self.bodies.iter().map(|b| b.contact_h).fold(f64::INFINITY, f64::min),
            e_min: self.bodies.iter().map(|b| self.materials[b.material].youngs_modulus()).fold(f64::INFINITY, f64::min),
            extent: self.x0.iter().map(|p| p[0].abs().max(p[1].abs())).fold(0.0, f64::max),
        })
    }

    /// One process's part of this model in a distributed run: the bodies `bodies` (indices
    /// into `self.bodies`, each once), in that order, of which the first `n_owned` are the
    /// process's own and the others its ghosts (other processes' bodies near its own, whose
    /// boundaries its contacts see). Returns the part and which node and element of `self`
    /// each of its nodes and elements is.
    ///
    /// The part has the walls, amplitudes, materials and parameters of `self`, its facts
    /// ([`Model::whole`], so that d̂, κ and the ties' stiffness are those of the whole model),
    /// the prescribed dofs of all its nodes (a ghost's dof is prescribed where its owner's is),
    /// and the loads, output groups and probes of its own bodies only (each is then counted
    /// by one process).
    ///
    /// # Errors
    /// [`ModelError::NoBody`] for an index out of range or listed twice.
    pub fn part(&self, bodies: &[usize], n_owned: usize) -> Result<(Model, PartMap), ModelError> {
        let nb = self.bodies.len();
        let mut local_body = vec![usize::MAX; nb];
        for (k, &b) in bodies.iter().enumerate() {
            if b >= nb || local_body[b] != usize::MAX {
                return Err(ModelError::NoBody(b));
            }
            local_body[b] = k;
        }
        let n_owned = n_owned.min(bodies.len());
        // node of self -> node of the part (usize::MAX: not in it), and whether it is owned
        let mut local_node = vec![usize::MAX; self.x0.len()];
        let mut local_elem = vec![usize::MAX; self.elements.len()];
        let (mut x0, mut elements, mut elem_material, mut elem_body, mut parts) = (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut map = PartMap::default();
        for (k, &b) in bodies.iter().enumerate() {
            let body = &self.bodies[b];
            let (node_offset, elem_offset) = (x0.len(), elements.len());
            for n in 0..body.mesh.n_nodes() {
                local_node[body.node_offset + n] = node_offset + n;
                map.node.push(body.node_offset + n);
            }
            x0.extend_from_slice(&self.x0[body.node_offset..body.node_offset + body.mesh.n_nodes()]);
            for (j, e) in body.mesh.elements.iter().enumerate() {
                local_elem[body.elem_offset + j] = elements.len();
                map.element.push(body.elem_offset + j);
                elements.push(e.map(|n| n + node_offset));
                elem_material.push(body.material);
                elem_body.push(k);
            }
            parts.push(Body { node_offset, elem_offset, ..body.clone() });
        }
        let n_owned_nodes = parts.get(n_owned).map_or(x0.len(), |b| b.node_offset);
        let owned_node = |n: usize| local_node[n] != usize::MAX && local_node[n] < n_owned_nodes;
        let mut new = Model { bodies: parts, x0: Vec::new(), elements, elem_material, elem_body, whole: Some(self.whole_facts()), ..self.clone_parameters() };
        new.loading.prescribed = self.loading.prescribed.iter().filter(|p| local_node[p.dof / 2] != usize::MAX).map(|p| crate::loading::PrescribedDof { dof: 2 * local_node[p.dof / 2] + p.dof % 2, ..*p }).collect();
        new.loading.prescribed.sort_by_key(|p| p.dof);
        new.loading.loads = self
            .loading
            .loads
            .iter()
            .map(|l| crate::loading::EdgeLoad { edges: l.edges.iter().filter(|e| owned_node(e[0]) && owned_node(e[1])).map(|e| e.map(|n| local_node[n])).collect(), ..l.clone() })
            .collect();
        let groups = |gs: &[NodeGroup]| -> Vec<NodeGroup> { gs.iter().map(|g| NodeGroup { label: g.label.clone(), nodes: g.nodes.iter().filter(|&&n| owned_node(n)).map(|&n| local_node[n]).collect() }).collect() };
        new.reaction_groups = groups(&self.reaction_groups);
        new.displacement_groups = groups(&self.displacement_groups);
        let owned_elem = |e: usize| local_elem[e] != usize::MAX && local_body[self.elem_body[e]] < n_owned;
        new.probes = self
            .probes
            .iter()
            .filter_map(|p| {
                let at = match &p.at {
                    ProbeAt::Point { element, xi } => owned_elem(*element).then(|| ProbeAt::Point { element: local_elem[*element], xi: *xi })?,
                    ProbeAt::Node { node, corners } => owned_node(*node).then(|| ProbeAt::Node { node: local_node[*node], corners: corners.iter().map(|&(e, a)| (local_elem[e], a)).collect() })?,
                };
                Some(Probe { name: p.name.clone(), at })
            })
            .collect();
        new.x0 = x0;
        Ok((new, map))
    }

    /// This whole model without its meshes ([`ModelFrame`]). `None` for a part of a model
    /// (whose loads, groups and probes are its own bodies' only).
    pub fn frame(&self) -> Option<ModelFrame> {
        if self.whole.is_some() {
            return None;
        }
        // (the bodies' nodes are contiguous, in body order)
        let node = |n: usize| -> BodyLocal {
            let b = self.bodies.partition_point(|b| b.node_offset <= n).saturating_sub(1);
            (b, n - self.bodies[b].node_offset)
        };
        let element = |e: usize| -> BodyLocal {
            let b = self.elem_body[e];
            (b, e - self.bodies[b].elem_offset)
        };
        let groups = |gs: &[NodeGroup]| gs.iter().map(|g| (g.label.clone(), g.nodes.iter().map(|&n| node(n)).collect())).collect();
        Some(ModelFrame {
            params: self.clone_parameters(),
            n_bodies: self.bodies.len(),
            loads: self.loading.loads.iter().map(|l| (crate::loading::EdgeLoad { edges: Vec::new(), ..l.clone() }, l.edges.iter().map(|e| e.map(node)).collect())).collect(),
            reaction_groups: groups(&self.reaction_groups),
            displacement_groups: groups(&self.displacement_groups),
            probes: self
                .probes
                .iter()
                .map(|p| {
                    let at = match &p.at {
                        ProbeAt::Point { element: e, xi } => LocalProbe::Point { element: element(*e), xi: *xi },
                        ProbeAt::Node { node: n, corners } => LocalProbe::Node { node: node(*n), corners: corners.iter().map(|&(e, a)| (element(e), a)).collect() },
                    };
                    (p.name.clone(), at)
                })
                .collect(),
        })
    }

    /// Body `k` of this model as a ghost takes it ([`GhostBody`]). Panics for a body out of
    /// range (the caller names its own bodies).
    pub fn ghost_body(&self, k: usize) -> GhostBody {
        let body = &self.bodies[k];
        let nodes = body.node_offset..body.node_offset + body.mesh.n_nodes();
        let dofs = 2 * nodes.start..2 * nodes.end;
        let prescribed = self.loading.prescribed.iter().filter(|p| dofs.contains(&p.dof)).map(|p| crate::loading::PrescribedDof { dof: p.dof - dofs.start, ..*p }).collect();
        GhostBody { body: body.clone(), x0: self.x0[nodes].to_vec(), prescribed }
    }

    /// This part of a model ([`Model::part`]) with other ghosts: its first `n_owned` bodies,
    /// their nodes, elements, prescribed dofs, loads, output groups and probes as they are
    /// (a part's loads, groups and probes are on its own bodies only, whose numbers do not
    /// change), then `ghosts` in their order, numbered after them.
    ///
    /// # Errors
    /// [`ModelError::NoBody`] for `n_owned` above the bodies, or a ghost whose reference
    /// coordinates are not one per node of its mesh (the index of the ghost among `ghosts`).
    pub fn with_ghosts(&self, n_owned: usize, ghosts: Vec<GhostBody>) -> Result<Model, ModelError> {
        if n_owned > self.bodies.len() {
            return Err(ModelError::NoBody(n_owned));
        }
        if let Some(k) = ghosts.iter().position(|g| g.x0.len() != g.body.mesh.n_nodes()) {
            return Err(ModelError::NoBody(k));
        }
        let (n_nodes, n_elements) = self.bodies.get(n_owned).map_or((self.x0.len(), self.elements.len()), |b| (b.node_offset, b.elem_offset));
        let mut new = Model {
            bodies: self.bodies[..n_owned].to_vec(),
            x0: self.x0[..n_nodes].to_vec(),
            elements: self.elements[..n_elements].to_vec(),
            elem_material: self.elem_material[..n_elements].to_vec(),
            elem_body: self.elem_body[..n_elements].to_vec(),
            reaction_groups: self.reaction_groups.clone(),
            displacement_groups: self.displacement_groups.clone(),
            probes: self.probes.clone(),
            ..self.clone_parameters()
        };
        new.loading.loads = self.loading.loads.clone();
        new.loading.prescribed = self.loading.prescribed.iter().filter(|p| p.dof < 2 * n_nodes).cloned().collect();
        for GhostBody { body, x0, prescribed } in ghosts {
            let (node_offset, elem_offset) = (new.x0.len(), new.elements.len());
            let k = new.bodies.len();
            for e in &body.mesh.elements {
                new.elements.push(e.map(|n| n + node_offset));
                new.elem_material.push(body.material);
                new.elem_body.push(k);
            }
            new.x0.extend(x0);
            new.loading.prescribed.extend(prescribed.into_iter().map(|p| crate::loading::PrescribedDof { dof: p.dof + 2 * node_offset, ..p }));
            new.bodies.push(Body { node_offset, elem_offset, ..body });
        }
        new.loading.prescribed.sort_by_key(|p| p.dof);
        Ok(new)
    }

    /// A copy of everything but the meshes, the numbering and what refers to nodes (for
    /// [`Model::part`], which fills those in).
    fn clone_parameters(&self) -> Model {
        Model {
            title: self.title.clone(),
            formulation: self.formulation,
            plane_stress: self.plane_stress,
            element: self.element,
            loading: crate::loading::Loading { prescribed: Vec::new(), loads: Vec::new(), ..self.loading.clone() },
            contact: self.contact.clone(),
            stabilisation: self.stabilisation.clone(),
            stop: self.stop.clone(),
            remesh: self.remesh.clone(),
            materials: self.materials.clone(),
            densities: self.densities.clone(),
            bodies: Vec::new(),
            x0: Vec::new(),
            elements: Vec::new(),
            elem_material: Vec::new(),
            elem_body: Vec::new(),
            reaction_groups: Vec::new(),
            displacement_groups: Vec::new(),
            probes: Vec::new(),
            whole: self.whole,
        }
    }

    /// Whether bodies can touch: there are walls or several bodies.
    pub fn has_contact(&self) -> bool {
        !self.loading.walls.is_empty() || self.bodies.len() > 1
    }

    /// What the contact needs of each body: mesh, node offset, contact length, Young's modulus.
    pub fn contact_bodies(&self) -> Vec<ContactBody<'_>> {
        self.bodies
            .iter()
            .map(|b| ContactBody { mesh: &b.mesh, node_offset: b.node_offset, h: b.contact_h, e: self.materials[b.material].youngs_modulus() })
            .collect()
    }

    /// The contact problem of this model (`None` when nothing can touch, or with the barrier
    /// contact, see [`Model::barrier_contact`]).
    pub fn contact_problem(&self) -> Option<ContactProblem> {
        if self.contact.method == ContactMethod::Barrier {
            return None;
        }
        ContactProblem::new(&self.contact_bodies(), &self.x0, self.contact.clone())
    }

    /// The barrier contact of this model (`[contact] method = "barrier"`; `None` with another
    /// method or when nothing can touch).
    pub fn barrier_contact(&self) -> Option<crate::contact::barrier_problem::BarrierContact> {
        (self.contact.method == ContactMethod::Barrier && self.has_contact()).then(|| {
            // (a part's d̂ and κ are the whole model's)
            let w = self.whole_facts();
            crate::contact::barrier_problem::BarrierContact::of_bodies(&self.contact_bodies(), &self.x0, self.contact.dhat, self.contact.integration, (w.h_min, w.e_min))
        })
    }

    /// The rigid walls at time `t` as the planes the contact kernels take.
    pub fn wall_planes(&self, t: f64) -> Vec<Wall> {
        (0..self.loading.walls.len())
            .map(|w| {
                let (point, normal) = self.loading.wall_plane(w, t);
                Wall { point, normal }
            })
            .collect()
    }

    /// The particles that lie partly or wholly beyond a wall at the start (t = 0): for each,
    /// a message naming the body, the wall and how far its farthest node is beyond it. A node
    /// on the wall, or beyond it by round-off (1e-9 of the die's size), is inside.
    pub fn outside_walls(&self) -> Vec<String> {
        self.outside_walls_by_body().into_iter().map(|(_, m)| m).collect()
    }

    /// [`Model::outside_walls`] with the body of each message. The round-off is that of the
    /// whole model's size ([`Model::whole_facts`]), also on a model that holds some of its
    /// bodies' meshes only.
    pub fn outside_walls_by_body(&self) -> Vec<(usize, String)> {
        let walls = self.wall_planes(0.0);
        if walls.is_empty() {
            return Vec::new();
        }
        let size = walls.iter().flat_map(|w| [w.point[0].abs(), w.point[1].abs()]).fold(self.whole_facts().extent, f64::max);
        let tol = 1e-9 * size.max(1.0);
        let mut out = Vec::new();
        for (i, b) in self.bodies.iter().enumerate() {
            let nodes = &self.x0[b.node_offset..b.node_offset + b.mesh.nodes.len()];
            for (w, wall) in walls.iter().enumerate() {
                let depth = |p: &[f64; 2]| (p[0] - wall.point[0]) * wall.normal[0] + (p[1] - wall.point[1]) * wall.normal[1];
                let (lo, hi) = nodes.iter().map(depth).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| (a.min(d), b.max(d)));
                if lo < -tol {
                    let side = format!("{:?}", self.loading.walls[w].side).to_lowercase();
                    let how = if hi < -tol { "lies wholly" } else { "reaches" };
                    out.push((i, format!(
                        "bodies[{i}] (\"{}\") {how} beyond walls[{w}] (the {side} wall at {} mm): its farthest node {:.4} mm past it; expected every particle inside the die at the start (move the wall or the particle, or set the grid's or packing's solid_ratio lower)",
                        b.name,
                        self.loading.walls[w].position,
                        -lo
                    )));
                }
            }
        }
        out
    }

    /// The bodies whose meshes have an element of scaled Jacobian below `threshold` and none
    /// inverted (an inverted one is an error, not a warning), with that smallest scaled
    /// Jacobian ([`crate::mesh::quality::quality`]); a body without a mesh has none.
    pub fn poor_meshes(&self, threshold: f64) -> Vec<(usize, f64)> {
        self.bodies
            .iter()
            .enumerate()
            .filter(|(_, b)| b.mesh.n_elements() > 0)
            .filter_map(|(i, b)| {
                let q = crate::mesh::quality::quality(&b.mesh, &b.mesh.nodes);
                (q.n_inverted == 0 && q.min_scaled_jacobian < threshold).then_some((i, q.min_scaled_jacobian))
            })
            .collect()
    }

    /// Whether the global tangent of this model is symmetric (see [`symmetric_tangent`]; the
    /// materials of the bodies count).
    pub fn symmetric_tangent(&self) -> bool {
        let follower = self.loading.loads.iter().any(|l| matches!(l.kind, LoadKind::Pressure(_)));
        let contact = self.has_contact().then_some((&self.contact, self.bodies.len()));
        symmetric_tangent(self.bodies.iter().filter_map(|b| self.materials.get(b.material)), follower, contact)
    }

    /// Why body `b` cannot be re-meshed (its nodes are named by prescribed displacements,
    /// loads or output groups, whose node lists would lose their meaning), or `None` when it
    /// can (also for a body index out of range: [`Model::with_body_mesh`] reports that).
    pub fn remesh_constraint(&self, b: usize) -> Option<&'static str> {
        let body = self.bodies.get(b)?;
        let (lo, hi) = (body.node_offset, body.node_offset + body.mesh.n_nodes());
        let inside = |n: usize| (lo..hi).contains(&n);
        if self.loading.prescribed.iter().any(|p| inside(p.dof / 2)) {
            return Some("prescribed displacements");
        }
        if self.loading.loads.iter().any(|l| l.edges.iter().flatten().any(|&n| inside(n))) {
            return Some("loads");
        }
        if self.reaction_groups.iter().chain(&self.displacement_groups).any(|g| g.nodes.iter().any(|&n| inside(n))) {
            return Some("output groups");
        }
        if self.probes.iter().any(|p| match &p.at {
            ProbeAt::Point { element, .. } => self.elem_body.get(*element) == Some(&b),
            ProbeAt::Node { node, .. } => inside(*node),
        }) {
            return Some("probes");
        }
        None
    }

    /// The element that holds reference point `p` (see [`locate`]).
    pub fn locate(&self, p: [f64; 2], body: Option<usize>) -> Option<(usize, [f64; 2])> {
        locate(&self.x0, &self.elements, &self.elem_body, p, body)
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
        self.with_body_meshes(vec![(b, mesh)])
    }

    /// [`Model::with_body_mesh`] for several bodies at once (each listed once), renumbered
    /// once.
    ///
    /// # Errors
    /// As [`Model::with_body_mesh`], for the first body that fails; [`ModelError::NoBody`]
    /// for a body listed twice.
    pub fn with_body_meshes(&self, meshes: Vec<(usize, Mesh)>) -> Result<Model, ModelError> {
        let mut remeshed = vec![false; self.bodies.len()];
        for (b, _) in &meshes {
            let old = self.bodies.get(*b).ok_or(ModelError::NoBody(*b))?;
            if let Some(what) = self.remesh_constraint(*b) {
                return Err(ModelError::RemeshConstrained { body: old.name.clone(), what });
            }
            if std::mem::replace(&mut remeshed[*b], true) {
                return Err(ModelError::NoBody(*b));
            }
        }
        let mut new = self.clone();
        for (b, mesh) in meshes {
            new.bodies[b].mesh = mesh;
        }
        let (mut x0, mut elements, mut elem_material, mut elem_body) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        // old global node -> new global node, for the nodes of the other bodies
        let mut renumber = vec![usize::MAX; self.x0.len()];
        for (ib, body) in new.bodies.iter_mut().enumerate() {
            let (node_offset, elem_offset) = (x0.len(), elements.len());
            if remeshed[ib] {
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
        for p in &mut new.loading.prescribed {
            p.dof = 2 * renumber[p.dof / 2] + p.dof % 2;
        }
        for l in &mut new.loading.loads {
            for e in &mut l.edges {
                *e = e.map(|n| renumber[n]);
            }
        }
        for g in new.reaction_groups.iter_mut().chain(new.displacement_groups.iter_mut()) {
            for n in &mut g.nodes {
                *n = renumber[*n];
            }
        }
        // (the probes lie in the other bodies: their elements move with their body's offset)
        let element = |e: usize| {
            let c = self.elem_body[e];
            new.bodies[c].elem_offset + (e - self.bodies[c].elem_offset)
        };
        let probes = new
            .probes
            .iter()
            .map(|p| Probe {
                name: p.name.clone(),
                at: match &p.at {
                    ProbeAt::Point { element: e, xi } => ProbeAt::Point { element: element(*e), xi: *xi },
                    ProbeAt::Node { node, corners } => ProbeAt::Node { node: renumber[*node], corners: corners.iter().map(|&(e, a)| (element(e), a)).collect() },
                },
            })
            .collect();
        new.probes = probes;
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

/// The element of a mesh (coordinates `x0`, `elements`, their bodies `elem_body`) that holds
/// point `p` (in body `body` only, when given), and the local coordinates of `p` in it: the
/// first element in the global order whose closure holds it (to 1e-9 in ξ and η, which are
/// then clamped to [−1, 1]).
pub fn locate(x0: &[[f64; 2]], elements: &[[usize; 4]], elem_body: &[usize], p: [f64; 2], body: Option<usize>) -> Option<(usize, [f64; 2])> {
    const SLACK: f64 = 1e-9;
    for (e, el) in elements.iter().enumerate() {
        if body.is_some_and(|b| elem_body[e] != b) {
            continue;
        }
        let xe = el.map(|n| x0[n]);
        let (lo, hi) = xe.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), q| ([lo[0].min(q[0]), lo[1].min(q[1])], [hi[0].max(q[0]), hi[1].max(q[1])]));
        let pad = SLACK * (hi[0] - lo[0]).max(hi[1] - lo[1]);
        if p[0] < lo[0] - pad || p[0] > hi[0] + pad || p[1] < lo[1] - pad || p[1] > hi[1] + pad {
            continue;
        }
        if let Some(xi) = crate::element::local_coordinates(&xe, p) {
            if xi[0].abs() <= 1.0 + SLACK && xi[1].abs() <= 1.0 + SLACK {
                return Some((e, xi.map(|v| v.clamp(-1.0, 1.0))));
            }
        }
    }
    None
}

/// Every element at node `n` and the node's corner (0–3) in each.
pub fn node_corners(elements: &[[usize; 4]], n: usize) -> Vec<(usize, usize)> {
    elements.iter().enumerate().filter_map(|(e, el)| el.iter().position(|&m| m == n).map(|a| (e, a))).collect()
}
