//! Compaction runs: particles between rigid walls, node-to-wall and two-pass node-to-segment
//! contact.
//!
//! - one elasto-plastic disc squeezed between a left and a right wall: the two walls carry the
//!   same force (equilibrium of the disc, 1e-6 relative), the pressure rises monotonically once
//!   the disc touches, and the run stops at the target solid ratio;
//! - the same disc stopped by `[stop] wall_pressure` at the first step that reaches it;
//! - penalty and augmented Lagrangian agree on the 2 × 2 lateral job.
//!
//! The six 2 × 2 jobs themselves (symmetry, stabilisation work, target solid ratio) are run in
//! `tests/compaction_jobs.rs`.

use mpfem::case;
use mpfem::model::Model;
use mpfem::solver::{Simulation, StepReport};

fn run(text: &str) -> (Vec<StepReport>, mpfem::solver::RunSummary) {
    let c = case::parse(text, std::path::Path::new("jobs/compaction")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    let mut reports = Vec::new();
    let summary = sim.run(&mut |_, r| reports.push(r.clone())).unwrap();
    (reports, summary)
}

/// The lateral 2 × 2 job with one disc, to solid ratio 0.85.
fn single_disc_job() -> String {
    std::fs::read_to_string("jobs/compaction/discs_2x2_lateral.toml")
        .unwrap()
        .replace("nx = 2", "nx = 1")
        .replace("ny = 2", "ny = 1")
        .replace("solid_ratio = 0.95", "solid_ratio = 0.85")
}

#[test]
fn single_disc_between_two_walls() {
    let text = single_disc_job();
    let (reports, summary) = run(&text);
    assert_eq!(summary.stop_reason, "solid ratio reached");
    let last = reports.last().unwrap().compaction.clone().unwrap();
    assert!(last.solid_ratio >= 0.85);
    let (fl, fr) = (last.force[0], last.force[1]);
    assert!(fl > 0.0 && ((fl - fr) / fl).abs() < 1e-6, "left {fl} vs right {fr}");
    // the bottom and top walls are never touched before 0.85 in lateral compaction of one disc
    let touched: Vec<f64> = reports.iter().map(|r| r.compaction.as_ref().unwrap().pressure[0]).filter(|p| *p > 0.0).collect();
    assert!(touched.len() > 3);
    assert!(touched.windows(2).all(|w| w[1] >= w[0] * 0.999), "pressure must rise: {touched:?}");
}

/// `[stop] wall_pressure`: the run ends at the first step whose mean pressing-wall pressure
/// reaches the value, with stop reason "wall pressure reached". The reference is the same run
/// without the key: the two runs are the same up to that step (bit for bit: nothing else
/// differs), so the stop must come at exactly the first report of the reference run at or
/// above the value, chosen as the pressure halfway through the loaded steps.
#[test]
fn a_wall_pressure_stops_the_run_at_the_first_step_that_reaches_it() {
    let text = single_disc_job();
    let (reference, _) = run(&text);
    // the left and right walls press in lateral compaction
    let mean = |r: &StepReport| {
        let c = r.compaction.as_ref().unwrap();
        0.5 * (c.pressure[0] + c.pressure[1])
    };
    let loaded: Vec<usize> = (0..reference.len()).filter(|&i| mean(&reference[i]) > 0.0).collect();
    assert!(loaded.len() > 4, "{} loaded steps", loaded.len());
    let target = mean(&reference[loaded[loaded.len() / 2]]);
    let first = reference.iter().position(|r| mean(r) >= target).unwrap();
    assert!(first + 1 < reference.len());
    let stopped = text.replace("solid_ratio = 0.85", &format!("solid_ratio = 0.85\nwall_pressure = {target:e}"));
    assert_ne!(stopped, text);
    let (reports, summary) = run(&stopped);
    assert_eq!(summary.stop_reason, "wall pressure reached");
    assert_eq!(reports.len(), first + 1, "stopped after {} steps, expected {}", reports.len(), first + 1);
    assert!(mean(reports.last().unwrap()) >= target);
    assert!(reports[..first].iter().all(|r| mean(r) < target));
}

/// Penalty and augmented Lagrangian give the same wall pressure on the 2 × 2 job, within 2 %
/// at solid ratio 0.94 (the contact issue's criterion for its enforcement methods), and the
/// augmented Lagrangian penetrates less. Lagrange multipliers are not compared here: on this
/// job they stop near solid ratio 0.75 (see `contact::problem::Multipliers`); they are verified
/// against Hertz on rigid walls (`tests/hertz.rs`).
#[test]
fn penalty_and_augmented_lagrangian_agree_on_the_2x2_job() {
    let base = std::fs::read_to_string("jobs/compaction/discs_2x2_lateral.toml").unwrap();
    let al = base.replace("method = \"penalty\"", "method = \"augmented_lagrangian\"\npenetration_tol = 1e-4");
    let at = |reports: &[StepReport], phi: f64| -> (f64, f64) {
        let c: Vec<_> = reports.iter().map(|r| r.compaction.clone().unwrap()).collect();
        let k = c.iter().position(|x| x.solid_ratio >= phi).expect("reaches the solid ratio");
        let (a, b) = (&c[k - 1], &c[k]);
        let w = (phi - a.solid_ratio) / (b.solid_ratio - a.solid_ratio);
        (a.pressure[0] + w * (b.pressure[0] - a.pressure[0]), c[..=k].iter().map(|x| x.max_penetration).fold(0.0, f64::max))
    };
    let (rp, _) = run(&base);
    let (ra, _) = run(&al);
    let (pp, pen_p) = at(&rp, 0.94);
    let (pa, pen_a) = at(&ra, 0.94);
    eprintln!("p_left at solid ratio 0.94: penalty {pp:.3}, augmented Lagrangian {pa:.3} MPa; penetration {pen_p:.3e}, {pen_a:.3e} mm");
    assert!(pp > 50.0, "loaded: {pp}");
    assert!(((pp - pa) / pp).abs() < 0.02, "penalty {pp} vs augmented Lagrangian {pa} MPa");
    assert!(pen_a < pen_p, "AL penetration {pen_a} should be below penalty {pen_p}");
}

/// Tied (cohering) particles pushed by walls at 10 mm/s: a node passes the touch band of the
/// other particle within one step, and must be tied then, not left free (before the fix the
/// discs passed through each other and the walls carried nothing from step 5 on). Every step
/// after the first contact carries wall load, and no node sinks deeper than 1 % of the 10 mm
/// element size.
#[test]
fn cohering_discs_stay_in_contact_when_pushed_fast() {
    let text = std::fs::read_to_string("tests/data/discs_coarse.toml").unwrap().replace("contact = \"sliding\"", "contact = \"cohering\"");
    let (reports, summary) = run(&text);
    assert_eq!(summary.stop_reason, "solid ratio reached");
    let first = reports.iter().position(|r| r.compaction.as_ref().is_some_and(|c| c.force[0] > 0.0)).expect("the walls touch");
    for r in &reports[first..] {
        let c = r.compaction.as_ref().unwrap();
        assert!(c.force[0] > 0.0 && c.active_contacts > 0, "step {}: wall force {} with {} contacts", r.step, c.force[0], c.active_contacts);
        assert!(c.max_penetration < 0.1, "step {}: penetration {} mm", r.step, c.max_penetration);
    }
    let last = reports.last().unwrap().compaction.as_ref().unwrap();
    assert!(last.pressure[0] > 10.0, "left wall at the end: {} MPa", last.pressure[0]);
}

/// A wall may move by a `travel` times an amplitude, as a prescribed displacement does
/// (`loading`): with the ramp amplitude over the run, `travel = v · t_end` is the wall at
/// constant speed v, so the single-disc lateral run with its walls given either way has the same
/// history to round-off (wall pressures within 1e-9 relative; the positions differ by the
/// rounding of v·t against travel·t/t_end). A table amplitude that holds the walls after half
/// the travel stops the compaction there: the solid ratio stays put while the walls hold.
#[test]
fn walls_move_by_a_travel_times_an_amplitude() {
    let base = std::fs::read_to_string("jobs/compaction/discs_2x2_lateral.toml")
        .unwrap()
        .replace("nx = 2", "nx = 1")
        .replace("ny = 2", "ny = 1")
        .replace("solid_ratio = 0.95", "solid_ratio = 0.85");
    let c = case::parse(&base, std::path::Path::new("jobs/compaction")).unwrap();
    let t_end = c.time.end;
    let travel = format!("travel = {}", 10.0 * t_end);
    let ramp = base.replace("velocity = 10.0", &travel);
    assert_ne!(ramp, base, "the job's walls move at 10 mm/s");
    let (a, sa) = run(&base);
    let (b, sb) = run(&ramp);
    assert_eq!((sa.steps, sa.stop_reason.as_str()), (sb.steps, sb.stop_reason.as_str()));
    for (ra, rb) in a.iter().zip(&b) {
        let (ca, cb) = (ra.compaction.as_ref().unwrap(), rb.compaction.as_ref().unwrap());
        assert!((ca.solid_ratio - cb.solid_ratio).abs() < 1e-12, "step {}: {} vs {}", ra.step, ca.solid_ratio, cb.solid_ratio);
        for k in 0..4 {
            let scale = ca.pressure[k].abs().max(1.0);
            assert!((ca.pressure[k] - cb.pressure[k]).abs() < 1e-9 * scale, "step {} wall {k}: {} vs {}", ra.step, ca.pressure[k], cb.pressure[k]);
        }
    }
    // press by 5 % of the die's width in the first quarter of the run, then hold
    let hold = base.replace("velocity = 10.0", &format!("travel = {}\namplitude = [[0.0, 0.0], [{}, 1.0]]", 0.05 * 100.0 / 2.0, 0.25 * t_end));
    let model = Model::from_case(&case::parse(&hold, std::path::Path::new("jobs/compaction")).unwrap()).unwrap();
    let l = &model.loading;
    assert_eq!(l.wall_position(0, 0.25 * t_end), l.wall_position(0, t_end));
    let (h, _) = run(&hold);
    let late: Vec<f64> = h.iter().filter(|r| r.time > 0.3 * t_end).map(|r| r.compaction.as_ref().unwrap().solid_ratio).collect();
    assert!(late.len() > 2, "steps after the walls stop: {}", late.len());
    assert!(late.windows(2).all(|w| (w[1] - w[0]).abs() < 1e-12), "the solid ratio moves while the walls hold: {late:?}");
}

/// Bad wall motions are refused, naming the key and what was expected.
#[test]
fn wall_travel_errors_name_the_key() {
    let base = std::fs::read_to_string("jobs/compaction/discs_2x2_lateral.toml").unwrap();
    let both = base.replacen("velocity = 10.0", "velocity = 10.0\ntravel = 5.0", 1);
    let e = case::parse(&both, std::path::Path::new("jobs/compaction")).unwrap_err().to_string();
    assert!(e.starts_with("walls[0].travel: given with velocity = 10"), "{e}");
    let amp = base.replacen("velocity = 10.0", "velocity = 10.0\namplitude = \"constant\"", 1);
    let e = case::parse(&amp, std::path::Path::new("jobs/compaction")).unwrap_err().to_string();
    assert!(e.starts_with("walls[0].amplitude: value \"constant\": an amplitude shapes a wall's travel"), "{e}");
}
