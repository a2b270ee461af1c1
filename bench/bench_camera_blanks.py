"""How the paper's filter reads each world's camera (docs/deviations.md, "The simulated camera"): with a robot that
always waits and a uniform operator, the mean change of the log belief on the true assembly state per step, by
kind of step: ``idle`` (the operator did nothing), ``seen`` (it did an operation and the observation is not
blank), ``missed`` (it did one and the observation is blank); and the mean belief on the true state after the
last step that left the product unfinished. The factored model (the paper's), the same seeded episodes in both
worlds (``--world model`` and ``--world camera``).

Run: ``.venv/bin/python bench/bench_camera_blanks.py [--product pen|chain:N|complete:N] [--episodes 200]
[--seed 0]``. Seconds on the pen.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from planner import api, chain_product, complete_product  # noqa: E402
from planner.decision.camera_world import WORLDS  # noqa: E402
from planner.decision.mind_measures import step_readings  # noqa: E402
from planner.decision.operators import parse_operator  # noqa: E402

KINDS = ("idle", "seen", "missed")


class _Observer:
    def __init__(self, wait: int):
        self.wait = wait

    def action(self, belief) -> int:
        return self.wait


def step_changes(model, episodes) -> tuple[dict[str, list[float]], list[float]]:
    """Per kind of step, the changes of the log belief on the true state; and each episode's last belief on it
    before the product was finished (the steps before the first one with a positive belief are skipped)."""
    changes: dict[str, list[float]] = {kind: [] for kind in KINDS}
    last = []
    for episode in episodes:
        before, done = None, 0
        for k, step in enumerate(episode.steps, 1):
            if step.position >= len(episode.path):
                break
            now = step_readings(model, episode, k)["state"]
            kind = "idle" if step.operator_operations == done else "missed" if step.observation == 0 else "seen"
            if before and now > 0:
                changes[kind].append(float(np.log(now) - np.log(before)))
            before, done = now, step.operator_operations
        if before is not None:
            last.append(before)
    return changes, last


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--product", default="pen", help="pen, chain:N or complete:N")
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    kind, _, size = args.product.partition(":")
    product = api.resolve_product("pen") if args.product == "pen" else \
        {"chain": chain_product, "complete": complete_product}[kind](int(size))
    model = api.factored_decision_model(api.plan_of(product))
    print(f"{args.product}: {args.episodes} episodes, seed {args.seed}, a waiting robot, operator uniform")
    print("| world | " + " | ".join(f"{k} steps | {k}: mean log change" for k in KINDS) + " | last belief on the state |")
    print("|---|" + "---:|" * (2 * len(KINDS) + 1))
    for world in WORLDS:
        choice = api.EpisodeChoice(random=args.episodes, seed=args.seed, operator_model=parse_operator("uniform"),
                                   world=world)
        changes, last = step_changes(model, api.simulate(model, _Observer(model.wait), choice))
        cells = " | ".join(f"{len(changes[k])} | {np.mean(changes[k]):+.3f}" if changes[k] else "0 | -" for k in KINDS)
        print(f"| {world} | {cells} | {np.mean(last):.3f} |")


if __name__ == "__main__":
    main()
