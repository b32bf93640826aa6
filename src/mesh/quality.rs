//! Mesh quality measures for four-node quadrilaterals.
//!
//! - **Scaled Jacobian** of a quadrilateral: the minimum over its four corners of
//!   `(e_next × e_prev) / (|e_next| |e_prev|)`, where `e_next`, `e_prev` are the two edges leaving
//!   the corner (to the next and the previous node in counter-clockwise order). It is the sine of
//!   the smallest corner angle: 1 for a rectangle, in `(0, 1)` for a valid distorted element and
//!   `<= 0` when some corner is reflex or the element is inverted (clockwise). The bilinear
//!   map's Jacobian determinant is positive everywhere in the element exactly when it is positive
//!   at the four corners, so a positive scaled Jacobian means a valid element.
//! - **Angles**: interior corner angles in degrees, in `[0, 360)` (reflex corners above 180°).
//! - **Aspect ratio**: longest edge over shortest edge (1 for a square).

use super::Mesh;
use serde::Serialize;

/// Summary of the quality of a mesh (see the module docs for the definitions).
///
/// For a mesh without elements all minima/maxima are reported as `0.0`.
#[derive(Debug, Clone, Serialize)]
pub struct QualityReport {
    pub n_elements: usize,
    /// Smallest scaled Jacobian over all elements (1 = all rectangles, <= 0 = some inverted).
    pub min_scaled_jacobian: f64,
    /// Smallest interior corner angle over all elements, degrees.
    pub min_angle_deg: f64,
    /// Largest interior corner angle over all elements, degrees.
    pub max_angle_deg: f64,
    /// Largest ratio longest edge / shortest edge over all elements.
    pub max_aspect_ratio: f64,
    /// Number of elements with scaled Jacobian <= 0 (inverted, reflex or degenerate).
    pub n_inverted: usize,
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}

/// The two edges leaving corner `i`: to the next and to the previous node.
fn corner_edges(p: &[[f64; 2]; 4], i: usize) -> ([f64; 2], [f64; 2]) {
    (sub(p[(i + 1) % 4], p[i]), sub(p[(i + 3) % 4], p[i]))
}

/// Scaled Jacobian of a quadrilateral with corners `p` (counter-clockwise for a valid element):
/// min over corners of the corner cross product divided by the product of the two edge
/// lengths. 1 for a rectangle, `<= 0` for an inverted element; 0 if an edge has zero length.
pub fn scaled_jacobian(p: [[f64; 2]; 4]) -> f64 {
    let mut sj = f64::INFINITY;
    for i in 0..4 {
        let (a, b) = corner_edges(&p, i);
        let l = norm(a) * norm(b);
        let s = if l > 0.0 { cross(a, b) / l } else { 0.0 };
        sj = sj.min(s);
    }
    sj
}

/// Interior corner angles in degrees, in `[0, 360)`.
pub fn corner_angles_deg(p: &[[f64; 2]; 4]) -> [f64; 4] {
    let mut ang = [0.0; 4];
    for (i, a_out) in ang.iter_mut().enumerate() {
        let (a, b) = corner_edges(p, i);
        let mut t = cross(a, b).atan2(dot(a, b)).to_degrees();
        if t < 0.0 {
            t += 360.0;
        }
        *a_out = t;
    }
    ang
}

/// Longest over shortest side (infinite for a zero-length side).
pub fn aspect_ratio(p: &[[f64; 2]; 4]) -> f64 {
    let lens: Vec<f64> = (0..4).map(|i| norm(sub(p[(i + 1) % 4], p[i]))).collect();
    let max = lens.iter().cloned().fold(0.0, f64::max);
    let min = lens.iter().cloned().fold(f64::INFINITY, f64::min);
    if min > 0.0 {
        max / min
    } else {
        f64::INFINITY
    }
}

fn element_points(mesh: &Mesh, coords: &[[f64; 2]], e: usize) -> [[f64; 2]; 4] {
    mesh.elements[e].map(|n| coords[n])
}

/// Scaled Jacobian of every element, using the nodal coordinates `coords` (e.g. `mesh.nodes`
/// or the current configuration).
pub fn element_quality(mesh: &Mesh, coords: &[[f64; 2]]) -> Vec<f64> {
    (0..mesh.n_elements())
        .map(|e| scaled_jacobian(element_points(mesh, coords, e)))
        .collect()
}

/// Quality summary of the mesh with nodal coordinates `coords`.
pub fn quality(mesh: &Mesh, coords: &[[f64; 2]]) -> QualityReport {
    let n = mesh.n_elements();
    if n == 0 {
        return QualityReport {
            n_elements: 0,
            min_scaled_jacobian: 0.0,
            min_angle_deg: 0.0,
            max_angle_deg: 0.0,
            max_aspect_ratio: 0.0,
            n_inverted: 0,
        };
    }
    let mut r = QualityReport {
        n_elements: n,
        min_scaled_jacobian: f64::INFINITY,
        min_angle_deg: f64::INFINITY,
        max_angle_deg: f64::NEG_INFINITY,
        max_aspect_ratio: 0.0,
        n_inverted: 0,
    };
    for e in 0..n {
        let p = element_points(mesh, coords, e);
        let sj = scaled_jacobian(p);
        r.min_scaled_jacobian = r.min_scaled_jacobian.min(sj);
        if sj <= 0.0 {
            r.n_inverted += 1;
        }
        for a in corner_angles_deg(&p) {
            r.min_angle_deg = r.min_angle_deg.min(a);
            r.max_angle_deg = r.max_angle_deg.max(a);
        }
        r.max_aspect_ratio = r.max_aspect_ratio.max(aspect_ratio(&p));
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_rhombus_and_inverted() {
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!((scaled_jacobian(sq) - 1.0).abs() < 1e-15);
        // Rhombus with 60° and 120° corners: sin 60° = sin 120°.
        let c = 0.5;
        let s = 3f64.sqrt() / 2.0;
        let rh = [[0.0, 0.0], [1.0, 0.0], [1.0 + c, s], [c, s]];
        assert!((scaled_jacobian(rh) - s).abs() < 1e-15);
        let ang = corner_angles_deg(&rh);
        assert!((ang[0] - 60.0).abs() < 1e-12 && (ang[1] - 120.0).abs() < 1e-12);
        // Clockwise square: inverted.
        let cw = [sq[0], sq[3], sq[2], sq[1]];
        assert!((scaled_jacobian(cw) + 1.0).abs() < 1e-15);
        // Dart (reflex corner): non-positive.
        let dart = [[0.0, 0.0], [2.0, 0.0], [0.5, 0.5], [0.0, 2.0]];
        assert!(scaled_jacobian(dart) < 0.0);
        assert!(corner_angles_deg(&dart).iter().any(|&a| a > 180.0));
    }

    #[test]
    fn report_of_two_elements() {
        let mesh = Mesh {
            nodes: vec![
                [0.0, 0.0],
                [2.0, 0.0],
                [2.0, 1.0],
                [0.0, 1.0],
                [3.0, 0.0],
                [3.0, 1.0],
            ],
            elements: vec![[0, 1, 2, 3], [1, 4, 5, 2]],
            ..Default::default()
        };
        let r = quality(&mesh, &mesh.nodes);
        assert_eq!(r.n_elements, 2);
        assert_eq!(r.n_inverted, 0);
        assert!((r.min_scaled_jacobian - 1.0).abs() < 1e-15);
        assert!((r.min_angle_deg - 90.0).abs() < 1e-12);
        assert!((r.max_angle_deg - 90.0).abs() < 1e-12);
        assert!((r.max_aspect_ratio - 2.0).abs() < 1e-15);
        assert_eq!(element_quality(&mesh, &mesh.nodes).len(), 2);
    }
}
