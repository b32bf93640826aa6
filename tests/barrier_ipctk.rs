//! The barrier contact against the reference implementation: the IPC toolkit's Python bindings
//! (`ipctk` 1.6.1, installed by `scripts/setup.sh`), called through `python3` and
//! `tests/python/ipctk_barrier.py`. On four 2D configurations — two particles' boundaries near
//! each other, a particle on a wall that moves, a dense cluster of nine particles, and two
//! octagons whose flat sides face node to node (every node within d̂ of a vertex) — mpfem's
//! [`BarrierContact`] and `ipctk` compute
//! - the number of point–edge pairs closer than d̂ less the corner corrections (ipctk's
//!   collisions with the improved max approximator, counted by their weights): equal;
//! - the barrier energy Σ κ b(d², d̂²): equal to 1e-10 relative;
//! - its gradient: equal to 1e-10 relative to its largest entry;
//! - the collision-free step of a motion that makes the boundaries collide: mpfem's exact first
//!   time of impact t* and ipctk's step t_ipc satisfy 0.8 t* ≤ t_ipc ≤ t* (ipctk's conservative
//!   rescaling, `TightInclusionCCD.DEFAULT_CONSERVATIVE_RESCALING` = 0.8, is the documented
//!   margin; 1e-6 relative slack for its tolerance), and mpfem's own step is 0.8 t*.
//!
//! The test fails, not skips, when `python3` or `ipctk` is missing.

mod common;

use mpfem::contact::barrier::CCD_RESCALING;
use mpfem::contact::barrier_problem::{BarrierContact, BarrierEval};
use mpfem::contact::{Segment, Wall};
use mpfem::packing::regular_polygon;
use std::process::Command;

/// Particles (closed polygons, counter-clockwise: the body on the left of each edge) and at
/// most one wall, at t = 0 and after a motion.
struct Config {
    name: &'static str,
    polygons: Vec<Vec<[f64; 2]>>,
    moved: Vec<Vec<[f64; 2]>>,
    /// Wall through `point` with `normal` into the domain, and its advance along the normal.
    wall: Option<(Wall, f64)>,
    dhat: f64,
    kappa: f64,
}

struct Reference {
    energy: f64,
    gradient: Vec<f64>,
    step: f64,
    pairs: f64,
}

fn flatten(polys: &[Vec<[f64; 2]>]) -> (Vec<[f64; 2]>, Vec<Segment>, Vec<(usize, usize)>) {
    let mut x = Vec::new();
    let mut segments = Vec::new();
    let mut nodes = Vec::new();
    for (b, poly) in polys.iter().enumerate() {
        let off = x.len();
        for k in 0..poly.len() {
            segments.push(Segment { body: b, nodes: [off + k, off + (k + 1) % poly.len()] });
            nodes.push((off + k, b));
        }
        x.extend_from_slice(poly);
    }
    (x, segments, nodes)
}

/// ipctk's values: the wall becomes one long edge of its own body (its two vertices moving with
/// the wall).
fn reference(c: &Config) -> Reference {
    let (mut x0, segments, _) = flatten(&c.polygons);
    let (mut x1, _, _) = flatten(&c.moved);
    let mut edges: Vec<[usize; 2]> = segments.iter().map(|s| s.nodes).collect();
    let mut body: Vec<usize> = segments.iter().map(|s| s.body).collect();
    if let Some((w, shift)) = c.wall {
        let t = [-w.normal[1], w.normal[0]];
        let n = x0.len();
        for s in [-50.0, 50.0] {
            let p = [w.point[0] + s * t[0], w.point[1] + s * t[1]];
            x0.push(p);
            x1.push([p[0] + shift * w.normal[0], p[1] + shift * w.normal[1]]);
            body.push(c.polygons.len());
        }
        edges.push([n, n + 1]);
    }
    let dir = common::tmpdir(c.name);
    let input = serde_json::json!({
        "vertices": x0, "vertices_t1": x1, "edges": edges, "body": body,
        "dhat": c.dhat, "kappa": c.kappa,
    });
    std::fs::write(dir.join("in.json"), input.to_string()).unwrap();
    let script = common::root().join("tests/python/ipctk_barrier.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(dir.join("in.json"))
        .arg(dir.join("out.json"))
        .output()
        .unwrap_or_else(|e| panic!("python3 is needed for this test (run scripts/setup.sh): {e}"));
    assert!(
        out.status.success(),
        "{} failed (is ipctk installed? `pip install ipctk==1.6.1`, done by scripts/setup.sh):\n{}",
        script.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("out.json")).unwrap()).unwrap();
    assert_eq!(v["version"], "1.6.1", "the reference values are those of ipctk 1.6.1");
    assert_eq!(v["conservative_rescaling"].as_f64(), Some(CCD_RESCALING));
    Reference {
        energy: v["energy"].as_f64().unwrap(),
        gradient: v["gradient"].as_array().unwrap().iter().map(|g| g.as_f64().unwrap()).collect(),
        step: v["step"].as_f64().unwrap(),
        pairs: v["pairs"].as_f64().unwrap(),
    }
}

/// Compares, and returns how many corner corrections mpfem made.
fn compare(c: &Config) -> usize {
    let r = reference(c);
    let (x0, segments, nodes) = flatten(&c.polygons);
    let (x1, _, _) = flatten(&c.moved);
    let walls0: Vec<Wall> = c.wall.iter().map(|(w, _)| *w).collect();
    let walls1: Vec<Wall> = c.wall.iter().map(|(w, s)| Wall { point: [w.point[0] + s * w.normal[0], w.point[1] + s * w.normal[1]], normal: w.normal }).collect();
    let mut contact = BarrierContact::new(segments, nodes, c.dhat, c.kappa);
    let mut eval = BarrierEval::default();
    contact.evaluate(&x0, &walls0, false, &mut eval).expect("the configuration is free of intersections");
    let pairs = eval.edges.len() + eval.cancelled + eval.walls.len();
    assert!(pairs >= 3, "{}: only {pairs} pairs within d̂, the comparison would be weak", c.name);
    assert_eq!((pairs - eval.corners) as f64, r.pairs, "{}: pairs within d̂ less the corner corrections", c.name);
    assert!((eval.energy - r.energy).abs() <= 1e-10 * r.energy.abs(), "{}: energy {} against ipctk {}", c.name, eval.energy, r.energy);
    let mut g = vec![0.0; 2 * x0.len()];
    eval.add_gradient(&mut g);
    let scale = r.gradient.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(scale > 0.0);
    for (i, (a, b)) in g.iter().zip(&r.gradient).enumerate() {
        assert!((a - b).abs() <= 1e-10 * scale, "{}: gradient[{i}] {a} against ipctk {b}", c.name);
    }
    // the step: both collision-free, within the documented margin of each other
    let step = contact.collision_free_step(&x0, &x1, &walls0, &walls1);
    assert!(step < CCD_RESCALING, "{}: the motion should collide (step {step})", c.name);
    let toi = step / CCD_RESCALING;
    assert!(r.step <= toi * (1.0 + 1e-6), "{}: ipctk's step {} beyond mpfem's time of impact {toi}", c.name, r.step);
    assert!(r.step >= CCD_RESCALING * toi * (1.0 - 1e-6), "{}: ipctk's step {} below 0.8 × mpfem's time of impact {toi}", c.name, r.step);
    eprintln!("{}: {pairs} pairs, {} corner corrections, energy {:.6e} (ipctk {:.6e}), t* {toi:.6} (ipctk step {:.6})", c.name, eval.corners, eval.energy, r.energy, r.step);
    eval.corners
}

/// Rigid motion of a polygon: rotation by `angle` about its centroid, then translation.
fn moved(poly: &[[f64; 2]], shift: [f64; 2], angle: f64) -> Vec<[f64; 2]> {
    let n = poly.len() as f64;
    let c = [poly.iter().map(|p| p[0]).sum::<f64>() / n, poly.iter().map(|p| p[1]).sum::<f64>() / n];
    let (s, co) = angle.sin_cos();
    poly.iter()
        .map(|p| {
            let r = [p[0] - c[0], p[1] - c[1]];
            [c[0] + co * r[0] - s * r[1] + shift[0], c[1] + s * r[0] + co * r[1] + shift[1]]
        })
        .collect()
}

#[test]
fn two_particles_near_each_other() {
    let a = regular_polygon([0.0, 0.0], 1.0, 24, 0.0);
    let b = regular_polygon([2.02, 0.31], 1.0, 24, 0.07);
    let c = Config {
        name: "two_particles",
        moved: vec![moved(&a, [0.01, 0.0], 0.02), moved(&b, [-0.12, -0.03], -0.05)],
        polygons: vec![a, b],
        wall: None,
        dhat: 0.1,
        kappa: 1.0e3,
    };
    compare(&c);
}

#[test]
fn a_particle_on_a_moving_wall() {
    // a flat bottom edge (vertices at −90° ± 7.5°), tilted by 0.01 rad, 0.01–0.02 mm above the
    // wall: four nodes within d̂
    let p = regular_polygon([0.0, 1.0], 1.0, 24, std::f64::consts::PI / 24.0 + 0.01);
    let c = Config {
        name: "particle_on_wall",
        moved: vec![moved(&p, [0.02, -0.03], 0.03)],
        polygons: vec![p],
        wall: Some((Wall { point: [0.0, 0.0], normal: [0.0, 1.0] }, 0.06)),
        dhat: 0.1,
        kappa: 2.0e4,
    };
    compare(&c);
}

#[test]
fn a_dense_cluster_of_nine_particles() {
    // deterministic jitter (a linear congruential sequence): radii 0.95–1.05, spacing 2.12, so
    // every gap is at least 0.02 and many are below d̂
    let mut seed: u64 = 12345;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut polygons = Vec::new();
    let mut motion = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            let c = [2.12 * i as f64, 2.12 * j as f64];
            let r = 0.95 + 0.1 * rnd();
            polygons.push(regular_polygon(c, r, 20, rnd()));
            // towards the middle particle, with a small rotation
            motion.push(([0.1 * (1.0 - i as f64) + 0.01 * rnd(), 0.1 * (1.0 - j as f64) - 0.01 * rnd()], 0.02 * (rnd() - 0.5)));
        }
    }
    let c = Config {
        name: "dense_cluster",
        moved: polygons.iter().zip(&motion).map(|(p, (s, a))| moved(p, *s, *a)).collect(),
        polygons,
        wall: None,
        dhat: 0.15,
        kappa: 5.0e2,
    };
    compare(&c);
}

#[test]
fn octagons_facing_node_to_node() {
    // two octagons with a flat side each facing the other (the octagon grids' contacts), the
    // sides split into four edges so that nodes face vertices, 0.004 apart (d̂ = 0.01): every
    // node of the two sides is within d̂ of a vertex of the other, the case the corner
    // correction is for. The second is shifted along the side by 0.002 so that the nodes face
    // the vertices off their normal lines, and moves onto the first with a small rotation.
    let side = |c: [f64; 2]| -> Vec<[f64; 2]> {
        let oct = regular_polygon(c, 1.0, 8, std::f64::consts::PI / 8.0);
        // each edge split into four
        let mut out = Vec::new();
        for k in 0..8 {
            let (a, b) = (oct[k], oct[(k + 1) % 8]);
            for j in 0..4 {
                let t = j as f64 / 4.0;
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        out
    };
    let w = 2.0 * (std::f64::consts::PI / 8.0).cos();
    let a = side([0.0, 0.0]);
    let b = side([w + 0.004, 0.002]);
    let c = Config {
        name: "octagons_node_to_node",
        moved: vec![moved(&a, [0.002, 0.0], 0.0), moved(&b, [-0.01, 0.0], 0.01)],
        polygons: vec![a, b],
        wall: None,
        dhat: 0.01,
        kappa: 1.0e7,
    };
    let corners = compare(&c);
    assert!(corners >= 10, "{corners} corner corrections: the facing sides' nodes should face vertices");
}
