//! Plots of a results folder: wall pressure against solid ratio (PNG and SVG, one or several
//! runs overlaid) from `history.csv`, and snapshots of the deformed particles coloured by von
//! Mises stress (PNG) from `results.h5`.
//!
//! Files written into the output folder:
//! - `pressure.png`, `pressure.svg`: the pressure of each wall that carries a force, against the
//!   solid ratio (one run); `pressure_compare.png`, `pressure_compare.svg` when several runs are
//!   overlaid (one colour per run, one marker shape per wall);
//! - `snapshot_step_N.png`: the deformed mesh at output step `N` (the step number of
//!   `history.csv`), each element filled with the colour of its von Mises stress on a scale
//!   shared by the snapshot, with a colour bar in MPa and the walls as black lines.
//!
//! Text is drawn with a TrueType font read at run time: `MPFEM_FONT` (a `.ttf` file) when it is
//! set, otherwise DejaVu Sans (Debian's `fonts-dejavu-core`) or another common sans-serif font
//! from the usual system folders. Both PNG and SVG need it (SVG to lay out the text).
//!
//! The module never prints; it logs with `tracing` and returns [`PlotError`]s that name the
//! file and what was wrong.

use plotters::coord::Shift;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::OnceLock;
use thiserror::Error;

/// Walls in the order of the `history.csv` columns and of `wall_id` in `results.h5`.
pub const WALLS: [&str; 4] = ["left", "right", "bottom", "top"];

/// Series colours: one per wall for a single run, one per run for an overlay (cycled).
pub const SERIES_COLOURS: [(u8, u8, u8); 8] = [
    (31, 119, 180),
    (214, 39, 40),
    (44, 160, 44),
    (255, 127, 14),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (23, 190, 207),
];

/// Size of the pressure plot and of a snapshot, pixels.
pub const PRESSURE_SIZE: (u32, u32) = (900, 650);
pub const SNAPSHOT_SIZE: (u32, u32) = (1000, 820);

/// Width of the colour bar panel on the right of a snapshot, pixels.
const COLOUR_BAR_PANEL: u32 = 150;

/// A failure while reading the results or drawing the plots.
#[derive(Debug, Error)]
pub enum PlotError {
    /// Missing or malformed input (a folder, `history.csv`, `results.h5`, a step).
    #[error("{path}: {msg}")]
    Input { path: PathBuf, msg: String },
    #[error("{path}: {source}")]
    Hdf5 {
        path: PathBuf,
        #[source]
        source: hdf5::Error,
    },
    #[error("{path}: cannot draw the plot: {msg}")]
    Draw { path: PathBuf, msg: String },
    #[error("no font for the plot text (tried {tried}): install the fonts-dejavu-core package or set MPFEM_FONT to a .ttf file")]
    Font { tried: String },
}

impl PlotError {
    /// Whether the error is bad input (a missing folder or file, a malformed file, an unknown
    /// step) rather than a failure to draw.
    pub fn is_input(&self) -> bool {
        matches!(self, PlotError::Input { .. } | PlotError::Hdf5 { .. })
    }
}

fn input(path: &Path, msg: impl Into<String>) -> PlotError {
    PlotError::Input {
        path: path.to_path_buf(),
        msg: msg.into(),
    }
}

// ---------------------------------------------------------------------------------------------
// Fonts

static FONT: OnceLock<Result<PathBuf, String>> = OnceLock::new();

/// Font files tried in this order after `MPFEM_FONT`.
const FONT_CANDIDATES: [&str; 8] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// Register a sans-serif font for the plot text (once per process); returns the font file.
pub fn ensure_font() -> Result<PathBuf, PlotError> {
    let r = FONT.get_or_init(|| {
        let mut tried = Vec::new();
        let env = std::env::var_os("MPFEM_FONT").map(PathBuf::from);
        for p in env
            .into_iter()
            .chain(FONT_CANDIDATES.iter().map(PathBuf::from))
        {
            tried.push(p.display().to_string());
            let Ok(bytes) = std::fs::read(&p) else {
                continue;
            };
            // plotters keeps registered fonts for the life of the process: leaked once
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                tracing::debug!(font = %p.display(), "plot: font registered");
                return Ok(p);
            }
            tracing::warn!(font = %p.display(), "plot: not a usable TrueType font");
        }
        Err(tried.join(", "))
    });
    r.clone().map_err(|tried| PlotError::Font { tried })
}

// ---------------------------------------------------------------------------------------------
// history.csv

/// The columns of `history.csv` that the plots use.
#[derive(Clone, Debug)]
pub struct History {
    pub path: PathBuf,
    pub step: Vec<usize>,
    pub time: Vec<f64>,
    /// Present when the run wrote the compaction columns.
    pub compaction: Option<Compaction>,
}

/// Solid ratio and wall pressures and forces per row (walls in the order of [`WALLS`]).
#[derive(Clone, Debug)]
pub struct Compaction {
    pub solid_ratio: Vec<f64>,
    pub pressure: [Vec<f64>; 4],
    pub force: [Vec<f64>; 4],
}

impl Compaction {
    /// The walls (indices into [`WALLS`]) with a non-zero force in some row.
    pub fn loaded_walls(&self) -> Vec<usize> {
        (0..4)
            .filter(|&w| self.force[w].iter().any(|f| *f != 0.0))
            .collect()
    }
}

impl History {
    /// The solid ratio at a step, when the run has compaction columns and wrote that step.
    pub fn solid_ratio_at(&self, step: usize) -> Option<f64> {
        let c = self.compaction.as_ref()?;
        let i = self.step.iter().position(|s| *s == step)?;
        c.solid_ratio.get(i).copied()
    }
}

/// Read `history.csv`. A last row that is cut short or unparsable (a run killed while writing)
/// is skipped with a warning; any other bad row is an error naming the line.
pub fn read_history(path: &Path) -> Result<History, PlotError> {
    let text =
        std::fs::read_to_string(path).map_err(|e| input(path, format!("cannot read: {e}")))?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .peekable();
    let Some((_, header)) = lines.next() else {
        return Err(input(
            path,
            "empty file: expected a header line with the columns step,time,...",
        ));
    };
    let header: Vec<&str> = header.split(',').map(str::trim).collect();
    let col = |name: &str| header.iter().position(|c| *c == name);
    let (Some(i_step), Some(i_time)) = (col("step"), col("time")) else {
        return Err(input(
            path,
            "no `step` and `time` columns: not an mpfem history.csv",
        ));
    };
    let comp_cols: Option<(usize, [usize; 4], [usize; 4])> = (|| {
        let sr = col("solid_ratio")?;
        let mut p = [0; 4];
        let mut f = [0; 4];
        for (w, name) in WALLS.iter().enumerate() {
            p[w] = col(&format!("p_{name}"))?;
            f[w] = col(&format!("f_{name}"))?;
        }
        Some((sr, p, f))
    })();
    let mut h = History {
        path: path.to_path_buf(),
        step: Vec::new(),
        time: Vec::new(),
        compaction: comp_cols.map(|_| Compaction {
            solid_ratio: Vec::new(),
            pressure: Default::default(),
            force: Default::default(),
        }),
    };
    while let Some((n, line)) = lines.next() {
        let is_last = lines.peek().is_none();
        let v: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed = (v.len() == header.len())
            .then(|| {
                let num = |i: usize| v[i].parse::<f64>().ok().filter(|x| x.is_finite());
                let step = v[i_step].parse::<usize>().ok()?;
                let time = num(i_time)?;
                let comp = match comp_cols {
                    Some((sr, p, f)) => {
                        let mut pp = [0.0; 4];
                        let mut ff = [0.0; 4];
                        for w in 0..4 {
                            pp[w] = num(p[w])?;
                            ff[w] = num(f[w])?;
                        }
                        Some((num(sr)?, pp, ff))
                    }
                    None => None,
                };
                Some((step, time, comp))
            })
            .flatten();
        match parsed {
            Some((step, time, comp)) => {
                h.step.push(step);
                h.time.push(time);
                if let (Some(c), Some((sr, p, f))) = (h.compaction.as_mut(), comp) {
                    c.solid_ratio.push(sr);
                    for w in 0..4 {
                        c.pressure[w].push(p[w]);
                        c.force[w].push(f[w]);
                    }
                }
            }
            None if is_last => {
                tracing::warn!(file = %path.display(), line = n + 1, "plot: last row of history.csv is incomplete; skipped");
            }
            None => {
                return Err(input(
                    path,
                    format!(
                        "line {}: expected {} comma-separated numbers, found `{line}`",
                        n + 1,
                        header.len()
                    ),
                ))
            }
        }
    }
    Ok(h)
}

// ---------------------------------------------------------------------------------------------
// results.h5

/// One output step of `results.h5`: what a snapshot draws.
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub step: usize,
    pub time: f64,
    /// Current node positions (mm).
    pub coordinates: Vec<[f64; 2]>,
    /// Quadrilaterals, 0-based node numbers.
    pub cells: Vec<[usize; 4]>,
    /// Per cell (MPa).
    pub von_mises: Vec<f64>,
    /// Each wall as a segment (mm), with its `wall_id` (0 left, 1 right, 2 bottom, 3 top).
    pub walls: Vec<(i32, [[f64; 2]; 2])>,
}

/// The output steps in `results.h5`, ascending.
pub fn output_steps(h5: &Path) -> Result<Vec<usize>, PlotError> {
    let hdf = |source| PlotError::Hdf5 {
        path: h5.to_path_buf(),
        source,
    };
    let file = crate::h5::open(h5).map_err(hdf)?;
    let g = file
        .group("steps")
        .map_err(|_| input(h5, "no group /steps: not an mpfem results.h5"))?;
    let mut steps = Vec::new();
    for name in g.member_names().map_err(hdf)? {
        match name.parse::<usize>() {
            Ok(s) => steps.push(s),
            Err(_) => {
                tracing::warn!(file = %h5.display(), group = %name, "plot: group in /steps is not a step number; ignored")
            }
        }
    }
    steps.sort_unstable();
    Ok(steps)
}

/// Read output step `step` of `results.h5`.
pub fn read_snapshot(h5: &Path, step: usize) -> Result<Snapshot, PlotError> {
    let hdf = |source| PlotError::Hdf5 {
        path: h5.to_path_buf(),
        source,
    };
    let file = crate::h5::open(h5).map_err(hdf)?;
    let name = format!("steps/{step:06}");
    let g = file.group(&name).map_err(|_| {
        input(
            h5,
            format!("no group /{name}: step {step} is not an output step"),
        )
    })?;
    let time: f64 = g.attr("time").and_then(|a| a.read_scalar()).map_err(hdf)?;
    let read_f64 = |d: &str| -> Result<Vec<f64>, PlotError> {
        g.dataset(d)
            .and_then(|ds| ds.read_raw::<f64>())
            .map_err(|e| input(h5, format!("/{name}/{d}: {e}")))
    };
    let xy = read_f64("coordinates")?;
    if xy.len() % 2 != 0 {
        return Err(input(
            h5,
            format!(
                "/{name}/coordinates: {} values, expected n_nodes × 2",
                xy.len()
            ),
        ));
    }
    let coordinates: Vec<[f64; 2]> = xy.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
    let raw_cells: Vec<i64> = g
        .dataset("cells")
        .and_then(|ds| ds.read_raw::<i64>())
        .map_err(|e| input(h5, format!("/{name}/cells: {e}")))?;
    if raw_cells.len() % 4 != 0 {
        return Err(input(
            h5,
            format!(
                "/{name}/cells: {} values, expected n_cells × 4",
                raw_cells.len()
            ),
        ));
    }
    let n_nodes = coordinates.len();
    let mut cells = Vec::with_capacity(raw_cells.len() / 4);
    for c in raw_cells.chunks_exact(4) {
        let mut q = [0usize; 4];
        for (k, &n) in c.iter().enumerate() {
            q[k] = usize::try_from(n)
                .ok()
                .filter(|&n| n < n_nodes)
                .ok_or_else(|| {
                    input(
                        h5,
                        format!("/{name}/cells: node {n} out of range 0..{n_nodes}"),
                    )
                })?;
        }
        cells.push(q);
    }
    let von_mises = read_f64("von_mises")?;
    if von_mises.len() != cells.len() {
        return Err(input(
            h5,
            format!(
                "/{name}/von_mises: {} values for {} cells",
                von_mises.len(),
                cells.len()
            ),
        ));
    }
    let mut walls = Vec::new();
    if g.link_exists("wall_points") {
        let wp = read_f64("wall_points")?;
        let ids: Vec<i32> = g
            .dataset("wall_id")
            .and_then(|ds| ds.read_raw::<i32>())
            .map_err(|e| input(h5, format!("/{name}/wall_id: {e}")))?;
        if wp.len() != 4 * ids.len() {
            return Err(input(
                h5,
                format!(
                    "/{name}/wall_points: {} values for {} walls",
                    wp.len(),
                    ids.len()
                ),
            ));
        }
        for (id, p) in ids.iter().zip(wp.chunks_exact(4)) {
            walls.push((*id, [[p[0], p[1]], [p[2], p[3]]]));
        }
    }
    Ok(Snapshot {
        step,
        time,
        coordinates,
        cells,
        von_mises,
        walls,
    })
}

/// Which output steps to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepSpec {
    First,
    Last,
    Step(usize),
}

impl FromStr for StepSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "first" => Ok(StepSpec::First),
            "last" => Ok(StepSpec::Last),
            t => t.parse().map(StepSpec::Step).map_err(|_| {
                format!("`{t}` is not a step: expected a step number, `first` or `last`")
            }),
        }
    }
}

/// About `n` steps spread evenly over `available` (ascending), always with the first and last.
pub fn default_steps(available: &[usize], n: usize) -> Vec<usize> {
    let m = available.len();
    if m == 0 || n == 0 {
        return Vec::new();
    }
    if n == 1 {
        return vec![available[m - 1]];
    }
    let mut out: Vec<usize> = (0..n)
        .map(|i| available[((i * (m - 1)) as f64 / (n - 1) as f64).round() as usize])
        .collect();
    out.dedup();
    out
}

/// Resolve explicit step choices against the output steps of `h5`.
pub fn resolve_steps(
    h5: &Path,
    available: &[usize],
    specs: &[StepSpec],
) -> Result<Vec<usize>, PlotError> {
    let list = || {
        if available.len() <= 12 {
            available
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        } else {
            let a: Vec<String> = available[..5].iter().map(|s| s.to_string()).collect();
            format!(
                "{}, ..., {} ({} steps)",
                a.join(", "),
                available[available.len() - 1],
                available.len()
            )
        }
    };
    let mut out = Vec::new();
    for s in specs {
        let step = match s {
            StepSpec::First => available.first().copied(),
            StepSpec::Last => available.last().copied(),
            StepSpec::Step(n) => available.binary_search(n).ok().map(|_| *n),
        };
        match step {
            Some(st) if !out.contains(&st) => out.push(st),
            Some(_) => {}
            None if available.is_empty() => return Err(input(h5, "no output steps")),
            None => {
                let n = match s {
                    StepSpec::Step(n) => n.to_string(),
                    _ => "?".into(),
                };
                return Err(input(
                    h5,
                    format!(
                        "step {n} is not an output step; expected one of: {}, first, last",
                        list()
                    ),
                ));
            }
        }
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Colour map

/// Control points of the colour map (perceptually ordered, dark blue → green → yellow, in the
/// manner of viridis), evenly spaced on [0, 1].
const MAP: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];

/// The colour of `t` in [0, 1] (clamped; NaN maps to 0).
pub fn colour_map(t: f64) -> (u8, u8, u8) {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let s = t * (MAP.len() - 1) as f64;
    let i = (s.floor() as usize).min(MAP.len() - 2);
    let f = s - i as f64;
    let lerp = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (MAP[i], MAP[i + 1]);
    (lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

// ---------------------------------------------------------------------------------------------
// Pressure plot

/// One run of a pressure plot.
pub struct PressureRun<'a> {
    pub label: &'a str,
    pub history: &'a History,
    /// A line of text under the curves (the compaction-law fits), if any.
    pub note: Option<String>,
}

fn draw_err<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> PlotError + '_ {
    move |e| PlotError::Draw {
        path: path.to_path_buf(),
        msg: e.to_string(),
    }
}

/// Draw wall pressure against solid ratio for `runs` into `png` and `svg`. Runs without
/// compaction columns and walls without force are left out; returns the number of series
/// drawn (0: nothing to plot, no file written).
pub fn pressure_plot(runs: &[PressureRun], png: &Path, svg: &Path) -> Result<usize, PlotError> {
    let series = pressure_series(runs);
    if series.is_empty() {
        return Ok(0);
    }
    let overlay = runs.len() > 1;
    let notes: Vec<String> = runs
        .iter()
        .filter_map(|r| r.note.as_ref().map(|n| if overlay { format!("{}: {n}", r.label) } else { n.clone() }))
        .collect();
    ensure_font()?;
    {
        let root = BitMapBackend::new(png, PRESSURE_SIZE).into_drawing_area();
        draw_pressure(&root, &series, &notes).map_err(draw_err(png))?;
        root.present().map_err(draw_err(png))?;
    }
    {
        let root = SVGBackend::new(svg, PRESSURE_SIZE).into_drawing_area();
        draw_pressure(&root, &series, &notes).map_err(draw_err(svg))?;
        root.present().map_err(draw_err(svg))?;
    }
    tracing::info!(png = %png.display(), svg = %svg.display(), series = series.len(), "plot: pressure");
    Ok(series.len())
}

/// A line of the pressure plot.
struct Series {
    label: String,
    colour: RGBColor,
    /// Index into [`WALLS`]: selects the marker.
    wall: usize,
    points: Vec<(f64, f64)>,
}

fn pressure_series(runs: &[PressureRun]) -> Vec<Series> {
    let overlay = runs.len() > 1;
    let mut out = Vec::new();
    for (r, run) in runs.iter().enumerate() {
        let Some(c) = &run.history.compaction else {
            tracing::info!(file = %run.history.path.display(), "plot: no compaction columns (no walls, one body): no pressure plot for this run");
            continue;
        };
        let walls = c.loaded_walls();
        if walls.is_empty() {
            tracing::info!(file = %run.history.path.display(), "plot: no wall carries a force: no pressure plot for this run");
        }
        for w in walls {
            let (cr, cg, cb) = SERIES_COLOURS[if overlay { r } else { w } % SERIES_COLOURS.len()];
            let points: Vec<(f64, f64)> = c
                .solid_ratio
                .iter()
                .zip(&c.pressure[w])
                .map(|(&s, &p)| (s, p))
                .collect();
            let label = if overlay {
                format!("{}: {} wall", run.label, WALLS[w])
            } else {
                format!("{} wall", WALLS[w])
            };
            out.push(Series {
                label,
                colour: RGBColor(cr, cg, cb),
                wall: w,
                points,
            });
        }
    }
    out
}

/// A range around `lo..hi` with a margin, never empty.
fn padded(lo: f64, hi: f64, frac: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    if span <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
        let d = if lo == 0.0 { 1.0 } else { 0.05 * lo.abs() };
        return (lo - d, hi + d);
    }
    (lo - frac * span, hi + frac * span)
}

fn draw_pressure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    series: &[Series],
    notes: &[String],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let all = series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, f64::NEG_INFINITY);
    for &(x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let (x0, x1) = padded(x0, x1, 0.03);
    let (y0, y1) = padded(y0, y1, 0.05);
    let mut chart = ChartBuilder::on(root)
        .caption("Wall pressure against solid ratio", ("sans-serif", 24))
        .margin(20)
        .margin_bottom(20 + 20 * notes.len() as u32)
        .x_label_area_size(55)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc("solid ratio [-]")
        .y_desc("wall pressure [MPa]")
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    for s in series {
        // left and bottom are drawn wider under right and top, so that opposite walls with the
        // same pressure (a symmetric job) both stay visible
        let wide = s.wall % 2 == 0;
        let line = s.colour.stroke_width(if wide { 5 } else { 2 });
        let fill = s.colour.filled();
        let wall = s.wall;
        let size = if wide { 6 } else { 4 };
        chart
            .draw_series(LineSeries::new(s.points.iter().copied(), line))?
            .label(s.label.clone())
            .legend(move |(x, y)| {
                EmptyElement::at((x + 12, y))
                    + PathElement::new(vec![(-12, 0), (12, 0)], line)
                    + marker((0, 0), wall, size, fill)
            });
        // markers at about 12 points of each line tell the walls apart
        let k = s.points.len().div_ceil(12).max(1);
        let idx = (0..s.points.len())
            .step_by(k)
            .chain(s.points.len().checked_sub(1));
        chart.draw_series(idx.map(|i| {
            let p = s.points[i];
            EmptyElement::at(p) + marker((0, 0), wall, size, fill)
        }))?;
    }
    // the fits, one line per run, under the x axis label
    let (xs, _) = chart.plotting_area().get_pixel_range();
    let bottom = root.dim_in_pixel().1 as i32;
    let style = ("sans-serif", 14)
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Right, VPos::Bottom));
    for (i, n) in notes.iter().rev().enumerate() {
        root.draw(&Text::new(n.clone(), (xs.end, bottom - 12 - 20 * i as i32), style.clone()))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font(("sans-serif", 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Margin, x-label and y-label areas of the equal-aspect charts (pixels).
const MARGIN: u32 = 15;
const XL: u32 = 45;
const YL: u32 = 60;

/// A chart on `area` over the bounding box `bb` = [x_min, x_max, y_min, y_max] (mm, padded by
/// 3 %) with equal scales on both axes: the plot area is the panel less the margins and label
/// areas (exact pixel sizes), and the ranges are widened to its shape; axes in mm, no grid.
#[allow(clippy::type_complexity)]
fn equal_aspect_chart<'a, DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    bb: [f64; 4],
) -> Result<ChartContext<'a, DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>>, DrawingAreaErrorKind<DB::ErrorType>> {
    let (x0, x1) = padded(bb[0], bb[1], 0.03);
    let (y0, y1) = padded(bb[2], bb[3], 0.03);
    let (pw, ph) = area.dim_in_pixel();
    let pw = pw.saturating_sub(2 * MARGIN + YL).max(1) as f64;
    let ph = ph.saturating_sub(2 * MARGIN + XL).max(1) as f64;
    let scale = ((x1 - x0) / pw).max((y1 - y0) / ph);
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let (hx, hy) = (0.5 * pw * scale, 0.5 * ph * scale);
    let mut chart = ChartBuilder::on(area)
        .margin(MARGIN)
        .x_label_area_size(XL)
        .y_label_area_size(YL)
        .build_cartesian_2d(cx - hx..cx + hx, cy - hy..cy + hy)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x [mm]")
        .y_desc("y [mm]")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()?;
    Ok(chart)
}

/// A filled marker of half-size `r` centred at `c` (pixels): circle (left), triangle (right),
/// square (bottom), diamond (top).
fn marker<DB: DrawingBackend>(
    c: (i32, i32),
    wall: usize,
    r: i32,
    style: ShapeStyle,
) -> DynElement<'static, DB, (i32, i32)> {
    let (x, y) = c;
    let t = r + 1;
    match wall {
        0 => Circle::new(c, r, style).into_dyn(),
        1 => Polygon::new(vec![(x, y - t), (x + t, y + r), (x - t, y + r)], style).into_dyn(),
        2 => Rectangle::new([(x - r, y - r), (x + r, y + r)], style).into_dyn(),
        _ => Polygon::new(vec![(x, y - t), (x + t, y), (x, y + t), (x - t, y)], style).into_dyn(),
    }
}

// ---------------------------------------------------------------------------------------------
// Snapshots

/// Draw a snapshot into `png`: the deformed mesh filled by von Mises stress, the walls, a
/// colour bar with the range in MPa. The lines of `title` head the picture.
pub fn snapshot_png(snap: &Snapshot, title: &[String], png: &Path) -> Result<(), PlotError> {
    if snap.cells.is_empty() {
        return Err(input(png, format!("step {}: no cells to draw", snap.step)));
    }
    ensure_font()?;
    let root = BitMapBackend::new(png, SNAPSHOT_SIZE).into_drawing_area();
    draw_snapshot(&root, snap, title).map_err(draw_err(png))?;
    root.present().map_err(draw_err(png))?;
    tracing::info!(png = %png.display(), step = snap.step, "plot: snapshot");
    Ok(())
}

/// The shared stress scale of a snapshot (MPa), never empty.
pub fn stress_range(snap: &Snapshot) -> (f64, f64) {
    let (lo, hi) = snap
        .von_mises
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    // a field that is uniform to plotting accuracy sits in the middle of a narrow scale
    if hi - lo <= 1e-6 * hi.abs().max(lo.abs()).max(1.0) {
        let mid = 0.5 * (lo + hi);
        let d = (0.01 * mid.abs()).max(1e-3);
        return (mid - d, mid + d);
    }
    (lo, hi)
}

/// `root` cleared to white with the lines of `title` stacked on top; the area below them.
fn titled_area<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, title: &[String]) -> Result<DrawingArea<DB, Shift>, DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let mut body = root.clone();
    for line in title {
        body = body.titled(line, ("sans-serif", 20))?;
    }
    Ok(body)
}

fn draw_snapshot<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    snap: &Snapshot,
    title: &[String],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let body = titled_area(root, title)?;
    let (w, _) = body.dim_in_pixel();
    let (left, right) = body.split_horizontally(w.saturating_sub(COLOUR_BAR_PANEL));

    // data extent: nodes and walls
    let mut bb = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let pts = snap
        .coordinates
        .iter()
        .copied()
        .chain(snap.walls.iter().flat_map(|(_, s)| s.iter().copied()));
    for [x, y] in pts {
        if x.is_finite() && y.is_finite() {
            bb = [bb[0].min(x), bb[1].max(x), bb[2].min(y), bb[3].max(y)];
        }
    }
    let mut chart = equal_aspect_chart(&left, bb)?;
    let (pw, ph) = {
        let (w, h) = chart.plotting_area().dim_in_pixel();
        (w as f64, h as f64)
    };

    let (lo, hi) = stress_range(snap);
    let colour = |v: f64| {
        let (r, g, b) = colour_map((v - lo) / (hi - lo));
        RGBColor(r, g, b)
    };
    let quad = |c: &[usize; 4]| c.map(|n| (snap.coordinates[n][0], snap.coordinates[n][1]));
    chart.draw_series(
        snap.cells
            .iter()
            .zip(&snap.von_mises)
            .map(|(c, &v)| Polygon::new(quad(c).to_vec(), colour(v).filled())),
    )?;
    // element edges while they stay apart on the picture
    let px_per_elem = (pw * ph / snap.cells.len() as f64).sqrt();
    if px_per_elem >= 8.0 {
        let edge = RGBColor(40, 40, 40).mix(0.35).stroke_width(1);
        chart.draw_series(snap.cells.iter().map(|c| {
            let q = quad(c);
            PathElement::new(vec![q[0], q[1], q[2], q[3], q[0]], edge)
        }))?;
    }
    for (_, [a, b]) in &snap.walls {
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(a[0], a[1]), (b[0], b[1])],
            BLACK.stroke_width(3),
        )))?;
    }

    // colour bar
    let mut bar = ChartBuilder::on(&right)
        .margin_top(MARGIN)
        .margin_bottom(MARGIN + XL)
        .margin_left(10)
        .margin_right(5)
        .right_y_label_area_size(95)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    // tick labels with the digits the range needs, set off from the tick marks
    let decimals = (-(((hi - lo) / 8.0).log10().floor() as i32)).clamp(0, 8) as usize;
    let tick = move |v: &f64| format!(" {v:.decimals$}");
    bar.configure_mesh()
        .disable_mesh()
        .y_label_formatter(&tick)
        .disable_x_axis()
        .y_desc("von Mises [MPa]")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .y_labels(8)
        .draw()?;
    const BANDS: usize = 128;
    let dv = (hi - lo) / BANDS as f64;
    bar.draw_series((0..BANDS).map(|i| {
        let v0 = lo + i as f64 * dv;
        // the end bands carry the end colours of the map
        let t = i as f64 / (BANDS - 1) as f64;
        Rectangle::new(
            [(0.0, v0), (1.0, v0 + dv)],
            colour(lo + t * (hi - lo)).filled(),
        )
    }))?;
    bar.draw_series(std::iter::once(Rectangle::new(
        [(0.0, lo), (1.0, hi)],
        BLACK.stroke_width(1),
    )))?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Packing preview

/// Size of the packing preview, pixels.
pub const PACKING_SIZE: (u32, u32) = (1000, 860);

/// One particle of a packing preview: its outline (mm) and its material (an index into the
/// material names, which also picks the colour from [`SERIES_COLOURS`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PreviewParticle {
    pub outline: Vec<[f64; 2]>,
    pub material: usize,
}

/// Draw a packing into `png`: the particles filled with the colour of their material and
/// outlined, the die `[x0, x1, y0, y1]` (when there is one) as a black rectangle, a legend of
/// the materials with their particle counts on the right; the lines of `title` head the
/// picture.
pub fn packing_png(particles: &[PreviewParticle], materials: &[String], die: Option<[f64; 4]>, title: &[String], png: &Path) -> Result<(), PlotError> {
    if particles.is_empty() {
        return Err(input(png, "no particles to draw"));
    }
    ensure_font()?;
    let root = BitMapBackend::new(png, PACKING_SIZE).into_drawing_area();
    draw_packing(&root, particles, materials, die, title).map_err(draw_err(png))?;
    root.present().map_err(draw_err(png))?;
    tracing::info!(png = %png.display(), n = particles.len(), "plot: packing preview");
    Ok(())
}

fn draw_packing<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    particles: &[PreviewParticle],
    materials: &[String],
    die: Option<[f64; 4]>,
    title: &[String],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let body = titled_area(root, title)?;
    let mut bb = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
    let die_pts = die.map(|d| vec![[d[0], d[2]], [d[1], d[3]]]).unwrap_or_default();
    for [x, y] in particles.iter().flat_map(|p| p.outline.iter().copied()).chain(die_pts) {
        if x.is_finite() && y.is_finite() {
            bb = [bb[0].min(x), bb[1].max(x), bb[2].min(y), bb[3].max(y)];
        }
    }
    let (w, _) = body.dim_in_pixel();
    let (body, legend) = body.split_horizontally(w.saturating_sub(COLOUR_BAR_PANEL + 40));
    let mut chart = equal_aspect_chart(&body, bb)?;
    let colour = |m: usize| {
        let (r, g, b) = SERIES_COLOURS[m % SERIES_COLOURS.len()];
        RGBColor(r, g, b)
    };
    let pts = |p: &PreviewParticle| p.outline.iter().map(|v| (v[0], v[1])).collect::<Vec<_>>();
    chart.draw_series(particles.iter().map(|p| Polygon::new(pts(p), colour(p.material).mix(0.55).filled())))?;
    chart.draw_series(particles.iter().map(|p| {
        let mut v = pts(p);
        if let Some(&first) = v.first() {
            v.push(first);
        }
        PathElement::new(v, colour(p.material).stroke_width(2))
    }))?;
    if let Some([a, b, c, d]) = die {
        chart.draw_series(std::iter::once(PathElement::new(vec![(a, c), (b, c), (b, d), (a, d), (a, c)], BLACK.stroke_width(3))))?;
    }
    // legend in the right-hand panel: the materials that occur, with their particle counts
    let mut y = 2 * MARGIN as i32;
    for (m, name) in materials.iter().enumerate() {
        let n = particles.iter().filter(|p| p.material == m).count();
        if n == 0 {
            continue;
        }
        legend.draw(&Rectangle::new([(10, y), (34, y + 16)], colour(m).mix(0.55).filled()))?;
        legend.draw(&Rectangle::new([(10, y), (34, y + 16)], colour(m).stroke_width(2)))?;
        legend.draw(&Text::new(format!("{name} ({n})"), (42, y), ("sans-serif", 15)))?;
        y += 26;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// A results folder

/// A run to plot: its results folder and its label in the legends and titles.
#[derive(Clone, Debug)]
pub struct RunDir {
    pub dir: PathBuf,
    pub label: String,
}

/// Which snapshots to draw.
#[derive(Clone, Debug)]
pub enum StepChoice {
    /// About this many steps spread over the output steps, the first and the last included.
    Spread(usize),
    Explicit(Vec<StepSpec>),
}

/// Default number of snapshots.
pub const DEFAULT_SNAPSHOTS: usize = 4;

/// What [`plot_results`] draws.
#[derive(Clone, Debug)]
pub struct PlotRequest {
    /// The first run gives the snapshots; every run goes into the pressure plot.
    pub runs: Vec<RunDir>,
    /// Where the pictures go.
    pub out: PathBuf,
    pub steps: StepChoice,
}

impl PlotRequest {
    /// The results folders `dirs`, labelled by `labels` in their order (a folder without one:
    /// its name, [`default_label`]); the pictures go to `out` (default: the first folder);
    /// the snapshots are `steps` (default: [`DEFAULT_SNAPSHOTS`] spread over the output steps).
    pub fn of_folders(dirs: &[PathBuf], labels: &[String], steps: Option<Vec<StepSpec>>, out: Option<PathBuf>) -> Self {
        let runs = dirs.iter().enumerate().map(|(i, d)| RunDir { dir: d.clone(), label: labels.get(i).cloned().unwrap_or_else(|| default_label(d)) }).collect();
        let steps = steps.map_or(StepChoice::Spread(DEFAULT_SNAPSHOTS), StepChoice::Explicit);
        Self { out: out.unwrap_or_else(|| dirs.first().cloned().unwrap_or_default()), runs, steps }
    }
}

/// What [`plot_results`] did.
#[derive(Clone, Debug, Default)]
pub struct PlotReport {
    pub written: Vec<PathBuf>,
    /// Plots left out and why (also logged).
    pub skipped: Vec<String>,
}

/// Remove the pictures a previous run left in `dir` (`pressure.png`, `pressure.svg`,
/// `snapshot_step_N.png`), so that a new run's folder shows only its own steps. Returns how
/// many files were removed; files that cannot be removed are logged and left.
pub fn remove_old_plots(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut n = 0;
    for e in entries.flatten() {
        let name = e.file_name();
        let name = name.to_string_lossy();
        let ours = name == "pressure.png"
            || name == "pressure.svg"
            || name
                .strip_prefix("snapshot_step_")
                .and_then(|r| r.strip_suffix(".png"))
                .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()));
        if ours {
            match std::fs::remove_file(e.path()) {
                Ok(()) => n += 1,
                Err(err) => {
                    tracing::warn!(file = %e.path().display(), %err, "plot: cannot remove an old picture")
                }
            }
        }
    }
    n
}

/// The case title recorded in `DIR/summary.json`, if any.
/// The compaction-law fits of a run as one line of text, from its `summary.json`.
fn fits_note(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    let f = v.get("fits")?;
    let num = |x: &serde_json::Value, k: &str| x.get(k).and_then(|v| v.as_f64());
    let mut parts = Vec::new();
    if let Some(h) = f.get("heckel").filter(|h| !h.is_null()) {
        parts.push(format!("Heckel K = {:.3e} /MPa, A = {:.3}, R² = {:.3}", num(h, "k")?, num(h, "a")?, num(h, "r2")?));
    }
    if let Some(k) = f.get("kawakita").filter(|k| !k.is_null()) {
        parts.push(format!("Kawakita a = {:.3}, b = {:.3e} /MPa, R² = {:.3}", num(k, "a")?, num(k, "b")?, num(k, "r2")?));
    }
    (!parts.is_empty()).then(|| parts.join("; "))
}

fn run_title(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    let t = v.get("title")?.as_str()?.trim();
    (!t.is_empty()).then(|| t.to_string())
}

/// `s` cut to at most `n` characters (with an ellipsis).
fn shorten(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        return s.to_string();
    }
    let mut t: String = s.chars().take(n.saturating_sub(1)).collect();
    t.push('…');
    t
}

/// The label of a results folder: its last path component.
pub fn default_label(dir: &Path) -> String {
    dir.canonicalize()
        .ok()
        .and_then(|p| p.file_name().map(|s| s.to_string_lossy().into_owned()))
        .unwrap_or_else(|| dir.display().to_string())
}

/// Draw the pressure plot of every run and the snapshots of the first run.
pub fn plot_results(req: &PlotRequest) -> Result<PlotReport, PlotError> {
    let mut report = PlotReport::default();
    let Some(first) = req.runs.first() else {
        return Err(input(&req.out, "no results folder to plot"));
    };
    let mut histories = Vec::with_capacity(req.runs.len());
    for r in &req.runs {
        if !r.dir.is_dir() {
            return Err(input(
                &r.dir,
                "not a folder: expected a results folder written by `mpfem run`",
            ));
        }
        let h = r.dir.join("history.csv");
        if !h.is_file() {
            return Err(input(
                &h,
                "missing: expected the history.csv that `mpfem run` writes",
            ));
        }
        histories.push(read_history(&h)?);
    }
    // explicit steps are checked before anything is drawn
    let h5 = first.dir.join("results.h5");
    let steps = match (&req.steps, h5.is_file()) {
        (StepChoice::Explicit(specs), true) => resolve_steps(&h5, &output_steps(&h5)?, specs)?,
        (StepChoice::Explicit(_), false) => return Err(input(
            &h5,
            "missing: snapshots need the results.h5 that `mpfem run` writes ([output] every > 0)",
        )),
        (StepChoice::Spread(n), true) => default_steps(&output_steps(&h5)?, *n),
        (StepChoice::Spread(_), false) => {
            let msg = format!(
                "{}: no results.h5 ([output] every = 0?): no snapshots",
                first.dir.display()
            );
            tracing::info!("plot: {msg}");
            report.skipped.push(msg);
            Vec::new()
        }
    };
    std::fs::create_dir_all(&req.out)
        .map_err(|e| input(&req.out, format!("cannot create the folder: {e}")))?;

    let runs: Vec<PressureRun> = req
        .runs
        .iter()
        .zip(&histories)
        .map(|(r, h)| PressureRun {
            label: &r.label,
            history: h,
            note: fits_note(&r.dir),
        })
        .collect();
    let stem = if runs.len() > 1 {
        "pressure_compare"
    } else {
        "pressure"
    };
    let (png, svg) = (
        req.out.join(format!("{stem}.png")),
        req.out.join(format!("{stem}.svg")),
    );
    for (r, h) in req.runs.iter().zip(&histories) {
        match &h.compaction {
            None => report.skipped.push(format!(
                "{}: no compaction columns in history.csv (no walls, one body): no pressure plot",
                r.dir.display()
            )),
            Some(c) if c.loaded_walls().is_empty() => report.skipped.push(format!(
                "{}: no wall carries a force: no pressure plot",
                r.dir.display()
            )),
            Some(_) => {}
        }
    }
    if pressure_plot(&runs, &png, &svg)? > 0 {
        report.written.push(png);
        report.written.push(svg);
    }

    let heading = match run_title(&first.dir) {
        Some(t) if t != first.label => format!("{t} ({})", first.label),
        _ => first.label.clone(),
    };
    for step in steps {
        let snap = read_snapshot(&h5, step)?;
        let mut line = format!("step {}, t = {:.4} s", snap.step, snap.time);
        if let Some(sr) = histories[0].solid_ratio_at(step) {
            line.push_str(&format!(", solid ratio {sr:.3}"));
        }
        let title = [shorten(&heading, 90), line];
        let png = req.out.join(format!("snapshot_step_{step}.png"));
        snapshot_png(&snap, &title, &png)?;
        report.written.push(png);
    }
    Ok(report)
}
