"""The assembly state graph (Alg. 1) and its map from state edges to operations."""
from __future__ import annotations

from planner import make_plan


def test_operation_map_of_the_state_graph(pen):
    plan = make_plan(pen)
    states, andor = plan.states, plan.andor
    for s, t, o in zip(states.edge_source, states.edge_target, states.edge_operation):
        before, after = set(states.subassemblies_of(s)), set(states.subassemblies_of(t))
        op = andor.operations[o]
        assert before - after == set(op.children) and after - before == {op.parent}
