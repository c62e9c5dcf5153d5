#!/usr/bin/env bash
# Build strike with the `mpi` feature into the target directory "$1" (release) and print the
# binary's path, for tests/mpi.rs. Installs Debian's OpenMPI (libopenmpi-dev, openmpi-bin) and
# libclang-dev (the MPI bindings' build runs bindgen) only where they are missing and apt-get
# can be used (root, or sudo without a password). Called by the test itself, under a lock:
# `cargo test --release` needs no step before it.
set -euo pipefail
target="$1"

. "$(dirname "${BASH_SOURCE[0]}")/apt.sh"

have_libclang() {
    ls /usr/lib/llvm-*/lib/libclang*.so* /usr/lib/x86_64-linux-gnu/libclang*.so* >/dev/null 2>&1
}
if ! command -v mpirun >/dev/null 2>&1 || ! command -v mpicc >/dev/null 2>&1 || ! have_libclang; then
    apt_install libopenmpi-dev openmpi-bin libclang-dev
fi
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
"${CARGO:-cargo}" build --release --features mpi --bin strike --target-dir "$target" >&2
echo "$target/release/strike"
