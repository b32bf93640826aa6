//! Logarithmic-strain kinematics and the exponential-map return for plane strain.
//!
//! ## Kinematics (de Souza Neto, Perić & Owen 2008, ch. 14; Eterovic & Bathe 1990; Weber & Anand 1990)
//! With the committed inverse plastic right Cauchy–Green tensor C_p⁻¹, the trial elastic left
//! Cauchy–Green tensor is
//!
//! ```text
//!   b_e^tr = F C_p⁻¹ Fᵀ,          ε_e^tr = ½ ln b_e^tr.
//! ```
//!
//! Inelastic flow is isochoric and of von Mises type, so the return map is the small-strain
//! radial return applied to ε_e^tr (principal axes do not rotate during the return). The
//! updated elastic strain gives b_e = exp(2 ε_e) and the new history C_p⁻¹ = F⁻¹ b_e F⁻ᵀ.
//!
//! ## Plane strain
//! F has F₃₃ = 1 (any positive F₃₃ is accepted) and no out-of-plane shear, so z is always a
//! principal direction of b. Symmetric tensors are stored as [`Sym4`] = `[xx, yy, xy, zz]`
//! (tensor components, not engineering shear). The in-plane 2×2 eigenproblem is solved in
//! closed form: with m = ½(b_xx + b_yy), r = √(¼(b_xx − b_yy)² + b_xy²),
//! λ₁,₂ = m ± r and the first eigenvector at angle θ = ½ atan2(b_xy, ½(b_xx − b_yy)).
//!
//! ## Spatial tangent
//! A perturbation F → F + ε l F (history fixed) gives δb^tr = l b^tr + b^tr lᵀ, hence
//!
//! ```text
//!   A := δτ′ = D : ½ L : (l b + b lᵀ),    L = ∂ ln b / ∂b,
//!   cc : d = A − l τ′ − τ′ lᵀ             (Lie derivative of τ′, d = sym l),
//! ```
//!
//! where D = ∂τ′/∂ε_e^tr is the consistent (algorithmic) tangent of the small-strain return map.
//! L is the derivative of the isotropic tensor function ln: in the eigenbasis of b, the
//! component (i, j) of L : δb equals f⁽¹⁾(λᵢ, λⱼ) δb′ᵢⱼ with the divided difference
//! f⁽¹⁾(λᵢ, λⱼ) = (ln λᵢ − ln λⱼ)/(λᵢ − λⱼ), and its limit 1/λᵢ for equal eigenvalues
//! (see [`log_divided_difference`]). For an isotropic law the skew part of l drops out exactly
//! (objectivity), and τ′ and D are coaxial with b, so `cc` is formed in the eigenbasis of b,
//! where it is a 2 × 2 block on the normal components and one shear entry, and turned to x, y
//! ([`spatial_tangent`]; a unit test checks it against the column-by-column evaluation of the
//! formula above on the basis velocity gradients l = e_xx, e_yy and l_xy = l_yx = ½).
// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::{Matrix2, Matrix3};

use super::MaterialError;

/// Symmetric tensor with plane-strain structure, `[xx, yy, xy, zz]` (tensor components).
pub type Sym4 = [f64; 4];

/// The identity in [`Sym4`] layout.
pub const IDENTITY: Sym4 = [1.0, 1.0, 0.0, 1.0];

/// Double contraction a : b of two [`Sym4`] tensors (the shear counts twice).
#[inline]
pub fn ddot(a: &Sym4, b: &Sym4) -> f64 {
    a[0] * b[0] + a[1] * b[1] + 2.0 * a[2] * b[2] + a[3] * b[3]
}

/// Deviatoric part a − ⅓ tr(a) I.
#[inline]
pub fn dev(a: &Sym4) -> Sym4 {
    let m = (a[0] + a[1] + a[3]) / 3.0;
    [a[0] - m, a[1] - m, a[2], a[3] - m]
}

/// Checks that F is admissible: finite entries and det F > 0 (plane strain:
/// det F = (F_xx F_yy − F_xy F_yx) F_zz). Returns det F.
pub fn check_deformation(ff: &Matrix3<f64>) -> Result<f64, MaterialError> {
    let det = (ff[(0, 0)] * ff[(1, 1)] - ff[(0, 1)] * ff[(1, 0)]) * ff[(2, 2)];
    if !(det > 0.0) || !det.is_finite() || ff.iter().any(|v| !v.is_finite()) {
        return Err(MaterialError::InvertedElement(det));
    }
    Ok(det)
}

#[inline]
fn to_m2(t: &Sym4) -> Matrix2<f64> {
    Matrix2::new(t[0], t[2], t[2], t[1])
}

#[inline]
fn in_plane(ff: &Matrix3<f64>) -> Matrix2<f64> {
    Matrix2::new(ff[(0, 0)], ff[(0, 1)], ff[(1, 0)], ff[(1, 1)])
}

/// Trial elastic left Cauchy–Green tensor b = F C_p⁻¹ Fᵀ (plane strain: b_zz = F_zz² C_p⁻¹_zz).
pub fn left_cauchy_green(ff: &Matrix3<f64>, cp_inv: &Sym4) -> Sym4 {
    let f2 = in_plane(ff);
    let b2 = f2 * to_m2(cp_inv) * f2.transpose();
    let fzz = ff[(2, 2)];
    [
        b2[(0, 0)],
        b2[(1, 1)],
        0.5 * (b2[(0, 1)] + b2[(1, 0)]),
        fzz * fzz * cp_inv[3],
    ]
}

/// Pull-back of an elastic left Cauchy–Green tensor to the history variable:
/// C_p⁻¹ = F⁻¹ b_e F⁻ᵀ. Requires det F > 0 (checked by the caller).
pub fn cp_inv_from_be(ff: &Matrix3<f64>, be: &Sym4) -> Sym4 {
    let f2 = in_plane(ff);
    let det = f2[(0, 0)] * f2[(1, 1)] - f2[(0, 1)] * f2[(1, 0)];
    let finv = Matrix2::new(f2[(1, 1)], -f2[(0, 1)], -f2[(1, 0)], f2[(0, 0)]) / det;
    let c2 = finv * to_m2(be) * finv.transpose();
    let fzz = ff[(2, 2)];
    [
        c2[(0, 0)],
        c2[(1, 1)],
        0.5 * (c2[(0, 1)] + c2[(1, 0)]),
        be[3] / (fzz * fzz),
    ]
}

/// Divided difference of the logarithm, (ln λ₁ − ln λ₂)/(λ₁ − λ₂) for λ₁, λ₂ > 0.
///
/// Written as ln(1 + u)/(λ₁ − λ₂) with u = (λ₁ − λ₂)/λ₂ (`ln_1p` keeps full precision for
/// nearby eigenvalues); for |u| < 10⁻⁴ the series (1 − u/2 + u²/3 − u³/4)/λ₂ is used
/// (truncation error below u⁴/5 ≈ 2·10⁻¹⁷), whose limit u → 0 is the derivative 1/λ.
#[inline]
pub fn log_divided_difference(l1: f64, l2: f64) -> f64 {
    let d = l1 - l2;
    let u = d / l2;
    if u.abs() < 1e-4 {
        (1.0 - u * (0.5 - u * (1.0 / 3.0 - 0.25 * u))) / l2
    } else {
        u.ln_1p() / d
    }
}

/// Spectral decomposition of a plane-strain symmetric tensor: in-plane eigenvalues
/// λ₁ = m + r ≥ λ₂ = m − r with eigenvectors n₁ = (cos θ, sin θ), n₂ = (−sin θ, cos θ),
/// and λ₃ = t_zz along e_z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spectral {
    pub lam: [f64; 3],
    pub cos: f64,
    pub sin: f64,
}

impl Spectral {
    /// Closed-form eigen-decomposition: θ = ½ atan2(t_xy, ½(t_xx − t_yy)) ∈ (−π/2, π/2]
    /// (θ = 0 when the in-plane eigenvalues coincide), its cosine and sine taken from
    /// cos 2θ = ½(t_xx − t_yy)/r and sin 2θ = t_xy/r by the half-angle formulas, each where
    /// it has no cancellation (cos θ ≥ 1/√2 when t_xx ≥ t_yy, |sin θ| > 1/√2 otherwise). No
    /// trigonometric call: they were a third of the law's time (docs/performance.md).
    pub fn of(t: &Sym4) -> Self {
        let m = 0.5 * (t[0] + t[1]);
        let half_diff = 0.5 * (t[0] - t[1]);
        // (the components are strains or stretches of order one: no overflow to guard against)
        let r = (half_diff * half_diff + t[2] * t[2]).sqrt();
        let (cos, sin) = if !(r > 0.0) {
            (1.0, 0.0)
        } else if half_diff >= 0.0 {
            let c = ((r + half_diff) / (2.0 * r)).sqrt();
            (c, t[2] / (2.0 * r * c))
        } else {
            let s = ((r - half_diff) / (2.0 * r)).sqrt().copysign(t[2]);
            (t[2] / (2.0 * r * s), s)
        };
        Self { lam: [m + r, m - r, t[3]], cos, sin }
    }

    /// t = R t′ Rᵀ from its components in the eigenbasis, `[t′₁₁, t′₂₂, t′₁₂, t_zz]`.
    #[inline]
    pub fn from_principal(&self, p: &Sym4) -> Sym4 {
        let (c, s) = (self.cos, self.sin);
        let (cc, ss, cs) = (c * c, s * s, c * s);
        [
            cc * p[0] - 2.0 * cs * p[2] + ss * p[1],
            ss * p[0] + 2.0 * cs * p[2] + cc * p[1],
            cs * (p[0] - p[1]) + (cc - ss) * p[2],
            p[3],
        ]
    }

    /// Σᵢ vᵢ nᵢ ⊗ nᵢ: the coaxial tensor with principal values `v`.
    #[inline]
    pub fn compose(&self, v: [f64; 3]) -> Sym4 {
        self.from_principal(&[v[0], v[1], 0.0, v[2]])
    }
}

/// Hencky strain ε = ½ ln b of a symmetric positive definite plane-strain tensor.
pub fn hencky_strain(b: &Sym4) -> Sym4 {
    let sp = Spectral::of(b);
    sp.compose([
        0.5 * sp.lam[0].ln(),
        0.5 * sp.lam[1].ln(),
        0.5 * sp.lam[2].ln(),
    ])
}

/// Consistent tangent of a von Mises radial return on the deviatoric part, as a map from a
/// log-strain increment dε to dτ′ (de Souza Neto et al. 2008, Box 7.4):
///
/// ```text
///   D = 2G (1 − 3GΔγ/q_tr) I_dev + 6G² (Δγ/q_tr − 1/(3G + H)) N̂ ⊗ N̂,   N̂ = s_tr/‖s_tr‖,
/// ```
///
/// H = dq/dΔγ at the converged point (hardening slope, or the effective creep slope).
/// Elastic: D = 2G I_dev. N̂ is coaxial with b^tr and kept as its principal values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DevTangent {
    /// 2G (1 − 3GΔγ/q_tr).
    pub two_g_beta: f64,
    /// 6G² (Δγ/q_tr − 1/(3G + H)).
    pub coef_nn: f64,
    /// N̂'s principal values `[n₁, n₂, n₃]` in the eigenbasis of b^tr (zero when elastic).
    pub n_hat: [f64; 3],
}

impl DevTangent {
    /// Elastic D = 2G I_dev.
    pub fn elastic(g: f64) -> Self {
        Self {
            two_g_beta: 2.0 * g,
            coef_nn: 0.0,
            n_hat: [0.0; 3],
        }
    }
}

/// Spatial tangent `cc` (rows τ′ `[xx, yy, xy]`, columns `[d_xx, d_yy, 2 d_xy]`) from the
/// decomposition of b^tr, the principal values `tau` of the stress τ′ (coaxial with b^tr) and
/// the return-map tangent D: cc : d = D : ½ L : (d b + b d) − (d τ′ + τ′ d) (module docs).
///
/// Formed in the eigenbasis of b^tr, where b = diag(λ₁, λ₂), τ′ and N̂ are diagonal: for a
/// symmetric d there, ½ L : (d b + b d) has the normal components d₁₁, d₂₂ and the shear
/// ½ f⁽¹⁾(λ₁, λ₂)(λ₁ + λ₂) d₁₂, so the tangent is a 2 × 2 block on the normal components,
/// ```text
///   c₁₁ = ⅔ 2Gβ + k n₁² − 2τ₁,   c₂₂ = ⅔ 2Gβ + k n₂² − 2τ₂,   c₁₂ = −⅓ 2Gβ + k n₁ n₂,
/// ```
/// (k = 6G²(Δγ/q_tr − 1/(3G + H))) and the shear entry ½(½ 2Gβ f⁽¹⁾ (λ₁ + λ₂) − (τ₁ + τ₂)) per
/// engineering shear; then turned to x, y by the congruence with the strain's rotation.
pub fn spatial_tangent(sp: &Spectral, tau: &[f64; 3], d: &DevTangent) -> [[f64; 3]; 3] {
    let [l1, l2, _] = sp.lam;
    let (gb, k) = (d.two_g_beta, d.coef_nn);
    let [n1, n2, _] = d.n_hat;
    let a00 = 2.0 / 3.0 * gb + k * n1 * n1 - 2.0 * tau[0];
    let a11 = 2.0 / 3.0 * gb + k * n2 * n2 - 2.0 * tau[1];
    let a01 = -gb / 3.0 + k * n1 * n2;
    let g = 0.5 * (0.5 * gb * log_divided_difference(l1, l2) * (l1 + l2) - (tau[0] + tau[1]));
    // rows of the map from [d_xx, d_yy, 2 d_xy] to the eigenbasis's [d₁₁, d₂₂, 2 d₁₂]
    let (c, s) = (sp.cos, sp.sin);
    let (cc, ss, cs) = (c * c, s * s, c * s);
    let e1 = [cc, ss, cs];
    let e2 = [ss, cc, -cs];
    let e3 = [-2.0 * cs, 2.0 * cs, cc - ss];
    let mut out = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = a00 * e1[i] * e1[j] + a01 * (e1[i] * e2[j] + e2[i] * e1[j]) + a11 * e2[i] * e2[j] + g * e3[i] * e3[j];
        }
    }
    out
}

/// Outcome of [`exponential_map_update`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReturnOutcome {
    /// Deviatoric Kirchhoff stress τ′ `[xx, yy, xy, zz]`.
    pub tau: Sym4,
    /// Spatial tangent (see [`spatial_tangent`]).
    pub cc: [[f64; 3]; 3],
    /// Updated C_p⁻¹ (the old one, bit for bit, when the step is elastic).
    pub cp_inv: Sym4,
    /// Equivalent inelastic strain increment Δγ (0 when elastic).
    pub dgamma: f64,
    /// Trial von Mises equivalent stress q_tr = √(3/2) ‖s_tr‖.
    pub q_trial: f64,
}

/// Exponential-map update for an isochoric von Mises law with shear modulus `g`.
///
/// `solve(q_tr)` is the law's scalar return: it returns the equivalent inelastic increment Δγ
/// (0 for an elastic step) and the slope H = dq/dΔγ at the solution, where the relaxed
/// equivalent stress is q = q_tr − 3GΔγ. Then, in the principal frame of b^tr,
///
/// ```text
///   ε_tr = ½ ln λ,  s_tr = 2G dev ε_tr,  τ′ = (1 − 3GΔγ/q_tr) s_tr,
///   ε_e = ε_tr − Δγ (3/2) s_tr/q_tr,  b_e = exp(2 ε_e),  C_p⁻¹ = F⁻¹ b_e F⁻ᵀ,
/// ```
///
/// and the tangent is [`spatial_tangent`] with the [`DevTangent`] of Box 7.4.
pub fn exponential_map_update<S>(
    ff: &Matrix3<f64>,
    cp_inv: &Sym4,
    g: f64,
    solve: S,
) -> Result<ReturnOutcome, MaterialError>
where
    S: FnOnce(f64) -> Result<(f64, f64), MaterialError>,
{
    check_deformation(ff)?;
    let b = left_cauchy_green(ff, cp_inv);
    let sp = Spectral::of(&b);
    if !(sp.lam[1] > 0.0 && sp.lam[2] > 0.0) {
        // C_p⁻¹ not positive definite (corrupted history) or a degenerate F.
        return Err(MaterialError::InvertedElement(sp.lam[1].min(sp.lam[2])));
    }
    let eps = [
        0.5 * sp.lam[0].ln(),
        0.5 * sp.lam[1].ln(),
        0.5 * sp.lam[2].ln(),
    ];
    let mean = (eps[0] + eps[1] + eps[2]) / 3.0;
    let s_tr = [
        2.0 * g * (eps[0] - mean),
        2.0 * g * (eps[1] - mean),
        2.0 * g * (eps[2] - mean),
    ];
    let norm_s = (s_tr[0] * s_tr[0] + s_tr[1] * s_tr[1] + s_tr[2] * s_tr[2]).sqrt();
    let q_tr = (1.5f64).sqrt() * norm_s;
    let (dgamma, h) = solve(q_tr)?;

    if !(dgamma > 0.0) || !(q_tr > 0.0) {
        let tau = sp.compose(s_tr);
        let d = DevTangent::elastic(g);
        let cc = spatial_tangent(&sp, &s_tr, &d);
        return Ok(ReturnOutcome {
            tau,
            cc,
            cp_inv: *cp_inv,
            dgamma: 0.0,
            q_trial: q_tr,
        });
    }

    let beta = 1.0 - 3.0 * g * dgamma / q_tr;
    let s = [beta * s_tr[0], beta * s_tr[1], beta * s_tr[2]];
    let tau = sp.compose(s);
    let flow = 1.5 * dgamma / q_tr;
    let be_p = [
        (2.0 * (eps[0] - flow * s_tr[0])).exp(),
        (2.0 * (eps[1] - flow * s_tr[1])).exp(),
        (2.0 * (eps[2] - flow * s_tr[2])).exp(),
    ];
    let be = sp.compose(be_p);
    let cp_new = cp_inv_from_be(ff, &be);

    let n_hat = [s_tr[0] / norm_s, s_tr[1] / norm_s, s_tr[2] / norm_s];
    let inv_3g_h = if h.is_finite() {
        1.0 / (3.0 * g + h)
    } else {
        0.0
    };
    let d = DevTangent {
        two_g_beta: 2.0 * g * beta,
        coef_nn: 6.0 * g * g * (dgamma / q_tr - inv_3g_h),
        n_hat,
    };
    let cc = spatial_tangent(&sp, &s, &d);
    Ok(ReturnOutcome {
        tau,
        cc,
        cp_inv: cp_new,
        dgamma,
        q_trial: q_tr,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spectral_roundtrip_and_log() {
        let t = [2.0, 0.5, 0.3, 1.2];
        let sp = Spectral::of(&t);
        let back = sp.compose(sp.lam);
        for i in 0..4 {
            assert!((back[i] - t[i]).abs() < 1e-14);
        }
        // exp(2 ε) recovers b
        let e = hencky_strain(&t);
        let se = Spectral::of(&e);
        let b = se.compose([
            (2.0 * se.lam[0]).exp(),
            (2.0 * se.lam[1]).exp(),
            (2.0 * se.lam[2]).exp(),
        ]);
        for i in 0..4 {
            assert!((b[i] - t[i]).abs() < 1e-13);
        }
    }

    #[test]
    fn divided_difference_is_continuous() {
        let l2 = 1.3;
        for k in 0..12 {
            let d = 10f64.powi(-k);
            let exact = ((l2 + d).ln() - l2.ln()) / d;
            let got = log_divided_difference(l2 + d, l2);
            assert!(
                (got - exact).abs() < 1e-12 + 1e-16 / d,
                "d={d}: {got} vs {exact}"
            );
        }
        assert_eq!(log_divided_difference(l2, l2), 1.0 / l2);
    }

    /// A small deterministic generator of values in [−1, 1) for the sweeps below.
    fn sweep(n: usize) -> impl Iterator<Item = f64> {
        let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
        (0..n).map(move |_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            2.0 * ((seed >> 11) as f64 / (1u64 << 53) as f64) - 1.0
        })
    }

    #[test]
    fn eigenvectors_by_half_angles_are_those_of_atan2() {
        // Reference: θ = ½ atan2(t_xy, ½(t_xx − t_yy)), cos θ and sin θ by libm (the former
        // implementation); tolerance 4 ulp of one. Includes every sign of the shear with
        // t_xx above, equal to and below t_yy, and the coincident eigenvalues.
        let mut cases: Vec<Sym4> = vec![[1.0, 1.0, 0.0, 1.0], [2.0, 1.0, 0.0, 1.0], [1.0, 2.0, 0.0, 1.0], [1.0, 2.0, -0.0, 1.0], [1.5, 1.5, 0.2, 1.0], [1.5, 1.5, -0.2, 1.0], [1.0, 1.0 + 1e-12, 1e-13, 1.0]];
        let v: Vec<f64> = sweep(3000).collect();
        cases.extend(v.chunks(3).map(|c| [1.0 + 0.5 * c[0], 1.0 + 0.5 * c[1], 0.5 * c[2], 1.0]));
        for t in cases {
            let sp = Spectral::of(&t);
            let theta = 0.5 * t[2].atan2(0.5 * (t[0] - t[1]));
            let (c, s) = if t[0] == t[1] && t[2] == 0.0 { (1.0, 0.0) } else { (theta.cos(), theta.sin()) };
            assert!((sp.cos - c).abs() <= 4.0 * f64::EPSILON && (sp.sin - s).abs() <= 4.0 * f64::EPSILON, "{t:?}: ({}, {}) against ({c}, {s})", sp.cos, sp.sin);
            assert!((sp.cos * sp.cos + sp.sin * sp.sin - 1.0).abs() <= 4.0 * f64::EPSILON);
            // t n₁ = λ₁ n₁ and t n₂ = λ₂ n₂
            let (n1, n2) = ([sp.cos, sp.sin], [-sp.sin, sp.cos]);
            for (n, l) in [(n1, sp.lam[0]), (n2, sp.lam[1])] {
                let tn = [t[0] * n[0] + t[2] * n[1], t[2] * n[0] + t[1] * n[1]];
                assert!((tn[0] - l * n[0]).abs() <= 1e-14 && (tn[1] - l * n[1]).abs() <= 1e-14, "{t:?}");
            }
        }
    }

    /// Components of `t` in the eigenbasis of `sp`: `[t′₁₁, t′₂₂, t′₁₂, t_zz]` (t′ = Rᵀ t R).
    fn to_principal(sp: &Spectral, t: &Sym4) -> Sym4 {
        let (c, s) = (sp.cos, sp.sin);
        let (cc, ss, cs) = (c * c, s * s, c * s);
        [cc * t[0] + 2.0 * cs * t[2] + ss * t[1], ss * t[0] - 2.0 * cs * t[2] + cc * t[1], cs * (t[1] - t[0]) + (cc - ss) * t[2], t[3]]
    }

    /// L : δb, the directional derivative of ln b (b the tensor `sp` decomposes, all λ > 0):
    /// f⁽¹⁾(λᵢ, λⱼ) δb′ᵢⱼ in the eigenbasis (module docs).
    fn dlog(sp: &Spectral, db: &Sym4) -> Sym4 {
        let p = to_principal(sp, db);
        let [l1, l2, l3] = sp.lam;
        sp.from_principal(&[p[0] / l1, p[1] / l2, log_divided_difference(l1, l2) * p[2], p[3] / l3])
    }

    /// The spatial tangent evaluated as the module docs define it, column by column on the
    /// basis velocity gradients (the former implementation): A = D : ½ L : (l b + b lᵀ) minus
    /// the Lie terms l τ′ + τ′ lᵀ.
    fn tangent_by_columns(sp: &Spectral, b: &Sym4, tau: &Sym4, d: &DevTangent) -> [[f64; 3]; 3] {
        let n = sp.compose(d.n_hat);
        let basis: [Sym4; 3] = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.5, 0.0]];
        let mut cc = [[0.0; 3]; 3];
        for (j, l) in basis.iter().enumerate() {
            // l is symmetric here: l b + b l and l τ′ + τ′ l in [xx, yy, xy] components
            let sym = |a: &Sym4| [2.0 * (l[0] * a[0] + l[2] * a[2]), 2.0 * (l[2] * a[2] + l[1] * a[1]), l[0] * a[2] + l[2] * a[1] + a[0] * l[2] + a[2] * l[1], 0.0];
            let dl = dlog(sp, &sym(b));
            let de = [0.5 * dl[0], 0.5 * dl[1], 0.5 * dl[2], 0.5 * dl[3]];
            let dv = dev(&de);
            let nn = d.coef_nn * ddot(&n, &de);
            let lie = sym(tau);
            for i in 0..3 {
                cc[i][j] = d.two_g_beta * dv[i] + nn * n[i] - lie[i];
            }
        }
        cc
    }

    #[test]
    fn the_tangent_in_the_eigenbasis_is_the_tangent_by_columns() {
        // Elastic and plastic return tangents at stretched, sheared and rotated b, including
        // coincident in-plane eigenvalues; tolerance 1e-12 of the largest entry (round-off).
        let v: Vec<f64> = sweep(4000).collect();
        let mut bs: Vec<Sym4> = vec![[1.0, 1.0, 0.0, 1.0], [1.2, 1.2, 0.0, 0.7], [0.8, 0.8 + 1e-9, 0.0, 1.1]];
        bs.extend(v.chunks(4).map(|c| [1.0 + 0.6 * c[0], 1.0 + 0.6 * c[1], 0.3 * c[2], 1.0 + 0.3 * c[3]]));
        for (k, b) in bs.iter().enumerate() {
            let sp = Spectral::of(b);
            let g = 26_000.0;
            let eps = sp.lam.map(|l| 0.5 * l.ln());
            let m = (eps[0] + eps[1] + eps[2]) / 3.0;
            let s_tr = eps.map(|e| 2.0 * g * (e - m));
            let norm = (s_tr.iter().map(|x| x * x).sum::<f64>()).sqrt().max(1e-300);
            let plastic = k % 2 == 1;
            let (beta, d) = if plastic {
                let beta = 0.6;
                (beta, DevTangent { two_g_beta: 2.0 * g * beta, coef_nn: 6.0 * g * g * (0.4 / (3.0 * g) - 1.0 / (3.0 * g + 500.0)), n_hat: s_tr.map(|x| x / norm) })
            } else {
                (1.0, DevTangent::elastic(g))
            };
            let tau_p = s_tr.map(|x| beta * x);
            let fast = spatial_tangent(&sp, &tau_p, &d);
            let slow = tangent_by_columns(&sp, b, &sp.compose(tau_p), &d);
            let scale = slow.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
            for i in 0..3 {
                for j in 0..3 {
                    assert!((fast[i][j] - slow[i][j]).abs() <= 1e-12 * scale, "b = {b:?} ({i}, {j}): {} against {}", fast[i][j], slow[i][j]);
                }
            }
        }
    }
}
