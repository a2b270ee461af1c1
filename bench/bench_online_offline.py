"""The online planner against the offline policy where both exist (issue 12): mean discounted returns with 95 %
intervals, on the same world simulator and the same seeds.

Run: ``.venv/bin/python bench/bench_online_offline.py`` (about 25 minutes; prints a Markdown table).
Per product (each in a fresh subprocess): the lumped model (:mod:`planner.decision.lumped_model`, exactly the
flat model's value) is solved offline by the built-in solver for ``--solve-time`` seconds (one core; the pen
until the gap is at most 0.01), and both its policy (alpha vectors over classes, on the factored Bayes filter)
and the online planner (``--expansions`` per decision: a fixed amount of work, so a loaded machine gives the
same figures) play ``--episodes`` episodes (the pen: 2,000) drawn with the same seed, as ``aplan evaluate``
plays them.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner import api, chain_product, complete_product, make_plan, resolve_product  # noqa: E402
from planner.decision.episodes import EpisodeChoice, evaluate  # noqa: E402
from planner.decision.solvers.warm_start import solver_start  # noqa: E402
from planner.decision.online import OnlinePlanner  # noqa: E402
from planner.decision.solvers import PointBasedSolver  # noqa: E402

PRODUCTS = {"pen": 2000, "chain:7": 500, "complete:6": 500, "chain:9": 300}


def _product(name: str):
    if ":" in name:
        kind, n = name.split(":")
        return (chain_product if kind == "chain" else complete_product)(int(n))
    return resolve_product(name)


def _one(name: str, episodes: int, solve_time: float, expansions: int, seed: int) -> dict:
    lumped = api.lumped_model(make_plan(_product(name)))
    precision = 0.01 if name == "pen" else 1e-3
    limit = 2 * solve_time if name == "pen" else solve_time
    solver = PointBasedSolver(time_limit=limit, precision=precision)
    started = solver.clock()  # as api.solve starts it: the relaxed bounds within a quarter of the limit
    start = solver_start(lumped, deadline=started + limit / 4, clock=solver.clock)
    result = solver.solve(lumped.pomdp, started=started, **start.solve_options)
    started = time.perf_counter()
    offline = evaluate(lumped.factored, result.policy, EpisodeChoice(random=episodes, seed=seed))
    offline_s = time.perf_counter() - started
    started = time.perf_counter()
    online = evaluate(lumped.factored, OnlinePlanner(lumped.factored, expansions),
                      EpisodeChoice(random=episodes, seed=seed))
    online_s = time.perf_counter() - started
    return {"product": name, "classes": lumped.factored.n_classes, "solve_s": result.seconds,
            "lower": result.lower_bound, "upper": result.upper_bound, "episodes": episodes,
            "offline": offline[:2], "online": online[:2], "offline_s": offline_s, "online_s": online_s}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("products", nargs="*", default=list(PRODUCTS))
    parser.add_argument("--episodes", type=int, default=None, help="per product (default: 2,000 pen, else 300-500)")
    parser.add_argument("--solve-time", type=float, default=60.0)
    parser.add_argument("--expansions", type=int, default=50)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(_one(args.products[0], args.episodes, args.solve_time, args.expansions, args.seed)))
        return
    print("| product | classes | offline bounds (solve s) | offline return | online return | online - offline |")
    print("|---|---:|---|---|---|---:|")
    for name in args.products:
        episodes = args.episodes or PRODUCTS.get(name, 300)
        done = subprocess.run([sys.executable, __file__, name, "--one", "--episodes", str(episodes), "--solve-time",
                               str(args.solve_time), "--expansions", str(args.expansions), "--seed", str(args.seed)],
                              capture_output=True, text=True)
        if done.returncode != 0:
            print(f"| {name} | failed: {(done.stderr.strip().splitlines() or [done.returncode])[-1]} |")
            continue
        r = json.loads(done.stdout)
        (off, off_h), (on, on_h) = r["offline"], r["online"]
        print(f"| {name} | {r['classes']:,} | {r['lower']:.4f} / {r['upper']:.4f} ({r['solve_s']:.0f} s) | "
              f"{off:.3f} +- {off_h:.3f} | {on:.3f} +- {on_h:.3f} | {on - off:+.3f} |", flush=True)


if __name__ == "__main__":
    main()
