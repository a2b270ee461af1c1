"""Change of mind (issue 23 item 3, docs/deviations.md): an operator who switches sequence once per episode with
probability 0.3 (``--operator-sequence uniform,changing:0.3``: after a uniformly drawn number of operations, to
another completion of its state), against the paper's model and the model with a change of mind and mistakes
(``--switch``, ``--mistakes``), each with the online planner (a fixed number of expansions per decision: the same
actions on any machine), on the same seeded episodes.

Per model: the episodes with a belief reset (an observation of probability 0 under the belief) and the resets,
the switched episodes whose belief on the new true sequence passed 0.9 before the product was finished, the
robot's share of the operations, its wrong actions (and their share of its actions) and the mean return; for
context, the episodes (all) whose belief on the true sequence passed 0.9 before the product was finished.

Run: ``.venv/bin/python bench/bench_change_of_mind.py [--product pen] [--episodes 200] [--expansions 200]
[--switch 0.05] [--mistakes 0.02] [--operator uniform,changing:0.3]``.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from planner import api, chain_product, complete_product  # noqa: E402
from planner.decision.deviations import Deviations  # noqa: E402
from planner.decision.episode_measures import episode_measures, run_totals  # noqa: E402
from planner.decision.operators import parse_operator  # noqa: E402


def _run(plan, deviations, args) -> dict:
    model = api.factored_decision_model(plan, deviations=deviations)
    planner = api.online_planner(model, None, args.expansions)
    began = time.process_time()
    mean, half, played = api.evaluate_operator(model, planner, parse_operator(args.operator), args.episodes,
                                               args.seed, args.max_steps)
    measures = [episode_measures(e) for e in played]
    totals = run_totals(measures)
    return {"mean": mean, "half": half, "cpu": time.process_time() - began,
            "reset_episodes": sum(m["resets"] > 0 for m in measures), **totals}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--product", default="pen", help="pen, chain:N, complete:N or a product file")
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--expansions", type=int, default=200)
    parser.add_argument("--switch", type=float, default=0.05)
    parser.add_argument("--mistakes", type=float, default=0.02)
    parser.add_argument("--operator", default="uniform,changing:0.3")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-steps", type=int, default=100)
    args = parser.parse_args()
    kind, _, size = args.product.partition(":")
    product = {"chain": chain_product, "complete": complete_product}[kind](int(size)) if size else \
        api.resolve_product(args.product)
    plan = api.plan_of(product)
    print(f"{args.product}: operator {args.operator}, {args.episodes} episodes, online planner "
          f"{args.expansions} expansions per decision")
    print("| model | episodes with a reset (resets) | switched | confident on the new sequence | confident (all) "
          "| robot share | wrong robot actions | mean return | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, deviations in (("paper", None),
                             (f"switch {args.switch:g}, mistakes {args.mistakes:g}",
                              Deviations(args.switch, args.mistakes))):
        r = _run(plan, deviations, args)
        share = "-" if r["robot_share"] is None else f"{100 * r['robot_share']:.1f} %"
        wrong = "-" if r["wrong_share"] is None else f"{100 * r['wrong_share']:.1f} %"
        confident = (f"{r['confident_after_switch']} ({100 * r['confident_after_switch'] / r['switched']:.0f} %)"
                     if r["switched"] else "-")
        print(f"| {name} | {r['reset_episodes']} ({r['resets']}) | {r['switched']} | {confident} | "
              f"{r['episodes'] - r['never_confident']} | {share} | "
              f"{r['wrong_robot_actions']} ({wrong}) | {r['mean']:.3f} +- {r['half']:.3f} | {r['cpu']:.0f} |",
              flush=True)


if __name__ == "__main__":
    main()
