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
use super::geometry::Wall;
use super::search::ContactSearch;
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
}

impl BarrierContact {
    pub fn new(segments: Vec<Segment>, nodes: Vec<(usize, usize)>, dhat: f64, kappa: f64) -> Self {
        let search = ContactSearch::new(segments.clone());
        Self { segments, nodes, search, dhat, kappa }
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
            for &(node, _) in &self.nodes {
                let (d, sq) = point_wall_sq_distance(x[node], wall.point, n);
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

    /// The largest step η ∈ [0, 1] of the straight motion from `x0` to `x1` (every node; the
    /// walls from `walls0` to `walls1`, moving along their normals) that keeps every boundary
    /// node off every edge of another particle and in front of every wall, with IPC's
    /// conservative rescaling: [`CCD_RESCALING`] × the first time of impact, 1 when nothing
    /// meets. The broad phase is conservative: a node and an edge can meet only if their
    /// distance at `x0` is at most twice the largest motion of a boundary node.
    pub fn collision_free_step(&mut self, x0: &[[f64; 2]], x1: &[[f64; 2]], walls0: &[Wall], walls1: &[Wall]) -> f64 {
        let mut reach: f64 = 0.0;
        for &(n, _) in &self.nodes {
            reach = reach.max((x1[n][0] - x0[n][0]).hypot(x1[n][1] - x0[n][1]));
        }
        let mut toi: f64 = f64::INFINITY;
        if reach > 0.0 {
            self.search.update(x0);
            for (node, s) in self.search.pairs(x0, &self.nodes, 2.0 * reach * (1.0 + 1e-9)) {
                let seg = self.segments[s];
                let [a, b] = seg.nodes;
                if let Some(t) = point_edge_toi([x0[node], x0[a], x0[b]], [x1[node], x1[a], x1[b]]) {
                    toi = toi.min(t);
                }
            }
        }
        for (w0, w1) in walls0.iter().zip(walls1) {
            let n = unit(w0.normal);
            let shift = (w1.point[0] - w0.point[0]) * n[0] + (w1.point[1] - w0.point[1]) * n[1];
            for &(node, _) in &self.nodes {
                let (d0, _) = point_wall_sq_distance(x0[node], w0.point, n);
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

fn unit(v: [f64; 2]) -> [f64; 2] {
    let l = v[0].hypot(v[1]);
    [v[0] / l, v[1] / l]
}
