"""The best any habits could do (issue 23, "Habits help": why capable >= 30 % and wrong <= 2 % are not met
together): the flat model of a small product whose initial belief is the *true* operator's distribution over
full sequences (``habitual:K:STRENGTH``: K with probability STRENGTH, else uniform; K as bench_habits.py draws
it), i.e. a robot that knows the operator exactly, solved offline at each act confidence C and played on
``--episodes`` episodes of that operator. Learned habits (counts per state, bench_habits.py) cannot beat it:
it is the Bayes-optimal belief, so its (capable, wrong) curve bounds theirs.

Run: ``.venv/bin/python bench/bench_habits_oracle.py [pen] --act-confidence 0.9,0.95,0.98 [--episodes 500]``
(flat model: small products only, the pen's 24 sequences in seconds).
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from bench_habits import _confidences, _mean, _pct, favourite_of, paper_return  # noqa: E402
from planner import api  # noqa: E402
from planner.decision.episode_measures import episode_measures, run_totals  # noqa: E402
from planner.decision.factored_model import factored_model  # noqa: E402
from planner.decision.intention_model import intention_model  # noqa: E402
from planner.decision.operators import HabitualOperator  # noqa: E402
from planner.decision.presets import preset_rewards  # noqa: E402
from planner.decision.simulate import IntentionWorld, simulate_episode  # noqa: E402
from planner.decision.solvers import PointBasedSolver  # noqa: E402


def oracle_rows(product: str, confidences: list[float], episodes: int, seed: int, share: float, trials: int):
    plan = api.plan_of(api.resolve_product(product))
    fact = factored_model(plan)
    favourite = favourite_of(fact.n_sequences, seed)
    wanted = fact.sequence_operations(fact.sequence(favourite))
    for c in confidences:
        flat = intention_model(plan, preset_rewards(None, 10.0, -2.0, 0.0, None, c))
        full = flat.full_sequences()
        k = next(int(i) for i in full if flat.sequence_operations(int(i)) == wanted)
        initial = np.zeros(flat.pomdp.n_states)
        initial[full] = (1 - share) / full.size
        initial[k] += share
        truth = replace(flat.pomdp, initial=initial)
        result = PointBasedSolver(max_iterations=trials, time_limit=None, precision=1e-3).solve(truth)
        plans = HabitualOperator(k, share).plans(flat, episodes, np.random.default_rng([seed, 14]),
                                                 np.random.default_rng([seed, 15]))
        played = [simulate_episode(IntentionWorld(truth, p.sequence, flat.graph.successor, flat.final_state),
                                   result.policy, np.random.default_rng([seed, 12, j])) for j, p in enumerate(plans)]
        totals = run_totals([episode_measures(e) for e in played])
        mean, half = _mean([paper_return(e, truth.discount) for e in played])
        yield c, totals, mean, half, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("product", nargs="?", default="pen")
    parser.add_argument("--act-confidence", type=_confidences, default=[5 / 6, 0.9, 0.95, 0.98], metavar="C[,C]")
    parser.add_argument("--episodes", type=int, default=500)
    parser.add_argument("--share", type=float, default=0.8)
    parser.add_argument("--trials", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    for c, t, mean, half, result in oracle_rows(args.product, args.act_confidence, args.episodes, args.seed,
                                                args.share, args.trials):
        print(f"{args.product} C={c:g}: robot {_pct(t['robot_capable_share'])} of the operations it can do "
              f"({t['robot_operations']} of {t['robot_capable_operations']}), wrong {_pct(t['wrong_share'])} "
              f"({t['wrong_robot_actions']}); mean return (paper's rewards) {mean:.3f} +- {half:.3f}; bounds "
              f"{result.lower_bound:.3f} to {result.upper_bound:.3f}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
