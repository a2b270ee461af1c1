"""AND/OR graph, assembly state graph and intentions of the pen: the paper's figures and the authors' code."""
from __future__ import annotations

import numpy as np
import pytest
import reference

from planner import (
    DisconnectedProductError,
    LimitExceededError,
    NotDisassemblableError,
    Obstruction,
    Part,
    Product,
    and_or_graph,
    assembly_state_graph,
    count_intentions,
    count_sequences,
    intention_graph,
    make_plan,
    most_connected_part,
    plan_statistics,
)
from planner.product import AXIS_DIRECTIONS, Direction, TechnicalConstraint

PEN = {
    False: dict(parts=6, contacts=5, complexity=1.67, subassemblies=18, operations=21, actions=22, states=18,
                state_edges=32, intentions=69, observations=12, sequences=24),
    True: dict(parts=6, contacts=5, complexity=1.67, subassemblies=17, operations=17, actions=18, states=14,
               state_edges=21, intentions=39, observations=10, sequences=12),
}


@pytest.mark.parametrize("technical", [False, True])
def test_pen_figures(pen, technical):
    assert plan_statistics(make_plan(pen, technical)).as_dict() == PEN[technical]


def test_pen_technical_constraint_is_off_by_default(pen):
    assert plan_statistics(make_plan(pen)).as_dict() == PEN[False]


@pytest.mark.parametrize("technical", [False, True])
def test_pen_matches_the_literal_reference(pen, technical):
    andor = and_or_graph(pen, technical)
    subassemblies, operations = reference.andor(pen, technical)
    assert {andor.parts_of(i) for i in range(len(andor.subassemblies))} == subassemblies
    assert {(andor.parts_of(op.parent), frozenset(andor.parts_of(c) for c in op.children))
            for op in andor.operations} == operations
    ref_states, ref_edges = reference.state_graph(subassemblies, operations)
    states = assembly_state_graph(andor)
    as_sets = [frozenset(andor.parts_of(b) for b in states.subassemblies_of(s)) for s in range(states.n_states)]
    assert set(as_sets) == ref_states and len(as_sets) == len(ref_states)
    mine = {(as_sets[s], as_sets[t], (andor.parts_of(andor.operations[o].parent),
                                       frozenset(andor.parts_of(c) for c in andor.operations[o].children)))
            for s, t, o in zip(states.edge_source, states.edge_target, states.edge_operation)}
    assert mine == ref_edges
    graph = intention_graph(states)
    paths = {tuple(as_sets[s] for s in graph.path(i)) for i in range(graph.n_intentions)}
    assert paths == reference.intentions(ref_states, ref_edges)


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


def test_operation_map_of_the_state_graph(pen):
    plan = make_plan(pen)
    states, andor = plan.states, plan.andor
    for s, t, o in zip(states.edge_source, states.edge_target, states.edge_operation):
        before, after = set(states.subassemblies_of(s)), set(states.subassemblies_of(t))
        op = andor.operations[o]
        assert before - after == set(op.children) and after - before == {op.parent}


def test_intention_graph_is_a_tree_with_operation_map(pen):
    plan = make_plan(pen)
    graph = intention_graph(plan.states)
    assert graph.n_intentions == 69 and graph.successor[0] == -1
    assert (graph.successor[1:] >= 0).all() and (graph.successor[1:] < np.arange(1, 69)).all()
    ops = graph.operation
    for i in range(1, graph.n_intentions):
        j = graph.successor[i]
        edge = graph.step_edge[i]
        assert plan.states.edge_source[edge] == graph.first_state[i]
        assert plan.states.edge_target[edge] == graph.first_state[j]
        assert ops[i] == plan.states.edge_operation[edge]
    assert len(graph.full_sequences()) == 24
    networkx_graph = graph.to_networkx()
    assert networkx_graph.number_of_edges() == 68


def test_enumeration_limit_states_the_count(pen):
    states = make_plan(pen).states
    with pytest.raises(LimitExceededError, match="intention graph: 69 would be enumerated, more than the limit of 68"):
        intention_graph(states, limit=68)
    assert intention_graph(states, limit=69).n_intentions == 69


def test_base_part(pen):
    assert most_connected_part(pen) == "body"
    states = make_plan(pen).states
    per_part = {p: count_sequences(states, p) for p in pen.part_ids}
    # Every sequence starts by joining two parts, so each is counted for exactly two base parts.
    assert sum(per_part.values()) == 2 * count_sequences(states)
    graph = intention_graph(states)
    first_ops = [graph.operation[i] for i in graph.full_sequences()]
    body_first = sum("body" in set().union(*plan_inputs) for plan_inputs in
                     (make_plan(pen).andor.inputs(o) for o in first_ops))
    assert per_part["body"] == body_first == 10


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
