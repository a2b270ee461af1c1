"""Tables read from model files, kept sparse: entries in file order, the later one winning where they overlap.

Both file formats describe a table (``T(s' | s, a)``, ``O(z | s', a)``, a reward) as a list of entries; an entry
fixes some axes to one value, spreads one number over others (``*``: every value, the same number), lists
numbers along others (POMDPX's ``-``, a Cassandra row or matrix) or sets an identity. Where two entries cover
the same cell, the later one wins, zeros included (the authors' files list every zero). A
:class:`SparseTable` keeps the entries themselves, one number per fixed entry and one array per listed one,
and resolves them into the non-zero cells only: it never allocates the table's dense shape (a block of ``*``
over S x S cells is dense by nature and costs S x S).

Definition of the resolved table: cell ``c`` holds the value of the last entry covering ``c``, zero when none
does. Cost: O(N log N) time and O(N) memory for N entries plus the non-zero cells the entries spread
(``*``, ``-``, ``identity``), with one pass per distinct set of fixed axes.
"""
from __future__ import annotations

from array import array

import numpy as np
import scipy.sparse as sp

from ...defaults import SPREAD_CELL_LIMIT
from ...validation import CELLS_OPTION, InputLimitError

__all__ = ["SparseTable", "split_rows"]


_CHUNK = 1 << 21  # cells looked up at a time when resolving overlapping entries


def _run_ends(keys: np.ndarray) -> np.ndarray:
    """Where each run of equal values ends in the sorted ``keys`` (a boolean mask)."""
    return np.append(keys[1:] != keys[:-1], True) if keys.size else np.zeros(0, dtype=bool)


class _Group:
    """The entries that fix the same axes: their keys (the fixed cells' linear index within those axes),
    their order numbers and their constant values or the index of their block (``-1``: a constant)."""

    __slots__ = ("keys", "orders", "values", "blocks")

    def __init__(self) -> None:
        self.keys, self.orders, self.values, self.blocks = array("q"), array("q"), array("d"), array("q")


class SparseTable:
    """A table of ``shape`` built from entries in file order (module docstring); :meth:`cells` resolves it.

    An entry's ``index`` has one item per axis: an ``int`` fixes the axis, ``None`` covers every value.
    ``cell_limit``: the most cells the entries may spread over (``*``, rows, identities), counted as each entry
    comes, before anything is allocated; past it :class:`~planner.validation.InputLimitError` (None: no limit,
    for a table that is only looked up, never resolved: a ``.pomdp`` file's reward). A spread over the first
    axis (``O: * : s : z``, the action) is counted once as each entry comes, since a table whose entries all
    leave that axis free is resolved once and shared (:func:`split_rows`); a table that needs it resolved for
    every value is checked again, counting it, before it is (:meth:`check_spread`).
    """

    def __init__(self, shape: tuple[int, ...], cell_limit: int | None = SPREAD_CELL_LIMIT):
        self.cell_limit = cell_limit
        self.spread_cells = 0  # cells spread, a spread over the first axis counted once
        self.spread_first = 0  # cells spread, a spread over the first axis counted for every value
        self.shape = tuple(int(n) for n in shape)
        self.size = int(np.prod(self.shape, dtype=np.int64))
        self.order = 0
        self.groups: dict[tuple[bool, ...], _Group] = {}
        self.listed: list[tuple[tuple, str, tuple[int, ...], np.ndarray | None, int]] = []
        self._full = tuple(True for _ in self.shape)
        self._full_group = self._group(self._full)
        self._resolved: tuple[int, dict] = (-1, {})  # (entries when sorted, per group: its last entry per key)

    def _group(self, mask: tuple[bool, ...]) -> _Group:
        group = self.groups.get(mask)
        if group is None:
            group = self.groups[mask] = _Group()
        return group

    def _key(self, index) -> tuple[tuple[bool, ...], int]:
        mask = tuple(i is not None for i in index)
        key = 0
        for i, n in zip(index, self.shape):
            if i is not None:
                key = key * n + i
        return mask, key

    def set(self, index, value: float) -> None:
        """Set every cell that ``index`` covers to ``value``."""
        if None not in index:  # the bulk of a file: one cell, no mask to compute
            key = 0
            for i, n in zip(index, self.shape):
                key = key * n + i
            group = self._full_group
            group.values.append(value)
            group.blocks.append(-1)
        else:
            if value != 0:
                self._count(int(np.prod([n for k, (i, n) in enumerate(zip(index, self.shape)) if i is None and k],
                                        dtype=np.int64)), index)
            mask, key = self._key(index)
            group = self._group(mask)
            group.values.append(value)
            group.blocks.append(-1)
        group.keys.append(key)
        group.orders.append(self.order)
        self.order += 1

    def set_listed(self, index, axes: tuple[int, ...], values: np.ndarray) -> None:
        """Set the cells ``index`` covers to ``values``, an array over ``axes`` (increasing; ``None`` in
        ``index``), spread over the other ``None`` axes."""
        self._block(index, "listed", axes, np.asarray(values, dtype=float))

    def set_identity(self, index, axes: tuple[int, int]) -> None:
        """Set the cells ``index`` covers to 1 where the coordinates on ``axes`` are equal, else 0."""
        self._block(index, "identity", axes, None)

    def _count(self, cells: int, index) -> None:
        """Add ``cells`` (a spread over the first axis left out) to the cells the entries spread over; refuse
        past ``cell_limit``."""
        self.spread_cells += cells
        self.spread_first += cells * (self.shape[0] if index[0] is None else 1)
        self._refuse_past(self.spread_cells, "so far ")

    def _refuse_past(self, cells: int, when: str) -> None:
        if self.cell_limit is not None and cells > self.cell_limit:
            raise InputLimitError(f"the entries {when}spread over {cells:,} cells of a table of shape "
                                  f"{' x '.join(map(str, self.shape))}, more than the limit of {self.cell_limit:,} "
                                  f"(about 150 bytes each while the table is built; {CELLS_OPTION} raises it); list "
                                  "the non-zero entries instead of '*', uniform or whole rows")

    def same_along_first(self) -> bool:
        """Whether every entry leaves the first axis free (``O: * : ...``): then every slice along it is the
        same, resolved once (:func:`split_rows`)."""
        return self.leaves_free((0,))

    def leaves_free(self, axes: tuple[int, ...]) -> bool:
        """Whether every entry covers every value of each of ``axes`` with one number (``*``): the table is
        then the same along them."""
        return all(not any(mask[k] for k in axes) for mask, group in self.groups.items() if len(group.keys)) and \
            all(all(index[k] is None and k not in listed for k in axes) for index, _, listed, *_ in self.listed)

    def check_spread(self) -> None:
        """Before resolving every slice along the first axis (entries fix it somewhere): refuse past
        ``cell_limit`` counting a spread over that axis for each of its values."""
        self._refuse_past(self.spread_first, "")

    def _block(self, index, kind, axes, values) -> None:
        rest = int(np.prod([n for k, (i, n) in enumerate(zip(index, self.shape)) if i is None and k not in axes
                            and k], dtype=np.int64))
        listed = min(self.shape[axes[0]], self.shape[axes[1]]) if kind == "identity" else np.count_nonzero(values)
        self._count(int(listed) * rest, index if 0 not in axes else (0,) + tuple(index[1:]))
        mask, key = self._key(index)
        group = self._group(mask)
        group.keys.append(key)
        group.orders.append(self.order)
        group.values.append(0.0)
        group.blocks.append(len(self.listed))
        self.listed.append((tuple(index), kind, tuple(axes), values, self.order))
        self.order += 1

    # -- resolution -------------------------------------------------------------------------------------------

    def _offsets(self, axes) -> np.ndarray:
        """Linear offsets of every cell of the sub-grid over ``axes`` (the other coordinates zero)."""
        strides = np.cumprod((self.shape[1:] + (1,))[::-1], dtype=np.int64)[::-1]
        out = np.zeros(1, dtype=np.int64)
        for axis in axes:
            out = (out[:, None] + np.arange(self.shape[axis], dtype=np.int64)[None, :] * strides[axis]).ravel()
        return out

    def _base(self, mask, keys: np.ndarray) -> np.ndarray:
        """The linear index of each entry's fixed cell (zeros on its free axes)."""
        strides = np.cumprod((self.shape[1:] + (1,))[::-1], dtype=np.int64)[::-1]
        base = np.zeros(keys.size, dtype=np.int64)
        rest = keys.copy()
        for axis in reversed(range(len(self.shape))):
            if mask[axis]:
                base += (rest % self.shape[axis]) * strides[axis]
                rest //= self.shape[axis]
        return base

    def _spread(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every non-zero cell some entry writes: (linear index, value, order)."""
        lin, val, order = [], [], []
        for mask, group in self.groups.items():
            values = np.frombuffer(group.values, dtype=float)
            constant = (np.frombuffer(group.blocks, dtype=np.int64) < 0) & (values != 0)
            if not constant.any():
                continue
            keys = np.frombuffer(group.keys, dtype=np.int64)[constant]
            base = keys if mask == self._full else self._base(mask, keys)
            offsets = self._offsets([k for k, fixed in enumerate(mask) if not fixed])
            lin.append((base[:, None] + offsets[None, :]).ravel())
            val.append(np.repeat(values[constant], offsets.size))
            order.append(np.repeat(np.frombuffer(group.orders, dtype=np.int64)[constant], offsets.size))
        strides = np.cumprod((self.shape[1:] + (1,))[::-1], dtype=np.int64)[::-1]
        for index, kind, axes, values, number in self.listed:
            mask, key = self._key(index)
            base = self._base(mask, np.array([key], dtype=np.int64))[0]
            spread = self._offsets([k for k, i in enumerate(index) if i is None and k not in axes])
            if kind == "identity":
                diagonal = np.arange(min(self.shape[axes[0]], self.shape[axes[1]]), dtype=np.int64)
                cells = diagonal * (strides[axes[0]] + strides[axes[1]])
                cell_values = np.ones(diagonal.size)
            else:
                nonzero = np.nonzero(values)
                cells = np.zeros(nonzero[0].size, dtype=np.int64)
                for coordinate, axis in zip(nonzero, axes):
                    cells += coordinate.astype(np.int64) * strides[axis]
                cell_values = values[nonzero]
            lin.append((base + cells[:, None] + spread[None, :]).ravel())
            val.append(np.repeat(cell_values, spread.size))
            order.append(np.full(lin[-1].size, number, dtype=np.int64))
        if not lin:
            empty = np.zeros(0, dtype=np.int64)
            return empty, np.zeros(0), empty
        return np.concatenate(lin), np.concatenate(val), np.concatenate(order)

    def _last_per_key(self) -> dict:
        """Per group: its distinct keys, increasing, the index of the last entry of each and every entry's
        order (computed once per set of entries: the reward is looked up once per action)."""
        if self._resolved[0] != self.order:
            out = {}
            for mask, group in self.groups.items():
                keys = np.frombuffer(group.keys, dtype=np.int64)
                if keys.size:
                    orders = np.frombuffer(group.orders, dtype=np.int64)
                    sort = np.lexsort((orders, keys))  # by key, then by order: the last of each run wins
                    last = sort[_run_ends(keys[sort])]
                    out[mask] = (keys[last], last, orders)
            self._resolved = (self.order, out)
        return self._resolved[1]

    def _last(self, lin: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For each cell in ``lin``: the order of the last entry covering it (-1: none), its group's constant
        value and its block number (-1: a constant)."""
        order = np.full(lin.size, -1, dtype=np.int64)
        value = np.zeros(lin.size)
        block = np.full(lin.size, -1, dtype=np.int64)
        coords = None
        for mask, (ukeys, last, orders) in self._last_per_key().items():
            group = self.groups[mask]
            if mask == self._full:
                query = lin
            else:
                if coords is None:
                    coords = np.unravel_index(lin, self.shape)
                query = np.zeros(lin.size, dtype=np.int64)
                for axis, fixed in enumerate(mask):
                    if fixed:
                        query = query * self.shape[axis] + coords[axis]
            pos = np.minimum(np.searchsorted(ukeys, query), ukeys.size - 1)
            hit = ukeys[pos] == query
            later = hit & (orders[last[pos]] > order)
            chosen = last[pos[later]]
            order[later] = orders[chosen]
            value[later] = np.frombuffer(group.values, dtype=float)[chosen]
            block[later] = np.frombuffer(group.blocks, dtype=np.int64)[chosen]
        return order, value, block

    def cells(self) -> tuple[np.ndarray, np.ndarray]:
        """The resolved table's non-zero cells: (linear indices, increasing; values)."""
        if not self.listed and all(not g.keys for m, g in self.groups.items() if m != self._full):
            # every entry one cell: the last entry per cell wins, zeros included (a stable sort keeps file order)
            keys = np.frombuffer(self._full_group.keys, dtype=np.int64)
            values = np.frombuffer(self._full_group.values, dtype=float)
            sort = np.argsort(keys, kind="stable")
            last = sort[_run_ends(keys[sort])]
            last = last[values[last] != 0]
            return keys[last].copy(), values[last].copy()
        lin, val, order = self._spread()
        # in chunks: the lookups' temporaries (coordinates, keys, positions) stay a few times _CHUNK
        keep = np.flatnonzero(np.concatenate(
            [self._last(lin[i:i + _CHUNK])[0] == order[i:i + _CHUNK] for i in range(0, lin.size, _CHUNK)]
            or [np.zeros(0, dtype=bool)]))
        keep = keep[np.argsort(lin[keep], kind="stable")]
        return lin[keep], val[keep]

    def values_at(self, lin: np.ndarray) -> np.ndarray:
        """The resolved table's values at the cells ``lin`` (linear indices), without resolving the rest."""
        _, out, block = self._last(lin)
        for number in np.unique(block[block >= 0]):
            index, kind, axes, values, _ = self.listed[int(number)]
            where = np.flatnonzero(block == number)
            coords = np.unravel_index(lin[where], self.shape)
            if kind == "identity":
                out[where] = (coords[axes[0]] == coords[axes[1]]).astype(float)
            else:
                out[where] = values[tuple(coords[a] for a in axes)]
        return out

    def dense(self) -> np.ndarray:
        """The resolved table as a dense array (for the small ones: an initial belief, a reward table)."""
        out = np.zeros(self.size)
        lin, val = self.cells()
        out[lin] = val
        return out.reshape(self.shape)


def split_rows(table: SparseTable):
    """The CSR matrices ``M[k]`` (shape ``shape[1:]``) of a resolved 3-axis table, ``M[k][i, j] = table[k, i, j]``,
    built from its non-zero cells (never dense). When every entry leaves the first axis free (an observation
    table given for ``*`` actions) the slice is resolved once and the same matrix serves every ``k`` (as the
    writers mean it, and as the solvers share it); otherwise :meth:`SparseTable.check_spread` first.
    Cost: O(nnz + shape[0] x shape[1])."""
    K, R, C = table.shape
    if K > 1 and table.same_along_first():
        one = SparseTable((1, R, C), None)
        one.groups, one.listed, one.order = table.groups, table.listed, table.order
        one._full_group = one.groups.get(one._full, one._full_group)
        return split_rows(one) * K
    table.check_spread()
    lin, val = table.cells()
    bounds = np.searchsorted(lin, np.arange(K + 1, dtype=np.int64) * (R * C))
    out = []
    for k in range(K):
        part = lin[bounds[k]:bounds[k + 1]] - k * R * C
        out.append(sp.csr_matrix((val[bounds[k]:bounds[k + 1]], (part // C, part % C)), shape=(R, C)))
    return tuple(out)
