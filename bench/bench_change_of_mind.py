"""Change of mind (issue 23 item 3, docs/deviations.md): an operator who switches sequence once per episode with
probability 0.3 (``--operator-sequence uniform,changing:0.3``: after a uniformly drawn number of operations, to
another completion of its state), against the paper's model and the model with a change of mind and mistakes
(``--switch``, ``--mistakes``), on the same seeded episodes. Two robots per model: the online planner (a fixed
number of expansions per decision: the same actions on any machine) and an observer that always waits (its
belief is the model's Bayes filter on the operator's own work: what the model's belief can reach by itself).

Per model and robot: the episodes with a belief reset (an observation of probability 0 under the belief) and the
resets; the switched episodes whose belief on the new true intention (the flat model's belief on the current
assembly state and the new remaining sequence, ``confident_after_switch``) passed 0.9 at or after the switch
and before the product was finished; the switched episodes whose belief on the true assembly state passed 0.9
in those steps (what the operator has done, not what it will do); the robot's share of the operations, its
wrong actions (and their share of its actions) and the mean return; for context, the episodes (all) whose
belief on the true intention passed 0.9 before the product was finished.

Run: ``.venv/bin/python bench/bench_change_of_mind.py [--product pen|chain:N|complete:N|FILE|BUNDLE] [--level ID]
[--episodes 200] [--expansions 200] [--switch 0.05] [--mistakes 0.02] [--operator uniform,changing:0.3]
[--robots online,observer]`` (a bundle is planned with ``--fasteners auto --subassemblies auto``).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from planner import api, chain_product, complete_product  # noqa: E402
from planner.decision.deviations import Deviations  # noqa: E402
from planner.decision.episode_measures import episode_measures, run_totals  # noqa: E402
from planner.decision.operators import parse_operator  # noqa: E402


class _Observer:
    """A robot that always waits: every operation is the operator's, and the belief is the filter's alone."""

    def __init__(self, wait: int):
        self.wait = wait

    def action(self, belief) -> int:
        return self.wait


def state_known_after_switch(model, episode, threshold: float = 0.9) -> bool | None:
    """Whether the belief on the true assembly state (the mass of the classes that start there) passed
    ``threshold`` at or after the switch, before the product was finished; None without a switch."""
    if episode.switched_at is None:
        return None
    final = model.final_class
    for k in range(episode.switched_at, len(episode.steps) + 1):
        step, belief = episode.steps[k - 1], episode.beliefs[k]
        if not episode.unfinished(step):
            return False
        state = int(model.class_source[episode.path[step.position]])
        source = np.where(belief.classes == final, model.final_state,
                          model.class_source[np.minimum(belief.classes, final - 1)])
        if float(belief.mass[source == state].sum()) > threshold:
            return True
    return False


def _run(model, robot, args) -> dict:
    planner = api.online_planner(model, None, args.expansions) if robot == "online" else _Observer(model.wait)
    began = time.process_time()
    choice = api.EpisodeChoice(random=args.episodes, seed=args.seed, max_steps=args.max_steps,
                               operator_model=parse_operator(args.operator))
    mean, half, played = api.evaluate_operator(model, planner, choice)
    measures = [episode_measures(e) for e in played]
    totals = run_totals(measures)
    return {"mean": mean, "half": half, "cpu": time.process_time() - began,
            "reset_episodes": sum(m["resets"] > 0 for m in measures),
            "state_known": sum(bool(state_known_after_switch(model, e)) for e in played), **totals}


def _product(spec: str, level: str | None):
    kind, _, size = spec.partition(":")
    if kind in ("chain", "complete") and size:
        return {"chain": chain_product, "complete": complete_product}[kind](int(size))
    if spec == "pen":
        return api.resolve_product(spec)
    product = api.resolve_product(spec, None, "auto", None, "auto")
    return api.level_product(product, "designer", level) if level else product


def _share(count: int, of: int) -> str:
    return f"{count} of {of} ({100 * count / of:.0f} %)" if of else "-"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--product", default="pen", help="pen, chain:N, complete:N, a product file or a bundle")
    parser.add_argument("--level", help="the level (subassembly) of a bundle planned in workstations")
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--expansions", type=int, default=200)
    parser.add_argument("--switch", type=float, default=0.05)
    parser.add_argument("--mistakes", type=float, default=0.02)
    parser.add_argument("--operator", default="uniform,changing:0.3")
    parser.add_argument("--robots", default="online,observer", help="online, observer or both (comma-separated)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-steps", type=int, default=100)
    args = parser.parse_args()
    plan = api.plan_of(_product(args.product, args.level))
    print(f"{args.product}{' ' + args.level if args.level else ''}: operator {args.operator}, {args.episodes} "
          f"episodes, online planner {args.expansions} expansions per decision")
    print("| model | robot | episodes with a reset (resets) | confident on the new intention | state known after "
          "the switch | confident (all) | robot share | wrong robot actions | mean return | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, deviations in (("paper", None),
                             (f"switch {args.switch:g}, mistakes {args.mistakes:g}",
                              Deviations(args.switch, args.mistakes))):
        model = api.factored_decision_model(plan, deviations=deviations)
        for robot in args.robots.split(","):
            r = _run(model, robot, args)
            share = "-" if r["robot_share"] is None else f"{100 * r['robot_share']:.1f} %"
            wrong = "-" if r["wrong_share"] is None else f"{100 * r['wrong_share']:.1f} %"
            print(f"| {name} | {robot} | {r['reset_episodes']} ({r['resets']}) | "
                  f"{_share(r['confident_after_switch'], r['switched'])} | {_share(r['state_known'], r['switched'])} "
                  f"| {_share(r['episodes'] - r['never_confident'], r['episodes'])} | {share} | "
                  f"{r['wrong_robot_actions']} ({wrong}) | {r['mean']:.3f} +- {r['half']:.3f} | {r['cpu']:.0f} |",
                  flush=True)


if __name__ == "__main__":
    main()
