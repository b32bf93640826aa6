//! The owned + ghost state of a distributed run (`mpfem::parallel::part`,
//! `mpfem::comm::IndexMap`), on 4 real MPI processes: this test starts `mpirun -n 4` on its
//! own test binary, whose processes (`tests/common::on_ranks`) each build their part of a
//! 4 × 4 grid of elastic discs pressed together (every neighbour pair and every outer disc's
//! wall within the barrier's d̂) and check:
//!
//! - no process holds the whole mesh: its node and element counts equal its owned + ghost
//!   bodies' counts and are below the whole model's, and it has ghosts;
//! - the ghost layer is complete and each pair is evaluated once: the internal force of the
//!   owned elements plus the barrier gradient of the pairs whose first side is owned, summed
//!   onto the owners by the reverse scatter, equals the whole model's on every owned node
//!   (tolerance 1e-12 of the largest force: the same terms summed in another order); the
//!   barrier energies and wall forces summed over the processes equal the whole model's
//!   (1e-12 relative), and so does the smallest collision-free step fraction of a motion that
//!   closes the gaps (exactly: the same pairs' times of impact);
//! - the forward scatter gives every ghost node its owner's values exactly, and rank 0 gathers
//!   the whole model's node and element vectors from the owners exactly (for the output) and
//!   sends each process its part of a whole-model vector exactly (for a restart);
//! - a part grown again without the whole model (`RankPart::regrow`: its own bodies kept, its
//!   new ghosts sent by their owners) is the part made from the whole model with the same
//!   reach at the same coordinates, exactly (bodies, reference coordinates, meshes,
//!   elements, prescribed dofs, the node map, the whole model's node, element and equation
//!   numbers): from no ghosts to the neighbours, to the neighbours' neighbours, and back;
//! - (feature `petsc`) the distributed tangent: each process assembles its owned elements'
//!   and its pairs' terms (plus a diagonal shift on its own dofs) into the rows of its own and
//!   its ghost equations, PETSc (MUMPS LDLᵀ) gets the ghost rows through their owners, and the
//!   update of K du = −f on every local equation equals faer's LU of the whole model's
//!   tangent to 1e-10 of its largest entry (two direct solves of the same system).
//!
//! The reference is the serial evaluation of the whole model on each process (it is small).
#![cfg(feature = "mpi")]

mod common;

use mpfem::assembly::{number_equations, Assembler, ElementFields};
use mpfem::contact::barrier_problem::BarrierEval;
use mpfem::contact::geometry::Wall;
use mpfem::element::{Volumetric, N_ENH};
use mpfem::material::{ConstitutiveLaw, MatState, TimeIncrement};
use mpfem::model::Model;
use mpfem::parallel::part::RankPart;
use mpfem::parallel::Collective;
use std::sync::Arc;


const RANKS: usize = 4;

/// A deterministic pseudo-random number in [−1, 1) of `k` (a hash of it).
fn noise(k: usize) -> f64 {
    let mut z = (k as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// The whole model, a displacement that brings every neighbour pair of discs within d̂ (each
/// disc moved towards the die's centre and shrunk by 0.1 %, plus noise of d̂/100), and the
/// walls moved onto the outermost nodes (their barrier's zero lies d̂/2 behind them).
fn pressed_grid() -> (Model, Vec<f64>, Vec<Wall>) {
    let (n, side, ratio, h) = (4, 100.0, 0.7, 3.0);
    let text = mpfem::bench_support::disc_grid_case(n, side, ratio, h, "");
    let case = mpfem::case::parse(&text, std::path::Path::new(".")).expect("case");
    let model = Model::from_case(&case).expect("model");
    let dhat = model.barrier_contact().expect("barrier").dhat;
    let centre = [0.5 * side, 0.5 * side];
    // the discs' centres and radius, and the gap between neighbours
    let centres: Vec<[f64; 2]> = model
        .bodies
        .iter()
        .map(|b| {
            let nodes = &model.x0[b.node_offset..b.node_offset + b.mesh.n_nodes()];
            let (lo, hi) = nodes.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])]));
            [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]
        })
        .collect();
    let pitch = side / n as f64;
    let radius = {
        let b = &model.bodies[0];
        model.x0[b.node_offset..b.node_offset + b.mesh.n_nodes()].iter().map(|p| (p[0] - centres[0][0]).hypot(p[1] - centres[0][1])).fold(0.0, f64::max)
    };
    let shrink = 1e-3;
    let displacement = |s: f64| {
        let mut u = vec![0.0; model.n_dofs()];
        for (b, body) in model.bodies.iter().enumerate() {
            let c = centres[b];
            for k in body.node_offset..body.node_offset + body.mesh.n_nodes() {
                let p = model.x0[k];
                for d in 0..2 {
                    u[2 * k + d] = -s * (c[d] - centre[d]) - shrink * (p[d] - c[d]) + 0.01 * dhat * noise(2 * k + d);
                }
            }
        }
        u
    };
    // the smallest distance of a boundary node to another disc's boundary edge after moving
    // the centres by the fraction s of their distance to the die's centre
    let contact = model.barrier_contact().expect("barrier");
    let gap = |s: f64| {
        let x = coords(&model, &displacement(s));
        let mut g = f64::INFINITY;
        for &(node, body) in &contact.nodes {
            for seg in contact.segments.iter().filter(|seg| seg.body != body) {
                let (p, a, b) = (x[node], x[seg.nodes[0]], x[seg.nodes[1]]);
                let (ab, ap) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
                let t = ((ap[0] * ab[0] + ap[1] * ab[1]) / (ab[0] * ab[0] + ab[1] * ab[1])).clamp(0.0, 1.0);
                g = g.min((ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1]));
            }
        }
        g
    };
    // the first fraction that leaves the closest gap at d̂/2: scanned in steps that close the
    // gaps by 0.01 mm from 0.3 mm apart on the line of the centres, then bisected (the gap is
    // not monotone: once a vertex has passed another disc's edge it grows again)
    let step = 0.01 / pitch;
    let mut lo = (pitch - 2.0 * radius - 0.3) / pitch;
    assert!(gap(lo) > 0.5 * dhat);
    while gap(lo + step) > 0.5 * dhat {
        lo += step;
        assert!(lo < 1.0, "the discs never come within d̂/2");
    }
    let mut hi = lo + step;
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if gap(mid) > 0.5 * dhat {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let u = displacement(lo);
    let x: Vec<[f64; 2]> = model.x0.iter().enumerate().map(|(k, p)| [p[0] + u[2 * k], p[1] + u[2 * k + 1]]).collect();
    let walls = model
        .wall_planes(0.0)
        .into_iter()
        .map(|w| {
            let nn = w.normal[0].hypot(w.normal[1]);
            let n = [w.normal[0] / nn, w.normal[1] / nn];
            let depth = x.iter().map(|q| (q[0] - w.point[0]) * n[0] + (q[1] - w.point[1]) * n[1]).fold(f64::INFINITY, f64::min);
            Wall { point: [w.point[0] + depth * n[0], w.point[1] + depth * n[1]], normal: w.normal }
        })
        .collect();
    (model, u, walls)
}

/// Internal force of the elements `keep` (all when empty) at `u` from the reference state.
fn element_forces(model: &Model, u: &[f64], keep: &[bool]) -> Vec<f64> {
    assemble(model, u, keep, &[], false).3
}

/// The elements `keep` (all when empty) at `u` from the reference state: the assembler, its
/// pattern with the extra `blocks` (and with `tangent`, the element tangent in it), the
/// equation numbers and the internal force.
fn assemble(model: &Model, u: &[f64], keep: &[bool], blocks: &[Vec<usize>], tangent: bool) -> (Assembler, mpfem::linalg::CsrMatrix, Vec<usize>, Vec<f64>) {
    let (eq, n_free) = number_equations(model.n_dofs(), model.loading.prescribed.iter().map(|p| p.dof));
    let (mut assembler, mut kk) = Assembler::new(model, eq.clone(), n_free);
    assembler.set_terms(&mut kk, blocks, &[]);
    if !keep.is_empty() {
        assembler.retain_elements(keep);
    }
    let ne = model.elements.len();
    let vol: Vec<Volumetric> = model.elem_material.iter().map(|&m| Volumetric { kappa: model.materials[m].bulk_modulus().expect("compressible"), lambda: 0.0 }).collect();
    let mut f = vec![0.0; model.n_dofs()];
    let mut fields = ElementFields::new(ne);
    assembler
        .assemble(model, u, &vec![[MatState::default(); 4]; ne], &vec![[0.0; N_ENH]; ne], &vol, None, TimeIncrement { time: 0.0, dt: 1.0 }, tangent.then_some(&mut kk), &mut f, &mut fields, None)
        .expect("assembly");
    (assembler, kk, eq, f)
}

fn coords(model: &Model, u: &[f64]) -> Vec<[f64; 2]> {
    model.x0.iter().enumerate().map(|(k, p)| [p[0] + u[2 * k], p[1] + u[2 * k + 1]]).collect()
}

/// One process's checks (see the module docs); returns a line for the parent.
fn rank_work(comm: Arc<dyn Collective>) -> String {
    let (rank, size) = (comm.rank(), comm.size());
    assert_eq!(size, RANKS, "started on {RANKS} processes");
    let (whole, u, walls) = pressed_grid();
    // the whole model's references
    let x = coords(&whole, &u);
    let mut f_whole = element_forces(&whole, &u, &[]);
    let mut barrier = whole.barrier_contact().expect("barrier");
    let mut eval = BarrierEval::default();
    barrier.evaluate(&x, &walls, false, &mut eval).expect("admissible");
    eval.add_gradient(&mut f_whole);
    let (dhat, h) = (barrier.dhat, whole.whole_facts().h_min);
    // a motion that closes every gap (each node 0.6 d̂ towards the centre): its first impact
    let x1: Vec<[f64; 2]> = x.iter().map(|p| [p[0] + 0.6 * dhat * (50.0 - p[0]).signum(), p[1] + 0.6 * dhat * (50.0 - p[1]).signum()]).collect();
    let toi_whole = barrier.collision_free_step(&x, &x1, &walls, &walls);
    assert!(eval.edges.len() + eval.quads.len() > 100 && eval.walls.len() > 10, "the pressed grid has {} pair terms and {} wall terms", eval.edges.len() + eval.quads.len(), eval.walls.len());
    assert!(toi_whole < 1.0, "the motion closes a gap");

    // this process's part: the METIS owners (rank 0's), ghosts within d̂ + h
    let mut owner: Vec<f64> = mpfem::distribute::partition_particles(&whole, size).iter().map(|&o| o as f64).collect();
    comm.broadcast(&mut owner);
    let owner: Vec<usize> = owner.iter().map(|&o| o as usize).collect();
    let part = RankPart::new(&whole, &x, &owner, dhat + h, comm.clone()).expect("part");
    let m = &part.model;
    let n_ghost_bodies = part.bodies.len() - part.n_owned_bodies;
    let owned_nodes: usize = part.bodies[..part.n_owned_bodies].iter().map(|&b| whole.bodies[b].mesh.n_nodes()).sum();
    let ghost_nodes: usize = part.bodies[part.n_owned_bodies..].iter().map(|&b| whole.bodies[b].mesh.n_nodes()).sum();
    let part_elements: usize = part.bodies.iter().map(|&b| whole.bodies[b].mesh.n_elements()).sum();
    assert!(n_ghost_bodies > 0, "rank {rank} has ghosts");
    assert_eq!(m.n_nodes(), owned_nodes + ghost_nodes);
    assert_eq!((part.nodes.n_owned(), part.nodes.n_local()), (owned_nodes, owned_nodes + ghost_nodes));
    assert_eq!(m.elements.len(), part_elements);
    assert!(m.n_nodes() < whole.n_nodes() && m.elements.len() < whole.elements.len(), "rank {rank} holds {} of {} nodes, {} of {} elements", m.n_nodes(), whole.n_nodes(), m.elements.len(), whole.elements.len());
    assert_eq!(part.nodes.n_global(), whole.n_nodes());

    // grown again: from a part without ghosts (made where the discs are apart) to the
    // neighbours within d̂ + h where they are pressed, to those within a disc's diameter (the
    // neighbours kept, the next ones new), and back (the farther ones dropped)
    let lonely = RankPart::new(&whole, &whole.x0, &owner, 0.0, comm.clone()).expect("a part without ghosts");
    assert_eq!(lonely.bodies.len(), lonely.n_owned_bodies, "rank {rank}: the discs are apart at the start");
    let at = |p: &RankPart| -> Vec<[f64; 2]> { p.whole.node.iter().map(|&g| x[g]).collect() };
    let near = RankPart::regrow(lonely.view(), &at(&lonely), dhat + h).expect("grown to the neighbours");
    same_part(&near, &part, "the neighbours");
    let far_reach = 25.0;
    let far = RankPart::regrow(near.view(), &at(&near), far_reach).expect("grown farther");
    let far_whole = RankPart::new(&whole, &x, &owner, far_reach, comm.clone()).expect("the farther part");
    assert!(far.bodies.len() > near.bodies.len(), "rank {rank}: a disc's diameter holds more ghosts than d̂ + h");
    same_part(&far, &far_whole, "the neighbours' neighbours");
    let back = RankPart::regrow(far.view(), &at(&far), dhat + h).expect("grown back");
    same_part(&back, &part, "back to the neighbours");
    // with prescribed dofs on every fifth disc (the whole model's equations skip them; a part
    // grown again numbers its own from the layout's counts of them): the same
    let mut pinned = whole.clone();
    for b in (0..pinned.bodies.len()).step_by(5) {
        let n = pinned.bodies[b].node_offset;
        pinned.loading.prescribed.extend([2 * n + 1, 2 * n + 6, 2 * n + 7].map(|dof| mpfem::loading::PrescribedDof { dof, value: 0.0, amplitude: 0 }));
    }
    pinned.loading.prescribed.sort_by_key(|p| p.dof);
    let pinned_part = RankPart::new(&pinned, &x, &owner, dhat + h, comm.clone()).expect("the pinned part");
    let pinned_lonely = RankPart::new(&pinned, &pinned.x0, &owner, 0.0, comm.clone()).expect("the pinned part without ghosts");
    let pinned_near = RankPart::regrow(pinned_lonely.view(), &at(&pinned_lonely), dhat + h).expect("the pinned part grown");
    assert_ne!(pinned_near.whole_eq, near.whole_eq, "rank {rank}: the prescribed dofs change no equation");
    same_part(&pinned_near, &pinned_part, "with prescribed dofs");

    // the distributed residual: owned elements, owned first sides, reverse scatter
    let u_part = part.restrict(&u, 2);
    let xp = coords(m, &u_part);
    let mut f = element_forces(m, &u_part, &part.owned_elements());
    let mut bp = m.barrier_contact().expect("barrier");
    assert_eq!((bp.dhat, bp.kappa), (barrier.dhat, barrier.kappa), "d̂ and κ are the whole model's");
    bp.evaluate_only(part.owned_bodies());
    let mut ep = BarrierEval::default();
    bp.evaluate(&xp, &walls, false, &mut ep).expect("admissible");
    ep.add_gradient(&mut f);
    part.nodes.reverse_add(&mut f, 2);
    let scale = f_whole.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut worst = 0.0f64;
    for i in 0..part.nodes.n_owned() {
        let g = part.whole.node[i];
        for d in 0..2 {
            worst = worst.max((f[2 * i + d] - f_whole[2 * g + d]).abs());
        }
    }
    assert!(worst <= 1e-12 * scale, "rank {rank}: owned residual differs by {worst:e} (largest force {scale:e})");
    assert!(f[2 * part.nodes.n_owned()..].iter().all(|&v| v == 0.0), "the reverse scatter leaves the ghosts zero");
    let mut sums = vec![ep.energy];
    sums.extend_from_slice(&ep.wall_force);
    comm.sum_in_place(&mut sums);
    assert!((sums[0] - eval.energy).abs() <= 1e-12 * eval.energy.abs(), "barrier energy {} over the ranks, {} whole", sums[0], eval.energy);
    for (w, (&a, &b)) in sums[1..].iter().zip(&eval.wall_force).enumerate() {
        assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-300), "wall {w}: force {a} over the ranks, {b} whole");
    }
    let x1p: Vec<[f64; 2]> = part.whole.node.iter().map(|&g| x1[g]).collect();
    let toi = -comm.max(-bp.collision_free_step(&xp, &x1p, &walls, &walls));
    assert_eq!(toi, toi_whole, "collision-free step fraction over the ranks");

    // forward: the ghosts take their owners' values (owned entries filled, ghosts garbage)
    let mut v = vec![f64::NAN; 2 * part.nodes.n_local()];
    for i in 0..part.nodes.n_owned() {
        let g = part.whole.node[i];
        v[2 * i..2 * i + 2].copy_from_slice(&u[2 * g..2 * g + 2]);
    }
    part.nodes.forward(&mut v, 2);
    assert_eq!(v, u_part, "forward scatter gives every ghost its owner's value");
    // rank 0 gathers the whole model's node and element vectors from the owners
    let gathered = part.gather_nodes(&u_part, 2);
    let areas: Vec<f64> = m.elements.iter().map(|el| mpfem::mesh::polygon_area(el.iter().map(|&n| xp[n]))).collect();
    let gathered_areas = part.gather_elements(&areas, 1);
    if rank == 0 {
        assert_eq!(gathered.as_deref(), Some(&u[..]), "rank 0 gathers the whole displacement");
        let whole_areas: Vec<f64> = whole.elements.iter().map(|el| mpfem::mesh::polygon_area(el.iter().map(|&n| x[n]))).collect();
        assert_eq!(gathered_areas, Some(whole_areas), "rank 0 gathers every element's value");
    } else {
        assert!(gathered.is_none() && gathered_areas.is_none());
    }
    // and sends each process its part of a whole-model vector (a restart)
    let scattered = part.scatter_nodes((rank == 0).then_some(&u[..]), 2);
    assert_eq!(scattered, u_part, "every process receives its nodes' values, its ghosts' included");
    let from_case = part_from_the_case(&comm);
    #[cfg(feature = "petsc")]
    let solve = distributed_solve(&whole, &u, &eval, &part, &u_part, &ep);
    #[cfg(not(feature = "petsc"))]
    let solve = String::new();
    format!(
        "rank {rank}: {} owned + {n_ghost_bodies} ghost bodies, {} of {} nodes, {} of {} elements, {} pair terms; residual {:.1e} of {scale:.3e}; energy {:.6e}; step fraction {toi}; {from_case}{solve}",
        part.n_owned_bodies,
        m.n_nodes(),
        whole.n_nodes(),
        m.elements.len(),
        whole.elements.len(),
        ep.edges.len() + ep.quads.len() + ep.walls.len(),
        worst / scale,
        sums[0]
    )
}

/// The part a fresh run on parts starts with, made from the case without the whole model
/// (`mpfem::case::parts::start_part`: each process meshes a share of the bodies, the boxes and
/// counts are gathered, rank 0 partitions them, each process meshes its own bodies, its ghosts
/// and the bodies the loads, groups and probes name), against the part `RankPart::for_run`
/// makes of the whole model with the same reach: the same, exactly, on a 6 × 6 disc grid with
/// a prescribed displacement, a force, a reaction and a displacement group and a point and a
/// node probe on discs of several processes. Rank 0's model of the bodies those name makes the
/// whole model's frame (compared through `Debug`), and with every body's mesh put in it, the
/// whole model. No process meshes all the bodies.
fn part_from_the_case(comm: &Arc<dyn Collective>) -> String {
    let rank = comm.rank();
    let extra = r#"[[boundary]]
body = "g0_p7"
set = "boundary"
ux = 0.0
[[loads]]
body = "g0_p28"
set = "boundary"
type = "force"
value = [0.0, -5.0]
amplitude = "ramp"
[output]
every = 0
probes = [{ name = "q", point = [52.0, 47.0] }, { name = "n", body = "g0_p33", node = 3 }]
reactions = ["g0_p7.boundary"]
displacements = ["g0_p20.boundary"]
"#;
    let text = mpfem::bench_support::disc_grid_case(6, 120.0, 0.7, 4.0, extra);
    let case = mpfem::case::parse(&text, std::path::Path::new(".")).expect("case");
    let whole = Model::from_case(&case).expect("model");
    assert!(!whole.loading.prescribed.is_empty() && whole.loading.loads[0].edges.len() > 4 && whole.probes.len() == 2, "the case has its boundary, load and probes");
    let reach = RankPart::reach(&whole);
    let reference = RankPart::for_run(&whole, &whole.x0, reach, comm.clone()).expect("the part of the whole model");
    let start = mpfem::case::parts::start_part(&case, comm.clone(), 0.1).expect("the part made from the case");
    same_part(&start.part, &reference, "made from the case");
    assert_eq!(start.part.reach, reach, "rank {rank}: the reach");
    let held = start.held.as_ref();
    assert_eq!(held.is_some(), rank == 0, "rank {rank}: rank 0 alone keeps its held bodies");
    if let Some(h) = held {
        let meshed = h.bodies.iter().filter(|b| b.mesh.n_nodes() > 0).count();
        // (the bodies of the boundary, the load, the two groups and the two probes)
        assert!(meshed <= 6 && h.bodies.len() == whole.bodies.len(), "rank 0 holds {meshed} of {} bodies' meshes for the output", whole.bodies.len());
        let frame = h.frame().expect("a frame of the held bodies");
        assert_eq!(format!("{frame:?}"), format!("{:?}", whole.frame().expect("the whole model's frame")), "the frame of the held bodies is the whole model's");
        let rebuilt = frame.assemble((0..whole.bodies.len()).map(|k| whole.ghost_body(k)).collect()).expect("the whole model from the frame");
        assert_eq!(format!("{rebuilt:?}"), format!("{whole:?}"), "the frame and every body's mesh make the whole model");
    }
    // the probes and loads are the process's own bodies', as a part of the whole model has them
    let probes = comm.all_gather_varcount(&[start.part.model.probes.len() as f64, start.part.model.loading.loads[0].edges.len() as f64]);
    let (n_probes, n_edges): (f64, f64) = probes.chunks_exact(2).fold((0.0, 0.0), |a, c| (a.0 + c[0], a.1 + c[1]));
    assert_eq!((n_probes as usize, n_edges as usize), (2, whole.loading.loads[0].edges.len()), "each probe and load edge on one process");
    let restart = part_from_a_checkpoint(comm, &case, &text);
    format!("from the case: {} owned + {} ghost bodies, identical; {restart}", start.part.n_owned_bodies, start.part.bodies.len() - start.part.n_owned_bodies)
}

/// The part and state a restart on parts starts with, made from a checkpoint without the
/// whole model or the whole state (`start_part_from` and `set_whole_state_from`: each process
/// reads its share's meshes and its part's rows of the file), against the part
/// `RankPart::for_run` makes of the checkpoint's whole model (`Checkpoint::model`) at the
/// checkpoint's coordinates and the state `set_whole_state` takes from the whole state read
/// into memory: the same, exactly. The checkpoint has one disc re-meshed (finer: other node and
/// element counts than the case's), the bottom and top rows of discs swapped (each turned half
/// a turn about the die's centre, so that the ghosts at the checkpoint are not the reference
/// ones), every element field set to values of its own.
fn part_from_a_checkpoint(comm: &Arc<dyn Collective>, case: &mpfem::case::Case, text: &str) -> String {
    use mpfem::checkpoint::{Checkpoint, CheckpointFile};
    use mpfem::solver::Simulation;
    let rank = comm.rank();
    // the checkpoint: disc 0 re-meshed at 3 mm (the case meshes it at 4), written by rank 0
    let finer = mpfem::case::parse(&text.replace("mesh_size = 4", "mesh_size = 3"), std::path::Path::new(".")).expect("the finer case");
    let finer = Model::from_case(&finer).expect("the finer model").bodies[0].mesh.clone();
    let whole = Model::from_case(case).expect("model").with_body_mesh(0, finer).expect("disc 0 re-meshed");
    let serial: Arc<dyn Collective> = Arc::new(mpfem::comm::Serial);
    let mut state = Simulation::new_with(whole.clone(), case.time.clone(), case.solver.clone(), serial).expect("the whole simulation").state();
    for (b, body) in whole.bodies.iter().enumerate() {
        // (the bottom and top rows turned half a turn about the die's centre: each of their
        // discs in the other row's place; every disc shifted by up to 0.2 mm of its own)
        let turned = if b < 6 || b >= 30 { 1.0 } else { 0.0 };
        let shift = [0.2 * noise(b + 100), 0.2 * noise(b + 200)];
        for n in body.node_offset..body.node_offset + body.mesh.n_nodes() {
            let [x, y] = whole.x0[n];
            state.sol.u[2 * n] = turned * (120.0 - 2.0 * x) + shift[0];
            state.sol.u[2 * n + 1] = turned * (120.0 - 2.0 * y) + shift[1];
            state.u_prev[2 * n] = 0.5 * state.sol.u[2 * n];
            state.u_prev[2 * n + 1] = 0.5 * state.sol.u[2 * n + 1];
        }
    }
    let f = &mut state.sol.fields;
    for e in 0..whole.elements.len() {
        let v = |k: usize| noise(31 * e + k);
        for gp in 0..4 {
            f.states[e][gp] = MatState { cp_inv: [1.0 + 0.01 * v(gp), 0.01 * v(gp + 4), 0.01 * v(gp + 8), 1.0 + 0.01 * v(gp + 12)], eps_p: 0.1 * v(gp + 16).abs(), eps_c: 0.0 };
            f.sig[e][gp] = [v(gp + 20), v(gp + 24), v(gp + 28), v(gp + 32)];
        }
        f.pressure[e] = v(40);
        f.theta[e] = 1.0 + 0.01 * v(41);
        f.alpha[e] = std::array::from_fn(|k| 0.001 * v(42 + k));
        state.sol.lambda[e] = v(50);
        state.sol.j0[e] = 1.0 + 0.01 * v(51);
    }
    let mut id = [f64::from(std::process::id())];
    comm.broadcast(&mut id);
    let dir = std::env::temp_dir().join(format!("mpfem-ghosts-checkpoint-{}", id[0]));
    if rank == 0 {
        std::fs::create_dir_all(&dir).expect("a folder");
        mpfem::checkpoint::write_state(&dir, &whole, &state, "sha", &0u32).expect("the checkpoint written");
    }
    comm.max(0.0);
    // the reference: the checkpoint read whole, its model, the part at its coordinates
    let read = Checkpoint::read(&dir).expect("the checkpoint read whole");
    let ck_model = read.model(Model::from_case(case).expect("model")).expect("the checkpoint's model");
    assert_eq!(ck_model.bodies[0].mesh.n_nodes(), whole.bodies[0].mesh.n_nodes(), "disc 0 has its re-meshed mesh");
    let x: Vec<[f64; 2]> = ck_model.x0.iter().enumerate().map(|(n, p)| [p[0] + read.state.sol.u[2 * n], p[1] + read.state.sol.u[2 * n + 1]]).collect();
    let reach = RankPart::reach(&ck_model);
    let reference = RankPart::for_run(&ck_model, &x, reach, comm.clone()).expect("the part of the checkpoint's model");
    let moved = mpfem::parallel::part::ghost_bodies(&mpfem::distribute::particles(&ck_model), &reference.layout.owner, rank, reach).expect("reference ghosts") != reference.bodies[reference.n_owned_bodies..];
    let moved = comm.max(if moved { 1.0 } else { 0.0 }) > 0.0;
    assert!(moved, "the discs moved far enough that some process's ghosts at the checkpoint are not those of the reference configuration");
    // made from the checkpoint's file in pieces
    let file = CheckpointFile::open(&dir).expect("the checkpoint opened");
    let start = mpfem::case::parts::start_part_from(case, comm.clone(), 0.1, Some(&file)).expect("the part made from the checkpoint");
    same_part(&start.part, &reference, "made from the checkpoint");
    assert_eq!(start.part.reach, reach, "rank {rank}: the reach at the checkpoint");
    let (own, ghosts) = (start.part.n_owned_bodies, start.part.bodies.len() - start.part.n_owned_bodies);
    let mut a = Simulation::new_part_for_state(start.part, case.time.clone(), case.solver.clone()).expect("the part's simulation");
    a.set_whole_state_from(file.scalars.clone(), &file).expect("the state from the file's rows");
    let mut b = Simulation::new_part_for_state(reference, case.time.clone(), case.solver.clone()).expect("the reference simulation");
    b.set_whole_state(read.state).expect("the state from the whole state");
    let (sa, sb) = (a.state(), b.state());
    assert_eq!(sa.sol.u, sb.sol.u, "rank {rank}: the displacements");
    assert_eq!(sa.u_prev, sb.u_prev, "rank {rank}: the previous displacements");
    assert_eq!((&sa.sol.lambda, &sa.sol.j0), (&sb.sol.lambda, &sb.sol.j0), "rank {rank}: the element multipliers and j0");
    let (fa, fb) = (&sa.sol.fields, &sb.sol.fields);
    assert_eq!(format!("{:?}", (&fa.states, &fa.sig, &fa.pressure, &fa.theta, &fa.alpha)), format!("{:?}", (&fb.states, &fb.sig, &fb.pressure, &fb.theta, &fb.alpha)), "rank {rank}: the element fields");
    assert_eq!(format!("{:?}", sa.scalars), format!("{:?}", sb.scalars), "rank {rank}: the scalars");
    assert!(sa.sol.u.iter().any(|&v| v != 0.0) && fa.pressure.iter().any(|&v| v != 0.0), "rank {rank}: the state read is not empty");
    comm.max(0.0);
    if rank == 0 {
        let _ = std::fs::remove_dir_all(&dir);
    }
    format!("from a checkpoint: {own} owned + {ghosts} ghost bodies, part and state identical")
}

/// That `a` (a part grown again) is `b` (the part made from the whole model), exactly.
fn same_part(a: &RankPart, b: &RankPart, what: &str) {
    let rank = a.nodes.comm().rank();
    let m = (&a.model, &b.model);
    assert_eq!((&a.bodies, a.n_owned_bodies), (&b.bodies, b.n_owned_bodies), "rank {rank}, {what}: the bodies");
    assert_eq!(m.0.bodies, m.1.bodies, "rank {rank}, {what}: the bodies' meshes and offsets");
    assert_eq!(m.0.x0, m.1.x0, "rank {rank}, {what}: the reference coordinates");
    assert_eq!((&m.0.elements, &m.0.elem_body, &m.0.elem_material), (&m.1.elements, &m.1.elem_body, &m.1.elem_material), "rank {rank}, {what}: the elements");
    assert_eq!(m.0.loading, m.1.loading, "rank {rank}, {what}: the prescribed dofs and loads");
    assert_eq!((&m.0.reaction_groups, &m.0.displacement_groups, &m.0.probes), (&m.1.reaction_groups, &m.1.displacement_groups, &m.1.probes), "rank {rank}, {what}: the output groups");
    assert_eq!(m.0.whole, m.1.whole, "rank {rank}, {what}: the whole model's facts");
    assert_eq!((a.nodes.n_owned(), a.nodes.ghosts(), a.nodes.ghost_owners()), (b.nodes.n_owned(), b.nodes.ghosts(), b.nodes.ghost_owners()), "rank {rank}, {what}: the node map");
    assert_eq!(a.whole, b.whole, "rank {rank}, {what}: the whole model's nodes and elements");
    assert_eq!(a.whole_eq, b.whole_eq, "rank {rank}, {what}: the whole model's equations");
    assert_eq!(a.layout, b.layout, "rank {rank}, {what}: the bodies' layout");
}

/// The diagonal shift of the tangents (N/mm per dof): holds the discs' free rotations.
#[cfg(feature = "petsc")]
const SHIFT: f64 = 1e3;

/// The tangent of `model` at `u` (reference states): the elements `keep` (all when empty),
/// the barrier terms of `eval` and [`SHIFT`] on the diagonal of the dofs `own` (the first
/// `own` dofs); with the equation numbers of the dofs and −f on the free equations.
#[cfg(feature = "petsc")]
fn tangent(model: &Model, u: &[f64], eval: &BarrierEval, keep: &[bool], own: usize) -> (mpfem::linalg::CsrMatrix, Vec<usize>, Vec<f64>) {
    let blocks: Vec<Vec<usize>> = eval.edges.iter().map(|e| e.dofs.to_vec()).chain(eval.quads.iter().map(|q| q.dofs.to_vec())).chain(eval.walls.iter().map(|w| vec![2 * w.node, 2 * w.node + 1])).collect();
    let (assembler, mut kk, eq, mut f) = assemble(model, u, keep, &blocks, true);
    let map = assembler.block_map(&kk, &blocks);
    let hessians = eval.edges.iter().map(|e| e.term.hess.iter().flatten().copied().collect::<Vec<f64>>()).chain(eval.quads.iter().map(|q| q.term.hess.iter().flatten().copied().collect())).chain(eval.walls.iter().map(|w| w.term.hess.iter().flatten().copied().collect()));
    for (i, h) in hessians.enumerate() {
        map.add(&mut kk.values, i, &h);
    }
    let diagonal = assembler.diagonal_map(&kk);
    for d in 0..own {
        diagonal.add_entry(&mut kk.values, d, 0, 0, SHIFT);
    }
    eval.add_gradient(&mut f);
    let mut b = vec![0.0; assembler.n_free];
    for (d, &q) in eq.iter().enumerate() {
        if q != mpfem::assembly::FIXED {
            b[q] = -f[d];
        }
    }
    (kk, eq, b)
}

/// The distributed tangent solved by PETSc against the whole one solved by faer (see the
/// module docs); the report's tail.
#[cfg(feature = "petsc")]
fn distributed_solve(whole: &Model, u: &[f64], eval: &BarrierEval, part: &RankPart, u_part: &[f64], ep: &BarrierEval) -> String {
    use mpfem::linalg::petsc::{make_rows, PartRows, Rows};
    use mpfem::linalg::{make_solver, LinearSolverKind, SolverOptions};
    let comm = part.nodes.comm_arc();
    // the whole system, faer's LU
    let (kw, eqw, bw) = tangent(whole, u, eval, &[], whole.n_dofs());
    let mut lu = make_solver(&SolverOptions { kind: LinearSolverKind::Lu, ..Default::default() });
    let mut xw = vec![0.0; bw.len()];
    lu.analyze(&kw).expect("analyze");
    lu.factor(&kw).expect("factor");
    lu.solve(&kw, &bw, &mut xw).expect("solve");
    // the part's rows: its own and its ghosts' (−f complete on its own equations after the
    // reverse scatter of the forces)
    let m = &part.model;
    let (kp, eqp, _) = tangent(m, u_part, ep, &part.owned_elements(), 2 * part.nodes.n_owned());
    let mut f = element_forces(m, u_part, &part.owned_elements());
    ep.add_gradient(&mut f);
    part.nodes.reverse_add(&mut f, 2);
    let map = std::sync::Arc::new(part.equation_map(&eqp).expect("equation map"));
    let n_local = map.n_local();
    let mut b = vec![0.0; n_local];
    let mut dof = vec![None; n_local];
    for (d, &q) in eqp.iter().enumerate() {
        if q != mpfem::assembly::FIXED {
            b[q] = -f[d];
            dof[q] = Some((m.x0[d / 2], d % 2));
        }
    }
    assert_eq!(map.n_global(), bw.len(), "the free equations over the processes are the whole model's");
    let _petsc = mpfem::linalg::petsc::start("").expect("PETSc");
    // (no particle numbers: the direct solve has no coarse space)
    let particle = vec![mpfem::linalg::petsc::NO_PARTICLE; n_local];
    let mut solver = make_rows(Some(Rows::Part(PartRows { map: map.clone(), dof, particle })), true, 1e-10, 1000, 1e-8, comm.rank(), comm.size());
    let mut x = vec![0.0; n_local];
    solver.analyze(&kp).expect("analyze");
    solver.factor(&kp).expect("factor");
    solver.solve(&kp, &b, &mut x).expect("solve");
    let scale = xw.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut worst = 0.0f64;
    for (d, &q) in eqp.iter().enumerate() {
        if q != mpfem::assembly::FIXED {
            let g = 2 * part.whole.node[d / 2] + d % 2;
            worst = worst.max((x[q] - xw[eqw[g]]).abs());
        }
    }
    assert!(worst <= 1e-10 * scale, "rank {}: the distributed update differs from the whole one by {worst:e} (largest {scale:e})", comm.rank());
    format!("; {} with {} local equations: update {:.1e} of {scale:.3e}", solver.name(), n_local, worst / scale)
}

#[test]
fn owned_and_ghost_parts_on_four_processes() {
    for line in common::on_ranks(RANKS, "owned_and_ghost_parts_on_four_processes", rank_work) {
        eprintln!("GHOSTS {line}");
    }
}
