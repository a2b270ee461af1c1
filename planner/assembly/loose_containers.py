"""Containers of the document that are no subassemblies: a designer's subassembly whose members do not touch.

Definition. Public CAD files group parts by kind as often as by what is built together: an ``App::Part`` or a
group named ``Bolts`` or ``Nuts``, a link array of screws. Such a container becomes a subassembly of the
product (:func:`freecad_aplan.containers.document_subassemblies`), but its members do not touch each other, so
it cannot be built on its own (its level's connection diagram is not connected). Such a subassembly is
*dissolved*: its members go to the level that held it, in its place; a warning names it, its groups of touching
members and what was done. Only products drawn in CAD are changed this way (a product file written by hand is
planned as written: its disconnected level is an error naming the groups).

Cost: one :func:`~planner.assembly.hierarchy.product_levels` and one O(members + contacts) union-find per level
per round, at most one round per subassembly.
"""
from __future__ import annotations

import logging
from dataclasses import replace

from ..geometry.gaps import connection_groups
from ..product import Product
from .hierarchy import product_levels
from .untangle import dissolved

__all__ = ["connected_structure"]

log = logging.getLogger(__name__)


def connected_structure(product: Product) -> Product:
    """``product`` with every designer subassembly whose members do not all touch dissolved into the level above
    (module docstring), each named in a warning; ``product`` itself when none is, or when it is not drawn in
    CAD (some part without a mesh)."""
    from .interlocks import drawn_in_cad

    if not product.subassemblies or not drawn_in_cad(product):
        return product
    groups = list(product.subassemblies)
    for _ in range(len(groups)):
        current = replace(product, subassemblies=tuple(groups))
        ids = {g.id for g in groups if g.source == "designer"}
        loose = None
        for level in product_levels(current):
            if level.id not in ids:
                continue
            found = sorted(connection_groups(level.members, level.product.contacts), key=len, reverse=True)
            if len(found) > 1:
                loose = level.id
                shown = "; ".join("{" + ", ".join(g) + "}" for g in found[:4]) + ("; ..." if len(found) > 4 else "")
                log.warning("the document's container %s holds members that do not touch each other (%d groups: "
                            "%s): not a subassembly; its members are planned in the level above", loose,
                            len(found), shown)
                break
        if loose is None:
            break
        groups = dissolved(groups, loose)
    return replace(product, subassemblies=tuple(groups)) if len(groups) != len(product.subassemblies) else product
