"""How the paper's filter reads the camera world (docs/deviations.md, "The simulated camera"), and what a filter that
reads the camera as it works reaches on the same episodes. The factored model (the paper's), a robot that always
waits (the observer: its belief is the filter's alone).

1. Per kind of step, the mean change of the log belief on the true assembly state under the paper's filter, in
   each world (``--world model`` and ``--world camera``, the same seeded episodes, operator ``uniform``):
   ``idle`` (the operator did nothing), ``seen`` (it did an operation and the observation is not blank),
   ``missed`` (it did one and the observation is blank); and the mean belief on the true state after the last step
   that left the product unfinished.
2. The change-of-mind readings (planner/decision/mind_measures.py; operator ``uniform,changing:0.3``) in the
   camera world, under the paper's filter and under the *camera filter*: the exact Bayes filter of the camera
   world's own observations while the robot waits (after ``wait`` each class stays with probability 1/2 and
   then emits blank, or its operator does its step and the camera reports that step's observation with
   probability 4/5, else blank; the step then spreads over the target's classes by the prior, as the paper's).
   It differs from the paper's filter only in the observation's likelihood, which depends on the step taken,
   not on the state reached: the filter of ``--observe step`` (planner/decision/step_observations.py).

Run: ``.venv/bin/python bench/bench_camera_filter.py [--product pen|chain:N|complete:N|BUNDLE] [--level ID]
[--episodes 200] [--seed 0]``. Seconds on the pen.
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import numpy as np  # noqa: E402

from bench_change_of_mind import Observer, bench_product  # noqa: E402
from planner import api  # noqa: E402
from planner.decision.camera_world import WORLDS  # noqa: E402
from planner.decision.factored_updater import FactoredUpdater  # noqa: E402
from planner.decision.factored_simulate import true_intention_probability  # noqa: E402
from planner.decision.mind_measures import READINGS, step_readings, switch_totals  # noqa: E402
from planner.decision.operators import parse_operator  # noqa: E402

KINDS = ("idle", "seen", "missed")


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


def camera_filtered(model, episode):
    """``episode`` (a waiting robot's) with the camera filter's beliefs and beliefs on the true intention: the
    filter of the same model with observations of the step (``observe="step"``, planner/decision/
    step_observations.py), which is the camera world's own observation model."""
    camera = dataclasses.replace(model, observe="step")
    updater = FactoredUpdater(camera)
    beliefs, steps = [updater.initialize()], []
    for step in episode.steps:
        beliefs.append(updater.update(beliefs[-1], model.wait, step.observation))
        p_true = true_intention_probability(model, beliefs[-1], episode.path, step.position)
        steps.append(dataclasses.replace(step, p_true=p_true))
    return dataclasses.replace(episode, beliefs=beliefs, steps=steps)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--product", default="pen", help="pen, chain:N, complete:N or a bundle")
    parser.add_argument("--level", help="the level (subassembly) of a bundle planned in workstations")
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    model = api.factored_decision_model(api.plan_of(bench_product(args.product, args.level)))
    name = f"{args.product}{' ' + args.level if args.level else ''}"
    print(f"{name}: {args.episodes} episodes, seed {args.seed}, a waiting robot; 1. operator uniform")
    print("| world | " + " | ".join(f"{k} steps | {k}: mean log change" for k in KINDS) + " | last belief on the state |")
    print("|---|" + "---:|" * (2 * len(KINDS) + 1))
    for world in WORLDS:
        choice = api.EpisodeChoice(random=args.episodes, seed=args.seed, operator_model=parse_operator("uniform"),
                                   world=world)
        changes, last = step_changes(model, api.simulate(model, Observer(model.wait), choice))
        cells = " | ".join(f"{len(changes[k])} | {np.mean(changes[k]):+.3f}" if changes[k] else "0 | -" for k in KINDS)
        print(f"| {world} | {cells} | {np.mean(last):.3f} |")
    print(f"\n2. operator uniform,changing:0.3, the camera world; switched episodes whose reading passed 0.9")
    print("| filter | switched | resets | " + " | ".join(r.replace("_", " ") for r in READINGS) + " |")
    print("|---|---:|---:|" + "---:|" * len(READINGS))
    choice = api.EpisodeChoice(random=args.episodes, seed=args.seed,
                               operator_model=parse_operator("uniform,changing:0.3"), world="camera")
    played = api.simulate(model, Observer(model.wait), choice)
    ops = [o for e in played for o in model.sequence_operations(e.path)]
    seen = model.plan.operation_observation[np.asarray(ops, dtype=np.int64)]
    tool_only = sum(not model.plan.observations[z].parts for z in seen if z != 0)
    print(f"(the operations of the sequences done: {len(ops)}; seen as blank whatever the camera, no loose part and "
          f"no tool: {int(np.sum(seen == 0))}; the tool alone: {tool_only}; {len(set(seen.tolist()))} distinct "
          f"observations among them)")
    for label, episodes in (("paper", played), ("camera", [camera_filtered(model, e) for e in played])):
        totals = switch_totals(model, episodes)
        n = totals["switched"]
        cells = " | ".join(f"{totals[r]} ({100 * totals[r] / n:.0f} %)" if n else "-" for r in READINGS)
        print(f"| {label} | {n} | {totals['reset_episodes']} | {cells} |")


if __name__ == "__main__":
    main()
