#!/usr/bin/env python3
"""Speed-up and efficiency plots of a scaling study (Python 3 standard library only).

    python3 jobs/scaling/plot.py OUTDIR/scaling.csv [--cores N] [--note TEXT] [--date YYYY-MM-DD]

Reads the CSV written by jobs/scaling/study.sh and writes, next to it,
  speedup.svg     strong scaling: speed-up T1/TN against ranks, one line per solver, and the ideal;
  efficiency.svg  strong scaling T1/(N TN) and weak scaling T1/TN against ranks, per solver.
T1 is each solver's own time on the smallest rank count of its study (1 rank in the default
study; with a base of r0 ranks the speed-up is r0 T_r0 / TN). Only completed runs are drawn.
The points use scaling.csv (the fastest repeat); when runs.csv (every repeat) lies next to it,
a thin whisker below each point reaches the value of the slowest repeat of TN (T1 kept).
Ranks beyond --cores (default: this machine's) are shaded: there the ranks share cores.
"""
import argparse
import csv
import datetime
import math
import os
import sys
from xml.sax.saxutils import escape

COLOURS = {"cholesky": "#1f77b4", "pcg-schwarz": "#d62728", "mumps": "#2ca02c", "parts": "#9467bd", "parts-mg": "#ff7f0e"}
MARKERS = {"cholesky": "circle", "pcg-schwarz": "square", "mumps": "circle", "parts": "square", "parts-mg": "circle"}
LABELS = {
    "cholesky": "cholesky (gathered, rank 0 factors)",
    "pcg-schwarz": "pcg-schwarz (distributed)",
    "mumps": "mumps (PETSc, distributed LDLt)",
    "parts": "parts (own + ghost particles, barrier, MUMPS)",
    "parts-mg": "parts, CG with the particles' two levels",
}
FONT = "DejaVu Sans, Helvetica, Arial, sans-serif"


def load(path):
    """{study: {solver: {ranks: wall_s}}} of the completed runs, and the rows."""
    data, rows = {}, []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            rows.append(r)
            if r["status"] != "completed" or not r["wall_s"]:
                continue
            data.setdefault(r["study"], {}).setdefault(r["solver"], {})[int(r["ranks"])] = float(r["wall_s"])
    return data, rows


def load_slowest(path):
    """{study: {solver: {ranks: slowest completed wall_s}}} from runs.csv, or {}."""
    out = {}
    if not os.path.exists(path):
        return out
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            if r["status"] != "completed" or not r["wall_s"]:
                continue
            d = out.setdefault(r["study"], {}).setdefault(r["solver"], {})
            n = int(r["ranks"])
            d[n] = max(d.get(n, 0.0), float(r["wall_s"]))
    return out


def nice_step(span, target=6):
    raw = span / target
    mag = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 2.5, 5, 10):
        if raw <= m * mag:
            return m * mag
    return 10 * mag


def fmt(v):
    return f"{v:g}" if abs(v - round(v)) < 1e-9 else f"{v:.2f}".rstrip("0").rstrip(".")


class Panel:
    """One set of axes inside an SVG; data coordinates to pixels."""

    def __init__(self, x0, y0, w, h, xmax, ymax, ystep, xlabel, ylabel, title, cores):
        self.x0, self.y0, self.w, self.h = x0, y0, w, h
        self.xmin, self.xmax = 0.5, xmax + 0.5
        self.ymin, self.ymax, self.ystep = 0.0, ymax, ystep
        self.xlabel, self.ylabel, self.title, self.cores = xlabel, ylabel, title, cores
        self.out = []

    def px(self, x):
        return self.x0 + (x - self.xmin) / (self.xmax - self.xmin) * self.w

    def py(self, y):
        return self.y0 + self.h - (y - self.ymin) / (self.ymax - self.ymin) * self.h

    def frame(self, xticks):
        o = self.out
        if self.cores and self.cores < self.xmax - 0.5:
            xs = self.px(self.cores + 0.5)
            o.append(f'<rect x="{xs:.1f}" y="{self.y0}" width="{self.x0 + self.w - xs:.1f}" height="{self.h}" fill="#eeeeee"/>')
            o.append(f'<text x="{self.x0 + self.w - 6:.1f}" y="{self.y0 + 16}" font-size="11" fill="#777" text-anchor="end">more ranks than cores ({self.cores})</text>')
        y = 0.0
        while y <= self.ymax + 1e-9:
            p = self.py(y)
            o.append(f'<line x1="{self.x0}" y1="{p:.1f}" x2="{self.x0 + self.w}" y2="{p:.1f}" stroke="#dddddd" stroke-width="1"/>')
            o.append(f'<line x1="{self.x0 - 5}" y1="{p:.1f}" x2="{self.x0}" y2="{p:.1f}" stroke="#333"/>')
            o.append(f'<text x="{self.x0 - 8}" y="{p + 4:.1f}" font-size="12" text-anchor="end">{fmt(y)}</text>')
            y += self.ystep
        for x in xticks:
            p = self.px(x)
            o.append(f'<line x1="{p:.1f}" y1="{self.y0 + self.h}" x2="{p:.1f}" y2="{self.y0 + self.h + 5}" stroke="#333"/>')
            o.append(f'<text x="{p:.1f}" y="{self.y0 + self.h + 20}" font-size="12" text-anchor="middle">{x}</text>')
        o.append(f'<rect x="{self.x0}" y="{self.y0}" width="{self.w}" height="{self.h}" fill="none" stroke="#333" stroke-width="1.2"/>')
        o.append(f'<text x="{self.x0 + self.w / 2}" y="{self.y0 + self.h + 42}" font-size="13" text-anchor="middle">{escape(self.xlabel)}</text>')
        cy = self.y0 + self.h / 2
        o.append(f'<text x="{self.x0 - 46}" y="{cy}" font-size="13" text-anchor="middle" transform="rotate(-90 {self.x0 - 46} {cy})">{escape(self.ylabel)}</text>')
        if self.title:
            o.append(f'<text x="{self.x0 + self.w / 2}" y="{self.y0 - 10}" font-size="14" font-weight="bold" text-anchor="middle">{escape(self.title)}</text>')

    def line(self, pts, colour, dash=None, marker=None, labels=None, width=2.0, whiskers=None):
        """labels: {x: "above" | "below"} for the values to write next to the points."""
        if not pts:
            return
        for x, lo in (whiskers or {}).items():
            y = dict(pts).get(x)
            if y is not None and abs(lo - y) > 1e-12:
                X = self.px(x)
                self.out.append(f'<line x1="{X:.1f}" y1="{self.py(lo):.1f}" x2="{X:.1f}" y2="{self.py(y):.1f}" stroke="{colour}" stroke-width="1.2" stroke-opacity="0.7"/>')
                self.out.append(f'<line x1="{X - 4:.1f}" y1="{self.py(lo):.1f}" x2="{X + 4:.1f}" y2="{self.py(lo):.1f}" stroke="{colour}" stroke-width="1.2" stroke-opacity="0.7"/>')
        d = " ".join(f"{self.px(x):.1f},{self.py(y):.1f}" for x, y in pts)
        extra = f' stroke-dasharray="{dash}"' if dash else ""
        self.out.append(f'<polyline points="{d}" fill="none" stroke="{colour}" stroke-width="{width}"{extra}/>')
        for x, y in pts:
            X, Y = self.px(x), self.py(y)
            if marker == "circle":
                self.out.append(f'<circle cx="{X:.1f}" cy="{Y:.1f}" r="4.5" fill="{colour}" stroke="white" stroke-width="1"/>')
            elif marker == "square":
                self.out.append(f'<rect x="{X - 4:.1f}" y="{Y - 4:.1f}" width="8" height="8" fill="{colour}" stroke="white" stroke-width="1"/>')
            where = (labels or {}).get(x)
            if where:
                dy = -8 if where == "above" else 16
                self.out.append(f'<text x="{X + 9:.1f}" y="{Y + dy:.1f}" font-size="11" fill="{colour}">{y:.2f}</text>')



def legend_row(items, cx, y, maxw=1e9):
    """Centred rows of legend entries (label, colour, dash, marker) from height y on, each row
    at most maxw pixels wide."""
    widths = [44 + len(lab) * 6.9 + 24 for lab, *_ in items]
    rows, row, w_row = [], [], 0.0
    for it, w in zip(items, widths):
        if row and w_row + w > maxw:
            rows.append((row, w_row))
            row, w_row = [], 0.0
        row.append((it, w))
        w_row += w
    rows.append((row, w_row))
    out = []
    for k, (row, w_row) in enumerate(rows):
        out.extend(_legend_entries(row, cx - w_row / 2, y + 22 * k))
    return out


def _legend_entries(row, X, y):
    out = []
    for (lab, colour, dash, marker), w in row:
        extra = f' stroke-dasharray="{dash}"' if dash else ""
        out.append(f'<line x1="{X:.1f}" y1="{y - 4:.1f}" x2="{X + 30:.1f}" y2="{y - 4:.1f}" stroke="{colour}" stroke-width="2"{extra}/>')
        if marker == "circle":
            out.append(f'<circle cx="{X + 15:.1f}" cy="{y - 4:.1f}" r="4" fill="{colour}"/>')
        elif marker == "square":
            out.append(f'<rect x="{X + 11:.1f}" y="{y - 8:.1f}" width="8" height="8" fill="{colour}"/>')
        out.append(f'<text x="{X + 38:.1f}" y="{y:.1f}" font-size="12">{escape(lab)}</text>')
        X += w
    return out


def svg(width, height, title, subtitle, panels, extra=()):
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="{FONT}">',
        f'<rect width="{width}" height="{height}" fill="white"/>',
        f'<text x="{width / 2}" y="26" font-size="17" font-weight="bold" text-anchor="middle">{escape(title)}</text>',
    ]
    for i, line in enumerate(subtitle):
        parts.append(f'<text x="{width / 2}" y="{46 + 16 * i}" font-size="12" fill="#444" text-anchor="middle">{escape(line)}</text>')
    for p in panels:
        parts.extend(p.out)
    parts.extend(extra)
    parts.append("</svg>")
    return "\n".join(parts) + "\n"


def ratios(series, kind):
    """[(ranks, value)] for 'speedup' (r0 T_r0 / TN), 'strong' (r0 T_r0 / (N TN)), 'weak' (T_r0 / TN)."""
    if not series:
        return []
    r0 = min(series)
    t0 = series[r0]
    out = []
    for n in sorted(series):
        t = series[n]
        if kind == "speedup":
            out.append((n, r0 * t0 / t))
        elif kind == "strong":
            out.append((n, r0 * t0 / (n * t)))
        else:
            out.append((n, t0 / t))
    return out


def whisker_values(series, slowest, kind):
    """{ranks: ratio with the slowest repeat of TN} (the base time kept at its fastest)."""
    if not series or not slowest:
        return {}
    r0 = min(series)
    t0 = series[r0]
    out = {}
    for n, t in slowest.items():
        if n not in series:
            continue
        out[n] = {"speedup": r0 * t0 / t, "strong": r0 * t0 / (n * t), "weak": t0 / t}[kind]
    return out


def label_sides(curves, base):
    """{solver: {x: "above" | "below"}}: at every x the highest curve's value above, the others below."""
    sides = {s: {} for s in curves}
    xs = sorted({x for pts in curves.values() for x, _ in pts})
    for x in xs:
        if x == base:
            continue
        at = sorted(((dict(pts)[x], s) for s, pts in curves.items() if x in dict(pts)), reverse=True)
        for i, (_, s) in enumerate(at):
            sides[s][x] = "above" if i == 0 else "below"
    return sides


def core_ideal(r0, xmax, cores, kind):
    """Ideal curve when only `cores` cores exist: speed-up min(N, c) / r0-normalised, efficiency min(N, c) / N."""
    pts = []
    for n in range(r0, xmax + 1):
        m = min(n, cores) if cores else n
        pts.append((n, m / min(r0, cores) if kind == "speedup" else m / n * (r0 / min(r0, cores))))
    return pts


def solvers_of(data):
    seen = []
    for study in data.values():
        for s in study:
            if s not in seen:
                seen.append(s)
    order = list(COLOURS)
    return sorted(seen, key=lambda s: (order.index(s) if s in order else len(order), s))


def colour(s, i):
    return COLOURS.get(s, ["#2ca02c", "#9467bd", "#ff7f0e"][i % 3])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv")
    ap.add_argument("--cores", type=int, default=os.cpu_count())
    ap.add_argument("--note", default=None, help="machine note for the subtitle")
    ap.add_argument("--date", default=None, help="date for the subtitle (default: the CSV's)")
    a = ap.parse_args()

    data, rows = load(a.csv)
    slow = load_slowest(os.path.join(os.path.dirname(os.path.abspath(a.csv)), "runs.csv"))
    if not data:
        sys.exit(f"plot.py: no completed runs in {a.csv}")
    outdir = os.path.dirname(os.path.abspath(a.csv))
    date = a.date or datetime.datetime.fromtimestamp(os.path.getmtime(a.csv), datetime.timezone.utc).strftime("%Y-%m-%d")
    note = a.note or f"{a.cores} cores, shared"
    subtitle = [f"{note}; {date}"]
    repeats = set()
    if slow:
        with open(os.path.join(outdir, "runs.csv"), newline="") as f:
            repeats = {r.get("repeat") for r in csv.DictReader(f)}
    line2 = "T = wall time of the run (summary.json), one thread a rank"
    if len(repeats) > 1:
        line2 += f"; points: fastest of {len(repeats)} repeats, whiskers: slowest"
    subtitle.append(line2)
    solvers = solvers_of(data)
    all_ranks = sorted({int(r["ranks"]) for r in rows})
    xmax = max(all_ranks)

    def particles(study):
        ps = sorted({int(r["particles"]) for r in rows if r["study"] == study})
        return ps

    # speed-up
    strong = data.get("strong", {})
    sp = {s: ratios(strong.get(s, {}), "speedup") for s in solvers}
    ymax_sp = max([xmax] + [v for pts in sp.values() for _, v in pts]) * 1.08
    step = nice_step(ymax_sp)
    ymax_sp = math.ceil(ymax_sp / step) * step
    sp_ps = particles("strong")
    p = Panel(90, 96, 560, 360, xmax, ymax_sp, step, "MPI ranks", "speed-up T1 / TN",
              f"strong scaling, {sp_ps[0] if sp_ps else '?'} particles", a.cores)
    p.frame(all_ranks)
    r0 = min(all_ranks)
    p.line([(r0, 1.0), (xmax, xmax / r0)], "#555", dash="6 4", width=1.5)
    legend = [("ideal (N)", "#555", "6 4", None)]
    if a.cores and a.cores < xmax:
        p.line(core_ideal(r0, xmax, a.cores, "speedup"), "#999", dash="2 3", width=1.5)
        legend.append((f"ideal on {a.cores} cores", "#999", "2 3", None))
    sides = label_sides(sp, r0)
    for i, s in enumerate(solvers):
        wh = whisker_values(strong.get(s, {}), slow.get("strong", {}).get(s, {}), "speedup")
        p.line(sp[s], colour(s, i), marker=MARKERS.get(s, "circle"), labels=sides[s], whiskers=wh)
        legend.append((LABELS.get(s, s), colour(s, i), None, MARKERS.get(s, "circle")))
    with open(os.path.join(outdir, "speedup.svg"), "w") as f:
        f.write(svg(700, 576, "mpfem distributed runs: strong-scaling speed-up", subtitle, [p],
                    legend_row(legend, 370, 534, maxw=660)))

    # efficiency: strong and weak side by side
    panels = []
    weak = data.get("weak", {})
    eff = {
        "strong": {s: ratios(strong.get(s, {}), "strong") for s in solvers},
        "weak": {s: ratios(weak.get(s, {}), "weak") for s in solvers},
    }
    ymax_e = max([1.0] + [v for k in eff.values() for pts in k.values() for _, v in pts]) * 1.12
    estep = nice_step(ymax_e, 6)
    ymax_e = math.ceil(ymax_e / estep) * estep
    wps = particles("weak")
    per_rank = ""
    if wps:
        wr = sorted({(int(r["ranks"]), int(r["particles"])) for r in rows if r["study"] == "weak"})
        per = {pp // n for n, pp in wr}
        per_rank = f"{per.pop()} particles a rank" if len(per) == 1 else "weak"
    titles = {
        "strong": (f"strong: T1 / (N TN), {sp_ps[0] if sp_ps else '?'} particles", "parallel efficiency T1 / (N TN)"),
        "weak": (f"weak: T1 / TN, {per_rank}", "weak-scaling efficiency T1 / TN"),
    }
    legend = [("ideal (1)", "#555", "6 4", None)]
    if a.cores and a.cores < xmax:
        legend.append((f"ideal on {a.cores} cores", "#999", "2 3", None))
    for i, s in enumerate(solvers):
        legend.append((LABELS.get(s, s), colour(s, i), None, MARKERS.get(s, "circle")))
    for j, study in enumerate(("strong", "weak")):
        q = Panel(90 + j * 520, 96, 400, 340, xmax, ymax_e, estep, "MPI ranks", titles[study][1], titles[study][0], a.cores)
        q.frame(all_ranks)
        q.line([(r0, 1.0), (xmax, 1.0)], "#555", dash="6 4", width=1.5)
        if a.cores and a.cores < xmax:
            q.line(core_ideal(r0, xmax, a.cores, "efficiency"), "#999", dash="2 3", width=1.5)
        sides = label_sides(eff[study], r0)
        for i, s in enumerate(solvers):
            wh = whisker_values(data.get(study, {}).get(s, {}), slow.get(study, {}).get(s, {}), study)
            q.line(eff[study][s], colour(s, i), marker=MARKERS.get(s, "circle"), labels=sides[s], whiskers=wh)
        panels.append(q)
    with open(os.path.join(outdir, "efficiency.svg"), "w") as f:
        f.write(svg(1040, 536, "mpfem distributed runs: parallel efficiency", subtitle, panels,
                    legend_row(legend, 520, 521, maxw=1000)))
    print(f"plot.py: wrote {outdir}/speedup.svg and {outdir}/efficiency.svg")


if __name__ == "__main__":
    main()
