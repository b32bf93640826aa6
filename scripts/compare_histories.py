#!/usr/bin/env python3
"""Compare the results of two sets of runs whose history.csv files are expected to differ only
at the level of the solver's tolerances (a change of factorisation, of summation order).

    python3 scripts/compare_histories.py OLD_DIR NEW_DIR

OLD_DIR and NEW_DIR hold one run folder per job with the same names (as
`scripts/same_histories.sh` writes them under OUT/old and OUT/new). For every job it prints the
exit codes, the step counts, and:
- compaction runs (a solid_ratio column that rises): the largest relative difference of the
  wall pressures p_left..p_top between the two runs, both interpolated at the same solid ratios
  (20 points between the first loaded solid ratio and the smaller of the two final ones), among
  the walls that carry at least 1 % of the largest pressure there;
- other runs: the largest relative difference of the last row's numeric columns listed in
  COLUMNS (against the column's largest magnitude in the old run).
Exit 0 always: this is a report, the reader judges it against the solver's tolerances.
"""
import csv
import os
import sys

COLUMNS = ["time", "solid_ratio", "p_left", "p_right", "p_bottom", "p_top", "f_left", "f_right", "f_bottom", "f_top", "external_work"]
WALLS = ["p_left", "p_right", "p_bottom", "p_top"]


def read(path):
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError:
        return None
    return [{k: float(v) for k, v in r.items() if v not in ("", None)} for r in rows]


def interp(rows, x, key):
    for a, b in zip(rows, rows[1:]):
        if a["solid_ratio"] <= x <= b["solid_ratio"] and b["solid_ratio"] > a["solid_ratio"]:
            t = (x - a["solid_ratio"]) / (b["solid_ratio"] - a["solid_ratio"])
            return a[key] + t * (b[key] - a[key])
    return None


def compaction_diff(old, new, only_end=False):
    def loaded(rows):
        return [r for r in rows if max(r.get(w, 0.0) for w in WALLS) > 0.0]

    lo, ln = loaded(old), loaded(new)
    if len(lo) < 2 or len(ln) < 2:
        return None
    x0 = max(lo[0]["solid_ratio"], ln[0]["solid_ratio"])
    x1 = min(old[-1]["solid_ratio"], new[-1]["solid_ratio"])
    if x1 <= x0:
        return None
    worst = 0.0
    for i in [20] if only_end else range(21):
        x = x0 + (x1 - x0) * i / 20
        po = {w: interp(old, x, w) for w in WALLS}
        pn = {w: interp(new, x, w) for w in WALLS}
        if any(v is None for v in list(po.values()) + list(pn.values())):
            continue
        top = max(abs(v) for v in po.values())
        for w in WALLS:
            if abs(po[w]) >= 0.01 * top and top > 0:
                worst = max(worst, abs(pn[w] - po[w]) / abs(po[w]))
    return worst


def last_row_diff(old, new):
    worst = 0.0
    for k in COLUMNS:
        if k in old[-1] and k in new[-1]:
            scale = max(abs(r[k]) for r in old) or 1.0
            worst = max(worst, abs(new[-1][k] - old[-1][k]) / scale)
    return worst


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    a, b = sys.argv[1:]
    print(f"{'job':52s} {'exit':>9s} {'steps':>11s} {'final solid':>17s} {'max rel diff':>13s} what")
    for name in sorted(os.listdir(a)):
        pa, pb = os.path.join(a, name), os.path.join(b, name)
        if not os.path.isdir(pa):
            continue

        def code(p):
            try:
                return open(os.path.join(p, "exit_code")).read().strip()
            except OSError:
                return "?"

        old, new = read(os.path.join(pa, "history.csv")), read(os.path.join(pb, "history.csv"))
        if not old or not new:
            print(f"{name:52s} {code(pa):>4s}/{code(pb):<4s} (no history in one of them)")
            continue
        rising = old[-1].get("solid_ratio", 0.0) > old[0].get("solid_ratio", 0.0)
        d = compaction_diff(old, new) if rising else None
        what = "wall pressures at equal solid ratios"
        if d is None:
            d, what = last_row_diff(old, new), "last row"
        else:
            what += f"; {compaction_diff(old, new, True):.2e} at the last common one"
        fo, fn = old[-1].get("solid_ratio", 0.0), new[-1].get("solid_ratio", 0.0)
        print(f"{name:52s} {code(pa):>4s}/{code(pb):<4s} {len(old):>5d}/{len(new):<5d} {fo:8.5f}/{fn:8.5f} {d:13.2e} {what}")


if __name__ == "__main__":
    main()
