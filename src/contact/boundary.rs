//! The contact boundary of an assembly: every boundary segment (master side), every boundary
//! node (slave side) with its tributary length, the segments' neighbours (for the smoothed
//! master surface), and each body's contact length h and Young's modulus E (the default
//! penalty 10 E/h). Built once per set of meshes; everything the pair selection and the
//! kernels need to know about where a pair sits.

use super::enforce::{default_penalty, PenaltyParams};
use super::geometry::nts_project;
use super::search::boundary_of;
use super::smooth::{self, Master, NDOF};
use super::Segment;
use std::collections::HashMap;

/// What the contact needs of one body: its mesh and global node offset, its contact length h
/// ([`crate::model::Body::contact_h`], kept over re-meshes) and its Young's modulus (the
/// default penalty 10 E/h).
#[derive(Clone, Copy, Debug)]
pub struct ContactBody<'a> {
    pub mesh: &'a crate::mesh::Mesh,
    pub node_offset: usize,
    pub h: f64,
    pub e: f64,
}

/// The contact boundary (see the module docs).
#[derive(Clone, Debug)]
pub struct Boundary {
    pub segments: Vec<Segment>,
    /// Per segment: the boundary node before its first node and the one after its second node
    /// on the same body (the neighbours of the smoothed master surface), if any.
    pub neighbours: Vec<[Option<usize>; 2]>,
    /// Boundary nodes: (node, body), sorted by node.
    pub slaves: Vec<(usize, usize)>,
    /// Tributary (reference) boundary length of each slave node (mm).
    pub area: Vec<f64>,
    /// Contact length h and Young's modulus E of each body.
    pub body_h: Vec<f64>,
    pub body_e: Vec<f64>,
    /// Whether the master surfaces are smoothed (`[contact] normal = "smoothed"`).
    pub smoothed: bool,
}

impl Boundary {
    /// The boundary of `bodies` with reference coordinates `x0` (every node).
    pub fn new(bodies: &[ContactBody], x0: &[[f64; 2]], smoothed: bool) -> Self {
        let meshes: Vec<(&crate::mesh::Mesh, usize)> = bodies.iter().map(|b| (b.mesh, b.node_offset)).collect();
        let (segments, slaves) = boundary_of(&meshes);
        let mut len_at: HashMap<usize, f64> = HashMap::new();
        for s in &segments {
            let (a, b) = (x0[s.nodes[0]], x0[s.nodes[1]]);
            let l = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            for n in s.nodes {
                *len_at.entry(n).or_insert(0.0) += 0.5 * l;
            }
        }
        let area = slaves.iter().map(|(n, _)| len_at.get(n).copied().unwrap_or(0.0)).collect();
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
        Self { segments, neighbours, slaves, area, body_h: bodies.iter().map(|b| b.h).collect(), body_e: bodies.iter().map(|b| b.e).collect(), smoothed }
    }

    /// Smallest contact length h over the bodies (mm).
    pub fn h_min(&self) -> f64 {
        self.body_h.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Dofs of a pair: 6 with straight segments, [`NDOF`] with the smoothed surface.
    pub fn pair_width(&self) -> usize {
        if self.smoothed {
            NDOF
        } else {
            6
        }
    }

    /// The smoothed master surface of segment `seg` at configuration `x`.
    pub fn master(&self, seg: usize, x: &[[f64; 2]]) -> Master {
        let s = self.segments[seg];
        let [prev, next] = self.neighbours[seg];
        Master { x1: x[s.nodes[0]], x2: x[s.nodes[1]], prev: prev.map(|n| x[n]), next: next.map(|n| x[n]) }
    }

    /// The nodes of a pair of slave `node` and segment `seg` in the kernels' order: `[s, 1, 2]`,
    /// or `[s, 1, 2, 0, 3]` with the smoothed surface, where an absent neighbour takes the
    /// segment's own end node (its entries are zero). Unused entries are the slave node.
    pub fn pair_nodes(&self, node: usize, seg: usize) -> [usize; 5] {
        let s = self.segments[seg];
        if !self.smoothed {
            return [node, s.nodes[0], s.nodes[1], node, node];
        }
        let [prev, next] = self.neighbours[seg];
        [node, s.nodes[0], s.nodes[1], prev.unwrap_or(s.nodes[0]), next.unwrap_or(s.nodes[1])]
    }

    /// Global dofs of a pair (the first [`Boundary::pair_width`] are used).
    pub fn pair_dofs(&self, node: usize, seg: usize) -> [usize; NDOF] {
        let nodes = self.pair_nodes(node, seg);
        let mut d = [0; NDOF];
        for (i, &n) in nodes.iter().enumerate() {
            d[2 * i] = 2 * n;
            d[2 * i + 1] = 2 * n + 1;
        }
        d
    }

    /// Projection parameter ξ of the point `p` on segment `seg` (straight or smoothed; the
    /// straight projection, extrapolated beyond the ends, where the smoothed one has none).
    pub fn xi_at(&self, p: [f64; 2], seg: usize, x: &[[f64; 2]]) -> f64 {
        let s = self.segments[seg];
        let straight = || nts_project(p, x[s.nodes[0]], x[s.nodes[1]]).xi;
        if self.smoothed {
            smooth::smooth_project(p, &self.master(seg, x)).map_or_else(straight, |g| g.xi)
        } else {
            straight()
        }
    }

    /// The point of segment `seg` at parameter ξ on configuration `x` (on the smoothed surface
    /// when smoothed, else on the chord).
    pub fn point_at(&self, seg: usize, xi: f64, x: &[[f64; 2]]) -> [f64; 2] {
        let s = self.segments[seg];
        let (a, b) = (x[s.nodes[0]], x[s.nodes[1]]);
        let chord = [(1.0 - xi) * a[0] + xi * b[0], (1.0 - xi) * a[1] + xi * b[1]];
        if self.smoothed {
            smooth::smooth_point(&self.master(seg, x), xi).unwrap_or(chord)
        } else {
            chord
        }
    }

    /// The penalties of a pair between bodies `b1` and `b2` (`None`: a wall): the case's
    /// `penalty`, or 10 E/h of the softer, finer of the two.
    pub fn penalty(&self, penalty: Option<f64>, b1: usize, b2: Option<usize>) -> PenaltyParams {
        match penalty {
            Some(e) => PenaltyParams { eps_n: e, eps_t: e },
            None => {
                let (e, h) = match b2 {
                    Some(b2) => (self.body_e[b1].min(self.body_e[b2]), self.body_h[b1].min(self.body_h[b2])),
                    None => (self.body_e[b1], self.body_h[b1]),
                };
                default_penalty(e, h)
            }
        }
    }
}
