"""The intention graph (Alg. 2): a tree with its operation map, and the enumeration limit."""
from __future__ import annotations

import numpy as np
import pytest

from planner import LimitExceededError, intention_graph, make_plan


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
