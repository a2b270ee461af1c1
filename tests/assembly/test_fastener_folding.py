"""Folded fasteners in the plan: closed-form counts, the installing operations, their tool and observation."""
from __future__ import annotations

from dataclasses import replace

import pytest

from planner import and_or_graph, intention_graph, make_plan, plan_statistics, resolve_product
from planner.assembly.stats import statistics_within
from planner.assembly.tags import fastener_installs
from planner.product import FastenerGroup, OperationTag, Part, Product, Tool, fold, with_fastener_mode
from planner.product.synthetic import chain_product, fastened_product

# The pen's figures (tests/assembly/test_plan.py): folding must not change them.
PEN_FIGURES = {
    False: dict(parts=6, contacts=5, complexity=1.67, subassemblies=18, operations=21, actions=22, states=18,
                state_edges=32, intentions=69, observations=12, sequences=24),
    True: dict(parts=6, contacts=5, complexity=1.67, subassemblies=17, operations=17, actions=18, states=14,
               state_edges=21, intentions=39, observations=10, sequences=12),
}


def screwed_chain(screws: int = 1) -> Product:
    """The chain p1-p2-p3 and ``screws`` screws touching p1 and p2, in one group needing a screwdriver."""
    chain = chain_product(3)
    names = tuple(f"screw_{k}" for k in range(1, screws + 1))
    contacts = chain.contacts + tuple((p, s) for s in names for p in ("p1", "p2"))
    return Product(chain.parts + tuple(Part(s) for s in names), contacts, tools=(Tool("screwdriver"),),
                   fasteners=(FastenerGroup("screws", names, tool="screwdriver"),))


def _installed(plan) -> dict[str, tuple[str, ...]]:
    return {plan.andor.describe(j): tuple(sorted(plan.andor.parts_of(c) for c in plan.andor.operations[j].children))
            for k in range(len(plan.fasteners)) for j in plan.installs[k].tolist()}


def test_a_screwed_chain_of_three_counts_as_the_chain_of_three():
    plan = make_plan(screwed_chain(1))
    folded = plan_statistics(plan).as_dict()
    chain = plan_statistics(make_plan(chain_product(3))).as_dict()
    assert folded == chain
    # the closed forms of a chain of n = 3 (planner.product.synthetic)
    assert (folded["subassemblies"], folded["operations"], folded["states"], folded["sequences"]) == (6, 4, 4, 2)
    by_inputs = {plan.andor.describe(j): (plan.tags.tool[j], str(plan.observations[plan.operation_observation[j]]))
                 for j in range(len(plan.andor.operations))}
    assert by_inputs == {"{p1} + {p2}": ("screwdriver", "p1+p2+screw_1+[screwdriver]"),
                         "{p1} + {p2, p3}": ("screwdriver", "p1+screw_1+[screwdriver]"),
                         "{p1, p2} + {p3}": (None, "p3"),
                         "{p2} + {p3}": (None, "p2+p3")}


def test_four_screws_are_one_group_installed_once_per_sequence():
    plan = make_plan(screwed_chain(4))
    stats = plan_statistics(plan)
    assert stats.parts == 3 and stats.folded_parts == 4 and stats.installs == (2,)
    assert sorted(_installed(plan)) == ["{p1} + {p2, p3}", "{p1} + {p2}"]
    (group,) = plan.fasteners
    observation = plan.observations[plan.operation_observation[plan.installs[0][0]]]
    assert set(group.parts) <= set(observation.parts) and observation.tool == "screwdriver"
    graph = intention_graph(plan.states)
    for intention in graph.full_sequences().tolist():
        installing = [j for j in graph.operations(intention) if j in set(plan.installs[0].tolist())]
        assert len(installing) == 1


@pytest.mark.parametrize("screws", [1, 2, 3, 5])
def test_each_screw_doubles_the_subassemblies_unless_folded(screws):
    product = fastened_product(2, screws)
    unfolded = plan_statistics(make_plan(product)).subassemblies
    assert unfolded == 3 * 2 ** screws + screws  # the closed form of planner.product.synthetic
    names = tuple(p for p in product.part_ids if p.startswith("screw"))
    folded = plan_statistics(make_plan(replace(product, fasteners=(FastenerGroup("all", names),))))
    assert (folded.parts, folded.subassemblies, folded.operations, folded.installs) == (2, 3, 1, (1,))


def test_three_hosts_installed_where_they_first_come_together():
    # a bracket bolt touching p1, p2 and p3 of a chain p1-p2-p3-p4
    chain = chain_product(4)
    product = Product(chain.parts + (Part("bolt"),), chain.contacts + tuple((p, "bolt") for p in ("p1", "p2", "p3")),
                      fasteners=(FastenerGroup("bracket", ("bolt",)),))
    plan = make_plan(product)
    hosts = frozenset({"p1", "p2", "p3"})
    expected = {j for j in range(len(plan.andor.operations))
                if hosts <= (plan.andor.inputs(j)[0] | plan.andor.inputs(j)[1])
                and not hosts <= plan.andor.inputs(j)[0] and not hosts <= plan.andor.inputs(j)[1]}
    assert set(plan.installs[0].tolist()) == expected and expected
    assert plan.product.contacts[-1] == ("p1", "p3")  # the bolt is the liaison of p1 and p3, which do not touch
    liaison = Product(chain.parts, chain.contacts + (("p1", "p3"),))
    assert plan_statistics(plan).as_dict() == plan_statistics(make_plan(liaison)).as_dict() | {
        "observations": plan_statistics(plan).observations}
    graph = intention_graph(plan.states)
    for intention in graph.full_sequences().tolist():
        assert sum(j in expected for j in graph.operations(intention)) == 1


def test_an_operation_tag_wins_over_the_group_tool():
    product = screwed_chain(1)
    product = replace(product, tools=product.tools + (Tool("drill"),),
                      operations=(OperationTag((frozenset({"p1"}), frozenset({"p2"})), tool="drill"),))
    plan = make_plan(product)
    tools = {plan.andor.describe(j): plan.tags.tool[j] for j in range(len(plan.andor.operations))}
    assert tools["{p1} + {p2}"] == "drill" and tools["{p1} + {p2, p3}"] == "screwdriver"


def test_fastener_modes_and_statistics_within():
    product = screwed_chain(2)
    none = plan_statistics(make_plan(with_fastener_mode(product, "none")))
    assert none.parts == 5 and none.fasteners == ()
    plan, stats = statistics_within(product)
    assert stats.parts == 3 and stats.installs == (2,) and plan.designed == product


def test_the_pen_is_unchanged(pen):
    for mode in ("tagged", "auto", "none"):
        for technical in (False, True):
            stats = plan_statistics(make_plan(resolve_product(pen, mode), technical))
            assert stats.as_dict() == PEN_FIGURES[technical] and stats.fasteners == ()


def test_many_parts_and_many_groups():
    """Past 62 parts or groups the bitmasks are Python integers: a chain of 64 parts and a screw joining the
    last two is installed by the 63 splits of an interval [p_i, p_64] between p63 and p64; 70 groups on one
    joint are installed by its one operation, all 70 screws seen."""
    chain = chain_product(64)
    last, before = chain.part_ids[-1], chain.part_ids[-2]
    product = Product(chain.parts + (Part("screw"),), chain.contacts + ((before, "screw"), (last, "screw")),
                      fasteners=(FastenerGroup("g", ("screw",)),))
    folding = fold(product)
    andor = and_or_graph(folding.product)
    (installs,) = fastener_installs(andor, folding.groups)
    assert len(installs) == 63
    for j in installs.tolist():  # p63 in one input, p64 in the other
        first, second = andor.inputs(j)
        assert {before, last} <= first | second and (before in first) != (last in first)
    screws = tuple(f"s{k:02d}" for k in range(70))
    product = Product((Part("a"), Part("b")) + tuple(Part(s) for s in screws),
                      (("a", "b"),) + tuple((p, s) for s in screws for p in ("a", "b")),
                      fasteners=tuple(FastenerGroup(s, (s,)) for s in screws))
    plan = make_plan(product)
    assert len(plan.andor.operations) == 1 and len(plan.installs) == 70
    assert plan.observations[plan.operation_observation[0]].parts == ("a", "b") + screws
