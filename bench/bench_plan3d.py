"""The plan in 3D, headless: what the "Plan in 3D" panel asks the planner when it opens (the count, the first
200 sequences by rank, the exploded view of one) on synthetic products of growing size.

    .venv/bin/python bench/bench_plan3d.py       # about 15 s (the complete 11-part product's plan most of it)
"""
from __future__ import annotations

import time

from planner import api
from planner.assembly.explode import exploded_view, sequences_at
from planner.product.synthetic import chain_product, complete_product


def _seconds(work) -> tuple[float, object]:
    started = time.perf_counter()
    result = work()
    return time.perf_counter() - started, result


def _row(name: str, plan) -> str:
    count_s, (count, _) = _seconds(lambda: api.sequence_choices(plan, limit=0))
    first_s, _ = _seconds(lambda: api.sequence_choices(plan, limit=200))
    last_s, (last,) = _seconds(lambda: sequences_at(plan, [count - 1]))
    view_s, _ = _seconds(lambda: exploded_view(plan, last, 100.0))
    return (f"| {name} | {len(plan.andor.parts)} | {plan.states.n_states:,} | {plan.states.n_edges:,} | {count:,} | "
            f"{count_s:.3f} | {first_s:.3f} | {last_s:.3f} | {view_s:.3f} |")


def main() -> None:
    print("| product | parts | states | state edges | sequences | count s | first 200 s | last rank s | exploded view s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, make, sizes in (("chain", chain_product, (8, 10, 12)), ("complete", complete_product, (7, 9, 11))):
        for n in sizes:
            print(_row(name, api.plan_of(make(n))))


if __name__ == "__main__":
    main()
