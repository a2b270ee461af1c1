"""Proposed subassemblies never make an interlocked level (planner.assembly.untangle): two built units that
would block each other along every direction, though no two of their parts do, are not both kept."""
from __future__ import annotations

from dataclasses import replace

from planner import make_plan, plan_statistics
from planner.assembly.feasibility import interlocked_pairs
from planner.assembly.hierarchy import product_levels
from planner.assembly.untangle import untangled
from planner.product import Direction, Obstruction, Subassembly
from planner.product.synthetic import chain_product

AXES = [Direction.from_vector(v) for v in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))]


def _tangled():
    """p1 .. p4 in a chain; along X p1 hits p3 and p4 hits p2, along Y p2 hits p4 and p3 hits p1, along Z p1 hits
    p4 and p3 hits p2: no two parts are interlocked, but built, {p1, p2} and {p3, p4} are."""
    blocks = [(("p1", "p3"), ("p4", "p2")), (("p2", "p4"), ("p3", "p1")), (("p1", "p4"), ("p3", "p2"))]
    product = replace(chain_product(4), obstructions=tuple(Obstruction(a, b) for a, b in zip(AXES, blocks)))
    return product, (Subassembly("sa1", ("p1", "p2"), source="proposed"),
                     Subassembly("sa2", ("p3", "p4"), source="proposed"))


def test_two_units_that_would_interlock_are_not_both_kept(caplog):
    product, proposed = _tangled()
    assert interlocked_pairs(product) == []
    top = product_levels(replace(product, subassemblies=proposed))[-1].product
    assert [(p.first, p.second) for p in interlocked_pairs(top)] == [("sa1", "sa2")]
    kept = untangled(product, proposed)
    assert [g.id for g in kept] == ["sa1"] and "sa2 dissolved" in caplog.text
    for level in product_levels(replace(product, subassemblies=kept)):
        assert interlocked_pairs(level.product) == [], level.id
        assert plan_statistics(make_plan(level.product)).sequences >= 1, level.id


def test_proposals_that_do_not_interlock_are_kept():
    product, proposed = _tangled()
    free = replace(product, obstructions=())
    assert untangled(free, proposed) == proposed
