//! Particle partitions for distributed runs: which process owns which body.
//!
//! The partitioner (the `partition` crate) sees plain data: per body its element count (the
//! work to balance) and the bounding box of its reference coordinates. Bodies whose boxes are
//! close are joined by an edge — the pairs that are or will soon be in contact, whose contact
//! work crosses process boundaries when they are owned by different processes. METIS k-way
//! then balances the element counts and minimises the number of such pairs.

use crate::model::Model;
use partition::{Adjacency, Graph, Particle, PartitionError};

/// Proximity gap of [`partition_particles`] as a fraction of the median body size (the larger
/// side of its bounding box).
pub const PROXIMITY_GAP_FRACTION: f64 = 0.1;

/// The partitioner's view of every body, in body order: element count and bounding box of its
/// nodes in the reference configuration (`model.x0`). A body without nodes gets an empty box at
/// the origin.
pub fn particles(model: &Model) -> Vec<Particle> {
    model
        .bodies
        .iter()
        .map(|b| {
            let nodes = &model.x0[b.node_offset..b.node_offset + b.mesh.nodes.len()];
            let mut min = [f64::INFINITY; 2];
            let mut max = [f64::NEG_INFINITY; 2];
            for p in nodes {
                for k in 0..2 {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                }
            }
            if nodes.is_empty() {
                (min, max) = ([0.0; 2], [0.0; 2]);
            }
            Particle { elements: b.mesh.elements.len() as u64, min, max }
        })
        .collect()
}

/// The particle graph of the model: one vertex per body weighted by its element count; edges
/// between bodies whose reference bounding boxes are at most [`PROXIMITY_GAP_FRACTION`] × the
/// median body size apart.
pub fn particle_graph(model: &Model) -> Result<Graph, PartitionError> {
    let ps = particles(model);
    let mut sizes: Vec<f64> = ps.iter().map(|p| (p.max[0] - p.min[0]).max(p.max[1] - p.min[1])).collect();
    sizes.sort_by(f64::total_cmp);
    let median = sizes.get(sizes.len() / 2).copied().unwrap_or(0.0);
    let gap = if median.is_finite() { PROXIMITY_GAP_FRACTION * median } else { 0.0 };
    partition::particle_graph(&ps, Adjacency::Proximity { gap })
}

/// Owner (`0..nparts`) of every body of the model: METIS k-way partition of
/// [`particle_graph`], balancing element counts (to METIS's 3 %) with few close pairs split.
/// When the graph cannot be built or METIS fails, a warning is logged and the greedy BFS
/// partitioner is used (on a graph without edges if need be).
///
/// # Panics
/// If `nparts == 0`.
pub fn partition_particles(model: &Model, nparts: usize) -> Vec<usize> {
    assert!(nparts >= 1, "partition_particles: nparts must be at least 1");
    let graph = particle_graph(model).unwrap_or_else(|e| {
        tracing::warn!("particle graph: {e}; partitioning by element counts only");
        Graph::from_edges_weighted(model.bodies.iter().map(|b| b.mesh.elements.len() as u64).collect(), &[])
    });
    let owner = partition::metis_kway(&graph, nparts);
    tracing::info!(
        bodies = graph.n_vertices(),
        nparts,
        edge_cut = partition::edge_cut(&graph, &owner),
        imbalance = partition::imbalance(&graph, &owner, nparts),
        "particle partition"
    );
    owner
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc_grid(n: usize) -> Model {
        let text = format!(
            r#"title = "partition test"
[[materials]]
name = "m"
model = "elastic"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[grids]]
material = "m"
nx = {n}
ny = {n}
shape = "disc"
solid_ratio = 0.7
mesh_size = 4.0
[time]
end = 1.0
dt = 0.1
[[walls]]
side = "left"
position = 0.0
velocity = 1.0
[[walls]]
side = "right"
position = 100.0
velocity = 1.0
[[walls]]
side = "bottom"
position = 0.0
velocity = 1.0
[[walls]]
side = "top"
position = 100.0
velocity = 1.0
"#
        );
        let case = crate::case::parse(&text, std::path::Path::new(".")).expect("case");
        Model::from_case(&case).expect("model")
    }

    #[test]
    fn disc_grid_partition_balances_elements() {
        // 4 × 4 discs of equal size: the boxes of side neighbours are 1.4 mm apart (gap 2.4 mm),
        // so the particle graph holds at least the 24 side-neighbour pairs and is connected.
        let model = disc_grid(4);
        let ps = particles(&model);
        assert_eq!(ps.len(), 16);
        for (p, b) in ps.iter().zip(&model.bodies) {
            assert_eq!(p.elements, b.mesh.elements.len() as u64);
            assert!(p.min[0] < p.max[0] && p.min[1] < p.max[1]);
        }
        let g = particle_graph(&model).unwrap();
        assert!(g.n_edges() >= 24, "{} edges", g.n_edges());
        assert!(partition::is_connected(&g));
        for nparts in [1, 2, 4, 16, 20] {
            let owner = partition_particles(&model, nparts);
            assert_eq!(owner.len(), 16);
            assert!(owner.iter().all(|&p| p < nparts));
            let imb = partition::imbalance(&g, &owner, nparts.min(16));
            assert!(imb <= 1.05, "nparts {nparts}: imbalance {imb}");
        }
    }
}
