#!/usr/bin/env bash
# Peer benchmark: mpfem against CalculiX (ccx) on the same jobs at equal accuracy
# (docs/peer.md). Writes the decks, runs each job in mpfem and then in CalculiX, one after
# the other, and prints the table (also OUT/table.md, OUT/results.json).
#
#   bash scripts/peer_bench.sh [OUT]          # all three jobs (disc, 2 x 2 die, 4 x 4 die)
#   QUICK=1 bash scripts/peer_bench.sh [OUT]  # only a coarse disc in both codes (seconds)
#   MPFEM=path/to/mpfem CCX=path/to/ccx JOBS=disc,die2 bash scripts/peer_bench.sh OUT
#
# MPFEM defaults to target/release/mpfem (cargo build --release), CCX to ccx on PATH
# (Debian's calculix-ccx; scripts/setup.sh installs it). CPU seconds are the solver process's
# user + system time; mpfem runs with --threads 1 and CalculiX with OMP_NUM_THREADS=1.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-peer_out}"
export MPFEM="${MPFEM:-$here/target/release/mpfem}"
export CCX="${CCX:-ccx}"
if [ ! -x "$MPFEM" ]; then
  echo "peer_bench: no mpfem binary at $MPFEM (cargo build --release, or set MPFEM)" >&2
  exit 2
fi
if ! command -v "$CCX" >/dev/null 2>&1; then
  echo "peer_bench: CalculiX ($CCX) not found; bash scripts/setup.sh installs calculix-ccx" >&2
  exit 2
fi
args=(bench "$out")
if [ "${QUICK:-0}" = "1" ]; then
  args+=(--quick)
else
  args+=(--jobs "${JOBS:-disc,die2,die4}")
fi
exec python3 "$here/benches/peer/run_peer.py" "${args[@]}"
