//! User particles: the simple-polygon quadrilateral mesher, outline CSV and gmsh imports in the
//! case file (`shape = { type = "outline" }`, `shape = { type = "gmsh" }`, `[[imports]]`), the
//! non-convex overlap check, and a short compaction of imported particles.

use mpfem::case;
use mpfem::mesh::polygon::{resample_outline, simple_polygon, MIN_SCALED_JACOBIAN};
use mpfem::mesh::{polygon_area, quality, Mesh};
use std::path::Path;

fn l_shape() -> Vec<[f64; 2]> {
    vec![[0.0, 0.0], [6.0, 0.0], [6.0, 2.0], [2.0, 2.0], [2.0, 5.0], [0.0, 5.0]]
}

/// A five-pointed star (non-convex, tip angle 36°) about `c`.
fn star(c: [f64; 2], r_out: f64, r_in: f64) -> Vec<[f64; 2]> {
    (0..10)
        .map(|k| {
            let t = std::f64::consts::FRAC_PI_2 + k as f64 * std::f64::consts::PI / 5.0;
            let r = if k % 2 == 0 { r_out } else { r_in };
            [c[0] + r * t.cos(), c[1] + r * t.sin()]
        })
        .collect()
}

fn heptagon() -> Vec<[f64; 2]> {
    (0..7)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 7.0 + 0.1;
            [10.0 + 4.0 * t.cos(), -3.0 + 3.0 * t.sin()]
        })
        .collect()
}

/// Mean element edge length.
fn mean_edge(m: &Mesh) -> f64 {
    let mut s = 0.0;
    for el in &m.elements {
        for k in 0..4 {
            let (a, b) = (m.nodes[el[k]], m.nodes[el[(k + 1) % 4]]);
            s += (b[0] - a[0]).hypot(b[1] - a[1]);
        }
    }
    s / (4 * m.elements.len()) as f64
}

/// Distance from `p` to the closed polygon outline.
fn dist_to_outline(p: [f64; 2], poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|k| {
            let (a, b) = (poly[k], poly[(k + 1) % n]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let t = (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / (d[0] * d[0] + d[1] * d[1])).clamp(0.0, 1.0);
            (p[0] - a[0] - t * d[0]).hypot(p[1] - a[1] - t * d[1])
        })
        .fold(f64::INFINITY, f64::min)
}

/// Area to 1e-12, positive CCW elements above the quality bound, size near h, one closed
/// boundary loop (counter-clockwise) through the resampled outline's points in order, every
/// boundary node on the outline.
fn check_polygon_mesh(name: &str, poly: &[[f64; 2]], h: f64, min_sj: f64) {
    let m = simple_polygon(poly, h).unwrap();
    let a = polygon_area(poly.iter().copied()).abs();
    let am = m.area(&m.nodes);
    assert!(((am - a) / a).abs() < 1e-12, "{name}: mesh area {am} vs polygon {a}");
    let q = quality::quality(&m, &m.nodes);
    assert_eq!(q.n_inverted, 0, "{name}");
    assert!((0..m.n_elements()).all(|e| m.element_area(e, &m.nodes) > 0.0), "{name}: CCW elements");
    assert!(q.min_scaled_jacobian >= min_sj, "{name}: min scaled Jacobian {} < {min_sj}", q.min_scaled_jacobian);
    let le = mean_edge(&m);
    assert!(le > 0.6 * h && le < 1.2 * h, "{name}: mean edge {le} for h = {h}");
    // boundary: one closed loop, oriented with the body on the left (positive enclosed area)
    let loops = m.boundary_loops();
    assert_eq!(loops.len(), 1, "{name}: one boundary loop");
    let lp = &loops[0];
    assert_eq!(lp.len(), m.boundary.len());
    for (k, e) in m.boundary.iter().enumerate() {
        assert_eq!(e[1], m.boundary[(k + 1) % m.boundary.len()][0], "{name}: chained edges");
    }
    let loop_pts: Vec<[f64; 2]> = lp.iter().map(|&i| m.nodes[i]).collect();
    assert!(((polygon_area(loop_pts.iter().copied()) - a) / a).abs() < 1e-12, "{name}: the loop encloses the polygon, counter-clockwise");
    assert_eq!(m.edge_sets["boundary"], m.boundary);
    for p in &loop_pts {
        assert!(dist_to_outline(*p, poly) < 1e-12 * a.sqrt(), "{name}: boundary node {p:?} off the outline");
    }
    // the resampled outline's points appear in the loop, in order (CCW), and every boundary
    // edge is at most h long
    let ccw: Vec<[f64; 2]> = if polygon_area(poly.iter().copied()) > 0.0 { poly.to_vec() } else { poly.iter().rev().copied().collect() };
    let resampled = resample_outline(&ccw, 2.0 * h);
    let start = loop_pts.iter().position(|p| *p == resampled[0]).expect("first vertex on the boundary");
    let mut at = start;
    for r in &resampled[1..] {
        let step = (1..=loop_pts.len()).find(|s| loop_pts[(at + s) % loop_pts.len()] == *r);
        at = (at + step.unwrap_or_else(|| panic!("{name}: resampled point {r:?} not on the boundary loop in order"))) % loop_pts.len();
    }
    for e in &m.boundary {
        let (p, q) = (m.nodes[e[0]], m.nodes[e[1]]);
        assert!((q[0] - p[0]).hypot(q[1] - p[1]) <= h * (1.0 + 1e-9), "{name}: boundary edge longer than h");
    }
    eprintln!("{name}: {} elements, min scaled Jacobian {:.3}, mean edge {le:.3} (h = {h})", m.n_elements(), q.min_scaled_jacobian);
}

#[test]
fn polygon_mesher_l_shape() {
    check_polygon_mesh("L-shape", &l_shape(), 0.5, MIN_SCALED_JACOBIAN);
    // clockwise input gives the same kind of mesh
    let mut cw = l_shape();
    cw.reverse();
    check_polygon_mesh("L-shape (clockwise)", &cw, 0.7, MIN_SCALED_JACOBIAN);
}

#[test]
fn polygon_mesher_star() {
    // the 36° tips are sharper than the 30° angle limit allows for everywhere around them
    check_polygon_mesh("star", &star([1.0, 2.0], 5.0, 2.0), 0.4, 0.3);
}

#[test]
fn polygon_mesher_convex() {
    check_polygon_mesh("heptagon", &heptagon(), 0.5, MIN_SCALED_JACOBIAN);
}

#[test]
fn polygon_mesher_rejects_bad_outlines() {
    use mpfem::mesh::shapes::MeshError;
    let bow = [[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 1.0]];
    assert!(matches!(simple_polygon(&bow, 0.1), Err(MeshError::SelfIntersecting(0, 2))));
    assert!(matches!(simple_polygon(&bow[..2], 0.1), Err(MeshError::TooFewVertices(2))));
    assert!(matches!(simple_polygon(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]], 0.1), Err(MeshError::ZeroArea)));
    assert!(matches!(simple_polygon(&[[0.0, 0.0], [1.0, f64::INFINITY], [2.0, 2.0]], 0.1), Err(MeshError::NonFiniteVertex(1))));
}

fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

const MATERIALS: &str = r#"
[[materials]]
name = "alu"
model = "j2"
youngs_modulus = 64100.0
poisson_ratio = 0.3
hardening = { preset = "aluminium_250c" }

[[materials]]
name = "soft"
model = "elastic"
youngs_modulus = 10000.0
poisson_ratio = 0.35

[time]
end = 1.0
dt = 0.1
"#;

fn parse(extra: &str) -> Result<case::Case, case::CaseError> {
    case::parse(&format!("{MATERIALS}\n{extra}"), &data(""))
}

fn mesh_area(b: &case::BodySpec) -> f64 {
    let m = mpfem::case::mesh_body(b).unwrap();
    m.area(&m.nodes)
}

#[test]
fn csv_import_gives_three_bodies_with_their_areas() {
    let c = parse("[[imports]]\nfile = \"grains.csv\"\nmaterial = \"alu\"\nmesh_size = 1.0\n").unwrap();
    let names: Vec<&str> = c.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["i0_p0", "i0_p1", "i0_p2"]);
    for (b, area) in c.bodies.iter().zip([39.0, 39.0, 22.5]) {
        assert_eq!(b.shape.type_name(), "outline");
        assert_eq!(b.shape.edge_set_names(), ["boundary"]);
        let a = mesh_area(b);
        assert!(((a - area) / area).abs() < 1e-12, "{}: {a} vs {area}", b.name);
    }
    // the closing vertex of the second block was dropped
    let case::ShapeSpec::Outline { vertices } = &c.bodies[1].shape else { panic!() };
    assert_eq!(vertices.len(), 6);
    // scale and offset, and a mixture of materials
    let c = parse("[[imports]]\nfile = \"grains.csv\"\nmaterials = [\"alu\", \"soft\"]\nfractions = [2.0, 1.0]\nseed = 3\nmesh_size = 2.0\nscale = 2.0\noffset = [100.0, 0.0]\n").unwrap();
    let a = mesh_area(&c.bodies[2]);
    assert!((a - 4.0 * 22.5).abs() < 1e-9 * a, "{a}");
    let case::ShapeSpec::Outline { vertices } = &c.bodies[0].shape else { panic!() };
    assert_eq!(vertices[0], [104.0, 4.0]);
    let mut mats: Vec<usize> = c.bodies.iter().map(|b| b.material).collect();
    mats.sort();
    assert_eq!(mats, [0, 0, 1]);
    // the model meshes them
    let model = mpfem::model::Model::from_case(&c).unwrap();
    assert_eq!(model.bodies.len(), 3);
}

#[test]
fn gmsh_import_gives_one_body_per_physical_group() {
    let c = parse("[[imports]]\nfile = \"grains.msh\"\nmaterial = \"alu\"\n").unwrap();
    let names: Vec<&str> = c.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["grain_a", "grain_b"]);
    // grain_a: three unit quadrilaterals (one given clockwise); grain_b: a 2 x 2 square of
    // four triangles, each split into three quadrilaterals
    let expect = [(3.0, 3), (4.0, 12)];
    for (b, (area, n)) in c.bodies.iter().zip(expect) {
        let m = mpfem::case::mesh_body(b).unwrap();
        assert_eq!(m.n_elements(), n, "{}", b.name);
        assert!((m.area(&m.nodes) - area).abs() < 1e-12 * area, "{}", b.name);
        assert!((0..m.n_elements()).all(|e| m.element_area(e, &m.nodes) > 0.0), "{}: CCW", b.name);
        assert_eq!(m.boundary_loops().len(), 1, "{}", b.name);
        assert!(b.mesh_size > 0.0);
    }
    // mesh_size is not allowed for a gmsh file
    let e = parse("[[imports]]\nfile = \"grains.msh\"\nmaterial = \"alu\"\nmesh_size = 1.0\n").unwrap_err();
    assert_eq!(e.key, "imports[0].mesh_size");
    // one group as a body shape, scaled and shifted
    let c = parse("[[bodies]]\nname = \"b\"\nmaterial = \"alu\"\nshape = { type = \"gmsh\", file = \"grains.msh\", group = \"grain_b\", scale = 0.5, offset = [10.0, 0.0] }\n").unwrap();
    assert!((mesh_area(&c.bodies[0]) - 1.0).abs() < 1e-12);
    let e = parse("[[bodies]]\nname = \"b\"\nmaterial = \"alu\"\nshape = { type = \"gmsh\", file = \"grains.msh\", group = \"grain_c\" }\n").unwrap_err();
    assert_eq!(e.key, "bodies[0].shape.group");
    assert!(e.message.contains("grain_a, grain_b"), "{e}");
    // the packed case keeps the reference to the file and the group
    let t = mpfem::pack::body_table(&c.bodies[0], &c.materials);
    let shape = t["shape"].as_table().unwrap();
    assert_eq!(shape["type"].as_str(), Some("gmsh"));
    assert_eq!(shape["group"].as_str(), Some("grain_b"));
    assert!(Path::new(shape["file"].as_str().unwrap()).is_absolute());
}

#[test]
fn gmsh_errors_name_the_file_and_the_group() {
    use mpfem::mesh::import::{read_msh, MshError};
    let text = std::fs::read_to_string(data("grains.msh")).unwrap();
    // both surfaces in group 1: two separate squares
    let two = text.replace("2 3 0 0 5 2 0 1 2 0", "2 3 0 0 5 2 0 1 1 0");
    match read_msh(two.as_bytes()) {
        Err(e @ MshError::Disconnected { parts: 2, .. }) => assert!(e.to_string().contains("physical group 1 \"grain_a\""), "{e}"),
        other => panic!("{other:?}"),
    }
    // no physical group at all
    let none = text.replace("0 1 1 0\n", "0 0 0\n").replace("0 1 2 0\n", "0 0 0\n");
    assert_eq!(read_msh(none.as_bytes()), Err(MshError::NoSurfaceGroups));
    // the case error names the file
    let dir = std::env::temp_dir().join(format!("mpfem_import_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("two.msh"), &two).unwrap();
    let e = case::parse(&format!("{MATERIALS}\n[[imports]]\nfile = \"two.msh\"\nmaterial = \"alu\"\n"), &dir).unwrap_err();
    assert_eq!(e.key, "imports[0].file");
    assert!(e.message.contains("two.msh") && e.message.contains("grain_a") && e.message.contains("not one connected region"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn malformed_csv_line_is_an_error_naming_file_and_line() {
    let e = parse("[[imports]]\nfile = \"grains_bad.csv\"\nmaterial = \"alu\"\nmesh_size = 1.0\n").unwrap_err();
    assert_eq!(e.key, "imports[0].file");
    assert!(e.message.contains("grains_bad.csv") && e.message.contains("line 3") && e.message.contains("\"4; 0; 1\""), "{e}");
    assert!(e.message.contains("expected two finite numbers"), "{e}");
    // a missing mesh_size for a CSV file
    let e = parse("[[imports]]\nfile = \"grains.csv\"\nmaterial = \"alu\"\n").unwrap_err();
    assert_eq!(e.key, "imports[0].mesh_size");
    let e = parse("[[imports]]\nfile = \"grains.txt\"\nmaterial = \"alu\"\n").unwrap_err();
    assert!(e.message.contains("expected a .csv outline file or a .msh gmsh file"), "{e}");
}

#[test]
fn overlapping_outlines_are_an_error_naming_both() {
    let l = "[[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [1.0, 1.0], [1.0, 4.0], [0.0, 4.0]]";
    let body = |name: &str, vertices: &str| format!("[[bodies]]\nname = \"{name}\"\nmaterial = \"alu\"\nmesh_size = 0.5\nshape = {{ type = \"outline\", vertices = {vertices} }}\n");
    // a square in the notch of the L, touching it: fine
    let ok = body("l", l) + &body("sq", "[[1.0, 1.0], [3.0, 1.0], [3.0, 3.0], [1.0, 3.0]]");
    assert!(parse(&ok).is_ok());
    // moved into the L's arm: an error naming both
    let bad = body("l", l) + &body("sq", "[[0.5, 1.0], [2.5, 1.0], [2.5, 3.0], [0.5, 3.0]]");
    let e = parse(&bad).unwrap_err();
    assert_eq!(e.key, "bodies[1]");
    assert!(e.message.contains("\"sq\" (outline) overlaps body \"l\""), "{e}");
    // an outline against a disc
    let disc = "[[bodies]]\nname = \"d\"\nmaterial = \"alu\"\nmesh_size = 0.5\nshape = { type = \"disc\", center = [0.5, 3.0], radius = 0.6 }\n";
    let e = parse(&(body("l", l) + disc)).unwrap_err();
    assert!(e.message.contains("\"d\" (disc) overlaps body \"l\""), "{e}");
    // and a self-intersecting outline
    let e = parse(&body("x", "[[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 1.0]]")).unwrap_err();
    assert_eq!(e.key, "bodies[0].shape.vertices");
    assert!(e.message.contains("not simple"), "{e}");
    // imported grains overlapping a body
    let e = parse(&(body("l", "[[3.0, 3.0], [6.0, 3.0], [6.0, 6.0]]") + "[[imports]]\nfile = \"grains.csv\"\nmaterial = \"alu\"\nmesh_size = 1.0\n")).unwrap_err();
    assert!(e.message.contains("\"i0_p0\" (outline) overlaps body \"l\""), "{e}");
}

/// Two imported grains (an L and a pentagon) squeezed between a left and a right wall with the
/// default contact: the run converges to the target solid ratio 0.6 (from 0.434), the walls
/// carry load, nothing penetrates, and the particle area is conserved to 1 % (J2 plastic flow
/// is isochoric; the rest is elastic). (With `method = "penalty"` the same grains stall at
/// solid ratio 0.597, the penalty's active set alternating between two states at every step
/// size down to `dt_min`; main's binary of 88f10d8 got past that point with two cut-backs.)
#[test]
fn compaction_of_two_imported_grains() {
    let text = r#"
title = "two imported grains"
[[materials]]
name = "alu"
model = "j2"
youngs_modulus = 64100.0
poisson_ratio = 0.3
hardening = { preset = "aluminium_250c" }

[[walls]]
side = "left"
position = 0.0
velocity = 10.0

[[walls]]
side = "right"
position = 22.0
velocity = 10.0

[[walls]]
side = "bottom"
position = 0.0

[[walls]]
side = "top"
position = 11.0

[[imports]]
file = "two_grains.csv"
material = "alu"
mesh_size = 1.5

[stop]
solid_ratio = 0.6

[time]
end = 1.0
dt = 0.02
dt_max = 0.05
dt_min = 1e-5
"#;
    let c = case::parse(text, &data("")).unwrap();
    assert_eq!(c.bodies.len(), 2);
    let model = mpfem::model::Model::from_case(&c).unwrap();
    let mut sim = mpfem::solver::Simulation::new(model, c.time, c.solver).unwrap();
    let mut reports = Vec::new();
    let summary = sim.run(&mut |_, r| reports.push(r.clone())).unwrap();
    assert_eq!(summary.stop_reason, "solid ratio reached");
    let c: Vec<_> = reports.iter().map(|r| r.compaction.clone().unwrap()).collect();
    assert!(c.last().unwrap().solid_ratio >= 0.6);
    // the grains were squeezed (they also shift and turn against each other on the way, so
    // the wall forces come and go), and no node crossed another particle's boundary
    let peak = c.iter().map(|x| x.force[0].min(x.force[1])).fold(0.0, f64::max);
    assert!(peak > 50.0, "peak wall force {peak} N/mm");
    let pen = c.iter().map(|x| x.max_penetration).fold(0.0, f64::max);
    assert!(pen == 0.0, "penetration {pen} mm");
    let vol = sim.model.body_areas(&sim.coords(&sim.sol.u)).iter().sum::<f64>();
    let vol0 = sim.model.body_areas(&sim.model.x0).iter().sum::<f64>();
    assert!((vol0 - 105.0).abs() < 1e-9, "{vol0}");
    assert!(((vol - vol0) / vol0).abs() < 0.01, "area change {}", (vol - vol0) / vol0);
    eprintln!("{} steps, peak wall force {peak:.1} N/mm, area change {:.2e}", reports.len(), (vol - vol0) / vol0);
}

/// `mpfem pack` writes imported particles as bodies that load back to the same bodies:
/// outlines by their vertices, gmsh particles by a reference to the file and group.
#[test]
fn pack_writes_imported_particles_as_bodies() {
    let dir = std::env::temp_dir().join(format!("mpfem_import_pack_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let case_path = dir.join("case.toml");
    let text = format!(
        "{MATERIALS}\n[[imports]]\nfile = \"{}\"\nmaterial = \"alu\"\nmesh_size = 1.0\n\n[[imports]]\nfile = \"{}\"\nmaterial = \"soft\"\noffset = [0.0, 20.0]\n",
        data("grains.csv").display(),
        data("grains.msh").display()
    );
    std::fs::write(&case_path, text).unwrap();
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_mpfem")).arg("pack").arg(&case_path).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("5 particles"), "{}", String::from_utf8_lossy(&o.stdout));
    let a = case::load(&case_path).unwrap();
    let b = case::load(&out.join("packed.toml")).unwrap();
    assert_eq!(a.bodies, b.bodies);
    let packed = std::fs::read_to_string(out.join("packed.toml")).unwrap();
    assert!(!packed.lines().any(|l| l.starts_with("[[imports]]")));
    assert!(packed.contains("type = \"gmsh\"") && packed.contains("type = \"outline\""));
    std::fs::remove_dir_all(&dir).ok();
}
