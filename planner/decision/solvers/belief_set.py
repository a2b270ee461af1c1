"""Lower-bound value iteration over a growing set of reachable beliefs.

A *belief set* holds beliefs reachable from ``b0``, each with its *reach weight*: the largest
``gamma^depth * P(history)`` over the histories found to lead to it, i.e. how much an error in its value
can move the value at ``b0``. It grows by *expansion*: a belief's successors under the current policy's
action (the lower bound's greedy action), one for each observation, weighted by their probability. Growing
only the beliefs heavier than a threshold ``theta``, and lowering ``theta`` by a constant factor when none
is left, visits the beliefs that matter most first (breadth first by weight, not by depth).

A *sweep* backs up every belief of the set at once (point-based value iteration, Pineau et al. 2003, with
the batched form of Perseus, Spaan & Vlassis 2005): for belief ``b`` and action ``a``,
``Q(b, a) = R_a . b + gamma sum_z max_k (b T_a diag(O_z,a)) . alpha_k``, and the vector achieving the best
``Q(b, a)`` joins the lower bound when it beats the current value at ``b``. Actions whose fast-informed
upper bound at ``b`` is below the current lower bound there cannot improve it and are skipped.

Why it suits the operator-intent POMDP: observations reveal the operator's operation except for missed
detections, so beliefs branch into few heavy successors and a long tail of light ones (runs of blank
observations); the weights order that tail, and a sweep evaluates thousands of beliefs in a few matrix
products where a trial-based solver backs up one belief at a time.

Cost of a sweep over N beliefs with K vectors: O(N A' (nnz(T) + s Z K)), A' the actions not skipped and s
the number of states a predicted belief covers (all S for small models, multiplied densely).
"""
from __future__ import annotations

import hashlib
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from .tables import BLOCK, WORK, SolveStopped, Tables, best_products

__all__ = ["BeliefSet", "policy_successors", "sweep"]

SPARSE_STATES = 256  # above this many states, predicted beliefs are multiplied as sparse rows


class BeliefSet:
    """Reachable beliefs with reach weights, deduplicated to ``resolution`` (module docstring)."""

    def __init__(self, width: int, resolution: float = 1e-7):
        self.resolution = resolution
        self._rows = np.zeros((64, width))
        self._weight = np.zeros(64)
        self._expanded = np.zeros(64, dtype=bool)
        self._index: dict[bytes, int] = {}
        self.n = 0

    @property
    def rows(self) -> np.ndarray:
        """(n, S): the beliefs."""
        return self._rows[:self.n]

    @property
    def weights(self) -> np.ndarray:
        return self._weight[:self.n]

    @property
    def unexpanded(self) -> int:
        """How many beliefs have not been expanded yet."""
        return int((~self._expanded[:self.n]).sum())

    def add(self, beliefs: np.ndarray, weights: np.ndarray) -> None:
        """Add beliefs (n, S) with reach weights (n,); a belief already present keeps the larger weight."""
        keys = np.round(beliefs / self.resolution).astype(np.int64)
        for belief, key, weight in zip(beliefs, keys, weights):
            # A 128-bit digest of the rounded belief, not the S x 8 bytes themselves: the index would
            # otherwise hold as many bytes as the beliefs (a collision has probability about n^2 / 2^129).
            token = hashlib.blake2b(key.tobytes(), digest_size=16).digest()
            row = self._index.get(token)
            if row is not None:
                self._weight[row] = max(self._weight[row], weight)
                continue
            if self.n == len(self._rows):
                self._rows = np.concatenate([self._rows, np.zeros_like(self._rows)])
                self._weight = np.concatenate([self._weight, np.zeros_like(self._weight)])
                self._expanded = np.concatenate([self._expanded, np.zeros_like(self._expanded)])
            self._index[token] = self.n
            self._rows[self.n], self._weight[self.n], self._expanded[self.n] = belief, weight, False
            self.n += 1

    def take_frontier(self, theta: float) -> np.ndarray:
        """Indices of the beliefs heavier than ``theta`` not expanded yet; they count as expanded now."""
        todo = np.flatnonzero(~self._expanded[:self.n] & (self._weight[:self.n] > theta))
        self._expanded[todo] = True
        return todo


def policy_successors(m: Tables, beliefs: np.ndarray, actions: np.ndarray, weights: np.ndarray,
                      floor: float = 1e-12,
                      stop: Callable[[], bool] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The successors of ``beliefs`` (n, S), each after its own action (n,), for every observation of
    probability above ``floor``: the new beliefs (k, S) and their reach weights ``gamma * weight * P(z)``.
    ``stop`` (the solver's time limit) is checked before each product; once true, the successors found so far
    are returned (any subset of reachable beliefs is a valid belief set)."""
    out, out_w = [], []
    block = max(1, BLOCK // (m.Z * m.S))  # beliefs per product: (block, Z, S) joint probabilities at most
    for a in np.unique(actions):
        todo = np.flatnonzero(actions == a)
        for first in range(0, todo.size, block):
            if stop is not None and stop():
                break
            rows = todo[first:first + block]
            joint = m.step(beliefs[rows], int(a))[:, None, :] * m.OZ[a][None]   # (n_a, Z, S)
            pz = joint.sum(axis=2)
            r, z = np.nonzero(pz > floor)
            out.append(joint[r, z] / pz[r, z][:, None])
            out_w.append(m.gamma * weights[rows][r] * pz[r, z])
    if not out:
        return np.zeros((0, m.S)), np.zeros(0)
    return np.concatenate(out), np.concatenate(out_w)


def _projected(m: Tables, a: int, stepped: np.ndarray, alphas: np.ndarray, projections: dict, table: int,
               stop: Callable[[], bool] | None = None):
    """``(b T_a) . (O_z,a * alpha_k)`` for the predicted beliefs ``stepped`` (n, S), every observation z and
    vector k at once: (n, Z K). Small models: through the projection (S, Z K), built once per observation
    table (``projections``). Large ones (above ``SPARSE_STATES``): per observation, over the beliefs' non-zero
    entries only, never the projection (109,601 states, 18 observations and 123 vectors made it 1.9 GB, built
    in one step that no time limit could stop; ``stop`` is checked between observations then,
    :class:`~.tables.SolveStopped`). Cost: O(nnz(stepped) Z K)."""
    K = len(alphas)
    if m.S > SPARSE_STATES:
        rows = sp.csr_matrix(stepped)
        out = np.empty((len(stepped), m.Z, K))
        for z in range(m.Z):
            if z and stop is not None and stop():
                raise SolveStopped
            out[:, z] = rows.multiply(m.OZ[a][z][None, :]).tocsr() @ alphas.T
        return out.reshape(len(stepped), m.Z * K)
    if table not in projections:
        projections[table] = (m.OZ[a][:, :, None] * alphas.T[None]).transpose(1, 0, 2).reshape(m.S, m.Z * K)
    return stepped @ projections[table]


def sweep(m: Tables, beliefs: np.ndarray, alphas: np.ndarray, q_upper: np.ndarray, tolerance: float = 1e-9,
          stop: Callable[[], bool] | None = None):
    """Back up every belief of ``beliefs`` (N, S) against the vectors ``alphas`` (K, S).

    ``q_upper`` (A, S): an upper bound on Q (e.g. the fast informed bound), to skip actions that cannot
    improve. Returns ``(vectors, actions, improved, candidates)``: the distinct backed-up vectors (n, S) of
    the beliefs whose value improved by more than ``tolerance``, their actions (n,), the boolean mask (N,)
    of those beliefs, and how many (belief, action) pairs were backed up.

    ``stop`` (the solver's time limit) is checked before each block of back-ups and of the new vectors'
    construction: once true, the sweep ends with the actions backed up (and the vectors made) so far (a back-up over some of the actions is still the value of a policy, so
    its vector is a valid lower bound), or raises :class:`~.tables.SolveStopped` before the first (in the
    current values' products). On a large model one sweep takes tens of seconds (a 9-part chain: 36 s).
    """
    N, K = len(beliefs), len(alphas)
    current = best_products(beliefs, alphas, stop)[0]
    candidates = beliefs @ q_upper.T >= current[:, None] - tolerance           # (N, A)
    best_q = np.full(N, -np.inf)
    best_a = np.zeros(N, dtype=np.int64)
    best_choice = np.zeros((N, m.Z), dtype=np.int64)
    projections: dict[int, np.ndarray] = {}
    block = max(1, BLOCK // (m.Z * K))  # beliefs per product: (block, Z, K) values at most
    if m.S > SPARSE_STATES:  # and about WORK multiply-adds (large beliefs: a time limit can stop between them)
        support = int(np.count_nonzero(beliefs)) // max(1, N) + 1
        block = max(1, min(block, WORK // (support * m.Z * K)))
    backed_up, stopped = 0, False
    for a in range(m.A):
        todo = np.flatnonzero(candidates[:, a])
        if not todo.size:
            continue
        if stop is not None and stop():
            break
        table = int(m.observation_table[a])
        for first in range(0, todo.size, block):
            if first and stop is not None and stop():
                stopped = True
                break
            rows = todo[first:first + block]
            stepped = m.step(beliefs[rows], a)
            try:
                values = _projected(m, a, stepped, alphas, projections, table, stop).reshape(len(rows), m.Z, K)
            except SolveStopped:  # inside a block: drop it, keep the blocks done
                stopped = True
                break
            backed_up += len(rows)
            choice = values.argmax(axis=2)                                          # (n, Z)
            q = beliefs[rows] @ m.R[a] + m.gamma * np.take_along_axis(values, choice[:, :, None], 2).sum(axis=(1, 2))
            better = q > best_q[rows]
            rows = rows[better]
            best_q[rows], best_a[rows] = q[better], a
            best_choice[rows] = choice[better]
        if stopped:
            break
    improved = best_q > current + tolerance
    # Beliefs that pick the same action and the same vector for every observation share their new vector.
    keys = np.unique(np.column_stack([best_a, best_choice])[improved], axis=0)
    vectors = np.empty((len(keys), m.S))
    done = np.zeros(len(keys), dtype=bool)
    step = max(1, BLOCK // (m.Z * m.S))  # vectors per product: (step, Z, S) numbers at most
    for a in np.unique(keys[:, 0]):
        mine = np.flatnonzero(keys[:, 0] == a)
        for first in range(0, mine.size, step):
            if done.any() and stop is not None and stop():  # the vectors made so far are each valid
                return vectors[done], keys[done, 0], improved, backed_up
            part = mine[first:first + step]
            inner = (m.OZ[a][None] * alphas[keys[part, 1:]]).sum(axis=1)      # (n, S'): sum_z O_z * alpha_k(z)
            vectors[part] = m.R[a] + m.gamma * m.expect_one(int(a), inner)
            done[part] = True
    return vectors, keys[:, 0], improved, backed_up
