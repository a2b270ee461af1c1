"""Real products end to end (issue 13): from the .FCStd in ../shared/models to a finished simulated session,
as a user runs it, timed stage by stage, each stage a fresh process under one BLAS thread:

    export   aplan export-freecad MODEL -o BUNDLE [model options]        (FreeCADCmd, then the mesh engine)
    stats    aplan stats BUNDLE --fasteners auto --subassemblies auto
    session  aplan session BUNDLE --fasteners auto --subassemblies auto --demo 0 --log LOG
    whole    aplan session MODEL.FCStd [model options] --fasteners auto --subassemblies auto --demo 0 --log LOG
             (with model options: export, then session on the bundle, timed together)

Wall seconds, CPU seconds (user + system: what the stage costs one core, whatever else the machine runs) and
peak MiB (GNU time's maximum resident set size) per stage, and what the session printed at the end of each
level. Prints a Markdown table for bench/README.md.

    .venv/bin/python bench/bench_real_products.py            # about 6 minutes
    .venv/bin/python bench/bench_real_products.py --only truck
"""
from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
MODELS = REPO.parent / "shared" / "models"
APLAN = [sys.executable, "-m", "planner"]
PLAN = ["--fasteners", "auto", "--subassemblies", "auto"]

# name: (document, export options): the defaults, as a new user runs it. The pump's manifold shell 21_001 and its
# part 26_001 overlap by 1,434 mm^3 in the model and block each other along every axis: the interlock rules insert
# 26_001 along the overlap's axis (README, "Real products"; before, --group outlet=21_001,26_001 was needed).
PRODUCTS = {
    "truck": (MODELS / "toy_truck" / "asm_cement_mixer_truck.FCStd", []),
    "pump": (MODELS / "diaphragm_pump" / "asm_diaphragm_pump.FCStd", []),
}


def _timed(command: list[str], timeout: float) -> tuple[float, float, float, int, str]:
    """(wall seconds, CPU seconds, peak MiB, exit status, output) of ``command`` under GNU time."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    done = subprocess.run(["/usr/bin/time", "-f", "TIME %e %U %S %M", "timeout", str(timeout), *command],
                          capture_output=True, text=True, env=env, cwd=REPO)
    match = re.search(r"TIME ([\d.]+) ([\d.]+) ([\d.]+) (\d+)", done.stderr)
    if match is None:
        return float("nan"), float("nan"), 0.0, done.returncode, done.stdout + done.stderr
    wall, user, system, kib = float(match.group(1)), float(match.group(2)), float(match.group(3)), int(match.group(4))
    return wall, user + system, kib / 1024, done.returncode, done.stdout + done.stderr


def run(name: str, folder: Path) -> list[tuple]:
    model, options = PRODUCTS[name]
    bundle, rows = folder / name, []
    steps = [("export", APLAN + ["export-freecad", str(model), "-o", str(bundle), *options]),
             ("stats", APLAN + ["stats", str(bundle), *PLAN]),
             ("session", APLAN + ["session", str(bundle), *PLAN, "--demo", "0", "--log", str(folder / f"{name}.jsonl")]),
             ("whole", APLAN + ["session", str(model), *options, *PLAN, "--demo", "0", "--log",
                                str(folder / f"{name}-whole.jsonl")])]
    for stage, command in steps:
        seconds, cpu, mib, status, output = _timed(command, 900)
        levels = len(re.findall(r"^level \S+ \(\d+ of \d+\)", output, re.M))
        assembled = len(re.findall(r"^assembled:", output, re.M))
        last = next((line for line in reversed(output.splitlines()) if line.strip() and not line.startswith(("TIME ", "Command exited"))),
                    "")
        rows.append((name, stage, status, seconds, cpu, mib, f"{assembled} of {levels} levels assembled" if levels
                     else last[:160]))
        if status != 0:
            break
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=sorted(PRODUCTS))
    args = parser.parse_args()
    print("| product | stage | exit | seconds | CPU s | peak MiB | result |")
    print("|---|---|---:|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory(prefix="aplan-real-") as folder:
        for name in [args.only] if args.only else list(PRODUCTS):
            for row in run(name, Path(folder)):
                print("| {} | {} | {} | {:.1f} | {:.1f} | {:.0f} | {} |".format(*row), flush=True)


if __name__ == "__main__":
    main()
