//! Node-to-segment contact on a smoothed (C¹) master surface (`[contact] normal = "smoothed"`).
//!
//! # Why
//!
//! With the straight-segment kernel ([`super::enforce::segment_pair`]) the contact normal of a
//! slave node is the normal of its closest master segment. A node that slides round a convex
//! master corner (the 135° corners of the paper's octagons) changes segment, and the normal
//! turns at once by the corner's turning angle (45°); the state that converged with the old
//! pair starts the next step out of balance by the same jump, whatever the step size. Averaging
//! the normals at the nodes is not enough if the gap keeps being measured from the faceted
//! surface: a penalty force −p A ∇g is normal to the level sets of g, and the zero level set is
//! still the polygon, so ∇g still turns by 45° across the corner (with the averaged-normal
//! projection of Papadopoulos & Taylor / Yang–Laursen, ∇g at g → 0 is n_seg/(n_seg·ν̃), which
//! jumps like n_seg). The cure is a master *surface* with a continuous tangent, on which the
//! closest-point projection, the normal and the gap all move continuously (Wriggers,
//! *Computational Contact Mechanics*, 2nd ed., §9.4 "smooth contact discretisations", Hermite
//! and Bézier interpolations of the master surface; Padmanabhan & Laursen 2001; Puso & Laursen
//! 2002 for the 3D counterpart).
//!
//! # The smoothed master surface
//!
//! Master segment 1 → 2 with its boundary neighbours 0 (before 1) and 3 (after 2), chord
//! d = x₂ − x₁, ℓ = |d|, chord tangents t_ab = (x_b − x_a)/|x_b − x_a|.
//!
//! * Nodal tangents (Gouraud-type averaging, equivalently averaged nodal normals rotated by
//!   90°): T₁ = (t₀₁ + t₁₂)/|t₀₁ + t₁₂|, T₂ = (t₁₂ + t₂₃)/|t₁₂ + t₂₃|, i.e. T = R(θ) t₁₂ with the
//!   end angles θ₁ = ½(φ₀₁ − φ₁₂), θ₂ = ½(φ₂₃ − φ₁₂) (φ_ab the angle of x_b − x_a: half the
//!   boundary's turn at the node). A node where the boundary turns by more than
//!   [`SHARP_TURN_DEG`] (80°: the corners of rectangles, dies, blocks) is a feature corner and
//!   keeps the chord (θ = 0), as does a node without a neighbour; between
//!   [`SMOOTH_TURN_DEG`] (50°) and 80° the smoothing is phased out as below. A node that is nearly flat
//!   (turn β below [`FLAT_TURN_DEG`] = 0.1°) is not smoothed either, and between 0.1° and 0.3°
//!   the smoothing is phased in: θ = ∓½ β w(β) with a C¹ smoothstep w from 0 to 1 (there the
//!   two segments' tangents differ by β (1 − w) < 0.3°, a small kink that keeps flat faces
//!   exactly as the segment kernel has them, see [`FLAT_TURN_DEG`]).
//! * Cubic Hermite curve, ξ ∈ [0, 1]: c(ξ) = h₀₀ x₁ + h₀₁ x₂ + h₁₀ R(θ₁) d + h₁₁ R(θ₂) d, with
//!   h₀₀ = 2ξ³ − 3ξ² + 1, h₀₁ = 1 − h₀₀, h₁₀ = ξ³ − 2ξ² + ξ, h₁₁ = ξ³ − ξ² (R(θ) d = ℓ T). It
//!   passes through the nodes, and two segments that share a node share its tangent direction
//!   T there, so the surface is G¹ (normal continuous) across the nodes. On a straight master
//!   (θ₁ = θ₂ = 0) c(ξ) = x₁ + ξ d exactly. Outside [0, 1] the cubic itself is used (a pair
//!   frozen for a step whose slave slides past the segment's end). Continuing the curve along
//!   its end tangents instead (C¹, a closest point always exists, like the segment kernel's
//!   infinite line) was tried and measured worse: 5.2.1 jammed at 0.969 with Newton cycling at
//!   a relative residual of 7e-5 (5.2.2 reached 0.99 in 21 steps, 5.1.3 still failed at 0.80).
//! * Closest-point projection: ξ solves F(ξ) = (x_s − c(ξ))·c′(ξ) = 0 at the closest point of
//!   the curve over ξ ∈ [−0.25, 1.25] (sampled, then Newton safeguarded by bisection; a minimum
//!   needs F′ = −c′·c′ + (x_s − c)·c″ < 0, i.e. a penetration below the radius of curvature). Normal ν = (c′_y, −c′_x)/|c′| (outward, as n of a segment), gap
//!   g = (x_s − c(ξ))·ν, tangential gap g_T = (ξ − ξ_a) ℓ as in the segment kernel.
//! * Force: the virtual work of the pair is taken at **fixed end angles**,
//!   f_c = A(−p_N δg + t_T δg_T) with δq = ∂q/∂(x_s, x₁, x₂)|_θ: the force acts on the slave and
//!   on the segment's own two nodes only. Because the projection is a closest point,
//!   δg/δx_s = ν (the slave is pushed along the smoothed normal); the master nodes take the
//!   reaction of the curve point c(ξ) split as its virtual motion at fixed θ,
//!   δc = h₀₀ δx₁ + h₀₁ δx₂ + (h₁₀ R(θ₁) + h₁₁ R(θ₂)) δd. The pair's resultant force and moment
//!   vanish (δc of a rigid motion is that rigid motion, since R(θ) commutes with 2D rotations).
//!   On a straight master δc = (1 − ξ) δx₁ + ξ δx₂, so the force is the segment kernel's to
//!   round-off (the contact patch test is unchanged). The fully variational choice
//!   f = −p A ∇g (θ differentiated too) spreads the reaction of a straight master onto the
//!   neighbours 0 and 3 and fails the patch test (σ_yy off by 3.2 % instead of 0.8 %).
//! * Tangent: the full derivative of that force, θ = θ(x₀, x₁, x₂, x₃) included, over the 10
//!   dofs `[s, 1, 2, 0, 3]` (x, y each): K_c = A[−δg⊗dp_N − p_N d(δg) + δg_T⊗dt_T + t_T d(δg_T)]
//!   with dp_N = −ε_N dg (dg the full gradient), dt_T = ε_T dg_T (stick) or μ sign dp_N (slip).
//!   It is not symmetric (the force is not the gradient of a potential), so a model with the
//!   smoothed normal and particle pairs uses the LU solver.
//!
//! The derivatives are computed exactly by second-order forward differentiation ([`D`]:
//! value, gradient and Hessian over x_s, x₁, x₂, θ₁, θ₂), with dθ/dx from
//! ∂φ_ab/∂x_b = −∂φ_ab/∂x_a = (−v_y, v_x)/|v|², v = x_b − x_a. The projection ξ(x) is implicit;
//! starting from the converged value ξ* (a constant), two Newton steps in that arithmetic give
//! ξ with exact first and second derivatives (each step doubles the order to which the
//! derivatives are right: the error of the constant start is O(|δx|), after one step
//! O(|δx|²), after two O(|δx|⁴)).
//!
//! # Limits
//!
//! The surface passes through the nodes, so near a smoothed convex corner it bulges outwards
//! of the polygon by at most (4/27) ℓ sin θ (θ the angle between T and the chord: 22.5° at an
//! octagon corner, 0.057 ℓ); the finite elements themselves stay polygonal. Beyond the radius
//! of curvature of the surface (penetrations deeper than ~ℓ/3 near a corner) the projection may
//! have no minimum; the pair is then inactive for that evaluation (logged at debug level).
//!
//! Measured (2026-11-22, release): the 4 × 4 asphalt octagons (5.2.1 lateral, 5.2.2 vertical)
//! reach solid ratio 0.99 (152 steps each; `segment` jams at 0.923 and 0.958) with wall
//! pressures at 0.90 within 0.01 % of `segment`; the aluminium ellipses reach their targets
//! laterally and vertically (5.1.1, 5.1.2, in 59 and 54 steps instead of 297 and 126, wall
//! pressures at 0.90 differing from `segment` by 1–2 % and 5–15 %: another rearrangement of
//! the frictionless particles) but the biaxial job 5.1.3 fails at solid ratio 0.797 (Newton
//! does not converge while new apex contacts form; `segment` completes it). Hence `segment`
//! stays the default.

use std::ops::{Add, Mul, Neg, Sub};

/// Number of dofs of a smoothed pair: slave, master 1, master 2, neighbour 0, neighbour 3.
pub const NDOF: usize = 10;

/// A master node is a feature corner (not smoothed) when the boundary turns there by more than
/// this angle (degrees): rectangle and die corners (90°) stay sharp. Between
/// [`SMOOTH_TURN_DEG`] and this angle the smoothing is phased out (see the module docs): a hard
/// threshold made the surface jump when a corner's turn crossed it during the Newton iterations
/// (the apexes of the 5.1.3 ellipses turn by ~57°).
pub const SHARP_TURN_DEG: f64 = 80.0;

/// Turns up to this angle (degrees) are smoothed in full: the 45° corners of octagons and the
/// small turns of polygonal discs and ellipses.
pub const SMOOTH_TURN_DEG: f64 = 50.0;

/// A node where the boundary turns by less than this angle (degrees) is not smoothed, and the
/// smoothing is phased in up to three times this angle (see the module docs): a flat contact face
/// that bends a little under load keeps the segment kernel's surface, and with it its contact
/// patch test (σ_yy within 0.80 % of the exact value, as with `segment`; smoothing every node
/// gives 1.26 %). Measured on the 4 × 4 asphalt octagons (5.2.1): with 0.1° the run reaches
/// 0.99 (152 steps, the step size drops near 0.96); with 1° (band 1°–3°) it jams at 0.956
/// (Newton stalls at a relative residual of 1.2e-5); without the threshold it reaches 0.99 in
/// 22 steps but fails the patch test's 1 %.
pub const FLAT_TURN_DEG: f64 = 0.1;

/// Second-order forward-mode number: value, gradient and Hessian with respect to the
/// [`NDOF`] dofs of a pair.
#[derive(Clone, Copy, Debug)]
pub struct D {
    pub v: f64,
    pub g: [f64; NDOF],
    pub h: [[f64; NDOF]; NDOF],
}

impl D {
    fn cst(v: f64) -> D {
        D { v, g: [0.0; NDOF], h: [[0.0; NDOF]; NDOF] }
    }

    fn var(v: f64, i: usize) -> D {
        let mut d = D::cst(v);
        d.g[i] = 1.0;
        d
    }

    /// f(self) given f, f′, f″ at self.v.
    fn chain(self, f0: f64, f1: f64, f2: f64) -> D {
        let mut r = D::cst(f0);
        for i in 0..NDOF {
            r.g[i] = f1 * self.g[i];
            for j in 0..NDOF {
                r.h[i][j] = f1 * self.h[i][j] + f2 * self.g[i] * self.g[j];
            }
        }
        r
    }
}

impl Add for D {
    type Output = D;
    fn add(mut self, o: D) -> D {
        self.v += o.v;
        for i in 0..NDOF {
            self.g[i] += o.g[i];
            for j in 0..NDOF {
                self.h[i][j] += o.h[i][j];
            }
        }
        self
    }
}

impl Sub for D {
    type Output = D;
    fn sub(self, o: D) -> D {
        self + (-o)
    }
}

impl Neg for D {
    type Output = D;
    fn neg(mut self) -> D {
        self.v = -self.v;
        for i in 0..NDOF {
            self.g[i] = -self.g[i];
            for j in 0..NDOF {
                self.h[i][j] = -self.h[i][j];
            }
        }
        self
    }
}

impl Mul for D {
    type Output = D;
    fn mul(self, o: D) -> D {
        let mut r = D::cst(self.v * o.v);
        for i in 0..NDOF {
            r.g[i] = self.v * o.g[i] + o.v * self.g[i];
            for j in 0..NDOF {
                r.h[i][j] = self.v * o.h[i][j] + o.v * self.h[i][j] + self.g[i] * o.g[j] + o.g[i] * self.g[j];
            }
        }
        r
    }
}

/// The arithmetic the surface formulas are written in: f64 for the projection, [`D`] for the
/// derivatives.
pub trait Scalar: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self> {
    fn c(v: f64) -> Self;
    fn val(&self) -> f64;
    fn sqrt(self) -> Self;
    fn recip(self) -> Self;
    fn sin(self) -> Self;
    fn cos(self) -> Self;
}

impl Scalar for f64 {
    fn c(v: f64) -> Self {
        v
    }
    fn val(&self) -> f64 {
        *self
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn recip(self) -> Self {
        1.0 / self
    }
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn cos(self) -> Self {
        f64::cos(self)
    }
}

impl Scalar for D {
    fn c(v: f64) -> Self {
        D::cst(v)
    }
    fn val(&self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * self.v))
    }
    fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }
    fn sin(self) -> Self {
        let (s, c) = self.v.sin_cos();
        self.chain(s, c, -s)
    }
    fn cos(self) -> Self {
        let (s, c) = self.v.sin_cos();
        self.chain(c, -s, -c)
    }
}

type V<S> = [S; 2];

fn sub<S: Scalar>(a: V<S>, b: V<S>) -> V<S> {
    [a[0] - b[0], a[1] - b[1]]
}

fn dot<S: Scalar>(a: V<S>, b: V<S>) -> S {
    a[0] * b[0] + a[1] * b[1]
}

fn norm<S: Scalar>(a: V<S>) -> S {
    dot(a, a).sqrt()
}

fn unit<S: Scalar>(a: V<S>) -> V<S> {
    let r = norm(a).recip();
    [a[0] * r, a[1] * r]
}

/// The master side of a smoothed pair: segment 1 → 2 and its boundary neighbours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Master {
    pub x1: [f64; 2],
    pub x2: [f64; 2],
    /// The node before 1 on the body's boundary (None at an open end).
    pub prev: Option<[f64; 2]>,
    /// The node after 2.
    pub next: Option<[f64; 2]>,
}

/// Angle of the vector `v` and its gradient with respect to the vector's head (the tail's is
/// the negative): ∂φ/∂x_b = (−v_y, v_x)/|v|².
fn angle(v: [f64; 2]) -> (f64, [f64; 2]) {
    let q = v[0] * v[0] + v[1] * v[1];
    (v[1].atan2(v[0]), [-v[1] / q, v[0] / q])
}

fn wrap(a: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    a - tau * ((a + std::f64::consts::PI) / tau).floor()
}

/// C¹ smoothstep from 0 at `a0` to 1 at `a1` (either order) and its derivative.
fn smoothstep(a: f64, a0: f64, a1: f64) -> (f64, f64) {
    let u = (a - a0) / (a1 - a0);
    if u <= 0.0 {
        (0.0, 0.0)
    } else if u >= 1.0 {
        (1.0, 0.0)
    } else {
        (u * u * (3.0 - 2.0 * u), 6.0 * u * (1.0 - u) / (a1 - a0))
    }
}

/// The smoothed share s(β) = β w(β) of a boundary turn β (radians) and its derivative s′:
/// w = 0 up to [`FLAT_TURN_DEG`], rising to 1 at 3 × [`FLAT_TURN_DEG`], 1 up to
/// [`SMOOTH_TURN_DEG`], falling to 0 at [`SHARP_TURN_DEG`] and 0 beyond (C¹ smoothsteps
/// u²(3 − 2u) in both bands, so the surface changes smoothly as the corners deform).
fn blend(beta: f64) -> (f64, f64) {
    let a = beta.abs();
    let (w0, d0) = smoothstep(a, FLAT_TURN_DEG.to_radians(), 3.0 * FLAT_TURN_DEG.to_radians());
    let (w1, d1) = smoothstep(a, SHARP_TURN_DEG.to_radians(), SMOOTH_TURN_DEG.to_radians());
    let w = w0 * w1;
    (beta * w, w + a * (d0 * w1 + w0 * d1))
}

/// The end angles θ₁, θ₂ of the nodal tangents from the chord (T = R(θ) t₁₂) and their
/// gradients over the physical dofs `[s, 1, 2, 0, 3]` (zero for the slave, and for a sharp,
/// flat or open end): θ₁ = −½ s(β₁), β₁ = φ₁₂ − φ₀₁; θ₂ = ½ s(β₂), β₂ = φ₂₃ − φ₁₂ (see the module docs).
fn end_angles(m: &Master) -> ([f64; 2], [[f64; NDOF]; 2]) {
    let d = [m.x2[0] - m.x1[0], m.x2[1] - m.x1[1]];
    let (phi12, g12) = angle(d);
    let mut th = [0.0; 2];
    let mut jac = [[0.0; NDOF]; 2];
    if let Some(x0) = m.prev {
        let e = [m.x1[0] - x0[0], m.x1[1] - x0[1]];
        if e[0] != 0.0 || e[1] != 0.0 {
            let (phi01, g01) = angle(e);
            let (sb, ds) = blend(wrap(phi12 - phi01));
            th[0] = -0.5 * sb;
            // dβ₁: x0 +g01, x1 −g01 − g12, x2 +g12
            for k in 0..2 {
                jac[0][6 + k] = -0.5 * ds * g01[k];
                jac[0][2 + k] = 0.5 * ds * (g01[k] + g12[k]);
                jac[0][4 + k] = -0.5 * ds * g12[k];
            }
        }
    }
    if let Some(x3) = m.next {
        let e = [x3[0] - m.x2[0], x3[1] - m.x2[1]];
        if e[0] != 0.0 || e[1] != 0.0 {
            let (phi23, g23) = angle(e);
            let (sb, ds) = blend(wrap(phi23 - phi12));
            th[1] = 0.5 * sb;
            // dβ₂: x3 +g23, x2 −g23 − g12, x1 +g12
            for k in 0..2 {
                jac[1][8 + k] = 0.5 * ds * g23[k];
                jac[1][4 + k] = -0.5 * ds * (g23[k] + g12[k]);
                jac[1][2 + k] = 0.5 * ds * g12[k];
            }
        }
    }
    (th, jac)
}

/// The curve of one segment in arithmetic S: c(ξ) = h₀₀ x₁ + h₀₁ x₂ + h₁₀ R(θ₁) d + h₁₁ R(θ₂) d.
struct Curve<S> {
    x1: V<S>,
    x2: V<S>,
    l: S,
    a1: V<S>,
    a2: V<S>,
}

fn rotate<S: Scalar>(th: S, d: V<S>) -> V<S> {
    let (c, s) = (th.cos(), th.sin());
    [c * d[0] - s * d[1], s * d[0] + c * d[1]]
}

impl<S: Scalar> Curve<S> {
    fn new(x1: V<S>, x2: V<S>, th: [S; 2]) -> Option<Self> {
        let d = sub(x2, x1);
        let l = norm(d);
        if !(l.val() > 0.0 && l.val().is_finite()) {
            return None;
        }
        Some(Curve { x1, x2, l, a1: rotate(th[0], d), a2: rotate(th[1], d) })
    }

    /// c(ξ), c′(ξ), c″(ξ) (the cubic, also outside [0, 1]).
    fn eval(&self, xi: S) -> [V<S>; 3] {
        let one = S::c(1.0);
        let (x2, x3) = (xi * xi, xi * xi * xi);
        let two = S::c(2.0);
        let three = S::c(3.0);
        let six = S::c(6.0);
        // basis and its two derivatives: [h00, h01, h10, h11]
        let h = [two * x3 - three * x2 + one, three * x2 - two * x3, x3 - two * x2 + xi, x3 - x2];
        let h1 = [six * x2 - six * xi, six * xi - six * x2, three * x2 - S::c(4.0) * xi + one, three * x2 - two * xi];
        let h2 = [S::c(12.0) * xi - six, six - S::c(12.0) * xi, six * xi - S::c(4.0), six * xi - two];
        let comb = |b: &[S; 4]| -> V<S> {
            let mut r = [S::c(0.0); 2];
            for k in 0..2 {
                r[k] = b[0] * self.x1[k] + b[1] * self.x2[k] + b[2] * self.a1[k] + b[3] * self.a2[k];
            }
            r
        };
        [comb(&h), comb(&h1), comb(&h2)]
    }

    /// One Newton step of the projection of `xs`: ξ − F/F′, and F′.
    fn newton(&self, xs: V<S>, xi: S) -> (S, f64) {
        let [c, c1, c2] = self.eval(xi);
        let r = sub(xs, c);
        let f = dot(r, c1);
        let fp = dot(r, c2) - dot(c1, c1);
        (xi - f * fp.recip(), fp.val())
    }
}

/// Closest-point projection of a slave node on the smoothed master (f64 only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothProjection {
    /// Curve parameter of the closest point (in [0, 1] on the segment, extrapolated outside).
    pub xi: f64,
    /// Signed gap along the smoothed normal, negative = penetration (mm).
    pub gap: f64,
    /// Outward unit normal of the smoothed surface at ξ.
    pub normal: [f64; 2],
    /// Chord length ℓ (mm).
    pub length: f64,
}

/// Newton iterations of the projection at most.
const MAX_NEWTON: usize = 50;

/// Parameter range searched for the closest point, and the number of samples in it.
const XI_RANGE: (f64, f64) = (-0.25, 1.25);
const SAMPLES: usize = 30;

/// Closest point of the curve to `xs` over ξ ∈ [`XI_RANGE`]: the best of [`SAMPLES`] + 1
/// samples of |x_s − c(ξ)|², refined by Newton on F = (x_s − c)·c′ = −½ d|x_s − c|²/dξ
/// safeguarded by bisection inside the bracket of the neighbouring samples (F goes from + to −
/// across a minimum). `None` when the best sample is an end of the range (no minimum inside)
/// or the refined point is not a minimum (F′ ≥ 0).
fn project_f64(curve: &Curve<f64>, xs: [f64; 2]) -> Option<f64> {
    let (lo, hi) = XI_RANGE;
    let step = (hi - lo) / SAMPLES as f64;
    let dist2 = |xi: f64| {
        let c = curve.eval(xi)[0];
        let r = sub(xs, c);
        dot(r, r)
    };
    let mut best = (0, f64::INFINITY);
    for k in 0..=SAMPLES {
        let d = dist2(lo + step * k as f64);
        if d < best.1 {
            best = (k, d);
        }
    }
    if best.0 == 0 || best.0 == SAMPLES {
        return None;
    }
    let fval = |xi: f64| {
        let [c, c1, c2] = curve.eval(xi);
        let r = sub(xs, c);
        (dot(r, c1), dot(r, c2) - dot(c1, c1))
    };
    let (mut a, mut b) = (lo + step * (best.0 - 1) as f64, lo + step * (best.0 + 1) as f64);
    let (fa, fb) = (fval(a).0, fval(b).0);
    if !(fa >= 0.0 && fb <= 0.0) {
        return None;
    }
    let mut xi = lo + step * best.0 as f64;
    for _ in 0..MAX_NEWTON {
        let (f, fp) = fval(xi);
        if f == 0.0 {
            break;
        }
        if f > 0.0 {
            a = xi;
        } else {
            b = xi;
        }
        let newton = xi - f / fp;
        let next = if fp < 0.0 && newton > a && newton < b { newton } else { 0.5 * (a + b) };
        let moved = (next - xi).abs();
        xi = next;
        if moved <= 1e-15 * (1.0 + xi.abs()) || b - a <= 1e-15 * (1.0 + xi.abs()) {
            break;
        }
    }
    (fval(xi).1 < 0.0 && xi.is_finite()).then_some(xi)
}

/// Closest-point projection of `xs` on the smoothed master `m` (f64). `None` for a degenerate
/// segment or when the projection has no minimum (see the module docs).
pub fn smooth_project(xs: [f64; 2], m: &Master) -> Option<SmoothProjection> {
    let (th, _) = end_angles(m);
    let curve = Curve::<f64>::new(m.x1, m.x2, th)?;
    let xi = project_f64(&curve, xs)?;
    let [c, c1, _] = curve.eval(xi);
    let n = unit([c1[1], -c1[0]]);
    Some(SmoothProjection { xi, gap: dot(sub(xs, c), n), normal: n, length: curve.l })
}

/// The point c(ξ) of the smoothed master `m` (f64; the cubic, also outside [0, 1]). `None` for
/// a degenerate segment.
pub fn smooth_point(m: &Master, xi: f64) -> Option<[f64; 2]> {
    let (th, _) = end_angles(m);
    let curve = Curve::<f64>::new(m.x1, m.x2, th)?;
    Some(curve.eval(xi)[0])
}

/// Gap g and tangential gap g_T as functions of (x_s, x₁, x₂, θ₁, θ₂) — slots 0..6 and 6, 7 of
/// [`D`] — with their gradients and Hessians, at the converged projection `xi` (see the module
/// docs: two Newton steps in second-order arithmetic).
fn derivatives(xs: [f64; 2], m: &Master, th: [f64; 2], xi: f64, xi_anchor: f64) -> Option<(D, D)> {
    let var = |p: [f64; 2], i: usize| [D::var(p[0], 2 * i), D::var(p[1], 2 * i + 1)];
    let s = var(xs, 0);
    let curve = Curve::new(var(m.x1, 1), var(m.x2, 2), [D::var(th[0], 6), D::var(th[1], 7)])?;
    let mut z = D::cst(xi);
    for _ in 0..2 {
        let (next, fp) = curve.newton(s, z);
        if !(fp < 0.0) {
            return None;
        }
        z = next;
    }
    let [c, c1, _] = curve.eval(z);
    let n = unit([c1[1], -c1[0]]);
    let g = dot(sub(s, c), n);
    let gt = (z - D::cst(xi_anchor)) * curve.l;
    Some((g, gt))
}

/// Variation at fixed end angles (the force) and its full derivative (the tangent) of a
/// quantity q(x_s, x₁, x₂, θ₁, θ₂) with θ = θ(x): returns (δq|θ over the 10 physical dofs, zero
/// for the neighbours; dq/dx in full; d(∂q/∂x_i|θ)/dx_j).
fn split(q: &D, jac: &[[f64; NDOF]; 2]) -> ([f64; NDOF], [f64; NDOF], [[f64; NDOF]; NDOF]) {
    let mut var = [0.0; NDOF];
    let mut full = [0.0; NDOF];
    let mut h = [[0.0; NDOF]; NDOF];
    for j in 0..NDOF {
        let own = if j < 6 { q.g[j] } else { 0.0 };
        full[j] = own + q.g[6] * jac[0][j] + q.g[7] * jac[1][j];
    }
    for i in 0..6 {
        var[i] = q.g[i];
        for j in 0..NDOF {
            let own = if j < 6 { q.h[i][j] } else { 0.0 };
            h[i][j] = own + q.h[i][6] * jac[0][j] + q.h[i][7] * jac[1][j];
        }
    }
    (var, full, h)
}

/// The variations of the gap g and the tangential gap g_T of a slave node at `xs` whose
/// closest point on the smoothed master `m` is at `xi`, g_T measured from the anchor `anchor`
/// (see the module docs: the force at fixed end angles, the tangent in full).
#[derive(Clone, Copy, Debug)]
pub struct Variations {
    /// g_T (mm).
    pub gt: f64,
    /// δg at fixed end angles (the force), dg in full, d(δg).
    pub gv: [f64; NDOF],
    pub gf: [f64; NDOF],
    pub gh: [[f64; NDOF]; NDOF],
    /// The same for g_T.
    pub tv: [f64; NDOF],
    pub tf: [f64; NDOF],
    pub th: [[f64; NDOF]; NDOF],
}

/// [`Variations`] of a pair, or `None` when the projection has no minimum in second-order
/// arithmetic (the pair is then inactive).
pub fn variations(xs: [f64; 2], m: &Master, xi: f64, anchor: f64) -> Option<Variations> {
    let (th, jac) = end_angles(m);
    let (gd, gtd) = derivatives(xs, m, th, xi, anchor)?;
    let (gv, gf, gh) = split(&gd, &jac);
    let (tv, tf, th) = split(&gtd, &jac);
    Some(Variations { gt: gtd.v, gv, gf, gh, tv, tf, th })
}
