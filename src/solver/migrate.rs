//! Repartitioning on the processes' parts of a distributed model: particles change owner, and
//! their data goes with them. When a re-mesh has left the processes' element counts more
//! uneven than `[solver] repartition_imbalance`, METIS partitions the particles again (their
//! element counts and current boxes, all-gathered: five numbers a particle), and every particle
//! that changes owner is sent to its new owner whole — its mesh, reference coordinates and
//! prescribed dofs, its nodes' displacements (and the dynamics' vectors), every element's
//! material state, stresses, pressure, enhanced modes, multiplier and j₀, its re-mesh baseline,
//! and the ties on its nodes. Every part is then grown again around its new own particles, with
//! their ghosts from the new owners ([`crate::parallel::part::RankPart::regrow_with`]). No
//! process holds the whole model or state; the whole model's numbering (body order) does not
//! change, only the processes' ranges of the distributed one.
//!
//! A particle held by boundary conditions, loads, output groups or probes keeps its owner
//! (those are numbered in its owner's part).

use super::snapshot::{element_record, put_element_record, tie_from_record, tie_record, OwnState, ELEMENT_RECORD, TIE_RECORD};
use super::{Simulation, Solution};
use crate::assembly::ElementFields;
use crate::contact::barrier_problem::Tie;
use crate::model::GhostBody;
use crate::parallel::part::{read_ghost, read_slice, read_usize, write_ghost};
use crate::remesh::monitor::QUALITY_RECORD;
use std::collections::BTreeMap;
use std::sync::Arc;

/// A particle as its new owner receives it.
struct Arrival {
    body: GhostBody,
    /// Per node: u, u_{n−1} (and the dynamics' u, v, a, g), 2 values each.
    nodal: Vec<f64>,
    /// Per element: [`ELEMENT_RECORD`] values.
    elements: Vec<f64>,
    baseline: Option<crate::remesh::QualityCheck>,
    ties: Vec<Tie>,
    tied: Vec<(usize, usize)>,
}

impl Simulation {
    /// On a part: the simulation with the whole model's bodies owned by `owner` (every
    /// process's alike; one entry a body, each naming a process, every process owning at least
    /// one body) at this converged state. The bodies that change owner are sent to their new
    /// owners with all their state (see the module docs); every part is then grown again with
    /// the ghosts within its reach. The history continues as it would have on the old owners,
    /// but for the round-off of the distributed solver's new row order. Counts as a
    /// repartition. Collective.
    ///
    /// # Errors
    /// Not a part; owners of another length, naming no process, leaving a process without a
    /// body, or other than another process's; a body held by boundary conditions, loads,
    /// output groups or probes that would move; or what [`Simulation::regrown`] refuses — on
    /// every process alike.
    pub fn migrated(&self, owner: &[usize]) -> Result<Simulation, String> {
        self.migrated_with_cut(owner, None)
    }

    /// [`Simulation::migrated`], given the new owners' edge cut when the caller knows it (it is
    /// computed from every body's box, all-gathered, otherwise).
    fn migrated_with_cut(&self, owner: &[usize], cut: Option<usize>) -> Result<Simulation, String> {
        let Some(p) = &self.sys.part else { return Err("only a process's part of a distributed model is repartitioned".into()) };
        let started = std::time::Instant::now();
        let comm = p.nodes.comm_arc();
        let (rank, size) = (comm.rank(), comm.size());
        let nb = p.layout.owner.len();
        let n_own = p.own_bodies;
        let mut problem = None;
        if owner.len() != nb || owner.iter().any(|&o| o >= size) {
            problem = Some(format!("{} owners for {nb} bodies on {size} processes (expected one process below {size} per body)", owner.len()));
        } else if let Some(idle) = (0..size).find(|r| !owner.contains(r)) {
            problem = Some(format!("process {idle} would own none of the {nb} bodies (every process of a distributed run needs one)"));
        }
        // (the same owners on every process: a sum that weighs each body's owner differently)
        let sum: f64 = owner.iter().enumerate().map(|(b, &o)| ((b % 1021 + 1) * (o % 1021 + 1)) as f64).sum();
        if comm.max(sum) != -comm.max(-sum) {
            problem = problem.or(Some("the processes were given different owners".into()));
        }
        for (k, &g) in p.bodies[..n_own].iter().enumerate() {
            if owner.get(g).is_some_and(|&o| o != rank) {
                if let Some(what) = self.model.remesh_constraint(k) {
                    problem = problem.or(Some(format!("body {g} is held by {what} and cannot move to process {}", owner[g])));
                }
            }
        }
        if self.sys.any(problem.is_some()) {
            return Err(problem.unwrap_or_else(|| "the new owners, on another process".into()));
        }

        // the bodies that leave, each to its new owner, whole
        let (whole_ties, whole_tied) = self.whole_ties();
        let body_of = |n: usize| p.layout.node_body(n).unwrap_or(usize::MAX);
        // (the ties and tied pairs of each body, grouped once)
        let mut ties_of: BTreeMap<usize, (Vec<Tie>, Vec<(usize, usize)>)> = BTreeMap::new();
        for t in whole_ties {
            ties_of.entry(body_of(t.node)).or_default().0.push(t);
        }
        for t in whole_tied {
            ties_of.entry(body_of(t.0)).or_default().1.push(t);
        }
        let no_ties = (Vec::new(), Vec::new());
        let dynamics: Option<[&[f64]; 4]> = self.dynamics.as_ref().map(|d| [&d.u[..], &d.v[..], &d.a[..], &d.g[..]]);
        let mut send = vec![Vec::new(); size];
        let mut moved = 0;
        for (k, &g) in p.bodies[..n_own].iter().enumerate() {
            let to = owner[g];
            if to == rank {
                continue;
            }
            moved += 1;
            let out = &mut send[to];
            let body = &self.model.bodies[k];
            out.push(g as f64);
            write_ghost(&self.model.ghost_body(k), out);
            for n in body.node_offset..body.node_offset + body.mesh.n_nodes() {
                out.extend_from_slice(&self.sol.u[2 * n..2 * n + 2]);
                out.extend_from_slice(&self.u_prev[2 * n..2 * n + 2]);
                for v in dynamics.iter().flatten() {
                    out.extend_from_slice(&v[2 * n..2 * n + 2]);
                }
            }
            for e in body.elem_offset..body.elem_offset + body.mesh.n_elements() {
                element_record(&self.sol, e, true, out);
            }
            match &self.run.remesh_baseline[k] {
                Some(q) => {
                    out.push(1.0);
                    out.extend(q.to_record());
                }
                None => out.extend(std::iter::repeat_n(0.0, QUALITY_RECORD + 1)),
            }
            let (ties, tied) = ties_of.get(&g).unwrap_or(&no_ties);
            out.push(ties.len() as f64);
            out.extend(ties.iter().flat_map(tie_record));
            out.push(tied.len() as f64);
            out.extend(tied.iter().flat_map(|&(n, c)| [n as f64, c as f64]));
        }
        let got = comm.exchange(&send);
        drop(send);
        let bs = if dynamics.is_some() { 12 } else { 4 };
        let mut arrived = BTreeMap::new();
        for (r, buf) in got.iter().enumerate() {
            let mut at = &buf[..];
            while !at.is_empty() {
                match read_arrival(&mut at, bs) {
                    Ok((g, a)) if owner.get(g) == Some(&rank) && p.layout.n_nodes.get(g) == Some(&a.body.x0.len()) => {
                        arrived.insert(g, a);
                    }
                    Ok((g, _)) => {
                        problem = problem.or(Some(format!("process {r} sent body {g}, which is not to be process {rank}'s, or not whole")));
                        break;
                    }
                    Err(e) => {
                        problem = problem.or(Some(format!("the bodies sent by process {r}: {e}")));
                        break;
                    }
                }
            }
        }
        drop(got);
        let expected = owner.iter().enumerate().filter(|&(g, &o)| o == rank && p.bodies[..n_own].binary_search(&g).is_err()).count();
        if arrived.len() != expected {
            problem = problem.or(Some(format!("{} of the {expected} bodies process {rank} takes over arrived", arrived.len())));
        }

        // its new own bodies (ascending): those it keeps, and those that arrived after them in
        // its model, put in order by `Model::part`
        let keep: Vec<(usize, usize)> = p.bodies[..n_own].iter().enumerate().filter(|&(_, &g)| owner[g] == rank).map(|(k, &g)| (g, k)).collect();
        let mut order: Vec<(usize, usize)> = keep.iter().copied().chain(arrived.keys().enumerate().map(|(j, &g)| (g, n_own + j))).collect();
        order.sort_unstable();
        let owned: Vec<usize> = order.iter().map(|o| o.0).collect();
        let model = self.model.with_ghosts(n_own, arrived.values().map(|a| a.body.clone()).collect()).and_then(|m| m.part(&order.iter().map(|o| o.1).collect::<Vec<_>>(), order.len()));
        let model = match model {
            Ok((m, _)) if problem.is_none() => Some(m),
            Ok(_) => None,
            Err(e) => {
                problem = Some(format!("the new part's model: {e}"));
                None
            }
        };
        if self.sys.any(problem.is_some()) {
            return Err(problem.unwrap_or_else(|| "the bodies sent to another process".into()));
        }
        let Some(model) = model else { return Err("the new part's model".into()) };

        // their state, in the new part's order
        let (own_nodes, own_elements) = (model.n_nodes(), model.elements.len());
        let mut sol = Solution { time: self.sol.time, u: vec![0.0; 2 * own_nodes], fields: ElementFields::new(own_elements), lambda: vec![0.0; own_elements], j0: vec![1.0; own_elements] };
        let mut u_prev = vec![0.0; 2 * own_nodes];
        let mut dyn_new = dynamics.map(|_| std::array::from_fn::<Vec<f64>, 4, _>(|_| vec![0.0; 2 * own_nodes]));
        let mut baseline = Vec::with_capacity(order.len());
        let (mut ties, mut tied): (Vec<Tie>, Vec<(usize, usize)>) = (Vec::new(), Vec::new());
        let mut record = Vec::with_capacity(ELEMENT_RECORD);
        for (nb_new, &(g, k)) in model.bodies.iter().zip(&order) {
            let (n0, e0) = (nb_new.node_offset, nb_new.elem_offset);
            if let Some(a) = arrived.remove(&g) {
                for (i, r) in a.nodal.chunks_exact(bs).enumerate() {
                    let d = 2 * (n0 + i);
                    sol.u[d..d + 2].copy_from_slice(&r[0..2]);
                    u_prev[d..d + 2].copy_from_slice(&r[2..4]);
                    for (j, v) in dyn_new.iter_mut().flatten().enumerate() {
                        v[d..d + 2].copy_from_slice(&r[4 + 2 * j..6 + 2 * j]);
                    }
                }
                for (i, r) in a.elements.chunks_exact(ELEMENT_RECORD).enumerate() {
                    put_element_record(r, e0 + i, true, &mut sol);
                }
                baseline.push(a.baseline);
                ties.extend(a.ties);
                tied.extend(a.tied);
                continue;
            }
            let old = &self.model.bodies[k];
            let (src, dst, n) = (2 * old.node_offset, 2 * n0, 2 * old.mesh.n_nodes());
            sol.u[dst..dst + n].copy_from_slice(&self.sol.u[src..src + n]);
            u_prev[dst..dst + n].copy_from_slice(&self.u_prev[src..src + n]);
            for (v, w) in dyn_new.iter_mut().flatten().zip(dynamics.iter().flatten()) {
                v[dst..dst + n].copy_from_slice(&w[src..src + n]);
            }
            for i in 0..old.mesh.n_elements() {
                record.clear();
                element_record(&self.sol, old.elem_offset + i, true, &mut record);
                put_element_record(&record, e0 + i, true, &mut sol);
            }
            baseline.push(self.run.remesh_baseline[k].clone());
            if let Some((t, d)) = ties_of.remove(&g) {
                ties.extend(t);
                tied.extend(d);
            }
        }
        ties.sort_by_key(|t| (t.node, t.segment));
        tied.sort_unstable();
        let Solution { u, fields, lambda, j0, .. } = sol;
        let own = OwnState { u, u_prev, dynamics: dyn_new, fields, lambda, j0, baseline };

        // its new part, with the ghosts within reach of its new own bodies
        let cut = cut.unwrap_or_else(|| crate::distribute::proximity_graph(&self.all_body_boxes()).map_or(0, |g| partition::edge_cut(&g, owner)));
        let layout = Arc::new(p.layout.with_owners(owner.to_vec(), cut));
        let mut sim = self.grown(&model, own, &owned, &layout, &[], self.time, self.spec, p.reach, |sim| sim.local_ties(&ties, &tied))?;
        sim.interrupt = self.interrupt.clone();
        sim.clock = self.clock.clone();
        let moved = comm.all_gather_varcount(&[moved as f64]).iter().sum::<f64>() as usize;
        let stats = &mut sim.sys.partition;
        stats.repartitions += 1;
        stats.moved += moved;
        stats.time_s += comm.max(started.elapsed().as_secs_f64());
        Ok(sim)
    }

    /// On a part: every body's element count and box at the converged state, on every
    /// process (five numbers a body all-gathered). Collective.
    fn all_body_boxes(&self) -> Vec<partition::Particle> {
        let Some(p) = &self.sys.part else { return crate::distribute::particles_at(&self.model, &self.coords(&self.sol.u)) };
        let at = crate::distribute::particles_at(&self.model, &self.coords(&self.sol.u));
        let (mut boxes, _) = crate::parallel::part::all_boxes(&*self.sys.comm, p.bodies.iter().copied().zip(at).take(p.own_bodies), p.layout.owner.len());
        for (b, &n) in boxes.iter_mut().zip(&p.layout.n_elements) {
            b.elements = n as u64;
        }
        boxes
    }

    /// On a part whose bodies have changed (a re-mesh): keep the owners while their element
    /// counts' imbalance is at most `[solver] repartition_imbalance`, otherwise partition the
    /// particles again (METIS on their current boxes and element counts, rank 0's partition
    /// broadcast; the parts renamed to keep as many elements as possible where they are; a
    /// particle that cannot move keeps its owner) and move them ([`Simulation::migrated`])
    /// when that balances them better.
    /// A repartition that fails keeps the owners, with a warning. Collective.
    pub(super) fn rebalance_parts(&mut self) {
        let Some(p) = &self.sys.part else { return };
        let comm = Arc::clone(&self.sys.comm);
        let size = comm.size();
        let threshold = self.spec.repartition_imbalance;
        let before = p.layout.imbalance(size);
        if size == 1 {
            return;
        }
        if before <= threshold {
            self.sys.partition.kept += 1;
            tracing::info!(imbalance = before, threshold, "model changed: particle owners kept (imbalance within the threshold)");
            return;
        }
        let started = std::time::Instant::now();
        let old = p.layout.owner.clone();
        let nb = old.len();
        let boxes = self.all_body_boxes();
        let held: Vec<f64> = (0..p.own_bodies).map(|k| if self.model.remesh_constraint(k).is_some() { 1.0 } else { 0.0 }).collect();
        let held = crate::parallel::part::gather_records(&*comm, (0..p.own_bodies).map(|k| (p.bodies[k], &held[k..k + 1])), 1, nb, false);
        // rank 0 decides: the owners, then the edge cut
        let mut decided = vec![0.0; nb + 1];
        if let Some(held) = held {
            decided = old.iter().map(|&o| o as f64).chain([0.0]).collect();
            if let Ok(graph) = crate::distribute::proximity_graph(&boxes) {
                let r = crate::distribute::rebalance(&graph, Some(&old), size, threshold, partition::metis_kway);
                let mut owner = r.owner;
                for (b, o) in owner.iter_mut().enumerate() {
                    if held[b] == 1.0 {
                        *o = old[b];
                    }
                }
                // (every process keeps a body and the balance is better, or the owners stay:
                // moving particles for another split as uneven is not worth it)
                let better = crate::distribute::imbalance(&graph, &owner, size) < before - 1e-9;
                if better && (0..size).all(|q| owner.contains(&q)) {
                    decided = owner.iter().map(|&o| o as f64).chain([partition::edge_cut(&graph, &owner) as f64]).collect();
                }
            }
        }
        comm.broadcast(&mut decided);
        let owner: Vec<usize> = decided[..nb].iter().map(|&o| o as usize).collect();
        if owner == old {
            self.sys.partition.kept += 1;
            self.sys.partition.time_s += started.elapsed().as_secs_f64();
            tracing::info!(imbalance = before, threshold, "model changed: the particles' new partition keeps every owner");
            return;
        }
        match self.migrated_with_cut(&owner, Some(decided[nb] as usize)) {
            Ok(sim) => {
                *self = sim;
                let stats = &self.sys.partition;
                tracing::info!(imbalance_before = before, imbalance = stats.imbalance, edge_cut = stats.edge_cut, moved = owner.iter().zip(&old).filter(|(a, b)| a != b).count(), repartitions = stats.repartitions, "model changed: particles repartitioned (imbalance above the threshold)");
            }
            Err(e) => tracing::warn!(%e, "the particles could not be repartitioned: their owners stay"),
        }
    }
}

/// One particle of a [`Simulation::migrated`] message (after its body index): the body, `bs`
/// values a node, the elements' records, the baseline, the ties and tied pairs.
fn read_arrival(at: &mut &[f64], bs: usize) -> Result<(usize, Arrival), String> {
    let g = read_usize(at)?;
    let body = read_ghost(at)?;
    let nodal = read_slice(at, bs * body.x0.len())?.to_vec();
    let elements = read_slice(at, ELEMENT_RECORD * body.body.mesh.n_elements())?.to_vec();
    let q = read_slice(at, QUALITY_RECORD + 1)?;
    let baseline = if q[0] == 1.0 { crate::remesh::QualityCheck::from_record(&q[1..]) } else { None };
    let n = read_usize(at)?;
    let ties = read_slice(at, n.checked_mul(TIE_RECORD).ok_or("a tie count out of range")?)?.chunks_exact(TIE_RECORD).map(tie_from_record).collect();
    let n = read_usize(at)?;
    let tied = read_slice(at, n.checked_mul(2).ok_or("a tied count out of range")?)?.chunks_exact(2).map(|r| (r[0] as usize, r[1] as usize)).collect();
    Ok((g, Arrival { body, nodal, elements, baseline, ties, tied }))
}
