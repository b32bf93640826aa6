//! The pairs of a step and their histories: which master segment each boundary node faces
//! (frozen for the step's Newton iterations), and the history of every node-to-segment and
//! node-to-wall pair — committed (the last converged step), trial (the last evaluation) and
//! augmented (the last evaluation's Uzawa update) — with commit, augment, backup and restore,
//! and the carry of the committed histories over a re-mesh.
//!
//! Selection (after LLNL Tribol's "find pairs and freeze them"): the search gives the
//! candidate segments within the search distance of every boundary node (two-pass: every
//! boundary node is a slave against the other bodies); each node takes its closest segment
//! whose projection falls on it (a small tolerance at the ends), or both segments when it
//! faces their common node exactly (a tie, each carrying half its length).

use super::boundary::Boundary;
use super::enforce::{ContactKind, PairHistory};
use super::geometry::nts_project;
use super::search::{point_segment_distance, ContactSearch};
use super::smooth;
use std::collections::HashMap;

/// Gap (relative to the element size) below which a node touches: cohering (tied) pairs are
/// only created for touching nodes.
pub const TOUCH: f64 = 1e-6;

/// Two master segments are equally close to a slave node when their distances differ by less
/// than this (relative to the element size).
const TIE: f64 = 1e-9;

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

/// The committed histories (what a failed step goes back to).
pub type Backup = (HashMap<(usize, usize), PairHistory>, Vec<Vec<PairHistory>>);

/// The frozen pairs of the step and the histories of every pair (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct PairSet {
    pub pairs: Vec<FrozenPair>,
    /// Committed node-to-segment histories by (slave node, segment).
    pub(super) nts: HashMap<(usize, usize), PairHistory>,
    /// Committed node-to-wall histories, `[wall][slave]`.
    pub(super) walls: Vec<Vec<PairHistory>>,
    /// Histories of the last evaluation (per frozen pair; per wall and slave).
    pub(super) trial_nts: Vec<PairHistory>,
    pub(super) trial_walls: Vec<Vec<PairHistory>>,
    /// Uzawa-updated histories of the last evaluation (what `augment` commits).
    pub(super) aug_nts: Vec<PairHistory>,
    pub(super) aug_walls: Vec<Vec<PairHistory>>,
}

impl PairSet {
    /// No pairs, `n_walls` × `n_slaves` default wall histories.
    pub fn new(n_walls: usize, n_slaves: usize) -> Self {
        let walls = vec![vec![PairHistory::default(); n_slaves]; n_walls];
        Self { pairs: Vec::new(), nts: HashMap::new(), trial_walls: walls.clone(), aug_walls: walls.clone(), walls, trial_nts: Vec::new(), aug_nts: Vec::new() }
    }

    /// The committed history of node-to-segment pair `p`.
    pub fn committed(&self, b: &Boundary, p: &FrozenPair) -> PairHistory {
        self.nts.get(&(b.slaves[p.slave].0, p.segment)).copied().unwrap_or_default()
    }

    /// The committed history of slave `i` against wall `w`.
    pub fn committed_wall(&self, w: usize, i: usize) -> PairHistory {
        self.walls[w][i]
    }

    /// Choose the node-to-segment pairs for the next step on configuration `x` (frozen during
    /// the step): candidates within `distance` (mm); `kind` the contact kind between particles
    /// (tied pairs are created only for touching nodes); `exact_ties`: keep one segment per node
    /// even when two are equally close (exact Lagrange multipliers, where two nodes facing each
    /// other would give dependent rows). Returns true when the set of pairs changed.
    pub fn select(&mut self, b: &Boundary, search: &mut ContactSearch, x: &[[f64; 2]], distance: f64, kind: ContactKind, exact_ties: bool) -> bool {
        search.update(x);
        let candidates = search.pairs(x, &b.slaves, distance);
        // per slave node: the candidate segment with the smallest distance whose projection
        // falls on it (small tolerance at the ends)
        let slave_index: HashMap<usize, usize> = b.slaves.iter().enumerate().map(|(i, (n, _))| (*n, i)).collect();
        // (distance, the closest segments, how many: at most two, a tie)
        let mut best: HashMap<usize, (f64, [usize; 2], usize)> = HashMap::with_capacity(b.slaves.len());
        let cohering = matches!(kind, ContactKind::Cohering);
        for (node, seg) in candidates {
            let s = b.segments[seg];
            let (xi, gap, d) = if b.smoothed {
                // closest point on the smoothed surface; outside [0, 1] the distance to the
                // segment's end node (the neighbour segment then wins)
                let Some(g) = smooth::smooth_project(x[node], &b.master(seg, x)) else { continue };
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
                let g = nts_project(x[node], x[s.nodes[0]], x[s.nodes[1]]);
                (g.xi, g.gap, point_segment_distance(x[node], x[s.nodes[0]], x[s.nodes[1]]))
            };
            if !(xi >= -0.02 && xi <= 1.02) {
                continue;
            }
            let si = slave_index[&node];
            let h = b.body_h[b.slaves[si].1];
            if gap < -h {
                continue; // deeper than an element: not a physical contact of this node
            }
            // a tie is bilateral: only nodes that touch, or have passed the surface within the
            // step (a wall or particle moving faster than the touch band), or were tied before
            if cohering && gap > TOUCH * h && !self.nts.get(&(node, seg)).is_some_and(|h| h.active) {
                continue;
            }
            // closest segment; exact ties (node facing a master node) keep both segments, except
            // for exact Lagrange multipliers, where two nodes facing each other would give
            // dependent rows (the regularised ones take them)
            let tie = if exact_ties { -1.0 } else { TIE * h };
            match best.get_mut(&si) {
                Some((db, segs, n)) if (d - *db).abs() <= tie => {
                    if *n < 2 && !segs[..*n].contains(&seg) {
                        segs[*n] = seg;
                        *n += 1;
                    }
                }
                Some((db, _, _)) if *db < d => {}
                _ => {
                    best.insert(si, (d, [seg, seg], 1));
                }
            }
        }
        let mut pairs: Vec<FrozenPair> = best
            .into_iter()
            .flat_map(|(slave, (_, segs, n))| {
                let w = 1.0 / n as f64;
                segs.into_iter().take(n).map(move |segment| FrozenPair { slave, segment, weight: w })
            })
            .collect();
        pairs.sort_by_key(|p| (p.slave, p.segment));
        let changed = pairs != self.pairs;
        self.pairs = pairs;
        // new tied pairs stick from the start: anchor at the current projection
        if cohering {
            for p in &self.pairs {
                let node = b.slaves[p.slave].0;
                let xi = b.xi_at(x[node], p.segment, x);
                self.nts.entry((node, p.segment)).or_insert(PairHistory { xi_stick: xi, lambda_n: 0.0, lambda_t: 0.0, active: true });
            }
        }
        self.trial_nts = self.pairs.iter().map(|p| self.committed(b, p)).collect();
        self.aug_nts.clone_from(&self.trial_nts);
        changed
    }

    /// Uzawa update of every pair's multipliers (λ ← the pressure and shear of the last
    /// evaluation, already formed by the evaluation): no kernel is evaluated again.
    pub fn augment(&mut self, b: &Boundary) {
        for (k, p) in self.pairs.iter().enumerate() {
            self.nts.insert((b.slaves[p.slave].0, p.segment), self.aug_nts[k]);
        }
        self.walls.clone_from(&self.aug_walls);
    }

    /// Commit the trial histories of the last evaluation (after a converged step); only the
    /// pairs of this step are kept (a node that changed master starts afresh).
    pub fn commit(&mut self, b: &Boundary) {
        let mut next = HashMap::with_capacity(self.pairs.len());
        for (k, p) in self.pairs.iter().enumerate() {
            next.insert((b.slaves[p.slave].0, p.segment), self.trial_nts[k]);
        }
        self.nts = next;
        self.walls.clone_from(&self.trial_walls);
    }

    /// The committed histories, to go back to after a failed step.
    pub fn backup(&self) -> Backup {
        (self.nts.clone(), self.walls.clone())
    }

    pub fn restore(&mut self, backup: Backup) {
        self.nts = backup.0;
        self.walls = backup.1;
    }

    /// The committed node-to-segment histories, sorted by (slave node, segment).
    pub fn committed_nts(&self) -> Vec<((usize, usize), PairHistory)> {
        let mut nts: Vec<((usize, usize), PairHistory)> = self.nts.iter().map(|(k, v)| (*k, *v)).collect();
        nts.sort_by_key(|(k, _)| *k);
        nts
    }

    /// The committed node-to-wall histories, `[wall][slave]`.
    pub fn committed_walls(&self) -> &[Vec<PairHistory>] {
        &self.walls
    }

    /// Set the committed histories (from a checkpoint).
    pub fn set_committed(&mut self, nts: Vec<((usize, usize), PairHistory)>, walls: Vec<Vec<PairHistory>>) {
        self.nts = nts.into_iter().collect();
        self.walls = walls;
    }

    /// Carry the committed node-to-segment and node-to-wall histories of `old` (pairs of the
    /// boundary `ob`, configuration `x_old`) to this set on the boundary `nb` (configuration
    /// `x`), `map` giving each old node's new number (see
    /// [`super::problem::ContactProblem::carry_history`]). Returns (kept, moved, dropped, walls).
    pub fn carry(&mut self, old: &PairSet, ob: &Boundary, nb: &Boundary, map: &dyn Fn(usize) -> Option<usize>, kept_segment: &dyn Fn(usize) -> Option<usize>, x_old: &[[f64; 2]], x: &[[f64; 2]]) -> [usize; 4] {
        let (mut kept, mut moved, mut dropped, mut walls) = (0, 0, 0, 0);
        let slave_of: HashMap<usize, usize> = nb.slaves.iter().enumerate().map(|(i, (n, _))| (*n, i)).collect();
        // node-to-segment histories, in sorted order (a collision keeps the first)
        let mut nts: Vec<(&(usize, usize), &PairHistory)> = old.nts.iter().collect();
        nts.sort_by_key(|(k, _)| **k);
        let mut next: HashMap<(usize, usize), PairHistory> = HashMap::with_capacity(nts.len());
        for (&(slave, seg), h) in nts {
            let Some(s_new) = map(slave) else {
                dropped += usize::from(h.active);
                continue;
            };
            if let Some(k) = kept_segment(seg) {
                next.entry((s_new, k)).or_insert(*h);
                kept += usize::from(h.active);
                continue;
            }
            if !h.active {
                continue;
            }
            // the anchor as a point, onto the nearest new segment of the master body
            let body = ob.segments[seg].body;
            let anchor = ob.point_at(seg, h.xi_stick, x_old);
            let nearest = nb
                .segments
                .iter()
                .enumerate()
                .filter(|(_, s)| s.body == body)
                .map(|(k, s)| (point_segment_distance(x[s_new], x[s.nodes[0]], x[s.nodes[1]]), k))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let Some((_, k)) = nearest else {
                dropped += 1;
                continue;
            };
            let xi_stick = nb.xi_at(anchor, k, x);
            next.entry((s_new, k)).or_insert(PairHistory { xi_stick, ..*h });
            moved += 1;
        }
        self.nts = next;
        // node-to-wall histories follow the slave nodes
        for (i, &(n, _)) in ob.slaves.iter().enumerate() {
            let Some(j) = map(n).and_then(|m| slave_of.get(&m).copied()) else { continue };
            for w in 0..self.walls.len().min(old.walls.len()) {
                self.walls[w][j] = old.walls[w][i];
                walls += usize::from(old.walls[w][i].active);
            }
        }
        self.trial_walls.clone_from(&self.walls);
        self.aug_walls.clone_from(&self.walls);
        [kept, moved, dropped, walls]
    }
}
