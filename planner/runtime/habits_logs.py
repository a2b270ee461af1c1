"""Operator habits learned from session logs (issue 23; ``aplan habits LOG... -o habits.json``): a log names the
robot's operations but only what the operator was seen picking, which several sequences may explain; each log
counts as the posterior over every sequence that explains it (:mod:`~planner.runtime.log_posterior`, weighed by
the paper's prior or the per-state habits being added to): the operator's expected count of each state edge (a
session stopped early counts the steps it did; a step the robot did is walked, not counted: it was the robot's
choice, not the operator's). A finished log also records its *orders*, each explaining sequence of state edges
(the robot's steps included: the order the product was assembled in; :mod:`~planner.decision.orders`) with its
posterior weight as its count, when at most :data:`~planner.runtime.log_posterior.ORDERS_CAP` explain it; a
session stopped early records none. A log that one sequence explains counts exactly 1 per step and order.

A log stores the product it was recorded on. It is refused, naming it, when that product planned with the same
options has another state graph than the habits' (another version of the product: its parts, operations or
technical constraints differ; :func:`~planner.decision.habits.state_graph_fingerprint`), or when its sequence is
not one of the habits' plan. Cost per log: its replay (one model build and one belief update per step) and the
posterior's O(T (S + E)) for T steps (plus the orders' enumeration, at most the cap's sequences).
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..assembly.plan import Plan, make_plan
from ..assembly.explode import SequenceError
from ..decision.habits import (Habits, HabitsError, choice_probabilities, edge_counts, edge_keys, habits_from_counts,
                               state_graph_fingerprint)
from ..defaults import HABITS_PRIOR
from ..validation import InputLimits
from .log_posterior import ORDERS_CAP, explanations
from .logged_sequence import read_steps

__all__ = ["habits_from_logs", "count_log", "log_prior"]


def _on_plan(plan: Plan, logged: Plan, steps: list[tuple[str, int]], path: Path) -> list[tuple[str, int]]:
    """The logged steps as steps of ``plan``: robot operations matched by the part sets they join (each of a
    join's operations), observations by name."""
    index = {frozenset(plan.andor.inputs(j)): j for j in range(len(plan.andor.operations))}
    names = {name: z for z, name in enumerate(plan.observations)}

    def operation(value: int) -> int:
        key = frozenset(logged.andor.inputs(value))
        if key not in index:
            raise HabitsError(f"{path}: the logged operation {logged.andor.describe(value)} is not an operation "
                              f"of {plan.product.name or 'the product'}; the log belongs to another product version")
        return index[key]

    out = []
    for who, value in steps:
        if who == "robot":
            out.append((who, tuple(map(operation, value)) if isinstance(value, tuple) else operation(value)))
        else:
            name = logged.observations[value]
            if name not in names:
                raise HabitsError(f"{path}: the logged observation {name!r} is not one of "
                                  f"{plan.product.name or 'the product'}; the log belongs to another product version")
            out.append((who, names[name]))
    return out


def log_prior(plan: Plan, start: Habits | None = None) -> np.ndarray:
    """The prior's choice ``p(e | s)`` per state edge that a log's explanations are weighed by
    (:mod:`~planner.runtime.log_posterior`): the per-state habits ``start`` being added to, else the paper's
    (every full sequence equally likely). Cost: O(S + E log E)."""
    counts = np.zeros(plan.states.n_edges) if start is None else edge_counts(plan, start)
    prior = HABITS_PRIOR if start is None else start.prior
    return choice_probabilities(plan, counts, prior, "edge" if start is None else start.prior_per)


def count_log(plan: Plan, counts: np.ndarray, path: str | os.PathLike, technical: bool | None = None,
              limits: InputLimits = InputLimits(), orders: dict | None = None,
              choice: np.ndarray | None = None, notes: list[str] | None = None) -> float:
    """Add the operator's expected steps the session log at ``path`` recorded to ``counts`` (E,) of ``plan``,
    and its orders (a finished session's explaining sequences, as tuples of :func:`edge_keys`, with their
    posterior weights) to ``orders`` (order -> count) if given; returns the operator's expected steps counted.
    ``choice``: the prior the explanations are weighed by (:func:`log_prior`; None: the paper's); ``notes``, if
    given, gets a line for a finished log whose explanations are too many to record as orders. ``technical``:
    how ``plan`` switched its technical constraints (the log's product is planned the same way to compare state
    graphs). Raises :class:`HabitsError` naming the log and the fix."""
    path = Path(path)
    product, logged, steps = read_steps(path, limits)
    own = logged if technical is None else make_plan(product, technical)
    mine, theirs = state_graph_fingerprint(own), state_graph_fingerprint(plan)
    name = plan.product.name or "the product"
    if mine != theirs:
        what = "another product" if (product.name or "") != (plan.product.name or "") else "another version"
        fix = ("learn habits from the logs of one product at a time" if what == "another product" else
               "learn habits from logs of one version only, giving that version as --product")
        raise HabitsError(f"{path}: a log of {what} ({product.name or 'unnamed'!r}, state graph {mine}; the "
                          f"habits are of {name!r}, state graph {theirs}: parts, operations or technical constraints "
                          f"differ); {fix}")
    try:
        found = explanations(plan, _on_plan(plan, logged, steps, path), log_prior(plan) if choice is None else choice,
                             ORDERS_CAP)
    except SequenceError as exc:
        raise HabitsError(f"{path}: {exc}: the logged sequence is not one of this plan's (check --technical)") from None
    counts += found.counts
    if orders is not None and found.orders is None and notes is not None:
        notes.append(f"{path}: more than {ORDERS_CAP} sequences explain this log's observations: no order recorded "
                     "for it (its per-state counts are)")
    if orders is not None and found.orders:
        keys = edge_keys(plan)
        for edges, weight in found.orders:
            order = tuple(keys[e] for e in edges)
            orders[order] = orders.get(order, 0.0) + weight
    return float(found.counts.sum())


def habits_from_logs(plan: Plan | None, paths: Sequence[str | os.PathLike], prior: float = HABITS_PRIOR,
                     technical: bool | None = None, start: Habits | None = None,
                     limits: InputLimits = InputLimits(), notes: list[str] | None = None) -> tuple[Habits, float]:
    """The habits of ``plan`` counted from the session logs ``paths`` (module docstring), added to ``start``'s
    counts when given (checked to be of ``plan``), and the number of steps counted. ``plan`` None: the plan of
    the first log's product (``technical`` switched). Each log's explanations are weighed by ``start``'s
per-state habits (else the paper's prior), the same for every log (the result does not depend on the logs'
order); ``notes``: :func:`count_log`'s. Raises :class:`HabitsError` when no log records a step."""
    if not paths:
        raise HabitsError("no session log given; aplan habits LOG... -o FILE")
    if plan is None:
        plan = make_plan(read_steps(paths[0], limits)[0], technical)
    counts = edge_counts(plan, start) if start is not None else np.zeros(plan.states.n_edges)
    orders = dict(start.orders) if start is not None else {}
    choice = log_prior(plan, start)
    steps = sum(count_log(plan, counts, path, technical, limits, orders, choice, notes) for path in paths)
    if not counts.any():
        raise HabitsError(f"{', '.join(map(str, paths))}: the logs record no operation: nothing to learn (a session "
                          "that did at least one step is needed); nothing was written")
    habits = habits_from_counts(plan, counts, start.prior if start is not None and prior is None else
                                (prior if prior is not None else HABITS_PRIOR))
    if start is not None:
        habits = replace(habits, concentration=start.concentration, discount=start.discount)
    return replace(habits, orders=tuple(orders.items())), steps
