"""The last check on proposed subassemblies: no level they make is interlocked by them.

Definition. A proposal *tangles* a level when, in that level's product, an interlocked pair
(:func:`~planner.assembly.feasibility.interlocked_pairs`) has a proposed subassembly as a member: two built
units (or a unit and a part) that block each other along every direction, though their parts did not. Such a
subassembly is *dissolved*: its members go back to the level that held it. Dissolving only undoes grouping, so
it ends (at worst in the product planned flat, whose interlocked pairs are those of its parts).

Cost: one :func:`~planner.assembly.hierarchy.product_levels` and one O(n^2 D) test per level per round, at most
one round per proposed subassembly.
"""
from __future__ import annotations

import logging
from dataclasses import replace

from ..product import Product, Subassembly
from .feasibility import interlocked_pairs
from .hierarchy import product_levels

__all__ = ["untangled", "dissolved"]

log = logging.getLogger(__name__)


def untangled(product: Product, proposed: tuple[Subassembly, ...]) -> tuple[Subassembly, ...]:
    """``proposed`` (subassemblies of ``product``, which has none of its own) with every subassembly that tangles
    a level dissolved (module docstring), each named in a warning."""
    groups = list(proposed)
    for _ in range(len(proposed)):
        ids = {g.id for g in groups}
        culprit = None
        for level in product_levels(replace(product, subassemblies=tuple(groups))):
            for pair in interlocked_pairs(level.product):
                culprit = next((m for m in (pair.second, pair.first) if m in ids), None)
                if culprit is not None:
                    log.warning("proposed subassembly %s and %s would block each other along every direction once "
                                "built (level %s): %s dissolved into the level above", pair.first, pair.second,
                                level.id, culprit)
                    break
            if culprit is not None:
                break
        if culprit is None:
            break
        groups = dissolved(groups, culprit)
    return tuple(groups)


def dissolved(groups: list[Subassembly], gone: str) -> list[Subassembly]:
    """``groups`` without subassembly ``gone``: its members take its place in the subassembly that held it (or
    join the top level). Cost: O(members)."""
    members = next(g for g in groups if g.id == gone).parts
    return [replace(g, parts=tuple(m for p in g.parts for m in (members if p == gone else (p,))))
            for g in groups if g.id != gone]
