#!/usr/bin/env python3
"""Where a barrier run's Newton iterations go: one line per solve attempt of a `-vv` log.

    mpfem run CASE.toml --out OUT -vv -q --no-plots 2> run.log
    python3 scripts/newton_anatomy.py run.log            # one line per attempt
    python3 scripts/newton_anatomy.py run.log --attempt 6  # that attempt iteration by iteration

Per attempt: how it ended (converged, failed and retried descending, failed and cut back), its
iterations, how many of its last updates were taken whole (eta = eta_max = 1: neither the
collision-free step nor the line search held them back), how many line searches the
collision-free step limited (eta_max < 1) or backtracked (eta < eta_max), how many tangents
were shifted (and the largest tau) or had their pair Hessians projected, the last relative
residual, the median step, how many updates moved their furthest-moved particle mostly
rigidly (its deformation below half its largest nodal update: a loose particle the tangent
barely holds) rather than by deforming it, and the bodies that carried the largest
out-of-balance force most often. A retry held up by one loose particle shows as one body in
most of its iterations (docs/robustness.md, eleventh measurement).
Standard library only.
"""
import collections
import re
import sys

KV = re.compile(r'(\w+)=("[^"]*"|\[[^\]]*\]|\S+)')


def attempts(path):
    """The attempts of the log, each a dict with its iterations' records."""
    out = []
    cur = None

    def new(kind):
        nonlocal cur
        cur = dict(kind=kind, end="converged", rows=[], its=0, res=[], eta=[], eta_max=[], shifts=[], projected=0,
                   bodies=collections.Counter(), rigid=0)
        out.append(cur)

    new("first")
    for line in open(path, errors="replace"):
        if " newton " in line and "iteration=" in line:
            d = dict(KV.findall(line))
            k = int(d["iteration"])
            if k == 0 and cur["res"]:
                # a new solve: the next step, or the re-solve after a friction or tie update
                new("next")
            cur["its"] = k
            cur["res"].append(float(d["residual"]))
            cur["bodies"][d.get("body")] += 1
            cur["rows"].append(("it", k, d["residual"], d.get("body"), d.get("worst_force"), d.get("x", "")))
        elif "largest update" in line:
            d = dict(KV.findall(line))
            largest, deformation = float(d["largest"]), float(d["deformation"])
            cur["rigid"] += deformation < 0.5 * largest
            cur["rows"].append(("lu", d["body"], largest, float(d["translation"]), float(d["turn"]), deformation))
        elif "barrier line search" in line:
            d = dict(KV.findall(line))
            cur["eta"].append(float(d["eta"]))
            cur["eta_max"].append(float(d["eta_max"]))
            cur["rows"].append(("ls", d["eta"], d["eta_max"], d.get("last_update"), d.get("min_distance")))
        elif "indefinite tangent shifted" in line:
            tau = float(dict(KV.findall(line))["tau"])
            cur["shifts"].append(tau)
            cur["rows"].append(("tau", tau))
        elif "projecting the pairs" in line:
            cur["projected"] += 1
            cur["rows"].append(("projected",))
        elif "retrying with definite tangents" in line:
            cur["end"] = "failed, retried"
            new("retry")
        elif "cutting back" in line:
            cur["end"] = "failed, cut back"
            new("cut back")
    return [a for a in out if a["res"]]


def summary(i, a):
    n = len(a["eta"])
    limited = sum(1 for m in a["eta_max"] if m < 1.0)
    backtracked = sum(1 for e, m in zip(a["eta"], a["eta_max"]) if e < m)
    median = sorted(a["eta"])[n // 2] if n else float("nan")
    # the updates taken whole (η = η_max = 1) at the attempt's end
    tail = 0
    for e, m in zip(reversed(a["eta"]), reversed(a["eta_max"])):
        if e != 1.0 or m != 1.0:
            break
        tail += 1
    top = ", ".join(f"{b}: {c}" for b, c in a["bodies"].most_common(2))
    return (f"{i:4d} {a['kind']:8s} {a['end']:16s} its {a['its']:3d}  whole at the end {tail:3d}  ccd-limited {limited:3d}  backtracked {backtracked:3d}"
            f"  shifts {len(a['shifts']):3d} (max tau {max(a['shifts'], default=0):.0e})  projected {a['projected']:2d}"
            f"  last residual {a['res'][-1]:.1e}  median eta {median:.2f}  rigid {a['rigid']:3d}  worst bodies {top}")


def detail(a):
    lines = []
    for r in a["rows"]:
        if r[0] == "it":
            lines.append(f"\n{r[1]:4d} residual {float(r[2]):.3e} body {r[3]} force {r[4]} at {r[5]}")
        elif r[0] == "ls":
            lines.append(f"  eta {float(r[1]):.3g}/{float(r[2]):.3g} update {r[3]} gap {r[4]}")
        elif r[0] == "lu":
            lines.append(f"  furthest body {r[1]} {r[2]:.3g} mm (translation {r[3]:.3g} mm, turn {r[4]:.3g} rad, deformation {r[5]:.3g} mm)")
        elif r[0] == "tau":
            lines.append(f"  tau {r[1]:.0e}")
        else:
            lines.append("  projected")
    return "".join(lines)


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    found = attempts(argv[1])
    if len(argv) >= 4 and argv[2] == "--attempt":
        print(detail(found[int(argv[3])]))
        return 0
    for i, a in enumerate(found):
        print(summary(i, a))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
