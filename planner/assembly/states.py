"""Assembly state graph (Alg. 1 of Cramer et al. 2021).

Definitions
-----------
An *assembly state* is a partition of the parts into subassemblies of the AND/OR graph that the complete
product can be disassembled into by a sequence of operations. Alg. 1 starts from the complete product and
applies every operation backwards (splits a subassembly into the operation's two children); each split
``S -> S'`` gives the edge ``(S', S)`` in the assembly direction, mapped to its operation (``m_ST``).
The *initial* state holds every part on its own; the *final* state is the complete product.

Representation
--------------
``blocks[s, p]`` is the index (in ``andor.subassemblies``) of the subassembly that holds part ``p`` in
state ``s``. States are numbered by their number of blocks: state 0 is the final state, the last one the
initial state; ``level_start[k - 1]`` is the first state with ``k`` blocks. Edges run from the less to the
more assembled state and are sorted by ``edge_target``.

The construction is breadth-first by level and vectorised with numpy: all splits of all states of a level
are made at once and the new states are deduplicated by a packed key (the lowest part of each part's block),
which each operation changes by a constant, so a level costs one sort of its edges.
"""
from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import MemoryLimitError, gib
from .andor import AndOrGraph
from .bitsets import bit_indices
from .guards import OPTIONS, Progress, default_memory_budget, memory_options

__all__ = ["AssemblyStateGraph", "assembly_state_graph", "state_table_bytes", "state_graph_bytes", "check_counted"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class AssemblyStateGraph:
    """The assembly state graph of an AND/OR graph (see the module docstring for the layout).

    Attributes: ``blocks`` (S, n) int32; ``level_start`` (n + 1,) int64; ``edge_source``, ``edge_target``,
    ``edge_operation`` (E,) int32 (operation indices into ``andor.operations``).
    """

    andor: AndOrGraph
    blocks: np.ndarray
    level_start: np.ndarray
    edge_source: np.ndarray
    edge_target: np.ndarray
    edge_operation: np.ndarray

    @property
    def n_states(self) -> int:
        return int(self.blocks.shape[0])

    @property
    def n_edges(self) -> int:
        return int(self.edge_source.shape[0])

    @property
    def final(self) -> int:
        """The complete product."""
        return 0

    @property
    def initial(self) -> int:
        """Every part on its own."""
        return self.n_states - 1

    def subassemblies_of(self, state: int) -> list[int]:
        """The subassembly indices that make up ``state`` (ordered by their lowest part)."""
        return list(dict.fromkeys(int(b) for b in self.blocks[state]))

    def describe(self, state: int) -> str:
        """``{a, b} {c}`` for a state."""
        return " ".join(self.andor.names(b) for b in self.subassemblies_of(state))

    def incoming(self) -> tuple[np.ndarray, np.ndarray]:
        """CSR of the edges into each state: edges into ``t`` are ``start[t]:start[t] + count[t]``."""
        start = np.searchsorted(self.edge_target, np.arange(self.n_states + 1))
        return start[:-1], np.diff(start)

    def to_networkx(self):
        """A ``networkx.DiGraph`` over state indices; each edge carries its ``operation``."""
        import networkx as nx

        graph = nx.DiGraph()
        graph.add_nodes_from(range(self.n_states))
        graph.add_edges_from((int(s), int(t), {"operation": int(o)})
                             for s, t, o in zip(self.edge_source, self.edge_target, self.edge_operation))
        return graph


def _subassembly_tables(andor: AndOrGraph):
    n = len(andor.parts)
    count = len(andor.subassemblies)
    member = np.zeros((count, n), dtype=bool)
    lowest = np.empty(count, dtype=np.int32)
    for v, mask in enumerate(andor.subassemblies):
        members = bit_indices(mask)
        member[v, members] = True
        lowest[v] = members[0]
    parent = np.fromiter((op.parent for op in andor.operations), dtype=np.int64, count=len(andor.operations))
    first = np.fromiter((op.children[0] for op in andor.operations), dtype=np.int32, count=len(andor.operations))
    second = np.fromiter((op.children[1] for op in andor.operations), dtype=np.int32, count=len(andor.operations))
    op_start = np.searchsorted(parent, np.arange(count + 1))
    return member, lowest, first, second, op_start[:-1], np.diff(op_start)


def _key_layout(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Where each part's label sits in a packed state key: (word index, bit shift) per part.

    A label (the lowest part of the part's block) takes ``ceil(log2 n)`` bits; fields never straddle words.
    """
    bits = max(1, (n - 1).bit_length())
    per_word = 64 // bits
    parts = np.arange(n)
    return parts // per_word, ((parts % per_word) * bits).astype(np.uint64)


def _group(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each distinct key row, the position of one occurrence, and each row's distinct-key index.

    ``keys`` is (m, words) uint64; one sort (``lexsort`` over the words when there are several).
    """
    order = np.argsort(keys[:, 0]) if keys.shape[1] == 1 else np.lexsort(keys.T[::-1])
    ordered = keys[order]
    new = np.empty(ordered.shape[0], dtype=bool)
    new[:1] = True
    np.any(ordered[1:] != ordered[:-1], axis=1, out=new[1:])
    inverse = np.empty(ordered.shape[0], dtype=np.int64)
    inverse[order] = np.cumsum(new) - 1
    return order[new], inverse


def state_table_bytes(n_parts: int, n_subassemblies: int, n_operations: int) -> int:
    """The bytes of the per-operation tables :func:`assembly_state_graph` builds before its first level: the
    key change of each operation per part (uint64, with its temporaries) and part membership."""
    return 24 * n_operations * n_parts + 2 * n_subassemblies * n_parts


def _level_bytes(edges: int, words: int) -> int:
    """Peak temporaries of one level of ``edges`` new state edges: operation, source and sort indices
    (int64), and the packed keys of the new states with their sums and sorted copy (``words`` uint64 each)."""
    return edges * (96 + 32 * words)


def state_graph_bytes(n_states: int, n_edges: int, n_parts: int) -> int:
    """The bytes the finished state graph holds: a block per part and state (int32), three int32 per edge.
    The build holds them twice at its end (the levels and their concatenation)."""
    return 4 * n_states * n_parts + 12 * n_edges


_HINT = ("Its states are the partitions of the parts into subassemblies that the product can be taken apart "
         "into, and they multiply with every part that can join the others in several ways. Plan with fewer "
         "parts: fold the fasteners into the operations that install them, leave out or group parts that are "
         "always assembled together, or plan one subassembly (one workstation) at a time.")


def _refuse(needed: int, budget: int, detail: str, what: str = "assembly state graph") -> MemoryLimitError:
    return MemoryLimitError(what, needed, budget, detail, _HINT,
                            memory_options(needed) + [OPTIONS[k] for k in ("fasteners", "exclude", "group")])


def check_counted(count, n_parts: int, max_bytes: int, reserve: Callable[[int, int], int] | None = None,
                  reserve_for: str = "") -> None:
    """Refuse at once (:class:`~planner.errors.MemoryLimitError`) a state graph whose counted states and edges
    (a :class:`~planner.assembly.state_count.StateCount`: edges exact or from below) would not fit in
    ``max_bytes``: the build's end holds :func:`state_graph_bytes` twice; ``reserve(states, edges)``: the
    bytes the command builds on the plan afterwards (``reserve_for`` names it), with the plan held."""
    held = state_graph_bytes(count.states, count.edges, n_parts)
    after = reserve(count.states, count.edges) if reserve is not None else 0
    needed = max(2 * held, held + after)
    if needed <= max_bytes:
        return
    edges = f"{count.edges:,}" if count.exact else f"at least {count.edges:,}"
    detail = (f"{count.states:,} states and {edges} state edges over {n_parts} parts, counted before "
              "building: with no constraint between them every partition of the parts into connected sets is "
              "a state")
    if 2 * held >= held + after:
        raise _refuse(needed, max_bytes, detail)
    raise MemoryLimitError(f"the plan and {reserve_for}", needed, max_bytes, detail + f"; the plan alone "
                           f"{gib(held)}", "What is built on the plan grows with its state edges (and, for a "
                           "model over actions, with the robot's actions). " + _HINT.split(". ", 1)[1],
                           memory_options(needed) + [OPTIONS[k] for k in ("fasteners", "exclude", "group")])


def assembly_state_graph(andor: AndOrGraph, max_bytes: int | None = None,
                         reserve: Callable[[int, int], int] | None = None, reserve_for: str = ""
                         ) -> AssemblyStateGraph:
    """Build the assembly state graph of ``andor`` (Alg. 1), with the map from edges to operations.

    ``max_bytes``: the memory budget (default :func:`~planner.assembly.guards.default_memory_budget`). The
    per-operation tables are estimated first, and each level before its arrays are made (its edges are
    counted first, its new states after deduplication); when the estimate passes the budget it raises
    :class:`~planner.errors.MemoryLimitError` with the states and edges built so far, having used at most
    the budget. Estimates are within about 20 % of the measured peak (complete 10 and 11, chain 16).
    ``reserve(states, edges)``: bytes the command builds on the plan afterwards (``reserve_for`` names it,
    e.g. the factored model), counted from the states and edges so far, so that the plan stops where what
    comes after would not fit either.

    Cost: O(E log E + S n) time and O(E + S n) memory for S states and E state edges over n parts (each
    level is built with vectorised splits and deduplicated with one sort of its edges' keys).
    """
    n = len(andor.parts)
    max_bytes = default_memory_budget() if max_bytes is None else max_bytes
    tables = state_table_bytes(n, len(andor.subassemblies), len(andor.operations))
    if tables > max_bytes:
        raise _refuse(tables, max_bytes, f"tables of {len(andor.operations):,} operations over {n} parts, "
                                                "before any state")
    member, lowest, first, second, op_start, op_count = _subassembly_tables(andor)
    parts = np.arange(n)
    # A state's key packs, per part, the lowest part of its block. A split only relabels the parts of the
    # child that lacks the parent's lowest part, so each operation adds a fixed amount to each key word.
    word, shift = _key_layout(n)
    words = int(word[-1]) + 1
    parent_low = lowest[np.repeat(np.arange(len(op_count)), op_count)].astype(np.uint64)
    change = (lowest[second].astype(np.uint64) - parent_low)[:, None] << shift  # (operations, n)
    delta = np.zeros((len(second), words), dtype=np.uint64)
    for w in range(words):
        delta[:, w] = np.where(member[second][:, word == w], change[:, word == w], 0).sum(axis=1, dtype=np.uint64)
    keys = np.zeros((1, words), dtype=np.uint64)  # the final state: every part labelled 0
    rows = np.zeros((1, n), dtype=np.int32)  # the final state: every part in subassembly 0
    levels = [rows]
    sources, targets, operations = [], [], []
    offset = 0
    held = rows.nbytes  # states' rows and edges (int32 x 3) so far: concatenated at the end, so held twice then
    progress = Progress(log)
    for level in range(1, n):
        progress.report("assembly state graph: %s states with at most %d of %d subassemblies, about %s",
                        f"{offset + rows.shape[0]:,}", level, n, gib(tables + held))
        state, part = np.nonzero(lowest[rows] == parts)  # one (state, block) pair per block, by its lowest part
        block = rows[state, part]
        count = op_count[block]
        total = int(count.sum())
        if total == 0:
            break
        # Refused before the level's arrays exist: its temporaries, or the final concatenation, would not fit.
        edges_so_far = sum(map(len, sources)) + total
        after = reserve(offset + rows.shape[0], edges_so_far) if reserve is not None else 0
        needed = tables + max(held + _level_bytes(total, words), 2 * (held + 12 * total), held + 12 * total + after)
        if needed > max_bytes:
            raise _refuse(needed, max_bytes, f"{offset + rows.shape[0]:,} states and "
                          f"{sum(map(len, sources)):,} state edges with at most {level} subassemblies, and "
                          f"{total:,} more edges to states of {level + 1}",
                          "assembly state graph" + (f" and {reserve_for}" if after else ""))
        split_of = np.repeat(state, count)
        ends = np.cumsum(count)
        operation = np.repeat(op_start[block] - ends + count, count) + np.arange(total)
        new_keys = keys[split_of] + delta[operation]
        first_row, inverse = _group(new_keys)
        new_rows = 4 * n * first_row.shape[0]  # int32 per part; _split makes two temporaries of that size
        needed = tables + max(held + 12 * total + 3 * new_rows, 2 * (held + 12 * total + new_rows))
        if needed > max_bytes:
            raise _refuse(needed, max_bytes, f"{offset + levels[-1].shape[0]:,} states with at most "
                          f"{level} subassemblies, and {first_row.shape[0]:,} more states of {level + 1} "
                          f"subassemblies with {total:,} edges")
        keys = new_keys[first_row]
        rows = _split(rows[split_of[first_row]], first[operation[first_row]], second[operation[first_row]], member)
        held += 12 * total + rows.nbytes
        next_offset = offset + levels[-1].shape[0]
        sources.append((next_offset + inverse).astype(np.int32))
        targets.append((offset + split_of).astype(np.int32))
        operations.append(operation.astype(np.int32))
        levels.append(rows)
        offset = next_offset
    sizes = [lvl.shape[0] for lvl in levels] + [0] * (n - len(levels))
    level_start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    empty = np.zeros(0, dtype=np.int32)
    return AssemblyStateGraph(
        andor=andor,
        blocks=np.concatenate(levels),
        level_start=level_start,
        edge_source=np.concatenate(sources) if sources else empty,
        edge_target=np.concatenate(targets) if targets else empty,
        edge_operation=np.concatenate(operations) if operations else empty,
    )


def _split(rows: np.ndarray, first: np.ndarray, second: np.ndarray, member: np.ndarray) -> np.ndarray:
    """Apply one split per row: the parts of each operation's children move to those children."""
    return np.where(member[second], second[:, None], np.where(member[first], first[:, None], rows))
