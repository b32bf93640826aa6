#!/usr/bin/env bash
# Time one job on 1 and on 2 MPI ranks (one thread each) with a release build of the `mpi`
# feature, check that both histories are identical, and print the speed-up.
#   bash jobs/mpi/bench.sh [CASE] [RANKS]     (default: jobs/mpi/discs_8x8_bench.toml, 2)
set -euo pipefail
cd "$(dirname "$0")/../.."
case_file=${1:-jobs/mpi/discs_8x8_bench.toml}
ranks=${2:-2}
cargo build --release --locked --features mpi --bin mpfem >&2
exe=${CARGO_TARGET_DIR:-target}/release/mpfem
out=$(mktemp -d)
# (root in containers; local ranks without ssh)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_plm=${OMPI_MCA_plm:-isolated}
run() { # ranks dir
  local t0 t1
  t0=$(date +%s.%N)
  mpirun --oversubscribe --bind-to none -n "$1" "$exe" run "$case_file" --out "$2" --quiet --no-plots --threads 1
  t1=$(date +%s.%N)
  awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }' 
}
t1=$(run 1 "$out/r1")
tn=$(run "$ranks" "$out/r$ranks")
if cmp -s "$out/r1/history.csv" "$out/r$ranks/history.csv"; then same=identical; else same=DIFFERENT; fi
phases() { python3 -c "import json,sys; s=json.load(open(sys.argv[1])); print(' '.join(f'{k} {v:.2f}' for k,v in s['run']['timing'].items()))" "$1/summary.json"; }
echo "1 rank:      ${t1} s  ($(phases "$out/r1"))"
echo "$ranks ranks:     ${tn} s  (rank 0: $(phases "$out/r$ranks"))"
echo "speed-up:    $(awk -v a="$t1" -v b="$tn" 'BEGIN { printf "%.2f", a / b }')   (histories $same)"
rm -rf "$out"
