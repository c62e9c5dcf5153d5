#!/usr/bin/env bash
# Build strike with the `mpi` feature into the target directory "$1" (release) and print the
# binary's path, for tests/mpi.rs. "$2", if given, is the release directory of the build that
# runs the tests: a new target directory starts from a copy of its dependencies' artifacts, so
# that only strike and the crates the feature adds (or builds with other features) are
# compiled (2 min 28 s → 1 min 6 s on this 2-core VM). Installs Debian's OpenMPI
# (libopenmpi-dev, openmpi-bin) and libclang-dev (the MPI bindings' build runs bindgen) only
# where they are missing and apt-get can be used (root, or sudo without a password). Called
# by the test itself, under a lock: `cargo test --release` needs no step before it.
set -euo pipefail
target="$1"
seed="${2:-}"

. "$(dirname "${BASH_SOURCE[0]}")/apt.sh"

have_libclang() {
    ls /usr/lib/llvm-*/lib/libclang*.so* /usr/lib/x86_64-linux-gnu/libclang*.so* >/dev/null 2>&1
}
if ! command -v mpirun >/dev/null 2>&1 || ! command -v mpicc >/dev/null 2>&1 || ! have_libclang; then
    apt_install libopenmpi-dev openmpi-bin libclang-dev
fi
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
if [ -n "$seed" ] && [ -d "$seed/deps" ] && [ ! -e "$target/release" ]; then
    # Cargo names each artifact by a hash of the crate, its version, features and profile, and
    # rebuilds whatever its fingerprint finds stale, so a copy can only save work. strike's own
    # artifacts are left out: they are rebuilt with the feature anyway.
    mkdir -p "$target/release/deps"
    find "$seed/deps" -maxdepth 1 -type f \( -name 'lib*.rlib' -o -name 'lib*.rmeta' \
        -o -name 'lib*.so' -o -name '*.d' \) ! -name 'libstrike-*' ! -name 'strike-*' \
        -exec cp --preserve=timestamps -t "$target/release/deps" {} +
    cp -a "$seed/build" "$seed/.fingerprint" "$target/release/"
fi
"${CARGO:-cargo}" build --release --features mpi --bin strike --target-dir "$target" >&2
echo "$target/release/strike"
