//! `[output] probes` (issue 22): named points whose displacement, Cauchy stress and equivalent
//! strains go to `probes.csv` every step.
//!
//! - Hill's thick-walled cylinder (`jobs/verification/thick_cylinder.toml`: a = 100 mm,
//!   b = 200 mm, incompressible, elastic–perfectly plastic, the bore driven outwards past the
//!   limit load): a probe at the outer radius follows the closed form u_b(p) of
//!   [`mpfem::analytical::hill::outer_displacement`] to 2 % (the tolerance) at every
//!   step up to 0.9 p_L, through first yield; beyond, where u_b(p) rises ever more steeply
//!   towards the limit, the pressure Hill gives for the probe's displacement, to 2 %. The mean displacement over the outer
//!   edge (`[output] displacements`) is not the displacement of any point there (0.9 of u_b
//!   on a quarter arc, 2√2/π), which is why probes exist.
//! - A node probe reads the node's displacement in `results.h5` exactly (`probes.csv` writes
//!   every number in full), and a point probe placed on a node reads it to round-off.
//! - Bad probes are refused with the key, the value and what was expected, exit code 2.

use mpfem::analytical::hill;
use mpfem::case;
use mpfem::model::Model;
use mpfem::output::{probe_columns, probe_values};
use mpfem::solver::Simulation;

mod common;
use common::{mpfem, root, tmpdir};

#[test]
fn a_probe_at_the_outer_radius_follows_hill() {
    let (a, b, sy, e) = (100.0, 200.0, 240.0, 210_000.0);
    let (k, g) = (sy / 3f64.sqrt(), e / 3.0);
    let r45 = b * std::f64::consts::FRAC_1_SQRT_2;
    let text = std::fs::read_to_string(root().join("jobs/verification/thick_cylinder.toml")).unwrap()
        + &format!("\n[output]\nprobes = [{{ name = \"outer45\", point = [{r45}, {r45}] }}, {{ name = \"outer0\", body = \"cylinder\", point = [{b}, 0.0] }}]\ndisplacements = [\"cylinder.outer\"]\n");
    let c = case::parse(&text, &root().join("jobs/verification")).unwrap();
    let model = Model::from_case(&c).unwrap();
    assert_eq!(probe_columns(&model)[2..4], ["outer45_x".to_string(), "outer45_y".to_string()]);
    let inner = model.bodies[0].mesh.node_set("inner").unwrap();
    let mut sim = Simulation::new(model, c.time.clone(), c.solver.clone()).unwrap();
    let mut rows = Vec::new();
    sim.run(&mut |s, r| {
        // the bore's pressure: the radial reactions of the bore's nodes over its current arc
        let x = s.coords(&s.sol.u);
        let force: f64 = inner.iter().map(|&n| {
            let rr = s.nodal_reaction(n);
            (rr[0] * x[n][0] + rr[1] * x[n][1]) / x[n][0].hypot(x[n][1])
        }).sum();
        let mut pts: Vec<[f64; 2]> = inner.iter().map(|&n| x[n]).collect();
        pts.sort_by(|p, q| p[1].atan2(p[0]).total_cmp(&q[1].atan2(q[0])));
        let arc: f64 = pts.windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).sum();
        rows.push((force / arc, probe_values(&s.snapshot()), r.displacements[0]));
    })
    .unwrap();
    // u_b(p) up to 0.9 p_L; beyond, u_b(p) rises so steeply (dp/du_b → 0 at the limit) that the
    // test turns round: the pressure Hill gives for the probe's displacement, to the same 2 %
    let pl = hill::limit_pressure(a, b, k);
    let (mut worst_u, mut worst_p, mut plastic) = (0.0f64, 0.0f64, 0);
    for (p, v, mean) in &rows {
        let ub = hill::outer_displacement(*p, a, b, k, g);
        // the radial displacement at 45° and at 0° (its x component there)
        let u45 = (v[2] + v[3]) * std::f64::consts::FRAC_1_SQRT_2;
        let u0 = v[10 + 2];
        for u in [u45, u0] {
            if *p <= 0.9 * pl {
                worst_u = worst_u.max((u / ub - 1.0).abs());
                assert!((u / ub - 1.0).abs() <= 0.02, "p = {p:.2} MPa: probe u_b = {u:.6} mm, Hill {ub:.6} mm");
            } else {
                let ph = hill::pressure_for_outer_displacement(u, a, b, k, g);
                worst_p = worst_p.max((p / ph - 1.0).abs());
                assert!((p / ph - 1.0).abs() <= 0.02, "probe u_b = {u:.6} mm: p = {p:.2} MPa, Hill {ph:.2} MPa");
            }
        }
        // the probe's position is its reference point plus its displacement
        assert!((v[0] - (r45 + v[2])).abs() < 1e-9 && (v[1] - (r45 + v[3])).abs() < 1e-9);
        if *p > hill::first_yield_pressure(a, b, k) {
            plastic += 1;
        }
        // the edge set's mean is not a point's: its radial part is 2√2/π of u_b on the arc
        let mean_r = (mean[0] * mean[0] + mean[1] * mean[1]).sqrt();
        assert!(mean_r < 0.95 * u45, "mean {mean_r} vs probe {u45}");
    }
    eprintln!("Hill cylinder: {} steps ({plastic} past first yield), largest |u_probe / u_b(p) − 1| = {worst_u:.2e} up to 0.9 p_L, |p / p(u_probe) − 1| = {worst_p:.2e} beyond", rows.len());
    assert!(plastic >= rows.len() / 2, "the wall must go well into the plastic range: {plastic} of {} steps", rows.len());
}

/// The CLI writes `probes.csv`: a node probe's displacement is the node's in `results.h5`
/// to the bit, a point probe on the same node's reference position equals it to 1e-12 mm, and
/// the rows follow the history's steps.
#[test]
fn a_node_probe_reads_results_h5_exactly() {
    let dir = tmpdir("node_probe");
    let case = std::fs::read_to_string(root().join("jobs/verification/coulomb_block.toml")).unwrap()
        + "probes = [{ name = \"corner\", body = \"block\", node = 5 }, { name = \"mid\", point = [4.0, 4.0] }]\n";
    assert!(case.contains("[output]\nreactions = [\"block.top\"]\nprobes"), "the probes must go into [output]");
    let path = dir.join("case.toml");
    std::fs::write(&path, &case).unwrap();
    let out = dir.join("out");
    let st = mpfem().args(["run", "--quiet", "--no-plots", "--out"]).arg(&out).arg(&path).status().unwrap();
    assert!(st.success());
    let text = std::fs::read_to_string(out.join("probes.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.len(), 2 + 2 * 10);
    assert_eq!(&header[..6], &["step", "time", "corner_x", "corner_y", "corner_ux", "corner_uy"]);
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    assert_eq!(rows.len(), history.lines().count() - 1, "one probe row per history row");
    let last = rows.last().unwrap();
    // the node's displacement in the last output step of results.h5
    let file = hdf5::File::open(out.join("results.h5")).unwrap();
    let steps = file.group("steps").unwrap();
    let mut names = steps.member_names().unwrap();
    names.sort();
    let g = steps.group(names.last().unwrap()).unwrap();
    let time: f64 = g.attr("time").unwrap().read_scalar().unwrap();
    assert_eq!(time, last[1]);
    let u: Vec<f64> = g.dataset("displacement").unwrap().read_raw().unwrap();
    let x0: Vec<f64> = g.dataset("coordinates").unwrap().read_raw().unwrap();
    assert_eq!([last[4], last[5]], [u[3 * 5], u[3 * 5 + 1]], "node probe vs results.h5");
    assert_eq!([last[2], last[3]], [x0[2 * 5], x0[2 * 5 + 1]], "node probe position vs results.h5 coordinates");
    // the mid probe: at (4, 4), a node of the block's 5 × 5 mesh
    let centre = (0..x0.len() / 2).find(|&n| (x0[2 * n] - u[3 * n] - 4.0).abs() < 1e-9 && (x0[2 * n + 1] - u[3 * n + 1] - 4.0).abs() < 1e-9).expect("a node at (4, 4)");
    assert!((last[14] - u[3 * centre]).abs() < 1e-12 && (last[15] - u[3 * centre + 1]).abs() < 1e-12, "point probe {:?} vs node {:?}", &last[14..16], &u[3 * centre..3 * centre + 2]);
    // pressed and pushed: the block carries stress at the probes
    assert!(last[2 + 5] < 0.0 && last[12 + 5] < 0.0, "σ_yy at the probes: {} {}", last[7], last[17]);
}

#[test]
fn bad_probes_are_refused_with_the_key() {
    let dir = tmpdir("bad_probes");
    let base = std::fs::read_to_string(root().join("jobs/verification/coulomb_block.toml")).unwrap();
    for (probes, key, says) in [
        ("{ name = \"p\", point = [50.0, 5.0] }", "output.probes[0].point", "expected a point inside a particle"),
        ("{ name = \"p\", body = \"block\", node = 1000 }", "output.probes[0].node", "expected a node of body \"block\""),
        ("{ name = \"p\", point = [1.0, 1.0], body = \"block\", node = 2 }", "output.probes[0].node", "not both"),
        ("{ name = \"p\", node = 2 }", "output.probes[0].body", "missing"),
        ("{ name = \"p\", point = [1.0, 1.0] }, { name = \"p\", point = [2.0, 2.0] }", "output.probes[1].name", "already defined"),
        ("{ name = \"a b\", point = [1.0, 1.0] }", "output.probes[0].name", "letters, digits"),
        ("{ point = [1.0, 1.0] }", "output.probes[0].name", "missing"),
        ("{ name = \"p\", body = \"nope\", point = [1.0, 1.0] }", "output.probes[0].body", "no body named"),
        ("{ name = \"p\" }", "output.probes[0].point", "missing"),
    ] {
        let path = dir.join("bad.toml");
        std::fs::write(&path, format!("{base}probes = [{probes}]\n")).unwrap();
        let o = mpfem().args(["run", "--quiet", "--no-plots", "--out"]).arg(dir.join("out")).arg(&path).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{probes}: exit code, stderr {err}");
        assert!(err.contains(key) && err.contains(says), "{probes}: stderr {err:?} should name {key} and say {says:?}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// A particle that holds a probe is not re-meshed (its point would lose its element), and a
/// re-mesh of another particle renumbers the elements after it: the probe keeps its element's
/// reference corners and its local coordinates.
#[test]
fn probes_hold_their_particle_and_follow_a_renumbering() {
    let text = std::fs::read_to_string(root().join("tests/data/die_wall_friction.toml")).unwrap() + "\n[output]\nprobes = [{ name = \"d3\", point = [75.0, 75.0] }]\n";
    let c = case::parse(&text, &root().join("tests/data")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let holder = |m: &Model| match &m.probes[0].at {
        mpfem::model::ProbeAt::Point { element, xi } => (m.elem_body[*element], m.elements[*element].map(|n| m.x0[n]), *xi),
        other => panic!("{other:?}"),
    };
    let (body, corners, xi) = holder(&model);
    assert_eq!(body, 3, "the probe at (75, 75) lies in the fourth disc");
    assert_eq!(model.remesh_constraint(3), Some("probes"));
    assert_eq!(model.remesh_constraint(0), None);
    // the first disc meshed twice as fine: every later element moves
    let mut spec = c.bodies[0].clone();
    spec.mesh_size *= 0.5;
    let finer = case::mesh_body(&spec).unwrap();
    assert!(finer.elements.len() > model.bodies[0].mesh.elements.len());
    let new = model.with_body_mesh(0, finer).unwrap();
    assert_eq!(holder(&new), (body, corners, xi));
}

/// A whole model's frame (`Model::frame`: the model without its meshes, its loads, output
/// groups and probes in their bodies' own numbering — what rank 0 of a run on owned + ghost
/// parts keeps for the output, issue 21) takes the bodies' meshes back into the very same
/// model; with a re-meshed body's new mesh, into the model `with_body_mesh` makes (every later
/// node and element renumbered). Compared in full through their `Debug` forms, which print
/// every float in full.
#[test]
fn a_model_frame_takes_its_meshes_back() {
    let same = |a: &Model, b: &Model| format!("{a:?}") == format!("{b:?}");
    let ghosts = |m: &Model| (0..m.bodies.len()).map(|k| m.ghost_body(k)).collect::<Vec<_>>();
    // a traction, prescribed displacements, both kinds of output group and of probe, on two
    // bodies
    let text = std::fs::read_to_string(root().join("jobs/verification/contact_patch.toml")).unwrap()
        + "\n[output]\nreactions = [\"lower.bottom\"]\ndisplacements = [\"upper.top\"]\nprobes = [{ name = \"p\", point = [5.0, 2.5] }, { name = \"n\", body = \"upper\", node = 3 }]\n";
    let c = case::parse(&text, &root().join("jobs/verification")).unwrap();
    let model = Model::from_case(&c).unwrap();
    assert!(!model.loading.loads[0].edges.is_empty() && !model.loading.prescribed.is_empty());
    assert_eq!((model.reaction_groups.len(), model.displacement_groups.len(), model.probes.len()), (1, 1, 2));
    let frame = model.frame().expect("a whole model has a frame");
    assert_eq!(frame.n_bodies(), 2);
    assert!(same(&frame.assemble(ghosts(&model)).unwrap(), &model), "the contact patch's frame with its meshes is not the model");

    // discs with probes in the fourth (a point and a node), the first re-meshed finer
    let text = std::fs::read_to_string(root().join("tests/data/die_wall_friction.toml")).unwrap()
        + "\n[output]\nprobes = [{ name = \"d3\", point = [75.0, 75.0] }, { name = \"n3\", body = \"g0_p3\", node = 5 }]\n";
    let c = case::parse(&text, &root().join("tests/data")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let frame = model.frame().unwrap();
    let mut spec = c.bodies[0].clone();
    spec.mesh_size *= 0.5;
    let remeshed = model.with_body_mesh(0, case::mesh_body(&spec).unwrap()).unwrap();
    assert_ne!(remeshed.x0.len(), model.x0.len());
    assert!(same(&frame.assemble(ghosts(&remeshed)).unwrap(), &remeshed), "the discs' frame with a re-meshed disc is not with_body_mesh's model");

    // another number of bodies is refused; a part has no frame
    assert!(frame.assemble(ghosts(&model)[..3].to_vec()).is_err());
    assert!(model.part(&[0, 1], 1).unwrap().0.frame().is_none());
}
