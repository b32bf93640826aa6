//! Field results for post-processing: `results.h5` (HDF5) and `results.xdmf` (an XDMF temporal
//! collection over it that ParaView opens directly).
//!
//! ## Layout of `results.h5`
//! One group per output step, `/steps/NNNNNN` (`NNNNNN` = the solver's step number, zero
//! padded), with the attributes `time` (s, f64) and `step` (u64), holding
//! - `coordinates` (n_nodes × 2, f64, mm): current node positions x = X + u;
//! - `cells` (n_elements × 4, i64): the quadrilaterals, 0-based node numbers, counter-clockwise;
//! - `particle_id`, `material_id` (n_elements, i32): body and material index of each cell;
//! - `displacement` (n_nodes × 3, f64, mm): u_x, u_y and u_z = 0 (plane strain; three
//!   components so that ParaView shows it as a vector);
//! - cell fields (n_elements, f64), averages over the element's Gauss points:
//!   `stress_xx`, `stress_yy`, `stress_xy`, `stress_zz` (Cauchy, MPa), `von_mises` (MPa),
//!   `pressure` = −tr σ / 3 (MPa), `eq_plastic_strain` and `eq_creep_strain` (the equivalent
//!   strains of the material state, 0 for a law without them);
//! - `velocity` (n_nodes × 3, f64, mm/s): the Newmark velocity in a dynamic run, otherwise the
//!   mean velocity of the step (u_n − u_{n−1})/Δt;
//! - when the model has contact (walls or several particles), node fields from the last
//!   converged contact evaluation: `contact_pressure` and `contact_shear` (n_nodes, MPa: the
//!   normal and tangential components of the node's contact force over its tributary contact
//!   length, current configuration, both sides of a pair alike; pressure positive in
//!   compression, shear positive along the boundary with the particle on its left; see
//!   `crate::contact::NodalContact::set_tractions`), `contact_gap` (n_nodes, mm, smallest normal gap to a
//!   candidate segment or wall, negative = penetration, NaN for a node without one),
//!   `contact_status` (n_nodes, i32: 0 open, 1 sliding, 2 sticking, 3 tied), `contact_force`
//!   (n_nodes × 3, N/mm: the force the contacts exert on the node) and `wall_force`
//!   (n_nodes × 4, N/mm: the normal force the node exerts on the left, right, bottom and top
//!   wall; its column sums are `f_left` … `f_top` of the history). With the barrier contact
//!   (`crate::solver::Snapshot::nodal`): the gap is the distance the barrier
//!   acts on (positive; NaN beyond d̂), the status 0 / 1 / 2 / 3 as above (sticking: a slip
//!   of the step below ε_v), the force that of the barrier, the friction and the ties;
//! - when the model has walls: `wall_points` (2 n_walls × 2, f64, mm) and `wall_cells`
//!   (n_walls × 2, i64): each wall as a line segment at its current position, spanning the
//!   two walls across it (or the particles' extent when one of those is missing), and
//!   `wall_id` (n_walls, i32: 0 left, 1 right, 2 bottom, 3 top).
//!
//! `/history` (n_rows × n_columns, f64, chunked, grows by one row per converged step) holds the
//! history table of `history.csv`, its column names in the attribute `columns`.
//!
//! `results.xdmf` describes the particles; `walls.xdmf` (written when the model has walls)
//! describes the walls over the same steps; open both in ParaView.
//!
//! The file is flushed after every output step, so a run that is killed leaves a readable
//! file with every step written so far. `results.xdmf` is rewritten after every output step
//! through a temporary file and a rename, so it is always complete and names only steps that
//! are in `results.h5`.

use crate::loading::WallSide;
use crate::solver::{Snapshot, StepReport};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A failure while writing the results files.
#[derive(Debug, Error)]
pub enum ResultsError {
    #[error("{path}: {source}")]
    Hdf5 {
        path: PathBuf,
        #[source]
        source: hdf5::Error,
    },
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// The XDMF text of a written step.
#[derive(Clone, Debug)]
struct WrittenStep {
    /// Its grid in `results.xdmf`.
    grid: String,
    /// Its grid in `walls.xdmf` (None without walls).
    walls: Option<String>,
}

/// Cell (element) fields written per step, in this order.
pub const CELL_FIELDS: [&str; 8] = [
    "stress_xx",
    "stress_yy",
    "stress_xy",
    "stress_zz",
    "von_mises",
    "pressure",
    "eq_plastic_strain",
    "eq_creep_strain",
];

/// Writes `results.h5` and `results.xdmf` step by step.
pub struct ResultsWriter {
    file: hdf5::File,
    pub h5_path: PathBuf,
    pub xdmf_path: PathBuf,
    /// `walls.xdmf`: the walls as line segments, a temporal collection of its own (written
    /// when the model has walls; a separate file so that the particles' cell fields are not
    /// partial arrays of a multi-block data set in ParaView).
    pub walls_xdmf_path: PathBuf,
    every: usize,
    /// Number of history columns and rows written.
    history_columns: usize,
    history_rows: usize,
    steps: Vec<WrittenStep>,
    /// Wall-clock time spent writing the results so far (s).
    pub elapsed_s: f64,
    last_step: Option<usize>,
}

/// The von Mises equivalent of a plane-strain Cauchy stress `[xx, yy, xy, zz]`.
pub fn von_mises(s: &[f64; 4]) -> f64 {
    let [xx, yy, xy, zz] = *s;
    (0.5 * ((xx - yy).powi(2) + (yy - zz).powi(2) + (zz - xx).powi(2)) + 3.0 * xy * xy).sqrt()
}

impl ResultsWriter {
    /// Create (truncate) `DIR/results.h5` and write an empty `DIR/results.xdmf`. `every` is the
    /// output frequency in converged steps (must be ≥ 1); `columns` are the names of the
    /// history columns ([`crate::output::history_columns`]).
    pub fn create(dir: &Path, every: usize, columns: &[String]) -> Result<Self, ResultsError> {
        let h5_path = dir.join("results.h5");
        let xdmf_path = dir.join("results.xdmf");
        let walls_xdmf_path = dir.join("walls.xdmf");
        let _ = std::fs::remove_file(&walls_xdmf_path);
        let file = crate::h5::create(&h5_path).map_err(|source| ResultsError::Hdf5 {
            path: h5_path.clone(),
            source,
        })?;
        let w = Self {
            file,
            h5_path,
            xdmf_path,
            walls_xdmf_path,
            every: every.max(1),
            history_columns: columns.len(),
            history_rows: 0,
            elapsed_s: 0.0,
            steps: Vec::new(),
            last_step: None,
        };
        let names: Vec<hdf5::types::VarLenUnicode> = columns
            .iter()
            .map(|c| c.parse().unwrap_or_default())
            .collect();
        w.h5(|f| {
            f.create_group("steps")?;
            let h = f
                .new_dataset::<f64>()
                .chunk((64, columns.len().max(1)))
                .shape((0.., columns.len()))
                .create("history")?;
            h.new_attr::<hdf5::types::VarLenUnicode>()
                .shape(names.len())
                .create("columns")?
                .write_raw(&names)?;
            f.flush()
        })?;
        w.write_xdmf()?;
        Ok(w)
    }

    /// Continue `DIR/results.h5` after a restart from step `keep_step`: the output steps and
    /// history rows up to `keep_step` stay, later ones go, and so does a step at `keep_step`
    /// that is not an output step (the last step the stopped run wrote on closing), so that
    /// the file ends as that of an uninterrupted run. A missing file is created anew.
    pub fn open_append(dir: &Path, every: usize, columns: &[String], keep_step: usize) -> Result<Self, ResultsError> {
        let h5_path = dir.join("results.h5");
        if !h5_path.is_file() {
            tracing::warn!(path = %h5_path.display(), "restart: no results.h5 to continue, the steps before the checkpoint are missing");
            return Self::create(dir, every, columns);
        }
        let file = crate::h5::open_rw(&h5_path).map_err(|source| ResultsError::Hdf5 { path: h5_path.clone(), source })?;
        let every = every.max(1);
        let mut w = Self {
            file,
            h5_path,
            xdmf_path: dir.join("results.xdmf"),
            walls_xdmf_path: dir.join("walls.xdmf"),
            every,
            history_columns: columns.len(),
            history_rows: 0,
            elapsed_s: 0.0,
            steps: Vec::new(),
            last_step: None,
        };
        let h5 = w.h5_path.file_name().map_or_else(|| "results.h5".into(), |s| s.to_string_lossy().into_owned());
        let (rows, steps, last) = w.h5(|f| {
            let h = f.dataset("history")?;
            let shape = h.shape();
            if shape.len() != 2 || shape[1] != columns.len() {
                return Err(hdf5::Error::from(format!("/history has shape {shape:?}, the case has {} columns", columns.len())));
            }
            let values = h.read_raw::<f64>()?;
            let rows = values.chunks_exact(columns.len().max(1)).take_while(|r| r.first().is_some_and(|&s| s <= keep_step as f64)).count();
            h.resize((rows, columns.len()))?;
            let group = f.group("steps")?;
            let mut names = group.member_names()?;
            names.sort();
            let mut steps = Vec::new();
            let mut last = None;
            for name in names {
                let Ok(step) = name.parse::<usize>() else { continue };
                if step > keep_step || (step == keep_step && step % every != 0) {
                    group.unlink(&name)?;
                    continue;
                }
                let g = group.group(&name)?;
                let time: f64 = g.attr("time")?.read_scalar()?;
                let n_nodes = g.dataset("coordinates")?.shape()[0];
                let n_cells = g.dataset("cells")?.shape()[0];
                let contact = g.link_exists("contact_pressure");
                let walls = if g.link_exists("wall_id") { Some(g.dataset("wall_id")?.shape()[0]) } else { None };
                let gp = format!("/steps/{name}");
                steps.push(WrittenStep {
                    grid: particle_grid(&h5, &gp, time, n_nodes, n_cells, contact),
                    walls: walls.map(|n| wall_grid(&h5, &gp, time, n)),
                });
                last = Some(step);
            }
            f.flush()?;
            Ok((rows, steps, last))
        })?;
        w.history_rows = rows;
        w.steps = steps;
        w.last_step = last;
        w.write_xdmf()?;
        Ok(w)
    }

    fn h5<T>(&self, op: impl FnOnce(&hdf5::File) -> hdf5::Result<T>) -> Result<T, ResultsError> {
        op(&self.file).map_err(|source| ResultsError::Hdf5 {
            path: self.h5_path.clone(),
            source,
        })
    }

    /// Number of steps written so far.
    pub fn n_written(&self) -> usize {
        self.steps.len()
    }

    /// Write the step of `report` when its number is a multiple of the output frequency.
    /// Returns whether it was written.
    pub fn observe(&mut self, sim: &Snapshot, report: &StepReport) -> Result<bool, ResultsError> {
        self.append_history(report)?;
        if report.step % self.every == 0 {
            self.write_step(sim, report.step, report.time)?;
            return Ok(true);
        }
        Ok(false)
    }

    /// Append the history row of `report` to `/history` (flushed at the next output step, or
    /// at once when output steps are rare).
    pub fn append_history(&mut self, report: &StepReport) -> Result<(), ResultsError> {
        let row = crate::output::history_values(report);
        let (n, m) = (self.history_rows, self.history_columns);
        if row.len() != m {
            // cannot happen for the model the columns came from; keep the file consistent
            tracing::warn!(got = row.len(), expected = m, "history row of the wrong length not written to results.h5");
            return Ok(());
        }
        let flush = report.step % self.every != 0 && self.every > 1;
        self.h5(|f| {
            let h = f.dataset("history")?;
            h.resize((n + 1, m))?;
            h.write_slice(&row[..], (n, ..))?;
            if flush {
                f.flush()?;
            }
            Ok(())
        })?;
        self.history_rows += 1;
        Ok(())
    }

    /// Write the current state of `sim` (the end of the last converged step) unless that step
    /// is already written: call once after the run so that the last step is always there.
    pub fn finish(
        &mut self,
        sim: &Snapshot,
        last: Option<&StepReport>,
    ) -> Result<(), ResultsError> {
        let Some(r) = last else { return Ok(()) };
        if self.last_step != Some(r.step) {
            self.write_step(sim, r.step, r.time)?;
        }
        Ok(())
    }

    /// Write the current state of `sim` as output step `step` at time `time`, flush the HDF5
    /// file and rewrite the XDMF file.
    pub fn write_step(
        &mut self,
        sim: &Snapshot,
        step: usize,
        time: f64,
    ) -> Result<(), ResultsError> {
        let started = std::time::Instant::now();
        let model = sim.model;
        let u = &sim.sol.u;
        let x = sim.coords();
        let n_nodes = x.len();
        let n_cells = model.elements.len();
        let coords: Vec<f64> = x.iter().flat_map(|p| [p[0], p[1]]).collect();
        let disp: Vec<f64> = (0..n_nodes)
            .flat_map(|n| [u[2 * n], u[2 * n + 1], 0.0])
            .collect();
        let cells: Vec<i64> = model
            .elements
            .iter()
            .flat_map(|e| e.map(|n| n as i64))
            .collect();
        let vel = sim.velocity();
        let velocity: Vec<f64> = (0..n_nodes)
            .flat_map(|n| [vel[2 * n], vel[2 * n + 1], 0.0])
            .collect();
        let contact = sim.nodal.filter(|c| c.pressure.len() == n_nodes).map(|c| {
            let mut wall_force = vec![0.0; 4 * n_nodes];
            for (w, f) in model.loading.walls.iter().zip(&c.wall_force) {
                let side = w.side.index();
                for (n, v) in f.iter().enumerate() {
                    wall_force[4 * n + side] += v;
                }
            }
            let force: Vec<f64> = c.force.iter().flat_map(|f| [f[0], f[1], 0.0]).collect();
            (c, force, wall_force)
        });
        let particle: Vec<i32> = model.elem_body.iter().map(|&b| b as i32).collect();
        let material: Vec<i32> = model.elem_material.iter().map(|&m| m as i32).collect();

        let f = &sim.sol.fields;
        let mut cell: Vec<Vec<f64>> = vec![Vec::with_capacity(n_cells); CELL_FIELDS.len()];
        for e in 0..n_cells {
            let mut s = [0.0; 4];
            let (mut ep, mut ec) = (0.0, 0.0);
            let ngp = f.sig.get(e).map_or(0, |g| g.len());
            if let Some(gps) = f.sig.get(e) {
                for g in gps {
                    for c in 0..4 {
                        s[c] += g[c] / ngp as f64;
                    }
                }
            }
            if let Some(st) = f.states.get(e) {
                for q in st {
                    ep += q.eps_p / st.len() as f64;
                    ec += q.eps_c / st.len() as f64;
                }
            }
            let vals = [
                s[0],
                s[1],
                s[2],
                s[3],
                von_mises(&s),
                -(s[0] + s[1] + s[3]) / 3.0,
                ep,
                ec,
            ];
            for (k, v) in vals.into_iter().enumerate() {
                cell[k].push(v);
            }
        }

        // Walls as line segments.
        let t = sim.sol.time;
        let loading = &model.loading;
        let walls = &loading.walls;
        let pos = |side: WallSide| loading.wall_on(side).map(|w| loading.wall_position(w, t));
        let extent = |c: usize| {
            x.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p[c]), hi.max(p[c]))
                })
        };
        let mut wall_points = Vec::with_capacity(4 * walls.len());
        let mut wall_ids = Vec::with_capacity(walls.len());
        for (iw, w) in walls.iter().enumerate() {
            let p = loading.wall_position(iw, t);
            match w.side {
                WallSide::Left | WallSide::Right => {
                    let (lo, hi) = match (pos(WallSide::Bottom), pos(WallSide::Top)) {
                        (Some(a), Some(b)) => (a, b),
                        _ => extent(1),
                    };
                    wall_points.extend([p, lo, p, hi]);
                }
                WallSide::Bottom | WallSide::Top => {
                    let (lo, hi) = match (pos(WallSide::Left), pos(WallSide::Right)) {
                        (Some(a), Some(b)) => (a, b),
                        _ => extent(0),
                    };
                    wall_points.extend([lo, p, hi, p]);
                }
            }
            wall_ids.push(w.side.index() as i32);
        }
        let wall_cells: Vec<i64> = (0..2 * walls.len() as i64).collect();

        let group = format!("steps/{step:06}");
        self.h5(|file| {
            let g = file.create_group(&group)?;
            g.new_attr::<f64>().create("time")?.write_scalar(&time)?;
            g.new_attr::<u64>()
                .create("step")?
                .write_scalar(&(step as u64))?;
            g.new_dataset::<f64>()
                .shape((n_nodes, 2))
                .create("coordinates")?
                .write_raw(&coords)?;
            g.new_dataset::<i64>()
                .shape((n_cells, 4))
                .create("cells")?
                .write_raw(&cells)?;
            g.new_dataset::<i32>()
                .shape(n_cells)
                .create("particle_id")?
                .write_raw(&particle)?;
            g.new_dataset::<i32>()
                .shape(n_cells)
                .create("material_id")?
                .write_raw(&material)?;
            g.new_dataset::<f64>()
                .shape((n_nodes, 3))
                .create("displacement")?
                .write_raw(&disp)?;
            g.new_dataset::<f64>()
                .shape((n_nodes, 3))
                .create("velocity")?
                .write_raw(&velocity)?;
            if let Some((c, force, wall_force)) = &contact {
                for (name, v) in [("contact_pressure", &c.pressure), ("contact_shear", &c.shear), ("contact_gap", &c.gap)] {
                    g.new_dataset::<f64>().shape(n_nodes).create(name)?.write_raw(v)?;
                }
                g.new_dataset::<i32>()
                    .shape(n_nodes)
                    .create("contact_status")?
                    .write_raw(&c.status)?;
                g.new_dataset::<f64>()
                    .shape((n_nodes, 3))
                    .create("contact_force")?
                    .write_raw(force)?;
                g.new_dataset::<f64>()
                    .shape((n_nodes, 4))
                    .create("wall_force")?
                    .write_raw(wall_force)?;
            }
            for (name, v) in CELL_FIELDS.iter().zip(&cell) {
                g.new_dataset::<f64>()
                    .shape(n_cells)
                    .create(*name)?
                    .write_raw(v)?;
            }
            if !walls.is_empty() {
                g.new_dataset::<f64>()
                    .shape((2 * walls.len(), 2))
                    .create("wall_points")?
                    .write_raw(&wall_points)?;
                g.new_dataset::<i64>()
                    .shape((walls.len(), 2))
                    .create("wall_cells")?
                    .write_raw(&wall_cells)?;
                g.new_dataset::<i32>()
                    .shape(walls.len())
                    .create("wall_id")?
                    .write_raw(&wall_ids)?;
            }
            file.flush()
        })?;
        let h5 = self
            .h5_path
            .file_name()
            .map_or_else(|| "results.h5".into(), |s| s.to_string_lossy().into_owned());
        let g = format!("/{group}");
        self.steps.push(WrittenStep {
            grid: particle_grid(&h5, &g, time, n_nodes, n_cells, contact.is_some()),
            walls: (!walls.is_empty()).then(|| wall_grid(&h5, &g, time, walls.len())),
        });
        self.last_step = Some(step);
        self.write_xdmf()?;
        self.elapsed_s += started.elapsed().as_secs_f64();
        tracing::debug!(step, time, "results: wrote step");
        Ok(())
    }

    /// The XDMF text for the steps written so far (the grids are formatted once, when their
    /// step is written).
    fn xdmf_text(&self) -> String {
        let mut s =
            String::with_capacity(256 + self.steps.iter().map(|st| st.grid.len()).sum::<usize>());
        s.push_str(XDMF_HEAD);
        s.push_str(
            "    <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
        );
        for st in &self.steps {
            s.push_str(&st.grid);
        }
        s.push_str("    </Grid>\n  </Domain>\n</Xdmf>\n");
        s
    }

    /// The XDMF text of the walls for the steps written so far (`None` without walls).
    fn walls_xdmf_text(&self) -> Option<String> {
        if self.steps.iter().all(|st| st.walls.is_none()) {
            return None;
        }
        let mut s = String::new();
        s.push_str(XDMF_HEAD);
        s.push_str(
            "    <Grid Name=\"walls\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
        );
        for w in self.steps.iter().filter_map(|st| st.walls.as_ref()) {
            s.push_str(w);
        }
        s.push_str("    </Grid>\n  </Domain>\n</Xdmf>\n");
        Some(s)
    }

    /// Rewrite `results.xdmf` (and `walls.xdmf`) atomically (temporary file, then rename).
    fn write_xdmf(&self) -> Result<(), ResultsError> {
        replace_file(&self.xdmf_path, &self.xdmf_text())?;
        if let Some(text) = self.walls_xdmf_text() {
            replace_file(&self.walls_xdmf_path, &text)?;
        }
        Ok(())
    }
}

/// Write `text` to `path` through a temporary file and a rename, so that `path` is always
/// either the old or the new complete file.
fn replace_file(path: &Path, text: &str) -> Result<(), ResultsError> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let io = |source| ResultsError::Io {
        path: path.to_path_buf(),
        source,
    };
    // (a temporary file cut short by a full disk is not left behind)
    let written = std::fs::write(&tmp, text).and_then(|()| std::fs::rename(&tmp, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written.map_err(io)
}

const XDMF_HEAD: &str = "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n  <Domain>\n";

/// An XDMF data item pointing into the HDF5 file.
fn item(h5: &str, dims: String, ty: &str, prec: u8, path: &str) -> String {
    format!("<DataItem Dimensions=\"{dims}\" NumberType=\"{ty}\" Precision=\"{prec}\" Format=\"HDF\">{h5}:{path}</DataItem>")
}

/// The XDMF grid of the particles at one output step (HDF5 group `g`), with the contact node
/// fields when `contact`.
fn particle_grid(h5: &str, g: &str, time: f64, n_nodes: usize, n_cells: usize, contact: bool) -> String {
    let name = g.rsplit('/').next().unwrap_or("step");
    let mut s = String::new();
    let _ = writeln!(s, "      <Grid Name=\"step_{name}\" GridType=\"Uniform\">");
    let _ = writeln!(s, "        <Time Value=\"{time:.17e}\"/>");
    let _ = writeln!(
        s,
        "        <Topology TopologyType=\"Quadrilateral\" NumberOfElements=\"{n_cells}\">{}</Topology>",
        item(h5, format!("{n_cells} 4"), "Int", 8, &format!("{g}/cells"))
    );
    let _ = writeln!(
        s,
        "        <Geometry GeometryType=\"XY\">{}</Geometry>",
        item(
            h5,
            format!("{n_nodes} 2"),
            "Float",
            8,
            &format!("{g}/coordinates")
        )
    );
    let vectors: &[&str] = if contact { &["displacement", "velocity", "contact_force"] } else { &["displacement", "velocity"] };
    for name in vectors {
        let _ = writeln!(
            s,
            "        <Attribute Name=\"{name}\" AttributeType=\"Vector\" Center=\"Node\">{}</Attribute>",
            item(h5, format!("{n_nodes} 3"), "Float", 8, &format!("{g}/{name}"))
        );
    }
    if contact {
        for (name, ty, prec) in [("contact_pressure", "Float", 8), ("contact_shear", "Float", 8), ("contact_gap", "Float", 8), ("contact_status", "Int", 4)] {
            let _ = writeln!(
                s,
                "        <Attribute Name=\"{name}\" AttributeType=\"Scalar\" Center=\"Node\">{}</Attribute>",
                item(h5, n_nodes.to_string(), ty, prec, &format!("{g}/{name}"))
            );
        }
    }
    for name in ["particle_id", "material_id"] {
        let _ = writeln!(
            s,
            "        <Attribute Name=\"{name}\" AttributeType=\"Scalar\" Center=\"Cell\">{}</Attribute>",
            item(h5, n_cells.to_string(), "Int", 4, &format!("{g}/{name}"))
        );
    }
    for name in CELL_FIELDS {
        let _ = writeln!(
            s,
            "        <Attribute Name=\"{name}\" AttributeType=\"Scalar\" Center=\"Cell\">{}</Attribute>",
            item(h5, n_cells.to_string(), "Float", 8, &format!("{g}/{name}"))
        );
    }
    s.push_str("      </Grid>\n");
    s
}

/// The XDMF grid of the walls at one output step (HDF5 group `g`).
fn wall_grid(h5: &str, g: &str, time: f64, n_walls: usize) -> String {
    let name = g.rsplit('/').next().unwrap_or("step");
    let mut s = String::new();
    let _ = writeln!(s, "      <Grid Name=\"walls_{name}\" GridType=\"Uniform\">");
    let _ = writeln!(s, "        <Time Value=\"{time:.17e}\"/>");
    let _ = writeln!(
        s,
        "        <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\"{n_walls}\">{}</Topology>",
        item(h5, format!("{n_walls} 2"), "Int", 8, &format!("{g}/wall_cells"))
    );
    let _ = writeln!(
        s,
        "        <Geometry GeometryType=\"XY\">{}</Geometry>",
        item(
            h5,
            format!("{} 2", 2 * n_walls),
            "Float",
            8,
            &format!("{g}/wall_points")
        )
    );
    let _ = writeln!(
        s,
        "        <Attribute Name=\"wall_id\" AttributeType=\"Scalar\" Center=\"Cell\">{}</Attribute>",
        item(h5, n_walls.to_string(), "Int", 4, &format!("{g}/wall_id"))
    );
    s.push_str("      </Grid>\n");
    s
}
