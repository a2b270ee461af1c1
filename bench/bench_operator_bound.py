"""The best mean return any robot can have against bench_habits.py's habitual operator (issue 23, "Habits help").

bench_habits.py measures each model against an operator who follows one sequence (K, drawn from the seed as
there) with probability S and otherwise a uniformly drawn one. The issue's return target is twice the paper
model's mean. Where a level misses it, this bench tells whether any robot could meet it under the same
observations: it builds the model whose prior IS that operator (its exact probability of each state edge, no
learning: per-edge counts ``sum over sequences of P(sequence) [edge in sequence]`` with a prior of 1e-9), with
the joins rule or without (``--parallel``), the paper's rewards (+10 / -2 / -50 / 0, discount 0.9), lumps it and
solves it with the point-based solver (``--trials``, no clock). The upper bound at the initial belief then
bounds the expected discounted return of every policy, over every robot whose world is the model's: the same
transitions, the paper's observation function, the same rewards.

It is exact when the operator's distribution over sequences is a Markov chain on the assembly states (each
state's next step independent of how it was reached). The bench checks it: it prints the largest difference
between a sequence's probability under the per-state chain and under the operator (0 on a level of three
operations or fewer: a state one step in has one history, and two steps in, one way on). Else the bound is of
the per-state operator closest to it, and says so.

Its twin, ``bench_habits_oracle.py``, puts the true operator in the flat model's initial belief: exact for any
operator, but without the joins rule (the flat model has no parallel variant) and for small products only. This
one is for the joins model and a bundle's levels (lumped).

    nice -n 10 prlimit --as=6000000000 .venv/bin/python bench/bench_operator_bound.py BUNDLE --level top \
        [--parallel joins] [--share 0.8] [--seed 0] [--trials 2000]

Cost: one factored and one lumped model of the level, the sequences enumerated once (refused past
``--max-sequences``), and the solve (``--trials`` trials).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import numpy as np  # noqa: E402

from bench_habits import _products, favourite_of  # noqa: E402
from planner import api  # noqa: E402
from planner.decision.factored_model import factored_model  # noqa: E402
from planner.decision.habits import add_sequence, choice_probabilities, habit_weights_from  # noqa: E402
from planner.decision.lumped_model import lumped_model  # noqa: E402
from planner.decision.solvers import PointBasedSolver  # noqa: E402

PRIOR = 1e-9


def operator_edge_counts(plan, model, favourite: int, share: float) -> tuple[np.ndarray, np.ndarray]:
    """Per state edge, the operator's probability of taking it (``sum over sequences of P(sequence) [edge in
    it]``), and each sequence's probability ``P`` (rank order). Cost: O(sequences x operations)."""
    n = model.n_sequences
    probability = np.full(n, (1.0 - share) / n)
    probability[favourite] += share
    counts = np.zeros(plan.states.n_edges)
    for rank in range(n):
        once = np.zeros(plan.states.n_edges)
        add_sequence(plan, once, model.sequence_operations(model.sequence(rank)))
        counts += probability[rank] * once
    return counts, probability


def markov_gap(plan, model, counts: np.ndarray, probability: np.ndarray) -> float:
    """The largest |P_chain(sequence) - P(sequence)| over the sequences, P_chain the product of the per-state
    choice probabilities the counts give (the model's prior over sequences)."""
    choice = choice_probabilities(plan, counts, PRIOR)
    chain = np.array([np.prod(choice[model.sequence(rank)]) for rank in range(model.n_sequences)])
    return float(np.max(np.abs(chain - probability)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("product", help="pen, chain:N, complete:N, or a product file or bundle (planned as a CAD "
                                        "model is by default: proposed fasteners and workstations)")
    parser.add_argument("--level", help="the workstation(s), comma-separated (default: every level)")
    parser.add_argument("--parallel", choices=("none", "joins", "projected"), default="joins")
    parser.add_argument("--share", type=float, default=0.8, help="the operator's strength S (default 0.8)")
    parser.add_argument("--seed", type=int, default=0, help="draws the favourite as bench_habits.py does")
    parser.add_argument("--trials", type=int, default=2000)
    parser.add_argument("--max-sequences", type=int, default=100_000)
    args = parser.parse_args()
    if not 0.0 <= args.share <= 1.0:
        parser.error(f"--share {args.share} is not in [0, 1]")
    import tempfile
    with tempfile.TemporaryDirectory() as folder:
        for name, product in _products([args.product], args.level, Path(folder)):
            plan = api.plan_of(product)
            paper = factored_model(plan)
            if paper.n_sequences > args.max_sequences:
                print(f"{name}: {paper.n_sequences:,} sequences, more than --max-sequences {args.max_sequences:,}")
                continue
            favourite = favourite_of(paper.n_sequences, args.seed)
            counts, probability = operator_edge_counts(plan, paper, favourite, args.share)
            weights = habit_weights_from(plan, counts, PRIOR)
            parallel = False if args.parallel == "none" else args.parallel
            model = factored_model(plan, weights=weights, parallel=parallel)
            lumped = lumped_model(plan, model.rewards, weights=weights, parallel=parallel)
            result = PointBasedSolver(max_iterations=args.trials, time_limit=None, precision=1e-4).solve(lumped.pomdp)
            print(json.dumps({"product": name, "sequences": paper.n_sequences, "favourite": favourite,
                              "share": args.share, "parallel": args.parallel,
                              "markov_gap": markov_gap(plan, paper, counts, probability),
                              "lower_bound": round(result.lower_bound, 4),
                              "upper_bound": round(result.upper_bound, 4), "trials": args.trials}))


if __name__ == "__main__":
    main()
