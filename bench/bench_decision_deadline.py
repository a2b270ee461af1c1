"""Online decisions against their deadline on the large products (issue 22, item 4): every decision of a few
random episodes timed, with the belief's size and the expansions done, the slowest listed.

    .venv/bin/python bench/bench_decision_deadline.py complete:11 3     # PRODUCT EPISODES [DECISION_TIME]

The product is planned and its factored model and online planner built (timed: "build", not a decision);
then EPISODES random full sequences are played as ``aplan simulate PRODUCT --random N`` plays them, at
DECISION_TIME seconds per decision (default 0.1). Prints one JSON line (median, p95 and max of the planner's
``search`` call, peak resident MiB) and the twelve slowest decisions. Cap its memory (complete 12 and chain 23
take about 8 GB): ``prlimit --as=$((11*2**30)) -- ...``.
"""
from __future__ import annotations

import json
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner import api, chain_product, complete_product, make_plan  # noqa: E402
from planner.decision.factored_simulate import PathWorld  # noqa: E402
from planner.decision.simulate import simulate_episode  # noqa: E402


def main() -> None:
    name, episodes = sys.argv[1], int(sys.argv[2])
    decision_time = float(sys.argv[3]) if len(sys.argv) > 3 else 0.1
    kind, n = name.split(":")
    began = time.perf_counter()
    plan = make_plan((chain_product if kind == "chain" else complete_product)(int(n)))
    model = api.factored_decision_model(plan)
    planner = api.online_planner(model, decision_time)
    print(f"build {time.perf_counter() - began:.1f} s, {model.n_classes:,} classes", flush=True)
    search, decisions = planner.search, []

    def timed(belief):
        report = search(belief)
        decisions.append((report.seconds, belief.classes.size, report.expansions))
        return report

    planner.search = timed
    rng = np.random.default_rng(0)
    for _ in range(episodes):
        simulate_episode(PathWorld(model, model.sample_sequence(rng)), planner, rng, 400)
    seconds = np.array([d[0] for d in decisions])
    print(json.dumps({"product": name, "episodes": episodes, "decisions": len(decisions),
                      "median_ms": round(1000 * float(np.median(seconds)), 1),
                      "p95_ms": round(1000 * float(np.percentile(seconds, 95)), 1),
                      "max_ms": round(1000 * float(seconds.max()), 1),
                      "peak_mib": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)}))
    for s, k, x in sorted(decisions, reverse=True)[:12]:
        print(f"{1000 * s:8.1f} ms  classes {k:>10,}  expansions {x}")


if __name__ == "__main__":
    main()
