//! Plots: `mpfem run` draws the wall pressure against solid ratio (PNG and SVG) and snapshots
//! coloured by von Mises stress by default; `mpfem plot DIR` redraws them, overlays several
//! runs, draws chosen steps and rejects bad input with exit code 2.
//!
//! The runs are the small 2 × 2 disc job of tests/results_h5.rs (coarse mesh, lateral
//! compaction to solid ratio 0.741, output every 2 steps: well under a second) and the default
//! job (one block, no walls). The pictures are decoded and checked for what they show: the
//! series colours in the plot area, one SVG polyline per wall series that carries a force, the
//! axis labels and legend labels, the colour-map colours of the extreme elements, the colour
//! bar, and the equal aspect ratio of the snapshot.
//!
//! Needs a TrueType font (`fonts-dejavu-core`, installed by scripts/setup.sh).

use mpfem::plot::{colour_map, PRESSURE_SIZE, SERIES_COLOURS, SNAPSHOT_SIZE, WALLS};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::tmpdir;

const CASE: &str = include_str!("data/discs_coarse.toml");

fn mpfem(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mpfem"))
        .args(args)
        .output()
        .unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Run `case_text` into `dir/out` (extra arguments appended); returns the output folder.
fn run_case(dir: &Path, case_text: &str, extra: &[&str]) -> (PathBuf, Output) {
    std::fs::create_dir_all(dir).unwrap();
    let case = dir.join("case.toml");
    std::fs::write(&case, case_text).unwrap();
    let out = dir.join("out");
    let mut args = vec!["run", "--quiet", s(&case), "--out", s(&out)];
    args.extend_from_slice(extra);
    let o = mpfem(&args);
    (out, o)
}

/// The case of tests/results_h5.rs with all four walls moving in (biaxial): reaches solid
/// ratio 0.741 in a few steps, every wall carries a force at the end.
fn biaxial_case() -> String {
    CASE.replace(
        "side = \"bottom\"\nposition = 0.0\n",
        "side = \"bottom\"\nposition = 0.0\nvelocity = 10.0\n",
    )
    .replace(
        "side = \"top\"\nposition = 100.0\n",
        "side = \"top\"\nposition = 100.0\nvelocity = 10.0\n",
    )
}

/// Walls (indices into WALLS) whose force column of history.csv is non-zero in some row.
fn loaded_walls(out: &Path) -> Vec<usize> {
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (0..4)
        .filter(|&w| {
            let c = header
                .iter()
                .position(|h| *h == format!("f_{}", WALLS[w]))
                .unwrap();
            rows.iter().any(|r| r[c] != 0.0)
        })
        .collect()
}

struct Image {
    w: usize,
    h: usize,
    /// RGB per pixel, row major.
    px: Vec<[u8; 3]>,
}

fn read_png(p: &Path) -> Image {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(p).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "{}", p.display());
    let (w, h) = (info.width as usize, info.height as usize);
    let bpp = info.line_size / w;
    assert!(
        bpp == 3 || bpp == 4,
        "RGB or RGBA, got {bpp} bytes per pixel"
    );
    let px = (0..w * h)
        .map(|i| {
            let row = i / w;
            let o = row * info.line_size + (i % w) * bpp;
            [buf[o], buf[o + 1], buf[o + 2]]
        })
        .collect();
    Image { w, h, px }
}

impl Image {
    /// Pixels in columns `x0..x1` within `tol` (per channel) of `c`.
    fn count_near(&self, c: (u8, u8, u8), tol: u8, x0: usize, x1: usize) -> usize {
        let c = [c.0, c.1, c.2];
        (0..self.h)
            .flat_map(|y| (x0..x1.min(self.w)).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let p = self.px[y * self.w + x];
                (0..3).all(|k| p[k].abs_diff(c[k]) <= tol)
            })
            .count()
    }
}

/// The polylines of an SVG as (stroke colour, number of points).
fn svg_polylines(svg: &str) -> Vec<(String, usize)> {
    svg.split("<polyline")
        .skip(1)
        .map(|t| {
            let tag = &t[..t.find('>').unwrap()];
            let attr = |name: &str| {
                let i = tag.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
                tag[i..i + tag[i..].find('"').unwrap()].to_string()
            };
            (
                attr("stroke").to_uppercase(),
                attr("points").split_whitespace().count(),
            )
        })
        .collect()
}

fn hex((r, g, b): (u8, u8, u8)) -> String {
    format!("#{r:02X}{g:02X}{b:02X}")
}

/// The text elements of an SVG.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .map(|t| {
            let body = &t[t.find('>').unwrap() + 1..];
            body[..body.find("</text>").unwrap()].trim().to_string()
        })
        .collect()
}

#[test]
fn run_draws_the_pressure_plot_and_snapshots_by_default() {
    let dir = tmpdir("run");
    let (out, o) = run_case(&dir, CASE, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("wrote plots"), "{err}");
    let walls = loaded_walls(&out);
    assert_eq!(
        walls,
        vec![0, 1],
        "lateral compaction: the moving left and right walls push"
    );

    // PNG: the size asked for; in the plot area (the whole picture but the y-label column),
    // the colour of each loaded wall (single run: colour = wall) and none of the others.
    // Left and right pressures coincide (symmetry), so the left wall shows in its legend entry
    // and its circle markers around the right wall's triangles: a few tens of pixels at least.
    let img = read_png(&out.join("pressure.png"));
    assert_eq!((img.w as u32, img.h as u32), PRESSURE_SIZE);
    for w in 0..4 {
        let n = img.count_near(SERIES_COLOURS[w], 0, 100, img.w);
        if walls.contains(&w) {
            assert!(n >= 20, "{} wall colour: {n} pixels", WALLS[w]);
        } else {
            assert_eq!(n, 0, "{} wall carries no force but is drawn", WALLS[w]);
        }
    }

    // SVG: one polyline with every history row per loaded wall, in the wall's colour (grid
    // lines, axes and legend samples are 2-point polylines), the axis labels with units and the
    // legend labels
    let svg = std::fs::read_to_string(out.join("pressure.svg")).unwrap();
    let rows = std::fs::read_to_string(out.join("history.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    let series: Vec<(String, usize)> = svg_polylines(&svg)
        .into_iter()
        .filter(|(_, n)| *n >= 3)
        .collect();
    assert_eq!(series.len(), walls.len(), "{series:?}");
    for ((colour, n), w) in series.iter().zip(&walls) {
        assert_eq!(colour, &hex(SERIES_COLOURS[*w]));
        assert_eq!(*n, rows, "one point per history row");
    }
    let texts = svg_texts(&svg);
    for t in [
        "solid ratio [-]",
        "wall pressure [MPa]",
        "left wall",
        "right wall",
    ] {
        assert!(texts.iter().any(|x| x == t), "no text `{t}` in {texts:?}");
    }
    // the Heckel fit of summary.json, printed under the plot with its slope
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let k = summary["fits"]["heckel"]["k"].as_f64().expect("a Heckel fit in summary.json");
    let fit_line = texts.iter().find(|x| x.starts_with("Heckel K = ")).unwrap_or_else(|| panic!("no Heckel line in {texts:?}"));
    assert!(fit_line.contains(&format!("{k:.3e}")), "{fit_line} vs K = {k}");

    // snapshots: output steps 2, 4, 6 and the last step (7): all four drawn
    let steps = {
        let f = mpfem::h5::open(&out.join("results.h5")).unwrap();
        let mut v: Vec<usize> = f
            .group("steps")
            .unwrap()
            .member_names()
            .unwrap()
            .iter()
            .map(|n| n.parse().unwrap())
            .collect();
        v.sort();
        v
    };
    assert!(steps.len() <= 4, "{steps:?}");
    for st in &steps {
        assert!(
            out.join(format!("snapshot_step_{st}.png")).is_file(),
            "snapshot of step {st}"
        );
    }
    let last = *steps.last().unwrap();
    let img = read_png(&out.join(format!("snapshot_step_{last}.png")));
    assert_eq!((img.w as u32, img.h as u32), SNAPSHOT_SIZE);
    // the mesh panel is the picture less the 150 px colour bar panel on the right; the element
    // with the lowest and the one with the highest von Mises stress are filled with the ends of
    // the colour map (tolerance 1 for rounding), each over many pixels (elements are ~60 px)
    let panel = img.w - 150;
    for t in [0.0, 1.0] {
        let n = img.count_near(colour_map(t), 1, 0, panel);
        assert!(n > 100, "colour map at {t}: {n} pixels in the mesh panel");
        let n = img.count_near(colour_map(t), 1, panel, img.w);
        assert!(n > 100, "colour map at {t}: {n} pixels in the colour bar");
    }
    // the walls are black lines 3 px wide around ~600 px of die: more than 4 × 500 black pixels
    assert!(img.count_near((0, 0, 0), 0, 0, panel) > 2000);

    // equal aspect ratio: the box of the coloured (saturated) pixels of the mesh panel has the
    // shape of the particles' box at that step, within 3 % (a pixel or two of edge lines)
    let f = mpfem::h5::open(&out.join("results.h5")).unwrap();
    let xy: Vec<f64> = f
        .dataset(&format!("steps/{last:06}/coordinates"))
        .unwrap()
        .read_raw()
        .unwrap();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in xy.chunks(2) {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let (mut px0, mut px1, mut py0, mut py1) = (usize::MAX, 0, usize::MAX, 0);
    for y in 0..img.h {
        for x in 0..panel {
            let p = img.px[y * img.w + x];
            let sat = p.iter().max().unwrap() - p.iter().min().unwrap();
            if sat > 30 {
                (px0, px1, py0, py1) = (px0.min(x), px1.max(x), py0.min(y), py1.max(y));
            }
        }
    }
    let data = (hi[0] - lo[0]) / (hi[1] - lo[1]);
    let pict = (px1 - px0) as f64 / (py1 - py0) as f64;
    assert!(
        (pict / data - 1.0).abs() < 0.03,
        "aspect of the picture {pict} vs the particles {data}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn plot_redraws_chosen_steps_and_rejects_bad_input_with_exit_2() {
    let dir = tmpdir("redraw");
    let (out, o) = run_case(&dir, CASE, &["--no-plots"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pngs = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".png") || n.ends_with(".svg"))
            .collect();
        v.sort();
        v
    };
    assert!(
        pngs(&out).is_empty(),
        "--no-plots draws nothing: {:?}",
        pngs(&out)
    );

    let o = mpfem(&["plot", s(&out), "--steps", "first,last"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // output steps 2, 4, 6, 7 (every 2 and the last)
    assert_eq!(
        pngs(&out),
        [
            "pressure.png",
            "pressure.svg",
            "snapshot_step_2.png",
            "snapshot_step_7.png"
        ]
    );
    let o = mpfem(&["plot", s(&out), "--steps", "4"]);
    assert!(o.status.success());
    assert!(out.join("snapshot_step_4.png").is_file());
    // a new run in the folder removes the old pictures (they would not match its results)
    let (out2, o) = run_case(&dir, CASE, &["--no-plots"]);
    assert!(o.status.success());
    assert_eq!(out2, out);
    assert!(pngs(&out).is_empty(), "{:?}", pngs(&out));
    let o = mpfem(&["plot", s(&out)]);
    assert!(o.status.success());

    // bad input: exit 2, the path or value and what was expected, no panic
    let check = |args: &[&str], needles: &[&str]| {
        let o = mpfem(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: `{n}` not in: {err}");
        }
    };
    let missing = dir.join("no-such-dir");
    check(&["plot", s(&missing)], &[s(&missing), "not a folder"]);
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    check(
        &["plot", s(&empty)],
        &[
            &format!("{}", empty.join("history.csv").display()),
            "missing",
        ],
    );
    check(
        &["plot", s(&out), "--steps", "3"],
        &["results.h5", "step 3 is not an output step", "2, 4, 6, 7"],
    );
    check(&["plot", s(&out), "--steps", "late"], &["`late`", "first"]);
    check(
        &["plot", s(&out), "--compare", s(&out), "--label", "only-one"],
        &["--label", "2 run(s)"],
    );
    // a history.csv that is not one
    std::fs::write(empty.join("history.csv"), "a,b\n1,2\n").unwrap();
    check(&["plot", s(&empty)], &["history.csv", "`step` and `time`"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn overlay_of_two_runs_has_one_colour_per_run_and_both_labels() {
    let dir = tmpdir("overlay");
    let (a, o) = run_case(&dir.join("a"), CASE, &["--no-plots"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (b, o) = run_case(&dir.join("b"), &biaxial_case(), &["--no-plots"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cmp = dir.join("cmp");
    let o = mpfem(&[
        "plot",
        s(&a),
        "--compare",
        s(&b),
        "--label",
        "lateral",
        "--label",
        "biaxial",
        "--out",
        s(&cmp),
        "--steps",
        "last",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let (wa, wb) = (loaded_walls(&a), loaded_walls(&b));
    assert_eq!(wb.len(), 4, "biaxial: all four walls push");
    let svg = std::fs::read_to_string(cmp.join("pressure_compare.svg")).unwrap();
    let series: Vec<(String, usize)> = svg_polylines(&svg)
        .into_iter()
        .filter(|(_, n)| *n >= 3)
        .collect();
    assert_eq!(
        series.len(),
        wa.len() + wb.len(),
        "one polyline per wall and run: {series:?}"
    );
    // overlay: colour = run
    let (ca, cb) = (hex(SERIES_COLOURS[0]), hex(SERIES_COLOURS[1]));
    assert_eq!(series.iter().filter(|(c, _)| *c == ca).count(), wa.len());
    assert_eq!(series.iter().filter(|(c, _)| *c == cb).count(), wb.len());
    let texts = svg_texts(&svg);
    for w in &wa {
        let t = format!("lateral: {} wall", WALLS[*w]);
        assert!(texts.contains(&t), "no legend `{t}` in {texts:?}");
    }
    for w in &wb {
        let t = format!("biaxial: {} wall", WALLS[*w]);
        assert!(texts.contains(&t), "no legend `{t}` in {texts:?}");
    }
    let img = read_png(&cmp.join("pressure_compare.png"));
    assert_eq!((img.w as u32, img.h as u32), PRESSURE_SIZE);
    assert!(img.count_near(SERIES_COLOURS[0], 0, 100, img.w) > 20);
    assert!(img.count_near(SERIES_COLOURS[1], 0, 100, img.w) > 20);
    // snapshots come from the first run only
    assert!(cmp.join("snapshot_step_7.png").is_file());
    assert!(
        !a.join("pressure.png").exists(),
        "the overlay goes to --out"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn runs_without_walls_get_snapshots_only_also_when_the_run_fails() {
    // the default job (one block, no walls) allowed 3 steps: exits 1 after three converged
    // steps; the plots are drawn from what was written
    let dir = tmpdir("nowalls");
    let text = std::fs::read_to_string("jobs/default.toml")
        .unwrap()
        .replace("[time]", "[time]\nmax_steps = 3");
    let (out, o) = run_case(&dir, &text, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("no pressure plot"), "{err}");
    assert!(!out.join("pressure.png").exists() && !out.join("pressure.svg").exists());
    for st in 1..=3 {
        assert!(
            out.join(format!("snapshot_step_{st}.png")).is_file(),
            "step {st}: {err}"
        );
    }
    let img = read_png(&out.join("snapshot_step_3.png"));
    assert_eq!((img.w as u32, img.h as u32), SNAPSHOT_SIZE);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn history_and_step_choice() {
    let dir = tmpdir("history");
    let h = dir.join("history.csv");
    // a cut last row (a killed run) is skipped; a bad row before it is an error naming the line
    std::fs::write(&h, "step,time,solid_ratio,p_left,p_right,p_bottom,p_top,f_left,f_right,f_bottom,f_top\n1,0.1,0.7,1,1,0,0,2,2,0,0\n2,0.2,0.71,2,2,0,0,4,4,0,0\n3,0.3,0.7").unwrap();
    let hist = mpfem::plot::read_history(&h).unwrap();
    assert_eq!(hist.step, [1, 2]);
    let c = hist.compaction.as_ref().unwrap();
    assert_eq!(c.loaded_walls(), [0, 1]);
    assert_eq!(hist.solid_ratio_at(2), Some(0.71));
    std::fs::write(&h, "step,time\n1,0.1\n2,x\n3,0.3\n").unwrap();
    let e = mpfem::plot::read_history(&h).unwrap_err().to_string();
    assert!(e.contains("history.csv") && e.contains("line 3"), "{e}");

    use mpfem::plot::default_steps;
    assert_eq!(default_steps(&[2, 4, 6, 7], 4), [2, 4, 6, 7]);
    assert_eq!(
        default_steps(&(1..=14).collect::<Vec<_>>(), 4),
        [1, 5, 10, 14]
    );
    assert_eq!(default_steps(&[3, 5], 4), [3, 5]);
    assert_eq!(default_steps(&[3, 5], 1), [5]);
    assert!(default_steps(&[], 4).is_empty());
    // the colour map runs from dark to bright
    let lum = |(r, g, b): (u8, u8, u8)| 0.3 * r as f64 + 0.59 * g as f64 + 0.11 * b as f64;
    let l: Vec<f64> = (0..=10).map(|i| lum(colour_map(i as f64 / 10.0))).collect();
    assert!(l.windows(2).all(|w| w[1] > w[0]), "{l:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
