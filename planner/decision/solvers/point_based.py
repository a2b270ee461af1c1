"""An anytime point-based POMDP solver with certified bounds: heuristic search for the upper bound, value
iteration over reachable beliefs for the lower bound.

The value ``V*(b0)`` is bracketed by a lower bound (a set of alpha vectors: the value of a policy that can
be executed) and an upper bound (belief points with values, interpolated by the sawtooth rule, and the fast
informed bound). Two processes share the time, balanced by work:

- *Trials* (Smith & Simmons, HSVI2, 2005) descend from ``b0`` following the action that is best for the
  upper bound and the observation with the largest weighted excess gap, and back up both bounds on the way
  up; every other trial follows the lower bound's policy instead.
- *Sweeps* (:mod:`planner.solvers.belief_set`) grow a set of beliefs reachable under the lower bound's
  policy, heaviest first, and back up all of them at once, which tightens the lower bound far faster than
  one belief per trial step (on the pen: within 0.001 of the optimum in about half a second).

It stops at the time limit, at the iteration limit, or when ``upper - lower <= precision`` at ``b0``: the
gap is a certificate, ``V*(b0)`` lies between the bounds.

A trial step evaluates all actions and observations at once (numpy) and costs
O(A (nnz(T) + S Z) + (K + N) S M) for K alpha vectors, N upper-bound points and M = A x Z successors; a
sweep costs O(A S (S + Z K)) per belief.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..policy import AlphaVectorPolicy
from ..pomdp import POMDP
from .belief_set import BeliefSet, policy_successors, sweep
from .tables import Rows, Tables, blind_lower_bound, fast_informed_bound

__all__ = ["PointBasedSolver", "SolveResult"]


@dataclass(frozen=True)
class SolveResult:
    """The policy (lower-bound alpha vectors), the bounds at ``b0`` and how they evolved."""

    policy: AlphaVectorPolicy
    lower_bound: float
    upper_bound: float
    seconds: float
    iterations: int
    history: list = field(default_factory=list)  # (seconds, lower, upper) after each trial or sweep

    @property
    def gap(self) -> float:
        return self.upper_bound - self.lower_bound

    def as_dict(self) -> dict:
        return {"lower_bound": self.lower_bound, "upper_bound": self.upper_bound, "gap": self.gap,
                "alpha_vectors": int(self.policy.alphas.shape[0]), "seconds": round(self.seconds, 3),
                "iterations": self.iterations}


@dataclass(frozen=True)
class PointBasedSolver:
    """Point-based solver with certified bounds (module docstring). Same configuration, same result: the
    two processes are balanced by counted work, not by the clock, so only the time limit depends on speed.

    ``time_limit`` (s), ``precision`` (target gap at b0), ``max_iterations`` (trials), ``max_depth``,
    ``gap_fraction``: each trial aims at this fraction of the current gap at b0 (at least ``precision``);
    every ``lower_trial_every``-th trial follows the lower bound's policy. Sweeps: ``theta`` is the first
    reach-weight threshold for growing the belief set, divided by ``theta_factor`` whenever no belief above
    it is left to grow; ``sweeps_per_round`` sweeps follow each growth, over ``chunk`` beliefs at a time;
    the set stops growing at ``belief_memory`` stored numbers (400 MB). Sharing: work is counted in
    estimated multiply-adds (the costs in the module docstring); it goes to the process that has recently
    closed the gap at b0 the fastest per unit of work (half-life ``rate_horizon`` units), each keeping at
    least ``min_share`` of it.
    """

    time_limit: float = 60.0
    precision: float = 1e-3
    max_iterations: int | None = None
    max_depth: int = 300
    gap_fraction: float = 0.5
    lower_trial_every: int = 2
    theta: float = 1e-3
    theta_factor: float = 3.0
    sweeps_per_round: int = 3
    chunk: int = 4096
    min_share: float = 0.2
    rate_horizon: float = 1e9
    belief_memory: int = 50_000_000
    seed: int = 0

    def solve(self, model: POMDP, progress: Callable[[float, float, float], None] | None = None) -> SolveResult:
        start = time.perf_counter()
        m = Tables(model)
        gamma = m.gamma
        b0 = np.asarray(model.initial, dtype=float)
        alphas = Rows(m.S)
        alphas.extend(blind_lower_bound(m))
        actions: list[int] = list(range(m.A))
        # Any iterate of the fast informed bound is an upper bound: it gets at most a quarter of the time.
        Q = fast_informed_bound(m, deadline=start + self.time_limit / 4)
        corner = Q.max(axis=0)
        points = Rows(m.S)
        fingerprint = np.random.default_rng(self.seed).random(m.S)
        point_at: dict[float, int] = {}
        point_excess: list[float] = []  # v_i - corner . b_i: how far below the corner interpolation
        excess_array = np.zeros(0)
        beliefs = BeliefSet(m.S)
        beliefs.add(b0[None], np.ones(1))

        def lower(B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            values = B @ alphas.rows.T
            best = values.argmax(axis=1)
            return values[np.arange(len(B)), best], best

        def upper(B: np.ndarray, allowed: np.ndarray | None = None) -> np.ndarray:
            """The upper bound at the beliefs ``B``; ``allowed`` (points, len(B)): which points may serve
            which belief (default: all)."""
            base = B @ corner
            bound = np.minimum((B @ Q.T).max(axis=1), base)
            if points.n:
                inside = points.support @ (B <= 0).T.astype(np.float32) == 0  # supp(point) within supp(b)
                if allowed is not None:
                    inside &= allowed
                i_idx, b_idx = np.nonzero(inside)
                if i_idx.size:
                    # Sawtooth: the largest lambda with b - lambda b_i >= 0 is 1 / max_s b_i(s) / b(s).
                    cols = np.flatnonzero((B > 0).any(axis=0))
                    Bc = B[:, cols]
                    inverse = np.divide(1.0, Bc, out=np.zeros_like(Bc), where=Bc > 0)
                    ratio = 1.0 / (points.rows[i_idx][:, cols] * inverse[b_idx]).max(axis=1)
                    best_gain = np.zeros(len(B))
                    np.minimum.at(best_gain, b_idx, excess_array[i_idx] * ratio)
                    bound = np.minimum(bound, base + best_gain)
            return bound

        def prune_points(chunk: int = 64) -> None:
            """Drop the upper-bound points that the others (and the informed bound) already bound as tightly
            at their own belief (HSVI2's pruning). Dropping points never invalidates the bound."""
            nonlocal excess_array
            keep = np.ones(points.n, dtype=bool)
            for first in range(0, points.n, chunk):
                query = np.arange(first, min(first + chunk, points.n))
                B = points.rows[query]
                others = np.repeat(keep[:, None], len(query), axis=1)
                others[query, np.arange(len(query))] = False                   # not the point itself
                keep[query] &= upper(B, others) > B @ corner + excess_array[query] + 1e-12
            points.keep(keep)
            point_excess[:] = [point_excess[i] for i in np.flatnonzero(keep)]
            excess_array = np.asarray(point_excess)
            point_at.clear()
            point_at.update({float(b @ fingerprint): i for i, b in enumerate(points.rows)})

        def evaluate(b: np.ndarray) -> list:
            """Successors of b with their bounds: [a_idx, z_idx, probs, beliefs, lower, best alpha, upper]."""
            a_idx, z_idx, probs, nxt = m.successors(b)
            # Many actions leave most intentions as they are: bound each distinct successor belief once.
            _, first, back = np.unique(nxt @ fingerprint, return_index=True, return_inverse=True)
            distinct = nxt[first]
            if not np.array_equal(distinct[back], nxt):  # a fingerprint collision: compare whole rows
                distinct, back = np.unique(nxt, axis=0, return_inverse=True)
            back = back.reshape(-1)
            lo, best = lower(distinct)
            return [a_idx, z_idx, probs, nxt, lo[back], best[back], upper(distinct)[back]]

        def q_upper(b: np.ndarray, evaluation) -> np.ndarray:
            a_idx, _, probs, _, _, _, up = evaluation
            q = m.R @ b
            q += np.bincount(a_idx, gamma * probs * up, minlength=m.A)
            return q

        def backup(b: np.ndarray, evaluation, known: tuple[float, int, float]) -> tuple[float, int, float]:
            """Back up both bounds at ``b``; ``known``: its (lower, best vector, upper) bounds when the trial
            went down (still valid bounds: they can only have tightened since). Returns the new ones."""
            nonlocal excess_array
            low, best_vector, high = known
            a_idx, z_idx, probs, nxt, lo, best, up = evaluation
            chosen = alphas.rows[best]                                   # (M, S): best vector per successor
            weighted = m.OZ[a_idx, z_idx] * chosen                       # (M, S')
            per_action = np.zeros((m.A, m.S))
            # a_idx is sorted (successors come action by action): sum each action's block at once.
            present, starts = np.unique(a_idx, return_index=True)
            per_action[present] = np.add.reduceat(weighted, starts, axis=0)
            vectors = m.R + gamma * m.expect(per_action)
            a = int(np.argmax(vectors @ b))
            if vectors[a] @ b > low + 1e-12:
                low, best_vector = float(vectors[a] @ b), alphas.n
                alphas.append(vectors[a])
                actions.append(a)
            value = float(q_upper(b, evaluation).max())
            if value < high - 1e-12:
                high = value
                key = float(b @ fingerprint)
                row = point_at.get(key)
                if row is not None and np.array_equal(points.rows[row], b):
                    point_excess[row] = value - float(b @ corner)  # the same belief again: lower its value
                else:
                    point_at[key] = points.n
                    points.append(b)
                    point_excess.append(value - float(b @ corner))
                excess_array = np.asarray(point_excess)
            return low, best_vector, high

        def trial(iteration: int, epsilon: float) -> float:
            """One trial from b0; returns its work (estimated multiply-adds)."""
            path = []  # (belief, evaluation, index of the successor the trial went on to, its known bounds)
            b, depth, weight = b0, 0, 1.0
            low, best_vector = (float(v[0]) for v in lower(b0[None]))
            known = (low, int(best_vector), float(upper(b0[None])[0]))
            reached, weights = [], []
            while depth < self.max_depth:
                evaluation = evaluate(b)
                a_idx, z_idx, probs, nxt, lo, best, up = evaluation
                path.append([b, evaluation, None, known])
                if known[2] - known[0] <= epsilon * gamma ** (-depth):
                    break
                if iteration % self.lower_trial_every == 0:
                    # Now and then, follow the current policy (the lower bound's best action) instead, so the
                    # beliefs that policy visits get backed up too (SARSOP samples near it for the same reason).
                    q_low = m.R @ b
                    q_low += np.bincount(a_idx, gamma * probs * lo, minlength=m.A)
                    a = int(np.argmax(q_low))
                else:
                    a = int(np.argmax(q_upper(b, evaluation)))
                mine = np.flatnonzero(a_idx == a)
                if mine.size == 0:
                    break
                excess = probs[mine] * (up[mine] - lo[mine] - epsilon * gamma ** (-(depth + 1)))
                if excess.max() <= 0:
                    break
                k = int(mine[int(np.argmax(excess))])
                path[-1][2] = k
                b, depth, weight = nxt[k], depth + 1, weight * gamma * probs[k]
                known = (float(lo[k]), int(best[k]), float(up[k]))
                reached.append(b)
                weights.append(weight)
            child = None
            for b, evaluation, k, known in reversed(path):
                if k is not None:
                    # Only the successor the trial went through has new bounds; the others' bounds can only
                    # have tightened since, so their stored values remain valid bounds.
                    evaluation[4][k], evaluation[5][k], evaluation[6][k] = child
                child = backup(b, evaluation, known)
            if reached:
                beliefs.add(np.asarray(reached), np.asarray(weights))  # the sweeps back them up from now on
            # Per step: every action and observation, then each distinct successor against both bounds
            # (counted to 6 digits, so that a model written with rounded numbers costs the same).
            distinct = sum(len(np.unique(np.round(evaluation[3] @ fingerprint, 6))) for _, evaluation, _, _ in path)
            return float(len(path) * m.A * m.Z * m.S + distinct * m.S * (alphas.n + points.n))

        def prune() -> None:
            """Keep the alpha vectors that are best at some belief of the set (and the blind ones)."""
            best = np.unique(lower(beliefs.rows)[1])
            mask = np.zeros(alphas.n, dtype=bool)
            mask[best] = True
            mask[:m.A] = True
            alphas.keep(mask)
            actions[:] = [actions[i] for i in np.flatnonzero(mask)]

        def sweeps():
            """The lower bound's process (module docstring), as a generator yielding its work (estimated
            multiply-adds)."""
            theta = self.theta
            while True:
                todo = np.zeros(0, dtype=np.int64)
                if beliefs.n * m.S < self.belief_memory:
                    todo = beliefs.take_frontier(theta)
                    while not todo.size and theta > 0 and beliefs.unexpanded:
                        theta /= self.theta_factor
                        todo = beliefs.take_frontier(theta)
                if todo.size:
                    greedy = np.asarray(actions)[lower(beliefs.rows[todo])[1]]
                    beliefs.add(*policy_successors(m, beliefs.rows[todo], greedy, beliefs.weights[todo]))
                    yield float(todo.size * m.Z * m.S)
                for _ in range(self.sweeps_per_round):
                    for first in range(0, beliefs.n, self.chunk):
                        chunk = beliefs.rows[first:first + self.chunk]
                        backups = alphas.n * len(chunk) * m.S  # the current values, and per candidate:
                        vectors, chosen, _, candidates = sweep(m, chunk, alphas.rows, Q)
                        alphas.extend(vectors)
                        actions.extend(int(a) for a in chosen)
                        yield float(backups + candidates * m.S * m.Z * alphas.n)
                    prune()

        history = []
        iterations = 0
        lower_process = sweeps()
        # Work (in belief-set backups) goes to the process that has recently closed the gap at b0 the
        # fastest per unit of work, each keeping at least min_share of it: [decayed gap closed, decayed work].
        recent = {"sweeps": [0.0, 0.0], "trials": [0.0, 0.0]}
        done = {"sweeps": 0.0, "trials": 0.0}
        pruned_at = 0  # upper-bound points after the last pruning
        lb, ub = float(lower(b0[None])[0][0]), float(upper(b0[None])[0])
        history.append((time.perf_counter() - start, lb, ub))
        while (ub - lb > self.precision and time.perf_counter() - start < self.time_limit
               and (self.max_iterations is None or iterations < self.max_iterations)):
            rates = {k: (g / w if w > 0 else np.inf) for k, (g, w) in recent.items()}
            total = rates["sweeps"] + rates["trials"]
            share = 0.5 if not np.isfinite(total) or total <= 0 else rates["sweeps"] / total
            share = min(max(share, self.min_share), 1 - self.min_share)
            if done["sweeps"] * (1 - share) <= done["trials"] * share:
                process, work = "sweeps", float(next(lower_process))
            else:
                iterations += 1
                # Trials aim at a fraction of the current gap, so early trials stay shallow (HSVI's epsilon).
                epsilon = max(self.precision, self.gap_fraction * (ub - lb))
                process, work = "trials", trial(iterations, epsilon)
                if points.n >= max(512, 2 * pruned_at):
                    prune_points()
                    pruned_at = points.n
            gap = ub - lb
            lb, ub = float(lower(b0[None])[0][0]), float(upper(b0[None])[0])
            decay = 0.5 ** (work / self.rate_horizon)
            recent[process] = [recent[process][0] * decay + (gap - (ub - lb)), recent[process][1] * decay + work]
            done[process] += work
            elapsed = time.perf_counter() - start
            history.append((elapsed, lb, ub))
            if progress is not None:
                progress(elapsed, lb, ub)
        policy = AlphaVectorPolicy(alphas.rows.copy(), np.asarray(actions, dtype=np.int64))
        return SolveResult(policy, lb, ub, time.perf_counter() - start, iterations, history)
