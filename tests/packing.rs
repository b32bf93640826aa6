//! Random packings: exact solid ratio, no overlaps (checked pair by pair), particles inside the
//! die, seeded reproducibility, material fractions, meshable particles, and the `[[packings]]`
//! table of a case (expanded to bodies, checked by `mpfem check` after `mpfem pack`).

use std::path::Path;

use mpfem::mesh::quality::quality;
use mpfem::mesh::shapes;
use mpfem::packing::overlap::{signed_distance, Convex};
use mpfem::packing::random::{material_counts, random_discs, voronoi_ellipses, voronoi_polygons, Die, PackError, Packing, RandomSpec, Sizes};

mod common;
use common::{mpfem, tmpdir};

type Generator = fn(Die, &RandomSpec) -> Result<Packing, PackError>;
const GENERATORS: [Generator; 3] = [voronoi_polygons, voronoi_ellipses, random_discs];

const DIE: Die = Die { x: [10.0, 110.0], y: [-20.0, 60.0] };

fn spec(count: usize, seed: u64, phi: f64, sizes: Sizes) -> RandomSpec {
    RandomSpec { count, seed, solid_ratio: phi, sizes, lloyd: 10, aspect: 1.0, fractions: vec![1.0] }
}

/// Every pair apart (positive signed distance) and every particle inside the die.
fn assert_valid(p: &Packing) {
    let n = p.particles.len();
    for i in 0..n {
        let b = p.particles[i].shape.aabb();
        assert!(b[0] > p.die.x[0] && b[1] < p.die.x[1] && b[2] > p.die.y[0] && b[3] < p.die.y[1], "particle {i} leaves the die: {b:?}");
        for j in i + 1..n {
            let d = signed_distance(&p.particles[i].shape, &p.particles[j].shape).unwrap();
            assert!(d > 0.0, "particles {i} and {j} overlap: signed distance {d}");
        }
    }
}

/// Mesh every particle (element size a fifth of its typical size) and require no inverted
/// element.
fn assert_meshable(p: &Packing) {
    for (i, part) in p.particles.iter().enumerate() {
        let mesh = match &part.shape {
            Convex::Disc { center, radius } => shapes::disc(*center, *radius, radius / 2.0),
            Convex::Polygon(v) => {
                let h = 0.3 * part.shape.area().sqrt();
                shapes::convex_polygon(v, h).unwrap_or_else(|e| panic!("particle {i}: {e}"))
            }
            Convex::Ellipse { center, semi_axes, angle_deg } => shapes::ellipse(*center, *semi_axes, *angle_deg, semi_axes[1] / 2.0),
        };
        let q = quality(&mesh, &mesh.nodes);
        assert_eq!(q.n_inverted, 0, "particle {i}: inverted elements");
        assert!(q.min_scaled_jacobian > 0.2, "particle {i}: min scaled Jacobian {} {:?} {} elems h {}", q.min_scaled_jacobian, part.shape, mesh.elements.len(), 0.3 * part.shape.area().sqrt());
    }
}

#[test]
fn voronoi_polygons_hit_the_solid_ratio_exactly() {
    for (count, phi, sizes) in [(16, 0.65, Sizes::Equal), (16, 0.80, Sizes::Equal), (12, 0.75, Sizes::Uniform { ratio: 1.6 }), (9, 0.70, Sizes::LogNormal { sigma: 0.2, ratio: 2.0 })] {
        let p = voronoi_polygons(DIE, &spec(count, 7, phi, sizes)).unwrap();
        assert_eq!(p.particles.len(), count);
        assert!((p.solid_ratio() - phi).abs() < 1e-12, "{count} polygons at {phi}: {}", p.solid_ratio());
        assert_valid(&p);
        assert_meshable(&p);
        for part in &p.particles {
            let Convex::Polygon(v) = &part.shape else { panic!("not a polygon") };
            assert!(v.len() >= 3 && mpfem::mesh::polygon_area(v.iter().copied()) > 0.0, "counter-clockwise polygon");
        }
    }
    // more seeds: every cell meshes well
    for seed in 0..8 {
        let p = voronoi_polygons(DIE, &spec(16, seed, 0.8, Sizes::Equal)).unwrap();
        assert!((p.solid_ratio() - 0.8).abs() < 1e-12);
        assert_meshable(&p);
    }
    // even 0.97 is reachable (the simplified cells cover more of the die)
    for seed in 0..8 {
        let p = voronoi_polygons(DIE, &spec(16, seed, 0.97, Sizes::Equal)).unwrap();
        assert!((p.solid_ratio() - 0.97).abs() < 1e-12);
        assert_valid(&p);
    }
    // ... but not 0.999: refused with a message naming the cover
    let e = voronoi_polygons(DIE, &spec(16, 0, 0.999, Sizes::Equal)).unwrap_err();
    assert_eq!(e.param, "solid_ratio");
    assert!(e.message.contains("cover"), "{e}");
}

#[test]
fn random_discs_hit_the_solid_ratio_exactly() {
    for (count, phi, sizes) in [(16, 0.65, Sizes::Equal), (16, 0.70, Sizes::Equal), (16, 0.68, Sizes::Uniform { ratio: 2.0 }), (12, 0.65, Sizes::LogNormal { sigma: 0.3, ratio: 2.5 })] {
        let p = random_discs(DIE, &spec(count, 3, phi, sizes)).unwrap_or_else(|e| panic!("{count} discs at {phi}: {e}"));
        assert_eq!(p.particles.len(), count);
        assert!((p.solid_ratio() - phi).abs() < 1e-12, "{count} discs at {phi}: {}", p.solid_ratio());
        assert_valid(&p);
        assert_meshable(&p);
        let radii: Vec<f64> = p.particles.iter().map(|q| match q.shape { Convex::Disc { radius, .. } => radius, _ => panic!("not a disc") }).collect();
        let (lo, hi) = radii.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
        match sizes {
            Sizes::Equal => assert!(hi / lo - 1.0 < 1e-12),
            Sizes::Uniform { ratio } | Sizes::LogNormal { ratio, .. } => assert!(hi / lo > 1.05 && hi / lo <= ratio * (1.0 + 1e-12), "radius ratio {}", hi / lo),
        }
    }
}

#[test]
fn voronoi_ellipses_hit_the_solid_ratio_exactly() {
    for (count, phi, sizes, aspect) in [(16, 0.65, Sizes::Equal, 1.0), (16, 0.70, Sizes::Uniform { ratio: 2.0 }, 1.0), (12, 0.65, Sizes::Equal, 2.0), (9, 0.65, Sizes::LogNormal { sigma: 0.2, ratio: 2.0 }, 0.5)] {
        let p = voronoi_ellipses(DIE, &RandomSpec { aspect, ..spec(count, 2, phi, sizes) }).unwrap_or_else(|e| panic!("{count} ellipses at {phi}: {e}"));
        assert_eq!(p.particles.len(), count);
        assert!((p.solid_ratio() - phi).abs() < 1e-12, "{count} ellipses at {phi}: {}", p.solid_ratio());
        assert_valid(&p);
        assert_meshable(&p);
        // elongated cells give ellipses elongated along x (on average)
        let mean_x_extent: f64 = p.particles.iter().map(|q| { let b = q.shape.aabb(); (b[1] - b[0]) / (b[3] - b[2]) }).sum::<f64>() / count as f64;
        if aspect > 1.0 {
            assert!(mean_x_extent > 1.3, "{mean_x_extent}");
        } else if aspect < 1.0 {
            assert!(mean_x_extent < 0.8, "{mean_x_extent}");
        }
    }
    let e = voronoi_ellipses(DIE, &spec(16, 0, 0.85, Sizes::Equal)).unwrap_err();
    assert_eq!(e.param, "solid_ratio");
    assert!(e.message.contains("cover"), "{e}");
}

#[test]
fn too_dense_discs_are_refused_with_a_message() {
    // 4 equal discs in a square die cannot beat pi/4
    let e = random_discs(Die { x: [0.0, 10.0], y: [0.0, 10.0] }, &spec(4, 1, 0.80, Sizes::Equal)).unwrap_err();
    assert_eq!(e.param, "solid_ratio");
    assert!(e.message.contains("0.8"), "{e}");
}

#[test]
fn same_seed_same_packing_other_seed_other_packing() {
    for make in GENERATORS {
        let s = spec(8, 42, 0.6, Sizes::Uniform { ratio: 1.5 });
        let a = make(DIE, &s).unwrap();
        let b = make(DIE, &s).unwrap();
        assert_eq!(a, b);
        let c = make(DIE, &RandomSpec { seed: 43, ..s }).unwrap();
        assert_ne!(a, c);
    }
}

#[test]
fn material_fractions_are_within_one_particle() {
    let fr = [0.5, 0.3, 0.2];
    for count in [1, 5, 7, 13, 16] {
        let counts = material_counts(count, &fr);
        assert_eq!(counts.iter().sum::<usize>(), count);
        for (c, f) in counts.iter().zip(fr) {
            assert!((*c as f64 - f * count as f64).abs() < 1.0, "{counts:?} for {count}");
        }
    }
    for make in GENERATORS {
        let s = RandomSpec { fractions: fr.to_vec(), ..spec(16, 5, 0.65, Sizes::Equal) };
        let p = make(DIE, &s).unwrap();
        for (m, f) in fr.iter().enumerate() {
            let n = p.particles.iter().filter(|q| q.material == m).count();
            assert!((n as f64 - f * 16.0).abs() <= 1.0, "material {m}: {n} of 16 for fraction {f}");
        }
        // mixed, not in blocks: the first half holds more than one material
        let first: std::collections::BTreeSet<usize> = p.particles[..8].iter().map(|q| q.material).collect();
        assert!(first.len() > 1);
    }
}

// ---------------------------------------------------------------------------------------------
// The case table and `mpfem pack`

const CASE: &str = r#"
title = "random packing"

[[materials]]
name = "alu"
model = "elastic"
youngs_modulus = 64100.0
poisson_ratio = 0.3

[[materials]]
name = "lead"
model = "elastic"
youngs_modulus = 16000.0
poisson_ratio = 0.44

[[walls]]
side = "left"
position = 0.0
velocity = 10.0

[[walls]]
side = "right"
position = 100.0
velocity = 10.0

[[walls]]
side = "bottom"
position = 0.0

[[walls]]
side = "top"
position = 80.0

[[packings]]
kind = "voronoi_polygons"
count = 9
seed = 11
solid_ratio = 0.75
materials = ["alu", "lead"]
fractions = [2.0, 1.0]
mesh_size = 6.0

[time]
end = 1.0
dt = 0.1
"#;

#[test]
fn packings_expand_to_bodies_in_the_die() {
    for (kind, extra) in [("voronoi_polygons", ""), ("voronoi_ellipses", "aspect = 1.5\n"), ("discs", "sizes = { distribution = \"uniform\", ratio = 1.5 }\n")] {
        let text = CASE.replace("kind = \"voronoi_polygons\"", &format!("kind = \"{kind}\"\n{extra}")).replace("solid_ratio = 0.75", "solid_ratio = 0.65");
        let c = mpfem::case::parse(&text, Path::new(".")).unwrap();
        assert_eq!(c.bodies.len(), 9);
        assert!(c.bodies.iter().enumerate().all(|(k, b)| b.name == format!("r0_p{k}") && b.mesh_size == 6.0));
        let area: f64 = c.bodies.iter().map(|b| b.shape.convex().unwrap().area()).sum();
        assert!((area / 8000.0 - 0.65).abs() < 1e-12);
        let alu = c.bodies.iter().filter(|b| b.material == 0).count();
        assert_eq!(alu, 6, "2 : 1 of 9");
        // the same text gives the same bodies
        assert_eq!(mpfem::case::parse(&text, Path::new(".")).unwrap().bodies, c.bodies);
    }
}

#[test]
fn pack_writes_a_case_that_checks_and_a_preview() {
    let dir = tmpdir("cli");
    let case = dir.join("case.toml");
    std::fs::write(&case, CASE).unwrap();
    let out = dir.join("out");
    let o = mpfem().arg("pack").arg(&case).arg("--out").arg(&out).output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("9 particles") && stdout.contains("solid ratio 0.750000"), "{stdout}");
    let packed = out.join("packed.toml");
    let text = std::fs::read_to_string(&packed).unwrap();
    assert!(!text.contains("\n[[packings]]") && !text.contains("kind = ") && text.contains("r0_p8"), "{text}");
    // the written case has the same bodies, listed, and passes `mpfem check` (meshes, no
    // inverted element)
    let a = mpfem::case::load(&case).unwrap();
    let b = mpfem::case::load(&packed).unwrap();
    assert_eq!(a.bodies, b.bodies);
    let o = mpfem().arg("check").arg(&packed).output().unwrap();
    assert!(o.status.success(), "{}\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("0 inverted element(s)"));
    // the preview is a PNG picture
    let png = std::fs::read(out.join("packing.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"));
    // a case without walls and with a hardening table file: no die, and the file is found
    // from the written case
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("jobs/examples/upsetting_table_file.toml");
    let out2 = dir.join("out2");
    let o = mpfem().arg("pack").arg(&src).arg("--out").arg(&out2).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("1 particles (no die"));
    assert_eq!(mpfem::case::load(&out2.join("packed.toml")).unwrap().materials, mpfem::case::load(&src).unwrap().materials);
    // a missing case file is bad input
    let o = mpfem().arg("pack").arg(dir.join("missing.toml")).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
}
