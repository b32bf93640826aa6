//! Per-body meshes: four-node quadrilaterals, counter-clockwise, with named boundary edge sets.
//!
//! Every body is meshed on its own. The generators in [`shapes`] build all-quadrilateral
//! meshes (so the mean-dilatation Q1/P0 element never meets a locking triangle) of discs,
//! ellipses, convex polygons, rectangles, annulus sectors and Cook's membrane, with a target
//! element size `h` (mm); [`polygon::simple_polygon`] meshes any simple (possibly non-convex)
//! polygon, and [`import`] reads particles from files (polygon outlines in CSV, gmsh `.msh`
//! meshes). [`quality`] gives the usual quality measures.

pub mod import;
pub mod polygon;
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

    /// A mesh from nodes and counter-clockwise quadrilaterals: the boundary is every element
    /// edge used by one element only, with the element's orientation (body on the left),
    /// chained head to tail (closed loops, each starting at its smallest node); the only edge
    /// set is `"boundary"`.
    pub fn from_quads(nodes: Vec<[f64; 2]>, elements: Vec<[usize; 4]>) -> Mesh {
        let mut count: std::collections::HashMap<[usize; 2], usize> = std::collections::HashMap::new();
        for el in &elements {
            for k in 0..4 {
                let (a, b) = (el[k], el[(k + 1) % 4]);
                *count.entry([a.min(b), a.max(b)]).or_insert(0) += 1;
            }
        }
        let mut boundary = Vec::new();
        for el in &elements {
            for k in 0..4 {
                let (a, b) = (el[k], el[(k + 1) % 4]);
                if count[&[a.min(b), a.max(b)]] == 1 {
                    boundary.push([a, b]);
                }
            }
        }
        let boundary = shapes::chain(boundary);
        let mut edge_sets = BTreeMap::new();
        edge_sets.insert("boundary".to_string(), boundary.clone());
        Mesh { nodes, elements, boundary, edge_sets }
    }

    /// The closed loops of [`Mesh::boundary`] as node index lists (each loop once, without
    /// repeating its first node), in the order of `boundary`. An open chain (not expected in a
    /// valid mesh) is returned as it is.
    pub fn boundary_loops(&self) -> Vec<Vec<usize>> {
        let mut loops: Vec<Vec<usize>> = Vec::new();
        let mut current: Vec<usize> = Vec::new();
        for (k, e) in self.boundary.iter().enumerate() {
            if current.is_empty() {
                current.push(e[0]);
            }
            let closes = e[1] == current[0];
            let next_starts_here = self.boundary.get(k + 1).is_some_and(|n| n[0] == e[1]);
            if closes || !next_starts_here {
                if !closes {
                    current.push(e[1]);
                }
                loops.push(std::mem::take(&mut current));
            } else {
                current.push(e[1]);
            }
        }
        loops
    }
}

/// Bounding box `[lo, hi]` of a set of points (`lo` = +∞ and `hi` = −∞ for no points).
pub fn bounding_box(pts: &[[f64; 2]]) -> [[f64; 2]; 2] {
    pts.iter().fold([[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]], |[lo, hi], q| {
        [[lo[0].min(q[0]), lo[1].min(q[1])], [hi[0].max(q[0]), hi[1].max(q[1])]]
    })
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
