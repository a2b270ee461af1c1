"""The lumped decision model: Alg. 3's POMDP over the factored model's *classes* instead of intentions.

Definition. The classes of :class:`~planner.decision.factored_model.FactoredIntentionModel` are the state edges
``c < E`` (the current assembly state is the edge's source, the operator's next step is the edge) and the
finished product ``E``. The lumped POMDP has one state per class and the flat model's actions, observations,
discount and rewards:

- transitions: with ``M`` the *advance* matrix (class ``c`` goes to the classes ``c'`` that start at
  ``target(c)`` with probability ``class_fraction[c'] = N(target(c')) / N(target(c))``; the finished product
  stays), ``wait`` is ``W = (I + M) / 2`` (stay or advance one step); the action that performs ``c``'s step
  is ``M W`` on class ``c`` (the robot's step, then the operator's stay-or-advance); every other action
  leaves the class as it is;
- observations: those of the class's current state, the same table (one shared object) for every action;
- rewards: ``R(c, a)`` of the class's next step (unfavorable, favorable, wrong operation or wait);
- initial belief: the factored model's (the classes out of the initial state, by their share of the full
  sequences).

Exactness. Call a flat belief over intentions *uniform within classes* when every intention of a class holds
the same probability. The flat initial belief is; the flat prediction keeps the property (every intention of
class ``c`` continues along its own path, and those paths fan out over the classes at ``target(c)`` in
proportion to their path counts: that is ``M``); the Bayes update keeps it (the observation likelihood of an
intention depends only on its current state, the same for the whole class). On such beliefs the flat
prediction, the observation probabilities and the expected rewards equal the lumped ones at the class masses
(the sums over each class), so every belief the flat model reaches from its initial belief corresponds to
one the lumped model reaches with the same probability and the same expected rewards. The optimal value at
corresponding beliefs is the same, and a policy over class masses runs on the flat model unchanged (sum the
flat belief per class, or keep the factored model's belief). The flat model is not lumpable in the strong
sense (an intention's successor is one intention, not a class), so the lumped model says nothing about flat
beliefs that are not uniform within classes; none is ever reached from the initial belief.

The parallel model (:mod:`~planner.decision.parallel`, docs/parallel.md) is defined on these classes: a right
parallel action moves class ``c`` to ``e'`` then by ``W`` (with probability ``q``), a wrong one leaves it.

With operator habits (edge weights, :mod:`~planner.decision.habits`) the same holds with "uniform within
classes" read as "in proportion to the intentions' prior weights within classes": the factored model's weighted
``class_fraction`` is then ``M``, and nothing else changes.

Cost. ``E + 1`` states instead of the intentions (pen: 33 instead of 69; chain of 7: 193 instead of 1,957;
complete 6: 857 instead of 6,872). Building it costs O(nnz(M^2) + (E + 1) A) time and memory: one sparse
product ``M M`` (the two-step advance), one row selection per action and a dense reward table.
"""
from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..assembly.plan import Plan
from ..defaults import DISCOUNT
from .delayed_reveal import DelayedReveal, delayed_reveal_bound
from .deviations import Deviations, lumped_switch, mixed_observations
from .factored_model import FactoredIntentionModel, factored_model
from .intention_model import Rewards
from .online import revealed_state_values
from .parallel_values import parallel_rows
from .pomdp import POMDP
from .solvers.upper import CornerGroups, RelaxedQ

__all__ = ["LumpedModel", "lumped_model", "lumped_pomdp", "lumped_pomdp_bytes", "class_names", "advance_matrix",
           "solver_bounds",
           "SolverStart", "solver_start",
           "LUMPED_SUFFIX"]

log = logging.getLogger(__name__)

LUMPED_SUFFIX = ":lumped"  # appended to the model's name: a policy file's ``model`` attribute tells it apart


def class_names(model: FactoredIntentionModel) -> tuple[str, ...]:
    """``c<k>:s<source>>s<target>`` for the state edges, ``c<E>:finished`` for the finished product."""
    E = model.final_class
    source, target = model.class_source[:E], model.class_target[:E]
    return tuple(f"c{c}:s{s}>s{t}" for c, s, t in zip(range(E), source.tolist(), target.tolist())) + \
        (f"c{E}:finished",)


def advance_matrix(model: FactoredIntentionModel) -> sp.csr_matrix:
    """``M`` (E+1, E+1) CSR: one step along the path (module docstring); the finished product stays.
    Cost: O(E + nnz(M))."""
    E = model.final_class
    out, count = model.starting_at(model.class_target[:E].astype(np.int64))
    rows = np.append(np.repeat(np.arange(E), count), E)
    cols = np.append(out, E)
    values = np.append(model.class_fraction[out], 1.0)
    return sp.csr_matrix((values, (rows, cols)), shape=(E + 1, E + 1))


def _transitions(model: FactoredIntentionModel) -> tuple[sp.csr_matrix, ...]:
    n, A = model.n_classes, len(model.action_operations)
    identity = sp.identity(n, format="csr")
    advance = advance_matrix(model)
    wait = ((identity + advance) * 0.5).tocsr()
    if model.deviations is not None and model.deviations.switch:  # a change of mind first (deviations.py)
        wait = (lumped_switch(model) @ wait).tocsr()
    performed = (advance @ wait).tocsr()        # the robot's step, then the operator's stay-or-advance
    tables = []
    extra = parallel_rows(model, wait)  # the parallel model's right actions (None: the paper's)
    for a in range(A - 1):
        performs = (model.class_action == a).astype(float)
        if extra is None:
            tables.append((sp.diags(performs) @ performed + sp.diags(1.0 - performs)).tocsr())
        else:
            right, taken = extra[a]
            tables.append((sp.diags(performs) @ performed + sp.diags(1.0 - performs - taken) + right).tocsr())
    tables.append(wait)
    for table in tables:
        table.sum_duplicates()
        table.eliminate_zeros()
    return tuple(tables)


def _observations(model: FactoredIntentionModel) -> sp.csr_matrix:
    """O(z | class): the blank at a quarter of the weight of each observation into the class's state."""
    n, Z = model.n_classes, len(model.plan.observations)
    source = model.class_source.astype(np.int64)
    lo = np.searchsorted(model.emit_keys, source * Z)
    hi = np.searchsorted(model.emit_keys, (source + 1) * Z)
    count = hi - lo
    ends = np.cumsum(count)
    at = np.repeat(lo - ends + count, count) + np.arange(int(ends[-1]) if n else 0)
    rows = np.concatenate([np.arange(n), np.repeat(np.arange(n), count)])
    cols = np.concatenate([np.zeros(n, dtype=np.int64), model.emit_keys[at] % Z])
    weight = model.emit_weight[source]
    values = np.concatenate([0.25 * weight, np.repeat(weight, count)])
    table = sp.csr_matrix((values, (rows, cols)), shape=(n, Z))
    if model.deviations is not None and model.deviations.mistake:
        table = mixed_observations(table, model.deviations.mistake)
    return table


def _rewards(model: FactoredIntentionModel) -> np.ndarray:
    n, A = model.n_classes, len(model.action_operations)
    reward = np.full((A, n), model.rewards.wrong, dtype=float)
    reward[-1] = model.rewards.wait
    doing = np.flatnonzero(model.class_action >= 0)
    reward[model.class_action[doing], doing] = model.class_match_reward[doing]
    if model.parallel is not None:  # R = wrong + q (r(o) - wrong) on the parallel pairs
        par = model.parallel
        reward[par.action, par.pair_class] = model.rewards.wrong + par.fraction * (par.reward - model.rewards.wrong)
    return reward


def lumped_pomdp_bytes(n_classes: int, n_actions: int) -> int:
    """The most :func:`lumped_pomdp` takes for ``n_classes`` classes and ``n_actions`` actions, on top of the
    factored model, from counts alone: per action and class a transition entry (12 bytes) and a row pointer
    (4), and a float64 reward (the dense (A, classes) table): 24 bytes; the performing rows' second steps,
    the observation table and the class names about 200 bytes a class more, and each action's table object
    about 3 KB. Measured within a factor 3 above (chain 7: tests/decision/test_memory_estimates.py; 26.3
    bytes per class and action on chain 16)."""
    return 26 * n_classes * n_actions + 200 * n_classes + 3000 * n_actions


def lumped_pomdp(model: FactoredIntentionModel) -> POMDP:
    """The POMDP over the classes of ``model`` (module docstring), named ``<product>:lumped``.

    Cost: O(nnz(M^2) + (E + 1) A) for E state edges and A actions.
    """
    transition = _transitions(model)
    table = _observations(model)
    observation = tuple(table for _ in transition)  # one object: solvers and updaters share its products
    return POMDP(class_names(model), model.actions, model.observations, transition, observation,
                 _rewards(model), model.initial_belief().dense(model.n_classes), model.discount,
                 name=model.name + LUMPED_SUFFIX)


@dataclass(frozen=True)
class LumpedModel:
    """The factored model (what the classes mean, its Bayes filter) and its lumped POMDP (for solvers and
    files): a policy of ``pomdp`` is over class masses, ``factored.initial_belief().dense(n)`` its start."""

    factored: FactoredIntentionModel
    pomdp: POMDP

    @property
    def name(self) -> str:
        return self.pomdp.name


def lumped_model(plan: Plan, rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                 base_part: str | None = None, weights: np.ndarray | None = None,
                 parallel: bool = False, deviations: Deviations | None = None) -> LumpedModel:
    """The factored model of ``plan`` (from ``base_part`` if given; ``weights``: operator habits, per state edge;
    ``parallel``: the parallel model, docs/parallel.md; ``deviations``: change of mind and mistakes) and its
    lumped POMDP. Cost: that of :func:`factored_model` plus :func:`lumped_pomdp`."""
    factored = factored_model(plan, rewards, discount, base_part, weights, parallel, deviations)
    return LumpedModel(factored, lumped_pomdp(factored))


def solver_bounds(model: FactoredIntentionModel, reveal: DelayedReveal | None = None
                  ) -> tuple[np.ndarray, CornerGroups | None]:
    """What a point-based solver starts the lumped POMDP's upper bound from: the Q-values (A, classes) of
    :func:`~planner.decision.online.revealed_state_values` (the robot knows the class now and every later
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
