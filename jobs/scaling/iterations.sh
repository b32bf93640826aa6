#!/usr/bin/env bash
# Krylov iterations per Newton solve of PETSc's iterative preconditioners against the number of
# particles (issue 21's benchmark; a documented command, not a test): the elastic disc grid of
# discs_32x32_parts.toml at N x N discs for N in SIZES, two steps of 0.1 s (the loose start and
# the first loaded step), on 2 ranks on owned + ghost parts, once per preconditioner in PCS
# (`-pc_type mg`: the particles' two-level preconditioner; `gamg`: algebraic multigrid).
#
#   bash jobs/scaling/iterations.sh [OUT]          # SIZES="8 16 32 64" PCS="mg" by default
#   SIZES="8" PCS="gamg" TIMEOUT=600 bash jobs/scaling/iterations.sh
#
# Needs a build with PETSc (`cargo build --release --features petsc`) and Open MPI. Prints
# one line a run: discs, preconditioner, free dofs, steps, Newton iterations, linear solves,
# Krylov iterations, iterations a solve, wall time (s), linear-solve time (s), peak memory of
# the larger rank (MB), how the run ended. Units: mm, N, MPa, s.
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$(pwd)
out=${1:-$(mktemp -d)}
mkdir -p "$out"
bin=${MPFEM:-$root/target/release/mpfem}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_plm=isolated
echo "discs pc free_dofs steps newton solves krylov per_solve wall_s solve_s peak_mb end"
for n in ${SIZES:-8 16 32 64}; do
  for pc in ${PCS:-mg}; do
    w=$((10 * n))
    case_file="$out/discs_${n}x${n}_$pc.toml"
    sed -e "s/^nx = 32/nx = $n/; s/^ny = 32/ny = $n/; s/= 320.0/= $w.0/; s/^end = 0.3/end = 0.2/" \
        -e "s/^linear = \"petsc\"/linear = \"petsc\"\npetsc_options = \"-pc_type $pc\"\npcg_tol = 1e-10/" \
        jobs/scaling/discs_32x32_parts.toml > "$case_file"
    grep -q "nx = $n" "$case_file" && grep -q -- "-pc_type $pc" "$case_file" || { echo "the case moved: $case_file" >&2; exit 1; }
    run="$out/discs_${n}x${n}_$pc"
    timeout "${TIMEOUT:-3600}" mpirun --oversubscribe --bind-to none -n 2 "$bin" run "$case_file" --out "$run" \
      --no-plots --threads 1 -q > "$run.log" 2>&1 || true
    python3 - "$run/summary.json" "$((n * n))" "$pc" <<'PY'
import json, sys
path, discs, pc = sys.argv[1:]
try:
    s = json.load(open(path))
except (OSError, ValueError) as e:
    print(discs, pc, "no summary:", e)
    sys.exit(0)
r = s.get("run") or {}
t = r.get("timing") or {}
solves = t.get("linear_solves") or 0
its = t.get("linear_iterations") or 0
peak = max(s.get("peak_memory_mb") or [0])
print(discs, pc, r.get("n_free"), r.get("steps"), r.get("newton_iterations"), solves, its,
      round(its / solves, 1) if solves else "-", round(s.get("wall_time_s") or 0, 1),
      round(t.get("linear_solve") or 0, 1), round(peak), r.get("stop_reason") or s.get("error"))
PY
  done
done
