"""Trials (Smith & Simmons, HSVI2, 2005): descend from ``b0`` along the largest weighted excess gap, then
back up both bounds at every belief on the way up.

At depth ``t`` a belief is *finished* when ``V^(b) - V_(b) <= epsilon gamma^-t`` (its gap cannot move the
gap at ``b0`` by more than ``epsilon``). Otherwise the trial takes the action that is best for the upper
bound (or, when ``follow_lower``, for the lower bound: the beliefs the current policy visits get backed up
too, as SARSOP samples near it) and the observation ``z`` that maximises
``P(z | b, a) (V^(b') - V_(b') - epsilon gamma^-(t+1))``, and stops where that is not positive.

A *backup* at ``b`` is the point-based Bellman update of both bounds from the bounds at its successors: the
alpha vector ``R_a + gamma sum_z T_a diag(O_z,a) alpha_{k(z)}`` of the best action (``k(z)``: the vector
best at the successor), kept if it raises ``V_(b)``, and ``max_a R_a . b + gamma sum_z P(z | b, a) V^(b')``,
kept as a point if it lowers ``V^(b)``.

A step evaluates all actions and observations at once (numpy) and costs
O(A (nnz(T) + S Z) + (K + N) S M) for K alpha vectors, N upper-bound points and M = A x Z successors.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .belief_set import BeliefSet
from .lower import LowerBound
from .tables import SolveStopped, Tables
from .upper import UpperBound

__all__ = ["Successors", "candidate_actions", "successors", "q_upper", "q_lower", "backup", "backup_groups", "bounds_at", "descend",
           "trial"]

Bounds = tuple[float, int, float]  # (lower bound, index of its best vector, upper bound) at one belief


@dataclass
class Successors:
    """The successors of a belief with probability > 0, in order of action, and the bounds at each: arrays
    of length M, ``beliefs`` (M, S). ``low``, ``best`` and ``high`` are updated in place by a trial."""

    action: np.ndarray
    observation: np.ndarray
    probability: np.ndarray
    beliefs: np.ndarray
    low: np.ndarray
    best: np.ndarray
    high: np.ndarray
    reward: np.ndarray | None = None   # (A,): R_a . b, kept by :func:`_q` (its belief's, computed once)


@dataclass
class Step:
    """One belief of a trial's path: its successors, the one the trial went on to (or None) and the bounds
    at it when the trial went down (still valid bounds on the way up: they can only have tightened)."""

    belief: np.ndarray
    successors: Successors
    next: int | None
    known: Bounds


def candidate_actions(m: Tables, b: np.ndarray, upper: UpperBound, low: float) -> np.ndarray:
    """The actions whose informed upper bound at ``b`` reaches ``low`` (a lower bound on V*(b)), sorted: the
    others have Q*(b, a) <= Q^(b, a) < low <= V*(b), so they are never optimal at ``b``, and the best of the
    candidates' upper bounds is still an upper bound on V*(b). Cost: O(A S)."""
    q = upper.Q @ b
    return np.flatnonzero(q >= min(low, q.max()) - 1e-9)


def successors(m: Tables, b: np.ndarray, lower: LowerBound, upper: UpperBound,
               low: float | None = None, stop: Callable[[], bool] | None = None) -> Successors:
    """The successors of ``b`` under every action and observation (with ``low``, a lower bound on V*(b):
    under the :func:`candidate_actions` only), with both bounds at each. Cost: O(A (nnz(T) + S Z)) for the
    beliefs and O((K + N) S d) for the bounds at the d distinct ones."""
    a_idx, z_idx, probs, nxt = m.successors(b, None if low is None else candidate_actions(m, b, upper, low), stop)
    # Many actions leave most intentions as they are: bound each distinct successor belief once.
    _, first, back = np.unique(nxt @ upper.fingerprint, return_index=True, return_inverse=True)
    back = back.reshape(-1)
    distinct = nxt[first]
    # A row whose fingerprint is another's but whose numbers are not (a true collision; or the same belief
    # reached through two actions, off in the last bits, past 1e-12) is bounded on its own: comparing rows is
    # O(K S), where sorting whole rows (np.unique along axis 0) took 15 s on complete 7's lumped b0.
    other = np.flatnonzero(np.abs(distinct[back] - nxt).max(axis=1, initial=0.0) > 1e-12)
    if other.size:
        back[other] = len(distinct) + np.arange(other.size)
        distinct = np.vstack([distinct, nxt[other]])
    lo, best = lower.at(distinct, stop)
    return Successors(a_idx, z_idx, probs, nxt, lo[back], best[back], upper.at(distinct, stop=stop)[back])


def _q(m: Tables, b: np.ndarray, s: Successors, values: np.ndarray) -> np.ndarray:
    if s.reward is None:  # a trial asks for the Q-values of a belief up to three times
        s.reward = m.R @ b
        s.reward[np.bincount(s.action, minlength=m.A) == 0] = -np.inf  # actions left out (candidate_actions)
    return s.reward + np.bincount(s.action, m.gamma * s.probability * values, minlength=m.A)


def q_upper(m: Tables, b: np.ndarray, s: Successors) -> np.ndarray:
    """(A,): ``R_a . b + gamma sum_z P(z | b, a) V^(b_az)``, an upper bound on Q(b, a); -inf for the actions
    whose successors were left out. Cost: O(A S + M)."""
    return _q(m, b, s, s.high)


def q_lower(m: Tables, b: np.ndarray, s: Successors) -> np.ndarray:
    """(A,): the same with the lower bound at the successors. Cost: O(A S + M)."""
    return _q(m, b, s, s.low)


def backup_vector(m: Tables, s: Successors, vectors: np.ndarray, a: int) -> np.ndarray:
    """(S,): ``R_a + gamma sum_z T_a diag(O_z,a) alpha_{best(a, z)}``, the alpha vector backed up for the
    action ``a`` from the successors ``s`` (``vectors``: the lower bound's). Cost: O(Z_a S + nnz(T_a)), Z_a
    the observations ``a`` has successors for."""
    mine = np.flatnonzero(s.action == a)
    inner = (m.OZ[a, s.observation[mine]] * vectors[s.best[mine]]).sum(axis=0)
    return m.R[a] + m.gamma * m.expect_one(a, inner[None])[0]


def backup(m: Tables, b: np.ndarray, s: Successors, known: Bounds, lower: LowerBound,
           upper: UpperBound, store: bool = True) -> Bounds:
    """Back up both bounds at ``b`` from its successors ``s``; ``known``: the bounds at ``b`` (module
    docstring). Returns the new ones; ``store=False`` keeps the upper value out of the points (the caller
    keeps it). The lower bound's new vector is built for the best action only: its value at ``b`` is
    :func:`q_lower`'s (``R_a . b + gamma sum_z P(z) alpha_best(a,z) . b_az``), so the action is chosen from
    those values, without the (A, S) vectors of every action (10 s at a 9-part chain's b0).
    Cost: O(A S + M + Z S + nnz(T_a))."""
    low, best_vector, high = known
    a = int(np.argmax(q_lower(m, b, s)))
    vector = backup_vector(m, s, lower.vectors, a)
    if vector @ b > low + 1e-12:
        low, best_vector = float(vector @ b), lower.n
        lower.add(vector, a)
    value = float(q_upper(m, b, s).max())
    if value < high - 1e-12:
        high = value
        if store:
            upper.update(b, value)
    return low, best_vector, high


def bounds_at(b: np.ndarray, lower: LowerBound, upper: UpperBound, high: float | None = None) -> Bounds:
    """Both bounds at one belief ``b`` and the index of the lower bound's best vector there (``high``: the
    upper bound there when the caller knows it is current). Cost: O((K + N) S)."""
    low, best_vector = (v[0] for v in lower.at(b[None]))
    return float(low), int(best_vector), upper.value(b) if high is None else high


def descend(m: Tables, b0: np.ndarray, lower: LowerBound, upper: UpperBound, epsilon: float,
            follow_lower: bool = False, max_depth: int = 300, stop: Callable[[], bool] | None = None,
            start: Bounds | None = None) -> list[Step]:
    """The path of one trial from ``b0`` (module docstring), at most ``max_depth`` steps down, and none once
    ``stop()`` is true (the solver's time limit: a deep trial can take seconds); ``start``: the bounds at
    ``b0`` if the caller has them (:func:`bounds_at`: the same numbers, not computed twice). Cost: one
    :func:`successors` per step."""
    b, depth, known = b0, 0, bounds_at(b0, lower, upper) if start is None else start
    path: list[Step] = []
    while depth < max_depth and not (depth and stop is not None and stop()):
        try:
            s = successors(m, b, lower, upper, known[0], stop)
        except SolveStopped:  # the time limit inside a long step: drop it (the path so far stays valid)
            break
        path.append(Step(b, s, None, known))
        if known[2] - known[0] <= epsilon * m.gamma ** (-depth):
            break
        a = int(np.argmax(q_lower(m, b, s) if follow_lower else q_upper(m, b, s)))
        mine = np.flatnonzero(s.action == a)
        if mine.size == 0:
            break
        excess = s.probability[mine] * (s.high[mine] - s.low[mine] - epsilon * m.gamma ** (-(depth + 1)))
        if excess.max() <= 0:
            break
        k = int(mine[int(np.argmax(excess))])
        path[-1].next = k
        b, depth = s.beliefs[k], depth + 1
        known = (float(s.low[k]), int(s.best[k]), float(s.high[k]))
    return path


def trial(m: Tables, b0: np.ndarray, lower: LowerBound, upper: UpperBound, beliefs: BeliefSet | None,
          epsilon: float, follow_lower: bool = False, max_depth: int = 300,
          stop: Callable[[], bool] | None = None, start: Bounds | None = None) -> float:
    """One trial from ``b0``: :func:`descend`, then :func:`backup` at each belief of the path, deepest
    first. The beliefs it reached join ``beliefs`` (the sweeps back them up from then on) with their reach
    weight ``gamma^t P(path)``; ``stop`` and ``start``: :func:`descend`'s. Returns its work in estimated
    multiply-adds (module docstring)."""
    path = descend(m, b0, lower, upper, epsilon, follow_lower, max_depth, stop, start)
    child = None
    for step in reversed(path):
        if step.next is not None and child is not None:
            # Only the successor the trial went through has new bounds; the others' bounds can only have
            # tightened since, so their stored values remain valid bounds.
            s, k = step.successors, step.next
            s.low[k], s.best[k], s.high[k] = child
        child = backup(m, step.belief, step.successors, step.known, lower, upper)
    went = [step for step in path if step.next is not None]
    if beliefs is not None and went:
        weights, weight = [], 1.0
        for step in went:
            weight = weight * m.gamma * step.successors.probability[step.next]
            weights.append(weight)
        beliefs.add(np.asarray([step.successors.beliefs[step.next] for step in went]), np.asarray(weights))
    # Per step: every action and observation, then each distinct successor against both bounds (counted to
    # 6 digits, so that a model written with rounded numbers costs the same).
    distinct = sum(len(np.unique(np.round(step.successors.beliefs @ upper.fingerprint, 6))) for step in path)
    return float(len(path) * m.A * m.Z * m.S + distinct * m.S * (lower.n + upper.n))


def backup_groups(m: Tables, lower: LowerBound, upper: UpperBound, stop: Callable[[], bool] | None = None) -> float:
    """Back up both bounds at every corner group's belief (:class:`~.upper.CornerGroups`), in the groups'
    order (put the ones nearer the end first, so one pass carries values back); an upper value that is lower
    than the group's replaces it. ``stop``: checked before each group (the pass ends there; every group
    backed up so far keeps its values). Returns the work, counted as :func:`trial` counts it. Cost: one
    :func:`successors` and one :func:`backup` per group."""
    if upper.groups is None:
        return 0.0
    work = 0.0
    for g, b in enumerate(upper.group_beliefs):
        if stop is not None and stop():
            break
        low, best = (float(v[0]) for v in lower.at(b[None]))
        s = successors(m, b, lower, upper, low)
        high = float(upper.group_value[g])
        low, _, value = backup(m, b, s, (low, int(best), np.inf), lower, upper, store=False)
        upper.lower_group(g, min(value, high))
        work += m.A * m.Z * m.S + len(s.action) * m.S * (lower.n + upper.n)
    return work
