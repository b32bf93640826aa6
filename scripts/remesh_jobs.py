#!/usr/bin/env python3
"""Runs the paper's jobs (jobs/paper, all but the rigid section 4 job) and the 2 x 2 aluminium
die job (jobs/compaction/discs_2x2_lateral.toml, taken on to solid ratio 0.99) with adaptive
re-meshing on (`[remesh]` with its defaults appended to each case), and prints one table row per
job: the stop, the final solid ratio, steps, wall time, how many particles were re-meshed, the
share of the run time spent re-meshing (new meshes, transfers, rebuilds and the
re-equilibrations), the largest volume error, and the final wall pressures.

    python3 scripts/remesh_jobs.py [--out results/remesh] [--jobs 2] [--only NAME ...] [--no-run]

It runs `target/release/mpfem` (build it first: `cargo build --release`; the environment variable
MPFEM names another binary, e.g. a copy kept while the tree is rebuilt), two jobs at a time
by default; `--no-run` only prints the table from an earlier run's results. Each job's case
(with `[remesh]`), log, and results are in OUT/NAME. Units: mm, N, MPa, s.
"""
import argparse
import concurrent.futures
import csv
import json
import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent


def cases():
    out = {}
    for p in sorted((ROOT / "jobs" / "paper").glob("*.toml")):
        if p.stem.startswith("4_"):
            continue  # rigid particles: nothing to re-mesh
        out[p.stem] = p.read_text()
    text = (ROOT / "jobs" / "compaction" / "discs_2x2_lateral.toml").read_text()
    if "solid_ratio = 0.95\n" not in text:
        sys.exit("discs_2x2_lateral.toml: its [stop] solid_ratio = 0.95 line has changed")
    out["discs_2x2_lateral_to_0.99"] = text.replace("solid_ratio = 0.95\n", "solid_ratio = 0.99\n")
    return out


def run(name, text, out_dir, exe):
    d = out_dir / name
    d.mkdir(parents=True, exist_ok=True)
    # relative file references of the jobs are relative to jobs/<dir>/
    text = text.replace('file = "../', f'file = "{ROOT / "jobs"}/')
    if "[remesh]" not in text:
        text += "\n[remesh]\n"
    case = d / "case.toml"
    case.write_text(text)
    with open(d / "log.txt", "w") as log:
        rc = subprocess.call([str(exe), "run", "-q", "--no-plots", "-o", str(d / "out"), str(case)], stdout=log, stderr=subprocess.STDOUT)
    return name, rc


def row(name, d):
    s = d / "out" / "summary.json"
    h = d / "out" / "history.csv"
    if not s.exists() or not h.exists():
        return f"| {name} | no results | | | | | | | |"
    j = json.loads(s.read_text())
    r = list(csv.DictReader(open(h)))
    run_ = j["run"]
    t = run_.get("timing", {})
    total = j["phases"]["total"]
    share = (t.get("remesh", 0.0) + t.get("reequilibration", 0.0)) / total if total > 0 else 0.0
    vol = max(float(x["volume_error"]) for x in r) if r else float("nan")
    last = r[-1] if r else {}
    p = "/".join(f"{float(last[k]):.1f}" for k in ("p_left", "p_bottom")) if last else ""
    return (f"| {name} | {run_['stop_reason']} | {float(last.get('solid_ratio', 'nan')):.4f} | {run_['steps']} | "
            f"{run_['wall_time_s']:.0f} | {run_.get('remeshes', 0)} | {100 * share:.1f} % | {vol:.1e} | {p} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=str(ROOT / "results" / "remesh"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--only", nargs="*")
    ap.add_argument("--no-run", action="store_true")
    a = ap.parse_args()
    out_dir = pathlib.Path(a.out)
    todo = cases()
    if a.only:
        unknown = [n for n in a.only if n not in todo]
        if unknown:
            sys.exit(f"--only: no job {unknown}; the jobs are {sorted(todo)}")
        todo = {n: todo[n] for n in a.only}
    if not a.no_run:
        exe = pathlib.Path(os.environ.get("MPFEM", ROOT / "target" / "release" / "mpfem"))
        if not exe.exists():
            sys.exit(f"{exe} not found: run `cargo build --release` first (or set MPFEM to a binary)")
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
            for name, rc in pool.map(lambda kv: run(kv[0], kv[1], out_dir, exe), todo.items()):
                print(f"{name}: exit {rc}", file=sys.stderr)
    print("| job | stop | final solid ratio | steps | wall (s) | re-meshes | re-meshing share of run time | largest volume error | final p left / bottom (MPa) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in todo:
        print(row(name, out_dir / name))


if __name__ == "__main__":
    main()
