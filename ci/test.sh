#!/usr/bin/env bash
# The README's test command. Installs what the tests need (Debian packages for
# the `reference` feature: SUNDIALS is built from the sundials-sys crate's own
# sources with cmake, HDF5 comes from Debian), checks that the default build
# (what `cargo run --release` builds) compiles, then runs every test with the
# reference feature. Works on a fresh Debian 12 machine with Rust.
set -euo pipefail
cd "$(dirname "$0")/.."
# A build from scratch gains nothing from incremental caches (writing them
# made the crate's test build 9% slower: 144 → 132 s without).
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"

if [ -f ci/install-reference.sh ]; then
  bash ci/install-reference.sh
fi

# The default features only leave out the reference solvers: every test but
# the reference ones is the same code with or without them (the two
# `cfg(not(feature = "reference"))` stubs in src/study/bench.rs and the HDF5
# stubs aside), so running the suite twice cost a build and ~2.5 minutes of
# tests for nothing; `cargo check` compiles the default build, stubs
# included, in ~2.5 minutes. Measured on fresh clones (packages installed):
# 1,064 s with both test runs, 831 s with the check.
echo "== cargo check (default features)"
cargo check --locked --all-targets
echo "== cargo test --features reference"
cargo test --locked --features reference
echo "== cargo test --features mumps (MUMPS, mpirun -n 2)"; cargo test --locked --features mumps --test linalg_mumps
