//! Tests of the contact pair kernels: the geometry records of a straight master segment and a
//! rigid wall (`mpfem::contact::geometry`) under the penalty, augmented-Lagrangian and friction
//! laws (`mpfem::contact::enforce`).
//!
//! Tolerances and why:
//! * Tangent checks: central finite differences of f with a perturbation of 1e-7 mm; the
//!   relative error max|K_fd − K| / max|K| must be ≤ 1e-6. Truncation error of the central
//!   difference is O(h²·|f'''|) ≈ 1e-14 relative here (|f'''| ~ |K|/ℓ² with ℓ ~ 1 mm) and the
//!   round-off is O(ε_mach·|f|/h) ≈ 1e-16·|f|/1e-7 ≈ 1e-11 relative, so 1e-6 is loose for a correct
//!   tangent yet any missing term (geometric 1/ℓ terms, ∂ξ terms, the slip coupling) gives O(1e-3)
//!   or more. States are chosen away from the kinks (contact opening, stick/slip threshold) so that
//!   f is smooth in the ±1e-7 neighbourhood.
//! * Closed-form checks (projection, penalty force, balance, Coulomb values): 1e-12 relative,
//!   i.e. a few thousand ulps of the quantities involved — only round-off is allowed.
//! * Uzawa: the penetration must decrease strictly at every update, with the analytical rate
//!   k/(k + ε_N A) to 1e-9, and the pressure must reach the exact constrained value to 1e-9.

use mpfem::contact::enforce::*;
use mpfem::contact::geometry::{nts_project, Wall};

type PairOut = PairResult<6>;
type WallOut = PairResult<2>;

const H_FD: f64 = 1e-7;
const FD_TOL: f64 = 1e-6;
const EXACT: f64 = 1e-12;

fn rot(a: f64) -> ([f64; 2], [f64; 2]) {
    let t = [a.cos(), a.sin()];
    (t, [t[1], -t[0]])
}

/// Rotated master segment of length 2 at 30°, slave at parameter ξ and normal offset g.
fn setup(xi: f64, g: f64) -> ([f64; 2], [f64; 2], [f64; 2]) {
    let (t, n) = rot(30f64.to_radians());
    let x1 = [0.7, -0.4];
    let l = 2.0;
    let x2 = [x1[0] + l * t[0], x1[1] + l * t[1]];
    let xs = [x1[0] + xi * l * t[0] + g * n[0], x1[1] + xi * l * t[1] + g * n[1]];
    (xs, x1, x2)
}

fn eval_nts(x: &[f64; 6], area: f64, kind: ContactKind, p: &PenaltyParams, old: &PairHistory) -> PairOut {
    segment_pair([x[0], x[1]], [x[2], x[3]], [x[4], x[5]], area, kind, p, old)
}

fn max_abs<const N: usize>(k: &[[f64; N]; N]) -> f64 {
    k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// Relative error of the kernel tangent against central differences of f.
fn fd_check_nts(x: [f64; 6], area: f64, kind: ContactKind, p: &PenaltyParams, old: &PairHistory) -> (f64, PairOut) {
    let out = eval_nts(&x, area, kind, p, old);
    let mut err = 0.0f64;
    for j in 0..6 {
        let mut xp = x;
        let mut xm = x;
        xp[j] += H_FD;
        xm[j] -= H_FD;
        let fp = eval_nts(&xp, area, kind, p, old);
        let fm = eval_nts(&xm, area, kind, p, old);
        assert_eq!(fp.slip, out.slip, "state changed in the FD stencil");
        assert_eq!(fm.active, out.active, "state changed in the FD stencil");
        for i in 0..6 {
            let fd = (fp.f[i] - fm.f[i]) / (2.0 * H_FD);
            err = err.max((fd - out.k[i][j]).abs());
        }
    }
    (err / max_abs(&out.k), out)
}

fn eval_wall(
    x: [f64; 2],
    wall: &Wall,
    d: f64,
    area: f64,
    kind: ContactKind,
    p: &PenaltyParams,
    old: &PairHistory,
) -> WallOut {
    wall_pair(x, wall, d, area, kind, p, old)
}

fn fd_check_wall(
    x: [f64; 2],
    wall: &Wall,
    d: f64,
    area: f64,
    kind: ContactKind,
    p: &PenaltyParams,
    old: &PairHistory,
) -> (f64, WallOut) {
    let out = eval_wall(x, wall, d, area, kind, p, old);
    let mut err = 0.0f64;
    for j in 0..2 {
        let mut xp = x;
        let mut xm = x;
        xp[j] += H_FD;
        xm[j] -= H_FD;
        let fp = eval_wall(xp, wall, d, area, kind, p, old);
        let fm = eval_wall(xm, wall, d, area, kind, p, old);
        assert_eq!(fp.slip, out.slip);
        assert_eq!(fm.slip, out.slip);
        for i in 0..2 {
            let fd = (fp.f[i] - fm.f[i]) / (2.0 * H_FD);
            err = err.max((fd - out.k[i][j]).abs());
        }
    }
    (err / max_abs(&out.k), out)
}

fn pack(xs: [f64; 2], x1: [f64; 2], x2: [f64; 2]) -> [f64; 6] {
    [xs[0], xs[1], x1[0], x1[1], x2[0], x2[1]]
}

fn params() -> PenaltyParams {
    // E = 100 MPa, h = 1 mm → ε_N = ε_T = 1000 MPa/mm.
    default_penalty(100.0, 1.0)
}

// ---------------------------------------------------------------------------------------------
// Geometry
// ---------------------------------------------------------------------------------------------

#[test]
fn projection_on_rotated_segment_matches_hand_values() {
    // Segment (1,1) → (1+√3, 2): ℓ = 2, t = (√3/2, 1/2), n = (1/2, −√3/2).
    let s3 = 3f64.sqrt();
    let x1 = [1.0, 1.0];
    let x2 = [1.0 + s3, 2.0];
    // Slave below-right (outside the body, which lies on the upper-left): r = (1, −0.5).
    let g = nts_project([2.0, 0.5], x1, x2);
    assert!((g.length - 2.0).abs() < EXACT);
    assert!((g.xi - (s3 / 2.0 - 0.25) / 2.0).abs() < EXACT);
    assert!((g.gap - (0.5 + s3 / 4.0)).abs() < EXACT);
    assert!(g.gap > 0.0, "outside the master body the gap is positive");
    assert!((g.normal[0] - 0.5).abs() < EXACT && (g.normal[1] + s3 / 2.0).abs() < EXACT);
    assert!((g.tangent[0] - s3 / 2.0).abs() < EXACT && (g.tangent[1] - 0.5).abs() < EXACT);
    // Slave inside the body: r = (0, 1) → ξ = 1/4, g = −√3/2 (penetration negative).
    let g = nts_project([1.0, 2.0], x1, x2);
    assert!((g.xi - 0.25).abs() < EXACT);
    assert!((g.gap + s3 / 2.0).abs() < EXACT);
    // Axis-aligned: segment along +x, body above (left), slave below → open.
    let g = nts_project([0.5, -0.1], [0.0, 0.0], [1.0, 0.0]);
    assert_eq!(g.normal, [0.0, -1.0]);
    assert!((g.gap - 0.1).abs() < EXACT && (g.xi - 0.5).abs() < EXACT);
    // Degenerate segment: inactive, no NaN in the output.
    let g = nts_project([0.5, -0.1], [1.0, 1.0], [1.0, 1.0]);
    assert!(g.gap.is_infinite() && g.gap > 0.0);
    let out = segment_pair([0.5, -0.1], [1.0, 1.0], [1.0, 1.0], 1.0, ContactKind::Cohering, &params(), &PairHistory::default());
    assert!(!out.active && out.f == [0.0; 6]);
}

#[test]
fn wall_gap_sign_and_tangent() {
    let wall = Wall { point: [0.0, -2.0], normal: [0.0, 1.0] };
    assert_eq!(wall.tangent(), [-1.0, 0.0]);
    let p = params();
    let o = eval_wall([3.0, -2.01], &wall, 0.0, 1.0, ContactKind::Sliding, &p, &PairHistory::default());
    assert!((o.gap + 0.01).abs() < EXACT && o.active);
    let o = eval_wall([3.0, -1.99], &wall, 0.0, 1.0, ContactKind::Sliding, &p, &PairHistory::default());
    assert!(o.gap > 0.0 && !o.active && o.f == [0.0; 2] && o.k == [[0.0; 2]; 2]);
    // A non-unit normal is normalised.
    let w2 = Wall { point: [0.0, -2.0], normal: [0.0, 5.0] };
    let o2 = eval_wall([3.0, -2.01], &w2, 0.0, 1.0, ContactKind::Sliding, &p, &PairHistory::default());
    assert!((o2.gap + 0.01).abs() < EXACT);
}

#[test]
fn default_penalty_is_ten_e_over_h() {
    let p = default_penalty(70_000.0, 2.0);
    assert_eq!(p.eps_n, 350_000.0);
    assert_eq!(p.eps_t, 350_000.0);
}

// ---------------------------------------------------------------------------------------------
// Penalty law and balance
// ---------------------------------------------------------------------------------------------

#[test]
fn frictionless_penalty_force_balance_and_moment() {
    let p = params();
    let g0 = -0.013;
    let area = 0.37;
    let (xs, x1, x2) = setup(0.3, g0);
    let out = eval_nts(&pack(xs, x1, x2), area, ContactKind::Sliding, &p, &PairHistory::default());
    let geo = nts_project(xs, x1, x2);
    assert!(out.active && !out.slip);
    assert!((out.gap - g0).abs() < EXACT);
    let mag = p.eps_n * g0.abs() * area;
    assert!((out.pressure - p.eps_n * g0.abs()).abs() < EXACT * out.pressure);
    // Slave: f_c = −p A n (the contact force on the node, −f_c, pushes it out along n).
    for c in 0..2 {
        assert!((out.f[c] + mag * geo.normal[c]).abs() < EXACT * mag);
    }
    // Action = reaction and zero moment about the origin.
    let xsn = [xs, x1, x2];
    let (mut fx, mut fy, mut m) = (0.0, 0.0, 0.0);
    for (a, xa) in xsn.iter().enumerate() {
        let f = [out.f[2 * a], out.f[2 * a + 1]];
        fx += f[0];
        fy += f[1];
        m += xa[0] * f[1] - xa[1] * f[0];
    }
    let lever = xsn.iter().fold(0.0f64, |mx, x| mx.max(x[0].hypot(x[1])));
    assert!(fx.abs() < EXACT * mag && fy.abs() < EXACT * mag);
    assert!(m.abs() < EXACT * mag * lever, "moment {m}");
    // Master split (1 − ξ, ξ).
    for c in 0..2 {
        assert!((out.f[2 + c] - 0.7 * mag * geo.normal[c]).abs() < EXACT * mag);
        assert!((out.f[4 + c] - 0.3 * mag * geo.normal[c]).abs() < EXACT * mag);
    }
    // Open pair: nothing.
    let (xs, x1, x2) = setup(0.3, 0.01);
    let out = eval_nts(&pack(xs, x1, x2), area, ContactKind::Rubbing { mu: 0.3 }, &p, &PairHistory::default());
    assert!(!out.active && out.f == [0.0; 6] && out.k == [[0.0; 6]; 6] && out.pressure == 0.0);
}

// ---------------------------------------------------------------------------------------------
// Tangents vs finite differences
// ---------------------------------------------------------------------------------------------

#[test]
fn fd_tangent_frictionless_rotated_segment() {
    let p = params();
    let (xs, x1, x2) = setup(0.3, -0.02);
    for lam in [0.0, 5.0] {
        let old = PairHistory { lambda_n: lam, ..Default::default() };
        let (e, out) = fd_check_nts(pack(xs, x1, x2), 0.4, ContactKind::Sliding, &p, &old);
        assert!(out.active);
        assert!(e < FD_TOL, "frictionless tangent rel. error {e:e}");
        // Frictionless tangent is symmetric (Hessian of the penalty potential).
        for i in 0..6 {
            for j in 0..6 {
                assert!((out.k[i][j] - out.k[j][i]).abs() < EXACT * max_abs(&out.k));
            }
        }
    }
}

#[test]
fn fd_tangent_stick() {
    let p = params();
    let (xs, x1, x2) = setup(0.3, -0.01);
    // Anchor 0.0005 mm behind along t: g_T = +5e-4, trial t = λ_T + 0.5 MPa, μ p = 0.3·12 = 3.6.
    let old = PairHistory { xi_stick: 0.3 - 0.0005 / 2.0, lambda_n: 2.0, lambda_t: 0.2, active: true };
    let (e, out) = fd_check_nts(pack(xs, x1, x2), 0.4, ContactKind::Rubbing { mu: 0.3 }, &p, &old);
    assert!(out.active && !out.slip);
    assert!((out.shear - 0.7).abs() < 1e-9, "shear {}", out.shear);
    assert!(e < FD_TOL, "stick tangent rel. error {e:e}");
    assert_eq!(out.new_history.xi_stick, old.xi_stick, "stick keeps the anchor");
}

#[test]
fn fd_tangent_slip() {
    let p = params();
    let (xs, x1, x2) = setup(0.3, -0.01);
    for sign in [1.0, -1.0] {
        // g_T = ±0.02 mm → |trial| = 20 MPa > μ p = 3 MPa.
        let old = PairHistory { xi_stick: 0.3 - sign * 0.02 / 2.0, lambda_n: 0.0, lambda_t: 0.0, active: true };
        let (e, out) = fd_check_nts(pack(xs, x1, x2), 0.4, ContactKind::Rubbing { mu: 0.3 }, &p, &old);
        assert!(out.slip);
        assert!((out.shear - sign * 0.3 * out.pressure).abs() < EXACT * out.pressure);
        assert!(e < FD_TOL, "slip tangent rel. error {e:e}");
        // Non-symmetric.
        let asym = (0..6)
            .flat_map(|i| (0..6).map(move |j| (i, j)))
            .fold(0.0f64, |m, (i, j)| m.max((out.k[i][j] - out.k[j][i]).abs()));
        assert!(asym > 1e-3 * max_abs(&out.k));
        // Return mapping: re-evaluating with the new anchor at the same configuration gives the
        // slip traction exactly on the cone.
        let again = eval_nts(&pack(xs, x1, x2), 0.4, ContactKind::Rubbing { mu: 0.3 }, &p, &out.new_history);
        assert!((again.shear - out.shear).abs() < 1e-9 * out.shear.abs());
    }
}

#[test]
fn fd_tangent_cohering_in_tension() {
    let p = params();
    let (xs, x1, x2) = setup(0.3, 0.01); // open by 0.01 mm
    let old = PairHistory { xi_stick: 0.31, lambda_n: 0.0, lambda_t: 0.0, active: true };
    let (e, out) = fd_check_nts(pack(xs, x1, x2), 0.4, ContactKind::Cohering, &p, &old);
    assert!(out.active && !out.slip);
    assert!((out.pressure + 10.0).abs() < 1e-9, "tension pressure {}", out.pressure);
    assert!((out.shear - p.eps_t * (0.3 - 0.31) * 2.0).abs() < 1e-9);
    assert!(e < FD_TOL, "cohering tangent rel. error {e:e}");
}

#[test]
fn fd_tangent_wall_all_modes() {
    let p = params();
    let (t, n) = rot(0.4);
    let wall = Wall { point: [1.0, 2.0], normal: [-n[0], -n[1]] };
    let wt = wall.tangent();
    let d = 0.25;
    let area = 0.6;
    let at = |g: f64, s: f64| {
        // node with gap g and wall-frame coordinate s (x·t_w − d = s)
        let wn = [-n[0], -n[1]];
        let base = [wall.point[0] + g * wn[0], wall.point[1] + g * wn[1]];
        let s0 = base[0] * wt[0] + base[1] * wt[1] - d;
        [base[0] + (s - s0) * wt[0], base[1] + (s - s0) * wt[1]]
    };
    let _ = t;
    // Sliding
    let x = at(-0.01, 0.0);
    let (e, o) = fd_check_wall(x, &wall, d, area, ContactKind::Sliding, &p, &PairHistory::default());
    assert!(o.active && (o.gap + 0.01).abs() < 1e-12 && e < FD_TOL, "sliding {e:e}");
    // Stick
    let old = PairHistory { xi_stick: -0.001, lambda_n: 1.0, lambda_t: -0.3, active: true };
    let (e, o) = fd_check_wall(x, &wall, d, area, ContactKind::Rubbing { mu: 0.3 }, &p, &old);
    assert!(!o.slip && (o.shear - 0.7).abs() < 1e-9 && e < FD_TOL, "stick {e:e}");
    // Slip both ways
    for sg in [1.0, -1.0] {
        let old = PairHistory { xi_stick: -sg * 0.05, lambda_n: 0.0, lambda_t: 0.0, active: true };
        let (e, o) = fd_check_wall(x, &wall, d, area, ContactKind::Rubbing { mu: 0.3 }, &p, &old);
        assert!(o.slip && (o.shear - sg * 3.0).abs() < 1e-9 && e < FD_TOL, "slip {e:e}");
    }
    // Cohering in tension
    let x = at(0.02, 0.0);
    let old = PairHistory { xi_stick: 0.004, lambda_n: 0.0, lambda_t: 0.0, active: true };
    let (e, o) = fd_check_wall(x, &wall, d, area, ContactKind::Cohering, &p, &old);
    assert!(
        o.active && (o.pressure + 20.0).abs() < 1e-9 && (o.shear + 4.0).abs() < 1e-9 && e < FD_TOL,
        "cohering {e:e}"
    );
}

// ---------------------------------------------------------------------------------------------
// Coulomb
// ---------------------------------------------------------------------------------------------

#[test]
fn coulomb_drag_on_wall_stick_then_slip() {
    let p = PenaltyParams { eps_n: 1000.0, eps_t: 500.0 };
    let mu = 0.25;
    let area = 0.5;
    let wall = Wall { point: [0.0, 0.0], normal: [0.0, 1.0] };
    let t = wall.tangent();
    let g = -0.02; // p_N = 20 MPa, μ p_N = 5 MPa → stick up to g_T = 0.01 mm
    let pn = 20.0;
    let mut x = [0.3, g];
    // First contact: anchor set at the current point, no shear.
    let mut hist = PairHistory::default();
    let o = eval_wall(x, &wall, 0.0, area, ContactKind::Rubbing { mu }, &p, &hist);
    assert!(o.active && o.shear == 0.0 && !o.slip);
    hist = o.new_history;
    let s_anchor0 = hist.xi_stick;
    let mut total = 0.0;
    let mut slipped = false;
    for _ in 0..20 {
        // drag the node by 0.002 mm along +t per step
        x = [x[0] + 0.002 * t[0], x[1] + 0.002 * t[1]];
        total += 0.002;
        let o = eval_wall(x, &wall, 0.0, area, ContactKind::Rubbing { mu }, &p, &hist);
        assert!((o.pressure - pn).abs() < EXACT * pn);
        let gt = o.xi - hist.xi_stick;
        if !slipped && total <= 0.01 - 1e-9 {
            assert!(!o.slip, "stick expected at g_T = {total}");
            assert!((o.shear - p.eps_t * gt).abs() < EXACT * pn);
            assert!((gt - total).abs() < 1e-12);
            assert_eq!(o.new_history.xi_stick, s_anchor0);
        } else if total > 0.01 + 1e-9 {
            assert!(o.slip, "slip expected at total drag {total}");
            assert!((o.shear - mu * pn).abs() < EXACT * pn, "shear {} vs μp {}", o.shear, mu * pn);
            assert!(o.new_history.xi_stick > hist.xi_stick, "anchor moves with the slip");
            slipped = true;
        }
        // The force on the node (−f_c) opposes the drag: f_c·t = A t_T > 0.
        assert!(o.f[0] * t[0] + o.f[1] * t[1] >= 0.0);
        hist = o.new_history;
    }
    assert!(slipped);
    // Dragging the wall by −δ along t (node fixed) is the same relative motion as the node by +δ.
    let old = PairHistory { xi_stick: 0.0, lambda_n: 0.0, lambda_t: 0.0, active: true };
    let x0 = [0.0, g];
    let a = eval_wall(
        [x0[0] + 0.004 * t[0], x0[1] + 0.004 * t[1]],
        &wall,
        0.0,
        area,
        ContactKind::Rubbing { mu },
        &p,
        &old,
    );
    let b = eval_wall(x0, &wall, -0.004, area, ContactKind::Rubbing { mu }, &p, &old);
    assert!((a.shear - b.shear).abs() < 1e-9 && (a.shear - 2.0).abs() < 1e-9);
}

#[test]
fn nts_coulomb_threshold() {
    let p = params();
    let (xs, x1, x2) = setup(0.5, -0.01); // p = 10 MPa, μp = 3 MPa with μ = 0.3
    let x = pack(xs, x1, x2);
    let below = PairHistory { xi_stick: 0.5 - 0.0029 / 2.0, active: true, ..Default::default() };
    let o = eval_nts(&x, 0.5, ContactKind::Rubbing { mu: 0.3 }, &p, &below);
    assert!(!o.slip && (o.shear - 2.9).abs() < 1e-9);
    let above = PairHistory { xi_stick: 0.5 - 0.0031 / 2.0, active: true, ..Default::default() };
    let o = eval_nts(&x, 0.5, ContactKind::Rubbing { mu: 0.3 }, &p, &above);
    assert!(o.slip && (o.shear - 0.3 * o.pressure).abs() < EXACT * o.pressure);
    assert!(o.new_history.xi_stick > above.xi_stick);
}

// ---------------------------------------------------------------------------------------------
// Augmented Lagrangian (Uzawa)
// ---------------------------------------------------------------------------------------------

/// A node on a linear spring (stiffness k, N/mm per mm) whose support sits δ beyond a wall:
/// the exact constrained solution is y = 0 with contact force k δ, i.e. pressure k δ / A.
/// Each Uzawa update reduces the penetration by the factor k/(k + ε_N A).
#[test]
fn uzawa_on_wall_converges_monotonically() {
    let p = params();
    let (kspr, delta, area) = (100.0, 0.1, 0.5);
    let wall = Wall { point: [0.0, 0.0], normal: [0.0, 1.0] };
    let target = kspr * delta / area;
    let rate = kspr / (kspr + p.eps_n * area);
    let mut hist = PairHistory::default();
    let mut y = 0.0;
    let mut pens = Vec::new();
    let mut last: Option<WallOut> = None;
    for _ in 0..14 {
        // Newton on R(y) = −k (y + δ) − f_c,y(y).
        let mut converged = false;
        for _ in 0..20 {
            let o = eval_wall([0.0, y], &wall, 0.0, area, ContactKind::Sliding, &p, &hist);
            let r = -kspr * (y + delta) - o.f[1];
            if r.abs() < 1e-13 * kspr * delta {
                last = Some(o);
                converged = true;
                break;
            }
            y += r / (kspr + o.k[1][1]);
        }
        let l = last.expect("converged");
        assert!(converged && l.active);
        pens.push(-l.gap);
        hist = augment(&l);
    }
    // Pure penalty (first solve): penetration k δ/(k + ε A).
    assert!((pens[0] - kspr * delta / (kspr + p.eps_n * area)).abs() < 1e-12);
    for w in pens.windows(2) {
        assert!(w[1] < w[0], "penetration must decrease: {pens:?}");
        // The rate is checked while the penetration is well above round-off (~1e-17 mm here).
        assert!((w[1] / w[0] - rate).abs() < 1e-6 || w[1] < 1e-10, "rate {} vs {rate}", w[1] / w[0]);
    }
    let last = last.expect("converged");
    assert!((last.pressure - target).abs() < 1e-9 * target, "pressure {} vs {target}", last.pressure);
}

/// Same with a node-to-segment pair: the slave on an isotropic spring, the rotated master fixed.
#[test]
fn uzawa_on_segment_converges_monotonically() {
    let p = params();
    let (kspr, delta, area) = (100.0, 0.1, 0.5);
    let (_, x1, x2) = setup(0.4, 0.0);
    let geo0 = nts_project(setup(0.4, 0.0).0, x1, x2);
    let n = geo0.normal;
    let (support, _, _) = setup(0.4, -delta);
    let mut xs = setup(0.4, 0.0).0;
    let mut hist = PairHistory::default();
    let mut pens = Vec::new();
    let mut last: Option<PairOut> = None;
    for _ in 0..13 {
        let mut converged = false;
        for _ in 0..20 {
            let o = eval_nts(&pack(xs, x1, x2), area, ContactKind::Sliding, &p, &hist);
            let r = [-kspr * (xs[0] - support[0]) - o.f[0], -kspr * (xs[1] - support[1]) - o.f[1]];
            if r[0].hypot(r[1]) < 1e-13 * kspr * delta {
                last = Some(o);
                converged = true;
                break;
            }
            let a = [[kspr + o.k[0][0], o.k[0][1]], [o.k[1][0], kspr + o.k[1][1]]];
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            xs[0] += (a[1][1] * r[0] - a[0][1] * r[1]) / det;
            xs[1] += (-a[1][0] * r[0] + a[0][0] * r[1]) / det;
        }
        let l = last.expect("converged");
        assert!(converged && l.active);
        pens.push(-l.gap);
        hist = augment(&l);
    }
    let last = last.expect("converged");
    for w in pens.windows(2) {
        assert!(w[1] < w[0], "penetration must decrease: {pens:?}");
    }
    let target = kspr * delta / area;
    assert!((last.pressure - target).abs() < 1e-9 * target);
    // The slave ends on the master line with the force along n.
    assert!(last.gap.abs() < 1e-9 * delta);
    assert!((last.f[0] + target * area * n[0]).abs() < 1e-8 * target);
}

#[test]
fn augment_keeps_anchor_in_stick_and_moves_it_in_slip() {
    let p = params();
    let (xs, x1, x2) = setup(0.3, -0.01);
    let x = pack(xs, x1, x2);
    let kind = ContactKind::Rubbing { mu: 0.3 };
    // Stick: λ_T ← t_T, anchor kept.
    let old = PairHistory { xi_stick: 0.3 - 0.001 / 2.0, lambda_n: 0.0, lambda_t: 0.0, active: true };
    let o = eval_nts(&x, 0.4, kind, &p, &old);
    let h = augment(&o);
    assert!(!o.slip && h.xi_stick == old.xi_stick && h.lambda_t == o.shear && h.lambda_n == o.pressure);
    // Slip: anchor to the current ξ, λ_T = t_T, so the same configuration gives the same shear.
    let old = PairHistory { xi_stick: 0.3 - 0.02 / 2.0, lambda_n: 0.0, lambda_t: 0.0, active: true };
    let o = eval_nts(&x, 0.4, kind, &p, &old);
    let h = augment(&o);
    assert!(o.slip && (h.xi_stick - o.xi).abs() < EXACT);
    let again = eval_nts(&x, 0.4, kind, &p, &h);
    assert!((again.shear - o.shear).abs() < 1e-9);
    // Inactive resets.
    let (xs, x1, x2) = setup(0.3, 0.05);
    let o = eval_nts(&pack(xs, x1, x2), 0.4, kind, &p, &h);
    let h2 = augment(&o);
    assert!(!h2.active && h2.lambda_n == 0.0 && h2.lambda_t == 0.0);
}
