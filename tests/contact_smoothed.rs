//! Tests of the smoothed node-to-segment kernel (`mpfem::contact::smooth`, `[contact] normal =
//! "smoothed"`).
//!
//! Tolerances and why:
//! * Tangent: central finite differences of f with a perturbation of 1e-7 mm; the relative
//!   error max|K_fd − K| / max|K| must be ≤ 1e-6 (as in tests/contact_kernels.rs: truncation
//!   O(h²) ≈ 1e-14, round-off ≈ 1e-16 |f| / h ≈ 1e-9 relative here, any missing term O(1e-3)).
//! * Straight master: the smoothed surface is the segment itself (Hermite interpolation
//!   reproduces straight lines) and the force is taken at fixed end angles, so gap, ξ,
//!   pressure and the 6 forces equal the segment kernel's to 1e-12 relative (round-off of the
//!   Newton projection only), and the neighbours get no force.
//! * Corner sweep: a slave node moved in 2000 and 4000 equal steps round a 45° convex master
//!   corner (an octagon corner). Continuous quantities change by O(step): the largest change of
//!   the force between two positions must halve (ratio ≤ 0.6) when the step halves and stay
//!   below 1 % of the largest force. The segment kernel's force turns by the corner angle at
//!   the switch: its largest change is |n_A − n_B| p A = 2 sin(22.5°) p A (p the pressure at
//!   the switch) to 2 %, the same at both resolutions.

use mpfem::contact::enforce::*;
use mpfem::contact::smooth::*;

type SmoothPairOut = PairResult<NDOF>;

const H_FD: f64 = 1e-7;
const FD_TOL: f64 = 1e-6;

fn eval(x: &[f64; 10], has: [bool; 2], area: f64, kind: ContactKind, p: &PenaltyParams, old: &PairHistory) -> SmoothPairOut {
    let m = Master { x1: [x[2], x[3]], x2: [x[4], x[5]], prev: has[0].then_some([x[6], x[7]]), next: has[1].then_some([x[8], x[9]]) };
    smooth_pair([x[0], x[1]], &m, area, kind, p, old)
}

fn fd_check(x: [f64; 10], has: [bool; 2], kind: ContactKind, p: &PenaltyParams, old: &PairHistory) -> (f64, SmoothPairOut) {
    let out = eval(&x, has, 0.7, kind, p, old);
    assert!(out.active, "the state must be active");
    let kmax = out.k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut err = 0.0f64;
    for j in 0..10 {
        let (mut xp, mut xm) = (x, x);
        xp[j] += H_FD;
        xm[j] -= H_FD;
        let fp = eval(&xp, has, 0.7, kind, p, old);
        let fm = eval(&xm, has, 0.7, kind, p, old);
        assert_eq!((fp.slip, fm.slip, fp.active, fm.active), (out.slip, out.slip, true, true), "state changed in the FD stencil");
        for i in 0..10 {
            let fd = (fp.f[i] - fm.f[i]) / (2.0 * H_FD);
            err = err.max((fd - out.k[i][j]).abs());
        }
    }
    (err / kmax, out)
}

/// A master polyline with two smoothed corners: 0 → 1 → 2 → 3 turning by 30° and 45° at 1
/// and 2 (convex, body on the left), slave near the segment 1 → 2 at parameter `xi`, normal
/// offset `g` from the chord.
fn corner_state(xi: f64, g: f64) -> [f64; 10] {
    turn_state(xi, g, 30.0, 45.0)
}

/// As [`corner_state`] with turns of `b1` and `b2` degrees at nodes 1 and 2 (negative =
/// concave).
fn turn_state(xi: f64, g: f64, b1: f64, b2: f64) -> [f64; 10] {
    let x0 = [-1.1, 0.0];
    let x1 = [0.0, 0.0];
    let a1 = b1.to_radians();
    let x2 = [1.3 * a1.cos(), 1.3 * a1.sin()];
    let a2 = a1 + b2.to_radians();
    let x3 = [x2[0] + 0.9 * a2.cos(), x2[1] + 0.9 * a2.sin()];
    let d = [x2[0] - x1[0], x2[1] - x1[1]];
    let l = (d[0] * d[0] + d[1] * d[1]).sqrt();
    let n = [d[1] / l, -d[0] / l];
    let xs = [x1[0] + xi * d[0] + g * n[0], x1[1] + xi * d[1] + g * n[1]];
    [xs[0], xs[1], x1[0], x1[1], x2[0], x2[1], x0[0], x0[1], x3[0], x3[1]]
}

#[test]
fn smoothed_tangent_matches_finite_differences() {
    let p = PenaltyParams { eps_n: 1.0e3, eps_t: 5.0e2 };
    let frictionless = PairHistory::default();
    // ξ = 1.1 and −0.1: past the ends, on the cubic's continuation
    for &(xi, g) in &[(0.2, -0.08), (0.5, -0.1), (0.93, -0.03), (0.05, -0.05), (1.1, -0.2), (-0.1, -0.2)] {
        let x = corner_state(xi, g);
        for has in [[true, true], [false, true], [true, false]] {
            let (err, out) = fd_check(x, has, ContactKind::Sliding, &p, &frictionless);
            eprintln!("frictionless ξ = {xi}, g = {g}, neighbours {has:?}: relative tangent error {err:.3e}");
            assert!(err < FD_TOL, "frictionless ξ = {xi}, g = {g}, neighbours {has:?}: relative tangent error {err:.3e}");
            // the force acts on the slave and the segment's own nodes only (fixed end angles),
            // its resultant vanishes, and the neighbours appear in the tangent's columns
            let fmax = out.f.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(out.f[6..].iter().all(|v| *v == 0.0));
            for c in 0..2 {
                assert!((out.f[c] + out.f[2 + c] + out.f[4 + c]).abs() <= 1e-12 * fmax, "resultant");
            }
            if has[0] && xi < 1.0 {
                let k0 = (0..6).map(|i| out.k[i][6].abs().max(out.k[i][7].abs())).fold(0.0, f64::max);
                assert!(k0 > 1e-6 * out.k[0][0].abs(), "the neighbour 0 must enter the tangent");
            }
        }
    }
    // augmented-Lagrangian multiplier, stick and slip, tied
    let x = corner_state(0.4, -0.09);
    let with_lambda = PairHistory { xi_stick: 0.0, lambda_n: 3.0, lambda_t: 0.0, active: false };
    let (err, _) = fd_check(x, [true, true], ContactKind::Sliding, &p, &with_lambda);
    eprintln!("lambda_n: {err:.3e}");
    assert!(err < FD_TOL, "lambda_n: {err:.3e}");
    let stick = PairHistory { xi_stick: 0.395, lambda_n: 1.0, lambda_t: 0.2, active: true };
    let (err, out) = fd_check(x, [true, true], ContactKind::Rubbing { mu: 0.5 }, &p, &stick);
    assert!(!out.slip && out.shear != 0.0, "stick state expected");
    eprintln!("stick: {err:.3e}");
    assert!(err < FD_TOL, "stick: {err:.3e}");
    let slip = PairHistory { xi_stick: 0.3, lambda_n: 0.0, lambda_t: 0.0, active: true };
    let (err, out) = fd_check(x, [true, true], ContactKind::Rubbing { mu: 0.2 }, &p, &slip);
    assert!(out.slip, "slip state expected");
    eprintln!("slip: {err:.3e}");
    assert!(err < FD_TOL, "slip: {err:.3e}");
    // turns in the phase-in band of the smoothing (0.1°–0.3°) and its phase-out band (50°–80°),
    // convex and concave
    for (b1, b2) in [(0.2, 0.15), (-0.16, 0.27), (0.22, -0.25), (62.0, -71.0), (55.0, 78.0)] {
        let x = turn_state(0.37, -0.01, b1, b2);
        let (err, _) = fd_check(x, [true, true], ContactKind::Sliding, &p, &frictionless);
        eprintln!("turns {b1}°, {b2}°: {err:.3e}");
        assert!(err < FD_TOL, "turns {b1}°, {b2}°: {err:.3e}");
    }
    let tied = PairHistory { xi_stick: 0.41, lambda_n: 0.0, lambda_t: 0.0, active: true };
    let x = corner_state(0.4, 0.09);
    let (err, _) = fd_check(x, [true, true], ContactKind::Cohering, &p, &tied);
    eprintln!("cohering: {err:.3e}");
    assert!(err < FD_TOL, "cohering in tension: {err:.3e}");
}

#[test]
fn smoothed_equals_segment_on_a_straight_master() {
    let p = PenaltyParams { eps_n: 1.0e3, eps_t: 1.0e3 };
    let (t, l) = ([30f64.to_radians().cos(), 30f64.to_radians().sin()], 2.0);
    let n = [t[1], -t[0]];
    let x1 = [0.7, -0.4];
    let at = |s: f64| [x1[0] + s * t[0], x1[1] + s * t[1]];
    let m = Master { x1, x2: at(l), prev: Some(at(-0.8)), next: Some(at(l + 1.5)) };
    for &(xi, g) in &[(0.1, -0.02), (0.5, -0.001), (0.97, -0.04)] {
        let xs = [x1[0] + xi * l * t[0] + g * n[0], x1[1] + xi * l * t[1] + g * n[1]];
        for (kind, old) in [
            (ContactKind::Sliding, PairHistory::default()),
            (ContactKind::Rubbing { mu: 0.3 }, PairHistory { xi_stick: xi - 0.001, lambda_n: 0.0, lambda_t: 0.0, active: true }),
        ] {
            let seg = segment_pair(xs, m.x1, m.x2, 0.5, kind, &p, &old);
            let sm = smooth_pair(xs, &m, 0.5, kind, &p, &old);
            let fmax = seg.f.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!((sm.gap - seg.gap).abs() <= 1e-12 * l && (sm.xi - seg.xi).abs() <= 1e-12, "gap/xi: {} {} vs {} {}", sm.gap, sm.xi, seg.gap, seg.xi);
            for i in 0..6 {
                assert!((sm.f[i] - seg.f[i]).abs() <= 1e-12 * fmax, "f[{i}]: {} vs {}", sm.f[i], seg.f[i]);
            }
            assert!(sm.f[6..].iter().all(|v| *v == 0.0), "no force on the neighbours");
            assert!((sm.pressure - seg.pressure).abs() <= 1e-12 * seg.pressure.abs() && (sm.shear - seg.shear).abs() <= 1e-12 * fmax);
            assert_eq!((sm.slip, sm.active), (seg.slip, seg.active));
        }
    }
}

/// Slave force (on the slave node, −f[0..2]) and gap along a sweep round the convex corner of
/// the master polyline P0 → P1 → C → Q1 → Q2 (a 45° turn at C, body on the left: above the
/// first leg and to the left of the second), choosing per position the segment as the driver
/// does (ξ in [0, 1], closest). The slave moves on a circle of radius 0.45 about a point 0.5
/// inside the corner along its bisector: it penetrates both legs by 0.012 at the ends of the
/// sweep and by 0.046 on the bisector.
fn corner_sweep(smoothed: bool, n: usize) -> Vec<([f64; 2], f64, f64)> {
    let s2 = 0.5f64.sqrt();
    let c = [0.0, 0.0];
    let pts = [[-2.0, 0.0], [-1.0, 0.0], c, [s2, s2], [2.0 * s2, 2.0 * s2], [2.0 * s2 - 0.3, 2.0 * s2 + 1.0]];
    // segments A = 1 → C and B = C → Q1 with their neighbours
    let segs = [(1usize, 2usize), (2, 3)];
    let bis = unit([-(22.5f64.to_radians().sin()), 22.5f64.to_radians().cos()]);
    let centre = [c[0] + 0.5 * bis[0], c[1] + 0.5 * bis[1]];
    let p = PenaltyParams { eps_n: 100.0, eps_t: 100.0 };
    let area = 1.0;
    let (a0, a1) = ((-100f64).to_radians(), (-35f64).to_radians());
    (0..=n)
        .map(|i| {
            let a = a0 + (a1 - a0) * i as f64 / n as f64;
            let xs = [centre[0] + 0.45 * a.cos(), centre[1] + 0.45 * a.sin()];
            let mut best: Option<(f64, [f64; 2], f64, f64)> = None;
            for &(i1, i2) in &segs {
                let (x1, x2) = (pts[i1], pts[i2]);
                let (xi, gap, f, pr) = if smoothed {
                    let m = Master { x1, x2, prev: Some(pts[i1 - 1]), next: Some(pts[i2 + 1]) };
                    let out = smooth_pair(xs, &m, area, ContactKind::Sliding, &p, &PairHistory::default());
                    (out.xi, out.gap, [-out.f[0], -out.f[1]], out.pressure)
                } else {
                    let out = segment_pair(xs, x1, x2, area, ContactKind::Sliding, &p, &PairHistory::default());
                    (out.xi, out.gap, [-out.f[0], -out.f[1]], out.pressure)
                };
                if !(0.0..=1.0).contains(&xi) {
                    continue;
                }
                if best.is_none_or(|b| gap.abs() < b.0) {
                    best = Some((gap.abs(), f, gap, pr));
                }
            }
            let (_, f, gap, pr) = best.expect("a segment faces the slave");
            (f, gap, pr)
        })
        .collect()
}

fn unit(v: [f64; 2]) -> [f64; 2] {
    let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
    [v[0] / l, v[1] / l]
}

/// Largest change of the force and of the gap between consecutive positions, the largest
/// force, and the pressure where the force changed most.
fn jumps(s: &[([f64; 2], f64, f64)]) -> (f64, f64, f64, f64) {
    let mut df: f64 = 0.0;
    let mut dg: f64 = 0.0;
    let mut p_at = 0.0;
    for w in s.windows(2) {
        let d = ((w[1].0[0] - w[0].0[0]).powi(2) + (w[1].0[1] - w[0].0[1]).powi(2)).sqrt();
        if d > df {
            df = d;
            p_at = 0.5 * (w[0].2 + w[1].2);
        }
        dg = dg.max((w[1].1 - w[0].1).abs());
    }
    let fmax = s.iter().map(|q| (q.0[0].powi(2) + q.0[1].powi(2)).sqrt()).fold(0.0, f64::max);
    (df, dg, fmax, p_at)
}

#[test]
fn smoothed_force_is_continuous_round_a_convex_corner() {
    let (df1, dg1, fmax, _) = jumps(&corner_sweep(true, 2000));
    let (df2, dg2, _, _) = jumps(&corner_sweep(true, 4000));
    eprintln!("smoothed: max |Δf| = {df1:.3e} (2000 steps), {df2:.3e} (4000), max |f| = {fmax:.3e}; max |Δg| = {dg1:.3e}, {dg2:.3e}");
    assert!(df2 <= 0.6 * df1 && dg2 <= 0.6 * dg1, "the changes do not shrink with the step: {df1} → {df2}, {dg1} → {dg2}");
    assert!(df1 < 1e-2 * fmax, "largest force change {df1} vs max force {fmax}");

    let (sf1, _, _, p1) = jumps(&corner_sweep(false, 2000));
    let (sf2, _, _, p2) = jumps(&corner_sweep(false, 4000));
    let expected = |p: f64| 2.0 * 22.5f64.to_radians().sin() * p; // |n_A − n_B| p A, A = 1
    eprintln!("segment: max |Δf| = {sf1:.3e} (2000 steps), {sf2:.3e} (4000); expected {:.3e}", expected(p1));
    assert!((sf1 - expected(p1)).abs() < 0.02 * expected(p1), "segment jump {sf1} vs {}", expected(p1));
    assert!((sf2 - expected(p2)).abs() < 0.02 * expected(p2), "segment jump {sf2} vs {}", expected(p2));
}
