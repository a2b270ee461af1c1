"""The solver's time limit is a limit (issue 14, item 9): ``aplan solve`` with a limit, timed from outside.

    .venv/bin/python bench/bench_time_limit.py            # about 2 minutes

Each row runs the command line in a fresh process and reports the solver's own seconds (``--json``: its set-up
included, the model's construction and the policy's writing not: those are the ``model_seconds`` and
``write_seconds`` columns) and the whole command's wall time. Rows:
the pen with a discount of 0.99999 (value iteration for the upper bound would need over 100,000 sweeps) and
the flat model of a 9-part chain (109,601 intentions; before issue 14: 89 s for a 10 s limit).
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CASES = [
    ("pen, discount 0.99999", ["pen", "--discount", "0.99999"], 2),
    ("pen", ["pen"], 2),
    ("chain 9 (flat, 109,601 states)", ["{folder}/chain9.json"], 10),
]


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        subprocess.run([sys.executable, "-m", "planner", "synth", "chain", "9", "-o", f"{folder}/chain9.json"],
                       check=True)
        print("| case | --time-limit s | solver s | model s | policy writing s | command wall s | lower | upper |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|")
        for name, arguments, limit in CASES:
            command = [sys.executable, "-m", "planner", "solve", *[a.format(folder=folder) for a in arguments],
                       "-o", str(Path(folder) / "p.policy"), "--time-limit", str(limit), "--json", "--force"]
            start = time.perf_counter()
            done = subprocess.run(command, capture_output=True, text=True, check=True)
            wall = time.perf_counter() - start
            result = json.loads(done.stdout)
            print(f"| {name} | {limit} | {result['seconds']:.2f} | {result['model_seconds']:.1f} | "
                  f"{result['write_seconds']:.1f} | {wall:.1f} | {result['lower_bound']:.4f} | "
                  f"{result['upper_bound']:.4f} |", flush=True)


if __name__ == "__main__":
    main()
