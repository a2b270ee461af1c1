"""Help before the last step (issue 23, item 2): the parallel and projected models (docs/parallel.md) against the
paper's, with a uniform operator (``--operator-sequence uniform``) and the online planner (a fixed number of
expansions per decision: the same actions on any machine), on the same seeded episodes. Per product: the robot's
share of the operations and of the operations it is able to do, its wrong actions as a share of its actions, and
the mean discounted return.

Run: ``.venv/bin/python bench/bench_parallel.py [--episodes 20] [--expansions 100] [--products pen,chain9,complete7]
[--truck BUNDLE] [--pump BUNDLE] [--levels sa1,top] [--models paper,parallel,projected,joins] [--habitual K]
[--rewards U,F,W]`` (default: the paper's rewards, and the projected model's own act confidence for it, -490
as ``aplan --projected``; ``BUNDLE``: ``aplan export-freecad ../shared/models/toy_truck/asm_cement_mixer_truck.FCStd
-o BUNDLE``, the pump's with ``--group outlet=21_001,26_001``; its levels as ``aplan session BUNDLE --fasteners
auto --subassemblies auto`` plans them; ``--levels``: only those). ``--habitual K``: instead, an operator who does sequence ``K``
80 % of the time (``habitual:K:0.8``), both models with the habits counted from 20 other plans of that operator
(counted directly, as ``aplan habits`` counts logs).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from planner import api, chain_product, complete_product, make_plan  # noqa: E402
from planner.decision.episode_measures import episode_measures, run_totals  # noqa: E402
from planner.decision.factored_model import factored_model  # noqa: E402
from planner.decision.habits import add_sequence, habit_weights_from  # noqa: E402
from planner.decision.intention_model import Rewards  # noqa: E402
from planner.decision.online import OnlinePlanner  # noqa: E402
from planner.decision.operators import parse_operator  # noqa: E402
from planner.decision.presets import preset_rewards  # noqa: E402
from planner.decision.projected import PROJECTED_CONFIDENCE  # noqa: E402


def _products(names: list[str], bundles: list[tuple[str, str]], levels: set[str] | None):
    for name in names:
        if name == "pen":
            yield "pen", api.resolve_product("pen")
        elif name.startswith("chain"):
            yield name, chain_product(int(name[5:]))
        elif name.startswith("complete"):
            yield name, complete_product(int(name[8:]))
        else:
            raise SystemExit(f"unknown product {name!r}")
    for label, bundle in bundles:
        product = api.resolve_product(bundle, None, "auto", {"groups": {}, "exclude": []}, "auto", 8)
        for level in api.levels_of(product, "designer"):
            if levels is None or level.id in levels:
                yield f"{label}:{level.id}", level.product


def _habits(plan, operator, seed: int, sessions: int = 20):
    model = factored_model(plan)
    counts = np.zeros(plan.states.n_edges)
    for p in operator.plans(model, sessions, np.random.default_rng([seed, 99]), np.random.default_rng([seed, 98])):
        add_sequence(plan, counts, model.sequence_operations(p.sequence))
    return habit_weights_from(plan, counts, 1.0)


def _later_q(model) -> float:
    """The largest chance, over the pairs, that the robot's operation ``o`` is right under a wider rule: ``o``
    comes at *any* later step of the operator's sequence, every step before it leaving ``o``'s subassemblies alone
    (so the sequence stays feasible with ``o`` done now). By one pass over the state edges ``(x, o)``, the final
    level first: ``g(x, o) = sum over e out of x of f(e) [op(e) = o] + f(e) g(target e, o) [o still possible
    there]``; a pair's chance is ``g(target e, o)``. Diagnostic only (the model is the step after next)."""
    E = model.final_class
    source, target = model.class_source[:E].astype(int), model.class_target[:E].astype(int)
    operation = model.class_operation[:E].astype(int)
    edge = {(int(s), int(o)): k for k, (s, o) in enumerate(zip(source, operation))}
    g = np.zeros(E)
    for f in np.argsort(source, kind="stable"):  # states are numbered from the final one: targets come first
        x, o = int(source[f]), int(operation[f])
        for e in model.classes_from(x).tolist():
            if operation[e] == o:
                g[f] += model.class_fraction[e]
            elif (int(target[e]), o) in edge:
                g[f] += model.class_fraction[e] * g[edge[int(target[e]), o]]
    par = model.parallel
    chances = [g[edge[int(target[c]), int(model.action_operations[a])]] for c, a in zip(par.pair_class, par.action)]
    return max(chances, default=0.0)


def _run(plan, parallel: bool | str, episodes: int, expansions: int, seed: int, habitual: int | None, rewards: Rewards):
    operator = parse_operator("uniform" if habitual is None else f"habitual:{habitual}:0.8")
    weights = None if habitual is None else _habits(plan, operator, seed)
    model = factored_model(plan, rewards, weights=weights, parallel=parallel)
    planner = OnlinePlanner(model, expansions, None)
    began = time.perf_counter()
    mean, half, played = api.evaluate_operator(model, planner, api.EpisodeChoice(random=episodes, seed=seed,
                                                                             operator_model=operator))
    totals = run_totals([episode_measures(e) for e in played])
    pairs = "- | - | -"
    if parallel:  # and those whose expected reward beats waiting's (q r + (1 - q) wrong > wait)
        par = model.parallel
        worth = int((rewards.wrong + par.fraction * (par.reward - rewards.wrong) > rewards.wait).sum())
        if parallel in ("projected", "joins"):  # the certain ones (q = 1: right for every completion of the class)
            certain = int((par.fraction > 1 - 1e-9).sum())
            pairs = f"{par.size:,} ({worth:,}) | {par.fraction.max(initial=0.0):.3f} | {certain:,} certain"
        else:
            pairs = f"{par.size:,} ({worth:,}) | {par.fraction.max(initial=0.0):.3f} | {_later_q(model):.3f}"
    return mean, half, totals, pairs, time.perf_counter() - began


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--expansions", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--products", default="pen,chain9,complete7")
    parser.add_argument("--truck", metavar="BUNDLE")
    parser.add_argument("--pump", metavar="BUNDLE")
    parser.add_argument("--levels", metavar="ID,ID", help="only these levels of the bundles")
    parser.add_argument("--models", default="paper,parallel", help="of paper, parallel, projected, joins")
    parser.add_argument("--habitual", type=int, metavar="K")
    parser.add_argument("--rewards", default=None, metavar="U,F,W",
                        help="unfavorable, favorable and wrong rewards (default the paper's 10,-2,-50, and for the "
                             "projected model its own act confidence, as aplan's --projected: -490)")
    args = parser.parse_args()
    given = None if args.rewards is None else Rewards(*(float(x) for x in args.rewards.split(",")), 0.0)
    kinds = {"paper": False, "parallel": True, "projected": "projected", "joins": "joins"}
    models = [m for m in args.models.split(",") if m]
    if not models or any(m not in kinds for m in models):
        raise SystemExit(f"--models: a list of {', '.join(kinds)}, got {args.models!r}")
    bundles = [(label, path) for label, path in (("truck", args.truck), ("pump", args.pump)) if path]
    levels = set(args.levels.split(",")) if args.levels else None
    print("| product | model | pairs (worth a try) | max q | max q, any later step / certain | robot share | capable "
          "share | wrong / robot actions | mean return (95 %) | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, product in _products([p for p in args.products.split(",") if p], bundles, levels):
        plan = make_plan(product)
        for label in models:
            own = (f"--{label}", PROJECTED_CONFIDENCE) if label in ("projected", "joins") else None
            rewards = given if given is not None else preset_rewards(None, 10.0, -2.0, 0.0, None, None, own)
            cpu = time.process_time()
            mean, half, t, pairs, _ = _run(plan, kinds[label], args.episodes, args.expansions, args.seed,
                                           args.habitual, rewards)
            cpu = time.process_time() - cpu
            share = "-" if t["robot_share"] is None else f"{100 * t['robot_share']:.1f} % ({t['robot_operations']})"
            capable = "-" if t["robot_capable_share"] is None else \
                f"{100 * t['robot_capable_share']:.1f} % of {t['robot_capable_operations']}"
            wrong = "-" if t["wrong_share"] is None else f"{100 * t['wrong_share']:.1f} % ({t['wrong_robot_actions']})"
            interval = f"{mean:.3f} +- {half:.3f}" if math.isfinite(half) else f"{mean:.3f}"
            print(f"| {name} | {label} | {pairs} | {share} | {capable} | {wrong} | {interval} | {cpu:.0f} |",
                  flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
