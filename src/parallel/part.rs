//! A process's part of a distributed model: its own particles and a ghost layer.
//!
//! The particles are dealt out whole (the METIS partition of the particle graph,
//! [`crate::distribute`]). A process holds the bodies it owns and, as ghosts, the bodies of
//! other processes that lie within a reach of one of its own (their bounding boxes, grown by
//! the reach, overlap) — the contact search distance: every contact pair whose first side is
//! on an owned body then has its second side at hand. A ghost is held whole for now (its mesh
//! and its nodes); only its boundary is ever read.
//!
//! The nodes are numbered over all processes with one contiguous range per process, in rank
//! order, each process's owned bodies in ascending order ([`DistributedNumbering`]); the
//! part's local numbering puts its owned nodes first in that order and its ghosts' nodes after
//! them, and an [`IndexMap`] moves values between the owners and the ghosts.

use crate::comm::{Collective, IndexMap, IndexMapError};
use crate::model::{Body, GhostBody, Model, ModelError, PartMap, WholeModel};
use crate::mesh::Mesh;
use std::sync::Arc;

/// The ghosts of process `rank`: the bodies other processes own (`owner`) whose boxes come
/// within `reach` of the box of a body it owns, ascending. (The relation is symmetric: when
/// process p ghosts q's body B for its body A, q ghosts A for B.)
///
/// # Errors
/// A box that is not finite, or a reach that is negative or not finite (the partitioner's
/// message).
pub fn ghost_bodies(boxes: &[partition::Particle], owner: &[usize], rank: usize, reach: f64) -> Result<Vec<usize>, partition::PartitionError> {
    let graph = partition::particle_graph(boxes, partition::Adjacency::Proximity { gap: reach })?;
    let mut ghost = vec![false; boxes.len()];
    for (b, _) in owner.iter().enumerate().filter(|&(_, &o)| o == rank) {
        for &c in graph.neighbors(b) {
            if owner[c] != rank {
                ghost[c] = true;
            }
        }
    }
    Ok(ghost.iter().enumerate().filter_map(|(b, &g)| g.then_some(b)).collect())
}

/// Every body's box (of the `n` bodies of the whole model), from every process's own bodies'
/// `(body, box)`, on every process, and whether each was sent (a body no process sent keeps an
/// empty box of no elements). Collective: five numbers a body.
pub fn all_boxes(comm: &dyn Collective, own: impl Iterator<Item = (usize, partition::Particle)>, n: usize) -> (Vec<partition::Particle>, Vec<bool>) {
    let mine: Vec<f64> = own.flat_map(|(g, b)| [g as f64, b.min[0], b.min[1], b.max[0], b.max[1]]).collect();
    let all = comm.all_gather_varcount(&mine);
    let mut boxes = vec![partition::Particle { elements: 0, min: [0.0; 2], max: [0.0; 2] }; n];
    let mut known = vec![false; n];
    for r in all.chunks_exact(5) {
        let b = r[0] as usize;
        if b < n {
            boxes[b] = partition::Particle { elements: 1, min: [r[1], r[2]], max: [r[3], r[4]] };
            known[b] = true;
        }
    }
    (boxes, known)
}

/// The global node numbering of a distributed run: one contiguous range per process in rank
/// order, each process's bodies in ascending order, each body's nodes in its mesh's order.
/// Built from the owners and the node count of every body (a few numbers per body, which every
/// process holds).
#[derive(Clone, Debug, PartialEq)]
pub struct DistributedNumbering {
    /// Global index of node 0 of every body.
    pub body_start: Vec<usize>,
    /// Nodes owned by each process.
    pub rank_nodes: Vec<usize>,
}

impl DistributedNumbering {
    pub fn new(owner: &[usize], body_nodes: &[usize], ranks: usize) -> Self {
        let mut rank_nodes = vec![0; ranks];
        for (&o, &n) in owner.iter().zip(body_nodes) {
            rank_nodes[o] += n;
        }
        let mut next: Vec<usize> = rank_nodes.iter().scan(0, |at, &n| {
            let s = *at;
            *at += n;
            Some(s)
        }).collect();
        let body_start = owner
            .iter()
            .zip(body_nodes)
            .map(|(&o, &n)| {
                let s = next[o];
                next[o] += n;
                s
            })
            .collect();
        Self { body_start, rank_nodes }
    }
}

/// What every process of a run on parts keeps of the whole model's bodies: a few numbers a
/// body, from which the parts are grown again without the whole model ([`RankPart::regrow`]).
#[derive(Clone, Debug, PartialEq)]
pub struct BodyLayout {
    /// The process owning each body (changed by a repartition only,
    /// [`crate::solver::Simulation::migrated`]).
    pub owner: Vec<usize>,
    /// Each body's node count.
    pub n_nodes: Vec<usize>,
    /// The whole model's node and element of each body's first.
    pub node_offset: Vec<usize>,
    pub elem_offset: Vec<usize>,
    /// The whole model's boundary edge of each body's first (the contact's segments: every
    /// body's `mesh.boundary` in body order), and one past the last body's.
    pub segment_offset: Vec<usize>,
    /// Each body's element count.
    pub n_elements: Vec<usize>,
    /// The prescribed dofs of the bodies before each body, and of all of them (one past the
    /// last): the whole model's equation of a body's free dof is its whole dof less those and
    /// its own prescribed dofs before it ([`crate::assembly::number_equations`]).
    pub fixed_before: Vec<usize>,
    /// Close pairs of bodies (edges of the particle graph, [`crate::distribute::particle_graph`])
    /// owned by different processes: of the reference configuration when the parts were first
    /// made, of the configuration of the last repartition since.
    pub edge_cut: usize,
}

/// A body's new sizes after a re-mesh: (body, nodes, elements, boundary edges).
pub type Resized = (usize, usize, usize, usize);

impl BodyLayout {
    /// The layout of `whole`'s bodies owned by `owner`.
    pub fn new(whole: &Model, owner: &[usize]) -> Self {
        let b = &whole.bodies;
        let mut fixed = vec![0; b.len()];
        for p in &whole.loading.prescribed {
            let n = p.dof / 2;
            let k = b.partition_point(|b| b.node_offset <= n);
            if k >= 1 {
                fixed[k - 1] += 1;
            }
        }
        let mut layout = Self::from_sizes(owner.to_vec(), b.iter().map(|b| (b.mesh.n_nodes(), b.mesh.n_elements(), b.mesh.boundary.len())).collect(), &fixed);
        layout.edge_cut = crate::distribute::particle_graph(whole).map_or(0, |g| if g.n_vertices() == owner.len() { partition::edge_cut(&g, owner) } else { 0 });
        layout
    }

    /// The heaviest process's element count over the mean of `ranks` processes.
    pub fn imbalance(&self, ranks: usize) -> f64 {
        let mut load = vec![0usize; ranks.max(1)];
        for (&o, &n) in self.owner.iter().zip(&self.n_elements) {
            if let Some(l) = load.get_mut(o) {
                *l += n;
            }
        }
        let total: usize = load.iter().sum();
        if total == 0 {
            return 1.0;
        }
        load.iter().copied().max().unwrap_or(0) as f64 * load.len() as f64 / total as f64
    }

    /// The layout of bodies owned by `owner` with `sizes` (nodes, elements, boundary edges)
    /// and `fixed` prescribed dofs each, numbered in body order (its `edge_cut` 0: the caller
    /// counts it).
    pub fn from_sizes(owner: Vec<usize>, sizes: Vec<(usize, usize, usize)>, fixed: &[usize]) -> Self {
        let prefix = |f: &dyn Fn(&(usize, usize, usize)) -> usize| -> Vec<usize> {
            std::iter::once(0)
                .chain(sizes.iter().scan(0, |at, s| {
                    *at += f(s);
                    Some(*at)
                }))
                .collect()
        };
        let mut node_offset = prefix(&|s| s.0);
        let mut elem_offset = prefix(&|s| s.1);
        node_offset.pop();
        elem_offset.pop();
        let segment_offset = prefix(&|s| s.2);
        let fixed_before = std::iter::once(0)
            .chain(fixed.iter().scan(0, |at, &f| {
                *at += f;
                Some(*at)
            }))
            .collect();
        Self { owner, n_nodes: sizes.iter().map(|s| s.0).collect(), node_offset, elem_offset, segment_offset, n_elements: sizes.iter().map(|s| s.1).collect(), fixed_before, edge_cut: 0 }
    }

    /// This layout with the bodies of `resized` re-meshed to their new sizes (every body after
    /// them renumbered). A re-meshed body has no prescribed dof ([`Model::remesh_constraint`]).
    pub fn resized(&self, resized: &[Resized]) -> Self {
        let mut sizes: Vec<(usize, usize, usize)> = (0..self.owner.len()).map(|b| (self.n_nodes[b], self.n_elements[b], self.segment_offset[b + 1] - self.segment_offset[b])).collect();
        for &(b, nn, ne, ns) in resized {
            if let Some(s) = sizes.get_mut(b) {
                *s = (nn, ne, ns);
            }
        }
        let fixed: Vec<usize> = self.fixed_before.windows(2).map(|w| w[1] - w[0]).collect();
        Self { edge_cut: self.edge_cut, ..Self::from_sizes(self.owner.clone(), sizes, &fixed) }
    }

    /// The body holding the whole model's element `e` (None past the last).
    pub fn element_body(&self, e: usize) -> Option<usize> {
        let b = self.elem_offset.partition_point(|&o| o <= e);
        (b >= 1 && e < self.elem_offset[b - 1] + self.n_elements[b - 1]).then(|| b - 1)
    }

    /// The whole model's nodes and elements.
    pub fn totals(&self) -> (usize, usize) {
        let n = self.owner.len();
        if n == 0 {
            return (0, 0);
        }
        (self.node_offset[n - 1] + self.n_nodes[n - 1], self.elem_offset[n - 1] + self.n_elements[n - 1])
    }

    /// The body holding the whole model's node `n` (None past the last).
    pub fn node_body(&self, n: usize) -> Option<usize> {
        let b = self.node_offset.partition_point(|&o| o <= n);
        (b >= 1 && n < self.node_offset[b - 1] + self.n_nodes[b - 1]).then(|| b - 1)
    }

    /// This layout with the bodies owned by `owner` (every body's place in the whole model
    /// stays: it follows the body order, not the owners) and `edge_cut` close pairs split.
    pub fn with_owners(&self, owner: Vec<usize>, edge_cut: usize) -> Self {
        Self { owner, edge_cut, ..self.clone() }
    }

    /// The body whose boundary holds the whole model's boundary edge `w` (None past the last).
    pub fn segment_body(&self, w: usize) -> Option<usize> {
        let b = self.segment_offset.partition_point(|&o| o <= w);
        (b >= 1 && b < self.segment_offset.len()).then(|| b - 1)
    }
}

/// Why a part cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    #[error("the ghost layer: {0}")]
    Ghosts(#[from] partition::PartitionError),
    #[error("the part's model: {0}")]
    Model(#[from] ModelError),
    #[error("the node map: {0}")]
    Map(#[from] IndexMapError),
    #[error("body owners: {0}")]
    Owners(String),
    #[error("the part's equations: {0}")]
    Equations(String),
    #[error("the new ghosts: {0}")]
    Migration(String),
}

/// One process's part of a distributed model (see the module docs).
pub struct RankPart {
    /// The process's model: its own bodies (ascending), then its ghosts (ascending), with the
    /// whole model's facts ([`Model::part`]).
    pub model: Model,
    /// The body of the whole model each of the part's bodies is.
    pub bodies: Vec<usize>,
    /// How many of `bodies` (the first) this process owns.
    pub n_owned_bodies: usize,
    /// The owners and ghosts of the part's nodes (owned nodes first, in the global numbering's
    /// order).
    pub nodes: IndexMap,
    /// The node and element of the whole model each of the part's nodes and elements is.
    pub whole: PartMap,
    /// The whole model's equation number of each of the part's dofs (its free dofs numbered
    /// in dof order, [`crate::assembly::number_equations`]; [`crate::assembly::FIXED`] for a
    /// prescribed dof): where a quantity defined on the whole model's equations is read.
    pub whole_eq: Vec<usize>,
    /// Every body's owner, size and place in the whole model.
    pub layout: Arc<BodyLayout>,
    /// The reach its ghosts were chosen with (mm).
    pub reach: f64,
}

/// A part as [`RankPart::regrow`] reads it (the fields of a [`RankPart`], wherever they are
/// kept: a simulation holds them apart).
pub struct PartView<'a> {
    pub model: &'a Model,
    pub nodes: &'a IndexMap,
    pub bodies: &'a [usize],
    pub n_owned_bodies: usize,
    pub layout: &'a Arc<BodyLayout>,
}

impl RankPart {
    /// This process's part of `whole` for a run: the bodies partitioned over the processes
    /// by METIS ([`crate::distribute::partition_particles`], rank 0's partition broadcast),
    /// the ghosts within `reach` of its bodies at coordinates `x` ([`RankPart::reach`] as a
    /// rule). Collective.
    ///
    /// # Errors
    /// As [`RankPart::new`].
    pub fn for_run(whole: &Model, x: &[[f64; 2]], reach: f64, comm: Arc<dyn Collective>) -> Result<Self, PartError> {
        let mut owner: Vec<f64> = crate::distribute::partition_particles(whole, comm.size()).iter().map(|&o| o as f64).collect();
        comm.broadcast(&mut owner);
        let owner: Vec<usize> = owner.iter().map(|&o| o as usize).collect();
        Self::new(whole, x, &owner, reach, comm)
    }

    /// How far from its bodies a part takes other processes' bodies as ghosts: a quarter of
    /// the median body's size, at least four of the smallest contact lengths h. The ghosts
    /// must hold every body within d̂ + h of an own one at the start of every step (checked
    /// then); the margin lets the particles move some steps before a new ghost is needed.
    pub fn reach(whole: &Model) -> f64 {
        Self::reach_of(&crate::distribute::particles(whole), whole.whole_facts().h_min)
    }

    /// [`RankPart::reach`] of bodies whose reference boxes are `boxes` and whose smallest
    /// contact length is `h_min`.
    pub fn reach_of(boxes: &[partition::Particle], h_min: f64) -> f64 {
        let mut sizes: Vec<f64> = boxes.iter().map(|p| (p.max[0] - p.min[0]).max(p.max[1] - p.min[1])).collect();
        sizes.sort_by(f64::total_cmp);
        let median = sizes.get(sizes.len() / 2).copied().unwrap_or(0.0);
        (0.25 * median).max(if h_min.is_finite() { 4.0 * h_min } else { 0.0 })
    }

    /// This process's part made from `held`, a model of the whole model's bodies in which at
    /// least this process's own bodies `owned` and its ghosts `ghosts` (both ascending) are
    /// meshed (the others may be empty: [`crate::case`]'s distributed start meshes no more),
    /// laid out by `layout` (every process's alike) and with the whole model's `facts`: the
    /// part [`RankPart::new`] makes of the whole model with the same owners and ghosts, without
    /// it. Collective.
    ///
    /// # Errors
    /// A body of `owned` or `ghosts` out of range, listed twice or whose size is not the
    /// layout's; an owner that is not `layout`'s.
    pub fn from_held(held: &Model, owned: &[usize], ghosts: &[usize], layout: Arc<BodyLayout>, facts: WholeModel, reach: f64, comm: Arc<dyn Collective>) -> Result<Self, PartError> {
        let (rank, size) = (comm.rank(), comm.size());
        let bodies: Vec<usize> = owned.iter().chain(ghosts).copied().collect();
        let mut problem = None;
        if layout.owner.len() != held.bodies.len() || layout.owner.iter().any(|&o| o >= size) {
            problem = Some(format!("{} owners for {} bodies on {size} processes", layout.owner.len(), held.bodies.len()));
        } else if let Some(&b) = bodies.iter().find(|&&b| held.bodies.get(b).map(|x| x.mesh.n_nodes()) != layout.n_nodes.get(b).copied()) {
            problem = Some(format!("body {b} is not held with the layout's size"));
        } else if let Some(&b) = owned.iter().find(|&&b| layout.owner[b] != rank) {
            problem = Some(format!("body {b} is not process {rank}'s"));
        }
        // (every process goes on to the node map, so that none waits for one that failed)
        let failed = comm.max(if problem.is_some() { 1.0 } else { 0.0 }) > 0.0;
        let numbering = DistributedNumbering::new(&layout.owner, &layout.n_nodes, size);
        let ghost_nodes: Vec<usize> = if failed { Vec::new() } else { ghosts.iter().flat_map(|&b| numbering.body_start[b]..numbering.body_start[b] + layout.n_nodes[b]).collect() };
        let nodes = IndexMap::new(Arc::clone(&comm), if failed { 0 } else { numbering.rank_nodes[rank] }, ghost_nodes)?;
        if failed {
            return Err(PartError::Owners(problem.unwrap_or_else(|| "on another process".into())));
        }
        let (mut model, _) = held.part(&bodies, owned.len())?;
        model.whole = Some(facts);
        let whole = whole_map(&model, &bodies, &layout);
        let whole_eq = whole_equations(&model, &bodies, owned.len(), &layout, &nodes);
        Ok(Self { model, bodies, n_owned_bodies: owned.len(), nodes, whole, whole_eq, layout, reach })
    }

    /// This process's part of `whole`, whose bodies are owned by `owner` (every process's
    /// owners alike), with the ghosts within `reach` of its bodies at coordinates `x` (every
    /// node of `whole`). Collective.
    ///
    /// # Errors
    /// Owners that do not name a process for every body, boxes that are not finite, or a
    /// negative reach — on every process alike, as they all see the same input.
    pub fn new(whole: &Model, x: &[[f64; 2]], owner: &[usize], reach: f64, comm: Arc<dyn Collective>) -> Result<Self, PartError> {
        let (rank, size) = (comm.rank(), comm.size());
        if owner.len() != whole.bodies.len() || owner.iter().any(|&o| o >= size) {
            return Err(PartError::Owners(format!("{} owners for {} bodies on {size} processes (expected one process below {size} per body)", owner.len(), whole.bodies.len())));
        }
        // (a process without a body would take other paths through a step than the others)
        if let Some(idle) = (0..size).find(|&r| !owner.contains(&r)) {
            return Err(PartError::Owners(format!("process {idle} owns none of the {} bodies (every process of a distributed run needs one)", whole.bodies.len())));
        }
        let ghosts = ghost_bodies(&crate::distribute::particles_at(whole, x), owner, rank, reach)?;
        let owned: Vec<usize> = (0..owner.len()).filter(|&b| owner[b] == rank).collect();
        Self::from_held(whole, &owned, &ghosts, Arc::new(BodyLayout::new(whole, owner)), whole.whole_facts(), reach, comm)
    }

    /// This part's fields as [`RankPart::regrow`] reads them.
    pub fn view(&self) -> PartView<'_> {
        PartView { model: &self.model, nodes: &self.nodes, bodies: &self.bodies, n_owned_bodies: self.n_owned_bodies, layout: &self.layout }
    }

    /// The part `part` with its ghosts chosen again: the other processes' bodies within
    /// `reach` of its own at coordinates `x` (one per node of the part; its own bodies' are
    /// read), as [`RankPart::new`] would choose them on the whole model — without it. Its own
    /// bodies keep their owner, their place and their numbers; a ghost it keeps is taken from
    /// its own model, and a new one is sent by its owner (its mesh, reference coordinates and
    /// prescribed dofs, [`GhostBody`]); the ghosts' whole equation numbers come from their
    /// owners through the new node map. What is exchanged is the bodies' boxes (five numbers
    /// a body, to every process) and the new ghosts, so no process ever holds the whole
    /// model. Collective.
    ///
    /// # Errors
    /// Coordinates of another length than the part's nodes, boxes that are not finite, a
    /// negative reach, or a ghost its owner cannot send — on every process alike.
    pub fn regrow(part: PartView<'_>, x: &[[f64; 2]], reach: f64) -> Result<Self, PartError> {
        let layout = Arc::clone(part.layout);
        Self::regrow_with(part, x, reach, &layout, &[])
    }

    /// [`RankPart::regrow`] with the bodies laid out by `layout` (every process's alike), which
    /// may differ from the part's in the sizes of bodies re-meshed since
    /// ([`BodyLayout::resized`]: `part.model` holds its own re-meshed bodies already), and with
    /// the ghosts of `stale` (bodies re-meshed by their owners, ascending) sent again by their
    /// owners rather than kept. Collective.
    ///
    /// # Errors
    /// As [`RankPart::regrow`], and own bodies whose sizes are not the layout's.
    pub fn regrow_with(part: PartView<'_>, x: &[[f64; 2]], reach: f64, layout: &Arc<BodyLayout>, stale: &[usize]) -> Result<Self, PartError> {
        let comm = part.nodes.comm_arc();
        let (rank, size) = (comm.rank(), comm.size());
        let nb = layout.owner.len();
        let n_own = part.n_owned_bodies;
        let mut problem = (x.len() != part.model.n_nodes()).then(|| format!("{} coordinates for the part's {} nodes", x.len(), part.model.n_nodes()));
        if let Some(k) = (0..n_own).find(|&k| part.model.bodies.get(k).map(|b| b.mesh.n_nodes()) != layout.n_nodes.get(part.bodies[k]).copied()) {
            problem = problem.or(Some(format!("own body {} has other sizes than the layout's", part.bodies[k])));
        }
        // every process's own bodies' boxes, to every process
        let own = if problem.is_none() { crate::distribute::particles_at(part.model, x) } else { Vec::new() };
        let (boxes, _) = all_boxes(&*comm, part.bodies.iter().copied().zip(own).take(n_own), nb);
        let ghosts = ghost_bodies(&boxes, &layout.owner, rank, reach)?;
        drop(boxes);
        // the new ghosts this process does not hold, asked of their owners
        let held = |g: usize| if stale.binary_search(&g).is_ok() { None } else { part.bodies[n_own..].binary_search(&g).ok().map(|k| n_own + k) };
        let mut ask = vec![Vec::new(); size];
        for &g in ghosts.iter().filter(|&&g| held(g).is_none()) {
            ask[layout.owner[g]].push(g as f64);
        }
        let asked = comm.exchange(&ask);
        let mut send = vec![Vec::new(); size];
        for (r, list) in asked.iter().enumerate() {
            for &g in list {
                match part.bodies[..n_own].binary_search(&(g as usize)) {
                    Ok(k) => {
                        send[r].push(g);
                        write_ghost(&part.model.ghost_body(k), &mut send[r]);
                    }
                    Err(_) => problem = problem.or(Some(format!("process {r} asked for body {g}, which is not one of process {rank}'s"))),
                }
            }
        }
        let got = comm.exchange(&send);
        drop(send);
        let mut fresh = std::collections::BTreeMap::new();
        for (r, buf) in got.iter().enumerate() {
            let mut at = &buf[..];
            while !at.is_empty() {
                match read_usize(&mut at).and_then(|g| read_ghost(&mut at).map(|b| (g, b))) {
                    Ok((g, b)) => {
                        fresh.insert(g, b);
                    }
                    Err(e) => {
                        problem = problem.or(Some(format!("the bodies sent by process {r}: {e}")));
                        break;
                    }
                }
            }
        }
        drop(got);
        let mut new_ghosts = Vec::with_capacity(ghosts.len());
        for &g in &ghosts {
            match held(g).map(|k| part.model.ghost_body(k)).or_else(|| fresh.remove(&g)) {
                Some(b) if b.x0.len() == layout.n_nodes[g] => new_ghosts.push(b),
                _ => problem = problem.or(Some(format!("body {g}, a new ghost, was not received whole"))),
            }
        }
        // (every process goes on to the node map, so that none waits for one that failed)
        let failed = comm.max(if problem.is_some() { 1.0 } else { 0.0 }) > 0.0;
        let numbering = DistributedNumbering::new(&layout.owner, &layout.n_nodes, size);
        let ghost_nodes: Vec<usize> = if failed { Vec::new() } else { ghosts.iter().flat_map(|&b| numbering.body_start[b]..numbering.body_start[b] + layout.n_nodes[b]).collect() };
        let nodes = IndexMap::new(Arc::clone(&comm), numbering.rank_nodes[rank], ghost_nodes)?;
        if failed {
            return Err(PartError::Migration(problem.unwrap_or_else(|| "on another process".into())));
        }
        let mut model = part.model.with_ghosts(n_own, new_ghosts)?;
        let (n_nodes, n_elements) = layout.totals();
        if let Some(w) = model.whole.as_mut() {
            (w.n_nodes, w.n_elements) = (n_nodes, n_elements);
        }
        let bodies: Vec<usize> = part.bodies[..n_own].iter().chain(&ghosts).copied().collect();
        let whole = whole_map(&model, &bodies, layout);
        let whole_eq = whole_equations(&model, &bodies, n_own, layout, &nodes);
        Ok(Self { model, bodies, n_owned_bodies: n_own, nodes, whole, whole_eq, layout: Arc::clone(layout), reach })
    }

    /// The part's slice of a vector of the whole model's nodes (`bs` values per node).
    pub fn restrict(&self, whole: &[f64], bs: usize) -> Vec<f64> {
        self.whole.node.iter().flat_map(|&n| whole[n * bs..(n + 1) * bs].iter().copied()).collect()
    }

    /// The map of the part's free equations, for equation numbers `eq` of its dofs (2 per
    /// node; [`crate::assembly::FIXED`] for a prescribed dof) that number the free dofs in dof
    /// order (as [`crate::assembly::number_equations`] does): its own equations are then the
    /// first, and each process's are a contiguous range of the global equations in rank
    /// order. Collective.
    ///
    /// # Errors
    /// `eq` of another length than the part's dofs (on this process; the others complete the
    /// call), or a ghost equation its owner does not know.
    pub fn equation_map(&self, eq: &[usize]) -> Result<IndexMap, PartError> {
        use crate::assembly::FIXED;
        let comm = self.nodes.comm_arc();
        let n_dofs = 2 * self.nodes.n_local();
        let ok = eq.len() == n_dofs;
        let n_own_dofs = 2 * self.nodes.n_owned();
        let n_own = if ok { eq[..n_own_dofs].iter().filter(|&&q| q != FIXED).count() } else { 0 };
        let counts = comm.all_gather_varcount(&[n_own as f64]);
        let start: usize = counts[..comm.rank()].iter().map(|&c| c as usize).sum();
        // every dof's global equation (−1: prescribed), the ghosts' from their owners
        let mut global: Vec<f64> = (0..n_dofs).map(|d| if d < n_own_dofs && ok && eq[d] != FIXED { (start + eq[d]) as f64 } else { -1.0 }).collect();
        self.nodes.forward(&mut global, 2);
        let mut problem = (!ok).then(|| format!("{} equation numbers for the part's {n_dofs} dofs", eq.len()));
        let mut ghosts = Vec::new();
        for d in (n_own_dofs..n_dofs).filter(|_| ok) {
            match (eq[d] != FIXED, global[d] >= 0.0) {
                (true, true) if eq[d] == n_own + ghosts.len() => ghosts.push(global[d] as usize),
                (true, true) => problem = problem.or(Some(format!("ghost dof {d} has equation {}, expected {} (the free dofs numbered in dof order)", eq[d], n_own + ghosts.len()))),
                (false, false) => {}
                (free, _) => problem = problem.or(Some(format!("ghost dof {d} is {} here but not on its owner", if free { "free" } else { "prescribed" }))),
            }
        }
        // (every process makes the map, so that none waits for one that failed)
        let map = IndexMap::new(comm, n_own, if problem.is_none() { ghosts } else { Vec::new() });
        match problem {
            Some(p) => Err(PartError::Equations(p)),
            None => Ok(map?),
        }
    }

    /// Rank 0's whole-model vector of `bs` values per node, gathered from every process's own
    /// nodes (`local`: `bs` values per node of the part; its ghosts' are not read): for the
    /// results and checkpoints, which rank 0 writes in the whole model's numbering. None on the
    /// other processes. Collective.
    pub fn gather_nodes(&self, local: &[f64], bs: usize) -> Option<Vec<f64>> {
        let own = self.nodes.n_owned();
        gather_records(self.nodes.comm(), (0..own).map(|i| (self.whole.node[i], &local[i * bs..(i + 1) * bs])), bs, self.nodes.n_global(), false)
    }

    /// [`RankPart::gather_nodes`] for element values (`bs` per element of the part; its own
    /// bodies' elements are read).
    pub fn gather_elements(&self, local: &[f64], bs: usize) -> Option<Vec<f64>> {
        let own: Vec<usize> = (0..self.model.elements.len()).filter(|&e| self.model.elem_body[e] < self.n_owned_bodies).collect();
        let total = self.nodes.comm().all_gather_varcount(&[own.len() as f64]).iter().sum::<f64>() as usize;
        gather_records(self.nodes.comm(), own.iter().map(|&e| (self.whole.element[e], &local[e * bs..(e + 1) * bs])), bs, total, false)
    }

    /// The part's vector (`bs` values per node, its ghosts' included) of rank 0's whole-model
    /// vector `whole` (given on rank 0; the others pass None): what a restart reads from a
    /// checkpoint written in the whole model's numbering. Collective.
    pub fn scatter_nodes(&self, whole: Option<&[f64]>, bs: usize) -> Vec<f64> {
        let comm = self.nodes.comm();
        // every process's nodes to rank 0, which sends each its values
        let wanted: Vec<f64> = self.whole.node.iter().map(|&n| n as f64).collect();
        let size = comm.size();
        let mut out = vec![Vec::new(); size];
        let lists = comm.gather_varcount_to_root(&[wanted.len() as f64]);
        let nodes = comm.gather_varcount_to_root(&wanted);
        if let (true, Some(w)) = (comm.is_root(), whole) {
            let mut at = 0;
            for (r, &count) in lists.iter().enumerate() {
                let count = count as usize;
                out[r] = nodes[at..at + count].iter().flat_map(|&n| w[n as usize * bs..(n as usize + 1) * bs].iter().copied()).collect();
                at += count;
            }
        }
        let got = comm.exchange(&out);
        got.into_iter().next().unwrap_or_default()
    }

    /// Whether each of the part's bodies is owned here (the owned ones come first).
    pub fn owned_bodies(&self) -> Vec<bool> {
        (0..self.bodies.len()).map(|k| k < self.n_owned_bodies).collect()
    }

    /// Whether each of the part's elements is on an owned body.
    pub fn owned_elements(&self) -> Vec<bool> {
        self.model.elem_body.iter().map(|&b| b < self.n_owned_bodies).collect()
    }
}

/// A ghost body as numbers (for [`Collective::exchange`]): name, material, mesh size,
/// contact length, nodes and reference coordinates, elements, boundary, edge sets, prescribed
/// dofs, each list after its length. Every count and index is below 2⁵³, so exact in an f64.
pub(crate) fn write_ghost(g: &GhostBody, out: &mut Vec<f64>) {
    fn text(t: &str, out: &mut Vec<f64>) {
        out.push(t.len() as f64);
        out.extend(t.bytes().map(f64::from));
    }
    let (b, m) = (&g.body, &g.body.mesh);
    text(&b.name, out);
    out.extend([b.material as f64, b.mesh_size, b.contact_h, m.nodes.len() as f64]);
    out.extend(m.nodes.iter().chain(&g.x0).flatten());
    out.push(m.elements.len() as f64);
    out.extend(m.elements.iter().flatten().map(|&n| n as f64));
    out.push(m.boundary.len() as f64);
    out.extend(m.boundary.iter().flatten().map(|&n| n as f64));
    out.push(m.edge_sets.len() as f64);
    for (name, edges) in &m.edge_sets {
        text(name, out);
        out.push(edges.len() as f64);
        out.extend(edges.iter().flatten().map(|&n| n as f64));
    }
    out.push(g.prescribed.len() as f64);
    for p in &g.prescribed {
        out.extend([p.dof as f64, p.value, p.amplitude as f64]);
    }
}

/// The next number of `at` as a count or index (a whole number from 0 to 2⁵³).
pub(crate) fn read_usize(at: &mut &[f64]) -> Result<usize, String> {
    let (&v, rest) = at.split_first().ok_or("the record ends early")?;
    *at = rest;
    if v >= 0.0 && v <= 9.007_199_254_740_992e15 && v.fract() == 0.0 {
        Ok(v as usize)
    } else {
        Err(format!("{v} is not a count"))
    }
}

/// The next `n` numbers of `at` (at most what is left).
pub(crate) fn read_slice<'a>(at: &mut &'a [f64], n: usize) -> Result<&'a [f64], String> {
    if n > at.len() {
        return Err(format!("{n} numbers asked, {} left", at.len()));
    }
    let (v, rest) = at.split_at(n);
    *at = rest;
    Ok(v)
}

/// The next `n` records of `K` indices below `below`.
fn read_indices<const K: usize>(at: &mut &[f64], below: usize) -> Result<Vec<[usize; K]>, String> {
    let n = read_usize(at)?;
    let v = read_slice(at, n.checked_mul(K).ok_or("too many indices")?)?;
    v.chunks_exact(K)
        .map(|c| {
            let mut r = [0; K];
            for (r, x) in r.iter_mut().zip(c.chunks(1)) {
                *r = read_usize(&mut &x[..])?;
                if *r >= below {
                    return Err(format!("index {r} of {below}"));
                }
            }
            Ok(r)
        })
        .collect()
}

/// A ghost body written by [`write_ghost`], with every count and index checked.
pub(crate) fn read_ghost(at: &mut &[f64]) -> Result<GhostBody, String> {
    fn text(at: &mut &[f64]) -> Result<String, String> {
        let n = read_usize(at)?;
        let bytes = read_slice(at, n)?.iter().map(|&v| if (0.0..256.0).contains(&v) { Ok(v as u8) } else { Err(format!("{v} is not a byte")) }).collect::<Result<Vec<u8>, String>>()?;
        String::from_utf8(bytes).map_err(|e| e.to_string())
    }
    let name = text(at)?;
    let material = read_usize(at)?;
    let &[mesh_size, contact_h] = read_slice(at, 2)? else { unreachable!("two numbers were read") };
    let n = read_usize(at)?;
    let xy = read_slice(at, n.checked_mul(4).ok_or("too many nodes")?)?;
    let points = |v: &[f64]| v.chunks_exact(2).map(|c| [c[0], c[1]]).collect::<Vec<_>>();
    let (nodes, x0) = (points(&xy[..2 * n]), points(&xy[2 * n..]));
    let elements = read_indices::<4>(at, n)?;
    let boundary = read_indices::<2>(at, n)?;
    let mut edge_sets = std::collections::BTreeMap::new();
    for _ in 0..read_usize(at)? {
        let set = text(at)?;
        edge_sets.insert(set, read_indices::<2>(at, n)?);
    }
    let prescribed = (0..read_usize(at)?)
        .map(|_| {
            let dof = read_usize(at)?;
            let value = read_slice(at, 1)?[0];
            let amplitude = read_usize(at)?;
            if dof < 2 * n { Ok(crate::loading::PrescribedDof { dof, value, amplitude }) } else { Err(format!("prescribed dof {dof} of {}", 2 * n)) }
        })
        .collect::<Result<Vec<_>, String>>()?;
    let mesh = Mesh { nodes, elements, boundary, edge_sets };
    Ok(GhostBody { body: Body { name, mesh, material, node_offset: 0, elem_offset: 0, mesh_size, contact_h }, x0, prescribed })
}

/// Where the nodes and elements of a part (`model`, whose bodies are the whole model's
/// `bodies`) are in the whole model laid out by `layout`.
fn whole_map(model: &Model, bodies: &[usize], layout: &BodyLayout) -> PartMap {
    let mut whole = PartMap::default();
    for (b, &g) in model.bodies.iter().zip(bodies) {
        whole.node.extend(layout.node_offset[g]..layout.node_offset[g] + b.mesh.n_nodes());
        whole.element.extend(layout.elem_offset[g]..layout.elem_offset[g] + b.mesh.n_elements());
    }
    whole
}

/// The whole model's equation of each dof of a part (`model`, whose bodies are the whole
/// model's `bodies`, the first `n_own` its own; `nodes` its node map), as
/// [`crate::assembly::number_equations`] numbers the whole model's free dofs
/// ([`crate::assembly::FIXED`] for a prescribed one): its own from the layout (a free dof's
/// equation is its whole dof less the prescribed dofs before it), the ghosts' from their
/// owners. Collective.
fn whole_equations(model: &Model, bodies: &[usize], n_own: usize, layout: &BodyLayout, nodes: &IndexMap) -> Vec<usize> {
    // (−1: prescribed, or a ghost's before the exchange)
    let mut eq = vec![-1.0; 2 * nodes.n_local()];
    let prescribed = &model.loading.prescribed;
    let mut at = 0;
    for (b, &g) in model.bodies[..n_own].iter().zip(bodies) {
        let first = 2 * b.node_offset;
        let base = 2 * layout.node_offset[g] - layout.fixed_before[g];
        let mut fixed_here = 0;
        for d in first..first + 2 * b.mesh.n_nodes() {
            while at < prescribed.len() && prescribed[at].dof < d {
                at += 1;
            }
            if at < prescribed.len() && prescribed[at].dof == d {
                fixed_here += 1;
            } else {
                eq[d] = (base + d - first - fixed_here) as f64;
            }
        }
    }
    nodes.forward(&mut eq, 2);
    let fixed = crate::assembly::FIXED;
    eq.iter().map(|&q| if q < 0.0 { fixed } else { q as usize }).collect()
}

/// Every process's `bodies` (whole model's body, its [`GhostBody`]) on rank 0, in body order;
/// empty on the others. Collective.
///
/// # Errors
/// A record that does not decode (on rank 0).
pub fn bodies_to_root(comm: &dyn Collective, bodies: &[(usize, GhostBody)]) -> Result<Vec<(usize, GhostBody)>, PartError> {
    let mut buf = Vec::new();
    for (g, b) in bodies {
        buf.push(*g as f64);
        write_ghost(b, &mut buf);
    }
    let all = comm.gather_varcount_to_root(&buf);
    drop(buf);
    let mut out = Vec::new();
    let mut at = &all[..];
    while !at.is_empty() {
        let g = read_usize(&mut at).map_err(PartError::Migration)?;
        out.push((g, read_ghost(&mut at).map_err(PartError::Migration)?));
    }
    out.sort_by_key(|(g, _)| *g);
    Ok(out)
}

/// Rank 0's vector of `n` records of `bs` values, each process sending `(index, values)`
/// records (every index once over the processes); None on the others.
/// With `everywhere`, every process gets the vector (an all-gather).
pub fn gather_records<'a>(comm: &dyn Collective, records: impl Iterator<Item = (usize, &'a [f64])>, bs: usize, n: usize, everywhere: bool) -> Option<Vec<f64>> {
    let mut out = if everywhere || comm.is_root() { vec![f64::NAN; n * bs] } else { Vec::new() };
    let received = receive_records(comm, records, bs, everywhere, |i, v| {
        if i < n {
            out[i * bs..(i + 1) * bs].copy_from_slice(v);
        }
    });
    received.then_some(out)
}

/// [`gather_records`] handing each record received to `put(index, values)` as it is read, so
/// that the receiver holds the records once (not again in a vector of its own). Returns
/// whether this process received them (rank 0, or every process with `everywhere`).
pub fn receive_records<'a>(comm: &dyn Collective, records: impl Iterator<Item = (usize, &'a [f64])>, bs: usize, everywhere: bool, mut put: impl FnMut(usize, &[f64])) -> bool {
    let mut buf = Vec::new();
    for (i, v) in records {
        buf.push(i as f64);
        buf.extend_from_slice(v);
    }
    let all = if everywhere { comm.all_gather_varcount(&buf) } else { comm.gather_varcount_to_root(&buf) };
    drop(buf);
    if !everywhere && !comm.is_root() {
        return false;
    }
    for r in all.chunks_exact(bs + 1) {
        put(r[0] as usize, &r[1..]);
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxed(x0: f64, y0: f64) -> partition::Particle {
        partition::Particle { elements: 1, min: [x0, y0], max: [x0 + 1.0, y0 + 1.0] }
    }

    #[test]
    fn ghosts_are_the_other_processes_bodies_within_reach() {
        // a row of unit boxes 0.5 apart: 0 1 | 2 3 (owners 0 0 1 1)
        let boxes: Vec<_> = (0..4).map(|i| boxed(1.5 * f64::from(i), 0.0)).collect();
        let owner = [0, 0, 1, 1];
        assert_eq!(ghost_bodies(&boxes, &owner, 0, 0.6).unwrap(), vec![2]);
        assert_eq!(ghost_bodies(&boxes, &owner, 1, 0.6).unwrap(), vec![1]);
        // out of reach: no ghosts; a reach past two gaps: the next but one too
        assert!(ghost_bodies(&boxes, &owner, 0, 0.4).unwrap().is_empty());
        assert_eq!(ghost_bodies(&boxes, &owner, 0, 2.1).unwrap(), vec![2, 3]);
        assert!(ghost_bodies(&boxes, &owner, 0, -1.0).is_err());
    }

    #[test]
    fn the_numbering_is_contiguous_per_process_in_rank_order() {
        // bodies of 3, 4, 5, 6 nodes owned by 1, 0, 1, 0
        let n = DistributedNumbering::new(&[1, 0, 1, 0], &[3, 4, 5, 6], 2);
        assert_eq!(n.rank_nodes, vec![10, 8]);
        assert_eq!(n.body_start, vec![10, 0, 13, 4]);
    }
}
