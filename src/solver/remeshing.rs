//! Re-meshing a running simulation ([`crate::remesh`]): a particle whose mesh crosses the
//! quality limits after a step, or whose element inverts during one, gets a new mesh in its
//! current configuration; its state is transferred, the simulation is rebuilt for the new
//! numbering (the other particles keep their solution, the contact its history), and the
//! state is brought back into equilibrium.

use super::{NewtonFailure, Phase, Simulation, SolveError};
use crate::material::TimeIncrement;
use std::collections::HashMap;

/// With the barrier contact a re-mesh keeps where they are the boundary nodes of a particle
/// within d̂ + `HOLD_REACH` h of another particle or a wall (h its contact length): the new
/// boundary's free points move by at most the coarsening tolerance 0.05 h plus the small
/// offset that gives the area back ([`crate::remesh::remesh_particle_keeping`]), so twice that
/// tolerance leaves them short of what they face. Without it the offset pushed nodes pressed
/// against a wall through it (measured on the 5.2.1 job with `[remesh]`: 0.16 mm behind the
/// bottom wall, every re-mesh refused and the run jammed at solid ratio 0.908).
pub const HOLD_REACH: f64 = 0.1;

impl Simulation {
    /// Re-mesh body `b` in its current configuration with elements of size about `h` (mm)
    /// and carry the solution over ([`crate::remesh`]): the new mesh keeps every boundary point
    /// of the old one (area and contact surface unchanged), its reference configuration is the
    /// current one (u = 0 on its nodes, the last step's increment moved by nodal transfer so
    /// that the inertial stabilisation keeps its anchor), and the material states, initial
    /// volume ratios and element pressures are transferred ([`crate::remesh::transfer_body`]).
    /// Everything else is rebuilt for the new numbering; the other bodies keep their solution.
    /// The run's counters, energies and initial areas (for the volume error) are kept.
    /// The contact history of every pair (stick anchors, augmented-Lagrangian and Lagrange
    /// multipliers, wall histories) and the tributary lengths of the kept contact zones are
    /// carried to the new numbering ([`crate::contact::ContactProblem::carry_history`]).
    ///
    /// # Errors
    /// [`SolveError::Remesh`] for an implicit dynamic analysis (velocities and accelerations
    /// are not transferred), a body held by boundary conditions, loads or output groups, or a
    /// boundary the mesher refuses.
    pub fn remesh_body(&mut self, b: usize, h: f64) -> Result<crate::remesh::BodyTransfer, SolveError> {
        let hold = self.contact_nodes(b);
        self.remesh_body_holding(b, h, &hold)
    }

    /// Re-mesh the particles `bodies` now, each as [`Self::remesh_body`] does (in the current
    /// state, its contact zones held, the quality limits of `[remesh]` not asked), then
    /// re-equilibrate once. On a process's part of a distributed model `bodies` are the whole
    /// model's (every process's list alike) and each is re-meshed by its owner. A particle
    /// that cannot be re-meshed keeps its mesh (a warning says why), and `[remesh]
    /// max_remeshes` holds. Returns how many were re-meshed. Collective on a part.
    pub fn remesh_bodies(&mut self, bodies: &[usize]) -> usize {
        self.remesh_and_rebalance_all(bodies)
    }

    /// The boundary nodes of body `b` (numbered within the body) in contact, as slave or
    /// master, at the last evaluation of the committed state; with the barrier contact, those
    /// within d̂ + [`HOLD_REACH`] h (h the particle's contact length) of another particle or
    /// a wall at the committed state ([`crate::contact::barrier_problem::BarrierContact::near_nodes`]).
    pub(super) fn contact_nodes(&mut self, b: usize) -> Vec<usize> {
        let Some(body) = self.model.bodies.get(b) else { return Vec::new() };
        let (n0, nn) = (body.node_offset, body.mesh.n_nodes());
        if self.barrier.is_some() {
            let x = self.coords(&self.sol.u);
            let walls = self.model.wall_planes(self.sol.time);
            let h = body.contact_h;
            let Some(c) = self.barrier.as_mut().map(|r| &mut r.contact) else { return Vec::new() };
            let reach = c.dhat + HOLD_REACH * h;
            return c.near_nodes(&x, &walls, b, reach).into_iter().filter_map(|n| n.checked_sub(n0).filter(|&k| k < nn)).collect();
        }
        match self.contact.as_ref() {
            Some(c) => (0..nn)
                .filter(|&k| {
                    let g = n0 + k;
                    c.nodal.status.get(g).is_some_and(|&s| s > 0) || c.nodal.force.get(g).is_some_and(|f| f[0] != 0.0 || f[1] != 0.0)
                })
                .collect(),
            None => Vec::new(),
        }
    }

    /// Body `b`'s new mesh in the current state and its state carried over (see
    /// [`Self::remesh_body`]), the simulation itself unchanged.
    pub(super) fn remeshed_body(&self, b: usize, h: f64, hold: &[usize]) -> Result<Remeshed, SolveError> {
        let fail = |reason: String| SolveError::Remesh { body: b, reason };
        if self.dynamics.is_some() {
            return Err(fail("implicit dynamics: velocities and accelerations are not transferred".into()));
        }
        let body = self.model.bodies.get(b).ok_or_else(|| fail("no such body".into()))?;
        let (n0, nn) = (body.node_offset, body.mesh.n_nodes());
        let (e0, ne) = (body.elem_offset, body.mesh.n_elements());
        let x = self.coords(&self.sol.u);
        let (xb0, xb) = (&self.model.x0[n0..n0 + nn], &x[n0..n0 + nn]);
        let new_mesh = crate::remesh::remesh_particle_keeping(&body.mesh, xb, h, hold).map_err(|e| fail(e.to_string()))?;
        // An incompressible body carries its element pressures p = λ + κ (Θ − 1) whole in λ,
        // with j₀ := 1 on the new mesh (Θ = 1 there): with κ = `incompressible_penalty` · G the
        // part κ (Θ − 1) would turn the smoothing of the element volume ratios Θ (equal to 1
        // within `volume_tol`, with the element-to-element scatter of Q1/P0) into pressure
        // errors of the order of the stresses themselves (measured: the re-equilibration
        // started at a relative residual of 1.0 and took 24 iterations on one asphalt octagon).
        let incompressible = (e0..e0 + ne).all(|e| self.incompressible[e]);
        let pressure_like = if incompressible { &self.sol.fields.pressure } else { &self.sol.lambda };
        let old_state = crate::remesh::BodyState {
            states: self.sol.fields.states[e0..e0 + ne].to_vec(),
            j0: self.sol.j0[e0..e0 + ne].to_vec(),
            lambda: pressure_like[e0..e0 + ne].to_vec(),
        };
        // the last step's increment u_n − u_{n−1} of the body goes to the new nodes too
        let incr = crate::remesh::NodalField { n_comp: 2, values: (2 * n0..2 * (n0 + nn)).map(|d| self.sol.u[d] - self.u_prev[d]).collect() };
        let mut moved = crate::remesh::transfer_body(&body.mesh, xb0, xb, &old_state, &[incr], &new_mesh).map_err(|e| fail(e.to_string()))?;
        let increment = moved.nodal.pop().ok_or_else(|| fail("the increment was not transferred".into()))?;
        if incompressible {
            moved.state.j0.iter_mut().for_each(|j| *j = 1.0);
        }
        // the old boundary nodes the new mesh keeps where they are, bit for bit (the held
        // contact zones): old node of the body → its number in the new mesh
        let bits = |p: [f64; 2]| p.map(f64::to_bits);
        let new_boundary: HashMap<[u64; 2], usize> = new_mesh.boundary.iter().flatten().map(|&k| (bits(new_mesh.nodes[k]), k)).collect();
        let kept: Vec<Option<usize>> = xb.iter().map(|&p| new_boundary.get(&bits(p)).copied()).collect();
        Ok(Remeshed { mesh: new_mesh, moved, increment, kept })
    }

    /// [`Self::remesh_body`] with the boundary nodes `hold` (numbered within the body) kept
    /// where they are (see [`crate::remesh::remesh_particle_keeping`]).
    fn remesh_body_holding(&mut self, b: usize, h: f64, hold: &[usize]) -> Result<crate::remesh::BodyTransfer, SolveError> {
        let fail = |reason: String| SolveError::Remesh { body: b, reason };
        let Remeshed { mesh: new_mesh, moved, increment: incr_new, kept } = self.remeshed_body(b, h, hold)?;
        let x = self.coords(&self.sol.u);
        let model = self.model.with_body_mesh(b, new_mesh).map_err(|e| fail(e.to_string()))?;
        // the owners are kept unless the new element counts unbalance them too much
        let owners = self.sys.par.as_ref().map(|p| p.body_owner.as_slice());
        let mut next = Simulation::build(model, self.time, self.spec, self.sys.comm.clone(), Some((owners, &self.sys.partition)))?;
        next.interrupt = self.interrupt.clone();
        // the solution: other bodies renumbered, the re-meshed body from the transfer
        for (c, (ob, nb)) in self.model.bodies.iter().zip(&next.model.bodies).enumerate() {
            if c == b {
                for k in 0..nb.mesh.n_nodes() {
                    for d in 0..2 {
                        next.u_prev[2 * (nb.node_offset + k) + d] = -incr_new.values[2 * k + d];
                    }
                }
                let r = nb.elem_offset..nb.elem_offset + nb.mesh.n_elements();
                next.sol.fields.states[r.clone()].copy_from_slice(&moved.state.states);
                next.sol.j0[r.clone()].copy_from_slice(&moved.state.j0);
                next.sol.lambda[r].copy_from_slice(&moved.state.lambda);
                continue;
            }
            let (src, dst, n) = (2 * ob.node_offset, 2 * nb.node_offset, 2 * ob.mesh.n_nodes());
            next.sol.u[dst..dst + n].copy_from_slice(&self.sol.u[src..src + n]);
            next.u_prev[dst..dst + n].copy_from_slice(&self.u_prev[src..src + n]);
            let (src, dst, n) = (ob.elem_offset, nb.elem_offset, ob.mesh.n_elements());
            // (every field, the element pressures too: a particle re-meshed after this one in
            // the same step transfers its pressures from them — they were left at zero, and the
            // 16 incompressible octagons of the 5.2.1 job re-meshed together then started their
            // re-equilibration at a relative residual of 1.0 instead of 0.42)
            let (f, g) = (&mut next.sol.fields, &self.sol.fields);
            f.states[dst..dst + n].copy_from_slice(&g.states[src..src + n]);
            f.sig[dst..dst + n].copy_from_slice(&g.sig[src..src + n]);
            f.pressure[dst..dst + n].copy_from_slice(&g.pressure[src..src + n]);
            f.theta[dst..dst + n].copy_from_slice(&g.theta[src..src + n]);
            f.alpha[dst..dst + n].copy_from_slice(&g.alpha[src..src + n]);
            next.sol.j0[dst..dst + n].copy_from_slice(&self.sol.j0[src..src + n]);
            next.sol.lambda[dst..dst + n].copy_from_slice(&self.sol.lambda[src..src + n]);
        }
        // (the default contact penalty 10 E/h and the stabilisation springs ζ E a/h² keep the
        // particle's own h, `Body::contact_h`, which `with_body_mesh` keeps)
        let x_new = next.coords(&next.sol.u);
        // old node → new node: the other bodies' all, the re-meshed body's that the new mesh
        // keeps where they were
        let mut node_map = vec![None; self.model.x0.len()];
        for (c, (ob, nb)) in self.model.bodies.iter().zip(&next.model.bodies).enumerate() {
            for k in 0..ob.mesh.n_nodes() {
                node_map[ob.node_offset + k] = if c == b { kept[k].map(|m| nb.node_offset + m) } else { Some(nb.node_offset + k) };
            }
        }
        if let (Some(old), Some(new)) = (self.contact.as_ref(), next.contact.as_mut()) {
            // the contact history of the whole assembly (stick anchors, multipliers, wall
            // histories) goes to the new numbering, not only the re-meshed body's
            let carried = new.carry_history(old, &node_map, [&self.model.x0, &x], [&next.model.x0, &x_new]);
            tracing::debug!(body = b, ?carried, "contact history carried over the re-mesh");
        }
        next.sol.time = self.sol.time;
        if let Some(old) = self.barrier.as_ref() {
            // the barrier's state (κ, the descent, the ties in the new numbering), then the new
            // boundary checked: apart from every other particle and wall, crossing none
            let mut state = old.state();
            let new_segments = next.barrier.as_ref().map_or(&[][..], |n| &n.contact.segments[..]);
            (state.ties, state.tied) = carry_ties(&old.contact.segments, new_segments, &state.ties, &node_map);
            let dropped = old.contact.ties.len() - state.ties.len();
            if dropped > 0 {
                tracing::debug!(body = b, dropped, "ties on the re-meshed particle's moved boundary dropped");
            }
            next.restore_barrier(state).map_err(|e| fail(format!("the new boundary: {e}")))?;
            let walls = next.model.wall_planes(next.sol.time);
            let crossed = next.barrier.as_ref().map_or(0, |n| n.contact.crossings_of(&x_new, &walls, Some(b)));
            if crossed > 0 {
                return Err(fail(format!("the new boundary: {crossed} boundary node(s) inside another particle or behind a wall")));
            }
        }
        // the run's counters, energies, step size and references go on (the volume error
        // keeps the initial areas)
        next.run = self.run.clone();
        next.springs.energy = self.springs.energy;
        next.clock = self.clock.clone();
        *self = next;
        Ok(moved)
    }

    /// After a converged step (`[remesh] enabled`): re-mesh every particle whose mesh, in the
    /// current configuration, crosses the quality limits (the worst first), then re-equilibrate
    /// once. Particles held by boundary conditions, loads or output groups are never
    /// re-meshed. Returns the number of particles re-meshed.
    pub(super) fn remesh_after_step(&mut self) -> usize {
        if !self.model.remesh.enabled {
            return 0;
        }
        let limits = self.model.remesh.limits;
        let x = self.coords(&self.sol.u);
        // (smallest scaled Jacobian, body) of every particle that asks for a new mesh
        let mut worst: Vec<(f64, usize)> = Vec::new();
        // (a part: its own bodies, named by the whole model's numbers)
        let (n_own, names) = match &self.sys.part {
            Some(p) => (p.own_bodies, p.bodies.clone()),
            None => (self.model.bodies.len(), (0..self.model.bodies.len()).collect()),
        };
        for (b, body) in self.model.bodies.iter().enumerate().take(n_own) {
            if self.model.remesh_constraint(b).is_some() {
                continue;
            }
            let xb = &x[body.node_offset..body.node_offset + body.mesh.n_nodes()];
            match crate::remesh::check_quality(&body.mesh, xb, &limits) {
                Ok(q) if q.needs_remesh => {
                    let worse = match &self.run.remesh_baseline[b] {
                        None => true,
                        Some(base) => {
                            q.scaled_jacobian.value < 0.9 * base.scaled_jacobian.value
                                || q.aspect_ratio.value > 1.1 * base.aspect_ratio.value
                                || q.min_angle_deg.value < 0.9 * base.min_angle_deg.value
                        }
                    };
                    if worse {
                        tracing::debug!(body = names[b], violated = ?q.violated, scaled_jacobian = q.scaled_jacobian.value, aspect_ratio = q.aspect_ratio.value, min_angle = q.min_angle_deg.value, "quality limits crossed");
                        worst.push((q.scaled_jacobian.value, names[b]));
                    }
                }
                Ok(_) => {}
                Err(e) => tracing::warn!(body = b, %e, "quality check failed"),
            }
        }
        // every particle that asks for it, the worst first, then one re-equilibration: on a
        // regular grid the particles cross the limits together, and re-meshing one of them
        // while its neighbours keep their distorted corner elements perturbs those elements at
        // the brink of inversion (measured on the 16 octagons of 5.2.1 at φ 0.906: the next
        // step then failed at every step size, 25 Newton iterations stalling on the corner
        // elements of the other particles)
        if let Some(p) = &self.sys.part {
            // every process's, to every process (in body order, as the whole model's list)
            let mine: Vec<f64> = worst.iter().flat_map(|&(q, g)| [q, g as f64]).collect();
            let all = p.nodes.comm().all_gather_varcount(&mine);
            worst = all.chunks_exact(2).map(|r| (r[0], r[1] as usize)).collect();
            worst.sort_by_key(|w| w.1);
        }
        worst.sort_by(|a, b| a.0.total_cmp(&b.0));
        let bodies: Vec<usize> = worst.iter().map(|&(_, b)| b).collect();
        self.remesh_and_rebalance_all(&bodies)
    }

    /// Whether body `b`'s mesh in the last converged state is within a factor 2 of the quality
    /// limits (scaled Jacobian below twice its limit, aspect ratio above half its limit or
    /// smallest angle below twice its limit): only then is an inverted element answered by a
    /// re-mesh rather than a cut-back.
    pub(super) fn mesh_is_poor(&self, b: usize) -> bool {
        let body = &self.model.bodies[b];
        let x = self.coords(&self.sol.u);
        let xb = &x[body.node_offset..body.node_offset + body.mesh.n_nodes()];
        let l = self.model.remesh.limits;
        let relaxed = crate::remesh::QualityLimits {
            min_scaled_jacobian: (2.0 * l.min_scaled_jacobian).min(0.99),
            max_aspect_ratio: (0.5 * l.max_aspect_ratio).max(1.01),
            min_angle_deg: (2.0 * l.min_angle_deg).min(89.0),
        };
        crate::remesh::check_quality(&body.mesh, xb, &relaxed).is_ok_and(|q| q.needs_remesh)
    }

    /// Re-mesh body `b` in the current state (at `[remesh] mesh_size` or its own mesh size),
    /// then re-equilibrate the transferred state at the same time and wall positions. A body
    /// whose re-mesh fails keeps its mesh (a warning says why); a failed re-equilibration leaves
    /// the transferred state for the next step to balance. Returns whether it was re-meshed.
    pub(super) fn remesh_and_rebalance(&mut self, b: usize) -> bool {
        self.remesh_and_rebalance_all(&[b]) > 0
    }

    /// [`Self::remesh_and_rebalance`] for several bodies: each is re-meshed, then the state is
    /// re-equilibrated once. Returns how many were re-meshed.
    ///
    /// On a part `bodies` are the whole model's (every process's list alike) and each is
    /// re-meshed by its owner ([`Self::remesh_parts`]).
    fn remesh_and_rebalance_all(&mut self, bodies: &[usize]) -> usize {
        if self.sys.part.is_some() {
            return self.remesh_parts(bodies);
        }
        let mut done = 0;
        // the contact nodes of every body before the first rebuild (a rebuilt contact problem
        // starts without them; a body's own node numbers do not change when another one is
        // re-meshed)
        let holds: Vec<Vec<usize>> = bodies.iter().map(|&b| self.contact_nodes(b)).collect();
        for (&b, hold) in bodies.iter().zip(&holds) {
            if self.run.total_remeshes >= self.model.remesh.max_remeshes {
                tracing::warn!(max = self.model.remesh.max_remeshes, "the largest number of re-meshes (remesh.max_remeshes) is reached: no more re-meshing");
                break;
            }
            let h = self.model.remesh.mesh_size.unwrap_or(self.model.bodies[b].mesh_size);
            // (the rebuild's set-up is not counted in any other phase)
            let moved = {
                let _t = self.clock.scope(Phase::Remesh);
                self.remesh_body_holding(b, h, hold)
            };
            let moved = match moved {
                Ok(m) => m,
                Err(e) => {
                    tracing::warn!(body = b, %e, "re-meshing failed: the particle keeps its mesh");
                    continue;
                }
            };
            self.run.total_remeshes += 1;
            done += 1;
            let body = &self.model.bodies[b];
            let q = crate::remesh::check_quality(&body.mesh, &body.mesh.nodes, &self.model.remesh.limits).ok().filter(|q| q.needs_remesh);
            if let Some(q) = &q {
                tracing::warn!(body = b, violated = ?q.violated, "the new mesh itself crosses the quality limits (boundary points are kept); re-meshed again only once it is worse");
            }
            self.run.remesh_baseline[b] = q;
            tracing::info!(time = self.sol.time, body = b, name = %body.name, elements = body.mesh.n_elements(), area_change = moved.area.relative_change, "particle re-meshed");
        }
        if done > 0 {
            self.reequilibrate_after_remesh();
        }
        done
    }

    /// After particles were re-meshed: [`Self::equilibrate`], a failure left for the next step
    /// to balance (a warning says so).
    pub(super) fn reequilibrate_after_remesh(&mut self) {
        let _t = self.clock.scope(Phase::Reequilibration);
        match self.equilibrate() {
            Ok(its) => tracing::debug!(iterations = its, "re-equilibrated after re-meshing"),
            Err(e) => tracing::warn!(%e, "re-equilibration after re-meshing failed: the next step starts from the transferred state"),
        }
    }

    /// Bring the state back into equilibrium at the current time and wall positions (after a
    /// re-mesh: the transferred stresses are not exactly balanced on the new mesh). A Newton
    /// solve with Δt = 0 (no creep, the springs anchored where they are), committed in place:
    /// time, step counter and the last increment (for the next prediction) are kept. Returns
    /// the Newton iterations.
    pub fn equilibrate(&mut self) -> Result<usize, NewtonFailure> {
        if self.dynamics.is_some() {
            return Err(NewtonFailure::Linear("re-equilibration is for quasi-static analyses".into()));
        }
        let inc = TimeIncrement { time: self.sol.time, dt: 0.0 };
        let snapshot = self.contact.as_ref().map(|c| c.snapshot());
        let (stab_all, stab_viscous) = (self.springs.all, self.springs.viscous);
        self.springs.viscous = true;
        let result = self.prepare_contact(0.0).and_then(|()| self.release_imbalance(inc));
        self.sys.eq_offset.clear();
        self.springs.all = stab_all;
        self.springs.viscous = stab_viscous;
        let trial = match result {
            Ok(t) => t,
            Err(e) => {
                if let (Some(c), Some(snap)) = (self.contact.as_mut(), snapshot) {
                    c.restore(snap);
                }
                return Err(e);
            }
        };
        self.springs.energy += self.springs.work(&trial.u, &self.sol.u);
        if self.contact.is_some() {
            let x = self.coords(&trial.u);
            if let Some(c) = self.contact.as_mut() {
                c.commit(&x);
            }
        }
        for d in 0..self.u_prev.len() {
            self.u_prev[d] += trial.u[d] - self.sol.u[d];
        }
        self.sol.u = trial.u;
        self.sol.lambda = trial.lambda;
        std::mem::swap(&mut self.sol.fields, &mut self.sys.trial_fields);
        self.run.total_iterations += trial.iterations;
        Ok(trial.iterations)
    }
}

/// A body's new mesh and its state carried over ([`Simulation::remeshed_body`]).
pub(super) struct Remeshed {
    pub mesh: crate::mesh::Mesh,
    /// The material state on the new mesh.
    pub moved: crate::remesh::BodyTransfer,
    /// The last step's increment u_n − u_{n−1} at the new nodes.
    pub increment: crate::remesh::NodalField,
    /// Each old node's number in the new mesh where it is kept, bit for bit (the held contact
    /// zones).
    pub kept: Vec<Option<usize>>,
}

/// The ties `ties` (cohering particles) of the contact whose boundary edges were `old` in the
/// numbering of a re-meshed model whose edges are `new`, with `node_map` the old node → new
/// node: a tie goes over when its node and its edge's two ends are kept (the re-meshed
/// particle keeps its contact zones' nodes where they were, and consecutive kept nodes stay an
/// edge of the new boundary); the others are dropped. Returns the ties and the (node, body)
/// pairs they hold, sorted.
pub(super) fn carry_ties(old: &[crate::contact::Segment], new: &[crate::contact::Segment], ties: &[crate::contact::barrier_problem::Tie], node_map: &[Option<usize>]) -> (Vec<crate::contact::barrier_problem::Tie>, Vec<(usize, usize)>) {
    let edges: HashMap<[usize; 2], usize> = new.iter().enumerate().map(|(s, seg)| (seg.nodes, s)).collect();
    let map = |n: usize| node_map.get(n).copied().flatten();
    let mut out = Vec::with_capacity(ties.len());
    let mut tied = Vec::with_capacity(ties.len());
    for t in ties {
        let Some(seg) = old.get(t.segment) else { continue };
        let (Some(n), Some(a), Some(c)) = (map(t.node), map(seg.nodes[0]), map(seg.nodes[1])) else { continue };
        let Some(&s) = edges.get(&[a, c]) else { continue };
        out.push(crate::contact::barrier_problem::Tie { node: n, segment: s, dofs: [2 * n, 2 * n + 1, 2 * a, 2 * a + 1, 2 * c, 2 * c + 1], ..*t });
        tied.push((n, new[s].body));
    }
    tied.sort_unstable();
    tied.dedup();
    (out, tied)
}
