//! The particle graph: one vertex per particle, weighted by its element count, and edges between
//! particles that touch (contact pairs) or are close (bounding boxes within a gap).
//!
//! Built from plain data ([`Particle`]: element count and axis-aligned bounding box), so it knows
//! nothing of meshes or models. Partitioning it balances the element work of the parts while
//! the edge cut counts the particle pairs whose contact crosses a part boundary (the
//! communication of a distributed run).

use crate::metis_wrap::PartitionError;
use crate::Graph;

/// One particle as the partitioner sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    /// Number of finite elements (the vertex weight: the particle's assembly work).
    pub elements: u64,
    /// Lower-left corner of the axis-aligned bounding box.
    pub min: [f64; 2],
    /// Upper-right corner of the axis-aligned bounding box.
    pub max: [f64; 2],
}

/// Which particle pairs become edges of the particle graph.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Adjacency<'a> {
    /// Exactly these pairs (e.g. the pairs in contact); `(i, j)` and `(j, i)` are the same edge,
    /// repeats and `(i, i)` are ignored.
    Contacts(&'a [(usize, usize)]),
    /// Every pair whose bounding boxes are at most `gap` apart (Euclidean distance between the
    /// two rectangles, 0 when they overlap); `gap = 0` joins overlapping or touching boxes.
    Proximity { gap: f64 },
}

/// Euclidean distance between two axis-aligned boxes (0 when they overlap or touch).
fn box_distance(a: &Particle, b: &Particle) -> f64 {
    let dx = (a.min[0] - b.max[0]).max(b.min[0] - a.max[0]).max(0.0);
    let dy = (a.min[1] - b.max[1]).max(b.min[1] - a.max[1]).max(0.0);
    dx.hypot(dy)
}

/// Builds the particle graph: vertex `i` is `particles[i]` with weight `particles[i].elements`,
/// edges as chosen by `adjacency`.
///
/// Proximity edges are found by a sweep over the boxes sorted by their lower x (only pairs
/// whose x-extents come within `gap` are compared), so typical packings cost
/// `O(n log n + pairs)`.
///
/// # Errors
/// A contact pair refers to a particle `>= particles.len()`; a box has a non-finite corner or
/// `min > max`; `gap` is negative or not finite.
pub fn particle_graph(
    particles: &[Particle],
    adjacency: Adjacency<'_>,
) -> Result<Graph, PartitionError> {
    let n = particles.len();
    let vwgt: Vec<u64> = particles.iter().map(|p| p.elements).collect();
    match adjacency {
        Adjacency::Contacts(pairs) => {
            if let Some(&(a, b)) = pairs.iter().find(|&&(a, b)| a >= n || b >= n) {
                return Err(PartitionError::InvalidGraph(format!(
                    "contact pair ({a}, {b}) refers to a particle outside 0..{n}"
                )));
            }
            Ok(Graph::from_edges_weighted(vwgt, pairs))
        }
        Adjacency::Proximity { gap } => {
            if !(gap.is_finite() && gap >= 0.0) {
                return Err(PartitionError::InvalidGraph(format!(
                    "proximity gap {gap} must be finite and ≥ 0"
                )));
            }
            for (i, p) in particles.iter().enumerate() {
                let finite = p.min.iter().chain(&p.max).all(|v| v.is_finite());
                if !finite || p.min[0] > p.max[0] || p.min[1] > p.max[1] {
                    return Err(PartitionError::InvalidGraph(format!(
                        "particle {i} has an invalid bounding box {:?}–{:?}",
                        p.min, p.max
                    )));
                }
            }
            let mut order: Vec<usize> = (0..n).collect();
            order.sort_by(|&a, &b| particles[a].min[0].total_cmp(&particles[b].min[0]));
            let mut edges = Vec::new();
            for (k, &i) in order.iter().enumerate() {
                let reach = particles[i].max[0] + gap;
                for &j in &order[k + 1..] {
                    if particles[j].min[0] > reach {
                        break;
                    }
                    if box_distance(&particles[i], &particles[j]) <= gap {
                        edges.push((i, j));
                    }
                }
            }
            Ok(Graph::from_edges_weighted(vwgt, &edges))
        }
    }
}
