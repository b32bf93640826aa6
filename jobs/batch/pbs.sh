#!/usr/bin/env bash
# PBS Pro / Torque batch template for mpfem, with checkpoint and rerun on pre-emption.
#
#   qsub -v CASE=my_case.toml,OUT=out jobs/batch/pbs.sh
#
# PBS sends SIGTERM (then SIGKILL after its kill delay) at the wall-time limit or on
# pre-emption; this script passes it on, mpfem finishes its current step, writes
# $OUT/checkpoint.h5 and exits 3, and the job asks to be rerun (`qrerun`). The rerun finds the
# checkpoint and continues from it. Set the server's kill delay above the time of one step.
#PBS -N mpfem
#PBS -l select=1:ncpus=4:mpiprocs=4
#PBS -l walltime=02:00:00
#PBS -r y
#PBS -j oe
# Overridable for a dry run outside PBS: LAUNCH (default "mpirun"), REQUEUE (default
# "qrerun"), MPFEM (default: mpfem on PATH).
set -uo pipefail

cd "${PBS_O_WORKDIR:-.}" || exit 2
: "${CASE:?set CASE to the case file (qsub -v CASE=...)}"
OUT=${OUT:-out}
mpfem=${MPFEM:-mpfem}
read -r -a launch <<< "${LAUNCH-mpirun}"
read -r -a requeue <<< "${REQUEUE:-qrerun}"
# Open MPI's mpirun kills its ranks 1 s after it passes them a SIGTERM
# (odls_base_sigkill_timeout = 1), too soon for the checkpoint of a large model (a
# 4,096-particle checkpoint of 110 MB was cut at 77 MB): give them 120 s.
export OMPI_MCA_odls_base_sigkill_timeout=${OMPI_MCA_odls_base_sigkill_timeout:-120}

cmd=("$mpfem" run "$CASE" --out "$OUT" --quiet)
if [ -f "$OUT/checkpoint.h5" ]; then
  echo "pbs: continuing from $OUT/checkpoint.h5"
  cmd+=(--restart "$OUT")
fi

"${launch[@]}" "${cmd[@]}" &
pid=$!
trap 'kill -TERM "$pid" 2>/dev/null' TERM INT
wait "$pid"
code=$?
while kill -0 "$pid" 2>/dev/null; do
  wait "$pid"
  code=$?
done

# exit code 3: stopped with a checkpoint (a launcher may report another non-zero code for
# it, e.g. Open MPI's mpirun after a forwarded SIGTERM: summary.json then says "interrupted")
if [ "$code" -eq 3 ] || { [ "$code" -ne 0 ] && grep -q '"status": *"interrupted"' "$OUT/summary.json" 2>/dev/null; }; then
  echo "pbs: stopped with a checkpoint, asking for a rerun of ${PBS_JOBID:-?}"
  "${requeue[@]}" "${PBS_JOBID:-0}"
fi
exit "$code"
