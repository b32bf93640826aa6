//! Compaction with the barrier contact (`[contact] method = "barrier"`, the defaults: d̂ = h/20,
//! κ from [`mpfem::contact::barrier_problem::default_kappa`], the springs as a fictitious
//! inertia) on the 2 × 2 biaxial job of `jobs/compaction/`, which the penalty method completes:
//! - it reaches its target solid ratio 0.95;
//! - every converged state is admissible: no boundary node inside another particle or behind a
//!   wall, no element with a non-positive corner Jacobian (counted at every step, asserted 0);
//! - the stabilisation springs take at most 1 % of the wall work;
//! - the wall pressures at solid ratio 0.95 agree with the penalty method's within 3 % (the
//!   barrier issue's check: two enforcements of the same contact, each with its own small
//!   error — a gap of d̂/100…d̂ against a penetration of p h/(10E));
//! - the gap does not distort the physics: halving d̂ changes the mean wall pressures over
//!   solid ratios 0.93–0.95 by less than 1 %.
//!
//! The two comparisons run the jobs at Δt = 0.01 s (the job's steps grow to 0.05 s): the
//! pressure rises steeply and convexly near 0.95, and the trapezoidal rule over 0.05-s steps
//! (Δφ ≈ 0.01) is off by about 1 % itself, the size of the tolerance: with the job's steps the
//! barrier on edge points gave 1.0–1.3 % between d̂ = h/20 and h/40 in the mean, and between
//! d̂ = 0.2 and 0.1 mm (`mpfem run`) 0.4–0.9 % with the job's steps but 0.3–0.4 % at
//! Δt = 0.01 s (the barrier on the nodes: 0.7–0.9 % and 0.6–0.8 %). The runs at the job's own
//! steps are kept for the other checks (admissibility, springs, step growth).
//! Pressures at 0.95 are interpolated linearly in the solid ratio between the two steps that
//! bracket it. The d̂ check takes the mean over 0.93–0.95 (trapezoidal rule over the steps,
//! the ends interpolated) rather than the value at 0.95: there the pressure rises by 4 MPa
//! per 0.01 of solid ratio as the central pore closes, and where on the path that rise starts
//! moves with the Newton path by ±0.003 (which step sizes, cut-backs and retries the run
//! took), ±1 % of the pressure at 0.95 whatever d̂. Measured with the retry of failed steps
//! on definite tangents: d̂ and d̂/2 differ by 1.2 % at 0.95 (168.7 and 166.7 MPa on the left
//! wall) and by 0.07 % in the mean (162.43 and 162.32 MPa); d̂ = 0.1 mm and d̂ = h/40, which
//! are 2 % apart, differ by 0.7 % at 0.95.

use mpfem::case;
use mpfem::model::Model;
use mpfem::solver::{Simulation, StepReport};
use std::path::Path;

const JOB: &str = "jobs/compaction/discs_2x2_biaxial.toml";

struct Run {
    reports: Vec<StepReport>,
    /// The step size each step was tried at (the step-size control's choice after the step
    /// before; the first: `[time] dt`), beside `reports`.
    tried: Vec<f64>,
    /// Whether each step started descending on the potential (beside `reports`).
    descended: Vec<bool>,
    growth: f64,
    dt_max: f64,
    easy_iterations: usize,
    stop: String,
    crossings: usize,
    inverted: usize,
    /// With ties: how many at the end, and the largest tie gap over the converged states (mm).
    ties: usize,
    tie_gap: f64,
}

/// Elements with a corner whose Jacobian (the cross product of its two edges) is not positive.
fn inverted_elements(model: &Model, x: &[[f64; 2]]) -> usize {
    model
        .elements
        .iter()
        .filter(|e| {
            (0..4).any(|k| {
                let (p, a, b) = (x[e[k]], x[e[(k + 1) % 4]], x[e[(k + 3) % 4]]);
                let (u, v) = ([a[0] - p[0], a[1] - p[1]], [b[0] - p[0], b[1] - p[1]]);
                u[0] * v[1] - u[1] * v[0] <= 0.0
            })
        })
        .count()
}

fn run(text: &str) -> Run {
    let c = case::parse(text, Path::new("jobs/compaction")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    let mut reports = Vec::new();
    let mut tried = vec![c.time.dt];
    let mut descended = vec![sim.barrier_descends()];
    let (growth, dt_max, easy_iterations) = (sim.time.growth, sim.time.dt_max, sim.time.easy_iterations);
    let (mut crossings, mut inverted, mut ties, mut tie_gap) = (0, 0, 0, 0.0f64);
    let summary = sim
        .run(&mut |s, r| {
            reports.push(r.clone());
            tried.push(s.next_dt());
            descended.push(s.barrier_descends());
            crossings += s.barrier_crossings().unwrap_or(0);
            inverted += inverted_elements(&s.model, &s.coords(&s.sol.u));
            if let Some((n, gap)) = s.barrier_ties() {
                (ties, tie_gap) = (n, tie_gap.max(gap));
            }
        })
        .unwrap();
    tried.truncate(reports.len());
    descended.truncate(reports.len());
    Run { reports, tried, descended, growth, dt_max, easy_iterations, stop: summary.stop_reason, crossings, inverted, ties, tie_gap }
}

/// The step-size control as `Simulation::step_easy` states it for the barrier, checked on
/// every step of a run that was not shortened to land on the stop solid ratio: a step that
/// converged at the size it was tried grows the next one by `[time] growth` (up to `dt_max`)
/// whatever its Newton iterations — without a retry, or descending on the potential in the
/// one retry after its first attempt failed (one cut-back counted, the size kept) or from its
/// start, the descent being on for good once a step has needed the retry; every other step
/// keeps its size. Returns how many steps grew after more than `easy_iterations` Newton
/// iterations (the rule of the other contact methods would have held them), so that a caller
/// can tell the check was not vacuous. (These discs are frictionless and compressible: a
/// step's iterations are those of its one solve.)
fn check_step_growth(run: &Run) -> usize {
    let mut grown_past_easy = 0;
    for (k, r) in run.reports.iter().enumerate().take(run.reports.len() - 1) {
        let at_size = r.dt == run.tried[k];
        if !at_size {
            // cut back, or shortened to land on the stop solid ratio
            continue;
        }
        // the descent on from the step's start, or its retry at the size (so on after it)
        let sticky = run.descended[k];
        let descended_at_size = if sticky { r.cutbacks == 0 } else { r.cutbacks == 1 && run.descended[k + 1] };
        let easy = r.cutbacks == 0 || descended_at_size;
        let expected = if easy { (r.dt * run.growth).min(run.dt_max) } else { r.dt };
        assert!((run.tried[k + 1] / expected - 1.0).abs() < 1e-12, "step {} ({} iterations, {} cut-backs at dt {}, descending from its start: {sticky}): the next step tried {}, expected {}", r.step, r.newton_iterations, r.cutbacks, r.dt, run.tried[k + 1], expected);
        if easy && r.newton_iterations > run.easy_iterations && r.dt < run.dt_max {
            grown_past_easy += 1;
        }
    }
    grown_past_easy
}

/// The four wall pressures (left, right, bottom, top; MPa) at solid ratio `phi`.
fn pressures_at(reports: &[StepReport], phi: f64) -> [f64; 4] {
    let c: Vec<_> = reports.iter().map(|r| r.compaction.clone().unwrap()).collect();
    let k = c.iter().position(|c| c.solid_ratio >= phi).unwrap_or_else(|| panic!("solid ratio {phi} not reached"));
    assert!(k > 0, "the first step is already beyond {phi}");
    let (a, b) = (&c[k - 1], &c[k]);
    let s = (phi - a.solid_ratio) / (b.solid_ratio - a.solid_ratio);
    std::array::from_fn(|i| a.pressure[i] + s * (b.pressure[i] - a.pressure[i]))
}

/// The mean of the four wall pressures (MPa) over solid ratios `lo`–`hi`: the trapezoidal
/// rule over the steps in between, the pressures at the ends interpolated.
fn mean_pressures(reports: &[StepReport], lo: f64, hi: f64) -> [f64; 4] {
    let mut pts: Vec<(f64, [f64; 4])> = vec![(lo, pressures_at(reports, lo))];
    for r in reports {
        let c = r.compaction.clone().unwrap();
        if c.solid_ratio > lo && c.solid_ratio < hi {
            pts.push((c.solid_ratio, c.pressure));
        }
    }
    pts.push((hi, pressures_at(reports, hi)));
    std::array::from_fn(|i| pts.windows(2).map(|w| 0.5 * (w[0].1[i] + w[1].1[i]) * (w[1].0 - w[0].0)).sum::<f64>() / (hi - lo))
}

#[test]
fn biaxial_discs_compact_with_the_barrier() {
    let penalty_text = std::fs::read_to_string(JOB).unwrap();
    assert!(penalty_text.contains("method = \"penalty\""));

    let barrier_text = penalty_text.replace("method = \"penalty\"", "method = \"barrier\"");
    let barrier = run(&barrier_text);
    assert_eq!(barrier.stop, "solid ratio reached");
    assert_eq!(barrier.crossings, 0, "boundary nodes inside another particle or behind a wall");
    assert_eq!(barrier.inverted, 0, "inverted elements in converged states");
    let last = barrier.reports.last().unwrap().compaction.clone().unwrap();
    let share = last.stabilisation_energy / last.external_work;
    assert!(share <= 0.01, "the springs took {:.2} % of the wall work", 100.0 * share);
    let grown = check_step_growth(&barrier);

    // d̂ halved: the default is h/20 with h the smallest element size of the particles
    let c = case::parse(&barrier_text, Path::new("jobs/compaction")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let h = model.bodies.iter().map(|b| b.contact_h).fold(f64::INFINITY, f64::min);
    let half = barrier_text.replace("method = \"barrier\"", &format!("method = \"barrier\"\ndhat = {:e}", h / 40.0));
    let halved = run(&half);
    assert_eq!(halved.stop, "solid ratio reached");
    assert_eq!(halved.crossings + halved.inverted, 0);
    let grown = grown + check_step_growth(&halved);
    // room to grow: the job's steps reach its `dt_max` before the particles load each other,
    // so the rule is also checked with ten times that (steps of 11–64 iterations then grow)
    let roomy_text = barrier_text.replacen("dt_max = 0.05\n", "dt_max = 0.5\n", 1);
    assert!(roomy_text.contains("dt_max = 0.5\n"), "the job's [time] changed");
    let roomy = run(&roomy_text);
    assert_eq!(roomy.stop, "solid ratio reached");
    assert_eq!(roomy.crossings + roomy.inverted, 0);
    let grown = grown + check_step_growth(&roomy);
    assert!(grown > 0, "no step that converged at its size in more than `easy_iterations` grew the next one: the check above saw none");
    // the comparisons on fine steps (module docs)
    let fine = |text: &str| {
        let t = text.replacen("dt = 0.02\n", "dt = 0.01\n", 1).replacen("dt_max = 0.05\n", "dt_max = 0.01\n", 1);
        assert!(t.contains("dt = 0.01\n") && t.contains("dt_max = 0.01\n"), "the job's [time] changed");
        let r = run(&t);
        assert_eq!(r.stop, "solid ratio reached");
        r
    };
    let (penalty, barrier, halved) = (fine(&penalty_text), fine(&barrier_text), fine(&half));
    assert_eq!(barrier.crossings + barrier.inverted + halved.crossings + halved.inverted, 0);
    let (p_pen, p_bar, p_half) = (pressures_at(&penalty.reports, 0.95), pressures_at(&barrier.reports, 0.95), pressures_at(&halved.reports, 0.95));
    let (m_bar, m_half) = (mean_pressures(&barrier.reports, 0.93, 0.95), mean_pressures(&halved.reports, 0.93, 0.95));

    eprintln!("pressures at solid ratio 0.95 (left, right, bottom, top; MPa), Δt = 0.01 s:");
    eprintln!("  penalty          {p_pen:?} ({} steps)", penalty.reports.len());
    eprintln!("  barrier          {p_bar:?} ({} steps, springs {:.3} % of the work)", barrier.reports.len(), 100.0 * share);
    eprintln!("  barrier, d̂ / 2   {p_half:?} ({} steps)", halved.reports.len());
    eprintln!("mean pressures over 0.93–0.95: d̂ {m_bar:?}, d̂ / 2 {m_half:?}");
    for i in 0..4 {
        assert!((p_bar[i] / p_pen[i] - 1.0).abs() < 0.03, "wall {i}: barrier {} against penalty {} MPa", p_bar[i], p_pen[i]);
        assert!((m_half[i] / m_bar[i] - 1.0).abs() < 0.01, "wall {i}: mean over 0.93–0.95 with d̂/2 {} against d̂ {} MPa", m_half[i], m_bar[i]);
    }
}

/// Tied (cohering) discs with the barrier, the same 2 × 2 biaxial job: a node that comes
/// within d̂ of another disc is tied to it at the end of the step, and the ties hold from then
/// on. The penalty method does not complete this job (it fails at the first ties), so the
/// checks are the barrier's own: the target is reached with every converged state admissible
/// (the tied pairs, which leave the barrier, are out of the crossing count: their nodes sit
/// on the other disc's boundary), ties are made, every tie's gap stays below 1e-3 h over the
/// run (the multipliers' updates close it to 1e-10 h unless they stall, when a tie stays a
/// penalty of 100 E), and the springs take at most 1 % of the wall work.
#[test]
fn biaxial_discs_tied_with_the_barrier() {
    let text = std::fs::read_to_string(JOB).unwrap().replace("method = \"penalty\"", "method = \"barrier\"").replace("contact = \"sliding\"", "contact = \"cohering\"");
    assert!(text.contains("contact = \"cohering\""));
    let c = case::parse(&text, Path::new("jobs/compaction")).unwrap();
    let h = Model::from_case(&c).unwrap().bodies.iter().map(|b| b.contact_h).fold(f64::INFINITY, f64::min);
    let tied = run(&text);
    assert_eq!(tied.stop, "solid ratio reached");
    assert_eq!(tied.crossings, 0, "boundary nodes inside another particle or behind a wall");
    assert_eq!(tied.inverted, 0, "inverted elements in converged states");
    let last = tied.reports.last().unwrap().compaction.clone().unwrap();
    let share = last.stabilisation_energy / last.external_work;
    eprintln!(
        "tied discs: {} ties, largest tie gap {:.3e} h, springs {:.3} % of the work, pressures at 0.95 {:?} MPa ({} steps)",
        tied.ties,
        tied.tie_gap / h,
        100.0 * share,
        pressures_at(&tied.reports, 0.95),
        tied.reports.len()
    );
    assert!(tied.ties >= 8, "only {} ties were made", tied.ties);
    assert!(tied.tie_gap <= 1e-3 * h, "a tie opened by {:.3e} h", tied.tie_gap / h);
    assert!(share <= 0.01, "the springs took {:.2} % of the wall work", 100.0 * share);
}

/// A loose frictional packing with the defaults: robustness case 03 (16 random Voronoi
/// polygons, μ = 0.2, compacted biaxially from 0.75 to 0.95). Its walls load nothing until
/// about 0.92, so the forces up to there are round-off sized; measured against themselves
/// (before the reference force had a floor, `LOAD_FLOOR` in src/solver/barrier.rs) a polygon
/// sliding under 5e-8 N of out-of-balance force was never in equilibrium and the steps were
/// cut to 2e-5 s. With `dt_min` raised to 1e-3 s that would fail the run. Checked: the target
/// reached with no crossing or inverted element in any converged state, and the springs off
/// by default (their stiffness on the tangent only), so no work went into them at all.
#[test]
fn a_loose_frictional_packing_compacts_without_springs() {
    let text = std::fs::read_to_string("jobs/robustness/03_voronoi_polygons_16_biaxial_mu02.toml").unwrap();
    let text = text.replacen("dt_min = 1e-05\n", "dt_min = 1e-3\n", 1);
    assert!(text.contains("dt_min = 1e-3\n") && text.contains("friction = 0.2"), "the case changed");
    let r = run(&text);
    assert_eq!(r.stop, "solid ratio reached");
    assert_eq!(r.crossings, 0, "boundary nodes inside another particle or behind a wall");
    assert_eq!(r.inverted, 0, "inverted elements in converged states");
    let last = r.reports.last().unwrap().compaction.clone().unwrap();
    assert!(last.solid_ratio >= 0.95 - 1e-9, "{}", last.solid_ratio);
    assert_eq!(last.stabilisation_energy, 0.0, "no springs in the residual by default");
    assert!(last.external_work > 0.0);
    eprintln!("case 03: {} steps, {} Newton iterations, pressures at 0.95 {:?} MPa", r.reports.len(), r.reports.iter().map(|s| s.newton_iterations).sum::<usize>(), pressures_at(&r.reports, 0.95));
}

/// The barrier's tangent is symmetric whatever the kind of contact (its barrier, lagged
/// friction and ties are potentials, whose Hessians the conformance battery checks against
/// finite differences), and so are the J2 and elastic particles' (their updates are
/// variational, `tests/material_conformance.rs` check (d)): the symmetric factorisation is
/// chosen for the barrier with either material. The penalty method keeps LU with friction or
/// ties, and with J2 particles whatever the kind (see `model::symmetric_tangent`).
#[test]
fn the_barrier_takes_the_symmetric_factorisation() {
    let j2 = std::fs::read_to_string(JOB).unwrap();
    assert!(j2.contains("model = \"j2\""));
    let elastic = j2.replace("model = \"j2\"", "model = \"elastic\"").replace("hardening = { preset = \"aluminium_250c\" }\n", "");
    assert!(elastic.contains("model = \"elastic\"") && !elastic.contains("preset"));
    for base in [&j2, &elastic] {
        for (kind, extra) in [("sliding", ""), ("rubbing", "\nfriction = 0.2"), ("cohering", "")] {
            for method in ["barrier", "penalty"] {
                let text = base.replace("method = \"penalty\"", &format!("method = \"{method}\"")).replace("contact = \"sliding\"", &format!("contact = \"{kind}\"{extra}"));
                let c = case::parse(&text, Path::new("jobs/compaction")).unwrap();
                let model = Model::from_case(&c).unwrap();
                let want = method == "barrier" || (kind == "sliding" && !base.contains("j2"));
                assert_eq!(model.symmetric_tangent(), want, "{method}, {kind}, {}", if base.contains("j2") { "J2" } else { "elastic" });
            }
        }
    }
}

/// Bad input: the barrier has no tied walls yet, its d̂ and integration only go with it, and it
/// has no master normal — each a clear error naming the key (and, for a bad choice, the value).
#[test]
fn barrier_keys_are_checked() {
    let base = std::fs::read_to_string(JOB).unwrap();
    let barrier = base.replace("method = \"penalty\"", "method = \"barrier\"");
    let cases = [
        (barrier.replacen("[[walls]]", "[[walls]]\ncontact = \"cohering\"", 1), "walls[0].contact"),
        (base.replace("method = \"penalty\"", "method = \"penalty\"\ndhat = 0.1"), "contact.dhat"),
        (barrier.replace("method = \"barrier\"", "method = \"barrier\"\ndhat = -1.0"), "contact.dhat"),
        (barrier.replace("method = \"barrier\"", "method = \"barrier\"\nnormal = \"smoothed\""), "contact.normal"),
        (base.replace("method = \"penalty\"", "method = \"penalty\"\nintegration = \"nodes\""), "contact.integration"),
        (barrier.replace("method = \"barrier\"", "method = \"barrier\"\nintegration = \"gauss\""), "\"gauss\""),
    ];
    for (text, key) in cases {
        let err = case::parse(&text, Path::new("jobs/compaction")).err().unwrap_or_else(|| panic!("accepted a bad {key}")).to_string();
        assert!(err.contains(key), "{err}");
    }
}

/// `integration` picks where the barrier between particles is evaluated: by default four Gauss
/// points an edge beside node terms of reach d̂/10, with "nodes" the nodes alone at full reach
/// (IPC's sum); the patch test of `tests/contact_friction.rs` checks what the default does.
#[test]
fn barrier_integration_key_is_wired() {
    use mpfem::contact::barrier_problem::{EDGE_POINTS, NODE_REACH};
    let base = std::fs::read_to_string(JOB).unwrap();
    let barrier = base.replace("method = \"penalty\"", "method = \"barrier\"");
    for (extra, points, reach) in [("", EDGE_POINTS, NODE_REACH), ("\nintegration = \"edges\"", EDGE_POINTS, NODE_REACH), ("\nintegration = \"nodes\"", 0, 1.0)] {
        let text = barrier.replace("method = \"barrier\"", &format!("method = \"barrier\"{extra}"));
        let c = case::parse(&text, Path::new("jobs/compaction")).unwrap();
        let b = Model::from_case(&c).unwrap().barrier_contact().expect("a barrier");
        assert_eq!((b.quad_points, b.node_reach), (points, reach), "integration key {extra:?}");
    }
}

/// Particles that touch at the start (the contact patch test's two blocks) cannot start with the
/// barrier: a clear error before the first step, not a failure after twenty cut-backs.
#[test]
fn touching_particles_are_a_clear_error() {
    let text = std::fs::read_to_string("jobs/verification/contact_patch.toml").unwrap();
    assert!(text.contains("method = \"augmented_lagrangian\"\n"));
    let text = text.replace("method = \"augmented_lagrangian\"\n", "method = \"barrier\"\n").replace("penetration_tol = 1e-6\n", "");
    let c = case::parse(&text, Path::new("jobs/verification")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let err = Simulation::new(model, c.time.clone(), c.solver.clone()).err().expect("touching particles accepted").to_string();
    assert!(err.contains("apart") && err.contains("touches edge"), "{err}");
}
