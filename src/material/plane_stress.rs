//! Plane stress for every law: the through-thickness condition σ₃₃ = 0 solved in the update.
//!
//! The element gives the in-plane deformation gradient F₂ (2×2). [`PlaneStress`] wraps a law
//! and finds the thickness stretch λ₃ = F₃₃ for which the whole Kirchhoff stress
//! τ₃₃ = τ′₃₃(F) + τ_v vanishes, τ′ the law's deviatoric stress at F = diag(F₂, λ₃) and
//! τ_v = K ln J the volumetric one (J = λ₃ det F₂, K the bulk modulus; an incompressible law,
//! ν = 0.5, takes K = [`INCOMPRESSIBLE_BULK`] G, so that J = 1 to σ/(10⁴ G)). Newton on ln λ₃
//! with the derivative ∂τ′₃₃/∂ ln λ₃ by central differences, to |τ₃₃| ≤ 1e-12 (G + K).
//!
//! It returns the whole in-plane Kirchhoff stress (τ₃₃ = 0; the element then carries no
//! mean-dilatation pressure of its own: plane stress does not lock), λ₃ (so that the element
//! reports the Cauchy stress τ / (λ₃ det F₂)), the law's new state, and the in-plane spatial
//! tangent condensed on σ₃₃ = 0: with c the whole 4×4 spatial tangent (rows τ
//! `[xx, yy, xy, zz]`, columns d `[xx, yy, 2xy, zz]`),
//! c_ps = c_ab − c_a3 c_3b / c_33, because L_v τ₃₃ = τ̇₃₃ = 0 at τ₃₃ = 0. The law gives the
//! in-plane block of its deviatoric part; its zz row and column are central differences of its
//! stress under F → (I + h l) F (l = the in-plane basis rates for the row, e₃ ⊗ e₃ for the
//! column, whose Lie derivative adds −2 τ′₃₃ to c_33); the volumetric part's is exact:
//! K m ⊗ m − 2 τ_v I (m = [1, 1, 0, 1], I with ½ for the shear).
//!
//! Cost: about eighteen calls of the law per Gauss point instead of one.

use super::{ConstitutiveLaw, MatResponse, MatState, MaterialError, TimeIncrement};
use nalgebra::Matrix3;

/// The bulk modulus an incompressible law (ν = 0.5) takes in plane stress, times its shear
/// modulus.
pub const INCOMPRESSIBLE_BULK: f64 = 1e4;

/// The law `law` in plane stress (see the module docs).
pub struct PlaneStress<'a> {
    pub law: &'a dyn ConstitutiveLaw,
}

impl PlaneStress<'_> {
    fn bulk(&self) -> f64 {
        self.law.bulk_modulus().unwrap_or(INCOMPRESSIBLE_BULK * self.law.shear_modulus())
    }
}

/// diag(F₂, λ₃) with λ₃ = exp(e3).
fn with_thickness(ff: &Matrix3<f64>, e3: f64) -> Matrix3<f64> {
    let mut f = *ff;
    f[(0, 2)] = 0.0;
    f[(1, 2)] = 0.0;
    f[(2, 0)] = 0.0;
    f[(2, 1)] = 0.0;
    f[(2, 2)] = e3.exp();
    f
}

impl ConstitutiveLaw for PlaneStress<'_> {
    fn elastic_constants(&self) -> (f64, f64) {
        self.law.elastic_constants()
    }
    fn symmetric_tangent(&self) -> bool {
        self.law.symmetric_tangent()
    }
    /// `ff`: the in-plane F₂ (its F₃₃ is replaced by the λ₃ found here).
    fn update(&self, ff: &Matrix3<f64>, old: &MatState, inc: TimeIncrement) -> Result<MatResponse, MaterialError> {
        let (g, k) = (self.law.shear_modulus(), self.bulk());
        let det2 = ff[(0, 0)] * ff[(1, 1)] - ff[(0, 1)] * ff[(1, 0)];
        if !(det2 > 0.0) || !det2.is_finite() {
            return Err(MaterialError::InvertedElement(det2));
        }
        let ln2 = det2.ln();
        let tau33 = |e3: f64| -> Result<(f64, MatResponse), MaterialError> {
            let r = self.law.update(&with_thickness(ff, e3), old, inc)?;
            Ok((r.tau[3] + k * (e3 + ln2), r))
        };
        // start from the elastic thickness strain of small-strain plane stress
        let (_, nu) = self.law.elastic_constants();
        let mut e3 = -nu / (1.0 - nu) * ln2;
        let tol = 1e-12 * (g + k);
        const H: f64 = 1e-6;
        let mut converged = None;
        for _ in 0..50 {
            let (t, r) = tau33(e3)?;
            if t.abs() <= tol {
                converged = Some(r);
                break;
            }
            let slope = (tau33(e3 + H)?.0 - tau33(e3 - H)?.0) / (2.0 * H);
            if !(slope > 0.0) {
                return Err(MaterialError::ReturnMapFailed { iterations: 0, residual: t });
            }
            e3 -= t / slope;
        }
        let Some(r) = converged else {
            let (t, _) = tau33(e3)?;
            return Err(MaterialError::ReturnMapFailed { iterations: 50, residual: t });
        };
        let tv = k * (e3 + ln2);
        // the whole 4×4 spatial tangent: the law's in-plane block, its zz row and column by
        // central differences, and the volumetric part
        let mut c = [[0.0; 4]; 4];
        for a in 0..3 {
            for b in 0..3 {
                c[a][b] = r.cc[a][b];
            }
        }
        let (plus, minus) = (self.law.update(&with_thickness(ff, e3 + H), old, inc)?, self.law.update(&with_thickness(ff, e3 - H), old, inc)?);
        for a in 0..4 {
            c[a][3] = (plus.tau[a] - minus.tau[a]) / (2.0 * H);
        }
        c[3][3] -= 2.0 * r.tau[3];
        let f3 = with_thickness(ff, e3);
        for (b, l) in [[[1.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 1.0]], [[0.0, 0.5], [0.5, 0.0]]].iter().enumerate() {
            let lm = Matrix3::new(l[0][0], l[0][1], 0.0, l[1][0], l[1][1], 0.0, 0.0, 0.0, 0.0);
            let fp = (Matrix3::identity() + lm * H) * f3;
            let fm = (Matrix3::identity() - lm * H) * f3;
            c[3][b] = (self.law.update(&fp, old, inc)?.tau[3] - self.law.update(&fm, old, inc)?.tau[3]) / (2.0 * H);
        }
        let m = [1.0, 1.0, 0.0, 1.0];
        let half = [1.0, 1.0, 0.5, 1.0];
        for a in 0..4 {
            for b in 0..4 {
                c[a][b] += k * m[a] * m[b];
            }
            c[a][a] -= 2.0 * tv * half[a];
        }
        let mut cc = [[0.0; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                cc[a][b] = c[a][b] - c[a][3] * c[3][b] / c[3][3];
            }
        }
        Ok(MatResponse { tau: [r.tau[0] + tv, r.tau[1] + tv, r.tau[2], 0.0], cc, state: r.state, thickness: e3.exp() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Creep, CreepParams, Elastic, HardeningTable, J2Plastic, Material};

    /// The condensed tangent against central differences of the wrapper's own stress (which
    /// re-solves the thickness for each perturbed F₂): cc : sym l = A − l τ − τ lᵀ on the
    /// in-plane components, for the three symmetric in-plane basis rates, at deformed states
    /// that are elastic, plastic and creeping; 1e-5 of the largest entry (the inner and outer
    /// differences, h = 1e-6 and 1e-5). Also τ_zz = 0 and a positive thickness.
    #[test]
    fn the_condensed_tangent_is_the_derivative_of_the_plane_stress_response() {
        let table = HardeningTable::from_total_strain(70_000.0, &[[240.0 / 70_000.0, 240.0], [0.5, 400.0]]).unwrap();
        let laws = [
            ("elastic", Material::Elastic(Elastic::new(1000.0, 0.3)), 1.0),
            ("elastic, nu = 0.5", Material::Elastic(Elastic::new(526.0, 0.5)), 1.0),
            ("J2", Material::J2(J2Plastic::new(70_000.0, 0.3, table)), 1.0),
            ("creep", Material::Creep(Creep::new(526.0, 0.5, CreepParams::asphalt_table2(1e6))), 2.0),
        ];
        let states = [Matrix3::new(1.002, 0.001, 0.0, -0.0005, 0.999, 0.0, 0.0, 0.0, 1.0), Matrix3::new(1.03, 0.01, 0.0, 0.004, 0.985, 0.0, 0.0, 0.0, 1.0)];
        for (name, law, dt) in &laws {
            let ps = PlaneStress { law };
            let inc = TimeIncrement { time: *dt, dt: *dt };
            let old = MatState::default();
            for f in &states {
                let r = ps.update(f, &old, inc).unwrap();
                assert!(r.tau[3] == 0.0 && r.thickness > 0.0);
                let scale = r.cc.iter().flatten().fold(0.0f64, |a, b| a.max(b.abs()));
                const EPS: f64 = 1e-5;
                for (b, l) in [[[1.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 1.0]], [[0.0, 0.5], [0.5, 0.0]]].iter().enumerate() {
                    let lm = Matrix3::new(l[0][0], l[0][1], 0.0, l[1][0], l[1][1], 0.0, 0.0, 0.0, 0.0);
                    let tp = ps.update(&((Matrix3::identity() + lm * EPS) * f), &old, inc).unwrap().tau;
                    let tm = ps.update(&((Matrix3::identity() - lm * EPS) * f), &old, inc).unwrap().tau;
                    let t = Matrix3::new(r.tau[0], r.tau[2], 0.0, r.tau[2], r.tau[1], 0.0, 0.0, 0.0, 0.0);
                    let corr = lm * t + t * lm.transpose();
                    let fd = [
                        (tp[0] - tm[0]) / (2.0 * EPS) - corr[(0, 0)],
                        (tp[1] - tm[1]) / (2.0 * EPS) - corr[(1, 1)],
                        (tp[2] - tm[2]) / (2.0 * EPS) - corr[(0, 1)],
                    ];
                    for a in 0..3 {
                        assert!((r.cc[a][b] - fd[a]).abs() <= 1e-5 * scale, "{name}, F = {f:?}: cc[{a}][{b}] = {} vs {}", r.cc[a][b], fd[a]);
                    }
                }
            }
        }
    }
}
