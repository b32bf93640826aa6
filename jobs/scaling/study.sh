#!/usr/bin/env bash
# Strong and weak scaling of the distributed runs, for both linear solvers, in one command:
#
#   bash jobs/scaling/study.sh [OUTDIR]          (default OUTDIR: docs/scaling)
#
# Writes OUTDIR/runs.csv (every run, appended as it finishes), OUTDIR/scaling.csv (for every
# study, solver and rank count the fastest of the REPEAT runs) and, with jobs/scaling/plot.py
# (Python 3 standard library only), OUTDIR/speedup.svg and OUTDIR/efficiency.svg.
#
# Job: n_x x n_y elastic, frictionless aluminium discs (penalty contact, so the tangent is
# symmetric) pressed laterally in a die of 10 n_x by 10 n_y mm from solid ratio 0.76, mesh size
# 2.5 mm (32 elements a disc), 4 steps of 0.01 s (both side walls move at 0.4 n_x mm/s).
#   strong scaling: 16 x 16 discs (256 particles, 8 192 elements) on every rank count;
#   weak scaling:   16 discs a rank: 1 rank 4 x 4, 2 ranks 8 x 4, 3 ranks 12 x 4, 4 ranks 8 x 8
#                   (N ranks: 4k x 4k when N = k^2, else 4N x 4).
# Solvers: "cholesky" (the tangent is gathered and rank 0 factors it), "pcg-schwarz"
# (linear = "pcg", preconditioner = "schwarz", pcg_tol = 1e-8: every rank factorises the blocks
# of its own particles; a system it fails on is solved directly on rank 0, counted in the
# direct_fallbacks column) and "mumps" (linear = "petsc": PETSc with MUMPS's distributed LDLt,
# every rank factorising its particles' rows; needs a build with --features petsc) and "parts"
# (linear = "petsc" with the barrier contact instead of the penalty method: each rank holds
# only its own particles and their neighbours, the owned + ghost parts of issue 21) and
# "parts-mg" (the same parts, solved by CG with the particles' two-level preconditioner,
# petsc_options = "-pc_type mg", pcg_tol = 1e-8). Every run: mpirun -n N ... --threads 1 (one thread a rank, also for
# N = 1; THREADS changes it); wall time and phases from the run's summary.json (mpirun's start-up not included);
# assembly_s = element + contact assembly, linear_s = linear solves, peak_mb = the largest peak
# resident memory of the run's ranks (summary.json's peak_memory_mb).
# Time: the default 3 rounds (48 runs) took 4 min 47 s on the shared 2-core development machine
# (load average ~3; one round took 2.5 min at load ~7), see docs/scaling/README.md: the sizes
# above are the ones the issue asks for, not cut back.
#
# Environment:
#   MPFEM      the mpfem binary, built with --features petsc (or mpi, without the mumps solver;
#              default: target/release/mpfem, built with `cargo build --release --features petsc`
#              when missing)
#   RANKS      rank counts (default "1 2 3 4")
#   REPEAT     rounds over all runs (default 3; 1 with QUICK=1); scaling.csv keeps the fastest
#   MESH_SIZE  element size in mm (default 2.5; smaller makes every job larger)
#   THREADS    threads a rank (default 1; 0 = the node's cores divided among its ranks)
#   SOLVERS    the solvers to run (default "cholesky pcg-schwarz mumps parts"; "parts-mg" too)
#   STRONG     the strong study's grid: STRONG x STRONG discs (default 16; 4 with QUICK=1; 32 is
#              the 1,024-disc case)
#   QUICK=1    tiny sizes (4 x 4 discs strong, 2 discs a rank weak, 2 steps), one round: a
#              smoke run of about 20 s
#   OMPI_MCA_mpi_yield_when_idle  default 1 here: ranks waiting in MPI give up the core (more
#              ranks than cores otherwise busy-wait against the rank that works)
# Exit: 0 when every run completed; 1 (with a message) when mpirun or the binary is missing, the
# binary is not an MPI build, or a run fails (the runs so far stay in runs.csv and scaling.csv).
set -euo pipefail

die() { echo "study.sh: $*" >&2; exit 1; }

outdir=${1:-docs/scaling}
mkdir -p "$outdir"
outdir=$(cd "$outdir" && pwd)
here=$(pwd)
cd "$(dirname "$0")/../.."
root=$(pwd)

command -v mpirun >/dev/null 2>&1 || die "mpirun not found (Open MPI: bash scripts/setup.sh installs it)"
command -v python3 >/dev/null 2>&1 || die "python3 not found (needed for summary.json and the plots)"

if [ -n "${MPFEM:-}" ]; then
  case $MPFEM in /*) exe=$MPFEM ;; */*) exe=$here/$MPFEM ;; *) exe=$(command -v "$MPFEM" || echo "$MPFEM") ;; esac
  [ -x "$exe" ] || die "MPFEM=$MPFEM is not an executable file"
else
  exe=$root/${CARGO_TARGET_DIR:-target}/release/mpfem
  case ${CARGO_TARGET_DIR:-} in /*) exe=$CARGO_TARGET_DIR/release/mpfem ;; esac
  if [ ! -x "$exe" ]; then
    echo "study.sh: $exe missing, building it (cargo build --release --features petsc)" >&2
    cargo build --release --locked --features petsc --bin mpfem >&2 || die "the build failed"
    [ -x "$exe" ] || die "the build did not produce $exe"
  fi
fi

ranks_list=${RANKS:-1 2 3 4}
for n in $ranks_list; do
  [[ $n =~ ^[1-9][0-9]*$ ]] || die "RANKS must hold positive integers, got '$ranks_list'"
done
quick=${QUICK:-0}
repeats=${REPEAT:-3}
[ "$quick" = 1 ] && repeats=${REPEAT:-1}
[[ $repeats =~ ^[1-9][0-9]*$ ]] || die "REPEAT must be a positive integer, got '$repeats'"
mesh_size=${MESH_SIZE:-2.5}
# threads per rank (mpfem run --threads): 1 by default; 0 divides the node's cores among the ranks
threads=${THREADS:-1}
solvers=${SOLVERS:-cholesky pcg-schwarz mumps parts}
for s in $solvers; do
  [ "$s" = cholesky ] || [ "$s" = pcg-schwarz ] || [ "$s" = mumps ] || [ "$s" = parts ] || [ "$s" = parts-mg ] || die "SOLVERS must name cholesky, pcg-schwarz, mumps, parts and/or parts-mg, got '$solvers'"
done
[[ $threads =~ ^[0-9]+$ ]] || die "THREADS must be a non-negative integer, got '$threads'"

# (root in containers; local ranks without ssh; waiting ranks yield the core)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_plm=${OMPI_MCA_plm:-isolated}
export OMPI_MCA_mpi_yield_when_idle=${OMPI_MCA_mpi_yield_when_idle:-1}

tmp=$(mktemp -d "${TMPDIR:-/tmp}/mpfem-scaling.XXXXXX")
sampler=
cleanup() {
  [ -n "$sampler" ] && kill "$sampler" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT

if [ "$quick" = 1 ]; then end=0.02; else end=0.04; fi

# case file for an nx x ny disc grid and a solver (cholesky | pcg-schwarz)
write_case() { # file nx ny solver
  local L=$((10 * $2)) Ly=$((10 * $3)) v solver_table contact=penalty
  v=$(awk -v l="$L" 'BEGIN { printf "%g", 0.4 * l }')
  case $4 in
    cholesky) solver_table='linear = "cholesky"' ;;
    pcg-schwarz) solver_table=$'linear = "pcg"\npreconditioner = "schwarz"\npcg_tol = 1e-8' ;;
    mumps) solver_table='linear = "petsc"' ;;
    parts) solver_table='linear = "petsc"' contact=barrier ;;
    parts-mg) solver_table=$'linear = "petsc"\npetsc_options = "-pc_type mg"\npcg_tol = 1e-8' contact=barrier ;;
    *) die "unknown solver $4" ;;
  esac
  cat >"$1" <<EOF
title = "scaling study: $2 x $3 elastic discs, $4"

[[materials]]
name = "alu"
model = "elastic"
youngs_modulus = 64100.0
poisson_ratio = 0.3

[[walls]]
side = "left"
position = 0.0
velocity = $v

[[walls]]
side = "right"
position = $L
velocity = $v

[[walls]]
side = "bottom"
position = 0.0

[[walls]]
side = "top"
position = $Ly

[[grids]]
material = "alu"
nx = $2
ny = $3
shape = "disc"
solid_ratio = 0.76
mesh_size = $mesh_size

[contact]
method = "$contact"

[time]
end = $end
dt = 0.01
dt_max = 0.01

[solver]
$solver_table

[output]
every = 0
EOF
}

launch() { # ranks case out log
  mpirun --oversubscribe --bind-to none -n "$1" "$exe" run "$2" --out "$3" --quiet --no-plots --threads "$threads" >"$4" 2>&1
}

# The binary must be an MPI build: otherwise mpirun starts N independent serial runs.
write_case "$tmp/probe.toml" 2 2 cholesky
launch 2 "$tmp/probe.toml" "$tmp/probe" "$tmp/probe.log" || { tail -20 "$tmp/probe.log" >&2; die "the 2-rank probe run failed ($exe)"; }
grep -q "2 MPI ranks" "$tmp/probe.log" || {
  head -5 "$tmp/probe.log" >&2
  die "$exe is not an MPI build (2 ranks ran as 2 serial runs): build it with cargo build --release --features petsc, or set MPFEM"
}
if [[ " $solvers " == *" mumps "* || " $solvers " == *" parts "* || " $solvers " == *" parts-mg "* ]]; then
  write_case "$tmp/probe-mumps.toml" 2 2 mumps
  launch 2 "$tmp/probe-mumps.toml" "$tmp/probe-mumps" "$tmp/probe-mumps.log" || {
    tail -5 "$tmp/probe-mumps.log" >&2
    die "the mumps solver needs a build with PETSc (cargo build --release --features petsc after bash scripts/setup.sh), or leave it out: SOLVERS=\"cholesky pcg-schwarz\""
  }
fi

csv=$outdir/scaling.csv
runs_csv=$outdir/runs.csv
header=study,solver,ranks,particles,elements,wall_s,assembly_s,linear_s,linear_solves,linear_iterations,status,direct_fallbacks,peak_mb
echo "$header,repeat" >"$runs_csv"
rm -f "$csv"

# scaling.csv: for every (study, solver, ranks) the fastest completed repeat (a failed one if
# none completed), in the order the runs were made
summarise() {
  python3 - "$runs_csv" "$csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1], newline="")))
best, order = {}, []
for r in rows:
    k = (r["study"], r["solver"], r["ranks"])
    if k not in best:
        order.append(k)
        best[k] = r
        continue
    b = best[k]
    ok_r, ok_b = r["status"] == "completed", b["status"] == "completed"
    if (ok_r and not ok_b) or (ok_r and ok_b and float(r["wall_s"]) < float(b["wall_s"])):
        best[k] = r
with open(sys.argv[2], "w", newline="") as f:
    fields = [c for c in rows[0].keys() if c != "repeat"] if rows else []
    w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for k in order:
        w.writerow(best[k])
PY
}

# load average every 10 s while the study runs
(while true; do cut -d" " -f1 /proc/loadavg >>"$tmp/load"; sleep 10; done) </dev/null >/dev/null 2>&1 &
sampler=$!
start_load=$(cut -d' ' -f1-3 /proc/loadavg)
t_start=$(date +%s)

run() { # study solver ranks nx ny repeat
  local name=$1-$2-$3-r$6 row rc=0 fb
  write_case "$tmp/$name.toml" "$4" "$5" "$2"
  printf 'study.sh: [%d/%d] %-6s %-11s %d rank(s), %3d x %-3d discs ... ' "$6" "$repeats" "$1" "$2" "$3" "$4" "$5" >&2
  launch "$3" "$tmp/$name.toml" "$tmp/$name" "$tmp/$name.log" || rc=$?
  # systems the Schwarz solver handed to the direct solve on rank 0 (its warning, rank 0 only)
  fb=$(grep -c "Schwarz.*failed" "$tmp/$name.log" || true)
  row=$(python3 - "$tmp/$name/summary.json" "$1" "$2" "$3" "$(($4 * $5))" "$rc" "$fb" "$6" <<'PY'
import json, sys
path, study, solver, ranks, particles, rc, fb, rep = sys.argv[1:]
try:
    s = json.load(open(path))
except (OSError, ValueError):
    print(f"{study},{solver},{ranks},{particles},,,,,,,no-summary(exit {rc}),{fb},,{rep}")
    sys.exit(0)
t = s["run"]["timing"]
status = s["status"] if rc == "0" else f"{s['status']}(exit {rc})"
print(f"{study},{solver},{ranks},{particles},{s['n_elements']},{s['wall_time_s']:.4f},"
      f"{t['element_assembly'] + t['contact_assembly']:.4f},{t['linear_solve']:.4f},"
      f"{t['linear_solves']},{t['linear_iterations']},{status},{fb},{max(s.get('peak_memory_mb') or [float('nan')]):.0f},{rep}")
PY
  )
  echo "$row" >>"$runs_csv"
  local status
  status=$(cut -d, -f11 <<<"$row")
  if [ "$status" != completed ]; then
    echo "FAILED" >&2
    tail -20 "$tmp/$name.log" >&2
    summarise
    die "run $name failed ($status); the runs so far are in $runs_csv and $csv"
  fi
  echo "$(cut -d, -f6 <<<"$row") s$([ "$fb" -gt 0 ] && echo " ($fb systems solved directly after the Schwarz solver failed)")" >&2
}

if [ "$quick" = 1 ]; then snx=${STRONG:-4}; else snx=${STRONG:-16}; fi
[[ $snx =~ ^[1-9][0-9]*$ ]] || die "STRONG must be a positive integer, got '$snx'"
sny=$snx
weak_grid() { # ranks -> "nx ny"
  if [ "$quick" = 1 ]; then echo "$((2 * $1)) 1"; return; fi
  local k
  k=$(awk -v n="$1" 'BEGIN { k = int(sqrt(n) + 0.5); print (k * k == n) ? k : 0 }')
  if [ "$k" -gt 0 ]; then echo "$((4 * k)) $((4 * k))"; else echo "$((4 * $1)) 4"; fi
}
# the repeats are whole rounds over all runs, so that a burst of load from elsewhere does not
# hit every repeat of one configuration
for rep in $(seq 1 "$repeats"); do
  for solver in $solvers; do
    for n in $ranks_list; do run strong "$solver" "$n" "$snx" "$sny" "$rep"; done
  done
  for solver in $solvers; do
    for n in $ranks_list; do
      read -r wnx wny <<<"$(weak_grid "$n")"
      run weak "$solver" "$n" "$wnx" "$wny" "$rep"
    done
  done
done
summarise

t_end=$(date +%s)
kill "$sampler" 2>/dev/null; wait "$sampler" 2>/dev/null || true; sampler=
load=$(sort -n "$tmp/load" | awk '{ a[NR] = $1; s += $1 } END { printf "min %.2f, mean %.2f, max %.2f", a[1], s / NR, a[NR] }')
note="$(nproc) cores, shared; load average $load"
python3 "$root/jobs/scaling/plot.py" "$csv" --cores "$(nproc)" --note "$note" --date "$(date -u +%Y-%m-%d)"
echo "study.sh: $((t_end - t_start)) s for all runs; load average at the start $start_load, during the runs (every 10 s) $load" >&2
echo "study.sh: wrote $csv, $runs_csv, $outdir/speedup.svg, $outdir/efficiency.svg" >&2
