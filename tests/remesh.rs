//! Re-meshing building blocks end to end, through the public API only: a hexagonal particle
//! meshed by `shapes::convex_polygon`, deformed by a swirl that vanishes on its boundary (plus
//! an affine map), until the quality monitor asks for a new mesh; the new mesh is built by the
//! same mesher on the deformed boundary polygon (a stand-in for the polygon mesher of
//! `mesh::polygon`), and the material history is carried over.

use mpfem::material::logstrain::{self, Spectral};
use mpfem::material::MatState;
use mpfem::mesh::{shapes, Mesh};
use mpfem::remesh::{self, FieldTransfer, NodalField, QualityLimits, QuadField};
use nalgebra::Matrix3;
use std::f64::consts::PI;

/// Regular hexagon of circumradius 1 about the origin (turned by 0.1 rad).
fn hexagon() -> Vec<[f64; 2]> {
    (0..6).map(|k| {
        let t = PI / 3.0 * k as f64 + 0.1;
        [t.cos(), t.sin()]
    })
    .collect()
}

/// Product of the normalised distances to the six sides: 1 at the centre, 0 on the boundary.
fn bubble(p: [f64; 2]) -> f64 {
    let d = (PI / 6.0).cos();
    (0..6)
        .map(|k| {
            let t = PI / 3.0 * (k as f64 + 0.5) + 0.1;
            (d - (t.cos() * p[0] + t.sin() * p[1])) / d
        })
        .product()
}

/// The deformation: a swirl of amplitude `amp` that vanishes on the boundary, then an affine
/// shear/compression. Boundary points move affinely, so the deformed boundary is a hexagon.
fn deform(p: [f64; 2], amp: f64) -> [f64; 2] {
    let b = amp * bubble(p);
    let (c, s) = (b.cos(), b.sin());
    let u = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
    [1.1 * u[0] + 0.25 * u[1] + 0.3, -0.05 * u[0] + 0.8 * u[1] - 0.2]
}

/// The corners of the boundary polygon of `mesh` in the coordinates `x`: boundary edges
/// chained counter-clockwise, collinear vertices dropped.
fn boundary_corners(mesh: &Mesh, x: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let next: std::collections::HashMap<usize, usize> = mesh.boundary.iter().map(|e| (e[0], e[1])).collect();
    let start = mesh.boundary[0][0];
    let mut chain = vec![start];
    let mut n = next[&start];
    while n != start {
        chain.push(n);
        n = next[&n];
    }
    let m = chain.len();
    (0..m)
        .filter(|&i| {
            let (a, b, c) = (x[chain[(i + m - 1) % m]], x[chain[i]], x[chain[(i + 1) % m]]);
            let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
            let cr = u[0] * v[1] - u[1] * v[0];
            cr.abs() > 1e-9 * (u[0].hypot(u[1]) * v[0].hypot(v[1]))
        })
        .map(|i| x[chain[i]])
        .collect()
}

/// Swirl of the pipeline test: strong enough for the monitor (defaults) to fire at h = 0.1,
/// while every element stays valid.
const SWIRL: f64 = 1.6;
/// Milder swirl of the convergence study, whose coarsest mesh (h = 0.2) must stay valid.
const SWIRL_STUDY: f64 = 1.2;

struct Setup {
    old: Mesh,
    x_old: Vec<[f64; 2]>,
    new: Mesh,
}

fn setup(h_old: f64, h_new: f64, swirl: f64) -> Setup {
    let old = shapes::convex_polygon(&hexagon(), h_old).unwrap();
    let x_old: Vec<[f64; 2]> = old.nodes.iter().map(|&p| deform(p, swirl)).collect();
    let corners = boundary_corners(&old, &x_old);
    assert_eq!(corners.len(), 6, "the deformed boundary is a hexagon");
    let new = shapes::convex_polygon(&corners, h_new).unwrap();
    Setup { old, x_old, new }
}

/// The monitor fires on the swirled mesh and not on the new one; the area is kept (1e-12
/// relative: both meshes tile the same hexagon, round-off of ~10³ shoelace terms); every new
/// Gauss point lies inside the old mesh and new boundary nodes on its boundary (1e-12 mm); a
/// linear field moves exactly (1e-10 relative, as in the unit tests).
#[test]
fn swirled_hexagon_is_remeshed_and_fields_move() {
    let s = setup(0.1, 0.07, SWIRL);
    let lim = QualityLimits::default();
    let before = remesh::check_quality(&s.old, &s.old.nodes, &lim).unwrap();
    assert!(!before.needs_remesh, "{before:?}");
    let q_old = remesh::check_quality(&s.old, &s.x_old, &lim).unwrap();
    assert!(q_old.needs_remesh, "{q_old:?}");
    assert!(q_old.scaled_jacobian.value > 0.0, "still valid: {q_old:?}");
    let q_new = remesh::check_quality(&s.new, &s.new.nodes, &lim).unwrap();
    assert!(!q_new.needs_remesh, "{q_new:?}");

    let a = remesh::area_check(&s.old, &s.x_old, &s.new, &s.new.nodes).unwrap();
    assert!(a.relative_change.abs() < 1e-12, "{a:?}");

    let mut t = FieldTransfer::new(&s.old, &s.x_old, &s.new, &s.new.nodes).unwrap();
    assert_eq!(t.quadrature_stats().n_outside, 0);
    assert!(t.node_stats().max_distance < 1e-12, "{:?}", t.node_stats());

    let lin = |p: [f64; 2], o: &mut [f64]| o[0] = 1.0 + 2.0 * p[0] - 3.0 * p[1];
    let f_old = QuadField::from_fn(&remesh::quadrature_points(&s.old, &s.x_old).unwrap(), 1, lin);
    let f_new = t.quadrature_field(&f_old).unwrap();
    let exact = QuadField::from_fn(&remesh::quadrature_points(&s.new, &s.new.nodes).unwrap(), 1, lin);
    let scale = exact.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let err = f_new.values.iter().zip(&exact.values).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(err < 1e-10 * scale, "linear field error {err:e}");
    let n_new = t.nodal_field(&NodalField::from_fn(&s.x_old, 1, lin)).unwrap();
    let n_exact = NodalField::from_fn(&s.new.nodes, 1, lin);
    let err = n_new.values.iter().zip(&n_exact.values).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(err < 1e-10 * scale, "nodal linear field error {err:e}");
}

/// A prescribed elastic strain field ε(x) (spatial, smooth) and plastic strain ε̄ᵖ(x): the old
/// states hold it as C_p⁻¹ = F⁻¹ exp(2ε) F⁻ᵀ with the old total F (large: the swirl). After the
/// transfer, the new states (F = I) must give τ′ = 2G dev ε(x) at the new Gauss points.
fn strain(p: [f64; 2]) -> [f64; 4] {
    [0.02 * (p[0] + 0.5 * p[1]).sin(), -0.015 * (1.5 * p[1]).cos(), 0.01 * p[0] * p[1], 0.005 * p[0]]
}

fn eps_p(p: [f64; 2]) -> f64 {
    0.1 + 0.05 * p[0] * p[0]
}

const G: f64 = 26_923.0;

/// Relative L2 errors (over the new Gauss points, equal weights) of τ′ and of ε̄ᵖ after the
/// transfer; with `push_forward = false` the old C_p⁻¹ is transferred as if it were b_e (the
/// mistake the push-forward avoids).
fn state_errors(h_old: f64, h_new: f64, push_forward: bool) -> (f64, f64) {
    let s = setup(h_old, h_new, SWIRL_STUDY);
    let gp_old = remesh::quadrature_points(&s.old, &s.x_old).unwrap();
    let mut states = vec![[MatState::default(); 4]; s.old.n_elements()];
    for (e, el) in s.old.elements.iter().enumerate() {
        let (p0, p) = (el.map(|n| s.old.nodes[n]), el.map(|n| s.x_old[n]));
        for (q, gp) in mpfem::element::GAUSS.iter().enumerate() {
            let f = remesh::deformation_gradient(&p0, &p, *gp).unwrap();
            let ff = Matrix3::new(f[0][0], f[0][1], 0.0, f[1][0], f[1][1], 0.0, 0.0, 0.0, 1.0);
            let eps = strain(gp_old[4 * e + q]);
            let sp = Spectral::of(&eps);
            let be = sp.compose([(2.0 * sp.lam[0]).exp(), (2.0 * sp.lam[1]).exp(), (2.0 * sp.lam[2]).exp()]);
            states[e][q] = MatState { cp_inv: logstrain::cp_inv_from_be(&ff, &be), eps_p: eps_p(gp_old[4 * e + q]), eps_c: 0.0 };
        }
    }
    let field = if push_forward {
        remesh::states_to_field(&s.old, &s.old.nodes, &s.x_old, &states).unwrap()
    } else {
        let identity: Vec<[f64; 2]> = s.old.nodes.clone();
        remesh::states_to_field(&s.old, &s.old.nodes, &identity, &states).unwrap()
    };
    let mut t = FieldTransfer::new(&s.old, &s.x_old, &s.new, &s.new.nodes).unwrap();
    let new_states = remesh::states_from_field(&t.quadrature_field(&field).unwrap()).unwrap();
    let gp_new = remesh::quadrature_points(&s.new, &s.new.nodes).unwrap();
    let (mut e_tau, mut n_tau, mut e_p, mut n_p) = (0.0, 0.0, 0.0, 0.0);
    for (i, st) in new_states.iter().flatten().enumerate() {
        let r = logstrain::exponential_map_update(&Matrix3::identity(), &st.cp_inv, G, |_| Ok((0.0, f64::INFINITY))).unwrap();
        let exact = logstrain::dev(&strain(gp_new[i])).map(|v| 2.0 * G * v);
        e_tau += logstrain::ddot(&[r.tau[0] - exact[0], r.tau[1] - exact[1], r.tau[2] - exact[2], r.tau[3] - exact[3]], &[r.tau[0] - exact[0], r.tau[1] - exact[1], r.tau[2] - exact[2], r.tau[3] - exact[3]]);
        n_tau += logstrain::ddot(&exact, &exact);
        e_p += (st.eps_p - eps_p(gp_new[i])).powi(2);
        n_p += eps_p(gp_new[i]).powi(2);
    }
    ((e_tau / n_tau).sqrt(), (e_p / n_p).sqrt())
}

/// Convergence of the transferred stress and plastic strain for h, h/2, h/4 (old h = 0.2, 0.1,
/// 0.05, the middle one with 294 elements; new h = 0.75 × old), measured:
///
/// | old h | rel. L2 error τ′ | rate | rel. L2 error ε̄ᵖ | rate |
/// |-------|------------------|------|------------------|------|
/// | 0.2   | 3.21e-3          |      | 1.88e-3          |      |
/// | 0.1   | 1.06e-3          | 1.60 | 6.41e-4          | 1.55 |
/// | 0.05  | 3.00e-4          | 1.82 | 1.85e-4          | 1.79 |
///
/// i.e. approaching second order (the coarse swirled meshes are pre-asymptotic). Asserted:
/// rates ≥ 1.4 (first order is the requirement; the values are deterministic). Without the
/// push-forward (old C_p⁻¹ transferred as if it were b_e) the stress error is 48.8 (4877 %):
/// asserted > 0.5.
#[test]
fn nonuniform_state_transfer_converges() {
    let e: Vec<(f64, f64)> = [(0.2, 0.15), (0.1, 0.075), (0.05, 0.0375)].iter().map(|&(a, b)| state_errors(a, b, true)).collect();
    let rate = |a: f64, b: f64| (a / b).log2();
    let r_tau = [rate(e[0].0, e[1].0), rate(e[1].0, e[2].0)];
    let r_p = [rate(e[0].1, e[1].1), rate(e[1].1, e[2].1)];
    assert!(r_tau.iter().chain(&r_p).all(|&r| r >= 1.4), "errors {e:?}, stress rates {r_tau:?}, eps_p rates {r_p:?}");
    assert!(e[2].0 < 1e-2 && e[2].1 < 1e-3, "{e:?}");
    let wrong = state_errors(0.05, 0.0375, false);
    assert!(wrong.0 > 0.5, "without the push-forward the stress is wrong by O(1): {wrong:?}");
}

/// The nodes of `mesh` with a dent (points near x = +10 pushed in by up to 3 mm, smoothly, as
/// a neighbour's corner would) and then the linear map `a` (rows).
fn dented(mesh: &Mesh, a: [[f64; 2]; 2]) -> Vec<[f64; 2]> {
    mesh.nodes
        .iter()
        .map(|p| {
            let push = 3.0 * (-(p[1] / 3.0).powi(2)).exp() * (p[0] / 10.0).max(0.0).powi(4);
            let q = [p[0] - push, p[1]];
            [a[0][0] * q[0] + a[0][1] * q[1], a[1][0] * q[0] + a[1][1] * q[1]]
        })
        .collect()
}

/// `remesh::remesh_particle` on a disc deformed into a non-convex, badly distorted shape (a
/// dent pushed into one side, as a neighbour's corner would, then sheared by 2.5 and squashed
/// to 0.6 of its height): the monitor asks for a new mesh;
/// the new one, built on the deformed boundary by the polygon mesher after coarsening it to
/// about 2h, keeps the area to 1e-12 (the area-restoring offset), stays within 0.1 h of the old
/// boundary (the coarsening tolerance 0.05 h plus the offset), passes the monitor, does not
/// multiply the boundary points when re-meshed again and again where it stands (five more
/// times: at most 1.3 times as many as after the first; without the coarsening and the
/// thinning the mesher's side midpoints double them at every re-mesh), and carries a linear field over exactly (1e-10) at the
/// points inside the old mesh and to |∇f| × 0.1 h at the others (clamped to the old boundary).
#[test]
fn remesh_particle_keeps_boundary_and_area_and_passes_the_monitor() {
    let old = shapes::disc([0.0, 0.0], 10.0, 1.5);
    // a dent, a shear of 2.5 and a squash to 0.6
    let x = dented(&old, [[1.0, 2.5], [0.0, 0.6]]);
    let limits = QualityLimits::default();
    let before = remesh::check_quality(&old, &x, &limits).unwrap();
    assert!(before.needs_remesh, "the deformation must cross a limit: {before:?}");
    let new = remesh::remesh_particle(&old, &x, 1.5).unwrap();
    let after = remesh::check_quality(&new, &new.nodes, &limits).unwrap();
    assert!(!after.needs_remesh, "the new mesh must pass: {after:?}");
    let area = remesh::area_check(&old, &x, &new, &new.nodes).unwrap();
    assert!(area.relative_change.abs() < 1e-12, "{area:?}");
    // the new boundary follows the old one and has about as many points
    let h = 1.5;
    let dist_to_old = |q: [f64; 2]| {
        old.boundary
            .iter()
            .map(|e| {
                let (a, b) = (x[e[0]], x[e[1]]);
                let (d, w) = ([b[0] - a[0], b[1] - a[1]], [q[0] - a[0], q[1] - a[1]]);
                let t = ((w[0] * d[0] + w[1] * d[1]) / (d[0] * d[0] + d[1] * d[1])).clamp(0.0, 1.0);
                (w[0] - t * d[0]).hypot(w[1] - t * d[1])
            })
            .fold(f64::INFINITY, f64::min)
    };
    let shift = new.boundary.iter().map(|e| dist_to_old(new.nodes[e[0]])).fold(0.0, f64::max);
    assert!(shift <= 0.1 * h, "the new boundary is {shift} mm off the old one");
    // re-meshing the new mesh where it stands, again and again, does not multiply its boundary
    // points (measured: 78, then 90, 98, 96, 96, 96 boundary edges; each re-mesh keeps
    // the area)
    let mut again = new.clone();
    let mut counts = vec![new.boundary.len()];
    for _ in 0..5 {
        let next = remesh::remesh_particle(&again, &again.nodes, h).unwrap();
        let area2 = remesh::area_check(&again, &again.nodes, &next, &next.nodes).unwrap();
        assert!(area2.relative_change.abs() < 1e-12, "{area2:?}");
        counts.push(next.boundary.len());
        again = next;
    }
    assert!(counts.iter().all(|&c| c as f64 <= 1.3 * counts[0] as f64), "boundary edges over five re-meshes: {counts:?}");
    eprintln!("boundary edges {} -> {counts:?}, largest shift {shift:.3e} mm", old.boundary.len());
    // a linear field moves exactly
    let f = |p: [f64; 2], out: &mut [f64]| out[0] = 2.0 + 0.3 * p[0] - 0.7 * p[1];
    let qp_old = remesh::quadrature_points(&old, &x).unwrap();
    let field = QuadField::from_fn(&qp_old, 1, f);
    let mut tr = FieldTransfer::new(&old, &x, &new, &new.nodes).unwrap();
    let moved = tr.quadrature_field(&field).unwrap();
    let qp_new = remesh::quadrature_points(&new, &new.nodes).unwrap();
    let exact = QuadField::from_fn(&qp_new, 1, f);
    let locator = remesh::PointLocator::new(&old, &x).unwrap();
    let grad = 0.3_f64.hypot(0.7);
    for i in 0..exact.n_points() {
        let err = (moved.point(i)[0] - exact.point(i)[0]).abs();
        let inside = locator.locate(qp_new[i]).is_ok_and(|l| l.distance <= 1e-12);
        let bound = if inside { 1e-9 } else { grad * 0.1 * h };
        assert!(err <= bound, "point {i} (inside the old mesh: {inside}): linear field error {err:.3e}");
    }
}

/// `Model::with_body_mesh`: one particle of the 2 × 2 disc job replaced by a new mesh of its
/// boundary (here in the reference configuration): the other bodies keep their nodes, in the
/// new numbering (exact), every body keeps its area (1e-12), the element lists and offsets
/// are consistent; a body with prescribed displacements is refused with an error naming it.
#[test]
fn model_with_a_remeshed_body() {
    use mpfem::case;
    use mpfem::model::{Model, ModelError};
    let c = case::load(std::path::Path::new("jobs/compaction/discs_2x2_lateral.toml")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let b = 1;
    let body = &model.bodies[b];
    let coords = &model.x0[body.node_offset..body.node_offset + body.mesh.n_nodes()];
    let mesh = remesh::remesh_particle(&body.mesh, coords, 0.7).unwrap();
    let n_new = mesh.n_nodes();
    let new = model.with_body_mesh(b, mesh).unwrap();
    assert_eq!(new.bodies[b].mesh.n_nodes(), n_new);
    let a0 = model.body_areas(&model.x0);
    let a1 = new.body_areas(&new.x0);
    for (x, y) in a0.iter().zip(&a1) {
        assert!(((x - y) / x).abs() < 1e-12, "areas {a0:?} vs {a1:?}");
    }
    for (c, (ob, nb)) in model.bodies.iter().zip(&new.bodies).enumerate() {
        if c != b {
            for k in 0..ob.mesh.n_nodes() {
                assert_eq!(model.x0[ob.node_offset + k], new.x0[nb.node_offset + k]);
            }
        }
        for (e, el) in nb.mesh.elements.iter().enumerate() {
            assert_eq!(new.elements[nb.elem_offset + e], el.map(|n| n + nb.node_offset));
            assert_eq!(new.elem_body[nb.elem_offset + e], c);
        }
    }
    assert_eq!(new.x0.len(), new.bodies.iter().map(|b| b.mesh.n_nodes()).sum::<usize>());
    // a body held by prescribed displacements cannot be re-meshed
    let c = case::load(std::path::Path::new("jobs/verification/patch_test.toml")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let body = &model.bodies[0];
    let err = model.with_body_mesh(0, body.mesh.clone()).unwrap_err();
    assert!(matches!(err, ModelError::RemeshConstrained { what: "prescribed displacements", .. }), "{err}");
    assert!(err.to_string().contains(&body.name), "{err}");
}

/// `Simulation::remesh_body` in the middle of a compaction: two copies of the 2 × 2 lateral disc
/// job (J2 aluminium, penalty contact), at mesh size 2 mm, run to solid ratio 0.85
/// identically; one re-meshes a disc at the same size. The particle areas are unchanged
/// (1e-12), and the disc's total stabilisation spring ζ E A / h² changes only with the
/// reference area A (1e-9: h is the particle's, not the new mesh's, whose smaller h made the
/// springs stiffer by the ratio of the element counts before); the transferred state re-converges in place (`Simulation::equilibrate`, Δt = 0)
/// in at most 8 Newton iterations (measured 6: the nodes in contact keep their positions;
/// 10 when the coarsening's area-restoring offset still moved them), and after one more step
/// (dt = 0.01 s) the wall forces of the two agree to the issue's 1 % (measured 0.54 % and
/// 0.01 %; 0.003 % and 0.006 % since the mesher keeps the held stretches' spacing). That
/// step itself takes more iterations than without the re-mesh (printed, not asserted;
/// measured 14 against 5 on 2026-12-01, 9 and 17 in earlier versions): the frictionless 2 × 2
/// columns are an unstable equilibrium, and the re-meshed disc breaks their mirror symmetry.
/// At the job's own 4 mm the forces differ by 1.4 % (a coarse re-mesh is a different
/// discretisation), at 6 mm by 5 %.
/// Two simulations of case `c` advanced step by step together until the solid ratio reaches
/// `phi` (one to be re-meshed, one to compare with), and the solid ratio they reached.
fn twins_at(c: &mpfem::case::Case, phi: f64) -> (mpfem::solver::Simulation, mpfem::solver::Simulation, f64) {
    let mk = || mpfem::solver::Simulation::new(mpfem::model::Model::from_case(c).unwrap(), c.time, c.solver).unwrap();
    let (mut a, mut b) = (mk(), mk());
    let mut reached = 0.0;
    while reached < phi {
        reached = a.advance(c.time.dt).unwrap().compaction.unwrap().solid_ratio;
        b.advance(c.time.dt).unwrap();
    }
    (a, b, reached)
}

#[test]
fn remeshing_a_disc_mid_run_keeps_the_wall_forces() {
    use mpfem::case;
    use mpfem::solver::Simulation;
    let text = std::fs::read_to_string("jobs/compaction/discs_2x2_lateral.toml").unwrap();
    let path = std::env::temp_dir().join(format!("remesh_mid_run_{}.toml", std::process::id()));
    std::fs::write(&path, text.replace("mesh_size = 4.0", "mesh_size = 2.0")).unwrap();
    let c = case::load(&path).unwrap();
    let (mut a, mut b, phi) = twins_at(&c, 0.85);
    let areas_before = b.model.body_areas(&b.coords(&b.sol.u));
    // the disc's stabilisation springs, summed: ζ E A / h² per direction with the particle's
    // own h, whatever its mesh (they were stiffened by the finer new mesh before)
    let springs = |s: &Simulation| {
        let body = &s.model.bodies[0];
        s.stabilisation_springs()[2 * body.node_offset..2 * (body.node_offset + body.mesh.n_nodes())].iter().sum::<f64>()
    };
    let springs_before = springs(&b);
    // (the springs go with the reference area: the original disc's before, its current area after)
    let area_ratio = areas_before[0] / b.model.body_areas(&b.model.x0)[0];
    let h = c.bodies[0].mesh_size;
    let moved = b.remesh_body(0, h).unwrap();
    let springs_after = springs(&b);
    assert!(springs_before > 0.0 && (springs_after / springs_before / area_ratio - 1.0).abs() < 1e-9, "stabilisation springs {springs_before} -> {springs_after} (area ratio {area_ratio})");
    assert!(moved.area.relative_change.abs() < 1e-12, "{:?}", moved.area);
    let areas_after = b.model.body_areas(&b.coords(&b.sol.u));
    for (x, y) in areas_before.iter().zip(&areas_after) {
        assert!(((x - y) / x).abs() < 1e-12, "{areas_before:?} vs {areas_after:?}");
    }
    // the transferred state is re-equilibrated in place (Δt = 0) in a few Newton iterations
    let t = b.sol.time;
    let its = b.equilibrate().unwrap();
    assert_eq!(b.sol.time, t);
    assert!(its <= 8, "re-equilibration took {its} Newton iterations");
    let ra = a.advance(0.01).unwrap();
    let rb = b.advance(0.01).unwrap();
    let _ = std::fs::remove_file(&path);
    let (fa, fb) = (ra.compaction.unwrap().force, rb.compaction.unwrap().force);
    eprintln!("phi {phi:.4}: forces {fa:?} vs {fb:?}; re-equilibration {its} iterations; next step {} vs {} iterations", ra.newton_iterations, rb.newton_iterations);

    for w in 0..4 {
        let scale = fa.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
        assert!((fa[w] - fb[w]).abs() <= 0.01 * scale, "wall {w}: {} vs {} N/mm", fa[w], fb[w]);
    }
}


/// `[remesh]` in a whole run, through the command line: one incompressible asphalt octagon
/// (the paper's 5.2.1 job with a 1 × 1 grid), compacted laterally to solid ratio 0.94 with the
/// default quality limits, output at every step. Its corner elements cross the limits
/// (measured: once, at φ 0.88). Checked:
/// - the particle is re-meshed (the `remeshes` history column) and the run reaches 0.94;
/// - the volume error stays within 1e-8 at every step (measured 1.2e-11; the issue's bound
///   for a whole incompressible run is 0.05 %): the re-mesh keeps the particle's area to 1e-12
///   and the re-meshed elements keep the incompressibility (j₀ carries their volume ratio);
/// - `results.h5` takes the topology change: steps before and after a re-mesh carry their own
///   `cells` (different counts), every cell refers to a node of its step, and `results.xdmf`
///   names every written step with that step's sizes;
/// - `summary.json` reports the re-mesh count and the re-meshing phase.
#[test]
fn a_run_with_remeshing_keeps_volume_and_writes_each_mesh() {
    use std::process::Command;
    let dir = std::env::temp_dir().join(format!("mpfem_remesh_run_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string("jobs/paper/5_2_1_asphalt_lateral.toml").unwrap();
    assert!(!text.contains("[remesh]") && !text.contains("[output]"));
    let base = std::fs::canonicalize("jobs").unwrap();
    let text = text
        .replace("file = \"../", &format!("file = \"{}/", base.display()))
        .replace("nx = 4", "nx = 1")
        .replace("ny = 4", "ny = 1")
        .replace("solid_ratio = 0.9913\n", "solid_ratio = 0.94\n")
        // the penalty method: its corner pressed into the walls crosses the quality limits; with
        // the barrier (the default) the octagon reaches 0.99 on its first mesh
        .replace("contact = \"sliding\"", "method = \"penalty\"\ncontact = \"sliding\"");
    assert!(text.contains("nx = 1") && text.contains("ny = 1") && text.contains("solid_ratio = 0.94") && text.contains("method = \"penalty\""));
    let case = dir.join("case.toml");
    std::fs::write(&case, format!("{text}\n[remesh]\n\n[output]\nevery = 1\n")).unwrap();
    let out = dir.join("out");
    let st = Command::new(env!("CARGO_BIN_EXE_mpfem")).args(["run", "-q", "--no-plots", "-o"]).arg(&out).arg(&case).status().unwrap();
    assert!(st.success());

    let csv = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    let (c_step, c_rm, c_vol, c_phi) = (col("step"), col("remeshes"), col("volume_error"), col("solid_ratio"));
    let text_rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // the counts are written as integers (`active_contacts` once came out as 8.000000000e0)
    for name in ["step", "newton_iterations", "cutbacks", "remeshes", "active_contacts"] {
        let c = col(name);
        for r in &text_rows {
            assert!(r[c].parse::<u64>().is_ok(), "column {name}: {} is not an integer", r[c]);
        }
    }
    let rows: Vec<Vec<f64>> = text_rows.iter().map(|r| r.iter().map(|v| v.parse().unwrap()).collect()).collect();
    let remeshes: f64 = rows.iter().map(|r| r[c_rm]).sum();
    let worst_volume = rows.iter().map(|r| r[c_vol]).fold(0.0, f64::max);
    let last = rows.last().unwrap();
    eprintln!("{} steps, {remeshes} re-meshes, worst volume error {worst_volume:.3e}, final solid ratio {:.4}", rows.len(), last[c_phi]);
    assert!(remeshes >= 1.0, "no particle was re-meshed");
    assert!(last[c_phi] >= 0.94, "stopped at solid ratio {}", last[c_phi]);
    assert!(worst_volume <= 1e-8, "volume error {worst_volume:.3e}");

    // every step's own mesh in results.h5
    let file = mpfem::h5::open(&out.join("results.h5")).unwrap();
    let steps = file.group("steps").unwrap().member_names().unwrap();
    assert_eq!(steps.len(), rows.len(), "one output step per history row");
    let mut counts = Vec::new();
    for s in &steps {
        let g = file.group(&format!("steps/{s}")).unwrap();
        let cells: Vec<i64> = g.dataset("cells").unwrap().read_raw().unwrap();
        let n_nodes = g.dataset("coordinates").unwrap().shape()[0];
        assert!(cells.iter().all(|&n| n >= 0 && (n as usize) < n_nodes), "step {s}: a cell refers to a node that is not there");
        let particles: Vec<i32> = g.dataset("particle_id").unwrap().read_raw().unwrap();
        assert_eq!(particles.len() * 4, cells.len());
        assert_eq!(g.dataset("displacement").unwrap().shape()[0], n_nodes);
        counts.push((cells.len() / 4, n_nodes));
    }
    let first_rm = rows.iter().position(|r| r[c_rm] > 0.0).unwrap();
    assert_ne!(counts[0], *counts.last().unwrap(), "the mesh written after a re-mesh is the new one");
    assert_ne!(counts[first_rm.saturating_sub(1)], counts[first_rm], "step {}: re-meshed but the same mesh written", rows[first_rm][c_step]);
    let xdmf = std::fs::read_to_string(out.join("results.xdmf")).unwrap();
    for (cells, nodes) in &counts {
        assert!(xdmf.contains(&format!("NumberOfElements=\"{cells}\"")), "results.xdmf does not name a grid of {cells} cells");
        assert!(xdmf.contains(&format!("{nodes} 2")), "results.xdmf does not name {nodes} nodes");
    }

    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["run"]["remeshes"].as_f64().unwrap(), remeshes);
    assert!(summary["phases"]["remesh"].as_f64().unwrap() > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `remesh::remesh_particle_keeping` with held boundary nodes (the nodes in contact), on a
/// disc of mesh size 1.5 mm dented as in the test above and mildly sheared (its boundary
/// spacing stays near the target size; a stretched held stretch is refined by the mesher
/// as any side longer than 2h is): every held node is a boundary node of the new
/// mesh, bit for bit where it was, and the held stretch keeps its old spacing — every other
/// held node is a vertex of the polygon given to the mesher and the mesher's side midpoint is
/// moved back onto the node in between (before, every held node was a polygon vertex and the
/// midpoints doubled the boundary nodes there: measured on an asphalt octagon of the 5.2.1
/// job held all round, 96 boundary nodes and 588 elements from 48 and 72; now 48 and 162).
/// Held all round, the new boundary is the old one exactly (the same points, no others). The
/// area is kept to 1e-12 and the new mesh passes the monitor (defaults) in both cases.
#[test]
fn held_boundary_nodes_keep_their_places_and_their_spacing() {
    let old = shapes::disc([0.0, 0.0], 10.0, 1.5);
    let x = dented(&old, [[0.9, 0.3], [0.0, 1.05]]);
    let lp = &old.boundary_loops()[0];
    let limits = QualityLimits::default();
    let bits = |p: [f64; 2]| p.map(f64::to_bits);
    // a contact zone (a third of the boundary, the dented side included) and all round
    let third: Vec<usize> = lp.iter().copied().filter(|&v| old.nodes[v][0] > 4.0).collect();
    for (name, hold) in [("a third", third), ("all round", lp.clone())] {
        let new = remesh::remesh_particle_keeping(&old, &x, 1.5, &hold).unwrap();
        let new_lp = &new.boundary_loops()[0];
        let on_new: std::collections::HashSet<[u64; 2]> = new_lp.iter().map(|&v| bits(new.nodes[v])).collect();
        for &v in &hold {
            assert!(on_new.contains(&bits(x[v])), "{name}: held node {v} at {:?} is not a boundary node of the new mesh", x[v]);
        }
        // two held nodes next to each other on the old boundary are next to each other on the
        // new one: no point was added between them
        let pos: std::collections::HashMap<[u64; 2], usize> = new_lp.iter().enumerate().map(|(i, &v)| (bits(new.nodes[v]), i)).collect();
        let held: std::collections::HashSet<usize> = hold.iter().copied().collect();
        let nl = new_lp.len();
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            if held.contains(&a) && held.contains(&b) {
                let (pa, pb) = (pos[&bits(x[a])], pos[&bits(x[b])]);
                assert!((pb + nl - pa) % nl == 1 || (pa + nl - pb) % nl == 1, "{name}: a point was added between the held nodes {a} and {b}");
            }
        }
        if hold.len() == lp.len() {
            assert_eq!(new_lp.len(), lp.len(), "all round: the new boundary has other points than the old one");
        }
        let area = remesh::area_check(&old, &x, &new, &new.nodes).unwrap();
        assert!(area.relative_change.abs() < 1e-12, "{name}: {area:?}");
        let q = remesh::check_quality(&new, &new.nodes, &limits).unwrap();
        assert!(!q.needs_remesh, "{name}: the new mesh must pass: {q:?}");
        eprintln!("{name}: {} held, boundary nodes {} -> {}, elements {} -> {}", hold.len(), lp.len(), new_lp.len(), old.n_elements(), new.n_elements());
    }
}

/// Every active contact history of `sim` (node-to-segment and node-to-wall, committed), keyed
/// by where its nodes are: the bits of the current coordinates of the slave node and of the
/// master segment's nodes (node-to-wall: the wall's number instead of the segment), so that
/// two numberings of the same assembly can be compared.
type HistoryKey = ([u64; 2], [u64; 4], usize);
fn active_histories(sim: &mpfem::solver::Simulation) -> std::collections::HashMap<HistoryKey, mpfem::contact::PairHistory> {
    let c = sim.contact.as_ref().expect("a contact problem");
    let x = sim.coords(&sim.sol.u);
    let bits = |p: [f64; 2]| p.map(f64::to_bits);
    let st = c.state();
    let mut out = std::collections::HashMap::new();
    for ((slave, seg), h) in st.nts.iter().filter(|(_, h)| h.active) {
        let [a, b] = c.boundary.segments[*seg].nodes;
        let (pa, pb) = (bits(x[a]), bits(x[b]));
        out.insert((bits(x[*slave]), [pa[0], pa[1], pb[0], pb[1]], usize::MAX), *h);
    }
    for (w, hs) in st.walls.iter().enumerate() {
        for (i, h) in hs.iter().enumerate().filter(|(_, h)| h.active) {
            out.insert((bits(x[c.boundary.slaves[i].0]), [0; 4], w), *h);
        }
    }
    out
}

/// The contact history of the assembly survives a re-mesh (the issue's "contact history such
/// as stick points and multipliers"): the 2 × 2 disc job (J2 aluminium, mesh size 2 mm) with
/// Coulomb friction μ = 0.2 between the discs and on the walls and augmented-Lagrangian
/// enforcement — so the committed multipliers λ_N, λ_T carry most of every contact force and
/// the stick anchors the rest — run to solid ratio 0.85 in two copies; one re-meshes disc 0.
/// Checked:
/// - right after the re-mesh, every active history whose slave node and master nodes are
///   still there (all pairs between the other discs, with the walls, and the held contact
///   zones of disc 0) is found in the new numbering, identical bit for bit; the others are
///   re-anchored (counted, at most a tenth);
/// - the re-equilibration (Δt = 0) takes at most 8 Newton iterations and the wall forces after
///   one more step agree with the un-re-meshed run to the issue's 1 %;
/// - without the carried history (the contact state reset, as before this was done) the same
///   re-mesh gives wall forces that differ by more than that: the check can fail.
#[test]
fn remeshing_keeps_the_contact_history_of_the_assembly() {
    use mpfem::case;
    use mpfem::model::Model;
    use mpfem::solver::Simulation;
    let text = std::fs::read_to_string("jobs/compaction/discs_2x2_lateral_mu02.toml").unwrap();
    let text = text.replace("mesh_size = 4.0", "mesh_size = 2.0").replace("method = \"penalty\"", "method = \"augmented_lagrangian\"\npenetration_tol = 1e-4");
    assert!(text.contains("mesh_size = 2.0") && text.contains("augmented_lagrangian"));
    let path = std::env::temp_dir().join(format!("remesh_history_{}.toml", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let c = case::load(&path).unwrap();
    let _ = std::fs::remove_file(&path);
    let mk = || Simulation::new(Model::from_case(&c).unwrap(), c.time, c.solver).unwrap();
    let (mut a, mut b, mut r) = (mk(), mk(), mk());
    let mut phi = 0.0;
    while phi < 0.85 {
        let ra = a.advance(c.time.dt).unwrap();
        b.advance(c.time.dt).unwrap();
        r.advance(c.time.dt).unwrap();
        phi = ra.compaction.unwrap().solid_ratio;
    }
    let before = active_histories(&b);
    let sticking = before.values().filter(|h| h.lambda_t != 0.0).count();
    let h = c.bodies[0].mesh_size;
    b.remesh_body(0, h).unwrap();
    r.remesh_body(0, h).unwrap();
    let after = active_histories(&b);
    let same = before.iter().filter(|(k, h)| after.get(*k) == Some(*h)).count();
    let multipliers: f64 = before.values().map(|h| h.lambda_n).sum();
    eprintln!("phi {phi:.4}: {} active histories ({sticking} with a shear multiplier, sum of lambda_N {multipliers:.1} MPa), {same} carried bit for bit, {} in the new state", before.len(), after.len());
    assert!(before.len() >= 8 && sticking >= 1 && multipliers > 0.0, "the state to carry is not there");
    assert!(10 * same >= 9 * before.len(), "only {same} of {} active histories carried", before.len());
    assert!(after.len() >= before.len() * 9 / 10, "{} active histories after, {} before", after.len(), before.len());
    // the reference: the same re-mesh with the contact state reset
    let reset = r.contact.as_ref().unwrap().state();
    let empty = mpfem::contact::ContactState {
        nts: Vec::new(),
        walls: reset.walls.iter().map(|w| vec![Default::default(); w.len()]).collect(),
        lm_committed: Vec::new(),
        nodal: reset.nodal.clone(),
        body_h: reset.body_h.clone(),
        area: Vec::new(),
    };
    r.contact.as_mut().unwrap().set_state(empty).unwrap();
    let its = b.equilibrate().unwrap();
    let its_reset = r.equilibrate().map_or_else(|e| format!("failed: {e}"), |n| n.to_string());
    let ra = a.advance(0.01).unwrap();
    let rb = b.advance(0.01).unwrap();
    let rr = r.advance(0.01).map(|s| s.compaction.unwrap().force);
    let (fa, fb) = (ra.compaction.unwrap().force, rb.compaction.unwrap().force);
    let scale = fa.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
    let dev = |f: &[f64; 4]| (0..4).map(|w| (fa[w] - f[w]).abs() / scale).fold(0.0, f64::max);
    eprintln!("re-equilibration {its} iterations (reset: {its_reset}); forces {fa:?} / carried {fb:?} ({:.2e}) / reset {rr:?} ({:?})", dev(&fb), rr.as_ref().map(dev));
    assert!(its <= 8, "re-equilibration took {its} Newton iterations");
    assert!(dev(&fb) <= 0.01, "wall forces {fb:?} against {fa:?}");
    let its_reset: usize = its_reset.parse().unwrap_or(usize::MAX);
    assert!(its < its_reset, "re-equilibration from the carried history {its} iterations, from a reset one {its_reset}: the carried state is no nearer to equilibrium");
}

/// `ContactProblem::carry_history` when the master segment of a pair is re-meshed away: a
/// 4 × 2 mm block (mesh 1 mm) rests on a 10 × 4 mm slab (mesh 1 mm, its top side from x = 0
/// to 10); the pair of the block's corner node at x = 3 on the slab's top carries a stick
/// anchor 0.4 mm behind it, λ_N = 5 MPa and λ_T = 1 MPa. The slab gets a new mesh of 13 × 5 elements
/// (other nodes, other segments, the same straight top side), and the block keeps its nodes.
/// Checked: the history is found in the new problem on the slab's new segment nearest to the
/// slave node, with λ_N, λ_T unchanged, and its anchor is the same point of the top side
/// (1e-12 mm: the sides are collinear, so re-projecting the point is exact); the counts say
/// one history was moved and none dropped.
#[test]
fn a_stick_anchor_on_a_remeshed_master_stays_at_its_point() {
    use mpfem::contact::{ContactState, PairHistory};
    use mpfem::model::Model;
    let text = r#"
title = "block on slab"
[[materials]]
name = "m"
model = "elastic"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[bodies]]
name = "block"
material = "m"
mesh_size = 1.0
shape = { type = "rectangle", origin = [3.0, 4.0], size = [4.0, 2.0] }
[[bodies]]
name = "slab"
material = "m"
mesh_size = 1.0
shape = { type = "rectangle", origin = [0.0, 0.0], size = [10.0, 4.0] }
[contact]
method = "penalty"
contact = "rubbing"
friction = 0.3
[time]
end = 1.0
dt = 0.1
"#;
    let c = mpfem::case::parse(text, std::path::Path::new(".")).unwrap();
    let model = Model::from_case(&c).unwrap();
    let mut old = model.contact_problem().unwrap();
    let x = model.x0.clone();
    // the block's node at (3, 4) and the slab's top segment under it, from x = 3 to 4 (the slab's
    // top side runs right to left: the body lies on the segment's left)
    let slave = (0..model.bodies[0].mesh.n_nodes()).find(|&k| x[k] == [3.0, 4.0]).unwrap();
    let seg = old.boundary.segments.iter().position(|s| s.body == 1 && x[s.nodes[0]] == [4.0, 4.0] && x[s.nodes[1]] == [3.0, 4.0]).unwrap();
    // ξ along the segment from (4, 4) to (3, 4): the anchor at x = 3.4 is ξ = 0.6
    let h = PairHistory { xi_stick: 0.6, lambda_n: 5.0, lambda_t: 1.0, active: true };
    let st = old.state();
    old.set_state(ContactState { nts: vec![((slave, seg), h)], ..st }).unwrap();
    // the slab re-meshed with 13 x 5 elements (where it stands: reference = current here)
    let new_mesh = mpfem::mesh::shapes::rectangle([0.0, 0.0], 10.0, 4.0, 13, 5);
    let near = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).abs() + (p[1] - q[1]).abs() < 1e-9;
    assert!(!new_mesh.nodes.iter().any(|&p| near(p, [3.0, 4.0]) || near(p, [4.0, 4.0])), "the new top side must not keep the old segment's nodes");
    let new_model = model.with_body_mesh(1, new_mesh).unwrap();
    let mut new = new_model.contact_problem().unwrap();
    let mut node_map = vec![None; model.x0.len()];
    for k in 0..model.bodies[0].mesh.n_nodes() {
        node_map[model.bodies[0].node_offset + k] = Some(new_model.bodies[0].node_offset + k);
    }
    let carried = new.carry_history(&old, &node_map, [&model.x0, &model.x0], [&new_model.x0, &new_model.x0]);
    assert_eq!((carried.moved, carried.dropped, carried.kept), (1, 0, 0), "{carried:?}");
    let st = new.state();
    assert_eq!(st.nts.len(), 1, "{:?}", st.nts);
    let ((s_new, k), h_new) = st.nts[0];
    let xn = &new_model.x0;
    assert_eq!(xn[s_new], [3.0, 4.0]);
    let s = new.boundary.segments[k];
    assert_eq!(s.body, 1);
    let (a, b) = (xn[s.nodes[0]], xn[s.nodes[1]]);
    assert!(mpfem::contact::search::point_segment_distance([3.0, 4.0], a, b) < 1e-12, "segment {a:?}-{b:?} is not under the slave node");
    assert_eq!((h_new.lambda_n, h_new.lambda_t, h_new.active), (5.0, 1.0, true));
    let anchor = [(1.0 - h_new.xi_stick) * a[0] + h_new.xi_stick * b[0], (1.0 - h_new.xi_stick) * a[1] + h_new.xi_stick * b[1]];
    assert!((anchor[0] - 3.4).abs() < 1e-12 && (anchor[1] - 4.0).abs() < 1e-12, "anchor moved to {anchor:?}");
}

/// Re-meshing with the barrier contact (the default): the 2 × 2 aluminium discs of
/// `jobs/compaction/discs_2x2_lateral.toml` with the barrier instead of the penalty method
/// (frictionless, or cohering: the particles tied where they touch), compacted to solid ratio
/// 0.85, then disc 0 re-meshed mid-run. Before the barrier's near nodes were held, the
/// re-mesh's area-restoring offset pushed the disc's nodes pressed against the walls behind
/// them (0.16 mm on the 5.2.1 job) and every re-mesh was refused. Checked:
/// - the re-mesh is taken; every old boundary point of the disc within d̂ + 0.1 h of a wall
///   (the wall's barrier zero at d̂/2 behind its plane, as the barrier measures it) is a point
///   of the new boundary bit for bit;
/// - no boundary node lies inside another particle or behind a wall
///   (`Simulation::barrier_crossings`), the barrier's κ is kept, and every tie goes over
///   (cohering: the tied nodes are within d̂ of the other particle, so they are held);
/// - the transferred state re-converges in place and, after one more step of 0.01 s, the
///   wall forces agree with the run that was not re-meshed to 1 % of the largest (the
///   penalty test's tolerance above).
#[test]
fn remeshing_with_the_barrier_holds_the_contact_zones() {
    use mpfem::case;
    for cohering in [false, true] {
        let text = std::fs::read_to_string("jobs/compaction/discs_2x2_lateral.toml").unwrap();
        let contact = if cohering { "contact = \"cohering\"" } else { "contact = \"sliding\"" };
        let text = text.replace("method = \"penalty\"\ncontact = \"sliding\"", contact);
        assert!(!text.contains("penalty") && text.contains(contact), "the job's [contact] table changed");
        let path = std::env::temp_dir().join(format!("remesh_barrier_{}_{cohering}.toml", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let c = case::load(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        let (mut a, mut b, phi) = twins_at(&c, 0.85);
        let ties_before = b.barrier_ties().unwrap().0;
        assert!(!cohering || ties_before > 0, "no tie before the re-mesh");
        let kappa = b.state().scalars.barrier.unwrap().kappa;
        // the old boundary points of disc 0 within d̂ + 0.1 h of a wall's barrier zero
        let body = &b.model.bodies[0];
        let (n0, h) = (body.node_offset, body.contact_h);
        let dhat = h / 20.0;
        let x = b.coords(&b.sol.u);
        let walls = b.model.wall_planes(b.sol.time);
        let near_wall: Vec<[f64; 2]> = body
            .mesh
            .boundary
            .iter()
            .map(|e| x[n0 + e[0]])
            .filter(|p| walls.iter().any(|w| (p[0] - w.point[0]) * w.normal[0] + (p[1] - w.point[1]) * w.normal[1] + 0.5 * dhat < dhat + 0.1 * h))
            .collect();
        assert!(near_wall.len() >= 2, "disc 0 does not touch a wall at solid ratio {phi}");
        b.remesh_body(0, c.bodies[0].mesh_size).unwrap_or_else(|e| panic!("cohering {cohering}: {e}"));
        let body = &b.model.bodies[0];
        let x = b.coords(&b.sol.u);
        let new_points: std::collections::HashSet<[u64; 2]> = body.mesh.boundary.iter().map(|e| x[body.node_offset + e[0]].map(f64::to_bits)).collect();
        let moved = near_wall.iter().filter(|p| !new_points.contains(&p.map(f64::to_bits))).count();
        assert_eq!(moved, 0, "cohering {cohering}: {moved} of the {} points at the walls moved", near_wall.len());
        assert_eq!(b.barrier_crossings(), Some(0));
        assert_eq!(b.state().scalars.barrier.unwrap().kappa, kappa, "κ not carried over the re-mesh");
        assert_eq!(b.barrier_ties().unwrap().0, ties_before, "cohering {cohering}: ties lost in the re-mesh");
        let its = b.equilibrate().unwrap();
        let ra = a.advance(0.01).unwrap();
        let rb = b.advance(0.01).unwrap();
        let (fa, fb) = (ra.compaction.unwrap().force, rb.compaction.unwrap().force);
        eprintln!("cohering {cohering}, phi {phi:.4}: {} held points at the walls, {ties_before} ties; re-equilibrated in {its} iterations; forces {fa:?} vs {fb:?}", near_wall.len());
        let scale = fa.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
        for w in 0..4 {
            assert!((fa[w] - fb[w]).abs() <= 0.01 * scale, "cohering {cohering}, wall {w}: {} vs {} N/mm", fa[w], fb[w]);
        }
    }
}

/// Several incompressible particles re-meshed one after the other (as `[remesh]` re-meshes every
/// particle crossing the limits in one step): each carries its own element pressures over.
/// The 2 × 2 asphalt octagons (`jobs/compaction/octagons_2x2_asphalt_lateral.toml`) compacted
/// to solid ratio 0.88, then every octagon re-meshed in turn (`remesh_body` 0 to 3): the
/// area-weighted mean multiplier λ of the last one's new elements (an incompressible particle
/// carries its pressure whole in λ) equals the mean pressure of its old elements to 5 % (the
/// lumped projection need not keep the mean exactly). Each re-mesh's rebuild had left the
/// other particles' pressures at zero, so every octagon but the first came out with λ = 0
/// (and the 16 octagons of the 5.2.1 job re-meshed in one step began their re-equilibration
/// at a relative residual of 1.0 instead of 0.42).
#[test]
fn particles_remeshed_in_turn_keep_their_pressures() {
    use mpfem::case;
    use mpfem::model::Model;
    use mpfem::solver::Simulation;
    let c = case::load(std::path::Path::new("jobs/compaction/octagons_2x2_asphalt_lateral.toml")).unwrap();
    let mut sim = Simulation::new(Model::from_case(&c).unwrap(), c.time, c.solver).unwrap();
    let mut phi = 0.0;
    while phi < 0.88 {
        phi = sim.advance(c.time.dt).unwrap().compaction.unwrap().solid_ratio;
    }
    // the area-weighted mean of an element field over body `b`
    let mean = |s: &Simulation, b: usize, v: &[f64]| {
        let body = &s.model.bodies[b];
        let x = s.coords(&s.sol.u);
        let (mut sum, mut area) = (0.0, 0.0);
        for e in body.elem_offset..body.elem_offset + body.mesh.n_elements() {
            let a = mpfem::mesh::polygon_area(s.model.elements[e].iter().map(|&n| x[n]));
            sum += a * v[e];
            area += a;
        }
        sum / area
    };
    let before = mean(&sim, 3, &sim.sol.fields.pressure);
    assert!(before.abs() > 1.0, "octagon 3 carries {before} MPa at solid ratio {phi}: too little to test");
    for b in 0..4 {
        let h = sim.model.bodies[b].mesh_size;
        sim.remesh_body(b, h).unwrap_or_else(|e| panic!("octagon {b}: {e}"));
    }
    let after = mean(&sim, 3, &sim.sol.lambda);
    eprintln!("octagon 3 at solid ratio {phi:.4}: mean pressure {before:.4} MPa, its new elements' mean λ {after:.4} MPa");
    assert!((after - before).abs() <= 0.05 * before.abs(), "octagon 3's pressure {before} MPa came out of its re-mesh as {after} MPa");
}
