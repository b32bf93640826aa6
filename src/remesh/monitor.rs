//! When to re-mesh: element quality of a particle's mesh in its current configuration.
//!
//! The measures are those of [`crate::mesh::quality`] (same definitions; a test checks that the
//! mesh-wide extremes agree with [`crate::mesh::quality::quality`]):
//! - scaled Jacobian: min over the corners of the sine of the corner angle (1 for a rectangle,
//!   ≤ 0 when a corner is reflex or the element inverted). It catches both very acute and very
//!   obtuse (flattened) corners;
//! - aspect ratio: longest over shortest edge;
//! - smallest interior corner angle, degrees.
//!
//! A particle needs re-meshing as soon as one element crosses one of the [`QualityLimits`].
use super::{check_mesh, RemeshError};
use crate::mesh::quality::{aspect_ratio, corner_angles_deg, scaled_jacobian};
use crate::mesh::Mesh;

/// Thresholds that trigger a re-mesh.
///
/// Defaults (chosen so that the generator meshes of [`crate::mesh::shapes`] for discs and
/// ellipses up to 3:1 are far from them, and so that the Q1/P0 element still gives usable
/// stresses at the limit):
/// - `min_scaled_jacobian = 0.2`: a corner angle below 11.5° or above 168.5° (at 0 the element
///   inverts);
/// - `max_aspect_ratio = 10`: flattened elements (the aspect ratio of the O-grid ellipse meshes
///   grows roughly like the axis ratio, see [`crate::mesh::shapes::ellipse`]);
/// - `min_angle_deg = 15`: acute corners (sin 15° = 0.26, so for acute corners this fires
///   before the scaled Jacobian limit; the latter then guards the obtuse ones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QualityLimits {
    pub min_scaled_jacobian: f64,
    pub max_aspect_ratio: f64,
    pub min_angle_deg: f64,
}

impl Default for QualityLimits {
    fn default() -> Self {
        Self { min_scaled_jacobian: 0.2, max_aspect_ratio: 10.0, min_angle_deg: 15.0 }
    }
}

/// The three quality measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum QualityMeasure {
    ScaledJacobian,
    AspectRatio,
    MinAngle,
}

/// The worst value of one measure over the mesh and the (first) element that has it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Worst {
    pub value: f64,
    pub element: usize,
}

/// Result of [`check_quality`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct QualityCheck {
    /// True when at least one limit is crossed (`violated` is not empty).
    pub needs_remesh: bool,
    /// The limits crossed, in the order scaled Jacobian, aspect ratio, angle.
    pub violated: Vec<QualityMeasure>,
    /// Smallest scaled Jacobian.
    pub scaled_jacobian: Worst,
    /// Largest aspect ratio (infinite for an element with a zero-length edge).
    pub aspect_ratio: Worst,
    /// Smallest interior corner angle, degrees.
    pub min_angle_deg: Worst,
    /// Number of elements crossing at least one limit.
    pub n_bad_elements: usize,
}

/// The numbers of a [`QualityCheck`] record ([`QualityCheck::to_record`]).
pub const QUALITY_RECORD: usize = 9;

impl QualityCheck {
    /// The check as numbers (to send between processes): whether a limit is crossed, the
    /// limits crossed as bits (1 scaled Jacobian, 2 aspect ratio, 4 angle), each measure's
    /// worst value and element, and the elements crossing a limit.
    pub fn to_record(&self) -> [f64; QUALITY_RECORD] {
        let bits = self.violated.iter().map(|m| match m {
            QualityMeasure::ScaledJacobian => 1,
            QualityMeasure::AspectRatio => 2,
            QualityMeasure::MinAngle => 4,
        });
        let w = |w: Worst| [w.value, w.element as f64];
        let [a, b] = w(self.scaled_jacobian);
        let [c, d] = w(self.aspect_ratio);
        let [e, f] = w(self.min_angle_deg);
        [f64::from(u8::from(self.needs_remesh)), f64::from(bits.fold(0u8, |m, b| m | b)), a, b, c, d, e, f, self.n_bad_elements as f64]
    }

    /// The check of a record of [`Self::to_record`]; None for one that is not (bits out of
    /// range, counts that are not whole numbers).
    pub fn from_record(r: &[f64]) -> Option<Self> {
        let count = |v: f64| (v >= 0.0 && v.fract() == 0.0 && v < 1e15).then_some(v as usize);
        let [needs, bits, a, b, c, d, e, f, n] = <[f64; QUALITY_RECORD]>::try_from(r).ok()?;
        let bits = count(bits).filter(|&b| b < 8)?;
        let violated = [(1, QualityMeasure::ScaledJacobian), (2, QualityMeasure::AspectRatio), (4, QualityMeasure::MinAngle)].into_iter().filter(|(m, _)| bits & m != 0).map(|(_, q)| q).collect();
        Some(Self {
            needs_remesh: needs != 0.0,
            violated,
            scaled_jacobian: Worst { value: a, element: count(b)? },
            aspect_ratio: Worst { value: c, element: count(d)? },
            min_angle_deg: Worst { value: e, element: count(f)? },
            n_bad_elements: count(n)?,
        })
    }

    /// The worst value and element of a measure.
    pub fn worst(&self, m: QualityMeasure) -> Worst {
        match m {
            QualityMeasure::ScaledJacobian => self.scaled_jacobian,
            QualityMeasure::AspectRatio => self.aspect_ratio,
            QualityMeasure::MinAngle => self.min_angle_deg,
        }
    }
}

/// Quality of `mesh` with nodal coordinates `coords` (the current configuration) against
/// `limits`. A value exactly at a limit does not cross it.
///
/// # Errors
/// An empty mesh, a coordinate count different from the node count, a node index out of range
/// or a non-finite coordinate.
pub fn check_quality(mesh: &Mesh, coords: &[[f64; 2]], limits: &QualityLimits) -> Result<QualityCheck, RemeshError> {
    check_mesh(mesh, coords)?;
    let mut sj_w = Worst { value: f64::INFINITY, element: 0 };
    let mut ar_w = Worst { value: f64::NEG_INFINITY, element: 0 };
    let mut an_w = Worst { value: f64::INFINITY, element: 0 };
    let mut n_bad = 0;
    for (e, el) in mesh.elements.iter().enumerate() {
        let p = el.map(|n| coords[n]);
        let sj = scaled_jacobian(p);
        let ar = aspect_ratio(&p);
        let an = corner_angles_deg(&p).into_iter().fold(f64::INFINITY, f64::min);
        if sj < sj_w.value {
            sj_w = Worst { value: sj, element: e };
        }
        if ar > ar_w.value {
            ar_w = Worst { value: ar, element: e };
        }
        if an < an_w.value {
            an_w = Worst { value: an, element: e };
        }
        if sj < limits.min_scaled_jacobian || ar > limits.max_aspect_ratio || an < limits.min_angle_deg {
            n_bad += 1;
        }
    }
    let mut violated = Vec::new();
    if sj_w.value < limits.min_scaled_jacobian {
        violated.push(QualityMeasure::ScaledJacobian);
    }
    if ar_w.value > limits.max_aspect_ratio {
        violated.push(QualityMeasure::AspectRatio);
    }
    if an_w.value < limits.min_angle_deg {
        violated.push(QualityMeasure::MinAngle);
    }
    if !violated.is_empty() {
        tracing::debug!(?violated, ?sj_w, ?ar_w, ?an_w, n_bad, "mesh quality below the re-meshing limits");
    }
    Ok(QualityCheck {
        needs_remesh: !violated.is_empty(),
        violated,
        scaled_jacobian: sj_w,
        aspect_ratio: ar_w,
        min_angle_deg: an_w,
        n_bad_elements: n_bad,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{quality, shapes};

    /// A 3×3 grid of unit squares (elements numbered row by row, element 8 at the top right).
    fn grid() -> Mesh {
        shapes::rectangle([0.0, 0.0], 3.0, 3.0, 3, 3)
    }

    /// Index of the node at (i, j) of the 4×4 node grid (row by row from the bottom left).
    fn node(i: usize, j: usize) -> usize {
        4 * j + i
    }

    /// A check goes through its record unchanged (a distributed run's checkpoint sends it so),
    /// and a record out of range is refused.
    #[test]
    fn a_check_survives_its_record() {
        let mut m = grid();
        m.nodes[node(3, 3)] = [6.0, 2.5];
        let limits = QualityLimits { min_scaled_jacobian: 0.2, max_aspect_ratio: 1.5, min_angle_deg: 15.0 };
        let c = check_quality(&m, &m.nodes, &limits).unwrap();
        assert!(c.violated.len() >= 2, "{c:?}");
        assert_eq!(QualityCheck::from_record(&c.to_record()), Some(c.clone()));
        let mut bad = c.to_record();
        bad[1] = 8.0;
        assert_eq!(QualityCheck::from_record(&bad), None);
        bad = c.to_record();
        bad[3] = 1.5;
        assert_eq!(QualityCheck::from_record(&bad), None);
    }

    #[test]
    fn undistorted_grid_passes() {
        let m = grid();
        let c = check_quality(&m, &m.nodes, &QualityLimits::default()).unwrap();
        assert!(!c.needs_remesh && c.violated.is_empty() && c.n_bad_elements == 0);
        // exact values of unit squares (to round-off of sin/atan2)
        assert!((c.scaled_jacobian.value - 1.0).abs() < 1e-15);
        assert!((c.aspect_ratio.value - 1.0).abs() < 1e-15);
        assert!((c.min_angle_deg.value - 90.0).abs() < 1e-12);
    }

    /// Element 8 = (2,2), (3,2), P, (2,3) with the top-right node moved to P by hand.
    /// - P = (6, 2.5): the corner at (3,2) opens to 180° − atan(0.5/3) = 170.5°, scaled Jacobian
    ///   sin = 0.5/√9.25 = 0.1644 < 0.2; the acute corner at P is atan2(3.5, 11.75) = 16.6° and
    ///   the aspect ratio |P − (2,3)| = 4.03: only the scaled Jacobian limit is crossed;
    /// - P = (7, 3.5): the corner at P is atan2(5.5, 20.75) = 14.85° < 15°, the obtuse corner at
    ///   (3,2) is 159.4° (sin 0.351), sin 14.85° = 0.256, aspect ratio 5.02: only the angle.
    ///
    /// Values to 1e-12 (closed-form sin/atan2 of exact small numbers). The definitions are
    /// cross-checked with `mesh::quality` (bit-identical extremes).
    #[test]
    fn each_threshold_is_crossed() {
        let m = grid();
        let lim = QualityLimits::default();

        let mut x = m.nodes.clone();
        x[node(3, 3)] = [6.0, 2.5];
        let c = check_quality(&m, &x, &lim).unwrap();
        assert!(c.needs_remesh);
        assert_eq!(c.violated, vec![QualityMeasure::ScaledJacobian]);
        assert_eq!(c.scaled_jacobian.element, 8);
        assert!((c.scaled_jacobian.value - 0.5 / 9.25f64.sqrt()).abs() < 1e-12, "{c:?}");
        assert!((c.min_angle_deg.value - 3.5f64.atan2(11.75).to_degrees()).abs() < 1e-12);
        assert!((c.aspect_ratio.value - 16.25f64.sqrt()).abs() < 1e-12);
        assert_eq!(c.n_bad_elements, 1);
        let q = quality::quality(&m, &x);
        assert_eq!(q.min_scaled_jacobian, c.scaled_jacobian.value);
        assert_eq!(q.min_angle_deg, c.min_angle_deg.value);
        assert_eq!(q.max_aspect_ratio, c.aspect_ratio.value);

        x[node(3, 3)] = [7.0, 3.5];
        let c = check_quality(&m, &x, &lim).unwrap();
        assert_eq!(c.violated, vec![QualityMeasure::MinAngle]);
        assert_eq!(c.worst(QualityMeasure::MinAngle).element, 8);
        assert!((c.min_angle_deg.value - 5.5f64.atan2(20.75).to_degrees()).abs() < 1e-12, "{c:?}");
        assert!((c.scaled_jacobian.value - 5.5f64.atan2(20.75).sin()).abs() < 1e-12);
        assert!(c.scaled_jacobian.value > lim.min_scaled_jacobian);
        assert!(c.aspect_ratio.value < lim.max_aspect_ratio);

        // a limit exactly at the worst value is not crossed
        let at = QualityLimits { min_angle_deg: c.min_angle_deg.value, ..lim };
        assert!(!check_quality(&m, &x, &at).unwrap().needs_remesh);
    }

    /// A flattened row of elements crosses the aspect-ratio default, an inverted element the
    /// scaled Jacobian default.
    #[test]
    fn defaults_catch_flattening_and_inversion() {
        let m = grid();
        // compress the top row to height 0.08: its elements are 1 × 0.08 (aspect ratio 12.5)
        let x: Vec<[f64; 2]> = m.nodes.iter().map(|&[a, b]| [a, if b > 2.5 { 2.08 } else { b }]).collect();
        let c = check_quality(&m, &x, &QualityLimits::default()).unwrap();
        assert!((c.aspect_ratio.value - 12.5).abs() < 1e-9, "{c:?}");
        assert_eq!(c.violated, vec![QualityMeasure::AspectRatio]);
        assert_eq!(c.n_bad_elements, 3);
        assert!(c.aspect_ratio.element >= 6);

        // push node (1,1) across the diagonal of element 0: inverted corner
        let mut x = m.nodes.clone();
        x[node(1, 1)] = [0.2, 0.2];
        let c = check_quality(&m, &x, &QualityLimits::default()).unwrap();
        assert!(c.scaled_jacobian.value < 0.0);
        assert_eq!(c.scaled_jacobian.element, 0);
        assert!(c.violated.contains(&QualityMeasure::ScaledJacobian));
    }

    #[test]
    fn generator_meshes_pass_the_defaults() {
        for m in [
            shapes::disc([0.0, 0.0], 1.0, 0.1),
            shapes::ellipse([0.0, 0.0], [3.0, 1.0], 30.0, 0.2),
            shapes::convex_polygon(&[[0.0, 0.0], [2.0, 0.0], [2.5, 1.5], [0.5, 2.0]], 0.2).unwrap(),
        ] {
            let c = check_quality(&m, &m.nodes, &QualityLimits::default()).unwrap();
            assert!(!c.needs_remesh, "{c:?}");
        }
    }

    #[test]
    fn degenerate_input() {
        let m = grid();
        assert_eq!(check_quality(&Mesh::default(), &[], &QualityLimits::default()), Err(RemeshError::EmptyMesh));
        let mut x = m.nodes.clone();
        x[0] = [f64::INFINITY, 0.0];
        assert!(check_quality(&m, &x, &QualityLimits::default()).is_err());
        // collapsed element (all nodes at one point): scaled Jacobian 0, aspect ratio infinite
        let x = vec![[0.5, 0.5]; m.nodes.len()];
        let c = check_quality(&m, &x, &QualityLimits::default()).unwrap();
        assert!(c.needs_remesh && c.scaled_jacobian.value == 0.0 && c.aspect_ratio.value.is_infinite());
    }
}
