//! The four-node isoparametric plane-strain element in Bathe's incremental form, total and
//! updated Lagrangian, with a mean-dilatation (Q1/P0) volumetric part that does not lock.
//! Plane stress is the same element with the law wrapped in
//! [`crate::material::plane_stress::PlaneStress`] (which returns the whole in-plane stress and
//! the thickness stretch) and no mean-dilatation pressure; small strains are
//! [`evaluate_linear`].
//!
//! ## Deviatoric part (per Gauss point, 2×2 Gauss rule)
//! The law returns the deviatoric Kirchhoff stress τ′ and its spatial tangent c (see
//! [`crate::material`]). With N_a the bilinear shape functions:
//!
//! - **Total Lagrangian** (paper eq. 5–11; Bathe ch. 6.3): second Piola–Kirchhoff stress
//!   S = F⁻¹ τ′ F⁻ᵀ and material tangent D = T c Tᵀ (T the Voigt push-back of F⁻¹), with
//!   `₀B_L` (3×8, rows δE₁₁, δE₂₂, 2δE₁₂, holding the initial-displacement effect through F)
//!   and `₀B_NL` (4×8, rows ∂u₁/∂X₁, ∂u₁/∂X₂, ∂u₂/∂X₁, ∂u₂/∂X₂):
//!   `F = ∫ B_Lᵀ Ŝ dV₀`, `K_L = ∫ B_Lᵀ D B_L dV₀`, `K_NL = ∫ B_NLᵀ [S 0; 0 S] B_NL dV₀`.
//! - **Updated Lagrangian** (paper eq. 12–17): Cauchy stress σ′ = τ′/J and tangent c/J on the
//!   current configuration, `ₜB_L` the small-strain operator in current coordinates:
//!   `F = ∫ B_Lᵀ σ̂′ dv`, `K_L = ∫ B_Lᵀ (c/J) B_L dv`, `K_NL = ∫ B_NLᵀ [σ′ 0; 0 σ′] B_NL dv`.
//!
//! The two are the same linearisation written in two configurations, so they agree to
//! round-off (a test checks it).
//!
//! ## Volumetric part (mean dilatation; Simo, Taylor & Pister 1985; Bathe's u/p with a
//! condensed constant pressure)
//! With v_e the current and V_e the reference element area (shoelace formula, exact for the
//! bilinear quadrilateral), j₀ the initial volume ratio of the element (see below; 1 for a
//! mesh built in the undeformed configuration) and Θ = j₀ v_e/V_e, the element stores the
//! volumetric energy `V̂_e U(Θ) + λ_e (v_e − V̂_e)` with V̂_e = V_e/j₀,
//! U(Θ) = ½ κ (ln Θ)², so the element pressure (Cauchy, mean stress, positive in tension) is
//! `p = λ_e + κ ln Θ / Θ`, giving Kirchhoff pressure κ ln Θ for λ_e = 0 as in Hencky
//! elasticity. Then
//! `f_vol = p g`, `K_vol = (U″(Θ)/V̂_e) g gᵀ + p H` with g = ∂v_e/∂x and H = ∂²v_e/∂x²
//! (constant).
//! - compressible law: κ = K (bulk modulus), λ_e = 0;
//! - incompressible law (ν = 0.5): κ is a penalty and λ_e an augmented-Lagrangian multiplier
//!   updated by the driver (Uzawa: λ_e ← p) until |Θ − 1| is below a tolerance.
//!
//! ## Initial volume ratio j₀ (re-meshing: reference configuration = a deformed one)
//! The laws return Kirchhoff stresses τ = J σ per unit volume of the *original* configuration
//! (the one in which Θ = 1 and C_p⁻¹ = I means stress free). When a particle is re-meshed in
//! its current configuration, the new reference configuration already carries the volume
//! ratio j₀ = Θ_old with respect to the original one, and the material history is pushed
//! forward (C_p⁻¹ := b_e of before, see [`crate::remesh::state`]). The element then works
//! with the total volume ratio j₀ J (J = det F relative to its own reference):
//! - volumetric part: Θ = j₀ v_e/V_e and reference area V̂_e = V_e/j₀ (above);
//! - deviatoric part: the law's τ′ is divided by j₀ before it enters the element, i.e. the
//!   Kirchhoff stress and its tangent relative to the element's reference configuration are
//!   τ′/j₀ and c/j₀; hence the Cauchy stress σ′ = τ′/(j₀ J), and TL (S = F⁻¹ (τ′/j₀) F⁻ᵀ over
//!   dV₀) and UL (σ′ over dv) stay the same linearisation.
//!
//! With the history pushed forward and j₀ = Θ_old, an element built on the deformed
//! coordinates with zero displacement has the stress, pressure and internal force of the old
//! one (exactly for a homogeneous deformation, `tests/rereference.rs`). j₀ is one value per
//! element (P0, like the pressure); where the old deformation varied inside an element, the
//! deviatoric Cauchy stress carries the factor J_old(point)/Θ_old of that variation.
//! j₀ = 1 ([`ElementInput::j0`]) gives the same results, bit for bit, as an element without
//! the option: every j₀ operation is then exact.

use crate::material::{ConstitutiveLaw, MatResponse, MatState, MaterialError, TimeIncrement};
use nalgebra::Matrix3;

/// Which incremental formulation the element uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Formulation {
    /// Total Lagrangian (reference configuration), paper eq. 5–11.
    TotalLagrangian,
    /// Updated Lagrangian (current configuration), paper eq. 12–17.
    #[default]
    UpdatedLagrangian,
    /// Linear (small-strain) kinematics, for verification against linear references
    /// (`[model] kinematics = "linear"`, [`evaluate_linear`]): strains ε = sym ∇₀u, equilibrium
    /// on the reference configuration, no geometric stiffness.
    Linear,
}

/// Gauss points of the 2×2 rule (ξ, η); all weights are 1.
const G: f64 = 0.577_350_269_189_625_8;
pub const GAUSS: [[f64; 2]; 4] = [[-G, -G], [G, -G], [G, G], [-G, G]];
const XI_A: [f64; 4] = [-1.0, 1.0, 1.0, -1.0];
const ETA_A: [f64; 4] = [-1.0, -1.0, 1.0, 1.0];

/// Shape functions N_a(ξ, η).
pub fn shape(xi: f64, eta: f64) -> [f64; 4] {
    let mut n = [0.0; 4];
    for a in 0..4 {
        n[a] = 0.25 * (1.0 + XI_A[a] * xi) * (1.0 + ETA_A[a] * eta);
    }
    n
}

/// Derivatives ∂N_a/∂ξ, ∂N_a/∂η.
pub fn shape_derivs(xi: f64, eta: f64) -> [[f64; 2]; 4] {
    let mut d = [[0.0; 2]; 4];
    for a in 0..4 {
        d[a][0] = 0.25 * XI_A[a] * (1.0 + ETA_A[a] * eta);
        d[a][1] = 0.25 * ETA_A[a] * (1.0 + XI_A[a] * xi);
    }
    d
}

/// The local coordinates (ξ, η) of point `p` in the quadrilateral with corners `xe` (in the
/// element's node order): Newton on x(ξ, η) = Σ N_a x_a from the centre, to 1e-13 of the
/// element's size. `None` when it does not converge (a degenerate element). The point is
/// inside (or on the boundary) when both |ξ| and |η| are at most 1.
pub fn local_coordinates(xe: &[[f64; 2]; 4], p: [f64; 2]) -> Option<[f64; 2]> {
    let size = (0..4).map(|a| (xe[a][0] - xe[(a + 2) % 4][0]).hypot(xe[a][1] - xe[(a + 2) % 4][1])).fold(0.0, f64::max);
    let mut xi = [0.0f64; 2];
    for _ in 0..50 {
        let (n, d) = (shape(xi[0], xi[1]), shape_derivs(xi[0], xi[1]));
        let (mut r, mut j) = ([p[0], p[1]], [[0.0; 2]; 2]);
        for a in 0..4 {
            for c in 0..2 {
                r[c] -= n[a] * xe[a][c];
                for k in 0..2 {
                    j[c][k] += d[a][k] * xe[a][c];
                }
            }
        }
        if r[0].hypot(r[1]) <= 1e-13 * size {
            return Some(xi);
        }
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if !(det.abs() > 0.0) || !det.is_finite() {
            return None;
        }
        xi[0] += (j[1][1] * r[0] - j[0][1] * r[1]) / det;
        xi[1] += (j[0][0] * r[1] - j[1][0] * r[0]) / det;
        if !(xi[0].abs() < 1e6 && xi[1].abs() < 1e6) {
            return None;
        }
    }
    None
}

/// The value at (ξ, η) of the bilinear field through an element's four Gauss-point values
/// (in the order of [`GAUSS`]): inside the Gauss points an interpolation, beyond them (up to
/// the corners) the usual extrapolation.
pub fn from_gauss_points(values: [f64; 4], xi: [f64; 2]) -> f64 {
    let n = shape(xi[0] / G, xi[1] / G);
    (0..4).map(|a| n[a] * values[a]).sum()
}

/// The corner (ξ, η) of an element's node `a` (0–3, counter-clockwise from (−1, −1)).
pub fn corner(a: usize) -> [f64; 2] {
    [XI_A[a], ETA_A[a]]
}

/// Volumetric treatment of one element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Volumetric {
    /// κ: bulk modulus (compressible) or penalty (incompressible), MPa.
    pub kappa: f64,
    /// λ_e: augmented-Lagrangian multiplier (a pressure, MPa); 0 for compressible laws.
    pub lambda: f64,
}

/// Gauss-point output of an element evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussOut {
    /// Cauchy stress `[xx, yy, xy, zz]` = τ′/J + p I (MPa).
    pub sig: [f64; 4],
    /// New (uncommitted) material state.
    pub state: MatState,
}

/// What one element contributes: internal force, tangent, Gauss-point results, pressure.
#[derive(Clone, Debug, PartialEq)]
pub struct ElementOut {
    /// Internal force vector (N/mm), dof order `[x0, y0, x1, y1, …]`.
    pub f_int: [f64; 8],
    /// Tangent stiffness ∂f_int/∂x (N/mm²); left zero when not requested.
    pub kk: [[f64; 8]; 8],
    pub gauss: [GaussOut; 4],
    /// Element pressure p (Cauchy, MPa, positive in tension).
    pub pressure: f64,
    /// Volume (area) ratio Θ = j₀ v_e/V_e with respect to the original configuration
    /// (module docs; j₀ = 1 unless the mesh was built in a deformed configuration).
    pub theta: f64,
    /// Enhanced-mode parameters (zero for Q1/P0).
    pub alpha: [f64; N_ENH],
}

impl Default for ElementOut {
    fn default() -> Self {
        Self {
            f_int: [0.0; 8],
            kk: [[0.0; 8]; 8],
            gauss: [GaussOut { sig: [0.0; 4], state: MatState::default() }; 4],
            pressure: 0.0,
            theta: 1.0,
            alpha: [0.0; N_ENH],
        }
    }
}

/// Shoelace area of a quadrilateral and its gradient g = ∂v/∂x (dof order x0, y0, x1, …).
pub fn quad_area_grad(x: &[[f64; 2]; 4]) -> (f64, [f64; 8]) {
    let mut v = 0.0;
    let mut g = [0.0; 8];
    for a in 0..4 {
        let n = (a + 1) % 4;
        let p = (a + 3) % 4;
        v += x[a][0] * x[n][1] - x[n][0] * x[a][1];
        g[2 * a] = 0.5 * (x[n][1] - x[p][1]);
        g[2 * a + 1] = 0.5 * (x[p][0] - x[n][0]);
    }
    (0.5 * v, g)
}

/// Add `s · H` to `kk`, H = ∂²v/∂x² of the shoelace area (entries ±½).
fn add_area_hessian(kk: &mut [[f64; 8]; 8], s: f64) {
    for a in 0..4 {
        let n = (a + 1) % 4;
        // ∂²v/∂x_a∂y_n = +½, ∂²v/∂y_a∂x_n = −½
        kk[2 * a][2 * n + 1] += 0.5 * s;
        kk[2 * n + 1][2 * a] += 0.5 * s;
        kk[2 * a + 1][2 * n] -= 0.5 * s;
        kk[2 * n][2 * a + 1] -= 0.5 * s;
    }
}

/// Voigt matrix T with `T τ̂ = (G τ Gᵀ)^` for a 2×2 G, stresses `[11, 22, 12]`; the strain-like
/// transformation (engineering shear) is Tᵀ.
fn voigt_congruence(g: &[[f64; 2]; 2]) -> [[f64; 3]; 3] {
    [
        [g[0][0] * g[0][0], g[0][1] * g[0][1], 2.0 * g[0][0] * g[0][1]],
        [g[1][0] * g[1][0], g[1][1] * g[1][1], 2.0 * g[1][0] * g[1][1]],
        [g[0][0] * g[1][0], g[0][1] * g[1][1], g[0][0] * g[1][1] + g[0][1] * g[1][0]],
    ]
}

fn inv2(m: &[[f64; 2]; 2]) -> (f64, [[f64; 2]; 2]) {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let id = 1.0 / det;
    (det, [[m[1][1] * id, -m[0][1] * id], [-m[1][0] * id, m[0][0] * id]])
}

/// The mean-dilatation volumetric part shared by both element technologies.
struct VolumetricPart {
    /// Reference area of the mesh element V_e (mm²).
    area0: f64,
    /// Reference area of the volumetric part V̂_e = V_e/j₀ (mm²).
    vol0: f64,
    /// g = ∂v_e/∂x.
    g: [f64; 8],
    /// Θ = j₀ v_e / V_e.
    theta: f64,
    /// Element pressure p = λ_e + κ ln Θ / Θ (MPa).
    p: f64,
    /// U″(Θ) = κ (1 − ln Θ) / Θ².
    upp: f64,
}

/// Checks the initial volume ratio j₀ of an element (positive and finite).
fn check_j0(j0: f64) -> Result<(), MaterialError> {
    if j0 > 0.0 && j0.is_finite() {
        Ok(())
    } else {
        Err(MaterialError::InvalidVolumeRatio(j0))
    }
}

impl VolumetricPart {
    /// Areas from coordinates relative to node 0 and v − V from the displacements, so that
    /// neither the shoelace sums nor ln Θ lose tiny strains to round-off. `j0` is the initial
    /// volume ratio (checked by the caller).
    fn new(xx0: &[[f64; 2]; 4], uu: &[[f64; 2]; 4], vol: Volumetric, j0: f64) -> Result<Self, MaterialError> {
        let xc: [[f64; 2]; 4] = std::array::from_fn(|a| [xx0[a][0] - xx0[0][0], xx0[a][1] - xx0[0][1]]);
        let x: [[f64; 2]; 4] = std::array::from_fn(|a| [xc[a][0] + uu[a][0], xc[a][1] + uu[a][1]]);
        let (area0, _) = quad_area_grad(&xc);
        let (_, g) = quad_area_grad(&x);
        // v − V = ½ Σ (X_a × u_{a+1} + u_a × X_{a+1} + u_a × u_{a+1})
        let cross = |p: [f64; 2], q: [f64; 2]| p[0] * q[1] - p[1] * q[0];
        let mut dvol = 0.0;
        for a in 0..4 {
            let n = (a + 1) % 4;
            dvol += cross(xc[a], uu[n]) + cross(uu[a], xc[n]) + cross(uu[a], uu[n]);
        }
        dvol *= 0.5;
        let ratio = 1.0 + dvol / area0;
        if ratio <= 0.0 || area0 <= 0.0 {
            return Err(MaterialError::InvertedElement(ratio));
        }
        // j₀ = 1: ln j₀ = 0 and j₀ · ratio = ratio exactly, so nothing changes
        let theta = j0 * ratio;
        let ln_t = j0.ln() + (dvol / area0).ln_1p();
        let p = vol.lambda + vol.kappa * ln_t / theta;
        let upp = vol.kappa * (1.0 - ln_t) / (theta * theta);
        Ok(Self { area0, vol0: area0 / j0, g, theta, p, upp })
    }

    /// f += p g and, with a tangent, K += (U″/V) g gᵀ + p H.
    fn add_to(&self, f: &mut [f64; 8], kk: Option<&mut [[f64; 8]; 8]>) {
        for i in 0..8 {
            f[i] += self.p * self.g[i];
        }
        if let Some(kk) = kk {
            let s = self.upp / self.vol0;
            for i in 0..8 {
                for j in 0..8 {
                    kk[i][j] += s * self.g[i] * self.g[j];
                }
            }
            add_area_hessian(kk, self.p);
        }
    }
}

/// D = T c Tᵀ: the spatial tangent pulled back to the material tangent ∂S/∂E.
fn pull_back_tangent(t: &[[f64; 3]; 3], cc: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut tc = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                tc[i][j] += t[i][k] * cc[k][j];
            }
        }
    }
    let mut dd = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                dd[i][j] += tc[i][k] * t[j][k];
            }
        }
    }
    dd
}

/// S = T τ̂ (Voigt), the second Piola–Kirchhoff stress from the Kirchhoff stress.
fn pull_back_stress(t: &[[f64; 3]; 3], tau: &[f64; 4]) -> [f64; 3] {
    std::array::from_fn(|i| t[i][0] * tau[0] + t[i][1] * tau[1] + t[i][2] * tau[2])
}

/// F = I + Σ u_a ⊗ ∂N_a/∂X (2×2, from the displacements).
fn compatible_gradient(uu: &[[f64; 2]; 4], dn_dx0: &[[f64; 2]; 4]) -> [[f64; 2]; 2] {
    let mut f2 = [[1.0, 0.0], [0.0, 1.0]];
    for a in 0..4 {
        for i in 0..2 {
            for k in 0..2 {
                f2[i][k] += uu[a][i] * dn_dx0[a][k];
            }
        }
    }
    f2
}

/// ∂N_a/∂ξ and the reference Jacobian J₀ = ∂X/∂ξ = Σ_a X_a ⊗ ∂N_a/∂ξ at (ξ, η).
fn reference_jacobian(xx0: &[[f64; 2]; 4], xi: f64, eta: f64) -> ([[f64; 2]; 4], [[f64; 2]; 2]) {
    let dn = shape_derivs(xi, eta);
    let mut j0 = [[0.0; 2]; 2];
    for a in 0..4 {
        for i in 0..2 {
            for k in 0..2 {
                j0[i][k] += xx0[a][i] * dn[a][k];
            }
        }
    }
    (dn, j0)
}

/// det J₀ and ∂N_a/∂X = ∂N_a/∂ξ J₀⁻¹ at (ξ, η), with J₀ = ∂X/∂ξ the reference Jacobian;
/// an error if the reference element is inverted there.
fn reference_gradients(xx0: &[[f64; 2]; 4], xi: f64, eta: f64) -> Result<(f64, [[f64; 2]; 4]), MaterialError> {
    let (dn, j0) = reference_jacobian(xx0, xi, eta);
    let (det_j0, j0_inv) = inv2(&j0);
    if det_j0 <= 0.0 {
        return Err(MaterialError::InvertedElement(det_j0));
    }
    let mut dn_dx0 = [[0.0; 2]; 4];
    for a in 0..4 {
        for k in 0..2 {
            dn_dx0[a][k] = dn[a][0] * j0_inv[0][k] + dn[a][1] * j0_inv[1][k];
        }
    }
    Ok((det_j0, dn_dx0))
}

/// The law's response at a Gauss point with the in-plane deformation gradient `f2`, relative
/// to an element reference configuration with initial volume ratio j₀: τ′/j₀ and c/j₀ (module
/// docs), returned with J = det F (λ₃ det F₂ in plane stress) and F⁻¹ (in-plane). `inv_j0` = 1/j₀ (exactly 1 for j₀ = 1, which leaves
/// the response unchanged bit for bit). An error if F is inverted (J ≤ 0).
fn law_response(
    law: &dyn ConstitutiveLaw,
    f2: &[[f64; 2]; 2],
    old: &MatState,
    inc: TimeIncrement,
    inv_j0: f64,
) -> Result<(f64, [[f64; 2]; 2], MatResponse), MaterialError> {
    let (jac, f_inv) = inv2(f2);
    if jac <= 0.0 {
        return Err(MaterialError::InvertedElement(jac));
    }
    let ff = Matrix3::new(f2[0][0], f2[0][1], 0.0, f2[1][0], f2[1][1], 0.0, 0.0, 0.0, 1.0);
    let mut r = law.update(&ff, old, inc)?;
    r.tau.iter_mut().for_each(|v| *v *= inv_j0);
    r.cc.iter_mut().flatten().for_each(|v| *v *= inv_j0);
    // (plane stress: the volume ratio counts the thickness stretch, so that τ / J is the Cauchy
    // stress; the forces, per unit reference thickness, use τ and do not see it)
    Ok((jac * r.thickness, f_inv, r))
}

/// Cauchy stress `[xx, yy, xy, zz]` = τ′/J + p I of a Gauss point.
fn cauchy(tau: &[f64; 4], jac: f64, p: f64) -> [f64; 4] {
    [tau[0] / jac + p, tau[1] / jac + p, tau[2] / jac, tau[3] / jac + p]
}

/// What an element evaluation reads, the same for both element kinds ([`evaluate`],
/// [`evaluate_enhanced`]).
#[derive(Clone, Copy)]
pub struct ElementInput<'a> {
    /// The element's constitutive law.
    pub law: &'a dyn ConstitutiveLaw,
    /// Reference nodal coordinates (mm).
    pub xx0: &'a [[f64; 2]; 4],
    /// Nodal displacements (mm). Kinematics are formed from the displacements (F = I + ∇₀u,
    /// v − V from the shoelace formula of the differences) so that tiny strains are not lost
    /// to round-off in X + u.
    pub uu: &'a [[f64; 2]; 4],
    /// Committed Gauss-point states.
    pub old: &'a [MatState; 4],
    /// The time increment.
    pub inc: TimeIncrement,
    /// Volumetric treatment.
    pub vol: Volumetric,
    /// Initial volume ratio j₀ of the element's reference configuration (module docs:
    /// Θ = j₀ v_e/V_e, deviatoric stress τ′/(j₀ J)); 1 when the reference configuration is the
    /// original one.
    pub j0: f64,
    /// Whether to form the tangent `kk`.
    pub tangent: bool,
}

/// Evaluate one Q1/P0 element in the given formulation.
///
/// Errors when an element is inverted at a Gauss point or a local return map fails, and
/// [`MaterialError::InvalidVolumeRatio`] when `j0` is not positive and finite.
pub fn evaluate(formulation: Formulation, input: ElementInput<'_>, out: &mut ElementOut) -> Result<(), MaterialError> {
    if formulation == Formulation::Linear {
        return evaluate_linear(input, out);
    }
    let ElementInput { law, xx0, uu, old, inc, vol, j0, tangent } = input;
    check_j0(j0)?;
    let inv_j0 = 1.0 / j0;
    out.f_int = [0.0; 8];
    if tangent {
        out.kk = [[0.0; 8]; 8];
    }

    // --- volumetric part (mean dilatation) ---
    let vp = VolumetricPart::new(xx0, uu, vol, j0)?;
    vp.add_to(&mut out.f_int, if tangent { Some(&mut out.kk) } else { None });
    let p = vp.p;
    out.pressure = p;
    out.theta = vp.theta;

    // --- deviatoric part, Gauss loop ---
    for (q, gp) in GAUSS.iter().enumerate() {
        let (det_j0, dn_dx0) = reference_gradients(xx0, gp[0], gp[1])?;
        let f2 = compatible_gradient(uu, &dn_dx0);
        let (jac, f_inv, MatResponse { tau, cc, state, .. }) = law_response(law, &f2, &old[q], inc, inv_j0)?;
        let w0 = det_j0; // Gauss weight 1, unit thickness: dV₀ = det J0

        out.gauss[q] = GaussOut { sig: cauchy(&tau, jac, p), state };

        match formulation {
            Formulation::TotalLagrangian => {
                // S = F⁻¹ τ′ F⁻ᵀ, D = T c Tᵀ with T the congruence by F⁻¹
                let t = voigt_congruence(&f_inv);
                let s = pull_back_stress(&t, &tau);
                // ₀B_L for node a: rows δE11, δE22, 2δE12; cols (u_a, v_a)
                let mut bl = [[0.0; 8]; 3];
                for a in 0..4 {
                    let (n1, n2) = (dn_dx0[a][0], dn_dx0[a][1]);
                    bl[0][2 * a] = f2[0][0] * n1;
                    bl[0][2 * a + 1] = f2[1][0] * n1;
                    bl[1][2 * a] = f2[0][1] * n2;
                    bl[1][2 * a + 1] = f2[1][1] * n2;
                    bl[2][2 * a] = f2[0][0] * n2 + f2[0][1] * n1;
                    bl[2][2 * a + 1] = f2[1][0] * n2 + f2[1][1] * n1;
                }
                for i in 0..8 {
                    out.f_int[i] += w0 * (bl[0][i] * s[0] + bl[1][i] * s[1] + bl[2][i] * s[2]);
                }
                if tangent {
                    let dd = pull_back_tangent(&t, &cc);
                    add_bt_d_b(&mut out.kk, &bl, &dd, w0);
                    add_geometric(&mut out.kk, &dn_dx0, &[[s[0], s[2]], [s[2], s[1]]], w0);
                }
            }
            Formulation::UpdatedLagrangian | Formulation::Linear => {
                // ∂N_a/∂x = ∂N_a/∂X F⁻¹
                let mut dn_dx = [[0.0; 2]; 4];
                for a in 0..4 {
                    for k in 0..2 {
                        dn_dx[a][k] = dn_dx0[a][0] * f_inv[0][k] + dn_dx0[a][1] * f_inv[1][k];
                    }
                }
                let dv = w0 * jac;
                let sig = [tau[0] / jac, tau[1] / jac, tau[2] / jac];
                let bl = small_strain_b(&dn_dx);
                for i in 0..8 {
                    out.f_int[i] += dv * (bl[0][i] * sig[0] + bl[1][i] * sig[1] + bl[2][i] * sig[2]);
                }
                if tangent {
                    // c/J integrated over dv = c integrated over dV₀
                    add_bt_d_b_small_strain(&mut out.kk, &dn_dx, &cc, w0);
                    add_geometric(&mut out.kk, &dn_dx, &[[sig[0], sig[2]], [sig[2], sig[1]]], dv);
                }
            }
        }
    }
    Ok(())
}

/// The exponential of the symmetric 2×2 strain `[[a, b], [b, d]]`: e^m (cosh r I + sinh r / r
/// (A − m I)) with m = (a + d)/2 and r = √(((a − d)/2)² + b²).
fn exp_sym2(a: f64, b: f64, d: f64) -> [[f64; 2]; 2] {
    let (m, h) = (0.5 * (a + d), 0.5 * (a - d));
    let r = h.hypot(b);
    // sinh r / r, by its series below 1e-4 (no 0/0)
    let s = if r < 1e-4 { 1.0 + r * r / 6.0 } else { r.sinh() / r };
    let (c, e) = (r.cosh(), m.exp());
    [[e * (c + s * h), e * s * b], [e * s * b, e * (c - s * h)]]
}

/// One Q1/P0 element with linear (small-strain) kinematics ([`Formulation::Linear`]), for
/// verification against linear references at any load:
/// - strain ε = sym ∇₀u at each Gauss point; the law is given the stretch F = exp ε (no
///   rotation), whose logarithmic strain is ε exactly, so that the Hencky law is linear
///   elasticity, τ′ = 2G dev ε, and the J2 and creep updates on the logarithmic elastic strain
///   are the small-strain return maps up to terms of the order of the strains times the
///   plastic strains (the exponential map on a non-coaxial C_p⁻¹);
/// - stress σ = τ′ + p I, internal force ∫ B₀ᵀ σ dV₀ on the reference configuration and the
///   tangent ∫ B₀ᵀ c B₀ dV₀ (the law's tangent, the small-strain one up to terms of the order of
///   the strains), without geometric stiffness;
/// - mean dilatation linearised: e_v = g₀·u / V (g₀ = ∂V/∂X), p = λ_e + κ e_v, f = p g₀,
///   K = κ g₀ g₀ᵀ / V; Θ = 1 + e_v for the incompressibility updates.
///
/// The element's reference configuration must be the original one (j₀ = 1: no re-meshing).
pub fn evaluate_linear(input: ElementInput<'_>, out: &mut ElementOut) -> Result<(), MaterialError> {
    let ElementInput { law, xx0, uu, old, inc, vol, j0, tangent } = input;
    if j0 != 1.0 {
        return Err(MaterialError::InvalidVolumeRatio(j0));
    }
    out.f_int = [0.0; 8];
    if tangent {
        out.kk = [[0.0; 8]; 8];
    }
    let xc: [[f64; 2]; 4] = std::array::from_fn(|a| [xx0[a][0] - xx0[0][0], xx0[a][1] - xx0[0][1]]);
    let (area0, g0) = quad_area_grad(&xc);
    if area0 <= 0.0 {
        return Err(MaterialError::InvertedElement(area0));
    }
    let ev = (0..4).map(|a| g0[2 * a] * uu[a][0] + g0[2 * a + 1] * uu[a][1]).sum::<f64>() / area0;
    let p = vol.lambda + vol.kappa * ev;
    for i in 0..8 {
        out.f_int[i] += p * g0[i];
    }
    if tangent {
        for i in 0..8 {
            for j in 0..8 {
                out.kk[i][j] += vol.kappa * g0[i] * g0[j] / area0;
            }
        }
    }
    out.pressure = p;
    out.theta = 1.0 + ev;
    for (q, gp) in GAUSS.iter().enumerate() {
        let (det_j0, dn_dx0) = reference_gradients(xx0, gp[0], gp[1])?;
        let mut grad = [[0.0; 2]; 2];
        for a in 0..4 {
            for i in 0..2 {
                for k in 0..2 {
                    grad[i][k] += uu[a][i] * dn_dx0[a][k];
                }
            }
        }
        let f2 = exp_sym2(grad[0][0], 0.5 * (grad[0][1] + grad[1][0]), grad[1][1]);
        let (_, _, MatResponse { tau, cc, state, .. }) = law_response(law, &f2, &old[q], inc, 1.0)?;
        out.gauss[q] = GaussOut { sig: cauchy(&tau, 1.0, p), state };
        let bl = small_strain_b(&dn_dx0);
        for i in 0..8 {
            out.f_int[i] += det_j0 * (bl[0][i] * tau[0] + bl[1][i] * tau[1] + bl[2][i] * tau[2]);
        }
        if tangent {
            add_bt_d_b(&mut out.kk, &bl, &cc, det_j0);
        }
    }
    Ok(())
}

/// The small-strain operator B (rows ε_xx, ε_yy, 2ε_xy; columns (u_a, v_a)) of the shape
/// function gradients `dn` (the updated Lagrangian's in current coordinates, the small-strain
/// element's in reference ones).
#[inline]
fn small_strain_b(dn: &[[f64; 2]; 4]) -> [[f64; 8]; 3] {
    let mut bl = [[0.0; 8]; 3];
    for a in 0..4 {
        let (n1, n2) = (dn[a][0], dn[a][1]);
        bl[0][2 * a] = n1;
        bl[1][2 * a + 1] = n2;
        bl[2][2 * a] = n2;
        bl[2][2 * a + 1] = n1;
    }
    bl
}

/// kk += w B_Lᵀ D B_L
#[inline]
fn add_bt_d_b(kk: &mut [[f64; 8]; 8], bl: &[[f64; 8]; 3], dd: &[[f64; 3]; 3], w: f64) {
    let mut db = [[0.0; 8]; 3];
    for i in 0..3 {
        for j in 0..8 {
            db[i][j] = dd[i][0] * bl[0][j] + dd[i][1] * bl[1][j] + dd[i][2] * bl[2][j];
        }
    }
    for i in 0..8 {
        for j in 0..8 {
            kk[i][j] += w * (bl[0][i] * db[0][j] + bl[1][i] * db[1][j] + bl[2][i] * db[2][j]);
        }
    }
}

/// kk += w Bᵀ D B for the small-strain B of [`small_strain_b`] (rows ε_xx, ε_yy, 2ε_xy; node a's
/// columns (n₁, 0, n₂) and (0, n₂, n₁)), over its nonzeros only: D B_b for each node b, then
/// B_aᵀ (D B_b) for each pair, 176 products against the 264 of the dense [`add_bt_d_b`] (test
/// `the_small_strain_product_is_the_dense_one`).
#[inline]
fn add_bt_d_b_small_strain(kk: &mut [[f64; 8]; 8], dn: &[[f64; 2]; 4], dd: &[[f64; 3]; 3], w: f64) {
    // w D B_b: column x = D e₀ n₁ + D e₂ n₂, column y = D e₁ n₂ + D e₂ n₁
    let mut db = [[[0.0; 2]; 3]; 4];
    for b in 0..4 {
        let (n1, n2) = (w * dn[b][0], w * dn[b][1]);
        for i in 0..3 {
            db[b][i] = [dd[i][0] * n1 + dd[i][2] * n2, dd[i][1] * n2 + dd[i][2] * n1];
        }
    }
    for a in 0..4 {
        let (n1, n2) = (dn[a][0], dn[a][1]);
        for b in 0..4 {
            let d = &db[b];
            for k in 0..2 {
                kk[2 * a][2 * b + k] += n1 * d[0][k] + n2 * d[2][k];
                kk[2 * a + 1][2 * b + k] += n2 * d[1][k] + n1 * d[2][k];
            }
        }
    }
}

/// kk += w B_NLᵀ [s 0; 0 s] B_NL, i.e. (∇N_a · s ∇N_b) I₂ for each node pair.
#[inline]
fn add_geometric(kk: &mut [[f64; 8]; 8], dn: &[[f64; 2]; 4], s: &[[f64; 2]; 2], w: f64) {
    for a in 0..4 {
        let sa = [
            s[0][0] * dn[a][0] + s[0][1] * dn[a][1],
            s[1][0] * dn[a][0] + s[1][1] * dn[a][1],
        ];
        for b in 0..4 {
            let gab = w * (sa[0] * dn[b][0] + sa[1] * dn[b][1]);
            kk[2 * a][2 * b] += gab;
            kk[2 * a + 1][2 * b + 1] += gab;
        }
    }
}

/// Element technology, chosen per case (`[model] element`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ElementKind {
    /// Q1/P0: bilinear displacement, constant element pressure (mean dilatation). Robust under
    /// the very large compressions of compaction; stiff in bending on coarse meshes.
    #[default]
    Q1P0,
    /// Q1/P0 with four enhanced (incompatible) deviatoric modes condensed at element level
    /// (Simo & Armero 1992, Q1/E4): accurate in bending on coarse meshes.
    Q1P0Enhanced,
}

/// Number of enhanced modes of [`ElementKind::Q1P0Enhanced`].
pub const N_ENH: usize = 4;

/// Evaluate the enhanced-strain element (Simo & Armero 1992, "Q1/E4", with the mean-dilatation
/// pressure of [`evaluate`]).
///
/// The deformation gradient at a Gauss point is F = I + ∇₀u + F̃(α) with the enhanced part
/// `F̃ = (j₀/j(ξ)) M(ξ; α) J₀⁻¹`, M = [[α₁ξ, α₂η], [α₃ξ, α₄η]] (rows: x, y; columns: ξ, η),
/// J₀ = ∂X/∂ξ and j₀ = det J₀ at the element centre. Because ∫ F̃ dV₀ = j₀ ∫ M dξ J₀⁻¹ = 0, the
/// element passes the patch test. The internal parameters α solve the element equations
/// R_α = ∫ S : δE(δα) dV₀ = 0 by a local Newton iteration at fixed u (starting from `alpha`);
/// the returned stiffness is the condensed K_uu − K_uα K_αα⁻¹ K_αu, the exact derivative of the
/// internal force with α eliminated.
///
/// Both TL and UL requests are computed in the total Lagrangian algebra: each column j of the
/// 12 generalised degrees of freedom has a gradient variation δFʲ, with
/// `B_L[:, j] = sym(Fᵀ δFʲ)` (rows δE₁₁, δE₂₂, 2δE₁₂) and `K_NL[i][j] = δFⁱ : (δFʲ S)`.
/// On return `alpha` holds the solution.
///
/// Errors as [`evaluate`], and [`MaterialError::ReturnMapFailed`] when the local iteration
/// does not converge.
pub fn evaluate_enhanced(input: ElementInput<'_>, alpha: &mut [f64; N_ENH], out: &mut ElementOut) -> Result<(), MaterialError> {
    let ElementInput { law, xx0, uu, old, inc, vol, j0, tangent } = input;
    check_j0(j0)?;
    let inv_j0 = 1.0 / j0;
    // volumetric part and pressure: same as the Q1/P0 element
    let vp = VolumetricPart::new(xx0, uu, vol, j0)?;
    let p = vp.p;

    // centre Jacobian
    let (_, jc) = reference_jacobian(xx0, 0.0, 0.0);
    let (det_jc, jc_inv) = inv2(&jc);

    // per Gauss point geometry (fixed during the local iteration)
    struct Gp {
        w0: f64,
        dn_dx0: [[f64; 2]; 4],
        /// δF of each enhanced mode per unit α
        enh: [[[f64; 2]; 2]; N_ENH],
    }
    let mut gps: [Gp; 4] = std::array::from_fn(|_| Gp { w0: 0.0, dn_dx0: [[0.0; 2]; 4], enh: [[[0.0; 2]; 2]; N_ENH] });
    for (q, gp) in GAUSS.iter().enumerate() {
        let (det_j0, dn_dx0) = reference_gradients(xx0, gp[0], gp[1])?;
        gps[q].dn_dx0 = dn_dx0;
        gps[q].w0 = det_j0;
        let s = det_jc / det_j0;
        // M_m: (row, column-in-ξη, value)
        let modes = [(0usize, 0usize, gp[0]), (0, 1, gp[1]), (1, 0, gp[0]), (1, 1, gp[1])];
        for (m, &(row, col, v)) in modes.iter().enumerate() {
            for k in 0..2 {
                gps[q].enh[m][row][k] = s * v * jc_inv[col][k];
            }
        }
    }

    const NT: usize = 8 + N_ENH;
    let mut kk = [[0.0; NT]; NT];
    let mut rr = [0.0; NT];
    let mut converged = false;
    let mut ra_prev = f64::INFINITY;
    for iter in 0..25 {
        kk = [[0.0; NT]; NT];
        rr = [0.0; NT];
        for (q, gp) in gps.iter().enumerate() {
            let mut f2 = compatible_gradient(uu, &gp.dn_dx0);
            for m in 0..N_ENH {
                for i in 0..2 {
                    for k in 0..2 {
                        f2[i][k] += alpha[m] * gp.enh[m][i][k];
                    }
                }
            }
            let (jac, f_inv, MatResponse { tau, cc, state, .. }) = law_response(law, &f2, &old[q], inc, inv_j0)?;
            out.gauss[q] = GaussOut { sig: cauchy(&tau, jac, p), state };
            let t = voigt_congruence(&f_inv);
            let s = pull_back_stress(&t, &tau);
            // δF of every generalised dof
            let mut dfs = [[[0.0; 2]; 2]; NT];
            for a in 0..4 {
                for k in 0..2 {
                    dfs[2 * a][0][k] = gp.dn_dx0[a][k];
                    dfs[2 * a + 1][1][k] = gp.dn_dx0[a][k];
                }
            }
            dfs[8..].copy_from_slice(&gp.enh);
            let mut bl = [[0.0; NT]; 3];
            for j in 0..NT {
                let d = &dfs[j];
                bl[0][j] = f2[0][0] * d[0][0] + f2[1][0] * d[1][0];
                bl[1][j] = f2[0][1] * d[0][1] + f2[1][1] * d[1][1];
                bl[2][j] = f2[0][0] * d[0][1] + f2[1][0] * d[1][1] + f2[0][1] * d[0][0] + f2[1][1] * d[1][0];
            }
            let w0 = gp.w0;
            for j in 0..NT {
                rr[j] += w0 * (bl[0][j] * s[0] + bl[1][j] * s[1] + bl[2][j] * s[2]);
            }
            let dd = pull_back_tangent(&t, &cc);
            let smat = [[s[0], s[2]], [s[2], s[1]]];
            for i in 0..NT {
                let db: [f64; 3] = std::array::from_fn(|r| dd[r][0] * bl[0][i] + dd[r][1] * bl[1][i] + dd[r][2] * bl[2][i]);
                // δFⁱ S
                let fs: [[f64; 2]; 2] = std::array::from_fn(|r| std::array::from_fn(|c| dfs[i][r][0] * smat[0][c] + dfs[i][r][1] * smat[1][c]));
                for j in 0..NT {
                    let kl = bl[0][j] * db[0] + bl[1][j] * db[1] + bl[2][j] * db[2];
                    let knl = fs[0][0] * dfs[j][0][0] + fs[0][1] * dfs[j][0][1] + fs[1][0] * dfs[j][1][0] + fs[1][1] * dfs[j][1][1];
                    kk[i][j] += w0 * (kl + knl);
                }
            }
        }
        // local equations R_α = 0
        let ra: [f64; N_ENH] = std::array::from_fn(|m| rr[8 + m]);
        let scale = rr[..8].iter().map(|v| v.abs()).fold(0.0, f64::max).max(vol.kappa.abs() * 1e-12 * vp.area0.sqrt());
        let ra_norm = ra.iter().map(|v| v.abs()).fold(0.0, f64::max);
        // converged, or stagnating at round-off (Newton converges quadratically here, so a
        // residual that stops halving is at the floor of the arithmetic)
        let stagnating = iter > 0 && ra_norm >= 0.5 * ra_prev && ra_norm <= 1e-6 * scale;
        if ra_norm <= 1e-11 * scale || stagnating {
            converged = true;
            break;
        }
        ra_prev = ra_norm;
        let kaa = nalgebra::Matrix4::from_fn(|i, j| kk[8 + i][8 + j]);
        let Some(inv) = kaa.try_inverse() else {
            return Err(MaterialError::ReturnMapFailed { iterations: iter, residual: ra_norm });
        };
        for m in 0..N_ENH {
            let mut d = 0.0;
            for n in 0..N_ENH {
                d += inv[(m, n)] * ra[n];
            }
            alpha[m] -= d;
        }
    }
    if !converged {
        let ra_norm = (8..NT).map(|m| rr[m].abs()).fold(0.0, f64::max);
        return Err(MaterialError::ReturnMapFailed { iterations: 25, residual: ra_norm });
    }

    // condensed force and stiffness + volumetric part
    out.f_int = std::array::from_fn(|i| rr[i]);
    if tangent {
        let kaa = nalgebra::Matrix4::from_fn(|i, j| kk[8 + i][8 + j]);
        let inv = kaa.try_inverse().ok_or(MaterialError::ReturnMapFailed { iterations: 0, residual: f64::NAN })?;
        // K_uu − (K_uα K_αα⁻¹) K_αu
        let mut kua_inv = [[0.0; N_ENH]; 8];
        for i in 0..8 {
            for n in 0..N_ENH {
                for m in 0..N_ENH {
                    kua_inv[i][n] += kk[i][8 + m] * inv[(m, n)];
                }
            }
        }
        for i in 0..8 {
            for j in 0..8 {
                let mut c = 0.0;
                for n in 0..N_ENH {
                    c += kua_inv[i][n] * kk[8 + n][j];
                }
                out.kk[i][j] = kk[i][j] - c;
            }
        }
    }
    vp.add_to(&mut out.f_int, if tangent { Some(&mut out.kk) } else { None });
    out.pressure = p;
    out.theta = vp.theta;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Elastic, HardeningTable, J2Plastic, Material};

    const XX0: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.1], [1.1, 1.0], [-0.1, 0.9]];

    /// The inverse of the bilinear map: points mapped from known (ξ, η) (inside, on the edges,
    /// at the corners and outside) come back to them to 1e-12; the Gauss-point field through
    /// the values of a bilinear function is that function everywhere (interpolation and
    /// extrapolation to the corners exact to 1e-12).
    #[test]
    fn local_coordinates_invert_the_map_and_gauss_values_extrapolate_bilinear_fields() {
        let map = |xi: [f64; 2]| {
            let n = shape(xi[0], xi[1]);
            [(0..4).map(|a| n[a] * XX0[a][0]).sum::<f64>(), (0..4).map(|a| n[a] * XX0[a][1]).sum::<f64>()]
        };
        for xi in [[0.0, 0.0], [0.3, -0.7], [1.0, 1.0], [-1.0, 0.25], [0.999, -1.0], [1.5, 0.2], [-1.3, -1.2]] {
            let back = local_coordinates(&XX0, map(xi)).unwrap();
            assert!((back[0] - xi[0]).abs() < 1e-12 && (back[1] - xi[1]).abs() < 1e-12, "{xi:?} -> {back:?}");
        }
        let f = |xi: [f64; 2]| 2.0 - 0.5 * xi[0] + 3.0 * xi[1] + 0.7 * xi[0] * xi[1];
        let values = GAUSS.map(f);
        for xi in [[0.0, 0.0], [0.1, 0.9], [1.0, -1.0], [-1.0, 1.0], [-0.4, -0.2]] {
            assert!((from_gauss_points(values, xi) - f(xi)).abs() < 1e-12, "{xi:?}");
        }
        for a in 0..4 {
            assert_eq!(corner(a), [XI_A[a], ETA_A[a]]);
        }
    }

    fn run(kind: Option<Formulation>, law: &Material, uu: &[[f64; 2]; 4], vol: Volumetric, j0: f64, tangent: bool) -> ElementOut {
        let old = [MatState::default(); 4];
        let inc = TimeIncrement { time: 1.0, dt: 1.0 };
        let mut out = ElementOut::default();
        match kind {
            Some(f) => evaluate(f, ElementInput { law, xx0: &XX0, uu, old: &old, inc, vol, j0, tangent }, &mut out).unwrap(),
            None => {
                let mut alpha = [0.0; N_ENH];
                evaluate_enhanced(ElementInput { law, xx0: &XX0, uu, old: &old, inc, vol, j0, tangent }, &mut alpha, &mut out).unwrap();
            }
        }
        out
    }

    /// With j₀ ≠ 1 the tangent is still the derivative of the internal force: central
    /// differences (h = 1e-7 mm on 1 mm elements: truncation ~h², round-off ~1e-16/h) agree
    /// to 1e-6 of the largest stiffness entry, for Q1/P0 TL and UL and Q1/E4, elastic, J2 in
    /// the plastic range and the incompressible volumetric part with a multiplier (the same
    /// check and tolerance as tests/element_assembly.rs for j₀ = 1).
    #[test]
    fn tangent_is_consistent_with_j0() {
        let uu = [[0.0, 0.0], [0.05, -0.02], [0.08, 0.03], [-0.02, 0.04]];
        let hard = HardeningTable::from_plastic_strain(&[[0.0, 20.0], [0.1, 40.0], [1.0, 60.0]]).unwrap();
        let laws = [
            (Material::Elastic(Elastic::new(1000.0, 0.3)), 0.0),
            (Material::J2(J2Plastic::new(20_000.0, 0.3, hard)), 0.0),
            (Material::Elastic(Elastic::new(1000.0, 0.5)), 7.5),
        ];
        for (law, lambda) in &laws {
            let kappa = law.bulk_modulus().unwrap_or(1e3 * law.shear_modulus());
            let vol = Volumetric { kappa, lambda: *lambda };
            for kind in [Some(Formulation::TotalLagrangian), Some(Formulation::UpdatedLagrangian), None] {
                for j0 in [0.7, 1.3] {
                    let out = run(kind, law, &uu, vol, j0, true);
                    let scale = out.kk.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
                    let h = 1e-7;
                    for j in 0..8 {
                        let (mut up, mut dn) = (uu, uu);
                        up[j / 2][j % 2] += h;
                        dn[j / 2][j % 2] -= h;
                        let (fp, fm) = (run(kind, law, &up, vol, j0, false).f_int, run(kind, law, &dn, vol, j0, false).f_int);
                        for i in 0..8 {
                            let fd = (fp[i] - fm[i]) / (2.0 * h);
                            assert!((fd - out.kk[i][j]).abs() < 1e-6 * scale, "{law:?} {kind:?} j0={j0}: K[{i}][{j}] = {} vs {fd}", out.kk[i][j]);
                        }
                    }
                }
            }
        }
    }

    /// How j₀ enters, checked against the formulas of the module docs for a virgin state
    /// (1e-13 relative: a few roundings): Θ = j₀ v/V, p = κ ln Θ / Θ, and the deviatoric
    /// Cauchy stress of the law divided by j₀.
    #[test]
    fn j0_scales_theta_pressure_and_deviatoric_stress() {
        let law = Material::Elastic(Elastic::new(1000.0, 0.3));
        let vol = Volumetric { kappa: law.bulk_modulus().unwrap(), lambda: 0.0 };
        let uu = [[0.0, 0.0], [0.05, -0.02], [0.08, 0.03], [-0.02, 0.04]];
        for kind in [Some(Formulation::TotalLagrangian), Some(Formulation::UpdatedLagrangian), None] {
            let one = run(kind, &law, &uu, vol, 1.0, false);
            let j0 = 1.25;
            let two = run(kind, &law, &uu, vol, j0, false);
            assert!((two.theta - j0 * one.theta).abs() < 1e-13);
            let p = vol.kappa * two.theta.ln() / two.theta;
            assert!((two.pressure - p).abs() < 1e-13 * p.abs());
            for q in 0..4 {
                for i in 0..4 {
                    let pi = if i == 2 { 0.0 } else { 1.0 };
                    let dev1 = one.gauss[q].sig[i] - pi * one.pressure;
                    let dev2 = two.gauss[q].sig[i] - pi * two.pressure;
                    assert!((dev2 - dev1 / j0).abs() < 1e-13 * dev1.abs().max(1.0), "{kind:?}");
                }
            }
        }
    }

    /// A j₀ that is not positive and finite is an error (no panic).
    #[test]
    fn invalid_j0() {
        let law = Material::Elastic(Elastic::new(1000.0, 0.3));
        let vol = Volumetric { kappa: 833.0, lambda: 0.0 };
        let old = [MatState::default(); 4];
        let inc = TimeIncrement { time: 1.0, dt: 1.0 };
        let mut out = ElementOut::default();
        for bad in [0.0, -2.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let input = ElementInput { law: &law, xx0: &XX0, uu: &[[0.0; 2]; 4], old: &old, inc, vol, j0: bad, tangent: true };
            let e = evaluate(Formulation::TotalLagrangian, input, &mut out);
            assert!(matches!(e, Err(MaterialError::InvalidVolumeRatio(_))), "{bad}: {e:?}");
            let mut a = [0.0; N_ENH];
            let e = evaluate_enhanced(input, &mut a, &mut out);
            assert!(matches!(e, Err(MaterialError::InvalidVolumeRatio(_))), "{bad}: {e:?}");
        }
    }

    #[test]
    fn the_small_strain_product_is_the_dense_one() {
        // Reference: the dense Bᵀ D B over the full small-strain B; an unsymmetric D (creep's
        // tangent may be) and a distorted element's gradients; tolerance 1e-13 of the largest entry.
        let dn = [[-0.31, -0.22], [0.27, -0.19], [0.35, 0.26], [-0.29, 0.18]];
        let dd = [[7.1e4, 2.3e4, 1.1e3], [2.2e4, 6.9e4, -0.8e3], [1.3e3, -0.7e3, 2.4e4]];
        let (mut fast, mut dense) = ([[0.5; 8]; 8], [[0.5; 8]; 8]);
        add_bt_d_b_small_strain(&mut fast, &dn, &dd, 0.37);
        add_bt_d_b(&mut dense, &small_strain_b(&dn), &dd, 0.37);
        let scale = dense.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
        for i in 0..8 {
            for j in 0..8 {
                assert!((fast[i][j] - dense[i][j]).abs() <= 1e-13 * scale, "({i}, {j}): {} against {}", fast[i][j], dense[i][j]);
            }
        }
    }
}
