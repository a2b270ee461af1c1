"""`aplan stats` on every FreeCAD document in ../shared/models: wall time, peak memory, and what it printed.

Each document runs in a fresh process, as a user would run it:

    /usr/bin/time -v timeout 120 prlimit --as=8000000000 aplan stats MODEL.FCStd --json

(FreeCADCmd exports the document into a temporary bundle, the mesh engine analyses it, the planner counts).
Peak MiB is GNU time's maximum resident set size: that of the largest process of the run (FreeCADCmd or the
planner). Prints a Markdown table for bench/README.md.

    .venv/bin/python bench/bench_guards.py                 # about 10 minutes (33 documents)
    .venv/bin/python bench/bench_guards.py --only asm_      # the assemblies alone
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
MODELS = REPO.parent / "shared" / "models"
APLAN = [sys.executable, "-m", "planner"]


def run_stats(model: Path, timeout: int, address_space: int) -> dict:
    command = ["/usr/bin/time", "-v", "timeout", str(timeout), "prlimit", f"--as={address_space}", *APLAN,
               "stats", str(model), "--json"]
    done = subprocess.run(command, capture_output=True, text=True, cwd=REPO)
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", done.stderr).group(1)
    seconds = sum(float(x) * 60 ** i for i, x in enumerate(reversed(wall.split(":"))))
    peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr).group(1)) / 1024
    status = int(re.search(r"Exit status: (\d+)", done.stderr).group(1))
    return {"seconds": seconds, "peak_mib": peak, "status": status, "stdout": done.stdout,
            "stderr": "\n".join(line for line in done.stderr.splitlines() if line.startswith("aplan"))}


def summary(result: dict) -> str:
    """The figures printed, or the refusal's first words."""
    if result["status"] == 124:
        return "killed by timeout"
    try:
        data = json.loads(result["stdout"])
    except json.JSONDecodeError:
        message = result["stderr"].removeprefix("aplan: error: ")
        return "error: " + (message[:110] + " ..." if len(message) > 110 else message)
    figures = ", ".join(f"{k} {v:,}" if isinstance(v, int) else f"{k} {v}" for k, v in data.items()
                        if v is not None and k in ("parts", "contacts", "subassemblies", "states", "intentions",
                                                   "sequences"))
    if "not_computed" in data:
        reason = data["not_computed"]["reason"]
        figures += "; not computed: " + reason.split(". ")[0]
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="", help="only documents whose name contains this")
    parser.add_argument("--timeout", type=int, default=120)
    parser.add_argument("--address-space", type=int, default=8_000_000_000)
    args = parser.parse_args()
    models = sorted(p for p in MODELS.rglob("*.FCStd") if args.only in p.name)
    print("load average before: %.2f %.2f %.2f" % os.getloadavg())
    print("| document | exit | wall s | peak MiB | printed |")
    print("|---|---:|---:|---:|---|")
    for model in models:
        result = run_stats(model, args.timeout, args.address_space)
        print(f"| {model.relative_to(MODELS)} | {result['status']} | {result['seconds']:.1f} | "
              f"{result['peak_mib']:.0f} | {summary(result)} |", flush=True)
    print("load average after: %.2f %.2f %.2f" % os.getloadavg())


if __name__ == "__main__":
    main()
