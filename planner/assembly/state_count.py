"""The assembly states and state edges of a product counted before the state graph is built.

Definition. When the AND/OR graph holds every connected part set and every cut of one into two connected
halves (:attr:`~planner.assembly.andor.AndOrGraph.every_cut`: no technical or geometric constraint removed
any), the assembly states are exactly the partitions of the parts into connected sets: such a partition's
blocks can be merged two adjacent ones at a time (each merge is a cut of a connected set into connected
halves, an operation) up to the complete product, so it is reachable from the complete product by splits,
and every state is one. A state's out-edges (towards fewer blocks read backwards: Alg. 1's splits) are the
operations of its blocks, so the state edges are ``sum over states of sum over their blocks of ops(block)``.

Both sums run over the partitions by their block holding the lowest remaining part: ``count(R)`` for the
parts ``R`` still to place is ``sum over connected B in R holding R's lowest part of count(R - B)`` (and the
edges likewise), memoised on ``R``. Cost: O(sum over the remainders R met of the connected subsets of R
holding its lowest part): 3^n / 2 for a complete diagram of n parts, n^2 for a chain; stopped (None) past
``work`` subsets, so the count never costs more than a bounded amount of work whatever the product.

With constraints the partitions into subassemblies are only an upper bound on the states, so nothing is
counted then (the state graph's builder guards each level instead). A product without obstructions and
without active technical constraints is counted before its AND/OR graph is even built
(:func:`count_unconstrained`): its states exactly, its edges from below (a connected set of k parts has at
least k - 1 cuts into connected halves: one per edge of a spanning tree).
"""
from __future__ import annotations

from dataclasses import dataclass

from .andor import AndOrGraph
from .bitsets import connected_subsets

__all__ = ["StateCount", "count_states", "count_unconstrained", "is_unconstrained", "COUNT_WORK"]

COUNT_WORK = 2_000_000  # connected subsets the count may enumerate (about a second; complete 13: 0.8 M)


@dataclass(frozen=True)
class StateCount:
    """The numbers of assembly states and state edges of a plan, counted without building them; ``exact``
    False: ``edges`` is a lower bound (the states are exact either way)."""

    states: int
    edges: int
    exact: bool = True


def is_unconstrained(product) -> bool:
    """Whether no constraint can remove a connected set or a cut from ``product``'s AND/OR graph: no
    obstruction diagram and no active technical constraint."""
    return not product.obstructions and not any(c.active for c in product.technical_constraints)


def count_unconstrained(adjacency: list[int], work: int = COUNT_WORK) -> StateCount | None:
    """The states (exact) and a lower bound on the state edges of an unconstrained product
    (:func:`is_unconstrained`) from its connection diagram alone, before the AND/OR graph; None past
    ``work`` subsets."""
    found = _partitions(adjacency, lambda block: block.bit_count() - 1, work)
    return None if found is None else StateCount(*found, exact=False)


def count_states(andor: AndOrGraph, adjacency: list[int], work: int = COUNT_WORK) -> StateCount | None:
    """The states and state edges of ``andor`` (module docstring) when it holds every connected set and cut
    (``andor.every_cut``), else None; None too past ``work`` enumerated subsets. ``adjacency``: the
    connection diagram as neighbour masks (:func:`~planner.assembly.andor.liaison_adjacency`)."""
    if not andor.every_cut:
        return None
    operations = [0] * len(andor.subassemblies)
    for op in andor.operations:
        operations[op.parent] += 1
    ops_of = {mask: operations[i] for i, mask in enumerate(andor.subassemblies)}
    found = _partitions(adjacency, ops_of.__getitem__, work)
    return None if found is None else StateCount(*found)


def _partitions(adjacency: list[int], ops, work: int) -> tuple[int, int] | None:
    """(partitions of every part into connected sets, sum over them of ``ops(block)`` over their blocks),
    or None past ``work`` enumerated subsets."""
    memo: dict[int, tuple[int, int]] = {0: (1, 0)}
    pending: dict[int, list[int]] = {}  # the blocks of the remainders waiting for their own remainders
    left = work
    stack = [(1 << len(adjacency)) - 1]  # iterative: deep products never hit Python's recursion limit
    while stack:
        mask = stack[-1]
        if mask in memo:
            stack.pop()
            continue
        blocks = pending.pop(mask, None)
        if blocks is None:
            blocks = list(connected_subsets(adjacency, mask, (mask & -mask).bit_length() - 1))
            left -= len(blocks)
            if left < 0:
                return None
        missing = [mask ^ b for b in blocks if mask ^ b not in memo]
        if missing:
            pending[mask] = blocks
            stack.extend(missing)
            continue
        states = edges = 0
        for b in blocks:
            c, e = memo[mask ^ b]
            states += c
            edges += e + c * ops(b)
        memo[mask] = (states, edges)
        stack.pop()
    return memo[(1 << len(adjacency)) - 1]
