//! Run outputs: `history.csv` (one row per converged step, flushed every step so a run that
//! fails or is killed keeps every row written so far) and `summary.json` (written at the end,
//! also when the run fails, with the status and the error).

use crate::model::Model;
use crate::solver::{RunSummary, Snapshot, StepReport};
use serde::Serialize;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Compaction columns (the contact issue's exact names), present when the model has walls or
/// several bodies.
pub const COMPACTION_COLUMNS: [&str; 21] = [
    "solid_ratio",
    "p_left",
    "p_right",
    "p_bottom",
    "p_top",
    "f_left",
    "f_right",
    "f_bottom",
    "f_top",
    "max_penetration",
    "active_contacts",
    "stabilisation_energy",
    "external_work",
    "ft_left",
    "ft_right",
    "ft_bottom",
    "ft_top",
    "travel_left",
    "travel_right",
    "travel_bottom",
    "travel_top",
];

/// Whether a model writes the compaction columns.
pub fn has_compaction(model: &Model) -> bool {
    model.has_contact()
}

/// Column names of `history.csv` for a model.
pub fn history_columns(model: &Model) -> Vec<String> {
    let mut c: Vec<String> = [
        "step",
        "time",
        "dt",
        "newton_iterations",
        "volume_updates",
        "cutbacks",
        "residual",
        "volume_error",
        "volume_error_max_body",
        "max_element_volume_change",
        "kinetic_energy",
        "remeshes",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if has_compaction(model) {
        for k in COMPACTION_COLUMNS {
            c.push(k.to_string());
        }
    }
    for g in &model.reaction_groups {
        c.push(format!("rx_{}", g.label));
        c.push(format!("ry_{}", g.label));
    }
    for g in &model.displacement_groups {
        c.push(format!("ux_{}", g.label));
        c.push(format!("uy_{}", g.label));
    }
    c
}

/// A CSV table written row by row, each row whole or not at all (`history.csv`, `probes.csv`):
/// its first column is the step, by which a restart keeps the rows written before its
/// checkpoint.
struct CsvTable {
    out: File,
    /// The bytes of the rows written whole (a failed row is cut back to it).
    len: u64,
    path: PathBuf,
    /// Per column: whether it holds a count (written as an integer).
    integer: Vec<bool>,
    /// Whether the other numbers are written in full (the shortest form that reads back to
    /// the same f64) instead of ten significant digits.
    exact: bool,
}

impl CsvTable {
    fn create(path: PathBuf, header: &str, integer: Vec<bool>, exact: bool) -> std::io::Result<Self> {
        let mut out = File::create(&path)?;
        let line = format!("{header}\n");
        out.write_all(line.as_bytes())?;
        Ok(Self { out, len: line.len() as u64, path, integer, exact })
    }

    /// Continue `path` after a restart from step `keep_step`: the rows of steps up to
    /// `keep_step` stay, later ones (written after the checkpoint) go. A missing file is
    /// created anew (a warning says the earlier rows are lost); a file with another header is
    /// an error.
    fn open_append(path: PathBuf, header: &str, integer: Vec<bool>, exact: bool, keep_step: usize) -> std::io::Result<Self> {
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                tracing::warn!(path = %path.display(), "restart: no file to continue, the rows before the checkpoint are missing");
                return Self::create(path, header, integer, exact);
            }
            Err(e) => return Err(e),
        };
        let mut lines = text.lines();
        if lines.next() != Some(header) {
            return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, format!("{}: its columns are not those of the case", path.display())));
        }
        let mut kept = header.to_string();
        kept.push('\n');
        let mut last = 0;
        for line in lines {
            let step = line.split(',').next().and_then(|v| v.trim().parse::<usize>().ok());
            if let Some(s) = step.filter(|&s| s <= keep_step) {
                kept.push_str(line);
                kept.push('\n');
                last = last.max(s);
            }
        }
        if last < keep_step {
            tracing::warn!(path = %path.display(), last_row = last, checkpoint = keep_step, "restart: the file's rows end at step {last}, the checkpoint is at step {keep_step}: steps {} to {keep_step} are missing from it", last + 1);
        }
        let mut tmp = path.clone().into_os_string();
        tmp.push(".tmp");
        let tmp = PathBuf::from(tmp);
        let len = kept.len() as u64;
        if let Err(e) = std::fs::write(&tmp, kept) {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
        std::fs::rename(&tmp, &path)?;
        let out = std::fs::OpenOptions::new().append(true).open(&path)?;
        Ok(Self { out, len, path, integer, exact })
    }

    /// Append the row `values`, whole: a write that fails part-way (a full disk) is cut back
    /// to the rows before it, and the error returned.
    fn write(&mut self, values: &[f64]) -> std::io::Result<()> {
        use std::fmt::Write as _;
        let mut row = String::with_capacity(24 * values.len());
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                row.push(',');
            }
            // (writing into a String cannot fail)
            let _ = if self.integer.get(i).copied().unwrap_or(false) {
                write!(row, "{v}")
            } else if self.exact {
                write!(row, "{v:e}")
            } else {
                write!(row, "{v:.9e}")
            };
        }
        row.push('\n');
        match self.out.write_all(row.as_bytes()) {
            Ok(()) => {
                self.len += row.len() as u64;
                Ok(())
            }
            Err(e) => {
                // (the part of the row that went out is taken back; the file is opened for
                // appending, so the next row follows the whole ones)
                let _ = self.out.set_len(self.len);
                Err(e)
            }
        }
    }
}

/// Writes `history.csv` row by row.
pub struct HistoryWriter {
    table: CsvTable,
    pub path: PathBuf,
}

impl HistoryWriter {
    pub fn create(dir: &Path, model: &Model) -> std::io::Result<Self> {
        let table = CsvTable::create(dir.join("history.csv"), &history_columns(model).join(","), integer_columns(model), false)?;
        Ok(Self { path: table.path.clone(), table })
    }

    /// Continue `DIR/history.csv` after a restart from step `keep_step`: the rows of steps up
    /// to `keep_step` stay, later ones (written after the checkpoint) go. A missing file is
    /// created anew (a warning says the earlier rows are lost); a file with other columns is an
    /// error.
    pub fn open_append(dir: &Path, model: &Model, keep_step: usize) -> std::io::Result<Self> {
        let table = CsvTable::open_append(dir.join("history.csv"), &history_columns(model).join(","), integer_columns(model), false, keep_step)?;
        Ok(Self { path: table.path.clone(), table })
    }

    pub fn write(&mut self, r: &StepReport) -> std::io::Result<()> {
        self.table.write(&history_values(r))
    }
}

/// What a probe reports, the suffixes of its columns in `probes.csv`: its current position,
/// displacement, Cauchy stress and equivalent plastic and creep strains.
pub const PROBE_QUANTITIES: [&str; 10] = ["x", "y", "ux", "uy", "sxx", "syy", "sxy", "szz", "peeq", "ceeq"];

/// The columns of `probes.csv`: `step`, `time`, then `NAME_x` … `NAME_ceeq` per probe.
pub fn probe_columns(model: &Model) -> Vec<String> {
    let mut c = vec!["step".to_string(), "time".to_string()];
    for p in &model.probes {
        c.extend(PROBE_QUANTITIES.iter().map(|q| format!("{}_{q}", p.name)));
    }
    c
}

/// The probes' values in the state of `sim` (the order of [`PROBE_QUANTITIES`] per probe). A
/// point probe: the element's bilinear interpolation of the nodal displacement at its local
/// coordinates, and of the element's Gauss-point stresses and strains (the bilinear field
/// through the four Gauss points, [`crate::element::from_gauss_points`]). A node probe: the
/// node's own displacement, and the mean over the elements at the node of their Gauss-point
/// fields extrapolated to it.
pub fn probe_values(sim: &Snapshot) -> Vec<f64> {
    use crate::element::{corner, from_gauss_points, shape};
    use crate::model::ProbeAt;
    let (model, u, f) = (sim.model, &sim.sol.u, &sim.sol.fields);
    // the element's fields at (ξ, η): [sxx, syy, sxy, szz, peeq, ceeq]
    let fields = |e: usize, xi: [f64; 2]| -> [f64; 6] {
        let mut out = [0.0; 6];
        if let Some(sig) = f.sig.get(e) {
            for c in 0..4 {
                out[c] = from_gauss_points([sig[0][c], sig[1][c], sig[2][c], sig[3][c]], xi);
            }
        }
        if let Some(st) = f.states.get(e) {
            out[4] = from_gauss_points(st.map(|q| q.eps_p), xi);
            out[5] = from_gauss_points(st.map(|q| q.eps_c), xi);
        }
        out
    };
    let mut v = Vec::with_capacity(PROBE_QUANTITIES.len() * model.probes.len());
    for p in &model.probes {
        let (xx, uu, s) = match &p.at {
            ProbeAt::Point { element, xi } => {
                let (n, el) = (shape(xi[0], xi[1]), model.elements[*element]);
                let (mut xx, mut uu) = ([0.0; 2], [0.0; 2]);
                for a in 0..4 {
                    for c in 0..2 {
                        xx[c] += n[a] * model.x0[el[a]][c];
                        uu[c] += n[a] * u[2 * el[a] + c];
                    }
                }
                (xx, uu, fields(*element, *xi))
            }
            ProbeAt::Node { node, corners } => {
                let mut s = [0.0; 6];
                for &(e, a) in corners {
                    let q = fields(e, corner(a));
                    for c in 0..6 {
                        s[c] += q[c] / corners.len() as f64;
                    }
                }
                (model.x0[*node], [u[2 * node], u[2 * node + 1]], s)
            }
        };
        v.extend([xx[0] + uu[0], xx[1] + uu[1], uu[0], uu[1]]);
        v.extend(s);
    }
    v
}

/// Writes `probes.csv` row by row (only for a model with probes), every number in full so that
/// a node probe's displacement reads back as the bits of `results.h5`.
pub struct ProbeWriter {
    table: CsvTable,
}

impl ProbeWriter {
    /// `DIR/probes.csv` for the probes of `model`; `None` without probes.
    pub fn create(dir: &Path, model: &Model) -> std::io::Result<Option<Self>> {
        if model.probes.is_empty() {
            return Ok(None);
        }
        Ok(Some(Self { table: CsvTable::create(dir.join("probes.csv"), &probe_columns(model).join(","), probe_integer(model), true)? }))
    }

    /// `DIR/probes.csv` continued after a restart from step `keep_step` (as
    /// [`HistoryWriter::open_append`]); `None` without probes.
    pub fn open_append(dir: &Path, model: &Model, keep_step: usize) -> std::io::Result<Option<Self>> {
        if model.probes.is_empty() {
            return Ok(None);
        }
        Ok(Some(Self { table: CsvTable::open_append(dir.join("probes.csv"), &probe_columns(model).join(","), probe_integer(model), true, keep_step)? }))
    }

    /// The row of the converged step `r` of `sim`.
    pub fn write(&mut self, sim: &Snapshot, r: &StepReport) -> std::io::Result<()> {
        let mut values = vec![r.step as f64, r.time];
        values.extend(probe_values(sim));
        self.table.write(&values)
    }
}

fn probe_integer(model: &Model) -> Vec<bool> {
    (0..2 + PROBE_QUANTITIES.len() * model.probes.len()).map(|i| i == 0).collect()
}

/// The columns of [`history_columns`] that hold counts, by name (positions went stale once
/// when a column was added).
const INTEGER_COLUMNS: [&str; 6] = ["step", "newton_iterations", "volume_updates", "cutbacks", "remeshes", "active_contacts"];

/// Per column of [`history_columns`]: whether it is written as an integer.
fn integer_columns(model: &Model) -> Vec<bool> {
    history_columns(model).iter().map(|c| INTEGER_COLUMNS.contains(&c.as_str())).collect()
}

/// One row of the history, in the order of [`history_columns`] (integers as exact f64).
pub fn history_values(r: &StepReport) -> Vec<f64> {
    let mut v = vec![
        r.step as f64,
        r.time,
        r.dt,
        r.newton_iterations as f64,
        r.volume_updates as f64,
        r.cutbacks as f64,
        r.residual,
        r.volume_error,
        r.volume_error_max_body,
        r.max_element_volume_change,
        r.kinetic_energy,
        r.remeshes as f64,
    ];
    if let Some(c) = &r.compaction {
        v.push(c.solid_ratio);
        v.extend(c.pressure.iter().chain(&c.force));
        v.extend([c.max_penetration, c.active_contacts as f64, c.stabilisation_energy, c.external_work]);
        v.extend(c.shear.iter().chain(&c.travel));
    }
    for x in r.reactions.iter().chain(&r.displacements) {
        v.extend(x);
    }
    v
}

/// The state at the end of a run (the last converged step), for `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct FinalState {
    pub step: usize,
    pub time: f64,
    /// Solid ratio (None without a die of four walls).
    pub solid_ratio: Option<f64>,
    /// Wall pressures and forces (MPa, N/mm) in the order left, right, bottom, top.
    pub pressure: Option<[f64; 4]>,
    pub force: Option<[f64; 4]>,
    /// Tangential wall forces (N/mm, along y on the left and right walls, x on the bottom and
    /// top ones) and the walls' inward travel since t = 0 (mm), in the same order.
    pub shear: Option<[f64; 4]>,
    pub travel: Option<[f64; 4]>,
    /// |A − A₀|/A₀ over all particles at the end, and the largest per-particle value over the
    /// whole run.
    pub volume_error: f64,
    pub max_particle_volume_error: f64,
    /// Work against the stabilisation springs / external work of the walls.
    pub stabilisation_ratio: Option<f64>,
}

impl FinalState {
    pub fn of(r: &StepReport, max_particle_volume_error: f64) -> Self {
        let c = r.compaction.as_ref();
        Self {
            step: r.step,
            time: r.time,
            solid_ratio: c.map(|c| c.solid_ratio).filter(|p| *p > 0.0),
            pressure: c.map(|c| c.pressure),
            force: c.map(|c| c.force),
            shear: c.map(|c| c.shear),
            travel: c.map(|c| c.travel),
            volume_error: r.volume_error,
            max_particle_volume_error,
            stabilisation_ratio: c.filter(|c| c.external_work > 0.0).map(|c| c.stabilisation_energy / c.external_work),
        }
    }
}

/// Wall-clock time per phase of a run (s) and their shares of the total.
#[derive(Clone, Debug, Serialize)]
pub struct Phases {
    pub contact_search: f64,
    pub contact_assembly: f64,
    pub element_assembly: f64,
    pub linear_solve: f64,
    /// New meshes, state transfer and solver rebuilds of the re-meshed particles (their
    /// re-equilibration is in the assembly and solve phases).
    pub remesh: f64,
    /// history.csv and results.h5/xdmf.
    pub output: f64,
    /// Everything else (set-up, predictors, bookkeeping).
    pub other: f64,
    pub total: f64,
    /// Each phase's share of `total` (%), same order as above.
    pub percent: [f64; 7],
}

impl Phases {
    pub fn split(t: &crate::solver::Timing, output: f64, total: f64) -> Self {
        let parts = [t.contact_search, t.contact_assembly, t.element_assembly, t.linear_solve, t.remesh, output];
        let other = (total - parts.iter().sum::<f64>()).max(0.0);
        let share = |v: f64| if total > 0.0 { 100.0 * v / total } else { 0.0 };
        Self {
            contact_search: parts[0],
            contact_assembly: parts[1],
            element_assembly: parts[2],
            linear_solve: parts[3],
            remesh: parts[4],
            output,
            other,
            total,
            percent: [share(parts[0]), share(parts[1]), share(parts[2]), share(parts[3]), share(parts[4]), share(output), share(other)],
        }
    }
}

/// Contents of `summary.json`.
#[derive(Serialize)]
pub struct SummaryFile<'a> {
    pub mpfem_version: &'static str,
    pub title: &'a str,
    /// The case file (path, SHA-256 of its text); None for the built-in default job.
    pub case: Option<serde_json::Value>,
    /// "completed", "failed" or "interrupted" (stopped by a signal after a checkpoint).
    pub status: &'a str,
    /// The checkpoints this run was continued from (`mpfem run --restart`): path, step and
    /// time of each, oldest first; absent for a run that never restarted.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub restarts: Vec<serde_json::Value>,
    pub error: Option<String>,
    pub formulation: String,
    pub n_bodies: usize,
    pub n_nodes: usize,
    pub n_elements: usize,
    pub wall_time_s: f64,
    /// The peak resident memory of each process of the run, rank 0 first (MB: `VmHWM`; absent
    /// where the system does not tell).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub peak_memory_mb: Vec<f64>,
    /// The last converged step (also of a failed run).
    #[serde(rename = "final")]
    pub final_state: Option<FinalState>,
    pub phases: Phases,
    /// Heckel and Kawakita fits of the pressure–density curve (compaction runs).
    pub fits: Option<crate::fits::CompactionFits>,
    pub run: Option<&'a RunSummary>,
    pub last_step: Option<&'a StepReport>,
}

pub fn write_summary(dir: &Path, s: &SummaryFile) -> std::io::Result<PathBuf> {
    let path = dir.join("summary.json");
    let text = serde_json::to_string_pretty(s).map_err(std::io::Error::other)? + "\n";
    // whole or not at all: a temporary file renamed over it; where that cannot be written (a
    // full disk), over the space the run reserved at its start ([`reserve_summary`])
    let tmp = dir.join("summary.json.tmp");
    match std::fs::write(&tmp, &text).and_then(|()| std::fs::rename(&tmp, &path)) {
        Ok(()) => Ok(path),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            let reserved = std::fs::metadata(&path).map_or(0, |m| m.len());
            if (text.len() as u64) > reserved {
                return Err(e);
            }
            let mut f = std::fs::OpenOptions::new().write(true).open(&path)?;
            f.write_all(text.as_bytes())?;
            f.set_len(text.len() as u64)?;
            f.sync_data()?;
            tracing::warn!(%e, "summary.json written over the space reserved at the start (no room for a new file)");
            Ok(path)
        }
    }
}

/// The bytes [`reserve_summary`] holds for `summary.json`.
pub const SUMMARY_RESERVE: usize = 64 * 1024;

/// At the start of a run: `summary.json` saying the run is under way, padded to
/// [`SUMMARY_RESERVE`] bytes, so that the final summary can be written over it when the disk
/// has filled meanwhile ([`write_summary`]).
///
/// # Errors
/// The file cannot be written (the run should not start).
pub fn reserve_summary(dir: &Path, title: &str) -> std::io::Result<()> {
    let head = serde_json::json!({ "mpfem_version": env!("CARGO_PKG_VERSION"), "title": title, "status": "running" }).to_string();
    let mut text = head.into_bytes();
    text.resize(SUMMARY_RESERVE - 1, b' ');
    text.push(b'\n');
    std::fs::write(dir.join("summary.json"), text)
}
