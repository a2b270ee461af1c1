"""Planner benchmarks: pen latency, the 11-part synthetic products, and growth from 4 to 12 parts.

Run: ``.venv/bin/python bench/bench_planner.py`` (about a minute; prints a Markdown table).
Each size runs in a fresh subprocess so its peak resident memory (ru_maxrss) is its own.
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

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner import (  # noqa: E402
    and_or_graph,
    assembly_state_graph,
    chain_product,
    complete_product,
    count_intentions,
    count_sequences,
    example_path,
    intention_graph,
    load_product,
    make_plan,
)


def pen_latency(repeats: int = 2000) -> dict:
    """Product file -> AND/OR graph -> state graph -> intention graph, in-process, median of ``repeats``."""
    path = example_path("pen")
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        intention_graph(make_plan(load_product(path)).states)
        times.append(time.perf_counter() - start)
    return {"median_ms": statistics.median(times) * 1e3, "p95_ms": sorted(times)[int(0.95 * repeats)] * 1e3}


def one_size(kind: str, n: int) -> dict:
    product = (chain_product if kind == "chain" else complete_product)(n)
    start = time.perf_counter()
    andor = and_or_graph(product)
    t_andor = time.perf_counter()
    states = assembly_state_graph(andor)
    t_states = time.perf_counter()
    intentions = count_intentions(states)
    sequences = count_sequences(states)
    t_count = time.perf_counter()
    return {"kind": kind, "parts": n, "subassemblies": len(andor.subassemblies), "operations": len(andor.operations),
            "states": states.n_states, "state_edges": states.n_edges, "intentions": intentions,
            "sequences": sequences, "andor_s": t_andor - start, "states_s": t_states - t_andor,
            "count_s": t_count - t_states, "total_s": t_count - start,
            "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def run_isolated(kind: str, n: int) -> dict:
    out = subprocess.run([sys.executable, __file__, "--one", kind, str(n)], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--one", nargs=2, metavar=("KIND", "N"), help=argparse.SUPPRESS)
    parser.add_argument("--max-complete", type=int, default=12)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one_size(args.one[0], int(args.one[1]))))
        return
    pen = pen_latency()
    print(f"pen, product file to intention graph: median {pen['median_ms']:.2f} ms, p95 {pen['p95_ms']:.2f} ms\n")
    print("| product | parts | subassemblies | operations | states | state edges | intentions | AND/OR s "
          "| states s | count s | peak MiB |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for kind, top in (("chain", 12), ("complete", args.max_complete)):
        for n in range(4, top + 1):
            r = run_isolated(kind, n)
            print(f"| {kind} | {n} | {r['subassemblies']:,} | {r['operations']:,} | {r['states']:,} | "
                  f"{r['state_edges']:,} | {r['intentions']:,} | {r['andor_s']:.3f} | {r['states_s']:.3f} | "
                  f"{r['count_s']:.3f} | {r['peak_mib']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
