"""Operator habits (issue 23, "Habits help" and "Nothing is lost"): on any product, level by level, an operator who
follows one full sequence with probability 0.8 (``habitual:K:0.8``, else any sequence uniformly); its habits
learned through the real pipeline (20 session logs written by the session loop and log writer, the operator
assembling alone, then ``aplan habits LOG... -o H.json`` run as a command); then the paper's model and the
habits' model on the same 500 fresh episodes (the same plans and the same world draws, episode by episode).

Per product and level it prints the robot's share of the operations it is able to do (robot-capable operations
of the sequences done), its wrong actions as a share of its actions, and the mean discounted return +- 95 %
(normal approximation) under both models, with the issue's targets checked (share >= 30 %, wrong <= 2 %, return
>= 2x the paper model's, or > 0 where that is <= 0). ``--operator uniform`` is the "Nothing is lost" case: the
habits of a uniform operator, against the paper's model (target: the habits model's mean within the paper
model's 95 % interval or above).

Planner: the online planner with a fixed number of expansions per decision (``--expansions``, no clock: the same
actions on any machine) on the factored model, which is exact (the same beliefs and values as the flat model);
``--planner offline`` solves a policy over the lumped model's classes instead (bounded by ``--trials``), when
the lumped model is small enough (``--max-classes``); ``auto`` (the default) takes that policy only when the
solve closes the gap between its bounds at the initial belief to ``--max-gap``, else the online planner.

Run: ``.venv/bin/python bench/bench_habits.py PRODUCT... [--episodes 500] [--logs 20] [--expansions 200]``
with PRODUCT ``pen``, ``chain:9`` / ``complete:7`` (written by ``aplan synth``), a product file or a bundle
folder (planned with ``--fasteners auto --subassemblies auto``; every level, or ``--level ID,ID``).
``--write-habits FILE`` also writes the learned habits (``--episodes 0``: only that), for ``aplan evaluate
--habits FILE --operator-sequence habitual:K:0.8``.

The habits' model's knobs (docs/habits.md): ``--prior ALPHA --prior-per edge|state`` (given to ``aplan habits``),
``--act-confidence C[,C...]`` (the habits' model's eagerness, each C a row of its own on the same episodes: the
trade-off curve; the paper's model keeps the paper's rewards), ``--model confident`` (the preset: its prior and
confidence unless given), ``--model orders`` (the orders' model, planner/decision/orders.py: the Pitman-Yor
mixture over the recorded orders, ``--concentration A --discount D`` given to ``aplan habits``, at each
``--act-confidence``, default the preset's 0.95; with it the per-state habits of ``--model confident`` on the same
episodes, for comparison).

``--world camera`` plays every episode in the camera world (planner/decision/camera_world.py: the camera reports
the operation done, blank when nothing was) and ``--observe step`` gives every model but the paper's a camera's
observations (planner/decision/step_observations.py; row ``step``: the uniform prior with them).

``--parallel projected|joins`` (repeatable, or a comma list; docs/parallel.md) adds, on the same episodes, the
robot's help before the last step: the parallel model with the paper's uniform prior (label ``joins``) and with
the per-state habits of ``--model confident`` (``state+joins``), at each ``--act-confidence``, by default the
projected model's own confidence (0.98, the larger of it and the preset's). The orders' model with a parallel
model is refused by the model (planner/decision/orders.py, ``check_alone``), so none is built.
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from planner import api  # noqa: E402
from planner.decision.episode_measures import episode_measures, run_totals  # noqa: E402
from planner.decision.factored_model import factored_model  # noqa: E402
from planner.decision.factored_simulate import PathWorld  # noqa: E402
from planner.decision.simulate import simulate_episode  # noqa: E402
from planner.decision.habits import habit_weights  # noqa: E402
from planner.decision.io.habits_file import read_habits  # noqa: E402
from planner.decision.operators import HabitualOperator, UniformOperator  # noqa: E402
from planner.decision.orders import orders_prior  # noqa: E402
from planner.decision.presets import PRESETS, preset_habits, preset_rewards  # noqa: E402
from planner.decision.projected import PROJECTED, PROJECTED_CONFIDENCE  # noqa: E402
from planner.decision.joins import JOINS  # noqa: E402
from planner.runtime.log import EventLog  # noqa: E402
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot  # noqa: E402
from planner.runtime.session import run_session  # noqa: E402

APLAN = [sys.executable, "-m", "planner"]


class _Wait:
    """The robot of the learning sessions: it waits, so every logged step is the operator's own choice."""

    def __init__(self, wait: int):
        self.wait = wait

    def action(self, belief) -> int:
        return self.wait


def _products(specs: list[str], level: str | None, folder: Path) -> list[tuple[str, api.Product]]:
    """``(name, product)`` per level to measure: ``pen``; ``chain:N`` / ``complete:N`` through ``aplan synth``;
    a product file or bundle planned as a CAD model is by default (proposed fasteners and workstations)."""
    out = []
    for spec in specs:
        if spec == "pen":
            out.append(("pen", api.resolve_product("pen")))
            continue
        if spec.split(":")[0] in ("chain", "complete"):
            out.append((spec.replace(":", " "), api.resolve_product(synth_product(spec, folder))))
            continue
        product = api.resolve_product(spec, None, "auto", None, "auto")
        name = Path(spec).name
        ids = level.split(",") if level else [lv.id for lv in api.levels_of(product)]
        for lv in ids:
            out.append((f"{name} {lv}" if len(ids) > 1 or level else name, api.level_product(product, "designer", lv)))
    return out


def synth_product(spec: str, folder: Path) -> Path:
    """``chain:N`` or ``complete:N`` written by ``aplan synth`` into ``folder``."""
    kind, n = spec.split(":")
    path = folder / f"{kind}{n}.json"
    subprocess.run(APLAN + ["synth", kind, n, "-o", str(path)], check=True, cwd=ROOT, capture_output=True)
    return path


def favourite_of(n_sequences: int, seed: int) -> int:
    """The habitual operator's sequence (a rank), drawn from the seed: no hand-picked one."""
    return int(np.random.default_rng([seed, 13]).integers(n_sequences))


def learn_habits(product: Path, logs: int, seed: int, folder: Path, share: float = 0.8,
                 prior: tuple[str, ...] = ()) -> tuple[Path, int]:
    """The habits file learned (:func:`_learn`) from ``logs`` sessions of the operator ``habitual:K:share`` on
    ``product`` (K: :func:`favourite_of`), and K."""
    plan = api.plan_of(api.resolve_product(product))
    model = factored_model(plan)
    favourite = favourite_of(model.n_sequences, seed)
    _learn(plan, model, HabitualOperator(favourite, share), logs, seed, folder, product.name, prior)
    return folder / "habits.json", favourite


def _learn(plan, model, operator, logs: int, seed: int, folder: Path, name: str, prior: tuple[str, ...] = ()):
    """The habits of ``operator`` from ``logs`` sessions (the session loop, its log writer, then ``aplan
    habits`` as a command): the habits read back and checked against ``plan``, and the steps counted."""
    plans = operator.plans(model, logs, np.random.default_rng([seed, 10]), np.random.default_rng([seed, 11]))
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for k, drawn in enumerate(plans):
        path = folder / f"session-{k:02d}.jsonl"
        person = ScriptedOperator(plan, model.sequence_operations(drawn.sequence))
        result = run_session(model, _Wait(model.wait), person, ScriptedRobot(), EventLog(path))
        if not result.assembled:
            raise SystemExit(f"{name}: learning session {k} did not finish: {result.message}")
        paths.append(str(path))
    output = folder / "habits.json"
    done = subprocess.run(APLAN + ["habits", *paths, "-o", str(output), "--json", *prior], cwd=ROOT,
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{name}: aplan habits failed: {done.stderr.strip()}")
    return read_habits(output), json.loads(done.stdout)["steps"]


def _policy(args, plan, model, build: dict):
    """The robot's policy on ``model`` (``factored_model(plan, rewards, **build)``: edge weights, orders, a
    parallel model) and what it is: ``offline`` (or ``auto`` when its solve closes the gap at the initial belief
    to ``--max-gap``) a policy over the lumped model's classes (the same model lumped), else the online planner."""
    # (a model with a camera's observations has no lumped tables: the online planner's alone)
    if args.planner in ("offline", "auto") and model.n_classes <= args.max_classes and model.observe == "state":
        from planner.decision.lumped_model import lumped_model
        from planner.decision.solvers import PointBasedSolver

        lumped = lumped_model(plan, model.rewards, **build)
        result = PointBasedSolver(max_iterations=args.trials, time_limit=None, precision=1e-3).solve(lumped.pomdp)
        gap = result.upper_bound - result.lower_bound
        if args.planner == "offline" or gap <= args.max_gap:
            return result.policy, (f"offline lumped policy ({args.trials} trials, bounds {result.lower_bound:.3f} "
                                   f"to {result.upper_bound:.3f})")
    return (api.online_planner(model, decision_time=None, expansions=args.expansions),
            f"online planner, {args.expansions} expansions per decision")


def paid_share(model, plans) -> float:
    """Of the robot-capable operations in the sequences the operator sets out to do, the share the paper's
    rewards pay the robot for (unfavorable to humans: +10; the others give it -2, so an optimal robot leaves them
    to the operator): the most of the capable share the robot can take without losing reward."""
    tags, capable, paid = model.plan.tags, 0, 0
    for p in plans:
        ops = model.sequence_operations(p.sequence)
        capable += sum(bool(tags.robot[o]) for o in ops)
        paid += sum(bool(tags.robot[o] and tags.unfavorable[o]) for o in ops)
    return round(paid / capable, 4) if capable else 0.0


def _run(model, policy, plans, seed: int, orders=None, camera: bool = False) -> list:
    """One episode per plan, each with its own world stream: the same draws for every model given them (the
    plans' real state edges as the orders' augmented classes on the orders' model); ``camera``: the camera
    world's observations (planner/decision/camera_world.py) instead of the model's."""
    path = (lambda s: s) if orders is None else orders.augmented_path
    return [simulate_episode(PathWorld(model, path(p.sequence), camera=camera), policy,
                             np.random.default_rng([seed, 12, k]), switch=p.switch) for k, p in enumerate(plans)]


def paper_return(episode, discount: float, wrong: float = -50.0) -> float:
    """The episode's discounted return under the paper's rewards: only the wrong action's reward differs
    between the variants (a right operation's and waiting's are the paper's in all), so the returns of models
    of other eagerness compare on one scale (the issue's "mean return" target)."""
    total, g = 0.0, 1.0
    for step in episode.steps:
        total += g * (wrong if step.wrong_action else step.reward)
        g *= discount
    return total


def _mean(values) -> tuple[float, float]:
    values = np.asarray(values, dtype=float)
    half = 1.96 * float(values.std(ddof=1)) / math.sqrt(values.size) if values.size > 1 else float("nan")
    return float(values.mean()), half


def _pct(x) -> str:
    return "-" if x is None else f"{100 * x:.1f} %"


def _prior_options(args) -> tuple[str, ...]:
    """The ``aplan habits`` options of the prior (``--prior``, ``--prior-per``, or the preset's)."""
    out = []
    if args.prior is not None:
        out += ["--prior", repr(args.prior)]
    if args.prior_per is not None:
        out += ["--prior-per", args.prior_per]
    for flag in ("concentration", "discount"):
        if getattr(args, flag) is not None:
            out += [f"--{flag}", repr(getattr(args, flag))]
    return tuple(out)


def _variants(args, plan, habits) -> list[tuple[str, object, dict]]:
    """``(label, model, build)`` (``build``: the keywords of ``factored_model`` besides its rewards): the paper's
    model (its rewards), then the habits' model at each ``--act-confidence`` (the preset's, or the paper's rewards
    without one); with ``--model orders`` the per-state habits of ``--model confident`` first, then the orders'
    model at each confidence; then :func:`_parallel_variants`."""
    preset = PRESETS.get(args.model)
    confidences = args.act_confidence or [None]
    out = [("paper", factored_model(plan), {})]
    if args.observe == "step":  # the paper's model stays the reference; the uniform prior with a camera's too
        out.append(("step", factored_model(plan, observe="step"), {}))
    if preset is not None and preset.orders:
        counts = PRESETS["confident"]
        weights = habit_weights(plan, preset_habits(counts, habits))
        out.append(("state", factored_model(plan, preset_rewards(counts, 10.0, -2.0, 0.0, None, None),
                                            weights=weights, observe=args.observe), {"weights": weights}))
        orders = orders_prior(plan, preset_habits(preset, habits))
        for c in confidences:
            label = "orders" if len(confidences) == 1 else f"orders C={c:g}"
            out.append((label, factored_model(plan, preset_rewards(preset, 10.0, -2.0, 0.0, None, c), orders=orders,
                                                observe=args.observe),
                        {"orders": orders}))
        return out + _parallel_variants(args, plan, habits)
    weights = habit_weights(plan, habits)
    for c in confidences:
        rewards = preset_rewards(preset, 10.0, -2.0, 0.0, None, c)
        label = "habits" if len(confidences) == 1 else f"habits C={c:g}"
        out.append((label, factored_model(plan, rewards, weights=weights, observe=args.observe), {"weights": weights}))
    return out + _parallel_variants(args, plan, habits)


def _parallel_variants(args, plan, habits) -> list[tuple[str, object, dict]]:
    """Per ``--parallel`` rule R and ``--act-confidence`` C: ``R`` (the paper's uniform prior) and ``state+R`` (the
    per-state habits of ``--model confident``), each at C, else at the larger of the projected model's own
    confidence and the preset's (``preset_rewards``' ``model_confidence``, as ``aplan --joins --model confident``
    takes it). Cost: two factored models (and parallel tables) per rule and confidence."""
    out, confident = [], PRESETS["confident"]
    weights = habit_weights(plan, preset_habits(confident, habits)) if args.parallel else None
    confidences = args.act_confidence or [None]
    for rule in args.parallel:
        own = (f"--{rule}", PROJECTED_CONFIDENCE)
        for c in confidences:
            tail = "" if len(confidences) == 1 else f" C={c:g}"
            for label, preset, w in ((rule, None, None), (f"state+{rule}", confident, weights)):
                rewards = preset_rewards(preset, 10.0, -2.0, 0.0, None, c, own)
                out.append((label + tail, factored_model(plan, rewards, weights=w, parallel=rule, observe=args.observe),
                            {"weights": w, "parallel": rule}))
    return out


def _measure(args, name: str, product, folder: Path) -> dict:
    began = time.perf_counter()
    plan = api.plan_of(product, args.technical)
    paper = factored_model(plan)
    n = paper.n_sequences
    favourite = favourite_of(n, args.seed) if args.favourite is None else args.favourite
    operator = UniformOperator() if args.operator == "uniform" else HabitualOperator(favourite % n, args.share)
    habits, steps = _learn(plan, paper, operator, args.logs, args.seed, folder, name, _prior_options(args))
    if args.write_habits:  # for aplan evaluate --habits FILE --operator-sequence (README, Simulated operators)
        Path(args.write_habits).write_bytes((folder / "habits.json").read_bytes())
        print(f"{name}: wrote {args.write_habits} (operator {operator!r})")
    if args.episodes == 0:
        return None
    plans = operator.plans(paper, args.episodes, np.random.default_rng([args.seed, 14]),
                           np.random.default_rng([args.seed, 15]))
    row = {"product": name, "parts": len(plan.product.parts), "sequences": n, "operator": repr(operator),
           "logs": args.logs, "steps_learned": steps, "episodes": args.episodes,
           "prior": habits.prior, "prior_per": habits.prior_per, "recorded_orders": [n for _, n in habits.orders],
           "concentration": habits.concentration, "discount": habits.discount}
    returns, chosen = {}, {}
    for label, model, build in _variants(args, plan, habits):
        started = time.perf_counter()
        chosen[label] = (model, *_policy(args, plan, model, build), time.perf_counter() - started,
                         build.get("orders"))
    if args.online_episodes and any(how.startswith("online") for _, _, how, _, _ in chosen.values()):
        plans = plans[:args.online_episodes]  # the first ones: the same episodes for both models
        row["episodes"] = len(plans)
    row["paid_share"] = paid_share(paper, plans)
    row["labels"] = list(chosen)
    for label, (model, policy, how, solving, orders) in chosen.items():
        started = time.perf_counter() - solving
        played = _run(model, policy, plans, args.seed, orders, args.world == "camera")
        totals = run_totals([episode_measures(e) for e in played])
        returns[label] = [paper_return(e, model.discount) for e in played]
        mean, half = _mean(returns[label])
        own, own_half = _mean([e.discounted_return for e in played])
        row[label] = {"mean_return": round(mean, 4), "ci95": round(half, 4), "wrong_reward": model.rewards.wrong,
                      "own_return": round(own, 4), "own_ci95": round(own_half, 4),
                      "robot_capable_share": totals["robot_capable_share"], "wrong_share": totals["wrong_share"],
                      "robot_share": totals["robot_share"], "never_helped": totals["never_helped"],
                      "robot_operations": totals["robot_operations"], "wrong_robot_actions": totals["wrong_robot_actions"],
                      "robot_capable_operations": totals["robot_capable_operations"],
                      "planner": how, "seconds": round(time.perf_counter() - started, 1)}
        if label != "paper":
            diff_mean, diff_half = _mean(np.subtract(returns[label], returns["paper"]))
            row[label]["paired_difference"] = {"mean": round(diff_mean, 4), "ci95": round(diff_half, 4)}
            row[label]["targets"] = _targets(args.operator, row["paper"], row[label])
    row["seconds"] = round(time.perf_counter() - began, 1)
    return row


def _targets(operator: str, p: dict, h: dict) -> dict:
    if operator == "uniform":  # nothing lost: within the paper model's 95 % interval, or above it
        return {"within_or_above": h["mean_return"] >= p["mean_return"] - p["ci95"]}
    paper = p["mean_return"]
    return {"share_30": (h["robot_capable_share"] or 0) >= 0.30,
            "wrong_2": h["wrong_share"] is None or h["wrong_share"] <= 0.02,
            "return_2x": h["mean_return"] > 0 if paper <= 0 else h["mean_return"] >= 2 * paper}


def _print(row: dict) -> None:
    print(f"{row['product']}: {row['parts']} parts, {row['sequences']:,} sequences; operator {row['operator']}; "
          f"{row['steps_learned']} steps learned from {row['logs']} logs (prior {row['prior']:g} per "
          f"{row['prior_per']}; orders recorded {row['recorded_orders']}, a {row['concentration']:g}, d {row['discount']:g}); "
          f"{row['episodes']} episodes; "
          f"{_pct(row['paid_share'])} of the capable operations are unfavorable to humans (paid +10)")
    for label in row["labels"]:
        m = row[label]
        print(f"  {label:>6}: robot {_pct(m['robot_capable_share'])} of the operations it can do ("
              f"{m['robot_operations']} of {m['robot_capable_operations']}; {_pct(m['robot_share'])} of all), wrong "
              f"{_pct(m['wrong_share'])} of its actions ({m['wrong_robot_actions']}), never helped "
              f"in {m['never_helped']}; mean return (paper's rewards) {m['mean_return']:.3f} +- {m['ci95']:.3f}, "
              f"under its own (wrong {m['wrong_reward']:g}) {m['own_return']:.3f}; {m['planner']}, {m['seconds']} s")
        if label != "paper":
            d = m["paired_difference"]
            missed = [k for k, ok in m["targets"].items() if not ok]
            print(f"          - paper (paired): {d['mean']:.3f} +- {d['ci95']:.3f}; targets "
                  + ("met" if not missed else "MISSED: " + ", ".join(missed)))


def _parallel_rules(text: str) -> list[str]:
    """``--parallel``'s rules: a comma list of ``projected`` and ``joins`` (factored_model's names)."""
    out = [r.strip() for r in text.split(",") if r.strip()]
    if not out or any(r not in (PROJECTED, JOINS) for r in out):
        raise argparse.ArgumentTypeError(f"--parallel takes {PROJECTED} or {JOINS} (or both, comma-separated), got "
                                         f"{text!r}")
    return out


def _confidences(text: str) -> list[float]:
    out = [float(c) for c in text.split(",")]
    if not all(0 < c < 1 for c in out):  # NaN fails too
        raise argparse.ArgumentTypeError(f"each confidence must be above 0 and below 1, got {text}")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("products", nargs="*", default=["pen"], metavar="PRODUCT")
    parser.add_argument("--level", help="only these levels (ID,ID...) of a product planned in workstations")
    parser.add_argument("--episodes", type=int, default=500)
    parser.add_argument("--logs", type=int, default=20)
    parser.add_argument("--operator", choices=("habitual", "uniform"), default="habitual",
                        help="habitual (habitual:K:SHARE) or uniform (the 'nothing is lost' case)")
    parser.add_argument("--share", type=float, default=0.8, help="how often the operator takes its favourite")
    parser.add_argument("--favourite", type=int, help="the favourite sequence's rank (default: a seeded draw)")
    parser.add_argument("--planner", choices=("auto", "online", "offline"), default="auto",
                        help="auto: the offline lumped policy when its solve converges (--max-gap), else online")
    parser.add_argument("--expansions", type=int, default=200)
    parser.add_argument("--online-episodes", type=int, metavar="N",
                        help="when the online planner decides (slow on a loaded machine), only the first N episodes")
    parser.add_argument("--trials", type=int, default=300, help="solver trials for --planner offline or auto")
    parser.add_argument("--max-gap", type=float, default=0.5, help="auto: the largest upper - lower bound accepted")
    parser.add_argument("--max-classes", type=int, default=2000, help="largest lumped model --planner offline solves")
    parser.add_argument("--technical", action=argparse.BooleanOptionalAction, default=None)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--world", choices=("model", "camera"), default="model",
                        help="the simulated world's observations: the paper's model's (default) or the camera's")
    parser.add_argument("--observe", choices=("state", "step"), default="state",
                        help="the robot's model (all but the paper's row): the paper's observations, or a camera's "
                             "(step: adds the row 'step', the uniform prior with a camera's; online planner only)")
    parser.add_argument("--json", action="store_true", help="one JSON line per product and level")
    parser.add_argument("--write-habits", metavar="FILE", help="also write the learned habits (one product)")
    parser.add_argument("--prior", type=float, help="aplan habits --prior ALPHA (default: its own)")
    parser.add_argument("--prior-per", choices=("edge", "state"), help="aplan habits --prior-per (default: edge)")
    parser.add_argument("--act-confidence", type=_confidences, metavar="C[,C...]",
                        help="the habits' model's eagerness (one row each on the same episodes; default: -50)")
    parser.add_argument("--model", choices=("habits", "confident", "orders"), default="habits",
                        help="confident: the preset's prior and act confidence, unless given; orders: the orders' "
                             "model (and the per-state habits of confident, for comparison)")
    parser.add_argument("--parallel", type=_parallel_rules, action="append", default=[], metavar="RULE[,RULE]",
                        help="also the parallel model RULE (projected or joins; docs/parallel.md) with the paper's "
                             "prior and with the per-state habits of --model confident, at each --act-confidence "
                             f"(default {PROJECTED_CONFIDENCE:g}, the projected model's own)")
    parser.add_argument("--concentration", type=float, help="aplan habits --concentration (the orders' a)")
    parser.add_argument("--discount", type=float, help="aplan habits --discount (the orders' d)")
    args = parser.parse_args()
    args.parallel = list(dict.fromkeys(r for rules in args.parallel for r in rules))  # repeated: once each
    if args.model == "confident":
        preset = PRESETS["confident"]
        args.prior = preset.prior if args.prior is None else args.prior
        args.prior_per = args.prior_per or preset.prior_per
    if args.episodes == 1 or args.episodes < 0 or args.logs < 1:
        parser.error("--episodes must be 0 (only learn) or at least 2, and --logs at least 1")
    if args.write_habits and len(args.products) > 1:
        parser.error("--write-habits writes one product's habits: give one PRODUCT (and one --level)")
    with tempfile.TemporaryDirectory() as folder:
        for k, (name, product) in enumerate(_products(args.products, args.level, Path(folder))):
            row = _measure(args, name, product, Path(folder) / f"logs-{k}")
            if row is None:
                continue
            if args.json:
                print(json.dumps(row))
            else:
                _print(row)
            sys.stdout.flush()


if __name__ == "__main__":
    main()
