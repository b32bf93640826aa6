#!/usr/bin/env bash
# Run an mpfem case on this machine, resuming from its checkpoint when there is one.
#
#   jobs/batch/run_local.sh CASE.toml OUT_DIR [RANKS]
#
# RANKS > 1 starts `mpirun -n RANKS` (an mpfem built with `--features mpi`); as root it adds
# --allow-run-as-root, and --oversubscribe when RANKS exceeds the cores. Environment:
#   MPFEM    the mpfem binary (default: mpfem on PATH)
#   MPIRUN   the MPI launcher (default: mpirun)
# SIGTERM/SIGINT are passed on to mpfem, which finishes its step, writes OUT_DIR/checkpoint.h5
# and exits 3; running this script again continues from there.
# Exit code: mpfem's (0 done, 1 failed step, 2 bad input, 3 stopped with a checkpoint).
set -uo pipefail

if [ $# -lt 2 ]; then
  echo "usage: $0 CASE.toml OUT_DIR [RANKS]" >&2
  exit 2
fi
case_file=$1
out=$2
ranks=${3:-1}
mpfem=${MPFEM:-mpfem}

cmd=("$mpfem" run "$case_file" --out "$out")
if [ -f "$out/checkpoint.h5" ]; then
  echo "run_local: $out/checkpoint.h5 found, continuing from it" >&2
  cmd+=(--restart "$out")
fi
if [ "$ranks" -gt 1 ]; then
  launch=("${MPIRUN:-mpirun}" -n "$ranks" --bind-to none)
  [ "$(id -u)" -eq 0 ] && launch+=(--allow-run-as-root)
  [ "$ranks" -gt "$(nproc)" ] && launch+=(--oversubscribe)
  # Open MPI's mpirun kills its ranks 1 s after it passes them a SIGTERM
  # (odls_base_sigkill_timeout = 1), too soon for the checkpoint of a large model (a
  # 4,096-particle checkpoint of 110 MB was cut at 77 MB): give them 120 s.
  export OMPI_MCA_odls_base_sigkill_timeout=${OMPI_MCA_odls_base_sigkill_timeout:-120}
  cmd=("${launch[@]}" "${cmd[@]}")
fi

# run in the background so that a signal to this script reaches mpfem
"${cmd[@]}" &
pid=$!
trap 'kill -TERM "$pid" 2>/dev/null' TERM INT
wait "$pid"
code=$?
# a trapped signal interrupts `wait`: wait again for mpfem's own exit code
while kill -0 "$pid" 2>/dev/null; do
  wait "$pid"
  code=$?
done
exit "$code"
