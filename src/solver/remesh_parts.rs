//! Re-meshing on the processes' parts of a distributed model ([`super::remeshing`] for the
//! whole model). The processes agree on the particles to re-mesh (every process's own that ask
//! for it, the worst first); each owner re-meshes its own in the current state and carries
//! their states over, exactly as the whole model's re-mesh does; the bodies' new sizes are
//! all-gathered (four numbers a body) into the layout, so that every process numbers the
//! whole model alike; and every part is grown again from its own bodies, with the re-meshed
//! ghosts sent again by their owners ([`crate::parallel::part::RankPart::regrow_with`]). Rank 0
//! gets the new meshes with the others at the next output step ([`Simulation::gather`]). No
//! process holds the whole model.
//!
//! The new meshes and their states are those of the whole model's re-mesh (a particle's new
//! mesh depends on its own state and on the nodes it holds, computed before any is re-meshed),
//! so a run on parts re-meshes as the serial run does. Where a new boundary cannot be taken
//! (it touches or crosses another particle or a wall), the particles named are left out and the
//! others re-meshed again; when the failure names none, each particle is tried on its own.

use super::remeshing::{carry_ties, Remeshed};
use super::snapshot::OwnState;
use super::{Phase, Simulation};
use crate::assembly::ElementFields;
use crate::parallel::part::Resized;
use std::collections::HashMap;
use std::sync::Arc;

/// Why re-meshing particles on the parts failed.
enum Failed {
    /// These particles (the whole model's bodies) could not be re-meshed.
    Bodies(Vec<usize>),
    /// Something that names no particle.
    Unnamed(String),
}

impl Simulation {
    /// On a part: re-mesh the whole model's bodies `list` (every process's list alike, the
    /// worst first; each is re-meshed by its owner) within `[remesh] max_remeshes`, then
    /// re-equilibrate once. Returns how many were re-meshed (every process alike). Collective.
    pub(super) fn remesh_parts(&mut self, list: &[usize]) -> usize {
        let left = self.model.remesh.max_remeshes.saturating_sub(self.run.total_remeshes);
        if list.len() > left {
            tracing::warn!(max = self.model.remesh.max_remeshes, "the largest number of re-meshes (remesh.max_remeshes) is reached: no more re-meshing");
        }
        let mut tried: Vec<usize> = list.iter().copied().take(left).collect();
        let mut done = 0;
        while !tried.is_empty() {
            let attempt = {
                let _t = self.clock.scope(Phase::Remesh);
                self.try_remesh_part(&tried)
            };
            match attempt {
                Ok(n) => {
                    done += n;
                    break;
                }
                Err(Failed::Bodies(failed)) => {
                    for g in &failed {
                        if self.owns_body(*g) {
                            tracing::warn!(body = g, "re-meshing failed: the particle keeps its mesh");
                        }
                    }
                    tried.retain(|g| !failed.contains(g));
                }
                Err(Failed::Unnamed(e)) => {
                    tracing::warn!(%e, bodies = ?tried, "re-meshing the particles together failed: each on its own");
                    if tried.len() > 1 {
                        for g in tried {
                            let attempt = {
                                let _t = self.clock.scope(Phase::Remesh);
                                self.try_remesh_part(&[g])
                            };
                            match attempt {
                                Ok(n) => done += n,
                                Err(Failed::Bodies(_)) => tracing::warn!(body = g, "re-meshing failed: the particle keeps its mesh"),
                                Err(Failed::Unnamed(e)) => tracing::warn!(body = g, %e, "re-meshing failed: the particle keeps its mesh"),
                            }
                        }
                    }
                    break;
                }
            }
        }
        if done > 0 {
            // (the new element counts may call for new owners: moved before the solve)
            self.rebalance_parts();
            self.reequilibrate_after_remesh();
        }
        done
    }

    /// Whether this process owns the whole model's body `g` (always without a part).
    fn owns_body(&self, g: usize) -> bool {
        self.sys.part.as_ref().is_none_or(|p| p.bodies[..p.own_bodies].binary_search(&g).is_ok())
    }

    /// On a part: whether the whole model's element `e` (an element that inverted) lies in a
    /// particle that re-meshing may help — its owner's answer ([`Self::mesh_is_poor`], no
    /// [`crate::model::Model::remesh_constraint`]), known to every process — and that body.
    /// Collective.
    pub(super) fn part_body_to_remesh(&self, e: usize) -> Option<usize> {
        let p = self.sys.part.as_ref()?;
        let g = p.layout.element_body(e);
        let own = g.and_then(|g| p.bodies[..p.own_bodies].binary_search(&g).ok());
        let poor = own.is_some_and(|k| self.model.remesh_constraint(k).is_none() && self.mesh_is_poor(k));
        if self.sys.any(poor) {
            g
        } else {
            None
        }
    }

    /// One attempt at re-meshing the whole model's bodies `tried` on the parts: every owner
    /// re-meshes its own, the parts are grown again on the new layout, and the new boundaries
    /// are checked. On success this simulation is the new one and the count is returned; on a
    /// failure it is unchanged. Collective.
    fn try_remesh_part(&mut self, tried: &[usize]) -> Result<usize, Failed> {
        let Some(p) = self.sys.part.as_ref() else { return Err(Failed::Unnamed("not a part".into())) };
        let comm = p.nodes.comm_arc();
        let own_bodies = p.own_bodies;
        let old_bodies = p.bodies.clone();
        let (layout, reach) = (Arc::clone(&p.layout), p.reach);
        // this process's own bodies to re-mesh (local index, whole body), ascending
        let mut own: Vec<(usize, usize)> = tried.iter().filter_map(|&g| old_bodies[..own_bodies].binary_search(&g).ok().map(|k| (k, g))).collect();
        own.sort_unstable();
        // (the held nodes of every body before any is re-meshed, as the whole model's re-mesh)
        let holds: Vec<Vec<usize>> = own.iter().map(|&(k, _)| self.contact_nodes(k)).collect();
        let mut made: Vec<(usize, usize, Remeshed)> = Vec::new();
        let mut failed_here = Vec::new();
        for (&(k, g), hold) in own.iter().zip(&holds) {
            let h = self.model.remesh.mesh_size.unwrap_or(self.model.bodies[k].mesh_size);
            // (a particle held by boundary conditions, loads or output groups is not re-meshed)
            let made_here = match self.model.remesh_constraint(k) {
                Some(what) => Err(super::SolveError::Remesh { body: g, reason: format!("held by {what}") }),
                None => self.remeshed_body(k, h, hold),
            };
            match made_here {
                Ok(r) => made.push((k, g, r)),
                Err(e) => {
                    tracing::debug!(body = g, %e, "re-meshing failed");
                    failed_here.push(g);
                }
            }
        }
        // every process's outcome: (body, made, nodes, elements, boundary edges)
        let mine: Vec<f64> = made
            .iter()
            .map(|(_, g, r)| [*g as f64, 1.0, r.mesh.n_nodes() as f64, r.mesh.n_elements() as f64, r.mesh.boundary.len() as f64])
            .chain(failed_here.iter().map(|&g| [g as f64, 0.0, 0.0, 0.0, 0.0]))
            .flatten()
            .collect();
        let all = comm.all_gather_varcount(&mine);
        let failed: Vec<usize> = all.chunks_exact(5).filter(|r| r[1] == 0.0).map(|r| r[0] as usize).collect();
        if !failed.is_empty() {
            return Err(Failed::Bodies(failed));
        }
        let mut resized: Vec<Resized> = all.chunks_exact(5).map(|r| (r[0] as usize, r[2] as usize, r[3] as usize, r[4] as usize)).collect();
        resized.sort_unstable();
        if resized.is_empty() {
            return Ok(0);
        }
        let new_layout = Arc::new(layout.resized(&resized));
        let stale: Vec<usize> = resized.iter().map(|r| r.0).collect();

        // its own bodies with their new meshes, and their state (the others' as the whole
        // model's re-mesh keeps it: displacements and every element field)
        let model = self.model.with_body_meshes(made.iter().map(|(k, _, r)| (*k, r.mesh.clone())).collect());
        // (agreed before the collective calls that follow)
        if self.sys.any(model.is_err()) {
            return Err(Failed::Unnamed(model.err().map_or_else(|| "a new mesh on another process".into(), |e| e.to_string())));
        }
        let Ok(mut model) = model else { return Err(Failed::Unnamed("a new mesh".into())) };
        // (the whole model's largest reference coordinate: a re-meshed body's reference is
        // its current configuration)
        let extent = model.bodies[..own_bodies].iter().flat_map(|b| &model.x0[b.node_offset..b.node_offset + b.mesh.n_nodes()]).fold(0.0_f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
        let extent = comm.max(extent);
        if let Some(w) = model.whole.as_mut() {
            w.extent = extent;
        }
        let own_nodes = model.bodies.get(own_bodies).map_or(model.n_nodes(), |b| b.node_offset);
        let own_elements = model.bodies.get(own_bodies).map_or(model.elements.len(), |b| b.elem_offset);
        let (mut u, mut u_prev) = (vec![0.0; 2 * own_nodes], vec![0.0; 2 * own_nodes]);
        let mut fields = ElementFields::new(own_elements);
        let (mut lambda, mut j0) = (vec![0.0; own_elements], vec![1.0; own_elements]);
        for k in 0..own_bodies {
            let (ob, nb) = (&self.model.bodies[k], &model.bodies[k]);
            if let Some((_, _, r)) = made.iter().find(|m| m.0 == k) {
                for (i, v) in r.increment.values.iter().enumerate() {
                    u_prev[2 * nb.node_offset + i] = -v;
                }
                let e = nb.elem_offset..nb.elem_offset + nb.mesh.n_elements();
                fields.states[e.clone()].copy_from_slice(&r.moved.state.states);
                j0[e.clone()].copy_from_slice(&r.moved.state.j0);
                lambda[e].copy_from_slice(&r.moved.state.lambda);
                continue;
            }
            let (src, dst, n) = (2 * ob.node_offset, 2 * nb.node_offset, 2 * ob.mesh.n_nodes());
            u[dst..dst + n].copy_from_slice(&self.sol.u[src..src + n]);
            u_prev[dst..dst + n].copy_from_slice(&self.u_prev[src..src + n]);
            let (src, dst, n) = (ob.elem_offset, nb.elem_offset, ob.mesh.n_elements());
            let g = &self.sol.fields;
            fields.states[dst..dst + n].copy_from_slice(&g.states[src..src + n]);
            fields.sig[dst..dst + n].copy_from_slice(&g.sig[src..src + n]);
            fields.pressure[dst..dst + n].copy_from_slice(&g.pressure[src..src + n]);
            fields.theta[dst..dst + n].copy_from_slice(&g.theta[src..src + n]);
            fields.alpha[dst..dst + n].copy_from_slice(&g.alpha[src..src + n]);
            j0[dst..dst + n].copy_from_slice(&self.sol.j0[src..src + n]);
            lambda[dst..dst + n].copy_from_slice(&self.sol.lambda[src..src + n]);
        }
        let baseline = self.run.remesh_baseline[..own_bodies].to_vec();
        let own_state = OwnState { u, u_prev, dynamics: None, fields, lambda, j0, baseline };

        // the ties (on its own nodes) through the node map from this part to the new one: a
        // body not re-meshed keeps its nodes' order, a re-meshed one (its own or a ghost)
        // the nodes its new mesh keeps where they were, bit for bit
        let x_old = self.coords(&self.sol.u);
        let ties = |sim: &Simulation| {
            let (Some(ob), Some(nb), Some(np)) = (self.barrier.as_ref(), sim.barrier.as_ref(), sim.sys.part.as_ref()) else { return Ok((Vec::new(), Vec::new())) };
            let new_body: HashMap<usize, usize> = np.bodies.iter().enumerate().map(|(k, &g)| (g, k)).collect();
            let mut map = vec![None; self.model.n_nodes()];
            for (k, &g) in old_bodies.iter().enumerate() {
                let Some(&kn) = new_body.get(&g) else { continue };
                let (obody, nbody) = (&self.model.bodies[k], &sim.model.bodies[kn]);
                let (o0, n0) = (obody.node_offset, nbody.node_offset);
                if stale.binary_search(&g).is_ok() {
                    let at: HashMap<[u64; 2], usize> = (0..nbody.mesh.n_nodes()).map(|i| (sim.model.x0[n0 + i].map(f64::to_bits), n0 + i)).collect();
                    for i in 0..obody.mesh.n_nodes() {
                        map[o0 + i] = at.get(&x_old[o0 + i].map(f64::to_bits)).copied();
                    }
                } else {
                    for i in 0..obody.mesh.n_nodes() {
                        map[o0 + i] = Some(n0 + i);
                    }
                }
            }
            let (ties, tied) = carry_ties(&ob.contact.segments, &nb.contact.segments, &ob.contact.ties, &map);
            if ties.len() < ob.contact.ties.len() {
                tracing::debug!(dropped = ob.contact.ties.len() - ties.len(), "ties on a re-meshed particle's moved boundary dropped");
            }
            Ok((ties, tied))
        };
        let mut sim = self.grown(&model, own_state, &old_bodies[..own_bodies], &new_layout, &stale, self.time, self.spec, reach, ties).map_err(Failed::Unnamed)?;

        // the new boundaries: apart from everything (the barrier at the new state was
        // evaluated when the state was set) and crossing nothing
        let x_new = sim.coords(&sim.sol.u);
        let walls = sim.model.wall_planes(sim.sol.time);
        let np: Vec<usize> = sim.sys.part.as_ref().map_or_else(Vec::new, |p| p.bodies[..p.own_bodies].to_vec());
        let crossed: Vec<f64> = match sim.barrier.as_ref() {
            Some(b) => made.iter().filter(|(_, g, _)| np.binary_search(g).is_ok_and(|k| b.contact.crossings_of(&x_new, &walls, Some(k)) > 0)).map(|(_, g, _)| *g as f64).collect(),
            None => Vec::new(),
        };
        let crossed = comm.all_gather_varcount(&crossed);
        if !crossed.is_empty() {
            return Err(Failed::Bodies(crossed.iter().map(|&g| g as usize).collect()));
        }

        // taken: the run's counts and the new meshes' quality as their baselines
        sim.interrupt = self.interrupt.clone();
        sim.clock = self.clock.clone();
        sim.run.total_remeshes += resized.len();
        for (_, g, r) in &made {
            let Some(k) = np.binary_search(g).ok() else { continue };
            let body = &sim.model.bodies[k];
            let q = crate::remesh::check_quality(&body.mesh, &body.mesh.nodes, &sim.model.remesh.limits).ok().filter(|q| q.needs_remesh);
            if let Some(q) = &q {
                tracing::warn!(body = g, violated = ?q.violated, "the new mesh itself crosses the quality limits (boundary points are kept); re-meshed again only once it is worse");
            }
            sim.run.remesh_baseline[k] = q;
            tracing::info!(time = sim.sol.time, body = g, name = %body.name, elements = body.mesh.n_elements(), area_change = r.moved.area.relative_change, "particle re-meshed");
        }
        *self = sim;
        Ok(resized.len())
    }
}
