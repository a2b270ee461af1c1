"""The builtin solver on the lumped model (classes instead of intentions): bounds at the initial belief over
time, time to a gap of 0.05, peak memory.

Run: ``.venv/bin/python bench/bench_lumped.py [--time-limit 60] [--cpu] [PRODUCT ...]`` (about the time limit
per product; prints a Markdown table). Each product runs in a fresh subprocess, so its peak resident memory
(ru_maxrss) is its own: the model built, the solver run (one BLAS thread: the solver picks it below 10,000
states). The limit counts the upper bound's start (:func:`~planner.decision.solvers.warm_start.solver_start`: the
delayed-reveal bounds) as ``aplan solve --lumped`` does; with ``--cpu`` it is in CPU seconds of the process
(one core), not wall seconds, so that a loaded machine gives the same figures; each row also gives the CPU
seconds used and the load average when it ran. ``--flat`` solves the flat model over intentions instead
(for comparison where it fits).
PRODUCTs: ``pen`` (no technical constraint), ``pen-technical``, ``chain:N``, ``complete:N``.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner import chain_product, complete_product, count_intentions, make_plan, resolve_product  # noqa: E402
from planner.decision import intention_pomdp  # noqa: E402
from planner.decision.lumped_model import lumped_model  # noqa: E402
from planner.decision.solvers.warm_start import solver_start  # noqa: E402
from planner.decision.solvers import PointBasedSolver  # noqa: E402

PRODUCTS = ["complete:5", "chain:7", "complete:6", "chain:9"]
MARKS = (1, 5, 10, 30, 60, 120)
GAP = 0.05


def _plan(name: str):
    if ":" in name:
        kind, n = name.split(":")
        return make_plan((chain_product if kind == "chain" else complete_product)(int(n)))
    return make_plan(resolve_product("pen"), name == "pen-technical")


class CpuClock:
    """The process's CPU seconds, read at most every 20 ms of wall time (``time.process_time`` can cost a
    millisecond per call, and the solver reads its clock often)."""

    def __init__(self) -> None:
        self.wall, self.cpu = 0.0, time.process_time()

    def __call__(self) -> float:
        now = time.perf_counter()
        if now - self.wall > 0.02:
            self.wall, self.cpu = now, time.process_time()
        return self.cpu


def one(name: str, time_limit: float, flat: bool, cpu: bool) -> dict:
    plan = _plan(name)
    clock = CpuClock() if cpu else time.perf_counter
    load = os.getloadavg()[0]
    cpu_start, start = time.process_time(), clock()
    lumped = None if flat else lumped_model(plan)
    pomdp = intention_pomdp(plan) if flat else lumped.pomdp
    # As api.solve does: a lumped model's upper bound starts from the relaxed bounds, within a quarter of the limit.
    options = {} if flat else solver_start(lumped, deadline=start + time_limit / 4, clock=clock).solve_options
    built = clock() - start
    result = PointBasedSolver(time_limit=time_limit, precision=1e-4, clock=clock).solve(pomdp, started=start,
                                                                                        **options)
    marks = [t for t in MARKS if t <= time_limit]
    at = [[(lo, up) for s, lo, up in result.history if s <= t] for t in marks]
    reached = next((s for s, lo, up in result.history if up - lo <= GAP), None)
    return {"product": name, "states": pomdp.n_states, "intentions": count_intentions(plan.states),
            "actions": pomdp.n_actions, "observations": pomdp.n_observations, "build_s": built,
            "marks": marks, "bounds": [a[-1] if a else None for a in at], "gap_at": reached,
            "final": [result.lower_bound, result.upper_bound, result.seconds], "iterations": result.iterations,
            "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "cpu_s": time.process_time() - cpu_start, "load": [load, os.getloadavg()[0]]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--one", help="run one product in this process and print JSON (internal)")
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--flat", action="store_true", help="the flat model over intentions instead")
    parser.add_argument("--cpu", action="store_true", help="the time limit in CPU seconds of the process")
    parser.add_argument("products", nargs="*", default=PRODUCTS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one, args.time_limit, args.flat, args.cpu)))
        return
    marks = [t for t in MARKS if t <= args.time_limit]
    print("| model | states (classes) | intentions | " + " | ".join(f"lower / upper at {t} s" for t in marks)
          + f" | gap <= {GAP} at | trials | start s | CPU s | load | peak MiB |")
    print("|---|---:|---:|" + "---|" * len(marks) + "---:|---:|---:|---:|---|---:|")
    for name in args.products:
        command = [sys.executable, __file__, "--one", name, "--time-limit", str(args.time_limit)]
        extra = (["--flat"] if args.flat else []) + (["--cpu"] if args.cpu else [])
        out = subprocess.run(command + extra, capture_output=True, text=True, check=True)
        r = json.loads(out.stdout)
        cells = [f"{b[0]:.4f} / {b[1]:.4f}" if b else "-" for b in r["bounds"]]
        reached = f"{r['gap_at']:.1f} s" if r["gap_at"] is not None else "-"
        print(f"| {r['product']}{' (flat)' if args.flat else ''} | {r['states']:,} | {r['intentions']:,} | "
              + " | ".join(cells) + f" | {reached} | {r['iterations']} | {r['build_s']:.1f} | {r['cpu_s']:.1f} | "
              + f"{r['load'][0]:.1f}-{r['load'][1]:.1f} | {r['peak_mib']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
