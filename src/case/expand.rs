//! The generators of a case file: `[[grids]]`, `[[packings]]` and `[[imports]]` entries are
//! validated here (every key with its message) and expanded into raw bodies by the generators
//! where they belong: the regular grids and random packings of [`crate::packing`], the
//! outline CSV and gmsh readers of [`crate::mesh::import`].

use super::raw;
use super::validate::{join_names, valid_body_name, Cx};
use super::{die_of, CaseError, MaterialSpec, ShapeSpec, WallSpec, DEFAULT_LLOYD, MAX_GRID_PARTICLES, MAX_PACKING_COUNT, MAX_POLYGON_SIDES};
use std::path::Path;

impl Cx<'_>{
    /// The die `[x0, x1, y0, y1]` closed by the four walls, for the generator at `key`.
    fn die(&self, key: &str, what: &str, walls: &[WallSpec]) -> Result<[f64; 4], CaseError> {
        let [x0, x1, y0, y1] = die_of(walls).ok_or_else(|| self.err(key, format!("a {what} fills the die, which needs all four [[walls]] (left, right, bottom, top)")))?;
        if !(x1 > x0 && y1 > y0) {
            // (absurd positions in exponent form, not as 300 digits)
            let v = |x: f64| if x == 0.0 || (1e-4..1e9).contains(&x.abs()) { format!("{x}") } else { format!("{x:e}") };
            return Err(self.err("walls", format!("the die [{}, {}] x [{}, {}] mm is empty; expected left < right and bottom < top", v(x0), v(x1), v(y0), v(y1))));
        }
        Ok([x0, x1, y0, y1])
    }

    /// The materials of a generator: `material = "a"` or `materials = ["a", "b"]`, each a known
    /// material; `(name, key)` pairs.
    fn material_list(&self, key: &str, material: Option<String>, list: Option<Vec<String>>, materials: &[MaterialSpec]) -> Result<Vec<(String, String)>, CaseError> {
        let k = |field: &str| format!("{key}.{field}");
        let names: Vec<(String, String)> = match (material, list) {
            (Some(m), None) => vec![(m, k("material"))],
            (None, Some(ms)) if !ms.is_empty() => ms.into_iter().enumerate().map(|(i, m)| (m, format!("{key}.materials[{i}]"))).collect(),
            (None, Some(_)) => return Err(self.err(&k("materials"), "empty list; expected at least one material name")),
            (Some(_), Some(_)) => return Err(self.err(&k("materials"), "given together with material; expected material = \"name\" or materials = [\"a\", \"b\", ...], not both")),
            (None, None) => return Err(self.missing(&k("material"), "material = \"name\" or materials = [\"a\", \"b\", ...] (with fractions)")),
        };
        for (name, nkey) in &names {
            if !materials.iter().any(|m| &m.name == name) {
                return Err(self.err(nkey, format!("value \"{name}\": no material named \"{name}\" (known: {})", join_names(materials.iter().map(|m| m.name.as_str())))));
            }
        }
        Ok(names)
    }

    /// `fractions` of a generator with `n` materials (default: equal shares).
    fn fractions(&self, key: &str, fractions: Option<Vec<f64>>, n: usize) -> Result<Vec<f64>, CaseError> {
        let Some(f) = fractions else { return Ok(vec![1.0; n]) };
        if f.len() != n {
            return Err(self.err(&format!("{key}.fractions"), format!("{} value(s) for {n} material(s); expected one fraction per material", f.len())));
        }
        for (i, v) in f.iter().enumerate() {
            self.positive(&format!("{key}.fractions[{i}]"), *v, "a fraction (relative share of the particles)")?;
        }
        Ok(f)
    }

    /// Expand a `[[packings]]` entry into raw bodies named `r{i}_p{k}` inside the die.
    pub(super) fn packing(&self, key: &str, index: usize, p: raw::PackingRaw, walls: &[WallSpec], materials: &[MaterialSpec]) -> Result<Vec<raw::Body>, CaseError> {
        use crate::packing::random::{self, RandomSpec, Sizes};
        let k = |field: &str| format!("{key}.{field}");
        let [x0, x1, y0, y1] = self.die(key, "random packing", walls)?;
        let kind = self.req(p.kind, &k("kind"), "\"voronoi_polygons\", \"voronoi_ellipses\" or \"discs\"")?;
        let kind = self.choice(&k("kind"), &kind, &["voronoi_polygons", "voronoi_ellipses", "discs"])?;
        let aspect = match p.aspect {
            None => 1.0,
            Some(_) if kind == "discs" => return Err(self.err(&k("aspect"), "not a parameter of kind \"discs\"; expected only with voronoi_polygons or voronoi_ellipses")),
            Some(v) => self.num(&k("aspect"), v, (0.1..=10.0).contains(&v), "an elongation of the cells along x in [0.1, 10] (1 = roundish)")?,
        };
        let count = self.count(&k("count"), self.req(p.count, &k("count"), "the number of particles (>= 1)")?, 1)?;
        if count > MAX_PACKING_COUNT {
            return Err(self.err(&k("count"), format!("value {count}; expected at most {MAX_PACKING_COUNT} particles")));
        }
        let seed = match p.seed {
            None => 0,
            Some(v) => self.count(&k("seed"), v, 0)? as u64,
        };
        let phi = self.req(p.solid_ratio, &k("solid_ratio"), "the initial solid ratio in (0, 1)")?;
        let phi = self.num(&k("solid_ratio"), phi, phi > 0.0 && phi < 1.0, "a solid ratio in (0, 1)")?;
        let h = self.positive(&k("mesh_size"), self.req(p.mesh_size, &k("mesh_size"), "an element size in mm")?, "an element size in mm")?;
        let lloyd = match p.lloyd {
            None => DEFAULT_LLOYD,
            Some(v) => {
                let n = self.count(&k("lloyd"), v, 0)?;
                if n > 1000 {
                    return Err(self.err(&k("lloyd"), format!("value {n}; expected at most 1000 relaxation steps")));
                }
                n
            }
        };
        let names = self.material_list(key, p.material, p.materials, materials)?;
        let fractions = self.fractions(key, p.fractions, names.len())?;
        let sizes = match p.sizes {
            None => Sizes::Equal,
            Some(sz) => {
                let dkey = k("sizes.distribution");
                let dist = self.req(sz.distribution, &dkey, "\"equal\", \"uniform\" or \"lognormal\"")?;
                let dist = self.choice(&dkey, &dist, &["equal", "uniform", "lognormal"])?;
                let ratio = |cx: &Self| -> Result<f64, CaseError> {
                    let rkey = k("sizes.ratio");
                    let r = cx.req(sz.ratio, &rkey, "the largest / smallest radius ratio (> 1)")?;
                    cx.num(&rkey, r, r > 1.0 && r <= 100.0, "a largest / smallest radius ratio in (1, 100]")
                };
                match dist {
                    "equal" => {
                        for (name, is) in [("ratio", sz.ratio.is_some()), ("sigma", sz.sigma.is_some())] {
                            if is {
                                return Err(self.err(&k(&format!("sizes.{name}")), "not a parameter of distribution \"equal\"; expected only with \"uniform\" (ratio) or \"lognormal\" (sigma, ratio)"));
                            }
                        }
                        Sizes::Equal
                    }
                    "uniform" => {
                        if sz.sigma.is_some() {
                            return Err(self.err(&k("sizes.sigma"), "not a parameter of distribution \"uniform\"; expected only ratio"));
                        }
                        Sizes::Uniform { ratio: ratio(self)? }
                    }
                    _ => {
                        let skey = k("sizes.sigma");
                        let sigma = self.req(sz.sigma, &skey, "the standard deviation of ln(radius) (> 0)")?;
                        let sigma = self.num(&skey, sigma, sigma > 0.0 && sigma <= 2.0, "a standard deviation of ln(radius) in (0, 2]")?;
                        Sizes::LogNormal { sigma, ratio: ratio(self)? }
                    }
                }
            }
        };
        let spec = RandomSpec { count, seed, solid_ratio: phi, sizes, lloyd, aspect, fractions };
        let die = random::Die { x: [x0, x1], y: [y0, y1] };
        let packing = match kind {
            "voronoi_polygons" => random::voronoi_polygons(die, &spec),
            "voronoi_ellipses" => random::voronoi_ellipses(die, &spec),
            _ => random::random_discs(die, &spec),
        }
        .map_err(|e| {
            let at = match e.param {
                "die" => "walls".to_string(),
                "count" | "solid_ratio" | "sizes" | "fractions" | "aspect" => k(e.param),
                _ => key.to_string(),
            };
            self.err(&at, e.message)
        })?;
        Ok(packing
            .particles
            .into_iter()
            .enumerate()
            .map(|(j, part)| {
                let material = names[part.material].0.clone();
                raw::Body::generated(format!("r{index}_p{j}"), material, h, raw::Shape::from_convex(part.shape))
            })
            .collect())
    }

    /// The particles of a gmsh file (read once per file).
    fn msh(&self, key: &str, path: &Path) -> Result<std::rc::Rc<Vec<crate::mesh::import::MshParticle>>, CaseError> {
        if let Some(m) = self.msh_cache.borrow().get(path) {
            return Ok(m.clone());
        }
        let bytes = std::fs::read(path).map_err(|e| self.err(key, format!("cannot read gmsh file \"{}\": {e}", path.display())))?;
        let parts = crate::mesh::import::read_msh(&bytes).map_err(|e| self.err(key, format!("in gmsh file \"{}\": {e}", path.display())))?;
        let parts = std::rc::Rc::new(parts);
        self.msh_cache.borrow_mut().insert(path.to_path_buf(), parts.clone());
        Ok(parts)
    }

    /// `scale` (default 1) and `offset` (default [0, 0]) of an import or a gmsh shape.
    fn placement(&self, key: &str, scale: Option<f64>, offset: Option<raw::P2>) -> Result<(f64, [f64; 2]), CaseError> {
        let scale = match scale {
            None => 1.0,
            Some(v) => self.positive(&format!("{key}.scale"), v, "a scale factor")?,
        };
        let offset = self.finite2(&format!("{key}.offset"), offset.map_or([0.0, 0.0], |p| p.0), "a finite shift (mm)")?;
        Ok((scale, offset))
    }

    /// `shape = { type = "gmsh", file, group, scale, offset }`.
    pub(super) fn gmsh_shape(&self, key: &str, s: raw::Shape) -> Result<ShapeSpec, CaseError> {
        let fkey = format!("{key}.file");
        let file = self.req(s.file, &fkey, "the path of a gmsh .msh file (relative to the case file)")?;
        // absolute, so that a case written elsewhere (mpfem pack) refers to the same file
        let path = self.base_dir.join(&file);
        let path = std::path::absolute(&path).unwrap_or(path);
        let parts = self.msh(&fkey, &path)?;
        let (scale, offset) = self.placement(key, s.scale, s.offset)?;
        let label = |p: &crate::mesh::import::MshParticle| p.name.clone().unwrap_or_else(|| p.tag.to_string());
        let known = || {
            let tags: Vec<String> = parts.iter().map(|p| p.tag.to_string()).collect();
            format!("{}; tags {}", join_names(parts.iter().filter_map(|p| p.name.as_deref())), tags.join(", "))
        };
        let gkey = format!("{key}.group");
        let part = match s.group {
            Some(g) => parts
                .iter()
                .find(|p| p.name.as_deref() == Some(g.as_str()))
                .or_else(|| parts.iter().find(|p| p.tag.to_string() == g))
                .ok_or_else(|| self.err(&gkey, format!("value \"{g}\": gmsh file \"{}\" has no 2D physical group named or tagged \"{g}\" (names: {})", path.display(), known())))?,
            None if parts.len() == 1 => &parts[0],
            None => return Err(self.missing(&gkey, &format!("the physical group (name or tag) of the particle: gmsh file \"{}\" has {} (names: {})", path.display(), parts.len(), known()))),
        };
        let mut mesh = part.mesh.clone();
        for p in &mut mesh.nodes {
            *p = [scale * p[0] + offset[0], scale * p[1] + offset[1]];
        }
        Ok(ShapeSpec::Gmsh { file: path, group: label(part), scale, offset, mesh: std::sync::Arc::new(mesh) })
    }

    /// Expand an `[[imports]]` entry into raw bodies: the particles of an outline CSV file
    /// (named `i{index}_p{k}`, k the particle's block in the file) or of a gmsh file (named by
    /// their physical name, or `i{index}_g{tag}` without one).
    pub(super) fn import(&self, key: &str, index: usize, imp: raw::ImportRaw, materials: &[MaterialSpec]) -> Result<Vec<raw::Body>, CaseError> {
        let k = |field: &str| format!("{key}.{field}");
        let file = self.req(imp.file, &k("file"), "the path of an outline CSV file (.csv) or a gmsh file (.msh), relative to the case file")?;
        let path = self.base_dir.join(&file);
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
        let ext = match ext.as_str() {
            "csv" | "msh" => ext,
            _ => return Err(self.err(&k("file"), format!("value \"{file}\": unknown file type; expected a .csv outline file or a .msh gmsh file"))),
        };
        let names = self.material_list(key, imp.material, imp.materials, materials)?;
        let fractions = self.fractions(key, imp.fractions, names.len())?;
        let seed = match imp.seed {
            None => 0,
            Some(v) => self.count(&k("seed"), v, 0)? as u64,
        };
        let (scale, offset) = self.placement(key, imp.scale, imp.offset)?;
        let material_of = |count: usize| -> Vec<String> {
            crate::packing::random::mixture(seed, count, &fractions).into_iter().map(|m| names[m.min(names.len() - 1)].0.clone()).collect()
        };
        if ext == "csv" {
            let h = self.req(imp.mesh_size, &k("mesh_size"), "an element size in mm (the outlines are meshed with it)")?;
            let h = self.positive(&k("mesh_size"), h, "an element size in mm")?;
            let text = std::fs::read_to_string(&path).map_err(|e| self.err(&k("file"), format!("cannot read outline file \"{}\": {e}", path.display())))?;
            let outlines = crate::mesh::import::read_outlines_csv(&text).map_err(|e| self.err(&k("file"), format!("in \"{}\", {e}", path.display())))?;
            let mats = material_of(outlines.len());
            return Ok(outlines
                .into_iter()
                .zip(mats)
                .enumerate()
                .map(|(j, (o, m))| {
                    let v = o.vertices.iter().map(|p| [scale * p[0] + offset[0], scale * p[1] + offset[1]]).collect();
                    raw::Body::generated(format!("i{index}_p{j}"), m, h, raw::Shape::outline(v))
                })
                .collect());
        }
        if let Some(h) = imp.mesh_size {
            return Err(self.err(&k("mesh_size"), format!("value {h:?}: not allowed for a gmsh file (the elements come from the file); expected no mesh_size")));
        }
        let parts = self.msh(&k("file"), &path)?;
        let mats = material_of(parts.len());
        let mut out = Vec::with_capacity(parts.len());
        for (p, m) in parts.iter().zip(mats) {
            let (name, group) = match &p.name {
                Some(n) if valid_body_name(n) => (n.clone(), n.clone()),
                Some(_) => {
                    return Err(self.err(
                        &k("file"),
                        format!("in gmsh file \"{}\": {}: the name is not a valid body name; expected ASCII letters, digits, '_' and '-' (rename the physical group)", path.display(), p.describe()),
                    ))
                }
                None => (format!("i{index}_g{}", p.tag), p.tag.to_string()),
            };
            out.push(raw::Body::imported(name, m, raw::Shape::gmsh(file.clone(), group, scale, offset)));
        }
        Ok(out)
    }

    /// Expand a `[[grids]]` entry into raw bodies named `g{i}_p{k}` inside the die of the walls.
    pub(super) fn grid(&self, key: &str, g: raw::GridRaw, walls: &[WallSpec], materials: &[MaterialSpec]) -> Result<Vec<raw::Body>, CaseError> {
        let [x0, x1, y0, y1] = self.die(key, "particle grid", walls)?;
        let names = self.material_list(key, g.material, g.materials, materials)?;
        let nx = self.count(&format!("{key}.nx"), self.req(g.nx, &format!("{key}.nx"), "particles along x (>= 1)")?, 1)?;
        let ny = self.count(&format!("{key}.ny"), self.req(g.ny, &format!("{key}.ny"), "particles along y (>= 1)")?, 1)?;
        if nx.checked_mul(ny).is_none_or(|n| n > MAX_GRID_PARTICLES) {
            return Err(self.err(&format!("{key}.nx"), format!("value {nx} with ny = {ny}: nx × ny particles; expected at most {MAX_GRID_PARTICLES} particles in a grid")));
        }
        let shape = g.shape.unwrap_or_else(|| "disc".into());
        let sides = match self.choice(&format!("{key}.shape"), &shape, &["disc", "ellipse", "polygon"])? {
            "disc" => 0,
            "ellipse" => usize::MAX,
            _ => self.count(&format!("{key}.sides"), g.sides.unwrap_or(6), 3)?,
        };
        if sides != usize::MAX && sides > MAX_POLYGON_SIDES {
            return Err(self.err(&format!("{key}.sides"), format!("value {sides}; expected at most {MAX_POLYGON_SIDES} sides (a disc for more)")));
        }
        let phi = self.req(g.solid_ratio, &format!("{key}.solid_ratio"), "the initial solid ratio in (0, 1)")?;
        let phi = self.num(&format!("{key}.solid_ratio"), phi, phi > 0.0 && phi < 1.0, "a solid ratio in (0, 1)")?;
        let h = self.positive(&format!("{key}.mesh_size"), self.req(g.mesh_size, &format!("{key}.mesh_size"), "an element size in mm")?, "an element size in mm")?;
        let arrangement = match g.arrangement.as_deref() {
            None => crate::packing::Arrangement::Square,
            Some(a) => match self.choice(&format!("{key}.arrangement"), a, &["square", "hexagonal"])? {
                "hexagonal" => {
                    if nx < 2 {
                        return Err(self.err(&format!("{key}.nx"), format!("value {nx}; a hexagonal grid needs nx >= 2 (its odd rows hold nx - 1 particles)")));
                    }
                    crate::packing::Arrangement::Hexagonal
                }
                _ => crate::packing::Arrangement::Square,
            },
        };
        let cells = crate::packing::grid_cells(nx, ny, arrangement);
        let assigned: Vec<usize> = match g.pattern {
            Some(pat) => {
                let pkey = format!("{key}.pattern");
                let pat = self.choice(&pkey, &pat, &["checkerboard", "rows", "columns"])?;
                for (field, given) in [("fractions", g.fractions.is_some()), ("seed", g.seed.is_some())] {
                    if given {
                        return Err(self.err(&format!("{key}.{field}"), "not allowed with pattern; expected either a pattern or fractions (with a seed)"));
                    }
                }
                let m = names.len();
                cells
                    .iter()
                    .map(|&(i, j)| match pat {
                        "checkerboard" => (i + j) % m,
                        "rows" => j % m,
                        _ => i % m,
                    })
                    .collect()
            }
            None => {
                let fractions = self.fractions(key, g.fractions, names.len())?;
                let seed = match g.seed {
                    None => 0,
                    Some(v) => self.count(&format!("{key}.seed"), v, 0)? as u64,
                };
                crate::packing::random::mixture(seed, cells.len(), &fractions)
            }
        };
        let material = |k: usize| names[assigned.get(k).copied().unwrap_or(0)].0.clone();
        let ix = key.trim_start_matches("grids[").trim_end_matches(']');
        let angle0 = match g.orientation.as_deref() {
            None => std::f64::consts::FRAC_PI_2,
            Some(o) => {
                let okey = format!("{key}.orientation");
                if sides == 0 || sides == usize::MAX {
                    return Err(self.err(&okey, format!("value \"{o}\": not allowed for shape \"{shape}\"; expected orientation only with shape = \"polygon\"")));
                }
                match self.choice(&okey, o, &["vertex", "flat"])? {
                    "flat" => std::f64::consts::PI / sides as f64,
                    _ => std::f64::consts::FRAC_PI_2,
                }
            }
        };
        if sides == usize::MAX {
            let places = crate::packing::arranged_grid_ellipses(nx, ny, x1 - x0, y1 - y0, phi, arrangement).map_err(|m| self.err(&format!("{key}.solid_ratio"), m))?;
            return Ok(places
                .iter()
                .enumerate()
                .map(|(k, (c, ab))| {
                    let mut shape = raw::Shape::disc([x0 + c[0], y0 + c[1]], 0.0);
                    shape.kind = Some("ellipse".into());
                    shape.radius = None;
                    shape.semi_axes = Some(raw::Pair(*ab));
                    shape.angle = Some(0.0);
                    raw::Body::generated(format!("g{ix}_p{k}"), material(k), h, shape)
                })
                .collect());
        }
        let places = crate::packing::oriented_grid(nx, ny, x1 - x0, y1 - y0, phi, sides, arrangement, angle0).map_err(|m| self.err(&format!("{key}.solid_ratio"), m))?;
        Ok(places
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let c = [x0 + p.center[0], y0 + p.center[1]];
                let shape = if sides == 0 {
                    raw::Shape::disc(c, p.radius)
                } else {
                    raw::Shape::polygon(crate::packing::regular_polygon(c, p.radius, sides, angle0))
                };
                raw::Body::generated(format!("g{ix}_p{k}"), material(k), h, shape)
            })
            .collect())
    }
}
