#!/usr/bin/env python3
"""Run the peer benchmark (mpfem against CalculiX) and write its table.

  run_peer.py bench OUT [--quick] [--jobs disc,die2,die4]
      each job at its chosen meshes (CHOSEN below), mpfem first, then CalculiX, one after
      the other; writes OUT/<job>/..., OUT/results.json and OUT/table.md.
  run_peer.py study OUT --job JOB --ccx-n 2,4,8 --mpfem-h 1,0.5 [--element CPE4R] ...
      a mesh study: every mesh of both codes; writes OUT/study_<job>.json and .md.

CPU seconds are user + system time of the solver process (getrusage of the waited child),
so a second process on the other core changes them little (wall time would change more).
mpfem runs with --threads 1, CalculiX with OMP_NUM_THREADS=1 (and its CCX_NPROC_* = 1).
The binary of mpfem is $MPFEM (default target/release/mpfem), CalculiX's is $CCX (ccx).
"""

import argparse
import csv
import json
import math
import os
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
import make_decks  # noqa: E402

# The meshes the benchmark runs (from the mesh study in docs/peer.md): the coarsest mesh of
# each code whose quantity lies within the job's tolerance of the reference; on the dies
# CalculiX's finest mesh that reaches the end (n = 16 with increments of at most 0.01 s on the
# 2 x 2 die, n = 8 on the 4 x 4; neither is within the tolerance yet, so the dies' ratios are
# lower bounds) against an mpfem mesh at least as accurate (h = 2 on both dies).
CHOSEN = {
    "disc": {"ccx": {"n": 24, "element": "CPE4", "dtmax": 0.05}, "mpfem": {"h": 0.5, "dt": 1 / 24}},
    "die2": {"ccx": {"n": 16, "element": "CPE4", "dtmax": 0.01}, "mpfem": {"h": 2.0, "dt": 0.02, "dt_max": 0.05}},
    "die4": {"ccx": {"n": 8, "element": "CPE4", "dtmax": 0.02}, "mpfem": {"h": 2.0, "dt": 0.02, "dt_max": 0.05}},
}
# QUICK=1 and tests/peer_calculix.rs: a coarse disc in both codes (seconds)
QUICK = {"disc": {"ccx": {"n": 16, "element": "CPE4", "dtmax": 0.05}, "mpfem": {"h": 0.5, "dt": 1 / 24}}}


def timed(cmd, cwd, env=None, log=None):
    """Run cmd; return (exit code, CPU seconds user + sys of the child, wall seconds)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    with open(log or os.devnull, "w") as out:
        rc = subprocess.call(cmd, cwd=cwd, env=env, stdout=out, stderr=subprocess.STDOUT)
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return rc, cpu, wall


def interp(ts, vs, t):
    """Linear interpolation of (ts, vs) at t; None beyond the last point."""
    if not ts or t > ts[-1] + 1e-9:
        return None
    pts = [(0.0, 0.0)] + list(zip(ts, vs))
    for (t0, v0), (t1, v1) in zip(pts, pts[1:]):
        if t <= t1 + 1e-12:
            return v1 if t1 == t0 else v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    return pts[-1][1]


def nominal_solid(meta, t):
    w = meta["width"]
    return meta["solid0"] * w * w / (w * (w - 2 * meta["speed"] * t))


def quantity_names(meta):
    return "plate force (N/mm, whole disc)" if meta["job"] == "disc" else "moving walls' pressure (MPa)"


def run_mpfem(toml, meta, out, binary):
    rc, cpu, wall = timed([binary, "run", os.path.basename(toml), "--out", out, "--no-plots", "--quiet",
                           "--threads", "1"], cwd=os.path.dirname(toml), log=out + ".log")
    res = {"code": "mpfem", "mesh": "h = %g mm" % meta["h"], "cpu_s": cpu, "wall_s": wall, "exit": rc}
    try:
        s = json.load(open(os.path.join(out, "summary.json")))
        res.update(status=s["status"], iterations=s["run"]["newton_iterations"], steps=s["run"]["steps"],
                   cutbacks=s["run"]["cutbacks"], stop=s["run"].get("stop_reason"), elements=s["n_elements"],
                   dofs=s["run"].get("n_free"))
    except (OSError, KeyError, ValueError) as e:
        res.update(status="no summary (%s)" % e)
    rows = list(csv.DictReader(open(os.path.join(out, "history.csv")))) if os.path.exists(
        os.path.join(out, "history.csv")) else []
    ts = [float(r["time"]) for r in rows]
    if meta["job"] == "disc":
        vs = [2.0 * float(r["f_top"]) for r in rows]  # quarter -> whole disc
    else:
        vs = [0.5 * (float(r["p_left"]) + float(r["p_right"])) for r in rows]
    res["values"] = [interp(ts, vs, t) for t in meta["times"]]
    res["final_time"] = ts[-1] if ts else 0.0
    if meta["job"] != "disc" and rows:
        res["solid_ratio"] = float(rows[-1]["solid_ratio"])
        res["nominal_solid_ratio"] = nominal_solid(meta, res["final_time"])
    return res


def parse_ccx(job_dir, name, meta):
    """Totals of the reaction forces per node set and time from NAME.dat, the iterations
    from NAME.cvg (every Newton iteration, also those of abandoned attempts) and the
    converged increments from NAME.sta."""
    totals = {}
    t = None
    setname = None
    dat = os.path.join(job_dir, name + ".dat")
    if os.path.exists(dat):
        lines = open(dat).read().splitlines()
        for i, line in enumerate(lines):
            if "total force (fx,fy,fz) for set" in line:
                w = line.split()
                setname = w[w.index("set") + 1]
                t = float(w[-1])
            elif setname and line.strip():
                f = [float(x) for x in line.split()]
                totals.setdefault(setname, []).append((t, f))
                setname = None
    iters = 0
    cvg = os.path.join(job_dir, name + ".cvg")
    if os.path.exists(cvg):
        for line in open(cvg).read().splitlines()[4:]:
            if len(line.split()) >= 5:
                iters += 1
    incs, attempts, last_t = 0, 0, 0.0
    sta = os.path.join(job_dir, name + ".sta")
    if os.path.exists(sta):
        for line in open(sta).read().splitlines()[2:]:
            w = line.split()
            if len(w) >= 7:
                attempts += 1
                if not w[2].endswith("U"):
                    incs += 1
                    last_t = float(w[4])
    return totals, iters, incs, attempts, last_t


def run_ccx(inp, meta, binary="ccx"):
    job_dir, name = os.path.dirname(inp), os.path.basename(inp)[:-4]
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_EQUATION_SOLVER="1", CCX_NPROC_STIFFNESS="1",
               CCX_NPROC_RESULTS="1", CCX_NPROC_CFD="1")
    log = os.path.join(job_dir, name + ".log")
    rc, cpu, wall = timed([binary, "-i", name], cwd=job_dir, env=env, log=log)
    text = open(log, errors="replace").read()
    totals, iters, incs, attempts, last_t = parse_ccx(job_dir, name, meta)
    # a die deck starts at t0 (the rigid approach of the discs is left out, make_decks.py)
    t0 = meta.get("t0", 0.0)
    last_t += t0
    totals = {k: [(t + t0, f) for t, f in v] for k, v in totals.items()}
    finished = "Job finished" in text
    end = meta.get("end", 1.0)
    # the .sta file prints times to 6 digits: a finished step that ends within that of the
    # end time has reached it
    if finished and abs(last_t - end) < 1e-5 * end:
        last_t = end
        totals = {k: v[:-1] + [(end, v[-1][1])] if v and abs(v[-1][0] - end) < 1e-5 * end else v
                  for k, v in totals.items()}
    err = [ln.strip() for ln in text.splitlines() if "ERROR" in ln]
    res = {"code": "ccx", "mesh": "n = %d (h = %.3g mm), %s" % (meta["n"], meta["h"], meta["element"]),
           "cpu_s": cpu, "wall_s": wall, "exit": rc, "iterations": iters, "steps": incs,
           "cutbacks": attempts - incs, "elements": meta["elements"],
           "status": "completed" if finished and last_t == end else "failed",
           "stop": "end time" if finished else (err[0] if err else "stopped (exit %d)" % rc)}
    if meta["job"] == "disc":
        ser = totals.get("PLATEN", [])
        ts = [a for a, _ in ser]
        vs = [-2.0 * f[1] for _, f in ser]  # quarter -> whole disc; RF is the force on the plate
    else:
        left, right = totals.get("LEFT", []), totals.get("RIGHT", [])
        ts = [a for a, _ in left]
        h = meta["width"]
        vs = [0.5 * (fl[0] - fr[0]) / h for (_, fl), (_, fr) in zip(left, right)]
        ts, vs = [t0] + ts, [0.0] + vs
    res["final_time"] = last_t
    res["values"] = [interp(ts, vs, t) if t <= last_t + 1e-9 else None for t in meta["times"]]
    if meta["job"] != "disc":
        res["nominal_solid_ratio"] = nominal_solid(meta, last_t)
    return res


def write_case(out, job, code, cfg, name):
    args = [sys.executable, os.path.join(HERE, "make_decks.py"), out, "--job", job, "--name", name]
    if code == "ccx":
        args += ["--ccx-n", str(cfg["n"]), "--element", cfg.get("element", "CPE4"),
                 "--ccx-dtmax", str(cfg.get("dtmax", 0.1))]
        if cfg.get("k"):
            args += ["--k-contact", str(cfg["k"])]
    else:
        args += ["--mpfem-h", str(cfg["h"]), "--mpfem-dt", str(cfg["dt"])]
        if "dt_max" in cfg:
            args += ["--mpfem-dtmax", str(cfg["dt_max"])]
    subprocess.check_call(args)
    ext = ".inp" if code == "ccx" else ".toml"
    return os.path.join(out, name + ext), json.load(open(os.path.join(out, name + ".json")))


def run_one(out, job, code, cfg, name, mpfem_bin, ccx_bin):
    path, meta = write_case(out, job, code, cfg, name)
    if code == "mpfem":
        res = run_mpfem(os.path.abspath(path), meta, os.path.abspath(os.path.join(out, name)), mpfem_bin)
    else:
        res = run_ccx(os.path.abspath(path), meta, ccx_bin)
    res.update(job=job, name=name, config=cfg, labels=meta["labels"], times=meta["times"])
    print("  %-6s %-5s %-34s CPU %7.2f s  iterations %5s  %s  values %s" % (
        job, code, res["mesh"], res["cpu_s"], res.get("iterations"), res.get("status"),
        ", ".join("-" if v is None else "%.4g" % v for v in res["values"])), flush=True)
    return res


def fmt(v, d=4):
    return "–" if v is None else ("%%.%dg" % d) % v


def reach(r):
    if r["job"] == "disc":
        return "%.1f %% (%s)" % (30.0 * r["final_time"], r.get("status"))
    s = "nominal %.3f" % r["nominal_solid_ratio"]
    if "solid_ratio" in r:
        s += " (solid ratio %.3f)" % r["solid_ratio"]
    return s + ("" if r.get("status") == "completed" else ", stopped")


def table(results):
    out = ["| job | code | mesh | CPU s | wall s | Newton iterations | increments (cut-backs) | how far | quantity (disc: plate force, N/mm, at % of the diameter; dies: moving walls' pressure, MPa, at nominal solid ratio) | CalculiX CPU / mpfem CPU |",
           "| --- | --- | --- | ---: | ---: | ---: | ---: | --- | --- | ---: |"]
    for job in ("disc", "die2", "die4"):
        rs = [r for r in results if r["job"] == job]
        if not rs:
            continue
        m = [r for r in rs if r["code"] == "mpfem"]
        c = [r for r in rs if r["code"] == "ccx"]
        # the ratio only where both codes reached the end (otherwise not at equal accuracy)
        both = m and c and m[0].get("status") == "completed" and c[0].get("status") == "completed"
        ratio = c[0]["cpu_s"] / m[0]["cpu_s"] if both and m[0]["cpu_s"] > 0 else None
        for r in rs:
            q = ", ".join("%s: %s" % (l, fmt(v)) for l, v in zip(r["labels"], r["values"]))
            out.append("| %s | %s | %s | %.2f | %.2f | %s | %s (%s) | %s | %s | %s |" % (
                job, r["code"], r["mesh"], r["cpu_s"], r["wall_s"], r.get("iterations"), r.get("steps"),
                r.get("cutbacks"), reach(r), q,
                "" if r["code"] != "ccx" else ("%.1f" % ratio if ratio else "– (CalculiX stopped)")))
    return "\n".join(out) + "\n"


def retable(out):
    """Rewrite OUT/table.md from OUT/results.json."""
    t = table(json.load(open(os.path.join(out, "results.json"))))
    open(os.path.join(out, "table.md"), "w").write(t)
    return t


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["bench", "study"])
    ap.add_argument("out")
    ap.add_argument("--quick", action="store_true", help="only the coarse disc in both codes")
    ap.add_argument("--jobs", default="disc,die2,die4")
    ap.add_argument("--job", default="disc")
    ap.add_argument("--ccx-n", default="")
    ap.add_argument("--element", default="CPE4")
    ap.add_argument("--ccx-dtmax", type=float, default=None)
    ap.add_argument("--k", type=float, default=None, help="CalculiX contact slope (MPa/mm)")
    ap.add_argument("--mpfem-h", default="")
    ap.add_argument("--mpfem-dt", type=float, default=None)
    ap.add_argument("--mpfem-dtmax", type=float, default=None)
    a = ap.parse_args()
    mpfem_bin = os.path.abspath(os.environ.get("MPFEM", "target/release/mpfem"))
    ccx_bin = os.environ.get("CCX", "ccx")
    os.makedirs(a.out, exist_ok=True)
    results = []
    if a.mode == "bench":
        chosen = QUICK if a.quick else {j: CHOSEN[j] for j in a.jobs.split(",")}
        for job, cfg in chosen.items():
            d = os.path.join(a.out, job)
            os.makedirs(d, exist_ok=True)
            results.append(run_one(d, job, "mpfem", cfg["mpfem"], "%s_mpfem" % job, mpfem_bin, ccx_bin))
            results.append(run_one(d, job, "ccx", cfg["ccx"], "%s_ccx" % job, mpfem_bin, ccx_bin))
        json.dump(results, open(os.path.join(a.out, "results.json"), "w"), indent=1)
        t = table(results)
        open(os.path.join(a.out, "table.md"), "w").write(t)
        print()
        print(t)
        bad = [r for r in results if r.get("exit") not in (0,) and r["code"] == "mpfem"]
        return 1 if bad else 0
    # study
    d = os.path.join(a.out, a.job)
    os.makedirs(d, exist_ok=True)
    default_dt = {"disc": (1 / 6, None), "die2": (0.02, 0.05), "die4": (0.02, 0.05)}[a.job]
    for h in [x for x in a.mpfem_h.split(",") if x]:
        cfg = {"h": float(h), "dt": a.mpfem_dt or default_dt[0]}
        if a.job != "disc":
            cfg["dt_max"] = a.mpfem_dtmax or default_dt[1]
        results.append(run_one(d, a.job, "mpfem", cfg, "mpfem_h%s_dt%.4g" % (h, cfg["dt"]), mpfem_bin, ccx_bin))
    for n in [x for x in a.ccx_n.split(",") if x]:
        cfg = {"n": int(n), "element": a.element,
               "dtmax": a.ccx_dtmax or (0.1 if a.job == "disc" else 0.02)}
        if a.k:
            cfg["k"] = a.k
        results.append(run_one(d, a.job, "ccx", cfg, "ccx_%s_n%s_dt%.4g%s" % (
            a.element, n, cfg["dtmax"], "_k%g" % a.k if a.k else ""), mpfem_bin, ccx_bin))
    path = os.path.join(a.out, "study_%s.json" % a.job)
    old = json.load(open(path)) if os.path.exists(path) else []
    json.dump(old + results, open(path, "w"), indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
