"""The lumped model's warm start: what the point-based solver's upper bound starts from on a
:class:`~planner.decision.lumped_model.LumpedModel` (the relaxed bounds: the state told now, or told late), as a
field of the solver's configuration (:attr:`~planner.decision.solvers.PointBasedSolver.warm_start`).

The bounds come from the class MDP (:func:`~planner.decision.bounds.revealed_state_values`) and the
delayed-reveal graph (:mod:`~planner.decision.delayed_reveal`); the solver takes them as a known upper bound on
Q*, corner groups, sawtooth points and relaxed Q-values (:meth:`~.point_based.PointBasedSolver.solve`).
"""
from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..bounds import revealed_state_values
from ..delayed_reveal import DelayedReveal, delayed_reveal_bound
from ..factored_model import FactoredIntentionModel
from ..lumped_model import LumpedModel
from .upper import CornerGroups, RelaxedQ

__all__ = ["WARM_START_SHARE", "WarmStart", "SolverStart", "solver_bounds", "solver_start", "POINT_NUMBERS"]

log = logging.getLogger(__name__)

# The share of the time left that the warm start may take (the rest is the solver's own): its finest graph is
# only tried while it fits.
WARM_START_SHARE = 1 / 4


@dataclass(frozen=True)
class WarmStart:
    """The lumped model's warm start as solver configuration: ``model`` the lumped model, ``points`` whether the
    delayed-reveal beliefs go in as sawtooth points, ``groups`` whether the corner groups do (both optional:
    :func:`~planner.decision.budget.lumped_start_fits` says what fits in memory), ``share`` of the time left
    (:data:`WARM_START_SHARE`)."""

    model: LumpedModel
    points: bool = True
    groups: bool = True
    share: float = WARM_START_SHARE

    def options(self, clock: Callable[[], float], started: float, time_limit: float | None,
                stopped: Callable[[], int] = lambda: 0) -> dict:
        """:meth:`PointBasedSolver.solve`'s start options (:func:`solver_start`) within ``share`` of the time
        from ``started`` to ``time_limit`` on ``clock``; ``stopped()`` non-zero (an interrupt) ends its
        building at once. Cost: :func:`solver_start`'s."""
        finite = time_limit is not None and math.isfinite(time_limit)
        left = started + time_limit - clock() if finite else math.inf
        start = solver_start(self.model, points=self.points,
                             deadline=clock() + left * self.share if finite else math.inf,
                             clock=lambda: math.inf if stopped() else clock()).solve_options
        if not self.groups:
            start["groups"] = None
        return start


def solver_bounds(model: FactoredIntentionModel, reveal: DelayedReveal | None = None
                  ) -> tuple[np.ndarray, CornerGroups | None]:
    """What a point-based solver starts the lumped POMDP's upper bound from: the Q-values (A, classes) of
    :func:`~planner.decision.bounds.revealed_state_values` (the robot knows the class now and every later
    assembly state), and one corner group per assembly state with two or more classes out of it: the belief
    that spreads over them by ``class_fraction`` (every belief the model reaches holds such a spread, save
    for the classes a wrong robot action ruled out) with the value for a robot that knows the state but not
    the next step (None when no state has two classes). Groups come in the states' order, the final level
    first, so that one pass of backups carries values from the end of the assembly to its start. With
    ``reveal`` (:func:`~planner.decision.delayed_reveal.delayed_reveal_bound`), each Q-value and group value
    is the lower of the two bounds (the minimum of two upper bounds is one; a class's relaxed value bounds
    every action's Q-value there). Cost: O(S + E) after the bounds' own passes.
    """
    values = revealed_state_values(model)
    Q = values.q_matrix(model)
    if reveal is not None:
        Q = np.minimum(Q, reveal.corner_values[None, :])
    start = model.state_class_start
    count = np.diff(start)
    states = np.flatnonzero(count >= 2)        # in index order: level by level from the final state
    if not states.size:
        return Q, None
    member = np.concatenate([model.state_classes[start[s]:start[s + 1]] for s in states])
    first = np.concatenate([[0], np.cumsum(count[states])[:-1]]).astype(np.int64)
    group_values = np.asarray(values.state)[states].astype(float)
    if reveal is not None:
        group_values = np.minimum(group_values, reveal.spread_values(states))
    groups = CornerGroups(member.astype(np.int64), model.class_fraction[member].astype(float), first, group_values)
    return Q, groups


@dataclass(frozen=True)
class SolverStart:
    """What :meth:`~planner.decision.solvers.PointBasedSolver.solve` takes to start a lumped model's upper
    bound: ``upper`` (A, classes), ``groups``, ``points`` (beliefs (N, classes), values (N,)), the relaxed
    Q-values (:class:`~planner.decision.solvers.upper.RelaxedQ`) and the delayed-reveal bound they came
    from (None when none was built in time)."""

    upper: np.ndarray
    groups: CornerGroups | None
    points: tuple[np.ndarray, np.ndarray] | None
    relaxed: RelaxedQ | None
    reveal: DelayedReveal | None

    @property
    def solve_options(self) -> dict:
        return {"upper": self.upper, "groups": self.groups, "points": self.points, "relaxed": self.relaxed}


def solver_start(model: LumpedModel, finest: int = 2, points: bool = True, deadline: float | None = None,
                 clock: Callable[[], float] | None = None, max_nodes: int = 30_000) -> SolverStart:
    """The tightest start :func:`solver_bounds` can give within ``deadline`` (a ``clock()`` value): the
    delayed-reveal bound (:mod:`~planner.decision.delayed_reveal`) with the state told after every action,
    then after every second one, ... up to every ``finest``-th (each finer one is below the last: the robot is
    told less), the last one built in time tightening the Q-values and the groups, giving its relaxed
    Q-values (a bound at every belief that takes one action for the whole belief) and, with ``points``, its
    beliefs as sawtooth points (the least value per belief over its phases). A finer graph is only tried when
    the last one's growth says it fits in ``max_nodes`` nodes and, with a deadline, in the time left (its
    time times that growth). Cost: that of the bounds (chain 7: 0.24 s and 1.0 s for the first two; complete
    6: 1.1 s and 4.9 s)."""
    reveal = None
    previous_nodes, previous_seconds = None, None
    # With deviations the relaxed beliefs are no longer spreads or single classes (a redraw mixes them): the
    # graph would not close, so the bound starts from the revealed-state values alone.
    finest = 0 if model.factored.deviations is not None else finest
    for every in range(1, finest + 1):
        if reveal is not None and previous_nodes:
            growth = reveal.graph.n / previous_nodes
            if reveal.graph.n * growth > max_nodes:
                break
            if deadline is not None and clock is not None and clock() + previous_seconds * growth > deadline:
                break
        began = clock() if clock is not None else 0.0
        built = delayed_reveal_bound(model.factored, model.pomdp, every, deadline=deadline, clock=clock)
        if built is None:
            break
        previous_nodes = reveal.graph.n if reveal is not None else max(1, built.graph.n // 4)
        previous_seconds = (clock() - began) if clock is not None else 0.0
        reveal = built
    upper, groups = solver_bounds(model.factored, reveal)
    relaxed = None
    if reveal is not None:
        relaxed = reveal.relaxed_q(np.flatnonzero(np.diff(model.factored.state_class_start) >= 2))
    late = deadline is not None and clock is not None and clock() >= deadline
    if late and reveal is not None and points:  # the points are optional: the Q-values hold the bound already
        log.info("the solver's warm start passed its share of the time limit: its %s beliefs are left out of "
                 "the upper bound (a larger --time-limit keeps them)", f"{reveal.graph.n:,}")
    keep = reveal is not None and points and not late
    return SolverStart(upper, groups, _least_per_belief(reveal) if keep else None, relaxed, reveal)


# The delayed-reveal beliefs given to the solver as sawtooth points: at most this many numbers (dense rows),
# the first found (nearest the initial belief) first; chain 11 has 15,961 beliefs over 5,121 classes (650 MB).
POINT_NUMBERS = 20_000_000


def _least_per_belief(reveal: DelayedReveal, numbers: int = POINT_NUMBERS) -> tuple[np.ndarray, np.ndarray]:
    """The graph's distinct beliefs over two or more classes (a belief recurs once per phase), in the graph's
    order, at most ``numbers`` dense numbers of them, each with its least value. Single classes are left out:
    the corner values already hold their bound. Cost: O(nnz) (one key per row) plus the dense rows kept."""
    beliefs, values = reveal.graph.beliefs, reveal.values
    ptr, cols, data = beliefs.indptr, beliefs.indices, np.round(beliefs.data, 12)
    index: dict[bytes, int] = {}
    first, least = [], []
    for row in np.flatnonzero(np.diff(ptr) >= 2):
        lo, hi = ptr[row], ptr[row + 1]
        key = cols[lo:hi].tobytes() + data[lo:hi].tobytes()
        at = index.get(key)
        if at is None:
            if (len(first) + 1) * beliefs.shape[1] > numbers:
                continue
            index[key] = at = len(first)
            first.append(row)
            least.append(np.inf)
        least[at] = min(least[at], float(values[row]))
    return beliefs[np.asarray(first, dtype=np.int64)].toarray(), np.asarray(least)
