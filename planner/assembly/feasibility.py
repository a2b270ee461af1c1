"""Proofs that a product cannot be disassembled, found before any enumeration.

Definition. Two parts ``x`` and ``y`` are *interlocked* when, along every direction ``d`` of the obstruction
diagrams, ``x`` moving along ``d`` hits ``y`` and ``y`` moving along ``d`` hits ``x``. Every disassembly
separates them at some split (``x`` on one side, ``y`` on the other), and that split is blocked: the side
holding ``x`` cannot leave along ``d`` (``x`` hits ``y``), nor the other side (``y`` hits ``x``), whatever the
other parts. So one interlocked pair proves that the product cannot be disassembled, and the reverse cut-set
algorithm (which would search every connected part set to find it out) need not start.

What interlocks parts in practice: geometry that overlaps (a press fit, a screw modelled through a part, a
mesh that lost faces), or a part that leaves along a direction the diagrams do not have (a wheel along its
axle, a pin along an inclined bore).

Cost: O(n^2 D) bit operations for n parts and D directions.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from ..product import Product

__all__ = ["InterlockedPair", "interlocked_pairs", "interlock_message", "interlock_error", "directions_tried",
           "released_interlocks"]


@dataclass(frozen=True)
class InterlockedPair:
    """Parts ``first`` and ``second`` block each other along every one of ``directions``."""

    first: str
    second: str
    directions: tuple[str, ...]


def interlocked_pairs(product: Product) -> list[InterlockedPair]:
    """Every interlocked pair of ``product`` (module docstring), in part order; none when the product has no
    obstruction diagrams (nothing blocks). Cost: O(n^2 D)."""
    if not product.obstructions:
        return []
    index = {p: i for i, p in enumerate(product.part_ids)}
    both = None  # both[i]: the parts that i hits, and that hit i, along every direction so far
    for obstruction in product.obstructions:
        hits, hit_by = [0] * len(index), [0] * len(index)
        for x, y in obstruction.blocks:
            hits[index[x]] |= 1 << index[y]
            hit_by[index[y]] |= 1 << index[x]
        mutual = [h & b for h, b in zip(hits, hit_by)]
        both = mutual if both is None else [a & m for a, m in zip(both, mutual)]
    directions = tuple(o.direction.name for o in product.obstructions)
    parts = product.part_ids
    return [InterlockedPair(parts[i], parts[j], directions)
            for i, mask in enumerate(both) for j in range(i + 1, len(parts)) if mask >> j & 1]


def released_interlocks(product: Product) -> list[InterlockedPair]:
    """The pairs a designer's not-blocking mark released: interlocked with the obstruction pairs the marks took
    out (``geometry.analysis.designer.released``, :mod:`planner.product.designer`) put back, and not
    interlocked now. Cost: O(n^2 D + released)."""
    released = product.geometry.get("analysis", {}).get("designer", {}).get("released", [])
    if not released:
        return []
    back: dict[str, set[tuple[str, str]]] = {}
    parts = set(product.part_ids)
    for x, y, direction in released:
        if x in parts and y in parts:  # a level or a folded product holds fewer parts
            back.setdefault(direction, set()).add((x, y))
    restored = replace(product, obstructions=tuple(
        replace(o, blocks=o.blocks + tuple(sorted(back.get(o.direction.name, set()) - set(o.blocks))))
        for o in product.obstructions))
    now = {(p.first, p.second) for p in interlocked_pairs(product)}
    return [p for p in interlocked_pairs(restored) if (p.first, p.second) not in now]


def interlock_message(pairs: list[InterlockedPair], shown: int = 6, released: list[InterlockedPair] = ()) -> str:
    """The explanation for :class:`~planner.errors.NotDisassemblableError`: the pairs (the first ``shown``),
    the directions tried, what to check, and the pairs the designer's marks released (``released``:
    :func:`released_interlocks`)."""
    if not pairs:
        return ""
    directions = directions_tried(pairs)
    listed = "; ".join(f"{p.first} and {p.second}" for p in pairs[:shown])
    more = f" (and {len(pairs) - shown} more pairs)" if len(pairs) > shown else ""
    return (f"{len(pairs)} pair(s) of parts block each other along every direction tried ({directions}), so no "
            f"disassembly can separate them: {listed}{more}. Look for overlapping geometry between them (a press "
            "fit, a screw modelled through a part), add the direction a part really leaves along (aplan analyze "
            "--direction X,Y,Z, or the workbench's diagrams panel), mark a relation that does not block "
            "(--not-blocking BLOCKED BLOCKING DIRECTION), fold fasteners into operations, or make one "
            "component of each pair (--group)" + _released_note(released))


def directions_tried(pairs: list[InterlockedPair]) -> str:
    """The directions the pairs were tried along, as messages show them (``+/-X, +/-Y, +/-Z``)."""
    return ", ".join(f"+/-{d.lstrip('+-')}" if d[:1] in "+-" else f"{d} and its reverse"
                     for d in pairs[0].directions) if pairs else ""


def interlock_error(product: Product, pairs: list[InterlockedPair]) -> "InterlockedPartsError":
    """The :class:`~planner.errors.InterlockedPartsError` that ``pairs`` prove (one line in its summary, the
    whole explanation in its message); the :class:`~planner.errors.InterlockRefusedError` of a refused proposal
    when the designer refused one for them (:mod:`planner.assembly.interlock_proposals`). Cost: O(n^2 D) for the pairs the designer's marks released."""
    from ..errors import InterlockedPartsError
    from .interlock_refusals import refusal_error

    refused = refusal_error(product, pairs)  # a proposal the designer turned down: its own message
    if refused is not None:
        return refused
    order = {p: i for i, p in enumerate(product.part_ids)}
    stuck = sorted({p for pair in pairs for p in (pair.first, pair.second)}, key=order.get)
    return InterlockedPartsError(stuck, interlock_message(pairs, released=released_interlocks(product)),
                                 [(p.first, p.second) for p in pairs], directions_tried(pairs))


def _released_note(released: list[InterlockedPair]) -> str:
    if not released:
        return ""
    listed = "; ".join(f"{p.first} and {p.second}" for p in released)
    return f" (the designer's not-blocking marks released {len(released)} other pair(s): {listed})"
