//! What the output reads of a simulation after a converged step — its model, solution,
//! previous displacement, counters and the contact's nodal values — as one borrowed view
//! ([`Snapshot`]), whether the simulation holds the whole model ([`Simulation::snapshot`]) or
//! a process's part of it, whose own nodes, elements and bodies — their meshes too — rank 0
//! gathers into the whole model's numbering for the writing and drops after it
//! ([`Simulation::gather`], [`Gathered`]).
//! A restart on parts goes the other way: every process takes its nodes, elements and bodies
//! out of the checkpoint's whole state ([`Simulation::set_whole_state`]). When the particles
//! have moved out of their ghost layers, each process grows its part again from its own state
//! and what the owners of its new ghosts send it ([`Simulation::regrown`]).

use super::{RunState, SimScalars, SimState, Simulation, SolveError, SolverSpec, Solution};
use crate::contact::barrier_problem::Tie;
use crate::assembly::ElementFields;
use crate::contact::NodalContact;
use crate::element::N_ENH;
use crate::model::Model;

/// A part's own bodies' state ([`Simulation::own_state`]): the values of its own nodes and
/// elements.
pub(super) struct OwnState {
    pub u: Vec<f64>,
    pub u_prev: Vec<f64>,
    pub dynamics: Option<[Vec<f64>; 4]>,
    pub fields: ElementFields,
    pub lambda: Vec<f64>,
    pub j0: Vec<f64>,
    pub baseline: Vec<Option<crate::remesh::QualityCheck>>,
}

/// A converged state as the output reads it (see the module docs).
pub struct Snapshot<'a> {
    pub model: &'a Model,
    pub sol: &'a Solution,
    /// u_{n−1}.
    pub u_prev: &'a [f64],
    pub run: &'a RunState,
    /// The Newmark velocities of an implicit dynamic analysis.
    pub dynamic_velocity: Option<&'a [f64]>,
    /// The contact's nodal values at the converged state (None without contact).
    pub nodal: Option<&'a NodalContact>,
}

impl Snapshot<'_> {
    /// Current nodal coordinates x = X + u.
    pub fn coords(&self) -> Vec<[f64; 2]> {
        let u = &self.sol.u;
        self.model.x0.iter().enumerate().map(|(n, p)| [p[0] + u[2 * n], p[1] + u[2 * n + 1]]).collect()
    }

    /// Nodal velocities of the last committed step (mm/s, dof `2 n + c`): the Newmark
    /// velocity with inertia, otherwise the step's mean velocity (u_n − u_{n−1})/Δt (zero
    /// before the first step).
    pub fn velocity(&self) -> Vec<f64> {
        if let Some(v) = self.dynamic_velocity {
            return v.to_vec();
        }
        if self.run.step == 0 || !(self.run.dt_prev > 0.0) {
            return vec![0.0; self.sol.u.len()];
        }
        self.sol.u.iter().zip(self.u_prev).map(|(a, b)| (a - b) / self.run.dt_prev).collect()
    }
}

/// The whole state of a distributed run, gathered on rank 0 from the processes' parts: what
/// [`Simulation::state`] and the contact's nodal values are for the whole model. Held only
/// while the output is written.
pub struct Gathered {
    pub state: SimState,
    pub nodal: Option<NodalContact>,
    /// Whether the whole state was gathered (a checkpoint may be written of it), or only what
    /// the output reads.
    pub complete: bool,
    /// On a part: every body of the whole model, in order, with its current mesh, reference
    /// coordinates and prescribed dofs, from its owner (what [`crate::model::ModelFrame`]
    /// makes the whole model of, for the writing). Empty without a part (the simulation's
    /// model is the whole one).
    pub bodies: Vec<crate::model::GhostBody>,
}

impl Gathered {
    /// The view of this state on `whole`, the model the parts were made from.
    pub fn snapshot<'a>(&'a self, whole: &'a Model) -> Snapshot<'a> {
        Snapshot {
            model: whole,
            sol: &self.state.sol,
            u_prev: &self.state.u_prev,
            run: &self.state.scalars.run,
            dynamic_velocity: self.state.dynamics.as_ref().map(|d| d[1].as_slice()),
            nodal: self.nodal.as_ref(),
        }
    }
}

/// Values per element in a gathered record: the four Gauss points' material states (6 each)
/// and stresses (4 each), pressure, Θ, the enhanced modes, λ and j₀ — or, for the output only
/// ([`OUTPUT_RECORD`]), the stresses and the equivalent plastic and creep strains.
pub(super) const ELEMENT_RECORD: usize = 4 * 6 + 4 * 4 + 2 + N_ENH + 2;
const OUTPUT_RECORD: usize = 4 * 4 + 4 * 2;

pub(super) fn element_record(sol: &Solution, e: usize, complete: bool, out: &mut Vec<f64>) {
    let f = &sol.fields;
    for s in &f.sig[e] {
        out.extend(s);
    }
    for q in &f.states[e] {
        if complete {
            out.extend(q.cp_inv);
        }
        out.extend([q.eps_p, q.eps_c]);
    }
    if complete {
        out.extend([f.pressure[e], f.theta[e]]);
        out.extend(f.alpha[e]);
        out.extend([sol.lambda[e], sol.j0[e]]);
    }
}

/// Element `e`'s fields (and with `complete` its multiplier and j₀) from its record `r`.
pub(super) fn put_element_record(r: &[f64], e: usize, complete: bool, sol: &mut Solution) {
    let f = &mut sol.fields;
    for g in 0..4 {
        f.sig[e][g].copy_from_slice(&r[4 * g..4 * g + 4]);
    }
    let w = if complete { 6 } else { 2 };
    for g in 0..4 {
        let q = &r[16 + w * g..16 + w * (g + 1)];
        let st = &mut f.states[e][g];
        if complete {
            st.cp_inv = [q[0], q[1], q[2], q[3]];
        }
        (st.eps_p, st.eps_c) = (q[w - 2], q[w - 1]);
    }
    if complete {
        let r = &r[40..];
        f.pressure[e] = r[0];
        f.theta[e] = r[1];
        f.alpha[e].copy_from_slice(&r[2..2 + N_ENH]);
        sol.lambda[e] = r[2 + N_ENH];
        sol.j0[e] = r[3 + N_ENH];
    }
}

impl Simulation {
    /// The view of this simulation's converged state the output reads.
    pub fn snapshot(&self) -> Snapshot<'_> {
        Snapshot {
            model: &self.model,
            sol: &self.sol,
            u_prev: &self.u_prev,
            run: &self.run,
            dynamic_velocity: self.dynamics.as_ref().map(|d| d.v.as_slice()),
            nodal: self.nodal_contact(),
        }
    }

    /// Whether this simulation is a process's part of a distributed model
    /// ([`Simulation::new_part`]).
    pub fn is_part(&self) -> bool {
        self.sys.part.is_some()
    }

    /// On a part: the whole model's bodies this process owns (ascending) and every body's
    /// owner. None without a part.
    pub fn owners(&self) -> Option<(&[usize], &[usize])> {
        self.sys.part.as_ref().map(|p| (&p.bodies[..p.own_bodies], &p.layout.owner[..]))
    }

    /// On a part: rank 0's whole state in the whole model's numbering (nodes, elements and
    /// bodies from the processes owning them; the counters, energies and contact parameters,
    /// which every process holds alike, rank 0's), None on the other processes. Without a
    /// part: the state itself. Collective on a part.
    ///
    /// With `complete` false only what the output reads is gathered (the displacements, the
    /// stresses, the equivalent strains, the contact's nodal values): the rest of the state
    /// holds its initial values and must not be checkpointed ([`Gathered::complete`]).
    pub fn gather(&self, complete: bool) -> Option<Gathered> {
        let Some(p) = &self.sys.part else {
            return Some(Gathered { state: self.state(), nodal: self.nodal_contact().cloned(), complete: true, bodies: Vec::new() });
        };
        let comm = p.nodes.comm();
        let whole = self.model.whole_facts();
        let n_own = p.nodes.n_owned();
        let nodal = self.nodal_contact().filter(|c| c.pressure.len() == self.model.x0.len());
        let nw = nodal.map_or(0, |c| c.wall_force.len());
        // (every process has the nodal values when one has: they are set at every commit)
        let with_nodal = comm.max(if nodal.is_some() { 1.0 } else { 0.0 }) > 0.0;
        // the implicit dynamics' u, v, a, g (the velocity alone for the output)
        let dynamic: Vec<&[f64]> = match &self.dynamics {
            Some(d) if complete => vec![&d.u, &d.v, &d.a, &d.g],
            Some(d) => vec![&d.v],
            None => Vec::new(),
        };
        let dn = 2 * dynamic.len();
        let node_bs = 4 + dn + if with_nodal { 6 + comm.max(nw as f64) as usize } else { 0 };
        let mut local = Vec::with_capacity(n_own * node_bs);
        for n in 0..n_own {
            local.extend([self.sol.u[2 * n], self.sol.u[2 * n + 1], self.u_prev[2 * n], self.u_prev[2 * n + 1]]);
            for v in &dynamic {
                local.extend_from_slice(&v[2 * n..2 * n + 2]);
            }
            if with_nodal {
                match nodal {
                    Some(c) => {
                        local.extend([c.pressure[n], c.shear.get(n).copied().unwrap_or(0.0), c.gap[n], f64::from(c.status[n]), c.force[n][0], c.force[n][1]]);
                        local.extend(c.wall_force.iter().map(|w| w[n]));
                    }
                    None => local.extend(std::iter::repeat_n(0.0, node_bs - 4 - dn)),
                }
            }
        }
        // (every record goes straight into the whole state: the receiver holds it once; the
        // others allocate nothing of it)
        let receives = comm.is_root();
        let (nn, ne) = if receives { (whole.n_nodes, whole.n_elements) } else { (0, 0) };
        let (mut u, mut u_prev) = (vec![0.0; 2 * nn], vec![0.0; 2 * nn]);
        let nw = node_bs.saturating_sub(10 + dn);
        let mut nodal = with_nodal.then(|| NodalContact { pressure: vec![0.0; nn], shear: vec![0.0; nn], gap: vec![f64::NAN; nn], status: vec![0; nn], force: vec![[0.0; 2]; nn], wall_force: vec![vec![0.0; nn]; nw] });
        let mut dynamics = vec![vec![0.0; 2 * nn]; dynamic.len()];
        let received = crate::parallel::part::receive_records(comm, (0..n_own).map(|n| (p.whole.node[n], &local[n * node_bs..(n + 1) * node_bs])), node_bs, false, |n, r| {
            if n >= nn {
                return;
            }
            u[2 * n..2 * n + 2].copy_from_slice(&r[..2]);
            u_prev[2 * n..2 * n + 2].copy_from_slice(&r[2..4]);
            for (k, v) in dynamics.iter_mut().enumerate() {
                v[2 * n..2 * n + 2].copy_from_slice(&r[4 + 2 * k..6 + 2 * k]);
            }
            // (the contact's values after the dynamics', at 4.. as without them)
            let r = &r[dn..];
            if let Some(c) = nodal.as_mut() {
                (c.pressure[n], c.shear[n], c.gap[n], c.status[n]) = (r[4], r[5], r[6], r[7] as i32);
                c.force[n] = [r[8], r[9]];
                for (w, v) in c.wall_force.iter_mut().zip(&r[10..]) {
                    w[n] = *v;
                }
            }
        });
        drop(local);
        let own_elements: Vec<usize> = (0..self.model.elements.len()).filter(|&e| self.model.elem_body[e] < p.own_bodies).collect();
        let bs = if complete { ELEMENT_RECORD } else { OUTPUT_RECORD };
        let mut local = Vec::with_capacity(own_elements.len() * bs);
        for &e in &own_elements {
            element_record(&self.sol, e, complete, &mut local);
        }
        let mut sol = Solution { time: self.sol.time, u, fields: ElementFields::new(ne), lambda: vec![0.0; ne], j0: vec![1.0; ne] };
        let got_elements = crate::parallel::part::receive_records(comm, own_elements.iter().enumerate().map(|(i, &e)| (p.whole.element[e], &local[i * bs..(i + 1) * bs])), bs, false, |e, r| {
            if e < ne {
                put_element_record(r, e, complete, &mut sol);
            }
        });
        drop(local);
        let areas = crate::parallel::part::gather_records(comm, (0..p.own_bodies).map(|b| (p.bodies[b], std::slice::from_ref(&self.run.area0_body[b]))), 1, whole.n_bodies, false);
        // the re-mesh baselines of its own bodies (a checkpoint's): present, then the check
        let baselines = complete.then(|| {
            use crate::remesh::monitor::QUALITY_RECORD;
            let local: Vec<f64> = (0..p.own_bodies)
                .flat_map(|b| match &self.run.remesh_baseline[b] {
                    Some(q) => std::iter::once(1.0).chain(q.to_record()).collect::<Vec<f64>>(),
                    None => vec![0.0; QUALITY_RECORD + 1],
                })
                .collect();
            let records = (0..p.own_bodies).map(|b| (p.bodies[b], &local[b * (QUALITY_RECORD + 1)..(b + 1) * (QUALITY_RECORD + 1)]));
            crate::parallel::part::gather_records(comm, records, QUALITY_RECORD + 1, whole.n_bodies, false)
                .map(|all| all.chunks_exact(QUALITY_RECORD + 1).map(|r| if r[0] == 1.0 { crate::remesh::QualityCheck::from_record(&r[1..]) } else { None }).collect::<Vec<_>>())
        });
        // the ties (cohering particles) in the whole model's numbering, every process's own
        let ties = self.barrier.as_ref().filter(|b| complete && b.tie_stiffness > 0.0).map(|_| {
            let (ties, tied) = self.whole_ties();
            let mut local: Vec<f64> = ties.iter().flat_map(tie_record).collect();
            let all = comm.gather_varcount_to_root(&local);
            local = tied.iter().flat_map(|&(n, b)| [n as f64, b as f64]).collect();
            let all_tied = comm.gather_varcount_to_root(&local);
            let mut ties: Vec<Tie> = all.chunks_exact(TIE_RECORD).map(tie_from_record).collect();
            ties.sort_by_key(|t| (t.node, t.segment));
            let mut tied: Vec<(usize, usize)> = all_tied.chunks_exact(2).map(|r| (r[0] as usize, r[1] as usize)).collect();
            tied.sort_unstable();
            (ties, tied)
        });
        // the bodies' meshes (rank 0 keeps none of them between the writes)
        let own: Vec<(usize, crate::model::GhostBody)> = (0..p.own_bodies).map(|k| (p.bodies[k], self.model.ghost_body(k))).collect();
        let bodies = crate::parallel::part::bodies_to_root(comm, &own);
        drop(own);
        let bodies = match bodies {
            Ok(b) if b.len() == whole.n_bodies && b.iter().enumerate().all(|(i, (g, _))| *g == i) => b.into_iter().map(|(_, b)| b).collect(),
            Ok(b) if !comm.is_root() && b.is_empty() => Vec::new(),
            Ok(b) => {
                tracing::error!(bodies = b.len(), expected = whole.n_bodies, "the gathered bodies are not every body once");
                return None;
            }
            Err(e) => {
                tracing::error!(%e, "the bodies' meshes did not reach rank 0");
                return None;
            }
        };
        let (true, true, Some(areas)) = (received, got_elements, areas) else { return None };
        // (the output's velocity alone: u, a and g hold zeros, not to be checkpointed)
        let dynamics = match <[Vec<f64>; 4]>::try_from(dynamics) {
            Ok(all) => Some(all),
            Err(mut v) => v.pop().map(|vel| [vec![0.0; 2 * nn], vel, vec![0.0; 2 * nn], vec![0.0; 2 * nn]]),
        };
        let mut state = SimState { scalars: self.scalars(), sol, u_prev, dynamics };
        if let (Some(b), Some((ties, tied))) = (state.scalars.barrier.as_mut(), ties) {
            (b.ties, b.tied) = (ties, tied);
        }
        state.scalars.run.area0_body = areas;
        state.scalars.run.remesh_baseline = baselines.flatten().unwrap_or_else(|| vec![None; whole.n_bodies]);
        Some(Gathered { state, nodal, complete, bodies })
    }

    /// On a part: continue from `whole`, the whole model's state held in memory: each process
    /// takes its nodes', elements' and bodies' values ([`Simulation::set_whole_state_from`]).
    /// Without a part: [`Simulation::set_state`].
    ///
    /// # Errors
    /// As [`Simulation::set_whole_state_from`].
    pub fn set_whole_state(&mut self, whole: SimState) -> Result<(), String> {
        if self.sys.part.is_none() {
            return self.set_state(whole);
        }
        let scalars = whole.scalars.clone();
        self.set_whole_state_from(scalars, &whole)
    }

    /// Continue from the whole model's state: its `scalars` and its arrays `whole`, of which
    /// this process reads the rows of its part's nodes and elements only (from a checkpoint's
    /// file no process reads more, [`crate::checkpoint::CheckpointFile`]); the bodies' areas,
    /// re-meshing baselines and the barrier's ties are taken for its bodies. Collective on a
    /// part (every process learns whether one could not take its ties).
    ///
    /// # Errors
    /// What does not fit: an array of another size than the whole model's, a row that cannot
    /// be read, ties that are not on the part, or what [`Simulation::set_state`] refuses.
    pub fn set_whole_state_from(&mut self, mut scalars: SimScalars, whole: &dyn WholeRows) -> Result<(), String> {
        let w = self.model.whole_facts();
        let (nodes, elements): (Vec<usize>, Vec<usize>) = match &self.sys.part {
            Some(p) => (p.whole.node.clone(), p.whole.element.clone()),
            None => ((0..w.n_nodes).collect(), (0..w.n_elements).collect()),
        };
        let read = |name: &str, width: usize, rows: &[usize], count: usize| -> Result<Vec<f64>, String> {
            match whole.values(name) {
                Some(n) if n == width * count => whole.rows(name, width, rows),
                Some(n) => Err(format!("{name}: {n} values in the checkpoint, {} in the model ({count} × {width})", width * count)),
                None => Err(format!("{name}: not in the checkpoint")),
            }
        };
        let nodal = |name: &str| read(name, 2, &nodes, w.n_nodes);
        let per_element = |name: &str, width: usize| read(name, width, &elements, w.n_elements);
        let u = nodal("solution/u")?;
        let u_prev = nodal("solution/u_prev")?;
        let dynamics = match whole.values("dynamics/u") {
            Some(_) => Some([nodal("dynamics/u")?, nodal("dynamics/v")?, nodal("dynamics/a")?, nodal("dynamics/g")?]),
            None => None,
        };
        let lambda = per_element("solution/lambda", 1)?;
        let j0 = per_element("solution/j0", 1)?;
        let states = per_element("solution/states", 24)?;
        let sig = per_element("solution/sig", 16)?;
        let alpha = per_element("solution/alpha", N_ENH)?;
        let fields = ElementFields::from_records(&states, &sig, &alpha, per_element("solution/pressure", 1)?, per_element("solution/theta", 1)?);
        if scalars.run.area0_body.len() != w.n_bodies {
            return Err(format!("body areas: {} in the checkpoint, {} in the model", scalars.run.area0_body.len(), w.n_bodies));
        }
        let bodies: Vec<usize> = self.sys.part.as_ref().map_or_else(|| (0..w.n_bodies).collect(), |p| p.bodies.clone());
        scalars.run.area0_body = bodies.iter().map(|&b| scalars.run.area0_body[b]).collect();
        scalars.run.remesh_baseline = bodies.iter().map(|&b| scalars.run.remesh_baseline.get(b).cloned().flatten()).collect();
        if let Some(b) = scalars.barrier.as_mut() {
            // (every process learns whether one could not take its ties, before the
            // collective calls of the state's restore)
            let ties = self.local_ties(&b.ties, &b.tied);
            if self.sys.any(ties.is_err()) {
                return Err(ties.err().unwrap_or_else(|| "barrier ties: another process's do not fit its part".into()));
            }
            (b.ties, b.tied) = ties?;
        }
        let sol = Solution { time: scalars.time, u, fields, lambda, j0 };
        self.set_state(SimState { scalars, sol, u_prev, dynamics })
    }

    /// On a part: the simulation of this part grown again ([`crate::parallel::part::RankPart::regrow`]),
    /// with the other processes' bodies within `reach` of its own where they are now as its
    /// ghosts, at this converged state: its own nodes, elements and bodies keep their values
    /// and places; the ghosts' displacements come from their owners (the new node map's
    /// forward scatter), their bodies' reference areas from every process's own (one number a
    /// body). No process gathers the whole state. It counts as a repartition. Collective on a
    /// part.
    ///
    /// # Errors
    /// Not a part, a part that cannot be grown again, or what [`Simulation::new_part`] and
    /// [`Simulation::set_state`] refuse.
    pub fn regrown(&self, time: crate::solver::TimeSpec, spec: SolverSpec, reach: f64) -> Result<Simulation, String> {
        let Some(p) = &self.sys.part else { return Err("only a process's part of a distributed model is grown again".into()) };
        let whole_ties = self.whole_ties();
        let mut sim = self.grown(&self.model, self.own_state(), &p.bodies[..p.own_bodies], &p.layout.clone(), &[], time, spec, reach, |sim| sim.local_ties(&whole_ties.0, &whole_ties.1))?;
        sim.sys.partition.repartitions += 1;
        Ok(sim)
    }

    /// On a part: its own bodies' state, as [`Self::grown`] takes it.
    pub(super) fn own_state(&self) -> OwnState {
        let own_bodies = self.sys.part.as_ref().map_or(self.model.bodies.len(), |p| p.own_bodies);
        let own_nodes = self.model.bodies.get(own_bodies).map_or(self.model.n_nodes(), |b| b.node_offset);
        let own_elements = self.model.bodies.get(own_bodies).map_or(self.model.elements.len(), |b| b.elem_offset);
        let f = &self.sol.fields;
        let own = ..own_elements;
        OwnState {
            u: self.sol.u[..2 * own_nodes].to_vec(),
            u_prev: self.u_prev[..2 * own_nodes].to_vec(),
            dynamics: self.dynamics.as_ref().map(|d| [&d.u, &d.v, &d.a, &d.g].map(|v| v[..2 * own_nodes].to_vec())),
            fields: ElementFields { states: f.states[own].to_vec(), sig: f.sig[own].to_vec(), pressure: f.pressure[own].to_vec(), theta: f.theta[own].to_vec(), alpha: f.alpha[own].to_vec() },
            lambda: self.sol.lambda[own].to_vec(),
            j0: self.sol.j0[own].to_vec(),
            baseline: self.run.remesh_baseline[..own_bodies].to_vec(),
        }
    }

    /// On a part: the simulation of this part grown again from `model` (its own bodies first,
    /// possibly re-meshed, then its ghosts as they were) and `own` (its own bodies' state,
    /// [`Self::own_state`]), its bodies laid out by `layout`,
    /// the ghosts of `stale` sent again by their owners
    /// ([`crate::parallel::part::RankPart::regrow_with`]), and the ties `ties` gives for the
    /// new part (its own nodes', in its numbering). The ghosts' displacements come from their
    /// owners, the bodies' reference areas from every process's own. Collective.
    ///
    /// # Errors
    /// Not a part, a part that cannot be grown again, or what [`Simulation::new_part`] and
    /// [`Simulation::set_state`] refuse — on every process alike.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn grown(&self, model: &Model, own: OwnState, owned: &[usize], layout: &std::sync::Arc<crate::parallel::part::BodyLayout>, stale: &[usize], time: crate::solver::TimeSpec, spec: SolverSpec, reach: f64, ties: impl FnOnce(&Simulation) -> Result<(Vec<Tie>, Vec<(usize, usize)>), String>) -> Result<Simulation, String> {
        use crate::parallel::part::{PartView, RankPart};
        let Some(p) = &self.sys.part else { return Err("only a process's part of a distributed model is grown again".into()) };
        let OwnState { u: own_u, u_prev: own_u_prev, dynamics: own_dynamics, fields: own_fields, lambda: own_lambda, j0: own_j0, baseline } = own;
        let own_bodies = p.own_bodies;
        let own_nodes = own_u.len() / 2;
        // the coordinates of every node of the part: its own from `own`, its ghosts' (when
        // `model` keeps this part's) as they are
        let ghosts_from = self.model.bodies.get(own_bodies).map_or(self.model.n_nodes(), |b| b.node_offset);
        let keeps_ghosts = model.bodies.len() > owned.len();
        let ghost_nodes = if keeps_ghosts { ghosts_from..self.model.n_nodes() } else { 0..0 };
        let x: Vec<[f64; 2]> = (0..own_nodes)
            .map(|n| [model.x0[n][0] + own_u[2 * n], model.x0[n][1] + own_u[2 * n + 1]])
            .chain(ghost_nodes.map(|n| [self.model.x0[n][0] + self.sol.u[2 * n], self.model.x0[n][1] + self.sol.u[2 * n + 1]]))
            .collect();
        let bodies: Vec<usize> = owned.iter().chain(if keeps_ghosts { &p.bodies[own_bodies..] } else { &[] }).copied().collect();
        let view = PartView { model, nodes: &p.nodes, bodies: &bodies, n_owned_bodies: owned.len(), layout: &p.layout };
        let part = RankPart::regrow_with(view, &x, reach, layout, stale).map_err(|e| e.to_string())?;
        drop(x);
        let comm = p.nodes.comm();
        let (n_local, ne, nb) = (part.nodes.n_local(), part.model.elements.len(), part.bodies.len());
        // the nodal vectors (displacements, the dynamics' u, v, a, g): its own, then the
        // ghosts' from their owners
        let mut vectors: Vec<&[f64]> = vec![&own_u, &own_u_prev];
        if let Some(d) = &own_dynamics {
            vectors.extend(d.iter().map(|v| &v[..]));
        }
        let bs = 2 * vectors.len();
        let mut all = vec![0.0; bs * n_local];
        for n in 0..own_nodes {
            for (k, v) in vectors.iter().enumerate() {
                all[bs * n + 2 * k..bs * n + 2 * k + 2].copy_from_slice(&v[2 * n..2 * n + 2]);
            }
        }
        part.nodes.forward(&mut all, bs);
        let mut vectors: Vec<Vec<f64>> = (0..vectors.len()).map(|k| all.chunks_exact(bs).flat_map(|r| [r[2 * k], r[2 * k + 1]]).collect()).collect();
        drop(all);
        let dynamics = (vectors.len() == 6).then(|| {
            let d: Vec<Vec<f64>> = vectors.drain(2..).collect();
            <[Vec<f64>; 4]>::try_from(d).expect("four dynamic vectors")
        });
        let (u_prev, u) = (vectors.pop().unwrap_or_default(), vectors.pop().unwrap_or_default());
        // the elements: its own as they are; a ghost's are not read (its owner evaluates it)
        let mut fields = ElementFields::new(ne);
        let own = ..own_lambda.len();
        fields.states[own].copy_from_slice(&own_fields.states);
        fields.sig[own].copy_from_slice(&own_fields.sig);
        fields.pressure[own].copy_from_slice(&own_fields.pressure);
        fields.theta[own].copy_from_slice(&own_fields.theta);
        fields.alpha[own].copy_from_slice(&own_fields.alpha);
        let (mut lambda, mut j0) = (vec![0.0; ne], vec![1.0; ne]);
        lambda[own].copy_from_slice(&own_lambda);
        j0[own].copy_from_slice(&own_j0);
        let sol = Solution { time: self.sol.time, u, fields, lambda, j0 };
        // the bodies' reference areas: every process's own, to every process
        let area = crate::parallel::part::gather_records(comm, (0..own_bodies).map(|b| (p.bodies[b], std::slice::from_ref(&self.run.area0_body[b]))), 1, layout.owner.len(), true).unwrap_or_default();
        let mut scalars = self.scalars();
        scalars.run.area0_body = part.bodies.iter().map(|&b| area.get(b).copied().unwrap_or(f64::NAN)).collect();
        scalars.run.remesh_baseline = baseline.into_iter().chain(std::iter::repeat(None)).take(nb).collect();
        let mut sim = Simulation::part_simulation(part, time, spec, true).map_err(|e: SolveError| e.to_string())?;
        // its ties (on its own nodes) in the new part's numbering of the edges and bodies
        if let Some(b) = scalars.barrier.as_mut() {
            let ties = ties(&sim);
            if sim.sys.any(ties.is_err()) {
                return Err(ties.err().unwrap_or_else(|| "barrier ties: another process's do not fit its new part".into()));
            }
            (b.ties, b.tied) = ties?;
        }
        let set = sim.set_state(SimState { scalars, sol, u_prev, dynamics });
        if sim.sys.any(set.is_err()) {
            return Err(set.err().unwrap_or_else(|| "the state of another process's new part does not fit it".into()));
        }
        Ok(sim)
    }

    /// On a part: its ties (cohering particles: on its own nodes) and its (node, particle)
    /// pairs held by them, in the whole model's numbering of the nodes, boundary edges and
    /// bodies (the tie's dofs too). Empty without ties or without a part.
    pub(super) fn whole_ties(&self) -> (Vec<Tie>, Vec<(usize, usize)>) {
        let (Some(p), Some(b)) = (&self.sys.part, &self.barrier) else { return (Vec::new(), Vec::new()) };
        let segments = &b.contact.segments;
        let first = first_segments(segments, self.model.bodies.len());
        let node = |n: usize| p.whole.node[n];
        let ties = b
            .contact
            .ties
            .iter()
            .map(|t| {
                let s = &segments[t.segment];
                let w = p.layout.segment_offset[p.bodies[s.body]] + t.segment - first[s.body];
                let [n, a, c] = [t.node, s.nodes[0], s.nodes[1]].map(node);
                Tie { node: n, segment: w, dofs: [2 * n, 2 * n + 1, 2 * a, 2 * a + 1, 2 * c, 2 * c + 1], ..*t }
            })
            .collect();
        let tied = b.contact.tied.iter().map(|&(n, k)| (node(n), p.bodies[k])).collect();
        (ties, tied)
    }

    /// The ties of the whole model's `ties` and `tied` (its numbering, [`Self::whole_ties`])
    /// on this part's own nodes, in its numbering. Without a part: as they are.
    ///
    /// # Errors
    /// A tie whose edge is not on one of the part's bodies, or out of the whole model's range.
    pub(super) fn local_ties(&self, ties: &[Tie], tied: &[(usize, usize)]) -> Result<(Vec<Tie>, Vec<(usize, usize)>), String> {
        let (Some(p), Some(b)) = (&self.sys.part, &self.barrier) else { return Ok((ties.to_vec(), tied.to_vec())) };
        let segments = &b.contact.segments;
        let first = first_segments(segments, self.model.bodies.len());
        let own: std::collections::HashMap<usize, usize> = p.whole.node[..p.nodes.n_owned()].iter().enumerate().map(|(i, &g)| (g, i)).collect();
        let local_body: std::collections::HashMap<usize, usize> = p.bodies.iter().enumerate().map(|(k, &g)| (g, k)).collect();
        let mut out = Vec::new();
        for t in ties {
            let Some(&n) = own.get(&t.node) else { continue };
            let body = p.layout.segment_body(t.segment).ok_or_else(|| format!("barrier ties: edge {} is not in the model", t.segment))?;
            let k = *local_body.get(&body).ok_or_else(|| format!("barrier ties: node {} is tied to body {body}, which is not within the ghost layer of process {}", t.node, p.nodes.comm().rank()))?;
            let s = first[k] + t.segment - p.layout.segment_offset[body];
            let [a, c] = segments[s].nodes;
            out.push(Tie { node: n, segment: s, dofs: [2 * n, 2 * n + 1, 2 * a, 2 * a + 1, 2 * c, 2 * c + 1], ..*t });
        }
        let mut held: Vec<(usize, usize)> = tied.iter().filter_map(|&(n, g)| Some((*own.get(&n)?, *local_body.get(&g)?))).collect();
        held.sort_unstable();
        Ok((out, held))
    }
}

/// The whole model's arrays of a state, read by rows, named as in a checkpoint
/// ([`crate::checkpoint`]): `solution/u`, `solution/u_prev` and `dynamics/{u,v,a,g}` (2 values
/// a node), `solution/{lambda,j0,pressure,theta}` (1 an element), `solution/states` (24),
/// `solution/sig` (16) and `solution/alpha` ([`N_ENH`]). A state in memory is one; a checkpoint's
/// file is another, from which each process of a run on parts reads its own rows
/// ([`Simulation::set_whole_state_from`]).
pub trait WholeRows {
    /// How many values the array `name` has (None: it has none, as `dynamics/*` in a static
    /// analysis).
    fn values(&self, name: &str) -> Option<usize>;
    /// The rows `rows` of the array `name`, `width` values a row, in the order of `rows`.
    ///
    /// # Errors
    /// A row beyond the array, or an array that cannot be read.
    fn rows(&self, name: &str, width: usize, rows: &[usize]) -> Result<Vec<f64>, String>;
}

impl WholeRows for SimState {
    fn values(&self, name: &str) -> Option<usize> {
        let ne = self.sol.lambda.len();
        match name {
            "solution/states" => Some(24 * ne),
            "solution/sig" => Some(16 * ne),
            "solution/alpha" => Some(N_ENH * ne),
            _ => self.flat(name).map(<[f64]>::len),
        }
    }

    fn rows(&self, name: &str, width: usize, rows: &[usize]) -> Result<Vec<f64>, String> {
        let n = self.values(name).ok_or_else(|| format!("{name}: no such array"))?;
        if let Some(&r) = rows.iter().find(|&&r| width * (r + 1) > n) {
            return Err(format!("{name}: row {r} of {} rows of {width}", n / width.max(1)));
        }
        let f = &self.sol.fields;
        let mut out = Vec::with_capacity(width * rows.len());
        for &r in rows {
            match name {
                "solution/states" => out.extend(f.states[r].iter().flat_map(|q| [q.cp_inv[0], q.cp_inv[1], q.cp_inv[2], q.cp_inv[3], q.eps_p, q.eps_c])),
                "solution/sig" => out.extend(f.sig[r].iter().flatten()),
                "solution/alpha" => out.extend_from_slice(&f.alpha[r]),
                _ => out.extend_from_slice(&self.flat(name).ok_or_else(|| format!("{name}: no such array"))?[width * r..width * (r + 1)]),
            }
        }
        Ok(out)
    }
}

impl SimState {
    /// The array `name` of [`WholeRows`] kept flat in this state.
    fn flat(&self, name: &str) -> Option<&[f64]> {
        let (sol, d) = (&self.sol, self.dynamics.as_ref());
        Some(match name {
            "solution/u" => &sol.u,
            "solution/u_prev" => &self.u_prev,
            "solution/lambda" => &sol.lambda,
            "solution/j0" => &sol.j0,
            "solution/pressure" => &sol.fields.pressure,
            "solution/theta" => &sol.fields.theta,
            "dynamics/u" => &d?[0],
            "dynamics/v" => &d?[1],
            "dynamics/a" => &d?[2],
            "dynamics/g" => &d?[3],
            _ => return None,
        })
    }
}

/// Values of a tie in the whole model's numbering as a record ([`tie_record`]).
pub(super) const TIE_RECORD: usize = 11;

/// A tie in the whole model's numbering ([`Simulation::whole_ties`]) as numbers: its node,
/// edge, the edge's two nodes, ξ, offset and multipliers (every index below 2⁵³, exact).
pub(super) fn tie_record(t: &Tie) -> [f64; TIE_RECORD] {
    [t.node as f64, t.segment as f64, t.dofs[2] as f64 / 2.0, t.dofs[4] as f64 / 2.0, t.xi, t.offset[0], t.offset[1], t.lambda[0], t.lambda[1], t.lambda0[0], t.lambda0[1]]
}

/// The tie of a [`tie_record`].
pub(super) fn tie_from_record(r: &[f64]) -> Tie {
    let [n, a, b] = [r[0], r[2], r[3]].map(|v| v as usize);
    Tie { node: n, segment: r[1] as usize, dofs: [2 * n, 2 * n + 1, 2 * a, 2 * a + 1, 2 * b, 2 * b + 1], xi: r[4], offset: [r[5], r[6]], lambda: [r[7], r[8]], lambda0: [r[9], r[10]] }
}

/// The first of `segments` (the contact's boundary edges, body by body) of each of `n_bodies`
/// bodies.
fn first_segments(segments: &[crate::contact::Segment], n_bodies: usize) -> Vec<usize> {
    let mut first = vec![segments.len(); n_bodies];
    for (s, seg) in segments.iter().enumerate().rev() {
        first[seg.body] = s;
    }
    first
}
