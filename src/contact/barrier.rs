//! Barrier contact kernels (Incremental Potential Contact: Li et al., "Incremental Potential
//! Contact: Intersection- and Inversion-free, Large-Deformation Dynamics", ACM TOG 39(4), 2020):
//! the unsigned distance of a point to an edge and to a rigid wall with its first and second
//! derivatives, the smoothly clamped log barrier on it, the projection of a pair's Hessian onto
//! the positive semi-definite cone, and the continuous collision detection (CCD) of 2D
//! point–edge and point–wall motion along a straight trajectory.
//!
//! Like the other enforcement kernels these read only coordinates: no mesh, no node number,
//! no matrix. [`super::barrier_problem`] sums them over the pairs of a model.
//!
//! # Distances
//!
//! Everything works on the **squared** distance d² (smooth where the distance itself is not).
//! A point p and an edge (a, b), with e = b − a and the projection parameter
//! s = (p − a)·e / |e|², lie in one of three regions ([`PointEdgeRegion`]): s ≤ 0 (the closest
//! point is a, d² = |p − a|²), s ≥ 1 (it is b), or the interior (d² = (e × (p − a))² / |e|²).
//! d² is C¹ across the region boundaries (its gradient is continuous, its Hessian jumps), as in
//! IPC. Dofs are ordered `[p_x, p_y, a_x, a_y, b_x, b_y]`.
//!
//! A node against a rigid wall (a half-plane with unit normal n into the domain through a
//! point w): d = (p − w)·n, d² its square; the wall is not a dof.
//!
//! # The barrier
//!
//! b(x; x̂) = −(x − x̂)² ln(x / x̂) for 0 < x < x̂, 0 for x ≥ x̂, with x = d² and x̂ = d̂²: the
//! function IPC uses (and `ipctk`'s `BarrierPotential(dhat, stiffness)` evaluates as
//! κ b(d², d̂²)). It is C² at the clamp x = x̂ (b = b' = b'' = 0 there) and tends to +∞ as the
//! distance tends to zero, so a minimiser never lets two boundaries touch. A pair contributes
//! the energy κ b(d², d̂²) (per unit thickness: energy in N·mm/mm = N,
//! b in mm⁴, so κ in N/mm⁴; see [`barrier_term`]).
//!
//! # Continuous collision detection
//!
//! Along a straight trajectory x(t) = x₀ + t Δx, t ∈ [0, 1], a point hits an edge when
//! e(t) × (p(t) − a(t)) = 0 (a quadratic in t) with the projection parameter in [0, 1];
//! [`point_edge_toi`] returns the smallest such t. A point hits a wall moving along its normal
//! when the signed distance, linear in t, reaches zero ([`point_wall_toi`]). A line search that
//! steps to [`CCD_RESCALING`] × the smallest time of impact keeps every iterate free of
//! crossings with a margin (IPC's conservative rescaling, also `ipctk`'s default, 0.8).

/// The fraction of the first time of impact a collision-free step may take (IPC's conservative
/// rescaling; `ipctk::TightInclusionCCD.DEFAULT_CONSERVATIVE_RESCALING` is also 0.8): the step
/// stops at 80 % of the way to the first contact, so the next distance is about a fifth of the
/// last one at the least, never zero.
pub const CCD_RESCALING: f64 = 0.8;

/// Where the closest point of an edge to a point lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointEdgeRegion {
    /// At the first end a (s ≤ 0).
    A,
    /// At the second end b (s ≥ 1).
    B,
    /// Inside the edge (0 < s < 1).
    Interior,
}

/// A squared distance and its derivatives over N dofs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SqDistance<const N: usize> {
    /// d² (mm²).
    pub d2: f64,
    /// ∂d²/∂x (mm).
    pub grad: [f64; N],
    /// ∂²d²/∂x² (dimensionless), symmetric.
    pub hess: [[f64; N]; N],
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// The projection parameter s = (p − a)·e / |e|² of p on edge (a, b), e = b − a (0 for a
/// degenerate edge).
pub fn projection_parameter(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let e = sub(b, a);
    let l = dot(e, e);
    if !(l > 0.0) {
        return 0.0;
    }
    dot(sub(p, a), e) / l
}

/// The region of the closest point of edge (a, b) to p. A degenerate edge (a = b) is `A`.
pub fn point_edge_region(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> PointEdgeRegion {
    let s = projection_parameter(p, a, b);
    if s <= 0.0 {
        PointEdgeRegion::A
    } else if s >= 1.0 {
        PointEdgeRegion::B
    } else {
        PointEdgeRegion::Interior
    }
}

/// Squared distance of p to edge (a, b), with its gradient and Hessian over
/// `[p_x, p_y, a_x, a_y, b_x, b_y]` (see the module docs for the three regions).
pub fn point_edge_sq_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> SqDistance<6> {
    match point_edge_region(p, a, b) {
        PointEdgeRegion::A => point_point(p, a, 1),
        PointEdgeRegion::B => point_point(p, b, 2),
        PointEdgeRegion::Interior => point_line(p, a, b),
    }
}

/// d² = |p − q|² with q the node in slot `k` (1 = a, 2 = b) of the 6-dof layout: the distance
/// of p to an end of an edge, whether or not it is the edge's closest point.
pub fn point_point(p: [f64; 2], q: [f64; 2], k: usize) -> SqDistance<6> {
    let r = sub(p, q);
    let mut out = SqDistance { d2: dot(r, r), grad: [0.0; 6], hess: [[0.0; 6]; 6] };
    for c in 0..2 {
        out.grad[c] = 2.0 * r[c];
        out.grad[2 * k + c] = -2.0 * r[c];
        out.hess[c][c] = 2.0;
        out.hess[2 * k + c][2 * k + c] = 2.0;
        out.hess[c][2 * k + c] = -2.0;
        out.hess[2 * k + c][c] = -2.0;
    }
    out
}

/// d² = c² / L of p to the line through a and b, c = e × (p − a), L = |e|², e = b − a (the
/// point–edge distance in the edge's interior; also at an end where p lies exactly on the
/// end's normal line, where it equals the distance to that end with a Hessian that is the
/// limit from the interior side).
pub fn point_line(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> SqDistance<6> {
    let e = sub(b, a);
    let r = sub(p, a);
    let c = cross(e, r);
    let l = dot(e, e);
    // ∇c over (p, a, b): c = b×p − b×a − a×p
    let gc = [-e[1], e[0], e[1] - r[1], r[0] - e[0], r[1], -r[0]];
    // ∇L: 2e on b, −2e on a
    let gl = [0.0, 0.0, -2.0 * e[0], -2.0 * e[1], 2.0 * e[0], 2.0 * e[1]];
    // ∇²c: the cross product u×v has ∂²/∂u∂v = J = [[0, 1], [−1, 0]]
    let j = [[0.0, 1.0], [-1.0, 0.0]];
    let mut hc = [[0.0; 6]; 6];
    let mut put = |u: usize, v: usize, sign: f64| {
        // term sign·(u × v): block (u, v) = sign J, block (v, u) = sign Jᵀ
        for i in 0..2 {
            for k in 0..2 {
                hc[2 * u + i][2 * v + k] += sign * j[i][k];
                hc[2 * v + k][2 * u + i] += sign * j[i][k];
            }
        }
    };
    put(2, 0, 1.0); // b × p
    put(2, 1, -1.0); // −b × a
    put(1, 0, -1.0); // −a × p
    // ∇²L: 2I on (a, a) and (b, b), −2I on (a, b) and (b, a)
    let mut hl = [[0.0; 6]; 6];
    for i in 0..2 {
        hl[2 + i][2 + i] = 2.0;
        hl[4 + i][4 + i] = 2.0;
        hl[2 + i][4 + i] = -2.0;
        hl[4 + i][2 + i] = -2.0;
    }
    let mut out = SqDistance { d2: c * c / l, grad: [0.0; 6], hess: [[0.0; 6]; 6] };
    for i in 0..6 {
        out.grad[i] = 2.0 * c / l * gc[i] - c * c / (l * l) * gl[i];
        for k in 0..6 {
            out.hess[i][k] = 2.0 / l * gc[i] * gc[k] + 2.0 * c / l * hc[i][k]
                - 2.0 * c / (l * l) * (gc[i] * gl[k] + gl[i] * gc[k])
                - c * c / (l * l) * hl[i][k]
                + 2.0 * c * c / (l * l * l) * gl[i] * gl[k];
        }
    }
    out
}

/// Signed distance d = (p − w)·n of p to a wall through `point` with unit `normal` (into the
/// domain), and the squared distance d² with its derivatives over `[p_x, p_y]`.
pub fn point_wall_sq_distance(p: [f64; 2], point: [f64; 2], normal: [f64; 2]) -> (f64, SqDistance<2>) {
    let d = dot(sub(p, point), normal);
    let n = normal;
    let out = SqDistance {
        d2: d * d,
        grad: [2.0 * d * n[0], 2.0 * d * n[1]],
        hess: [[2.0 * n[0] * n[0], 2.0 * n[0] * n[1]], [2.0 * n[1] * n[0], 2.0 * n[1] * n[1]]],
    };
    (d, out)
}

/// The clamped log barrier b(x; x̂) = −(x − x̂)² ln(x/x̂) on 0 < x < x̂ and its first two
/// derivatives by x, `[b, b', b'']`; zero for x ≥ x̂, +∞ (with −∞, +∞ derivatives) for x ≤ 0.
pub fn clamped_log(x: f64, xh: f64) -> [f64; 3] {
    if x >= xh {
        return [0.0; 3];
    }
    if !(x > 0.0) {
        return [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY];
    }
    let g = x - xh;
    let ln = (x / xh).ln();
    [-g * g * ln, -2.0 * g * ln - g * g / x, -2.0 * ln - 4.0 * g / x + g * g / (x * x)]
}

/// A pair's barrier energy κ b(d², d̂²) (N per unit thickness), its gradient (N/mm) and Hessian
/// (N/mm²) over the pair's dofs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BarrierTerm<const N: usize> {
    pub energy: f64,
    pub grad: [f64; N],
    pub hess: [[f64; N]; N],
}

/// The barrier term of one pair at squared distance `d`, activation distance `dhat` (mm) and
/// stiffness `kappa` (N/mm⁴); `None` when the pair is at or beyond d̂ (no contribution).
/// With `project`, the Hessian is projected onto the positive semi-definite matrices
/// ([`project_psd`]), which Newton on the incremental potential needs (the exact Hessian of
/// the barrier on a point–edge distance is indefinite).
pub fn barrier_term<const N: usize>(d: &SqDistance<N>, dhat: f64, kappa: f64, project: bool) -> Option<BarrierTerm<N>> {
    let xh = dhat * dhat;
    if d.d2 >= xh {
        return None;
    }
    let [b, b1, b2] = clamped_log(d.d2, xh);
    let mut t = BarrierTerm { energy: kappa * b, grad: [0.0; N], hess: [[0.0; N]; N] };
    for i in 0..N {
        t.grad[i] = kappa * b1 * d.grad[i];
        for k in 0..N {
            t.hess[i][k] = kappa * (b2 * d.grad[i] * d.grad[k] + b1 * d.hess[i][k]);
        }
    }
    if project {
        project_psd(&mut t.hess);
    }
    Some(t)
}

/// Replace a symmetric matrix by its projection onto the positive semi-definite cone (negative
/// eigenvalues set to zero), in place. The eigen-decomposition is the cyclic Jacobi method on
/// the stack (no allocation; N ≤ 8 here), stopped when the off-diagonal part is within 1e-13 of
/// the norm: the eigenvalues are then within about that of the norm, a tangent's accuracy
/// (until the twenty-fifth measurement of docs/robustness.md it was 1e-15).
pub fn project_psd<const N: usize>(h: &mut [[f64; N]; N]) {
    let mut a = [[0.0; N]; N];
    for i in 0..N {
        for k in 0..N {
            a[i][k] = 0.5 * (h[i][k] + h[k][i]);
        }
    }
    let norm: f64 = a.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
    let mut v = [[0.0; N]; N];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _sweep in 0..50 {
        let off: f64 = (0..N).flat_map(|i| (0..N).filter(move |&k| k != i).map(move |k| (i, k))).map(|(i, k)| a[i][k] * a[i][k]).sum::<f64>().sqrt();
        if off <= 1e-13 * norm || off == 0.0 {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                if a[p][q].abs() <= 1e-16 * norm {
                    continue;
                }
                // the rotation that zeroes a[p][q]
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..N {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..N {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    if (0..N).all(|i| a[i][i] >= 0.0) {
        return;
    }
    // H = V diag(max(λ, 0)) Vᵀ
    for i in 0..N {
        for k in 0..N {
            h[i][k] = (0..N).map(|m| v[i][m] * a[m][m].max(0.0) * v[k][m]).sum();
        }
    }
}

/// The projection of a pair's Hessian onto the positive semi-definite matrices ([`project_psd`])
/// for a pair whose energy does not change when all its `N / 2` points move together: its
/// Hessian vanishes along the two translations, and the eigen-decomposition is made on the
/// orthogonal complement, `M = N − 2` wide (Helmert's contrasts between the points, times the
/// two directions), with the translations' eigenvalues zero. Measured on a 256-polygon
/// compaction whose tangent is mostly indefinite (docs/robustness.md, twenty-fifth
/// measurement), the projections took 18.9 % of its first 80 s on the whole 6 × 6 and 8 × 8
/// matrices and 7.2 % of its first 60 s on the reduced ones.
pub fn project_psd_relative<const N: usize, const M: usize>(h: &mut [[f64; N]; N]) {
    assert!(N == M + 2 && N % 2 == 0, "project_psd_relative: N = M + 2 and even");
    let m = N / 2;
    // the orthonormal basis Q (N × M) of the dofs' vectors with no net translation: column
    // 2k + c (k = 0 … m − 2, c the direction) is the k-th Helmert contrast of the points in
    // direction c, (1, …, 1, −(k + 1), 0, …) / √((k + 1)(k + 2))
    let mut q = [[0.0; M]; N];
    for k in 0..m - 1 {
        let w = 1.0 / (((k + 1) * (k + 2)) as f64).sqrt();
        for c in 0..2 {
            for point in 0..=k {
                q[2 * point + c][2 * k + c] = w;
            }
            q[2 * (k + 1) + c][2 * k + c] = -((k + 1) as f64) * w;
        }
    }
    project_psd_in(h, &q);
}

/// The projection ([`project_psd`]) of the Hessian of a pair whose first side is a point
/// x = (1 − ξ) c + ξ d of an edge (c, d) (dofs `[c, d, a, b]`) and whose energy depends only
/// on x − a and b − a, (a, b) the other edge: a point of an edge facing an edge. Its Hessian
/// is Jᵀ K J with J the map of the 8 dofs to those 4, so it vanishes outside the range of
/// Jᵀ, 4 wide, and the eigen-decomposition is made there: P(H) = U P(Uᵀ H U) Uᵀ with U an
/// orthonormal basis of that range. The same projection as [`project_psd_relative`]'s on the
/// 6 directions without net translation, up to round-off, on a 4 × 4 matrix instead of a
/// 6 × 6 one: 2.2 µs → 0.7 µs a pair (`cargo bench --bench projection`). Measured on
/// robustness cases 11 and 12 these projections took 9–11 % of the time.
pub fn project_psd_point_on_edge(h: &mut [[f64; 8]; 8], xi: f64) {
    // the node weights of J's two rows in each direction, x − a and b − a (nodes c, d, a, b),
    // made orthonormal (Gram–Schmidt)
    let v1 = [1.0 - xi, xi, -1.0, 0.0];
    let v2 = [0.0, 0.0, -1.0, 1.0];
    let n1 = v1.iter().map(|v| v * v).sum::<f64>().sqrt();
    let u1 = v1.map(|v| v / n1);
    let along = (0..4).map(|i| v2[i] * u1[i]).sum::<f64>();
    let w: [f64; 4] = std::array::from_fn(|i| v2[i] - along * u1[i]);
    let n2 = w.iter().map(|v| v * v).sum::<f64>().sqrt();
    let u2 = w.map(|v| v / n2);
    let mut q = [[0.0; 4]; 8];
    for node in 0..4 {
        for c in 0..2 {
            q[2 * node + c][c] = u1[node];
            q[2 * node + c][2 + c] = u2[node];
        }
    }
    project_psd_in(h, &q);
}

/// H ← Q P(QᵀHQ) Qᵀ for Q (N × M) with orthonormal columns that span the range of H.
fn project_psd_in<const N: usize, const M: usize>(h: &mut [[f64; N]; N], q: &[[f64; M]; N]) {
    // Qᵀ H Q
    let mut hq = [[0.0; M]; N];
    for i in 0..N {
        for j in 0..M {
            hq[i][j] = (0..N).map(|k| h[i][k] * q[k][j]).sum();
        }
    }
    let mut r = [[0.0; M]; M];
    for i in 0..M {
        for j in 0..M {
            r[i][j] = (0..N).map(|k| q[k][i] * hq[k][j]).sum();
        }
    }
    project_psd(&mut r);
    // H ← Q P(QᵀHQ) Qᵀ
    let mut rq = [[0.0; N]; M];
    for i in 0..M {
        for j in 0..N {
            rq[i][j] = (0..M).map(|k| r[i][k] * q[j][k]).sum();
        }
    }
    for i in 0..N {
        for j in 0..N {
            h[i][j] = (0..M).map(|k| q[i][k] * rq[k][j]).sum();
        }
    }
}

/// IPC's friction mollifier f₀ on a tangential slip y ≥ 0 (mm) with the transition slip ε
/// (mm), and its first two derivatives, `[f₀, f₀', f₀'']`: f₀(y) = −y³/(3ε²) + y²/ε + ε/3 below
/// ε, y above (C² at ε; f₀' rises from 0 to 1, so the friction force μλ f₀' reaches the
/// Coulomb value μλ once the slip exceeds ε — the static regime is an elastic slip below ε).
pub fn friction_mollifier(y: f64, eps: f64) -> [f64; 3] {
    if y >= eps {
        return [y, 1.0, 0.0];
    }
    [-y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0, -y * y / (eps * eps) + 2.0 * y / eps, -2.0 * y / (eps * eps) + 2.0 / eps]
}

/// The lagged friction of a pair (IPC's lagged, mollified Coulomb friction): the potential
/// μλ f₀(|u_T|) of the tangential slip u_T = w · Δx over the step, with the normal force λ
/// (N/mm), the tangent weights w (the tangent at the closest point times the pair's barycentric
/// weights: +1 on the node, −(1 − s) and −s on the edge's ends) and the slip transition ε
/// frozen at the lagged state; `dx` is the pair's displacement since the start of the step.
/// Its gradient is the friction force (a contribution to the internal force) and its Hessian
/// μλ f₀''(|u_T|) w wᵀ is positive semi-definite.
pub fn friction_term<const N: usize>(w: &[f64; N], dx: &[f64; N], mu_lambda: f64, eps: f64) -> BarrierTerm<N> {
    let y: f64 = w.iter().zip(dx).map(|(a, b)| a * b).sum();
    let [f0, f1, f2] = friction_mollifier(y.abs(), eps);
    let sign = if y < 0.0 { -1.0 } else { 1.0 };
    let mut t = BarrierTerm { energy: mu_lambda * f0, grad: [0.0; N], hess: [[0.0; N]; N] };
    for i in 0..N {
        t.grad[i] = mu_lambda * f1 * sign * w[i];
        for k in 0..N {
            t.hess[i][k] = mu_lambda * f2 * w[i] * w[k];
        }
    }
    t
}

/// Real roots of c₂ t² + c₁ t + c₀ = 0 in ascending order (a linear or constant equation when
/// the leading coefficients vanish relative to the others). The constant zero equation gives
/// no roots (see [`point_edge_toi`] for that case).
fn quadratic_roots(c2: f64, c1: f64, c0: f64) -> ([f64; 2], usize) {
    let scale = c2.abs().max(c1.abs()).max(c0.abs());
    if scale == 0.0 {
        return ([0.0; 2], 0);
    }
    if c2.abs() <= 1e-14 * scale {
        if c1.abs() <= 1e-14 * scale {
            return ([0.0; 2], 0);
        }
        return ([-c0 / c1, 0.0], 1);
    }
    let disc = c1 * c1 - 4.0 * c2 * c0;
    if disc < 0.0 {
        return ([0.0; 2], 0);
    }
    // the numerically stable pair of formulas
    let q = -0.5 * (c1 + c1.signum() * disc.sqrt());
    let (mut r0, mut r1) = if q != 0.0 { (q / c2, c0 / q) } else { (0.0, 0.0) };
    if r0 > r1 {
        std::mem::swap(&mut r0, &mut r1);
    }
    ([r0, r1], 2)
}

/// The first time of impact t ∈ [0, 1] of point p with edge (a, b), each moving on a straight
/// line from its position at t = 0 (`x0`, `[p, a, b]`) to t = 1 (`x1`); `None` when they do
/// not meet. Exact up to round-off: the roots of the collinearity quadratic
/// e(t) × (p(t) − a(t)) = 0 whose projection parameter lies in [0, 1]. A point that stays on
/// the edge's line for the whole motion is checked against the two ends (it can only enter the
/// edge through one of them).
pub fn point_edge_toi(x0: [[f64; 2]; 3], x1: [[f64; 2]; 3]) -> Option<f64> {
    let [p0, a0, b0] = x0;
    let [p1, a1, b1] = x1;
    let r0 = sub(p0, a0);
    let e0 = sub(b0, a0);
    let dr = sub(sub(p1, p0), sub(a1, a0));
    let de = sub(sub(b1, b0), sub(a1, a0));
    let c0 = cross(e0, r0);
    let c1 = cross(e0, dr) + cross(de, r0);
    let c2 = cross(de, dr);
    let on_edge = |t: f64| {
        let r = [r0[0] + t * dr[0], r0[1] + t * dr[1]];
        let e = [e0[0] + t * de[0], e0[1] + t * de[1]];
        let l = dot(e, e);
        if !(l > 0.0) {
            return dot(r, r) == 0.0;
        }
        let s = dot(r, e) / l;
        let slack = 1e-12;
        (-slack..=1.0 + slack).contains(&s)
    };
    let size = dot(e0, e0).max(dot(r0, r0)).max(dot(dr, dr)).max(dot(de, de));
    if c0.abs() <= 1e-14 * size && c1.abs() <= 1e-14 * size && c2.abs() <= 1e-14 * size {
        // collinear all along: the point meets the edge when it reaches an end
        let mut best: Option<f64> = None;
        for (q0, q1) in [(a0, a1), (b0, b1)] {
            let d0 = sub(p0, q0);
            let dd = sub(sub(p1, p0), sub(q1, q0));
            let l = dot(dd, dd);
            if l > 0.0 {
                let t = (-dot(d0, dd) / l).clamp(0.0, 1.0);
                let m = [d0[0] + t * dd[0], d0[1] + t * dd[1]];
                if dot(m, m) <= 1e-24 * size {
                    best = Some(best.map_or(t, |b: f64| b.min(t)));
                }
            }
        }
        return if on_edge(0.0) { Some(0.0) } else { best };
    }
    let (roots, n) = quadratic_roots(c2, c1, c0);
    roots[..n].iter().copied().filter(|t| (0.0..=1.0).contains(t)).find(|&t| on_edge(t))
}

/// The first time of impact t ∈ [0, 1] of a point moving from `p0` to `p1` with a wall whose
/// signed distance to the point goes from `d0` (> 0) at t = 0 by the wall's own motion along
/// its normal: the wall's point moves by `wall_shift` along the unit `normal`. `None` when the
/// point stays in front of the wall.
pub fn point_wall_toi(d0: f64, p0: [f64; 2], p1: [f64; 2], normal: [f64; 2], wall_shift: f64) -> Option<f64> {
    let dd = dot(sub(p1, p0), normal) - wall_shift;
    if d0 <= 0.0 {
        return Some(0.0);
    }
    if dd >= 0.0 {
        return None;
    }
    let t = -d0 / dd;
    (t <= 1.0).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point of an edge facing an edge: its Hessian Jᵀ K J (K any symmetric 4 × 4 on x − a
    /// and b − a, indefinite as a barrier pair's mostly is, J the map of (c, d, a, b) with
    /// x = (1 − ξ) c + ξ d) projected on its 4-wide range agrees with the projection on the 6
    /// directions without net translation to 1e-12 of its norm (the same in exact arithmetic;
    /// the Jacobi sweeps stop at 1e-13 of the norm, and 1e-13 is what `cargo bench --bench
    /// projection` measures on its 1,000), and is positive semi-definite.
    #[test]
    fn a_point_on_an_edge_is_projected_on_its_range_as_on_the_relative_motions() {
        let mut seed = 99u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut worst: f64 = 0.0;
        for _ in 0..500 {
            let xi = 0.5 + 0.5 * rnd();
            let mut k = [[0.0; 4]; 4];
            let g: [f64; 4] = std::array::from_fn(|_| rnd());
            for i in 0..4 {
                for j in 0..=i {
                    let v = 1e3 * g[i] * g[j] + 10.0 * rnd();
                    k[i][j] = v;
                    k[j][i] = v;
                }
            }
            let h = crate::bench_support::edge_point_hessian(&k, xi);
            let (mut old, mut new) = (h, h);
            project_psd_relative::<8, 6>(&mut old);
            project_psd_point_on_edge(&mut new, xi);
            let norm = h.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
            let diff = old.iter().flatten().zip(new.iter().flatten()).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
            worst = worst.max(diff / norm);
            let mut check = new;
            project_psd(&mut check);
            let moved = check.iter().flatten().zip(new.iter().flatten()).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
            assert!(moved <= 1e-12 * norm, "not positive semi-definite: projecting again moves it by {moved:e}");
        }
        assert!(worst <= 1e-12, "largest relative difference {worst:e}");
    }

    #[test]
    fn regions_and_distances_agree_with_the_closest_point() {
        let (a, b) = ([0.0, 0.0], [2.0, 0.0]);
        assert_eq!(point_edge_region([-1.0, 1.0], a, b), PointEdgeRegion::A);
        assert_eq!(point_edge_region([3.0, 1.0], a, b), PointEdgeRegion::B);
        assert_eq!(point_edge_region([1.0, 1.0], a, b), PointEdgeRegion::Interior);
        assert!((point_edge_sq_distance([-1.0, 1.0], a, b).d2 - 2.0).abs() < 1e-15);
        assert!((point_edge_sq_distance([3.0, 1.0], a, b).d2 - 2.0).abs() < 1e-15);
        assert!((point_edge_sq_distance([1.0, 0.5], a, b).d2 - 0.25).abs() < 1e-15);
    }

    #[test]
    fn the_barrier_is_c2_at_the_clamp_and_infinite_at_contact() {
        let xh = 0.01;
        let [b, b1, b2] = clamped_log(xh * (1.0 - 1e-9), xh);
        assert!(b.abs() < 1e-20 && b1.abs() < 1e-10 && b2.abs() < 1e-6, "{b} {b1} {b2}");
        assert_eq!(clamped_log(0.0, xh)[0], f64::INFINITY);
        assert_eq!(clamped_log(2.0 * xh, xh), [0.0; 3]);
    }

    #[test]
    fn time_of_impact_of_simple_motions() {
        // a point falling straight onto a fixed edge: crosses at t = 0.05 / 0.25
        let t = point_edge_toi([[0.3, 0.05], [0.0, 0.0], [1.0, 0.0]], [[0.3, -0.2], [0.0, 0.0], [1.0, 0.0]]).unwrap();
        assert!((t - 0.2).abs() < 1e-14);
        // passing beside the edge: no impact
        assert!(point_edge_toi([[1.3, 0.05], [0.0, 0.0], [1.0, 0.0]], [[1.3, -0.2], [0.0, 0.0], [1.0, 0.0]]).is_none());
        // an edge rotating onto a fixed point: b = (cos θ, sin θ) linear from θ = 0.3 to −0.3
        let t = point_edge_toi([[0.5, 0.0], [0.0, 0.0], [0.3f64.cos(), 0.3f64.sin()]], [[0.5, 0.0], [0.0, 0.0], [0.3f64.cos(), -0.3f64.sin()]]).unwrap();
        assert!((t - 0.5).abs() < 1e-14, "{t}");
        // a point moving along the edge's line into it
        let t = point_edge_toi([[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]], [[1.0, 0.0], [0.0, 0.0], [1.0, 0.0]]).unwrap();
        assert!((t - 0.5).abs() < 1e-14, "{t}");
        // a wall advancing 0.3 onto a point 0.1 away that moves 0.1 towards it: impact at 0.25
        let t = point_wall_toi(0.1, [0.0, 0.1], [0.0, 0.0], [0.0, 1.0], 0.3).unwrap();
        assert!((t - 0.25).abs() < 1e-15);
        assert!(point_wall_toi(0.1, [0.0, 0.1], [0.0, 0.2], [0.0, 1.0], 0.05).is_none());
    }

    #[test]
    fn projection_onto_psd_clears_negative_eigenvalues_only() {
        let mut h = [[2.0, 0.0], [0.0, -1.0]];
        project_psd(&mut h);
        assert!((h[0][0] - 2.0).abs() < 1e-15 && h[1][1].abs() < 1e-15);
        let mut h = [[2.0, 1.0], [1.0, 2.0]];
        project_psd(&mut h);
        assert_eq!(h, [[2.0, 1.0], [1.0, 2.0]]);
    }

    /// The projection on the complement of the translations equals the projection of the
    /// whole matrix (to 1e-12 of its norm) for a Hessian that vanishes along the translations:
    /// a random indefinite sum of ±v vᵀ over vectors v with no net translation, of both widths
    /// the pairs have.
    #[test]
    fn projecting_without_the_translations_is_projecting() {
        fn check<const N: usize, const M: usize>(rand: &mut impl FnMut() -> f64) {
            // the translation-free matrices: S on random relative vectors (their components
            // with the point mean taken away in each direction)
            let mut h = [[0.0; N]; N];
            for _ in 0..M {
                let mut v: [f64; N] = std::array::from_fn(|_| rand());
                for c in 0..2 {
                    let mean = (0..N / 2).map(|k| v[2 * k + c]).sum::<f64>() / (N / 2) as f64;
                    (0..N / 2).for_each(|k| v[2 * k + c] -= mean);
                }
                let sign = if rand() < 0.0 { -1.0 } else { 1.0 };
                for i in 0..N {
                    for k in 0..N {
                        h[i][k] += sign * v[i] * v[k];
                    }
                }
            }
            let norm: f64 = h.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
            let (mut full, mut relative) = (h, h);
            project_psd(&mut full);
            project_psd_relative::<N, M>(&mut relative);
            let diff: f64 = full.iter().flatten().zip(relative.iter().flatten()).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
            assert!(diff <= 1e-12 * norm, "N = {N}: {diff:e} against {norm:e}");
        }
        let mut seed = 777u64;
        let mut rand = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..200 {
            check::<6, 4>(&mut rand);
            check::<8, 6>(&mut rand);
        }
    }
}
