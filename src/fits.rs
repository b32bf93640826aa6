//! Compaction laws fitted to a run's pressure–density curve (beyond the paper; issue 5).
//!
//! - **Heckel** (Heckel 1961): ln(1/(1 − D)) = K P + A, with D the solid ratio and P the
//!   compaction pressure (MPa). K (1/MPa) measures plasticity (1/K is the Heckel yield
//!   pressure); A the densification before plastic flow. Fitted by linear least squares over
//!   the points with P ≥ [`HECKEL_FROM`] × P_max: the law describes the plastic stage, not the
//!   rearrangement at the first contacts.
//! - **Kawakita** (Kawakita & Lüdde 1971): C = a b P / (1 + b P) with the engineering volume
//!   strain C = (V₀ − V)/V₀ of the die. With the particle area constant, V = A_p / D, so
//!   C = 1 − D₀/D (D₀ the initial solid ratio). a is the limiting strain, 1/b (MPa) the
//!   pressure at half of it. Fitted through its linear form P/C = P/a + 1/(a b) over the points
//!   with P ≥ [`KAWAKITA_FROM`] × P_max; the reported R² is that of C itself (the model's C
//!   against the run's), not of the linear form.
//!
//! The compaction pressure is the mean pressure of the moving walls (the ones that press), or
//! of every loaded wall when none moves.

use serde::Serialize;

/// Heckel fit: points below this share of the largest pressure are left out.
pub const HECKEL_FROM: f64 = 0.1;
/// Kawakita fit: points below this share of the largest pressure are left out.
pub const KAWAKITA_FROM: f64 = 0.05;

/// One point of the pressure–density curve.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CurvePoint {
    pub solid_ratio: f64,
    /// Compaction pressure (MPa).
    pub pressure: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Heckel {
    /// Slope K (1/MPa).
    pub k: f64,
    /// Intercept A (–).
    pub a: f64,
    /// Heckel yield pressure 1/K (MPa).
    pub yield_pressure: f64,
    /// Coefficient of determination of ln(1/(1 − D)) against K P + A.
    pub r2: f64,
    pub points: usize,
    /// Pressure range fitted (MPa).
    pub pressure_range: [f64; 2],
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Kawakita {
    /// Limiting volume strain a (–).
    pub a: f64,
    /// b (1/MPa); 1/b is the pressure at which C = a/2.
    pub b: f64,
    /// Coefficient of determination of C against a b P / (1 + b P).
    pub r2: f64,
    pub points: usize,
    pub pressure_range: [f64; 2],
}

/// Both fits of one run (None where the data do not allow one: fewer than three usable
/// points, no spread in pressure, or a non-physical result).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CompactionFits {
    /// Which walls the pressure is the mean of, e.g. "left, right".
    pub pressure_of: String,
    /// Initial solid ratio D₀ used by Kawakita.
    pub initial_solid_ratio: f64,
    pub heckel: Option<Heckel>,
    pub kawakita: Option<Kawakita>,
}

/// Least-squares line y = s x + i through the points; returns (s, i, R²). None with fewer
/// than three points or no spread in x.
pub fn linear_fit(x: &[f64], y: &[f64]) -> Option<(f64, f64, f64)> {
    let n = x.len();
    if n < 3 || y.len() != n {
        return None;
    }
    let mx = x.iter().sum::<f64>() / n as f64;
    let my = y.iter().sum::<f64>() / n as f64;
    let sxx: f64 = x.iter().map(|v| (v - mx) * (v - mx)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    if !(sxx > 0.0) {
        return None;
    }
    let s = sxy / sxx;
    let i = my - s * mx;
    let r2 = r_squared(y, &x.iter().map(|v| s * v + i).collect::<Vec<_>>());
    Some((s, i, r2))
}

/// R² = 1 − SS_res / SS_tot of a model's values against data (1 for data without spread that
/// the model matches).
fn r_squared(data: &[f64], model: &[f64]) -> f64 {
    let m = data.iter().sum::<f64>() / data.len() as f64;
    let ss_tot: f64 = data.iter().map(|v| (v - m) * (v - m)).sum();
    let ss_res: f64 = data.iter().zip(model).map(|(d, f)| (d - f) * (d - f)).sum();
    if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else if ss_res == 0.0 {
        1.0
    } else {
        0.0
    }
}

fn usable(points: &[CurvePoint], from: f64) -> Vec<CurvePoint> {
    let p_max = points.iter().map(|p| p.pressure).fold(0.0, f64::max);
    points
        .iter()
        .copied()
        .filter(|p| p.pressure.is_finite() && p.solid_ratio.is_finite() && p.pressure > 0.0 && p.pressure >= from * p_max)
        .collect()
}

fn range(points: &[CurvePoint]) -> [f64; 2] {
    points.iter().fold([f64::INFINITY, f64::NEG_INFINITY], |r, p| [r[0].min(p.pressure), r[1].max(p.pressure)])
}

/// The Heckel fit of a curve.
pub fn heckel(points: &[CurvePoint]) -> Option<Heckel> {
    let pts: Vec<CurvePoint> = usable(points, HECKEL_FROM).into_iter().filter(|p| p.solid_ratio > 0.0 && p.solid_ratio < 1.0).collect();
    let x: Vec<f64> = pts.iter().map(|p| p.pressure).collect();
    let y: Vec<f64> = pts.iter().map(|p| (1.0 / (1.0 - p.solid_ratio)).ln()).collect();
    let (k, a, r2) = linear_fit(&x, &y)?;
    (k > 0.0).then(|| Heckel { k, a, yield_pressure: 1.0 / k, r2, points: pts.len(), pressure_range: range(&pts) })
}

/// The Kawakita fit of a curve that started at solid ratio `d0`.
pub fn kawakita(points: &[CurvePoint], d0: f64) -> Option<Kawakita> {
    if !(d0 > 0.0 && d0 < 1.0) {
        return None;
    }
    let pts: Vec<CurvePoint> = usable(points, KAWAKITA_FROM).into_iter().filter(|p| p.solid_ratio > d0).collect();
    let strain = |p: &CurvePoint| 1.0 - d0 / p.solid_ratio;
    let x: Vec<f64> = pts.iter().map(|p| p.pressure).collect();
    let y: Vec<f64> = pts.iter().map(|p| p.pressure / strain(p)).collect();
    let (s, i, _) = linear_fit(&x, &y)?;
    if !(s > 0.0 && i > 0.0) {
        return None;
    }
    let (a, b) = (1.0 / s, s / i);
    let c: Vec<f64> = pts.iter().map(strain).collect();
    let model: Vec<f64> = x.iter().map(|p| a * b * p / (1.0 + b * p)).collect();
    Some(Kawakita { a, b, r2: r_squared(&c, &model), points: pts.len(), pressure_range: range(&pts) })
}

/// Both fits.
pub fn fit(points: &[CurvePoint], d0: f64, pressure_of: String) -> CompactionFits {
    CompactionFits { pressure_of, initial_solid_ratio: d0, heckel: heckel(points), kawakita: kawakita(points, d0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact Heckel data (K = 0.01 /MPa, A = 0.6) are recovered to round-off.
    #[test]
    fn heckel_recovers_exact_data() {
        let pts: Vec<CurvePoint> = (1..=20)
            .map(|i| {
                let p = 10.0 * i as f64;
                CurvePoint { pressure: p, solid_ratio: 1.0 - (-(0.01 * p + 0.6)).exp() }
            })
            .collect();
        let h = heckel(&pts).unwrap();
        assert!((h.k - 0.01).abs() < 1e-12 && (h.a - 0.6).abs() < 1e-10, "{h:?}");
        assert!((h.r2 - 1.0).abs() < 1e-12);
        assert_eq!(h.points, 19, "P = 10 MPa is below 10 % of the largest pressure (200 MPa)");
        assert!((h.yield_pressure - 100.0).abs() < 1e-8);
    }

    /// Exact Kawakita data (a = 0.3, b = 0.02 /MPa, D₀ = 0.65) are recovered to round-off, and
    /// the points below 5 % of the largest pressure (450 MPa) are left out: the outlier and
    /// P = 15 MPa.
    #[test]
    fn kawakita_recovers_exact_data() {
        let (a, b, d0) = (0.3, 0.02, 0.65);
        let mut pts = vec![CurvePoint { pressure: 0.5, solid_ratio: 0.9 }]; // an outlier at low P
        pts.extend((1..=30).map(|i| {
            let p = 15.0 * i as f64;
            let c = a * b * p / (1.0 + b * p);
            CurvePoint { pressure: p, solid_ratio: d0 / (1.0 - c) }
        }));
        let k = kawakita(&pts, d0).unwrap();
        assert!((k.a - a).abs() < 1e-12 && (k.b - b).abs() < 1e-12, "{k:?}");
        assert!((k.r2 - 1.0).abs() < 1e-12);
        assert_eq!(k.points, 29);
    }

    /// Noise lowers R² below 1 but the fit stays close; degenerate data give no fit.
    #[test]
    fn noisy_and_degenerate_data() {
        let pts: Vec<CurvePoint> = (1..=40)
            .map(|i| {
                let p = 5.0 * i as f64;
                // deterministic ±0.5 % noise on the Heckel ordinate
                let noise = 0.005 * if i % 2 == 0 { 1.0 } else { -1.0 };
                CurvePoint { pressure: p, solid_ratio: 1.0 - (-(0.01 * p + 0.6) * (1.0 + noise)).exp() }
            })
            .collect();
        let h = heckel(&pts).unwrap();
        assert!(h.r2 < 1.0 && h.r2 > 0.99, "{h:?}");
        assert!((h.k - 0.01).abs() < 5e-4, "{h:?}");
        let flat = vec![CurvePoint { pressure: 100.0, solid_ratio: 0.9 }; 5];
        assert!(heckel(&flat).is_none(), "no spread in pressure");
        assert!(heckel(&pts[..2]).is_none(), "two points");
        assert!(kawakita(&pts, 1.2).is_none(), "D0 out of range");
        let (s, i, r2) = linear_fit(&[0.0, 1.0, 2.0], &[1.0, 3.0, 5.0]).unwrap();
        assert!((s - 2.0).abs() < 1e-15 && (i - 1.0).abs() < 1e-15 && (r2 - 1.0).abs() < 1e-15);
    }
}
