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
    """A growing (n, width) float array (amortised appends)."""

    def __init__(self, width: int):
        self._data = np.zeros((64, width))
        self.n = 0

    def append(self, row: np.ndarray) -> None:
        if self.n == self._data.shape[0]:
            self._data = np.concatenate([self._data, np.zeros_like(self._data)])
        self._data[self.n] = row
        self.n += 1

    @property
    def rows(self) -> np.ndarray:
        return self._data[:self.n]


class _Model:
    """The tables a solver needs, in the shapes it needs them."""

    def __init__(self, model: POMDP):
        self.S, self.A, self.Z = model.n_states, model.n_actions, model.n_observations
        self.T = [t.tocsr() for t in model.transition]               # rows: from
        self.Tt = [t.T.tocsr() for t in model.transition]            # rows: to
        self.OZ = np.stack([o.toarray().T for o in model.observation])  # (A, Z, S): O(z | s', a)
        self.R = np.asarray(model.reward, dtype=float)                 # (A, S)
        self.gamma = model.discount

    def successors(self, b: np.ndarray):
        """Non-zero (action, observation) pairs after ``b``: their indices, probabilities and beliefs."""
        predicted = np.stack([t @ b for t in self.Tt])                  # (A, S)
        joint = self.OZ * predicted[:, None, :]                          # (A, Z, S)
        pz = joint.sum(axis=2)
        a_idx, z_idx = np.nonzero(pz > 1e-15)
        probs = pz[a_idx, z_idx]
        return a_idx, z_idx, probs, joint[a_idx, z_idx] / probs[:, None]


def _blind_lower_bound(m: _Model) -> np.ndarray:
    """For each action, the value of repeating it forever: (I - gamma T_a) alpha = R_a."""
    identity = sp.identity(m.S, format="csc")
    return np.array([spla.spsolve((identity - m.gamma * m.T[a]).tocsc(), m.R[a]) for a in range(m.A)])


def _fast_informed_bound(m: _Model, tolerance: float = 1e-9, max_sweeps: int = 100_000) -> np.ndarray:
    """Q (A, S): Q(s,a) = R(s,a) + gamma sum_z max_a' sum_s' T(s'|s,a) O(z|s',a) Q(s',a') (Hauskrecht 2000)."""
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

    ``time_limit`` (s), ``precision`` (target gap at b0), ``max_iterations`` (trials), ``max_depth``.
    """

    time_limit: float = 60.0
    precision: float = 1e-3
    max_iterations: int | None = None
    max_depth: int = 300
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
        points, point_values = _Rows(m.S), []

        def lower(B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            values = B @ alphas.rows.T
            best = values.argmax(axis=1)
            return values[np.arange(len(B)), best], best

        def upper(B: np.ndarray) -> np.ndarray:
            base = B @ corner
            bound = np.minimum((B @ Q.T).max(axis=1), base)
            if points.n:
                P = points.rows
                inside = (P > 0).astype(float) @ (B <= 0).T.astype(float) == 0  # supp(point) within supp(b)
                i_idx, b_idx = np.nonzero(inside)
                if i_idx.size:
                    Pi = P[i_idx]
                    ratio = np.where(Pi > 0, B[b_idx] / np.where(Pi > 0, Pi, 1.0), np.inf).min(axis=1)
                    gain = (np.asarray(point_values)[i_idx] - Pi @ corner) * ratio
                    best_gain = np.zeros(len(B))
                    np.minimum.at(best_gain, b_idx, gain)
                    bound = np.minimum(bound, base + best_gain)
            return bound

        def evaluate(b: np.ndarray):
            a_idx, z_idx, probs, nxt = m.successors(b)
            lo, best = lower(nxt)
            up = upper(nxt)
            q_upper = m.R @ b
            np.add.at(q_upper, a_idx, gamma * probs * up)
            return a_idx, z_idx, probs, nxt, lo, best, up, q_upper

        def backup(b: np.ndarray, evaluation) -> None:
            a_idx, z_idx, probs, nxt, lo, best, up, q_upper = evaluation
            chosen = alphas.rows[best]                                   # (M, S): best vector per successor
            weighted = m.OZ[a_idx, z_idx] * chosen                       # (M, S')
            per_action = np.zeros((m.A, m.S))
            np.add.at(per_action, a_idx, weighted)
            vectors = m.R + gamma * np.stack([m.T[a] @ per_action[a] for a in range(m.A)])
            a = int(np.argmax(vectors @ b))
            if vectors[a] @ b > lower(b[None])[0][0] + 1e-12:
                alphas.append(vectors[a])
                actions.append(a)
            value = float(q_upper.max())
            if value < upper(b[None])[0] - 1e-12:
                points.append(b)
                point_values.append(value)

        history = []
        iterations = 0
        lb, ub = float(lower(b0[None])[0][0]), float(upper(b0[None])[0])
        history.append((time.perf_counter() - start, lb, ub))
        while (ub - lb > self.precision and time.perf_counter() - start < self.time_limit
               and (self.max_iterations is None or iterations < self.max_iterations)):
            iterations += 1
            epsilon = self.precision
            path = []
            b, depth = b0, 0
            while depth < self.max_depth:
                evaluation = evaluate(b)
                a_idx, z_idx, probs, nxt, lo, best, up, q_upper = evaluation
                path.append((b, evaluation))
                if float(upper(b[None])[0]) - float(lower(b[None])[0][0]) <= epsilon * gamma ** (-depth):
                    break
                a = int(np.argmax(q_upper))
                mine = np.flatnonzero(a_idx == a)
                if mine.size == 0:
                    break
                excess = probs[mine] * (up[mine] - lo[mine] - epsilon * gamma ** (-(depth + 1)))
                k = mine[int(np.argmax(excess))]
                if excess.max() <= 0:
                    break
                b, depth = nxt[k], depth + 1
            for b, _ in reversed(path):
                backup(b, evaluate(b))
            lb, ub = float(lower(b0[None])[0][0]), float(upper(b0[None])[0])
            elapsed = time.perf_counter() - start
            history.append((elapsed, lb, ub))
            if progress is not None:
                progress(elapsed, lb, ub)
        policy = AlphaVectorPolicy(alphas.rows.copy(), np.asarray(actions, dtype=np.int64))
        return SolveResult(policy, lb, ub, time.perf_counter() - start, iterations, history)
