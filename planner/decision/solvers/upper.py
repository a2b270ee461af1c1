"""The upper bound: the fast informed bound, tightened by belief points with values (the sawtooth rule).

With ``Q`` (A, S) an upper bound on the Q-function and ``c = max_a Q(a, .)`` the *corner values* (the
bound at each state's corner belief), a stored point ``(b_i, v_i)`` with ``v_i >= V*(b_i)`` has the *excess* ``e_i = v_i - c . b_i``
(how far it lies below the corner interpolation; negative for any point worth storing). Then, for every
belief ``b`` (Hauskrecht 2000; Smith & Simmons 2005)::

    V^(b) = min( max_a Q(a) . b,  c . b + min_i lambda_i(b) e_i ),   lambda_i(b) = min_{s: b_i(s) > 0} b(s) / b_i(s)

where ``lambda_i(b)`` is the largest ``lambda`` with ``b - lambda b_i >= 0`` (zero unless the support of
``b_i`` lies within that of ``b``). Both terms are upper bounds by convexity of ``V*``.

*Corner groups* tighten the corner interpolation where the reachable beliefs never come near a corner (the
lumped model: a belief always spreads over the classes out of a state by fixed fractions). A group ``g`` is a
belief ``B_g`` with a known bound ``u_g >= V*(B_g)``; groups have disjoint supports. With ``alpha_g(b) =
min_{s in supp B_g} b(s) / B_g(s)`` (how much of ``B_g`` fits under ``b``) and ``D_g = max(0, c . B_g - u_g)``
(how far ``u_g`` lies below the corners), convexity gives ``V*(b) <= c . b - sum_g alpha_g(b) D_g`` (write
``b`` as ``sum_g alpha_g B_g`` plus a non-negative rest on the corners). A point then bounds ``b`` by
``lambda v_i + base(b - lambda b_i)``; since ``alpha_g(b - lambda b_i) >= alpha_g(b) - lambda beta_g(b_i)``
with ``beta_g(b_i) = max_{s in supp B_g} b_i(s) / B_g(s)``, the sawtooth term becomes::

    base(b) + min_i ( lambda_i(b) e_i + sum_g min(alpha_g(b), lambda_i(b) beta_g(b_i)) D_g )

(exact when ``b_i`` holds a multiple of ``B_g``). Backing up ``B_g`` lowers ``u_g`` (:meth:`UpperBound.lower_group`).

Points are keyed by a *fingerprint* (a random projection ``b . f``), so backing up a belief that is already
stored lowers its value instead of adding a second point. :meth:`UpperBound.prune` drops the points that the
others already bound as tightly at their own belief (HSVI2): dropping them never loosens the bound.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .tables import BLOCK, WORK, Rows, SolveStopped

__all__ = ["CornerGroups", "RelaxedQ", "SparseRows", "UpperBound"]


@dataclass(frozen=True)
class RelaxedQ:
    """Q-values of a relaxed problem whose value bounds ``V*`` from above at every belief, in pieces that are
    exact where the belief is linear in them (the lumped model's delayed reveal,
    :meth:`~planner.decision.delayed_reveal.DelayedReveal.relaxed_q`): ``robot`` (A, S) per action and
    state (robot actions only), ``wait`` (S,) per state and ``spread_wait`` (G,) at each corner group's
    belief. The bound at ``b``::

        max( max_a robot[a] . b,  wait . b - sum_g alpha_g(b) (wait . B_g - spread_wait[g]) )

    The waiting term writes ``b`` as ``sum_g alpha_g(b) B_g`` plus a non-negative rest over single states
    and uses that the relaxed continuation is convex and positively homogeneous in the (unnormalised)
    belief, hence subadditive (the module docstring of :mod:`~planner.decision.delayed_reveal`)."""

    robot: np.ndarray
    wait: np.ndarray
    spread_wait: np.ndarray

    def __post_init__(self) -> None:
        if not (np.all(np.isfinite(self.robot)) and np.all(np.isfinite(self.wait))
                and np.all(np.isfinite(self.spread_wait))):
            raise ValueError("relaxed Q-values must be finite")


class SparseRows:
    """Rows kept by their non-zeros (CSR, amortised appends): ``arrays()`` gives ``(ptr, cols, vals)``, row
    ``i`` holding ``vals[ptr[i]:ptr[i+1]]`` at ``cols[ptr[i]:ptr[i+1]]``."""

    def __init__(self, rows: np.ndarray | None = None):
        self._ptr, self._cols, self._vals = np.zeros(65, dtype=np.int64), np.zeros(256, dtype=np.int64), np.zeros(256)
        self.n = 0
        for row in ([] if rows is None else rows):
            self.append(row)

    def append(self, row: np.ndarray) -> None:
        cols = np.flatnonzero(row)
        start, end = int(self._ptr[self.n]), int(self._ptr[self.n]) + len(cols)
        if end > len(self._cols):
            size = max(end, 2 * len(self._cols))
            self._cols, self._vals = np.resize(self._cols, size), np.resize(self._vals, size)
        if self.n + 2 > len(self._ptr):
            self._ptr = np.resize(self._ptr, 2 * len(self._ptr))
        self._cols[start:end], self._vals[start:end] = cols, row[cols]
        self.n += 1
        self._ptr[self.n] = end

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        end = int(self._ptr[self.n])
        return self._ptr[:self.n + 1], self._cols[:end], self._vals[:end]


def _flatten(starts: np.ndarray, lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For segments ``[starts[k], starts[k] + lengths[k])``: each element's segment and position, in order."""
    total = int(lengths.sum())
    segment = np.repeat(np.arange(len(lengths)), lengths)
    offset = np.arange(total) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    return segment, np.repeat(starts, lengths) + offset


@dataclass(frozen=True)
class CornerGroups:
    """Beliefs with disjoint supports and an upper bound at each (module docstring): group ``g`` holds the
    states ``member[start[g]:start[g+1]]`` with probabilities ``weight`` (summing to 1 per group), bounded
    by ``value[g]``."""

    member: np.ndarray
    weight: np.ndarray
    start: np.ndarray
    value: np.ndarray

    def __post_init__(self) -> None:
        if len(np.unique(self.member)) != len(self.member):
            raise ValueError("corner groups must have disjoint supports")
        if not np.all(self.weight > 0) or not np.all(np.isfinite(self.value)):
            raise ValueError("corner groups need positive weights and finite values")

    @property
    def n(self) -> int:
        return len(self.start)

    def beliefs(self, n_states: int) -> np.ndarray:
        """(G, S): the group beliefs ``B_g``."""
        out = np.zeros((self.n, n_states))
        rows = np.repeat(np.arange(self.n), np.diff(np.append(self.start, len(self.member))))
        out[rows, self.member] = self.weight
        return out

    def fit(self, B: np.ndarray) -> np.ndarray:
        """(m, G): ``alpha_g(b)`` for the beliefs ``B`` (m, S). Cost: O(m S)."""
        return np.minimum.reduceat(B[:, self.member] / self.weight, self.start, axis=1)

    def reach(self, B: np.ndarray) -> np.ndarray:
        """(m, G): ``beta_g(b)`` for the beliefs ``B`` (m, S). Cost: O(m S)."""
        return np.maximum.reduceat(B[:, self.member] / self.weight, self.start, axis=1)


class UpperBound:
    """The informed bound ``Q`` (A, S) with sawtooth points and optional corner ``groups``; ``fingerprint``
    (S,): random weights that key beliefs (module docstring)."""

    def __init__(self, Q: np.ndarray, fingerprint: np.ndarray, groups: CornerGroups | None = None,
                 relaxed: RelaxedQ | None = None):
        self.Q = Q
        self.corner = Q.max(axis=0)
        self.fingerprint = fingerprint
        self.points = Rows(Q.shape[1])
        self._sparse = SparseRows()        # the points again, as sparse rows (the sawtooth's pairs)
        self._support = Rows(Q.shape[1], True, np.float32, by_row=False)  # their supports, by column
        self._sparse_reach = SparseRows()  # beta_g(b_i) > 0 of each point, sparse
        self._excess = np.zeros(64)
        self._key: dict[float, int] = {}   # fingerprint -> row of points
        self.groups = groups
        if groups is not None:
            self.group_beliefs = groups.beliefs(Q.shape[1])
            self.group_value = np.minimum(groups.value, self.group_beliefs @ self.corner)
            self._drop = self.group_beliefs @ self.corner - self.group_value
            self._reach = Rows(groups.n)   # beta_g(b_i) of the points
        self.relaxed = relaxed
        if relaxed is not None:
            drop = (self.group_beliefs @ relaxed.wait - relaxed.spread_wait) if groups is not None else np.zeros(0)
            self._wait_drop = np.maximum(drop, 0.0)   # >= 0 by subadditivity; 0 keeps a rounding error safe

    @property
    def n(self) -> int:
        """How many points are stored."""
        return self.points.n

    @property
    def excess(self) -> np.ndarray:
        """(n,): ``v_i - c . b_i`` for each stored point."""
        return self._excess[:self.points.n]

    def at(self, B: np.ndarray, allowed: np.ndarray | None = None, stop=None) -> np.ndarray:
        """The bound at the beliefs ``B`` (m, S); ``allowed`` (n, m): which points may serve which belief
        (default: all); ``stop``: checked before each block of beliefs (about ``WORK`` multiply-adds for the
        corner and Q products) and each block of the sawtooth (:class:`~.tables.SolveStopped`).
        Cost: O(m S (A + n)) (the sawtooth only over the pairs whose supports nest)."""
        rows = max(1, WORK // max(1, B.shape[1] * (len(self.Q) + 1)))
        if len(B) > rows:  # many beliefs over many states: in blocks, each bound on its own
            parts = []
            for first in range(0, len(B), rows):
                if first and stop is not None and stop():
                    raise SolveStopped
                parts.append(self.at(B[first:first + rows], None if allowed is None else allowed[:, first:first + rows],
                                     stop))
            return np.concatenate(parts)
        base = B @ self.corner
        fit = None
        if self.groups is not None:
            fit = self.groups.fit(B)
            base = base - fit @ self._drop
        bound = np.minimum((B @ self.Q.T).max(axis=1), base)
        if self.relaxed is not None:
            waiting = B @ self.relaxed.wait - (fit @ self._wait_drop if fit is not None else 0.0)
            bound = np.minimum(bound, np.maximum((B @ self.relaxed.robot.T).max(axis=1), waiting))
        if not self.points.n:
            return bound
        # supp(point) within supp(b): counted over the columns some belief covers (a point reaching outside
        # them is inside none), so the product is only as wide as the beliefs' supports.
        covers = (B > 0).any(axis=0)
        # Only the points whose support lies within that union can nest in a belief (counted over the
        # union's columns: O(n S') for S' covered states), and only those enter the (beliefs x points) product.
        ptr, point_cols, _ = self._sparse.arrays()
        lengths = np.diff(ptr)
        cols = np.flatnonzero(covers)
        if len(cols) * self.n <= BLOCK:
            support = self._support.columns[cols]                                       # (S', n) of 0 and 1
            candidates = np.flatnonzero(np.ones(len(cols), dtype=np.float32) @ support == lengths)
            support = support[:, candidates]
        else:  # wide beliefs and many points: counted on the points' non-zeros instead, O(nnz)
            candidates = np.flatnonzero(np.add.reduceat(covers[point_cols], ptr[:-1]) == lengths)
            support = self._support.columns[np.ix_(cols, candidates)]
        if not candidates.size:
            return bound
        # supp(b_i) within supp(b) for each (belief, candidate): counted over the covered columns (exact
        # small integers in float32), in one product.
        covered = (B[:, cols] > 0).astype(np.float32) @ support
        inside = covered == lengths[candidates].astype(np.float32)                       # (m, candidates)
        if allowed is not None:
            inside &= allowed[candidates].T
        b_idx, i_idx = np.nonzero(inside)                 # pairs sorted by belief
        i_idx = candidates[i_idx]
        if b_idx.size:
            best_gain = self._sawtooth_gains(B, fit, i_idx, b_idx, stop)
            bound = np.minimum(bound, base + best_gain)
        return bound

    def _sawtooth_gains(self, B: np.ndarray, fit: np.ndarray | None, i_idx: np.ndarray, b_idx: np.ndarray,
                        stop=None) -> np.ndarray:
        """(m,): ``min_i lambda_i(b) e_i + sum_g min(alpha_g(b), lambda_i(b) beta_g(b_i)) D_g`` over the pairs
        ``(i_idx, b_idx)`` (0 for beliefs in no pair), each pair touching only the non-zeros of its point and
        the groups the point reaches (sparse rows). Cost: O(sum over pairs of nnz(b_i) + groups(b_i))."""
        m, S = B.shape
        inverse = np.divide(1.0, B, out=np.zeros_like(B), where=B > 0).reshape(-1)
        ptr, cols, vals = self._sparse.arrays()
        lens = ptr[i_idx + 1] - ptr[i_idx]
        best_gain = np.zeros(m)
        ends = np.cumsum(lens)
        first = 0
        while first < i_idx.size:
            # a block of pairs whose non-zeros add up to at most BLOCK numbers
            last = max(first + 1, int(np.searchsorted(ends, (ends[first - 1] if first else 0) + BLOCK, "right")))
            if stop is not None and stop():
                raise SolveStopped
            ii, bb, ll = i_idx[first:last], b_idx[first:last], lens[first:last]
            pair, pos = _flatten(ptr[ii], ll)
            product = vals[pos] * inverse[bb[pair] * S + cols[pos]]
            # Sawtooth: the largest lambda with b - lambda b_i >= 0 is 1 / max_s b_i(s) / b(s).
            ratio = 1.0 / np.maximum.reduceat(product, np.cumsum(ll) - ll)
            gain = self.excess[ii] * ratio
            if fit is not None:  # what the groups still cover once lambda b_i is taken out
                gptr, gidx, gval = self._sparse_reach.arrays()
                gpair, gpos = _flatten(gptr[ii], gptr[ii + 1] - gptr[ii])
                g = gidx[gpos]
                term = np.minimum(fit[bb[gpair], g], ratio[gpair] * gval[gpos]) * self._drop[g]
                gain += np.bincount(gpair, weights=term, minlength=len(ii))
            # the pairs come sorted by belief: each belief's least gain is one segment's minimum
            starts = np.flatnonzero(np.concatenate(([True], bb[1:] != bb[:-1])))
            mine = bb[starts]
            best_gain[mine] = np.minimum(best_gain[mine], np.minimum.reduceat(gain, starts))
            first = last
        return best_gain

    def value(self, b: np.ndarray) -> float:
        """The bound at one belief ``b`` (S,). Cost: O(S (A + n))."""
        return float(self.at(b[None])[0])

    def update(self, b: np.ndarray, value: float) -> None:
        """Store the point ``(b, value)``; if ``b`` is stored already, its value becomes ``value``. The
        caller checks that ``value`` is an upper bound at ``b``. Amortised cost: O(S)."""
        excess = value - float(b @ self.corner)
        key = float(b @ self.fingerprint)
        row = self._key.get(key)
        if row is not None and np.array_equal(self.points.rows[row], b):
            self._excess[row] = excess
            return
        self._key[key] = self.points.n
        if self.points.n == len(self._excess):
            self._excess = np.concatenate([self._excess, np.zeros_like(self._excess)])
        self._excess[self.points.n] = excess
        self.points.append(b)
        self._sparse.append(b)
        self._support.append(b > 0)
        if self.groups is not None:
            reach = self.groups.reach(b[None])[0]
            self._reach.append(reach)
            self._sparse_reach.append(reach)

    def lower_group(self, g: int, value: float) -> bool:
        """Lower group ``g``'s bound to ``value`` (an upper bound at its belief, e.g. a backup); whether it
        moved. Cost: O(1)."""
        if value >= self.group_value[g] - 1e-12:
            return False
        self.group_value[g] = value
        self._drop[g] = float(self.group_beliefs[g] @ self.corner) - value
        return True

    def prune(self, chunk: int = 64, stop=None) -> None:
        """Drop the points that the others (and the informed bound) already bound as tightly at their own
        belief (HSVI2's pruning), ``chunk`` points at a time. The bound anywhere stays the same (up to
        1e-12 per dropped point): if ``V^_{-i}(b_i) <= v_i``, point ``i``'s sawtooth term is implied at every
        belief by the terms that bound it. ``stop``: checked before each chunk; the points not examined yet
        are kept. Cost: O(n^2 S)."""
        keep = np.ones(self.points.n, dtype=bool)
        for first in range(0, self.points.n, chunk):
            if stop is not None and stop():
                break
            query = np.arange(first, min(first + chunk, self.points.n))
            B = self.points.rows[query]
            others = np.repeat(keep[:, None], len(query), axis=1)
            others[query, np.arange(len(query))] = False                       # not the point itself
            keep[query] &= self.at(B, others) > B @ self.corner + self.excess[query] + 1e-12
        excess = self.excess[keep]
        self.points.keep(keep)
        self._support.keep(keep)
        self._sparse = SparseRows(self.points.rows)
        if self.groups is not None:
            self._reach.keep(keep)
            self._sparse_reach = SparseRows(self._reach.rows)
        self._excess[:len(excess)] = excess
        self._key = {float(b @ self.fingerprint): i for i, b in enumerate(self.points.rows)}
