#!/usr/bin/env python3
"""Regenerate REPRODUCTION.md: run every job of jobs/paper/ (release build) and set our
figures beside the paper's (section numbers of the source paper; its figures as gathered in
the project's design notes).

    python3 scripts/reproduce.py              # run the jobs and studies that have no results yet, then write
    python3 scripts/reproduce.py --rerun      # run every job and study again
    python3 scripts/reproduce.py --no-studies # the jobs of jobs/paper/ only
    python3 scripts/reproduce.py --no-run     # only rewrite REPRODUCTION.md from results/

Results go to results/paper/<job>/ (history.csv, summary.json, results.h5, plots) and
results/studies/<study>/ (one directory per run, the overlay plot, study.csv and study.md).
MPFEM=path/to/mpfem runs that binary instead of `cargo run --release` (e.g. a copy, so that a
build beside the runs does not change it).
Standard library only; needs `cargo` on the PATH (unless MPFEM is set).
"""
import csv
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "results", "paper")

# The paper's figures: final solid ratio, wall pressures (MPa) at that solid ratio, run time
# and steps (its adaptive steps), solid ratio where the pressure starts to rise.
PAPER = {
    "5_1_1_aluminium_lateral": dict(section="5.1.1", phi=0.9843, p={"left/right": 290.0, "bottom/top": 224.8}, time=40, steps=130, onset="0.77-0.79"),
    "5_1_2_aluminium_vertical": dict(section="5.1.2", phi=0.9790, p={"left/right": 290.8, "bottom/top": 228.9}, time=50, steps=170, onset="0.77-0.79"),
    "5_1_3_aluminium_biaxial": dict(section="5.1.3", phi=0.9937, p={"left": 290.9, "right": 309.9, "top": 280.3, "bottom": 297.2}, time=40, steps=130, onset="0.77-0.79"),
    "5_2_1_asphalt_lateral": dict(section="5.2.1", phi=0.9913, p={"left/right": 128.4, "bottom/top": 62.5}, time=43, steps=None, onset="0.86"),
    "5_2_2_asphalt_vertical": dict(section="5.2.2", phi=0.9919, p={"left/right": 162.7, "bottom/top": 97.5}, time=43, steps=None, onset="0.86"),
    "5_2_3_asphalt_biaxial": dict(section="5.2.3", phi=0.9928, p={"left": 143.1, "right": 146.1, "top": 132.9, "bottom": 142.4}, time=43, steps=None, onset="0.86"),
}
# Why ours differ, per job: each note is a function of the run (its history rows and
# summary.json), so that the figures it quotes are those of the tables above it; what it says
# of earlier versions of this file is history (their figures are in its git history).


def mean_at(rows, phi, keys):
    """Mean of the columns `keys` at solid ratio `phi` (None beyond the run)."""
    vals = [at(rows, phi, k) for k in keys]
    return None if any(v is None for v in vals) else sum(vals) / len(vals)


LR, BT = ("p_left", "p_right"), ("p_bottom", "p_top")


def rel(ours, ref):
    """`ours` against `ref`, in percent with its sign."""
    return f"{100 * (ours / ref - 1):+.1f} %"


def within(onset_, lo, hi):
    """How a measured onset sits against the paper's range lo-hi."""
    if onset_ is None:
        return "not found"
    if lo - 1e-9 <= onset_ <= hi + 1e-9:
        return f"within the paper's {lo}-{hi}"
    return f"{'below' if onset_ < lo else 'above'} the paper's {lo}-{hi}"


def note_5_1_1(rows, s):
    lr, bt = mean_at(rows, 0.9843, LR), mean_at(rows, 0.9843, BT)
    o = onset(rows, pressing_walls(rows))
    return (f"At 98.43 % our walls are {lr:.1f} (left/right, {rel(lr, 290.0)}) and {bt:.1f} MPa (bottom/top, "
            f"{rel(bt, 224.8)}) against the paper's 290.0 and 224.8. The paper's particles and positions are not given "
            "(we use a regular 4 x 5 grid of ellipses) and it re-meshes; ours does not need to. The pressure starts to "
            f"rise at {o:.3f}, {within(o, 0.77, 0.79)} (0.775-0.81 on the twelve earlier paths of this file; the "
            "penalty runs: 0.73, their springs and overlaps carrying load early). This regular grid's path scatters "
            "near full density (see 6.1): the earlier versions of this file, on other Newton paths, had its walls at "
            "98.43 % from 7.1 % below to 7.8 % above the paper's (with the penalty method, before the barrier was the "
            "default: 11.5 % and 8.9 % below).")


def note_5_1_2(rows, s):
    lr, bt = mean_at(rows, 0.9790, LR), mean_at(rows, 0.9790, BT)
    o = onset(rows, pressing_walls(rows))
    return ("The paper gives left/right 290.8 and top/bottom 228.9 MPa, yet says in the same paragraph that the "
            "left-right pressure is less than the up-down pressure; in our run the pressing (top/bottom) walls carry "
            f"{'more' if bt > lr else 'less'} ({bt:.1f} against {lr:.1f} MPa at 0.9790), which agrees with that "
            f"sentence{', not with its numbers' if bt > lr else ''}. The top/bottom value is {rel(bt, 228.9)} against "
            f"the paper's, in {len(rows)} steps; the earlier versions of this file, on other Newton paths, had "
            "238.7-259.6 MPa there (the path scatter of this regular grid, see 6.1). The pressure first rises at "
            f"{o:.3f}, {within(o, 0.77, 0.79)} (0.748-0.766 on the last two earlier paths, one of which jammed "
            "at 0.748 and let go again).")


def note_5_1_3(rows, s):
    lr, bt = mean_at(rows, 0.9937, LR), mean_at(rows, 0.9937, BT)
    lr0, bt0 = mean_at(rows, 0.987, LR), mean_at(rows, 0.987, BT)
    lo = min(100 * (lr / 309.9 - 1), 100 * (bt / 297.2 - 1))
    hi = max(100 * (lr / 290.9 - 1), 100 * (bt / 280.3 - 1))
    slope = (lr - lr0) / (0.9937 - 0.987) / 1000
    return ("Our run reaches the paper's 0.9937 without re-meshing. Our regular grid gives exactly equal left/right "
            "and top/bottom pairs; the paper's four walls differ by up to 10 %, the mark of an irregular packing. "
            f"Ours are {lo:.0f}-{hi:.0f} % above the paper's at 0.9937 ({lr:.1f} and {bt:.1f} MPa), where the "
            f"pressure rises steeply: from 0.987 to 0.9937 it grows by {100 * (lr / lr0 - 1):.0f} % "
            f"({lr0:.1f} -> {lr:.1f} MPa left/right, {bt0:.1f} -> {bt:.1f} top/bottom), so a shift of 0.001 in "
            f"solid ratio moves it by about {slope:.0f} MPa. The earlier versions of this file, on other Newton "
            "paths, had 364.0-422.0 (left/right) and 390.6-439.8 MPa (top/bottom) there; with fixed steps of 0.5, "
            "0.25, 0.125 and 0.0625 s the left/right walls were 351.2, 379.6, 343.4 and 355.7 MPa (docs/robustness.md, "
            "twenty-third measurement): near full density this grid's pressures depend on the sequence of steps. The "
            "penalty method gave 302 and 340 MPa, its overlaps counting as solid.")


ASPHALT = ("Asphalt creeps, so the loading time matters: the paper reports 43 s to reach ~99 %, but walls at "
           "10 mm/s close a 1 m die from 0.80 to 0.99 in under 10 s (our runs), so the paper's particles had about four "
           "times longer to relax and its pressures are lower; the stress unit of the creep coefficient A is not stated "
           "either (we read Pa; jobs/examples/asphalt_creep_block.toml shows how strongly that choice matters). "
           "nu = 0.5 is enforced exactly (augmented Lagrangian), so our volume error (6.5) is round-off; the paper's "
           "0.6 % is not reproduced by design.")
CORNERS = ("With the barrier contact, the default, the octagon grids need no contact key and no re-meshing. With the "
           "penalty method they needed the smoothed contact normal (with straight segments they jammed at 0.92-0.96) and "
           "let the octagons overlap by up to 2.6 mm (a quarter of an element), overlap that counts as solid: at 0.95 the "
           "two methods agreed within 2.2 %, at 0.99 the barrier's walls carried 9-31 % more (docs/robustness.md, "
           "measured on an earlier version; these grids' paths have changed since: see 6.2).")


def asphalt_onset(rows):
    o = onset(rows, pressing_walls(rows))
    return f" The pressure starts to rise at {o:.3f}, against the paper's 0.86."


def note_5_2_1(rows, s):
    lr, bt = mean_at(rows, 0.9913, LR), mean_at(rows, 0.9913, BT)
    return (ASPHALT + asphalt_onset(rows) + " " + CORNERS + f" The walls at 0.9913 carry {lr:.1f} (left/right) and "
            f"{bt:.1f} MPa (bottom/top); the earlier versions of this file, on other Newton paths, had 198.7-255.6 and "
            "176.1-217.0 MPa, and with fixed steps of 0.5, 0.25, 0.125 and 0.0625 s the left/right walls at 0.9914 were "
            "199.9, 210.9, 211.6 and 269.5 MPa (docs/robustness.md, twenty-third measurement): near full density this "
            "grid's pressures depend on the sequence of steps.")


def note_5_2_2(rows, s):
    lateral = os.path.join(OUT, "5_2_1_asphalt_lateral", "history.csv")
    twin = ""
    if os.path.exists(lateral):
        other = history("5_2_1_asphalt_lateral")
        same = 0
        for x, y in zip(other, rows):
            pairs = [(x["solid_ratio"], y["solid_ratio"]), (x["p_left"], y["p_bottom"]), (x["p_bottom"], y["p_left"])]
            if any(abs(u - v) > 1e-9 * max(abs(u), abs(v), 1e-30) for u, v in pairs):
                break
            same += 1
        a, b = mean_at(other, 0.99, LR), mean_at(rows, 0.99, BT)
        twin = (" On this square grid vertical compaction is lateral compaction turned by 90 degrees: the two runs "
                f"agree, walls swapped, in their first {same} steps, to solid ratio {rows[same - 1]['solid_ratio']:.3f}, to "
                "nine digits or more, and then part as round-off takes the two grids along different branches (the "
                f"pressing walls at 0.99: {a:.1f} and {b:.1f} MPa, {abs(100 * (b / a - 1)):.1f} % apart).") if same else ""
    return ASPHALT + asphalt_onset(rows) + twin + " See 5.2.1 for the contact."


def note_5_2_3(rows, s):
    parted = [r for r in rows if r["p_left"] > 0 and abs(r["p_left"] / r["p_bottom"] - 1) > 1e-3]
    lr, bt = mean_at(rows, 0.9928, LR), mean_at(rows, 0.9928, BT)
    pairs = (f"the left/right and bottom/top pairs part by more than 0.1 % from {parted[0]['solid_ratio']:.3f} on "
             f"({lr:.1f} and {bt:.1f} MPa at 0.9928)") if parted else f"all four walls stay equal to 0.1 % ({lr:.1f} MPa at 0.9928)"
    return (ASPHALT + asphalt_onset(rows) + " The regular grid gives equal left/right and bottom/top pairs; " + pairs +
            ". The paper's four walls differ by up to 10 %. See 5.2.1 for the contact.")


NOTES = {
    "5_1_1_aluminium_lateral": note_5_1_1,
    "5_1_2_aluminium_vertical": note_5_1_2,
    "5_1_3_aluminium_biaxial": note_5_1_3,
    "5_2_1_asphalt_lateral": note_5_2_1,
    "5_2_2_asphalt_vertical": note_5_2_2,
    "5_2_3_asphalt_biaxial": note_5_2_3,
}


def runs_of(d):
    """The runs of a study directory: (label, history rows, summary) in the study's order."""
    order = sorted(os.listdir(d))
    table = os.path.join(d, "study.csv")
    if os.path.exists(table):
        with open(table) as f:
            order = [r["label"] for r in csv.DictReader(f)]
    out = []
    for label in order:
        path = os.path.join(d, label, "history.csv")
        if os.path.exists(path):
            with open(path) as f:
                rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
            summary = os.path.join(d, label, "summary.json")
            out.append((label, rows, json.load(open(summary)) if os.path.exists(summary) else {}))
    return out


def values(runs, phi, keys):
    return [mean_at(rows, phi, keys) for _, rows, _ in runs]


def listing(vals, spec=".1f"):
    return ", ".join("—" if v is None else format(v, spec) for v in vals)


def steps_and_cutbacks(runs):
    steps = [len(rows) for _, rows, _ in runs]
    cuts = [((s.get("run") or {}).get("cutbacks") or 0) for _, _, s in runs]
    springs = max(((s.get("final") or {}).get("stabilisation_ratio") or 0.0) for _, _, s in runs)
    spr = "the springs doing no work" if springs == 0 else f"the springs taking at most {100 * springs:.3f} % of the wall work"
    def span(v):
        return f"{min(v)}" if min(v) == max(v) else f"{min(v)}-{max(v)}"
    return f"{span(steps)} steps with {span(cuts)} cut-backs, {spr}"


def spread(vals):
    v = [x for x in vals if x is not None]
    return 100 * (max(v) / min(v) - 1)


def complete(runs, phis=(0.90, 0.95, 0.98)):
    """Whether every run of a study got to each solid ratio of `phis` (its note compares them there)."""
    return bool(runs) and all(mean_at(rows, phi, LR + BT) is not None for _, rows, _ in runs for phi in phis)


INCOMPLETE = "Not every run got to solid ratio 0.98, where this note compares them: see the tables above."


def study_5_3(runs):
    if not complete(runs):
        return INCOMPLETE
    labels = [l for l, _, _ in runs]
    parts = []
    for phi in (0.90, 0.95, 0.98):
        v = values(runs, phi, ("p_top",))
        hi, lo = labels[v.index(max(v))], labels[v.index(min(v))]
        parts.append(f"{listing(v)} MPa at {phi:.2f} ({spread(v):.0f} %; {hi} the stiffest, {lo} the softest)")
    return ("The paper (its Table 3 and the four arrangements are illegible or pictures only) gives the order of the "
            "required pressure, arrangement 1 > 4 > 3 > 2; its arrangements cannot be matched to ours, so the order "
            f"cannot be checked. Ours, with three asphalts whose creep coefficient spans a factor 4 ({', '.join(labels)}): "
            f"all four reach the 0.99 target in {steps_and_cutbacks(runs)}. The top wall carries " + "; ".join(parts) +
            ". Which arrangement is the stiffest has changed from version to version of this file (the random one, "
            "the checkerboard and the columns each were, at 0.98), and in an older one all four were within 5 % at "
            "0.98: the spread near full density is which branch each grid takes, not the arrangements', and it is not a "
            "result. At 10 mm/s the particles have little time to creep, so how the creep rates are arranged matters "
            "little. With the penalty method the random and checkerboard runs snapped near 0.89, with springs "
            "stiffened on cut-back that took up to 8 % of the wall work.")


def study_6_1(runs):
    if not complete(runs):
        return INCOMPLETE
    labels = [l for l, _, _ in runs]
    parts, signs = [], []
    for phi in (0.90, 0.95, 0.98):
        v = values(runs, phi, LR)
        d = [100 * (x / v[0] - 1) for x in v[1:]]
        parts.append(f"{listing(v)} MPa at {phi:.2f} ({', '.join(f'{x:+.1f} %' for x in d)} against frictionless)")
        signs.append((phi, all(x > 0 for x in d), all(x < 0 for x in d)))
    up = [f"{phi:.2f}" for phi, u, _ in signs if u]
    verdict = (f"Confirmed in sign at {', '.join(up)} only" if up else "Not confirmed in sign at 0.90, 0.95 or 0.98")
    return ("The paper: friction raises the wall pressure, about 20 % between the cases. " + verdict + ": on the "
            f"pressing (left/right) walls the runs ({', '.join(labels)}) carry " + "; ".join(parts) + ". All four reach "
            f"0.99 in {steps_and_cutbacks(runs)}, the sticking one with the barrier's ties (with the penalty method it "
            "failed at 0.715, an element inverting at the first ties). The path scatter decides: on the regular grid the "
            "ellipses choose between branches (a row that slides, a column that buckles) by round-off and by the step "
            "sizes, and between the versions of this file one run's walls moved by up to 28 % at 0.90, 11 % at 0.95 "
            "and 13 % at 0.98 (this job's 5.1.1 is the frictionless run). The earlier versions had friction raising "
            "the pressing walls at 0.90 by up to 31 % and at 0.95 by 4-11 %, and at 0.98 raising or lowering them by "
            "a few per cent: differences between the friction cases smaller than that scatter are not a result.")


def study_6_2(runs):
    if not complete(runs):
        return INCOMPLETE
    labels = [l.replace("phi0_", "") for l, _, _ in runs]
    parts = [f"{listing(values(runs, phi, LR))} MPa at {phi:.2f}" for phi in (0.90, 0.95, 0.98)]
    steps = [len(rows) for _, rows, _ in runs]
    v95, v98 = values(runs, 0.95, LR), values(runs, 0.98, LR)
    soft = labels[v98.index(min(v98))]
    stiff = labels[v98.index(max(v98))]
    sooner = steps[0] == min(steps)
    return ("The paper: about 15 % spread between initial solid ratios 0.65 and 0.80, the 0.65 case converging sooner. "
            f"Ours: all four reach the target in {steps_and_cutbacks(runs)}. Left/right walls for the starts "
            f"{', '.join(labels)}: " + "; ".join(parts) + f"; a spread of {spread(v95):.0f} % at 0.95 and "
            f"{spread(v98):.0f} % at 0.98, the start from {stiff} the stiffest and from {soft} the softest at 0.98. "
            f"{'Confirmed' if sooner else 'Not confirmed'}: the 0.65 case converging sooner ({listing(steps, 'd')} "
            "steps; it has the furthest to go). The grids lose stability on the way (the grid from 0.65, compressed "
            "from the sides, turns into an arrangement of rotated octagons) and go on along another branch, softer or "
            "stiffer by the path: the order of the starts has changed from version to version of this file (the start "
            "from 0.80, the same run as 5.2.1, was the stiffest in one and the softest in others), so only the spread's "
            "size is a result; the paper does not say which way. History: when a node facing a corner first felt one "
            "barrier, the run from 0.65 jammed at 0.9545 (it kept the symmetric path past the point where it lost "
            "stability and then snapped); since a converged saddle is left (docs/robustness.md, sixteenth measurement) "
            "every version has reached the target. With the penalty method the runs from 0.65 and 0.75 jammed at 0.935 "
            "and 0.968.")


def study_6_3(runs):
    if not complete(runs):
        return INCOMPLETE
    labels = [l.replace("n", "") for l, _, _ in runs]
    v90, v95, v98 = (values(runs, phi, LR) for phi in (0.90, 0.95, 0.98))
    rel98 = ", ".join(f"{100 * (x / v98[0] - 1):+.0f} %" for x in v98[1:])
    softer = all(b < a for a, b in zip(v98, v98[1:]))
    return ("The paper: the more particles, the softer, about 10 % spread. " + ("Confirmed" if softer else "Not confirmed") +
            f": at solid ratio 0.98 the left/right walls carry {listing(v98)} MPa for {', '.join(labels)} octagons "
            f"({rel98} against one); at 0.90 {listing(v90)} MPa, at 0.95 {listing(v95)}. The 16-octagon run is 6.2's "
            "run from 0.80 and 5.2.1, whose walls near full density have moved by a third between versions of this "
            "file (138.0 to 205.1 MPa at 0.98): the trend is within the path scatter of these grids. All four reach the "
            f"target in {steps_and_cutbacks(runs)} (with the penalty method they needed the smoothed normal, the "
            "viscous retry and the stiffened springs).")


def study_6_4(runs):
    v = {label: (mean_at(rows, 0.95, LR), mean_at(rows, 0.98, LR)) for label, rows, _ in runs}
    lat, ver, bia = v.get("lateral"), v.get("vertical"), v.get("biaxial")
    if not (lat and ver and bia) or None in lat + ver + bia:
        return INCOMPLETE
    def cmp(a, b):
        return f"{100 * (a[0] / b[0] - 1):+.0f} % and {100 * (a[1] / b[1] - 1):+.0f} %"
    above_v = bia[0] > ver[0] and bia[1] > ver[1]
    above_l = bia[0] > lat[0] and bia[1] > lat[1]
    return ("The paper: the lateral (left/right) pressure of biaxial compaction about 10 % above lateral and about 40 % "
            "above vertical compaction. Ours, left/right walls at solid ratios 0.95 and 0.98: biaxial "
            f"{bia[0]:.1f} and {bia[1]:.1f} MPa, lateral {lat[0]:.1f} and {lat[1]:.1f}, vertical {ver[0]:.1f} and "
            f"{ver[1]:.1f}; biaxial is {cmp(bia, ver)} against vertical ({'confirmed' if above_v else 'not confirmed'} "
            f"in sign) and {cmp(bia, lat)} against lateral ({'confirmed' if above_l else 'not confirmed'} in sign). In "
            "our lateral run the left/right walls are the pressing ones; in the biaxial run the load is shared by all "
            "four walls. The lateral and vertical runs carry the path scatter of 6.1 (they are 5.1.1 and 5.1.2), and "
            "the earlier versions of this file had biaxial 5-49 % above vertical and 2-14 % below lateral at 0.95: only "
            f"the signs are results. All three reach their target in {steps_and_cutbacks(runs)}.")


STUDY_NOTES = {
    "5_3_mixed_asphalts": study_5_3,
    "6_1_friction": study_6_1,
    "6_2_initial_solid_ratio": study_6_2,
    "6_3_particle_count": study_6_3,
    "6_4_compaction_types": study_6_4,
}
WALLS = {"left": ["p_left"], "right": ["p_right"], "bottom": ["p_bottom"], "top": ["p_top"],
         "left/right": ["p_left", "p_right"], "bottom/top": ["p_bottom", "p_top"]}


def mpfem():
    """The command that runs mpfem: $MPFEM, or the release build through cargo."""
    binary = os.environ.get("MPFEM")
    return [binary] if binary else ["cargo", "run", "--release", "--quiet", "--"]


def run(job, rerun):
    out = os.path.join(OUT, job)
    if not rerun and os.path.exists(os.path.join(out, "summary.json")):
        return
    case = os.path.join(ROOT, "jobs", "paper", job + ".toml")
    print(f"reproduce: running {case}", file=sys.stderr)
    subprocess.run(mpfem() + ["run", case, "--out", out], cwd=ROOT, check=False)


def run_study(name, rerun):
    out = os.path.join(ROOT, "results", "studies", name)
    if not rerun and os.path.exists(os.path.join(out, "study.md")):
        return
    study = os.path.join(ROOT, "jobs", "studies", name + ".toml")
    print(f"reproduce: running the study {study}", file=sys.stderr)
    subprocess.run(mpfem() + ["study", study, "--out", out], cwd=ROOT, check=False)


def studies():
    d = os.path.join(ROOT, "jobs", "studies")
    return sorted(f[:-5] for f in os.listdir(d) if f.endswith(".toml"))


def history(job):
    with open(os.path.join(OUT, job, "history.csv")) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def at(rows, phi, key):
    """Value of column `key` at solid ratio `phi` (linear interpolation), None beyond the run."""
    for a, b in zip(rows, rows[1:]):
        if a["solid_ratio"] <= phi <= b["solid_ratio"] and b["solid_ratio"] > a["solid_ratio"]:
            f = (phi - a["solid_ratio"]) / (b["solid_ratio"] - a["solid_ratio"])
            return a[key] + f * (b[key] - a[key])
    return None


def pressing_walls(rows):
    """The pressure columns of the walls that carry load at the end of a run."""
    return [k for k in ["p_left", "p_right", "p_bottom", "p_top"] if rows and rows[-1][k] > 0]


def onset(rows, keys):
    """Solid ratio where the mean pressure of `keys` first exceeds 5 % of its last value."""
    last = sum(rows[-1][k] for k in keys) / len(keys)
    for r in rows:
        if sum(r[k] for k in keys) / len(keys) > 0.05 * last > 0:
            return r["solid_ratio"]
    return None


def fmt(v, spec=".1f"):
    return "—" if v is None else format(v, spec)


def report():
    found = []
    for job in ("5_1_1_aluminium_lateral", "5_1_2_aluminium_vertical", "5_1_3_aluminium_biaxial"):
        if os.path.exists(os.path.join(OUT, job, "history.csv")):
            rows = history(job)
            pressing = pressing_walls(rows)
            o = onset(rows, pressing) if pressing else None
            if o is not None:
                found.append(o)
    onsets = f"{min(found):.3f}-{max(found):.3f}" if found else "—"
    lines = ["# Reproduction of the paper's experiments", "",
             "Generated by `python3 scripts/reproduce.py` from the runs in `results/paper/` (release build,",
             "jobs in `jobs/paper/`). Pressures are compared at the paper's final solid ratio when our run",
             "gets there, otherwise at our last step (marked *). The paper jobs run without re-meshing",
             "(`[remesh]` is off) to their target solid ratio (0.99, or the paper's final one where it is higher),",
             "with the barrier contact, the default since the barrier issue: no iterate crosses or inverts, and",
             "no job or study needs a stabilisation, contact-normal or retry key. What changed against the penalty",
             "method these jobs used before: section 4",
             "runs with the paper's friction mu = 0.1 instead of frictionless with viscous dashpots; every job and",
             "every study run reaches its target (with the penalty method the 6.1 sticking run failed at 0.715, and",
             f"two of the 6.2 runs jammed at 0.935 and 0.968); the pressure rise starts at {onsets} on the aluminium",
             "grids of 5.1 (the paper: 0.77-0.79; the penalty method: 0.72-0.73, its overlaps counting as solid);",
             "and near full density the walls carry more than with the penalty method. A step that would pass the",
             "target solid ratio ends on it. The notes under each table quote its figures, computed from the runs",
             "(`scripts/reproduce.py`); what they say of earlier versions of this file is history.",
             "",
             "This regeneration (2026-12-08) follows the one of 2026-12-07, evening (26cda6f). Only the frictional",
             "steps changed: the solves that precede an update of the lagged friction now stop early (once the",
             "out-of-balance force is below the last update's change of mu*lambda), and only the solve that finds",
             "the friction settled is converged to the solver's tolerance (docs/robustness.md, thirty-sixth",
             "measurement). Every frictionless run took the same path, its figures unchanged but for the wall",
             "times; the frictional ones (section 4, and 6.1's mu_0.1 and mu_0.2) took other paths and every one",
             "still reaches its target. The regeneration before it came after a change of the material law's",
             "arithmetic alone, which moved the regular grids' pressures near full density by up to 12 % in the",
             "paper jobs and 47 % in the studies: the grids' own sensitivity (main's binary before it, with the",
             "bottom wall's speed changed by 1e-12 of itself, moved 5.1.2's left/right walls as far: docs/robustness.md,",
             "thirty-fifth measurement). The figures of every earlier version, with what",
             "changed in each, are in the git history of this file.", ""]
    lines += section4()
    for job, p in PAPER.items():
        path = os.path.join(OUT, job, "summary.json")
        lines.append(f"## {p['section']} `{job}`")
        lines.append("")
        if not os.path.exists(path):
            lines += ["not run yet", ""]
            continue
        s = json.load(open(path))
        rows = history(job)
        fin = s.get("final") or {}
        phi_end = rows[-1]["solid_ratio"] if rows else None
        reached = phi_end is not None and phi_end >= p["phi"]
        lines.append(f"Command: `mpfem run jobs/paper/{job}.toml --out results/paper/{job}`; status {s['status']}"
                     f" ({(s.get('run') or {}).get('stop_reason', s.get('error'))}), {len(rows)} steps, {s['wall_time_s']:.0f} s wall.")
        lines.append("")
        lines.append("| quantity | paper | mpfem |")
        lines.append("|---|---|---|")
        lines.append(f"| final solid ratio | {p['phi']:.4f} | {fmt(phi_end, '.4f')} |")
        where = p["phi"] if reached else phi_end
        star = "" if reached else "*"
        for name, value in p["p"].items():
            keys = WALLS[name]
            ours = None
            if rows:
                vals = [at(rows, where, k) if reached else rows[-1][k] for k in keys]
                if all(v is not None for v in vals):
                    ours = sum(vals) / len(vals)
            rel = f" ({100 * (ours / value - 1):+.1f} %)" if ours else ""
            lines.append(f"| p {name} at φ = {where:.4f}{star} (MPa) | {value} | {fmt(ours)}{rel} |")
        vol = at(rows, where, "volume_error") if reached else fin.get("volume_error")
        lines.append(f"| volume error | ≈ 0.6 % | {fmt(None if vol is None else 100 * vol, '.2f')} % |")
        pressing = pressing_walls(rows)
        lines.append(f"| pressure starts to rise near φ | {p['onset']} | {fmt(onset(rows, pressing) if pressing else None, '.3f')} |")
        lines.append(f"| time to the end (s) / steps | {p['time']} / {p['steps'] or '—'} | {rows[-1]['time']:.1f} / {len(rows)} |")
        note = NOTES.get(job)
        fits = s.get("fits") or {}
        if fits.get("heckel"):
            h = fits["heckel"]
            lines.append(f"| Heckel K (1/MPa), R² (not in the paper) | — | {h['k']:.3e}, {h['r2']:.3f} |")
        lines.append("")
        if note and rows and reached:
            lines += [note(rows, s), ""]
    # the studies of section 6 that have been run (mpfem study jobs/studies/X.toml --out results/studies/X)
    studies = os.path.join(ROOT, "results", "studies")
    if os.path.isdir(studies):
        lines += ["# Studies (sections 5.3 and 6)", ""]
        for name in sorted(os.listdir(studies)):
            table = os.path.join(studies, name, "study.md")
            if not os.path.exists(table):
                continue
            lines.append(f"Command: `mpfem study jobs/studies/{name}.toml --out results/studies/{name}`")
            lines.append("")
            lines += ["#" + l if l.startswith("# ") else l for l in open(table).read().splitlines()]
            lines.append("")
            lines += study_trends(os.path.join(studies, name))
            if name in STUDY_NOTES:
                text = STUDY_NOTES[name](runs_of(os.path.join(studies, name)))
                if text:
                    lines += [text, ""]
    lines += volume_table()
    with open(os.path.join(ROOT, "REPRODUCTION.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("reproduce: wrote REPRODUCTION.md", file=sys.stderr)


SECTION4 = "4_rigid_ellipses"


def section4():
    """Section 4: the paper shows only the final arrangement of 25 near-rigid ellipses."""
    lines = [f"## 4 `{SECTION4}` (verification against Tzaferopoulos)", ""]
    path = os.path.join(OUT, SECTION4, "summary.json")
    if not os.path.exists(path):
        return lines + ["not run yet", ""]
    s = json.load(open(path))
    rows = history(SECTION4)
    fin = s.get("final") or {}
    run_ = s.get("run") or {}
    lines += [f"Command: `mpfem run jobs/paper/{SECTION4}.toml --out results/paper/{SECTION4}`; status {s['status']}"
              f" ({run_.get('stop_reason', s.get('error'))}), {len(rows)} steps, {s['wall_time_s']:.0f} s wall.", "",
              "| quantity | paper | mpfem |", "|---|---|---|",
              f"| final solid ratio | not given (figure 1 only) | {fmt(fin.get('solid_ratio'), '.4f')} |",
              f"| top wall pressure at the end (MPa) | not given | {fmt((fin.get('pressure') or [None] * 4)[3], '.3e')} |",
              f"| stabilisation work / wall work | — | {fmt(fin.get('stabilisation_ratio'), '.3f')} |",
              f"| volume error | ≈ 0.6 % | {fmt(None if fin.get('volume_error') is None else 100 * fin['volume_error'], '.2e')} % |", "",
              "The paper compares its final arrangement with Tzaferopoulos' picture by eye; ours is",
              f"`results/paper/{SECTION4}/snapshot_step_{len(rows)}.png` (the last step of the run).",
              "What it shows: the top wall pushes the particles into one another until they lock in force",
              "chains from the top wall to the bottom, with pores left open, as in the paper's figure. It",
              "runs as the paper states it, with Coulomb friction mu = 0.1 between the particles (with the",
              "penalty method the first contact between two near-rigid particles did not converge, and the",
              "job ran frictionless with viscous dashpots that took 39 % of the wall work). It ends when the",
              "top wall's pressure reaches 1e-3 E, an elastic strain of about 0.1 % that rigid particles would",
              "not have: the particles are locked, and with E = 2e10 MPa they take any load the wall gives. The",
              "stabilisation springs' work is the share in the table above.", ""]
    return lines


TREND_PHI = (0.85, 0.90, 0.95, 0.98)


def study_trends(d):
    """Mean left/right and bottom/top pressures of every run of a study at common solid ratios
    (the curves compared where they all exist, not at each run's own end)."""
    runs = [(label, rows) for label, rows, _ in runs_of(d)]
    if not runs:
        return []
    head = " | ".join(f"φ = {phi:.2f}" for phi in TREND_PHI)
    lines = ["Wall pressures (MPa, left/right ; bottom/top) at common solid ratios, from each run's history (— : the run did not get there):", "",
             f"| run | {head} |", "|---|" + "---|" * len(TREND_PHI)]
    for label, rows in runs:
        cells = []
        for phi in TREND_PHI:
            lr, bt = mean_at(rows, phi, LR), mean_at(rows, phi, BT)
            cells.append("—" if lr is None or bt is None else f"{lr:.1f} ; {bt:.1f}")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return lines + [""]


def volume_table():
    """Section 6.5: the volume error of every run there is (paper jobs and study runs)."""
    runs = [(f"`{job}`", os.path.join(OUT, job)) for job in [SECTION4] + list(PAPER)]
    studies = os.path.join(ROOT, "results", "studies")
    if os.path.isdir(studies):
        for name in sorted(os.listdir(studies)):
            d = os.path.join(studies, name)
            for label in sorted(os.listdir(d)):
                runs.append((f"{name} / {label}", os.path.join(d, label)))
    rows = []
    for name, d in runs:
        path = os.path.join(d, "summary.json")
        if not os.path.exists(path):
            continue
        s = json.load(open(path))
        fin = s.get("final") or {}
        if "volume_error" not in fin:
            continue
        rows.append((name, fin.get("solid_ratio"), fin["volume_error"], fin.get("max_particle_volume_error"), s.get("status")))
    if not rows:
        return []
    lines = ["# 6.5 Volume error of every run", "",
             "The paper: about 0.6 % on average over its runs (particle area change / initial area). Ours",
             "at the last converged step of each run: total and the largest single particle (aluminium is",
             "plastically incompressible but elastically compressible, so its error is its elastic volume",
             "change; asphalt (nu = 0.5) is held incompressible by an augmented Lagrangian).", "",
             "| run | status | final solid ratio | volume error | largest particle |", "|---|---|---|---|---|"]
    for name, phi, v, vmax, status in rows:
        lines.append(f"| {name} | {status} | {fmt(phi, '.4f')} | {100 * v:.2e} % | {fmt(None if vmax is None else 100 * vmax, '.2e')} % |")
    asphalt = [v for name, _, v, _, _ in rows if "asphalt" in name or "6_2" in name or "6_3" in name or "5_3" in name]
    if asphalt:
        lines += ["", f"Largest total volume error of the asphalt runs: {100 * max(asphalt):.1e} % (the issue asks for at most 0.05 %)."]
    return lines + [""]


if __name__ == "__main__":
    args = sys.argv[1:]
    if "--no-run" not in args:
        for job in [SECTION4] + list(PAPER):
            run(job, "--rerun" in args)
        if "--no-studies" not in args:
            for name in studies():
                run_study(name, "--rerun" in args)
    report()
