#!/usr/bin/env bash
# Quick start 2/2: set up (FreeCAD included where apt can install it), then run the whole test suite.
# APLAN_REQUIRE_FREECAD=1 (set by CI) turns a missing FreeCAD into a failure instead of a skip.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --freecad
exec .venv/bin/python -m pytest -q "$@"
