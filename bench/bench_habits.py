"""Operator habits (issue 23), a quick measure: on the pen (no technical constraint), an operator who follows one
full sequence 80 % of the time (else any other, uniformly); habits learned from 20 session logs of that operator
(written through the project's session loop and log writer, the operator assembling alone); then the paper's
model and the habits' model, each with the online planner (a fixed number of expansions per decision: the same
actions on any machine), on the same seeded episodes drawn from that operator.

Run: ``.venv/bin/python bench/bench_habits.py [--episodes 300] [--logs 20] [--expansions 200]`` (about a minute
per 100 episodes on one core). ``--write-habits FILE`` also writes the learned habits (for ``aplan evaluate
--habits FILE --operator-sequence habitual:5:0.8``; ``--episodes 0``: only that).
"""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from planner import api  # noqa: E402
from planner.decision.factored_model import factored_model  # noqa: E402
from planner.decision.factored_simulate import simulate_factored_episode  # noqa: E402
from planner.decision.habits import habit_weights  # noqa: E402
from planner.decision.intention_model import intention_model  # noqa: E402
from planner.decision.io.habits_file import write_habits  # noqa: E402
from planner.runtime.habits_logs import habits_from_logs  # noqa: E402
from planner.runtime.log import EventLog  # noqa: E402
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot  # noqa: E402
from planner.runtime.session import run_session  # noqa: E402


class _Wait:
    def __init__(self, n_actions: int):
        self.wait = n_actions - 1

    def action(self, belief) -> int:
        return self.wait


def _operator_rank(rng: np.random.Generator, favourite: int, n: int, share: float) -> int:
    """The operator's sequence: ``favourite`` with probability ``share``, else any other, uniformly."""
    if rng.random() < share:
        return favourite
    other = int(rng.integers(n - 1))
    return other if other < favourite else other + 1


def _write_logs(plan, ranks: list[int], folder: Path) -> list[Path]:
    flat = intention_model(plan)
    fact = factored_model(plan)
    paths = []
    for k, rank in enumerate(ranks):
        operator = ScriptedOperator(plan, fact.sequence_operations(fact.sequence(rank)))
        path = folder / f"session-{k:02d}.jsonl"
        result = run_session(flat, _Wait(len(flat.actions)), operator, ScriptedRobot(), EventLog(path))
        assert result.assembled, result.message
        paths.append(path)
    return paths


def _mean(returns: list[float]) -> tuple[float, float]:
    mean = float(np.mean(returns))
    return mean, 1.96 * float(np.std(returns, ddof=1)) / math.sqrt(len(returns))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--logs", type=int, default=20)
    parser.add_argument("--expansions", type=int, default=200)
    parser.add_argument("--share", type=float, default=0.8, help="how often the operator takes its favourite")
    parser.add_argument("--favourite", type=int, default=5, help="the favourite sequence's rank (0 to 23)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--write-habits", metavar="FILE", help="write the learned habits to FILE")
    args = parser.parse_args()

    plan = api.plan_of("pen", technical=False)
    paper = factored_model(plan)
    n = paper.n_sequences
    rng = np.random.default_rng(args.seed)
    learned_ranks = [_operator_rank(rng, args.favourite, n, args.share) for _ in range(args.logs)]
    with tempfile.TemporaryDirectory() as folder:
        began = time.perf_counter()
        logs = _write_logs(plan, learned_ranks, Path(folder))
        habits, steps = habits_from_logs(plan, logs)
        learned = time.perf_counter() - began
    if args.write_habits:
        write_habits(args.write_habits, habits, len(logs))
        print(f"wrote {args.write_habits}")
    print(f"pen: {n} sequences; {args.logs} logs ({learned_ranks.count(args.favourite)} of the favourite "
          f"sequence {args.favourite}), {steps} steps counted, {len(habits.counts)} state edges, "
          f"{learned:.1f} s to write and learn them")
    weighted = factored_model(plan, weights=habit_weights(plan, habits))
    start = paper.sequence(args.favourite)
    print(f"prior of the favourite sequence: paper {1 / n:.4f}, habits "
          f"{math.exp(sum(math.log(weighted.class_fraction[e]) for e in start)):.4f}")

    if args.episodes < 1:
        return
    episode_rng = np.random.default_rng(args.seed + 1)
    ranks = [_operator_rank(episode_rng, args.favourite, n, args.share) for _ in range(args.episodes)]
    seeds = episode_rng.integers(2 ** 32, size=args.episodes)
    for name, model in (("paper", paper), ("habits", weighted)):
        planner = api.online_planner(model, decision_time=None, expansions=args.expansions)
        began = time.perf_counter()
        returns, steps_taken = [], []
        for rank, seed in zip(ranks, seeds):
            episode = simulate_factored_episode(model, planner, paper.sequence(rank), np.random.default_rng(int(seed)))
            returns.append(episode.discounted_return)
            steps_taken.append(len(episode.steps))
        mean, half = _mean(returns)
        fav = [r for r, k in zip(returns, ranks) if k == args.favourite]
        rest = [r for r, k in zip(returns, ranks) if k != args.favourite]
        print(f"{name:>6}: mean return {mean:.3f} +- {half:.3f} (95 %) over {len(returns)} episodes; favourite "
              f"{np.mean(fav):.3f} ({len(fav)}), others {np.mean(rest):.3f} ({len(rest)}); mean steps "
              f"{np.mean(steps_taken):.2f}; {time.perf_counter() - began:.1f} s")


if __name__ == "__main__":
    main()
