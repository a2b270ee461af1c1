"""Containers of a CAD document whose members do not touch are no subassemblies (planner.assembly.
loose_containers): a ``Bolts`` folder is dissolved into the level above, with a warning; a container of parts
that touch is kept; a product written by hand keeps its structure (its disconnected level stays an error)."""
from __future__ import annotations

from dataclasses import replace

import pytest

from planner import api, make_plan
from planner.assembly.hierarchy import product_levels
from planner.assembly.loose_containers import connected_structure
from planner.errors import PlannerError
from planner.product import Subassembly
from planner.product.synthetic import chain_product


def _drawn(product):
    """``product`` as if drawn in CAD: every part has a mesh (the file is never read here)."""
    return replace(product, parts=tuple(replace(p, mesh=f"meshes/{p.id}.stl") for p in product.parts))


def _product(drawn: bool):
    """p1 .. p5 in a chain (p1-p2-p3-p4-p5); the container 'ends' holds p1 and p5, which do not touch, inside
    'all' with p3; 'middle' holds p2 and p3, which do."""
    chain = chain_product(5)
    chain = _drawn(chain) if drawn else chain
    return replace(chain, subassemblies=(Subassembly("ends", ("p1", "p5")), Subassembly("middle", ("p2", "p3")),
                                         Subassembly("all", ("ends", "middle", "p4"))))


def test_a_container_of_parts_that_do_not_touch_is_dissolved_into_the_level_above(caplog):
    kept = connected_structure(_product(drawn=True))
    assert [(g.id, g.parts) for g in kept.subassemblies] == [("middle", ("p2", "p3")),
                                                             ("all", ("p1", "p5", "middle", "p4"))]
    assert "the document's container ends holds members that do not touch each other (2 groups: {p1}; {p5})" \
        in caplog.text
    for level in product_levels(kept):
        assert level.product.parts, level.id
    # Resolving the product (what every command does) plans it.
    assert [level.id for level in api.levels_of(api.resolve_product(_product(drawn=True)))] == ["middle", "all"]


def test_containers_of_touching_parts_and_products_written_by_hand_are_kept():
    connected = replace(_product(drawn=True), subassemblies=(Subassembly("middle", ("p2", "p3")),))
    assert connected_structure(connected) is connected
    by_hand = _product(drawn=False)
    assert connected_structure(by_hand) is by_hand
    with pytest.raises(PlannerError, match="not connected"):
        make_plan(api.level_product(api.resolve_product(by_hand), "designer", "ends"))
