"""Decision-model benchmarks: the solver on the pen (ours and the authors' files), belief updates at scale,
and the solver's BLAS threads.

Run: ``.venv/bin/python bench/bench_decision.py [--time-limit 60]`` (about 4 x the time limit). The solver
picks its BLAS threads itself (``planner.decision.solvers.threads``); ``--blas-threads N`` imposes N.
``--threads`` instead times a fixed amount of solver work (no clock) with one thread and with every core,
on models of growing size (about 2 minutes).
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from planner import chain_product, complete_product, make_plan, resolve_product  # noqa: E402
from planner.decision import intention_pomdp  # noqa: E402
from planner.decision.belief import DiscreteUpdater  # noqa: E402
from planner.decision.io.pomdpx import read_pomdpx  # noqa: E402
from planner.decision.solvers import PointBasedSolver  # noqa: E402

REFERENCE = ROOT.parent / "shared" / "models" / "bourjault_pen" / "reference_pomdp"
MARKS = (1, 5, 10, 30, 60, 120, 300, 600)
# Issue 4's lower-bound targets: no technical constraint 2.7965, technical constraint 3.9305.
TARGETS = {False: 2.7965, True: 3.9305}


def _first(history, test) -> str:
    return next((f"{s:.1f} s" for s, lo, up in history if test(lo, up)), "-")


def solver_rows(time_limit: float, blas_threads: int | None = None) -> None:
    pen = resolve_product("pen")
    cases = [("ours, no technical constraint", False, intention_pomdp(make_plan(pen, False))),
             ("authors' file, no technical constraint", False,
              read_pomdpx(REFERENCE / "pen_no_technical.pomdpx.gz")),
             ("ours, technical constraint", True, intention_pomdp(make_plan(pen, True))),
             ("authors' file, technical constraint", True, read_pomdpx(REFERENCE / "pen_technical.pomdpx.gz"))]
    marks = [t for t in MARKS if t <= time_limit]
    print("| model | " + " | ".join(f"lower/upper at {t} s" for t in marks)
          + " | lower >= target at | gap <= 0.05 at | gap <= 0.01 at |")
    print("|---|" + "---|" * (len(marks) + 3))
    for name, technical, model in cases:
        result = PointBasedSolver(time_limit=time_limit, precision=1e-4, blas_threads=blas_threads).solve(model)
        cells = []
        for t in marks:
            lower, upper = [(lo, up) for s, lo, up in result.history if s <= t][-1]
            cells.append(f"{lower:.5f} / {upper:.5f}")
        target = TARGETS[technical]
        reach = [_first(result.history, lambda lo, up: lo >= target)] + \
                [_first(result.history, lambda lo, up, g=g: up - lo <= g) for g in (0.05, 0.01)]
        print(f"| {name} | " + " | ".join(cells) + " | " + " | ".join(reach) + " |", flush=True)


def belief_rows() -> None:
    plan = make_plan(chain_product(9))
    start = time.perf_counter()
    model = intention_pomdp(plan, limit=200_000)
    built = time.perf_counter() - start
    updater = DiscreteUpdater(model)
    rng = np.random.default_rng(0)
    belief = updater.initialize()
    times = []
    for _ in range(200):
        action = int(rng.integers(model.n_actions))
        predicted = updater.predict(belief, action)
        likely = (np.stack([updater.observation_likelihood(action, z) for z in range(model.n_observations)])
                  @ predicted)
        observation = int(rng.choice(model.n_observations, p=likely / likely.sum()))
        t0 = time.perf_counter()
        belief = updater.update(belief, action, observation)
        times.append(time.perf_counter() - t0)
    print(f"\nbelief update, chain of 9 parts: {model.n_states:,} intentions, {model.n_actions} actions, "
          f"{model.n_observations} observations (model built in {built:.2f} s): median "
          f"{statistics.median(times) * 1e3:.3f} ms, max {max(times) * 1e3:.3f} ms over 200 updates")


def thread_rows() -> None:
    """The same solver work (trials, no time limit) with one BLAS thread and with every core; best of two."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    pen = resolve_product("pen")
    cases = [("pen, technical constraint", make_plan(pen, True), 150),
             ("pen, no technical constraint", make_plan(pen, False), 150),
             ("chain of 5 parts", make_plan(chain_product(5)), 100),
             ("chain of 6 parts", make_plan(chain_product(6)), 40),
             ("complete graph of 5 parts", make_plan(complete_product(5)), 20)]
    print(f"| model | states | trials | 1 thread | {cores} threads |\n|---|---:|---:|---:|---:|")
    for name, plan, trials in cases:
        model = intention_pomdp(plan)
        best = {}
        for _ in range(2):
            for threads in (1, cores):
                start = time.perf_counter()
                PointBasedSolver(time_limit=None, max_iterations=trials, blas_threads=threads).solve(model)
                best[threads] = min(best.get(threads, np.inf), time.perf_counter() - start)
        print(f"| {name} | {model.n_states:,} | {trials} | {best[1]:.2f} s | {best[cores]:.2f} s |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--time-limit", type=float, default=60.0)
    parser.add_argument("--blas-threads", type=int, default=None, help="impose this many BLAS threads")
    parser.add_argument("--threads", action="store_true", help="time fixed work at 1 thread and every core")
    args = parser.parse_args()
    if args.threads:
        thread_rows()
        return
    solver_rows(args.time_limit, args.blas_threads)
    with threadpool_limits(1, user_api="blas"):  # as measured before: one thread
        belief_rows()


if __name__ == "__main__":
    main()
