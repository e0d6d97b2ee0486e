#!/usr/bin/env bash
# System packages that `cargo build --features reference` needs (Debian).
#  - cmake, a C compiler: sundials-sys builds SUNDIALS 7.1.1 from the crate's
#    own sources (features build_libraries + static_libraries), which avoids
#    Debian's libsundials-dev and the PETSc/OpenMPI stack it pulls in.
#  - libclang-dev: bindgen (sundials-sys and hdf5-metno-sys generate bindings).
#  - libhdf5-dev, pkg-config: the serial HDF5 library for the hdf5 crate
#    (.cargo/config.toml sets HDF5_NO_PKG_CONFIG=1 so that an OpenMPI HDF5
#    installed alongside is not picked).
#  - parallel: GNU parallel, for the test that runs a sweep item by item on
#    2 workers (tests/run/sweeps.rs; it fails without it under CI=true).
# Idempotent: apt-get install skips what is already there.
set -euo pipefail

packages=(cmake build-essential libclang-dev libhdf5-dev pkg-config)
packages+=(libmumps-dev openmpi-bin libopenmpi-dev)  # --features mumps (MUMPS 5 + OpenMPI, src/linalg/mumps.rs)
packages+=(parallel)  # tests/run/sweeps.rs: sweeps item by item under GNU parallel

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done

if [ "${#missing[@]}" -eq 0 ]; then
    echo "install-reference: all present: ${packages[*]}"
    exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    SUDO="sudo"
fi
echo "install-reference: installing ${missing[*]}"
$SUDO apt-get update -qq
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
