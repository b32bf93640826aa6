//! Isotropic hardening tables: piecewise-linear flow stress σ_y(ε̄ᵖ).
//!
//! The table holds breakpoints (ε̄ᵖ_k, σ_k) with ε̄ᵖ_0 = 0 (σ_0 is the initial yield stress),
//! strictly increasing plastic strain and non-decreasing stress (no softening, so the J2
//! return-map equation has exactly one root). Between breakpoints σ_y is linear; beyond the
//! last point the material is perfectly plastic (slope 0).
// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// Piecewise-linear flow stress σ_y(ε̄ᵖ) (MPa vs equivalent plastic strain).
#[derive(Clone, Debug, PartialEq)]
pub struct HardeningTable {
    pub eps_p: Vec<f64>,
    pub sigma_y: Vec<f64>,
}

/// The paper's Table 1: uniaxial total strain (as a fraction, the paper prints %) vs stress
/// (MPa) for the aluminium alloy at 250 °C, with E = 64.1 GPa and ν = 0.3 in the elastic range
/// (source: the compaction paper in `/work/shared/seeds/000_e93b1aa71ee83dbe.txt`, §5.1,
/// "Table 1. The stress-strain relation of aluminum alloy at 250 °C"). Convert with
/// [`HardeningTable::from_total_strain`]`(64100.0, &aluminium_250c())`.
pub fn aluminium_250c() -> Vec<[f64; 2]> {
    vec![
        [0.0, 0.0],
        [0.0011, 70.5],
        [0.0031, 111.2],
        [0.0087, 129.1],
        [0.016, 130.2],
    ]
}

/// Young's modulus that goes with [`aluminium_250c`] (MPa).
pub const ALUMINIUM_250C_E: f64 = 64100.0;
/// Poisson's ratio that goes with [`aluminium_250c`].
pub const ALUMINIUM_250C_NU: f64 = 0.3;

fn check_finite(i: usize, p: &[f64; 2]) -> Result<(), String> {
    if !p[0].is_finite() || !p[1].is_finite() {
        return Err(format!(
            "point {i} (strain {}, stress {}): values must be finite",
            p[0], p[1]
        ));
    }
    if p[0] < 0.0 || p[1] < 0.0 {
        return Err(format!(
            "point {i} (strain {}, stress {}): values must not be negative",
            p[0], p[1]
        ));
    }
    Ok(())
}

impl HardeningTable {
    /// Perfect plasticity at constant flow stress `sigma_y` (MPa).
    pub fn perfect(sigma_y: f64) -> Self {
        Self {
            eps_p: vec![0.0],
            sigma_y: vec![sigma_y],
        }
    }

    /// From points `[ε̄ᵖ, σ_y]`. Requirements (an `Err` names the offending point, 0-based):
    /// at least one point; finite, non-negative values; the first point at ε̄ᵖ = 0 with
    /// σ_y > 0 (initial yield); strictly increasing ε̄ᵖ; non-decreasing σ_y.
    pub fn from_plastic_strain(points: &[[f64; 2]]) -> Result<Self, String> {
        if points.is_empty() {
            return Err("hardening table is empty".to_string());
        }
        for (i, p) in points.iter().enumerate() {
            check_finite(i, p)?;
        }
        let p0 = points[0];
        if p0[0] != 0.0 {
            return Err(format!(
                "point 0 (plastic strain {}, stress {}): the first point must be the initial yield at plastic strain 0",
                p0[0], p0[1]
            ));
        }
        if !(p0[1] > 0.0) {
            return Err(format!(
                "point 0 (plastic strain {}, stress {}): initial yield stress must be positive",
                p0[0], p0[1]
            ));
        }
        for i in 1..points.len() {
            let (a, b) = (points[i - 1], points[i]);
            if !(b[0] > a[0]) {
                return Err(format!(
                    "point {i} (plastic strain {}, stress {}): plastic strain must increase",
                    b[0], b[1]
                ));
            }
            if b[1] < a[1] {
                return Err(format!(
                    "point {i} (plastic strain {}, stress {}): stress must not decrease (softening is not supported)",
                    b[0], b[1]
                ));
            }
        }
        Ok(Self {
            eps_p: points.iter().map(|p| p[0]).collect(),
            sigma_y: points.iter().map(|p| p[1]).collect(),
        })
    }

    /// From a uniaxial table of total strain ε vs stress σ (points `[ε, σ]`, strain as a
    /// fraction) and Young's modulus `e`:
    /// - a leading origin point (0, 0) is dropped;
    /// - plastic strain ε̄ᵖ = ε − σ/E for every point;
    /// - the first remaining point is the initial yield: its plastic strain must vanish within
    ///   roundoff of the elastic line, |ε − σ/E| ≤ 10⁻³ ε (Table 1's first point has
    ///   ε − σ/E = 1.6·10⁻⁷ at ε = 1.1·10⁻³), and is set to exactly 0;
    /// - errors, naming the point index in the input (0-based) and its values: empty table,
    ///   negative or non-finite values, non-increasing strain, decreasing stress, a first point
    ///   clearly off the elastic line, any point whose strain is clearly below the elastic strain
    ///   σ/E, and a segment stiffer than E (plastic strain not increasing).
    pub fn from_total_strain(e: f64, points: &[[f64; 2]]) -> Result<Self, String> {
        if !(e > 0.0) || !e.is_finite() {
            return Err(format!(
                "Young's modulus must be positive and finite (got {e})"
            ));
        }
        if points.is_empty() {
            return Err("stress-strain table is empty".to_string());
        }
        for (i, p) in points.iter().enumerate() {
            check_finite(i, p)?;
        }
        for i in 1..points.len() {
            let (a, b) = (points[i - 1], points[i]);
            if !(b[0] > a[0]) {
                return Err(format!(
                    "point {i} (strain {}, stress {}): strain must increase",
                    b[0], b[1]
                ));
            }
            if b[1] < a[1] {
                return Err(format!(
                    "point {i} (strain {}, stress {}): stress must not decrease",
                    b[0], b[1]
                ));
            }
        }
        let start = usize::from(points[0][0] == 0.0 && points[0][1] == 0.0);
        if start == points.len() {
            return Err("stress-strain table has only the origin point".to_string());
        }
        let mut eps_p = Vec::with_capacity(points.len() - start);
        let mut sigma_y = Vec::with_capacity(points.len() - start);
        for (i, p) in points.iter().enumerate().skip(start) {
            let ep = p[0] - p[1] / e;
            let tol = 1e-3 * p[0];
            if i == start {
                if ep.abs() > tol {
                    return Err(format!(
                        "point {i} (strain {}, stress {}): the first point after the origin must lie on the elastic line \
                         σ = Eε (initial yield), but its plastic strain ε − σ/E is {ep:.3e}",
                        p[0], p[1]
                    ));
                }
                if !(p[1] > 0.0) {
                    return Err(format!(
                        "point {i} (strain {}, stress {}): initial yield stress must be positive",
                        p[0], p[1]
                    ));
                }
                eps_p.push(0.0);
            } else {
                if ep < -tol {
                    return Err(format!(
                        "point {i} (strain {}, stress {}): strain is below the elastic strain σ/E = {:.6e}",
                        p[0],
                        p[1],
                        p[1] / e
                    ));
                }
                let prev = *eps_p.last().unwrap_or(&0.0);
                if !(ep > prev) {
                    return Err(format!(
                        "point {i} (strain {}, stress {}): plastic strain ε − σ/E = {ep:.6e} does not increase \
                         (segment stiffer than E)",
                        p[0], p[1]
                    ));
                }
                eps_p.push(ep);
            }
            sigma_y.push(p[1]);
        }
        Ok(Self { eps_p, sigma_y })
    }

    /// Initial yield stress σ_y(0).
    pub fn initial_yield(&self) -> f64 {
        self.sigma_y[0]
    }

    /// Index k of the segment [ε̄ᵖ_k, ε̄ᵖ_{k+1}) containing `eps_p` (the last index means the
    /// perfectly plastic tail; negative input maps to segment 0).
    #[inline]
    pub fn segment(&self, eps_p: f64) -> usize {
        self.eps_p
            .partition_point(|&x| x <= eps_p)
            .saturating_sub(1)
    }

    /// Slope dσ_y/dε̄ᵖ of segment k (0 on the perfectly plastic tail).
    #[inline]
    pub fn slope(&self, k: usize) -> f64 {
        if k + 1 < self.eps_p.len() {
            (self.sigma_y[k + 1] - self.sigma_y[k]) / (self.eps_p[k + 1] - self.eps_p[k])
        } else {
            0.0
        }
    }

    /// Flow stress and slope at `eps_p`: (σ_y, dσ_y/dε̄ᵖ), right-continuous slope at
    /// breakpoints; σ_y = σ_last and slope 0 after the last point.
    #[inline]
    pub fn eval(&self, eps_p: f64) -> (f64, f64) {
        let k = self.segment(eps_p);
        let h = self.slope(k);
        (self.sigma_y[k] + h * (eps_p - self.eps_p[k]).max(0.0), h)
    }

    /// Exact return-map solve for q_tr − 3GΔγ − σ_y(ε̄ᵖ_n + Δγ) = 0 (piecewise linear, σ_y
    /// non-decreasing, so the left side is strictly decreasing in Δγ). Walks the segments from
    /// ε̄ᵖ_n until the sign changes and solves the linear equation on that segment:
    /// Δγ = (e_lo − ε̄ᵖ_n) + f(e_lo)/(3G + H_k). Returns (Δγ, H_k); (0, ∞) when
    /// q_tr ≤ σ_y(ε̄ᵖ_n) (elastic step).
    pub fn return_map(&self, three_g: f64, q_tr: f64, eps_n: f64) -> (f64, f64) {
        let (sy, _) = self.eval(eps_n);
        if !(q_tr > sy) {
            return (0.0, f64::INFINITY);
        }
        let mut k = self.segment(eps_n);
        let mut e_lo = eps_n;
        let mut s_lo = sy;
        loop {
            let h = self.slope(k);
            let f_lo = q_tr - three_g * (e_lo - eps_n) - s_lo;
            let last = k + 1 >= self.eps_p.len();
            if last || q_tr - three_g * (self.eps_p[k + 1] - eps_n) - self.sigma_y[k + 1] <= 0.0 {
                return ((e_lo - eps_n) + f_lo / (three_g + h), h);
            }
            k += 1;
            e_lo = self.eps_p[k];
            s_lo = self.sigma_y[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_point() {
        let e = HardeningTable::from_total_strain(
            1000.0,
            &[[0.0, 0.0], [0.001, 1.0], [0.002, 50.0], [0.002, 50.0]],
        )
        .unwrap_err();
        assert!(
            e.contains("point 3") && e.contains("strain must increase"),
            "{e}"
        );
        assert!(HardeningTable::from_total_strain(1000.0, &[]).is_err());
        assert!(
            HardeningTable::from_total_strain(1000.0, &[[0.001, 1.0], [0.002, 0.5]])
                .unwrap_err()
                .contains("point 1")
        );
        assert!(HardeningTable::from_total_strain(1000.0, &[[0.001, -1.0]]).is_err());
        // first point clearly plastic (not at initial yield)
        assert!(HardeningTable::from_total_strain(1000.0, &[[0.002, 1.0]]).is_err());
        assert!(HardeningTable::from_plastic_strain(&[[0.0, 10.0], [0.1, 9.0]]).is_err());
    }

    #[test]
    fn return_map_on_table() {
        let t = HardeningTable::from_plastic_strain(&[[0.0, 100.0], [0.01, 110.0], [0.03, 120.0]])
            .unwrap();
        let three_g = 3000.0;
        for &q_tr in &[105.0, 150.0, 400.0] {
            let (dg, h) = t.return_map(three_g, q_tr, 0.0);
            let (sy, hh) = t.eval(dg);
            assert!((q_tr - three_g * dg - sy).abs() < 1e-10);
            assert_eq!(h, hh);
        }
        assert_eq!(t.return_map(three_g, 99.0, 0.0).0, 0.0);
    }
}
