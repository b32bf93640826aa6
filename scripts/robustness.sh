#!/usr/bin/env bash
# The robustness suite (jobs/robustness/): run its cases and print one line a case — how the
# run ended, the final solid ratio, steps, Newton iterations a step, cut-backs, the share of
# the wall work the stabilisation springs took, and the wall time. `it/step` counts the Newton
# iterations of the converged attempts; `solves/step` counts the linear solves of every attempt
# (the failed attempts before a retry or a cut-back included), the work the run did.
#
#   bash scripts/robustness.sh OUT [CASE.toml ...]
#
# Without cases: every jobs/robustness/*.toml up to 64 particles (the 256- and 1,024-particle
# cases are run by naming them). METHOD=penalty (or any other contact method) runs them with
# `[contact] method = "$METHOD"` instead of the default (the barrier); TIMEOUT (s, default 1800) stops a case that takes longer; MPFEM
# (default target/release/mpfem) is the binary. OUT keeps each run's folder and the table
# OUT/robustness.txt. Exit 0 when every case reached its target (or, for a jam case, jammed).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ]; then
  sed -n '2,14p' "$0" >&2
  exit 2
fi
out=$1
shift
mkdir -p "$out"
out=$(readlink -f "$out")
bin=$(readlink -f "${MPFEM:-target/release/mpfem}")
method=${METHOD:-default}
timeout_s=${TIMEOUT:-1800}
if [ $# -gt 0 ]; then
  cases=("$@")
else
  cases=()
  for f in jobs/robustness/*.toml; do
    case "$f" in *_256_* | *_1024_*) continue ;; esac
    cases+=("$f")
  done
fi
table="$out/robustness.txt"
printf '%-48s %-8s %-22s %8s %6s %8s %11s %8s %8s %9s\n' case method end solid steps it/step solves/step cutbacks springs wall_s | tee "$table"
all_ok=0
for f in "${cases[@]}"; do
  name=$(basename "$f" .toml)
  case_file="$out/$name.toml"
  cp "$f" "$case_file"
  if [ "$method" != default ]; then
    sed -i "s/^\\[contact\\]/[contact]\\nmethod = \"$method\"/" "$case_file"
  fi
  start=$(date +%s.%N)
  rc=0
  timeout "$timeout_s" "$bin" run "$case_file" --out "$out/$name" --no-plots --quiet > "$out/$name.log" 2>&1 || rc=$?
  end=$(date +%s.%N)
  line=$(python3 - "$out/$name/summary.json" "$rc" "$start" "$end" <<'PY'
import json, sys
path, rc, start, end = sys.argv[1:]
wall = float(end) - float(start)
try:
    s = json.load(open(path))
except (OSError, ValueError):
    print(f"{'timeout' if rc == '124' else 'no summary (exit ' + rc + ')':22s} {'-':>8s} {'-':>6s} {'-':>8s} {'-':>11s} {'-':>8s} {'-':>8s} {wall:9.1f} 1")
    sys.exit()
run = s.get("run") or {}
final = s.get("final") or {}
reason = run.get("stop_reason") or s.get("status") or "?"
steps = run.get("steps") or final.get("step") or 0
its = run.get("newton_iterations", 0)
solves = (run.get("timing") or {}).get("linear_solves", 0)
share = final.get("stabilisation_ratio", float("nan"))
ok = reason in ("solid ratio reached", "wall pressure reached", "jammed")
print(f"{reason[:22]:22s} {final.get('solid_ratio', float('nan')):8.4f} {steps:6d} {its / max(steps, 1):8.1f} {solves / max(steps, 1):11.1f} "
      f"{run.get('cutbacks', 0):8d} {100 * share:7.2f}% {wall:9.1f} {0 if ok else 1}")
PY
)
  ok=${line##* }
  [ "$ok" = 0 ] || all_ok=1
  printf '%-48s %-8s %s\n' "$name" "$method" "${line% *}" | tee -a "$table"
done
exit $all_ok
