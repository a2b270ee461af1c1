"""Sets of parts as integer bitmasks (bit ``i`` set = part ``i`` present) and graph helpers over them.

Python integers are unbounded, so a bitmask works for any number of parts; the set operations the graph
builders need (union, intersection, subset test) are then single integer operations.
"""
from __future__ import annotations

from typing import Iterator, Sequence

__all__ = ["bit_indices", "lowest_bit", "mask_of", "components", "connected_subsets"]


def bit_indices(mask: int) -> list[int]:
    """The indices of the set bits of ``mask``, ascending."""
    out = []
    while mask:
        low = mask & -mask
        out.append(low.bit_length() - 1)
        mask ^= low
    return out


def lowest_bit(mask: int) -> int:
    """The lowest set bit of ``mask`` as a mask (0 for 0)."""
    return mask & -mask


def mask_of(indices) -> int:
    """The bitmask with the bits of ``indices`` set."""
    mask = 0
    for i in indices:
        mask |= 1 << i
    return mask


def _neighbours(adjacency: Sequence[int], mask: int) -> int:
    out = 0
    while mask:
        low = mask & -mask
        out |= adjacency[low.bit_length() - 1]
        mask ^= low
    return out


def components(adjacency: Sequence[int], mask: int) -> list[int]:
    """The connected components of the subgraph induced by ``mask`` (each a mask), by lowest member.

    ``adjacency[i]`` is the mask of the neighbours of vertex ``i``. Cost: O(|mask| + edges inside mask).
    """
    out = []
    remaining = mask
    while remaining:
        seen = frontier = remaining & -remaining
        while frontier:
            frontier = _neighbours(adjacency, frontier) & remaining & ~seen
            seen |= frontier
        out.append(seen)
        remaining &= ~seen
    return out


def connected_subsets(adjacency: Sequence[int], allowed: int, root: int) -> Iterator[int]:
    """Every connected subset of ``allowed`` that contains vertex ``root``, each exactly once.

    The classic extension-with-exclusion enumeration: a set grows by one neighbour at a time, and a
    neighbour once tried is banned from the sets grown later from the same parent, so no set repeats.
    Cost: O(number of such subsets x |allowed|).
    """
    start = 1 << root
    stack = [(start, adjacency[root] & allowed & ~start, start)]
    while stack:
        current, candidates, banned = stack.pop()
        yield current
        tried = 0
        pending = candidates
        while pending:
            v = pending & -pending
            pending ^= v
            child_banned = banned | tried | v
            child_candidates = (candidates & ~tried & ~v) | (adjacency[v.bit_length() - 1] & allowed & ~child_banned)
            stack.append((current | v, child_candidates, child_banned))
            tried |= v
