#!/usr/bin/env bash
# Create the Python environment used by the VTK file tests (tests/vtk_check.py):
# .venv at the repository root with VTK's own Python package.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
if [ -x .venv/bin/python ] && .venv/bin/python -c 'import vtk' 2>/dev/null; then
    echo "setup_python: .venv already has vtk $(.venv/bin/python -c 'import vtk; print(vtk.vtkVersion.GetVTKVersion())')"
    exit 0
fi
if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet vtk
.venv/bin/python -c 'import vtk; print("setup_python: vtk", vtk.vtkVersion.GetVTKVersion())'
