"""What the point-based solvers share: a model's tables in the shapes they need, growing row arrays, and
the two initial bounds (blind policies below, the fast informed bound above)."""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from ..pomdp import POMDP

__all__ = ["pomdp_bytes", "solver_bytes",
           "BLOCK", "SolveStopped", "best_products", "Rows", "Tables", "blind_lower_bound", "mdp_upper_bound", "moving_rows", "fast_informed_bound"]

SUCCESSOR_BLOCK = 10_000_000  # numbers of the (actions, observations, states) product built at once, at most
DENSE_LIMIT = 20_000_000  # A * S * S entries up to which transitions may be kept dense
# Numbers per temporary array in the solver's batched products (16 MB): larger batches are cut into blocks, so
# peak memory stays bounded and the allocator reuses the blocks instead of faulting in fresh pages each time.
BLOCK = 2_000_000
# Multiply-adds per product that a time limit cannot stop (about 0.1 s): products of many beliefs with many
# vectors over many states (a 9-part chain's 207 successors of b0 x 121 vectors x 40,320 states: 7 s) are
# cut into blocks of rows of about this much work, and the limit is checked between them.
WORK = 200_000_000


def pomdp_bytes(model: POMDP) -> int:
    """The bytes ``model``'s tables hold: its sparse transition and observation tables (a float64 and an
    index per entry, an index per row; a table shared by several actions once) and its dense rewards."""
    tables = {id(t): t for t in (*model.transition, *model.observation)}.values()
    return sum(t.data.nbytes + t.indices.nbytes + t.indptr.nbytes for t in tables) + model.reward.nbytes


def solver_bytes(model: POMDP) -> int:
    """The bytes the point-based solver takes for ``model``, on top of the model, from its sizes alone (before
    :class:`Tables` is built): dense transitions (A x S x S, twice) where :class:`Tables` keeps them, else the
    transposed tables, their stack and their block diagonal (12 bytes an entry and 4 a row each, with the
    block diagonal's triplets while built), the one observation table it makes dense (Z x S) and its bounds:
    about seven (A, S) float64 tables at once (the informed bound's iterates, its sums and the starting
    bounds). The alpha vectors and beliefs it adds grow with its iterations and are not counted. Measured
    within 40 % above on the pen and chain 6, 7 (tests/decision/test_memory_estimates.py)."""
    S, A, Z = model.n_states, model.n_actions, model.n_observations
    nonzero = sum(int(t.nnz) for t in model.transition)
    entries = A * S * S
    dense = entries <= DENSE_LIMIT and (entries <= 250_000 or nonzero >= 0.05 * entries)
    transitions = 16 * entries if dense else 3 * (12 * nonzero + 4 * A * (S + 1)) + 24 * nonzero
    distinct = len({id(o) for o in model.observation})
    return transitions + 8 * Z * S * distinct + 7 * 8 * A * S


class SolveStopped(Exception):
    """Raised inside a long step when its ``stop()`` turns true (the solver's time limit): the caller drops the
    unfinished step, which leaves every bound as valid as before it."""


def _check(stop: Callable[[], bool] | None) -> None:
    if stop is not None and stop():
        raise SolveStopped


def best_products(B: np.ndarray, V: np.ndarray, stop: Callable[[], bool] | None = None,
                  columns: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """For each row b of ``B`` (m, S): ``max_k V[k] . b`` and its ``k``, over ``V`` (n, S), computed
    ``BLOCK`` products and about ``WORK`` multiply-adds at a time (``stop``: checked before each block,
    :class:`SolveStopped`); ``columns``: ``V.T`` stored by column (:attr:`Rows.columns`), which lets
    beliefs with small supports read only their columns of ``V``. Cost: O(m n S') time for the S' columns
    some belief covers, O(BLOCK) extra memory."""
    values, best = np.empty(len(B)), np.empty(len(B), dtype=np.int64)
    cols = np.flatnonzero((B != 0).any(axis=0))
    VT = V.T
    if 4 * len(cols) < 3 * B.shape[1] and (len(B) >= 8 or columns is not None):  # small supports: their columns
        B, VT = B[:, cols], (V[:, cols].T if columns is None else columns[cols])
    step = max(1, min(BLOCK // max(1, len(V)), WORK // max(1, len(V) * B.shape[1])))
    for first in range(0, len(B), step):
        _check(stop)
        products = B[first:first + step] @ VT
        best[first:first + step] = products.argmax(axis=1)
        values[first:first + step] = products[np.arange(len(products)), best[first:first + step]]
    return values, best


class Rows:
    """A growing (n, width) array (amortised appends); with ``columns``, also kept column by column
    (:attr:`columns`), so that a product over a few columns reads only those; ``by_row=False`` keeps only
    that copy (:attr:`rows` is then None)."""

    def __init__(self, width: int, columns: bool = False, dtype=float, by_row: bool = True):
        self.width, self._capacity, self.n = width, 64, 0
        self._data = np.zeros((64, width), dtype=dtype) if by_row else None
        self._columns = np.zeros((width, 64), dtype=dtype) if columns else None

    def extend(self, rows: np.ndarray) -> None:
        """Append the rows of ``rows`` (k, width)."""
        need = self.n + len(rows)
        if need > self._capacity:
            self._capacity = max(need, 2 * self._capacity)
            if self._data is not None:
                grown = np.zeros((self._capacity, self.width), dtype=self._data.dtype)
                grown[:self.n] = self._data[:self.n]
                self._data = grown
            if self._columns is not None:
                grown = np.zeros((self.width, self._capacity), dtype=self._columns.dtype)
                grown[:, :self.n] = self._columns[:, :self.n]
                self._columns = grown
        if self._data is not None:
            self._data[self.n:need] = rows
        if self._columns is not None:
            self._columns[:, self.n:need] = np.asarray(rows).T
        self.n = need

    def append(self, row: np.ndarray) -> None:
        self.extend(row[None])

    def keep(self, mask: np.ndarray) -> None:
        kept = int(mask.sum())
        if self._data is not None:
            self._data[:kept] = self._data[:self.n][mask]
        if self._columns is not None:
            self._columns[:, :kept] = self._columns[:, :self.n][:, mask]
        self.n = kept

    @property
    def rows(self) -> np.ndarray | None:
        return None if self._data is None else self._data[:self.n]

    @property
    def columns(self) -> np.ndarray | None:
        """(width, n): the rows' transpose, contiguous by column (None unless asked for)."""
        return None if self._columns is None else self._columns[:, :self.n]


class Tables:
    """A model's tables, in the shapes a solver needs: ``T`` (A sparse (S, S), rows "from"), dense ``TD``
    (A, S, S) when small enough, ``OZ`` (A, Z, S) = O(z | s', a), ``observation_table`` (A,): the first
    action with the same observation table object, ``R`` (A, S), ``gamma``."""

    def __init__(self, model: POMDP):
        self.S, self.A, self.Z = model.n_states, model.n_actions, model.n_observations
        self.T = [t.tocsr() for t in model.transition]
        entries = self.A * self.S * self.S
        nonzero = sum(t.nnz for t in self.T)
        # Dense products win for small or dense tables; sparse ones (the intentions' few successors) beyond.
        self.dense = entries <= DENSE_LIMIT and (entries <= 250_000 or nonzero >= 0.05 * entries)
        if self.dense:
            self.TD = np.stack([t.toarray() for t in model.transition])
            self._by_origin = np.ascontiguousarray(self.TD.transpose(1, 0, 2)).reshape(self.S, self.A * self.S)
        else:
            self.T_to = [t.T.tocsr() for t in self.T]                         # rows "to", for step
            self.stacked_t = sp.vstack(self.T_to).tocsr()                      # (A*S, S): rows "to"
            self.block = sp.block_diag(self.T, format="csr")                   # (A*S, A*S)
        # Actions whose observation tables are the same object share one index (the intention POMDP's do).
        first: dict[int, int] = {}
        self.observation_table = np.array([first.setdefault(id(o), a) for a, o in enumerate(model.observation)])
        dense = {a: model.observation[a].toarray().T for a in first.values()}  # each distinct table once
        if len(dense) == 1:  # one table for every action: a read-only view, not A copies (A x Z x S numbers)
            self.OZ = np.broadcast_to(next(iter(dense.values())), (self.A, self.Z, self.S))
        else:
            self.OZ = np.stack([dense[int(t)] for t in self.observation_table])
        self.R = np.asarray(model.reward, dtype=float)
        self.gamma = model.discount

    def predict(self, b: np.ndarray) -> np.ndarray:
        """(A, S): the next-state distribution after each action."""
        if self.dense:
            return (b @ self._by_origin).reshape(self.A, self.S)
        return (self.stacked_t @ b).reshape(self.A, self.S)

    def step(self, B: np.ndarray, a: int) -> np.ndarray:
        """(n, S): the next-state distributions of the beliefs ``B`` (n, S) after action ``a``."""
        return B @ self.TD[a] if self.dense else np.asarray((self.T_to[a] @ B.T).T)

    def expect(self, W: np.ndarray) -> np.ndarray:
        """(A, S): for each action a, sum_s' T(s'|s,a) W[a, s']."""
        if self.dense:
            return np.matmul(self.TD, W[:, :, None])[:, :, 0]
        return (self.block @ W.reshape(-1)).reshape(self.A, self.S)

    def expect_one(self, a: int, W: np.ndarray) -> np.ndarray:
        """(n, S): for each row w of ``W`` (n, S), sum_s' T(s'|s,a) w[s']."""
        return W @ self.TD[a].T if self.dense else np.asarray((self.T[a] @ W.T).T)

    def successors(self, b: np.ndarray, actions: np.ndarray | None = None, stop: Callable[[], bool] | None = None):
        """Non-zero (action, observation) pairs after ``b`` under ``actions`` (sorted; default: all): their
        action and observation indices, probabilities and beliefs (``stop``: checked per action on large
        models, :class:`SolveStopped`)."""
        if actions is None or len(actions) == self.A:
            predicted, actions = self.predict(b), np.arange(self.A)              # (A, S)
        elif not self.dense and self.stacked_t.nnz <= 100_000:  # one small product beats one per action (same sums)
            predicted = self.predict(b)[actions]
        else:
            predicted = np.stack([self.step(b[None], int(a))[0] for a in actions])
        if len(actions) * self.Z * self.S > SUCCESSOR_BLOCK:  # large: never the whole (A', Z, S) product
            rows = []
            for i, a in enumerate(actions):
                _check(stop)
                rows.append(self.OZ[a] @ predicted[i])
            pz = np.stack(rows)  # (A', Z)
            a_idx, z_idx = np.nonzero(pz > 1e-15)
            probs = pz[a_idx, z_idx]
            beliefs = self.OZ[actions[a_idx], z_idx] * predicted[a_idx] / probs[:, None]
            return actions[a_idx], z_idx, probs, beliefs
        joint = self.OZ[actions] * predicted[:, None, :]                 # (A', Z, S)
        pz = joint.sum(axis=2)
        a_idx, z_idx = np.nonzero(pz > 1e-15)
        probs = pz[a_idx, z_idx]
        return actions[a_idx], z_idx, probs, joint[a_idx, z_idx] / probs[:, None]


def blind_lower_bound(m: Tables, deadline: float | None = None,
                      clock: Callable[[], float] = time.perf_counter) -> np.ndarray:
    """(A, S): for each action, the value of repeating it forever: (I - gamma T_a) alpha = R_a, the actions with
    the best mean reward first. Once ``clock()`` passes ``deadline``, the remaining actions get the value every
    policy reaches, ``min R / (1 - gamma)`` (a lower bound too). Cost: one sparse solve of size S per action (seconds each past 100,000 states)."""
    import scipy.sparse.linalg as spla  # here: 70 ms of every command's start otherwise

    identity = sp.identity(m.S, format="csc")
    floor = float(m.R.min()) / (1 - m.gamma)
    rows = np.full((m.A, m.S), floor)
    # The actions with the best mean reward first (waiting, on the intention models): when the deadline cuts
    # the list short, the vectors most likely to matter are done.
    for a in np.argsort(-m.R.mean(axis=1), kind="stable"):
        if deadline is not None and clock() >= deadline:
            break
        rows[a] = spla.spsolve((identity - m.gamma * m.T[a]).tocsc(), m.R[a])
    return rows


def mdp_upper_bound(m: Tables, tolerance: float = 1e-6, max_sweeps: int = 100_000, deadline: float | None = None,
                    clock: Callable[[], float] = time.perf_counter) -> np.ndarray:
    """Q (A, S) of the fully observable MDP, Q(s,a) = R(s,a) + gamma sum_s' T(s'|s,a) max_a' Q(s',a'): an
    upper bound on the POMDP's Q. Value iteration from R_max / (1 - gamma), which only decreases, so it can
    stop at any sweep: at ``tolerance``, after ``max_sweeps`` sweeps, or once ``clock()`` passes ``deadline``
    (with a discount near 1 it converges slowly: 1 - gamma = 1e-5 needs over 100,000 sweeps).
    Cost per sweep: O(nnz(T)) (one product with all the tables at once)."""
    V = np.full(m.S, np.abs(m.R).max() / (1 - m.gamma))
    for _ in range(max_sweeps):
        Q = m.R + m.gamma * m.expect(np.broadcast_to(V, (m.A, m.S)))
        new = Q.max(axis=0)
        if np.abs(new - V).max() < tolerance or (deadline is not None and clock() >= deadline):
            break
        V = new
    return Q


def moving_rows(table: sp.csr_matrix) -> np.ndarray:
    """The rows of a transition table that are not "stay where you are" (a single 1 on the diagonal)."""
    table = table.tocsr()
    count = np.diff(table.indptr)
    single = count == 1
    at = table.indptr[:-1][single]
    stays = np.zeros(table.shape[0], dtype=bool)
    stays[np.flatnonzero(single)] = (table.indices[at] == np.flatnonzero(single)) & (table.data[at] == 1.0)
    return np.flatnonzero(~stays)


def fast_informed_bound(m: Tables, tolerance: float = 1e-3, max_sweeps: int = 100_000,
                        deadline: float | None = None, chunk: int = 4_000_000,
                        start: np.ndarray | None = None, clock: Callable[[], float] = time.perf_counter) -> np.ndarray:
    """Q (A, S): Q(s,a) = R(s,a) + gamma sum_z max_a' sum_s' T(s'|s,a) O(z|s',a) Q(s',a') (Hauskrecht 2000).

    Iterated from the MDP bound (:func:`mdp_upper_bound`), or from its minimum with ``start`` (any upper bound
    on Q*), which the operator can only lower: it is monotone and maps an upper bound on Q* to one (it relaxes
    the Bellman operator), so every iterate is an upper bound too, and the iteration can stop early:
    when a sweep changes no entry by more than ``tolerance``, after ``max_sweeps`` sweeps, or at ``deadline``
    (a ``clock()`` value; checked after each block of observations too, and then the unfinished sweep is
    dropped: the iterate before it is the bound; the MDP bound it starts from stops there as well). Where
    action ``a`` leaves state ``s`` as it is, the sum is ``sum_z O(z|s,a) max_a' Q(s,a')``, with no product; the (S', z x A') blocks of ``O_z Q`` (at most ``chunk``
    numbers) are built once per observation table, not per action (the intention models' robot actions
    move only the intentions whose next step they perform, and every action shares one table).
    Cost per sweep: O(Z A (S + sum_a nnz(T_a rows that move))).
    """
    Q = mdp_upper_bound(m, deadline=deadline, clock=clock)
    if start is not None:  # another upper bound (A, S): the operator keeps any upper bound one
        Q = np.minimum(Q, start)
    step = max(1, chunk // max(1, m.S * m.A))  # observations per block
    moving = [moving_rows(t) for t in m.T]
    moved = [m.T[a][moving[a]] for a in range(m.A)]
    tables = {int(t): np.flatnonzero(m.observation_table == t) for t in np.unique(m.observation_table)}
    emitted = {t: m.OZ[t].sum(axis=0) for t in tables}                        # sum_z O(z | s), about 1
    for _ in range(max_sweeps):
        corner = Q.max(axis=0)
        total = np.empty_like(Q)
        for t, actions in tables.items():
            total[actions] = emitted[t] * corner
            sums = {int(a): np.zeros(len(moving[a])) for a in actions if moving[a].size}
            for first in range(0, m.Z, step):
                emit = m.OZ[t][first:first + step]                                  # (z, S')
                block = (emit.T[:, :, None] * Q.T[:, None, :]).reshape(m.S, -1)     # (S', z * A')
                for a, acc in sums.items():
                    reached = moved[a] @ block                                      # (moving, z * A')
                    acc += reached.reshape(len(acc), len(emit), m.A).max(axis=2).sum(axis=1)
                    if deadline is not None and clock() >= deadline:
                        return Q  # the sweep is unfinished: the last full iterate is the bound
            for a, acc in sums.items():
                total[a, moving[a]] = acc
        new = m.R + m.gamma * total
        if start is not None:  # the minimum of two upper bounds is one; the operator may not be below start
            new = np.minimum(new, start)
        done = np.abs(new - Q).max() < tolerance
        Q = new
        if done or (deadline is not None and clock() >= deadline):
            break
    return Q
