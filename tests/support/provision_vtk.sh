#!/usr/bin/env bash
# Provision a Python virtual environment with VTK's own Python package at "$1", for the tests
# that read strike's output files back with VTK's reader (tests/vtk_check.py). Called by the
# tests themselves (tests/support/mod.rs), once, under a lock: `cargo test --release` needs no
# step before it. Installs Debian's python3-venv and the few X/GL libraries VTK's wheel links
# only where they are missing and apt-get can be used (root, or sudo without a password).
set -euo pipefail
venv="$1"

. "$(dirname "${BASH_SOURCE[0]}")/apt.sh"

if ! "$venv/bin/python" -c 'import sys' 2>/dev/null; then
    rm -rf "$venv"
    if ! python3 -m venv "$venv" >&2; then
        rm -rf "$venv"
        apt_install python3-venv
        python3 -m venv "$venv" >&2
    fi
fi
if ! "$venv/bin/python" -c 'import vtk' 2>/dev/null; then
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check vtk >&2
fi
if ! "$venv/bin/python" -c 'import vtk' 2>/dev/null; then
    # The wheel is there but a shared library it links is not.
    apt_install libgl1 libxrender1 libxext6 libx11-6 libxt6 || true
fi
"$venv/bin/python" -c 'import vtk; print("vtk", vtk.vtkVersion.GetVTKVersion())'
