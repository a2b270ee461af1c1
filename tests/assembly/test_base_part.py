"""The base part (paper Sec. V): the sequences that start from it and their intentions, counted in closed form
and enumerated by Alg. 2, against brute force over the paths of the assembly state graph (networkx)."""
from __future__ import annotations

from math import comb, factorial

import networkx as nx
import pytest
from test_properties import merge_orders, stirling2

from planner import PlannerError, chain_product, complete_product, count_intentions, count_sequences, make_plan
from planner.assembly import base_part_first_edges, intention_graph


def _brute_force(states, base_part):
    """(allowed full sequences, restricted intentions) as sets of state paths: a full sequence is allowed when its
    first operation's result holds the base part; the intentions are every suffix of an allowed sequence."""
    graph = states.to_networkx()
    andor = states.andor
    bit = 1 << andor.parts.index(base_part)
    if states.initial == states.final:
        sequences = {(states.final,)}
    else:
        sequences = {tuple(path) for path in nx.all_simple_paths(graph, states.initial, states.final)
                     if andor.subassemblies[andor.operations[graph.edges[path[0], path[1]]["operation"]].parent] & bit}
    intentions = {path[k:] for path in sequences for k in range(len(path))}
    return sequences, intentions


def _products(pen):
    return [("pen", make_plan(pen)), ("pen-technical", make_plan(pen, True)), ("pen-free", make_plan(pen, False)),
            ("chain1", make_plan(chain_product(1))), ("chain2", make_plan(chain_product(2))),
            ("chain5", make_plan(chain_product(5))), ("complete4", make_plan(complete_product(4))),
            ("complete5", make_plan(complete_product(5)))]


def test_counts_and_graph_match_brute_force(pen):
    checked = 0
    for name, plan in _products(pen):
        states = plan.states
        for part in plan.andor.parts:
            sequences, intentions = _brute_force(states, part)
            assert count_sequences(states, part) == len(sequences), (name, part)
            assert count_intentions(states, base_part=part) == len(intentions), (name, part)
            if not sequences:
                with pytest.raises(PlannerError, match="no assembly sequence starts from the base part"):
                    intention_graph(states, base_part=part)
                continue
            graph = intention_graph(states, base_part=part)
            paths = [tuple(graph.path(i)) for i in range(graph.n_intentions)]
            assert set(paths) == intentions and len(paths) == len(intentions), (name, part)
            assert {paths[i] for i in graph.full_sequences()} == sequences
            assert graph.base_part == part and graph.successor[0] == -1 and paths[0] == (states.final,)
            for i in range(1, graph.n_intentions):  # a tree: each intention's successor is its path after one step
                assert paths[int(graph.successor[i])] == paths[i][1:]
                assert states.edge_source[graph.step_edge[i]] == paths[i][0]
            checked += 1
    assert checked > 20


def test_numbering_keeps_the_unrestricted_order(pen):
    """The restricted graph lists its intentions in the order of the unrestricted one (by length, then Alg. 2)."""
    states = make_plan(pen).states
    whole = intention_graph(states)
    order = {tuple(whole.path(i)): i for i in range(whole.n_intentions)}
    restricted = intention_graph(states, base_part="body")
    positions = [order[tuple(restricted.path(i))] for i in range(restricted.n_intentions)]
    assert positions == sorted(positions) and positions[0] == 0


def test_pen_figures_by_hand(pen):
    """The pen (no technical constraints): 24 sequences; the first operation joins two of its 6 parts, and the
    sequences starting from each part add up to twice the total."""
    states = make_plan(pen, False).states
    per_part = {p: count_sequences(states, p) for p in pen.part_ids}
    assert sum(per_part.values()) == 2 * 24
    assert count_intentions(states) == 69 and count_intentions(states, base_part=None) == 69


def test_a_base_part_that_is_not_a_part(pen):
    states = make_plan(pen).states
    for call in (lambda: count_sequences(states, "lid"), lambda: count_intentions(states, base_part="lid"),
                 lambda: intention_graph(states, base_part="lid"), lambda: base_part_first_edges(states, "lid")):
        with pytest.raises(PlannerError, match=r"base part 'lid' is not a part of the product; parts: .*body"):
            call()


def test_restricted_limit_counts_the_restricted_intentions(pen):
    states = make_plan(pen, False).states
    total = count_intentions(states, base_part="body")
    assert total < 69
    with pytest.raises(PlannerError, match=f"{total} would be enumerated"):
        intention_graph(states, limit=total - 1, base_part="body")
    assert intention_graph(states, limit=total, base_part="body").n_intentions == total


@pytest.mark.parametrize("n", range(2, 11))
def test_chain_closed_form(n):
    """Chain p1..pn: a state is the set of links joined, and N(state with m links) = (n-1-m)!. The base part pj has d
    links (1 at the ends, else 2): d (n-2)! sequences start from it, and the reachable states are those that join
    at least one of its links: C(n-1, m) - C(n-1-d, m) of them with m links."""
    states = make_plan(chain_product(n)).states
    parts = states.andor.parts
    for j, part in enumerate(parts):
        d = (j > 0) + (j < n - 1)
        sequences = d * factorial(n - 2)
        reachable = sum((comb(n - 1, m) - comb(n - 1 - d, m)) * factorial(n - 1 - m) for m in range(1, n))
        assert count_sequences(states, part) == sequences
        assert count_intentions(states, base_part=part) == sequences + reachable


@pytest.mark.parametrize("n", range(2, 9))
def test_complete_closed_form(n):
    """Complete graph of n parts: a state with k blocks has M(k) = k!(k-1)!/2^(k-1) paths to the end; the first
    operation joins one of the C(n, 2) pairs, 2/n of them holding the base part; the reachable states are the set
    partitions where its block has two parts or more: S(n, k) - S(n-1, k-1) with k blocks."""
    states = make_plan(complete_product(n)).states
    sequences = 2 * merge_orders(n) // n
    reachable = sum((stirling2(n, k) - stirling2(n - 1, k - 1)) * merge_orders(k) for k in range(1, n + 1))
    for part in states.andor.parts[:2]:
        assert count_sequences(states, part) == sequences
        assert count_intentions(states, base_part=part) == sequences + reachable
