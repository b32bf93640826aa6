//! The contact problem of a model: the boundary, the search, the frozen pairs with their
//! histories, the Lagrange multipliers, and the evaluation of every pair into forces, tangent
//! blocks, statistics and nodal results.
//!
//! Lifecycle per step (after LLNL Tribol): [`ContactProblem::select_pairs`] on the converged
//! configuration (search → pairs frozen for the step) → at every Newton iterate
//! [`ContactProblem::evaluate`] (the kernels of the pairs a process owns, from the committed
//! histories) and [`ContactProblem::apply`] (every process's evaluations, in the serial order:
//! forces, tangent blocks through the assembler's [`BlockMap`]s, trial histories, statistics,
//! nodal results) → optionally [`ContactProblem::augment`] (Uzawa) and solve again →
//! [`ContactProblem::commit`]. On one process `apply(evaluate(..))` is the whole evaluation;
//! on several the evaluations are exchanged between `evaluate` and `apply` by the caller
//! ([`crate::parallel`]): this module never sees a process.

use super::boundary::{Boundary, ContactBody};
use super::enforce::{self, ContactKind, PairHistory, PairResult, PenaltyParams};
use super::geometry::{nts_project, Linearised, PairGeometry, SegmentGeometry, SmoothGeometry, Wall};
use super::pairs::{Backup, FrozenPair, PairSet, TOUCH};
use super::search::ContactSearch;
use super::smooth::{self, NDOF};
use super::{ContactMethod, ContactParams, Segment};
use crate::linalg::BlockMap;
use std::collections::HashMap;

/// A contact normal holds a body in a coordinate direction when its component along that
/// direction exceeds this (|cos| > 0.2, i.e. within ~78° of the axis).
pub const SUPPORT_COSINE: f64 = 0.2;

/// What the contact contributions of one evaluation amount to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactStats {
    /// Normal force of the particles on each wall (N/mm, positive in compression), in the order
    /// of the model's walls.
    pub wall_force: Vec<f64>,
    /// The whole force of the particles on each wall, normal and friction (N/mm, a vector in
    /// the global axes): the sum of the wall pairs' contributions to the internal force, so that
    /// −`wall_load`·n (n the wall's normal into the die) is `wall_force`.
    pub wall_load: Vec<[f64; 2]>,
    /// Largest penetration over all active pairs (mm, ≥ 0).
    pub max_penetration: f64,
    /// Number of active pairs (node-to-segment and node-to-wall).
    pub active: usize,
    /// Largest violation of the enforced constraints (mm): penetration, and for tied or
    /// sticking pairs also the normal separation and the elastic tangential slip. The
    /// augmented Lagrangian drives it below its tolerance.
    pub violation: f64,
}

/// Contact state per node (global node numbers) at one evaluation, for the results files.
/// Every node-to-segment pair contributes to its slave node (two-pass: each boundary node is a
/// slave of its own pairs), every node-to-wall pair to its node.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NodalContact {
    /// Normal contact pressure (MPa, positive in compression, negative only where a tie pulls):
    /// the normal component of `force` over the node's tributary contact length, in the current
    /// configuration, on both sides of a pair alike ([`NodalContact::set_tractions`]).
    pub pressure: Vec<f64>,
    /// Contact shear stress (MPa): the tangential component of `force` over the same length,
    /// positive along the boundary's direction (the particle on its left, counter-clockwise).
    #[serde(default)]
    pub shear: Vec<f64>,
    /// Smallest normal gap of the node over its pairs and the walls (mm, negative =
    /// penetration); NaN for a node without any candidate.
    pub gap: Vec<f64>,
    /// 0 open, 1 sliding (frictionless, or Coulomb slip), 2 sticking, 3 tied (the largest over
    /// the node's pairs).
    pub status: Vec<i32>,
    /// Force the contacts exert on the node (N/mm): the slave's and the master nodes' shares.
    pub force: Vec<[f64; 2]>,
    /// Normal force each node exerts on each wall (N/mm, compression positive), `[wall][node]`;
    /// summed over the nodes it is the wall force of the history.
    pub wall_force: Vec<Vec<f64>>,
}

impl NodalContact {
    fn reset(&mut self, n_nodes: usize, n_walls: usize) {
        self.pressure.clear();
        self.pressure.resize(n_nodes, 0.0);
        self.gap.clear();
        self.gap.resize(n_nodes, f64::NAN);
        self.status.clear();
        self.status.resize(n_nodes, 0);
        self.shear.clear();
        self.shear.resize(n_nodes, 0.0);
        self.force.clear();
        self.force.resize(n_nodes, [0.0; 2]);
        self.wall_force.resize(n_walls, Vec::new());
        for w in &mut self.wall_force {
            w.clear();
            w.resize(n_nodes, 0.0);
        }
    }

    fn gap(&mut self, node: usize, g: f64) {
        if g.is_finite() && !(self.gap[node] <= g) {
            self.gap[node] = g;
        }
    }

    /// Record an active pair of `kind` acting on `node`.
    fn active(&mut self, node: usize, kind: ContactKind, slip: bool) {
        let s = match kind {
            ContactKind::Cohering => 3,
            ContactKind::Sliding => 1,
            ContactKind::Rubbing { mu } if slip || !(mu > 0.0) => 1,
            ContactKind::Rubbing { .. } => 2,
        };
        self.status[node] = self.status[node].max(s);
    }

    /// The contact pressure and shear of every node from its contact force (`force`, the
    /// whole force the contacts put on it, both sides of a pair alike) at coordinates `x`,
    /// with the boundary `segments` (oriented with their particle on the left): the force's
    /// normal and tangential components over the node's tributary contact length.
    ///
    /// The tributary length is half of each boundary edge at the node that faces the force
    /// (the force within 30° of the edge's inward normal), so that a node at a particle's
    /// corner takes only the side in contact (a square block's corner on a flat: half of its
    /// top edge, not of its side as well); when no edge faces it (a force along a corner's
    /// bisector), both edges. The normal is that of those edges together (their length-weighted
    /// mean). So a uniform pressure p on a straight side reads p at every node of it, ends
    /// included, and Σ pressure × length over a side is the normal force it carries. A node
    /// that carries a contact force but is not the node of a pair itself (an end of the segment
    /// of another node's pair) is marked in contact (status 1) if it was open.
    pub fn set_tractions(&mut self, x: &[[f64; 2]], segments: &[Segment]) {
        let n = x.len();
        self.pressure.clear();
        self.pressure.resize(n, 0.0);
        self.shear.clear();
        self.shear.resize(n, 0.0);
        // per node: the (at most two) boundary edges at it, as vectors along the boundary
        let mut edges: Vec<[[f64; 2]; 2]> = vec![[[0.0; 2]; 2]; n];
        let mut count = vec![0u8; n];
        for s in segments {
            let [a, b] = s.nodes;
            let e = [x[b][0] - x[a][0], x[b][1] - x[a][1]];
            for v in [a, b] {
                if self.force[v] != [0.0; 2] && count[v] < 2 {
                    edges[v][count[v] as usize] = e;
                    count[v] += 1;
                }
            }
        }
        const FACING: f64 = 0.866_025_403_784_438_6; // cos 30°
        for v in 0..n {
            let f = self.force[v];
            let size = f[0].hypot(f[1]);
            if size == 0.0 || count[v] == 0 {
                continue;
            }
            if self.status[v] == 0 {
                self.status[v] = 1;
            }
            let all = &edges[v][..count[v] as usize];
            // an edge e = (Δx, Δy) has the outward normal (Δy, −Δx)/ℓ; the force faces it when
            // it points along the inward normal: −f·n ≥ cos 30° |f|
            let faces = |e: &[f64; 2]| -(f[0] * e[1] - f[1] * e[0]) >= FACING * size * e[0].hypot(e[1]);
            let (mut facing, mut nf) = ([[0.0; 2]; 2], 0);
            for e in all.iter().filter(|e| faces(e)) {
                facing[nf] = *e;
                nf += 1;
            }
            let used: &[[f64; 2]] = if nf == 0 { all } else { &facing[..nf] };
            let length: f64 = used.iter().map(|e| 0.5 * e[0].hypot(e[1])).sum();
            // the sum of the edge vectors is the length-weighted mean direction
            let d = used.iter().fold([0.0; 2], |s, e| [s[0] + e[0], s[1] + e[1]]);
            let dl = d[0].hypot(d[1]);
            if !(length > 0.0) || !(dl > 0.0) {
                continue;
            }
            let (t, nrm) = ([d[0] / dl, d[1] / dl], [d[1] / dl, -d[0] / dl]);
            self.pressure[v] = -(f[0] * nrm[0] + f[1] * nrm[1]) / length;
            self.shear[v] = (f[0] * t[0] + f[1] * t[1]) / length;
        }
    }

    /// Add the force −f (f: the contribution to the internal force) on `nodes`.
    fn force(&mut self, nodes: &[usize], f: &[f64]) {
        for (i, &n) in nodes.iter().enumerate() {
            self.force[n][0] -= f[2 * i];
            self.force[n][1] -= f[2 * i + 1];
        }
    }
}

/// What [`ContactProblem::carry_history`] carried over a re-mesh (counts).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CarriedHistory {
    /// Active node-to-segment histories carried unchanged (slave node and master segment kept).
    pub kept: usize,
    /// Active node-to-segment histories whose master segment was re-meshed: the anchor moved
    /// onto the new boundary at the same point.
    pub moved: usize,
    /// Active node-to-segment histories dropped (their slave node is not in the new mesh).
    pub dropped: usize,
    /// Active node-to-wall histories carried.
    pub walls: usize,
    /// Committed Lagrange multipliers carried.
    pub multipliers: usize,
    /// Slave nodes whose tributary length took the old reference lengths of kept segments.
    pub areas: usize,
}

/// The committed contact state of a [`ContactProblem`] (global node and segment numbers), see
/// [`ContactProblem::state`].
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactState {
    /// Node-to-segment pair histories by (slave node, segment), sorted.
    pub nts: Vec<((usize, usize), PairHistory)>,
    /// Node-to-wall histories, `[wall][slave]`.
    pub walls: Vec<Vec<PairHistory>>,
    /// Committed Lagrange multipliers by candidate key, sorted.
    pub lm_committed: Vec<((u8, usize, usize), f64)>,
    /// Nodal contact results of the last committed step.
    pub nodal: NodalContact,
    /// Element size of each body used for the default penalty (kept over re-meshes).
    pub body_h: Vec<f64>,
    /// Tributary length of every slave node (mm): after a re-mesh the kept contact zones keep
    /// their old reference lengths ([`ContactProblem::carry_history`]), which a problem built
    /// afresh from the meshes would not know. Empty in checkpoints written before it was kept
    /// (the lengths of the meshes are used then).
    #[serde(default)]
    pub area: Vec<f64>,
}

/// A constraint carrying a Lagrange multiplier: a frozen node-to-segment pair (index into the
/// pairs) or a slave node against a wall.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Candidate {
    Pair(usize),
    Wall { wall: usize, slave: usize },
}

/// Lagrange-multiplier state (paper eq. 22–25), frictionless. One unknown λ_k (a contact
/// pressure, MPa, same sign as the penalty pressure) per candidate of the step; the contact
/// force is −λ A ∇g. The complementarity λ ≥ 0, g ≥ 0, λ g = 0 is written as
/// φ = min(λ, c g) = 0 (c the default penalty, MPa/mm, only a scale): at every evaluation a
/// candidate with λ − c g > 0 is *active* and its row F_λ = −A g enforces g = 0 (the transpose
/// of its force column), an inactive one has the row F_λ = −(A/c) λ, which drives λ to zero
/// ([`enforce::lagrange_row`]). Newton on this semismooth system is the primal–dual
/// active-set method (Hintermüller, Ito & Kunisch, SIAM J. Optim. 13, 2002). Node-to-segment
/// pairs are two-pass like the penalty methods (a node takes one master segment), so rows may
/// be nearly dependent.
///
/// Known limits (measured, see the contact issue's note): exact against rigid walls (Hertz
/// within 1.3 %); node-to-segment multipliers do not pass the contact patch test (local σ_yy
/// errors of ~60 % next to a non-matching interface, one- or two-pass: a mortar discretisation
/// is needed). Two-pass pairs over-constrain sliding between faceted particles: the 2 × 2
/// lateral job runs to solid ratio 0.95 only with `stabilisation_kind = "viscous"` and
/// `stabilise = "unsupported"`, and its wall pressure at 0.94 is then 5 % below the penalty
/// one (it fails near solid ratio 0.75 with the default inertial stabilisation); one-pass
/// pairs agree with the penalty within 1.5 % up to 0.85 but jam near 0.92 (seen again on
/// 2026-11-22: the one-pass choice breaks the mirror symmetry, the frictionless apex-to-apex
/// columns of discs then buckle and slide past each other, and an element inverts at 0.88).
/// With exact rows only the biaxial job ran (to 0.95, 2.0 % below the penalty pressure).
///
/// What fixed the 2 × 2 jobs (2026-11-22): with exact rows the symmetric tie-break cannot be
/// used (two discs touching apex to apex give two pairs with opposite, dependent rows), so
/// one arbitrary segment per node breaks the mirror symmetry, and the frictionless columns of
/// discs — an unstable equilibrium — buckle and slide. With the perturbed Lagrangian
/// (`contact.lagrange_regularisation` r, default 1e-4: active rows −A (g + r λ / c)) the
/// dependent rows are harmless, the tie-break is used, and the lateral job runs to 0.95 within
/// 0.3 % of the penalty pressures, with penetrations r λ / c ≈ 1e-7 mm.
#[derive(Clone, Debug, Default)]
pub struct Multipliers {
    pub candidates: Vec<Candidate>,
    /// Current iterate λ (MPa).
    pub lambda: Vec<f64>,
    /// λ at the start of the current Newton update (the base of the line search).
    pub start: Vec<f64>,
    /// c·F_λ of the last evaluation (a force, N/mm) and the scale c. The linear system is
    /// written for μ = λ/c (mm) with the rows multiplied by c — a symmetric diagonal scaling
    /// that gives the multiplier rows and columns the magnitude of the stiffness (c A) instead
    /// of A and A/c, which keeps the pivoting LU accurate.
    pub rows: Vec<f64>,
    pub scale: Vec<f64>,
    /// Committed multipliers by candidate key, to start the next step from.
    committed: HashMap<(u8, usize, usize), f64>,
    keys: Vec<(u8, usize, usize)>,
}

impl Multipliers {
    /// Remember the current iterate as the base of a Newton update.
    pub fn mark(&mut self) {
        self.start.clone_from(&self.lambda);
    }

    /// λ = start + η Δλ.
    pub fn step(&mut self, delta: &[f64], eta: f64) {
        for (k, l) in self.lambda.iter_mut().enumerate() {
            // the system's unknown is λ/c (see `rows`)
            *l = self.start[k] + eta * self.scale[k] * delta[k];
        }
    }
}

/// One pair as evaluated by the process that owns its slave node: what every process needs to
/// add it (the tangent block goes separately, to the solving process). `N` is the width of its
/// force: [`NDOF`] for node-to-segment pairs (the first [`Boundary::pair_width`] entries used),
/// 2 for node-to-wall pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eval<const N: usize> {
    /// The frozen pair's index, or `wall · n_slaves + slave` for a wall pair.
    pub key: usize,
    /// The contribution to the internal force.
    pub f: [f64; N],
    pub gap: f64,
    pub pressure: f64,
    pub violation: f64,
    pub slip: bool,
    pub active: bool,
    /// The history to commit, and the Uzawa-updated one.
    pub trial: PairHistory,
    pub aug: PairHistory,
}

/// A node-to-segment evaluation.
pub type PairEval = Eval<NDOF>;
/// A node-to-wall evaluation (only pairs that are active or carry a history; every other pair
/// is open with default histories).
pub type WallEval = Eval<2>;

/// The evaluations of one process (or of all, concatenated in process order): see
/// [`ContactProblem::evaluate`].
#[derive(Clone, Debug, Default)]
pub struct ContactEvals {
    pub pairs: Vec<PairEval>,
    pub walls: Vec<WallEval>,
    /// (slave, its smallest gap over the walls) of every slave with a finite wall gap.
    pub gaps: Vec<(usize, f64)>,
    /// The tangent blocks of the active node-to-segment pairs: pair indices, and their blocks
    /// (row-major, [`Boundary::pair_width`] squared each) one after the other.
    pub pair_blocks: Vec<usize>,
    pub pair_block_values: Vec<f64>,
    /// The tangent blocks of the active node-to-wall pairs: keys, and 2 × 2 blocks.
    pub wall_blocks: Vec<usize>,
    pub wall_block_values: Vec<f64>,
}

impl ContactEvals {
    /// Append another process's evaluations (the concatenation in process order that
    /// [`ContactProblem::apply`] takes).
    pub fn append(&mut self, other: &ContactEvals) {
        self.pairs.extend_from_slice(&other.pairs);
        self.walls.extend_from_slice(&other.walls);
        self.gaps.extend_from_slice(&other.gaps);
        self.pair_blocks.extend_from_slice(&other.pair_blocks);
        self.pair_block_values.extend_from_slice(&other.pair_block_values);
        self.wall_blocks.extend_from_slice(&other.wall_blocks);
        self.wall_block_values.extend_from_slice(&other.wall_block_values);
    }

    fn clear(&mut self) {
        self.pairs.clear();
        self.walls.clear();
        self.gaps.clear();
        self.pair_blocks.clear();
        self.pair_block_values.clear();
        self.wall_blocks.clear();
        self.wall_block_values.clear();
    }
}

/// Where the tangent blocks of an evaluation go: the matrix values and the positions of the
/// pair blocks (one per frozen pair, over [`ContactProblem::pair_dof_lists`]), of the node blocks
/// (one per slave node, its two dofs: the wall pairs) and of the multiplier blocks (one per
/// candidate, over [`ContactProblem::multiplier_dofs`] and its own row last).
pub struct ContactTangent<'a> {
    pub values: &'a mut [f64],
    pub pairs: &'a BlockMap,
    pub nodes: &'a BlockMap,
    pub multipliers: &'a BlockMap,
}

pub struct ContactProblem {
    /// Contact kind of each rigid wall (the walls themselves, where they are at a time, are
    /// passed in as planes: [`crate::loading::Loading::wall_plane`]).
    pub wall_kinds: Vec<ContactKind>,
    pub spec: ContactParams,
    pub boundary: Boundary,
    search: ContactSearch,
    pub set: PairSet,
    /// Lagrange multipliers (method `lagrange`), see [`Multipliers`].
    pub lm: Multipliers,
    /// How far a wall may move in one step (mm): widens the wall candidates of the
    /// Lagrange multipliers. Set by the driver from the wall motion over the step.
    pub wall_reach: f64,
    /// Nodal contact state of the last evaluation, and of the last committed step.
    trial_nodal: NodalContact,
    pub nodal: NodalContact,
}

impl ContactProblem {
    /// The contact problem of the bodies `bodies` (reference coordinates `x0` of every node),
    /// or `None` when there is nothing that can touch (no walls and a single body).
    pub fn new(bodies: &[ContactBody], x0: &[[f64; 2]], spec: ContactParams) -> Option<Self> {
        if spec.walls.is_empty() && bodies.len() < 2 {
            return None;
        }
        let boundary = Boundary::new(bodies, x0, spec.normal == super::ContactNormal::Smoothed);
        let search = ContactSearch::new(boundary.segments.clone());
        let wall_kinds = spec.walls.clone();
        let set = PairSet::new(wall_kinds.len(), boundary.slaves.len());
        Some(Self { wall_kinds, spec, boundary, search, set, lm: Multipliers::default(), wall_reach: 0.0, trial_nodal: NodalContact::default(), nodal: NodalContact::default() })
    }

    /// Whether the master surfaces are smoothed.
    pub fn smoothed(&self) -> bool {
        self.boundary.smoothed
    }

    /// The frozen pairs of the step.
    pub fn pairs(&self) -> &[FrozenPair] {
        &self.set.pairs
    }

    /// Contact kind used between particles.
    pub fn kind(&self) -> ContactKind {
        self.spec.kind
    }

    fn params(&self, b1: usize, b2: Option<usize>) -> PenaltyParams {
        self.boundary.penalty(self.spec.penalty, b1, b2)
    }

    /// The frozen pairs that involve `node` (as the slave, or as a node of the master segment
    /// or its smoothing neighbours) on configuration `x`, one line each: for the logs of a
    /// stalled Newton solve.
    pub fn describe_node(&self, node: usize, x: &[[f64; 2]]) -> Vec<String> {
        let b = &self.boundary;
        let mut lines = Vec::new();
        for p in &self.set.pairs {
            let (slave, body) = b.slaves[p.slave];
            let s = b.segments[p.segment];
            let [prev, next] = b.neighbours[p.segment];
            let role = if slave == node {
                "slave"
            } else if s.nodes.contains(&node) {
                "master"
            } else if prev == Some(node) || next == Some(node) {
                "neighbour"
            } else {
                continue;
            };
            let (xi, gap) = if b.smoothed {
                smooth::smooth_project(x[slave], &b.master(p.segment, x)).map_or((f64::NAN, f64::NAN), |g| (g.xi, g.gap))
            } else {
                let g = nts_project(x[slave], x[s.nodes[0]], x[s.nodes[1]]);
                (g.xi, g.gap)
            };
            lines.push(format!("{role}: slave {slave} (body {body}) on segment {:?} (body {}) weight {} xi {xi:.6} gap {gap:.6e}", s.nodes, s.body, p.weight));
        }
        lines
    }

    /// Choose the node-to-segment pairs (and the Lagrange candidates) for the next step on
    /// configuration `x` with the walls at `walls` (frozen during the step). Returns true when
    /// they changed (the sparsity pattern must follow).
    pub fn select_pairs(&mut self, x: &[[f64; 2]], walls: &[Wall]) -> bool {
        let distance = self.spec.search_distance.unwrap_or(self.boundary.h_min());
        let exact_lm = self.spec.method == ContactMethod::Lagrange && self.spec.lagrange_regularisation <= 0.0;
        let changed = self.set.select(&self.boundary, &mut self.search, x, distance, self.spec.kind, exact_lm);
        if self.spec.method == ContactMethod::Lagrange {
            return self.select_candidates(x, walls, distance) || changed;
        }
        changed
    }

    fn lm_key(&self, c: Candidate) -> (u8, usize, usize) {
        match c {
            Candidate::Pair(k) => (0, self.boundary.slaves[self.set.pairs[k].slave].0, self.set.pairs[k].segment),
            Candidate::Wall { wall, slave } => (1, wall, slave),
        }
    }

    /// Lagrange multipliers of the step: every frozen pair, and every slave node closer to a
    /// wall than the search distance plus `wall_reach` (how far a wall may move in one step);
    /// λ starts from its committed value. True when the set changed.
    fn select_candidates(&mut self, x: &[[f64; 2]], walls: &[Wall], distance: f64) -> bool {
        let mut cands: Vec<Candidate> = (0..self.set.pairs.len()).map(Candidate::Pair).collect();
        for (w, wall) in walls.iter().enumerate() {
            for (i, &(node, _)) in self.boundary.slaves.iter().enumerate() {
                let g = (x[node][0] - wall.point[0]) * wall.normal[0] + (x[node][1] - wall.point[1]) * wall.normal[1];
                if g < distance + self.wall_reach {
                    cands.push(Candidate::Wall { wall: w, slave: i });
                }
            }
        }
        let keys: Vec<_> = cands.iter().map(|&c| self.lm_key(c)).collect();
        let changed = keys != self.lm.keys;
        self.lm.lambda = keys.iter().map(|k| self.lm.committed.get(k).copied().unwrap_or(0.0)).collect();
        self.lm.start.clone_from(&self.lm.lambda);
        self.lm.rows = vec![0.0; cands.len()];
        self.lm.scale = vec![0.0; cands.len()];
        self.lm.candidates = cands;
        self.lm.keys = keys;
        changed
    }

    /// The global dofs every frozen pair couples (its tangent block's rows and columns, in the
    /// kernels' order): the connectivity of the pair contributions for the assembler.
    pub fn pair_dof_lists(&self) -> Vec<Vec<usize>> {
        let w = self.boundary.pair_width();
        self.set.pairs.iter().map(|p| self.boundary.pair_dofs(self.boundary.slaves[p.slave].0, p.segment)[..w].to_vec()).collect()
    }

    /// The two dofs of every slave node (the connectivity of the wall pairs).
    pub fn node_dof_lists(&self) -> Vec<Vec<usize>> {
        self.boundary.slaves.iter().map(|&(n, _)| vec![2 * n, 2 * n + 1]).collect()
    }

    /// Global dofs each Lagrange multiplier couples with (empty unless method = lagrange).
    pub fn multiplier_dofs(&self) -> Vec<Vec<usize>> {
        let w = self.boundary.pair_width();
        self.lm
            .candidates
            .iter()
            .map(|&c| match c {
                Candidate::Pair(k) => {
                    let p = self.set.pairs[k];
                    self.boundary.pair_dofs(self.boundary.slaves[p.slave].0, p.segment)[..w].to_vec()
                }
                Candidate::Wall { slave, .. } => {
                    let n = self.boundary.slaves[slave].0;
                    vec![2 * n, 2 * n + 1]
                }
            })
            .collect()
    }

    /// Lagrange-multiplier contributions at configuration `x`, walls `walls`: forces −λ A ∇g
    /// into `f_int`, the rows F_λ into `self.lm.rows`, and with a tangent the blocks
    /// [−λ A ∇∇g, −A ∇g; −A ∇gᵀ, 0] (active) or [0, 0; 0, −A/c] (inactive), the multiplier of
    /// candidate k being the last row of multiplier block k.
    fn add_lagrange(&mut self, x: &[[f64; 2]], walls: &[Wall], f_int: &mut [f64], mut kk: Option<ContactTangent>) -> ContactStats {
        let mut stats = ContactStats { wall_force: vec![0.0; self.wall_kinds.len()], wall_load: vec![[0.0; 2]; self.wall_kinds.len()], ..Default::default() };
        self.trial_nodal.reset(x.len(), self.wall_kinds.len());
        let no_penalty = PenaltyParams { eps_n: 0.0, eps_t: 0.0 };
        let reg = self.spec.lagrange_regularisation;
        let b = &self.boundary;
        let wp = b.pair_width();
        for (k, &cand) in self.lm.candidates.iter().enumerate() {
            let lambda = self.lm.lambda[k];
            // the force column −λ A ∇g and the constraint row −A ∇g: the same gradient except for
            // the smoothed normal, whose force is taken at fixed end angles (see `smooth`)
            let mut dofs = [0usize; NDOF];
            let mut grad = [0.0; NDOF];
            let mut row_grad = [0.0; NDOF];
            let (n, gap, area, c) = match cand {
                Candidate::Pair(q) => {
                    let p = self.set.pairs[q];
                    let (node, body) = b.slaves[p.slave];
                    let s = b.segments[p.segment];
                    let (xs, x1, x2) = (x[node], x[s.nodes[0]], x[s.nodes[1]]);
                    let area = b.area[p.slave] * p.weight;
                    let c = self.params(body, Some(s.body)).eps_n;
                    dofs = b.pair_dofs(node, p.segment);
                    if b.smoothed {
                        let geo = SmoothGeometry::new(xs, &b.master(p.segment, x));
                        // the kernel with a zero penalty and λ as its multiplier gives the force
                        // and, when λ carries, the geometric stiffness −λ A ∇∇g
                        let hist = PairHistory { xi_stick: 0.0, lambda_n: lambda.max(0.0), lambda_t: 0.0, active: true };
                        let out: PairResult<NDOF> = enforce::evaluate(&geo, area, ContactKind::Sliding, &no_penalty, &hist);
                        if !out.gap.is_finite() {
                            self.lm.rows[k] = -area * lambda;
                            self.lm.scale[k] = c;
                            self.set.trial_nts[q] = PairHistory::default();
                            continue;
                        }
                        // the gradients of an inactive pair: the geometry's, at its projection
                        let lin = if out.active { None } else { geo.linearise(geo.xi()) };
                        (grad, row_grad) = match &lin {
                            None => (out.grad, out.grad_full),
                            Some(l) => (l.grad(), l.grad_full()),
                        };
                        if lambda > 0.0 && lambda - c * out.gap > 0.0 && out.active {
                            if let Some(t) = kk.as_mut() {
                                add_square(t.values, t.multipliers, k, NDOF, &out.k);
                            }
                        }
                        (NDOF, out.gap, area, c)
                    } else {
                        let g = nts_project(xs, x1, x2);
                        if !g.gap.is_finite() {
                            self.lm.rows[k] = -area * lambda;
                            self.lm.scale[k] = c;
                            self.set.trial_nts[q] = PairHistory::default();
                            continue;
                        }
                        let (n, xi) = (g.normal, g.xi);
                        let gv = [n[0], n[1], -(1.0 - xi) * n[0], -(1.0 - xi) * n[1], -xi * n[0], -xi * n[1]];
                        grad[..6].copy_from_slice(&gv);
                        row_grad[..6].copy_from_slice(&gv);
                        // force and geometric stiffness of the pressure λ: the penalty kernel with a
                        // zero penalty and λ as its multiplier
                        if lambda > 0.0 && lambda - c * g.gap > 0.0 {
                            let hist = PairHistory { xi_stick: xi, lambda_n: lambda, lambda_t: 0.0, active: true };
                            let out: PairResult<6> = enforce::evaluate(&SegmentGeometry::new(xs, x1, x2), area, ContactKind::Sliding, &no_penalty, &hist);
                            if let Some(t) = kk.as_mut() {
                                add_square(t.values, t.multipliers, k, 6, &out.k);
                            }
                        }
                        (6, g.gap, area, c)
                    }
                }
                Candidate::Wall { wall, slave } => {
                    let (node, body) = b.slaves[slave];
                    let w = &walls[wall];
                    let nw = w.normal;
                    let gap = (x[node][0] - w.point[0]) * nw[0] + (x[node][1] - w.point[1]) * nw[1];
                    dofs[..2].copy_from_slice(&[2 * node, 2 * node + 1]);
                    grad[..2].copy_from_slice(&nw);
                    row_grad[..2].copy_from_slice(&nw);
                    (2, gap, b.area[slave], self.params(body, None).eps_n)
                }
            };
            debug_assert!(n <= wp.max(2));
            // the force −λ A ∇g acts whatever the active set: an inactive candidate's row
            // drives its λ to zero in one Newton update, and its column removes the force
            for i in 0..n {
                f_int[dofs[i]] -= lambda * area * grad[i];
            }
            let (active, row, diagonal) = enforce::lagrange_row(lambda, gap, area, c, reg);
            let slave_node = dofs[0] / 2;
            self.trial_nodal.gap(slave_node, gap);
            if active && lambda > 0.0 {
                // the force on the node is minus its contribution −λ A ∇g to the internal force
                for i in 0..n {
                    let d = dofs[i];
                    self.trial_nodal.force[d / 2][d % 2] += lambda * area * grad[i];
                }
                self.trial_nodal.active(slave_node, ContactKind::Sliding, true);
                if let Candidate::Wall { wall, .. } = cand {
                    self.trial_nodal.wall_force[wall][slave_node] += lambda * area;
                }
            }
            self.lm.scale[k] = c;
            // perturbed Lagrangian: an active row is −A (g + r λ / c), which keeps the system
            // regular where two candidates constrain the same gap (two-pass pairs of two nodes
            // facing each other); it leaves a penetration r λ / c
            self.lm.rows[k] = row;
            if let Some(t) = kk.as_mut() {
                // the multiplier is the block's last row and column
                for i in 0..n {
                    t.multipliers.add_entry(t.values, k, i, n, -c * area * grad[i]);
                    if active {
                        t.multipliers.add_entry(t.values, k, n, i, -c * area * row_grad[i]);
                    }
                }
                if diagonal != 0.0 {
                    t.multipliers.add_entry(t.values, k, n, n, diagonal);
                }
            }
            let carries = active && lambda > 0.0;
            let hist = PairHistory { xi_stick: 0.0, lambda_n: if carries { lambda } else { 0.0 }, lambda_t: 0.0, active: carries };
            match cand {
                Candidate::Pair(q) => self.set.trial_nts[q] = hist,
                Candidate::Wall { wall, slave } => {
                    self.set.trial_walls[wall][slave] = hist;
                    if carries {
                        stats.wall_force[wall] += lambda * area;
                        // (the node's contribution −λ A ∇g to the internal force)
                        for c in 0..2 {
                            stats.wall_load[wall][c] -= lambda * area * grad[c];
                        }
                    }
                }
            }
            if carries {
                stats.active += 1;
                stats.max_penetration = stats.max_penetration.max(-gap);
            }
        }
        stats
    }

    /// Evaluate the kernels of the node-to-segment and node-to-wall pairs whose slave node
    /// belongs to a body `owns` accepts (one process: every body) at configuration `x` with
    /// the walls at `walls`, into `out` (cleared first): forces, gaps, pressures, violations,
    /// trial and augmented histories, and with `tangent` the blocks of the active pairs. The
    /// histories are read from the committed state (for the augmented Lagrangian, the current
    /// multipliers). Nothing of `self` changes: [`ContactProblem::apply`] adds the result.
    pub fn evaluate(&self, x: &[[f64; 2]], walls: &[Wall], tangent: bool, owns: &dyn Fn(usize) -> bool, out: &mut ContactEvals) {
        out.clear();
        let b = &self.boundary;
        let kind = self.spec.kind;
        for (k, p) in self.set.pairs.iter().enumerate() {
            let (node, body) = b.slaves[p.slave];
            if !owns(body) {
                continue;
            }
            let s = b.segments[p.segment];
            let old = self.set.committed(b, p);
            let params = self.params(body, Some(s.body));
            let area = b.area[p.slave] * p.weight;
            let mut f = [0.0; NDOF];
            let (gap, pressure, shear, slip, active, trial, aug) = if b.smoothed {
                let r: PairResult<NDOF> = enforce::smooth_pair(x[node], &b.master(p.segment, x), area, kind, &params, &old);
                if tangent && r.active {
                    out.pair_blocks.push(k);
                    out.pair_block_values.extend_from_slice(r.k.as_flattened());
                }
                f = r.f;
                (r.gap, r.pressure, r.shear, r.slip, r.active, r.new_history, enforce::augment(&r))
            } else {
                let r: PairResult<6> = enforce::segment_pair(x[node], x[s.nodes[0]], x[s.nodes[1]], area, kind, &params, &old);
                if tangent && r.active {
                    out.pair_blocks.push(k);
                    out.pair_block_values.extend_from_slice(r.k.as_flattened());
                }
                f[..6].copy_from_slice(&r.f);
                (r.gap, r.pressure, r.shear, r.slip, r.active, r.new_history, enforce::augment(&r))
            };
            let violation = if active { enforce::violation(kind, gap, shear, slip, &old, params.eps_t) } else { 0.0 };
            out.pairs.push(PairEval { key: k, f, gap, pressure, violation, slip, active, trial, aug });
        }
        let ns = b.slaves.len();
        let mut wall_gap = vec![f64::NAN; ns];
        for (w, (wall, &kind)) in walls.iter().zip(&self.wall_kinds).enumerate() {
            // tangential wall motion: the walls move along their normals only
            for (i, &(node, body)) in b.slaves.iter().enumerate() {
                if !owns(body) {
                    continue;
                }
                let old = self.set.committed_wall(w, i);
                if self.untied_wall(kind, wall, x[node], body, &old) {
                    // an open pair with its history kept for the augmentation (the anchor of an
                    // inactive history means nothing: the kernels start afresh from it)
                    if !unused(&old) {
                        out.walls.push(WallEval { key: w * ns + i, f: [0.0; 2], gap: f64::NAN, pressure: 0.0, violation: 0.0, slip: false, active: false, trial: PairHistory::default(), aug: old });
                    }
                    continue;
                }
                let params = self.params(body, None);
                let r: PairResult<2> = enforce::wall_pair(x[node], wall, 0.0, b.area[i], kind, &params, &old);
                if r.gap.is_finite() && !(wall_gap[i] <= r.gap) {
                    wall_gap[i] = r.gap;
                }
                let aug = enforce::augment(&r);
                // a pair without an evaluation is open with default histories
                if r.active || !unused(&r.new_history) || !unused(&aug) {
                    let violation = if r.active { enforce::violation(kind, r.gap, r.shear, r.slip, &old, params.eps_t) } else { 0.0 };
                    out.walls.push(WallEval { key: w * ns + i, f: r.f, gap: r.gap, pressure: r.pressure, violation, slip: r.slip, active: r.active, trial: r.new_history, aug });
                }
                if tangent && r.active {
                    out.wall_blocks.push(w * ns + i);
                    out.wall_block_values.extend_from_slice(r.k.as_flattened());
                }
            }
        }
        out.gaps.extend(wall_gap.iter().enumerate().filter(|(_, g)| g.is_finite()).map(|(i, &g)| (i, g)));
    }

    /// Add the contact contributions at configuration `x` (walls at `walls`) to `f_int` and,
    /// with `tangent`, their derivative to the matrix: [`ContactProblem::evaluate`] of every
    /// pair followed by [`ContactProblem::apply`] (one process), or the Lagrange multipliers.
    pub fn add(&mut self, x: &[[f64; 2]], walls: &[Wall], f_int: &mut [f64], tangent: Option<ContactTangent>, scratch: &mut ContactEvals) -> ContactStats {
        if self.spec.method == ContactMethod::Lagrange {
            return self.add_lagrange(x, walls, f_int, tangent);
        }
        self.evaluate(x, walls, tangent.is_some(), &|_| true, scratch);
        self.apply(scratch, x, f_int, tangent)
    }

    /// Add evaluations `evals` (every process's, concatenated in process order) in the serial
    /// order (pairs by index, then walls by wall and slave): forces into `f_int`, trial
    /// histories, nodal results and statistics, and, with a tangent, the blocks through its
    /// maps. Every process that applies the same evaluations gets the same bits as a serial run.
    /// Lagrange multipliers go through [`ContactProblem::add`].
    pub fn apply(&mut self, evals: &ContactEvals, x: &[[f64; 2]], f_int: &mut [f64], mut tangent: Option<ContactTangent>) -> ContactStats {
        let mut stats = ContactStats { wall_force: vec![0.0; self.wall_kinds.len()], wall_load: vec![[0.0; 2]; self.wall_kinds.len()], ..Default::default() };
        self.trial_nodal.reset(x.len(), self.wall_kinds.len());
        let b = &self.boundary;
        let w = b.pair_width();
        let npairs = self.set.pairs.len();
        // position of each pair's evaluation and tangent block
        let mut at = vec![usize::MAX; npairs];
        for (pos, r) in evals.pairs.iter().enumerate() {
            at[r.key] = pos;
        }
        let mut at_k = vec![usize::MAX; if tangent.is_some() { npairs } else { 0 }];
        if tangent.is_some() {
            for (pos, &k) in evals.pair_blocks.iter().enumerate() {
                at_k[k] = pos;
            }
        }
        let kind = self.spec.kind;
        for (k, p) in self.set.pairs.iter().enumerate() {
            let (node, _) = b.slaves[p.slave];
            let Some(r) = evals.pairs.get(at[k]) else {
                // (every pair has one owner, so this cannot happen; the pair then contributes
                // nothing)
                self.set.trial_nts[k] = PairHistory::default();
                self.set.aug_nts[k] = PairHistory::default();
                continue;
            };
            self.set.trial_nts[k] = r.trial;
            self.set.aug_nts[k] = r.aug;
            self.trial_nodal.gap(node, r.gap);
            if !r.active {
                continue;
            }
            stats.active += 1;
            stats.max_penetration = stats.max_penetration.max(-r.gap);
            stats.violation = stats.violation.max(r.violation);
            self.trial_nodal.active(node, kind, r.slip);
            let nodes = b.pair_nodes(node, p.segment);
            let dofs = b.pair_dofs(node, p.segment);
            self.trial_nodal.force(&nodes[..w / 2], &r.f[..w]);
            for i in 0..w {
                f_int[dofs[i]] += r.f[i];
            }
            if let Some(t) = tangent.as_mut() {
                if let Some(&pos) = at_k.get(k).filter(|&&pos| pos != usize::MAX) {
                    t.pairs.add(t.values, k, &evals.pair_block_values[pos * w * w..(pos + 1) * w * w]);
                }
            }
        }
        // walls: every pair without an evaluation is open, with default histories
        let ns = b.slaves.len();
        for w in 0..self.wall_kinds.len() {
            self.set.trial_walls[w].iter_mut().for_each(|h| *h = PairHistory::default());
            self.set.aug_walls[w].iter_mut().for_each(|h| *h = PairHistory::default());
        }
        for &(i, g) in &evals.gaps {
            self.trial_nodal.gap(b.slaves[i].0, g);
        }
        let mut order: Vec<usize> = (0..evals.walls.len()).collect();
        order.sort_by_key(|&q| evals.walls[q].key);
        // the tangent blocks in the same order, walked alongside
        let mut blocks: Vec<usize> = if tangent.is_some() { (0..evals.wall_blocks.len()).collect() } else { Vec::new() };
        blocks.sort_by_key(|&q| evals.wall_blocks[q]);
        let mut next_block = blocks.iter().peekable();
        for q in order {
            let r = &evals.walls[q];
            let (w, i) = (r.key / ns, r.key % ns);
            let (node, _) = b.slaves[i];
            let kind = self.wall_kinds[w];
            self.set.trial_walls[w][i] = r.trial;
            self.set.aug_walls[w][i] = r.aug;
            if !r.active {
                continue;
            }
            stats.active += 1;
            stats.max_penetration = stats.max_penetration.max(-r.gap);
            stats.violation = stats.violation.max(r.violation);
            stats.wall_force[w] += r.pressure * b.area[i];
            self.trial_nodal.wall_force[w][node] += r.pressure * b.area[i];
            self.trial_nodal.force(&[node], &r.f);
            self.trial_nodal.active(node, kind, r.slip);
            for c in 0..2 {
                f_int[2 * node + c] += r.f[c];
                stats.wall_load[w][c] += r.f[c];
            }
            if let Some(t) = tangent.as_mut() {
                while next_block.peek().is_some_and(|&&b| evals.wall_blocks[b] < r.key) {
                    next_block.next();
                }
                if let Some(&q) = next_block.next_if(|&&b| evals.wall_blocks[b] == r.key) {
                    t.nodes.add(t.values, i, &evals.wall_block_values[4 * q..4 * q + 4]);
                }
            }
        }
        stats
    }

    /// Uzawa update of every pair's multipliers (λ ← the pressure and shear of the last
    /// evaluation, which [`ContactProblem::apply`] has already formed): no kernel is evaluated
    /// again.
    pub fn augment(&mut self) {
        self.set.augment(&self.boundary);
    }

    /// A cohering wall ties only nodes that touch it (or were tied before): the kernel's normal
    /// law is bilateral and would otherwise pull every node towards the wall.
    fn untied_wall(&self, kind: ContactKind, wall: &Wall, x: [f64; 2], body: usize, old: &PairHistory) -> bool {
        if !matches!(kind, ContactKind::Cohering) || old.active {
            return false;
        }
        let g = (x[0] - wall.point[0]) * wall.normal[0] + (x[1] - wall.point[1]) * wall.normal[1];
        g > TOUCH * self.boundary.body_h[body]
    }

    /// Which directions (x, y) of each body the committed contacts hold: a body is held in x
    /// when it has an active contact pushing it towards +x and another pushing it towards −x
    /// (normal components beyond [`SUPPORT_COSINE`]), likewise in y. Node-to-segment pairs
    /// count for both bodies (with opposite normals), wall pairs for the particle. `x` is the
    /// committed configuration, `walls` the walls (their normals).
    pub fn body_support(&self, x: &[[f64; 2]], walls: &[Wall], n_bodies: usize) -> Vec<[bool; 2]> {
        let b = &self.boundary;
        // pushes[body][dir] = (towards +, towards −)
        let mut pushes = vec![[(false, false); 2]; n_bodies];
        let mut mark = |body: usize, n: [f64; 2]| {
            for c in 0..2 {
                if n[c] > SUPPORT_COSINE {
                    pushes[body][c].0 = true;
                } else if n[c] < -SUPPORT_COSINE {
                    pushes[body][c].1 = true;
                }
            }
        };
        let body_of: HashMap<usize, usize> = b.slaves.iter().copied().collect();
        for (&(node, seg), h) in &self.set.nts {
            if !h.active {
                continue;
            }
            let s = b.segments[seg];
            let g = nts_project(x[node], x[s.nodes[0]], x[s.nodes[1]]);
            if !g.length.is_finite() || g.length <= 0.0 {
                continue;
            }
            // the master's outward normal pushes the slave along +n and the master along −n
            if let Some(&bd) = body_of.get(&node) {
                mark(bd, g.normal);
            }
            mark(s.body, [-g.normal[0], -g.normal[1]]);
        }
        for (w, wall) in walls.iter().enumerate() {
            for (i, &(_, body)) in b.slaves.iter().enumerate() {
                if self.set.walls[w][i].active {
                    mark(body, wall.normal);
                }
            }
        }
        pushes.iter().map(|p| [p[0].0 && p[0].1, p[1].0 && p[1].1]).collect()
    }

    /// Whether the augmented Lagrangian asks for another update after a converged solve.
    pub fn needs_augmentation(&self, stats: &ContactStats) -> bool {
        if self.spec.method != ContactMethod::AugmentedLagrangian {
            return false;
        }
        stats.violation > self.spec.penetration_tol * self.boundary.h_min()
    }

    /// Commit the trial histories of the last evaluation (after a converged step).
    /// Commit the last evaluation, at coordinates `x` (the converged state): the pair
    /// histories and the nodal results, whose pressure and shear are formed here, once a step.
    pub fn commit(&mut self, x: &[[f64; 2]]) {
        self.set.commit(&self.boundary);
        self.trial_nodal.set_tractions(x, &self.boundary.segments);
        self.nodal.clone_from(&self.trial_nodal);
        if self.spec.method == ContactMethod::Lagrange {
            self.lm.committed = self.lm.keys.iter().zip(&self.lm.lambda).filter(|(_, &l)| l > 0.0).map(|(k, &l)| (*k, l)).collect();
        }
    }

    /// The committed histories, to forget the augmented multipliers of a failed step.
    pub fn snapshot(&self) -> Backup {
        self.set.backup()
    }

    pub fn restore(&mut self, snap: Backup) {
        self.set.restore(snap);
    }

    /// The committed contact state that a later step depends on (pair histories, Lagrange
    /// multipliers, nodal results, the element size per body), for a checkpoint. Everything else
    /// is rebuilt by the next step's pair selection.
    pub fn state(&self) -> ContactState {
        let mut lm_committed: Vec<((u8, usize, usize), f64)> = self.lm.committed.iter().map(|(k, v)| (*k, *v)).collect();
        lm_committed.sort_by_key(|(k, _)| *k);
        ContactState {
            nts: self.set.committed_nts(),
            walls: self.set.committed_walls().to_vec(),
            lm_committed,
            nodal: self.nodal.clone(),
            body_h: self.boundary.body_h.clone(),
            area: self.boundary.area.clone(),
        }
    }

    /// Set the committed state from [`ContactProblem::state`] of the same model.
    ///
    /// # Errors
    /// A message when the state does not fit this contact problem (walls, boundary nodes,
    /// bodies).
    pub fn set_state(&mut self, s: ContactState) -> Result<(), String> {
        let b = &mut self.boundary;
        if s.walls.len() != self.wall_kinds.len() || s.walls.iter().any(|w| w.len() != b.slaves.len()) {
            return Err(format!(
                "contact: {} wall(s) x {} boundary node(s) in the checkpoint, {} x {} in the model",
                s.walls.len(),
                s.walls.first().map_or(0, Vec::len),
                self.wall_kinds.len(),
                b.slaves.len()
            ));
        }
        if s.body_h.len() != b.body_h.len() {
            return Err(format!("contact: {} bodies in the checkpoint, {} in the model", s.body_h.len(), b.body_h.len()));
        }
        if !s.area.is_empty() && s.area.len() != b.area.len() {
            return Err(format!("contact: {} boundary lengths in the checkpoint, {} boundary nodes in the model", s.area.len(), b.area.len()));
        }
        if !s.area.is_empty() {
            b.area = s.area;
        }
        self.set.set_committed(s.nts, s.walls);
        self.lm.committed = s.lm_committed.into_iter().collect();
        self.nodal = s.nodal;
        b.body_h = s.body_h;
        Ok(())
    }

    /// Carry the committed contact state of `old` — the contact problem of the same model
    /// before one or more particles were re-meshed — over to this one (built for the model
    /// with the new meshes), so that a re-mesh does not reset the contact of the whole
    /// assembly. `node_map[n]` is the new global number of old node `n` (`None` for a node of
    /// a re-meshed particle that is not in its new mesh); `x_old`, `x0_old` are the current
    /// and reference coordinates of the old model, `x`, `x0` those of the new one.
    ///
    /// What moves, and how:
    /// - a node-to-segment history (stick anchor ξ_a, multipliers λ_N, λ_T) whose slave node
    ///   and both master nodes are in the new model, and whose master segment is one of its
    ///   segments, is carried unchanged: every pair between particles that were not
    ///   re-meshed, and the pairs of a re-meshed particle's contact zones (the re-mesh keeps
    ///   their nodes and spacing, see [`crate::remesh::remesh_particle_keeping`]);
    /// - an active history whose master segment was re-meshed away keeps its anchor as a
    ///   point: x_a = c(ξ_a) on the old segment (configuration `x_old`), re-projected onto the
    ///   new segment of the same body nearest to the slave node, so that the elastic slip
    ///   g_T = (ξ − ξ_a) ℓ measures the same distance;
    /// - node-to-wall histories (their anchors are wall coordinates) and committed Lagrange
    ///   multipliers follow their slave nodes;
    /// - the tributary length of a slave node (the contact force is p × length) takes the old
    ///   reference length of each of its boundary segments that the new mesh kept, so that a
    ///   contact zone carries the same forces after the re-mesh (the re-meshed particle's new
    ///   reference is its current shape, whose lengths differ by the boundary's stretch);
    /// - the nodal results of the last committed step follow their nodes (new nodes: none).
    ///
    /// A history whose slave node has no counterpart is dropped; the re-mesh holds every node
    /// in contact, so only inactive histories are lost in practice ([`CarriedHistory`] counts
    /// them).
    pub fn carry_history(&mut self, old: &ContactProblem, node_map: &[Option<usize>], [x0_old, x_old]: [&[[f64; 2]]; 2], [x0, x]: [&[[f64; 2]]; 2]) -> CarriedHistory {
        let mut out = CarriedHistory::default();
        let (ob, nb) = (&old.boundary, &self.boundary);
        let seg_of: HashMap<[usize; 2], usize> = nb.segments.iter().enumerate().map(|(k, s)| (s.nodes, k)).collect();
        let slave_of: HashMap<usize, usize> = nb.slaves.iter().enumerate().map(|(i, (n, _))| (*n, i)).collect();
        let map = |n: usize| node_map.get(n).copied().flatten();
        let kept_segment = |k: usize| -> Option<usize> {
            let [a, b] = ob.segments[k].nodes;
            seg_of.get(&[map(a)?, map(b)?]).copied()
        };
        [out.kept, out.moved, out.dropped, out.walls] = self.set.carry(&old.set, ob, nb, &map, &kept_segment, x_old, x);
        // nodal results follow their nodes
        let n_new = x.len();
        let mut nodal = NodalContact::default();
        nodal.reset(n_new, self.wall_kinds.len());
        for (n, m) in node_map.iter().enumerate() {
            let Some(m) = *m else { continue };
            if n >= old.nodal.pressure.len() || m >= n_new {
                continue;
            }
            nodal.pressure[m] = old.nodal.pressure[n];
            nodal.shear[m] = old.nodal.shear.get(n).copied().unwrap_or(0.0);
            nodal.gap[m] = old.nodal.gap[n];
            nodal.status[m] = old.nodal.status[n];
            nodal.force[m] = old.nodal.force[n];
            for (w, f) in old.nodal.wall_force.iter().enumerate().take(nodal.wall_force.len()) {
                nodal.wall_force[w][m] = f[n];
            }
        }
        self.nodal = nodal;
        // committed Lagrange multipliers: (0, slave node, segment) and (1, wall, slave index)
        let mut lm = HashMap::with_capacity(old.lm.committed.len());
        let mut keys: Vec<(&(u8, usize, usize), &f64)> = old.lm.committed.iter().collect();
        keys.sort_by_key(|(k, _)| **k);
        for (&(kind, a, b), &l) in keys {
            let key = match kind {
                0 => map(a).zip(kept_segment(b)).map(|(s, k)| (0, s, k)),
                _ => ob.slaves.get(b).and_then(|&(n, _)| map(n)).and_then(|m| slave_of.get(&m)).map(|&j| (1, a, j)),
            };
            if let Some(key) = key {
                lm.entry(key).or_insert(l);
                out.multipliers += 1;
            }
        }
        self.lm.committed = lm;
        // tributary lengths: the old reference length of every boundary segment kept
        let len = |p: [f64; 2], q: [f64; 2]| ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        let mut changed = vec![false; nb.slaves.len()];
        let mut area = nb.area.clone();
        for (k, s) in ob.segments.iter().enumerate() {
            let Some(knew) = kept_segment(k) else { continue };
            let [a, b] = s.nodes;
            let [an, bn] = nb.segments[knew].nodes;
            let delta = 0.5 * (len(x0_old[a], x0_old[b]) - len(x0[an], x0[bn]));
            if delta == 0.0 {
                continue;
            }
            for n in [an, bn] {
                if let Some(&j) = slave_of.get(&n) {
                    area[j] += delta;
                    changed[j] = true;
                }
            }
        }
        self.boundary.area = area;
        out.areas = changed.iter().filter(|&&c| c).count();
        out
    }
}

/// Add the row-major `n × n` block `k` (the first `n` rows and columns of multiplier block
/// `i`) through `map`.
fn add_square<const N: usize>(values: &mut [f64], map: &BlockMap, i: usize, n: usize, k: &[[f64; N]; N]) {
    for a in 0..n {
        for b in 0..n {
            map.add_entry(values, i, a, b, k[a][b]);
        }
    }
}

/// An inactive history without multipliers: the kernels take nothing from it (they re-anchor
/// an inactive pair), so any such history stands for the default one.
fn unused(h: &PairHistory) -> bool {
    !h.active && h.lambda_n == 0.0 && h.lambda_t == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::CsrMatrix;

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    fn histories(c: &ContactProblem) -> Vec<PairHistory> {
        let mut h = c.set.trial_nts.clone();
        h.extend(c.set.aug_nts.iter().copied());
        c.set.trial_walls.iter().chain(&c.set.aug_walls).for_each(|w| h.extend(w.iter().copied()));
        h
    }

    fn nodal_bits(n: &NodalContact) -> Vec<u64> {
        let mut v = bits(&n.pressure);
        v.extend(bits(&n.gap));
        v.extend(n.status.iter().map(|&s| s as u64));
        v.extend(n.force.iter().flat_map(|f| bits(f)));
        n.wall_force.iter().for_each(|w| v.extend(bits(w)));
        v
    }

    /// The contact kernels shared out over two processes by slave-node owner, their
    /// evaluations concatenated in process order and applied in the serial order, give the
    /// serial evaluation bit for bit: forces, every entry of the tangent, statistics, trial and
    /// augmented histories, nodal results. The 3 × 3 disc job of `tests/mpi_ranks.rs` (Coulomb
    /// friction 0.2) after 3 steps, and the same with smoothed normals and with the augmented
    /// Lagrangian.
    #[test]
    fn contact_shared_out_over_two_processes_is_the_serial_evaluation() {
        let base = include_str!("../../tests/data/mpi_discs_3x3.toml").replace("end = 3.0", "end = 0.15");
        let variants = [
            base.clone(),
            base.replace("friction = 0.2\n", "friction = 0.2\nnormal = \"smoothed\"\n"),
            base.replace("method = \"penalty\"", "method = \"augmented_lagrangian\"\npenetration_tol = 1e-4"),
        ];
        for (v, text) in variants.iter().enumerate() {
            let case = crate::case::parse(text, std::path::Path::new(".")).unwrap();
            let model = crate::model::Model::from_case(&case).unwrap();
            let mut sim = crate::solver::Simulation::new(model, case.time.clone(), case.solver.clone()).unwrap();
            let summary = sim.run(&mut |_, _| {}).unwrap();
            assert!(summary.steps >= 3, "variant {v}: {} steps", summary.steps);
            let x = sim.coords(&sim.sol.u);
            let t = sim.sol.time;
            let n = sim.model.n_dofs();
            let walls = sim.model.wall_planes(t);
            let c = sim.contact.as_mut().unwrap();
            // a full pattern, so that every block lands; every dof free
            let full: Vec<Vec<usize>> = (0..n).map(|_| (0..n).collect()).collect();
            let k0 = CsrMatrix::from_rows(n, &full);
            let pair_dofs = c.pair_dof_lists();
            let node_dofs = c.node_dof_lists();
            let pairs = BlockMap::locate(&k0, pair_dofs.iter().map(Vec::as_slice));
            let nodes = BlockMap::locate(&k0, node_dofs.iter().map(Vec::as_slice));
            let none = BlockMap::default();

            let mut f1 = vec![0.0; n];
            let mut k1 = k0.clone();
            let mut scratch = ContactEvals::default();
            let s1 = c.add(&x, &walls, &mut f1, Some(ContactTangent { values: &mut k1.values, pairs: &pairs, nodes: &nodes, multipliers: &none }), &mut scratch);
            let (h1, nodal1) = (histories(c), nodal_bits(&c.trial_nodal));
            assert!(s1.active > 20, "variant {v}: only {} active pairs", s1.active);
            assert!(s1.wall_force.iter().any(|&f| f > 0.0), "variant {v}: no wall carries load");

            // two processes: each evaluates its half, the evaluations are concatenated in
            // process order, and each process would then apply them all
            let mut all = ContactEvals::default();
            for rank in 0..2 {
                let mut local = ContactEvals::default();
                c.evaluate(&x, &walls, true, &|body| body % 2 == rank, &mut local);
                assert!(local.pairs.len() >= 10 && local.pair_blocks.len() >= 10, "variant {v}: rank {rank} evaluated {} pairs", local.pairs.len());
                all.append(&local);
            }
            c.trial_nodal = NodalContact::default();
            c.set.trial_nts.iter_mut().for_each(|h| *h = PairHistory { xi_stick: 9.0, ..Default::default() });
            let mut f2 = vec![0.0; n];
            let mut k2 = k0.clone();
            let s2 = c.apply(&all, &x, &mut f2, Some(ContactTangent { values: &mut k2.values, pairs: &pairs, nodes: &nodes, multipliers: &none }));
            assert_eq!(bits(&f1), bits(&f2), "variant {v}: forces");
            assert_eq!(bits(&k1.values), bits(&k2.values), "variant {v}: tangent");
            assert_eq!(s1, s2, "variant {v}: statistics");
            assert_eq!(h1, histories(c), "variant {v}: histories");
            assert_eq!(nodal1, nodal_bits(&c.trial_nodal), "variant {v}: nodal results");
        }
    }
}
