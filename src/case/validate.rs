//! Validation of the raw case file: ranges, finiteness, required keys, cross references,
//! duplicated names and files, each failure one [`CaseError`] naming the key, the value and
//! what was expected; and the source locations (line and column) of keys.

use super::raw;
use super::*;
use crate::linalg::{LinearSolverKind, Preconditioner};
use crate::material::creep::CreepParams;
use crate::material::{Creep, Elastic, HardeningTable, J2Plastic};
use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

// ---------------------------------------------------------------------------------------------
// Source locations: key path <-> byte span, line/column
// ---------------------------------------------------------------------------------------------

pub(super) struct Locator<'a> {
    text: &'a str,
    /// Every key and value of the document with its dotted path.
    entries: Vec<(String, Range<usize>)>,
    /// First byte of each path (the key for table entries, the value for array items).
    first: HashMap<String, usize>,
}

impl<'a> Locator<'a> {
    pub(super) fn new(text: &'a str, root: &toml::de::DeTable<'_>) -> Self {
        let mut loc = Locator {
            text,
            entries: Vec::new(),
            first: HashMap::new(),
        };
        loc.walk_table(root, "");
        loc
    }

    fn walk_table(&mut self, table: &toml::de::DeTable<'_>, prefix: &str) {
        for (k, v) in table.iter() {
            let path = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            let ks = k.span();
            self.first.entry(path.clone()).or_insert(ks.start);
            self.entries.push((path.clone(), ks));
            self.walk_value(v.get_ref(), v.span(), &path);
        }
    }

    fn walk_value(&mut self, v: &toml::de::DeValue<'_>, span: Range<usize>, path: &str) {
        self.entries.push((path.to_string(), span.clone()));
        self.first.entry(path.to_string()).or_insert(span.start);
        match v {
            toml::de::DeValue::Table(t) => self.walk_table(t, path),
            toml::de::DeValue::Array(a) => {
                for (i, item) in a.iter().enumerate() {
                    self.walk_value(item.get_ref(), item.span(), &format!("{path}[{i}]"));
                }
            }
            _ => {}
        }
    }

    /// The innermost key or value whose span contains byte `pos`.
    fn path_at(&self, pos: usize) -> Option<String> {
        self.entries
            .iter()
            .filter(|(_, r)| (r.start <= pos && pos < r.end) || (r.start == pos && r.end == pos))
            .min_by_key(|(_, r)| r.end - r.start)
            .map(|(p, _)| p.clone())
    }

    /// Line of `path` or of its nearest ancestor present in the file.
    fn line_of(&self, path: &str) -> Option<usize> {
        let mut p = path;
        loop {
            if let Some(&pos) = self.first.get(p) {
                return Some(line_col(self.text, pos).0);
            }
            let cut = p.rfind(['.', '['])?;
            p = &p[..cut];
            if p.is_empty() {
                return None;
            }
        }
    }
}

/// 1-based line and column (in characters) of byte `pos`.
fn line_col(text: &str, pos: usize) -> (usize, usize) {
    let mut pos = pos.min(text.len());
    while !text.is_char_boundary(pos) {
        pos -= 1;
    }
    let before = &text[..pos];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = text[line_start..pos].chars().count() + 1;
    (line, col)
}

pub(super) fn toml_error(text: &str, loc: Option<&Locator>, e: &toml::de::Error) -> CaseError {
    let mut msg = e.message().trim().replace('\n', "; ");
    match e.span() {
        Some(span) => {
            let (line, col) = line_col(text, span.start);
            let key = loc.and_then(|l| l.path_at(span.start)).unwrap_or_default();
            // the parser says "duplicate key" without the key: it is the text the error points
            // at (up to the `=` of its line)
            if msg == "duplicate key" {
                let at = text.get(span.start..).unwrap_or("");
                let name = at.lines().next().unwrap_or("").split('=').next().unwrap_or("").trim().trim_matches(['[', ']']).trim();
                if !name.is_empty() {
                    msg = format!("duplicate key `{name}` (given twice in the same table); expected each key once");
                }
            }
            CaseError::new(key, format!("line {line}, column {col}: {msg}"))
        }
        None if msg.contains("recursion limit") => {
            // no position from the parser: name the line nested deepest (dotted keys, nested
            // tables or arrays)
            let depth = |l: &str| l.matches(['.', '[', '{']).count();
            let (n, _) = text.lines().enumerate().max_by_key(|(_, l)| depth(l)).unwrap_or((0, ""));
            CaseError::new("", format!("line {}: nested too deeply (the parser's recursion limit); expected keys and tables a few levels deep", n + 1))
        }
        None => CaseError::new("", format!("invalid case file: {msg}")),
    }
}

// ---------------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------------

pub(super) struct Cx<'a> {
    pub(super) loc: &'a Locator<'a>,
    pub(super) base_dir: &'a Path,
    /// gmsh files read so far (a file with many particles is parsed once).
    pub(super) msh_cache: std::cell::RefCell<HashMap<PathBuf, std::rc::Rc<Vec<crate::mesh::import::MshParticle>>>>,
}

pub(super) fn join_names<'s>(names: impl IntoIterator<Item = &'s str>) -> String {
    let v: Vec<&str> = names.into_iter().collect();
    if v.is_empty() {
        "none".to_string()
    } else {
        v.join(", ")
    }
}

fn value_num(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    }
}

fn describe(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("{s:?}"),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::Float(f) => format!("{f:?}"),
        toml::Value::Boolean(b) => b.to_string(),
        toml::Value::Datetime(d) => d.to_string(),
        toml::Value::Array(a) => {
            let mut s = String::from("[");
            for (i, x) in a.iter().enumerate() {
                if i > 0 {
                    s.push_str(", ");
                }
                s.push_str(&describe(x));
            }
            s.push(']');
            s
        }
        toml::Value::Table(_) => "a table".to_string(),
    }
}

/// Allowed characters in body names (they appear in `body.set` and in CSV column names).
pub(super) fn valid_body_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

impl Cx<'_> {
    /// An error at `key`, with the line of the key (or its nearest ancestor) appended.
    pub(super) fn err(&self, key: &str, msg: impl Into<String>) -> CaseError {
        let mut message = msg.into();
        if let Some(line) = self.loc.line_of(key) {
            let _ = write!(message, " (line {line})");
        }
        CaseError::new(key, message)
    }

    pub(super) fn missing(&self, key: &str, expected: &str) -> CaseError {
        self.err(key, format!("missing; expected {expected}"))
    }

    pub(super) fn req<T>(&self, v: Option<T>, key: &str, expected: &str) -> Result<T, CaseError> {
        v.ok_or_else(|| self.missing(key, expected))
    }

    /// A finite number satisfying `ok`.
    pub(super) fn num(&self, key: &str, v: f64, ok: bool, expected: &str) -> Result<f64, CaseError> {
        if !v.is_finite() {
            return Err(self.err(
                key,
                format!("value {v:?} is not a finite number; expected {expected}"),
            ));
        }
        if !ok {
            return Err(self.err(key, format!("value {v:?}; expected {expected}")));
        }
        Ok(v)
    }

    pub(super) fn positive(&self, key: &str, v: f64, what: &str) -> Result<f64, CaseError> {
        self.num(key, v, v > 0.0, &format!("{what} > 0"))
    }

    pub(super) fn finite(&self, key: &str, v: f64, what: &str) -> Result<f64, CaseError> {
        self.num(key, v, true, what)
    }

    pub(super) fn finite2(&self, key: &str, v: [f64; 2], what: &str) -> Result<[f64; 2], CaseError> {
        for (i, x) in v.iter().enumerate() {
            self.finite(&format!("{key}[{i}]"), *x, what)?;
        }
        Ok(v)
    }

    pub(super) fn count(&self, key: &str, v: i64, min: i64) -> Result<usize, CaseError> {
        if v < min {
            return Err(self.err(key, format!("value {v}; expected an integer >= {min}")));
        }
        usize::try_from(v).map_err(|_| self.err(key, format!("value {v} is too large")))
    }

    pub(super) fn choice<'v>(&self, key: &str, v: &str, allowed: &[&'v str]) -> Result<&'v str, CaseError> {
        allowed.iter().find(|a| **a == v).copied().ok_or_else(|| {
            let list: Vec<String> = allowed.iter().map(|a| format!("\"{a}\"")).collect();
            self.err(
                key,
                format!("value \"{v}\"; expected one of {}", list.join(", ")),
            )
        })
    }

    // ---- whole case ---------------------------------------------------------------------

    pub(super) fn case(&self, r: raw::Case) -> Result<Case, CaseError> {
        let title = r.title.unwrap_or_default();
        let element = match r.model.as_ref().and_then(|m| m.element.clone()) {
            None => crate::element::ElementKind::Q1P0,
            Some(e) => match e.as_str() {
                "q1p0" => crate::element::ElementKind::Q1P0,
                "q1p0_enhanced" => crate::element::ElementKind::Q1P0Enhanced,
                _ => {
                    return Err(self.err(
                        "model.element",
                        format!("value \"{e}\"; expected \"q1p0\" (mean dilatation) or \"q1p0_enhanced\" (mean dilatation + enhanced bending modes)"),
                    ))
                }
            },
        };
        let plane_stress = match r.model.as_ref().and_then(|m| m.plane.clone()).as_deref() {
            None | Some("strain") => false,
            Some("stress") => true,
            Some(p) => return Err(self.err("model.plane", format!("value \"{p}\"; expected \"strain\" (plane strain, the default) or \"stress\" (plane stress: thin sheets, σ_zz = 0)"))),
        };
        let kinematics = r.model.as_ref().and_then(|m| m.kinematics.clone());
        let linear = match kinematics.as_deref() {
            None | Some("finite") => false,
            Some("linear") => true,
            Some(k) => return Err(self.err("model.kinematics", format!("value \"{k}\"; expected \"finite\" (large deformation, the default) or \"linear\" (small strain, for verification)"))),
        };
        if linear && element == crate::element::ElementKind::Q1P0Enhanced {
            return Err(self.err("model.element", "value \"q1p0_enhanced\" with kinematics = \"linear\": the enhanced element has no small-strain form yet; expected \"q1p0\""));
        }
        if linear && r.model.as_ref().is_some_and(|m| m.formulation.is_some()) {
            return Err(self.err("model.formulation", "given with kinematics = \"linear\", where total and updated Lagrangian are the same (the reference configuration); expected no formulation"));
        }
        let formulation = match r.model.and_then(|m| m.formulation) {
            None if linear => Formulation::Linear,
            None => Formulation::UpdatedLagrangian,
            Some(f) => match f.as_str() {
                "updated_lagrangian" | "ul" => Formulation::UpdatedLagrangian,
                "total_lagrangian" | "tl" => Formulation::TotalLagrangian,
                _ => {
                    return Err(self.err(
                        "model.formulation",
                        format!(
                            "value \"{f}\"; expected \"updated_lagrangian\" (or \"ul\") or \"total_lagrangian\" (or \"tl\")"
                        ),
                    ))
                }
            },
        };

        let raw_materials = r.materials.unwrap_or_default();
        // a density must be given explicitly when the analysis is dynamic (checked below)
        let density_given: Vec<bool> = raw_materials.iter().map(|m| m.density.is_some()).collect();
        if raw_materials.is_empty() {
            return Err(self.err(
                "materials",
                "no material defined; expected at least one [[materials]] table with name, model, youngs_modulus and poisson_ratio",
            ));
        }
        let mut materials = Vec::with_capacity(raw_materials.len());
        for (i, m) in raw_materials.into_iter().enumerate() {
            let key = format!("materials[{i}]");
            let spec = self.material(&key, m)?;
            if materials.iter().any(|x: &MaterialSpec| x.name == spec.name) {
                return Err(self.err(
                    &format!("{key}.name"),
                    format!(
                        "value \"{}\": duplicated material name; expected names to be unique",
                        spec.name
                    ),
                ));
            }
            materials.push(spec);
        }

        let raw_walls = r.walls.unwrap_or_default();
        let mut walls = Vec::with_capacity(raw_walls.len());
        let mut wall_kinds = Vec::with_capacity(raw_walls.len());
        for (i, w) in raw_walls.into_iter().enumerate() {
            let (wall, kind) = self.wall(&format!("walls[{i}]"), w)?;
            walls.push(wall);
            wall_kinds.push(kind);
        }
        let (mut contact, stabilisation) = self.contact(r.contact)?;
        contact.walls = wall_kinds;
        if contact.method == ContactMethod::Barrier {
            use crate::contact::ContactKind;
            if let Some(i) = contact.walls.iter().position(|k| matches!(k, ContactKind::Cohering)) {
                return Err(self.err(
                    &format!("walls[{i}].contact"),
                    "tied (cohering) walls with the barrier contact (contact.method = \"barrier\", the default) are not built yet; expected \"sliding\" or \"rubbing\", or contact.method = \"augmented_lagrangian\"",
                ));
            }
        }
        if contact.dhat.is_some() && contact.method != ContactMethod::Barrier {
            return Err(self.err("contact.dhat", "given without contact.method = \"barrier\": d̂ is the barrier's activation distance; expected it only with the barrier"));
        }
        if contact.method == ContactMethod::Lagrange {
            use crate::contact::ContactKind;
            if !matches!(contact.kind, ContactKind::Sliding) {
                return Err(self.err(
                    "contact.method",
                    "value \"lagrange\": Lagrange multipliers are implemented for frictionless contact only; expected contact.contact = \"sliding\" or method = \"augmented_lagrangian\" (which also ties and rubs)",
                ));
            }
            if let Some(i) = contact.walls.iter().position(|k| !matches!(k, ContactKind::Sliding)) {
                return Err(self.err(
                    &format!("walls[{i}].contact"),
                    "Lagrange multipliers (contact.method = \"lagrange\") are implemented for frictionless contact only; expected \"sliding\" or method = \"augmented_lagrangian\"",
                ));
            }
        }
        let stop = match r.stop {
            None => StopSpec { solid_ratio: None, wall_pressure: None, jam: true, jam_solid_ratio: 0.9 },
            Some(st) => StopSpec {
                solid_ratio: match st.solid_ratio {
                    Some(v) => Some(self.num("stop.solid_ratio", v, v > 0.0 && v <= 1.0, "a solid ratio in (0, 1]")?),
                    None => None,
                },
                wall_pressure: match st.wall_pressure {
                    Some(v) => {
                        let p = self.num("stop.wall_pressure", v, v > 0.0, "a pressure > 0 (MPa)")?;
                        if !walls.iter().any(|w| w.velocity != 0.0 || w.travel.as_ref().is_some_and(|(t, _)| *t != 0.0)) {
                            return Err(self.err("stop.wall_pressure", format!("value {v:?}: no wall moves, so no wall presses; expected a [[walls]] entry with a velocity or a travel")));
                        }
                        Some(p)
                    }
                    None => None,
                },
                jam: st.jam.unwrap_or(true),
                jam_solid_ratio: match st.jam_solid_ratio {
                    Some(v) => self.num("stop.jam_solid_ratio", v, v > 0.0 && v <= 1.0, "a solid ratio in (0, 1]")?,
                    None => 0.9,
                },
            },
        };
        let mut raw_bodies = r.bodies.unwrap_or_default();
        for (i, g) in r.grids.unwrap_or_default().into_iter().enumerate() {
            raw_bodies.extend(self.grid(&format!("grids[{i}]"), g, &walls, &materials)?);
        }
        for (i, p) in r.packings.unwrap_or_default().into_iter().enumerate() {
            raw_bodies.extend(self.packing(&format!("packings[{i}]"), i, p, &walls, &materials)?);
        }
        for (i, imp) in r.imports.unwrap_or_default().into_iter().enumerate() {
            raw_bodies.extend(self.import(&format!("imports[{i}]"), i, imp, &materials)?);
        }
        if raw_bodies.is_empty() {
            return Err(self.err(
                "bodies",
                "no body defined; expected at least one [[bodies]] table with name, material, mesh_size and shape (or [[grids]], [[packings]], [[imports]])",
            ));
        }
        let mut bodies: Vec<BodySpec> = Vec::with_capacity(raw_bodies.len());
        for (i, b) in raw_bodies.into_iter().enumerate() {
            let key = format!("bodies[{i}]");
            let spec = self.body(&key, b, &materials)?;
            if bodies.iter().any(|x| x.name == spec.name) {
                return Err(self.err(
                    &format!("{key}.name"),
                    format!(
                        "value \"{}\": duplicated body name; expected names to be unique",
                        spec.name
                    ),
                ));
            }
            bodies.push(spec);
        }
        self.check_overlaps(&bodies)?;

        let mut boundary = Vec::new();
        for (i, b) in r.boundary.unwrap_or_default().into_iter().enumerate() {
            boundary.push(self.dirichlet(&format!("boundary[{i}]"), b, &bodies)?);
        }
        let mut loads = Vec::new();
        for (i, l) in r.loads.unwrap_or_default().into_iter().enumerate() {
            loads.push(self.load(&format!("loads[{i}]"), l, &bodies)?);
        }

        let time = match r.time {
            Some(t) => self.time(t)?,
            None => {
                return Err(self.err(
                    "time",
                    "missing; expected a [time] table with at least `end` and `dt` (s)",
                ))
            }
        };
        if time.integrator.is_dynamic() {
            if let Some(i) = density_given.iter().position(|given| !given) {
                return Err(self.err(
                    &format!("materials[{i}].density"),
                    format!(
                        "missing for material \"{}\"; expected a density > 0 (t/mm^3): the dynamic integrator (time.integrator) needs the mass of every material",
                        materials[i].name
                    ),
                ));
            }
        }
        let petsc_options = r.solver.as_ref().and_then(|s| s.petsc_options.clone());
        let solver = self.solver(r.solver, contact.method == ContactMethod::Barrier)?;
        let petsc = solver.linear == LinearChoice::Fixed(LinearSolverKind::Petsc);
        if petsc && !cfg!(feature = "petsc") {
            return Err(self.err("solver.linear", format!("value \"petsc\": {}; expected \"auto\", \"lu\", \"cholesky\" or \"pcg\"", crate::linalg::petsc::NOT_BUILT)));
        }
        let petsc_options = match petsc_options {
            Some(o) if !petsc => return Err(self.err("solver.petsc_options", format!("value {o:?} with solver.linear other than \"petsc\"; expected solver.linear = \"petsc\" (PETSc reads these options) or no petsc_options"))),
            Some(o) => {
                if let Some(w) = o.split_whitespace().next().filter(|w| !w.starts_with('-')) {
                    return Err(self.err("solver.petsc_options", format!("value {o:?}: {w:?} is not an option; expected PETSc's command-line options, each starting with '-' (\"-ksp_type cg -pc_type gamg\")")));
                }
                if o.contains('\0') {
                    return Err(self.err("solver.petsc_options", "a NUL character; expected PETSc's command-line options"));
                }
                o
            }
            None => String::new(),
        };
        if contact.method == ContactMethod::Lagrange {
            if let LinearChoice::Fixed(k) = solver.linear {
                if k != LinearSolverKind::Lu {
                    return Err(self.err(
                        "solver.linear",
                        format!("value {k:?}: contact.method = \"lagrange\" gives an indefinite system; expected \"lu\" or \"auto\""),
                    ));
                }
            }
        }
        let output = self.output(r.output, &bodies)?;

        let remesh = match r.remesh {
            None => RemeshSpec::default(),
            Some(m) => self.remesh(m, &time)?,
        };
        if plane_stress && remesh.enabled {
            return Err(self.err("remesh.enabled", "true with model.plane = \"stress\": the thickness condition is solved on the original configuration and a re-mesh would lose it; expected false"));
        }
        if linear && remesh.enabled {
            return Err(self.err("remesh.enabled", "true with model.kinematics = \"linear\": small strains keep the reference configuration; expected false"));
        }
        Ok(Case {
            title,
            formulation,
            plane_stress,
            element,
            materials,
            bodies,
            boundary,
            loads,
            time,
            solver,
            petsc_options,
            output,
            walls,
            contact,
            stabilisation,
            stop,
            remesh,
            base_dir: self.base_dir.to_path_buf(),
        })
    }

    fn remesh(&self, m: raw::RemeshRaw, time: &TimeSpec) -> Result<RemeshSpec, CaseError> {
        let mut spec = RemeshSpec { enabled: m.enabled.unwrap_or(true), ..RemeshSpec::default() };
        if let Some(v) = m.min_scaled_jacobian {
            spec.limits.min_scaled_jacobian = self.num("remesh.min_scaled_jacobian", v, v > 0.0 && v < 1.0, "a scaled Jacobian in (0, 1)")?;
        }
        if let Some(v) = m.max_aspect_ratio {
            spec.limits.max_aspect_ratio = self.num("remesh.max_aspect_ratio", v, v > 1.0, "an aspect ratio > 1")?;
        }
        if let Some(v) = m.min_angle {
            spec.limits.min_angle_deg = self.num("remesh.min_angle", v, v > 0.0 && v < 90.0, "an angle in degrees in (0, 90)")?;
        }
        if let Some(v) = m.mesh_size {
            spec.mesh_size = Some(self.positive("remesh.mesh_size", v, "an element size (mm)")?);
        }
        if let Some(v) = m.max_remeshes {
            spec.max_remeshes = self.count("remesh.max_remeshes", v, 0)?;
        }
        if spec.enabled && time.integrator.is_dynamic() {
            return Err(self.err(
                "remesh.enabled",
                "value true with an implicit dynamic analysis (time.integrator): velocities and accelerations are not transferred to a new mesh; expected enabled = false or a quasi-static analysis",
            ));
        }
        Ok(spec)
    }

    // ---- materials ----------------------------------------------------------------------

    fn material(&self, key: &str, m: raw::Material) -> Result<MaterialSpec, CaseError> {
        let name = self.req(
            m.name,
            &format!("{key}.name"),
            "a unique, non-empty material name",
        )?;
        if name.trim().is_empty() {
            return Err(self.err(
                &format!("{key}.name"),
                "empty name; expected a unique, non-empty material name",
            ));
        }
        let model_key = format!("{key}.model");
        let model = self.req(m.model, &model_key, "\"elastic\", \"j2\" or \"creep\"")?;
        let model = self.choice(&model_key, &model, &["elastic", "j2", "creep"])?;

        let e_key = format!("{key}.youngs_modulus");
        let e = self.req(m.youngs_modulus, &e_key, "Young's modulus E > 0 (MPa)")?;
        let e = self.positive(&e_key, e, "Young's modulus E (MPa)")?;
        let nu_key = format!("{key}.poisson_ratio");
        let nu = self.req(m.poisson_ratio, &nu_key, "a Poisson's ratio in [0, 0.5]")?;
        let nu = self.num(
            &nu_key,
            nu,
            (0.0..=0.5).contains(&nu),
            "a Poisson's ratio in [0, 0.5]",
        )?;
        let density = match m.density {
            None => DEFAULT_DENSITY,
            Some(d) => self.positive(&format!("{key}.density"), d, "a density (t/mm^3)")?,
        };

        if model != "j2" {
            if m.yield_stress.is_some() {
                return Err(self.err(
                    &format!("{key}.yield_stress"),
                    format!("not allowed for model \"{model}\"; expected only with model = \"j2\""),
                ));
            }
            if m.hardening.is_some() {
                return Err(self.err(
                    &format!("{key}.hardening"),
                    format!("not allowed for model \"{model}\"; expected only with model = \"j2\""),
                ));
            }
        }
        if model != "creep" && m.creep.is_some() {
            return Err(self.err(
                &format!("{key}.creep"),
                format!("not allowed for model \"{model}\"; expected only with model = \"creep\""),
            ));
        }

        let material = match model {
            "elastic" => Material::Elastic(Elastic::new(e, nu)),
            "j2" => {
                let table = match (m.yield_stress, m.hardening) {
                    (Some(_), Some(_)) => {
                        return Err(self.err(
                            &format!("{key}.hardening"),
                            "given together with yield_stress; expected exactly one of yield_stress (perfect plasticity) or hardening (table)",
                        ))
                    }
                    (None, None) => {
                        return Err(self.err(
                            key,
                            "model \"j2\" needs its yield behaviour; expected exactly one of yield_stress = <MPa> or hardening = { ... }",
                        ))
                    }
                    (Some(sy), None) => {
                        let sy = self.positive(&format!("{key}.yield_stress"), sy, "a yield stress (MPa)")?;
                        HardeningTable::perfect(sy)
                    }
                    (None, Some(h)) => self.hardening(&format!("{key}.hardening"), h, e)?,
                };
                Material::J2(J2Plastic::new(e, nu, table))
            }
            _ => {
                let c = self.req(
                    m.creep,
                    &format!("{key}.creep"),
                    "a creep table, e.g. creep = { preset = \"asphalt_table2\", stress_unit = \"Pa\" }",
                )?;
                Material::Creep(Creep::new(e, nu, self.creep(&format!("{key}.creep"), c)?))
            }
        };
        Ok(MaterialSpec {
            name,
            density,
            material,
        })
    }

    fn hardening(&self, key: &str, h: raw::Hardening, e: f64) -> Result<HardeningTable, CaseError> {
        let sources = [h.points.is_some(), h.file.is_some(), h.preset.is_some()]
            .iter()
            .filter(|x| **x)
            .count();
        if sources != 1 {
            return Err(self.err(
                key,
                format!(
                    "{} of points, file, preset given; expected exactly one (points = [[strain, stress], ...], file = \"table.csv\" or preset = \"aluminium_250c\")",
                    sources
                ),
            ));
        }
        if let Some(preset) = h.preset {
            let pkey = format!("{key}.preset");
            self.choice(&pkey, &preset, &["aluminium_250c"])?;
            if h.strain.is_some() {
                return Err(self.err(
                    &format!("{key}.strain"),
                    "not allowed with preset (the preset defines its strain measure); expected only with points or file",
                ));
            }
            return HardeningTable::from_total_strain(
                e,
                &crate::material::hardening::aluminium_250c(),
            )
            .map_err(|msg| self.err(key, format!("preset \"aluminium_250c\" rejected: {msg}")));
        }
        let skey = format!("{key}.strain");
        let strain = self.req(
            h.strain,
            &skey,
            "the strain measure of the table: \"total\" (strain includes the elastic part) or \"plastic\"",
        )?;
        let strain = self.choice(&skey, &strain, &["total", "plastic"])?;

        let (points, pkey) = if let Some(points) = h.points {
            (
                points.into_iter().map(|p| p.0).collect(),
                format!("{key}.points"),
            )
        } else {
            let file = h.file.unwrap_or_default();
            let fkey = format!("{key}.file");
            let path = self.base_dir.join(&file);
            let text = std::fs::read_to_string(&path).map_err(|err| {
                self.err(
                    &fkey,
                    format!("cannot read hardening table \"{}\": {err}", path.display()),
                )
            })?;
            let pts = read_two_columns(&text)
                .map_err(|msg| self.err(&fkey, format!("in \"{}\": {msg}", path.display())))?;
            (pts, fkey)
        };
        self.check_table(&pkey, &points, strain)?;
        let table = if strain == "total" {
            HardeningTable::from_total_strain(e, &points)
        } else {
            HardeningTable::from_plastic_strain(&points)
        };
        table.map_err(|msg| self.err(key, format!("invalid hardening table: {msg}")))
    }

    /// Checks shared by both strain measures: finite, strain >= 0 and strictly increasing,
    /// stress >= 0 and non-decreasing (softening is not supported).
    fn check_table(&self, key: &str, pts: &[[f64; 2]], strain: &str) -> Result<(), CaseError> {
        if pts.is_empty() {
            return Err(self.err(
                key,
                "empty table; expected at least one [strain, stress] point",
            ));
        }
        for (i, p) in pts.iter().enumerate() {
            let k = format!("{key}[{i}]");
            if !p[0].is_finite() || !p[1].is_finite() {
                return Err(self.err(
                    &k,
                    format!(
                        "value [{:?}, {:?}]; expected finite numbers [strain, stress (MPa)]",
                        p[0], p[1]
                    ),
                ));
            }
            if p[0] < 0.0 || p[1] < 0.0 {
                return Err(self.err(
                    &k,
                    format!(
                        "value [{:?}, {:?}]; expected strain >= 0 and stress >= 0",
                        p[0], p[1]
                    ),
                ));
            }
            if i > 0 {
                let q = pts[i - 1];
                if p[0] <= q[0] {
                    return Err(self.err(
                        &k,
                        format!(
                            "{strain} strain {:?} after {:?}; expected a table with strictly increasing strain",
                            p[0], q[0]
                        ),
                    ));
                }
                if p[1] < q[1] {
                    return Err(self.err(
                        &k,
                        format!(
                            "stress {:?} MPa after {:?} MPa; expected a non-decreasing (hardening) stress, softening is not supported",
                            p[1], q[1]
                        ),
                    ));
                }
            }
        }
        if strain == "plastic" && pts[0][1] <= 0.0 {
            return Err(self.err(
                &format!("{key}[0]"),
                format!("initial yield stress {:?}; expected the first point's stress (the initial yield stress) > 0", pts[0][1]),
            ));
        }
        Ok(())
    }

    fn creep(&self, key: &str, c: raw::Creep) -> Result<CreepParams, CaseError> {
        let ukey = format!("{key}.stress_unit");
        let unit = c.stress_unit.ok_or_else(|| {
            self.err(
                &ukey,
                "missing; expected \"Pa\", \"kPa\", \"MPa\" or \"GPa\": the stress unit the creep coefficient A was fitted in. \
                 The paper does not state it, and because the creep rate goes as A·(s·σ)^n with s the unit factor, the choice changes the creep rate \
                 by orders of magnitude (a factor 10^(6n) between \"Pa\" and \"MPa\"), so there is no safe default",
            )
        })?;
        let stress_scale = match self.choice(&ukey, &unit, &["Pa", "kPa", "MPa", "GPa"])? {
            "Pa" => 1e6,
            "kPa" => 1e3,
            "MPa" => 1.0,
            _ => 1e-3,
        };
        let base = match &c.preset {
            Some(p) => {
                self.choice(&format!("{key}.preset"), p, &["asphalt_table2"])?;
                Some(CreepParams::asphalt_table2(1.0))
            }
            None => None,
        };
        let need = |v: Option<f64>,
                    name: &str,
                    preset: Option<f64>,
                    what: &str|
         -> Result<f64, CaseError> {
            match v.or(preset) {
                Some(x) => Ok(x),
                None => Err(self.missing(&format!("{key}.{name}"), what)),
            }
        };
        let a = need(
            c.a,
            "A",
            base.map(|b| b.a),
            "the creep coefficient A > 0 (or preset = \"asphalt_table2\")",
        )?;
        let n = need(
            c.n,
            "n",
            base.map(|b| b.n),
            "the stress exponent n > 0 (or preset = \"asphalt_table2\")",
        )?;
        let q = need(
            c.q,
            "q",
            base.map(|b| b.q),
            "the time exponent q > 0 (or preset = \"asphalt_table2\")",
        )?;
        let temperature = need(
            c.temperature,
            "temperature",
            base.map(|b| b.temperature),
            "a temperature T > 0 (or preset = \"asphalt_table2\")",
        )?;
        let m = c.m.or(base.map(|b| b.m)).unwrap_or(0.0);
        let p = c.p.or(base.map(|b| b.p)).unwrap_or(0.0);
        let a = self.positive(&format!("{key}.A"), a, "the creep coefficient A")?;
        let n = self.positive(&format!("{key}.n"), n, "the stress exponent n")?;
        let m = self.num(
            &format!("{key}.m"),
            m,
            m < 1.0,
            "the strain-hardening exponent m < 1",
        )?;
        let p = self.finite(&format!("{key}.p"), p, "a finite temperature exponent p")?;
        let q = self.positive(&format!("{key}.q"), q, "the time exponent q")?;
        let temperature = self.positive(
            &format!("{key}.temperature"),
            temperature,
            "a temperature T",
        )?;
        Ok(CreepParams {
            a,
            n,
            m,
            p,
            q,
            temperature,
            stress_scale,
        })
    }

    // ---- bodies -------------------------------------------------------------------------

    fn body(
        &self,
        key: &str,
        b: raw::Body,
        materials: &[MaterialSpec],
    ) -> Result<BodySpec, CaseError> {
        let nkey = format!("{key}.name");
        let name = self.req(
            b.name,
            &nkey,
            "a unique body name of letters, digits, '_' and '-'",
        )?;
        if !valid_body_name(&name) {
            return Err(self.err(
                &nkey,
                format!("value \"{name}\"; expected a non-empty name of ASCII letters, digits, '_' and '-' (it is used in \"body.set\" references and CSV column names)"),
            ));
        }
        let mkey = format!("{key}.material");
        let mat_name = self.req(b.material, &mkey, "the name of a material")?;
        let material = materials
            .iter()
            .position(|m| m.name == mat_name)
            .ok_or_else(|| {
                self.err(
                    &mkey,
                    format!(
                        "value \"{mat_name}\": no material named \"{mat_name}\" (known: {})",
                        join_names(materials.iter().map(|m| m.name.as_str()))
                    ),
                )
            })?;
        let shape = match b.shape {
            Some(s) => self.shape(&format!("{key}.shape"), s)?,
            None => {
                return Err(self.missing(
                    &format!("{key}.shape"),
                    "a shape, e.g. shape = { type = \"rectangle\", origin = [0.0, 0.0], size = [20.0, 20.0] }",
                ))
            }
        };
        let dkey = format!("{key}.divisions");
        let divisions = match b.divisions {
            None => None,
            Some(raw::Pair(d)) => {
                if !matches!(
                    shape,
                    ShapeSpec::Rectangle { .. } | ShapeSpec::Cook | ShapeSpec::AnnulusSector { .. }
                ) {
                    return Err(self.err(
                        &dkey,
                        format!(
                            "not allowed for shape type \"{}\"; expected divisions only for rectangle, cook and annulus_sector (use mesh_size)",
                            shape.type_name()
                        ),
                    ));
                }
                let mut out = [0usize; 2];
                for (i, v) in d.iter().enumerate() {
                    if !(1..=MAX_DIVISIONS).contains(v) {
                        return Err(self.err(
                            &format!("{dkey}[{i}]"),
                            format!(
                                "value {v}; expected a number of divisions in [1, {MAX_DIVISIONS}]"
                            ),
                        ));
                    }
                    out[i] = usize::try_from(*v).map_err(|_| {
                        self.err(&format!("{dkey}[{i}]"), format!("value {v} is too large"))
                    })?;
                }
                Some(out)
            }
        };
        let hkey = format!("{key}.mesh_size");
        if let ShapeSpec::Gmsh { mesh, .. } = &shape {
            if let Some(h) = b.mesh_size {
                return Err(self.err(
                    &hkey,
                    format!("value {h:?}: not allowed for shape type \"gmsh\" (the elements come from the file); expected no mesh_size"),
                ));
            }
            // the element size of the imported mesh: the side of a square of its mean element area
            let n = mesh.n_elements().max(1) as f64;
            let mesh_size = (mesh.area(&mesh.nodes).abs() / n).sqrt();
            return Ok(BodySpec { name, material, shape, mesh_size, divisions });
        }
        let mesh_size = match (b.mesh_size, divisions) {
            (Some(h), _) => self.positive(&hkey, h, "a target element edge length h (mm)")?,
            (None, Some(d)) => implied_mesh_size(&shape, d),
            (None, None) => {
                return Err(self.missing(
                    &hkey,
                    "a target element edge length h > 0 (mm), or divisions = [nx, ny]",
                ))
            }
        };
        Ok(BodySpec {
            name,
            material,
            shape,
            mesh_size,
            divisions,
        })
    }

    fn shape(&self, key: &str, s: raw::Shape) -> Result<ShapeSpec, CaseError> {
        let tkey = format!("{key}.type");
        let kind = self.req(
            s.kind.clone(),
            &tkey,
            "\"rectangle\", \"disc\", \"ellipse\", \"polygon\", \"outline\", \"gmsh\", \"cook\" or \"annulus_sector\"",
        )?;
        let kind = self.choice(
            &tkey,
            &kind,
            &[
                "rectangle",
                "disc",
                "ellipse",
                "polygon",
                "outline",
                "gmsh",
                "cook",
                "annulus_sector",
            ],
        )?;
        let allowed: &[&str] = match kind {
            "rectangle" => &["origin", "size"],
            "disc" => &["center", "radius", "part", "angle"],
            "ellipse" => &["center", "semi_axes", "angle", "part"],
            "polygon" | "outline" => &["vertices"],
            "gmsh" => &["file", "group", "scale", "offset"],
            "cook" => &[],
            _ => &["center", "inner_radius", "outer_radius", "angles"],
        };
        let present = [
            ("origin", s.origin.is_some()),
            ("size", s.size.is_some()),
            ("center", s.center.is_some()),
            ("radius", s.radius.is_some()),
            ("semi_axes", s.semi_axes.is_some()),
            ("angle", s.angle.is_some()),
            ("part", s.part.is_some()),
            ("vertices", s.vertices.is_some()),
            ("inner_radius", s.inner_radius.is_some()),
            ("outer_radius", s.outer_radius.is_some()),
            ("angles", s.angles.is_some()),
            ("file", s.file.is_some()),
            ("group", s.group.is_some()),
            ("scale", s.scale.is_some()),
            ("offset", s.offset.is_some()),
        ];
        for (field, is) in present {
            if is && !allowed.contains(&field) {
                return Err(self.err(
                    &format!("{key}.{field}"),
                    format!(
                        "not a parameter of shape type \"{kind}\"; expected only: {}",
                        if allowed.is_empty() {
                            "type".to_string()
                        } else {
                            format!("type, {}", allowed.join(", "))
                        }
                    ),
                ));
            }
        }
        let center = |cx: &Self| -> Result<[f64; 2], CaseError> {
            cx.finite2(
                &format!("{key}.center"),
                s.center.map_or([0.0, 0.0], |p| p.0),
                "a finite centre coordinate (mm)",
            )
        };
        Ok(match kind {
            "rectangle" => {
                let origin = self.finite2(
                    &format!("{key}.origin"),
                    s.origin.map_or([0.0, 0.0], |p| p.0),
                    "a finite coordinate (mm)",
                )?;
                let skey = format!("{key}.size");
                let size = self.req(
                    s.size.map(|p| p.0),
                    &skey,
                    "size = [width, height] > 0 (mm)",
                )?;
                for (i, v) in size.iter().enumerate() {
                    self.positive(&format!("{skey}[{i}]"), *v, "a side length (mm)")?;
                }
                ShapeSpec::Rectangle { origin, size }
            }
            "disc" => {
                let center = center(self)?;
                let rkey = format!("{key}.radius");
                let r = self.req(s.radius, &rkey, "a radius > 0 (mm)")?;
                let radius = self.positive(&rkey, r, "a radius (mm)")?;
                match self.shape_part(key, s.part.as_deref())? {
                    None if s.angle.is_some() => return Err(self.err(&format!("{key}.angle"), "given for a whole disc; expected it only with part = \"half\" or \"quarter\" (it turns the part)")),
                    None => ShapeSpec::Disc { center, radius },
                    Some(part) => {
                        let angle_deg = self.finite(&format!("{key}.angle"), s.angle.unwrap_or(0.0), "a finite angle (degrees)")?;
                        ShapeSpec::EllipsePart { center, semi_axes: [radius, radius], angle_deg, part, disc: true }
                    }
                }
            }
            "ellipse" => {
                let center = center(self)?;
                let akey = format!("{key}.semi_axes");
                let semi_axes = self.req(
                    s.semi_axes.map(|p| p.0),
                    &akey,
                    "semi_axes = [a, b] > 0 (mm)",
                )?;
                for (i, v) in semi_axes.iter().enumerate() {
                    self.positive(&format!("{akey}[{i}]"), *v, "a semi-axis (mm)")?;
                }
                let angle_deg = self.finite(
                    &format!("{key}.angle"),
                    s.angle.unwrap_or(0.0),
                    "a finite angle (degrees)",
                )?;
                match self.shape_part(key, s.part.as_deref())? {
                    None => ShapeSpec::Ellipse { center, semi_axes, angle_deg },
                    Some(part) => ShapeSpec::EllipsePart { center, semi_axes, angle_deg, part, disc: false },
                }
            }
            "polygon" => {
                let vkey = format!("{key}.vertices");
                let vertices: Vec<[f64; 2]> = self
                    .req(
                        s.vertices,
                        &vkey,
                        "at least 3 vertices [[x0, y0], [x1, y1], ...] (mm)",
                    )?
                    .into_iter()
                    .map(|p| p.0)
                    .collect();
                if vertices.len() < 3 {
                    return Err(self.err(
                        &vkey,
                        format!("{} vertices; expected at least 3", vertices.len()),
                    ));
                }
                for (i, v) in vertices.iter().enumerate() {
                    self.finite2(
                        &format!("{vkey}[{i}]"),
                        *v,
                        "a finite vertex coordinate (mm)",
                    )?;
                }
                let n = vertices.len();
                let area2: f64 = (0..n)
                    .map(|i| {
                        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                        a[0] * b[1] - b[0] * a[1]
                    })
                    .sum();
                let scale = vertices
                    .iter()
                    .fold(0.0f64, |m, v| m.max(v[0].abs()).max(v[1].abs()))
                    .max(1e-300);
                if area2.abs() <= 1e-12 * scale * scale {
                    return Err(self.err(
                        &vkey,
                        "the polygon has zero area; expected vertices of a convex polygon",
                    ));
                }
                ShapeSpec::Polygon { vertices }
            }
            "cook" => ShapeSpec::Cook,
            "outline" => {
                let vkey = format!("{key}.vertices");
                let vertices: Vec<[f64; 2]> = self
                    .req(s.vertices, &vkey, "at least 3 vertices [[x0, y0], [x1, y1], ...] (mm) of a simple polygon")?
                    .into_iter()
                    .map(|p| p.0)
                    .collect();
                for (i, v) in vertices.iter().enumerate() {
                    self.finite2(&format!("{vkey}[{i}]"), *v, "a finite vertex coordinate (mm)")?;
                }
                crate::mesh::polygon::check_simple_polygon(&vertices)
                    .map_err(|e| self.err(&vkey, format!("{} vertices: {e}; expected a simple polygon (sides that neither cross nor touch)", vertices.len())))?;
                ShapeSpec::Outline { vertices }
            }
            "gmsh" => self.gmsh_shape(key, s)?,
            _ => {
                let center = center(self)?;
                let ikey = format!("{key}.inner_radius");
                let okey = format!("{key}.outer_radius");
                let ri = self.req(s.inner_radius, &ikey, "an inner radius > 0 (mm)")?;
                let ri = self.positive(&ikey, ri, "an inner radius (mm)")?;
                let ro = self.req(s.outer_radius, &okey, "an outer radius > inner_radius (mm)")?;
                let ro = self.num(
                    &okey,
                    ro,
                    ro > ri,
                    &format!("an outer radius > inner_radius = {ri:?} (mm)"),
                )?;
                let gkey = format!("{key}.angles");
                let angles = self.req(
                    s.angles.map(|p| p.0),
                    &gkey,
                    "angles = [start, end] in degrees",
                )?;
                let angles = self.finite2(&gkey, angles, "finite angles (degrees)")?;
                let span = angles[1] - angles[0];
                if !(span > 0.0 && span <= 360.0) {
                    return Err(self.err(
                        &gkey,
                        format!("value [{:?}, {:?}]; expected start < end and end - start <= 360 degrees (360 = full ring)", angles[0], angles[1]),
                    ));
                }
                ShapeSpec::AnnulusSector {
                    center,
                    inner_radius: ri,
                    outer_radius: ro,
                    angles_deg: angles,
                }
            }
        })
    }

    /// Resolve `body` / `set` references of a boundary condition or a load.
    fn body_set(
        &self,
        key: &str,
        body: Option<String>,
        set: Option<String>,
        bodies: &[BodySpec],
    ) -> Result<(usize, String), CaseError> {
        let bkey = format!("{key}.body");
        let name = self.req(body, &bkey, "the name of a body")?;
        let bi = self.find_body(&bkey, &name, bodies)?;
        let skey = format!("{key}.set");
        let set = self.req(
            set,
            &skey,
            &format!(
                "an edge set of body \"{name}\" ({})",
                bodies[bi].shape.edge_set_names().join(", ")
            ),
        )?;
        self.check_set(&skey, &bodies[bi], &set)?;
        Ok((bi, set))
    }

    /// `part` of a disc or an ellipse: `None` for the whole shape.
    fn shape_part(&self, key: &str, part: Option<&str>) -> Result<Option<crate::mesh::shapes::EllipsePart>, CaseError> {
        use crate::mesh::shapes::EllipsePart;
        Ok(match part.map(|p| self.choice(&format!("{key}.part"), p, &["full", "half", "quarter"])).transpose()? {
            None | Some("full") => None,
            Some("half") => Some(EllipsePart::Half),
            _ => Some(EllipsePart::Quarter),
        })
    }

    fn find_body(&self, key: &str, name: &str, bodies: &[BodySpec]) -> Result<usize, CaseError> {
        bodies.iter().position(|b| b.name == name).ok_or_else(|| {
            self.err(
                key,
                format!(
                    "value \"{name}\": no body named \"{name}\" (known: {})",
                    join_names(bodies.iter().map(|b| b.name.as_str()))
                ),
            )
        })
    }

    pub(super) fn contact_kind(&self, key: &str, kind: Option<String>, friction: Option<f64>) -> Result<crate::contact::ContactKind, CaseError> {
        use crate::contact::ContactKind;
        let kind = kind.unwrap_or_else(|| "sliding".into());
        let fkey = key.rsplit_once('.').map_or("friction".to_string(), |(p, _)| format!("{p}.friction"));
        let mu = match friction {
            Some(v) => self.num(&fkey, v, v >= 0.0, "a Coulomb friction coefficient >= 0")?,
            None => 0.0,
        };
        Ok(match self.choice(key, &kind, &["sliding", "rubbing", "cohering"])? {
            "rubbing" => {
                if friction.is_none() {
                    return Err(self.missing(&fkey, "a friction coefficient mu >= 0 for contact = \"rubbing\""));
                }
                ContactKind::Rubbing { mu }
            }
            "cohering" => ContactKind::Cohering,
            _ => {
                if mu > 0.0 {
                    return Err(self.err(&fkey, format!("value {mu}: friction needs contact = \"rubbing\"")));
                }
                ContactKind::Sliding
            }
        })
    }

    /// A wall and its contact kind with the particles (which goes to [`Case::contact`]).
    fn wall(&self, key: &str, w: raw::WallRaw) -> Result<(WallSpec, crate::contact::ContactKind), CaseError> {
        let side_s = self.req(w.side, &format!("{key}.side"), "one of \"left\", \"right\", \"bottom\", \"top\"")?;
        let side = match self.choice(&format!("{key}.side"), &side_s, &["left", "right", "bottom", "top"])? {
            "left" => WallSide::Left,
            "right" => WallSide::Right,
            "bottom" => WallSide::Bottom,
            _ => WallSide::Top,
        };
        let position = self.finite(
            &format!("{key}.position"),
            self.req(w.position, &format!("{key}.position"), "the wall's x (left/right) or y (bottom/top) at t = 0, mm")?,
            "a position in mm",
        )?;
        let velocity = self.finite(&format!("{key}.velocity"), w.velocity.unwrap_or(0.0), "a velocity in mm/s (positive inward)")?;
        let travel = match (w.travel, w.velocity) {
            (None, _) => {
                if let Some(a) = &w.amplitude {
                    return Err(self.err(
                        &format!("{key}.amplitude"),
                        format!("value {a}: an amplitude shapes a wall's travel as it does a prescribed displacement; expected `travel` (mm) with it (a wall with `velocity` moves at constant speed)"),
                    ));
                }
                None
            }
            (Some(_), Some(v)) => {
                return Err(self.err(&format!("{key}.travel"), format!("given with velocity = {v}; expected either a constant `velocity` (mm/s) or a `travel` (mm) with an `amplitude`")));
            }
            (Some(d), None) => {
                let d = self.finite(&format!("{key}.travel"), d, "an inward travel in mm (times the amplitude)")?;
                Some((d, self.amplitude(&format!("{key}.amplitude"), w.amplitude)?))
            }
        };
        let kind = self.contact_kind(&format!("{key}.contact"), w.contact, w.friction)?;
        Ok((WallSpec { side, position, velocity, travel }, kind))
    }

    fn contact(&self, c: Option<raw::ContactRaw>) -> Result<(ContactParams, StabilisationParams), CaseError> {
        let (mut spec, mut stab) = (ContactParams::default(), StabilisationParams::default());
        let c = c.unwrap_or_default();
        let explicit_method = c.method.is_some();
        if let Some(m) = c.method {
            spec.method = match self.choice("contact.method", &m, &["penalty", "augmented_lagrangian", "lagrange", "barrier"])? {
                "penalty" => ContactMethod::Penalty,
                "lagrange" => ContactMethod::Lagrange,
                "barrier" => ContactMethod::Barrier,
                _ => ContactMethod::AugmentedLagrangian,
            };
        }
        if spec.method == ContactMethod::Barrier {
            // the keys of the node-to-segment methods mean nothing to the barrier: an error, not
            // a silent no-op, above all where the barrier is only the default
            let given = if explicit_method { "with contact.method = \"barrier\"" } else { "without contact.method, whose default is \"barrier\"" };
            let node_to_segment = [
                ("penalty", c.penalty.map(|v| v.to_string())),
                ("penetration_tol", c.penetration_tol.map(|v| v.to_string())),
                ("max_augmentations", c.max_augmentations.map(|v| v.to_string())),
                ("search_distance", c.search_distance.map(|v| v.to_string())),
                ("lagrange_regularisation", c.lagrange_regularisation.map(|v| v.to_string())),
                ("normal", c.normal.as_ref().map(|v| format!("\"{v}\""))),
            ];
            if let Some((key, Some(value))) = node_to_segment.into_iter().find(|(_, v)| v.is_some()) {
                return Err(self.err(
                    &format!("contact.{key}"),
                    format!("value {value} given {given}: `{key}` belongs to the node-to-segment methods and the barrier has no use for it; expected no `{key}` key, or contact.method = \"penalty\", \"augmented_lagrangian\" or \"lagrange\""),
                ));
            }
        }
        spec.kind = self.contact_kind("contact.contact", c.contact, c.friction)?;
        if let Some(v) = c.penalty {
            spec.penalty = if v == 0.0 { None } else { Some(self.positive("contact.penalty", v, "a penalty in MPa/mm (0 = automatic)")?) };
        }
        if let Some(v) = c.integration.as_deref() {
            use crate::contact::BarrierIntegration;
            if spec.method != ContactMethod::Barrier {
                return Err(self.err("contact.integration", format!("value \"{v}\" given without contact.method = \"barrier\": it says where the barrier is evaluated; expected it only with the barrier")));
            }
            spec.integration = match self.choice("contact.integration", v, &["edges", "nodes"])? {
                "nodes" => BarrierIntegration::Nodes,
                _ => BarrierIntegration::Edges,
            };
        }
        if let Some(v) = c.dhat {
            spec.dhat = Some(self.positive("contact.dhat", v, "the barrier's activation distance in mm (> 0; omit it for the default, 1/20 of the smallest element size)")?);
        }
        if let Some(v) = c.penetration_tol {
            spec.penetration_tol = self.positive("contact.penetration_tol", v, "a penetration tolerance relative to the element size")?;
        }
        if let Some(v) = c.max_augmentations {
            spec.max_augmentations = self.count("contact.max_augmentations", v, 1)?;
        }
        if let Some(v) = c.stabilisation {
            stab.factor = self.num("contact.stabilisation", v, v >= 0.0, "a stabilisation factor >= 0")?;
        }
        if let Some(v) = c.stabilise {
            stab.scope = match self.choice("contact.stabilise", &v, &["unsupported", "all"])? {
                "all" => Stabilise::All,
                _ => Stabilise::Unsupported,
            };
        }
        if let Some(v) = c.stabilisation_kind {
            stab.kind = match self.choice("contact.stabilisation_kind", &v, &["inertial", "viscous"])? {
                "viscous" => StabilisationKind::Viscous,
                _ => StabilisationKind::Inertial,
            };
        }
        if let Some(v) = c.viscous_retry {
            if v && stab.kind != StabilisationKind::Inertial {
                return Err(self.err("contact.viscous_retry", "value true: the springs are viscous already; expected viscous_retry only with stabilisation_kind = \"inertial\""));
            }
            stab.viscous_retry = v;
        }
        // the barrier's springs are a fictitious inertia: their stiffness grows as 1/Δt² on a
        // cut-back, as the inertia term of an implicit step does (see docs/case-file.md)
        stab.stiffen_on_cutback = c.stiffen_on_cutback.unwrap_or(spec.method == ContactMethod::Barrier);
        // with the barrier no springs in the residual by default, only their stiffness in the
        // tangent: a free particle's system stays regular, the solution is the equilibrium
        // itself and the springs do no work, however large the steps
        // (`stabilise::BARRIER_REGULARISATION`, docs/robustness.md, twenty-fourth measurement)
        // (springs asked for by the key regularise the tangent themselves: ρ on top of them
        // would make Newton take only part of their pull an iteration)
        if spec.method == ContactMethod::Barrier && c.stabilisation.is_none() {
            stab.factor = 0.0;
            stab.regularisation = crate::stabilise::BARRIER_REGULARISATION;
        }
        if let Some(v) = c.regularisation {
            stab.regularisation = self.num("contact.regularisation", v, v >= 0.0, "a regularisation factor >= 0")?;
        }
        if let Some(v) = c.lagrange_regularisation {
            spec.lagrange_regularisation =
                self.num("contact.lagrange_regularisation", v, (0.0..1.0).contains(&v), "a regularisation factor r with 0 <= r < 1 (0 = exact constraints)")?;
        }
        if let Some(v) = c.normal {
            spec.normal = match self.choice("contact.normal", &v, &["segment", "smoothed"])? {
                "smoothed" => ContactNormal::Smoothed,
                _ => ContactNormal::Segment,
            };
        }
        if let Some(v) = c.search_distance {
            spec.search_distance = if v == 0.0 { None } else { Some(self.positive("contact.search_distance", v, "a distance in mm (0 = one element size)")?) };
        }
        Ok((spec, stab))
    }

    /// Particles (bodies) must not overlap: the first overlapping pair is an error at the
    /// later body, naming both (see [`crate::packing::overlap`]; touching is allowed, annulus
    /// sectors are not checked).
    fn check_overlaps(&self, bodies: &[BodySpec]) -> Result<(), CaseError> {
        if bodies.len() < 2 {
            return Ok(());
        }
        let shapes: Vec<_> = bodies.iter().map(|b| b.shape.particle()).collect();
        let Some(o) = crate::packing::overlap::overlapping_particles(&shapes, 1e-9).into_iter().next() else {
            return Ok(());
        };
        let (a, b) = (&bodies[o.first], &bodies[o.second]);
        let depth = if o.depth.is_finite() { format!(" by {:.4} mm", o.depth) } else { String::new() };
        Err(self.err(
            &format!("bodies[{}]", o.second),
            format!(
                "body \"{}\" ({}) overlaps body \"{}\" (bodies[{}], {}){depth}; expected particles that do not overlap (touching is allowed): move or shrink one of them",
                b.name,
                b.shape.type_name(),
                a.name,
                o.first,
                a.shape.type_name()
            ),
        ))
    }
    fn check_set(&self, key: &str, body: &BodySpec, set: &str) -> Result<(), CaseError> {
        let names = body.shape.edge_set_names();
        if names.iter().any(|n| n == set) {
            Ok(())
        } else {
            Err(self.err(
                key,
                format!(
                    "value \"{set}\": body \"{}\" ({}) has no edge set \"{set}\" (known: {})",
                    body.name,
                    body.shape.type_name(),
                    names.join(", ")
                ),
            ))
        }
    }

    fn amplitude(&self, key: &str, v: Option<toml::Value>) -> Result<Amplitude, CaseError> {
        const EXPECTED: &str = "\"ramp\", \"constant\" or a table [[t0, f0], [t1, f1], ...] with strictly increasing times";
        let Some(v) = v else {
            return Ok(Amplitude::Ramp);
        };
        match &v {
            toml::Value::String(s) => match s.as_str() {
                "ramp" => Ok(Amplitude::Ramp),
                "constant" => Ok(Amplitude::Constant),
                _ => Err(self.err(key, format!("value \"{s}\"; expected {EXPECTED}"))),
            },
            toml::Value::Array(items) => {
                if items.is_empty() {
                    return Err(self.err(key, format!("empty table; expected {EXPECTED}")));
                }
                let mut pts: Vec<[f64; 2]> = Vec::with_capacity(items.len());
                for (i, item) in items.iter().enumerate() {
                    let ikey = format!("{key}[{i}]");
                    let pair = match item {
                        toml::Value::Array(p) if p.len() == 2 => {
                            match (value_num(&p[0]), value_num(&p[1])) {
                                (Some(t), Some(f)) => [t, f],
                                _ => return Err(self.err(
                                    &ikey,
                                    format!(
                                        "value {}; expected a pair of numbers [time (s), factor]",
                                        describe(item)
                                    ),
                                )),
                            }
                        }
                        _ => {
                            return Err(self.err(
                                &ikey,
                                format!(
                                    "value {}; expected a pair of numbers [time (s), factor]",
                                    describe(item)
                                ),
                            ))
                        }
                    };
                    self.finite2(&ikey, pair, "finite [time (s), factor]")?;
                    if let Some(prev) = pts.last() {
                        if pair[0] <= prev[0] {
                            return Err(self.err(
                                &ikey,
                                format!(
                                    "time {:?} after {:?}; expected strictly increasing times",
                                    pair[0], prev[0]
                                ),
                            ));
                        }
                    }
                    pts.push(pair);
                }
                Ok(Amplitude::Table(pts))
            }
            other => Err(self.err(
                key,
                format!("value {}; expected {EXPECTED}", describe(other)),
            )),
        }
    }

    fn dirichlet(
        &self,
        key: &str,
        b: raw::Boundary,
        bodies: &[BodySpec],
    ) -> Result<DirichletSpec, CaseError> {
        let (body, set) = self.body_set(key, b.body, b.set, bodies)?;
        let ux =
            b.ux.map(|v| self.finite(&format!("{key}.ux"), v, "a finite displacement (mm)"))
                .transpose()?;
        let uy =
            b.uy.map(|v| self.finite(&format!("{key}.uy"), v, "a finite displacement (mm)"))
                .transpose()?;
        let radial = b
            .radial
            .map(|v| {
                self.finite(
                    &format!("{key}.radial"),
                    v,
                    "a finite radial displacement (mm)",
                )
            })
            .transpose()?;
        if ux.is_none() && uy.is_none() && radial.is_none() {
            return Err(self.err(
                key,
                "no displacement given; expected at least one of ux, uy (mm) or radial (mm)",
            ));
        }
        if radial.is_some() {
            if ux.is_some() || uy.is_some() {
                return Err(self.err(
                    &format!("{key}.radial"),
                    "given together with ux/uy; expected either radial or ux/uy in one [[boundary]] entry",
                ));
            }
            let shape = &bodies[body].shape;
            if shape.center().is_none() {
                return Err(self.err(
                    &format!("{key}.radial"),
                    format!(
                        "not available for shape type \"{}\"; expected radial only on disc, ellipse or annulus_sector bodies",
                        shape.type_name()
                    ),
                ));
            }
        }
        let amplitude = self.amplitude(&format!("{key}.amplitude"), b.amplitude)?;
        Ok(DirichletSpec {
            body,
            set,
            ux,
            uy,
            radial,
            amplitude,
        })
    }

    fn load(&self, key: &str, l: raw::Load, bodies: &[BodySpec]) -> Result<LoadSpec, CaseError> {
        let (body, set) = self.body_set(key, l.body, l.set, bodies)?;
        let tkey = format!("{key}.type");
        let kind = self.req(l.kind, &tkey, "\"traction\", \"pressure\" or \"force\"")?;
        let kind = self.choice(&tkey, &kind, &["traction", "pressure", "force"])?;
        let vkey = format!("{key}.value");
        let v = self.req(
            l.value,
            &vkey,
            if kind == "pressure" {
                "a pressure p (MPa)"
            } else {
                "a vector [x, y]"
            },
        )?;
        let vector = |what: &str| -> Result<[f64; 2], CaseError> {
            match &v {
                toml::Value::Array(a) if a.len() == 2 => match (value_num(&a[0]), value_num(&a[1]))
                {
                    (Some(x), Some(y)) => self.finite2(&vkey, [x, y], &format!("a finite {what}")),
                    _ => Err(self.err(
                        &vkey,
                        format!(
                            "value {}; expected {what} as two numbers [x, y]",
                            describe(&v)
                        ),
                    )),
                },
                _ => Err(self.err(
                    &vkey,
                    format!(
                        "value {}; expected {what} as two numbers [x, y]",
                        describe(&v)
                    ),
                )),
            }
        };
        let kind = match kind {
            "traction" => LoadKind::Traction(vector("traction [tx, ty] (MPa)")?),
            "force" => LoadKind::Force(vector("force [Fx, Fy] (N/mm)")?),
            _ => match value_num(&v) {
                Some(p) => LoadKind::Pressure(self.finite(&vkey, p, "a finite pressure (MPa)")?),
                None => {
                    return Err(self.err(
                        &vkey,
                        format!(
                            "value {}; expected a single number, the pressure p (MPa)",
                            describe(&v)
                        ),
                    ))
                }
            },
        };
        let amplitude = self.amplitude(&format!("{key}.amplitude"), l.amplitude)?;
        Ok(LoadSpec {
            body,
            set,
            kind,
            amplitude,
        })
    }

    // ---- time, solver, output -----------------------------------------------------------

    fn time(&self, t: raw::Time) -> Result<TimeSpec, CaseError> {
        let end = self.req(t.end, "time.end", "the end time > 0 (s)")?;
        let end = self.positive("time.end", end, "the end time (s)")?;
        let dt = self.req(t.dt, "time.dt", "the initial time step, 0 < dt <= end (s)")?;
        let dt = self.num(
            "time.dt",
            dt,
            dt > 0.0 && dt <= end,
            &format!("an initial time step 0 < dt <= end = {end:?} (s)"),
        )?;
        let mut s = TimeSpec::new(end, dt);
        if let Some(v) = t.dt_min {
            s.dt_min = self.num(
                "time.dt_min",
                v,
                v > 0.0 && v <= dt,
                &format!("a minimum step 0 < dt_min <= dt = {dt:?} (s)"),
            )?;
        }
        if let Some(v) = t.dt_max {
            s.dt_max = self.num(
                "time.dt_max",
                v,
                v >= dt,
                &format!("a maximum step dt_max >= dt = {dt:?} (s)"),
            )?;
        }
        if let Some(v) = t.growth {
            s.growth = self.num("time.growth", v, v >= 1.0, "a step growth factor >= 1")?;
        }
        if let Some(v) = t.cutback {
            s.cutback = self.num(
                "time.cutback",
                v,
                v > 0.0 && v < 1.0,
                "a cut-back factor in (0, 1)",
            )?;
        }
        if let Some(v) = t.easy_iterations {
            s.easy_iterations = self.count("time.easy_iterations", v, 1)?;
        }
        if let Some(v) = t.max_steps {
            s.max_steps = self.count("time.max_steps", v, 1)?;
        }
        s.integrator = self.integrator(&t)?;
        // accuracy of a dynamic analysis is set by the step, not by the Newton iterations:
        // unless asked otherwise the step does not grow
        if s.integrator.is_dynamic() && t.dt_max.is_none() {
            s.dt_max = dt;
        }
        Ok(s)
    }

    /// `[time] integrator` and its parameters.
    fn integrator(&self, t: &raw::Time) -> Result<crate::dynamics::Integrator, CaseError> {
        use crate::dynamics::Integrator;
        let kind = match &t.integrator {
            None => "static",
            Some(v) => self.choice("time.integrator", v, &["static", "newmark", "hht"])?,
        };
        let only = |key: &str, given: bool, with: &str| -> Result<(), CaseError> {
            if given && kind != with {
                return Err(self.err(
                    key,
                    format!("not allowed with integrator = \"{kind}\"; expected only with integrator = \"{with}\""),
                ));
            }
            Ok(())
        };
        only("time.hht_alpha", t.hht_alpha.is_some(), "hht")?;
        only("time.newmark_beta", t.newmark_beta.is_some(), "newmark")?;
        only("time.newmark_gamma", t.newmark_gamma.is_some(), "newmark")?;
        Ok(match kind {
            "newmark" => {
                let gamma = match t.newmark_gamma {
                    None => 0.5,
                    Some(g) => self.num(
                        "time.newmark_gamma",
                        g,
                        (0.5..=1.0).contains(&g),
                        "a Newmark gamma in [0.5, 1] (unconditional stability needs gamma >= 0.5)",
                    )?,
                };
                let beta = match t.newmark_beta {
                    None => 0.25 * (gamma + 0.5) * (gamma + 0.5),
                    Some(b) => self.num(
                        "time.newmark_beta",
                        b,
                        b >= 0.5 * gamma && b <= 1.0,
                        &format!("a Newmark beta in [gamma/2, 1] = [{:?}, 1] (unconditional stability needs 2 beta >= gamma)", 0.5 * gamma),
                    )?,
                };
                Integrator::Newmark { beta, gamma }
            }
            "hht" => {
                let alpha = match t.hht_alpha {
                    None => -0.05,
                    Some(a) => self.num(
                        "time.hht_alpha",
                        a,
                        (-1.0 / 3.0..=0.0).contains(&a),
                        "an HHT alpha in [-1/3, 0]",
                    )?,
                };
                Integrator::Hht { alpha }
            }
            _ => Integrator::Static,
        })
    }

    /// The `[solver]` table. `barrier`: the contact is the barrier, whose Newton iterations
    /// a solve default to [`BARRIER_MAX_ITERATIONS`].
    fn solver(&self, r: Option<raw::Solver>, barrier: bool) -> Result<SolverSpec, CaseError> {
        let mut s = SolverSpec::default();
        let full_default = if barrier { BARRIER_MAX_ITERATIONS } else { s.max_iterations };
        let Some(r) = r else {
            s.max_iterations = full_default;
            return Ok(s);
        };
        if let Some(v) = &r.newton {
            s.newton = match self.choice("solver.newton", v, &["full", "modified"])? {
                "full" => NewtonKind::Full,
                _ => NewtonKind::Modified,
            };
        }
        s.max_iterations = match r.max_iterations {
            Some(v) => self.count("solver.max_iterations", v, 1)?,
            None if s.newton == NewtonKind::Modified => 60,
            None => full_default,
        };
        if let Some(v) = r.residual_tol {
            s.residual_tol =
                self.positive("solver.residual_tol", v, "a relative residual tolerance")?;
        }
        if let Some(v) = r.energy_tol {
            s.energy_tol = self.positive("solver.energy_tol", v, "a relative energy tolerance")?;
        }
        if let Some(v) = r.line_search {
            s.line_search = v;
        }
        if let Some(v) = &r.linear {
            s.linear = match self.choice("solver.linear", v, &["auto", "lu", "cholesky", "pcg", "petsc"])? {
                "auto" => LinearChoice::Auto,
                "lu" => LinearChoice::Fixed(LinearSolverKind::Lu),
                "cholesky" => LinearChoice::Fixed(LinearSolverKind::Cholesky),
                "petsc" => LinearChoice::Fixed(LinearSolverKind::Petsc),
                _ => LinearChoice::Fixed(LinearSolverKind::Pcg),
            };
        }
        if let Some(v) = &r.preconditioner {
            s.preconditioner = match self.choice("solver.preconditioner", v, &["ic0", "jacobi", "schwarz"])? {
                "ic0" => Preconditioner::Ic0,
                "schwarz" => Preconditioner::Schwarz,
                _ => Preconditioner::Jacobi,
            };
        }
        if let Some(v) = &r.ordering {
            s.ordering = match self.choice("solver.ordering", v, &["amd", "metis"])? {
                "amd" => crate::linalg::FillOrdering::Amd,
                _ => crate::linalg::FillOrdering::Metis,
            };
        }
        if let Some(v) = r.pcg_tol {
            s.pcg_tol = self.positive("solver.pcg_tol", v, "a PCG relative tolerance")?;
        }
        if let Some(v) = r.pcg_max_iterations {
            s.pcg_max_iterations = self.count("solver.pcg_max_iterations", v, 1)?;
        }
        if let Some(v) = r.threads {
            s.threads = self.count("solver.threads", v, 0)?;
        }
        if let Some(v) = r.incompressible_penalty {
            s.incompressible_penalty = self.positive(
                "solver.incompressible_penalty",
                v,
                "a penalty (in units of the shear modulus)",
            )?;
        }
        if let Some(v) = r.volume_tol {
            s.volume_tol = self.positive("solver.volume_tol", v, "a volume tolerance")?;
        }
        if let Some(v) = r.max_volume_updates {
            s.max_volume_updates = self.count("solver.max_volume_updates", v, 1)?;
        }
        if let Some(v) = r.repartition_imbalance {
            s.repartition_imbalance = self.num(
                "solver.repartition_imbalance",
                v,
                v >= 1.0,
                "a load imbalance (heaviest process's element count / mean) >= 1",
            )?;
        }
        Ok(s)
    }

    fn output(&self, r: Option<raw::Output>, bodies: &[BodySpec]) -> Result<OutputSpec, CaseError> {
        let mut out = OutputSpec::default();
        let Some(r) = r else { return Ok(out) };
        out.reactions =
            self.output_list("output.reactions", r.reactions.unwrap_or_default(), bodies)?;
        out.displacements = self.output_list(
            "output.displacements",
            r.displacements.unwrap_or_default(),
            bodies,
        )?;
        let mut names = HashSet::new();
        for (i, p) in r.probes.unwrap_or_default().into_iter().enumerate() {
            let key = format!("output.probes[{i}]");
            let name = self.req(p.name, &format!("{key}.name"), "a name for the probe's columns in probes.csv, e.g. name = \"outer\"")?;
            if !valid_body_name(&name) {
                return Err(self.err(&format!("{key}.name"), format!("value \"{name}\"; expected letters, digits, '_' or '-' (it prefixes the probe's columns in probes.csv)")));
            }
            if !names.insert(name.clone()) {
                return Err(self.err(&format!("{key}.name"), format!("value \"{name}\": a probe of that name is already defined; expected a name used once")));
            }
            let body = match &p.body {
                Some(b) => Some(self.find_body(&format!("{key}.body"), b, bodies)?),
                None => None,
            };
            let at = match (p.point, p.node) {
                (Some(point), None) => ProbeSpecAt::Point { point: self.finite2(&format!("{key}.point"), point.0, "a finite coordinate (mm)")?, body },
                (None, Some(node)) => {
                    let body = self.req(body, &format!("{key}.body"), "the body whose node it is, e.g. body = \"block\"")?;
                    ProbeSpecAt::Node { body, node: self.count(&format!("{key}.node"), node, 0)? }
                }
                (Some(_), Some(_)) => return Err(self.err(&format!("{key}.node"), "given with `point`; expected either point = [x, y] or body and node, not both")),
                (None, None) => return Err(self.missing(&format!("{key}.point"), "point = [x, y] (reference coordinates, mm), or body = \"...\" and node = N")),
            };
            out.probes.push(ProbeSpec { name, at });
        }
        if let Some(v) = r.every {
            out.every = self.count("output.every", v, 0)?;
        }
        if let Some(v) = r.checkpoint_every {
            out.checkpoint_every = self.count("output.checkpoint_every", v, 0)?;
        }
        if let Some(v) = r.checkpoint_minutes {
            out.checkpoint_minutes = self.num("output.checkpoint_minutes", v, v >= 0.0, "a wall-clock time in minutes >= 0 (0 = no checkpoint by time)")?;
        }
        Ok(out)
    }

    fn output_list(
        &self,
        key: &str,
        items: Vec<String>,
        bodies: &[BodySpec],
    ) -> Result<Vec<(usize, String)>, CaseError> {
        let mut seen = HashSet::new();
        let mut out = Vec::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            let ikey = format!("{key}[{i}]");
            let Some((body, set)) = item.rsplit_once('.') else {
                return Err(self.err(
                    &ikey,
                    format!("value \"{item}\"; expected \"body.set\", e.g. \"block.top\""),
                ));
            };
            let bi = self.find_body(&ikey, body, bodies)?;
            self.check_set(&ikey, &bodies[bi], set)?;
            if !seen.insert(item.as_str()) {
                return Err(self.err(
                    &ikey,
                    format!("value \"{item}\" is listed twice; expected each entry once"),
                ));
            }
            out.push((bi, set.to_string()));
        }
        Ok(out)
    }
}

/// A representative element size when only `divisions` are given.
fn implied_mesh_size(shape: &ShapeSpec, d: [usize; 2]) -> f64 {
    let (a, b) = match shape {
        ShapeSpec::Rectangle { size, .. } => (size[0], size[1]),
        ShapeSpec::Cook => (48.0, 44.0),
        ShapeSpec::AnnulusSector {
            inner_radius,
            outer_radius,
            angles_deg,
            ..
        } => (
            outer_radius - inner_radius,
            outer_radius * (angles_deg[1] - angles_deg[0]).to_radians(),
        ),
        _ => (1.0, 1.0),
    };
    (a / d[0].max(1) as f64).max(b / d[1].max(1) as f64)
}

/// Read a two-column numeric table (`strain, stress`): separators `,` `;` tab or spaces,
/// `#` starts a comment, one header line before the data is allowed.
fn read_two_columns(text: &str) -> Result<Vec<[f64; 2]>, String> {
    let mut pts = Vec::new();
    let mut header_seen = false;
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line
            .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .collect();
        let nums: Option<Vec<f64>> = fields.iter().map(|f| f.parse::<f64>().ok()).collect();
        match nums {
            Some(v) if v.len() == 2 => pts.push([v[0], v[1]]),
            None if pts.is_empty() && !header_seen => header_seen = true,
            _ => {
                return Err(format!(
                    "line {}: \"{line}\"; expected two numbers per line (strain, stress in MPa)",
                    i + 1
                ))
            }
        }
    }
    if pts.is_empty() {
        return Err("no data; expected lines of two numbers (strain, stress in MPa)".to_string());
    }
    Ok(pts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplitude_values() {
        assert_eq!(Amplitude::Ramp.at(0.5, 2.0), 0.25);
        assert_eq!(Amplitude::Ramp.at(3.0, 2.0), 1.0);
        assert_eq!(Amplitude::Constant.at(0.0, 2.0), 1.0);
        let t = Amplitude::Table(vec![[0.0, 0.0], [1.0, 2.0], [2.0, 2.0]]);
        assert_eq!(t.at(-1.0, 2.0), 0.0);
        assert_eq!(t.at(0.5, 2.0), 1.0);
        assert_eq!(t.at(5.0, 2.0), 2.0);
    }

    #[test]
    fn edge_sets() {
        let p = ShapeSpec::Polygon {
            vertices: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        };
        assert_eq!(p.edge_set_names(), ["boundary", "side0", "side1", "side2"]);
        assert_eq!(
            ShapeSpec::Cook.edge_set_names(),
            ["left", "right", "bottom", "top", "boundary"]
        );
        assert_eq!(ShapeSpec::Cook.center(), None);
    }

    #[test]
    fn two_column_reader() {
        let pts =
            read_two_columns("# comment\nstrain,stress\n0, 1\n0.1;2 # x\n\n0.2\t3\n").unwrap();
        assert_eq!(pts, vec![[0.0, 1.0], [0.1, 2.0], [0.2, 3.0]]);
        assert!(read_two_columns("a,b\n1,2\nx,y\n")
            .unwrap_err()
            .contains("line 3"));
        assert!(read_two_columns("# nothing\n").is_err());
    }

    #[test]
    fn line_and_column() {
        assert_eq!(line_col("ab\ncd", 4), (2, 2));
        assert_eq!(line_col("", 10), (1, 1));
    }
}

/// The default `[solver] max_iterations` of full Newton with the barrier contact (25 with the
/// node-to-segment methods). With 25, the octagon grids of the paper's studies failed their
/// first attempts where the particles slide into another arrangement, and the retries and
/// cut-backs made them snap (the 5.3 random run jammed at 0.9893); with 50 every paper job and
/// study run reached its target, but the 5.3 checkerboard and the 6.2 grid from 0.65 written
/// as 16 bodies still failed an attempt in a rearrangement, and the springs, stiffened on the
/// cut-back, held the grid until it snapped: 1.27 % and 1.54 % of the wall work. With 100 both
/// converge that attempt (springs 1.8e-7 and 3.6e-6) and most of the suite's cases cost about
/// the same. The price: an attempt that will not converge runs its whole 100 (400 in the
/// descent) — case 10 takes 1.66 times the iterations. The 1,024-octagon grid's retries at its
/// snap ran their 400 with every update cut short by the collision detection and did not get
/// through in 53 minutes; a retry now stops once its last `max_iterations` updates were all
/// cut so (`NewtonFailure::ContactLimited`), and the grid gets past its snap (docs/robustness.md,
/// seventeenth to nineteenth measurements).
pub const BARRIER_MAX_ITERATIONS: usize = 100;
