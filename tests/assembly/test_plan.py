"""A product's plan and its figures: the pen against the paper, the authors' code and a literal reference."""
from __future__ import annotations

import pytest
import reference

from planner import (
    and_or_graph,
    assembly_state_graph,
    count_sequences,
    intention_graph,
    make_plan,
    most_connected_part,
    plan_statistics,
)

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
