"""Operator habits learned from session logs (issue 23; ``aplan habits LOG... -o habits.json``): each log's
sequence of operations (:func:`~planner.runtime.logged_sequence.logged_sequence`: the robot's logged operations
and the operator's observations, explained by the first sequence that fits) counted along the state edges it
took, one count per step the operator did (a session stopped early counts the steps it did; a step the robot
did is walked, not counted: it was the robot's choice, not the operator's). A log whose sequence reaches the
finished product also records its *order*, the whole sequence of state edges (the robot's steps included: the
order the product was assembled in; :mod:`~planner.decision.orders`); a session stopped early records none.

A log stores the product it was recorded on. It is refused, naming it, when that product planned with the same
options has another state graph than the habits' (another version of the product: its parts, operations or
technical constraints differ; :func:`~planner.decision.habits.state_graph_fingerprint`), or when its sequence is
not one of the habits' plan. Cost per log: its replay (one model build and one belief update per step) and O(1)
per counted step.
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..assembly.plan import Plan, make_plan
from ..decision.habits import (Habits, HabitsError, add_sequence, edge_counts, edge_keys, habits_from_counts,
                               state_graph_fingerprint)
from ..defaults import HABITS_PRIOR
from ..validation import InputLimits
from .logged_sequence import logged_sequence

__all__ = ["habits_from_logs", "count_log"]


def _on_plan(plan: Plan, logged, path: Path) -> list[int]:
    """The logged operations as operations of ``plan`` (matched by the part sets they join)."""
    index = {frozenset(plan.andor.inputs(j)): j for j in range(len(plan.andor.operations))}
    out = []
    for operation in logged.operations:
        key = frozenset(logged.plan.andor.inputs(operation))
        if key not in index:
            raise HabitsError(f"{path}: the logged operation {logged.plan.andor.describe(operation)} is not an "
                              f"operation of {plan.product.name or 'the product'}; the log belongs to another product version")
        out.append(index[key])
    return out


def count_log(plan: Plan, counts: np.ndarray, path: str | os.PathLike, technical: bool | None = None,
              limits: InputLimits = InputLimits(), orders: dict | None = None) -> int:
    """Add the operator's steps the session log at ``path`` recorded to ``counts`` (E,) of ``plan``, and its order
    (a finished session's whole sequence, as a tuple of :func:`edge_keys`) to ``orders`` (order -> count) if
    given; returns the steps counted. ``technical``: how ``plan`` switched its technical constraints (the log's product is planned the
    same way to compare state graphs). Raises :class:`HabitsError` naming the log and the fix."""
    path = Path(path)
    logged = logged_sequence(path, limits)
    own = logged.plan if technical is None else make_plan(logged.product, technical)
    mine, theirs = state_graph_fingerprint(own), state_graph_fingerprint(plan)
    name = plan.product.name or "the product"
    if mine != theirs:
        what = "another product" if (logged.product.name or "") != (plan.product.name or "") else "another version"
        fix = ("learn habits from the logs of one product at a time" if what == "another product" else
               "learn habits from logs of one version only, giving that version as --product")
        raise HabitsError(f"{path}: a log of {what} ({logged.product.name or 'unnamed'!r}, state graph {mine}; the "
                          f"habits are of {name!r}, state graph {theirs}: parts, operations or technical constraints "
                          f"differ); {fix}")
    operations = _on_plan(plan, logged, path)
    operator = [who == "operator" for who in logged.by]
    edges: list[int] = []
    try:
        reached = add_sequence(plan, counts, operations, counted=operator, path=edges)
    except HabitsError as exc:
        raise HabitsError(f"{path}: {exc}: the logged sequence is not one of this plan's (check --technical)") from None
    if orders is not None and reached == plan.states.final and edges:
        keys = edge_keys(plan)
        order = tuple(keys[e] for e in edges)
        orders[order] = orders.get(order, 0.0) + 1.0
    return sum(operator)


def habits_from_logs(plan: Plan | None, paths: Sequence[str | os.PathLike], prior: float = HABITS_PRIOR,
                     technical: bool | None = None, start: Habits | None = None,
                     limits: InputLimits = InputLimits()) -> tuple[Habits, int]:
    """The habits of ``plan`` counted from the session logs ``paths`` (module docstring), added to ``start``'s
    counts when given (checked to be of ``plan``), and the number of steps counted. ``plan`` None: the plan of
    the first log's product (``technical`` switched). Raises :class:`HabitsError` when no log records a step."""
    if not paths:
        raise HabitsError("no session log given; aplan habits LOG... -o FILE")
    if plan is None:
        plan = make_plan(logged_sequence(paths[0], limits).product, technical)
    counts = edge_counts(plan, start) if start is not None else np.zeros(plan.states.n_edges)
    orders = dict(start.orders) if start is not None else {}
    steps = sum(count_log(plan, counts, path, technical, limits, orders) for path in paths)
    if not counts.any():
        raise HabitsError(f"{', '.join(map(str, paths))}: the logs record no operation: nothing to learn (a session "
                          "that did at least one step is needed); nothing was written")
    habits = habits_from_counts(plan, counts, start.prior if start is not None and prior is None else
                                (prior if prior is not None else HABITS_PRIOR))
    if start is not None:
        habits = replace(habits, concentration=start.concentration, discount=start.discount)
    return replace(habits, orders=tuple(orders.items())), steps
