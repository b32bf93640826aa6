//! Graph partitioning and fill-reducing orderings for mpfem.
//!
//! A partitioner is a plain function, [`Partitioner`]: it takes a [`Graph`] (CSR adjacency in
//! the METIS layout: `xadj`, `adjncy`, vertex weights `vwgt`) and a number of parts, and returns
//! the part index (`0..nparts`) of every vertex. Two are offered:
//!
//! - [`metis_kway`] (and [`try_metis_kway`], which returns errors instead of falling back):
//!   METIS 5 multilevel k-way, minimal edge cut with the vertex weights balanced to METIS's 3 %
//!   tolerance, contiguous parts on connected graphs. METIS is built from the C sources bundled
//!   with the `metis-sys` crate (a C compiler is all it needs).
//! - [`greedy_bfs`], the dependency-light serial stand-in: parts are grown one after the other
//!   by breadth-first search from a pseudo-peripheral seed until each holds its share of the
//!   total vertex weight. It is simple and deterministic, gives perfectly balanced parts for
//!   unit weights on connected graphs, and reasonable (not minimal) edge cuts on mesh-like
//!   graphs.
//!
//! Quality measures: [`edge_cut`] (number of edges between different parts) and [`imbalance`]
//! (heaviest part weight over the average part weight; 1.0 is perfect balance).
//!
//! The particle graph of a multi-particle model (vertex weight = element count, edges = contacts
//! or proximity of bounding boxes) is built from plain data by [`particle_graph`].
//!
//! Orderings: [`metis_nd`] is METIS's nested-dissection fill-reducing ordering of a graph;
//! [`graph_of_pattern`] turns a sparse matrix pattern into the graph it needs.

mod metis_wrap;
mod particles;

pub use crate::metis_wrap::{
    graph_of_pattern, is_connected, metis_kway, metis_nd, try_metis_kway, validate, PartitionError,
};
pub use crate::particles::{particle_graph, Adjacency, Particle};

use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

/// A graph partitioner: `(graph, nparts) -> part of each vertex`, every entry in `0..nparts`.
pub type Partitioner = fn(&Graph, usize) -> Vec<usize>;

/// Undirected graph in compressed sparse row form (METIS layout).
///
/// The neighbours of vertex `v` are `adjncy[xadj[v]..xadj[v + 1]]`; every edge is stored in
/// both directions, there are no self loops and no repeated neighbours. `vwgt[v]` is the
/// weight of vertex `v` (e.g. the work of an element).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Graph {
    pub xadj: Vec<usize>,
    pub adjncy: Vec<usize>,
    pub vwgt: Vec<u64>,
}

impl Graph {
    /// Builds a graph with `n` unit-weight vertices from an undirected edge list.
    ///
    /// Edges may be given in either direction and repeated; self loops are dropped.
    ///
    /// # Panics
    /// If an edge refers to a vertex `>= n`.
    pub fn from_edges(n: usize, edges: &[(usize, usize)]) -> Graph {
        Self::from_edges_weighted(vec![1; n], edges)
    }

    /// Builds a graph with the given vertex weights (`vwgt.len()` vertices) from an undirected
    /// edge list (see [`Graph::from_edges`]).
    ///
    /// # Panics
    /// If an edge refers to a vertex `>= vwgt.len()`.
    pub fn from_edges_weighted(vwgt: Vec<u64>, edges: &[(usize, usize)]) -> Graph {
        let n = vwgt.len();
        let mut lists: Vec<Vec<usize>> = vec![Vec::new(); n];
        for &(a, b) in edges {
            assert!(
                a < n && b < n,
                "edge ({a}, {b}) refers to a vertex outside 0..{n}"
            );
            if a != b {
                lists[a].push(b);
                lists[b].push(a);
            }
        }
        let mut xadj = Vec::with_capacity(n + 1);
        let mut adjncy = Vec::new();
        xadj.push(0);
        for mut l in lists {
            l.sort_unstable();
            l.dedup();
            adjncy.extend_from_slice(&l);
            xadj.push(adjncy.len());
        }
        Graph { xadj, adjncy, vwgt }
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.vwgt.len()
    }

    /// Number of (undirected) edges.
    pub fn n_edges(&self) -> usize {
        self.adjncy.len() / 2
    }

    /// Neighbours of vertex `v`.
    pub fn neighbors(&self, v: usize) -> &[usize] {
        &self.adjncy[self.xadj[v]..self.xadj[v + 1]]
    }

    /// Sum of all vertex weights.
    pub fn total_weight(&self) -> u64 {
        self.vwgt.iter().sum()
    }
}

/// Breadth-first search from `seed` restricted to vertices with `free[v]`; returns the last
/// vertex reached (one of the farthest).
fn farthest_free(graph: &Graph, free: &[bool], seed: usize) -> usize {
    let mut seen = vec![false; graph.n_vertices()];
    let mut queue = VecDeque::from([seed]);
    seen[seed] = true;
    let mut last = seed;
    while let Some(v) = queue.pop_front() {
        last = v;
        for &w in graph.neighbors(v) {
            if free[w] && !seen[w] {
                seen[w] = true;
                queue.push_back(w);
            }
        }
    }
    last
}

/// A pseudo-peripheral vertex of the free subgraph component containing `start` (two sweeps
/// of "go to the farthest vertex").
fn pseudo_peripheral(graph: &Graph, free: &[bool], start: usize) -> usize {
    let a = farthest_free(graph, free, start);
    farthest_free(graph, free, a)
}

/// Serial stand-in partitioner: grows parts `0, 1, …` one after the other by breadth-first
/// search, each until it holds its share of the remaining vertex weight (remaining weight /
/// remaining parts); the last part takes everything left.
///
/// Each part starts from a pseudo-peripheral vertex of the not-yet-assigned subgraph (found by
/// two farthest-vertex sweeps started next to the parts already grown). The search frontier is
/// ordered by gain — edges into the growing part minus edges to unassigned vertices — with ties
/// taken first-come first-served, i.e. breadth-first (greedy graph growing). This keeps parts
/// compact: on grid graphs it finds straight cuts. If a part's search runs out of reachable
/// vertices (disconnected remainder) it continues from a new seed.
/// A vertex is added while that brings the part weight closer to its target, so with unit
/// weights on a connected graph every part has `floor(n/nparts)` or `ceil(n/nparts)` vertices.
///
/// # Panics
/// If `nparts == 0`.
pub fn greedy_bfs(graph: &Graph, nparts: usize) -> Vec<usize> {
    assert!(nparts >= 1, "greedy_bfs: nparts must be at least 1");
    let n = graph.n_vertices();
    let mut part = vec![usize::MAX; n];
    if nparts == 1 || n == 0 {
        return vec![0; n];
    }
    let mut free = vec![true; n];
    let mut n_free = n;
    let mut remaining: u64 = graph.total_weight();
    for p in 0..nparts - 1 {
        if n_free == 0 {
            break;
        }
        let target = remaining as f64 / (nparts - p) as f64;
        let mut weight: u64 = 0;
        // Start next to the previous parts if possible, else anywhere.
        let start = (0..n)
            .filter(|&v| free[v])
            .max_by_key(|&v| {
                let assigned = graph.neighbors(v).iter().filter(|&&w| !free[w]).count();
                (assigned, std::cmp::Reverse(v))
            })
            .expect("a free vertex exists");
        let seed = pseudo_peripheral(graph, &free, start);
        // Frontier ordered by gain (edges into the part minus edges to free vertices, i.e. the
        // cut reduction of adding the vertex), ties first-come first-served (breadth-first).
        let mut heap: BinaryHeap<(i64, Reverse<u64>, usize)> = BinaryHeap::new();
        let mut gain: Vec<i64> = vec![i64::MIN; n];
        let mut order: u64 = 0;
        gain[seed] = 0;
        heap.push((0, Reverse(order), seed));
        loop {
            let v = match heap.pop() {
                Some((g, _, v)) => {
                    if !free[v] || g != gain[v] {
                        continue; // stale entry
                    }
                    v
                }
                None => match (0..n).find(|&v| free[v]) {
                    // Disconnected remainder: continue from any free vertex.
                    Some(s) => s,
                    None => break,
                },
            };
            let w = graph.vwgt[v];
            let after = (weight + w) as f64;
            if weight > 0 && (after - target).abs() > (weight as f64 - target).abs() {
                break;
            }
            part[v] = p;
            free[v] = false;
            n_free -= 1;
            weight += w;
            if weight as f64 >= target || n_free == 0 {
                break;
            }
            for &u in graph.neighbors(v) {
                if free[u] {
                    let g = graph
                        .neighbors(u)
                        .iter()
                        .map(|&x| {
                            if part[x] == p {
                                1
                            } else if free[x] {
                                -1
                            } else {
                                0
                            }
                        })
                        .sum::<i64>();
                    gain[u] = g;
                    order += 1;
                    heap.push((g, Reverse(order), u));
                }
            }
        }
        remaining -= weight;
    }
    for v in 0..n {
        if free[v] {
            part[v] = nparts - 1;
        }
    }
    part
}

/// Number of edges whose end vertices lie in different parts.
///
/// # Panics
/// If `parts.len()` differs from the number of vertices.
pub fn edge_cut(graph: &Graph, parts: &[usize]) -> usize {
    assert_eq!(parts.len(), graph.n_vertices(), "one part index per vertex");
    let mut cut = 0;
    for v in 0..graph.n_vertices() {
        for &w in graph.neighbors(v) {
            if v < w && parts[v] != parts[w] {
                cut += 1;
            }
        }
    }
    cut
}

/// Load imbalance: heaviest part weight divided by the average part weight
/// (`total weight / nparts`). 1.0 is perfect balance; an empty or weightless graph gives 1.0.
///
/// # Panics
/// If `parts.len()` differs from the number of vertices, or a part index is `>= nparts`.
pub fn imbalance(graph: &Graph, parts: &[usize], nparts: usize) -> f64 {
    assert_eq!(parts.len(), graph.n_vertices(), "one part index per vertex");
    assert!(nparts >= 1, "nparts must be at least 1");
    let mut w = vec![0u64; nparts];
    for (v, &p) in parts.iter().enumerate() {
        assert!(p < nparts, "vertex {v} has part {p} >= nparts = {nparts}");
        w[p] += graph.vwgt[v];
    }
    let total: u64 = w.iter().sum();
    if total == 0 {
        return 1.0;
    }
    let max = *w.iter().max().expect("nparts >= 1") as f64;
    max / (total as f64 / nparts as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(n: usize) -> Graph {
        let edges: Vec<(usize, usize)> = (0..n - 1).map(|i| (i, i + 1)).collect();
        Graph::from_edges(n, &edges)
    }

    /// `nx × ny` grid graph (4-neighbour), vertex `i + nx*j`.
    fn grid(nx: usize, ny: usize) -> Graph {
        let mut edges = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let v = i + nx * j;
                if i + 1 < nx {
                    edges.push((v, v + 1));
                }
                if j + 1 < ny {
                    edges.push((v, v + nx));
                }
            }
        }
        Graph::from_edges(nx * ny, &edges)
    }

    fn check_valid(g: &Graph, parts: &[usize], nparts: usize) {
        assert_eq!(parts.len(), g.n_vertices());
        assert!(parts.iter().all(|&p| p < nparts), "every vertex assigned");
    }

    #[test]
    fn csr_from_edges_is_symmetric_and_deduplicated() {
        let g = Graph::from_edges(4, &[(0, 1), (1, 0), (1, 2), (2, 2), (3, 2)]);
        assert_eq!(g.xadj, vec![0, 1, 3, 5, 6]);
        assert_eq!(g.adjncy, vec![1, 0, 2, 1, 3, 2]);
        assert_eq!(g.n_edges(), 3);
        assert_eq!(g.total_weight(), 4);
    }

    #[test]
    fn one_part_is_trivial() {
        let g = grid(7, 5);
        let parts = greedy_bfs(&g, 1);
        assert_eq!(parts, vec![0; 35]);
        assert_eq!(edge_cut(&g, &parts), 0);
        assert_eq!(imbalance(&g, &parts, 1), 1.0);
    }

    #[test]
    fn path_graph_splits_into_contiguous_pieces() {
        // A path split into k contiguous pieces has the optimal cut k - 1; with 100 unit-weight
        // vertices the pieces are exactly 100/k, so imbalance is exactly 1.
        let g = path(100);
        for nparts in [2, 4] {
            let parts = greedy_bfs(&g, nparts);
            check_valid(&g, &parts, nparts);
            assert_eq!(edge_cut(&g, &parts), nparts - 1, "nparts = {nparts}");
            assert_eq!(imbalance(&g, &parts, nparts), 1.0);
        }
    }

    #[test]
    fn grid_graph_two_and_four_parts() {
        // 16 × 16 grid: the optimal bisection cut is 16 (a straight line), the optimal 4-way cut
        // is 32 (quadrants). Plain BFS layers from a corner are anti-diagonals with about twice
        // the cut of a straight line; the gain ordering does better, and we require
        // cut <= 1.5 × optimal. Unit weights on a connected graph give parts of exactly
        // n/nparts vertices (256 divisible by 2 and 4): imbalance <= 1.1 is a loose check that
        // leaves room for a stand-in that trades balance for cut, as METIS does (its default
        // tolerance is 1.03 per constraint).
        let g = grid(16, 16);
        for (nparts, optimal) in [(2usize, 16usize), (4, 32)] {
            let parts = greedy_bfs(&g, nparts);
            check_valid(&g, &parts, nparts);
            let cut = edge_cut(&g, &parts);
            let imb = imbalance(&g, &parts, nparts);
            assert!(cut >= optimal, "cut {cut} below the optimum {optimal}?");
            assert!(
                2 * cut <= 3 * optimal,
                "nparts {nparts}: cut {cut} > 1.5 × {optimal}"
            );
            assert!(imb <= 1.1, "nparts {nparts}: imbalance {imb}");
        }
    }

    #[test]
    fn rectangular_grid_and_uneven_counts() {
        // 30 × 7 grid = 210 vertices into 4 parts: sizes 52/53, imbalance 53/52.5 ≈ 1.0095.
        // A 30 × 7 strip is cut best across its short side (7 edges per cut, 21 for 4 parts;
        // balance forces a one-column step in some cuts); allow 1.5× = 31.
        let g = grid(30, 7);
        let parts = greedy_bfs(&g, 4);
        check_valid(&g, &parts, 4);
        let cut = edge_cut(&g, &parts);
        assert!((21..=31).contains(&cut), "cut {cut}");
        assert!(imbalance(&g, &parts, 4) <= 1.1);
    }

    #[test]
    fn weighted_and_disconnected_graphs() {
        // Two disjoint paths of 10 vertices with weight 2 each: 2 parts must be balanced
        // exactly (each gets one path, cut 0).
        let mut edges: Vec<(usize, usize)> = (0..9).map(|i| (i, i + 1)).collect();
        edges.extend((10..19).map(|i| (i, i + 1)));
        let g = Graph::from_edges_weighted(vec![2; 20], &edges);
        let parts = greedy_bfs(&g, 2);
        check_valid(&g, &parts, 2);
        assert_eq!(imbalance(&g, &parts, 2), 1.0);
        assert_eq!(edge_cut(&g, &parts), 0);
        // More parts than vertices: every vertex assigned, some parts empty.
        let g = path(3);
        let parts = greedy_bfs(&g, 5);
        check_valid(&g, &parts, 5);
    }

    #[test]
    fn partitioner_type_accepts_greedy_bfs() {
        let f: Partitioner = greedy_bfs;
        let g = grid(4, 4);
        let parts = f(&g, 2);
        check_valid(&g, &parts, 2);
        assert_eq!(edge_cut(&g, &parts), edge_cut(&g, &greedy_bfs(&g, 2)));
    }

    /// Every part index in `0..nparts` is used.
    fn all_parts_used(parts: &[usize], nparts: usize) -> bool {
        let mut used = vec![false; nparts];
        parts.iter().for_each(|&p| used[p] = true);
        used.iter().all(|&u| u)
    }

    /// Every part induces a connected subgraph.
    fn parts_contiguous(g: &Graph, parts: &[usize], nparts: usize) -> bool {
        (0..nparts).all(|p| {
            let members: Vec<usize> = (0..g.n_vertices()).filter(|&v| parts[v] == p).collect();
            let Some(&s) = members.first() else {
                return true;
            };
            let mut seen = vec![false; g.n_vertices()];
            let mut stack = vec![s];
            seen[s] = true;
            let mut count = 1;
            while let Some(v) = stack.pop() {
                for &w in g.neighbors(v) {
                    if parts[w] == p && !seen[w] {
                        seen[w] = true;
                        count += 1;
                        stack.push(w);
                    }
                }
            }
            count == members.len()
        })
    }

    #[test]
    fn metis_kway_grid_32x32() {
        // 1024 unit-weight vertices into 2, 3, 4, 8 parts. Required: every part non-empty and
        // contiguous, imbalance <= 1.05 (the distributed-runs issue's 5 %), and an edge cut of
        // at most 1.2 × greedy_bfs's. The regular grid is METIS's weak spot and greedy_bfs's
        // strong one: the gain-ordered BFS finds (nearly) straight cuts — 64 = the optimum for
        // 4 parts — while METIS's coarsening meets ties everywhere and its refinement leaves
        // jagged boundaries (one try: 81 for 4 parts; best of 8 tries, as used: 73 = 1.14×).
        // On irregular graphs METIS is the better partitioner; the 1.2× bound only says it is
        // not much worse where the stand-in is at its best. Lower bounds: a bisection of a
        // 32 × 32 grid cuts at least 32 edges, a 4-way partition at least 64.
        let g = grid(32, 32);
        for (nparts, lower) in [(2usize, 32usize), (3, 32), (4, 64), (8, 64)] {
            let parts = try_metis_kway(&g, nparts).expect("METIS k-way");
            check_valid(&g, &parts, nparts);
            assert!(
                all_parts_used(&parts, nparts),
                "nparts {nparts}: an empty part"
            );
            assert!(
                parts_contiguous(&g, &parts, nparts),
                "nparts {nparts}: a part is not contiguous"
            );
            let imb = imbalance(&g, &parts, nparts);
            assert!(imb <= 1.05, "nparts {nparts}: imbalance {imb}");
            let cut = edge_cut(&g, &parts);
            let greedy = edge_cut(&g, &greedy_bfs(&g, nparts));
            eprintln!("grid nparts {nparts}: imbalance {imb:.4}, cut {cut}, greedy cut {greedy}");
            assert!(
                cut >= lower,
                "nparts {nparts}: cut {cut} below the bound {lower}?"
            );
            assert!(
                5 * cut <= 6 * greedy,
                "nparts {nparts}: METIS cut {cut} > 1.2 × greedy_bfs cut {greedy}"
            );
            // Deterministic: the same answer twice.
            assert_eq!(metis_kway(&g, nparts), parts);
        }
    }

    /// `n × n` particles of unit size on a grid of pitch 1.05 (gap 0.05 between neighbours),
    /// with element counts between 40 and 199.
    fn particle_grid(n: usize) -> Vec<Particle> {
        (0..n * n)
            .map(|k| {
                let (i, j) = ((k % n) as f64, (k / n) as f64);
                Particle {
                    elements: 40 + (k as u64 * 37) % 160,
                    min: [1.05 * i, 1.05 * j],
                    max: [1.05 * i + 1.0, 1.05 * j + 1.0],
                }
            })
            .collect()
    }

    #[test]
    fn particle_graph_edges() {
        let ps = particle_grid(8);
        // Gap 0.06: the 4 side neighbours (0.05 apart), not the diagonal ones (0.0707 apart).
        let g = particle_graph(&ps, Adjacency::Proximity { gap: 0.06 }).unwrap();
        validate(&g).unwrap();
        assert_eq!(g.n_edges(), 2 * 8 * 7);
        assert_eq!(g.vwgt, ps.iter().map(|p| p.elements).collect::<Vec<_>>());
        // Gap 0.08: the diagonal neighbours too, 2 × 7 × 7 more edges.
        let g = particle_graph(&ps, Adjacency::Proximity { gap: 0.08 }).unwrap();
        assert_eq!(g.n_edges(), 2 * 8 * 7 + 2 * 7 * 7);
        // Gap 0.04: nothing is that close.
        assert_eq!(
            particle_graph(&ps, Adjacency::Proximity { gap: 0.04 })
                .unwrap()
                .n_edges(),
            0
        );
        // Contacts as given (repeats and self pairs dropped).
        let g =
            particle_graph(&ps, Adjacency::Contacts(&[(0, 1), (1, 0), (2, 2), (5, 9)])).unwrap();
        assert_eq!(g.n_edges(), 2);
        assert_eq!(g.neighbors(9), &[5]);
        // Bad input is an error, not a panic.
        assert!(particle_graph(&ps, Adjacency::Contacts(&[(0, 64)])).is_err());
        assert!(particle_graph(&ps, Adjacency::Proximity { gap: -1.0 }).is_err());
        assert!(particle_graph(&ps, Adjacency::Proximity { gap: f64::NAN }).is_err());
        let mut bad = ps.clone();
        bad[3].max[0] = bad[3].min[0] - 1.0;
        assert!(particle_graph(&bad, Adjacency::Proximity { gap: 0.1 }).is_err());
        assert_eq!(
            particle_graph(&[], Adjacency::Proximity { gap: 0.1 })
                .unwrap()
                .n_vertices(),
            0
        );
    }

    #[test]
    fn metis_balances_particle_element_counts() {
        // 8 × 8 particles with 40..199 elements each (7 800 in all): the element counts of the
        // parts are balanced to 5 % for 2 and 4 parts, with contiguous parts.
        let ps = particle_grid(8);
        let g = particle_graph(&ps, Adjacency::Proximity { gap: 0.06 }).unwrap();
        for nparts in [2, 4] {
            let parts = try_metis_kway(&g, nparts).unwrap();
            check_valid(&g, &parts, nparts);
            assert!(all_parts_used(&parts, nparts));
            assert!(parts_contiguous(&g, &parts, nparts));
            let imb = imbalance(&g, &parts, nparts);
            eprintln!(
                "particles nparts {nparts}: imbalance {imb:.4}, cut {}",
                edge_cut(&g, &parts)
            );
            assert!(
                imb <= 1.05,
                "nparts {nparts}: element-count imbalance {imb}"
            );
            // A straight cut of the 8 × 8 grid crosses 8 edges (16 for 4 quadrants); the
            // weights force steps, allow twice that.
            let cut = edge_cut(&g, &parts);
            assert!(cut <= 16 * (nparts - 1), "nparts {nparts}: cut {cut}");
        }
    }

    #[test]
    fn metis_kway_edge_cases() {
        let g = grid(3, 2);
        assert_eq!(try_metis_kway(&g, 1).unwrap(), vec![0; 6]);
        assert_eq!(try_metis_kway(&g, 6).unwrap(), (0..6).collect::<Vec<_>>());
        assert_eq!(try_metis_kway(&g, 10).unwrap(), (0..6).collect::<Vec<_>>());
        assert_eq!(metis_kway(&g, 10), (0..6).collect::<Vec<_>>());
        assert_eq!(try_metis_kway(&g, 0), Err(PartitionError::NoParts));
        let empty = Graph::from_edges(0, &[]);
        assert_eq!(try_metis_kway(&empty, 3).unwrap(), Vec::<usize>::new());
        assert_eq!(metis_kway(&empty, 1), Vec::<usize>::new());
        // No edges at all, all weights zero: balanced by count.
        let g = Graph::from_edges_weighted(vec![0; 10], &[]);
        let parts = try_metis_kway(&g, 2).unwrap();
        check_valid(&g, &parts, 2);
        // Disconnected graph (no contiguity requested): two paths of 10, weight 2 each.
        let mut edges: Vec<(usize, usize)> = (0..9).map(|i| (i, i + 1)).collect();
        edges.extend((10..19).map(|i| (i, i + 1)));
        let g = Graph::from_edges_weighted(vec![2; 20], &edges);
        assert!(!is_connected(&g));
        let parts = try_metis_kway(&g, 2).unwrap();
        assert_eq!(imbalance(&g, &parts, 2), 1.0);
        assert_eq!(edge_cut(&g, &parts), 0);
        // Malformed graphs are errors, never panics (and METIS never sees them).
        let good = grid(3, 3);
        let mut bad = good.clone();
        bad.adjncy[0] = 9; // out of range
        assert!(matches!(
            try_metis_kway(&bad, 2),
            Err(PartitionError::InvalidGraph(_))
        ));
        let mut bad = good.clone();
        bad.adjncy[0] = 0; // self loop
        assert!(matches!(
            try_metis_kway(&bad, 2),
            Err(PartitionError::InvalidGraph(_))
        ));
        // One direction only: 0 → 1 and 1 → 0 replaced by 0 → 4 (4 does not list 0).
        let mut bad = good.clone();
        let k = bad.adjncy.iter().position(|&w| w == 1).unwrap();
        bad.adjncy[k] = 4;
        assert!(matches!(
            try_metis_kway(&bad, 2),
            Err(PartitionError::InvalidGraph(_))
        ));
        let mut bad = good.clone();
        bad.xadj.pop();
        assert!(matches!(
            try_metis_kway(&bad, 2),
            Err(PartitionError::InvalidGraph(_))
        ));
        assert!(metis_nd(&bad).is_err());
        let mut bad = good.clone();
        bad.vwgt[0] = u64::MAX / 2;
        assert!(matches!(
            try_metis_kway(&bad, 2),
            Err(PartitionError::TooLarge(_))
        ));
        // ... and metis_kway falls back to greedy_bfs there.
        check_valid(&bad, &metis_kway(&bad, 2), 2);
    }

    fn is_permutation_pair(perm: &[usize], iperm: &[usize]) -> bool {
        perm.len() == iperm.len()
            && perm
                .iter()
                .enumerate()
                .all(|(k, &v)| v < iperm.len() && iperm[v] == k)
    }

    #[test]
    fn metis_nd_orders_graphs() {
        let (p, ip) = metis_nd(&Graph::from_edges(0, &[])).unwrap();
        assert!(p.is_empty() && ip.is_empty());
        assert_eq!(
            metis_nd(&Graph::from_edges(1, &[])).unwrap(),
            (vec![0], vec![0])
        );
        let (p, ip) = metis_nd(&Graph::from_edges(5, &[])).unwrap();
        assert!(is_permutation_pair(&p, &ip));
        let g = grid(20, 20);
        let (p, ip) = metis_nd(&g).unwrap();
        assert!(is_permutation_pair(&p, &ip));
        // Nested dissection numbers a separator last: the last 20 vertices eliminated split the
        // grid (removing them leaves it disconnected).
        let last: Vec<bool> = (0..400).map(|v| ip[v] >= 380).collect();
        let rest: Vec<usize> = (0..400).filter(|&v| !last[v]).collect();
        let mut seen = vec![false; 400];
        let mut stack = vec![rest[0]];
        seen[rest[0]] = true;
        while let Some(v) = stack.pop() {
            for &w in g.neighbors(v) {
                if !last[w] && !seen[w] {
                    seen[w] = true;
                    stack.push(w);
                }
            }
        }
        assert!(
            rest.iter().any(|&v| !seen[v]),
            "the last 20 vertices are not a separator"
        );
        assert_eq!(metis_nd(&g).unwrap(), (p, ip), "deterministic");
    }

    #[test]
    fn graph_of_a_matrix_pattern() {
        // 3 × 3 pattern with a diagonal, an unsymmetric entry (0, 2) and a repeated (1, 0).
        let row_ptr = [0, 2, 5, 6];
        let col_idx = [0, 2, 0, 1, 0, 2];
        let g = graph_of_pattern(3, &row_ptr, &col_idx).unwrap();
        assert_eq!(g.xadj, vec![0, 2, 3, 4]);
        assert_eq!(g.adjncy, vec![1, 2, 0, 0]);
        validate(&g).unwrap();
        assert!(graph_of_pattern(3, &row_ptr, &[0, 2, 0, 1, 0, 3]).is_err());
        assert!(graph_of_pattern(2, &row_ptr, &col_idx).is_err());
    }
}
