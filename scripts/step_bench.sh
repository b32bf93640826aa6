#!/usr/bin/env bash
# Time per compaction step of two mpfem binaries, measured in one run: each job is run with
# OLD and NEW alternately, REPEAT times each, one thread, and the median wall time per step is
# compared (old / new: above 1 the new binary is faster). The histories must be identical
# (a refactor that keeps results), which the script checks too.
#
#   bash scripts/step_bench.sh OLD NEW [REPEAT] [JOB...]
#
# OLD, NEW: mpfem binaries (release builds). REPEAT: runs of each binary per job (default 5).
# JOBs: case files (default: jobs/mpi/discs_8x8_bench.toml, 64 J2 discs with friction 0.2, 51 712
# dofs, 5 steps; jobs/mpi/octagons_8x8_bench.toml, 64 asphalt octagons with the smoothed
# normal, 30 steps).
# Run it on an otherwise idle machine: the ratio is only as good as the machine is quiet.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  sed -n '2,13p' "$0" >&2
  exit 2
fi
old=$(readlink -f "$1")
new=$(readlink -f "$2")
repeat=${3:-5}
shift 2
[ $# -gt 0 ] && shift
out=$(mktemp -d)
jobs=("$@")
if [ ${#jobs[@]} -eq 0 ]; then
  jobs=(jobs/mpi/discs_8x8_bench.toml jobs/mpi/octagons_8x8_bench.toml)
fi
per_step() { # summary.json -> seconds per step
  python3 -c "import json,sys; s=json.load(open(sys.argv[1])); print(s['wall_time_s'] / max(1, s['run']['steps']))" "$1"
}
for job in "${jobs[@]}"; do
  name=$(basename "$job" .toml)
  : >"$out/$name.old"
  : >"$out/$name.new"
  for i in $(seq "$repeat"); do
    for which in old new; do
      exe=$old
      [ "$which" = new ] && exe=$new
      dir="$out/$name-$which-$i"
      "$exe" run "$job" --out "$dir" --quiet --no-plots --threads 1 >/dev/null 2>&1
      per_step "$dir/summary.json" >>"$out/$name.$which"
    done
  done
  same=identical
  cmp -s "$out/$name-old-1/history.csv" "$out/$name-new-1/history.csv" || same=DIFFERENT
  python3 - "$name" "$out/$name.old" "$out/$name.new" "$same" <<'PY'
import statistics, sys
name, a, b, same = sys.argv[1:]
old = [float(x) for x in open(a)]
new = [float(x) for x in open(b)]
mo, mn = statistics.median(old), statistics.median(new)
print(f"{name}: s/step old {mo:.4f} (min {min(old):.4f}), new {mn:.4f} (min {min(new):.4f}); old/new {mo / mn:.3f} (medians), {min(old) / min(new):.3f} (minima); histories {same}")
PY
done
rm -rf "$out"
