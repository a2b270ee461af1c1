"""The online planner at scale: decision times, peak memory, confidence and return on products far beyond the
flat model (issue 12).

Run: ``.venv/bin/python bench/bench_online.py`` (about 10 minutes; prints a Markdown table). Each product runs
in a fresh subprocess so its peak resident memory (ru_maxrss) is its own. Per product: the plan and the factored
model are built (timed), then ``--episodes`` random full sequences are played exactly as ``aplan simulate
PRODUCT --random N`` plays them (the operator acts with probability 1/2 per step, observations drawn from the
model, missed detections included) with the online planner at ``--decision-time`` seconds per decision. Every
decision is timed (the planner's ``action`` call alone, as the session logs it in ``decision_ms``).
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner import api, chain_product, complete_product, count_intentions, make_plan, resolve_product  # noqa: E402
from planner.defaults import CONFIDENCE, DECISION_TIME  # noqa: E402

PRODUCTS = ["pen", "chain:11", "complete:9", "complete:11"]


def _product(name: str):
    if ":" in name:
        kind, n = name.split(":")
        return (chain_product if kind == "chain" else complete_product)(int(n))
    return resolve_product(name)


def _one(name: str, episodes: int, decision_time: float, seed: int) -> dict:
    started = time.perf_counter()
    plan = make_plan(_product(name))
    model = api.factored_decision_model(plan)
    planner = api.online_planner(model, decision_time)
    build = time.perf_counter() - started
    runs = api.simulate(model, planner, api.EpisodeChoice(random=episodes, seed=seed, max_steps=400))
    times = np.array([s.decision_seconds for e in runs for s in e.steps])
    return {"product": name, "parts": len(plan.product.parts), "intentions": count_intentions(plan.states),
            "classes": model.n_classes, "build_s": build, "episodes": episodes,
            "finished": sum(e.finished for e in runs),
            "confident": sum(e.confident_before_finished(CONFIDENCE) for e in runs),
            "decisions": int(times.size), "median_ms": 1000 * float(np.median(times)),
            "p95_ms": 1000 * float(np.percentile(times, 95)), "max_ms": 1000 * float(times.max()),
            "mean_return": float(np.mean([e.discounted_return for e in runs])),
            "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("products", nargs="*", default=PRODUCTS)
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--decision-time", type=float, default=DECISION_TIME)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(_one(args.products[0], args.episodes, args.decision_time, args.seed)))
        return
    print("| product | parts | intentions | classes | build s | episodes finished | belief on the true intention "
          "> 0.9 before the end | decisions | median ms | p95 ms | max ms | mean return | peak MiB |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in args.products:
        done = subprocess.run([sys.executable, __file__, name, "--one", "--episodes", str(args.episodes),
                               "--decision-time", str(args.decision_time), "--seed", str(args.seed)],
                              capture_output=True, text=True)
        if done.returncode != 0:
            print(f"| {name} | failed: {done.stderr.strip().splitlines()[-1] if done.stderr else done.returncode} |")
            continue
        r = json.loads(done.stdout)
        print(f"| {r['product']} | {r['parts']} | {r['intentions']:,} | {r['classes']:,} | {r['build_s']:.2f} | "
              f"{r['finished']}/{r['episodes']} | {r['confident']}/{r['episodes']} | {r['decisions']} | "
              f"{r['median_ms']:.1f} | {r['p95_ms']:.1f} | {r['max_ms']:.1f} | {r['mean_return']:.3f} | "
              f"{r['peak_mib']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
