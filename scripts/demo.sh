#!/usr/bin/env bash
# Quick start 1/2: set up, then run the main job on the embedded example (Bourjault's ballpoint pen): the plan, a
# policy, a simulated camera session in which the robot decides, and the belief figure (scripts/demo.py; the
# outputs go to demo/, replaced by each run; options: --out DIR, --sequence K, --trials N).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/python scripts/demo.py "$@"
