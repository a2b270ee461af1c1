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
from planner.assembly.feasibility import InterlockedPair, interlocked_pairs
from planner.errors import InterlockedPartsError


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
    # Along +X: a hits b, b hits c, c hits a. No two parts block each other, yet {a, b, c} has no split.
    parts = tuple(Part(p) for p in ("a", "b", "c", "lid"))
    x = Direction("+X", AXIS_DIRECTIONS["+X"])
    cyclic = Obstruction(x, (("a", "b"), ("b", "c"), ("c", "a")))
    product = Product(parts, (("a", "b"), ("b", "c"), ("a", "c"), ("c", "lid")), obstructions=(cyclic,))
    with pytest.raises(NotDisassemblableError) as info:
        and_or_graph(product)
    assert not isinstance(info.value, InterlockedPartsError)
    assert info.value.stuck == ["a", "b", "c", "lid"]
    # lid leaves along +X (it hits nothing), and {a, b, c} left is the cycle itself: nothing floats.
    assert info.value.smallest == ["a", "b", "c"] and info.value.floating == ""
    assert ("subassembly {a, b, c, lid} has no feasible split (3 cut(s) blocked in every direction, e.g. {a} from "
            "{b, c, lid}; 1 cut(s) with a side that cannot be assembled itself, e.g. {a, b, c})") in str(info.value)


def test_interlocked_parts_are_found_before_any_enumeration():
    """Two parts that block each other along every direction: a proof, named with the directions tried."""
    parts = tuple(Part(p) for p in ("peg", "hole", "lid", "cap"))
    x, z = Direction("+X", AXIS_DIRECTIONS["+X"]), Direction("+Z", AXIS_DIRECTIONS["+Z"])
    along_x = Obstruction(x, (("peg", "hole"), ("hole", "peg"), ("lid", "hole"), ("hole", "lid")))
    along_z = Obstruction(z, (("peg", "hole"), ("hole", "peg"), ("lid", "hole")))
    product = Product(parts, (("peg", "hole"), ("hole", "lid"), ("lid", "cap")), obstructions=(along_x, along_z))
    assert interlocked_pairs(product) == [InterlockedPair("peg", "hole", ("+X", "+Z"))]
    with pytest.raises(InterlockedPartsError) as info:
        and_or_graph(product, limit=1)   # refused by the proof, not by the enumeration's limit
    assert info.value.stuck == ["peg", "hole"]
    assert ("1 pair(s) of parts block each other along every direction tried (+/-X, +/-Z), so no disassembly can "
            "separate them: peg and hole.") in str(info.value)
    assert interlocked_pairs(Product(parts[:2], (("peg", "hole"),))) == []   # no diagrams: nothing blocks


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
