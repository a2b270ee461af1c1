#!/usr/bin/env bash
# Quick start 2/2: set up (FreeCAD included where apt can install it), then run the whole test suite.
# APLAN_REQUIRE_FREECAD=1 and APLAN_REQUIRE_ROS=1 (set by CI) turn a missing FreeCAD or ROS 1 into a failure
# instead of a skip.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --freecad --ros
exec .venv/bin/python -m pytest -q "$@"
