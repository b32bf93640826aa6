//! Conformance battery for every contact enforcement on every pair geometry (the contract in
//! `src/contact/enforce.rs` and `src/contact/geometry.rs`). One generic function,
//! [`battery`], is applied to each combination of
//! - geometry: a straight master segment (6 dofs), the smoothed master surface with both
//!   neighbours (10 dofs), a rigid wall (2 dofs);
//! - enforcement: penalty, augmented Lagrangian (a history with multipliers λ_N, λ_T), and
//!   Lagrange multipliers (ε = 0, the pressure λ given: the kernel gives the force −λ A δg and
//!   its geometric stiffness; the constraint row comes from [`lagrange_row`]);
//! - law: frictionless, Coulomb in stick, Coulomb in slip, tied (Coulomb and ties only with the
//!   penalty-based enforcements: the Lagrange multipliers are frictionless).
//!
//! Checked, each against central finite differences with a perturbation of 1e-7 mm:
//! (a) the tangent K = ∂f/∂x, max |K_fd − K| ≤ 1e-6 · max |K| (truncation O(h²) ≈ 1e-14 and
//!     round-off ≈ 1e-16 |f|/h ≈ 1e-9 relative for these states, any missing term O(1e-3));
//! (b) the gap's variations: dg (`grad_full`) = ∂g/∂x over every dof, and δg (`grad`, the
//!     direction of the force) = ∂g/∂x_s on the slave node, 1e-6 relative;
//! (c) the force is the gradient of the penalty potential Π = A(−λ_N g + ½ ε_N g²) where the
//!     law has one (frictionless, straight segment or wall): f = ∂Π/∂x, 1e-6 relative;
//! (d) symmetry where it should hold (frictionless, straight segment or wall; also the
//!     Lagrange geometric stiffness there): |K_ij − K_ji| ≤ 1e-10 · max |K| (round-off only);
//! (e) the Lagrange row's derivatives: by x, −c A dg (a), by the unknown λ/c, −r c A (active)
//!     or −c A (inactive), against finite differences of the row, 1e-6 relative.
//! States are chosen away from the kinks (opening, stick/slip threshold) so that every quantity
//! is smooth in the ±1e-7 neighbourhood; the battery asserts the state does not change there.

use mpfem::contact::enforce::*;
use mpfem::contact::geometry::{nts_project, PairGeometry, SegmentGeometry, SmoothGeometry, Wall, WallGeometry};
use mpfem::contact::smooth::{Master, NDOF};

const H: f64 = 1e-7;
const FD_TOL: f64 = 1e-6;
const SYM_TOL: f64 = 1e-10;

/// A kernel's output, width-erased.
struct Out {
    f: Vec<f64>,
    k: Vec<Vec<f64>>,
    grad: Vec<f64>,
    grad_full: Vec<f64>,
    gap: f64,
    active: bool,
    slip: bool,
}

impl<const N: usize> From<PairResult<N>> for Out {
    fn from(r: PairResult<N>) -> Self {
        Out { f: r.f.to_vec(), k: r.k.iter().map(|row| row.to_vec()).collect(), grad: r.grad.to_vec(), grad_full: r.grad_full.to_vec(), gap: r.gap, active: r.active, slip: r.slip }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Geo {
    Segment,
    Smoothed,
    Wall,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Enforcement {
    Penalty,
    AugmentedLagrangian,
    Lagrange,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Law {
    Frictionless,
    Stick,
    Slip,
    Tied,
}

const AREA: f64 = 0.7;
const EPS: f64 = 1.0e3;

fn rot(a: f64) -> ([f64; 2], [f64; 2]) {
    let t = [a.cos(), a.sin()];
    (t, [t[1], -t[0]])
}

/// The state of a geometry: the dofs, with the slave at parameter ξ = 0.4 and normal offset
/// `g` from a master at 30° (the smoothed master turns by 20° and 35° at its ends).
fn state(geo: Geo, g: f64) -> Vec<f64> {
    let (t, n) = rot(30f64.to_radians());
    let x1 = [0.7, -0.4];
    let l = 2.0;
    let x2 = [x1[0] + l * t[0], x1[1] + l * t[1]];
    let xs = [x1[0] + 0.4 * l * t[0] + g * n[0], x1[1] + 0.4 * l * t[1] + g * n[1]];
    match geo {
        Geo::Segment => vec![xs[0], xs[1], x1[0], x1[1], x2[0], x2[1]],
        Geo::Wall => vec![xs[0], xs[1]],
        Geo::Smoothed => {
            let (t0, _) = rot((30f64 - 20.0).to_radians());
            let (t3, _) = rot((30f64 + 35.0).to_radians());
            let x0 = [x1[0] - 1.1 * t0[0], x1[1] - 1.1 * t0[1]];
            let x3 = [x2[0] + 0.9 * t3[0], x2[1] + 0.9 * t3[1]];
            vec![xs[0], xs[1], x1[0], x1[1], x2[0], x2[1], x0[0], x0[1], x3[0], x3[1]]
        }
    }
}

/// The wall of the wall geometry: the master line of the segment, the particles on the side
/// of its outward normal.
fn wall() -> Wall {
    let (_, n) = rot(30f64.to_radians());
    Wall { point: [0.7, -0.4], normal: n }
}

fn master(x: &[f64]) -> Master {
    Master { x1: [x[2], x[3]], x2: [x[4], x[5]], prev: Some([x[6], x[7]]), next: Some([x[8], x[9]]) }
}

/// The gap of the geometry at `x` (the quantity whose variations the kernels provide).
fn gap(geo: Geo, x: &[f64]) -> f64 {
    match geo {
        Geo::Segment => nts_project([x[0], x[1]], [x[2], x[3]], [x[4], x[5]]).gap,
        Geo::Smoothed => SmoothGeometry::new([x[0], x[1]], &master(x)).gap(),
        Geo::Wall => WallGeometry::new([x[0], x[1]], &wall(), 0.0).gap(),
    }
}

/// The projection parameter ξ (wall: s) of the geometry at `x`.
fn xi(geo: Geo, x: &[f64]) -> f64 {
    match geo {
        Geo::Segment => SegmentGeometry::new([x[0], x[1]], [x[2], x[3]], [x[4], x[5]]).xi(),
        Geo::Smoothed => SmoothGeometry::new([x[0], x[1]], &master(x)).xi(),
        Geo::Wall => WallGeometry::new([x[0], x[1]], &wall(), 0.0).xi(),
    }
}

fn eval(geo: Geo, x: &[f64], kind: ContactKind, p: &PenaltyParams, old: &PairHistory) -> Out {
    match geo {
        Geo::Segment => segment_pair([x[0], x[1]], [x[2], x[3]], [x[4], x[5]], AREA, kind, p, old).into(),
        Geo::Smoothed => smooth_pair([x[0], x[1]], &master(x), AREA, kind, p, old).into(),
        Geo::Wall => wall_pair([x[0], x[1]], &wall(), 0.0, AREA, kind, p, old).into(),
    }
}

fn max_abs(k: &[Vec<f64>]) -> f64 {
    k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// Central difference of a scalar function of the dofs.
fn fd_grad(x: &[f64], f: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    (0..x.len())
        .map(|j| {
            let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
            xp[j] += H;
            xm[j] -= H;
            (f(&xp) - f(&xm)) / (2.0 * H)
        })
        .collect()
}

fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

/// The battery for one combination; returns a one-line summary for the report.
fn battery(geo: Geo, enf: Enforcement, law: Law) -> String {
    let name = format!("{geo:?} / {enf:?} / {law:?}");
    // a penetration of 0.01 mm; a tie in tension (opened by 0.005 mm)
    let g = if law == Law::Tied { 0.005 } else { -0.01 };
    let x = state(geo, g);
    let n = x.len();
    let xi0 = xi(geo, &x);
    // the anchor 0.002 mm behind the slave (stick), or far behind it (slip); a wall's anchor is
    // a coordinate along the wall (mm), a segment's a parameter (ξ, ℓ = 2 mm)
    let metric = if geo == Geo::Wall { 1.0 } else { 2.0 };
    let (kind, anchor) = match law {
        Law::Frictionless => (ContactKind::Sliding, xi0),
        Law::Stick => (ContactKind::Rubbing { mu: 0.3 }, xi0 - 0.002 / metric),
        Law::Slip => (ContactKind::Rubbing { mu: 0.3 }, xi0 - 0.2 / metric),
        Law::Tied => (ContactKind::Cohering, xi0 - 0.002 / metric),
    };
    let (p, old) = match enf {
        Enforcement::Penalty => (PenaltyParams { eps_n: EPS, eps_t: EPS }, PairHistory { xi_stick: anchor, lambda_n: 0.0, lambda_t: 0.0, active: true }),
        Enforcement::AugmentedLagrangian => (PenaltyParams { eps_n: EPS, eps_t: EPS }, PairHistory { xi_stick: anchor, lambda_n: 4.0, lambda_t: 0.5, active: true }),
        // the pressure λ is the unknown: the kernel with ε = 0 and λ as its multiplier
        Enforcement::Lagrange => (PenaltyParams { eps_n: 0.0, eps_t: 0.0 }, PairHistory { xi_stick: xi0, lambda_n: 6.0, lambda_t: 0.0, active: true }),
    };
    let out = eval(geo, &x, kind, &p, &old);
    assert!(out.active, "{name}: the state must be active");
    assert!((out.gap - gap(geo, &x)).abs() <= 1e-12, "{name}: the kernel's gap is the geometry's");
    let expect_slip = law == Law::Slip;
    assert_eq!(out.slip, expect_slip, "{name}: slip");

    // (a) tangent
    let kmax = max_abs(&out.k);
    // (a flat wall has no geometric stiffness: the Lagrange force −λ A n is constant)
    let constant = geo == Geo::Wall && enf == Enforcement::Lagrange;
    assert!(kmax > 0.0 || constant, "{name}: empty tangent");
    let mut err = 0.0f64;
    for j in 0..n {
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[j] += H;
        xm[j] -= H;
        let (fp, fm) = (eval(geo, &xp, kind, &p, &old), eval(geo, &xm, kind, &p, &old));
        assert_eq!((fp.active, fm.active, fp.slip, fm.slip), (true, true, out.slip, out.slip), "{name}: state changed in the stencil");
        for i in 0..n {
            err = err.max(((fp.f[i] - fm.f[i]) / (2.0 * H) - out.k[i][j]).abs());
        }
    }
    assert!(err <= FD_TOL * kmax || (constant && err == 0.0), "{name}: tangent error {err:.3e} of max |K| {kmax:.3e}");

    // (b) the gap's variations
    let dg = fd_grad(&x, |y| gap(geo, y));
    let e_full = rel_err(&out.grad_full, &dg);
    assert!(e_full <= FD_TOL, "{name}: dg error {e_full:.3e}");
    let e_slave = rel_err(&out.grad[..2], &dg[..2]);
    assert!(e_slave <= FD_TOL, "{name}: δg on the slave error {e_slave:.3e}");

    // (c) the force is the gradient of the penalty potential (frictionless, not smoothed)
    let potential = law == Law::Frictionless && geo != Geo::Smoothed;
    if potential {
        let (lam, eps) = (old.lambda_n, p.eps_n);
        let dpi = fd_grad(&x, |y| {
            let g = gap(geo, y);
            AREA * (-lam * g + 0.5 * eps * g * g)
        });
        let e = rel_err(&out.f, &dpi);
        assert!(e <= FD_TOL, "{name}: f − ∂Π/∂x error {e:.3e}");
    }

    // (d) symmetry where it should hold
    if potential {
        let mut asym = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                asym = asym.max((out.k[i][j] - out.k[j][i]).abs());
            }
        }
        assert!(asym <= SYM_TOL * kmax, "{name}: |K − Kᵀ| {asym:.3e} of {kmax:.3e}");
    }

    // (e) the Lagrange row: −c A (g + r λ/c) active, −A λ inactive; derivatives by x and λ/c
    if enf == Enforcement::Lagrange {
        let (c, r) = (EPS, 1e-4);
        // the penetrating pair with its λ (active), and the pair opened by 0.2 mm with λ = 0
        // (inactive; the smoothed surface bulges out of the chord by a few hundredths of a mm)
        let x_open = state(geo, 0.2);
        for (lam, y, expect_active) in [(old.lambda_n, &x, true), (0.0, &x_open, false)] {
            let g0 = gap(geo, y);
            let (active, _, diagonal) = lagrange_row(lam, g0, AREA, c, r);
            assert_eq!(active, expect_active, "{name}: active set");
            let d_x = fd_grad(y, |z| lagrange_row(lam, gap(geo, z), AREA, c, r).1);
            if active {
                let expect: Vec<f64> = out.grad_full.iter().map(|g| -c * AREA * g).collect();
                let e = rel_err(&d_x, &expect);
                assert!(e <= FD_TOL, "{name}: row by x error {e:.3e}");
            } else {
                assert!(d_x.iter().all(|v| *v == 0.0), "{name}: an inactive row depends on x");
            }
            // by the unknown μ = λ/c
            let mu = lam / c;
            let d_mu = (lagrange_row(c * (mu + H), g0, AREA, c, r).1 - lagrange_row(c * (mu - H), g0, AREA, c, r).1) / (2.0 * H);
            assert!((d_mu - diagonal).abs() <= FD_TOL * diagonal.abs(), "{name}: row by λ/c {d_mu} vs {diagonal}");
        }
    }
    let kmax = kmax.max(f64::MIN_POSITIVE);
    format!("{name}: tangent {:.1e}, dg {e_full:.1e}", err / kmax)
}

/// Every enforcement on every geometry with every law it supports.
#[test]
fn every_contact_kernel_passes_the_conformance_battery() {
    let mut lines = Vec::new();
    for geo in [Geo::Segment, Geo::Smoothed, Geo::Wall] {
        for enf in [Enforcement::Penalty, Enforcement::AugmentedLagrangian, Enforcement::Lagrange] {
            let laws: &[Law] = if enf == Enforcement::Lagrange { &[Law::Frictionless] } else { &[Law::Frictionless, Law::Stick, Law::Slip, Law::Tied] };
            for &law in laws {
                lines.push(battery(geo, enf, law));
            }
        }
    }
    assert_eq!(lines.len(), 3 * (4 + 4 + 1));
    eprintln!("{}", lines.join("\n"));
}

/// The smoothed geometry's width is the kernels' [`NDOF`] and a straight segment's 6: the
/// battery's states have the widths the assembler's blocks expect.
#[test]
fn geometry_widths() {
    assert_eq!(state(Geo::Smoothed, -0.01).len(), NDOF);
    assert_eq!(state(Geo::Segment, -0.01).len(), 6);
    assert_eq!(state(Geo::Wall, -0.01).len(), 2);
}

// ---------------------------------------------------------------------------------------------
// Barrier contact (src/contact/barrier.rs): the squared distances and the barrier energy of a
// point–edge pair in each of its three regions, next to the region boundaries on both sides,
// next to the clamp at d̂ on both sides, and of a point against a wall. Checked against central
// finite differences (step 1e-7 mm relative to a unit-sized configuration, tolerance 1e-6
// relative to the largest entry, as for the other kernels): the gradient against the energy,
// the Hessian against the gradient. Across a region boundary d² is C¹ (the gradient agrees from
// both sides to 1e-6 relative), and across the clamp the barrier is C² (energy, gradient and
// Hessian tend to zero there).
// ---------------------------------------------------------------------------------------------

mod barrier_battery {
    use mpfem::contact::barrier::*;

    const H: f64 = 1e-7;
    const TOL: f64 = 1e-6;

    fn unpack(x: &[f64; 6]) -> ([f64; 2], [f64; 2], [f64; 2]) {
        ([x[0], x[1]], [x[2], x[3]], [x[4], x[5]])
    }

    fn pe(x: &[f64; 6]) -> SqDistance<6> {
        let (p, a, b) = unpack(x);
        point_edge_sq_distance(p, a, b)
    }

    /// Central differences of a scalar and of a vector function of the 6 dofs.
    fn fd_grad(f: &dyn Fn(&[f64; 6]) -> f64, x: &[f64; 6]) -> [f64; 6] {
        let mut g = [0.0; 6];
        for i in 0..6 {
            let (mut xp, mut xm) = (*x, *x);
            xp[i] += H;
            xm[i] -= H;
            g[i] = (f(&xp) - f(&xm)) / (2.0 * H);
        }
        g
    }

    fn fd_jac(f: &dyn Fn(&[f64; 6]) -> [f64; 6], x: &[f64; 6]) -> [[f64; 6]; 6] {
        let mut j = [[0.0; 6]; 6];
        for k in 0..6 {
            let (mut xp, mut xm) = (*x, *x);
            xp[k] += H;
            xm[k] -= H;
            let (fp, fm) = (f(&xp), f(&xm));
            for i in 0..6 {
                j[i][k] = (fp[i] - fm[i]) / (2.0 * H);
            }
        }
        j
    }

    fn close_vec(a: &[f64], b: &[f64], what: &str) {
        let scale = a.iter().chain(b).fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "{what}: all zero, nothing checked");
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert!((x - y).abs() <= TOL * scale, "{what}[{i}]: {x} against {y} (scale {scale})");
        }
    }

    fn close_mat(a: &[[f64; 6]; 6], b: &[[f64; 6]; 6], what: &str) {
        let fa: Vec<f64> = a.iter().flatten().copied().collect();
        let fb: Vec<f64> = b.iter().flatten().copied().collect();
        close_vec(&fa, &fb, what);
    }

    /// A configuration: edge a = (0.1, −0.05), b = (1.05, 0.08) and the point at projection
    /// parameter `s` and distance `h` from the edge's line (on its left).
    fn config(s: f64, h: f64) -> [f64; 6] {
        let (a, b): ([f64; 2], [f64; 2]) = ([0.1, -0.05], [1.05, 0.08]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let l = (e[0] * e[0] + e[1] * e[1]).sqrt();
        let n = [-e[1] / l, e[0] / l];
        [a[0] + s * e[0] + h * n[0], a[1] + s * e[1] + h * n[1], a[0], a[1], b[0], b[1]]
    }

    /// The distance battery: gradient and Hessian of d² against finite differences.
    fn check_distance(x: &[f64; 6], what: &str) {
        let d = pe(x);
        close_vec(&d.grad, &fd_grad(&|y| pe(y).d2, x), &format!("{what}: ∇d²"));
        close_mat(&d.hess, &fd_jac(&|y| pe(y).grad, x), &format!("{what}: ∇²d²"));
        for i in 0..6 {
            for k in 0..6 {
                assert!((d.hess[i][k] - d.hess[k][i]).abs() <= 1e-12, "{what}: Hessian not symmetric");
            }
        }
    }

    /// The barrier battery: energy → gradient → Hessian (exact, not projected).
    fn check_barrier(x: &[f64; 6], dhat: f64, kappa: f64, what: &str) {
        let t = barrier_term(&pe(x), dhat, kappa, false).unwrap_or_else(|| panic!("{what}: pair beyond d̂"));
        let energy = |y: &[f64; 6]| barrier_term(&pe(y), dhat, kappa, false).map_or(0.0, |t| t.energy);
        let grad = |y: &[f64; 6]| barrier_term(&pe(y), dhat, kappa, false).map_or([0.0; 6], |t| t.grad);
        assert!(t.energy > 0.0, "{what}: energy {}", t.energy);
        close_vec(&t.grad, &fd_grad(&energy, x), &format!("{what}: barrier gradient"));
        close_mat(&t.hess, &fd_jac(&grad, x), &format!("{what}: barrier Hessian"));
    }

    #[test]
    fn point_edge_distance_in_every_region_and_next_to_their_boundaries() {
        for (s, what) in [(-0.4, "end a"), (0.37, "interior"), (1.3, "end b"), (-1e-5, "just before a"), (1e-5, "just after a"), (1.0 - 1e-5, "just before b"), (1.0 + 1e-5, "just after b")] {
            for h in [0.3, -0.2, 1e-3] {
                check_distance(&config(s, h), &format!("{what}, h = {h}"));
            }
        }
    }

    #[test]
    fn the_distance_gradient_is_continuous_across_the_region_boundaries() {
        for s0 in [0.0, 1.0] {
            let left = pe(&config(s0 - 1e-10, 0.2));
            let right = pe(&config(s0 + 1e-10, 0.2));
            let region = |s: f64| {
                let (p, a, b) = unpack(&config(s, 0.2));
                point_edge_region(p, a, b)
            };
            let expect = if s0 == 0.0 { (PointEdgeRegion::A, PointEdgeRegion::Interior) } else { (PointEdgeRegion::Interior, PointEdgeRegion::B) };
            assert_eq!((region(s0 - 1e-10), region(s0 + 1e-10)), expect);
            assert!((left.d2 - right.d2).abs() < 1e-9);
            close_vec(&left.grad, &right.grad, &format!("∇d² across s = {s0}"));
        }
    }

    #[test]
    fn barrier_gradient_and_hessian_in_every_region_and_across_the_clamp() {
        let kappa = 3.0e4;
        for dhat in [0.05, 0.5] {
            for (s, what) in [(-0.2, "end a"), (0.37, "interior"), (1.2, "end b"), (-1e-5, "just before a"), (1e-5, "just after a"), (1.0 + 1e-5, "just after b")] {
                // distances from deep inside the barrier to next to the clamp (closer to it the barrier
                // is O((d² − d̂²)³) and finite differences lose their digits; the limit is checked
                // in `the_barrier_vanishes_with_two_derivatives_at_the_clamp`)
                for frac in [0.02, 0.3, 0.9, 0.99] {
                    // the point's distance to the edge is frac·d̂ (along the region's direction)
                    let h = if (0.0..=1.0).contains(&s) { frac * dhat } else {
                        let e = 0.95f64.hypot(0.13);
                        let along = if s < 0.0 { -s } else { s - 1.0 } * e;
                        let r = frac * dhat;
                        if r <= along { continue } else { (r * r - along * along).sqrt() }
                    };
                    check_barrier(&config(s, h), dhat, kappa, &format!("{what}, d/d̂ = {frac}, d̂ = {dhat}"));
                }
            }
        }
    }

    #[test]
    fn the_barrier_vanishes_with_two_derivatives_at_the_clamp() {
        let (dhat, kappa) = (0.1, 1.0e3);
        let inside = barrier_term(&pe(&config(0.4, dhat * (1.0 - 1e-7))), dhat, kappa, false).unwrap();
        assert!(pe(&config(0.4, dhat * (1.0 + 1e-7))).d2 > dhat * dhat);
        assert!(barrier_term(&pe(&config(0.4, dhat * (1.0 + 1e-7))), dhat, kappa, false).is_none());
        // b ~ (x − x̂)³, b' ~ (x − x̂)², b'' ~ (x − x̂): with x − x̂ ≈ 2e-9 all are tiny
        assert!(inside.energy.abs() < 1e-15);
        assert!(inside.grad.iter().all(|g| g.abs() < 1e-9), "{:?}", inside.grad);
        assert!(inside.hess.iter().flatten().all(|h| h.abs() < 1e-2), "{:?}", inside.hess);
        // while deeper inside the Hessian is of order κ d̂²
        let deep = barrier_term(&pe(&config(0.4, 0.5 * dhat)), dhat, kappa, false).unwrap();
        assert!(deep.hess.iter().flatten().any(|h| h.abs() > 1.0));
    }

    #[test]
    fn point_wall_distance_and_barrier() {
        let (point, n) = ([0.2, -0.1], [0.6, 0.8]);
        let (dhat, kappa) = (0.2, 5.0e3);
        let f = |p: [f64; 2]| barrier_term(&point_wall_sq_distance(p, point, n).1, dhat, kappa, false);
        for d in [0.01, 0.1, 0.19] {
            let p = [point[0] + d * n[0] + 0.3 * n[1], point[1] + d * n[1] - 0.3 * n[0]];
            let (dist, _) = point_wall_sq_distance(p, point, n);
            assert!((dist - d).abs() < 1e-14);
            let t = f(p).unwrap();
            for i in 0..2 {
                let (mut pp, mut pm) = (p, p);
                pp[i] += H;
                pm[i] -= H;
                let g = (f(pp).unwrap().energy - f(pm).unwrap().energy) / (2.0 * H);
                let scale = t.grad.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                assert!((g - t.grad[i]).abs() <= TOL * scale, "wall gradient at d = {d}");
                for k in 0..2 {
                    let hk = (f(pp).unwrap().grad[k] - f(pm).unwrap().grad[k]) / (2.0 * H);
                    let scale = t.hess.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                    assert!((hk - t.hess[k][i]).abs() <= TOL * scale, "wall Hessian at d = {d}");
                }
            }
        }
    }

    /// The lagged friction potential μλ f₀(|w·Δx|): gradient and Hessian against finite
    /// differences in the static regime (|u_T| < ε, both signs) and the sliding one, and the
    /// mollifier C² at ε (f₀ = ε, f₀' = 1, f₀'' = 0 from below).
    #[test]
    fn friction_gradient_and_hessian_in_both_regimes() {
        let w = [0.6, -0.8, -0.42, 0.56, -0.18, 0.24];
        let (ml, eps) = (37.0, 1e-3);
        for scale in [0.3e-3, -0.7e-3, 2.5e-3, -4e-3] {
            let dx = [scale, -scale * 0.5, 0.1 * scale, 0.2 * scale, -0.3 * scale, 0.05 * scale];
            let t = friction_term(&w, &dx, ml, eps);
            let e = |y: &[f64; 6]| friction_term(&w, y, ml, eps).energy;
            let g = |y: &[f64; 6]| friction_term(&w, y, ml, eps).grad;
            // the step must stay in one regime: H ≪ the distance of |u_T| from ε
            close_vec(&t.grad, &fd_grad(&e, &dx), &format!("friction gradient at {scale}"));
            let u_t: f64 = w.iter().zip(&dx).map(|(a, b)| a * b).sum();
            if u_t.abs() < eps {
                close_mat(&t.hess, &fd_jac(&g, &dx), &format!("friction Hessian at {scale}"));
            } else {
                // sliding: the force is μλ along ±w whatever the slip, its Hessian zero
                assert!(t.hess.iter().flatten().all(|h| *h == 0.0));
                assert!(fd_jac(&g, &dx).iter().flatten().all(|h| h.abs() <= 1e-6 * ml), "friction Hessian at {scale} is not zero");
                assert!((t.grad[0].abs() - ml * 0.6).abs() < 1e-12);
            }
        }
        let [f0, f1, f2] = friction_mollifier(eps * (1.0 - 1e-9), eps);
        assert!((f0 - eps).abs() < 1e-12 && (f1 - 1.0).abs() < 1e-8 && f2.abs() < 1e-5, "{f0} {f1} {f2}");
    }

    #[test]
    fn the_projected_hessian_is_positive_semidefinite_and_keeps_the_convex_part() {
        let (dhat, kappa) = (0.3, 1.0);
        let x = config(0.5, 0.1);
        let exact = barrier_term(&pe(&x), dhat, kappa, false).unwrap().hess;
        let proj = barrier_term(&pe(&x), dhat, kappa, true).unwrap().hess;
        let m = nalgebra::SMatrix::<f64, 6, 6>::from_fn(|i, k| exact[i][k]);
        let p = nalgebra::SMatrix::<f64, 6, 6>::from_fn(|i, k| proj[i][k]);
        assert!(m.symmetric_eigen().eigenvalues.min() < -1e-6, "the exact point–edge barrier Hessian is indefinite here");
        assert!(p.symmetric_eigen().eigenvalues.min() > -1e-9);
        // the projection changes only the negative part: (P − H) is PSD
        assert!((p - m).symmetric_eigen().eigenvalues.min() > -1e-9);
    }
}
