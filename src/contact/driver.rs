//! The contact problem of a model: walls, boundary segments, the pairs frozen for a step, their
//! histories, and the assembly of the pair kernels into the global force and tangent.
//!
//! Lifecycle per step: [`ContactProblem::select_pairs`] on the converged configuration (search
//! within the search distance, one master segment per slave node, two-pass: every boundary
//! node is a slave against the other bodies) → [`ContactProblem::add`] at every Newton
//! iterate (kernels from the committed histories) → optionally [`ContactProblem::augment`]
//! (Uzawa) and solve again → [`ContactProblem::commit`].

use super::kernels::{self, ContactKind, PairHistory, PairOut, PenaltyParams, Wall, WallOut};
use super::smooth::{self, SmoothPairOut};
use super::search::{boundary_of, ContactSearch};
use super::Segment;
use crate::assembly::FIXED;
use crate::case::{ContactMethod, ContactNormal, ContactSpec, WallSide, WallSpec};
use crate::linalg::CsrMatrix;
use crate::model::Model;
use std::collections::HashMap;

/// Gap (relative to the element size) below which a node touches: cohering (tied) pairs are
/// only created for touching nodes.
const TOUCH: f64 = 1e-6;

/// Two master segments are equally close to a slave node when their distances differ by less
/// than this (relative to the element size).
const TIE: f64 = 1e-9;

/// A contact normal holds a body in a coordinate direction when its component along that
/// direction exceeds this (|cos| > 0.2, i.e. within ~78° of the axis).
pub const SUPPORT_COSINE: f64 = 0.2;

/// A node-to-segment pair frozen for the current step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrozenPair {
    /// Index into the slave list.
    pub slave: usize,
    /// Index into the segment list.
    pub segment: usize,
    /// Share of the slave node's tributary length carried by this pair: 1, or 1/2 when the
    /// slave faces the common node of two master segments exactly (a tie that any single choice
    /// would break asymmetrically).
    pub weight: f64,
}

/// What the contact contributions of one evaluation amount to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactStats {
    /// Normal force of the particles on each wall (N/mm, positive in compression), in the order
    /// of the model's walls.
    pub wall_force: Vec<f64>,
    /// Largest penetration over all active pairs (mm, ≥ 0).
    pub max_penetration: f64,
    /// Number of active pairs (node-to-segment and node-to-wall).
    pub active: usize,
    /// Largest violation of the enforced constraints (mm): penetration, and for tied or
    /// sticking pairs also the normal separation and the elastic tangential slip. The
    /// augmented Lagrangian drives it below its tolerance.
    pub violation: f64,
}

/// Constraint violation of one active pair (see [`ContactStats::violation`]).
fn violation(kind: ContactKind, gap: f64, shear: f64, slip: bool, old: &PairHistory, eps_t: f64) -> f64 {
    let normal = if matches!(kind, ContactKind::Cohering) { gap.abs() } else { (-gap).max(0.0) };
    let tangential = match kind {
        ContactKind::Sliding => 0.0,
        _ if slip || !old.active || !(eps_t > 0.0) => 0.0,
        _ => ((shear - old.lambda_t) / eps_t).abs(),
    };
    normal.max(tangential)
}

/// Contact state per node (global node numbers) at one evaluation, for the results files.
/// Every node-to-segment pair contributes to its slave node (two-pass: each boundary node is a
/// slave of its own pairs), every node-to-wall pair to its node.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NodalContact {
    /// Normal contact pressure (MPa, ≥ 0 in compression): the sum over the node's pairs of the
    /// pair's share (weight) times its pressure, or the wall pressure when that is larger.
    pub pressure: Vec<f64>,
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

    /// Record an active pair of `kind` acting on `node` with pressure share `p`.
    fn active(&mut self, node: usize, p: f64, kind: ContactKind, slip: bool) {
        let s = match kind {
            ContactKind::Cohering => 3,
            ContactKind::Sliding => 1,
            ContactKind::Rubbing { mu } if slip || !(mu > 0.0) => 1,
            ContactKind::Rubbing { .. } => 2,
        };
        self.status[node] = self.status[node].max(s);
        self.pressure[node] += p;
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

pub struct ContactProblem {
    pub walls: Vec<WallSpec>,
    pub spec: ContactSpec,
    pub segments: Vec<Segment>,
    /// Per segment: the boundary node before its first node and the one after its second node
    /// on the same body (the neighbours of the smoothed master surface), if any.
    pub neighbours: Vec<[Option<usize>; 2]>,
    /// Boundary nodes: (node, body).
    pub slaves: Vec<(usize, usize)>,
    /// Tributary (reference) boundary length of each slave node (mm).
    pub area: Vec<f64>,
    /// Contact length h of each body ([`crate::model::Body::contact_h`], kept over re-meshes)
    /// and its Young's modulus.
    pub body_h: Vec<f64>,
    pub body_e: Vec<f64>,
    search: ContactSearch,
    pub pairs: Vec<FrozenPair>,
    nts_hist: HashMap<(usize, usize), PairHistory>,
    wall_hist: Vec<Vec<PairHistory>>,
    trial_nts: Vec<PairHistory>,
    trial_wall: Vec<Vec<PairHistory>>,
    /// Uzawa-updated histories of the last evaluation (what `augment` commits).
    aug_nts: Vec<PairHistory>,
    aug_wall: Vec<Vec<PairHistory>>,
    /// Lagrange multipliers (method `lagrange`), see [`Multipliers`].
    pub lm: Multipliers,
    /// How far a wall may move in one step (mm): widens the wall candidates of the
    /// Lagrange multipliers. Set by the driver from the wall speeds and the largest step.
    pub wall_reach: f64,
    /// Time of the configuration `select_pairs` is given (s).
    pub time: f64,
    /// Nodal contact state of the last evaluation, and of the last committed step.
    trial_nodal: NodalContact,
    pub nodal: NodalContact,
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
/// of its force column), an inactive one has the row F_λ = −(A/c) λ, which drives λ to zero.
/// Newton on this semismooth system is the primal–dual active-set method (Hintermüller, Ito &
/// Kunisch, SIAM J. Optim. 13, 2002). Node-to-segment pairs are two-pass like the penalty
/// methods (a node takes one master segment), so rows may be nearly dependent.
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

impl Wall {
    fn from_spec(w: &WallSpec, t: f64) -> Wall {
        let p = wall_position(w, t);
        match w.side {
            WallSide::Left => Wall { point: [p, 0.0], normal: [1.0, 0.0] },
            WallSide::Right => Wall { point: [p, 0.0], normal: [-1.0, 0.0] },
            WallSide::Bottom => Wall { point: [0.0, p], normal: [0.0, 1.0] },
            WallSide::Top => Wall { point: [0.0, p], normal: [0.0, -1.0] },
        }
    }
}

/// Position of a wall at time t (x of left/right, y of bottom/top, mm).
pub fn wall_position(w: &WallSpec, t: f64) -> f64 {
    match w.side {
        WallSide::Left | WallSide::Bottom => w.position + w.velocity * t,
        WallSide::Right | WallSide::Top => w.position - w.velocity * t,
    }
}

impl ContactProblem {
    /// The contact problem of a model, or `None` when there is nothing that can touch (no walls
    /// and a single body).
    pub fn new(model: &Model, walls: Vec<WallSpec>, spec: ContactSpec) -> Option<Self> {
        if walls.is_empty() && model.bodies.len() < 2 {
            return None;
        }
        let meshes: Vec<(&crate::mesh::Mesh, usize)> = model.bodies.iter().map(|b| (&b.mesh, b.node_offset)).collect();
        let (segments, slaves) = boundary_of(&meshes);
        let mut len_at: HashMap<usize, f64> = HashMap::new();
        for s in &segments {
            let (a, b) = (model.x0[s.nodes[0]], model.x0[s.nodes[1]]);
            let l = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            for n in s.nodes {
                *len_at.entry(n).or_insert(0.0) += 0.5 * l;
            }
        }
        let area = slaves.iter().map(|(n, _)| len_at.get(n).copied().unwrap_or(0.0)).collect();
        let mut body_h = Vec::new();
        let mut body_e = Vec::new();
        for b in &model.bodies {
            body_h.push(b.contact_h);
            body_e.push(match &model.materials[b.material] {
                crate::material::Material::Elastic(m) => m.e,
                crate::material::Material::J2(m) => m.e,
                crate::material::Material::Creep(m) => m.e,
            });
        }
        let nw = walls.len();
        let ns = slaves.len();
        let search = ContactSearch::new(segments.clone());
        // boundary neighbours: the segment ending at a segment's first node and the one
        // starting at its second node (unique on a closed boundary loop)
        let mut ending: HashMap<usize, Vec<usize>> = HashMap::new();
        let mut starting: HashMap<usize, Vec<usize>> = HashMap::new();
        for (k, s) in segments.iter().enumerate() {
            starting.entry(s.nodes[0]).or_default().push(k);
            ending.entry(s.nodes[1]).or_default().push(k);
        }
        let neighbours = segments
            .iter()
            .map(|s| {
                let prev = ending.get(&s.nodes[0]).filter(|v| v.len() == 1).map(|v| segments[v[0]].nodes[0]);
                let next = starting.get(&s.nodes[1]).filter(|v| v.len() == 1).map(|v| segments[v[0]].nodes[1]);
                [prev, next]
            })
            .collect();
        Some(Self {
            walls,
            spec,
            segments,
            neighbours,
            slaves,
            area,
            body_h,
            body_e,
            search,
            pairs: Vec::new(),
            nts_hist: HashMap::new(),
            wall_hist: vec![vec![PairHistory::default(); ns]; nw],
            trial_nts: Vec::new(),
            trial_wall: vec![vec![PairHistory::default(); ns]; nw],
            aug_nts: Vec::new(),
            aug_wall: vec![vec![PairHistory::default(); ns]; nw],
            lm: Multipliers::default(),
            wall_reach: 0.0,
            time: 0.0,
            trial_nodal: NodalContact::default(),
            nodal: NodalContact::default(),
        })
    }

    fn smoothed(&self) -> bool {
        self.spec.normal == ContactNormal::Smoothed
    }

    /// The smoothed master surface of segment `seg` at configuration `x`.
    fn master(&self, seg: usize, x: &[[f64; 2]]) -> smooth::Master {
        let s = self.segments[seg];
        let [prev, next] = self.neighbours[seg];
        smooth::Master { x1: x[s.nodes[0]], x2: x[s.nodes[1]], prev: prev.map(|n| x[n]), next: next.map(|n| x[n]) }
    }

    /// Global dofs of a smoothed pair in the kernel's order [s, 1, 2, 0, 3]; an absent
    /// neighbour takes the dofs of the segment's own end node (its entries are zero).
    fn smooth_dofs(&self, node: usize, seg: usize) -> ([usize; smooth::NDOF], [usize; 5]) {
        let s = self.segments[seg];
        let [prev, next] = self.neighbours[seg];
        let nodes = [node, s.nodes[0], s.nodes[1], prev.unwrap_or(s.nodes[0]), next.unwrap_or(s.nodes[1])];
        let mut d = [0; smooth::NDOF];
        for (i, &n) in nodes.iter().enumerate() {
            d[2 * i] = 2 * n;
            d[2 * i + 1] = 2 * n + 1;
        }
        (d, nodes)
    }

    /// Projection parameter ξ of `node` on segment `seg` (straight or smoothed).
    fn xi_of(&self, node: usize, seg: usize, x: &[[f64; 2]]) -> f64 {
        self.xi_at(x[node], seg, x)
    }

    /// Projection parameter ξ of the point `p` on segment `seg` (straight or smoothed; the
    /// straight projection, extrapolated beyond the ends, where the smoothed one has none).
    fn xi_at(&self, p: [f64; 2], seg: usize, x: &[[f64; 2]]) -> f64 {
        let s = self.segments[seg];
        let straight = || kernels::nts_project(p, x[s.nodes[0]], x[s.nodes[1]]).xi;
        if self.smoothed() {
            smooth::smooth_project(p, &self.master(seg, x)).map_or_else(straight, |g| g.xi)
        } else {
            straight()
        }
    }

    /// The point of segment `seg` at parameter ξ on configuration `x` (on the smoothed surface
    /// when `normal = "smoothed"`, else on the chord).
    fn point_at(&self, seg: usize, xi: f64, x: &[[f64; 2]]) -> [f64; 2] {
        let s = self.segments[seg];
        let (a, b) = (x[s.nodes[0]], x[s.nodes[1]]);
        let chord = [(1.0 - xi) * a[0] + xi * b[0], (1.0 - xi) * a[1] + xi * b[1]];
        if self.smoothed() {
            smooth::smooth_point(&self.master(seg, x), xi).unwrap_or(chord)
        } else {
            chord
        }
    }

    fn h_of(&self, body: usize) -> f64 {
        self.body_h[body]
    }

    fn params(&self, b1: usize, b2: Option<usize>) -> PenaltyParams {
        match self.spec.penalty {
            Some(e) => PenaltyParams { eps_n: e, eps_t: e },
            None => {
                let (e, h) = match b2 {
                    Some(b2) => (self.body_e[b1].min(self.body_e[b2]), self.body_h[b1].min(self.body_h[b2])),
                    None => (self.body_e[b1], self.body_h[b1]),
                };
                kernels::default_penalty(e, h)
            }
        }
    }

    /// The die [x_left, x_right, y_bottom, y_top] at time t, when all four walls exist.
    pub fn die(&self, t: f64) -> Option<[f64; 4]> {
        let pos = |s: WallSide| self.walls.iter().find(|w| w.side == s).map(|w| wall_position(w, t));
        Some([pos(WallSide::Left)?, pos(WallSide::Right)?, pos(WallSide::Bottom)?, pos(WallSide::Top)?])
    }

    /// Current length of wall `w` (mm): the distance between the two walls it spans, or the
    /// extent of the particles when those walls are missing.
    pub fn wall_length(&self, w: usize, t: f64, x: &[[f64; 2]]) -> f64 {
        let pos = |s: WallSide| self.walls.iter().find(|q| q.side == s).map(|q| wall_position(q, t));
        let extent = |c: usize| {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for &(n, _) in &self.slaves {
                lo = lo.min(x[n][c]);
                hi = hi.max(x[n][c]);
            }
            (lo, hi)
        };
        match self.walls[w].side {
            WallSide::Left | WallSide::Right => match (pos(WallSide::Bottom), pos(WallSide::Top)) {
                (Some(a), Some(b)) => b - a,
                _ => {
                    let (lo, hi) = extent(1);
                    hi - lo
                }
            },
            WallSide::Bottom | WallSide::Top => match (pos(WallSide::Left), pos(WallSide::Right)) {
                (Some(a), Some(b)) => b - a,
                _ => {
                    let (lo, hi) = extent(0);
                    hi - lo
                }
            },
        }
    }

    /// The frozen pairs that involve `node` (as the slave, or as a node of the master segment
    /// or its smoothing neighbours) on configuration `x`, one line each: for the logs of a
    /// stalled Newton solve.
    pub fn describe_node(&self, node: usize, x: &[[f64; 2]]) -> Vec<String> {
        let mut lines = Vec::new();
        for p in &self.pairs {
            let (slave, body) = self.slaves[p.slave];
            let s = self.segments[p.segment];
            let [prev, next] = self.neighbours[p.segment];
            let role = if slave == node {
                "slave"
            } else if s.nodes.contains(&node) {
                "master"
            } else if prev == Some(node) || next == Some(node) {
                "neighbour"
            } else {
                continue;
            };
            let (xi, gap) = if self.smoothed() {
                smooth::smooth_project(x[slave], &self.master(p.segment, x)).map_or((f64::NAN, f64::NAN), |g| (g.xi, g.gap))
            } else {
                let g = kernels::nts_project(x[slave], x[s.nodes[0]], x[s.nodes[1]]);
                (g.xi, g.gap)
            };
            lines.push(format!("{role}: slave {slave} (body {body}) on segment {:?} (body {}) weight {} xi {xi:.6} gap {gap:.6e}", s.nodes, s.body, p.weight));
        }
        lines
    }

    /// Choose the node-to-segment pairs for the next step on configuration `x` (frozen during
    /// the step). Returns true when the set of pairs changed (the sparsity pattern must follow).
    pub fn select_pairs(&mut self, x: &[[f64; 2]]) -> bool {
        let h_min = self.body_h.iter().copied().fold(f64::INFINITY, f64::min);
        let distance = self.spec.search_distance.unwrap_or(h_min);
        self.search.update(x);
        let candidates = self.search.pairs(x, &self.slaves, distance);
        // per slave node: the candidate segment with the smallest distance whose projection
        // falls on it (small tolerance at the ends)
        let slave_index: HashMap<usize, usize> = self.slaves.iter().enumerate().map(|(i, (n, _))| (*n, i)).collect();
        let mut best: HashMap<usize, (f64, Vec<usize>)> = HashMap::new();
        for (node, seg) in candidates {
            let s = self.segments[seg];
            let (xi, gap, d) = if self.smoothed() {
                // closest point on the smoothed surface; outside [0, 1] the distance to the
                // segment's end node (the neighbour segment then wins)
                let Some(g) = smooth::smooth_project(x[node], &self.master(seg, x)) else { continue };
                let end = |p: [f64; 2]| ((x[node][0] - p[0]).powi(2) + (x[node][1] - p[1]).powi(2)).sqrt();
                let d = if g.xi < 0.0 {
                    end(x[s.nodes[0]])
                } else if g.xi > 1.0 {
                    end(x[s.nodes[1]])
                } else {
                    g.gap.abs()
                };
                (g.xi, g.gap, d)
            } else {
                let g = kernels::nts_project(x[node], x[s.nodes[0]], x[s.nodes[1]]);
                (g.xi, g.gap, super::search::point_segment_distance(x[node], x[s.nodes[0]], x[s.nodes[1]]))
            };
            if !(xi >= -0.02 && xi <= 1.02) {
                continue;
            }
            let si = slave_index[&node];
            if gap < -self.h_of(self.slaves[si].1) {
                continue; // deeper than an element: not a physical contact of this node
            }
            // a tie is bilateral: only nodes that touch, or have passed the surface within the
            // step (a wall or particle moving faster than the touch band), or were tied before
            if matches!(self.spec.kind, ContactKind::Cohering)
                && gap > TOUCH * self.h_of(self.slaves[si].1)
                && !self.nts_hist.get(&(node, seg)).is_some_and(|h| h.active)
            {
                continue;
            }
            // closest segment; exact ties (node facing a master node) keep both segments, except
            // for exact Lagrange multipliers, where two nodes facing each other would give
            // dependent rows (the regularised ones take them)
            let exact_lm = self.spec.method == ContactMethod::Lagrange && self.spec.lagrange_regularisation <= 0.0;
            let tie = if exact_lm { -1.0 } else { TIE * self.h_of(self.slaves[si].1) };
            match best.get_mut(&si) {
                Some((db, segs)) if (d - *db).abs() <= tie => {
                    if segs.len() < 2 && !segs.contains(&seg) {
                        segs.push(seg);
                    }
                }
                Some((db, _)) if *db < d => {}
                _ => {
                    best.insert(si, (d, vec![seg]));
                }
            }
        }
        let mut pairs: Vec<FrozenPair> = best
            .into_iter()
            .flat_map(|(slave, (_, segs))| {
                let w = 1.0 / segs.len() as f64;
                segs.into_iter().map(move |segment| FrozenPair { slave, segment, weight: w })
            })
            .collect();
        pairs.sort_by_key(|p| (p.slave, p.segment));
        let changed = pairs != self.pairs;
        self.pairs = pairs;
        // new tied pairs stick from the start: anchor at the current projection
        if matches!(self.spec.kind, ContactKind::Cohering) {
            for p in &self.pairs {
                let node = self.slaves[p.slave].0;
                let xi = self.xi_of(node, p.segment, x);
                self.nts_hist.entry((node, p.segment)).or_insert(PairHistory { xi_stick: xi, lambda_n: 0.0, lambda_t: 0.0, active: true });
            }
        }
        self.trial_nts = self
            .pairs
            .iter()
            .map(|p| self.nts_hist.get(&(self.slaves[p.slave].0, p.segment)).copied().unwrap_or_default())
            .collect();
        self.aug_nts.clone_from(&self.trial_nts);
        if self.spec.method == ContactMethod::Lagrange {
            return self.select_candidates(x, distance) || changed;
        }
        changed
    }

    fn lm_key(&self, c: Candidate) -> (u8, usize, usize) {
        match c {
            Candidate::Pair(k) => (0, self.slaves[self.pairs[k].slave].0, self.pairs[k].segment),
            Candidate::Wall { wall, slave } => (1, wall, slave),
        }
    }

    /// Lagrange multipliers of the step: every frozen pair, and every slave node closer to a
    /// wall than the search distance plus `wall_reach` (how far a wall may move in one step);
    /// λ starts from its committed value. True when the set changed.
    fn select_candidates(&mut self, x: &[[f64; 2]], distance: f64) -> bool {
        let mut cands: Vec<Candidate> = (0..self.pairs.len()).map(Candidate::Pair).collect();
        for (w, spec) in self.walls.iter().enumerate() {
            let wall = Wall::from_spec(spec, self.time);
            for (i, &(node, _)) in self.slaves.iter().enumerate() {
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

    /// Global dofs each Lagrange multiplier couples with (empty unless method = lagrange).
    pub fn multiplier_dofs(&self) -> Vec<Vec<usize>> {
        self.lm
            .candidates
            .iter()
            .map(|&c| match c {
                Candidate::Pair(k) => {
                    let p = self.pairs[k];
                    let s = self.segments[p.segment];
                    let n = self.slaves[p.slave].0;
                    if self.smoothed() {
                        self.smooth_dofs(n, p.segment).0.to_vec()
                    } else {
                        vec![2 * n, 2 * n + 1, 2 * s.nodes[0], 2 * s.nodes[0] + 1, 2 * s.nodes[1], 2 * s.nodes[1] + 1]
                    }
                }
                Candidate::Wall { slave, .. } => {
                    let n = self.slaves[slave].0;
                    vec![2 * n, 2 * n + 1]
                }
            })
            .collect()
    }

    /// Lagrange-multiplier contributions at configuration `x`, time `t`: forces −λ A ∇g into
    /// `f_int`, the rows F_λ into `self.lm.rows`, and with a tangent the blocks
    /// [−λ A ∇∇g, −A ∇g; −A ∇gᵀ, 0] (active) or [0, 0; 0, −A/c] (inactive), the multiplier of
    /// candidate k being equation `n_free + k`.
    fn add_lagrange(&mut self, x: &[[f64; 2]], t: f64, f_int: &mut [f64], mut kk: Option<(&mut CsrMatrix, &[usize], usize)>) -> ContactStats {
        let mut stats = ContactStats { wall_force: vec![0.0; self.walls.len()], ..Default::default() };
        self.trial_nodal.reset(x.len(), self.walls.len());
        let walls: Vec<Wall> = self.walls.iter().map(|w| Wall::from_spec(w, t)).collect();
        let no_penalty = PenaltyParams { eps_n: 0.0, eps_t: 0.0 };
        let mut out = PairOut::default();
        let mut sout = SmoothPairOut::default();
        for (k, &cand) in self.lm.candidates.iter().enumerate() {
            let lambda = self.lm.lambda[k];
            // the force column −λ A ∇g and the constraint row −A ∇g: the same gradient except for
            // the smoothed normal, whose force is taken at fixed end angles (see `smooth`)
            let (dofs, grad, row_grad, gap, area, c): (Vec<usize>, Vec<f64>, Vec<f64>, f64, f64, f64) = match cand {
                Candidate::Pair(q) => {
                    let p = self.pairs[q];
                    let (node, body) = self.slaves[p.slave];
                    let s = self.segments[p.segment];
                    let (xs, x1, x2) = (x[node], x[s.nodes[0]], x[s.nodes[1]]);
                    let area = self.area[p.slave] * p.weight;
                    let c = self.params(body, Some(s.body)).eps_n;
                    if self.smoothed() {
                        let master = self.master(p.segment, x);
                        let (dofs, _) = self.smooth_dofs(node, p.segment);
                        // the kernel with a zero penalty and λ as its multiplier gives ∇g and,
                        // when λ carries, the geometric stiffness −λ A ∇∇g
                        let hist = PairHistory { xi_stick: 0.0, lambda_n: lambda.max(0.0), lambda_t: 0.0, active: true };
                        smooth::nts_smooth_pair(xs, &master, area, ContactKind::Sliding, &no_penalty, &hist, &mut sout);
                        if !sout.gap.is_finite() {
                            self.lm.rows[k] = -area * lambda;
                            self.lm.scale[k] = c;
                            self.trial_nts[q] = PairHistory::default();
                            continue;
                        }
                        let (grad, row) = if sout.active {
                            (sout.grad.to_vec(), sout.grad_full.to_vec())
                        } else {
                            // the gradients without a force: the kernel with a token multiplier
                            let token = PairHistory { lambda_n: 1.0, ..hist };
                            let mut probe = SmoothPairOut::default();
                            smooth::nts_smooth_pair(xs, &master, area, ContactKind::Sliding, &no_penalty, &token, &mut probe);
                            (probe.grad.to_vec(), probe.grad_full.to_vec())
                        };
                        if lambda > 0.0 && lambda - c * sout.gap > 0.0 && sout.active {
                            if let Some((m, eq, _)) = kk.as_mut() {
                                add_block(m, eq, &dofs, sout.k.as_flattened());
                            }
                        }
                        (dofs.to_vec(), grad, row, sout.gap, area, c)
                    } else {
                        let g = kernels::nts_project(xs, x1, x2);
                        if !g.gap.is_finite() {
                            self.lm.rows[k] = -area * lambda;
                            self.lm.scale[k] = c;
                            self.trial_nts[q] = PairHistory::default();
                            continue;
                        }
                        let (n, xi) = (g.normal, g.xi);
                        let grad = vec![n[0], n[1], -(1.0 - xi) * n[0], -(1.0 - xi) * n[1], -xi * n[0], -xi * n[1]];
                        let dofs = vec![2 * node, 2 * node + 1, 2 * s.nodes[0], 2 * s.nodes[0] + 1, 2 * s.nodes[1], 2 * s.nodes[1] + 1];
                        // force and geometric stiffness of the pressure λ: the penalty kernel with a
                        // zero penalty and λ as its multiplier
                        if lambda > 0.0 && lambda - c * g.gap > 0.0 {
                            let hist = PairHistory { xi_stick: xi, lambda_n: lambda, lambda_t: 0.0, active: true };
                            kernels::nts_pair(xs, x1, x2, area, ContactKind::Sliding, &no_penalty, &hist, &mut out);
                            if let Some((m, eq, _)) = kk.as_mut() {
                                add_block(m, eq, &[dofs[0], dofs[1], dofs[2], dofs[3], dofs[4], dofs[5]], out.k.as_flattened());
                            }
                        }
                        (dofs, grad.clone(), grad, g.gap, area, c)
                    }
                }
                Candidate::Wall { wall, slave } => {
                    let (node, body) = self.slaves[slave];
                    let w = &walls[wall];
                    let n = w.normal;
                    let gap = (x[node][0] - w.point[0]) * n[0] + (x[node][1] - w.point[1]) * n[1];
                    (vec![2 * node, 2 * node + 1], vec![n[0], n[1]], vec![n[0], n[1]], gap, self.area[slave], self.params(body, None).eps_n)
                }
            };
            // the force −λ A ∇g acts whatever the active set: an inactive candidate's row
            // drives its λ to zero in one Newton update, and its column removes the force
            for (i, &d) in dofs.iter().enumerate() {
                f_int[d] -= lambda * area * grad[i];
            }
            let active = lambda - c * gap > 0.0;
            let slave_node = dofs[0] / 2;
            self.trial_nodal.gap(slave_node, gap);
            if active && lambda > 0.0 {
                // the force on the node is minus its contribution −λ A ∇g to the internal force
                for (&d, &g) in dofs.iter().zip(&grad) {
                    self.trial_nodal.force[d / 2][d % 2] += lambda * area * g;
                }
                let share = match cand {
                    Candidate::Pair(q) => lambda * self.pairs[q].weight,
                    Candidate::Wall { .. } => 0.0,
                };
                self.trial_nodal.active(slave_node, share, ContactKind::Sliding, true);
                if let Candidate::Wall { wall, .. } = cand {
                    self.trial_nodal.wall_force[wall][slave_node] += lambda * area;
                    self.trial_nodal.pressure[slave_node] = self.trial_nodal.pressure[slave_node].max(lambda);
                }
            }
            self.lm.scale[k] = c;
            // perturbed Lagrangian: an active row is −A (g + r λ / c), which keeps the system
            // regular where two candidates constrain the same gap (two-pass pairs of two nodes
            // facing each other); it leaves a penetration r λ / c
            let reg = self.spec.lagrange_regularisation;
            self.lm.rows[k] = if active { -c * area * gap - reg * area * lambda } else { -area * lambda };
            if let Some((m, eq, n_free)) = kk.as_mut() {
                let row = *n_free + k;
                for (i, &d) in dofs.iter().enumerate() {
                    let q = eq[d];
                    if q == FIXED {
                        continue;
                    }
                    if let Some(pos) = m.find(q, row) {
                        m.values[pos] += -c * area * grad[i];
                    }
                    if active {
                        if let Some(pos) = m.find(row, q) {
                            m.values[pos] += -c * area * row_grad[i];
                        }
                    }
                }
                let diagonal = if active { -reg * c * area } else { -c * area };
                if diagonal != 0.0 {
                    if let Some(pos) = m.find(row, row) {
                        m.values[pos] += diagonal;
                    }
                }
            }
            let carries = active && lambda > 0.0;
            let hist = PairHistory { xi_stick: 0.0, lambda_n: if carries { lambda } else { 0.0 }, lambda_t: 0.0, active: carries };
            match cand {
                Candidate::Pair(q) => self.trial_nts[q] = hist,
                Candidate::Wall { wall, slave } => {
                    self.trial_wall[wall][slave] = hist;
                    if carries {
                        stats.wall_force[wall] += lambda * area;
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

    /// Node triples (slave, master 1, master 2) that the sparsity pattern must couple.
    /// With the smoothed normal a pair couples five nodes (s, 1, 2 and the neighbours 0, 3):
    /// four triples cover every couple of them.
    pub fn couplings(&self) -> Vec<[usize; 3]> {
        if self.smoothed() {
            return self
                .pairs
                .iter()
                .flat_map(|p| {
                    let (_, [s, a, b, p0, p3]) = self.smooth_dofs(self.slaves[p.slave].0, p.segment);
                    [[s, a, b], [s, p0, p3], [p0, a, p3], [p0, b, p3]]
                })
                .collect();
        }
        self.pairs
            .iter()
            .map(|p| {
                let s = self.segments[p.segment];
                [self.slaves[p.slave].0, s.nodes[0], s.nodes[1]]
            })
            .collect()
    }

    /// Add the contact forces to `f_int` and, with a tangent, their derivative to `kk`, at
    /// configuration `x` and time `t`. Histories are read from the committed state (for the
    /// augmented Lagrangian, the current multipliers); the trial histories are kept for commit.
    ///
    /// The kernels are shared out by `ex` (see [`PairExchange`]): this process evaluates the
    /// node-to-segment and node-to-wall pairs of the slave nodes of its bodies only, into
    /// records that `ex` gathers from every process; every process then adds the records in
    /// the serial order (pairs by index, then walls by wall and slave), so the forces, the
    /// statistics, the trial histories and the nodal results come out the same on every
    /// process and bit-identical to a serial run. `tangent` says whether a tangent is
    /// assembled (the same on every process: the blocks of the tangent go to the root only,
    /// which alone passes `kk`). Lagrange multipliers (`method = "lagrange"`) are evaluated on
    /// every process.
    pub fn add(&mut self, x: &[[f64; 2]], t: f64, f_int: &mut [f64], kk: Option<(&mut CsrMatrix, &[usize], usize)>, tangent: bool, ex: &dyn PairExchange) -> ContactStats {
        if self.spec.method == ContactMethod::Lagrange {
            return self.add_lagrange(x, t, f_int, kk);
        }
        let nf = if self.smoothed() { smooth::NDOF } else { 6 };
        let (local, local_k) = self.evaluate_own(x, t, tangent, ex);
        let all = ex.all_gather(local);
        let all_k = if tangent { ex.gather_to_root(local_k) } else { Vec::new() };
        let recs = Records::parse(&all, nf, false);
        let krecs = Records::parse(&all_k, nf, true);
        self.apply_records(x, f_int, kk, &recs, &krecs)
    }

    /// The kernels of the pairs whose slave node belongs to a body this process evaluates, as
    /// records (layout: [`Records`]): everything every process needs, and the tangent blocks
    /// of the active pairs (for the root) when `tangent`.
    fn evaluate_own(&self, x: &[[f64; 2]], t: f64, tangent: bool, ex: &dyn PairExchange) -> (Vec<f64>, Vec<f64>) {
        let smoothed = self.smoothed();
        let nf = if smoothed { smooth::NDOF } else { 6 };
        let (mut nts, mut nts_k) = (Vec::new(), Vec::new());
        let mut out = PairOut::default();
        let mut sout = SmoothPairOut::default();
        let (mut n_nts, mut n_nts_k) = (0usize, 0usize);
        for (k, p) in self.pairs.iter().enumerate() {
            let (node, body) = self.slaves[p.slave];
            if !ex.evaluates(body) {
                continue;
            }
            let s = self.segments[p.segment];
            let old = self.nts_hist.get(&(node, p.segment)).copied().unwrap_or_default();
            let params = self.params(body, Some(s.body));
            let kind = self.spec.kind;
            // (the tangent block goes straight into its buffer)
            let (f, gap, pressure, shear, slip, active, new, aug): (&[f64], _, _, _, _, _, _, _) = if smoothed {
                let master = self.master(p.segment, x);
                smooth::nts_smooth_pair(x[node], &master, self.area[p.slave] * p.weight, kind, &params, &old, &mut sout);
                if tangent && sout.active {
                    nts_k.push(k as f64);
                    nts_k.extend_from_slice(sout.k.as_flattened());
                    n_nts_k += 1;
                }
                (&sout.f, sout.gap, sout.pressure, sout.shear, sout.slip, sout.active, sout.new_history, smooth::augment(&sout))
            } else {
                kernels::nts_pair(x[node], x[s.nodes[0]], x[s.nodes[1]], self.area[p.slave] * p.weight, kind, &params, &old, &mut out);
                if tangent && out.active {
                    nts_k.push(k as f64);
                    nts_k.extend_from_slice(out.k.as_flattened());
                    n_nts_k += 1;
                }
                (&out.f, out.gap, out.pressure, out.shear, out.slip, out.active, out.new_history, kernels::augment(&old, &out))
            };
            let viol = if active { violation(kind, gap, shear, slip, &old, params.eps_t) } else { 0.0 };
            nts.push(k as f64);
            nts.extend_from_slice(f);
            nts.extend_from_slice(&[gap, pressure, viol, f64::from(u8::from(slip)), f64::from(u8::from(active))]);
            put_history(&mut nts, &new);
            put_history(&mut nts, &aug);
            n_nts += 1;
        }
        debug_assert_eq!(nts.len(), n_nts * Records::nts_len(nf));
        let (mut walls, mut walls_k, mut gaps) = (Vec::new(), Vec::new(), Vec::new());
        let (mut n_walls, mut n_walls_k) = (0usize, 0usize);
        let ns = self.slaves.len();
        let mut wall_gap = vec![f64::NAN; ns];
        let mut wout = WallOut::default();
        for (w, spec) in self.walls.iter().enumerate() {
            let wall = Wall::from_spec(spec, t);
            // tangential wall motion: the walls move along their normals only
            for (i, &(node, body)) in self.slaves.iter().enumerate() {
                if !ex.evaluates(body) {
                    continue;
                }
                let old = self.wall_hist[w][i];
                let mut eps_t = 0.0;
                let (new, aug, evaluated) = if self.untied_wall(spec, &wall, x[node], body, &old) {
                    (PairHistory::default(), old, false)
                } else {
                    let params = self.params(body, None);
                    eps_t = params.eps_t;
                    kernels::node_wall(x[node], &wall, 0.0, self.area[i], spec.kind, &params, &old, &mut wout);
                    let g = wout.gap;
                    if g.is_finite() && !(wall_gap[i] <= g) {
                        wall_gap[i] = g;
                    }
                    (wout.new_history, kernels::augment_wall(&old, &wout), true)
                };
                let active = evaluated && wout.active;
                // a pair without a record is open with default histories (the anchor of an
                // inactive history means nothing: the kernels start afresh from it)
                if active || !unused(&new) || !unused(&aug) {
                    walls.push((w * ns + i) as f64);
                    if evaluated {
                        walls.extend_from_slice(&wout.f);
                        let viol = if active { violation(spec.kind, wout.gap, wout.shear, wout.slip, &old, eps_t) } else { 0.0 };
                        walls.extend_from_slice(&[wout.gap, wout.pressure, viol, f64::from(u8::from(wout.slip)), f64::from(u8::from(active))]);
                    } else {
                        walls.extend_from_slice(&[0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0]);
                    }
                    put_history(&mut walls, &new);
                    put_history(&mut walls, &aug);
                    n_walls += 1;
                }
                if tangent && active {
                    walls_k.push((w * ns + i) as f64);
                    walls_k.extend_from_slice(wout.k.as_flattened());
                    n_walls_k += 1;
                }
            }
        }
        for (i, &g) in wall_gap.iter().enumerate() {
            if g.is_finite() {
                gaps.extend_from_slice(&[i as f64, g]);
            }
        }
        let n_gaps = gaps.len() / 2;
        let mut local = vec![n_nts as f64, n_walls as f64, n_gaps as f64];
        local.extend(nts);
        local.extend(walls);
        local.extend(gaps);
        let mut local_k = vec![n_nts_k as f64, n_walls_k as f64, 0.0];
        local_k.extend(nts_k);
        local_k.extend(walls_k);
        (local, local_k)
    }

    /// Add the gathered records of every process in the serial order (see
    /// [`ContactProblem::add`]): forces, trial histories, nodal results and statistics, and
    /// the tangent blocks `krecs` into `kk`.
    fn apply_records(&mut self, x: &[[f64; 2]], f_int: &mut [f64], mut kk: Option<(&mut CsrMatrix, &[usize], usize)>, recs: &Records, krecs: &Records) -> ContactStats {
        let mut stats = ContactStats { wall_force: vec![0.0; self.walls.len()], ..Default::default() };
        self.trial_nodal.reset(x.len(), self.walls.len());
        let smoothed = self.smoothed();
        let nf = recs.nf;
        let npairs = self.pairs.len();
        // position of each pair's record and tangent block
        let mut at = vec![usize::MAX; npairs];
        for (pos, r) in recs.nts.iter().enumerate() {
            at[r[0] as usize] = pos;
        }
        let mut at_k = vec![usize::MAX; if kk.is_some() { npairs } else { 0 }];
        if kk.is_some() {
            for (pos, r) in krecs.nts.iter().enumerate() {
                at_k[r[0] as usize] = pos;
            }
        }
        let kind = self.spec.kind;
        for (k, p) in self.pairs.iter().enumerate() {
            let (node, _) = self.slaves[p.slave];
            let s = self.segments[p.segment];
            let Some(r) = recs.nts.get(at[k]) else {
                // (every pair has one owner, so this cannot happen; the pair then contributes
                // nothing)
                self.trial_nts[k] = PairHistory::default();
                self.aug_nts[k] = PairHistory::default();
                continue;
            };
            let f = &r[1..1 + nf];
            let (gap, pressure, viol, slip, active) = (r[1 + nf], r[2 + nf], r[3 + nf], r[4 + nf] != 0.0, r[5 + nf] != 0.0);
            self.trial_nts[k] = get_history(&r[6 + nf..10 + nf]);
            self.aug_nts[k] = get_history(&r[10 + nf..14 + nf]);
            self.trial_nodal.gap(node, gap);
            if !active {
                continue;
            }
            stats.active += 1;
            stats.max_penetration = stats.max_penetration.max(-gap);
            stats.violation = stats.violation.max(viol);
            self.trial_nodal.active(node, p.weight * pressure, kind, slip);
            let block = kk.as_ref().and_then(|_| krecs.nts.get(at_k[k])).map(|b| &b[1..]);
            if smoothed {
                let (dofs, nodes) = self.smooth_dofs(node, p.segment);
                self.trial_nodal.force(&nodes, f);
                for i in 0..smooth::NDOF {
                    f_int[dofs[i]] += f[i];
                }
                if let (Some((m, eq, _)), Some(b)) = (kk.as_mut(), block) {
                    add_block(m, eq, &dofs, b);
                }
            } else {
                self.trial_nodal.force(&[node, s.nodes[0], s.nodes[1]], f);
                let dofs = [2 * node, 2 * node + 1, 2 * s.nodes[0], 2 * s.nodes[0] + 1, 2 * s.nodes[1], 2 * s.nodes[1] + 1];
                for i in 0..6 {
                    f_int[dofs[i]] += f[i];
                }
                if let (Some((m, eq, _)), Some(b)) = (kk.as_mut(), block) {
                    add_block(m, eq, &dofs, b);
                }
            }
        }
        // walls: every pair without a record is open, with default histories
        let ns = self.slaves.len();
        for w in 0..self.walls.len() {
            self.trial_wall[w].iter_mut().for_each(|h| *h = PairHistory::default());
            self.aug_wall[w].iter_mut().for_each(|h| *h = PairHistory::default());
        }
        for r in &recs.gaps {
            self.trial_nodal.gap(self.slaves[r[0] as usize].0, r[1]);
        }
        let mut order: Vec<usize> = (0..recs.walls.len()).collect();
        order.sort_by_key(|&q| recs.walls[q][0] as usize);
        // the tangent blocks in the same order, walked alongside
        let mut blocks: Vec<&[f64]> = if kk.is_some() { krecs.walls.clone() } else { Vec::new() };
        blocks.sort_by_key(|b| b[0] as usize);
        let mut next_block = blocks.iter().peekable();
        for q in order {
            let r = recs.walls[q];
            let key = r[0] as usize;
            let (w, i) = (key / ns, key % ns);
            let (node, _) = self.slaves[i];
            let spec = &self.walls[w];
            self.trial_wall[w][i] = get_history(&r[8..12]);
            self.aug_wall[w][i] = get_history(&r[12..16]);
            let (f, gap, pressure, viol, slip, active) = ([r[1], r[2]], r[3], r[4], r[5], r[6] != 0.0, r[7] != 0.0);
            if !active {
                continue;
            }
            stats.active += 1;
            stats.max_penetration = stats.max_penetration.max(-gap);
            stats.violation = stats.violation.max(viol);
            stats.wall_force[w] += pressure * self.area[i];
            self.trial_nodal.wall_force[w][node] += pressure * self.area[i];
            self.trial_nodal.force(&[node], &f);
            self.trial_nodal.active(node, 0.0, spec.kind, slip);
            self.trial_nodal.pressure[node] = self.trial_nodal.pressure[node].max(pressure);
            let dofs = [2 * node, 2 * node + 1];
            for c in 0..2 {
                f_int[dofs[c]] += f[c];
            }
            if let Some((m, eq, _)) = kk.as_mut() {
                while next_block.peek().is_some_and(|b| (b[0] as usize) < key) {
                    next_block.next();
                }
                if let Some(b) = next_block.next_if(|b| b[0] as usize == key) {
                    add_block(m, eq, &dofs, &b[1..]);
                }
            }
        }
        stats
    }

    /// Uzawa update of every pair's multipliers (λ ← the pressure and shear of the last
    /// evaluation, which [`ContactProblem::add`] has already formed): no kernel is evaluated
    /// again.
    pub fn augment(&mut self) {
        for (k, p) in self.pairs.iter().enumerate() {
            self.nts_hist.insert((self.slaves[p.slave].0, p.segment), self.aug_nts[k]);
        }
        self.wall_hist.clone_from(&self.aug_wall);
    }

    /// A cohering wall ties only nodes that touch it (or were tied before): the kernel's normal
    /// law is bilateral and would otherwise pull every node towards the wall.
    fn untied_wall(&self, spec: &WallSpec, wall: &Wall, x: [f64; 2], body: usize, old: &PairHistory) -> bool {
        if !matches!(spec.kind, ContactKind::Cohering) || old.active {
            return false;
        }
        let g = (x[0] - wall.point[0]) * wall.normal[0] + (x[1] - wall.point[1]) * wall.normal[1];
        g > TOUCH * self.h_of(body)
    }

    /// Which directions (x, y) of each body the committed contacts hold: a body is held in x
    /// when it has an active contact pushing it towards +x and another pushing it towards −x
    /// (normal components beyond [`SUPPORT_COSINE`]), likewise in y. Node-to-segment pairs
    /// count for both bodies (with opposite normals), wall pairs for the particle. `x` is the
    /// committed configuration.
    pub fn body_support(&self, x: &[[f64; 2]], n_bodies: usize) -> Vec<[bool; 2]> {
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
        let body_of: HashMap<usize, usize> = self.slaves.iter().copied().collect();
        for (&(node, seg), h) in &self.nts_hist {
            if !h.active {
                continue;
            }
            let s = self.segments[seg];
            let g = kernels::nts_project(x[node], x[s.nodes[0]], x[s.nodes[1]]);
            if !g.length.is_finite() || g.length <= 0.0 {
                continue;
            }
            // the master's outward normal pushes the slave along +n and the master along −n
            if let Some(&b) = body_of.get(&node) {
                mark(b, g.normal);
            }
            mark(s.body, [-g.normal[0], -g.normal[1]]);
        }
        for (w, spec) in self.walls.iter().enumerate() {
            let wall = Wall::from_spec(spec, 0.0);
            for (i, &(_, body)) in self.slaves.iter().enumerate() {
                if self.wall_hist[w][i].active {
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
        let h_min = self.body_h.iter().copied().fold(f64::INFINITY, f64::min);
        stats.violation > self.spec.penetration_tol * h_min
    }

    /// Commit the trial histories of the last evaluation (after a converged step).
    pub fn commit(&mut self) {
        // keep only the pairs of this step (a node that changed master starts afresh)
        let mut next = HashMap::with_capacity(self.pairs.len());
        for (k, p) in self.pairs.iter().enumerate() {
            next.insert((self.slaves[p.slave].0, p.segment), self.trial_nts[k]);
        }
        self.nts_hist = next;
        self.wall_hist.clone_from(&self.trial_wall);
        self.nodal.clone_from(&self.trial_nodal);
        if self.spec.method == ContactMethod::Lagrange {
            self.lm.committed = self.lm.keys.iter().zip(&self.lm.lambda).filter(|(_, &l)| l > 0.0).map(|(k, &l)| (*k, l)).collect();
        }
    }

    /// Forget augmented multipliers of a failed step: restore from the committed state.
    pub fn snapshot(&self) -> (HashMap<(usize, usize), PairHistory>, Vec<Vec<PairHistory>>) {
        (self.nts_hist.clone(), self.wall_hist.clone())
    }

    pub fn restore(&mut self, snap: (HashMap<(usize, usize), PairHistory>, Vec<Vec<PairHistory>>)) {
        self.nts_hist = snap.0;
        self.wall_hist = snap.1;
    }

    /// The committed contact state that a later step depends on (pair histories, Lagrange
    /// multipliers, nodal results, the element size per body), for a checkpoint. Everything else
    /// is rebuilt by the next step's pair selection.
    pub fn state(&self) -> ContactState {
        let mut nts: Vec<((usize, usize), PairHistory)> = self.nts_hist.iter().map(|(k, v)| (*k, *v)).collect();
        nts.sort_by_key(|(k, _)| *k);
        let mut lm_committed: Vec<((u8, usize, usize), f64)> = self.lm.committed.iter().map(|(k, v)| (*k, *v)).collect();
        lm_committed.sort_by_key(|(k, _)| *k);
        ContactState { nts, walls: self.wall_hist.clone(), lm_committed, nodal: self.nodal.clone(), body_h: self.body_h.clone(), area: self.area.clone() }
    }

    /// Set the committed state from [`ContactProblem::state`] of the same model.
    ///
    /// # Errors
    /// A message when the state does not fit this contact problem (walls, boundary nodes,
    /// bodies).
    pub fn set_state(&mut self, s: ContactState) -> Result<(), String> {
        if s.walls.len() != self.wall_hist.len() || s.walls.iter().any(|w| w.len() != self.slaves.len()) {
            return Err(format!(
                "contact: {} wall(s) x {} boundary node(s) in the checkpoint, {} x {} in the model",
                s.walls.len(),
                s.walls.first().map_or(0, Vec::len),
                self.wall_hist.len(),
                self.slaves.len()
            ));
        }
        if s.body_h.len() != self.body_h.len() {
            return Err(format!("contact: {} bodies in the checkpoint, {} in the model", s.body_h.len(), self.body_h.len()));
        }
        if !s.area.is_empty() && s.area.len() != self.area.len() {
            return Err(format!("contact: {} boundary lengths in the checkpoint, {} boundary nodes in the model", s.area.len(), self.area.len()));
        }
        if !s.area.is_empty() {
            self.area = s.area;
        }
        self.nts_hist = s.nts.into_iter().collect();
        self.wall_hist = s.walls;
        self.lm.committed = s.lm_committed.into_iter().collect();
        self.nodal = s.nodal;
        self.body_h = s.body_h;
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
        let seg_of: HashMap<[usize; 2], usize> = self.segments.iter().enumerate().map(|(k, s)| (s.nodes, k)).collect();
        let slave_of: HashMap<usize, usize> = self.slaves.iter().enumerate().map(|(i, (n, _))| (*n, i)).collect();
        let map = |n: usize| node_map.get(n).copied().flatten();
        let kept_segment = |k: usize| -> Option<usize> {
            let [a, b] = old.segments[k].nodes;
            seg_of.get(&[map(a)?, map(b)?]).copied()
        };
        // node-to-segment histories, in sorted order (a collision keeps the first)
        let mut nts: Vec<(&(usize, usize), &PairHistory)> = old.nts_hist.iter().collect();
        nts.sort_by_key(|(k, _)| **k);
        let mut next: HashMap<(usize, usize), PairHistory> = HashMap::with_capacity(nts.len());
        for (&(slave, seg), h) in nts {
            let Some(s_new) = map(slave) else {
                out.dropped += usize::from(h.active);
                continue;
            };
            if let Some(k) = kept_segment(seg) {
                next.entry((s_new, k)).or_insert(*h);
                out.kept += usize::from(h.active);
                continue;
            }
            if !h.active {
                continue;
            }
            // the anchor as a point, onto the nearest new segment of the master body
            let body = old.segments[seg].body;
            let anchor = old.point_at(seg, h.xi_stick, x_old);
            let nearest = self
                .segments
                .iter()
                .enumerate()
                .filter(|(_, s)| s.body == body)
                .map(|(k, s)| (super::search::point_segment_distance(x[s_new], x[s.nodes[0]], x[s.nodes[1]]), k))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let Some((_, k)) = nearest else {
                out.dropped += 1;
                continue;
            };
            let xi_stick = self.xi_at(anchor, k, x);
            next.entry((s_new, k)).or_insert(PairHistory { xi_stick, ..*h });
            out.moved += 1;
        }
        self.nts_hist = next;
        // node-to-wall histories and nodal results follow the slave nodes
        let n_new = x.len();
        let mut nodal = NodalContact::default();
        nodal.reset(n_new, self.walls.len());
        for (i, &(n, _)) in old.slaves.iter().enumerate() {
            let Some(j) = map(n).and_then(|m| slave_of.get(&m).copied()) else { continue };
            for w in 0..self.wall_hist.len().min(old.wall_hist.len()) {
                self.wall_hist[w][j] = old.wall_hist[w][i];
                out.walls += usize::from(old.wall_hist[w][i].active);
            }
        }
        self.trial_wall.clone_from(&self.wall_hist);
        self.aug_wall.clone_from(&self.wall_hist);
        for (n, m) in node_map.iter().enumerate() {
            let Some(m) = *m else { continue };
            if n >= old.nodal.pressure.len() || m >= n_new {
                continue;
            }
            nodal.pressure[m] = old.nodal.pressure[n];
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
                _ => old.slaves.get(b).and_then(|&(n, _)| map(n)).and_then(|m| slave_of.get(&m)).map(|&j| (1, a, j)),
            };
            if let Some(key) = key {
                lm.entry(key).or_insert(l);
                out.multipliers += 1;
            }
        }
        self.lm.committed = lm;
        // tributary lengths: the old reference length of every boundary segment kept
        let len = |p: [f64; 2], q: [f64; 2]| ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        let mut changed = vec![false; self.slaves.len()];
        for (k, s) in old.segments.iter().enumerate() {
            let Some(knew) = kept_segment(k) else { continue };
            let [a, b] = s.nodes;
            let [an, bn] = self.segments[knew].nodes;
            let delta = 0.5 * (len(x0_old[a], x0_old[b]) - len(x0[an], x0[bn]));
            if delta == 0.0 {
                continue;
            }
            for n in [an, bn] {
                if let Some(&j) = slave_of.get(&n) {
                    self.area[j] += delta;
                    changed[j] = true;
                }
            }
        }
        out.areas = changed.iter().filter(|&&c| c).count();
        out
    }

    /// Contact kind used between particles.
    pub fn kind(&self) -> ContactKind {
        self.spec.kind
    }
}

/// Add the row-major N × N block `k` (rows and columns: `dofs`) to `m`, skipping fixed dofs.
fn add_block<const N: usize>(m: &mut CsrMatrix, eq: &[usize], dofs: &[usize; N], k: &[f64]) {
    let n = N;
    for a in 0..n {
        let r = eq[dofs[a]];
        if r == FIXED {
            continue;
        }
        for b in 0..n {
            let c = eq[dofs[b]];
            if c == FIXED {
                continue;
            }
            if let Some(pos) = m.find(r, c) {
                m.values[pos] += k[a * n + b];
            }
        }
    }
}

/// An inactive history without multipliers: the kernels take nothing from it (they re-anchor
/// an inactive pair), so any such history stands for the default one.
fn unused(h: &PairHistory) -> bool {
    !h.active && h.lambda_n == 0.0 && h.lambda_t == 0.0
}

fn put_history(v: &mut Vec<f64>, h: &PairHistory) {
    v.extend_from_slice(&[h.xi_stick, h.lambda_n, h.lambda_t, f64::from(u8::from(h.active))]);
}

fn get_history(v: &[f64]) -> PairHistory {
    PairHistory { xi_stick: v[0], lambda_n: v[1], lambda_t: v[2], active: v[3] != 0.0 }
}

/// How the contact kernels of an evaluation are shared among the processes of a run
/// ([`ContactProblem::add`]): which slave nodes this process evaluates (those of its own
/// bodies; the master segments they need are there too, as every process holds the whole
/// configuration), and the exchange of the evaluated records. The solver passes the
/// distribution of its run; [`EveryPair`] is one process.
pub trait PairExchange {
    /// Whether this process evaluates the pairs whose slave node belongs to `body`.
    fn evaluates(&self, body: usize) -> bool;
    /// Every process's `local` records, concatenated in rank order, on every process.
    fn all_gather(&self, local: Vec<f64>) -> Vec<f64>;
    /// Every process's `local` records, concatenated in rank order, on the root (anything,
    /// typically empty, elsewhere).
    fn gather_to_root(&self, local: Vec<f64>) -> Vec<f64>;
}

/// One process evaluates every pair.
#[derive(Clone, Copy, Debug, Default)]
pub struct EveryPair;

impl PairExchange for EveryPair {
    fn evaluates(&self, _body: usize) -> bool {
        true
    }
    fn all_gather(&self, local: Vec<f64>) -> Vec<f64> {
        local
    }
    fn gather_to_root(&self, local: Vec<f64>) -> Vec<f64> {
        local
    }
}

/// The contact records of an evaluation gathered from every process: each process's part is
/// a header `[pairs, walls, gaps]` followed by that many node-to-segment records
/// `[pair, f (nf), gap, pressure, violation, slip, active, trial history (4), augmented history (4)]`,
/// node-to-wall records `[wall · slaves + slave, f (2), gap, pressure, violation, slip, active,
/// trial history (4), augmented history (4)]` (only the pairs that are active or have a
/// history) and gap records `[slave, smallest wall gap]`. The tangent's parts have the same
/// header with node-to-segment blocks `[pair, k (nf²)]` and node-to-wall blocks
/// `[wall · slaves + slave, k (4)]` of the active pairs.
struct Records<'a> {
    nf: usize,
    nts: Vec<&'a [f64]>,
    walls: Vec<&'a [f64]>,
    gaps: Vec<&'a [f64]>,
}

impl<'a> Records<'a> {
    const fn nts_len(nf: usize) -> usize {
        1 + nf + 5 + 8
    }
    const WALL_LEN: usize = 1 + 2 + 5 + 8;

    /// Split gathered value records, or tangent records (`tangent`: blocks of nf² and 4
    /// values).
    fn parse(all: &'a [f64], nf: usize, tangent: bool) -> Self {
        let mut r = Records { nf, nts: Vec::new(), walls: Vec::new(), gaps: Vec::new() };
        let mut pos = 0;
        while pos + 3 <= all.len() {
            let [n_nts, n_walls, n_gaps] = [all[pos] as usize, all[pos + 1] as usize, all[pos + 2] as usize];
            pos += 3;
            let (ln, lw) = if tangent { (1 + nf * nf, 1 + 4) } else { (Self::nts_len(nf), Self::WALL_LEN) };
            let mut take = |n: usize, len: usize, into: &mut Vec<&'a [f64]>| {
                for _ in 0..n {
                    let Some(rec) = all.get(pos..pos + len) else {
                        return false;
                    };
                    into.push(rec);
                    pos += len;
                }
                true
            };
            if !(take(n_nts, ln, &mut r.nts) && take(n_walls, lw, &mut r.walls) && take(n_gaps, 2, &mut r.gaps)) {
                break;
            }
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::CsrMatrix;

    /// One of two processes: evaluates the bodies of its parity (the records are exchanged by
    /// the test).
    struct Half(usize);

    impl PairExchange for Half {
        fn evaluates(&self, body: usize) -> bool {
            body % 2 == self.0
        }
        fn all_gather(&self, local: Vec<f64>) -> Vec<f64> {
            local
        }
        fn gather_to_root(&self, local: Vec<f64>) -> Vec<f64> {
            local
        }
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    fn histories(c: &ContactProblem) -> Vec<PairHistory> {
        let mut h = c.trial_nts.clone();
        h.extend(c.aug_nts.iter().copied());
        c.trial_wall.iter().chain(&c.aug_wall).for_each(|w| h.extend(w.iter().copied()));
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

    /// The contact kernels shared out over two processes by slave-node owner, their records
    /// exchanged and added in the serial order, give the serial evaluation bit for bit: forces,
    /// every entry of the tangent, statistics, trial and augmented histories, nodal results.
    /// The 3 × 3 disc job of `tests/mpi_ranks.rs` (Coulomb friction 0.2) after 3 steps, and
    /// the same with smoothed normals and with the augmented Lagrangian.
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
            let c = sim.contact.as_mut().unwrap();
            let nf = if c.smoothed() { smooth::NDOF } else { 6 };
            // a full pattern, so that every block lands; every dof free
            let full: Vec<Vec<usize>> = (0..n).map(|_| (0..n).collect()).collect();
            let eq: Vec<usize> = (0..n).collect();

            let mut f1 = vec![0.0; n];
            let mut k1 = CsrMatrix::from_rows(n, &full);
            let s1 = c.add(&x, t, &mut f1, Some((&mut k1, &eq, n)), true, &EveryPair);
            let (h1, nodal1) = (histories(c), nodal_bits(&c.trial_nodal));
            assert!(s1.active > 20, "variant {v}: only {} active pairs", s1.active);
            assert!(s1.wall_force.iter().any(|&f| f > 0.0), "variant {v}: no wall carries load");

            // two processes: each evaluates its half, the records are concatenated in rank
            // order, and each process would then add them all
            let (mut all, mut all_k) = (Vec::new(), Vec::new());
            for rank in 0..2 {
                let (local, local_k) = c.evaluate_own(&x, t, true, &Half(rank));
                assert!(local[0] >= 10.0 && local_k[0] >= 10.0, "variant {v}: rank {rank} evaluated {} pairs", local[0]);
                all.extend(local);
                all_k.extend(local_k);
            }
            c.trial_nodal = NodalContact::default();
            c.trial_nts.iter_mut().for_each(|h| *h = PairHistory { xi_stick: 9.0, ..Default::default() });
            let mut f2 = vec![0.0; n];
            let mut k2 = CsrMatrix::from_rows(n, &full);
            let s2 = c.apply_records(&x, &mut f2, Some((&mut k2, &eq, n)), &Records::parse(&all, nf, false), &Records::parse(&all_k, nf, true));
            assert_eq!(bits(&f1), bits(&f2), "variant {v}: forces");
            assert_eq!(bits(&k1.values), bits(&k2.values), "variant {v}: tangent");
            assert_eq!(s1, s2, "variant {v}: statistics");
            assert_eq!(h1, histories(c), "variant {v}: histories");
            assert_eq!(nodal1, nodal_bits(&c.trial_nodal), "variant {v}: nodal results");
        }
    }
}
