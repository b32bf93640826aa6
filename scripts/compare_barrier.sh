#!/usr/bin/env bash
# Run jobs with the barrier contact (the jobs' own stabilisation, normal and augmentation keys
# removed, so the barrier's defaults act) or as they are, to a target solid ratio, and print
# one line each: exit code, steps, final solid ratio, the springs' share of the wall work, the
# four wall pressures (MPa) and the wall time.
#
#   bash scripts/compare_barrier.sh barrier|keep TARGET OUT JOB.toml...
#
# e.g. bash scripts/compare_barrier.sh barrier 0.95 /tmp/cmp jobs/compaction/discs_2x2_*.toml
# MPFEM (default target/release/mpfem) is the binary.
set -euo pipefail
if [ $# -lt 4 ]; then
  sed -n '2,10p' "$0" >&2
  exit 2
fi
method=$1 target=$2 out=$3
shift 3
bin=$(readlink -f "${MPFEM:-target/release/mpfem}")
mkdir -p "$out"
for job in "$@"; do
  name=$(basename "$job" .toml)
  case_file="$out/${method}_${name}.toml"
  cp "$job" "$case_file"
  if [ "$method" = barrier ]; then
    sed -i -E -e 's/^method = "(penalty|augmented_lagrangian)"/method = "barrier"/' \
      -e '/^(stabilisation|stabilisation_kind|normal|stiffen_on_cutback|viscous_retry|penetration_tol|max_augmentations|regularisation) =/d' "$case_file"
    grep -q 'method = "barrier"' "$case_file" || sed -i 's/^\[contact\]/[contact]\nmethod = "barrier"/' "$case_file"
  fi
  python3 - "$case_file" "$target" <<'PY'
import re, sys
path, target = sys.argv[1:]
text = open(path).read()
text = re.sub(r'(\[stop\][^\[]*?solid_ratio = )[0-9.]+', lambda m: m.group(1) + target, text, flags=re.S)
open(path, 'w').write(text)
PY
  run="$out/${method}_${name}"
  start=$(date +%s.%N)
  rc=0
  (cd "$(dirname "$job")" && "$bin" run "$(readlink -f "$case_file")" --out "$(readlink -f "$out")/${method}_${name}" --no-plots --quiet) > "$run.log" 2>&1 || rc=$?
  end=$(date +%s.%N)
  python3 - "$name" "$method" "$rc" "$run/history.csv" "$start" "$end" <<'PY'
import sys
name, method, rc, hist, start, end = sys.argv[1:]
try:
    lines = open(hist).read().split('\n')
    head, last = lines[0].split(','), [l for l in lines if l][-1].split(',')
    d = dict(zip(head, last))
except OSError:
    d = {}
def f(k):
    try:
        return float(d[k])
    except (KeyError, ValueError):
        return float('nan')
work = f('external_work')
share = f('stabilisation_energy') / work if work > 0 else float('nan')
p = ', '.join(f"{f(k):.2f}" for k in ('p_left', 'p_right', 'p_bottom', 'p_top'))
print(f"{name:34s} {method:8s} exit={rc} steps={d.get('step')} solid_ratio={f('solid_ratio'):.4f} "
      f"springs={100 * share:.2f}% p=[{p}] wall={float(end) - float(start):.1f}s")
PY
done
