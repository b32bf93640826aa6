#!/usr/bin/env bash
# Parallel HDF5 against the gathered write, for one output step at 10⁵ and 10⁶ nodes
# (benches/phdf5; the figures are in docs/scaling/README.md, "Output at 10⁵ and 10⁶ nodes").
#
#   scripts/phdf5_bench.sh            # 1, 2 and 4 ranks; times to close, then to fsync
#   RANKS="2" SYNCS="0" REPS=3 scripts/phdf5_bench.sh
#
# Installs Debian's libhdf5-openmpi-dev when it is missing (as root) while keeping the serial
# HDF5 the default that pkg-config (and so mpfem's build) finds: the package registers
# hdf5-mpi.pc as a higher-priority alternative for hdf5.pc, so hdf5.pc is pinned to
# hdf5-serial.pc first. The benchmark crate is built against the MPI flavour through HDF5_DIR
# and its own target folder. Temporary files (up to about 160 MB at a time) go to $PHDF5_DIR,
# default the system temp folder, and are removed.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
ranks="${RANKS:-1 2 4}"
syncs="${SYNCS:-0 1}"
export REPS="${REPS:-5}"
target="${CARGO_TARGET_DIR:-$root/target/phdf5}"
mpi_hdf5=/usr/lib/x86_64-linux-gnu/hdf5/openmpi
serial_pc=/usr/lib/x86_64-linux-gnu/pkgconfig/hdf5-serial.pc

if ! dpkg-query -W -f='${Status}' libhdf5-openmpi-dev 2>/dev/null | grep -q "ok installed"; then
    if [ "$(id -u)" != 0 ]; then
        echo "libhdf5-openmpi-dev is missing; install it as root (this script does so when run as root)" >&2
        exit 1
    fi
    if [ -e "$serial_pc" ]; then
        update-alternatives --set hdf5.pc "$serial_pc"
    fi
    apt-get update -qq || true
    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends libhdf5-openmpi-dev
fi
if [ -e "$serial_pc" ] && [ "$(readlink -f /usr/lib/x86_64-linux-gnu/pkgconfig/hdf5.pc)" != "$serial_pc" ]; then
    if [ "$(id -u)" = 0 ]; then
        update-alternatives --set hdf5.pc "$serial_pc"
    else
        echo "warning: hdf5.pc does not point to the serial HDF5; mpfem's next clean build would link the MPI one" >&2
    fi
fi
echo "hdf5.pc -> $(readlink -f /usr/lib/x86_64-linux-gnu/pkgconfig/hdf5.pc) (what mpfem's build finds)"

HDF5_DIR="$mpi_hdf5" CARGO_TARGET_DIR="$target" \
    cargo build --release --locked --manifest-path "$root/benches/phdf5/Cargo.toml"
bin="$target/release/phdf5-bench"

if [ "$(id -u)" = 0 ]; then
    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
export OMPI_MCA_plm="${OMPI_MCA_plm:-isolated}"

out="$(mktemp)"
trap 'rm -f "$out"' EXIT
echo "before: $(uptime)"
for s in $syncs; do
    for n in $ranks; do
        echo "== mpirun -n $n, SYNC=$s"
        SYNC="$s" mpirun -n "$n" --oversubscribe "$bin" | tee -a "$out"
    done
done
echo "after:  $(uptime)"

# one row a (nodes, ranks, sync): median (min) in ms of each method
echo
echo "| nodes | bytes per step | ranks | to | gathered | (gather) | gathered, buffers reused | (gather) | parallel, collective | parallel, independent | bare (1 rank) |"
echo "|--:|--:|--:|--|--:|--:|--:|--:|--:|--:|--:|"
awk '
/^RESULT/ {
    for (i = 2; i <= NF; i++) { split($i, kv, "="); f[kv[1]] = kv[2] }
    key = f["nodes"] " " f["ranks"] " " f["sync"]
    if (!(key in seen)) { seen[key] = 1; order[++n] = key; bytes[key] = f["bytes"] }
    cell[key, f["method"]] = sprintf("%.1f (%.1f)", f["median_ms"], f["min_ms"])
    if ("gather_median_ms" in f) gather[key, f["method"]] = sprintf("%.1f", f["gather_median_ms"])
    delete f
}
END {
    for (k = 1; k <= n; k++) {
        key = order[k]; split(key, p, " ")
        printf "| %s | %.1f MB | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", p[1], bytes[key] / 1e6, p[2],
            (p[3] == 1 ? "fsync" : "close"), cell[key, "gathered"], gather[key, "gathered"],
            cell[key, "gathered_reused"], gather[key, "gathered_reused"], cell[key, "parallel_collective"],
            cell[key, "parallel_independent"], cell[key, "bare"]
    }
}' "$out" | sort -t'|' -k2,2n -k4,4n -k5,5
echo
echo "(median (min) ms of $REPS repetitions after a warm-up; each from a barrier to the close of the file, or to its fsync; (gather) is the median of the gathers alone)"
