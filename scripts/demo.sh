#!/usr/bin/env bash
# Quick start 1/2: set up, then run the main job on the embedded example (Bourjault's ballpoint pen).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/aplan stats pen "$@"
