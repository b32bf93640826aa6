#!/usr/bin/env bash
# Install what a fresh Debian/Ubuntu machine with only the Rust toolchain lacks to build mpfem.
# Idempotent: installs only missing packages (needs root or sudo for apt-get).
set -euo pipefail

need=()
# C compiler: also builds METIS from the sources bundled with the metis-sys crate (partition/)
command -v cc >/dev/null 2>&1 || need+=(gcc libc6-dev)
command -v pkg-config >/dev/null 2>&1 || need+=(pkg-config)
command -v make >/dev/null 2>&1 || need+=(make)
# HDF5 C library and headers for the hdf5-metno crate (results.h5)
dpkg -s libhdf5-dev >/dev/null 2>&1 || need+=(libhdf5-dev)
# a TrueType font for the text of the plots (src/plot.rs reads DejaVu Sans at run time)
dpkg -s fonts-dejavu-core >/dev/null 2>&1 || need+=(fonts-dejavu-core)
# ParaView's Python, headless, for tests/paraview.rs (opens results.xdmf like a user would)
command -v pvpython >/dev/null 2>&1 || need+=(paraview python3-paraview)
command -v xvfb-run >/dev/null 2>&1 || need+=(xvfb)
command -v xauth >/dev/null 2>&1 || need+=(xauth)
# Python with pip for the IPC toolkit's bindings below
command -v python3 >/dev/null 2>&1 || need+=(python3 python3-pip)
# Open MPI (mpirun, headers) and libclang (bindgen of the mpi-sys crate) for the `mpi` feature
# and tests/mpi_ranks.rs
command -v mpirun >/dev/null 2>&1 || need+=(openmpi-bin)
dpkg -s libopenmpi-dev >/dev/null 2>&1 || need+=(libopenmpi-dev)
dpkg -s libclang-dev >/dev/null 2>&1 || need+=(libclang-dev)
# PETSc 3.18 (with MUMPS, hypre, SuperLU_DIST, built against the same Open MPI) for the
# `petsc` feature: the distributed linear solves ([solver] linear = "petsc", petsc/)
dpkg -s libpetsc-real-dev >/dev/null 2>&1 || need+=(libpetsc-real-dev)
# an optimised BLAS for MUMPS's dense kernels (Debian's PETSc links the reference BLAS by
# default: its factorisations took 2.1 times as long, docs/scaling/README.md); the serial
# build, so that MPI ranks do not start BLAS threads on each other's cores
dpkg -s libopenblas0-serial >/dev/null 2>&1 || need+=(libopenblas0-serial)
# CalculiX (ccx) for the peer benchmark against another solver (scripts/peer_bench.sh,
# docs/peer.md) and its cross-check test tests/peer_calculix.rs
command -v ccx >/dev/null 2>&1 || need+=(calculix-ccx)

if ((${#need[@]})); then
  echo "setup: installing ${need[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${need[@]}"
fi

# the IPC toolkit's Python bindings (ipctk 1.6.1 from PyPI): the reference values of the
# barrier contact in tests/barrier_ipctk.rs, which calls the `python3` on PATH
if [ "$(python3 -c 'import ipctk; print(ipctk.__version__)' 2>/dev/null)" != "1.6.1" ]; then
  echo "setup: installing ipctk 1.6.1 for $(command -v python3)"
  python3 -m pip install --quiet ipctk==1.6.1 || python3 -m pip install --quiet --break-system-packages ipctk==1.6.1
fi

if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo not found; install the Rust toolchain (rustup) first" >&2
  exit 1
fi
echo "setup: system packages OK ($(cargo --version))"
