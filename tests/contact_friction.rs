//! Coulomb friction against a rigid wall (contact issue verification): a block pressed on a
//! fixed wall with μ = 0.3 and pushed sideways. While it sticks, the tangential force stays
//! below μN; once the whole base slides, the tangential force equals μN to 1e-6 (the slip
//! return map puts every node exactly on the Coulomb cone, and the top reactions balance the
//! wall forces).

use mpfem::case;
use mpfem::model::Model;
use mpfem::solver::Simulation;

#[test]
fn coulomb_block_sticks_then_slides_at_mu_n() {
    coulomb_block(std::fs::read_to_string("jobs/verification/coulomb_block.toml").unwrap(), 1e-6);
}

/// The same block with the barrier contact (`method = "barrier"`, IPC's lagged, mollified
/// friction, default ε): the barrier issue's tolerance, T/N = μ to 1e-3 while sliding (the
/// lagged normal force is converged to 1e-4 of the largest by the outer updates).
#[test]
fn coulomb_block_sticks_then_slides_at_mu_n_barrier() {
    let text = std::fs::read_to_string("jobs/verification/coulomb_block.toml").unwrap();
    assert!(text.contains("method = \"penalty\"\n"));
    coulomb_block(text.replace("method = \"penalty\"\n", "method = \"barrier\"\n"), 1e-3);
}

fn coulomb_block(text: String, tol: f64) {
    let c = case::parse(&text, std::path::Path::new("jobs/verification")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    let mut rows = Vec::new();
    let mut wall = Vec::new();
    sim.run(&mut |_, r| {
        rows.push((r.time, r.reactions[0]));
        let c = r.compaction.as_ref().expect("a wall: the compaction columns");
        wall.push((c.force[2], c.shear[2]));
    })
    .unwrap();
    // the wall's own columns are the block's equilibrium: the top's reaction is the force the
    // block puts on the wall (normal: f_bottom = −R_y; tangential along x: ft_bottom = R_x), to
    // 1e-6 of the normal force (the residual tolerance is 1e-8)
    for (&(t, r), &(f, ft)) in rows.iter().zip(&wall) {
        let scale = r[1].abs().max(f64::MIN_POSITIVE);
        assert!((f + r[1]).abs() <= 1e-6 * scale, "t = {t}: f_bottom = {f}, top reaction {r:?}");
        assert!((ft - r[0]).abs() <= 1e-6 * scale, "t = {t}: ft_bottom = {ft}, top reaction {r:?}");
    }
    let mu = 0.3;
    // pressing phase: no tangential force
    let (_, r_press) = rows.iter().find(|(t, _)| (*t - 0.5).abs() < 1e-9).copied().unwrap();
    assert!(r_press[1] < 0.0, "pressed down: {r_press:?}");
    assert!(r_press[0].abs() < 1e-9 * r_press[1].abs(), "no shear while pressing: {r_press:?}");
    // first push step: sticking, |T| < μ N
    let (_, r_stick) = rows.iter().find(|(t, _)| *t > 0.5 + 1e-9).copied().unwrap();
    assert!(r_stick[0].abs() > 0.0 && r_stick[0].abs() < mu * r_stick[1].abs(), "stick: {r_stick:?}");
    // end: sliding, |T| = μ N
    let (_, r_end) = *rows.last().unwrap();
    let ratio = r_end[0].abs() / r_end[1].abs();
    eprintln!("sliding: T/N = {ratio:.9} (μ = {mu})");
    assert!((ratio - mu).abs() < tol * mu, "sliding: T/N = {ratio}");
}

/// A die in equilibrium with wall friction (issue 22's check, the default barrier contact): 2 × 2
/// aluminium discs (μ = 0.2 between them and on every wall) pushed by the left wall alone
/// against the fixed right wall; once the discs spread onto the bottom and top walls, those
/// walls' friction carries part of the push. The particles are quasi-static and nothing but the
/// walls acts on them, so every step's wall forces balance: f_left − f_right = ft_bottom +
/// ft_top and f_bottom − f_top = ft_left + ft_right (`history.csv`'s sign convention: the force
/// of the particles on the wall along +x on the bottom and top walls, +y on the left and
/// right ones), to 1e-6 of the largest wall force (the residual tolerance is 1e-8 of the force
/// scale). The friction must carry at least 5 % of the push at the end, or the test would not
/// see a missing friction force. The walls' travel is their prescribed motion (10 mm/s on the
/// left, fixed on the right), to round-off.
#[test]
fn die_with_wall_friction_is_in_equilibrium() {
    let text = std::fs::read_to_string("tests/data/die_wall_friction.toml").unwrap();
    let c = case::parse(&text, std::path::Path::new("tests/data")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    let mut rows = Vec::new();
    sim.run(&mut |_, r| rows.push((r.time, r.compaction.clone().expect("walls: the compaction columns")))).unwrap();
    let fmax = rows.iter().flat_map(|(_, c)| c.force).fold(0.0, f64::max);
    assert!(fmax > 0.0, "the walls carried no load");
    for (t, c) in &rows {
        let [fl, fr, fb, ft] = c.force;
        let [sl, sr, sb, st] = c.shear;
        assert!((fl - fr - sb - st).abs() <= 1e-6 * fmax, "t = {t}: x: f_left − f_right = {}, ft_bottom + ft_top = {}", fl - fr, sb + st);
        assert!((fb - ft - sl - sr).abs() <= 1e-6 * fmax, "t = {t}: y: f_bottom − f_top = {}, ft_left + ft_right = {}", fb - ft, sl + sr);
        assert!((c.travel[0] - 10.0 * t).abs() <= 1e-12 * (1.0 + 10.0 * t), "t = {t}: travel_left = {}", c.travel[0]);
        assert_eq!(c.travel[1..], [0.0; 3], "t = {t}: the fixed walls' travel");
    }
    let (t, last) = rows.last().unwrap();
    let carried = last.shear[2] + last.shear[3];
    eprintln!("die at t = {t}: f_left = {:.3}, f_right = {:.3}, friction of the bottom and top walls {carried:.3} N/mm", last.force[0], last.force[1]);
    assert!(last.solid_ratio >= 0.9 - 1e-9, "the die reached {}", last.solid_ratio);
    assert!(carried >= 0.05 * last.force[0], "the bottom and top walls' friction carries {carried} of the push {}", last.force[0]);
}

/// Contact patch test (Taylor & Papadopoulos 1991): two blocks with non-matching meshes (7 and
/// 5 elements across) under a uniform pressure of 1 MPa, augmented Lagrangian, two-pass
/// node-to-segment. The contact must transmit the uniform stress: every Gauss point's σ_yy is
/// within 1 % of −1 MPa (the criterion for the default method).
#[test]
fn contact_patch_test_taylor_papadopoulos() {
    contact_patch_test(std::fs::read_to_string("jobs/verification/contact_patch.toml").unwrap(), "segment");
}

/// The contact patch test with the smoothed master surface (`[contact] normal = "smoothed"`):
/// the interface is straight and the block corners (90°) are feature corners, so the surface
/// is the segments themselves; the same 1 % criterion.
#[test]
fn contact_patch_test_smoothed_normal() {
    let text = std::fs::read_to_string("jobs/verification/contact_patch.toml").unwrap();
    assert!(text.contains("[contact]\n"));
    contact_patch_test(text.replace("[contact]\n", "[contact]\nnormal = \"smoothed\"\n"), "smoothed");
}

/// The contact patch test with the barrier: the upper block lifted by 0.02 mm (the barrier
/// needs the particles apart at the start; the gap closes to the barrier's under the load).
/// The barrier's terms on Gauss points of the edges carry the same pressure at a uniform gap
/// wherever the point lies, so the stress is uniform to the same 1 % at every Gauss point
/// (0.48 % measured; with the node terms alone it was 31 %: the ends of the interface and
/// the nodes of the non-matching sides carried equal forces, docs/robustness.md).
#[test]
fn contact_patch_test_barrier() {
    let text = std::fs::read_to_string("jobs/verification/contact_patch.toml").unwrap();
    let barrier = text
        .replace("method = \"augmented_lagrangian\"\n", "method = \"barrier\"\n")
        .replace("penetration_tol = 1e-6\n", "")
        .replace("origin = [0.0, 5.0]", "origin = [0.0, 5.02]");
    assert!(barrier.contains("method = \"barrier\"") && barrier.contains("[0.0, 5.02]"));
    contact_patch_test(barrier, "barrier");
}

/// The `contact_pressure` field on the contact patch test (issue 22's check): on both sides of
/// the interface, every node's pressure (the normal contact force over its tributary contact
/// length, current configuration) is uniform — to 1 % with the default barrier contact and to
/// 1e-3 with Lagrange multipliers, which transmit the uniform stress exactly — and Σ pressure ×
/// tributary length on each side is the applied load (1 MPa × 10 mm) to 1e-6 (the Newton
/// residual tolerance is 1e-8). The meshes: non-matching 7/5, 4/5 and 3/5 elements
/// across, and the finer mesh above as well as below (two-pass and the barrier have no master
/// side, so swapping the blocks' meshes swaps master and slave). The interface's ends are a
/// block corner each; their tributary length is the half edge along the interface only.
#[test]
fn contact_pressure_field_is_uniform_on_the_patch_test() {
    let base = std::fs::read_to_string("jobs/verification/contact_patch.toml").unwrap();
    let meshes = [([7, 3], [5, 3]), ([4, 2], [5, 2]), ([3, 2], [5, 2]), ([5, 2], [4, 2]), ([5, 2], [3, 2])];
    for (lower, upper) in meshes {
        let text = base
            .replace("divisions = [7, 3]", &format!("divisions = [{}, {}]", lower[0], lower[1]))
            .replace("divisions = [5, 3]", &format!("divisions = [{}, {}]", upper[0], upper[1]))
            .replace("penetration_tol = 1e-6\n", "");
        for (method, lift, tol) in [("barrier", 0.02, 0.01), ("lagrange", 0.0, 1e-3)] {
            let case = text
                .replace("method = \"augmented_lagrangian\"", &format!("method = \"{method}\""))
                .replace("origin = [0.0, 5.0]", &format!("origin = [0.0, {}]", 5.0 + lift));
            assert!(case.contains(&format!("method = \"{method}\"")) && case.contains(&format!("divisions = [{}, {}]", upper[0], upper[1])));
            let c = case::parse(&case, std::path::Path::new("jobs/verification")).unwrap();
            let model = Model::from_case(&c).unwrap();
            let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
            sim.run(&mut |_, _| {}).unwrap();
            let x = sim.coords(&sim.sol.u);
            let nodal = sim.nodal_contact().expect("two bodies: contact");
            for (b, y0) in [(0, 5.0), (1, 5.0 + lift)] {
                let body = &sim.model.bodies[b];
                let range = body.node_offset..body.node_offset + body.mesh.nodes.len();
                let mut side: Vec<usize> = range.filter(|&n| (sim.model.x0[n][1] - y0).abs() < 1e-9).collect();
                side.sort_by(|&m, &n| x[m][0].total_cmp(&x[n][0]));
                let p: Vec<f64> = side.iter().map(|&n| nodal.pressure[n]).collect();
                let mean = p.iter().sum::<f64>() / p.len() as f64;
                let spread = p.iter().map(|v| (v - mean).abs()).fold(0.0, f64::max) / mean;
                // tributary length along the interface: half of each interface edge at the node
                let mut length = vec![0.0; side.len()];
                for i in 1..side.len() {
                    let l = (x[side[i]][0] - x[side[i - 1]][0]).hypot(x[side[i]][1] - x[side[i - 1]][1]);
                    length[i - 1] += 0.5 * l;
                    length[i] += 0.5 * l;
                }
                let resultant: f64 = p.iter().zip(&length).map(|(p, l)| p * l).sum();
                let shear = side.iter().map(|&n| nodal.shear[n].abs()).fold(0.0, f64::max);
                eprintln!("patch {lower:?}/{upper:?} {method}, {} side: {} nodes, pressure {mean:.6} ± {spread:.2e}, resultant {resultant:.9} N/mm, largest |shear| {shear:.1e}", if b == 0 { "lower" } else { "upper" }, side.len());
                assert!(spread <= tol, "{method} {lower:?}/{upper:?} body {b}: pressures {p:?}");
                assert!((resultant - 10.0).abs() <= 1e-6 * 10.0, "{method} {lower:?}/{upper:?} body {b}: resultant {resultant}");
                assert!(shear <= 1e-3 * mean, "{method} {lower:?}/{upper:?} body {b}: frictionless, yet shear {shear}");
            }
        }
    }
}

/// The sliding contact patch test (issue 22): the upper block half as stiff (E = 500 against
/// 1,000, ν = 0.3), so that under the uniform load the blocks widen by different amounts and the
/// frictionless interface slides; the exact stress is still a uniform σ_yy = −1 MPa. The
/// barrier passes it to the same 1 % at every Gauss point (0.54 % measured), and its
/// `contact_pressure` field is uniform to 1 % on both sides (0.85 %); the node-to-segment
/// methods do not (largest deviation of an element's mean σ_yy, `mpfem run` on the same case:
/// penalty 11.7 %, augmented Lagrangian 10.0 %, Lagrange multipliers 10.0 %).
#[test]
fn contact_patch_test_sliding_barrier() {
    let text = std::fs::read_to_string("jobs/verification/contact_patch.toml").unwrap();
    let sliding = text
        .replacen("[[bodies]]\nname = \"lower\"", "[[materials]]\nname = \"soft\"\nmodel = \"elastic\"\nyoungs_modulus = 500.0\npoisson_ratio = 0.3\n\n[[bodies]]\nname = \"lower\"", 1)
        .replace("[[bodies]]\nname = \"upper\"\nmaterial = \"m\"", "[[bodies]]\nname = \"upper\"\nmaterial = \"soft\"")
        .replace("method = \"augmented_lagrangian\"\n", "method = \"barrier\"\n")
        .replace("penetration_tol = 1e-6\n", "")
        .replace("origin = [0.0, 5.0]", "origin = [0.0, 5.02]");
    assert!(sliding.contains("material = \"soft\"") && sliding.contains("method = \"barrier\"") && sliding.contains("[0.0, 5.02]"));
    contact_patch_test(sliding.clone(), "sliding, barrier");
    let c = case::parse(&sliding, std::path::Path::new("jobs/verification")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    sim.run(&mut |_, _| {}).unwrap();
    let nodal = sim.nodal_contact().unwrap();
    let p: Vec<f64> = nodal.pressure.iter().copied().filter(|&p| p > 0.1).collect();
    let mean = p.iter().sum::<f64>() / p.len() as f64;
    let spread = p.iter().map(|v| (v - mean).abs()).fold(0.0, f64::max) / mean;
    eprintln!("sliding patch test, barrier: {} loaded nodes, contact_pressure {mean:.5} ± {spread:.2e}", p.len());
    assert_eq!(p.len(), 8 + 6, "every node of the interface carries the load");
    assert!(spread <= 0.01, "pressures {p:?}");
}

fn contact_patch_test(text: String, label: &str) {
    let c = case::parse(&text, std::path::Path::new("jobs/verification")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    sim.run(&mut |_, _| {}).unwrap();
    let mut worst: f64 = 0.0;
    for e in &sim.sol.fields.sig {
        for g in e {
            worst = worst.max((g[1] + 1.0).abs());
        }
    }
    eprintln!("contact patch test ({label}): largest deviation of sigma_yy from -1 MPa = {worst:.3e}");
    assert!(worst < 0.01, "largest deviation of sigma_yy from -1 MPa: {worst}");
}

/// Tied contact: two stacked blocks with matching meshes, cohering, behave as one block (the
/// issue's criterion: displacements within 1e-6 relative). The augmented Lagrangian drives the
/// tie's gaps below 1e-10 of the element size.
#[test]
fn tied_blocks_behave_as_one_block() {
    tied_blocks_against_one_block(&std::fs::read_to_string("jobs/verification/tied_blocks.toml").unwrap(), "augmented Lagrangian");
}

/// The same with the barrier's ties: the blocks touch along their interface at the start,
/// every node there is tied at once, and the ties' multipliers are updated until their gaps
/// are below 1e-10 h (the same 1e-6 criterion against the single block).
#[test]
fn tied_blocks_behave_as_one_block_barrier() {
    let text = std::fs::read_to_string("jobs/verification/tied_blocks.toml")
        .unwrap()
        .replace("method = \"augmented_lagrangian\"", "method = \"barrier\"")
        .replace("penetration_tol = 1e-10\n", "")
        .replace("max_augmentations = 50\n", "");
    assert!(text.contains("method = \"barrier\""));
    tied_blocks_against_one_block(&text, "barrier");
}

fn tied_blocks_against_one_block(text: &str, label: &str) {
    let run = |text: &str| {
        let c = case::parse(text, std::path::Path::new("jobs/verification")).unwrap();
        let model = Model::from_case(&c).unwrap();
        let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
        sim.run(&mut |_, _| {}).unwrap();
        sim
    };
    let tied = run(text);
    // the same block in one piece: 5 x 6 elements, 10 x 10 mm
    let one = std::fs::read_to_string("jobs/verification/tied_blocks.toml")
        .unwrap()
        .split("[[bodies]]")
        .next()
        .unwrap()
        .to_string()
        + "[[bodies]]\nname = \"block\"\nmaterial = \"m\"\nmesh_size = 2.0\ndivisions = [5, 6]\nshape = { type = \"rectangle\", origin = [0.0, 0.0], size = [10.0, 10.0] }\n\n[[boundary]]\nbody = \"block\"\nset = \"bottom\"\nux = 0.0\nuy = 0.0\n\n[[loads]]\nbody = \"block\"\nset = \"top\"\ntype = \"traction\"\nvalue = [0.5, 1.0]\namplitude = \"ramp\"\n\n[time]\nend = 1.0\ndt = 0.5\n";
    let single = run(&one);
    // compare the displacement of every node of the single block with the tied node at the
    // same reference position
    let umax = single.sol.u.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let mut worst: f64 = 0.0;
    for (n, p) in single.model.x0.iter().enumerate() {
        let m = (0..tied.model.n_nodes())
            .min_by(|&a, &b| {
                let d = |k: usize| (tied.model.x0[k][0] - p[0]).powi(2) + (tied.model.x0[k][1] - p[1]).powi(2);
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        for c in 0..2 {
            worst = worst.max((single.sol.u[2 * n + c] - tied.sol.u[2 * m + c]).abs() / umax);
        }
    }
    eprintln!("tied blocks ({label}) vs one block: max |du| / max |u| = {worst:.3e}");
    assert!(worst < 1e-6, "tied blocks ({label}) differ from one block by {worst}");
}

/// The solves of a frictional step that precede a friction update stop early (at an
/// out-of-balance force of `LAG_FORCING` times the last change of μλ, src/solver/barrier.rs),
/// and only the last, with the friction settled, is converged to the solver's tolerance. The
/// step's end state must be the one the fully converged solves reach: the Coulomb block of
/// `coulomb_block_sticks_then_slides_at_mu_n_barrier` (its base sticking, then slipping from
/// its edges until the whole base slides) run both ways, every step of either converged to the
/// residual tolerance (1e-8), and the top's reactions of the two runs equal at every step to
/// 1e-4 of the largest (the lagging stops once no μλ moves by more than 1e-4 of the largest,
/// so two runs that reach the settled friction from different iterates may differ by that
/// order; measured: 1.3e-7). And the early stops must save Newton iterations over the run
/// (measured: 130 against 160, the sliding steps 6 each either way). (A regular grid of
/// particles is no case for this comparison: its symmetric path breaks where round-off
/// decides, docs/robustness.md, thirty-fifth and thirty-sixth measurements.)
#[test]
fn early_stopped_friction_solves_end_where_converged_ones_do() {
    let text = std::fs::read_to_string("jobs/verification/coulomb_block.toml").unwrap();
    assert!(text.contains("method = \"penalty\"\n"));
    let text = text.replace("method = \"penalty\"\n", "method = \"barrier\"\n");
    let run = |forcing: Option<f64>| {
        let c = case::parse(&text, std::path::Path::new("jobs/verification")).unwrap();
        let model = Model::from_case(&c).unwrap();
        let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
        if let Some(f) = forcing {
            sim.set_barrier_lag_forcing(f);
        }
        let mut rows = Vec::new();
        sim.run(&mut |_, r| rows.push((r.time, r.newton_iterations, r.residual, r.reactions[0]))).unwrap();
        rows
    };
    let early = run(None);
    let converged = run(Some(0.0));
    assert_eq!(early.len(), converged.len(), "the two runs took different steps");
    let rmax = converged.iter().map(|r| r.3[0].abs().max(r.3[1].abs())).fold(0.0, f64::max);
    assert!(rmax > 0.0, "the block carried no load");
    let mut worst: f64 = 0.0;
    for (a, b) in early.iter().zip(&converged) {
        eprintln!("t = {}: iterations {} / {}, reactions {:?} / {:?}", a.0, a.1, b.1, a.3, b.3);
        assert_eq!(a.0, b.0, "the two runs' steps differ in time");
        assert!(a.2 <= 1e-8 && b.2 <= 1e-8, "t = {}: relative residuals {} (early stops) and {} (converged solves)", a.0, a.2, b.2);
        for i in 0..2 {
            worst = worst.max((a.3[i] - b.3[i]).abs() / rmax);
        }
    }
    let its = |rows: &[(f64, usize, f64, [f64; 2])]| rows.iter().map(|r| r.1).sum::<usize>();
    let (n_early, n_converged) = (its(&early), its(&converged));
    eprintln!("{} steps; reactions apart by {worst:e} of the largest; Newton iterations {n_early} with early stops, {n_converged} without", early.len());
    assert!(worst <= 1e-4, "the reactions differ by {worst} of the largest");
    assert!(n_early < n_converged, "{n_early} Newton iterations with early stops, {n_converged} without");
}
