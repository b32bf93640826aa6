//! Distributed runs: the collective operations the solver driver needs, behind one small trait,
//! and the bookkeeping of which process owns which work.
//!
//! Two ways to run on several processes:
//! - **Owned + ghost parts** ([`part`], `Simulation::new_part`): each process holds its own
//!   particles and, as ghosts, the other processes' particles within the contact reach of
//!   them ([`part::RankPart`], its nodes numbered own-first with an [`IndexMap`] over them);
//!   it evaluates its own elements and the barrier pairs whose first side is its own
//!   (`BarrierContact::evaluate_only`), the forces its pairs put on ghosts go to their owners
//!   (the reverse scatter) and come back summed (the forward scatter), every norm, dot
//!   product, energy, extremum and collision-free step fraction is reduced over the processes,
//!   and PETSc assembles the distributed tangent from each process's own and ghost rows
//!   (`linalg::petsc::Rows::Part`) and solves it. No process holds the whole mesh or state.
//!   For now: the barrier contact without ties, quasi-statics, no re-meshing, the ghosts chosen
//!   when the part is made (the run stops at once, naming the bodies, when they no longer cover the
//!   contacts), and the library's API only (the command line runs the replicated model).
//!   `tests/mpi_parts_run.rs` holds it to the whole serial run on 1–4 processes.
//! - **The replicated model** (what `mpfem run` under `mpirun` does, below).
//!
//! The model is replicated on every process (each builds the same [`Model`] from the case);
//! the work is distributed: every process owns whole particles (a METIS partition of the
//! particle graph, [`crate::distribute::partition_particles`]) and evaluates the element
//! kernels of its own elements only, into arrays laid out on the same global sparsity pattern
//! everywhere. The driver ([`crate::solver::Simulation`]) then
//! - sums the element forces over the processes (every process gets them: residual, norms,
//!   reactions and energies are then the same on every process, and so are the Newton, line
//!   search and step decisions),
//! - sums the element tangent onto process 0, which adds the loads, contact and stabilisation
//!   terms, factors and solves it (the faer sparse LU / Cholesky of the serial run: the
//!   gathered reference solver) and broadcasts the update,
//! - agrees on failures (an inverted element anywhere fails the evaluation everywhere),
//! - makes the element fields (states, stresses, pressures) of all elements known everywhere
//!   after each Newton solve (for the augmented-Lagrangian updates, the commit and the output).
//!
//! Contact is shared out by slave node: every process selects the same pairs (the search is
//! replicated, about a tenth of the contact time), then evaluates the node-to-segment and
//! node-to-wall kernels of the slave nodes of its own particles only. The master segments a
//! process's slaves see on other processes' particles (the ghosts of the contact zones) are
//! at hand, as every process holds the whole configuration. The evaluated pairs go to every
//! process (forces, gaps, pressures, trial and augmented histories; the tangent blocks to
//! process 0 only: [`Distribution::gather_contact`], the one place that knows how an
//! evaluation is laid out for the exchange), and every process adds them in the serial order
//! ([`crate::contact::ContactProblem::apply`]): the contact histories, statistics and nodal
//! contact fields are then the same everywhere and bit-identical to the serial run's. The
//! contact forces are added on every process after the element forces are summed, the contact
//! tangent on process 0 only. Lagrange multipliers (`method = "lagrange"`) are still evaluated
//! on every process.
//!
//! Every element force and element tangent entry belongs to one particle, so one process adds
//! to it and the sums over the processes add only zeros: they are exact, process 0 then adds
//! everything else in the serial order, and a run on any number of processes is bit-identical
//! to the serial run (`tests/mpi_ranks.rs`).
//!
//! Physics code (elements, materials, contact kernels) never sees this module; a serial run uses
//! [`Serial`], whose operations do nothing, and takes exactly the serial code path.
//!
//! Repartitioning: when the model changes (a particle is re-meshed, which changes its element
//! count; bodies keep their indices), the simulation is rebuilt and [`Distribution::build`] is
//! given the previous owners: they are kept while their load imbalance with the new element
//! counts is at most `[solver] repartition_imbalance`, otherwise METIS partitions the particle
//! graph again ([`crate::distribute::rebalance`]). Since all state is replicated, a change of
//! owners moves no data: it only changes who assembles which elements (and who owns which
//! Schwarz blocks). The figures go to the log and to `summary.json` ([`PartitionStats`]). On
//! owned + ghost parts ([`part`]) the particles that change owner carry their data to their new
//! owners (`solver/migrate.rs`, [`crate::solver::Simulation::migrated`]).

pub mod part;

pub use crate::comm::{launch, Collective, IndexMap, Serial};

use crate::assembly::{AssemblyError, ElementFields};
use crate::contact::problem::Eval;
use crate::contact::{ContactEvals, PairHistory};
use crate::element::N_ENH;
use crate::material::{MatState, MaterialError};
use crate::model::Model;
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::time::Instant;

/// Values per element exchanged by [`Distribution::sync_fields`]: 4 Gauss points × (state: 6,
/// stress: 4), pressure, Θ and the enhanced modes.
const FIELD_WIDTH: usize = 4 * 6 + 16 + 2 + N_ENH;

/// The partition of a run over its processes, for `summary.json` (`run.partition`): the
/// current one and the repartitions so far. One process: `ranks` 1, `imbalance` 1, `edge_cut`
/// 0, no repartitions. Missing fields read as these defaults (older files).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PartitionStats {
    /// Number of processes.
    pub ranks: usize,
    /// Heaviest process's element count over the mean ([`crate::distribute::imbalance`]).
    pub imbalance: f64,
    /// Close pairs of particles (edges of the particle graph) owned by different processes.
    pub edge_cut: usize,
    /// Model changes (re-meshes) after which the particle graph was partitioned again, the
    /// imbalance of the owners being above `[solver] repartition_imbalance`.
    pub repartitions: usize,
    /// Model changes after which the owners were kept (imbalance within the threshold).
    pub kept: usize,
    /// Particles that changed owner over the repartitions.
    pub moved: usize,
    /// Wall-clock time spent on the partitions and decisions (graphs, METIS), s.
    pub time_s: f64,
}

impl Default for PartitionStats {
    fn default() -> Self {
        Self { ranks: 1, imbalance: 1.0, edge_cut: 0, repartitions: 0, kept: 0, moved: 0, time_s: 0.0 }
    }
}

/// Who owns what in a run on several processes (more than one).
pub struct Distribution {
    pub comm: Arc<dyn Collective>,
    /// Owning rank of every body.
    pub body_owner: Vec<usize>,
    /// Whether this process evaluates element `e`.
    pub owned_elements: Vec<bool>,
    /// Position of every element in the serial assembly order (colour by colour, see
    /// [`crate::assembly`]): a serial assembly reports the first element that fails in this
    /// order, and so does [`Distribution::agree`].
    elem_order: Vec<u64>,
}

impl Distribution {
    /// Partition the model's bodies over the processes of `comm` (METIS k-way on the particle
    /// graph: the same on every process, as the model is). `None` for a single process.
    pub fn new(model: &Model, comm: Arc<dyn Collective>) -> Option<Self> {
        Self::build(model, comm, None, f64::INFINITY, &mut PartitionStats::default())
    }

    /// [`Distribution::new`] for a model that has changed (a re-mesh): the `previous` owners of
    /// its bodies are kept when their imbalance with the new element counts is at most
    /// `threshold`, otherwise the particle graph is partitioned again
    /// ([`crate::distribute::rebalance`]); without previous owners it is partitioned. `stats`
    /// (the run's so far) is brought up to date: the current imbalance and edge cut, a
    /// repartition or a kept partition counted when there were previous owners, the time
    /// spent. Rank 0 logs the decision (imbalance before and after, edge cut, particles that
    /// changed owner, time).
    ///
    /// Every process takes the same decision, as it is computed from the replicated model; to
    /// be sure, rank 0's owners are broadcast and used everywhere (a difference is logged as a
    /// warning). `None` for a single process (`stats` is then left as it is but for `ranks`).
    pub fn build(model: &Model, comm: Arc<dyn Collective>, previous: Option<&[usize]>, threshold: f64, stats: &mut PartitionStats) -> Option<Self> {
        let size = comm.size();
        stats.ranks = size;
        if size <= 1 {
            return None;
        }
        let t0 = Instant::now();
        let graph = crate::distribute::particle_graph_or_weights(model);
        let decision = crate::distribute::rebalance(&graph, previous, size, threshold, partition::metis_kway);
        // rank 0's owners everywhere (indices are exact in f64)
        let mut buf: Vec<f64> = decision.owner.iter().map(|&o| o as f64).collect();
        comm.broadcast(&mut buf);
        let body_owner: Vec<usize> = buf.iter().map(|&o| o as usize).collect();
        let differs = comm.max(if body_owner != decision.owner { 1.0 } else { 0.0 }) > 0.0;
        let seconds = t0.elapsed().as_secs_f64();
        stats.imbalance = crate::distribute::imbalance(&graph, &body_owner, size);
        stats.edge_cut = partition::edge_cut(&graph, &body_owner);
        stats.time_s += seconds;
        if previous.is_some() {
            if decision.repartitioned {
                stats.repartitions += 1;
                stats.moved += decision.moved;
            } else {
                stats.kept += 1;
            }
        }
        let rank = comm.rank();
        let owned_elements: Vec<bool> = model.elem_body.iter().map(|&b| body_owner[b] == rank).collect();
        let mut per_rank = vec![(0usize, 0usize); size];
        for (b, &r) in body_owner.iter().enumerate() {
            per_rank[r].0 += 1;
            per_rank[r].1 += model.bodies[b].mesh.n_elements();
        }
        if comm.is_root() {
            if differs {
                tracing::warn!("the processes computed different particle partitions; rank 0's is used");
            }
            let imbalance_after = format!("{:.4}", stats.imbalance);
            if previous.is_none() {
                tracing::info!(ranks = size, bodies = graph.n_vertices(), imbalance = imbalance_after, edge_cut = stats.edge_cut, seconds, "particle partition");
            } else {
                let what = if decision.repartitioned { "model changed: particles repartitioned (imbalance above the threshold)" } else { "model changed: particle owners kept (imbalance within the threshold)" };
                tracing::info!(
                    imbalance_before = decision.imbalance_before.map_or_else(|| "-".to_string(), |v| format!("{v:.4}")),
                    imbalance_after,
                    threshold,
                    edge_cut_before = decision.edge_cut_before.map_or(-1, |c| c as i64),
                    edge_cut_after = stats.edge_cut,
                    moved = decision.moved,
                    repartitions = stats.repartitions,
                    seconds,
                    "{what}"
                );
            }
            tracing::info!(ranks = size, ?per_rank, "bodies and elements per rank");
        }
        let mut elem_order = vec![0; model.elements.len()];
        for (k, &e) in crate::assembly::color_elements(&model.elements, model.n_nodes()).iter().flatten().enumerate() {
            elem_order[e] = k as u64;
        }
        Some(Self { comm, body_owner, owned_elements, elem_order })
    }

    /// The assembly result of every process, agreed: an element failure on any process fails
    /// all of them with the same error, that of the element a serial assembly (one thread)
    /// would report, the first to fail in its order. (Which element failed matters: a run that
    /// re-meshes re-meshes its particle.)
    pub fn agree(&self, local: Result<(), AssemblyError>) -> Result<(), AssemblyError> {
        let order = |e: &AssemblyError| self.elem_order.get(e.element).copied().unwrap_or(u64::MAX - 1);
        let mine = local.as_ref().err().map_or(u64::MAX, order);
        let first = self.comm.min_u64(mine);
        if first == u64::MAX {
            return Ok(());
        }
        // the failing process tells the others what failed (each element has one owner, so
        // one process fills the buffer in)
        let mut code = [0.0; 4];
        if mine == first {
            if let Err(e) = &local {
                code = encode_failure(e);
            }
        }
        self.comm.sum_in_place(&mut code);
        Err(decode_failure(&code))
    }

    /// Make the element fields of every element the owner's, on every process: each process
    /// fills in its own elements (the others are zero) and the buffers are summed, which adds
    /// only zeros to every value, so the values arrive exactly.
    pub fn sync_fields(&self, fields: &mut ElementFields) {
        let ne = self.owned_elements.len();
        let mut buf = vec![0.0; ne * FIELD_WIDTH];
        for (e, chunk) in buf.chunks_exact_mut(FIELD_WIDTH).enumerate() {
            if !self.owned_elements[e] {
                continue;
            }
            let mut k = 0;
            let mut put = |v: f64| {
                chunk[k] = v;
                k += 1;
            };
            for g in 0..4 {
                let s = &fields.states[e][g];
                s.cp_inv.iter().for_each(|&v| put(v));
                put(s.eps_p);
                put(s.eps_c);
                fields.sig[e][g].iter().for_each(|&v| put(v));
            }
            put(fields.pressure[e]);
            put(fields.theta[e]);
            fields.alpha[e].iter().for_each(|&v| put(v));
        }
        self.comm.sum_in_place(&mut buf);
        for (e, chunk) in buf.chunks_exact(FIELD_WIDTH).enumerate() {
            if self.owned_elements[e] {
                continue;
            }
            let mut it = chunk.iter().copied();
            let mut get = || it.next().unwrap_or(0.0);
            for g in 0..4 {
                let mut s = MatState::default();
                s.cp_inv.iter_mut().for_each(|v| *v = get());
                s.eps_p = get();
                s.eps_c = get();
                fields.states[e][g] = s;
                fields.sig[e][g].iter_mut().for_each(|v| *v = get());
            }
            fields.pressure[e] = get();
            fields.theta[e] = get();
            fields.alpha[e].iter_mut().for_each(|v| *v = get());
        }
    }

    /// Whether this process owns body `b` (evaluates its elements and the contact pairs of its
    /// slave nodes).
    pub fn owns_body(&self, b: usize) -> bool {
        self.body_owner.get(b) == Some(&self.comm.rank())
    }

    /// The contact evaluations of every process, concatenated in process order, on every
    /// process; the tangent blocks (`tangent`) on rank 0 only. `width` is the contact's pair
    /// width (6 or 10 dofs).
    pub fn gather_contact(&self, local: &ContactEvals, tangent: bool, width: usize) -> ContactEvals {
        let mut out = ContactEvals::default();
        out.pairs = all_gather_evals(self.comm.as_ref(), &local.pairs);
        out.walls = all_gather_evals(self.comm.as_ref(), &local.walls);
        let buf: Vec<f64> = local.gaps.iter().flat_map(|&(i, g)| [i as f64, g]).collect();
        out.gaps = self.comm.all_gather_varcount(&buf).chunks_exact(2).map(|r| (r[0] as usize, r[1])).collect();
        if tangent {
            let indices = |v: &[usize]| v.iter().map(|&k| k as f64).collect::<Vec<f64>>();
            out.pair_blocks = self.comm.gather_varcount_to_root(&indices(&local.pair_blocks)).iter().map(|&k| k as usize).collect();
            out.pair_block_values = self.comm.gather_varcount_to_root(&local.pair_block_values);
            out.wall_blocks = self.comm.gather_varcount_to_root(&indices(&local.wall_blocks)).iter().map(|&k| k as usize).collect();
            out.wall_block_values = self.comm.gather_varcount_to_root(&local.wall_block_values);
            debug_assert!(!self.comm.is_root() || out.pair_block_values.len() == out.pair_blocks.len() * width * width);
        }
        out
    }
}

/// An element failure as four numbers (element, kind, two values), for an exchange.
pub fn encode_failure(e: &AssemblyError) -> [f64; 4] {
    let [kind, a, b] = match e.source {
        MaterialError::InvertedElement(j) => [1.0, j, 0.0],
        MaterialError::ReturnMapFailed { iterations, residual } => [2.0, iterations as f64, residual],
        MaterialError::InvalidVolumeRatio(j) => [3.0, j, 0.0],
    };
    [e.element as f64, kind, a, b]
}

/// The element failure of [`encode_failure`]'s numbers.
pub fn decode_failure(code: &[f64; 4]) -> AssemblyError {
    let source = match code[1] as i64 {
        2 => MaterialError::ReturnMapFailed { iterations: code[2] as usize, residual: code[3] },
        3 => MaterialError::InvalidVolumeRatio(code[2]),
        _ => MaterialError::InvertedElement(code[2]),
    };
    AssemblyError { element: code[0] as usize, source }
}

fn put_history(v: &mut Vec<f64>, h: &PairHistory) {
    v.extend_from_slice(&[h.xi_stick, h.lambda_n, h.lambda_t, f64::from(u8::from(h.active))]);
}

fn get_history(v: &[f64]) -> PairHistory {
    PairHistory { xi_stick: v[0], lambda_n: v[1], lambda_t: v[2], active: v[3] != 0.0 }
}

/// Values of a contact evaluation with a force of width N in an exchange: key, force (N),
/// gap, pressure, violation, slip, active, trial history (4), augmented history (4).
const fn eval_width(n: usize) -> usize {
    1 + n + 5 + 8
}

fn write_eval<const N: usize>(e: &Eval<N>, v: &mut Vec<f64>) {
    v.push(e.key as f64);
    v.extend_from_slice(&e.f);
    let flag = |b: bool| f64::from(u8::from(b));
    v.extend_from_slice(&[e.gap, e.pressure, e.violation, flag(e.slip), flag(e.active)]);
    put_history(v, &e.trial);
    put_history(v, &e.aug);
}

fn read_eval<const N: usize>(r: &[f64]) -> Eval<N> {
    let mut f = [0.0; N];
    f.copy_from_slice(&r[1..1 + N]);
    let s = &r[1 + N..];
    Eval { key: r[0] as usize, f, gap: s[0], pressure: s[1], violation: s[2], slip: s[3] != 0.0, active: s[4] != 0.0, trial: get_history(&s[5..9]), aug: get_history(&s[9..13]) }
}

/// Every process's evaluations, concatenated in process order, on every process.
fn all_gather_evals<const N: usize>(comm: &dyn Collective, local: &[Eval<N>]) -> Vec<Eval<N>> {
    let mut buf = Vec::with_capacity(local.len() * eval_width(N));
    for e in local {
        write_eval(e, &mut buf);
    }
    comm.all_gather_varcount(&buf).chunks_exact(eval_width(N)).map(read_eval).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every kind of element failure crosses an exchange unchanged (the numbers are exact in
    /// f64), so every process reports and acts on the same failure.
    #[test]
    fn element_failures_survive_the_exchange() {
        for source in [MaterialError::InvertedElement(-0.25), MaterialError::ReturnMapFailed { iterations: 50, residual: 3.5e-7 }, MaterialError::InvalidVolumeRatio(0.0)] {
            let e = AssemblyError { element: 123_456, source };
            assert_eq!(decode_failure(&encode_failure(&e)), e);
        }
    }
}
