"""The size of a model file before it is written, from the tables' non-zeros and the names' lengths.

The writers (:mod:`.pomdpx`, :mod:`.cassandra`) write one line per non-zero entry whose text is the names of
its action, state and column plus the value; summing those lengths over the entries (by rows and columns,
in numpy) gives the file's size within a few per cent without formatting a line.
"""
from __future__ import annotations

import re

import numpy as np

from ..pomdp import POMDP
from .cassandra import _num

__all__ = ["model_file_bytes", "FILE_KINDS"]

FILE_KINDS = ("pomdpx", "cassandra")


def _token_lengths(names, prefix: str = "") -> np.ndarray:
    """Lengths of the identifiers the writers make of ``names`` (``prefix``: the Cassandra writer's
    ``s12_``-style prefix letter, whose number is added)."""
    tokens = (re.sub(r"[^A-Za-z0-9_]+", "_", n).strip("_") or "x" for n in names)
    if prefix:
        return np.fromiter((len(prefix) + len(str(i)) + 1 + len(t) for i, t in enumerate(tokens)), dtype=np.int64,
                           count=len(names))
    return np.fromiter((len(t) for t in tokens), dtype=np.int64, count=len(names))


def _value_chars(values: np.ndarray) -> int:
    """The characters of the shortest exact texts of ``values`` (formatting each distinct value once)."""
    if values.size == 0:
        return 0
    distinct, counts = np.unique(values, return_counts=True)
    return int(sum(len(_num(v)) * int(c) for v, c in zip(distinct, counts)))


def _entry_chars(table, row_length: np.ndarray, column_length: np.ndarray) -> tuple[int, int]:
    """(non-zero entries, characters of their row names, column names and values) of a sparse table."""
    table = table.tocsr()
    per_row = np.diff(table.indptr)
    per_column = np.bincount(table.indices, minlength=table.shape[1])
    chars = int(per_row @ row_length) + int(per_column @ column_length) + _value_chars(table.data)
    return int(table.nnz), chars


def _is_identity(table) -> bool:
    table = table.tocsr()
    n = table.shape[0]
    return (table.shape == (n, n) and table.nnz == n and np.array_equal(table.indices, np.arange(n))
            and bool(np.all(table.data == 1)))


def model_file_bytes(model: POMDP, kind: str) -> int:
    """The bytes :func:`~planner.decision.io.write_pomdpx` (``kind="pomdpx"``) or
    :func:`~planner.decision.io.write_cassandra` (``"cassandra"``) would write for ``model``, within a few
    per cent. Cost: O(non-zeros) in numpy, plus one pass over the names."""
    if kind not in FILE_KINDS:
        raise ValueError(f"unknown model file kind {kind!r}; one of {', '.join(FILE_KINDS)}")
    cassandra = kind == "cassandra"
    S = _token_lengths(model.states, "s" if cassandra else "")
    A = _token_lengths(model.actions, "a" if cassandra else "")
    Z = _token_lengths(model.observations, "o" if cassandra else "")
    first = model.observation[0]
    shared = all(o is first for o in model.observation[1:])
    observation = [(1, first)] if shared else list(zip(A.tolist(), model.observation))
    # Per entry: the fixed text around the names, e.g. "T: a : s : s' v\n" (11 characters) or
    # "<Entry><Instance>a s s'</Instance><ProbTable>v</ProbTable></Entry>\n" (62).
    fixed = 11 if cassandra else 62
    total = int(S.sum() + A.sum() + Z.sum()) + len(S) + len(A) + len(Z) + 600  # declarations and sections
    total += int(np.count_nonzero(model.initial)) * (4 if cassandra else 50) + S[model.initial > 0].sum()
    for action_length, table in [*zip(A.tolist(), model.transition), *observation]:
        if not cassandra and _is_identity(table):
            total += fixed + action_length + 10
            continue
        entries, chars = _entry_chars(table, S, S if table.shape[1] == len(S) else Z)
        total += entries * (fixed + action_length) + chars
    for a in range(model.n_actions):
        row = model.reward[a]
        nonzero = np.flatnonzero(row)
        if cassandra:  # "R: a : s : * : * v\n" per non-zero reward
            total += nonzero.size * (19 + int(A[a])) + int(S[nonzero].sum()) + _value_chars(row[nonzero])
        elif nonzero.size:  # one value table per action: every state's reward, separated by spaces
            total += 67 + int(A[a]) + _value_chars(row) + row.size - 1
    return int(total)
