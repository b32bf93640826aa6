//! Per-body meshes: four-node quadrilaterals, counter-clockwise, with named boundary edge sets.
//!
//! Every body is meshed on its own. The generators in [`shapes`] build all-quadrilateral
//! meshes (so the mean-dilatation Q1/P0 element never meets a locking triangle) of discs,
//! ellipses, convex polygons, rectangles, annulus sectors and Cook's membrane, with a target
//! element size `h` (mm). [`quality`] gives the usual quality measures.

pub mod quality;
pub mod shapes;

use std::collections::BTreeMap;

/// A 2D mesh of four-node quadrilaterals.
///
/// - `nodes[i] = [X, Y]`: reference coordinates, mm.
/// - `elements[e] = [n0, n1, n2, n3]`: node indices, counter-clockwise (positive area).
/// - `boundary`: every boundary edge `[a, b]` oriented so that the body lies on its left
///   (outer boundary counter-clockwise).
/// - `edge_sets`: named subsets of boundary edges (e.g. `"left"`, `"outer"`, `"inner"`), same
///   orientation as `boundary`. Every generator also provides the set `"boundary"` (all edges).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub nodes: Vec<[f64; 2]>,
    pub elements: Vec<[usize; 4]>,
    pub boundary: Vec<[usize; 2]>,
    pub edge_sets: BTreeMap<String, Vec<[usize; 2]>>,
}

impl Mesh {
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    pub fn n_elements(&self) -> usize {
        self.elements.len()
    }

    /// Sorted, de-duplicated node indices of a named edge set, or `None` if there is no such set.
    pub fn node_set(&self, name: &str) -> Option<Vec<usize>> {
        let edges = self.edge_sets.get(name)?;
        let mut v: Vec<usize> = edges.iter().flat_map(|e| e.iter().copied()).collect();
        v.sort_unstable();
        v.dedup();
        Some(v)
    }

    /// Signed area of element `e` for the given nodal coordinates (shoelace formula; exact
    /// for the bilinear quadrilateral).
    pub fn element_area(&self, e: usize, coords: &[[f64; 2]]) -> f64 {
        polygon_area(self.elements[e].iter().map(|&n| coords[n]))
    }

    /// Total signed area of the mesh for the given nodal coordinates (mm²).
    pub fn area(&self, coords: &[[f64; 2]]) -> f64 {
        (0..self.elements.len()).map(|e| self.element_area(e, coords)).sum()
    }
}

/// Signed area of a closed polygon (positive when counter-clockwise).
pub fn polygon_area(pts: impl IntoIterator<Item = [f64; 2]>) -> f64 {
    let p: Vec<[f64; 2]> = pts.into_iter().collect();
    let n = p.len();
    let mut a = 0.0;
    for i in 0..n {
        let j = (i + 1) % n;
        a += p[i][0] * p[j][1] - p[j][0] * p[i][1];
    }
    0.5 * a
}
