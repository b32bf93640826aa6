//! The start of a run on owned + ghost parts without the whole model.
//!
//! Every process reads the case, whose bodies are a few numbers each; none meshes them all:
//!
//! 1. each process meshes every `size`-th body (its rank's share, round robin) and all the
//!    processes gather what the partition and the layout need of every body (box, node,
//!    element and boundary-edge counts, prescribed dofs, contact length, Young's modulus,
//!    extent: twelve numbers a body), where each point probe is, which particles lie beyond a
//!    wall and which meshes are poor;
//! 2. rank 0 partitions the boxes (METIS, as [`crate::distribute::partition_particles`] does on
//!    the whole model) and broadcasts the owners;
//! 3. each process meshes its own bodies, its ghosts (those within the parts' reach,
//!    [`RankPart::reach_of`]) and the few bodies that loads, output groups and probes name,
//!    and makes its part of that model ([`RankPart::from_held`]).
//!
//! The part is the one [`RankPart::for_run`] makes of the whole model (`tests/mpi_ghosts.rs`
//! compares them field by field on 4 processes), and rank 0 keeps the model of its held bodies
//! for the output's columns and frame ([`crate::model::Model::frame`]). The largest thing a
//! process builds is its part plus a share of the bodies, never the whole mesh.

use super::{Case, ProbeSpecAt};
use crate::checkpoint::CheckpointFile;
use crate::solver::WholeRows;
use crate::comm::Collective;
use crate::model::{Model, WholeModel};
use crate::parallel::part::{BodyLayout, PartError, RankPart};
use std::sync::Arc;

/// What a process of a run on parts starts with ([`start_part`]).
pub struct PartStart {
    /// Its part.
    pub part: RankPart,
    /// On rank 0: the model of the bodies that loads, output groups and probes name (the others
    /// without meshes, [`Model::from_case_holding`]) with every load, output group and probe of
    /// the whole model: the output files' columns and the frame of the whole model are made of
    /// it. `None` elsewhere.
    pub held: Option<Model>,
    /// On rank 0: the bodies whose meshes are poor (index, name, smallest scaled Jacobian,
    /// [`Model::poor_meshes`]), in body order.
    pub poor: Vec<(usize, String, f64)>,
}

/// Why a process could not start its part.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The case does not make a model on some process (this one's message, if it saw it;
    /// [`Model::from_case`] on the whole case gives the message of the first body that fails).
    #[error("the model: {}", .0.as_deref().unwrap_or("on another process"))]
    Model(Option<String>),
    /// A particle lies beyond a wall at the start: the message of the first (in body order) on
    /// rank 0 ([`Model::outside_walls`]).
    #[error("{}", .0.as_deref().unwrap_or("a particle lies beyond a wall (rank 0 names it)"))]
    Outside(Option<String>),
    /// The checkpoint a restart reads does not fit the case, or cannot be read (its message;
    /// on rank 0 the first process's that saw one).
    #[error("{}", .0.as_deref().unwrap_or("the checkpoint does not fit the case (on another process)"))]
    Restart(Option<String>),
    #[error(transparent)]
    Part(#[from] PartError),
}

/// Numbers a body in the gathered facts: body, nodes, elements, boundary edges, prescribed
/// dofs, contact length, Young's modulus, extent, box (x min, y min, x max, y max).
const FACTS: usize = 12;

/// This process's part of the model of `case` for a fresh run on owned + ghost parts (see the
/// module docs): the bodies partitioned by METIS (rank 0's, broadcast), the ghosts within
/// [`RankPart::reach_of`] of its own bodies in the reference configuration; the meshes with an
/// element of scaled Jacobian below `poor_below` are reported to rank 0. Collective; every
/// process returns an error when one fails.
///
/// # Errors
/// A body that cannot be meshed or a set or probe the case names that does not exist
/// ([`StartError::Model`]), a particle beyond a wall, a process without a body, or what
/// [`RankPart::from_held`] refuses.
pub fn start_part(case: &Case, comm: Arc<dyn Collective>, poor_below: f64) -> Result<PartStart, StartError> {
    start_part_from(case, comm, poor_below, None)
}

/// [`start_part`], or with `from` the start of a restart on parts from that checkpoint: the
/// bodies' meshes are the checkpoint's (re-meshing may have replaced some), the ghosts are
/// chosen where the particles are at the checkpoint, and each process reads of the checkpoint
/// only its share's and its part's meshes and rows (the state itself is set by
/// [`crate::solver::Simulation::set_whole_state_from`]). The partition is made on the
/// reference boxes, as on the whole model ([`RankPart::for_run`]); particles beyond a wall and
/// poor meshes are not looked for again. Collective.
///
/// # Errors
/// As [`start_part`]; [`StartError::Restart`] for a checkpoint that does not fit the case
/// (another number of bodies or nodes, a re-meshed body that is constrained) or cannot be read.
pub fn start_part_from(case: &Case, comm: Arc<dyn Collective>, poor_below: f64, from: Option<&CheckpointFile>) -> Result<PartStart, StartError> {
    let (rank, size) = (comm.rank(), comm.size());
    let nb = case.bodies.len();
    if let Some(ck) = from.filter(|ck| ck.n_bodies() != nb) {
        return Err(StartError::Restart(Some(mismatch(ck, format!("{} bodies in the checkpoint, {nb} in the case", ck.n_bodies())))));
    }
    // 1. this process's share of the bodies, and what every process needs of each
    let share: Vec<bool> = (0..nb).map(|b| b % size == rank).collect();
    let mut shared = agreed(&*comm, held_model(case, &share, &[], from))?;
    let boxes = crate::distribute::particles(&shared);
    let mut mine = Vec::with_capacity(FACTS * nb.div_ceil(size));
    for (b, body) in shared.bodies.iter().enumerate().filter(|&(b, _)| share[b]) {
        let nodes = body.node_offset..body.node_offset + body.mesh.n_nodes();
        let fixed = shared.loading.prescribed.iter().filter(|p| nodes.contains(&(p.dof / 2))).count();
        let extent = shared.x0[nodes].iter().map(|p| p[0].abs().max(p[1].abs())).fold(0.0, f64::max);
        let e = shared.materials[body.material].youngs_modulus();
        let bx = &boxes[b];
        mine.extend([b as f64, body.mesh.n_nodes() as f64, body.mesh.n_elements() as f64, body.mesh.boundary.len() as f64, fixed as f64, body.contact_h, e, extent, bx.min[0], bx.min[1], bx.max[0], bx.max[1]]);
    }
    let all = comm.all_gather_varcount(&mine);
    drop(mine);
    let mut boxes = vec![partition::Particle { elements: 0, min: [0.0; 2], max: [0.0; 2] }; nb];
    let mut sizes = vec![(0, 0, 0); nb];
    let mut fixed = vec![0; nb];
    let mut seen = vec![false; nb];
    let mut facts = WholeModel { n_bodies: nb, n_nodes: 0, n_elements: 0, h_min: f64::INFINITY, e_min: f64::INFINITY, extent: 0.0 };
    for r in all.chunks_exact(FACTS) {
        let b = r[0] as usize;
        let (nn, ne) = (r[1] as usize, r[2] as usize);
        sizes[b] = (nn, ne, r[3] as usize);
        fixed[b] = r[4] as usize;
        boxes[b] = partition::Particle { elements: ne as u64, min: [r[8], r[9]], max: [r[10], r[11]] };
        seen[b] = true;
        facts.n_nodes += nn;
        facts.n_elements += ne;
        facts.h_min = facts.h_min.min(r[5]);
        facts.e_min = facts.e_min.min(r[6]);
        facts.extent = facts.extent.max(r[7]);
    }
    drop(all);
    if seen.iter().any(|s| !s) {
        return Err(StartError::Model(Some(format!("{} of {nb} bodies were not gathered", seen.iter().filter(|s| !**s).count()))));
    }
    // where the point probes are: the first body holding the point, as the whole model finds it
    let mut found = Vec::new();
    for (i, p) in case.output.probes.iter().enumerate() {
        if let ProbeSpecAt::Point { point, body } = p.at {
            if let Some((e, _)) = shared.locate(point, body) {
                found.extend([i as f64, shared.elem_body[e] as f64]);
            }
        }
    }
    let found = comm.all_gather_varcount(&found);
    let mut pins: Vec<(usize, usize)> = Vec::new();
    for f in found.chunks_exact(2) {
        let (i, b) = (f[0] as usize, f[1] as usize);
        match pins.iter_mut().find(|p| p.0 == i) {
            Some(p) => p.1 = p.1.min(b),
            None => pins.push((i, b)),
        }
    }
    // (a point no body holds: the whole model's error names it)
    if case.output.probes.iter().enumerate().any(|(i, p)| matches!(p.at, ProbeSpecAt::Point { .. }) && !pins.iter().any(|q| q.0 == i)) {
        return Err(StartError::Model(None));
    }
    // particles beyond a wall, and poor meshes: to rank 0, in body order (a fresh run's)
    shared.whole = Some(facts);
    let mut poor = Vec::new();
    if from.is_none() {
        let outside: Vec<(usize, String)> = shared.outside_walls_by_body();
        let n_outside = comm.max(outside.len() as f64);
        let outside = texts_to_root(&*comm, &outside);
        let mine: Vec<f64> = shared.poor_meshes(poor_below).into_iter().flat_map(|(b, q)| [b as f64, q]).collect();
        poor = comm.gather_varcount_to_root(&mine).chunks_exact(2).map(|c| (c[0] as usize, case.bodies[c[0] as usize].name.clone(), c[1])).collect();
        poor.sort_by_key(|p| p.0);
        if n_outside > 0.0 {
            return Err(StartError::Outside(outside.into_iter().next().map(|(_, m)| m)));
        }
    }
    // 2. the owners (rank 0's partition) and the close pairs they split
    let mut owner = vec![0.0; nb + 1];
    if comm.is_root() {
        let own = crate::distribute::partition_boxes(&boxes, size);
        let cut = crate::distribute::proximity_graph(&boxes).map_or(0, |g| partition::edge_cut(&g, &own));
        for (o, &p) in owner.iter_mut().zip(&own) {
            *o = p as f64;
        }
        owner[nb] = cut as f64;
    }
    comm.broadcast(&mut owner);
    let edge_cut = owner.pop().map_or(0, |c| c as usize);
    let owner: Vec<usize> = owner.iter().map(|&o| o as usize).collect();
    if let Some(idle) = (0..size).find(|&r| !owner.contains(&r)) {
        return Err(PartError::Owners(format!("process {idle} owns none of the {nb} bodies (every process of a distributed run needs one)")).into());
    }
    let layout = Arc::new(BodyLayout { edge_cut, ..BodyLayout::from_sizes(owner.clone(), sizes, &fixed) });
    // 3. this process's bodies, its ghosts and the named ones, meshed; its part of them
    let reach = RankPart::reach_of(&boxes, facts.h_min);
    // (a restart: the ghosts are chosen where the particles are at the checkpoint)
    let now = match from {
        Some(ck) => Some(boxes_at(ck, &*comm, &shared, &share, &layout)?),
        None => None,
    };
    drop(shared);
    let ghosts = crate::parallel::part::ghost_bodies(now.as_ref().unwrap_or(&boxes), &owner, rank, reach).map_err(PartError::from)?;
    drop(boxes);
    drop(now);
    let owned: Vec<usize> = (0..nb).filter(|&b| owner[b] == rank).collect();
    let named = named_bodies(case, &pins);
    let mut held = vec![false; nb];
    for &b in owned.iter().chain(&ghosts).chain(&named) {
        held[b] = true;
    }
    let model = agreed(&*comm, held_model(case, &held, &pins, from))?;
    let part = RankPart::from_held(&model, &owned, &ghosts, layout, facts, reach, Arc::clone(&comm))?;
    drop(model);
    // (rank 0's output needs the named bodies only: the others' meshes are its part's)
    let held = match comm.is_root() {
        true => {
            held.iter_mut().enumerate().for_each(|(b, h)| *h = named.binary_search(&b).is_ok());
            Some(held_model(case, &held, &pins, from)?)
        }
        false => None,
    };
    Ok(PartStart { part, held, poor })
}

/// The model of `case` with the bodies `held` meshed ([`Model::from_case_holding`]); with a
/// checkpoint `from`, the held bodies that were re-meshed before it carry its meshes (as
/// [`crate::checkpoint::Checkpoint::model`] sets them on the whole model).
fn held_model(case: &Case, held: &[bool], pins: &[(usize, usize)], from: Option<&CheckpointFile>) -> Result<Model, StartError> {
    let model = Model::from_case_holding(case, Some(held), pins).map_err(|e| StartError::Model(Some(e.to_string())))?;
    let Some(ck) = from else { return Ok(model) };
    let mut changed = Vec::new();
    for b in (0..held.len()).filter(|&b| held[b]) {
        let mesh = ck.mesh(b).map_err(|e| StartError::Restart(Some(e.to_string())))?;
        if !crate::checkpoint::same_mesh(&model.bodies[b].mesh, &mesh) {
            tracing::debug!(body = b, elements = mesh.n_elements(), "restart: the body has its re-meshed mesh");
            changed.push((b, mesh));
        }
    }
    match changed.is_empty() {
        true => Ok(model),
        false => model.with_body_meshes(changed).map_err(|e| StartError::Restart(Some(mismatch(ck, e.to_string())))),
    }
}

/// The message of a checkpoint that does not fit the model of the case.
fn mismatch(ck: &CheckpointFile, reason: String) -> String {
    crate::checkpoint::CheckpointError::Mismatch { path: ck.path.clone(), reason }.to_string()
}

/// Every body's box where the checkpoint `ck` has it: each process adds its rows of the
/// checkpoint's displacements to the reference coordinates of its `share` of the bodies (the
/// nodes of `shared`, which holds that share only, in body order; `layout` places them in the
/// whole model), and the boxes are all-gathered. Collective.
fn boxes_at(ck: &CheckpointFile, comm: &dyn Collective, shared: &Model, share: &[bool], layout: &BodyLayout) -> Result<Vec<partition::Particle>, StartError> {
    let fail = |reason: String| StartError::Restart(Some(mismatch(ck, reason)));
    let mine: Vec<usize> = (0..share.len()).filter(|&b| share[b]).collect();
    let read = || -> Result<Vec<[f64; 2]>, StartError> {
        let n_nodes: usize = layout.n_nodes.iter().sum();
        match ck.values("solution/u") {
            Some(n) if n == 2 * n_nodes => {}
            n => return Err(fail(format!("the checkpoint has {} displacement dofs, the model {}", n.unwrap_or(0), 2 * n_nodes))),
        }
        let rows: Vec<usize> = mine.iter().flat_map(|&b| layout.node_offset[b]..layout.node_offset[b] + layout.n_nodes[b]).collect();
        let u = ck.rows("solution/u", 2, &rows).map_err(|e| StartError::Restart(Some(format!("{}: {e}", ck.path.display()))))?;
        Ok(shared.x0.iter().zip(u.chunks_exact(2)).map(|(p, d)| [p[0] + d[0], p[1] + d[1]]).collect())
    };
    let x = agreed(comm, read())?;
    let own = crate::distribute::particles_at(shared, &x);
    let (boxes, known) = crate::parallel::part::all_boxes(comm, mine.iter().map(|&b| (b, own[b])), share.len());
    match known.iter().filter(|k| !**k).count() {
        0 => Ok(boxes),
        missing => Err(StartError::Restart(Some(format!("{missing} of {} bodies' places at the checkpoint were not gathered", share.len())))),
    }
}

/// `r`, when every process's is Ok; otherwise an error on every process (collective): its own,
/// or on rank 0 the first other process's message of a checkpoint that does not fit (a model
/// that cannot be made is named on rank 0 by the caller, [`StartError::Model`] without one).
fn agreed<T>(comm: &dyn Collective, r: Result<T, StartError>) -> Result<T, StartError> {
    if comm.max(if r.is_err() { 1.0 } else { 0.0 }) == 0.0 {
        return r;
    }
    let mine: Vec<(usize, String)> = match &r {
        Err(StartError::Restart(Some(m))) => vec![(comm.rank(), m.clone())],
        _ => Vec::new(),
    };
    let theirs = texts_to_root(comm, &mine);
    match r {
        Err(e) => Err(e),
        Ok(_) if !theirs.is_empty() => Err(StartError::Restart(theirs.into_iter().next().map(|t| t.1))),
        Ok(_) if comm.is_root() => Err(StartError::Model(None)),
        Ok(_) => Err(StartError::Restart(None)),
    }
}

/// The bodies that loads, output groups and probes name (point probes: where `pins` places
/// them), ascending: every process holds them, so that the loads, groups and probes of its own
/// bodies are the whole model's, and rank 0 makes the output's frame of them.
fn named_bodies(case: &Case, pins: &[(usize, usize)]) -> Vec<usize> {
    let mut b: Vec<usize> = case.loads.iter().map(|l| l.body).chain(case.output.reactions.iter().chain(&case.output.displacements).map(|g| g.0)).collect();
    for (i, p) in case.output.probes.iter().enumerate() {
        match p.at {
            ProbeSpecAt::Node { body, .. } => b.push(body),
            ProbeSpecAt::Point { .. } => b.extend(pins.iter().filter(|q| q.0 == i).map(|q| q.1)),
        }
    }
    b.sort_unstable();
    b.dedup();
    b
}

/// `items` (an index and a text each) of every process on rank 0, ordered by index (empty
/// elsewhere). Collective.
fn texts_to_root(comm: &dyn Collective, items: &[(usize, String)]) -> Vec<(usize, String)> {
    let mut mine = Vec::new();
    for (i, t) in items {
        mine.push(*i as f64);
        mine.push(t.len() as f64);
        mine.extend(t.bytes().map(f64::from));
    }
    let all = comm.gather_varcount_to_root(&mine);
    let mut out = Vec::new();
    let mut at = &all[..];
    while at.len() >= 2 {
        let (i, n) = (at[0] as usize, at[1] as usize);
        let bytes: Vec<u8> = at[2..(2 + n).min(at.len())].iter().map(|&v| v as u8).collect();
        out.push((i, String::from_utf8_lossy(&bytes).into_owned()));
        at = &at[(2 + n).min(at.len())..];
    }
    out.sort_by_key(|t| t.0);
    out
}
