"""Subassemblies (issue 13, item 2): the product's tree checked, each level planned as a product of its own
(counts from the chain formulas), the members' contacts and obstructions, and the proposed decomposition."""
from __future__ import annotations

import logging
import re
from dataclasses import replace
from math import comb, factorial

import pytest
from real_models import BACKGROUND, real_bundles  # noqa: F401  (the exports, done in the background; a fixture)

from planner import make_plan, plan_statistics, resolve_product
from planner.assembly.feasibility import interlocked_pairs
from planner.assembly import statistics_within
from planner.assembly.hierarchy import (
    TOP,
    ConstraintViolationError,
    level_statistics,
    product_levels,
    select_level,
)
from planner.assembly.subassembly_proposals import propose_subassemblies, with_subassemblies
from planner.errors import PlannerError, ProductFormatError
from planner.product import (
    Direction,
    Markers,
    Obstruction,
    OperationTag,
    Part,
    Product,
    Subassembly,
    TechnicalConstraint,
    Tool,
    load_product,
    product_from_dict,
    product_to_dict,
    save_product,
)
from planner.product.synthetic import chain_product, complete_product


def _chain(n: int) -> dict:
    """Chain formulas (tests/product/test_synthetic.py): AND/OR nodes, operations, states, state edges,
    intentions, sequences of a chain of n parts."""
    return {"subassemblies": n * (n + 1) // 2, "operations": comb(n + 1, 3), "states": 2 ** (n - 1),
            "state_edges": (n - 1) * 2 ** (n - 2) if n > 1 else 0,
            "intentions": sum(comb(n - 1, j) * factorial(j) for j in range(n)), "sequences": factorial(n - 1)}


def _figures(stats) -> dict:
    return {k: getattr(stats, k) for k in ("subassemblies", "operations", "states", "state_edges", "intentions",
                                           "sequences")}


def two_chains(a: int = 3, b: int = 3) -> Product:
    """A chain a1..aA and a chain b1..bB, joined by one contact aA-b1, each a subassembly."""
    parts = tuple(Part(f"a{i}") for i in range(1, a + 1)) + tuple(Part(f"b{i}") for i in range(1, b + 1))
    contacts = tuple((f"a{i}", f"a{i + 1}") for i in range(1, a)) + tuple((f"b{i}", f"b{i + 1}") for i in range(1, b))
    groups = (Subassembly("A", tuple(f"a{i}" for i in range(1, a + 1))),
              Subassembly("B", tuple(f"b{i}" for i in range(1, b + 1))))
    return Product(parts, contacts + ((f"a{a}", "b1"),), subassemblies=groups, name="two chains")


# ---------------------------------------------------------------------------------------------- levels


@pytest.mark.parametrize("a, b", [(3, 3), (4, 2), (5, 3)])
def test_two_chains_levels_and_counts_by_the_chain_formulas(a, b):
    levels = product_levels(two_chains(a, b))
    assert [level.id for level in levels] == ["A", "B", TOP]
    assert levels[2].members == ("A", "B") and levels[2].product.contacts == (("A", "B"),)
    assert levels[0].parts == frozenset(f"a{i}" for i in range(1, a + 1))
    for level, n in zip(levels, (a, b, 2)):
        _, stats = statistics_within(level.product)
        assert _figures(stats) == _chain(n), level.id
    # Flat, the same product is a chain of a + b parts: far more of everything.
    _, flat = statistics_within(replace(two_chains(a, b), subassemblies=()))
    assert _figures(flat) == _chain(a + b)


def test_nested_subassemblies_are_planned_inner_first():
    # Three chains of 3: A and B joined into AB, then AB and C at the top.
    parts = tuple(Part(f"{c}{i}") for c in "abc" for i in (1, 2, 3))
    contacts = tuple((f"{c}{i}", f"{c}{i + 1}") for c in "abc" for i in (1, 2)) + (("a3", "b1"), ("b3", "c1"))
    groups = (Subassembly("AB", ("A", "B")), Subassembly("A", ("a1", "a2", "a3")),
              Subassembly("B", ("b1", "b2", "b3")), Subassembly("C", ("c1", "c2", "c3")))
    levels = product_levels(Product(parts, contacts, subassemblies=groups))
    order = [level.id for level in levels]
    assert order.index("A") < order.index("AB") and order.index("B") < order.index("AB") and order[-1] == TOP
    ab = select_level(Product(parts, contacts, subassemblies=groups), "AB")
    assert ab.members == ("A", "B") and ab.parts == frozenset(p.id for p in parts[:6])
    assert levels[-1].members == ("AB", "C") and levels[-1].product.contacts == (("AB", "C"),)


def test_one_subassembly_holding_everything_has_no_top_level():
    product = replace(chain_product(4), subassemblies=(Subassembly("all", ("p1", "p2", "p3", "p4")),))
    assert [level.id for level in product_levels(product)] == ["all"]


def test_members_are_blocked_when_any_of_their_parts_is():
    # Chain x - a1 - a2 - y; A = {a1, a2}. Along +X a2 hits y; along +Z x hits a1 and a1 hits x: at the top,
    # A moving +X hits y, and x and A block each other along Z.
    parts = tuple(Part(p) for p in ("x", "a1", "a2", "y"))
    x, z = Direction.from_vector((1.0, 0.0, 0.0)), Direction.from_vector((0.0, 0.0, 1.0))
    product = Product(parts, (("x", "a1"), ("a1", "a2"), ("a2", "y")),
                      (Obstruction(x, (("a2", "y"), ("a1", "a2"))), Obstruction(z, (("x", "a1"), ("a1", "x")))),
                      subassemblies=(Subassembly("A", ("a1", "a2")),))
    inner, top = product_levels(product)
    assert inner.product.obstructions[0].blocks == (("a1", "a2"),) and inner.product.obstructions[1].blocks == ()
    assert top.members == ("x", "y", "A")
    assert set(top.product.contacts) == {("x", "A"), ("A", "y")}
    assert top.product.obstructions[0].blocks == (("A", "y"),)
    assert top.product.obstructions[1].blocks == (("x", "A"), ("A", "x"))


def test_constraints_and_tags_are_restricted_to_the_level():
    parts = tuple(Part(p) for p in ("h", "i", "c", "b"))
    constraints = (TechnicalConstraint(frozenset({"i", "c"}), "h"),  # inside A: kept there
                   TechnicalConstraint(frozenset({"b"}), "h"),       # across the levels: kept at the top, on A
                   TechnicalConstraint(frozenset({"h"}), "i"))       # settled inside A: dropped at the top
    tags = (OperationTag((frozenset({"h"}), frozenset({"i"})), unfavorable=True),
            OperationTag((frozenset({"b"}), frozenset({"c", "h", "i"})), robot=False),
            OperationTag((frozenset({"b"}), frozenset({"c"})), robot=False))  # c is inside A: no such operation above
    product = Product(parts, (("h", "i"), ("i", "c"), ("c", "b")), technical_constraints=constraints,
                      operations=tags, subassemblies=(Subassembly("A", ("h", "i", "c")),))
    inner, top = product_levels(product)
    assert [c.parts for c in inner.product.technical_constraints] == [frozenset({"i", "c"}), frozenset({"h"})]
    assert [(c.parts, c.requires) for c in top.product.technical_constraints] == [(frozenset({"b"}), "A")]
    assert [t.inputs for t in inner.product.operations] == [(frozenset({"h"}), frozenset({"i"}))]
    assert [t.inputs for t in top.product.operations] == [(frozenset({"b"}), frozenset({"A"}))]


def test_the_pen_is_one_level_and_unchanged(pen):
    assert product_levels(pen) == [product_levels(pen)[0]] and product_levels(pen)[0].product is pen
    assert with_subassemblies(pen, "auto") is pen  # 6 parts: nothing to propose
    assert with_subassemblies(pen, "none") is pen


def test_select_level_errors_name_the_levels():
    with pytest.raises(PlannerError, match="3 subassemblies .*: A, B, top; pick one with --level ID"):
        select_level(two_chains(), None)
    with pytest.raises(PlannerError, match="--level C: no such subassembly; the levels are A, B, top"):
        select_level(two_chains(), "C")


# ---------------------------------------------------------------------------------------------- the format


def test_round_trip(tmp_path):
    product = two_chains()
    save_product(product, tmp_path / "p.json")
    again = load_product(tmp_path / "p.json")
    assert again == product and again.subassemblies[0] == Subassembly("A", ("a1", "a2", "a3"), "", "designer")


@pytest.mark.parametrize("groups, location, fragment", [
    ([{"id": "A", "parts": ["a1", "B"]}, {"id": "B", "parts": ["a2", "A"]}], r"subassemblies\[0\]",
     "cycle: A in B in A"),
    ([{"id": "A", "parts": ["a1", "a2"]}, {"id": "B", "parts": ["a2", "a3"]}], r"subassemblies\[1\]\.parts\[0\]",
     "'a2' is in two subassemblies: 'A' and 'B'"),
    ([{"id": "A", "parts": ["a1", "a9"]}], r"subassemblies\[0\]\.parts\[1\]", "'a9' is neither a part nor"),
    ([{"id": "a1", "parts": ["a2", "a3"]}], r"subassemblies\[0\]\.id", "also a part or tool id"),
    ([{"id": "A", "parts": ["a1", "a2"]}, {"id": "A", "parts": ["b1", "b2"]}], r"subassemblies\[1\]\.id",
     "duplicate subassembly id 'A'"),
    ([{"id": "A", "parts": ["a1"]}], r"subassemblies\[0\]\.parts", "at least 2 items|two or more"),
    ([{"id": "top", "parts": ["a1", "a2"]}], r"subassemblies\[0\]\.id", "'top' names the top level"),
])
def test_bad_trees_name_the_parts(groups, location, fragment):
    doc = product_to_dict(replace(two_chains(), subassemblies=()))
    doc["subassemblies"] = groups
    with pytest.raises(ProductFormatError, match=location) as info:
        product_from_dict(doc, "x.json")
    assert re.search(fragment, str(info.value)), str(info.value)


def test_a_cycle_above_a_subassembly_is_found_from_its_members():
    # C is in A, A in B, B in A: the walk up from C must not loop forever.
    doc = product_to_dict(replace(two_chains(), subassemblies=()))
    doc["subassemblies"] = [{"id": "C", "parts": ["a1", "a2"]}, {"id": "A", "parts": ["C", "B"]},
                            {"id": "B", "parts": ["A", "b1"]}]
    with pytest.raises(ProductFormatError, match="cycle"):
        product_from_dict(doc)


# ---------------------------------------------------------------------------------------------- proposals


def _check_proposal(product: Product, max_components: int) -> list:
    groups = propose_subassemblies(product, max_components)
    arranged = replace(product, subassemblies=groups)  # constructing it checks the tree
    levels = product_levels(arranged)
    held = [m for level in levels for m in level.members if m in product.part_ids]
    assert sorted(held) == sorted(product.part_ids)  # every part in exactly one level
    for level in levels:
        assert 2 <= len(level.members) <= max_components, level.id
        statistics_within(level.product)  # connected and buildable: raises otherwise
    return levels


@pytest.mark.parametrize("n, cap", [(8, 8), (9, 8), (20, 8), (20, 3), (30, 2)])
def test_chains_are_cut_into_workstations(n, cap):
    product = chain_product(n)
    levels = _check_proposal(product, cap) if n > cap else product_levels(product)
    # Each level of k members removes k - 1 of the n - 1 joins: at least (n - 1) / (cap - 1) levels, exactly
    # n - 1 with two members each.
    assert len(levels) >= -(-(n - 1) // (cap - 1))
    assert len(levels) == n - 1 if cap == 2 else True
    assert (n <= cap) == (len(levels) == 1)


@pytest.mark.parametrize("n, cap", [(12, 8), (10, 4)])
def test_complete_graphs_are_cut_into_workstations(n, cap):
    _check_proposal(complete_product(n), cap)


def test_proposed_ids_avoid_part_ids():
    product = Product(tuple(Part(p) for p in ("sa1", "sa2", "x", "y")), (("sa1", "sa2"), ("sa2", "x"), ("x", "y")))
    groups = propose_subassemblies(product, 2)
    assert {g.id for g in groups}.isdisjoint(product.part_ids) and all(g.source == "proposed" for g in groups)


def test_a_group_that_cannot_be_built_alone_is_reported_with_its_parts(caplog):
    # A chain of 10 where p01 and p02 block each other in every direction: no group holding both can be built.
    base = chain_product(10)
    pairs = (("p01", "p02"), ("p02", "p01"))
    axes = [Direction.from_vector(v) for v in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))]
    product = replace(base, obstructions=tuple(Obstruction(d, pairs) for d in axes))
    with caplog.at_level(logging.WARNING, logger="planner.assembly.hierarchy"):
        propose_subassemblies(product, 8)
    assert "cannot be built on its own" in caplog.text and "p01 and p02" in caplog.text  # an interlocked pair


def test_a_stuck_group_is_merged_with_the_neighbour_that_makes_it_buildable(caplog):
    # Chain p01..p10, max 4: the agglomeration gives {p01..p04}, {p05..p08}, {p09, p10}; but p09 and p10 may
    # only be together with p08 (a technical constraint), so {p09, p10} cannot be built alone and is merged
    # with {p05..p08} (6 members, within 1.5 x 4).
    base = chain_product(10)
    product = replace(base, technical_constraints=(TechnicalConstraint(frozenset({"p09", "p10"}), "p08"),))
    with caplog.at_level(logging.WARNING, logger="planner.assembly.hierarchy"):
        groups = propose_subassemblies(product, 4)
    assert [g.parts for g in groups] == [("p01", "p02", "p03", "p04"), ("p05", "p06", "p07", "p08", "p09", "p10")]
    assert "cannot be built" not in caplog.text
    # Without the constraint, the same chain gives three groups.
    assert len(propose_subassemblies(base, 4)) == 3


def test_a_subassembly_that_breaks_a_technical_constraint_is_named():
    # A = {p09, p10}, but p09 and p10 may only be together with p08.
    product = replace(chain_product(10), subassemblies=(Subassembly("A", ("p09", "p10")),),
                      technical_constraints=(TechnicalConstraint(frozenset({"p09", "p10"}), "p08"),))
    with pytest.raises(ConstraintViolationError, match="subassembly A .* holds p09, p10 without p08"):
        select_level(product, "A")
    found = {level.id: stats for level, stats in level_statistics(product)}
    assert isinstance(found["A"], ConstraintViolationError) and found[TOP].sequences is not None
    # Switched off, it binds nothing.
    assert not isinstance({lv.id: st for lv, st in level_statistics(product, technical=False)}["A"],
                          PlannerError)


def test_built_subassemblies_get_free_markers():
    product = replace(two_chains(), markers=Markers(tuple((p, k) for k, p in enumerate(("a1", "a2", "a3", "b1",
                                                                                       "b2", "b3"))) + (("t", 7),)),
                      tools=(Tool("t"),))
    inner, _, top = product_levels(product)
    assert dict(inner.product.markers.ids) == {"a1": 0, "a2": 1, "a3": 2, "t": 7}
    assert dict(top.product.markers.ids) == {"A": 6, "B": 8, "t": 7}  # 6 and 8: the first ids no one has


# -------------------------------------------------------------------------------------- with fasteners


def test_a_screw_between_two_subassemblies_is_driven_where_they_join():
    """Chains a1-a2-a3 and b1-b2-b3 held together only by the screw s (it touches a3 and b1): the chains are
    planned without it (2 sequences each), and the top level joins A and B installing s, with the
    screwdriver, in its one operation."""
    from planner import make_plan
    from planner.product import FastenerGroup, Tool

    base = two_chains()
    contacts = tuple(c for c in base.contacts if set(c) != {"a3", "b1"}) + (("s", "a3"), ("s", "b1"))
    product = replace(base, parts=base.parts + (Part("s"),), contacts=contacts, tools=(Tool("screwdriver"),),
                      fasteners=(FastenerGroup("screws", ("s",), tool="screwdriver"),))
    levels = {level.id: level for level in product_levels(product)}
    assert list(levels) == ["A", "B", TOP]
    assert "s" not in levels["A"].members and "s" not in levels["B"].members
    top = levels[TOP].product
    assert sorted(top.part_ids) == ["A", "B", "s"]
    assert [(g.id, sorted(g.hosts)) for g in top.fasteners] == [("screws", ["A", "B"])]
    plan = make_plan(top)
    # At the top level the built chains are single parts in the tray: the operator picks both, the screw and
    # the screwdriver.
    assert [str(o) for o in plan.observations if "s" in str(o)] == ["A+B+s+[screwdriver]"]
    from planner import plan_statistics

    figures = {level.id: plan_statistics(make_plan(level.product)) for level in product_levels(product)}
    assert [(figures[k].subassemblies, figures[k].sequences) for k in ("A", "B", TOP)] == [(6, 2), (6, 2), (3, 1)]


def test_proposed_subassemblies_leave_fasteners_out():
    """A chain of 8 with a screw on every contact: the proposal groups the 8 parts only (the screws are no
    members), and every screw is installed at the level where its two parts come together."""
    from planner.product import FastenerGroup

    chain = chain_product(8)
    screws = tuple(Part(f"s{i}") for i in range(1, 8))
    contacts = tuple(c for i, (a, b) in enumerate(chain.contacts) for c in ((f"s{i + 1}", a), (f"s{i + 1}", b)))
    product = replace(chain, parts=chain.parts + screws, contacts=contacts,
                      fasteners=tuple(FastenerGroup(f"g{i}", (f"s{i}",)) for i in range(1, 8)))
    proposed = propose_subassemblies(product, 4)
    members = {m for group in proposed for m in group.parts}
    assert members and not members & {p.id for p in screws}
    levels = product_levels(replace(product, subassemblies=proposed))
    installed = [g.id for level in levels for g in level.product.fasteners]
    assert sorted(installed) == [f"g{i}" for i in range(1, 8)]   # each screw once, somewhere


def test_groups_that_would_block_each_other_once_built_are_merged():
    """A chain of 9, at most 3 members: the first round pairs {p1, p2}, {p3, p4}, {p5, p6} and takes {p7, p8,
    p9}. Along +X (the only direction) p1 hits p3 and p4 hits p2: no two parts block each other, but built,
    {p1, p2} and {p3, p4} would (each hits the other), so no level above could take them apart. They are
    merged into one group of 4 (past the cap: a larger workstation rather than a product that cannot be
    taken apart), and every level can be built."""
    chain = chain_product(9)
    along_x = Obstruction(Direction.from_vector((1.0, 0.0, 0.0)), (("p1", "p3"), ("p4", "p2")))
    product = replace(chain, obstructions=(along_x,))
    proposed = propose_subassemblies(product, 3)
    assert ("p1", "p2", "p3", "p4") in [tuple(sorted(g.parts)) for g in proposed]
    for level in product_levels(replace(product, subassemblies=proposed)):
        assert plan_statistics(make_plan(level.product)).sequences >= 1
    # Without the relations the first round keeps the pairs.
    assert [("p1", "p2"), ("p3", "p4")] == [tuple(g.parts) for g in propose_subassemblies(chain, 3)][:2]


def test_groups_too_large_to_merge_are_peeled_instead():
    """A chain of 9, at most 4 members: the first round gives {p1..p4}, {p5, p6}, {p7, p8, p9}. Along +X p2 hits
    p8 and p8 hits p3: built, {p1..p4} and {p7, p8, p9} would block each other, and their union (7 members) is
    past 1.5 x 4. Taking p2 out (the first member whose removal leaves no interlocked pair) splits its group
    into {p1} and {p3, p4}; every level can be built and none passes the cap (merged, one would hold 7)."""
    chain = chain_product(9)
    along_x = Obstruction(Direction.from_vector((1.0, 0.0, 0.0)), (("p2", "p8"), ("p8", "p3")))
    product = replace(chain, obstructions=(along_x,))
    proposed = propose_subassemblies(product, 4)
    assert ("p3", "p4") in [g.parts for g in proposed] and ("p7", "p8", "p9") in [g.parts for g in proposed]
    levels = product_levels(replace(product, subassemblies=proposed))
    for level in levels:
        assert len(level.members) <= 4, level.id
        assert plan_statistics(make_plan(level.product)).sequences >= 1, level.id
    # the same groups without the relations: the first round is kept as it is
    assert [g.parts for g in propose_subassemblies(chain, 4)][:3] == [("p1", "p2", "p3", "p4"), ("p5", "p6"),
                                                                      ("p7", "p8", "p9")]


@pytest.mark.freecad
def test_the_pump_plans_at_every_level_in_workstations_of_at_most_eight(real_bundles):  # noqa: F811
    """The diaphragm pump exported with the defaults, its overlapping pair 21_001 / 26_001 (1,434 mm^3 shared in
    the model) resolved by the interlock rules (inserted along the overlap's axis: no flag), its fasteners
    proposed: every proposed level plans, none holds more than 8 members besides its fasteners (the long bolts
    13_* fold: before, the body's workstation held them and had 11), and the 24 fasteners are installed where
    their hosts meet. At other workstation sizes no level is interlocked either."""
    resolved = resolve_product(load_product(real_bundles["diaphragm_pump"] / "product.json"), fasteners="auto")
    decisions = resolved.geometry["analysis"]["interlocks"]
    assert {frozenset(d["parts"]) for d in decisions} == {frozenset(p) for p in [("1_001", "8_002"), ("1_001", "8_007"),
                                                                                  ("21_001", "26_001")]}
    assert {d["rule"] for d in decisions} == {"overlap"}
    for cap in (4, 6, 10):
        for level in product_levels(with_subassemblies(resolved, "auto", cap)):
            assert interlocked_pairs(level.product) == [], (cap, level.id)
    product = with_subassemblies(resolved, "auto")
    installed = set()
    for level, figures in level_statistics(product):
        fasteners = {p for group in level.product.fasteners for p in group.parts}
        installed |= fasteners
        assert not isinstance(figures, PlannerError), (level.id, figures)
        assert figures.sequences >= 1 and len(set(level.members) - fasteners) <= 8, level.id
    assert {f"13_00{k}" for k in range(1, 5)} <= installed and len(installed) == 32   # 24 fasteners, 8 fittings



def test_a_single_member_interlocked_with_a_group_joins_it_once():
    """Built, {p1, p2, p3} and p4 block each other along every axis (along X p1 hits p4 and p4 hits p2, and so
    on), though no two parts do: the single member p4 is merged into the group (4 members, within 1.5 x 3),
    and appears once."""
    from planner.assembly.subassembly_proposals import _separable_groups

    axes = [Direction.from_vector(v) for v in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))]
    blocks = [(("p1", "p4"), ("p4", "p2")), (("p2", "p4"), ("p4", "p3")), (("p3", "p4"), ("p4", "p1"))]
    product = replace(chain_product(6), obstructions=tuple(Obstruction(a, b) for a, b in zip(axes, blocks)))
    groups = _separable_groups(product, [], [["p1", "p2", "p3"], ["p4"], ["p5", "p6"]], product, 3)
    assert sorted(sorted(g) for g in groups) == [["p1", "p2", "p3", "p4"], ["p5", "p6"]]
