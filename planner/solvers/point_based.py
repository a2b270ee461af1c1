"""An anytime point-based POMDP solver with certified bounds (heuristic search value iteration).

The value ``V*(b0)`` is bracketed by a lower bound (a set of alpha vectors: the value of a policy that can
be executed) and an upper bound (belief points with values, interpolated by the sawtooth rule, and the fast
informed bound). Trials descend from ``b0`` following the action that is best for the upper bound and the
observation with the largest weighted excess gap, and back up both bounds on the way up (Smith & Simmons,
HSVI2, 2005). It stops at the time limit, at the iteration limit, or when ``upper - lower <= precision`` at
``b0``: the gap is a certificate, ``V*(b0)`` lies between the bounds.

Every step evaluates all actions and observations at once (numpy); a backup costs
O(A (nnz(T) + S Z) + (K + N) S M) for K alpha vectors, N upper-bound points and M = A x Z successors.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..policy import AlphaVectorPolicy
from ..pomdp import POMDP

__all__ = ["PointBasedSolver", "SolveResult"]


@dataclass(frozen=True)
class SolveResult:
    """The policy (lower-bound alpha vectors), the bounds at ``b0`` and how they evolved."""

    policy: AlphaVectorPolicy
    lower_bound: float
    upper_bound: float
    seconds: float
    iterations: int
    history: list = field(default_factory=list)  # (seconds, lower, upper) after each trial

    @property
    def gap(self) -> float:
        return self.upper_bound - self.lower_bound

    def as_dict(self) -> dict:
        return {"lower_bound": self.lower_bound, "upper_bound": self.upper_bound, "gap": self.gap,
                "alpha_vectors": int(self.policy.alphas.shape[0]), "seconds": round(self.seconds, 3),
                "iterations": self.iterations}


class _Rows:
    """A growing (n, width) float array (amortised appends), with its support pattern as floats."""

    def __init__(self, width: int):
        self._data = np.zeros((64, width))
        self._support = np.zeros((64, width), dtype=np.float32)
        self.n = 0

    def append(self, row: np.ndarray) -> None:
        if self.n == self._data.shape[0]:
            self._data = np.concatenate([self._data, np.zeros_like(self._data)])
            self._support = np.concatenate([self._support, np.zeros_like(self._support)])
        self._data[self.n] = row
        self._support[self.n] = row > 0
        self.n += 1

    def keep(self, mask: np.ndarray) -> None:
        kept = int(mask.sum())
        self._data[:kept] = self._data[:self.n][mask]
        self._support[:kept] = self._support[:self.n][mask]
        self.n = kept

    @property
    def rows(self) -> np.ndarray:
        return self._data[:self.n]

    @property
    def support(self) -> np.ndarray:
        return self._support[:self.n]


DENSE_LIMIT = 20_000_000  # A * S * S entries up to which transitions are kept dense (faster for small models)


class _Model:
    """The tables a solver needs, in the shapes it needs them."""

    def __init__(self, model: POMDP):
        self.S, self.A, self.Z = model.n_states, model.n_actions, model.n_observations
        self.T = [t.tocsr() for t in model.transition]               # rows: from
        self.dense = self.A * self.S * self.S <= DENSE_LIMIT
        if self.dense:
            self.TD = np.stack([t.toarray() for t in model.transition])  # (A, S, S)
        else:
            self.stacked_t = sp.vstack([t.T for t in model.transition]).tocsr()   # (A*S, S): rows "to"
            self.block = sp.block_diag(self.T, format="csr")                   # (A*S, A*S)
        self.OZ = np.stack([o.toarray().T for o in model.observation])  # (A, Z, S): O(z | s', a)
        self.R = np.asarray(model.reward, dtype=float)                 # (A, S)
        self.gamma = model.discount

    def predict(self, b: np.ndarray) -> np.ndarray:
        """(A, S): the next-state distribution after each action."""
        if self.dense:
            return np.tensordot(b, self.TD, axes=(0, 1))
        return (self.stacked_t @ b).reshape(self.A, self.S)

    def expect(self, W: np.ndarray) -> np.ndarray:
        """(A, S): for each action a, sum_s' T(s'|s,a) W[a, s']."""
        if self.dense:
            return np.einsum("ast,at->as", self.TD, W)
        return (self.block @ W.reshape(-1)).reshape(self.A, self.S)

    def successors(self, b: np.ndarray):
        """Non-zero (action, observation) pairs after ``b``: their indices, probabilities and beliefs."""
        predicted = self.predict(b)                                      # (A, S)
        joint = self.OZ * predicted[:, None, :]                          # (A, Z, S)
        pz = joint.sum(axis=2)
        a_idx, z_idx = np.nonzero(pz > 1e-15)
        probs = pz[a_idx, z_idx]
        return a_idx, z_idx, probs, joint[a_idx, z_idx] / probs[:, None]


def _blind_lower_bound(m: _Model) -> np.ndarray:
    """For each action, the value of repeating it forever: (I - gamma T_a) alpha = R_a."""
    identity = sp.identity(m.S, format="csc")
    return np.array([spla.spsolve((identity - m.gamma * m.T[a]).tocsc(), m.R[a]) for a in range(m.A)])


def _fast_informed_bound(m: _Model, tolerance: float = 1e-3, max_sweeps: int = 100_000) -> np.ndarray:
    """Q (A, S): Q(s,a) = R(s,a) + gamma sum_z max_a' sum_s' T(s'|s,a) O(z|s',a) Q(s',a') (Hauskrecht 2000).

    Iterated from the trivial upper bound R_max / (1 - gamma): the operator is monotone, so every iterate
    is an upper bound too, and the iteration can stop early.
    """
    Q = np.full((m.A, m.S), np.abs(m.R).max() / (1 - m.gamma))
    for _ in range(max_sweeps):
        new = np.empty_like(Q)
        for a in range(m.A):
            inner = np.stack([m.T[a] @ (m.OZ[a][z][:, None] * Q.T) for z in range(m.Z)])  # (Z, S, A')
            new[a] = m.R[a] + m.gamma * inner.max(axis=2).sum(axis=0)
        done = np.abs(new - Q).max() < tolerance
        Q = new
        if done:
            break
    return Q


@dataclass(frozen=True)
class PointBasedSolver:
    """HSVI-style point-based solver (module docstring). Same configuration and seed, same result.

    ``time_limit`` (s), ``precision`` (target gap at b0), ``max_iterations`` (trials), ``max_depth``,
    ``gap_fraction``: each trial aims at this fraction of the current gap at b0 (at least ``precision``);
    every ``lower_trial_every``-th trial follows the lower bound's policy; alpha vectors that are best at
    no visited belief are pruned every ``prune_every`` trials.
    """

    time_limit: float = 60.0
    precision: float = 1e-3
    max_iterations: int | None = None
    max_depth: int = 300
    gap_fraction: float = 0.5
    prune_every: int = 25
    lower_trial_every: int = 2
    seed: int = 0

    def solve(self, model: POMDP, progress: Callable[[float, float, float], None] | None = None) -> SolveResult:
        start = time.perf_counter()
        m = _Model(model)
        gamma = m.gamma
        b0 = np.asarray(model.initial, dtype=float)
        alphas = _Rows(m.S)
        actions: list[int] = []
        for a, alpha in enumerate(_blind_lower_bound(m)):
            alphas.append(alpha)
            actions.append(a)
        Q = _fast_informed_bound(m)
        corner = Q.max(axis=0)
        points = _Rows(m.S)
        fingerprint = np.random.default_rng(self.seed).random(m.S)
        point_at: dict[float, int] = {}
        point_excess: list[float] = []  # v_i - corner . b_i: how far below the corner interpolation
        excess_array = np.zeros(0)

        def lower(B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            values = B @ alphas.rows.T
            best = values.argmax(axis=1)
            return values[np.arange(len(B)), best], best

        def upper(B: np.ndarray) -> np.ndarray:
            base = B @ corner
            bound = np.minimum((B @ Q.T).max(axis=1), base)
            if points.n:
                inside = points.support @ (B <= 0).T.astype(np.float32) == 0  # supp(point) within supp(b)
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
            np.add.at(q, a_idx, gamma * probs * up)
            return q

        def backup(b: np.ndarray, evaluation) -> None:
            a_idx, z_idx, probs, nxt, lo, best, up = evaluation
            chosen = alphas.rows[best]                                   # (M, S): best vector per successor
            weighted = m.OZ[a_idx, z_idx] * chosen                       # (M, S')
            per_action = np.zeros((m.A, m.S))
            np.add.at(per_action, a_idx, weighted)
            vectors = m.R + gamma * m.expect(per_action)
            a = int(np.argmax(vectors @ b))
            if vectors[a] @ b > lower(b[None])[0][0] + 1e-12:
                alphas.append(vectors[a])
                actions.append(a)
            nonlocal excess_array
            value = float(q_upper(b, evaluation).max())
            if value < upper(b[None])[0] - 1e-12:
                key = float(b @ fingerprint)
                row = point_at.get(key)
                if row is not None and np.array_equal(points.rows[row], b):
                    point_excess[row] = value - float(b @ corner)  # the same belief again: lower its value
                else:
                    point_at[key] = points.n
                    points.append(b)
                    point_excess.append(value - float(b @ corner))
                excess_array = np.asarray(point_excess)

        visited = _Rows(m.S)

        def prune() -> None:
            """Keep the alpha vectors that are best at some visited belief (and the blind ones)."""
            V = visited.rows
            best = np.unique((V @ alphas.rows.T).argmax(axis=1))
            mask = np.zeros(alphas.n, dtype=bool)
            mask[best] = True
            mask[:m.A] = True
            alphas.keep(mask)
            kept = [actions[i] for i in np.flatnonzero(mask)]
            actions[:] = kept

        history = []
        iterations = 0
        lb, ub = float(lower(b0[None])[0][0]), float(upper(b0[None])[0])
        history.append((time.perf_counter() - start, lb, ub))
        while (ub - lb > self.precision and time.perf_counter() - start < self.time_limit
               and (self.max_iterations is None or iterations < self.max_iterations)):
            iterations += 1
            # Trials aim at a fraction of the current gap, so early trials stay shallow (HSVI's epsilon).
            epsilon = max(self.precision, self.gap_fraction * (ub - lb))
            path = []  # (belief, evaluation, index of the successor the trial went on to)
            b, depth = b0, 0
            while depth < self.max_depth:
                evaluation = evaluate(b)
                a_idx, z_idx, probs, nxt, lo, best, up = evaluation
                path.append([b, evaluation, None])
                if float(upper(b[None])[0]) - float(lower(b[None])[0][0]) <= epsilon * gamma ** (-depth):
                    break
                if iterations % self.lower_trial_every == 0:
                    # Now and then, follow the current policy (the lower bound's best action) instead, so the
                    # beliefs that policy visits get backed up too (SARSOP samples near it for the same reason).
                    q_low = m.R @ b
                    np.add.at(q_low, a_idx, gamma * probs * lo)
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
                b, depth = nxt[k], depth + 1
            for b, evaluation, k in reversed(path):
                if k is not None:
                    # Only the successor the trial went through has new bounds; the others' bounds can only
                    # have tightened since, so their stored values remain valid bounds.
                    child = evaluation[3][k][None]
                    low, idx = lower(child)
                    evaluation[4][k], evaluation[5][k], evaluation[6][k] = low[0], idx[0], upper(child)[0]
                backup(b, evaluation)
                visited.append(b)
            if iterations % self.prune_every == 0:
                prune()
            lb, ub = float(lower(b0[None])[0][0]), float(upper(b0[None])[0])
            elapsed = time.perf_counter() - start
            history.append((elapsed, lb, ub))
            if progress is not None:
                progress(elapsed, lb, ub)
        policy = AlphaVectorPolicy(alphas.rows.copy(), np.asarray(actions, dtype=np.int64))
        return SolveResult(policy, lb, ub, time.perf_counter() - start, iterations, history)
