"""The factored intention model (paper Sec. V): size, build time, belief-update time and peak memory.

Run: ``.venv/bin/python bench/bench_factored.py`` (about a minute; prints a Markdown table).
Each product runs in a fresh subprocess so its peak resident memory (ru_maxrss) is its own.

Per product: the plan is built, then the factored model (timed); then ``EPISODES`` episodes are simulated on
the factored model itself (a full sequence drawn uniformly; the operator acts with probability 1/2 per step;
the robot waits half the time and otherwise performs a random robot action, mostly wrong ones, after which
the model's operator does not act (this slows assembly and lets the belief spread); observations drawn
from the model, missed detections included), and
every ``FactoredUpdater.update`` is timed. Where the flat model has at most ``FLAT_LIMIT`` intentions, the
flat ``DiscreteUpdater`` runs beside it on the same actions and observations (its time, and the largest
difference between the flat belief and ``to_flat`` of the factored one).
"""
from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner import chain_product, complete_product, count_intentions, make_plan, resolve_product  # noqa: E402
from planner.decision import DiscreteUpdater, FactoredUpdater, factored_model, intention_model, to_flat  # noqa: E402

EPISODES = 5
MAX_STEPS = 200
FLAT_LIMIT = 10_000  # intentions: beside it, the flat filter on the same steps (time, largest difference)
PRODUCTS = ["pen", "chain:7", "complete:6", "chain:9", "chain:11", "complete:9", "complete:11"]


def _product(name: str):
    if ":" in name:
        kind, n = name.split(":")
        return (chain_product if kind == "chain" else complete_product)(int(n))
    return resolve_product(name)


def _episode(model, updater, rng, flat=None) -> tuple[list[float], list[float], float]:
    """One episode until the product is finished (or MAX_STEPS): the time of each belief update, and with
    ``flat`` (a flat model) the time of each flat update on the same actions and observations and the largest
    difference between the two beliefs."""
    path = model.sample_sequence(rng)
    position, times, flat_times, difference = 0, [], [], 0.0
    belief = updater.initialize()
    if flat is not None:
        flat_updater = DiscreteUpdater(flat.pomdp)
        b = flat_updater.initialize()
    n_actions = len(model.actions)
    for _ in range(MAX_STEPS):
        if position == len(path):
            break
        action = model.wait if rng.random() < 0.5 or n_actions == 1 else int(rng.integers(n_actions - 1))
        position = model.sample_position(path, position, action, rng)
        z = model.sample_observation(path, position, rng)
        start = time.perf_counter()
        belief = updater.update(belief, action, z)
        times.append(time.perf_counter() - start)
        if flat is not None:
            start = time.perf_counter()
            b = flat_updater.update(b, action, z)
            flat_times.append(time.perf_counter() - start)
            difference = max(difference, float(np.max(np.abs(to_flat(belief, flat.graph) - b))))
    assert not updater.events, "the true intention explains every observation"
    return times, flat_times, difference


def one(name: str) -> dict:
    plan = make_plan(_product(name))
    start = time.perf_counter()
    model = factored_model(plan)
    built = time.perf_counter() - start
    rng = np.random.default_rng(0)
    updater = FactoredUpdater(model)
    flat = intention_model(plan) if count_intentions(plan.states) <= FLAT_LIMIT else None
    times, flat_times, difference = [], [], 0.0
    for _ in range(EPISODES):
        t, f, d = _episode(model, updater, rng, flat)
        times, flat_times, difference = times + t, flat_times + f, max(difference, d)
    return {"product": name, "states": plan.states.n_states, "edges": plan.states.n_edges,
            "intentions": count_intentions(plan.states), "sequences": model.n_sequences, "build_s": built,
            "updates": len(times), "median_ms": statistics.median(times) * 1e3, "max_ms": max(times) * 1e3,
            "flat_median_ms": statistics.median(flat_times) * 1e3 if flat_times else None,
            "difference": difference if flat else None,
            "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--one", help="run one product in this process and print JSON (internal)")
    parser.add_argument("products", nargs="*", default=PRODUCTS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one)))
        return
    print("| product | states | state edges | intentions | build s | updates | median ms | max ms | peak MiB "
          "| flat median ms | largest difference |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in args.products:
        out = subprocess.run([sys.executable, __file__, "--one", name], capture_output=True, text=True, check=True)
        r = json.loads(out.stdout)
        print(f"| {r['product']} | {r['states']:,} | {r['edges']:,} | {r['intentions']:,} | {r['build_s']:.3f} | "
              f"{r['updates']} | {r['median_ms']:.3f} | {r['max_ms']:.2f} | {r['peak_mib']:.0f} | "
              + (f"{r['flat_median_ms']:.3f} | {r['difference']:.1e} |" if r["difference"] is not None else "- | - |"),
              flush=True)


if __name__ == "__main__":
    main()
