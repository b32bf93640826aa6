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
