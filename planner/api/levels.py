"""Stage 2 of the API, for products of several levels: a product planned as workstations (its subassemblies as
``--subassemblies`` asks), each level's product and figures, and the levels that cannot be built on their own."""
from __future__ import annotations

import os
from dataclasses import replace
from typing import Callable

import numpy as np

from ..assembly.andor import and_or_graph
from ..assembly.guards import SizeLimits
from ..assembly.hierarchy import (
    Level,
    check_level_constraints,
    level_statistics,
    product_levels,
    select_level,
)
from ..assembly.subassembly_proposals import propose_subassemblies, with_subassemblies
from ..assembly.stats import STAT_KEYS, PlanStatistics, statistics_within
from ..defaults import MAX_COMPONENTS, SUBASSEMBLY_LIMIT
from ..errors import LimitExceededError, PlannerError
from ..product import Product, Subassembly

from .products import resolve_product

__all__ = ["arranged", "levels_of", "level_product", "level_support_proposals", "hierarchy_statistics_of", "LEVEL_KEYS",
           "proposed_subassemblies", "structure_problems", "level_report", "level_table"]


def arranged(product: str | os.PathLike | Product, subassemblies: str = "designer", max_components: int = MAX_COMPONENTS) -> Product:
    """The product with the subassemblies ``subassemblies`` asks for
    (:func:`~planner.assembly.subassembly_proposals.with_subassemblies`): ``designer`` the file's, ``auto`` proposed when the
    file has none (at most ``max_components`` members each), ``none`` none."""
    product = product if isinstance(product, Product) else resolve_product(product)
    return with_subassemblies(product, subassemblies, max_components)


def levels_of(product: str | os.PathLike | Product, subassemblies: str = "designer",
              max_components: int = MAX_COMPONENTS) -> list[Level]:
    """The workstations of a product, bottom-up (:func:`~planner.assembly.hierarchy.product_levels`) with its
    subassemblies as ``subassemblies`` asks: ``designer`` (the file's), ``auto`` (proposed when the file has
    none, at most ``max_components`` members each) or ``none`` (one level: the product flat)."""
    product = product if isinstance(product, Product) else resolve_product(product)
    return product_levels(with_subassemblies(product, subassemblies, max_components))


def level_support_proposals(product: str | os.PathLike | Product) -> list[dict]:
    """The support contacts the levels of ``product`` (its own subassemblies) would get from the support rule's
    candidates that a detection recorded (a product too large to judge flat:
    :func:`~planner.assembly.level_supports.level_proposals`), each ``{"rule": "support", "parts": [part, host],
    "level", "text"}``; ``[]`` without candidates or levels. The workbench's interlocks panel lists them."""
    from ..assembly.level_supports import level_proposals

    product = product if isinstance(product, Product) else resolve_product(product)
    return level_proposals(product) if product.subassemblies else []


def level_product(product: str | os.PathLike | Product, subassemblies: str = "designer", level: str | None = None,
                  max_components: int = MAX_COMPONENTS) -> Product:
    """The product one workstation plans: level ``level`` (a subassembly id or ``top``), or the product itself
    when it is planned flat; several levels without ``level`` is a :class:`PlannerError` naming them."""
    product = product if isinstance(product, Product) else resolve_product(product)
    return select_level(with_subassemblies(product, subassemblies, max_components), level).product


def hierarchy_statistics_of(product: str | os.PathLike | Product, technical: bool | None = None,
                            limits: SizeLimits = SizeLimits(), subassemblies: str = "designer",
                            max_components: int = MAX_COMPONENTS, flat_limits: SizeLimits | None = None,
                            progress: Callable[[str], None] | None = None):
    """The figures of every level (``[(Level, PlanStatistics)]``, bottom-up) and of the product planned flat:
    a :class:`PlanStatistics` within ``flat_limits`` (default ``limits``), or the :class:`PlannerError` that
    stopped it (not connected, not disassemblable); None when the product is one level."""
    product = product if isinstance(product, Product) else resolve_product(product)
    arranged = with_subassemblies(product, subassemblies, max_components)
    levels = level_statistics(arranged, technical, limits, progress)
    if len(levels) == 1:
        return levels, None
    if progress is not None:
        progress("the product planned flat, for comparison")
    flat = replace(product, subassemblies=())
    try:
        _, flat_stats = statistics_within(flat, technical, None, flat_limits or limits)
    except PlannerError as error:
        return levels, error
    return levels, flat_stats


# The figures a hierarchy adds up over its levels (sequences multiply: each workstation picks its own).
LEVEL_KEYS = ("parts", "subassemblies", "operations", "states", "state_edges", "intentions", "sequences")


def proposed_subassemblies(product: Product, max_components: int = MAX_COMPONENTS) -> tuple[Subassembly, ...]:
    """The planner's subassembly tree for ``product``, ignoring any it already has
    (:func:`~planner.assembly.subassembly_proposals.propose_subassemblies`: what ``--subassemblies auto`` plans with)."""
    return propose_subassemblies(replace(product, subassemblies=()), max_components)


def structure_problems(product: Product, limit: int = 100_000) -> list[tuple[str, str]]:
    """``(level id, reason)`` for every level of ``product`` that cannot be built on its own: a technical
    constraint it breaks, members that do not touch, or stuck members (named by the planner's error).

    Each level's AND/OR graph is tried within ``limit`` connected part sets; a level past it is not judged
    here (its plan will say). Cost: at most ``limit`` connected sets per level, plus O(levels x relations).
    """
    problems = []
    for level in product_levels(product):
        try:
            check_level_constraints(product, level)
            and_or_graph(level.product, limit=limit)
        except LimitExceededError:
            continue
        except PlannerError as error:
            problems.append((level.id, str(error)))
    return problems


def level_report(product: Product, technical: bool | None = None, limits: SizeLimits = SizeLimits(),
                 flat_limits: SizeLimits | None = None, progress: Callable[[str], None] | None = None) -> dict:
    """The figures ``aplan stats --json`` prints for a product of several levels: ``levels`` (each level's id,
    members, figures and, when it was refused or failed, ``not_computed`` or ``error``), ``total`` (sums over
    the levels; parts: the product's; sequences: the product of the levels') and ``flat`` (the product planned
    flat within ``flat_limits``, else None and ``flat_not_computed``). ``progress(text)`` is told each level as
    it is done. Cost: the levels' plans plus the flat plan within its limits."""
    flat_limits = flat_limits or SizeLimits(min(limits.subassemblies, SUBASSEMBLY_LIMIT), min(limits.memory, 2 ** 30))
    levels, flat = hierarchy_statistics_of(product, technical, limits, flat_limits=flat_limits, progress=progress)
    return level_table(product, levels, flat)


def level_table(product: Product, levels: list, flat) -> dict:
    """:func:`level_report`'s dict from :func:`hierarchy_statistics_of`'s answer ``(levels, flat)`` (each
    level's statistics or the error it ended with; the flat statistics, the reason they are missing, or None).
    Cost: O(levels x figures)."""
    rows = []
    for level, stats in levels:
        row = {"level": level.id, "members": list(level.members)}
        if isinstance(stats, PlanStatistics):
            row.update(stats.as_dict())
            if stats.refused:
                row["not_computed"] = str(stats.refused)
        else:
            row.update({key: None for key in STAT_KEYS})
            row["error"] = str(stats)
        rows.append(row)
    total: dict[str, int | None] = {}
    for key in LEVEL_KEYS:
        values = [row[key] for row in rows]
        if key == "parts":
            total[key] = len(product.parts)
        elif any(v is None for v in values):
            total[key] = None
        elif key == "sequences":
            total[key] = int(np.prod(values, dtype=object))
        else:
            total[key] = sum(values)
    out = {"levels": rows, "total": total, "flat": flat.as_dict() if isinstance(flat, PlanStatistics) else None}
    reason = (str(flat.refused) if isinstance(flat, PlanStatistics) and flat.refused else
              None if isinstance(flat, PlanStatistics) or flat is None else str(flat))
    if reason:
        out["flat_not_computed"] = reason
    return out
