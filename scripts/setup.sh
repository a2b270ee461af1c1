#!/usr/bin/env bash
# Set up APLAN in ./.venv (idempotent). With --freecad, also install Debian's FreeCAD 0.20 (headless
# freecadcmd, the GUI and Xvfb) and the Python packages FreeCAD's own interpreter needs, when they are
# missing and apt can be used (as root, or through passwordless sudo). FreeCAD's own Python gets Debian's
# numpy, networkx, lxml, scipy, matplotlib, jsonschema and threadpoolctl (the planner, the occt engine, solving,
# pictures);
# the mesh engine's trimesh and manifold3d are not packaged by Debian, so the workbench runs that engine in
# this .venv.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
.venv/bin/python -m pip install --quiet --disable-pip-version-check -e '.[test]'

# Debian's FreeCAD runs the system Python 3: it needs these modules too (also where FreeCAD is installed already).
freecad_ready() {
    command -v freecadcmd >/dev/null 2>&1 && command -v xvfb-run >/dev/null 2>&1 &&
        /usr/bin/python3 -c "import numpy, networkx, lxml, scipy, matplotlib, jsonschema, threadpoolctl" 2>/dev/null
}

if [ "${1:-}" = "--freecad" ] && ! freecad_ready; then
    if [ "$(id -u)" = 0 ]; then as_root=(); elif sudo -n true 2>/dev/null; then as_root=(sudo -n); else as_root=(); fi
    if command -v apt-get >/dev/null 2>&1 && { [ "$(id -u)" = 0 ] || [ ${#as_root[@]} -gt 0 ]; }; then
        echo "setup: installing FreeCAD and its Python packages from Debian (about a minute)" >&2
        "${as_root[@]}" apt-get update -qq
        DEBIAN_FRONTEND=noninteractive "${as_root[@]}" apt-get install -y -qq --no-install-recommends \
            freecad-python3 freecad xvfb xauth python3-numpy python3-networkx python3-lxml python3-scipy \
            python3-matplotlib python3-jsonschema python3-threadpoolctl >/dev/null
    else
        echo "setup: FreeCAD (or a Python package it needs) is missing and apt-get cannot be used here: FreeCAD tests will be skipped" >&2
    fi
fi
