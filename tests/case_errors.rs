//! Case-file validation: every bad input gives one clear error naming the key, the value and
//! the expectation; every shipped job parses; defaults are applied as documented.

use std::path::Path;

use mpfem::case::{
    self, Amplitude, CaseError, Formulation, LinearChoice, LoadKind, NewtonKind, ShapeSpec,
    SolverSpec, TimeSpec,
};
use mpfem::dynamics::Integrator;
use mpfem::linalg::{LinearSolverKind, Preconditioner};
use mpfem::material::Material;

mod common;
use common::root;

fn bad(name: &str) -> CaseError {
    let path = root().join("jobs/examples/bad").join(name);
    assert!(path.exists(), "missing test input {}", path.display());
    match case::load(&path) {
        Ok(_) => panic!("{name} should have been rejected"),
        Err(e) => e,
    }
}

/// A minimal valid case with `extra` appended and `from` replaced by `to`.
const BASE: &str = r#"
[[materials]]
name = "alu"
model = "elastic"
youngs_modulus = 64100.0
poisson_ratio = 0.3

[[bodies]]
name = "block"
material = "alu"
mesh_size = 2.0
shape = { type = "rectangle", origin = [0.0, 0.0], size = [20.0, 20.0] }

[time]
end = 1.0
dt = 0.1
"#;

fn parse(text: &str) -> Result<case::Case, CaseError> {
    case::parse(text, Path::new("."))
}

fn err_of(text: &str) -> CaseError {
    match parse(text) {
        Ok(_) => panic!("should have been rejected:\n{text}"),
        Err(e) => e,
    }
}

fn with(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "{from} not in BASE");
    BASE.replacen(from, to, 1)
}

fn assert_has(e: &CaseError, parts: &[&str]) {
    let s = e.to_string();
    for p in parts {
        assert!(s.contains(p), "error {s:?} does not mention {p:?}");
    }
}

#[test]
fn base_is_valid() {
    parse(BASE).unwrap();
}

#[test]
fn unknown_key_names_line_and_field() {
    let e = bad("unknown_key.toml");
    assert_eq!(e.key, "materials[0].youngs_modulus2");
    assert_has(
        &e,
        &[
            "line 5, column 1",
            "unknown field `youngs_modulus2`",
            "expected one of",
            "`youngs_modulus`",
        ],
    );
    // in a nested inline table too
    let e = err_of(&with(
        "size = [20.0, 20.0] }",
        "size = [20.0, 20.0], radius = 1.0, colour = 3 }",
    ));
    assert_eq!(e.key, "bodies[0].shape.colour");
    assert_has(&e, &["line 12", "unknown field `colour`"]);
    // at the top level
    let e = err_of(&format!("{BASE}\n[mesh]\nsize = 1\n"));
    assert_has(&e, &["unknown field `mesh`", "line 18"]);
}

#[test]
fn wrong_type() {
    let e = bad("wrong_type.toml");
    assert_eq!(e.key, "materials[0].poisson_ratio");
    assert_has(
        &e,
        &["line 6", "invalid type: string \"0.3\"", "expected f64"],
    );
    let e = err_of(&with("mesh_size = 2.0", "mesh_size = true"));
    assert_has(&e, &["bodies[0].mesh_size", "boolean", "f64"]);
    let e = err_of(&format!("{BASE}\n[solver]\nmax_iterations = 2.5\n"));
    assert_has(&e, &["solver.max_iterations", "2.5", "i64"]);
    let e = err_of(&format!("{BASE}\n[solver]\nline_search = \"yes\"\n"));
    assert_has(&e, &["solver.line_search", "\"yes\"", "bool"]);
}

#[test]
fn pairs_must_have_two_entries() {
    let e = err_of(&with("size = [20.0, 20.0]", "size = [20.0, 20.0, 1.0]"));
    assert_eq!(e.key, "bodies[0].shape.size");
    assert_has(&e, &["line 12", "invalid length 3", "exactly two"]);
    let e = err_of(&with("size = [20.0, 20.0]", "size = [20.0]"));
    assert_has(&e, &["bodies[0].shape.size", "invalid length 1"]);
    let e = err_of(&with("mesh_size = 2.0", "divisions = [1, 2, 3]"));
    assert_has(&e, &["bodies[0].divisions", "invalid length 3"]);
}

#[test]
fn syntax_error_has_line() {
    let e = err_of(&with("poisson_ratio = 0.3", "poisson_ratio = = 0.3"));
    assert_has(&e, &["line 6"]);
}

/// Issue 23: the parser's "duplicate key" names the key, and its recursion limit (no position
/// from the parser) names the line nested deepest.
#[test]
fn duplicate_keys_and_deep_nesting_are_named() {
    let e = err_of(&with("poisson_ratio = 0.3", "poisson_ratio = 0.3\npoisson_ratio = 0.4"));
    assert_has(&e, &["line 7", "duplicate key `poisson_ratio`"]);
    let e = err_of(&format!("{BASE}\n[stop]\nsolid_ratio = 0.9\n[stop]\njam = true\n"));
    assert_has(&e, &["duplicate key `stop`"]);
    let deep = format!("{BASE}\n{} = 1\n", vec!["a"; 300].join("."));
    let line = deep.lines().count();
    let e = err_of(&deep);
    assert_has(&e, &[&format!("line {line}"), "nested too deeply"]);
}

#[test]
fn youngs_modulus_must_be_positive() {
    for v in ["0.0", "-5.0"] {
        let e = err_of(&with(
            "youngs_modulus = 64100.0",
            &format!("youngs_modulus = {v}"),
        ));
        assert_eq!(e.key, "materials[0].youngs_modulus");
        assert_has(&e, &[v, "Young's modulus", "> 0", "line 5"]);
    }
}

#[test]
fn poisson_ratio_range() {
    let e = bad("poisson_too_large.toml");
    assert_eq!(e.key, "materials[0].poisson_ratio");
    assert_has(&e, &["0.7", "Poisson's ratio in [0, 0.5]"]);
    let e = err_of(&with("poisson_ratio = 0.3", "poisson_ratio = -0.1"));
    assert_eq!(e.key, "materials[0].poisson_ratio");
    assert_has(&e, &["-0.1", "Poisson's ratio in [0, 0.5]"]);
    // the limits are accepted
    parse(&with("poisson_ratio = 0.3", "poisson_ratio = 0.5")).unwrap();
    parse(&with("poisson_ratio = 0.3", "poisson_ratio = 0")).unwrap();
}

#[test]
fn hardening_table_not_increasing() {
    let e = bad("hardening_not_increasing.toml");
    assert_eq!(e.key, "materials[0].hardening.points[2]");
    assert_has(&e, &["0.0011", "0.0031", "strictly increasing"]);
    let j2 = with("model = \"elastic\"", "model = \"j2\"");
    let e = err_of(&j2.replace(
        "poisson_ratio = 0.3",
        "poisson_ratio = 0.3\nhardening = { strain = \"plastic\", points = [[0.0, 100.0], [0.1, 90.0]] }",
    ));
    assert_eq!(e.key, "materials[0].hardening.points[1]");
    assert_has(&e, &["90.0", "100.0", "non-decreasing"]);
}

#[test]
fn missing_hardening_file_names_path() {
    let e = bad("missing_hardening_file.toml");
    assert_eq!(e.key, "materials[0].hardening.file");
    assert_has(&e, &["no_such_dir", "missing_table.csv", "cannot read"]);
}

#[test]
fn missing_case_file_names_path() {
    let p = root().join("jobs/does_not_exist.toml");
    let e = case::load(&p).unwrap_err();
    assert_has(&e, &["does_not_exist.toml", "cannot read case file"]);
}

#[test]
fn unknown_material_reference() {
    let e = bad("unknown_material.toml");
    assert_eq!(e.key, "bodies[0].material");
    assert_has(&e, &["\"steel\"", "no material named", "known: alu"]);
}

#[test]
fn unknown_edge_set() {
    let e = bad("unknown_edge_set.toml");
    assert_eq!(e.key, "boundary[0].set");
    assert_has(
        &e,
        &[
            "\"outer\"",
            "rectangle",
            "left, right, bottom, top, boundary",
        ],
    );
    let e = err_of(&format!(
        "{BASE}\n[output]\nreactions = [\"block.side3\"]\n"
    ));
    assert_eq!(e.key, "output.reactions[0]");
    assert_has(&e, &["side3"]);
    let e = err_of(&format!("{BASE}\n[output]\nreactions = [\"brick.top\"]\n"));
    assert_has(&e, &["no body named \"brick\"", "known: block"]);
}

#[test]
fn creep_without_stress_unit() {
    let e = bad("creep_without_stress_unit.toml");
    assert_eq!(e.key, "materials[0].creep.stress_unit");
    assert_has(
        &e,
        &[
            "missing",
            "\"Pa\"",
            "\"MPa\"",
            "paper does not state",
            "orders of magnitude",
        ],
    );
}

#[test]
fn duplicate_body_names() {
    let e = bad("duplicate_body.toml");
    assert_eq!(e.key, "bodies[1].name");
    assert_has(&e, &["\"block\"", "duplicated body name", "unique"]);
}

#[test]
fn dt_larger_than_end() {
    let e = bad("dt_larger_than_end.toml");
    assert_eq!(e.key, "time.dt");
    assert_has(&e, &["2.0", "dt <= end = 1.0"]);
}

#[test]
fn nan_and_inf_rejected() {
    let e = err_of(&with("youngs_modulus = 64100.0", "youngs_modulus = nan"));
    assert_eq!(e.key, "materials[0].youngs_modulus");
    assert_has(&e, &["NaN", "finite"]);
    let e = err_of(&with("end = 1.0", "end = inf"));
    assert_eq!(e.key, "time.end");
    assert_has(&e, &["inf", "finite"]);
    let e = err_of(&with("size = [20.0, 20.0]", "size = [20.0, nan]"));
    assert_eq!(e.key, "bodies[0].shape.size[1]");
}

#[test]
fn other_validation_errors() {
    // missing [time]
    let e = err_of(&BASE.replace("[time]\nend = 1.0\ndt = 0.1\n", ""));
    assert_eq!(e.key, "time");
    // j2 without yield behaviour, yield_stress on an elastic material
    let e = err_of(&with("model = \"elastic\"", "model = \"j2\""));
    assert_has(&e, &["materials[0]", "yield_stress", "hardening"]);
    let e = err_of(&with(
        "poisson_ratio = 0.3",
        "poisson_ratio = 0.3\nyield_stress = 100.0",
    ));
    assert_eq!(e.key, "materials[0].yield_stress");
    // bad choice strings
    let e = err_of(&format!("{BASE}\n[solver]\nlinear = \"gmres\"\n"));
    assert_has(&e, &["solver.linear", "\"gmres\"", "\"cholesky\""]);
    // PETSc's options: only with linear = "petsc", each word of its command line an option
    // or a value after one
    let e = err_of(&format!("{BASE}\n[solver]\npetsc_options = \"-ksp_type cg\"\n"));
    assert_has(&e, &["solver.petsc_options", "-ksp_type cg", "linear = \"petsc\""]);
    if cfg!(feature = "petsc") {
        let e = err_of(&format!("{BASE}\n[solver]\nlinear = \"petsc\"\npetsc_options = \"ksp_type cg\"\n"));
        assert_has(&e, &["solver.petsc_options", "\"ksp_type\"", "'-'"]);
        let c = parse(&format!("{BASE}\n[solver]\nlinear = \"petsc\"\npetsc_options = \"-ksp_type cg -pc_type gamg\"\n")).unwrap();
        assert_eq!((c.solver.linear, c.petsc_options.as_str()), (LinearChoice::Fixed(LinearSolverKind::Petsc), "-ksp_type cg -pc_type gamg"));
    } else {
        // a build without PETSc says so, naming the key and how to get it
        let e = err_of(&format!("{BASE}\n[solver]\nlinear = \"petsc\"\n"));
        assert_has(&e, &["solver.linear", "\"petsc\"", "without PETSc", "--features petsc"]);
    }
    // repartition threshold: an imbalance, at least 1 (1 itself is allowed)
    let e = err_of(&format!("{BASE}\n[solver]\nrepartition_imbalance = 0.9\n"));
    assert_has(&e, &["solver.repartition_imbalance", "0.9", ">= 1"]);
    let e = err_of(&format!("{BASE}\n[solver]\nrepartition_imbalance = nan\n"));
    assert_has(&e, &["solver.repartition_imbalance", "NaN", ">= 1"]);
    assert_eq!(parse(&format!("{BASE}\n[solver]\nrepartition_imbalance = 1.0\n")).unwrap().solver.repartition_imbalance, 1.0);
    let e = err_of(&format!("[model]\nformulation = \"eulerian\"\n{BASE}"));
    assert_has(
        &e,
        &["model.formulation", "\"eulerian\"", "total_lagrangian"],
    );
    // boundary without displacements, radial on a rectangle
    let e = err_of(&format!(
        "{BASE}\n[[boundary]]\nbody = \"block\"\nset = \"top\"\n"
    ));
    assert_eq!(e.key, "boundary[0]");
    let e = err_of(&format!(
        "{BASE}\n[[boundary]]\nbody = \"block\"\nset = \"top\"\nradial = 1.0\n"
    ));
    assert_eq!(e.key, "boundary[0].radial");
    // amplitude table times not increasing
    let e = err_of(&format!(
        "{BASE}\n[[boundary]]\nbody = \"block\"\nset = \"top\"\nuy = 1.0\namplitude = [[0.0, 0.0], [1.0, 1.0], [0.5, 2.0]]\n"
    ));
    assert_eq!(e.key, "boundary[0].amplitude[2]");
    assert_has(&e, &["strictly increasing"]);
    // pressure needs a scalar
    let e = err_of(&format!("{BASE}\n[[loads]]\nbody = \"block\"\nset = \"top\"\ntype = \"pressure\"\nvalue = [1.0, 2.0]\n"));
    assert_eq!(e.key, "loads[0].value");
    // shape parameter of another type
    let e = err_of(&with(
        "size = [20.0, 20.0] }",
        "size = [20.0, 20.0], radius = 3.0 }",
    ));
    assert_eq!(e.key, "bodies[0].shape.radius");
    // polygon with two vertices, divisions on a disc
    let e = err_of(&with(
        "shape = { type = \"rectangle\", origin = [0.0, 0.0], size = [20.0, 20.0] }",
        "shape = { type = \"polygon\", vertices = [[0, 0], [1, 0]] }",
    ));
    assert_eq!(e.key, "bodies[0].shape.vertices");
    let e = err_of(&with(
        "shape = { type = \"rectangle\", origin = [0.0, 0.0], size = [20.0, 20.0] }",
        "divisions = [4, 4]\nshape = { type = \"disc\", radius = 3.0 }",
    ));
    assert_eq!(e.key, "bodies[0].divisions");
    // time keys
    let e = err_of(&with("dt = 0.1", "dt = 0.1\ncutback = 1.0"));
    assert_eq!(e.key, "time.cutback");
    let e = err_of(&with("dt = 0.1", "dt = 0.1\nmax_steps = 0"));
    assert_has(&e, &["time.max_steps", "value 0", ">= 1"]);
    // creep parameter out of range
    let creep = with("model = \"elastic\"", "model = \"creep\"").replace(
        "poisson_ratio = 0.3",
        "poisson_ratio = 0.3\ncreep = { preset = \"asphalt_table2\", stress_unit = \"Pa\", m = 1.5 }",
    );
    let e = err_of(&creep);
    assert_eq!(e.key, "materials[0].creep.m");
    // duplicate material names
    let e = err_of(&format!(
        "{BASE}\n[[materials]]\nname = \"alu\"\nmodel = \"elastic\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.2\n"
    ));
    assert_eq!(e.key, "materials[1].name");
}

#[test]
fn dynamic_integrator_keys() {
    let dynamic = |keys: &str| with("dt = 0.1", &format!("dt = 0.1\n{keys}"));
    let dense = |text: String| text.replace("poisson_ratio = 0.3", "poisson_ratio = 0.3\ndensity = 2.7e-9");
    // the density is required, naming the material
    let e = err_of(&dynamic("integrator = \"newmark\""));
    assert_eq!(e.key, "materials[0].density");
    assert_has(&e, &["\"alu\"", "density > 0", "time.integrator"]);
    // bad choice, out-of-range and misplaced parameters
    let e = err_of(&dense(dynamic("integrator = \"explicit\"")));
    assert_has(&e, &["time.integrator", "\"explicit\"", "\"newmark\"", "\"hht\""]);
    let e = err_of(&dense(dynamic("integrator = \"hht\"\nhht_alpha = 0.1")));
    assert_eq!(e.key, "time.hht_alpha");
    assert_has(&e, &["value 0.1", "[-1/3, 0]"]);
    let e = err_of(&dense(dynamic("integrator = \"hht\"\nhht_alpha = -0.5")));
    assert_has(&e, &["time.hht_alpha", "-0.5"]);
    let e = err_of(&dense(dynamic("integrator = \"newmark\"\nhht_alpha = -0.1")));
    assert_eq!(e.key, "time.hht_alpha");
    assert_has(&e, &["not allowed", "\"newmark\"", "\"hht\""]);
    let e = err_of(&dense(dynamic("newmark_beta = 0.25")));
    assert_has(&e, &["time.newmark_beta", "\"static\""]);
    let e = err_of(&dense(dynamic("integrator = \"newmark\"\nnewmark_gamma = 0.4")));
    assert_has(&e, &["time.newmark_gamma", "value 0.4", "[0.5, 1]"]);
    let e = err_of(&dense(dynamic("integrator = \"newmark\"\nnewmark_beta = 0.1")));
    assert_has(&e, &["time.newmark_beta", "value 0.1", "[0.25, 1]"]);
    // defaults: HHT α = −0.05, trapezoidal Newmark, β from γ, the step does not grow
    let c = parse(&dense(dynamic("integrator = \"hht\""))).unwrap();
    assert_eq!(c.time.integrator, Integrator::Hht { alpha: -0.05 });
    assert_eq!(c.time.dt_max, 0.1);
    let c = parse(&dense(dynamic("integrator = \"newmark\"\ndt_max = 0.5"))).unwrap();
    assert_eq!(c.time.integrator, Integrator::Newmark { beta: 0.25, gamma: 0.5 });
    assert_eq!(c.time.dt_max, 0.5);
    let c = parse(&dense(dynamic("integrator = \"newmark\"\nnewmark_gamma = 0.6"))).unwrap();
    let Integrator::Newmark { beta, gamma } = c.time.integrator else { panic!("{:?}", c.time.integrator) };
    assert_eq!(gamma, 0.6);
    assert!((beta - 0.3025).abs() < 1e-15);
    // quasi-static cases need no density
    assert_eq!(parse(&dynamic("integrator = \"static\"")).unwrap().time.integrator, Integrator::Static);
}

#[test]
fn error_display_is_key_colon_message() {
    let e = CaseError::new("time.dt", "value 2.0; expected 0 < dt <= end");
    assert_eq!(e.to_string(), "time.dt: value 2.0; expected 0 < dt <= end");
}

#[test]
fn all_shipped_jobs_parse() {
    let mut files = vec![root().join("jobs/default.toml")];
    for entry in std::fs::read_dir(root().join("jobs/examples")).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            files.push(p);
        }
    }
    assert!(
        files.len() >= 6,
        "expected the example jobs, found {files:?}"
    );
    for f in &files {
        if let Err(e) = case::load(f) {
            panic!("{} does not parse: {e}", f.display());
        }
    }
}

#[test]
fn documented_complete_example_parses() {
    let doc = std::fs::read_to_string(root().join("docs/case-file.md")).unwrap();
    let section = doc
        .split("## Complete example")
        .nth(1)
        .expect("docs have a complete example");
    let block = section
        .split("```toml")
        .nth(1)
        .unwrap()
        .split("```")
        .next()
        .unwrap();
    let c = case::parse(block, &root())
        .unwrap_or_else(|e| panic!("documented example does not parse: {e}"));
    assert_eq!(c.materials.len(), 2);
    assert_eq!(c.bodies.len(), 2);
    assert_eq!(c.bodies[1].divisions, Some([10, 5]));
    assert_eq!(c.time.dt_min, 1e-7);
    assert_eq!(c.linear_kind(), LinearSolverKind::Lu);
}

#[test]
fn every_bad_job_is_rejected() {
    for entry in std::fs::read_dir(root().join("jobs/examples/bad")).unwrap() {
        let p = entry.unwrap().path();
        assert!(
            case::load(&p).is_err(),
            "{} should be rejected",
            p.display()
        );
    }
}

#[test]
fn default_case_parses() {
    let c = case::default_case();
    assert_eq!(c.formulation, Formulation::UpdatedLagrangian);
    assert_eq!(c.bodies.len(), 1);
    assert_eq!(c.bodies[0].name, "block");
    assert_eq!(
        c.bodies[0].shape,
        ShapeSpec::Rectangle {
            origin: [0.0, 0.0],
            size: [20.0, 20.0]
        }
    );
    assert_eq!(c.bodies[0].mesh_size, 2.0);
    assert!(matches!(c.materials[0].material, Material::J2(_)));
    assert_eq!(c.time.end, 0.6);
    assert_eq!(c.time.dt, 0.02);
    let top = c.boundary.iter().find(|b| b.set == "top").unwrap();
    assert_eq!(top.uy, Some(-6.0));
    assert_eq!(top.amplitude, Amplitude::Ramp);
    assert!(c.output.reactions.contains(&(0, "top".to_string())));
    assert_eq!(case::parse(case::DEFAULT_JOB, Path::new(".")).unwrap(), c);
}

#[test]
fn defaults_are_applied() {
    let c = parse(BASE).unwrap();
    assert_eq!(c.title, "");
    assert_eq!(c.formulation, Formulation::UpdatedLagrangian);
    assert_eq!(c.materials[0].density, 1e-9);
    assert!(c.boundary.is_empty() && c.loads.is_empty());
    assert_eq!(c.bodies[0].divisions, None);
    assert_eq!(
        c.time,
        TimeSpec {
            end: 1.0,
            dt: 0.1,
            dt_min: 1e-6,
            dt_max: 1.0,
            growth: 1.5,
            cutback: 0.5,
            easy_iterations: 6,
            max_steps: 100_000,
            integrator: Integrator::Static,
        }
    );
    let s = c.solver;
    // with the barrier contact (the default) full Newton gets 100 iterations a solve, 25 with
    // the node-to-segment methods
    assert_eq!(s, SolverSpec { max_iterations: 100, ..SolverSpec::default() });
    assert_eq!(s.newton, NewtonKind::Full);
    assert_eq!(s.max_iterations, 100);
    assert_eq!(SolverSpec::default().max_iterations, 25);
    assert_eq!(s.residual_tol, 1e-8);
    assert_eq!(s.energy_tol, 1e-16);
    assert!(s.line_search);
    assert_eq!(s.linear, LinearChoice::Auto);
    assert_eq!(s.preconditioner, Preconditioner::Ic0);
    assert_eq!(s.pcg_tol, 1e-10);
    assert_eq!(s.pcg_max_iterations, 10_000);
    assert_eq!(s.threads, 0);
    assert_eq!(s.incompressible_penalty, 1000.0);
    assert_eq!(s.volume_tol, 1e-10);
    assert_eq!(s.max_volume_updates, 30);
    assert_eq!(s.repartition_imbalance, 1.05);
    assert!(c.output.reactions.is_empty() && c.output.displacements.is_empty());
    assert_eq!(c.linear_kind(), LinearSolverKind::Cholesky);

    // modified Newton raises the default iteration limit
    let m = parse(&format!("{BASE}\n[solver]\nnewton = \"modified\"\n")).unwrap();
    assert_eq!(m.solver.newton, NewtonKind::Modified);
    assert_eq!(m.solver.max_iterations, 60);
    // dt_min default never exceeds dt
    let t = parse(&with("dt = 0.1", "dt = 1e-8")).unwrap();
    assert_eq!(t.time.dt_min, 1e-8);
    // "tl" alias, follower pressure switches auto to LU
    let p = parse(&format!(
        "[model]\nformulation = \"tl\"\n{BASE}\n[[loads]]\nbody = \"block\"\nset = \"top\"\ntype = \"pressure\"\nvalue = 2\n"
    ))
    .unwrap();
    assert_eq!(p.formulation, Formulation::TotalLagrangian);
    assert_eq!(p.loads[0].kind, LoadKind::Pressure(2.0));
    assert_eq!(p.loads[0].amplitude, Amplitude::Ramp);
    assert_eq!(p.linear_kind(), LinearSolverKind::Lu);
}

#[test]
fn examples_have_expected_content() {
    let c = case::load(&root().join("jobs/examples/asphalt_creep_block.toml")).unwrap();
    match &c.materials[0].material {
        Material::Creep(cr) => {
            assert_eq!(cr.params.a, 5.15e-8);
            assert_eq!(cr.params.n, 0.826);
            assert_eq!(cr.params.q, 0.22);
            assert_eq!(cr.params.stress_scale, 1e6);
        }
        other => panic!("expected creep, got {other:?}"),
    }
    let c = case::load(&root().join("jobs/examples/thick_cylinder.toml")).unwrap();
    assert_eq!(c.bodies[0].shape.center(), Some([0.0, 0.0]));
    assert_eq!(c.boundary[2].radial, Some(0.5));
    assert_eq!(c.bodies[0].divisions, Some([10, 16]));
    let c = case::load(&root().join("jobs/examples/cook_membrane.toml")).unwrap();
    assert_eq!(c.bodies[0].shape, ShapeSpec::Cook);
    assert_eq!(c.loads[0].kind, LoadKind::Force([0.0, 1.0]));
    assert!(c.bodies[0].mesh_size > 0.0);
    let c = case::load(&root().join("jobs/examples/upsetting_table_file.toml")).unwrap();
    assert_eq!(c.base_dir, root().join("jobs/examples"));
}

#[test]
fn never_panics_on_garbage() {
    let inputs = [
        "",
        "\u{0}",
        "[[materials]]",
        "materials = 3",
        "bodies = [1, 2]",
        "[time]\nend = -1\ndt = 0",
        "title = 5",
        "[[materials]]\nname = \"\"\n",
        "[[materials]]\nname = \"a\"\nmodel = \"j2\"\nyoungs_modulus = 1\npoisson_ratio = 0.3\nhardening = {}\n",
        "[[materials]]\nname = \"a\"\nmodel = \"creep\"\nyoungs_modulus = 1\npoisson_ratio = 0.3\ncreep = { stress_unit = \"Pa\" }\n",
        "ü = 1\n[x\n",
    ];
    for text in inputs {
        let r = std::panic::catch_unwind(|| case::parse(text, Path::new(".")));
        match r {
            Ok(res) => assert!(res.is_err(), "{text:?} should be rejected"),
            Err(_) => panic!("panicked on {text:?}"),
        }
    }
}

#[test]
fn lagrange_regularisation_is_checked_and_defaults_to_1e_4() {
    let c = parse(BASE).unwrap();
    assert_eq!(c.contact.lagrange_regularisation, 1e-4);
    let c = parse(&format!("{BASE}\n[contact]\nmethod = \"lagrange\"\nlagrange_regularisation = 0.0\n")).unwrap();
    assert_eq!(c.contact.lagrange_regularisation, 0.0);
    for v in ["-0.001", "1", "2.5"] {
        let e = err_of(&format!("{BASE}\n[contact]\nmethod = \"lagrange\"\nlagrange_regularisation = {v}\n"));
        assert_has(&e, &["contact.lagrange_regularisation", v, "0 <= r < 1"]);
    }
}

/// `[contact] normal` selects the node-to-segment contact normal; a bad value names the key,
/// the value and the expected values.
#[test]
fn contact_normal_is_segment_or_smoothed() {
    use mpfem::case::ContactNormal;
    assert_eq!(parse(BASE).unwrap().contact.normal, ContactNormal::default());
    for (v, n) in [("segment", ContactNormal::Segment), ("smoothed", ContactNormal::Smoothed)] {
        assert_eq!(parse(&format!("{BASE}\n[contact]\nmethod = \"penalty\"\nnormal = \"{v}\"\n")).unwrap().contact.normal, n);
    }
    let e = err_of(&format!("{BASE}\n[contact]\nmethod = \"penalty\"\nnormal = \"curved\"\n"));
    assert_eq!(e.key, "contact.normal");
    assert_has(&e, &["value \"curved\"", "\"segment\"", "\"smoothed\""]);
}

/// The barrier is the default contact method, with a tangent-only regularisation instead of
/// springs; the keys of the node-to-segment methods are an error with it (given or by default),
/// naming the key, the value and what was expected, not a silent no-op.
#[test]
fn barrier_is_the_default_and_refuses_node_to_segment_keys() {
    use mpfem::contact::ContactMethod;
    for text in [BASE.to_string(), format!("{BASE}\n[contact]\ncontact = \"sliding\"\n")] {
        let c = parse(&text).unwrap();
        assert_eq!(c.contact.method, ContactMethod::Barrier);
        // no springs in the residual, their stiffness in the tangent only
        assert_eq!(c.stabilisation.factor, 0.0);
        assert_eq!(c.stabilisation.regularisation, mpfem::stabilise::BARRIER_REGULARISATION);
    }
    // the keys still set springs and the regularisation with the barrier; springs asked for
    // come without the default regularisation
    let keyed = parse(&format!("{BASE}\n[contact]\nstabilisation = 1e-7\nregularisation = 2e-8\n")).unwrap();
    assert_eq!((keyed.stabilisation.factor, keyed.stabilisation.regularisation), (1e-7, 2e-8));
    let springs = parse(&format!("{BASE}\n[contact]\nstabilisation = 1e-7\n")).unwrap();
    assert_eq!((springs.stabilisation.factor, springs.stabilisation.regularisation), (1e-7, 0.0));
    let penalty = parse(&format!("{BASE}\n[contact]\nmethod = \"penalty\"\n")).unwrap();
    assert_eq!(penalty.contact.method, ContactMethod::Penalty);
    assert!(!penalty.stabilisation.stiffen_on_cutback);
    assert_eq!((penalty.stabilisation.factor, penalty.stabilisation.regularisation), (1e-5, 0.0));
    for (key, value) in [
        ("penalty", "1500.5"),
        ("penetration_tol", "0.001"),
        ("max_augmentations", "5"),
        ("search_distance", "2.5"),
        ("lagrange_regularisation", "0.5"),
        ("normal", "\"smoothed\""),
    ] {
        for (method, said) in [("", "whose default is \"barrier\""), ("method = \"barrier\"\n", "with contact.method = \"barrier\"")] {
            let e = err_of(&format!("{BASE}\n[contact]\n{method}{key} = {value}\n"));
            assert_eq!(e.key, format!("contact.{key}"));
            assert_has(&e, &[value, said, "\"penalty\""]);
        }
        let text = format!("{BASE}\n[contact]\nmethod = \"augmented_lagrangian\"\n{key} = {value}\n");
        assert!(parse(&text).is_ok(), "{key} refused with the augmented Lagrangian");
    }
}

/// `[contact] viscous_retry` is off by default, on when asked, and refused with viscous springs
/// (which it would not change), naming the key and the value.
#[test]
fn viscous_retry_defaults_off_and_needs_inertial_springs() {
    assert!(!parse(BASE).unwrap().stabilisation.viscous_retry);
    assert!(parse(&format!("{BASE}\n[contact]\nviscous_retry = true\n")).unwrap().stabilisation.viscous_retry);
    let e = err_of(&format!("{BASE}\n[contact]\nstabilisation_kind = \"viscous\"\nviscous_retry = true\n"));
    assert_eq!(e.key, "contact.viscous_retry");
    assert_has(&e, &["value true", "stabilisation_kind = \"inertial\""]);
}

/// Overlapping particles are an input error at the later body, naming both bodies, the depth
/// and the expectation: exact for two discs, GJK plus a projection search for polygons and
/// ellipses; touching particles are accepted.
#[test]
fn overlapping_bodies_are_rejected_naming_the_pair() {
    let two = |a: &str, b: &str| {
        format!(
            "{BASE}\n[[bodies]]\nname = \"p\"\nmaterial = \"alu\"\nmesh_size = 1.0\nshape = {a}\n\n[[bodies]]\nname = \"q\"\nmaterial = \"alu\"\nmesh_size = 1.0\nshape = {b}\n"
        )
        .replace("origin = [0.0, 0.0], size = [20.0, 20.0]", "origin = [-100.0, -100.0], size = [20.0, 20.0]")
    };
    // discs: centres 10 apart, radii 6 + 5 -> overlap 1 mm
    let e = err_of(&two("{ type = \"disc\", center = [0.0, 0.0], radius = 6.0 }", "{ type = \"disc\", center = [10.0, 0.0], radius = 5.0 }"));
    assert_eq!(e.key, "bodies[2]");
    assert_has(&e, &["\"q\"", "\"p\"", "bodies[1]", "overlaps", "by 1.0000 mm", "expected particles that do not overlap"]);
    // touching discs are fine
    parse(&two("{ type = \"disc\", center = [0.0, 0.0], radius = 5.0 }", "{ type = \"disc\", center = [10.0, 0.0], radius = 5.0 }")).unwrap();
    // a square and an ellipse reaching 0.25 mm into it
    let sq = "{ type = \"polygon\", vertices = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]] }";
    let e = err_of(&two(sq, "{ type = \"ellipse\", center = [5.0, 12.75], semi_axes = [1.0, 3.0] }"));
    assert_has(&e, &["\"q\" (ellipse) overlaps body \"p\"", "polygon", "by 0.2500 mm"]);
    // ... and the same ellipse just clear of it
    parse(&two(sq, "{ type = \"ellipse\", center = [5.0, 13.01], semi_axes = [1.0, 3.0] }")).unwrap();
    // a rotated ellipse crossing a corner of the square
    let e = err_of(&two(sq, "{ type = \"ellipse\", center = [11.5, 11.5], semi_axes = [3.0, 0.5], angle = 45.0 }"));
    assert_has(&e, &["bodies[1]", "overlaps"]);
    // two polygons sharing a side touch without overlapping
    parse(&two(sq, "{ type = \"polygon\", vertices = [[10.0, 0.0], [20.0, 0.0], [15.0, 10.0]] }")).unwrap();
    let e = err_of(&two(sq, "{ type = \"polygon\", vertices = [[9.0, 0.0], [20.0, 0.0], [15.0, 10.0]] }"));
    assert_has(&e, &["\"q\" (polygon) overlaps body \"p\""]);
    // the rectangle body of BASE is checked too
    let e = err_of(&with("mesh_size = 2.0\nshape", "mesh_size = 2.0\nshape").replace("[time]", "[[bodies]]\nname = \"d\"\nmaterial = \"alu\"\nmesh_size = 1.0\nshape = { type = \"disc\", center = [25.0, 10.0], radius = 6.0 }\n\n[time]"));
    assert_has(&e, &["\"d\" (disc) overlaps body \"block\" (bodies[0], rectangle) by 1.0000 mm"]);
}

/// Grid particles that overlap a listed body are named by their generated names.
#[test]
fn grid_particles_overlapping_a_body_are_named() {
    let text = format!(
        "{}\n[[walls]]\nside = \"left\"\nposition = 0.0\n[[walls]]\nside = \"right\"\nposition = 100.0\n[[walls]]\nside = \"bottom\"\nposition = 0.0\n[[walls]]\nside = \"top\"\nposition = 100.0\n\n[[grids]]\nmaterial = \"alu\"\nnx = 2\nny = 2\nsolid_ratio = 0.5\nmesh_size = 5.0\n",
        BASE
    );
    let e = err_of(&text);
    assert_has(&e, &["\"g0_p0\" (disc) overlaps body \"block\" (bodies[0], rectangle)"]);
}

/// `[[packings]]`: every bad key is a CaseError naming the key, the value and the expectation.
#[test]
fn packing_keys_are_checked() {
    let walls = "\n[[walls]]\nside = \"left\"\nposition = 100.0\n[[walls]]\nside = \"right\"\nposition = 200.0\n[[walls]]\nside = \"bottom\"\nposition = 0.0\n[[walls]]\nside = \"top\"\nposition = 100.0\n";
    let good = "\n[[packings]]\nkind = \"voronoi_polygons\"\ncount = 4\nseed = 1\nsolid_ratio = 0.7\nmaterial = \"alu\"\nmesh_size = 10.0\n";
    let case = |packing: &str| format!("{BASE}{walls}{packing}");
    let c = parse(&case(good)).unwrap();
    assert_eq!(c.bodies.len(), 5);
    assert_eq!(c.bodies[1].name, "r0_p0");
    for (from, to, key, parts) in [
        ("kind = \"voronoi_polygons\"", "kind = \"squares\"", "packings[0].kind", &["\"squares\"", "\"voronoi_polygons\", \"voronoi_ellipses\", \"discs\""][..]),
        ("seed = 1", "seed = 1\naspect = 20.0", "packings[0].aspect", &["[0.1, 10]"][..]),
        ("kind = \"voronoi_polygons\"", "kind = \"discs\"\naspect = 2.0", "packings[0].aspect", &["not a parameter of kind \"discs\""][..]),
        ("kind = \"voronoi_polygons\"", "kind = \"voronoi_ellipses\"\nlloyd = 3", "packings[0].solid_ratio", &["0.7", "inscribed in the cells cover"][..]),
        ("count = 4", "count = 0", "packings[0].count", &["value 0", ">= 1"][..]),
        ("count = 4", "count = 100001", "packings[0].count", &["at most 100000"][..]),
        ("seed = 1", "seed = -1", "packings[0].seed", &["value -1", ">= 0"][..]),
        ("solid_ratio = 0.7", "solid_ratio = 1.2", "packings[0].solid_ratio", &["1.2", "(0, 1)"][..]),
        ("solid_ratio = 0.7\n", "", "packings[0].solid_ratio", &["missing"][..]),
        ("material = \"alu\"", "material = \"steel\"", "packings[0].material", &["no material named \"steel\"", "known: alu"][..]),
        ("material = \"alu\"", "materials = [\"alu\", \"lead\"]", "packings[0].materials[1]", &["\"lead\""][..]),
        ("material = \"alu\"", "materials = [\"alu\"]\nfractions = [0.5, 0.5]", "packings[0].fractions", &["2 value(s) for 1 material(s)"][..]),
        ("material = \"alu\"", "materials = [\"alu\"]\nfractions = [-1.0]", "packings[0].fractions[0]", &["> 0"][..]),
        ("material = \"alu\"", "material = \"alu\"\nmaterials = [\"alu\"]", "packings[0].materials", &["not both"][..]),
        ("material = \"alu\"\n", "", "packings[0].material", &["missing"][..]),
        ("mesh_size = 10.0", "mesh_size = 0.0", "packings[0].mesh_size", &["> 0"][..]),
        ("seed = 1", "seed = 1\nlloyd = 5000", "packings[0].lloyd", &["at most 1000"][..]),
        ("seed = 1", "seed = 1\nsizes = { distribution = \"gauss\" }", "packings[0].sizes.distribution", &["\"gauss\"", "\"lognormal\""][..]),
        ("seed = 1", "seed = 1\nsizes = { distribution = \"uniform\" }", "packings[0].sizes.ratio", &["missing"][..]),
        ("seed = 1", "seed = 1\nsizes = { distribution = \"uniform\", ratio = 0.5 }", "packings[0].sizes.ratio", &["(1, 100]"][..]),
        ("seed = 1", "seed = 1\nsizes = { distribution = \"lognormal\", ratio = 2.0 }", "packings[0].sizes.sigma", &["missing"][..]),
        ("seed = 1", "seed = 1\nsizes = { distribution = \"equal\", sigma = 0.1 }", "packings[0].sizes.sigma", &["not a parameter"][..]),
        ("seed = 1", "seed = 1\nshape = \"disc\"", "packings[0].shape", &["unknown field"][..]),
        ("kind = \"voronoi_polygons\"\ncount = 4\nseed = 1\nsolid_ratio = 0.7", "kind = \"discs\"\ncount = 4\nseed = 1\nsolid_ratio = 0.784", "packings[0].solid_ratio", &["could not be pushed apart", "lower solid ratio"][..]),
    ] {
        let text = case(&good.replace(from, to));
        let e = err_of(&text);
        assert_eq!(e.key, key, "{to}: {e}");
        assert_has(&e, parts);
    }
    // no walls: no die
    let e = err_of(&format!("{BASE}{good}"));
    assert_eq!(e.key, "packings[0]");
    assert_has(&e, &["needs all four [[walls]]"]);
}

/// `[[grids]] arrangement`: hexagonal grids have staggered rows of nx and nx - 1 particles;
/// an unknown arrangement or nx < 2 is an error naming the key.
#[test]
fn hexagonal_grids() {
    let text = format!(
        "{}\n[[walls]]\nside = \"left\"\nposition = 100.0\n[[walls]]\nside = \"right\"\nposition = 130.0\n[[walls]]\nside = \"bottom\"\nposition = 0.0\n[[walls]]\nside = \"top\"\nposition = 26.0\n\n[[grids]]\nmaterial = \"alu\"\nnx = 3\nny = 3\narrangement = \"hexagonal\"\nsolid_ratio = 0.55\nmesh_size = 2.0\n",
        BASE
    );
    let c = parse(&text).unwrap();
    assert_eq!(c.bodies.len(), 1 + 8);
    let e = err_of(&text.replace("\"hexagonal\"", "\"triangular\""));
    assert_eq!(e.key, "grids[0].arrangement");
    assert_has(&e, &["\"triangular\"", "\"square\", \"hexagonal\""]);
    let e = err_of(&text.replace("nx = 3", "nx = 1"));
    assert_eq!(e.key, "grids[0].nx");
    assert_has(&e, &["nx >= 2"]);
}

/// `[[grids]] orientation = "flat"`: octagons with a side facing each wall reach φ = 0.80 in a
/// square grid (limit 2/(1 + √2) ≈ 0.828), vertex-up octagons do not (limit √2/2); the key is
/// refused for discs and ellipses and an unknown value is named.
#[test]
fn flat_polygon_grids() {
    let text = format!(
        "{}\n[[walls]]\nside = \"left\"\nposition = 100.0\n[[walls]]\nside = \"right\"\nposition = 140.0\n[[walls]]\nside = \"bottom\"\nposition = 0.0\n[[walls]]\nside = \"top\"\nposition = 40.0\n\n[[grids]]\nmaterial = \"alu\"\nnx = 2\nny = 2\nshape = \"polygon\"\nsides = 8\norientation = \"flat\"\nsolid_ratio = 0.80\nmesh_size = 2.0\n",
        BASE
    );
    let c = parse(&text).unwrap();
    assert_eq!(c.bodies.len(), 1 + 4);
    // flat sides up and to the right: the first vertex at 22.5 degrees, two vertices share
    // the largest y (to round-off)
    let v = match &c.bodies[1].shape {
        mpfem::case::ShapeSpec::Polygon { vertices } => vertices.clone(),
        other => panic!("expected a polygon, got {other:?}"),
    };
    let ymax = v.iter().map(|p| p[1]).fold(f64::MIN, f64::max);
    assert_eq!(v.iter().filter(|p| (p[1] - ymax).abs() < 1e-9).count(), 2);
    let e = err_of(&text.replace("orientation = \"flat\"\n", ""));
    assert_eq!(e.key, "grids[0].solid_ratio");
    assert_has(&e, &["at most 0.7071"]);
    let e = err_of(&text.replace("\"flat\"", "\"edge\""));
    assert_eq!(e.key, "grids[0].orientation");
    assert_has(&e, &["\"edge\"", "\"vertex\", \"flat\""]);
    let e = err_of(&text.replace("shape = \"polygon\"", "shape = \"ellipse\""));
    assert_eq!(e.key, "grids[0].orientation");
    assert_has(&e, &["not allowed for shape \"ellipse\""]);
}

/// `[[grids]]` mixtures: by pattern (checkerboard, rows, columns) or by fraction (shuffled by a
/// seed, reproducibly); bad combinations name the key.
#[test]
fn grid_material_mixtures() {
    let base = format!(
        "{}\n[[materials]]\nname = \"lead\"\nmodel = \"elastic\"\nyoungs_modulus = 16000.0\npoisson_ratio = 0.44\n\n[[walls]]\nside = \"left\"\nposition = 100.0\n[[walls]]\nside = \"right\"\nposition = 140.0\n[[walls]]\nside = \"bottom\"\nposition = 0.0\n[[walls]]\nside = \"top\"\nposition = 40.0\n\n[[grids]]\nmaterials = [\"alu\", \"lead\"]\nnx = 4\nny = 4\nsolid_ratio = 0.6\nmesh_size = 2.0\n",
        BASE
    );
    let materials = |text: &str| -> Vec<usize> { parse(text).unwrap().bodies[1..].iter().map(|b| b.material).collect() };
    let board = materials(&format!("{base}pattern = \"checkerboard\"\n"));
    assert_eq!(board, vec![0, 1, 0, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 1, 0]);
    let rows = materials(&format!("{base}pattern = \"rows\"\n"));
    assert_eq!(rows, vec![0, 0, 0, 0, 1, 1, 1, 1, 0, 0, 0, 0, 1, 1, 1, 1]);
    let cols = materials(&format!("{base}pattern = \"columns\"\n"));
    assert_eq!(cols[..4], [0, 1, 0, 1]);
    // by fraction: 3 : 1 of 16 = 12 and 4, shuffled, the same for the same seed
    let a = materials(&format!("{base}fractions = [3.0, 1.0]\nseed = 5\n"));
    assert_eq!(a.iter().filter(|&&m| m == 1).count(), 4);
    assert_eq!(a, materials(&format!("{base}fractions = [3.0, 1.0]\nseed = 5\n")));
    assert_ne!(a, materials(&format!("{base}fractions = [3.0, 1.0]\nseed = 6\n")));
    for (extra, key, part) in [
        ("pattern = \"stripes\"\n", "grids[0].pattern", "\"checkerboard\", \"rows\", \"columns\""),
        ("pattern = \"rows\"\nfractions = [1.0, 1.0]\n", "grids[0].fractions", "not allowed with pattern"),
        ("pattern = \"rows\"\nseed = 3\n", "grids[0].seed", "not allowed with pattern"),
        ("fractions = [1.0]\n", "grids[0].fractions", "1 value(s) for 2 material(s)"),
    ] {
        let e = err_of(&format!("{base}{extra}"));
        assert_eq!(e.key, key, "{extra}: {e}");
        assert_has(&e, &[part]);
    }
    let e = err_of(&base.replace("materials = [\"alu\", \"lead\"]", "materials = [\"alu\", \"tin\"]"));
    assert_eq!(e.key, "grids[0].materials[1]");
    assert_has(&e, &["no material named \"tin\""]);
}

/// `[remesh]`: off without the table, on with it (defaults 0.2 / 10 / 15°, each body's own
/// size); a value out of range names its key, the value and the range; re-meshing is refused
/// with implicit dynamics, whose velocities it would not carry.
#[test]
fn remesh_table_defaults_ranges_and_dynamics() {
    let off = parse(BASE).unwrap().remesh;
    assert!(!off.enabled);
    let on = parse(&format!("{BASE}\n[remesh]\n")).unwrap().remesh;
    assert!(on.enabled && on.mesh_size.is_none());
    assert_eq!((on.limits.min_scaled_jacobian, on.limits.max_aspect_ratio, on.limits.min_angle_deg), (0.2, 10.0, 15.0));
    let set = parse(&format!("{BASE}\n[remesh]\nmin_scaled_jacobian = 0.3\nmax_aspect_ratio = 6.0\nmin_angle = 20.0\nmesh_size = 2.5\nmax_remeshes = 7\n")).unwrap().remesh;
    assert_eq!((set.limits.min_scaled_jacobian, set.limits.max_aspect_ratio, set.limits.min_angle_deg, set.mesh_size, set.max_remeshes), (0.3, 6.0, 20.0, Some(2.5), 7));
    for (key, value, expected) in [
        ("min_scaled_jacobian", "1.5", "in (0, 1)"),
        ("max_aspect_ratio", "0.5", "> 1"),
        ("min_angle", "95.0", "(0, 90)"),
        ("mesh_size", "-1.0", "> 0"),
        ("max_remeshes", "-3", ">= 0"),
    ] {
        let e = err_of(&format!("{BASE}\n[remesh]\n{key} = {value}\n"));
        assert_eq!(e.key, format!("remesh.{key}"));
        assert_has(&e, &[&format!("value {value}"), expected]);
    }
    let dynamic = BASE.replace("[time]", "[time]\nintegrator = \"newmark\"").replace("poisson_ratio = 0.3\n", "poisson_ratio = 0.3\ndensity = 2.7e-9\n");
    assert!(dynamic.contains("density"));
    assert!(dynamic.contains("integrator"));
    let e = err_of(&format!("{dynamic}\n[remesh]\n"));
    assert_eq!(e.key, "remesh.enabled");
    assert_has(&e, &["value true", "time.integrator"]);
}

#[test]
fn checkpoint_keys() {
    // defaults: no checkpoint by step count, one every 30 minutes of wall clock
    let c = parse(BASE).unwrap();
    assert_eq!(c.output.checkpoint_every, 0);
    assert_eq!(c.output.checkpoint_minutes, 30.0);
    let c = parse(&format!("{BASE}\n[output]\ncheckpoint_every = 5\ncheckpoint_minutes = 2.5\n")).unwrap();
    assert_eq!(c.output.checkpoint_every, 5);
    assert_eq!(c.output.checkpoint_minutes, 2.5);
    let c = parse(&format!("{BASE}\n[output]\ncheckpoint_minutes = 0.0\n")).unwrap();
    assert_eq!(c.output.checkpoint_minutes, 0.0);
    let e = err_of(&format!("{BASE}\n[output]\ncheckpoint_every = -2\n"));
    assert_eq!(e.key, "output.checkpoint_every");
    assert_has(&e, &["-2", "integer >= 0"]);
    let e = err_of(&format!("{BASE}\n[output]\ncheckpoint_minutes = -1.0\n"));
    assert_eq!(e.key, "output.checkpoint_minutes");
    assert_has(&e, &["-1.0", "minutes >= 0"]);
}

/// `[stop] wall_pressure`: a positive pressure with a wall that moves; anything else names the
/// key, the value and the expectation. The block sits clear of the walls (x 0–20, walls at
/// −10 and 30).
#[test]
fn stop_wall_pressure_is_checked() {
    let walls = |velocity: f64| format!("\n[[walls]]\nside = \"left\"\nposition = -10.0\nvelocity = {velocity:?}\n[[walls]]\nside = \"right\"\nposition = 30.0\n");
    let case = |velocity: f64, p: &str| format!("{BASE}{}\n[stop]\nwall_pressure = {p}\n", walls(velocity));
    let c = parse(&case(1.0, "250.0")).unwrap();
    assert_eq!(c.stop.wall_pressure, Some(250.0));
    assert_eq!(parse(&format!("{BASE}{}", walls(1.0))).unwrap().stop.wall_pressure, None);
    for (velocity, p, parts) in [
        (1.0, "-5.0", &["-5.0", "a pressure > 0 (MPa)"][..]),
        (1.0, "0.0", &["0.0", "a pressure > 0 (MPa)"][..]),
        (1.0, "nan", &["NaN", "not a finite number"][..]),
        (0.0, "250.0", &["250.0", "no wall moves", "velocity or a travel"][..]),
    ] {
        let e = err_of(&case(velocity, p));
        assert_eq!(e.key, "stop.wall_pressure", "{e}");
        assert_has(&e, parts);
    }
}
