"""The lower bound's process: grow the belief set under the current policy, heaviest beliefs first, and
sweep it (:mod:`~planner.decision.solvers.belief_set`), as a generator that yields the work of each step.

Each round expands the beliefs heavier than ``theta`` not expanded yet (their successors under the lower
bound's greedy action join the set); when none is left, ``theta`` is divided by ``theta_factor`` until some
is. Then ``sweeps_per_round`` sweeps back up the whole set, ``chunk`` beliefs per step, and prune the
vectors that are best at none of them. The set stops growing once it holds ``belief_memory`` numbers.

Work, in estimated multiply-adds: O(n Z S) to expand n beliefs; for a chunk of n beliefs with K vectors,
O(K n S) for the current values plus O(S Z K) per (belief, action) pair backed up.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np

from .belief_set import BeliefSet, policy_successors, sweep
from .lower import LowerBound
from .tables import SolveStopped, Tables

__all__ = ["grow", "sweep_rounds"]


def grow(m: Tables, lower: LowerBound, beliefs: BeliefSet, theta: float, theta_factor: float,
         stop: Callable[[], bool] | None = None) -> tuple[int, float]:
    """Expand the unexpanded beliefs heavier than ``theta`` (divided by ``theta_factor`` while there are
    none) under the lower bound's greedy actions. Returns how many were expanded and the threshold used.
    ``stop``: the time limit, checked between products (:func:`policy_successors`; :class:`SolveStopped` in
    the greedy actions' products). Cost: O(n (K S + A nnz(T) / S + Z S)) for n beliefs expanded, K vectors."""
    todo = beliefs.take_frontier(theta)
    while not todo.size and theta > 0 and beliefs.unexpanded:
        theta /= theta_factor
        todo = beliefs.take_frontier(theta)
    if todo.size:
        greedy = np.asarray(lower.actions)[lower.at(beliefs.rows[todo], stop)[1]]
        beliefs.add(*policy_successors(m, beliefs.rows[todo], greedy, beliefs.weights[todo], stop=stop))
    return int(todo.size), theta


def sweep_rounds(m: Tables, lower: LowerBound, beliefs: BeliefSet, q_upper: np.ndarray, theta: float = 1e-3,
                 theta_factor: float = 3.0, sweeps_per_round: int = 3, chunk: int = 4096,
                 belief_memory: int = 50_000_000, stop: Callable[[], bool] | None = None) -> Iterator[float]:
    """The lower bound's process (module docstring), forever: yields the work of each expansion and of
    each chunk swept. ``q_upper`` (A, S): an upper bound on Q, to skip the actions that cannot improve.
    ``stop`` (the solver's time limit) is checked inside each step, which then ends early with the work done
    so far (:func:`grow`, :func:`sweep`; a pruning stopped midway is skipped), so a step on a large model
    does not run past the limit."""
    while True:
        if beliefs.n * m.S < belief_memory:
            try:
                expanded, theta = grow(m, lower, beliefs, theta, theta_factor, stop)
            except SolveStopped:
                expanded = 0
            if expanded:
                yield float(expanded * m.Z * m.S)
        for _ in range(sweeps_per_round):
            for first in range(0, beliefs.n, chunk):
                rows = beliefs.rows[first:first + chunk]
                backups = lower.n * len(rows) * m.S  # the current values, and per candidate:
                try:
                    vectors, chosen, _, candidates = sweep(m, rows, lower.vectors, q_upper, stop=stop)
                except SolveStopped:
                    yield 0.0
                    continue
                lower.extend(vectors, chosen)
                yield float(backups + candidates * m.S * m.Z * lower.n)
            try:
                lower.prune(beliefs.rows, stop)
            except SolveStopped:
                pass
