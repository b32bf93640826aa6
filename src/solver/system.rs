//! The global system of a simulation: the one assembler and its pattern, the matrix and the
//! vectors of a Newton iteration, the linear solver and the processes it runs on — and the one
//! way a residual and a tangent are formed (`Simulation::evaluate`).
//!
//! Every force term is a local contribution scattered into the one pattern, in a fixed order:
//! 1. the element kernels (colour-parallel, [`crate::assembly::Assembler::assemble`]; on several
//!    processes each adds its own particles' elements and the sums go to every process, the
//!    tangent to rank 0);
//! 2. the external loads (follower pressures add their derivative through their block map);
//! 3. the contact pairs ([`crate::contact::ContactProblem`]: node-to-segment blocks, wall
//!    blocks, multiplier blocks), evaluated by the owners of their slave nodes and added by
//!    every process in the serial order;
//! 4. the stabilisation springs and their regularisation (the diagonal);
//! 5. the inertia of an implicit dynamic analysis (the diagonal);
//! 6. a held-back imbalance (re-equilibration) and the multiplier rows.
//!
//! On several processes rank 0 adds steps 2–6 to the tangent after the element sum, so every
//! matrix entry receives its contributions in the same order as in a serial run: the runs are
//! bit-identical to the serial one.

use super::{NewtonFailure, Phase, Simulation};
use crate::assembly::{Assembler, ElementFields, FIXED};
use crate::comm::Collective;
use crate::contact::ContactTangent;
use crate::element::Volumetric;
use crate::linalg::{BlockMap, CsrMatrix, LinearSolver};
use crate::loading::LoadKind;
use crate::material::TimeIncrement;
use crate::parallel::{Distribution, PartitionStats};
use std::sync::Arc;

/// The positions of the non-element terms in the current pattern.
#[derive(Default)]
pub(super) struct TermMaps {
    /// One block per frozen contact pair (its dofs), per slave node (the wall pairs), per
    /// Lagrange multiplier (its dofs and its own row).
    pub pairs: BlockMap,
    pub nodes: BlockMap,
    pub multipliers: BlockMap,
    /// The diagonal entry of every dof (springs, inertia).
    pub diagonal: BlockMap,
    /// One block per edge of a follower-pressure load (its two nodes' dofs), in load order.
    pub pressure: BlockMap,
}

/// A process's part of a distributed model (the owned + ghost state,
/// [`crate::parallel::part`]): its vectors hold its own dofs and equations first, then its
/// ghosts'; every term is evaluated by one process (its elements, the barrier pairs whose first
/// side it owns), the forces of the ghosts go to their owners (the reverse scatter) and come
/// back summed (the forward scatter), and every norm, dot product and extremum is reduced over
/// the processes.
pub(super) struct PartSys {
    /// The map of the part's nodes (2 dofs each).
    pub nodes: crate::comm::IndexMap,
    /// The map of its free equations.
    pub eqs: Arc<crate::comm::IndexMap>,
    /// Its own dofs and equations (the first of each).
    pub own_dofs: usize,
    pub own_eqs: usize,
    /// The whole model's body of each of the part's bodies, and how many (the first) it owns.
    pub bodies: Vec<usize>,
    pub own_bodies: usize,
    /// The whole model's equation of each of the part's equations (for what is defined on the
    /// whole model's equations: the saddle's pseudo-random start).
    pub eq_whole: Vec<usize>,
    /// Every body's owner, size and place in the whole model (to grow the part again).
    pub layout: Arc<crate::parallel::part::BodyLayout>,
    /// The reach of its ghosts (mm; a re-mesh grows the part again with it).
    pub reach: f64,
    /// The whole model's node and element of each of the part's nodes and elements (to name
    /// a failed element, to gather the output).
    pub whole: crate::model::PartMap,
}

/// The global system (see the module docs).
pub(super) struct System {
    pub assembler: Assembler,
    pub kk: CsrMatrix,
    pub maps: TermMaps,
    /// The free residual F_ext − F_int (and the multiplier rows) and the Newton update.
    pub r: Vec<f64>,
    pub du: Vec<f64>,
    /// Internal and external forces of every dof at the last evaluation (N/mm).
    pub f_int: Vec<f64>,
    pub f_ext: Vec<f64>,
    /// ‖F_int‖ of the elements alone at the last evaluation (the force scale of a problem
    /// driven by walls).
    pub f_elem_norm: f64,
    /// The element fields of the last evaluation (committed with the step).
    pub trial_fields: ElementFields,
    /// Part of a transferred state's out-of-balance force still held back while a
    /// re-equilibration releases it (added to F_int; empty otherwise), per dof (N/mm).
    pub eq_offset: Vec<f64>,
    pub linear: Box<dyn LinearSolver>,
    pub linear_name: String,
    pub pool: Option<rayon::ThreadPool>,
    /// The processes of the run ([`crate::comm::Serial`] for one).
    pub comm: Arc<dyn Collective>,
    /// What this process owns in a run on several processes (None: one process).
    pub par: Option<Distribution>,
    /// The partition's figures (one process: 1 rank, imbalance 1, no cut, no repartitions).
    pub partition: PartitionStats,
    /// Whether every process takes part in the linear solves (the Schwarz PCG on several
    /// processes); otherwise rank 0 solves and broadcasts the update.
    pub distributed_solve: bool,
    /// This process's part of a distributed model (None: the whole model is here).
    pub part: Option<PartSys>,
}

impl System {
    /// `x` summed over the processes of a part (itself otherwise).
    pub fn sum(&self, x: f64) -> f64 {
        if self.part.is_none() {
            return x;
        }
        let mut v = [x];
        self.comm.sum_in_place(&mut v);
        v[0]
    }

    /// The largest `x` over the processes of a part (itself otherwise).
    pub fn max(&self, x: f64) -> f64 {
        if self.part.is_none() {
            x
        } else {
            self.comm.max(x)
        }
    }

    /// The smallest `x` over the processes of a part (itself otherwise).
    pub fn min(&self, x: f64) -> f64 {
        -self.max(-x)
    }

    /// Whether `flag` holds on any process of a part (itself otherwise).
    pub fn any(&self, flag: bool) -> bool {
        self.max(if flag { 1.0 } else { 0.0 }) > 0.0
    }

    /// The equations this process owns (all of them without a part).
    pub fn own_eqs(&self) -> usize {
        self.part.as_ref().map_or(self.r.len(), |p| p.own_eqs)
    }

    /// The dofs this process owns (all of them without a part).
    pub fn own_dofs(&self) -> usize {
        self.part.as_ref().map_or(self.f_int.len(), |p| p.own_dofs)
    }

    /// Σ a_q b_q over the free equations (of every process of a part).
    pub fn dot(&self, a: &[f64], b: &[f64]) -> f64 {
        let n = self.own_eqs();
        self.sum(a[..n].iter().zip(&b[..n]).map(|(x, y)| x * y).sum::<f64>())
    }

    /// ‖v‖ over the dofs (a vector of every dof; of every process of a part).
    pub fn norm_dofs(&self, v: &[f64]) -> f64 {
        let n = self.own_dofs();
        self.sum(v[..n].iter().map(|x| x * x).sum::<f64>()).sqrt()
    }

    /// A result of every process of a part, agreed: a failure on any fails all (the others
    /// with `elsewhere`'s words); the result itself otherwise.
    pub fn agree_part<T>(&self, r: Result<T, NewtonFailure>, elsewhere: &str) -> Result<T, NewtonFailure> {
        if self.part.is_none() {
            return r;
        }
        let failed = self.any(r.is_err());
        match r {
            Ok(_) if failed => Err(NewtonFailure::Contact(format!("{elsewhere} on another process"))),
            r => r,
        }
    }

    /// An element assembly of every process of a part, agreed: when elements failed, every
    /// process fails with the failure of the lowest process that had one (its element named by
    /// its number in the whole model), so that all take the same path after it (a failed
    /// element restarts a prediction, and is no reason for the barrier's descent).
    pub fn agree_elements(&self, local: Result<(), crate::assembly::AssemblyError>) -> Result<(), crate::assembly::AssemblyError> {
        let Some(p) = &self.part else { return local };
        let rank = self.comm.rank() as u64;
        let first = self.comm.min_u64(if local.is_err() { rank } else { u64::MAX });
        if first == u64::MAX {
            return Ok(());
        }
        let mut code = [0.0; 4];
        if let (true, Err(e)) = (first == rank, &local) {
            let whole = crate::assembly::AssemblyError { element: p.whole.element.get(e.element).copied().unwrap_or(e.element), source: e.source.clone() };
            code = crate::parallel::encode_failure(&whole);
        }
        self.comm.sum_in_place(&mut code);
        Err(crate::parallel::decode_failure(&code))
    }

    /// Whether this process takes part in the linear solves (rank 0, or every process with
    /// the distributed Schwarz PCG).
    pub fn solves_here(&self) -> bool {
        self.comm.is_root() || self.distributed_solve
    }

    /// A linear-algebra result of the solving process, known to every process.
    pub fn agree(&self, r: Result<(), NewtonFailure>, what: &str) -> Result<(), NewtonFailure> {
        if self.part.is_some() {
            return self.agree_part(r, &format!("{what} failed"));
        }
        agree_linear(self.par.as_ref(), r, what)
    }

    /// Locate the diagonal, node and follower-load blocks in the current pattern (after it
    /// changed).
    pub fn locate_fixed_terms(&mut self, model: &crate::model::Model, node_dofs: &[Vec<usize>]) {
        self.maps.diagonal = self.assembler.diagonal_map(&self.kk);
        self.maps.nodes = self.assembler.block_map(&self.kk, node_dofs);
        let edges: Vec<Vec<usize>> = model
            .loading
            .loads
            .iter()
            .filter(|l| matches!(l.kind, LoadKind::Pressure(_)))
            .flat_map(|l| l.edges.iter().map(|e| vec![2 * e[0], 2 * e[0] + 1, 2 * e[1], 2 * e[1] + 1]))
            .collect();
        self.maps.pressure = self.assembler.block_map(&self.kk, &edges);
    }

    /// The symbolic analysis of the current pattern, on the solving processes (a failure there
    /// fails every process).
    pub fn analyze(&mut self) -> Result<(), NewtonFailure> {
        if self.assembler.n_free == 0 {
            return Ok(());
        }
        let r = if self.solves_here() { self.linear.analyze(&self.kk).map_err(|e| NewtonFailure::Linear(e.to_string())) } else { Ok(()) };
        self.agree(r, "symbolic analysis")
    }
}

impl Simulation {
    /// External force vector at time t on configuration `x` (all dofs), and, with a tangent,
    /// the derivative of the follower pressures subtracted from it.
    fn external_forces(&mut self, t: f64, x: &[[f64; 2]], with_tangent: bool) {
        let sys = &mut self.sys;
        let f = &mut sys.f_ext;
        f.iter_mut().for_each(|v| *v = 0.0);
        let loading = &self.model.loading;
        let mut pressure_edge = 0;
        for load in &loading.loads {
            let amp = loading.amplitude(load.amplitude, t);
            for e in &load.edges {
                let (a, b) = (e[0], e[1]);
                match &load.kind {
                    LoadKind::Traction(tr) | LoadKind::Force(tr) => {
                        let scale = if matches!(load.kind, LoadKind::Force(_)) { 1.0 / load.length0 } else { 1.0 };
                        let (pa, pb) = (self.model.x0[a], self.model.x0[b]);
                        let len = ((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2)).sqrt();
                        for c in 0..2 {
                            let v = 0.5 * amp * scale * tr[c] * len;
                            f[2 * a + c] += v;
                            f[2 * b + c] += v;
                        }
                    }
                    LoadKind::Pressure(p) => {
                        // force on each node: −p/2 · (outward normal × length) = −p/2 (Δy, −Δx)
                        let p = p * amp;
                        let (xa, xb) = (x[a], x[b]);
                        let fx = -0.5 * p * (xb[1] - xa[1]);
                        let fy = 0.5 * p * (xb[0] - xa[0]);
                        for n in [a, b] {
                            f[2 * n] += fx;
                            f[2 * n + 1] += fy;
                        }
                        if with_tangent {
                            // K −= ∂f_ext/∂x:  ∂fx/∂y_b = −p/2, ∂fx/∂y_a = p/2, ∂fy/∂x_b = p/2,
                            // ∂fy/∂x_a = −p/2 (block dofs [a_x, a_y, b_x, b_y])
                            for ni in 0..2 {
                                for (row, col, d) in [(2 * ni, 3, -0.5 * p), (2 * ni, 1, 0.5 * p), (2 * ni + 1, 2, 0.5 * p), (2 * ni + 1, 0, -0.5 * p)] {
                                    sys.maps.pressure.add_entry(&mut sys.kk.values, pressure_edge, row, col, -d);
                                }
                            }
                        }
                        pressure_edge += 1;
                    }
                }
            }
        }
    }

    /// Assemble at displacement `u` (see the module docs for the order of the terms): fills
    /// `f_int`, `f_ext`, the free residual `r` and (if asked) the tangent. Returns ‖r‖.
    pub(super) fn evaluate(&mut self, u: &[f64], inc: TimeIncrement, vol: &[Volumetric], tangent: bool) -> Result<f64, NewtonFailure> {
        let x = self.coords(u);
        // on several processes the element tangent is summed onto rank 0 right after the
        // element assembly; the rest (loads, contact, springs, inertia) rank 0 alone adds
        // (a part's every process adds its own terms to its rows)
        let root_tangent = tangent && (self.sys.comm.is_root() || self.sys.part.is_some());
        // the barrier first: an iterate it cannot take fails before any work, and a pair
        // without a block grows the pattern before the elements fill it
        let barrier = self.evaluate_barrier(&x, tangent);
        self.sys.agree_part(barrier, "the barrier met a contact")?;
        {
            let _t = self.clock.scope(Phase::ElementAssembly);
            let sys = &mut self.sys;
            let kk = if tangent { Some(&mut sys.kk) } else { None };
            let assembled = sys.assembler.assemble(&self.model, u, &self.sol.fields.states, &self.sol.fields.alpha, vol, Some(&self.sol.j0), inc, kk, &mut sys.f_int, &mut sys.trial_fields, sys.pool.as_ref());
            match &sys.par {
                Some(p) => {
                    p.agree(assembled)?;
                    // every dof and every tangent entry of the elements belongs to one body, so
                    // only its owner adds to it: the sums are exact, and rank 0 then adds the
                    // rest in the serial order (the run is bit-identical to the serial one)
                    p.comm.sum_in_place(&mut sys.f_int);
                    if tangent {
                        p.comm.sum_to_root(&mut sys.kk.values);
                    }
                }
                None if sys.part.is_some() => sys.agree_elements(assembled)?,
                None => assembled?,
            }
        }
        self.external_forces(inc.time, &x, root_tangent);
        // element forces alone: with contact they balance the contact forces, which makes them
        // the force scale of a problem driven by walls (no external force, no reaction)
        self.sys.f_elem_norm = if self.sys.part.is_some() { self.sys.norm_dofs(&self.sys.f_int) } else { self.sys.f_int.iter().map(|v| v * v).sum::<f64>().sqrt() };
        if let Some(c) = self.contact.as_mut() {
            let _t = self.clock.scope(Phase::ContactAssembly);
            let sys = &mut self.sys;
            let walls = self.model.wall_planes(inc.time);
            let tangent_out = root_tangent.then_some(ContactTangent { values: &mut sys.kk.values, pairs: &sys.maps.pairs, nodes: &sys.maps.nodes, multipliers: &sys.maps.multipliers });
            self.contact_stats = match &sys.par {
                // each process evaluates the pairs of its own particles' slave nodes; the
                // evaluations go to every process (the tangent blocks to rank 0), which add
                // them in the serial order
                Some(p) if c.spec.method != crate::contact::ContactMethod::Lagrange => {
                    c.evaluate(&x, &walls, tangent, &|body| p.owns_body(body), &mut self.contact_evals);
                    let all = p.gather_contact(&self.contact_evals, tangent, c.boundary.pair_width());
                    c.apply(&all, &x, &mut sys.f_int, tangent_out)
                }
                _ => c.add(&x, &walls, &mut sys.f_int, tangent_out, &mut self.contact_evals),
            };
            // the stabilisation springs (in residual and tangent, dissipate energy) and the
            // tangent-only regularisation
            self.springs.add(u, &mut sys.f_int, root_tangent.then_some((&mut sys.kk.values[..], &sys.maps.diagonal)));
        }
        if self.barrier.is_some() {
            self.add_barrier(u, root_tangent);
            let sys = &mut self.sys;
            self.springs.add(u, &mut sys.f_int, root_tangent.then_some((&mut sys.kk.values[..], &sys.maps.diagonal)));
        }
        // implicit dynamics: inertia (HHT-weighted) in F_int, M/((1+α)βΔt²) on the diagonal
        if let Some(dy) = self.dynamics.as_ref() {
            let sys = &mut self.sys;
            // (a part: its own dofs; the ghosts' inertia is their owners')
            dy.add_inertia(u, inc.dt, sys.own_dofs(), &mut sys.f_int, root_tangent.then_some((&mut sys.kk.values[..], &sys.maps.diagonal)));
        }
        let sys = &mut self.sys;
        if let Some(p) = &sys.part {
            // the ghosts' forces to their owners, and the sums back to every copy
            p.nodes.reverse_add(&mut sys.f_int, 2);
            p.nodes.forward(&mut sys.f_int, 2);
            p.nodes.forward(&mut sys.f_ext, 2);
        }
        if !sys.eq_offset.is_empty() {
            for (f, o) in sys.f_int.iter_mut().zip(&sys.eq_offset) {
                *f += o;
            }
        }
        let mut norm2 = 0.0;
        let own = sys.own_eqs();
        for (d, &q) in sys.assembler.eq.iter().enumerate() {
            if q != FIXED {
                let v = sys.f_ext[d] - sys.f_int[d];
                sys.r[q] = v;
                if q < own {
                    norm2 += v * v;
                }
            }
        }
        let mut norm2 = sys.sum(norm2);
        // Lagrange-multiplier rows (scaled to forces, see `Multipliers::rows`)
        if let Some(c) = self.contact.as_ref() {
            let n_free = sys.assembler.n_free;
            for (k, &f) in c.lm.rows.iter().enumerate() {
                sys.r[n_free + k] = -f;
                norm2 += f * f;
            }
        }
        Ok(norm2.sqrt())
    }

    /// Factorise the tangent (the solving processes; the others learn the outcome).
    pub(super) fn factor(&mut self) -> Result<(), NewtonFailure> {
        let _t = self.clock.scope(Phase::LinearSolve);
        let sys = &mut self.sys;
        if sys.distributed_solve && sys.part.is_none() {
            // rank 0 holds the whole tangent (elements summed, contact added): every process
            // needs the rows of its particles
            sys.comm.broadcast(&mut sys.kk.values);
        }
        self.clock.count_factorisation();
        let r = if sys.solves_here() { sys.linear.factor(&sys.kk).map_err(|e| NewtonFailure::Linear(e.to_string())) } else { Ok(()) };
        sys.agree(r, "factorisation")
    }

    /// Factor the tangent only if it is positive definite: true when it is (factored), false
    /// when it is not or the factorisation failed (nothing usable is held). The solving
    /// process's answer, on every process. Cheaper than [`Simulation::factor`] on an indefinite
    /// tangent, whose indefinite fallback factorisation the barrier's descent never solves with
    /// (it shifts or projects the tangent and factors again).
    pub(super) fn factor_definite(&mut self) -> bool {
        let _t = self.clock.scope(Phase::LinearSolve);
        let sys = &mut self.sys;
        if sys.distributed_solve && sys.part.is_none() {
            sys.comm.broadcast(&mut sys.kk.values);
        }
        self.clock.count_factorisation();
        let r = if sys.solves_here() { sys.linear.factor_definite(&sys.kk).map_err(|e| NewtonFailure::Linear(e.to_string())) } else { Ok(true) };
        let definite = matches!(r, Ok(true));
        if sys.agree(r.map(|_| ()), "factorisation").is_err() {
            return false;
        }
        let mut flag = [if definite { 1.0 } else { 0.0 }];
        if sys.par.is_some() {
            sys.comm.broadcast(&mut flag);
        }
        // (a part: definite when so on every process)
        sys.min(flag[0]) > 0.5
    }

    /// Solve `kk du = r` (rank 0 solves, the others receive `du`).
    pub(super) fn solve_linear(&mut self) -> Result<(), NewtonFailure> {
        self.solve_linear_with(false)
    }

    /// [`Simulation::solve_linear`]; `indefinite`: the tangent may be indefinite
    /// ([`crate::linalg::LinearSolver::solve_indefinite`]).
    pub(super) fn solve_linear_with(&mut self, indefinite: bool) -> Result<(), NewtonFailure> {
        let sys = &mut self.sys;
        let r = if sys.solves_here() {
            let solved = if indefinite { sys.linear.solve_indefinite(&sys.kk, &sys.r, &mut sys.du) } else { sys.linear.solve(&sys.kk, &sys.r, &mut sys.du) };
            match solved {
                Ok(st) => {
                    self.clock.count_solve(st.iterations);
                    Ok(())
                }
                Err(e) => Err(NewtonFailure::Linear(e.to_string())),
            }
        } else {
            Ok(())
        };
        let r = sys.agree(r, "linear solve");
        // (the distributed solve leaves the same update on every process)
        if r.is_ok() && sys.par.is_some() && !sys.distributed_solve {
            sys.comm.broadcast(&mut sys.du);
        }
        r
    }
}

/// A linear-algebra result of rank 0 (the only one that factors and solves), known to every
/// process of a run on several processes (`par`); unchanged on one.
pub(super) fn agree_linear(par: Option<&Distribution>, r: Result<(), NewtonFailure>, what: &str) -> Result<(), NewtonFailure> {
    let Some(p) = par else { return r };
    // the other processes wait here while rank 0 factorises and solves: asleep, so that their
    // cores are free for other work (a blocking collective spins on them; with more ranks than
    // cores it took the core of a rank that was working)
    p.comm.idle_barrier();
    let mut failed = [if r.is_err() { 1.0 } else { 0.0 }];
    p.comm.broadcast(&mut failed);
    match r {
        Err(e) => Err(e),
        Ok(()) if failed[0] > 0.0 => Err(NewtonFailure::Linear(format!("{what} failed on rank 0"))),
        Ok(()) => Ok(()),
    }
}
