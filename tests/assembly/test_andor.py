"""The AND/OR graph by the reverse cut-set algorithm: hyperarcs, and products that cannot be planned."""
from __future__ import annotations

import pytest

from planner import (
    DisconnectedProductError,
    NotDisassemblableError,
    Obstruction,
    Part,
    Product,
    and_or_graph,
    count_intentions,
    make_plan,
    plan_statistics,
)
from planner.product import AXIS_DIRECTIONS, Direction, TechnicalConstraint


def test_no_duplicate_hyperarcs_for_equal_halves():
    # Four parts in a square: {a, b} + {c, d} and {a, d} + {b, c} are splits into equal halves.
    parts = tuple(Part(p) for p in "abcd")
    square = Product(parts, (("a", "b"), ("b", "c"), ("c", "d"), ("d", "a")))
    andor = and_or_graph(square)
    keys = [(op.parent, frozenset(op.children)) for op in andor.operations]
    assert len(keys) == len(set(keys))
    full_splits = {frozenset(map(frozenset, andor.inputs(j))) for j, op in enumerate(andor.operations) if op.parent == 0}
    assert frozenset({frozenset("ab"), frozenset("cd")}) in full_splits
    # 4 single-part splits + 2 pairs-of-pairs
    assert len(full_splits) == 6


def test_disconnected_liaison_graph_names_the_groups():
    parts = tuple(Part(p) for p in ("a", "b", "c", "d"))
    product = Product(parts, (("a", "b"), ("c", "d")))
    with pytest.raises(DisconnectedProductError, match=r"falls apart into 2 groups: \{a, b\} \| \{c, d\}"):
        and_or_graph(product)


def test_stuck_product_names_the_subassembly():
    parts = tuple(Part(p) for p in ("peg", "hole", "lid"))
    x = Direction("+X", AXIS_DIRECTIONS["+X"])
    blocked = Obstruction(x, (("peg", "hole"), ("hole", "peg"), ("lid", "hole"), ("hole", "lid")))
    product = Product(parts, (("peg", "hole"), ("hole", "lid")), obstructions=(blocked,))
    with pytest.raises(NotDisassemblableError) as info:
        and_or_graph(product)
    assert info.value.stuck == ["peg", "hole"]
    assert ("subassembly {peg, hole} has no feasible split (1 cut(s) blocked in every direction, e.g. {peg} from "
            "{hole}; it is needed by {peg, hole, lid})") in str(info.value)


def test_stuck_by_technical_constraint():
    parts = tuple(Part(p) for p in ("a", "b", "c"))
    # a and b need c, b and c need a, a and c need b: every two-part subassembly is infeasible.
    constraints = (TechnicalConstraint(frozenset("ab"), "c"), TechnicalConstraint(frozenset("bc"), "a"),
                   TechnicalConstraint(frozenset("ac"), "b"))
    product = Product(parts, (("a", "b"), ("b", "c"), ("a", "c")), technical_constraints=constraints)
    with pytest.raises(NotDisassemblableError, match="technically infeasible side"):
        and_or_graph(product)
    assert plan_statistics(make_plan(product, technical=False)).sequences == 3


def test_single_part_product():
    plan = make_plan(Product((Part("only"),), ()))
    stats = plan_statistics(plan, "only")
    assert (stats.subassemblies, stats.operations, stats.states, stats.intentions, stats.sequences) == (1, 0, 1, 1, 1)
    assert count_intentions(plan.states) == 1
