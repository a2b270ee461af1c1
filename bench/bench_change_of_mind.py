"""Change of mind (issue 23 item 3, docs/deviations.md, "What is measured"): an operator who switches sequence
once per episode with probability 0.3, against the paper's model and the model with a change of mind and mistakes
(``--switch``, ``--mistakes``), on the same seeded episodes. Two robots per model: the online planner (a fixed
number of expansions per decision: the same actions on any machine) and an observer that always waits (its
belief is the model's Bayes filter on the operator's own work: what the model's belief can reach by itself).

Operators: ``--operator SPELLING`` (default ``uniform,changing:0.3``: after a switch point drawn uniformly, to
another completion of its state, uniformly), or ``--crossing P``: an operator with two habitual sequences that
cross at one state (``CrossingOperator``), who sets out on one, 1/2 each, and with probability P switches there
to the other's completion; its habits are learned from ``--logs`` sessions of its own (the session loop and its
log writer, the robot waiting, then counted as ``aplan habits`` counts them), and the models are the paper's,
the habits' and the habits' with ``--switch`` and ``--mistakes``.

Per model and robot: the switched episodes; the episodes with a belief reset (an observation of probability 0
under the belief: the filter restarts from the prior) and the resets; per reading of "the belief on the new true
sequence" (planner/decision/mind_measures.py: the whole remaining sequence, ``intention``; the lumped model's
class of the next step, ``next class``; the next operation, ``next op``; the assembly state, ``state``) the
switched episodes in which it passed 0.9 at or after the switch and before the product was finished; the robot's
share of the operations, its wrong actions (and their share of its actions) and the mean return.

Run: ``.venv/bin/python bench/bench_change_of_mind.py [--product pen|chain:N|complete:N|FILE|BUNDLE] [--level ID]
[--episodes 200] [--expansions 200] [--switch 0.05] [--mistakes 0.02] [--operator uniform,changing:0.3 |
--crossing 0.3 [--logs 20] [--prior-per edge|state]] [--robots online,observer] [--world model|camera]
[--observe state|step|join]`` (a bundle is planned with ``--fasteners auto --subassemblies auto``). ``--world camera``:
the simulated camera reports the operation the operator did (planner/decision/camera_world.py), not a draw from
the paper's observation model. ``--observe step``: every model but the paper's reads the observations as the
camera's of the step taken (docs/camera.md), and the paper's model is measured a second time so (``paper, step``);
``--observe join``: the same with the camera that sees the pieces joined too (one observation per operation).
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from planner import api, chain_product, complete_product  # noqa: E402
from planner.decision.camera_world import WORLDS  # noqa: E402
from planner.decision.deviations import Deviations  # noqa: E402
from planner.decision.episode_measures import episode_measures, run_totals  # noqa: E402
from planner.decision.mind_measures import READINGS, switch_totals  # noqa: E402
from planner.decision.operators import CrossingOperator, crossing_pair, parse_operator  # noqa: E402
from planner.decision.step_observations import OBSERVE, STATE, of_step  # noqa: E402
from planner.runtime.habits_logs import habits_from_logs  # noqa: E402
from planner.runtime.log import EventLog  # noqa: E402
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot  # noqa: E402
from planner.runtime.session import run_session  # noqa: E402


class Observer:
    """A robot that always waits: every operation is the operator's, and the belief is the filter's alone."""

    def __init__(self, wait: int):
        self.wait = wait

    def action(self, belief) -> int:
        return self.wait


def _run(model, robot, operator, args) -> dict:
    planner = api.online_planner(model, None, args.expansions) if robot == "online" else Observer(model.wait)
    began = time.process_time()
    choice = api.EpisodeChoice(random=args.episodes, seed=args.seed, max_steps=args.max_steps,
                               operator_model=operator, world=args.world)
    mean, half, played = api.evaluate_operator(model, planner, choice)
    totals = run_totals([episode_measures(e) for e in played])
    return {"mean": mean, "half": half, "cpu": time.process_time() - began, **totals,
            **switch_totals(model, played)}


def bench_product(spec: str, level: str | None):
    """``pen``, ``chain:N`` / ``complete:N``, or a product file or bundle (planned as a CAD model is by default), at
    ``level`` if given."""
    kind, _, size = spec.partition(":")
    if kind in ("chain", "complete") and size:
        return {"chain": chain_product, "complete": complete_product}[kind](int(size))
    if spec == "pen":
        return api.resolve_product(spec)
    product = api.resolve_product(spec, None, "auto", None, "auto")
    return api.level_product(product, "designer", level) if level else product


def learned_habits(plan, model, operator: CrossingOperator, logs: int, seed: int, prior_per: str):
    """The habits of ``operator`` counted from ``logs`` session logs of its own (the session loop with a robot
    that waits, so every step is the operator's; each session does the sequence its plan says, switch
    included), as ``aplan habits LOG... --prior-per PRIOR_PER`` counts them."""
    plans = operator.plans(model, logs, np.random.default_rng([seed, 10]), np.random.default_rng([seed, 11]))
    with tempfile.TemporaryDirectory() as folder:
        paths = []
        for k, drawn in enumerate(plans):
            path = Path(folder) / f"session-{k:02d}.jsonl"
            person = ScriptedOperator(plan, model.sequence_operations(operator.done(drawn)))
            result = run_session(model, Observer(model.wait), person, ScriptedRobot(), EventLog(path))
            if not result.assembled:
                raise SystemExit(f"learning session {k} did not finish: {result.message}")
            paths.append(path)
        habits, _ = habits_from_logs(plan, paths)
    return dataclasses.replace(habits, prior_per=prior_per)


def _models(plan, args) -> tuple[object, list[tuple[str, object]]]:
    """The operator and ``(label, model)`` per model measured."""
    deviations = Deviations(args.switch, args.mistakes)
    dev = f"switch {args.switch:g}, mistakes {args.mistakes:g}"
    observe = args.observe
    step = [(f"paper, {observe}", api.factored_decision_model(plan, observe=observe))] if of_step(observe) else []
    if args.crossing is None:
        return parse_operator(args.operator), [
            ("paper", api.factored_decision_model(plan)), *step,
            (dev, api.factored_decision_model(plan, deviations=deviations, observe=observe))]
    paper = api.factored_decision_model(plan)
    first, second, position = crossing_pair(paper, np.random.default_rng([args.seed, 20]))
    operator = CrossingOperator(first, second, position, args.crossing)
    habits = learned_habits(plan, paper, operator, args.logs, args.seed, args.prior_per)
    print(f"crossing at operation {position} of {len(first)} (state {int(paper.class_source[first[position]])}, "
          f"{int(paper.paths[paper.class_source[first[position]]])} completions); the sequences share "
          f"{'their start' if first[:position] == second[:position] else 'only the crossing state'}; habits "
          f"from {args.logs} logs, {habits.total:g} choices counted, prior {habits.prior:g} per {habits.prior_per}")
    return operator, [("paper", paper), *step,
                      ("habits", api.factored_decision_model(plan, habits=habits, observe=observe)),
                      (f"habits, {dev}", api.factored_decision_model(plan, habits=habits, deviations=deviations,
                                                                     observe=observe))]


def _share(count: int, of: int) -> str:
    return f"{count} ({100 * count / of:.0f} %)" if of else "-"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--product", default="pen", help="pen, chain:N, complete:N, a product file or a bundle")
    parser.add_argument("--level", help="the level (subassembly) of a bundle planned in workstations")
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--expansions", type=int, default=200)
    parser.add_argument("--switch", type=float, default=0.05)
    parser.add_argument("--mistakes", type=float, default=0.02)
    parser.add_argument("--operator", help="an --operator-sequence spelling (default uniform,changing:0.3)")
    parser.add_argument("--crossing", type=float, metavar="P",
                        help="instead of --operator: two habitual sequences that cross, switching with probability P")
    parser.add_argument("--logs", type=int, default=20, help="--crossing: the sessions its habits are learned from")
    parser.add_argument("--prior-per", choices=("edge", "state"), default="edge",
                        help="--crossing: the habits' prior spread (aplan habits --prior-per)")
    parser.add_argument("--robots", default="online,observer", help="online, observer or both (comma-separated)")
    parser.add_argument("--world", choices=WORLDS, default="model",
                        help="what the simulated camera reports: model (the paper's O(z | i), default) or camera (the "
                             "operation the operator did)")
    parser.add_argument("--observe", choices=OBSERVE, default=STATE,
                        help="what the models but the paper's read an observation as: of the state reached (the "
                             "paper's), of the step taken (a camera's, docs/camera.md), or of the step and the pieces it "
                             "joined")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-steps", type=int, default=100)
    args = parser.parse_args()
    if args.crossing is not None and args.operator is not None:
        parser.error("--operator and --crossing are two operators: give one")
    args.operator = args.operator or "uniform,changing:0.3"
    plan = api.plan_of(bench_product(args.product, args.level))
    operator, models = _models(plan, args)
    print(f"{args.product}{' ' + args.level if args.level else ''}: operator {operator!r}, {args.episodes} "
          f"episodes, online planner {args.expansions} expansions per decision"
          + (f", world {args.world}" if args.world != "model" else "")
          + (f", observe {args.observe}" if args.observe != STATE else ""))
    print("| model | robot | switched | episodes with a reset (resets) | "
          + " | ".join(f"{name.replace('_', ' ')} > 0.9" for name in READINGS)
          + " | robot share | wrong robot actions | mean return | CPU s |")
    print("|---|---|---:|---:|" + "---:|" * len(READINGS) + "---:|---:|---:|---:|")
    for name, model in models:
        for robot in args.robots.split(","):
            r = _run(model, robot, operator, args)
            share = "-" if r["robot_share"] is None else f"{100 * r['robot_share']:.1f} %"
            wrong = "-" if r["wrong_share"] is None else f"{100 * r['wrong_share']:.1f} %"
            print(f"| {name} | {robot} | {r['switched']} of {r['episodes']} | {r['reset_episodes']} ({r['resets']}) | "
                  + " | ".join(_share(r[reading], r["switched"]) for reading in READINGS)
                  + f" | {share} | {r['wrong_robot_actions']} ({wrong}) | {r['mean']:.3f} +- {r['half']:.3f} | "
                  f"{r['cpu']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
