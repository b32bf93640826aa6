//! The barrier contact of an assembly (`[contact] method = "barrier"`): the sum of the barrier
//! kernels ([`super::barrier`]) over every boundary node and every boundary edge of another
//! particle closer than d̂, and over every boundary node and every wall closer than d̂ — no
//! master and slave, no active set, no frozen pairs: the pairs are found again at every
//! configuration (the search of [`super::search`] with the distance d̂). With it, the
//! collision-free step of a straight motion of the whole assembly (CCD over every pair the
//! motion can bring together) and the smallest distance.
//!
//! # A node facing a corner is counted once
//!
//! Summed over edges alone, a node whose closest point on another particle is a vertex V is
//! counted twice: once for each of the two edges that meet at V. On a flat side that makes a
//! node facing a vertex carry the barrier 2 b(d), and a node beside it b(d): the energy has a
//! ridge at every vertex, with a tangential curvature of −|b′|/d, as large as the normal
//! stiffness of the pair. Where the particles' meshes match (a regular grid of octagons whose
//! flat sides face node to node), every loaded node sits on such a ridge: every tangent is
//! indefinite, and once the symmetry breaks the nodes slide sideways with forces of the order
//! of their normal forces (the 1,024-octagon grid failed at solid ratio 0.863 that way,
//! docs/robustness.md). So, as the IPC toolkit's "improved max approximator" does (Li, Kaufman
//! and Jiang, "Convergent Incremental Potential Contact", 2023; `ipctk`'s
//! `CollisionSetType.IMPROVED_MAX_APPROX`), every node p and vertex V of another particle closer
//! than d̂ also contribute −(k − 1) b(|p − V|), k the number of boundary edges at V (2 on a
//! closed boundary): where both edges' closest point is V the two terms and the correction add
//! up to b(|p − V|) once, and a node sliding along a flat side sees b(d) throughout, with no
//! ridge. Each pair's term stays a barrier of its own: the correction goes to the edge at V
//! whose closest point to p is V (the first by index if both are; that pair's term then
//! cancels exactly and the pair is left out), and only where neither is (a vertex sharper than
//! a right angle) to the first edge at V, whose term b(d) − b(|p − V|) is then still positive
//! (d ≤ |p − V|).
//!
//! The pair set of the node terms is then the one `ipctk` builds (`NormalCollisions.build`
//! with the improved max approximator, without area weighting): its edge–vertex pairs, a
//! vertex–vertex collision weighted by the number of edge–vertex pairs it stands for, less one
//! for each end of the node–vertex pair whose vertex has two edges, so the potentials agree
//! (`tests/barrier_ipctk.rs`, with [`BarrierContact::new`], which makes the node terms alone).
//! Unlike the toolkit's default, nodes and edges of the same particle do not interact (a
//! particle's own boundary never folds onto itself in a compaction).
//!
//! # A uniform gap carries a uniform pressure
//!
//! Summed over nodes, the barrier cannot transmit a uniform pressure between two particles:
//! at a uniform gap every node carries the same force, so the end nodes of a contact, which
//! stand for half a tributary length, carry twice their share, and each side's nodes push on
//! the other side's edges as point loads that a non-matching mesh does not turn into its
//! consistent nodal forces. The contact patch test (two blocks meshed 7 and 5 across, 1 MPa)
//! then had stresses off by up to 31 % at its Gauss points, 19.8 % in element means.
//!
//! So this barrier ([`BarrierContact::of_bodies`]) integrates along the edges: every boundary
//! edge carries [`EDGE_POINTS`] Gauss–Legendre points x = (1 − ξ) x_c + ξ x_d, each a point of
//! the same kernel against every edge of another particle (with the same corner correction),
//! weighted by its quadrature weight times the edge's reference length over h (so that the
//! barrier per unit length is that of a node at spacing h, and κ keeps its meaning). At a
//! uniform gap the points' forces are a uniform traction, whose nodal forces on their own edge
//! are the consistent ones exactly, and on the other side those of the quadrature of its shape
//! functions. The nodes keep a term of their own, the same barrier with a reach of
//! [`NODE_REACH`] d̂: it holds the vertices the points cannot, a corner pressed into a flat
//! side and the ends of a contact, and adds little to a uniform traction. Each point's term
//! couples the four nodes of its edge and the other (8 dofs; the pattern key of an edge's
//! points is [`BarrierContact::edge_key`]). The walls keep the node terms at full reach, the
//! only terms a wall has. The collision detection is the nodes': two boundaries can first meet
//! only where a vertex meets an edge.
//!
//! The contact patch test passes to 0.48 % at every Gauss point (`tests/contact_friction.rs`;
//! 31 % with the node terms alone); docs/robustness.md, twentieth measurement, has the runs.

use super::barrier::{barrier_term, point_edge_region, point_edge_sq_distance, point_edge_toi, point_line, point_point, point_wall_sq_distance, point_wall_toi, projection_parameter, BarrierTerm, PointEdgeRegion, CCD_RESCALING};
use super::geometry::{unit, Wall};
use super::search::{for_each_swept_pair, ContactSearch, NearPairs};
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

/// A quadrature point of a boundary edge (of nodes c, d) closer than d̂ to an edge (a, b) of
/// another particle: the point x = (1 − ξ) x_c + ξ x_d, its term weighted by the quadrature
/// weight times the edge's reference length over h.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadTerm {
    pub edge: usize,
    pub segment: usize,
    /// Which of the edge's quadrature points (0 ‥ [`EDGE_POINTS`]).
    pub point: usize,
    /// Global dofs `[c, d, a, b]`.
    pub dofs: [usize; 8],
    pub xi: f64,
    /// Where the closest point of edge (a, b) lies.
    pub region: PointEdgeRegion,
    pub distance: f64,
    pub term: BarrierTerm<8>,
}

impl QuadTerm {
    /// The barrier force on the quadrature point (the gradient with respect to it).
    pub fn point_gradient(&self) -> [f64; 2] {
        [self.term.grad[0] + self.term.grad[2], self.term.grad[1] + self.term.grad[3]]
    }
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
    pub quads: Vec<QuadTerm>,
    pub walls: Vec<WallTerm>,
    /// Smallest distance over the pairs within d̂ (mm; +∞ without any).
    pub min_distance: f64,
    /// Normal force of the particles on each wall (N/mm, compression positive).
    pub wall_force: Vec<f64>,
    /// Node–edge pairs within d̂ whose term the corner correction cancels exactly (left out of
    /// `edges`), and the corner corrections made: Σ (k − 1) over the node–vertex pairs within
    /// d̂ whose vertex has k ≥ 2 edges (see the module docs).
    pub cancelled: usize,
    pub corners: usize,
}

impl BarrierEval {
    /// The slope of the barrier energy along a change `du` of the global dofs: ∇E·du.
    pub fn slope(&self, du: &[f64]) -> f64 {
        let edges: f64 = self.edges.iter().map(|e| e.dofs.iter().zip(&e.term.grad).map(|(&d, g)| g * du[d]).sum::<f64>()).sum();
        let walls: f64 = self.walls.iter().map(|w| w.term.grad[0] * du[2 * w.node] + w.term.grad[1] * du[2 * w.node + 1]).sum();
        let quads: f64 = self.quads.iter().map(|e| e.dofs.iter().zip(&e.term.grad).map(|(&d, g)| g * du[d]).sum::<f64>()).sum();
        edges + walls + quads
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
        for e in &self.quads {
            for (i, &d) in e.dofs.iter().enumerate() {
                f[d] += e.term.grad[i];
            }
        }
    }
}

/// The lagged friction of one barrier pair (see [`super::barrier::friction_term`]): the
/// pair's dofs (2 for a node and a wall, 6 for a node and an edge, 8 for a quadrature point of
/// an edge `[c, d]` and an edge), its tangent weights, and μλ, all frozen at the lagged state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionPair {
    /// The pattern pair that holds its Hessian (`(node or edge key, segment)`); `None` for a
    /// node–wall pair, whose block is the node's.
    pub block: Option<(usize, usize)>,
    /// Which pair it is, to follow it from one lagging to the next: (node, segment) for a
    /// node–edge pair, (edge key, segment · EDGE_POINTS + point) for a quadrature point's,
    /// (node, usize::MAX − wall) for a wall's.
    pub id: (usize, usize),
    /// The point it follows from one lagging to the next, whatever segment of the other body
    /// is nearest: (node, other body) for a node–edge pair, (edge key · EDGE_POINTS + point,
    /// other body) for a quadrature point's, its `id` for a wall's. A point sliding over a
    /// vertex moves its pair to the next segment; as the same point on the same body its
    /// friction changes little ([`friction_residual`]).
    pub follow: (usize, usize),
    /// The node whose status it sets (the point's nearer end for a quadrature point).
    pub node: usize,
    pub width: usize,
    pub dofs: [usize; 8],
    pub w: [f64; 8],
    /// μ times the pair's normal force (N/mm).
    pub mu_lambda: f64,
}

impl FrictionPair {
    /// The friction term at displacements `u` (every dof) from `u0`, the start of the step
    /// (entries beyond `width` zero).
    pub fn term(&self, u: &[f64], u0: &[f64], eps: f64) -> super::barrier::BarrierTerm<8> {
        let dx: [f64; 8] = std::array::from_fn(|i| if i < self.width { u[self.dofs[i]] - u0[self.dofs[i]] } else { 0.0 });
        super::barrier::friction_term(&self.w, &dx, self.mu_lambda, eps)
    }
}

/// The change of the lagged friction from `old` to `new` (the residual G(x) − x of its
/// fixed-point iteration): for every followed point ([`FrictionPair::follow`]) of either, the
/// sum of its pairs' μλ in `new` less that in `old`; sorted by the point.
pub fn friction_residual(old: &[FrictionPair], new: &[FrictionPair]) -> Vec<((usize, usize), f64)> {
    let mut all: Vec<((usize, usize), f64)> = new.iter().map(|f| (f.follow, f.mu_lambda)).chain(old.iter().map(|f| (f.follow, -f.mu_lambda))).collect();
    all.sort_by(|a, b| a.0.cmp(&b.0));
    let mut out: Vec<((usize, usize), f64)> = Vec::with_capacity(all.len());
    for (k, v) in all {
        match out.last_mut() {
            Some(last) if last.0 == k => last.1 += v,
            _ => out.push((k, v)),
        }
    }
    out
}

/// Where the lagging of the friction stands after a converged solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lagging {
    /// No point's μλ changed by more than the tolerance: the step is done.
    Converged,
    /// The lagging came back to the friction of two solves before: it alternates between two
    /// states, and more solves would not end it.
    Cycle,
    /// Solve again with the friction lagged at the last solution.
    Again,
}

/// The largest changes of the lagging after a solve, on this process's pairs: of the friction
/// lagged at its solution, `next`, from the one the solve used, `now`, and from the one the
/// solve before it used, `before` (infinite without), and the largest μλ of `now` and `next`
/// (N/mm): `[change, back, scale]`, for [`lagging`] once each is the largest over the processes.
pub fn lag_changes(before: Option<&[FrictionPair]>, now: &[FrictionPair], next: &[FrictionPair]) -> [f64; 3] {
    let largest = |r: Vec<((usize, usize), f64)>| r.iter().fold(0.0, |m: f64, e| m.max(e.1.abs()));
    let change = largest(friction_residual(now, next));
    let back = before.map_or(f64::INFINITY, |b| largest(friction_residual(b, next)));
    let scale = next.iter().chain(now).fold(0.0, |m: f64, f| m.max(f.mu_lambda));
    [change, back, scale]
}

/// The lagging's state from [`lag_changes`] and the tolerance `tol` relative to the largest
/// μλ: converged when the change is within it, a cycle when the way back to two solves before
/// is.
pub fn lagging([change, back, scale]: [f64; 3], tol: f64) -> Lagging {
    if change <= tol * scale {
        Lagging::Converged
    } else if back <= tol * scale {
        Lagging::Cycle
    } else {
        Lagging::Again
    }
}

/// The unit tangent of a barrier pair at point `p` and edge (xa, xb) with the closest point in
/// `region`, and the weights of the edge's ends in the relative slip.
fn pair_tangent(p: [f64; 2], xa: [f64; 2], xb: [f64; 2], region: PointEdgeRegion) -> ([f64; 2], f64, f64) {
    match region {
        PointEdgeRegion::Interior => {
            let ed = [xb[0] - xa[0], xb[1] - xa[1]];
            let l2 = ed[0] * ed[0] + ed[1] * ed[1];
            let s = ((p[0] - xa[0]) * ed[0] + (p[1] - xa[1]) * ed[1]) / l2;
            let l = l2.sqrt();
            ([ed[0] / l, ed[1] / l], -(1.0 - s), -s)
        }
        PointEdgeRegion::A | PointEdgeRegion::B => {
            let q = if region == PointEdgeRegion::A { xa } else { xb };
            let d = [p[0] - q[0], p[1] - q[1]];
            let l = d[0].hypot(d[1]);
            let t = [-d[1] / l, d[0] / l];
            if region == PointEdgeRegion::A {
                (t, -1.0, 0.0)
            } else {
                (t, 0.0, -1.0)
            }
        }
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
                let (t, wa, wb) = pair_tangent(x[e.node], x[a], x[b], e.region);
                let mut w = [0.0; 8];
                w[..6].copy_from_slice(&[t[0], t[1], wa * t[0], wa * t[1], wb * t[0], wb * t[1]]);
                let mut dofs = [0; 8];
                dofs[..6].copy_from_slice(&e.dofs);
                let follow = (e.node, contact.segments[e.segment].body);
                out.push(FrictionPair { block: Some((e.node, e.segment)), id: (e.node, e.segment), follow, node: e.node, width: 6, dofs, w, mu_lambda: mu * lambda });
            }
            for q in &self.quads {
                let g = q.point_gradient();
                let lambda = g[0].hypot(g[1]);
                let [c, d] = contact.segments[q.edge].nodes;
                let [a, b] = contact.segments[q.segment].nodes;
                let p = [(1.0 - q.xi) * x[c][0] + q.xi * x[d][0], (1.0 - q.xi) * x[c][1] + q.xi * x[d][1]];
                let (t, wa, wb) = pair_tangent(p, x[a], x[b], q.region);
                let (mc, md) = (1.0 - q.xi, q.xi);
                let w = [mc * t[0], mc * t[1], md * t[0], md * t[1], wa * t[0], wa * t[1], wb * t[0], wb * t[1]];
                let key = contact.edge_key(q.edge);
                let node = if q.xi < 0.5 { c } else { d };
                let follow = (key * EDGE_POINTS.max(1) + q.point, contact.segments[q.segment].body);
                out.push(FrictionPair { block: Some((key, q.segment)), id: (key, q.segment * EDGE_POINTS.max(1) + q.point), follow, node, width: 8, dofs: q.dofs, w, mu_lambda: mu * lambda });
            }
        }
        for wt in &self.walls {
            let m = mu_walls.get(wt.wall).copied().unwrap_or(0.0);
            if !(m > 0.0) {
                continue;
            }
            let n = unit(walls[wt.wall].normal);
            let lambda = wt.term.grad[0].hypot(wt.term.grad[1]);
            let w = [-n[1], n[0], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
            let dofs = [2 * wt.node, 2 * wt.node + 1, 0, 0, 0, 0, 0, 0];
            out.push(FrictionPair { block: None, id: (wt.node, usize::MAX - wt.wall), follow: (wt.node, usize::MAX - wt.wall), node: wt.node, width: 2, dofs, w, mu_lambda: m * lambda });
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
    /// The boundary segments at each node (by node number, sorted; empty off the boundary).
    vertex_segments: Vec<Vec<usize>>,
    /// The reach of the node terms as a fraction of d̂ ([`NODE_REACH`]), the quadrature points
    /// per edge (0: none) and each edge's reference length over h, the weight of its points'
    /// terms (see the module docs; `new` makes the toolkit's node terms alone, reach 1, and
    /// `of_bodies` the simulations' quadrature).
    pub node_reach: f64,
    pub quad_points: usize,
    pub quad_scale: Vec<f64>,
    /// Scratch of [`BarrierContact::evaluate`], kept so that its every call does not allocate:
    /// the nodes' coordinates followed by the edges' points, the points as search slaves, and
    /// each point's (edge, index, ξ, weight).
    quad_x: Vec<[f64; 2]>,
    quad_slaves: Vec<(usize, usize)>,
    quad_virt: Vec<(usize, usize, f64, f64)>,
    /// The bodies whose pairs this process evaluates ([`BarrierContact::evaluate_only`]): the
    /// pairs whose first side — a node, a point of an edge, a node facing a wall — is on one
    /// of them; empty: every body. And the boundary nodes of those bodies.
    first_sides: Vec<bool>,
    first_nodes: Vec<(usize, usize)>,
    /// The Verlet lists of [`BarrierContact::evaluate`]'s two searches, the nodes' and the
    /// edges' points' (see [`NearPairs`]).
    near_nodes: NearPairs,
    near_points: NearPairs,
}

/// Gauss–Legendre points on each boundary edge whose barrier terms carry the contact (see the
/// module docs, "A uniform gap carries a uniform pressure"). Four is the fewest with which the
/// contact patch test's stresses stay within 1 % of uniform at every Gauss point: 0.53 % with
/// four, 1.3 % with three, 2.7 % with two (non-matching 7 and 5 elements, 1 MPa; measured with
/// node terms of weight 0.01, before [`NODE_REACH`]; 0.48 % with four and the node terms now).
pub const EDGE_POINTS: usize = 4;

/// The reach of a node's own term beside its edges' points, as a fraction r of d̂: the node
/// term is the barrier with activation distance r d̂ and stiffness κ / r⁴, the same barrier as
/// the points' (κ d̂⁴ ln(d̂²/d²) to leading order) where a gap closes below r d̂, nothing beyond.
/// Where a vertex meets an edge (the ends of a contact, a corner of one particle pressed into
/// the flat side of another) no quadrature point of the vertex's own edges faces the other
/// side as closely as the vertex does, so it is the node term that holds it, and it must hold
/// it with the full barrier: a weak node term let such vertices reach gaps of 2e-4 d̂ under the
/// flat-punch forces at the ends of the contacts of an octagon grid, and Newton stalled there
/// (docs/robustness.md, nineteenth measurement). At a uniform gap, the loaded gaps of a
/// compaction lie about d̂/10 and below (see [`default_kappa`]), so the node terms still add
/// a little to the points' uniform traction: the patch test's stresses stay within 0.48 % of
/// uniform with r = 0.1 (0.53 % with node terms of weight 0.01 and full reach).
pub const NODE_REACH: f64 = 0.1;

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
    /// (its gap to the barrier's zero lies between d̂/100 and d̂, [`default_kappa`]). With
    /// `integration` [`super::BarrierIntegration::Edges`] the Gauss points of the edges carry
    /// the contact between particles (module docs), with `Nodes` the nodes alone, at full reach.
    ///
    /// `(h_min, e_min)` are the smallest contact length h and Young's modulus of every body of
    /// the model (those of `bodies` when they are the whole model; a process's part of a
    /// distributed model passes the whole model's, so that d̂ and κ are the same everywhere).
    pub fn of_bodies(bodies: &[super::ContactBody], x0: &[[f64; 2]], dhat: Option<f64>, integration: super::BarrierIntegration, (h_min, e_min): (f64, f64)) -> Self {
        let b = super::boundary::Boundary::new(bodies, x0, false);
        let dhat = dhat.unwrap_or_else(|| default_dhat(h_min));
        let mut c = Self::new(b.segments, b.slaves, dhat, default_kappa(e_min, h_min, dhat));
        c.wall_offset = 0.5 * dhat;
        if integration == super::BarrierIntegration::Nodes {
            return c;
        }
        c.node_reach = NODE_REACH;
        c.quad_points = EDGE_POINTS;
        c.quad_scale = c.segments.iter().map(|s| {
            let (a, b) = (x0[s.nodes[0]], x0[s.nodes[1]]);
            (b[0] - a[0]).hypot(b[1] - a[1]) / h_min
        }).collect();
        c
    }

    pub fn new(segments: Vec<Segment>, nodes: Vec<(usize, usize)>, dhat: f64, kappa: f64) -> Self {
        let search = ContactSearch::new(segments.clone());
        let n = segments.iter().flat_map(|s| s.nodes).max().map_or(0, |m| m + 1);
        let mut vertex_segments = vec![Vec::new(); n];
        for (i, s) in segments.iter().enumerate() {
            for &v in &s.nodes {
                vertex_segments[v].push(i);
            }
        }
        Self { segments, nodes, search, dhat, kappa, wall_offset: 0.0, ties: Vec::new(), tied: Vec::new(), vertex_segments, node_reach: 1.0, quad_points: 0, quad_scale: Vec::new(), quad_x: Vec::new(), quad_slaves: Vec::new(), quad_virt: Vec::new(), first_sides: Vec::new(), first_nodes: Vec::new(), near_nodes: NearPairs::default(), near_points: NearPairs::default() }
    }

    /// Evaluate (and check for collisions, [`BarrierContact::collision_free_step`]) only the
    /// pairs whose first side lies on a body `b` with `bodies[b]`: a process of a distributed
    /// run evaluates the pairs of its own particles, whose second sides may be on its ghosts;
    /// each pair is then evaluated by one process. An empty `bodies` evaluates every pair.
    pub fn evaluate_only(&mut self, bodies: Vec<bool>) {
        self.first_nodes = if bodies.is_empty() { Vec::new() } else { self.nodes.iter().copied().filter(|&(_, b)| bodies.get(b) == Some(&true)).collect() };
        self.first_sides = bodies;
    }

    /// The boundary nodes that are first sides of the pairs evaluated here.
    fn first_nodes(&self) -> &[(usize, usize)] {
        if self.first_sides.is_empty() {
            &self.nodes
        } else {
            &self.first_nodes
        }
    }

    /// Whether the pairs with a first side on `body` are evaluated here.
    fn first_side(&self, body: usize) -> bool {
        self.first_sides.is_empty() || self.first_sides.get(body) == Some(&true)
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
        out.cancelled = 0;
        out.corners = 0;
        out.quads.clear();
        // the node terms: reach r d̂ and stiffness κ / r⁴ (the same barrier near contact)
        let (dn, kn) = (self.dhat * self.node_reach, self.kappa / self.node_reach.powi(4));
        let first = if self.first_sides.is_empty() { &self.nodes } else { &self.first_nodes };
        for (node, s) in self.search.pairs_near(&mut self.near_nodes, x, first, self.dhat) {
            let seg = self.segments[s];
            if self.is_tied(node, seg.body) {
                continue;
            }
            let Some((region, distance, term)) = self.point_term(x[node], node, s, x, project, out, dn, kn)? else { continue };
            out.energy += term.energy;
            let [n1, n2] = seg.nodes;
            out.edges.push(EdgeTerm { node, segment: s, dofs: [2 * node, 2 * node + 1, 2 * n1, 2 * n1 + 1, 2 * n2, 2 * n2 + 1], region, distance, term });
        }
        if self.quad_points > 0 {
            let (xis, ws) = gauss_legendre(self.quad_points);
            let n = x.len();
            let (mut xe, mut slaves, mut virt) = (std::mem::take(&mut self.quad_x), std::mem::take(&mut self.quad_slaves), std::mem::take(&mut self.quad_virt));
            xe.clear();
            xe.extend_from_slice(x);
            slaves.clear();
            virt.clear();
            for (e, seg) in self.segments.iter().enumerate() {
                if !self.first_side(seg.body) {
                    continue;
                }
                let (c, d) = (x[seg.nodes[0]], x[seg.nodes[1]]);
                for (j, &xi) in xis.iter().enumerate() {
                    slaves.push((n + virt.len(), seg.body));
                    virt.push((e, j, xi, ws[j] * self.quad_scale[e]));
                    xe.push([(1.0 - xi) * c[0] + xi * d[0], (1.0 - xi) * c[1] + xi * d[1]]);
                }
            }
            for (vi, s) in self.search.pairs_near(&mut self.near_points, &xe, &slaves, self.dhat) {
                let (e, j, xi, w) = virt[vi - n];
                let [c, d] = self.segments[e].nodes;
                if self.is_tied(c, self.segments[s].body) || self.is_tied(d, self.segments[s].body) {
                    continue;
                }
                let Some((region, distance, t6)) = self.point_term(xe[vi], c, s, x, project, out, self.dhat, self.kappa)? else { continue };
                // x = (1 − ξ) x_c + ξ x_d: the point's gradient and Hessian go to c and d
                let m = [1.0 - xi, xi];
                let mut term = BarrierTerm::<8> { energy: w * t6.energy, grad: [0.0; 8], hess: [[0.0; 8]; 8] };
                // the 6-dof (p, a, b) layout's entries on the 8-dof (c, d, a, b) one
                let map = |i: usize| -> ([(usize, f64); 2], usize) {
                    if i < 2 {
                        ([(i, m[0]), (2 + i, m[1])], 2)
                    } else {
                        ([(i + 2, 1.0), (0, 0.0)], 1)
                    }
                };
                for i in 0..6 {
                    let (mi, ni) = map(i);
                    for &(ii, wi) in &mi[..ni] {
                        term.grad[ii] += w * wi * t6.grad[i];
                        for j in 0..6 {
                            let (mj, nj) = map(j);
                            for &(jj, wj) in &mj[..nj] {
                                term.hess[ii][jj] += w * wi * wj * t6.hess[i][j];
                            }
                        }
                    }
                }
                out.energy += term.energy;
                let [n1, n2] = self.segments[s].nodes;
                out.quads.push(QuadTerm { edge: e, segment: s, point: j, dofs: [2 * c, 2 * c + 1, 2 * d, 2 * d + 1, 2 * n1, 2 * n1 + 1, 2 * n2, 2 * n2 + 1], xi, region, distance, term });
            }
            (self.quad_x, self.quad_slaves, self.quad_virt) = (xe, slaves, virt);
        }
        for (w, wall) in walls.iter().enumerate() {
            let n = unit(wall.normal);
            let point = [wall.point[0] - self.wall_offset * n[0], wall.point[1] - self.wall_offset * n[1]];
            for &(node, _) in self.first_nodes() {
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

    /// The barrier term of a point `p` (node `node`, or a point of an edge at that node) and
    /// edge `s` with the corner correction (see the module docs): `None` beyond d̂ or where the
    /// correction cancels it.
    fn point_term(&self, p: [f64; 2], node: usize, s: usize, x: &[[f64; 2]], project: bool, out: &mut BarrierEval, dhat: f64, kappa: f64) -> Result<Option<(PointEdgeRegion, f64, BarrierTerm<6>)>, Intersection> {
        let xh = dhat * dhat;
        let seg = self.segments[s];
        let (a, b) = (x[seg.nodes[0]], x[seg.nodes[1]]);
        {
            // the region from the projection parameter once (as `point_edge_region` and
            // `point_edge_sq_distance` find it); p exactly on the normal line at an end (a
            // node facing a vertex of a flat side on a symmetric mesh) takes the interior's
            // form of the distance: its Hessian has no curvature along the edge, as on either
            // side of the line once the corner correction is made (the end's form would put
            // the ridge back into the tangent)
            let t = projection_parameter(p, a, b);
            let (region, d) = if t < 0.0 {
                (PointEdgeRegion::A, point_point(p, a, 1))
            } else if t > 1.0 {
                (PointEdgeRegion::B, point_point(p, b, 2))
            } else {
                let region = if t == 0.0 { PointEdgeRegion::A } else if t == 1.0 { PointEdgeRegion::B } else { PointEdgeRegion::Interior };
                (region, point_line(p, a, b))
            };
            if !(d.d2 > 0.0) {
                return Err(Intersection::Edge { node, segment: s, distance: d.d2.max(0.0).sqrt() });
            }
            if d.d2 >= xh {
                return Ok(None);
            }
            let distance = d.d2.sqrt();
            out.min_distance = out.min_distance.min(distance);
            // the corner corrections this pair takes: (slot of the vertex, k − 1)
            let mut corrections: [(usize, f64); 2] = [(0, 0.0); 2];
            let mut n_corr = 0;
            for (slot, v) in [(1, seg.nodes[0]), (2, seg.nodes[1])] {
                let q = x[v];
                let k = self.vertex_segments[v].len();
                if k < 2 || (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) >= xh {
                    continue;
                }
                if self.corner_owner(p, v, x) == s {
                    out.corners += k - 1;
                    corrections[n_corr] = (slot, (k - 1) as f64);
                    n_corr += 1;
                }
            }
            let at = match region {
                PointEdgeRegion::A => 1,
                PointEdgeRegion::B => 2,
                PointEdgeRegion::Interior => 0,
            };
            if n_corr == 1 && corrections[0] == (at, 1.0) {
                // the closest point is the vertex this pair corrects for: b − b = 0 exactly
                out.cancelled += 1;
                return Ok(None);
            }
            let Some(mut term) = barrier_term(&d, dhat, kappa, false) else { return Ok(None) };
            for &(slot, w) in &corrections[..n_corr] {
                let q = if slot == 1 { a } else { b };
                if let Some(c) = barrier_term(&point_point(p, q, slot), dhat, kappa, false) {
                    term.energy -= w * c.energy;
                    for i in 0..6 {
                        term.grad[i] -= w * c.grad[i];
                        for j in 0..6 {
                            term.hess[i][j] -= w * c.hess[i][j];
                        }
                    }
                }
            }
            if project {
                super::barrier::project_psd(&mut term.hess);
            }
            Ok(Some((region, distance, term)))
        }
    }

    /// The boundary nodes of particle `body` within `reach` of another particle or of a wall
    /// at `x` (the walls `walls`, their distance measured from the barrier's zero as in
    /// [`Self::evaluate`]): its nodes within `reach` of another particle's edges and the ends
    /// of its edges within `reach` of another particle's nodes, sorted. What a re-mesh keeps
    /// where it is ([`crate::remesh::remesh_particle_keeping`]), so that the new boundary does
    /// not move where the particle touches, or nearly touches, anything.
    pub fn near_nodes(&mut self, x: &[[f64; 2]], walls: &[Wall], body: usize, reach: f64) -> Vec<usize> {
        self.search.update(x);
        let (own, others): (Vec<(usize, usize)>, Vec<(usize, usize)>) = self.nodes.iter().partition(|&&(_, b)| b == body);
        let mut near: Vec<usize> = self.search.pairs(x, &own, reach).into_iter().map(|(n, _)| n).collect();
        for (_, s) in self.search.pairs(x, &others, reach) {
            if self.segments[s].body == body {
                near.extend(self.segments[s].nodes);
            }
        }
        for wall in walls {
            let n = unit(wall.normal);
            let point = [wall.point[0] - self.wall_offset * n[0], wall.point[1] - self.wall_offset * n[1]];
            near.extend(own.iter().filter(|&&(node, _)| point_wall_sq_distance(x[node], point, n).0 < reach).map(|&(node, _)| node));
        }
        near.sort_unstable();
        near.dedup();
        near
    }

    /// How many boundary nodes lie inside another particle (strictly, by the crossing number
    /// of a ray against that particle's boundary) or on or behind a wall's plane, at `x` with
    /// the walls `walls`: zero for every admissible configuration. An O(N·M) check with a box
    /// filter per particle, for tests and diagnostics.
    pub fn crossings(&self, x: &[[f64; 2]], walls: &[Wall]) -> usize {
        self.crossings_of(x, walls, None)
    }

    /// [`Self::crossings`] counting only what involves particle `body` when it is given: its
    /// nodes inside another particle or behind a wall, and the other particles' nodes inside
    /// it (a re-meshed particle's new boundary is checked so).
    pub fn crossings_of(&self, x: &[[f64; 2]], walls: &[Wall], body: Option<usize>) -> usize {
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
        let only = body;
        for &(node, body) in &self.nodes {
            // (with `only`: its nodes against everything, the others' against it alone)
            let mine = only.is_none_or(|o| o == body);
            let p = x[node];
            let inside = (0..n_bodies).filter(|&b| b != body && (mine || only == Some(b)) && !self.is_tied(node, b)).any(|b| {
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
            let behind = mine && walls.iter().any(|w| {
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

    /// The edge at vertex `v` that takes the corner correction of a node at `p` (see the
    /// module docs): the first of v's edges whose closest point to p is v, else the first.
    fn corner_owner(&self, p: [f64; 2], v: usize, x: &[[f64; 2]]) -> usize {
        let at_v = |s: usize| {
            let [a, b] = self.segments[s].nodes;
            match point_edge_region(p, x[a], x[b]) {
                PointEdgeRegion::A => a == v,
                PointEdgeRegion::B => b == v,
                PointEdgeRegion::Interior => false,
            }
        };
        let edges = &self.vertex_segments[v];
        edges.iter().copied().find(|&s| at_v(s)).unwrap_or(edges[0])
    }

    /// Tie every boundary node that is within d̂ of an edge of another particle it is not yet
    /// tied to (distance zero included: particles that touch at the start) to the closest such
    /// edge of that particle, at `x`. With `eval`, the evaluation of the barrier at `x`, a new
    /// tie takes over the barrier's force on its node as its multiplier, so that the state
    /// stays in balance. Returns how many ties were made.
    ///
    /// With [`BarrierContact::evaluate_only`] only the nodes of those bodies are tied: a
    /// process of a distributed run makes (and evaluates) the ties of its own particles'
    /// nodes, to edges of its own particles or of its ghosts.
    pub fn tie_close(&mut self, x: &[[f64; 2]], eval: Option<&BarrierEval>) -> usize {
        self.search.update(x);
        // the closest edge of every (node, other particle) within d̂
        let mut best: std::collections::BTreeMap<(usize, usize), (usize, f64)> = std::collections::BTreeMap::new();
        let nodes = if self.first_sides.is_empty() { &self.nodes } else { &self.first_nodes };
        for (node, s) in self.search.pairs(x, nodes, self.dhat) {
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
        let mut pairs = self.search.pairs(x, self.first_nodes(), reach);
        if self.quad_points > 0 {
            let edges: Vec<(usize, usize)> = pairs.iter().flat_map(|&(node, s)| self.vertex_segments[node].iter().map(move |&e| (e, s))).collect();
            pairs.extend(edges.into_iter().map(|(e, s)| (self.edge_key(e), s)));
            pairs.sort_unstable();
            pairs.dedup();
        }
        pairs
    }

    /// The pattern key of the quadrature points of edge `e` (the keys of nodes lie below).
    pub fn edge_key(&self, e: usize) -> usize {
        self.vertex_segments.len() + e
    }

    /// The dofs of a pattern pair (a node or an edge's points as [`Self::edge_key`], and an
    /// edge): `[p, a, b]` or `[c, d, a, b]`.
    pub fn pair_dofs(&self, (key, s): (usize, usize)) -> Vec<usize> {
        let [a, b] = self.segments[s].nodes;
        if key < self.vertex_segments.len() {
            vec![2 * key, 2 * key + 1, 2 * a, 2 * a + 1, 2 * b, 2 * b + 1]
        } else {
            let [c, d] = self.segments[key - self.vertex_segments.len()].nodes;
            vec![2 * c, 2 * c + 1, 2 * d, 2 * d + 1, 2 * a, 2 * a + 1, 2 * b, 2 * b + 1]
        }
    }

    /// The largest step η ∈ [0, 1] of the straight motion from `x0` to `x1` (every node; the
    /// walls from `walls0` to `walls1`, moving along their normals) that keeps every boundary
    /// node off every edge of another particle and in front of every wall, with IPC's
    /// conservative rescaling: [`CCD_RESCALING`] × the first time of impact, 1 when nothing
    /// meets. The broad phase is conservative: the barrier's Verlet list of its nodes where
    /// the motion is small enough for it to hold every pair that can meet
    /// ([`super::search::NearPairs::sweep_candidates`]: most updates near convergence), else
    /// the pairs whose swept boxes overlap ([`for_each_swept_pair`]). The first impact is the
    /// same either way; the list spares building the boxes' hierarchy for each update.
    pub fn collision_free_step(&self, x0: &[[f64; 2]], x1: &[[f64; 2]], walls0: &[Wall], walls1: &[Wall]) -> f64 {
        let moves = self.nodes.iter().any(|&(n, _)| x1[n] != x0[n]);
        let first = self.first_nodes();
        let mut toi: f64 = f64::INFINITY;
        if moves {
            let segments = &self.segments;
            let mut check = |node: usize, s: usize| {
                let seg = segments[s];
                if self.is_tied(node, seg.body) {
                    return;
                }
                let [a, b] = seg.nodes;
                if let Some(t) = point_edge_toi([x0[node], x0[a], x0[b]], [x1[node], x1[a], x1[b]]) {
                    toi = toi.min(t);
                }
            };
            // the barrier's Verlet list of its nodes where it holds every pair that can meet
            // (a small update), else the swept boxes: the same first impact either way
            match self.near_nodes.sweep_candidates(x0, x1, first) {
                Some(pairs) => pairs.iter().for_each(|&(node, s)| check(node, s)),
                None => for_each_swept_pair(segments, x0, x1, first, check),
            }
        }
        for (w0, w1) in walls0.iter().zip(walls1) {
            let n = unit(w0.normal);
            let shift = (w1.point[0] - w0.point[0]) * n[0] + (w1.point[1] - w0.point[1]) * n[1];
            let point = [w0.point[0] - self.wall_offset * n[0], w0.point[1] - self.wall_offset * n[1]];
            for &(node, _) in first {
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
        for q in &self.quads {
            let g = q.point_gradient();
            let l = g[0].hypot(g[1]);
            if l > 0.0 {
                let n = [g[0] / l, g[1] / l];
                hold(contact.segments[q.edge].body, n);
                hold(contact.segments[q.segment].body, n);
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

    /// The energy, gradient and (dense) Hessian of the barrier over every dof at `x`.
    fn totals(c: &mut BarrierContact, x: &[[f64; 2]]) -> (f64, Vec<f64>, Vec<Vec<f64>>, BarrierEval) {
        let mut eval = BarrierEval::default();
        c.evaluate(x, &[], false, &mut eval).expect("admissible");
        let n = 2 * x.len();
        let mut g = vec![0.0; n];
        eval.add_gradient(&mut g);
        let mut h = vec![vec![0.0; n]; n];
        for e in &eval.edges {
            for i in 0..6 {
                for j in 0..6 {
                    h[e.dofs[i]][e.dofs[j]] += e.term.hess[i][j];
                }
            }
        }
        for q in &eval.quads {
            for i in 0..8 {
                for j in 0..8 {
                    h[q.dofs[i]][q.dofs[j]] += q.term.hess[i][j];
                }
            }
        }
        (eval.energy, g, h, eval)
    }

    /// Assert that the barrier's gradient and Hessian at `x` match central differences of its
    /// energy and gradient (step 1e-7 mm) to 1e-6 of their largest entries; the evaluation at
    /// `x` for further checks.
    fn assert_central_differences(c: &mut BarrierContact, x: &[[f64; 2]], ci: usize) -> BarrierEval {
        let (_, g, h, eval) = totals(c, x);
        let step = 1e-7;
        let gs = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let hs = h.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..2 * x.len() {
            let mut shifted = |sgn: f64| {
                let mut y = x.to_vec();
                y[i / 2][i % 2] += sgn * step;
                totals(c, &y)
            };
            let (ep, gp, _, _) = shifted(1.0);
            let (em, gm, _, _) = shifted(-1.0);
            let fd = (ep - em) / (2.0 * step);
            assert!((fd - g[i]).abs() <= 1e-6 * gs, "config {ci}: gradient {i}: {} against {fd}", g[i]);
            for j in 0..2 * x.len() {
                let fd = (gp[j] - gm[j]) / (2.0 * step);
                assert!((fd - h[j][i]).abs() <= 1e-6 * hs, "config {ci}: Hessian ({j}, {i}): {} against {fd}", h[j][i]);
            }
        }
        eval
    }

    /// A node sliding along a flat side over one of its vertices: its barrier pair moves from
    /// one segment to the next, and its lagged friction follows it as one point. The
    /// friction's change between the two sides is the change of μλ (continuous: below 1e-6 of
    /// it for a slide of 2e-6 d̂), not the whole μλ once gone and once new, as comparing the
    /// pairs would have it; a node that leaves every barrier's reach changes by all of its μλ.
    #[test]
    fn lagged_friction_follows_a_point_over_a_vertex() {
        let dhat = 0.1;
        // body 1: a flat side of two segments meeting at node 2 = (0, 0); node 0 on body 0
        let segments = vec![Segment { nodes: [1, 2], body: 1 }, Segment { nodes: [2, 3], body: 1 }];
        let mut c = BarrierContact::new(segments, vec![(0, 0), (1, 1), (2, 1), (3, 1)], dhat, 1.0e3);
        let lagged = |c: &mut BarrierContact, p: [f64; 2]| {
            let x = vec![p, [-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]];
            let mut eval = BarrierEval::default();
            c.evaluate(&x, &[], true, &mut eval).expect("no contact");
            eval.friction_pairs(c, &x, &[], 0.3, &[])
        };
        let left = lagged(&mut c, [-1e-6 * dhat, 0.5 * dhat]);
        let right = lagged(&mut c, [1e-6 * dhat, 0.5 * dhat]);
        assert_eq!((left.len(), right.len()), (1, 1), "one pair a side: {left:?} {right:?}");
        assert_ne!(left[0].id, right[0].id, "the pair moved to the other segment");
        assert_eq!(left[0].follow, (0, 1));
        assert_eq!(left[0].follow, right[0].follow);
        let mu_lambda = left[0].mu_lambda;
        assert!(mu_lambda > 0.0);
        let r = friction_residual(&left, &right);
        assert_eq!(r.len(), 1);
        assert!(r[0].1.abs() <= 1e-6 * mu_lambda, "change {} of μλ {mu_lambda}", r[0].1);
        // beyond d̂: no pair, the point's friction all gone
        let gone = lagged(&mut c, [0.3, 2.0 * dhat]);
        assert!(gone.is_empty());
        let r = friction_residual(&left, &gone);
        assert_eq!(r, vec![((0, 1), -mu_lambda)]);
    }

    /// The lagging of a point whose friction alternates between two states (a, b, a: μλ 2 and
    /// 3 N/mm on two segments of one body) is a cycle at the third solve, and only there; one
    /// that contracts (2, 2.5, 2.75, … towards 3) is never one, and converged once a change is
    /// within the tolerance of the largest μλ (1e-4 · 3 N/mm: the k-th solve's change is 2⁻ᵏ,
    /// 4.9e-4 at the eleventh, 2.4e-4 at the twelfth).
    #[test]
    fn lagging_sees_a_cycle_and_a_contraction() {
        let pair = |segment: usize, mu_lambda: f64| FrictionPair { block: Some((0, segment)), id: (0, segment), follow: (0, 1), node: 0, width: 6, dofs: [0, 1, 2, 3, 4, 5, 0, 0], w: [1.0, 0.0, -0.5, 0.0, -0.5, 0.0, 0.0, 0.0], mu_lambda };
        let (a, b) = (vec![pair(0, 2.0)], vec![pair(1, 3.0)]);
        assert_eq!(lagging(lag_changes(None, &a, &b), 1e-4), Lagging::Again);
        assert_eq!(lagging(lag_changes(Some(&a), &b, &a), 1e-4), Lagging::Cycle);
        assert_eq!(lagging(lag_changes(Some(&b), &a, &a), 1e-4), Lagging::Converged);
        // a contraction: x ← (x + 3) / 2 from 2
        let mut states = vec![vec![pair(0, 2.0)]];
        let mut end = None;
        for k in 1..30 {
            let next = vec![pair(k % 2, 0.5 * (states[k - 1][0].mu_lambda + 3.0))];
            let state = lagging(lag_changes(if k >= 2 { Some(&states[k - 2]) } else { None }, &states[k - 1], &next), 1e-4);
            assert_ne!(state, Lagging::Cycle, "solve {k}");
            states.push(next);
            if state == Lagging::Converged {
                end = Some(k);
                break;
            }
        }
        assert_eq!(end, Some(12));
    }

    /// Gauss–Legendre with n points on [0, 1] integrates x^k exactly to 1 / (k + 1) up to
    /// k = 2n − 1 (to 1e-14, round-off), and the weights sum to 1.
    #[test]
    fn edge_quadrature_is_gauss_legendre() {
        for n in 1..=5 {
            let (x, w) = gauss_legendre(n);
            assert_eq!(x.len(), n);
            for k in 0..2 * n {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                assert!((q - 1.0 / (k as f64 + 1.0)).abs() < 1e-14, "{n} points, x^{k}: {q}");
            }
        }
    }

    /// Two blocks whose facing sides are split into 3 and 4 edges (non-matching), a gap of
    /// 0.07 d̂, 0.3 d̂ and 0.6 d̂ between them (the first inside the node terms' reach; not 0.06 d̂,
    /// which puts a node exactly at the reach, where the third derivative jumps), with
    /// the simulations' barrier (node terms of reach [`NODE_REACH`], [`EDGE_POINTS`] points an
    /// edge): the energy's gradient and Hessian against central differences (step 1e-7 mm) to
    /// 1e-6 relative.
    #[test]
    fn the_edge_quadrature_barrier_is_the_derivative_of_its_energy() {
        let dhat = 0.05;
        for (ci, g) in [0.07 * dhat, 0.3 * dhat, 0.6 * dhat].into_iter().enumerate() {
            // upper block (body 0): bottom side from x = 0 to 1 in 3 edges, y = g, closed by
            // a top at y = 1; lower block (body 1): top side in 4 edges at y = 0, shifted by
            // 0.1 to the right, closed by a bottom at y = −1
            let mut x: Vec<[f64; 2]> = (0..=3).map(|i| [i as f64 / 3.0, g]).collect();
            x.push([1.0, 1.0]);
            x.push([0.0, 1.0]);
            let lower0 = x.len();
            x.extend((0..=4).map(|i| [0.1 + i as f64 / 4.0, 0.0 - 0.002 * (i % 2) as f64]));
            x.push([1.1, -1.0]);
            x.push([0.1, -1.0]);
            let up = [0, 1, 2, 3, 4, 5];
            let lo: Vec<usize> = (0..7).map(|k| lower0 + k).collect();
            // counter-clockwise rings: upper 0 → 5 → 4 → 3 → 2 → 1 → 0 is clockwise, so go
            // 0 → 1 → 2 → 3 → 4 → 5 with the bottom first (outward normal down)
            let mut segments: Vec<Segment> = (0..6).map(|k| Segment { body: 0, nodes: [up[k], up[(k + 1) % 6]] }).collect();
            let ring = [lo[6], lo[5], lo[4], lo[3], lo[2], lo[1], lo[0]];
            segments.extend((0..7).map(|k| Segment { body: 1, nodes: [ring[k], ring[(k + 1) % 7]] }));
            let mut nodes: Vec<(usize, usize)> = up.iter().map(|&n| (n, 0)).collect();
            nodes.extend(lo.iter().map(|&n| (n, 1)));
            nodes.sort_unstable();
            let mut c = BarrierContact::new(segments.clone(), nodes, dhat, 1.0e4);
            c.node_reach = NODE_REACH;
            c.quad_points = EDGE_POINTS;
            c.quad_scale = segments.iter().map(|s| (x[s.nodes[1]][0] - x[s.nodes[0]][0]).hypot(x[s.nodes[1]][1] - x[s.nodes[0]][1]) / 0.25).collect();
            let eval = assert_central_differences(&mut c, &x, ci);
            assert!(eval.quads.len() >= 20, "config {ci}: {} quadrature pairs", eval.quads.len());
            assert!(ci > 0 || eval.edges.len() >= 3, "config {ci}: {} node pairs", eval.edges.len());
        }
    }

    /// A node sliding along a flat side made of collinear edges sees one barrier, κ b(d², d̂²),
    /// wherever it faces the side: facing a vertex (exactly, and 1e-3 d̂ to either side) as
    /// between them, with no tangential force and no negative tangential curvature (closed
    /// form; tolerance 1e-12 relative, round-off). Summed over the edges alone it would see
    /// 2 κ b at a vertex, a ridge with a curvature of −|∂E/∂d| / d along the side.
    #[test]
    fn a_node_sliding_along_a_flat_side_sees_one_barrier() {
        let (dhat, kappa, d) = (0.05, 3.0, 0.3 * 0.05);
        // the side: a closed rectangle of body 1 whose top is split into four edges of length
        // 1, the node (body 0) above it
        let mut x = vec![[0.0, 0.0]];
        let top: Vec<[f64; 2]> = (0..=4).map(|i| [i as f64, 0.0]).collect();
        x.extend(&top);
        x.push([4.0, -1.0]);
        x.push([0.0, -1.0]);
        // nodes 1..=5 the top (left to right), 6, 7 below; the rectangle counter-clockwise is
        // 7 → 6 → 5 → 4 → … → 1 → 7
        let ring = [7, 6, 5, 4, 3, 2, 1];
        let segments: Vec<Segment> = (0..ring.len()).map(|k| Segment { body: 1, nodes: [ring[k], ring[(k + 1) % ring.len()]] }).collect();
        let nodes = vec![(0, 0), (1, 1), (2, 1), (3, 1), (4, 1), (5, 1), (6, 1), (7, 1)];
        let mut c = BarrierContact::new(segments, nodes, dhat, kappa);
        let one = kappa * super::super::barrier::clamped_log(d * d, dhat * dhat)[0];
        for s in [1.5, 2.0 - 1e-3 * dhat, 2.0, 2.0 + 1e-3 * dhat, 2.0 + 0.5 * dhat, 2.5, 3.0] {
            x[0] = [s, d];
            let (energy, g, h, eval) = totals(&mut c, &x);
            assert!((energy - one).abs() <= 1e-12 * one, "at s = {s}: energy {energy} against one barrier {one}");
            assert!(g[0].abs() <= 1e-12 * g[1].abs(), "at s = {s}: a tangential force {} (normal {})", g[0], g[1]);
            assert!(h[0][0] >= -1e-12 * h[1][1], "at s = {s}: tangential curvature {} (normal {})", h[0][0], h[1][1]);
            let at_vertex = (s - s.round()).abs() < dhat;
            assert_eq!(eval.corners, usize::from(at_vertex), "at s = {s}: corner corrections");
        }
    }

    /// The barrier summed with its corner corrections is a potential with the gradient and
    /// Hessian it reports: central differences (step 1e-7 mm) of the energy and of the gradient
    /// against them, to 1e-6 relative, at nodes near the convex corners of an octagon (where
    /// one, both or neither of the corner's edges has its closest point at the vertex) and
    /// near a vertex of its flat side.
    #[test]
    fn the_corrected_barrier_is_the_derivative_of_its_energy() {
        let dhat = 0.05;
        let oct = crate::packing::regular_polygon([0.0, 0.0], 1.0, 8, std::f64::consts::PI / 8.0);
        // counter-clockwise from the flat right side's midpoint, made a vertex, to its corner
        // at 22.5° and on round
        let mut poly = vec![[oct[0][0], 0.0]];
        poly.extend(&oct);
        let v = oct[0];
        let n = poly.len();
        let mut configs = Vec::new();
        // around the corner: along the outward bisector and between the two edges' normals at
        // the vertex (both edges' closest point is the vertex), and beyond each normal (one
        // edge's is inside it)
        let ang = std::f64::consts::PI / 8.0;
        for (k, dir) in [ang, ang - 0.2, ang + 0.3, -0.1, ang + std::f64::consts::PI / 4.0 - 0.05].into_iter().enumerate() {
            let r = (0.2 + 0.15 * k as f64) * dhat;
            configs.push([v[0] + r * dir.cos(), v[1] + r * dir.sin()]);
        }
        // near the side's midpoint vertex, off its normal line
        configs.push([poly[0][0] + 0.4 * dhat, 0.3 * dhat]);
        configs.push([poly[0][0] + 0.25 * dhat, -0.6 * dhat]);
        for (ci, p) in configs.into_iter().enumerate() {
            let mut x = vec![p];
            x.extend(&poly);
            let segments: Vec<Segment> = (0..n).map(|k| Segment { body: 1, nodes: [1 + k, 1 + (k + 1) % n] }).collect();
            let mut nodes = vec![(0, 0)];
            nodes.extend((1..=n).map(|i| (i, 1)));
            let mut c = BarrierContact::new(segments, nodes, dhat, 1.0e4);
            let eval = assert_central_differences(&mut c, &x, ci);
            assert!(eval.corners >= 1, "config {ci}: the node should be within d̂ of a vertex");
        }
    }

}

/// Gauss–Legendre points on [0, 1] and weights (summing to 1).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (x, w): (&[f64], &[f64]) = match n {
        1 => (&[0.0], &[2.0]),
        2 => (&[-0.5773502691896257, 0.5773502691896257], &[1.0, 1.0]),
        3 => (&[-0.7745966692414834, 0.0, 0.7745966692414834], &[0.5555555555555556, 0.8888888888888888, 0.5555555555555556]),
        4 => (&[-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526], &[0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538]),
        _ => (&[-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640], &[0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665, 0.2369268850561891]),
    };
    (x.iter().map(|v| 0.5 * (v + 1.0)).collect(), w.iter().map(|v| 0.5 * v).collect())
}
