//! Contact search (broad phase): candidate node-to-segment pairs between different bodies.
//!
//! # Contract
//!
//! [`ContactSearch::pairs`] follows the broad-phase contract of rapier/parry: **false negatives
//! never, false positives allowed, within the stated distance**. For a search distance `d`
//! (mm) it returns every pair `(slave node, segment index)` such that the node and the segment
//! belong to different bodies and the Euclidean distance from the node to the (straight)
//! segment is `<= d`; it may also return pairs that are slightly farther apart. The extra pairs
//! are bounded: each candidate from the hierarchy is filtered by its exact point-to-segment
//! distance against `d + pad`, with a round-off pad of `1e-12 × (1 + |x|∞ + d + drift)` mm
//! (`x` the node, `drift` below), so an extra pair is farther than `d` by at most that pad
//! (far less than any segment length). [`brute_force_pairs`] is the exact O(N·M) reference with
//! the same contract and no false positives; the broad phase returns a superset of it that
//! differs only by pairs within the pad. The narrow phase (the contact kernels) computes the
//! exact gap of each pair.
//!
//! All pair lists are sorted by `(node, segment)` with no duplicates.
//!
//! # Method
//!
//! The segments' axis-aligned bounding boxes are the leaves of a bounding-volume hierarchy
//! ([`parry2d_f64::partitioning::Bvh`], binned SAH build). A slave node is queried with the box
//! `[x − r, x + r]` of half-width `r = d + drift + pad`; testing a point box inflated by `d`
//! against the tight segment boxes is the same as testing the point against the segment boxes
//! inflated by `d` (Minkowski sum), so one hierarchy serves every search distance. Every
//! segment point within `d` of the node lies in both boxes, so nothing is missed; the hits are
//! then filtered by their exact distance (O(1) each).
//!
//! [`ContactSearch::update`] refits the hierarchy to new coordinates (O(M)); when the boundary
//! has moved by more than the mean segment length since the last full build, it rebuilds it
//! instead (O(M log M)), so the tree stays tight while the topology changes. Boxes are never
//! stale: [`ContactSearch::pairs`] measures how far the segment end nodes have moved since the
//! last `update` (max-norm, O(M)) and inflates the query by that drift, so it stays conservative
//! even if the caller forgot to call `update` after moving the nodes (the queries are only
//! slower then: the exact filter keeps the result as tight). If `update` was never called, `pairs` builds a temporary hierarchy.
//!
//! # Cost
//!
//! With N slave nodes, M segments and K returned pairs: `update` O(M) (refit) or O(M log M)
//! (rebuild); `pairs` O(M) for the drift check plus about O(N log M + K) for the queries, plus
//! O(K log K) for sorting; memory O(M). [`brute_force_pairs`] is O(N·M).
//!
//! # Units
//!
//! Coordinates and distances in mm (any consistent length unit works: nothing is scaled except
//! the relative round-off pad). Coordinates must be finite; NaN coordinates give unspecified
//! (but non-panicking) results.
//!
//! The code is sequential: parallelism, if any, is the caller's business.

use super::Segment;
use crate::mesh::Mesh;
use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::Vector;
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};

/// Relative round-off pad of the query boxes (see the module docs).
const ROUND_OFF: f64 = 1e-12;

/// Candidate node-to-segment pairs between different bodies (broad phase over a BVH of segment
/// bounding boxes). See the module documentation for the contract.
pub struct ContactSearch {
    segments: Vec<Segment>,
    /// Hierarchy over the tight segment boxes at `box_coords`; `None` before the first update.
    bvh: Option<Bvh>,
    workspace: BvhWorkspace,
    /// End-node coordinates of every segment at the last `update` (the boxes in the tree).
    box_coords: Vec<[[f64; 2]; 2]>,
    /// End-node coordinates of every segment at the last full build.
    build_coords: Vec<[[f64; 2]; 2]>,
}

impl std::fmt::Debug for ContactSearch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ContactSearch")
            .field("segments", &self.segments.len())
            .field("built", &self.bvh.is_some())
            .finish()
    }
}

fn to_vec(p: [f64; 2]) -> Vector {
    Vector::new(p[0], p[1])
}

fn ends(coords: &[[f64; 2]], s: &Segment) -> [[f64; 2]; 2] {
    [coords[s.nodes[0]], coords[s.nodes[1]]]
}

/// Tight axis-aligned box of a segment (exact: min/max of the end coordinates).
fn segment_aabb(e: &[[f64; 2]; 2]) -> Aabb {
    let [a, b] = e;
    Aabb::new(
        Vector::new(a[0].min(b[0]), a[1].min(b[1])),
        Vector::new(a[0].max(b[0]), a[1].max(b[1])),
    )
}

fn build(ends: &[[[f64; 2]; 2]]) -> Bvh {
    Bvh::from_iter(
        BvhBuildStrategy::Binned,
        ends.iter().enumerate().map(|(i, e)| (i, segment_aabb(e))),
    )
}

/// Max-norm displacement of the segment end nodes between `old` and `coords`.
fn drift(segments: &[Segment], old: &[[[f64; 2]; 2]], coords: &[[f64; 2]]) -> f64 {
    let mut d: f64 = 0.0;
    for (s, o) in segments.iter().zip(old) {
        let n = ends(coords, s);
        for k in 0..2 {
            for c in 0..2 {
                d = d.max((n[k][c] - o[k][c]).abs());
            }
        }
    }
    d
}

impl ContactSearch {
    /// A search over the given boundary segments (global node numbering). Call
    /// [`update`](Self::update) with the nodal coordinates before querying (otherwise each
    /// query builds a temporary hierarchy).
    pub fn new(segments: Vec<Segment>) -> Self {
        ContactSearch {
            segments,
            bvh: None,
            workspace: BvhWorkspace::default(),
            box_coords: Vec::new(),
            build_coords: Vec::new(),
        }
    }

    /// The segments, in the order their indices refer to.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Rebuild or refit the hierarchy for the current nodal coordinates `coords[node] = [x, y]`
    /// (mm). Refits in O(M) when the boundary moved by less than the mean segment length since
    /// the last full build, rebuilds in O(M log M) otherwise.
    ///
    /// # Panics
    /// If a segment refers to a node outside `coords`.
    pub fn update(&mut self, coords: &[[f64; 2]]) {
        let new_ends: Vec<[[f64; 2]; 2]> = self.segments.iter().map(|s| ends(coords, s)).collect();
        let rebuild = match &self.bvh {
            None => true,
            Some(_) => {
                let mean_len = if new_ends.is_empty() {
                    0.0
                } else {
                    new_ends
                        .iter()
                        .map(|e| (e[1][0] - e[0][0]).hypot(e[1][1] - e[0][1]))
                        .sum::<f64>()
                        / new_ends.len() as f64
                };
                let moved = drift(&self.segments, &self.build_coords, coords);
                moved.is_nan() || moved > mean_len
            }
        };
        if rebuild {
            self.bvh = Some(build(&new_ends));
            self.build_coords = new_ends.clone();
        } else if let Some(bvh) = self.bvh.as_mut() {
            for (i, e) in new_ends.iter().enumerate() {
                let _ = bvh.insert_or_update_partially(segment_aabb(e), i as u32, 0.0);
            }
            bvh.refit(&mut self.workspace);
        }
        self.box_coords = new_ends;
    }

    /// Every pair `(slave node, segment index)` with `body(node) != segment.body` and
    /// `distance(node, segment) <= distance` (mm), for the coordinates `coords`; never misses
    /// such a pair, may return farther ones (see the module docs for the bound). Sorted by
    /// `(node, segment)`, no duplicates. `slave_nodes` lists `(node, body)`.
    ///
    /// `coords` should be the coordinates of the last [`update`](Self::update); if they are
    /// not, the result is still conservative and as tight (the queries are inflated by the
    /// drift of the segment nodes, the exact filter uses `coords`), just slower. A negative or
    /// NaN `distance` gives no pairs.
    ///
    /// # Panics
    /// If a node index is outside `coords`.
    pub fn pairs(
        &self,
        coords: &[[f64; 2]],
        slave_nodes: &[(usize, usize)],
        distance: f64,
    ) -> Vec<(usize, usize)> {
        if distance.is_nan() || distance < 0.0 || self.segments.is_empty() || slave_nodes.is_empty()
        {
            return Vec::new();
        }
        let temp;
        let (bvh, drift) = match &self.bvh {
            Some(b) => (b, drift(&self.segments, &self.box_coords, coords)),
            None => {
                let e: Vec<[[f64; 2]; 2]> = self.segments.iter().map(|s| ends(coords, s)).collect();
                temp = build(&e);
                (&temp, 0.0)
            }
        };
        let reach = distance + drift;
        let mut out = Vec::new();
        for &(node, body) in slave_nodes {
            let p = coords[node];
            let pad = ROUND_OFF * (1.0 + p[0].abs().max(p[1].abs()) + reach);
            let r = reach + pad;
            let q = Aabb::new(to_vec([p[0] - r, p[1] - r]), to_vec([p[0] + r, p[1] + r]));
            for leaf in bvh.intersect_aabb(&q) {
                let s = leaf as usize;
                let seg = &self.segments[s];
                // Cheap exact filter on the current coordinates (removes the box corners).
                if seg.body != body
                    && point_segment_distance(p, coords[seg.nodes[0]], coords[seg.nodes[1]])
                        <= distance + pad
                {
                    out.push((node, s));
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// [`ContactSearch::pairs`] after [`ContactSearch::update`] at `coords`, the same pairs in
    /// the same order, answered from the Verlet list `near` while it holds (see [`NearPairs`])
    /// and made again (with an update of the hierarchy) when it does not. The margin is the
    /// larger of `distance` and a quarter of the mean segment length.
    pub fn pairs_near(&mut self, near: &mut NearPairs, coords: &[[f64; 2]], slave_nodes: &[(usize, usize)], distance: f64) -> Vec<(usize, usize)> {
        if distance.is_nan() || distance < 0.0 || self.segments.is_empty() || slave_nodes.is_empty() {
            return Vec::new();
        }
        if !near.holds(coords, slave_nodes, distance) {
            self.update(coords);
            let mean_len = self.box_coords.iter().map(|e| (e[1][0] - e[0][0]).hypot(e[1][1] - e[0][1])).sum::<f64>() / self.box_coords.len() as f64;
            let margin = distance.max(0.25 * mean_len);
            near.candidates = self.pairs(coords, slave_nodes, distance + margin);
            near.distance = distance;
            near.margin = margin;
            near.slaves.clear();
            near.slaves.extend_from_slice(slave_nodes);
            near.coords.clear();
            near.coords.extend_from_slice(coords);
            near.builds += 1;
        }
        near.queries += 1;
        // the exact filter of `pairs` with the hierarchy's boxes at `coords` (no drift)
        near.candidates
            .iter()
            .copied()
            .filter(|&(node, s)| {
                let p = coords[node];
                let pad = ROUND_OFF * (1.0 + p[0].abs().max(p[1].abs()) + distance);
                let seg = &self.segments[s];
                point_segment_distance(p, coords[seg.nodes[0]], coords[seg.nodes[1]]) <= distance + pad
            })
            .collect()
    }
}

/// A Verlet list over a [`ContactSearch`] ([`ContactSearch::pairs_near`]): the candidate pairs
/// within `distance + margin` of the coordinates it was made at, which hold every pair within
/// `distance` for as long as no point has moved by more than half the margin since (a
/// point–segment distance changes by at most the point's displacement plus the largest of
/// its segment ends'). A Newton iteration's line search and the iterations after it mostly
/// move the boundary by much less than that, and a query then filters the list by the exact
/// distance instead of searching the hierarchy for every slave again.
#[derive(Debug, Default, Clone)]
pub struct NearPairs {
    distance: f64,
    margin: f64,
    slaves: Vec<(usize, usize)>,
    coords: Vec<[f64; 2]>,
    candidates: Vec<(usize, usize)>,
    /// How many times the list was made, and how many queries it answered (statistics).
    pub builds: usize,
    pub queries: usize,
}

impl NearPairs {
    /// Whether the list still holds every pair within `distance` of `coords` for these slaves.
    fn holds(&self, coords: &[[f64; 2]], slave_nodes: &[(usize, usize)], distance: f64) -> bool {
        if self.builds == 0 || distance != self.distance || coords.len() != self.coords.len() || slave_nodes != self.slaves.as_slice() {
            return false;
        }
        let mut moved2: f64 = 0.0;
        for (p, q) in coords.iter().zip(&self.coords) {
            let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
            moved2 = moved2.max(dx * dx + dy * dy);
        }
        // (twice the largest motion within 0.9 of the margin: the rest is far above the
        // round-off pad of the exact filter)
        let reach = 0.45 * self.margin;
        moved2 <= reach * reach
    }

    /// The candidates of a straight motion of every point from `x0` to `x1` for these slaves,
    /// when the list holds them all: every node and segment that meet on the way are in it
    /// while no point's two positions are farther than 0.45 of `distance + margin` from where
    /// the list was made (a pair that meets at some time was then at most twice that apart,
    /// each point on its way being no farther from there than the farther of its two
    /// positions). `None` otherwise (a search of the swept boxes is needed).
    pub fn sweep_candidates(&self, x0: &[[f64; 2]], x1: &[[f64; 2]], slave_nodes: &[(usize, usize)]) -> Option<&[(usize, usize)]> {
        if self.builds == 0 || x0.len() != self.coords.len() || x1.len() != self.coords.len() || slave_nodes != self.slaves.as_slice() {
            return None;
        }
        let reach = 0.45 * (self.distance + self.margin);
        let r2 = reach * reach;
        let far = |x: &[[f64; 2]]| x.iter().zip(&self.coords).any(|(p, q)| (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) > r2);
        if far(x0) || far(x1) {
            return None;
        }
        Some(&self.candidates)
    }
}

/// The pad of a swept box, relative to its largest coordinate: far above the round-off of the
/// coordinates and of the time-of-impact test's slack on the edge parameter (1e-12 of the
/// edge), far below any distance the contact resolves.
const SWEPT_PAD: f64 = 1e-9;

/// The box of the points `p`, padded by [`SWEPT_PAD`] of their largest coordinate.
fn swept_box(p: &[[f64; 2]]) -> Aabb {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut size: f64 = 1.0;
    for q in p {
        for c in 0..2 {
            lo[c] = lo[c].min(q[c]);
            hi[c] = hi[c].max(q[c]);
            size = size.max(q[c].abs());
        }
    }
    let pad = SWEPT_PAD * size;
    Aabb::new(to_vec([lo[0] - pad, lo[1] - pad]), to_vec([hi[0] + pad, hi[1] + pad]))
}

/// Every pair `(slave node, segment index)` of different bodies whose boxes swept by a
/// straight motion from `x0` to `x1` overlap, each once, handed to `f`: the broad phase of the
/// continuous collision detection. A node and a segment that meet at some time of the motion
/// are among them: the node is then in its box (the box of its two positions) and the
/// segment's point in the hull of its ends, so in its box (the box of its ends' four
/// positions). The boxes are padded by 1e-9 of their coordinates (round-off).
///
/// Unlike a search within the largest motion of any node, the work and memory follow what
/// each node and segment sweeps: one particle sent far by a soft mode does not make every
/// pair of the assembly a candidate (which held 15 GB in a 1,024-particle run).
///
/// Cost: a hierarchy of the M swept boxes (O(M log M)), then N queries (about O(N log M + K)
/// for K pairs); no list of pairs is made.
pub fn for_each_swept_pair(segments: &[Segment], x0: &[[f64; 2]], x1: &[[f64; 2]], slave_nodes: &[(usize, usize)], mut f: impl FnMut(usize, usize)) {
    if segments.is_empty() || slave_nodes.is_empty() {
        return;
    }
    let bvh = Bvh::from_iter(
        BvhBuildStrategy::Binned,
        segments.iter().enumerate().map(|(i, s)| {
            let [a, b] = s.nodes;
            (i, swept_box(&[x0[a], x0[b], x1[a], x1[b]]))
        }),
    );
    for &(node, body) in slave_nodes {
        let q = swept_box(&[x0[node], x1[node]]);
        for leaf in bvh.intersect_aabb(&q) {
            let s = leaf as usize;
            if segments[s].body != body {
                f(node, s);
            }
        }
    }
}

/// Exact O(N·M) reference: every `(slave node, segment index)` with `body(node) !=
/// segment.body` and `point_segment_distance <= distance` (mm), sorted, no duplicates.
pub fn brute_force_pairs(
    coords: &[[f64; 2]],
    segments: &[Segment],
    slave_nodes: &[(usize, usize)],
    distance: f64,
) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for &(node, body) in slave_nodes {
        let p = coords[node];
        for (s, seg) in segments.iter().enumerate() {
            if seg.body != body
                && point_segment_distance(p, coords[seg.nodes[0]], coords[seg.nodes[1]]) <= distance
            {
                out.push((node, s));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Euclidean distance from point `p` to the closed segment `a b` (mm). A degenerate segment
/// (`a == b`) is treated as the point `a`.
pub fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (px, py) = (p[0] - a[0], p[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        ((px * dx + py * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    if t == 0.0 {
        px.hypot(py)
    } else if t == 1.0 {
        (p[0] - b[0]).hypot(p[1] - b[1])
    } else {
        (px - t * dx).hypot(py - t * dy)
    }
}

/// All boundary segments and boundary `(node, body)` pairs of a list of meshes laid out in one
/// global numbering: mesh `k` is body `k`, and its local node `n` is global node
/// `offset_k + n`. Segments keep the meshes' orientation (body on the left) and come mesh by
/// mesh in boundary order; the node list is sorted by node index with no duplicates.
pub fn boundary_of(meshes: &[(&Mesh, usize)]) -> (Vec<Segment>, Vec<(usize, usize)>) {
    let mut segments = Vec::new();
    let mut nodes = Vec::new();
    for (body, (mesh, offset)) in meshes.iter().enumerate() {
        for e in &mesh.boundary {
            segments.push(Segment {
                body,
                nodes: [e[0] + offset, e[1] + offset],
            });
            nodes.push((e[0] + offset, body));
            nodes.push((e[1] + offset, body));
        }
    }
    nodes.sort_unstable();
    nodes.dedup();
    (segments, nodes)
}
