//! A simulation on the owned + ghost parts of a distributed model (`Simulation::new_part`), on
//! 1, 2, 3 and 4 real MPI processes (`mpirun` on its own test binary, `tests/common::on_ranks`):
//! a 3 × 3 grid of elastic aluminium discs with the
//! frictionless barrier contact (the default; the grid leaves saddles of its symmetric path,
//! which the parts take alike), compacted from solid ratio
//! 0.76 to 0.80 between two moving walls. Each process holds its own discs and its ghosts only,
//! assembles their elements and its pairs into its rows, PETSc (MUMPS) solves over the
//! processes, and every norm, dot product and wall force is reduced.
//!
//! The same with Coulomb friction 0.2 between the discs, to 1e-7 (see [`FRICTION_TOL`]).
//!
//! The same cohering (`contact = "cohering"`: discs that touch are tied from then on, 36 tied
//! nodes at the end), with every part grown again twice mid-run, after the ties are made
//! (`Simulation::regrown`: its ties go to the new numbering of its ghosts' edges): the number of
//! ties and their largest gap are the same just before and after, and the history equals the
//! whole serial run's to 1e-8.
//!
//! Reference: the same case run whole and serially (faer) on every process. Checked at every
//! step: the same step sizes, and the wall forces, pressures and the solid ratio equal to
//! 1e-8 relative of the largest value of their column (the tolerance for the
//! distributed direct solver; the Newton residual tolerance of 1e-11 keeps the iterates'
//! differences far below it). A part made without its ghosts (boxes that must overlap) stops
//! its run at its first step, without cut-backs, naming a body that came within the contact
//! reach and is not a ghost. (That no process holds the whole mesh is `tests/mpi_ghosts.rs`'s
//! check, on a 4 × 4 grid: in this 3 × 3 one every disc is near the middle one.)
//!
//! Why this case: it is one whose path round-off does not change. A 4 × 4 grid of the same discs
//! snaps at its fifth step (84 Newton iterations) into one of several equilibria, and which one
//! depends on round-off: faer's and MUMPS's factorisations of the whole model already end there
//! 3.7e-6 apart in solid ratio and finish in 7 and 9 steps (measured); friction and J2 make the
//! 3 × 3 grid as sensitive. The parts follow MUMPS's whole-model path there to the last digit.
#![cfg(feature = "petsc")]

mod common;

use mpfem::model::Model;
use mpfem::parallel::part::RankPart;
use mpfem::solver::{Simulation, StepReport};

/// The elastic, frictionless 3 × 3 discs of the MPI tests, with the barrier contact and the
/// default solver (`tests/data/mpi_discs_3x3_pcg.toml` less its penalty method and PCG).
fn case_text() -> String {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mpi_discs_3x3_pcg.toml")).expect("the case");
    let case = text.replace("method = \"penalty\"\n", "").replace("linear = \"pcg\"\npreconditioner = \"schwarz\"\npcg_tol = 1e-12\n", "");
    assert!(!case.contains("penalty") && !case.contains("pcg"), "the case's solver lines changed:\n{case}");
    case
}

/// The case of `text` and its whole model.
fn case_and_model(text: &str) -> (mpfem::case::Case, Model) {
    let case = mpfem::case::parse(text, std::path::Path::new(".")).expect("case");
    let whole = Model::from_case(&case).expect("model");
    (case, whole)
}

/// This process's part of `whole` as a simulation of `case`: the discs partitioned by METIS,
/// the ghosts within a quarter of a disc's size (the grid's neighbours).
fn part_of(whole: &Model, case: &mpfem::case::Case, comm: &std::sync::Arc<dyn mpfem::parallel::Collective>) -> Simulation {
    let part = RankPart::for_run(whole, &whole.x0, 0.25 * 100.0 / 3.0, comm.clone()).expect("part");
    Simulation::new_part(part, case.time.clone(), case.solver.clone()).expect("part simulation")
}

/// The compared columns of a report: solid ratio, wall pressures and forces.
fn row(r: &StepReport) -> Vec<f64> {
    let c = r.compaction.as_ref().expect("a compaction");
    let mut v = vec![r.time, c.solid_ratio];
    v.extend_from_slice(&c.pressure);
    v.extend_from_slice(&c.force);
    v
}

/// The largest difference of the parts' rows from the whole run's, relative to the largest
/// |value| of each column; asserts the same number of steps.
fn worst_difference(parts: &[Vec<f64>], serial: &[Vec<f64>], rank: usize) -> f64 {
    assert_eq!(parts.len(), serial.len(), "rank {rank}: {} steps on the parts, {} whole", parts.len(), serial.len());
    let mut worst = 0.0f64;
    for c in 0..serial[0].len() {
        let scale = serial.iter().map(|r| r[c].abs()).fold(0.0, f64::max).max(1e-300);
        for (a, b) in parts.iter().zip(serial) {
            worst = worst.max((a[c] - b[c]).abs() / scale);
        }
    }
    worst
}

fn run(sim: &mut Simulation) -> Vec<Vec<f64>> {
    let mut rows = Vec::new();
    sim.run(&mut |_, r| rows.push(row(r))).expect("the run completes");
    rows
}

fn rank_work(comm: std::sync::Arc<dyn mpfem::parallel::Collective>) -> String {
    let _petsc = mpfem::linalg::petsc::start("").expect("PETSc");
    let case = case_text();
    let friction = case.replace("[contact]\ncontact = \"sliding\"\n", "[contact]\ncontact = \"rubbing\"\nfriction = 0.2\n");
    assert_ne!(friction, case);
    let frictionless = compare(comm.clone(), &case, FRICTIONLESS_TOL, true);
    let rubbing = compare(comm.clone(), &friction, FRICTION_TOL, false);
    let cohering = case.replace("contact = \"sliding\"", "contact = \"cohering\"");
    assert_ne!(cohering, case);
    let tied = cohering_grown_again(comm.clone(), &cohering);
    let remeshed = cohering_remeshed(comm.clone(), &cohering);
    let migrated = repartitioned(comm.clone(), &cohering);
    let plastic = friction
        .replace("model = \"elastic\"\n", "model = \"j2\"\nhardening = { preset = \"aluminium_250c\" }\ndensity = 0.01\n")
        .replace("[time]\n", "[time]\nintegrator = \"hht\"\n");
    assert!(plastic.contains("j2") && plastic.contains("hht"), "the J2 dynamic case");
    let moved_whole = state_moves_whole(comm.clone(), &plastic);
    let rebalanced = remeshed_rebalanced(comm.clone(), &case);
    held_particle_left_out(comm, &case);
    format!("{frictionless}; with friction 0.2: {rubbing}; cohering, grown again: {tied}; cohering, re-meshed: {remeshed}; repartitioned, cohering: {migrated}; J2 with friction and inertia: {moved_whole}; re-meshed, repartitioned: {rebalanced}")
}

/// A particle that holds a probe is not re-meshed (its node numbers would lose their meaning):
/// asked to re-mesh it and another, the parts re-mesh the other only — every process alike,
/// none waiting for another — as the whole model does, and the run goes on.
fn held_particle_left_out(comm: std::sync::Arc<dyn mpfem::parallel::Collective>, text: &str) {
    let rank = comm.rank();
    let text = text.replace("[output]\n", "[output]\nprobes = [{ name = \"centre\", body = \"g0_p4\", node = 0 }]\n");
    assert!(text.contains("probes"), "the case has no [output] table");
    let (case, whole) = case_and_model(&text);
    let mut serial = Simulation::new(whole.clone(), case.time.clone(), case.solver.clone()).expect("serial simulation");
    let mut sim = part_of(&whole, &case, &comm);
    for s in [&mut serial, &mut sim] {
        for _ in 0..2 {
            s.advance(case.time.dt).expect("a step");
        }
        assert_eq!(s.remesh_bodies(&[4, 0]), 1, "rank {rank}: the disc with the probe re-meshed, or the other not");
        s.advance(case.time.dt).expect("the step after the re-mesh");
    }
}

/// The cohering run on parts with every disc re-meshed after step 4 (`Simulation::remesh_bodies`,
/// each by its owner, then re-equilibrated) against the whole serial run re-meshed alike: the
/// ties made by then all go over to the new meshes (their nodes are held where they are), on
/// the parts as serially, and both runs reach the target. Until the re-mesh the histories agree
/// to [`FRICTIONLESS_TOL`]; after it to [`REMESHED_TOL`] only: where the discs are tied the
/// re-mesher's choices (which boundary points a coarsened stretch keeps) flip with the 1e-9 mm
/// by which MUMPS's and faer's states differ, so that a disc may get 54 elements on the parts
/// and 48 serially (measured on one process: the wall forces of the two runs then end 0.06 %
/// apart). The frictionless discs of `tests/petsc_parts_output.rs` get the same meshes.
fn cohering_remeshed(comm: std::sync::Arc<dyn mpfem::parallel::Collective>, text: &str) -> String {
    use std::ops::ControlFlow;
    let (rank, size) = (comm.rank(), comm.size());
    let (case, whole) = case_and_model(text);
    let all: Vec<usize> = (0..whole.bodies.len()).collect();
    let run_remeshed = |sim: &mut Simulation| -> (Vec<Vec<f64>>, usize, usize, usize) {
        let mut rows = Vec::new();
        sim.run_controlled(&mut |_, r| {
            rows.push(row(r));
            if r.step == 4 { ControlFlow::Break("re-mesh".into()) } else { ControlFlow::Continue(()) }
        })
        .expect("the run goes on");
        let before = sim.barrier_ties().expect("the barrier").0;
        let done = sim.remesh_bodies(&all);
        let after = sim.barrier_ties().expect("the barrier").0;
        rows.extend(run(sim));
        (rows, before, after, done)
    };
    let (serial, s_before, s_after, s_done) = run_remeshed(&mut Simulation::new(whole.clone(), case.time.clone(), case.solver.clone()).expect("serial simulation"));
    let mut sim = part_of(&whole, &case, &comm);
    let (rows, before, after, done) = run_remeshed(&mut sim);
    assert_eq!((s_done, done), (all.len(), all.len()), "rank {rank}: every disc re-meshed, serially and on the parts");
    assert!(before > 0, "rank {rank}: no ties at step 4: the case no longer tests them");
    assert_eq!((before, after), (s_before, s_after), "rank {rank}: the ties before and after the re-mesh, on the parts and serially");
    assert_eq!(before, after, "rank {rank}: ties lost in the re-mesh");
    let until = worst_difference(&rows[..4], &serial[..4], rank);
    assert!(until <= FRICTIONLESS_TOL, "rank {rank} of {size}: the cohering parts differ from the whole run before the re-mesh by {until:e}");
    // (the last row: the solid ratio, the pressures and forces of the moving walls; the other
    // walls carry round-off)
    let (a, b) = (rows.last().expect("a row"), serial.last().expect("a row"));
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let after_remesh = [1, 2, 3, 6, 7].iter().map(|&c| (a[c] - b[c]).abs() / b[c].abs().max(1e-12 * scale)).fold(0.0, f64::max);
    assert!(after_remesh <= REMESHED_TOL, "rank {rank} of {size}: the cohering parts re-meshed end {after_remesh:e} from the whole run");
    format!("{after} ties kept, before the re-mesh {until:.1e}, at the end {after_remesh:.1e}")
}

/// The cohering run on parts whose discs all change owner after step 4 and again after step 6
/// (`Simulation::migrated`: every owner moves up one rank, each disc sent whole to its new owner
/// with its state and ties) against the whole serial run: the ties are the same before and
/// after, every process owns what it was given, and the history equals the whole run's to
/// [`FRICTIONLESS_TOL`] (the state goes over exactly, [`state_moves_whole`]; only the
/// distributed solver's row order changes).
fn repartitioned(comm: std::sync::Arc<dyn mpfem::parallel::Collective>, text: &str) -> String {
    use std::ops::ControlFlow;
    let (rank, size) = (comm.rank(), comm.size());
    let (case, whole) = case_and_model(text);
    let serial = run(&mut Simulation::new(whole.clone(), case.time.clone(), case.solver.clone()).expect("serial simulation"));
    let mut sim = part_of(&whole, &case, &comm);
    let mut rows = Vec::new();
    let mut ties = Vec::new();
    for stop in [4, 6, usize::MAX] {
        sim.run_controlled(&mut |_, r| {
            rows.push(row(r));
            if r.step == stop { ControlFlow::Break("repartition".into()) } else { ControlFlow::Continue(()) }
        })
        .expect("the run goes on");
        if stop == usize::MAX {
            break;
        }
        let before = sim.barrier_ties().expect("the barrier");
        let owner: Vec<usize> = sim.owners().expect("a part").1.iter().map(|&o| (o + 1) % size).collect();
        let repartitions = sim.partition().repartitions;
        sim = sim.migrated(&owner).expect("the discs move to their new owners");
        let (own, now) = sim.owners().expect("a part");
        assert_eq!(now, &owner[..], "rank {rank}: the owners after the repartition at step {stop}");
        assert_eq!(own, (0..owner.len()).filter(|&b| owner[b] == rank).collect::<Vec<_>>(), "rank {rank}: its own discs after the repartition at step {stop}");
        assert_eq!(sim.partition().repartitions, repartitions + 1, "rank {rank}: a repartition counted");
        let after = sim.barrier_ties().expect("the barrier");
        assert_eq!(before, after, "rank {rank}: the ties (count, largest gap) repartitioned at step {stop}");
        ties.push(after.0);
    }
    assert!(ties.iter().all(|&n| n > 0), "rank {rank}: no ties when the discs moved ({ties:?}): the case no longer tests it");
    // owners that leave a process without a disc are refused, on every process alike
    if size > 1 {
        let err = sim.migrated(&vec![0; whole.bodies.len()]).err().expect("owners leaving processes idle are refused");
        assert!(err.contains("none of the"), "rank {rank}: {err}");
    }
    let worst = worst_difference(&rows, &serial, rank);
    assert!(worst <= FRICTIONLESS_TOL, "rank {rank} of {size}: the parts repartitioned differ from the whole run by {worst:e}");
    format!("ties {ties:?} when the discs moved, largest difference {worst:.1e}")
}

/// J2 discs with friction 0.2 and inertia (HHT-α) on parts, every disc moved to the next rank
/// after step 3 (`Simulation::migrated`): the whole state gathered on rank 0 after the move —
/// displacements, u_{n−1}, the dynamics' u, v, a and g, every element's stresses, plastic state,
/// pressure, Θ, enhanced modes, multiplier and j₀, the bodies' reference areas and re-mesh
/// baselines — is bit for bit the state gathered before it, and the run goes on. (This case's
/// path is decided by round-off from its third step — the serial and the parts runs part
/// there, migrated or not — so the state is compared, not the history.)
fn state_moves_whole(comm: std::sync::Arc<dyn mpfem::parallel::Collective>, text: &str) -> String {
    use std::ops::ControlFlow;
    let (rank, size) = (comm.rank(), comm.size());
    let (case, whole) = case_and_model(text);
    let mut sim = part_of(&whole, &case, &comm);
    sim.run_controlled(&mut |_, r| if r.step == 3 { ControlFlow::Break("repartition".into()) } else { ControlFlow::Continue(()) }).expect("three steps");
    let describe = |g: Option<mpfem::solver::Gathered>| {
        g.map(|g| {
            let s = g.state;
            let plastic = s.sol.fields.states.iter().flatten().filter(|q| q.eps_p > 0.0).count();
            let text = format!("{:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}", s.sol.u, s.u_prev, s.dynamics, s.sol.fields, s.sol.lambda, s.sol.j0, s.scalars.run.area0_body, s.scalars.run.remesh_baseline, s.sol.time);
            (text, plastic, s.dynamics.is_some())
        })
    };
    let before = describe(sim.gather(true));
    let owner: Vec<usize> = sim.owners().expect("a part").1.iter().map(|&o| (o + 1) % size).collect();
    let mut sim = sim.migrated(&owner).expect("the discs move to their new owners");
    let after = describe(sim.gather(true));
    let said = match (before, after) {
        (Some((b, plastic, dynamic)), Some((a, ..))) => {
            assert!(plastic > 0 && dynamic, "rank 0: {plastic} yielded Gauss points, dynamics {dynamic}: the case no longer tests the state");
            assert!(a == b, "rank 0 of {size}: the state gathered after the move differs from the state before it");
            format!("{plastic} yielded Gauss points moved bit for bit")
        }
        (None, None) if rank > 0 => "gathered on rank 0".into(),
        _ => panic!("rank {rank}: gathered on another rank than 0"),
    };
    sim.advance(case.time.dt).expect("a step after the move");
    said
}

/// The discs owned unevenly (rank 0 all but one a process; `RankPart::new`) and every disc
/// re-meshed after step 3 (`Simulation::remesh_bodies`): the model has changed and the
/// imbalance is above `[solver] repartition_imbalance` (1.05), so the parts repartition —
/// METIS on the discs' current boxes and new element counts, the discs that change owner sent
/// whole — to a better balance, and the history equals the whole serial run re-meshed alike to
/// [`FRICTIONLESS_TOL`]. One process has nothing to balance.
fn remeshed_rebalanced(comm: std::sync::Arc<dyn mpfem::parallel::Collective>, text: &str) -> String {
    use std::ops::ControlFlow;
    let (rank, size) = (comm.rank(), comm.size());
    let (case, whole) = case_and_model(text);
    let nb = whole.bodies.len();
    // (process r > 0 owns disc r - 1, rank 0 the rest)
    let first: Vec<usize> = (0..nb).map(|b| if b + 1 < size { b + 1 } else { 0 }).collect();
    let part = RankPart::new(&whole, &whole.x0, &first, 0.25 * 100.0 / 3.0, comm.clone()).expect("part");
    let mut sim = Simulation::new_part(part, case.time.clone(), case.solver.clone()).expect("part simulation");
    let all: Vec<usize> = (0..nb).collect();
    let run_remeshed = |sim: &mut Simulation| -> (Vec<Vec<f64>>, usize) {
        let mut rows = Vec::new();
        sim.run_controlled(&mut |_, r| {
            rows.push(row(r));
            if r.step == 3 { ControlFlow::Break("re-mesh".into()) } else { ControlFlow::Continue(()) }
        })
        .expect("the run goes on");
        let done = sim.remesh_bodies(&all);
        rows.extend(run(sim));
        (rows, done)
    };
    let (serial, s_done) = run_remeshed(&mut Simulation::new(whole.clone(), case.time.clone(), case.solver.clone()).expect("serial simulation"));
    let (rows, done) = run_remeshed(&mut sim);
    assert_eq!((s_done, done), (nb, nb), "rank {rank}: every disc re-meshed, serially and on the parts");
    let p = sim.partition().clone();
    let owner = sim.owners().expect("a part").1.to_vec();
    let moved = owner.iter().zip(&first).filter(|(a, b)| a != b).count();
    let before = (nb + 1 - size) as f64 * size as f64 / nb as f64;
    if size > 1 {
        assert!(p.repartitions == 1 && moved > 0 && p.moved == moved, "rank {rank} of {size}: not repartitioned after the re-mesh ({p:?}, {moved} discs moved)");
        assert!(p.imbalance < before - 0.1, "rank {rank} of {size}: imbalance {} after the repartition, about {before} before", p.imbalance);
    } else {
        assert_eq!((p.repartitions, moved), (0, 0), "one process repartitioned");
    }
    let worst = worst_difference(&rows, &serial, rank);
    assert!(worst <= FRICTIONLESS_TOL, "rank {rank} of {size}: the parts re-meshed and repartitioned differ from the whole run by {worst:e}");
    format!("{moved} discs moved, imbalance {before:.2} -> {:.3}, largest difference {worst:.1e}", p.imbalance)
}

/// How far the re-meshed cohering runs may end apart (relative): a re-mesh whose choices
/// flipped is another discretisation (see [`cohering_remeshed`]).
const REMESHED_TOL: f64 = 1e-2;

/// The cohering run on parts grown again after steps 4 and 6 (ghosts within the least reach
/// the steps need, then every disc) against the whole serial run, to [`FRICTIONLESS_TOL`].
fn cohering_grown_again(comm: std::sync::Arc<dyn mpfem::parallel::Collective>, text: &str) -> String {
    use std::ops::ControlFlow;
    let (rank, size) = (comm.rank(), comm.size());
    let (case, whole) = case_and_model(text);
    let serial = run(&mut Simulation::new(whole.clone(), case.time.clone(), case.solver.clone()).expect("serial simulation"));
    let reach = 0.25 * 100.0 / 3.0;
    let part = RankPart::for_run(&whole, &whole.x0, reach, comm.clone()).expect("part");
    let mut sim = Simulation::new_part(part, case.time.clone(), case.solver.clone()).expect("part simulation");
    let mut rows = Vec::new();
    let mut ties = Vec::new();
    // (first the least reach the steps need, then one past the grid's far side: on 3 and 4
    // ranks the second brings new ghosts before the old ones, whose edges are numbered anew)
    let least = whole.barrier_contact().expect("the barrier").dhat + 2.0 * whole.whole_facts().h_min;
    for (stop, again) in [(4, least), (6, 40.0), (usize::MAX, 0.0)] {
        sim.run_controlled(&mut |_, r| {
            rows.push(row(r));
            if r.step == stop { ControlFlow::Break("grow the parts again".into()) } else { ControlFlow::Continue(()) }
        })
        .expect("the run goes on");
        if stop == usize::MAX {
            break;
        }
        let before = sim.barrier_ties().expect("the barrier");
        sim = sim.regrown(case.time.clone(), case.solver.clone(), again).expect("the parts grown again");
        let after = sim.barrier_ties().expect("the barrier");
        assert_eq!(before, after, "rank {rank}: the ties (count, largest gap) grown again at step {stop}");
        ties.push(after.0);
    }
    assert!(ties.iter().all(|&n| n > 0), "rank {rank}: no ties when the parts were grown again ({ties:?}): the case no longer tests it");
    let worst = worst_difference(&rows, &serial, rank);
    assert!(worst <= FRICTIONLESS_TOL, "rank {rank} of {size}: the cohering parts grown again differ from the whole run by {worst:e}");
    format!("ties {ties:?} when grown again, largest difference {worst:.1e}")
}

/// The tolerance of the frictionless case: the for the distributed direct solver.
const FRICTIONLESS_TOL: f64 = 1e-8;
/// The tolerance of the case with friction 0.2: its lagged friction amplifies the round-off of
/// the linear solves, so that faer's and MUMPS's factorisations of the *whole* model already
/// end 1.87e-8 apart (relative, `mpfem run` with and without `linear = "petsc"`, measured);
/// the parts on one process end 1.87e-8 from faer as well.
const FRICTION_TOL: f64 = 1e-7;

/// The run of `case` on the parts against the whole serial run, to `tol` relative; with
/// `blind` also a part without ghosts, which must stop. The report's words.
fn compare(comm: std::sync::Arc<dyn mpfem::parallel::Collective>, text: &str, tol: f64, blind: bool) -> String {
    let (rank, size) = (comm.rank(), comm.size());
    let (case, whole) = case_and_model(text);
    let serial = run(&mut Simulation::new(whole.clone(), case.time.clone(), case.solver.clone()).expect("serial simulation"));
    let mut owner: Vec<f64> = mpfem::distribute::partition_particles(&whole, size).iter().map(|&o| o as f64).collect();
    comm.broadcast(&mut owner);
    let owner: Vec<usize> = owner.iter().map(|&o| o as usize).collect();
    // ghosts: every disc within a quarter of a disc's size (the neighbours of the grid)
    let reach = 0.25 * 100.0 / 3.0;
    let part = RankPart::new(&whole, &whole.x0, &owner, reach, comm.clone()).expect("part");
    let (nodes, elements) = (part.model.n_nodes(), part.model.elements.len());
    assert_eq!(part.nodes.n_local(), nodes, "rank {rank}: the node map holds the part's nodes");
    let mut sim = Simulation::new_part(part, case.time.clone(), case.solver.clone()).expect("part simulation");
    let parts = run(&mut sim);
    if std::env::var_os("PARTS_DEBUG").is_some() {
        for (a, b) in parts.iter().zip(&serial) {
            eprintln!("DEBUG parts {a:?}\nDEBUG whole {b:?}");
        }
    }
    let worst = worst_difference(&parts, &serial, rank);
    assert!(worst <= tol, "rank {rank} of {size}: the parts' history differs from the whole run's by {worst:e} (relative; tolerance {tol:e})");
    // ghosts chosen too close (boxes that overlap only: none here) miss the pairs across the
    // processes: the run stops, naming a body that came within reach and is not a ghost
    if blind && size > 1 {
        let blind = RankPart::new(&whole, &whole.x0, &owner, 0.0, comm.clone()).expect("part");
        let mut sim = Simulation::new_part(blind, case.time.clone(), case.solver.clone()).expect("part simulation");
        let err = sim.run(&mut |_, _| {}).expect_err("a part without its ghosts fails");
        assert!(err.to_string().contains("ghost"), "rank {rank}: {err}");
        // (at once: no cut-back changes the ghosts)
        assert!(matches!(err, mpfem::solver::SolveError::StepFailed { dt, .. } if dt == case.time.dt), "rank {rank}: stopped after cut-backs: {err}");
    }
    format!("{size} ranks, rank {rank}: {nodes} of {} nodes, {elements} of {} elements, {} steps, largest difference {worst:.1e}", whole.n_nodes(), whole.elements.len(), parts.len())
}

#[test]
fn a_run_on_owned_and_ghost_parts_equals_the_whole_run() {
    for ranks in [1, 2, 3, 4] {
        for line in common::on_ranks(ranks, "a_run_on_owned_and_ghost_parts_equals_the_whole_run", rank_work) {
            eprintln!("PARTS {line}");
        }
    }
}
