//! The barrier contact of an assembly (`[contact] method = "barrier"`): the sum of the barrier
//! kernels ([`super::barrier`]) over every boundary node and every boundary edge of another
//! particle closer than d̂, and over every boundary node and every wall closer than d̂ — no
//! master and slave, no active set, no frozen pairs: the pairs are found again at every
//! configuration (the search of [`super::search`] with the distance d̂). With it, the
//! collision-free step of a straight motion of the whole assembly (CCD over every pair the
//! motion can bring together) and the smallest distance.
//!
//! The pair set is the one `ipctk` builds (`NormalCollisions.build`): in 2D the collisions of
//! the IPC toolkit are its edge–vertex pairs, with a vertex–vertex collision weighted by the
//! number of edge–vertex pairs it stands for, so the potentials agree pair by pair
//! (`tests/barrier_ipctk.rs`). Unlike the toolkit's default, nodes and edges of the same particle
//! do not interact (a particle's own boundary never folds onto itself in a compaction).

use super::barrier::{barrier_term, point_edge_region, point_edge_sq_distance, point_edge_toi, point_wall_sq_distance, point_wall_toi, BarrierTerm, PointEdgeRegion, CCD_RESCALING};
use super::geometry::{unit, Wall};
use super::search::{for_each_swept_pair, ContactSearch};
use super::Segment;

/// A node closer than d̂ to an edge of another particle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeTerm {
    pub node: usize,
    pub segment: usize,
    /// Global dofs `[p, a, b]` of the node and the edge's two ends.
    pub dofs: [usize; 6],
    /// Where the closest point of the edge lies.
    pub region: PointEdgeRegion,
    /// Distance (mm).
    pub distance: f64,
    pub term: BarrierTerm<6>,
}

/// A node closer than d̂ to a wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallTerm {
    pub wall: usize,
    pub node: usize,
    /// Distance to the wall (mm).
    pub distance: f64,
    pub term: BarrierTerm<2>,
}

/// The barrier terms of one configuration.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BarrierEval {
    /// Σ κ b(d², d̂²) over the pairs (N per unit thickness).
    pub energy: f64,
    pub edges: Vec<EdgeTerm>,
    pub walls: Vec<WallTerm>,
    /// Smallest distance over the pairs within d̂ (mm; +∞ without any).
    pub min_distance: f64,
    /// Normal force of the particles on each wall (N/mm, compression positive).
    pub wall_force: Vec<f64>,
}

impl BarrierEval {
    /// The slope of the barrier energy along a change `du` of the global dofs: ∇E·du.
    pub fn slope(&self, du: &[f64]) -> f64 {
        let edges: f64 = self.edges.iter().map(|e| e.dofs.iter().zip(&e.term.grad).map(|(&d, g)| g * du[d]).sum::<f64>()).sum();
        let walls: f64 = self.walls.iter().map(|w| w.term.grad[0] * du[2 * w.node] + w.term.grad[1] * du[2 * w.node + 1]).sum();
        edges + walls
    }

    /// Add the barrier gradient (its contribution to the internal force, N/mm) to `f`
    /// (global dofs).
    pub fn add_gradient(&self, f: &mut [f64]) {
        for e in &self.edges {
            for (i, &d) in e.dofs.iter().enumerate() {
                f[d] += e.term.grad[i];
            }
        }
        for w in &self.walls {
            f[2 * w.node] += w.term.grad[0];
            f[2 * w.node + 1] += w.term.grad[1];
        }
    }
}

/// The lagged friction of one barrier pair (see [`super::barrier::friction_term`]): the
/// pair's dofs (6 for a node and an edge, the first 2 for a node and a wall), its tangent
/// weights, and μλ, all frozen at the lagged state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionPair {
    /// `Some(segment)` for a node–edge pair, `None` for a node–wall pair.
    pub segment: Option<usize>,
    pub node: usize,
    pub dofs: [usize; 6],
    pub w: [f64; 6],
    /// μ times the pair's normal force (N/mm).
    pub mu_lambda: f64,
}

impl FrictionPair {
    /// The friction term at displacements `u` (every dof) from `u0`, the start of the step.
    pub fn term(&self, u: &[f64], u0: &[f64], eps: f64) -> super::barrier::BarrierTerm<6> {
        let dx: [f64; 6] = std::array::from_fn(|i| if self.segment.is_some() || i < 2 { u[self.dofs[i]] - u0[self.dofs[i]] } else { 0.0 });
        super::barrier::friction_term(&self.w, &dx, self.mu_lambda, eps)
    }
}

/// A tie of cohering particles (`contact = "cohering"` with the barrier): a boundary node
/// held at a fixed offset from a point of an edge of another particle, the point at the
/// fraction ξ along the edge where the node was closest when the tie was made. The tie is a
/// bond, not a contact: the node and the particle it is tied to leave the barrier (and the
/// collision detection) for good, and the tie holds the offset in both directions, in
/// tension as in compression and against slip.
///
/// Its potential is an augmented Lagrangian on the gap vector g = x_p − (1 − ξ) x_a − ξ x_b − o
/// (o the offset when made): Π = ½ k |g|² + λ·g, with the multiplier λ updated to λ + k g
/// after each converged solve until |g| is below the tolerance (Uzawa). The offset is fixed in
/// the global frame: a tie is made within d̂ (a few thousandths of an element), so a rotation
/// θ of the pair moves its ends by at most d̂ θ against each other.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Tie {
    pub node: usize,
    pub segment: usize,
    /// Global dofs `[p, a, b]`.
    pub dofs: [usize; 6],
    pub xi: f64,
    /// The offset o of the node from the edge's point (mm).
    pub offset: [f64; 2],
    /// The multiplier λ (N/mm): the tie's force on the node is −(k g + λ).
    pub lambda: [f64; 2],
    /// λ at the last converged step (a step that fails starts again from it).
    pub lambda0: [f64; 2],
}

impl Tie {
    /// The weights of the gap vector on the node and the edge's ends.
    fn weights(&self) -> [f64; 3] {
        [1.0, -(1.0 - self.xi), -self.xi]
    }

    /// The gap vector g at coordinates `x` (mm).
    pub fn gap(&self, x: &[[f64; 2]], segments: &[Segment]) -> [f64; 2] {
        let [a, b] = segments[self.segment].nodes;
        let w = self.weights();
        std::array::from_fn(|c| w[0] * x[self.node][c] + w[1] * x[a][c] + w[2] * x[b][c] - self.offset[c])
    }

    /// The tie's potential term with stiffness `k` (N/mm) at coordinates `x`: its energy,
    /// gradient over `dofs` and (constant) Hessian k w wᵀ ⊗ I.
    pub fn term(&self, x: &[[f64; 2]], segments: &[Segment], k: f64) -> BarrierTerm<6> {
        let g = self.gap(x, segments);
        let w = self.weights();
        let f = [k * g[0] + self.lambda[0], k * g[1] + self.lambda[1]];
        let mut term = BarrierTerm::<6> { energy: 0.5 * k * (g[0] * g[0] + g[1] * g[1]) + self.lambda[0] * g[0] + self.lambda[1] * g[1], grad: [0.0; 6], hess: [[0.0; 6]; 6] };
        for i in 0..3 {
            for c in 0..2 {
                term.grad[2 * i + c] = w[i] * f[c];
                for j in 0..3 {
                    term.hess[2 * i + c][2 * j + c] = k * (w[i] * w[j]);
                }
            }
        }
        term
    }
}

impl BarrierEval {
    /// The lagged friction of every pair of this evaluation (at configuration `x`, with the
    /// walls `walls`) whose coefficient is positive: `mu` between particles, `mu_walls[w]`
    /// against wall w. The normal force λ of a pair is the size of the barrier force on its
    /// node; the tangent is the edge's direction (or, where the closest point is an end, the
    /// normal to the line from that end to the node) or the wall's.
    pub fn friction_pairs(&self, contact: &BarrierContact, x: &[[f64; 2]], walls: &[Wall], mu: f64, mu_walls: &[f64]) -> Vec<FrictionPair> {
        let mut out = Vec::new();
        if mu > 0.0 {
            for e in &self.edges {
                let lambda = e.term.grad[0].hypot(e.term.grad[1]);
                let [a, b] = contact.segments[e.segment].nodes;
                let (p, xa, xb) = (x[e.node], x[a], x[b]);
                let (t, wa, wb) = match e.region {
                    PointEdgeRegion::Interior => {
                        let ed = [xb[0] - xa[0], xb[1] - xa[1]];
                        let l2 = ed[0] * ed[0] + ed[1] * ed[1];
                        let s = ((p[0] - xa[0]) * ed[0] + (p[1] - xa[1]) * ed[1]) / l2;
                        let l = l2.sqrt();
                        ([ed[0] / l, ed[1] / l], -(1.0 - s), -s)
                    }
                    PointEdgeRegion::A | PointEdgeRegion::B => {
                        let q = if e.region == PointEdgeRegion::A { xa } else { xb };
                        let d = [p[0] - q[0], p[1] - q[1]];
                        let l = d[0].hypot(d[1]);
                        let t = [-d[1] / l, d[0] / l];
                        if e.region == PointEdgeRegion::A {
                            (t, -1.0, 0.0)
                        } else {
                            (t, 0.0, -1.0)
                        }
                    }
                };
                let w = [t[0], t[1], wa * t[0], wa * t[1], wb * t[0], wb * t[1]];
                out.push(FrictionPair { segment: Some(e.segment), node: e.node, dofs: e.dofs, w, mu_lambda: mu * lambda });
            }
        }
        for wt in &self.walls {
            let m = mu_walls.get(wt.wall).copied().unwrap_or(0.0);
            if !(m > 0.0) {
                continue;
            }
            let n = unit(walls[wt.wall].normal);
            let lambda = wt.term.grad[0].hypot(wt.term.grad[1]);
            let w = [-n[1], n[0], 0.0, 0.0, 0.0, 0.0];
            let dofs = [2 * wt.node, 2 * wt.node + 1, 2 * wt.node, 2 * wt.node + 1, 2 * wt.node, 2 * wt.node + 1];
            out.push(FrictionPair { segment: None, node: wt.node, dofs, w, mu_lambda: m * lambda });
        }
        out
    }
}

/// A configuration that the barrier cannot take: two boundaries touch or cross, or a node is
/// on or behind a wall.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum Intersection {
    #[error("node {node} touches edge {segment} (distance {distance:e} mm)")]
    Edge { node: usize, segment: usize, distance: f64 },
    #[error("node {node} is on or behind wall {wall} (signed distance {distance:e} mm)")]
    Wall { node: usize, wall: usize, distance: f64 },
}

/// The barrier contact of an assembly (see the module docs).
#[derive(Debug)]
pub struct BarrierContact {
    pub segments: Vec<Segment>,
    /// Boundary nodes `(node, body)`, sorted.
    pub nodes: Vec<(usize, usize)>,
    search: ContactSearch,
    /// Activation distance d̂ (mm).
    pub dhat: f64,
    /// Barrier stiffness κ (N/mm⁴).
    pub kappa: f64,
    /// How far behind a wall's plane the wall's barrier has its zero (mm): the distance of a
    /// node to a wall is measured from there, so that a particle that touches a wall at the
    /// start is inside the barrier, not on its singularity (see [`BarrierContact::of_bodies`]).
    pub wall_offset: f64,
    /// The ties of cohering particles, and every (node, body) a tie keeps out of the barrier,
    /// sorted.
    pub ties: Vec<Tie>,
    pub tied: Vec<(usize, usize)>,
}

/// The default activation distance d̂: 1/20 of the smallest element size `h_min` (mm) of the
/// particles' boundaries. Gaps stay well below d̂ at the pressures of a compaction (see
/// [`default_kappa`]), so they are a few thousandths of an element at most: far below what
/// the solid ratio or the contact patches resolve.
pub fn default_dhat(h_min: f64) -> f64 {
    h_min / 20.0
}

/// The barrier stiffness κ (N/mm⁴) for the softest Young's modulus `e_min` (MPa), the element
/// size `h` (mm, the tributary length of a boundary node) and d̂ (mm): κ = E h / (1000 d̂³).
///
/// Rationale: away from the clamp the barrier force of a pair at distance d is
/// f ≈ 2 κ d̂⁴ / d (the ln term is small beside the 1/d one), a pressure f / h. With this κ the
/// pressure is E/50 at d = d̂/10 — a strain of 2 %, the scale of the pressures of a compaction
/// — so the gaps of a loaded contact lie between d̂/100 (p = E/5) and d̂; the normal
/// stiffness there, 2 κ d̂⁴/d² = 0.2 E h/d̂ at d̂/10, is of the order of the default penalty of
/// the other methods (10 E/h with d̂ = h/20), so the tangent is no worse conditioned.
pub fn default_kappa(e_min: f64, h: f64, dhat: f64) -> f64 {
    e_min * h / (1000.0 * dhat * dhat * dhat)
}

impl BarrierContact {
    /// The barrier contact of the bodies of a model: every boundary segment and node (the
    /// boundary of [`super::boundary::Boundary`]), d̂ from `dhat` or [`default_dhat`], κ from
    /// [`default_kappa`] with the softest body and the finest boundary, and the walls' barriers
    /// d̂/2 behind their planes: a particle may touch a wall at the start (the die is often
    /// drawn round the packing), and a loaded node then rests within d̂/2 of the wall's plane
    /// (its gap to the barrier's zero lies between d̂/100 and d̂, [`default_kappa`]).
    pub fn of_bodies(bodies: &[super::ContactBody], x0: &[[f64; 2]], dhat: Option<f64>) -> Self {
        let b = super::boundary::Boundary::new(bodies, x0, false);
        let h_min = b.h_min();
        let e_min = b.body_e.iter().copied().fold(f64::INFINITY, f64::min);
        let dhat = dhat.unwrap_or_else(|| default_dhat(h_min));
        let mut c = Self::new(b.segments, b.slaves, dhat, default_kappa(e_min, h_min, dhat));
        c.wall_offset = 0.5 * dhat;
        c
    }

    pub fn new(segments: Vec<Segment>, nodes: Vec<(usize, usize)>, dhat: f64, kappa: f64) -> Self {
        let search = ContactSearch::new(segments.clone());
        Self { segments, nodes, search, dhat, kappa, wall_offset: 0.0, ties: Vec::new(), tied: Vec::new() }
    }

    /// The barrier terms at coordinates `x` (every node) with the walls `walls` where they are;
    /// with `project` the pair Hessians are projected onto the PSD matrices. An error when a
    /// node touches an edge of another particle or is on or behind a wall (the barrier is
    /// infinite there).
    pub fn evaluate(&mut self, x: &[[f64; 2]], walls: &[Wall], project: bool, out: &mut BarrierEval) -> Result<(), Intersection> {
        out.energy = 0.0;
        out.edges.clear();
        out.walls.clear();
        out.min_distance = f64::INFINITY;
        out.wall_force.clear();
        out.wall_force.resize(walls.len(), 0.0);
        self.search.update(x);
        for (node, s) in self.search.pairs(x, &self.nodes, self.dhat) {
            let seg = self.segments[s];
            if self.is_tied(node, seg.body) {
                continue;
            }
            let (p, a, b) = (x[node], x[seg.nodes[0]], x[seg.nodes[1]]);
            let d = point_edge_sq_distance(p, a, b);
            if !(d.d2 > 0.0) {
                return Err(Intersection::Edge { node, segment: s, distance: d.d2.max(0.0).sqrt() });
            }
            let Some(term) = barrier_term(&d, self.dhat, self.kappa, project) else { continue };
            let distance = d.d2.sqrt();
            out.min_distance = out.min_distance.min(distance);
            out.energy += term.energy;
            let [n1, n2] = seg.nodes;
            out.edges.push(EdgeTerm {
                node,
                segment: s,
                dofs: [2 * node, 2 * node + 1, 2 * n1, 2 * n1 + 1, 2 * n2, 2 * n2 + 1],
                region: point_edge_region(p, a, b),
                distance,
                term,
            });
        }
        for (w, wall) in walls.iter().enumerate() {
            let n = unit(wall.normal);
            let point = [wall.point[0] - self.wall_offset * n[0], wall.point[1] - self.wall_offset * n[1]];
            for &(node, _) in &self.nodes {
                let (d, sq) = point_wall_sq_distance(x[node], point, n);
                if d >= self.dhat {
                    continue;
                }
                if !(d > 0.0) {
                    return Err(Intersection::Wall { node, wall: w, distance: d });
                }
                let Some(term) = barrier_term(&sq, self.dhat, self.kappa, project) else { continue };
                out.min_distance = out.min_distance.min(d);
                out.energy += term.energy;
                // the force on the wall is the gradient's component against its normal
                out.wall_force[w] -= term.grad[0] * n[0] + term.grad[1] * n[1];
                out.walls.push(WallTerm { wall: w, node, distance: d, term });
            }
        }
        Ok(())
    }

    /// How many boundary nodes lie inside another particle (strictly, by the crossing number
    /// of a ray against that particle's boundary) or on or behind a wall's plane, at `x` with
    /// the walls `walls`: zero for every admissible configuration. An O(N·M) check with a box
    /// filter per particle, for tests and diagnostics.
    pub fn crossings(&self, x: &[[f64; 2]], walls: &[Wall]) -> usize {
        let n_bodies = self.segments.iter().map(|s| s.body + 1).max().unwrap_or(0);
        let mut boxes = vec![[f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY]; n_bodies];
        let mut by_body: Vec<Vec<[usize; 2]>> = vec![Vec::new(); n_bodies];
        for s in &self.segments {
            by_body[s.body].push(s.nodes);
            for &n in &s.nodes {
                let b = &mut boxes[s.body];
                b[0] = b[0].min(x[n][0]);
                b[1] = b[1].min(x[n][1]);
                b[2] = b[2].max(x[n][0]);
                b[3] = b[3].max(x[n][1]);
            }
        }
        let mut count = 0;
        for &(node, body) in &self.nodes {
            let p = x[node];
            let inside = (0..n_bodies).filter(|&b| b != body && !self.is_tied(node, b)).any(|b| {
                let bb = boxes[b];
                if p[0] <= bb[0] || p[0] >= bb[2] || p[1] <= bb[1] || p[1] >= bb[3] {
                    return false;
                }
                // a ray in +x: an odd number of crossed edges is inside
                let mut odd = false;
                for &[i, j] in &by_body[b] {
                    let (a, c) = (x[i], x[j]);
                    if (a[1] > p[1]) != (c[1] > p[1]) {
                        let xc = a[0] + (p[1] - a[1]) / (c[1] - a[1]) * (c[0] - a[0]);
                        if xc > p[0] {
                            odd = !odd;
                        }
                    }
                }
                odd
            });
            let behind = walls.iter().any(|w| {
                let n = unit(w.normal);
                (p[0] - w.point[0]) * n[0] + (p[1] - w.point[1]) * n[1] <= -self.wall_offset
            });
            if inside || behind {
                count += 1;
            }
        }
        count
    }

    /// Whether `node` is tied to particle `body` (and so out of its barrier).
    pub fn is_tied(&self, node: usize, body: usize) -> bool {
        !self.tied.is_empty() && self.tied.binary_search(&(node, body)).is_ok()
    }

    /// Tie every boundary node that is within d̂ of an edge of another particle it is not yet
    /// tied to (distance zero included: particles that touch at the start) to the closest such
    /// edge of that particle, at `x`. With `eval`, the evaluation of the barrier at `x`, a new
    /// tie takes over the barrier's force on its node as its multiplier, so that the state
    /// stays in balance. Returns how many ties were made.
    pub fn tie_close(&mut self, x: &[[f64; 2]], eval: Option<&BarrierEval>) -> usize {
        self.search.update(x);
        // the closest edge of every (node, other particle) within d̂
        let mut best: std::collections::BTreeMap<(usize, usize), (usize, f64)> = std::collections::BTreeMap::new();
        for (node, s) in self.search.pairs(x, &self.nodes, self.dhat) {
            let seg = self.segments[s];
            if self.is_tied(node, seg.body) {
                continue;
            }
            let d2 = point_edge_sq_distance(x[node], x[seg.nodes[0]], x[seg.nodes[1]]).d2;
            if d2 >= self.dhat * self.dhat {
                continue;
            }
            let e = best.entry((node, seg.body)).or_insert((s, d2));
            if d2 < e.1 {
                *e = (s, d2);
            }
        }
        for (&(node, body), &(s, _)) in &best {
            let [a, b] = self.segments[s].nodes;
            let (p, xa, xb) = (x[node], x[a], x[b]);
            let e = [xb[0] - xa[0], xb[1] - xa[1]];
            let l2 = e[0] * e[0] + e[1] * e[1];
            let xi = if l2 > 0.0 { (((p[0] - xa[0]) * e[0] + (p[1] - xa[1]) * e[1]) / l2).clamp(0.0, 1.0) } else { 0.0 };
            let offset = [p[0] - xa[0] - xi * e[0], p[1] - xa[1] - xi * e[1]];
            // the barrier's force on the node from that particle's edges
            let mut lambda = [0.0; 2];
            if let Some(ev) = eval {
                for t in ev.edges.iter().filter(|t| t.node == node && self.segments[t.segment].body == body) {
                    lambda[0] += t.term.grad[0];
                    lambda[1] += t.term.grad[1];
                }
            }
            self.ties.push(Tie { node, segment: s, dofs: [2 * node, 2 * node + 1, 2 * a, 2 * a + 1, 2 * b, 2 * b + 1], xi, offset, lambda, lambda0: lambda });
            self.tied.push((node, body));
        }
        self.tied.sort_unstable();
        best.len()
    }

    /// Every node–edge pair (of different particles) closer than `reach` at `x`, sorted.
    pub fn candidates(&mut self, x: &[[f64; 2]], reach: f64) -> Vec<(usize, usize)> {
        self.search.update(x);
        self.search.pairs(x, &self.nodes, reach)
    }

    /// The largest step η ∈ [0, 1] of the straight motion from `x0` to `x1` (every node; the
    /// walls from `walls0` to `walls1`, moving along their normals) that keeps every boundary
    /// node off every edge of another particle and in front of every wall, with IPC's
    /// conservative rescaling: [`CCD_RESCALING`] × the first time of impact, 1 when nothing
    /// meets. The broad phase is conservative: a node and an edge can meet only if the boxes
    /// they sweep overlap ([`for_each_swept_pair`]).
    pub fn collision_free_step(&self, x0: &[[f64; 2]], x1: &[[f64; 2]], walls0: &[Wall], walls1: &[Wall]) -> f64 {
        let moves = self.nodes.iter().any(|&(n, _)| x1[n] != x0[n]);
        let mut toi: f64 = f64::INFINITY;
        if moves {
            let segments = &self.segments;
            for_each_swept_pair(segments, x0, x1, &self.nodes, |node, s| {
                let seg = segments[s];
                if self.is_tied(node, seg.body) {
                    return;
                }
                let [a, b] = seg.nodes;
                if let Some(t) = point_edge_toi([x0[node], x0[a], x0[b]], [x1[node], x1[a], x1[b]]) {
                    toi = toi.min(t);
                }
            });
        }
        for (w0, w1) in walls0.iter().zip(walls1) {
            let n = unit(w0.normal);
            let shift = (w1.point[0] - w0.point[0]) * n[0] + (w1.point[1] - w0.point[1]) * n[1];
            let point = [w0.point[0] - self.wall_offset * n[0], w0.point[1] - self.wall_offset * n[1]];
            for &(node, _) in &self.nodes {
                let (d0, _) = point_wall_sq_distance(x0[node], point, n);
                if let Some(t) = point_wall_toi(d0, x0[node], x1[node], n, shift) {
                    toi = toi.min(t);
                }
            }
        }
        if toi.is_finite() {
            CCD_RESCALING * toi
        } else {
            1.0
        }
    }
}

impl BarrierEval {
    /// Whether the pairs of this evaluation hold each body in x and in y (a pair's normal holds
    /// both of its bodies in a direction where its component exceeds
    /// [`super::problem::SUPPORT_COSINE`]; a wall holds its node's body), `[body][direction]`.
    pub fn body_support(&self, contact: &BarrierContact, walls: &[Wall], n_bodies: usize) -> Vec<[bool; 2]> {
        let mut held = vec![[false; 2]; n_bodies];
        let body_of = |node: usize| contact.nodes.binary_search_by_key(&node, |&(n, _)| n).ok().map(|i| contact.nodes[i].1);
        let mut hold = |body: usize, n: [f64; 2]| {
            for c in 0..2 {
                if n[c].abs() > super::problem::SUPPORT_COSINE {
                    held[body][c] = true;
                }
            }
        };
        for e in &self.edges {
            // the normal: from the closest point to the node
            let g = [e.term.grad[0], e.term.grad[1]];
            let l = g[0].hypot(g[1]);
            if l > 0.0 {
                let n = [g[0] / l, g[1] / l];
                if let Some(b) = body_of(e.node) {
                    hold(b, n);
                }
                hold(contact.segments[e.segment].body, n);
            }
        }
        for w in &self.walls {
            if let Some(b) = body_of(w.node) {
                hold(b, unit(walls[w.wall].normal));
            }
        }
        held
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tie's gradient and Hessian against central differences of its energy and gradient
    /// (step 1e-6 mm; a quadratic potential, so the differences are exact up to round-off:
    /// tolerance 1e-6 relative), its Hessian symmetric, and a tie at its offset with λ = 0
    /// exerting no force.
    #[test]
    fn tie_term_is_the_derivative_of_its_potential() {
        let segments = vec![Segment { nodes: [1, 2], body: 1 }];
        let x0 = vec![[0.3, 0.05], [0.0, 0.0], [1.0, 0.1]];
        let mut c = BarrierContact::new(segments.clone(), vec![(0, 0), (1, 1), (2, 1)], 0.1, 1.0);
        assert_eq!(c.tie_close(&x0, None), 1, "the node within d̂ of the edge is tied");
        assert!(c.is_tied(0, 1) && !c.is_tied(0, 0));
        let mut tie = c.ties[0];
        let k = 7.0;
        let at_rest = tie.term(&x0, &segments, k);
        assert!(at_rest.grad.iter().all(|g| g.abs() < 1e-12), "a tie at its offset pulls: {:?}", at_rest.grad);
        // a moved configuration and a multiplier
        tie.lambda = [0.4, -1.3];
        let x = vec![[0.41, 0.02], [0.03, -0.01], [0.97, 0.16]];
        let t = tie.term(&x, &segments, k);
        let h = 1e-6;
        let shifted = |i: usize, s: f64| {
            let mut y = x.clone();
            y[[0, 1, 2][i / 2]][i % 2] += s;
            tie.term(&y, &segments, k)
        };
        let scale_g = t.grad.iter().fold(0.0f64, |m, g| m.max(g.abs()));
        let scale_h = t.hess.iter().flatten().fold(0.0f64, |m, g| m.max(g.abs()));
        for i in 0..6 {
            let (p, m) = (shifted(i, h), shifted(i, -h));
            let fd = (p.energy - m.energy) / (2.0 * h);
            assert!((fd - t.grad[i]).abs() <= 1e-6 * scale_g, "gradient {i}: {} against {fd}", t.grad[i]);
            for j in 0..6 {
                let fd = (p.grad[j] - m.grad[j]) / (2.0 * h);
                assert!((fd - t.hess[j][i]).abs() <= 1e-6 * scale_h, "Hessian ({j}, {i}): {} against {fd}", t.hess[j][i]);
                assert_eq!(t.hess[i][j], t.hess[j][i], "the Hessian is symmetric");
            }
        }
    }
}
