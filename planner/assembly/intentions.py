"""Operator intentions: counts by dynamic programming and the intention graph (Alg. 2).

Definitions
-----------
An *operator intention* is a path in the assembly state graph from some state (the current one) to the
final state: the assembly states the operator has in mind from now on. The path of length 0 (the finished
product) is an intention too. A *full assembly sequence* is an intention that starts at the initial state.

Alg. 2 builds the *intention graph* backwards from the final state: each intention ``I`` starting at
state ``Y`` and each state edge ``(X, Y)`` give the intention ``I' = (X, I)`` and the edge ``(I', I)``,
mapped to the operation of ``(X, Y)`` (``m_I``). Every intention but the final one has exactly one
successor, so the intention graph is a tree rooted at the final intention.

Counting
--------
With ``P(final) = 1`` and ``P(s) = sum over edges (s, t) of P(t)``, ``P(s)`` is the number of paths from
``s`` to the final state; there are ``sum_s P(s)`` intentions and ``P(initial)`` full sequences. The sums run
level by level in floating point while they stay below 2**52, where they are exact, and in Python
integers above, so the counts are exact for any size.

Base part (paper Sec. V)
------------------------
With a *base part* ``b``, assembly starts from ``b``: the allowed full sequences are those whose first state
edge (from the initial state) is an operation whose result contains ``b`` (:func:`base_part_first_edges`).
After that first step every continuation is allowed, so the restricted intentions are the allowed full
sequences plus every intention that starts at a state reachable from the target of an allowed first edge
(:func:`base_part_states`); they are closed under "next step", so they form a subtree of the intention
graph. Their number is ``sum over allowed first edges (i, t) of P(t)`` plus ``sum over reachable states s of
P(s)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..defaults import INTENTION_LIMIT
from ..errors import LimitExceededError, MemoryLimitError, PlannerError
from ..product import Product
from .guards import OPTIONS, default_memory_budget, memory_options
from .states import AssemblyStateGraph

__all__ = [
    "IntentionGraph",
    "paths_to_final",
    "count_intentions",
    "count_sequences",
    "base_part_first_edges",
    "base_part_states",
    "allowed_edges",
    "most_connected_part",
    "intention_graph",
    "DEFAULT_INTENTION_LIMIT",
]

DEFAULT_INTENTION_LIMIT = INTENTION_LIMIT
_EXACT_FLOAT = 2.0 ** 52


def _sum_by(index: np.ndarray, values: np.ndarray, size: int) -> np.ndarray:
    """``out[k] = sum of values[index == k]``, exact: int64 when small enough, Python ints otherwise."""
    if values.dtype != object:
        out = np.bincount(index, weights=values, minlength=size)
        if out.sum() < _EXACT_FLOAT:
            return out.astype(np.int64)
        values = values.astype(object)
    out = np.zeros(size, dtype=object)
    if index.size:
        order = np.argsort(index, kind="stable")
        index, values = index[order], values[order]
        starts = np.flatnonzero(np.r_[True, index[1:] != index[:-1]])
        out[index[starts]] = np.add.reduceat(values, starts)
    return out


def paths_to_final(states: AssemblyStateGraph) -> list[np.ndarray]:
    """Per level (``k`` blocks at position ``k - 1``), the number of paths from each state to the final state.

    Each array is int64, or of Python ints where the counts exceed 2**52. Cost: O(E).
    """
    counts = [np.ones(1, dtype=np.int64)]
    start = states.level_start
    target = states.edge_target
    for k in range(1, len(start) - 1):
        lo, hi = np.searchsorted(target, [start[k - 1], start[k]])
        size = int(start[k + 1] - start[k])
        if size == 0:
            break
        counts.append(_sum_by(states.edge_source[lo:hi] - start[k], counts[-1][target[lo:hi] - start[k - 1]], size))
    return counts


def base_part_first_edges(states: AssemblyStateGraph, base_part: str) -> np.ndarray:
    """The state edges from the initial state whose operation's result (its parent subassembly) contains
    ``base_part``: the first steps of the sequences that start from the base part. Sorted edge indices.

    Raises :class:`~planner.errors.PlannerError`, listing the parts, when ``base_part`` is not a part.
    Cost: O(E).
    """
    andor = states.andor
    if base_part not in andor.parts:
        raise PlannerError(f"base part {base_part!r} is not a part of the product; parts: {', '.join(andor.parts)}")
    bit = 1 << andor.parts.index(base_part)
    first = np.flatnonzero(states.edge_source == states.initial)
    joins = [bool(andor.subassemblies[andor.operations[int(op)].parent] & bit)
             for op in states.edge_operation[first]]
    return first[np.array(joins, dtype=bool)] if first.size else first


def base_part_states(states: AssemblyStateGraph, base_part: str) -> np.ndarray:
    """Boolean mask over states: those reachable (themselves included) from the target of an allowed first
    edge (:func:`base_part_first_edges`); the initial state is not among them. Every continuation from these
    states is allowed. A product of one part: the single state. Cost: O(E log E) (one sort of the edges by
    source, then one pass per level, most assembled last)."""
    first = base_part_first_edges(states, base_part)
    reached = np.zeros(states.n_states, dtype=bool)
    if states.initial == states.final:
        reached[states.final] = True
        return reached
    reached[states.edge_target[first]] = True
    order = np.argsort(states.edge_source, kind="stable")
    source, target = states.edge_source[order], states.edge_target[order]
    start = states.level_start
    # States are numbered by their number of blocks, and an edge removes one block: levels from the most
    # blocks down, each reached state passes reachability to its targets.
    for k in range(len(start) - 3, 0, -1):  # sources with k + 1 blocks, from n - 1 down to 2
        lo, hi = np.searchsorted(source, [start[k], start[k + 1]])
        live = reached[source[lo:hi]]
        reached[target[lo:hi][live]] = True
    reached[states.initial] = False
    return reached


def allowed_edges(states: AssemblyStateGraph, base_part: str | None) -> np.ndarray:
    """Boolean mask over state edges that restricted intentions may take: the allowed first edges and every
    edge out of a reachable state (:func:`base_part_states`); all edges when ``base_part`` is None."""
    if base_part is None:
        return np.ones(states.n_edges, dtype=bool)
    allowed = base_part_states(states, base_part)[states.edge_source]
    allowed[base_part_first_edges(states, base_part)] = True
    return allowed


def count_intentions(states: AssemblyStateGraph, paths: list[np.ndarray] | None = None,
                     base_part: str | None = None) -> int:
    """The number of operator intentions (vertices of the intention graph), without enumerating them.

    With ``base_part``: those of the sequences that start from it (module docstring: the allowed full
    sequences plus the paths from every reachable state). ``paths``: :func:`paths_to_final`, if computed.
    Cost: O(E) (O(E log E) with a base part).
    """
    counts = paths if paths is not None else paths_to_final(states)
    if base_part is None:
        return sum(int(level.sum()) for level in counts)
    reached = base_part_states(states, base_part)
    if states.initial == states.final:
        return 1
    start = states.level_start
    continuations = sum(int(level[reached[start[k]:start[k] + level.shape[0]]].sum())
                        for k, level in enumerate(counts[:-1]))
    return count_sequences(states, base_part, counts) + continuations


def count_sequences(states: AssemblyStateGraph, base_part: str | None = None,
                    paths: list[np.ndarray] | None = None) -> int:
    """The number of full assembly sequences (paths from the initial to the final state).

    With ``base_part``, only the sequences whose first operation joins the base part are counted
    (assembly starts from the base part, paper Sec. V). ``paths``: :func:`paths_to_final`, if computed.
    """
    counts = paths if paths is not None else paths_to_final(states)
    if base_part is None:
        return int(counts[-1][-1])
    first = base_part_first_edges(states, base_part)
    if len(counts) == 1:
        return 1  # a single part: the empty sequence starts from it
    before_last, offset = counts[-2], states.level_start[len(counts) - 2]
    return sum(int(before_last[t - offset]) for t in states.edge_target[first])


def most_connected_part(product: Product) -> str:
    """The part with the most contacts (the base part of paper Sec. V); ties go to the first listed."""
    degree = {p: 0 for p in product.part_ids}
    for a, b in product.contacts:
        degree[a] += 1
        degree[b] += 1
    return max(product.part_ids, key=lambda p: degree[p])


@dataclass(frozen=True)
class IntentionGraph:
    """The intention graph as a tree over intention indices (0 is the final intention).

    ``first_state[i]``: the state intention ``i`` starts at (the current assembly state);
    ``successor[i]``: the intention after ``i``'s next step (-1 for the final intention);
    ``step_edge[i]``: the state edge of that step (-1 for the final intention), so the edge
    ``(i, successor[i])`` maps to operation ``states.edge_operation[step_edge[i]]`` (``m_I``).
    Intentions are numbered by their length, then by the order Alg. 2 finds them. ``base_part``: the part
    the sequences start from when the graph is restricted to them (module docstring), else None.
    """

    states: AssemblyStateGraph
    first_state: np.ndarray
    successor: np.ndarray
    step_edge: np.ndarray
    base_part: str | None = None

    @property
    def n_intentions(self) -> int:
        return int(self.first_state.shape[0])

    @property
    def operation(self) -> np.ndarray:
        """``m_I``: the operation of each intention's next step (-1 for the final intention)."""
        out = np.full(self.n_intentions, -1, dtype=np.int64)
        has = self.step_edge >= 0
        out[has] = self.states.edge_operation[self.step_edge[has]]
        return out

    def path(self, intention: int) -> list[int]:
        """The states of an intention, from its current state to the final state."""
        out = []
        while intention >= 0:
            out.append(int(self.first_state[intention]))
            intention = int(self.successor[intention])
        return out

    def operations(self, intention: int) -> list[int]:
        """The operations of an intention's steps, in order, to the finished product (empty for the final one)."""
        out, i = [], int(intention)
        while self.successor[i] >= 0:
            out.append(int(self.states.edge_operation[self.step_edge[i]]))
            i = int(self.successor[i])
        return out

    def full_sequences(self) -> np.ndarray:
        """The intentions that start at the initial state (the full assembly sequences)."""
        return np.flatnonzero(self.first_state == self.states.initial)

    def to_networkx(self):
        """A ``networkx.DiGraph`` over intention indices, edges ``(i, successor[i])`` with ``operation``."""
        import networkx as nx

        graph = nx.DiGraph()
        graph.add_nodes_from(range(self.n_intentions))
        ops = self.operation
        graph.add_edges_from((i, int(self.successor[i]), {"operation": int(ops[i])})
                             for i in range(self.n_intentions) if self.successor[i] >= 0)
        return graph


# Bytes per intention while the graph is built: three int64 arrays, held twice while they are concatenated.
_GRAPH_BYTES_PER_INTENTION = 56


def intention_graph(states: AssemblyStateGraph, limit: int = DEFAULT_INTENTION_LIMIT,
                    base_part: str | None = None, max_bytes: int | None = None) -> IntentionGraph:
    """Enumerate the intention graph (Alg. 2) with the map from its edges to operations.

    With ``base_part``, only the intentions of the sequences that start from it (module docstring), numbered
    in the same order (the final intention is still 0); Alg. 2 then extends an intention only along the
    allowed edges (:func:`allowed_edges`), which yields exactly them since they are closed under "next step".
    Raises :class:`~planner.errors.LimitExceededError`, stating the count, when there are more than
    ``limit`` intentions, or when the graph would take more than ``max_bytes`` (default: the machine's
    budget, :func:`~planner.assembly.guards.default_memory_budget`); the count itself never needs
    enumeration (:func:`count_intentions`); :class:`~planner.errors.PlannerError` when ``base_part`` is not a
    part or no sequence starts from it.
    Cost: O(I) time and memory for I intentions (plus O(E log E) with a base part).
    """
    total = count_intentions(states, base_part=base_part)
    if base_part is not None and count_sequences(states, base_part) == 0:
        raise PlannerError(f"no assembly sequence starts from the base part {base_part!r} (no first operation "
                           "joins it); choose another base part, or check the technical constraints")
    hint = "The counts (aplan stats) and the factored model need no enumeration."
    if total > limit:
        raise LimitExceededError("intention graph", total, limit, hint, [OPTIONS["intentions"]])
    needed = _GRAPH_BYTES_PER_INTENTION * total
    budget = default_memory_budget() if max_bytes is None else max_bytes
    if needed > budget:
        raise MemoryLimitError("intention graph", needed, budget, f"{total:,} intentions", hint,
                               memory_options(needed))
    allowed = None if base_part is None else allowed_edges(states, base_part)
    in_start, in_count = states.incoming()
    first = [np.array([states.final], dtype=np.int64)]
    successor = [np.array([-1], dtype=np.int64)]
    step = [np.array([-1], dtype=np.int64)]
    frontier = np.array([0], dtype=np.int64)
    produced = 1
    while frontier.size:
        at = first[-1]
        count = in_count[at]
        size = int(count.sum())
        if size == 0:
            break
        ends = np.cumsum(count)
        edge = np.repeat(in_start[at] - ends + count, count) + np.arange(size)
        after = np.repeat(frontier, count)
        if allowed is not None:
            keep = allowed[edge]
            edge, after = edge[keep], after[keep]
            size = int(edge.size)
            if size == 0:
                break
        successor.append(after)
        step.append(edge)
        first.append(states.edge_source[edge].astype(np.int64))
        frontier = produced + np.arange(size)
        produced += size
    return IntentionGraph(states, np.concatenate(first), np.concatenate(successor), np.concatenate(step),
                          base_part)
