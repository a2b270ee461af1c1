"""How soon the robot knows the operator's intention: for each of the pen's full assembly sequences, after
how many operator operations the belief on the true intention first exceeds 0.9 (issue 4; the paper saw 2,
2 and 4 in its three runs).

The policy is the builtin solver's after ``--time-limit`` seconds. Observations are random (missed
detections), so each sequence is played ``--episodes`` times with the operator taking turns with the robot as
in the paper's experiment (``aplan simulate --operator turns``); the table gives the median, the range and
how often the belief never passed 0.9 before the product was finished.

Run: ``.venv/bin/python bench/bench_confidence.py [--time-limit 30] [--episodes 200]`` (about a minute).
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from planner import make_plan, resolve_product  # noqa: E402
from planner.decision import intention_model  # noqa: E402
from planner.decision.simulate import IntentionWorld, simulate_episode  # noqa: E402
from planner.decision.solvers import PointBasedSolver  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--time-limit", type=float, default=30.0)
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--technical", action="store_true")
    args = parser.parse_args()
    plan = make_plan(resolve_product("pen"), args.technical)
    decision = intention_model(plan)
    model, graph = decision.pomdp, decision.graph
    result = PointBasedSolver(time_limit=args.time_limit, precision=1e-4).solve(model)
    print(f"policy: {result.policy.alphas.shape[0]} alpha vectors, bounds {result.lower_bound:.5f} / "
          f"{result.upper_bound:.5f} after {result.seconds:.0f} s; {args.episodes} episodes per sequence\n")
    print("| sequence | operations | median | min | max | never |")
    print("|---:|---|---:|---:|---:|---:|")
    rng = np.random.default_rng(0)
    medians = []
    for start in graph.full_sequences():
        start = int(start)
        steps = decision.describe_operations(start)
        counts = [simulate_episode(IntentionWorld(model, start, graph.successor, 0), result.policy, rng, 100, "turns")
                  .first_confident(0.9) for _ in range(args.episodes)]
        known = [c for c in counts if c is not None]
        median = statistics.median(known) if known else None
        medians.append(median)
        print(f"| {start} | {' ; '.join(steps)} | {format(median, 'g') if median is not None else '-'} | "
              f"{min(known) if known else '-'} | {max(known) if known else '-'} | "
              f"{(len(counts) - len(known)) / len(counts):.0%} |", flush=True)
    found = [m for m in medians if m is not None]
    print(f"\nmedian over sequences: {statistics.median(found) if found else '-'} operator operations")


if __name__ == "__main__":
    main()
