#!/usr/bin/env bash
# Prove that a change does not change results: run a stated set of jobs with two mpfem
# binaries and compare the md5 of every history.csv.
#
#   bash scripts/same_histories.sh OLD NEW [OUT]
#
# OLD and NEW are each a path to an mpfem binary (built with `--features mpi` for the MPI
# rows) or a git revision, which is then built in a temporary worktree with its own target
# folder (a release build of the `mpi` feature; slow, ~10 min a revision on 2 cores).
# OUT (default: a temporary folder) keeps both sets of run folders and the table, md5.txt.
#
# The set (the refactoring issue's list):
#   - every job of jobs/compaction/ and jobs/verification/, to its own end;
#   - every job of jobs/paper/ with its target solid ratio lowered to PAPER_TARGET (default
#     0.95: the full runs to 0.99 take many minutes; `PAPER_TARGET=keep` runs them as they are);
#   - the MPI runs: tests/data/mpi_discs_3x3.toml (friction, segment normal) and
#     jobs/mpi/octagons_8x8_bench.toml (smoothed normal) on 1, 2 and 4 ranks (`MPI=0` skips
#     them, e.g. for binaries built without the feature).
# Each binary runs with one thread (faer's threaded factorisations need not be bit-identical
# from run to run); the two binaries run side by side, one core each.
# Exit 0 when every history.csv is byte-identical and every run ended as before, 1 otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
if [ $# -lt 2 ]; then
  sed -n '2,22p' "$0" >&2
  exit 2
fi
out=${3:-$(mktemp -d)}
mkdir -p "$out"
target=${PAPER_TARGET:-0.95}
mpi=${MPI:-1}

# a binary path, or a git revision built in a worktree
binary() { # spec name
  if [ -x "$1" ] && [ -f "$1" ]; then
    readlink -f "$1"
    return
  fi
  local rev wt
  rev=$(git rev-parse --verify "$1^{commit}") || { echo "same_histories: '$1' is neither a binary nor a git revision" >&2; exit 2; }
  wt="$out/src-$2"
  rm -rf "$wt"
  git worktree add --detach "$wt" "$rev" >&2
  (cd "$wt" && CARGO_TARGET_DIR="$out/target-$2" cargo build --release --locked --features mpi --bin mpfem >&2)
  git worktree remove --force "$wt" >&2
  echo "$out/target-$2/release/mpfem"
}
old=$(binary "$1" old)
new=$(binary "$2" new)

# the job files in a scratch copy (the paper jobs' targets lowered), with the data they read
jobs="$out/jobs"
rm -rf "$jobs"
mkdir -p "$jobs"
cp -r jobs/compaction jobs/verification jobs/paper jobs/data jobs/mpi "$jobs/"
mkdir -p "$jobs/tests_data"
cp tests/data/mpi_discs_3x3.toml "$jobs/tests_data/"
if [ "$target" != keep ]; then
  for f in "$jobs"/paper/*.toml; do
    # the first `solid_ratio` after [stop] is the target
    awk -v t="$target" '/^\[/ { sec = $0 } sec == "[stop]" && /^solid_ratio *=/ && !done { print "solid_ratio = " t; done = 1; next } { print }' "$f" >"$f.tmp"
    mv "$f.tmp" "$f"
  done
fi

list=()
for f in "$jobs"/compaction/*.toml "$jobs"/verification/*.toml "$jobs"/paper/*.toml; do
  list+=("serial:$f")
done
if [ "$mpi" = 1 ]; then
  for n in 1 2 4; do
    list+=("mpi$n:$jobs/tests_data/mpi_discs_3x3.toml" "mpi$n:$jobs/mpi/octagons_8x8_bench.toml")
  done
fi

export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_plm=${OMPI_MCA_plm:-isolated}
run_all() { # binary tag
  local exe=$1 tag=$2 item how file name dir code
  for item in "${list[@]}"; do
    how=${item%%:*}
    file=${item#*:}
    name=$(basename "$(dirname "$file")")_$(basename "$file" .toml)_$how
    dir="$out/$tag/$name"
    rm -rf "$dir"
    mkdir -p "$dir"
    code=0
    if [ "$how" = serial ]; then
      "$exe" run "$file" --out "$dir" --quiet --no-plots --threads 1 >"$dir/log.txt" 2>&1 || code=$?
    else
      mpirun --oversubscribe --bind-to none -n "${how#mpi}" "$exe" run "$file" --out "$dir" --quiet --no-plots --threads 1 >"$dir/log.txt" 2>&1 || code=$?
    fi
    echo "$code" >"$dir/exit_code"
  done
}
t0=$(date +%s)
run_all "$old" old &
pid=$!
run_all "$new" new
wait "$pid"
t1=$(date +%s)

status=0
h() { [ -f "$1/history.csv" ] && md5sum <"$1/history.csv" | cut -d' ' -f1 || echo missing; }
{
  printf '%-52s %-4s %-32s %-4s %-32s %s\n' job exit "md5 (old)" exit "md5 (new)" same
  for d in "$out"/old/*/; do
    name=$(basename "$d")
    a=$(h "$out/old/$name")
    b=$(h "$out/new/$name")
    ea=$(cat "$out/old/$name/exit_code")
    eb=$(cat "$out/new/$name/exit_code")
    same=yes
    if [ "$a" != "$b" ] || [ "$ea" != "$eb" ] || [ "$a" = missing ]; then
      same=NO
    fi
    printf '%-52s %-4s %-32s %-4s %-32s %s\n' "$name" "$ea" "$a" "$eb" "$b" "$same"
  done
} >"$out/md5.txt"
cat "$out/md5.txt"
if grep -q ' NO$' "$out/md5.txt"; then status=1; fi
echo "same_histories: ${#list[@]} runs a binary, $((t1 - t0)) s; table in $out/md5.txt" >&2
if [ "$status" != 0 ]; then
  echo "same_histories: DIFFERENT results (see the rows marked NO)" >&2
fi
exit "$status"
