"""The built-in solver's bounds at fixed numbers of trials, with no time limit: a fingerprint of the algorithm
that any machine reproduces digit for digit (the work is counted, not timed). Used to check that reshaping the
solver (issue 11) changed nothing: the same table before and after.

    .venv/bin/python bench/bench_solver_trials.py [--trials 5 50 200]
"""
from __future__ import annotations

import argparse
import time

from planner import api
from planner.decision import PointBasedSolver


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, nargs="+", default=[5, 50, 200])
    args = parser.parse_args()
    print("| technical constraint | trials | lower bound | upper bound | alpha vectors | seconds |")
    print("|---|---:|---:|---:|---:|---:|")
    for technical in (False, True):
        model = api.decision_model("pen", technical)
        for trials in args.trials:
            start = time.perf_counter()
            result = PointBasedSolver(max_iterations=trials, time_limit=None, precision=1e-9).solve(model.pomdp)
            print(f"| {'on' if technical else 'off'} | {trials} | {result.lower_bound!r} | {result.upper_bound!r} "
                  f"| {result.policy.alphas.shape[0]} | {time.perf_counter() - start:.1f} |", flush=True)


if __name__ == "__main__":
    main()
