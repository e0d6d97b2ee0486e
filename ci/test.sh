#!/usr/bin/env bash
# The README's test command. Installs what the tests need (Debian packages for
# the `reference` feature: SUNDIALS is built from the sundials-sys crate's own
# sources with cmake, HDF5 comes from Debian), then runs the default-feature
# tests and the reference tests. Works on a fresh Debian 12 machine with Rust.
set -euo pipefail
cd "$(dirname "$0")/.."
# A build from scratch gains nothing from incremental caches (writing them
# made the crate's test build 9% slower: 144 → 132 s without).
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"

if [ -f ci/install-reference.sh ]; then
  bash ci/install-reference.sh
fi

echo "== cargo test (default features)"
cargo test --locked
echo "== cargo test --features reference"
cargo test --locked --features reference
echo "== cargo test --features mumps (MUMPS, mpirun -n 2)"; cargo test --locked --features mumps --test linalg_mumps
