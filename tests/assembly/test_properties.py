"""Property-based tests on random products: closed forms, reachability, monotonicity, the literal reference."""
from __future__ import annotations

from math import comb, factorial

import numpy as np
import reference
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner import (
    NotDisassemblableError,
    Obstruction,
    Part,
    Product,
    and_or_graph,
    assembly_state_graph,
    chain_product,
    complete_product,
    count_intentions,
    count_sequences,
    intention_graph,
)
from planner.product import AXIS_DIRECTIONS, Direction, TechnicalConstraint

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def stirling2(n: int, k: int) -> int:
    table = [[0] * (n + 1) for _ in range(n + 1)]
    table[0][0] = 1
    for i in range(1, n + 1):
        for j in range(1, i + 1):
            table[i][j] = j * table[i - 1][j] + table[i - 1][j - 1]
    return table[n][k]


def merge_orders(k: int) -> int:
    """Ways to merge k blocks pairwise into one, any pair at each step: k!(k-1)!/2^(k-1)."""
    return factorial(k) * factorial(k - 1) // 2 ** (k - 1)


def closed_form(kind: str, n: int) -> dict:
    if kind == "chain":
        return dict(subassemblies=n * (n + 1) // 2, operations=comb(n + 1, 3), states=2 ** (n - 1),
                    state_edges=(n - 1) * 2 ** (n - 2) if n > 1 else 0,
                    intentions=sum(comb(n - 1, j) * factorial(j) for j in range(n)), sequences=factorial(n - 1))
    return dict(subassemblies=2 ** n - 1, operations=(3 ** n + 1) // 2 - 2 ** n,
                states=sum(stirling2(n, k) for k in range(1, n + 1)),
                state_edges=sum(stirling2(n, k) * comb(k, 2) for k in range(1, n + 1)),
                intentions=sum(stirling2(n, k) * merge_orders(k) for k in range(1, n + 1)),
                sequences=merge_orders(n))


def figures(product: Product) -> dict:
    andor = and_or_graph(product)
    states = assembly_state_graph(andor)
    return dict(subassemblies=len(andor.subassemblies), operations=len(andor.operations), states=states.n_states,
                state_edges=states.n_edges, intentions=count_intentions(states), sequences=count_sequences(states))


@given(kind=st.sampled_from(["chain", "complete"]), n=st.integers(1, 8))
@SETTINGS
def test_synthetic_closed_forms(kind, n):
    product = (chain_product if kind == "chain" else complete_product)(n)
    assert figures(product) == closed_form(kind, n)


@st.composite
def products(draw, max_parts: int = 6):
    n = draw(st.integers(2, max_parts))
    names = [f"q{i}" for i in range(n)]
    # A random spanning tree keeps the liaison graph connected; extra edges on top.
    contacts = {frozenset((names[i], names[draw(st.integers(0, i - 1))])) for i in range(1, n)}
    pairs = [(a, b) for i, a in enumerate(names) for b in names[i + 1:]]
    contacts |= {frozenset(p) for p in draw(st.lists(st.sampled_from(pairs), max_size=n))}
    ordered = [(a, b) for a, b in pairs if frozenset((a, b)) in contacts]
    axes = draw(st.lists(st.sampled_from(["+X", "+Y", "+Z"]), unique=True, max_size=3))
    ordered_pairs = [(a, b) for a in names for b in names if a != b]
    obstructions = tuple(
        Obstruction(Direction(axis, AXIS_DIRECTIONS[axis]),
                    tuple(draw(st.lists(st.sampled_from(ordered_pairs), unique=True, max_size=2 * n))))
        for axis in axes)
    constraints = []
    for _ in range(draw(st.integers(0, 2))):
        r1 = draw(st.sets(st.sampled_from(names), min_size=1, max_size=n - 1))
        r2 = draw(st.sampled_from([p for p in names if p not in r1]))
        constraints.append(TechnicalConstraint(frozenset(r1), r2))
    return Product(tuple(Part(p) for p in names), tuple(ordered), obstructions, tuple(constraints))


def plan_sets(product: Product):
    """(subassembly sets, operation sets, state sets, intentions, sequences), or None when stuck."""
    try:
        andor = and_or_graph(product)
    except NotDisassemblableError:
        return None
    states = assembly_state_graph(andor)
    subs = {andor.parts_of(i) for i in range(len(andor.subassemblies))}
    ops = {frozenset(andor.inputs(j)) for j in range(len(andor.operations))}
    state_sets = {frozenset(andor.parts_of(b) for b in states.subassemblies_of(s)) for s in range(states.n_states)}
    return subs, ops, state_sets, count_intentions(states), count_sequences(states)


@given(products())
@SETTINGS
def test_matches_the_literal_reference(product):
    expected = reference.andor(product)
    got = plan_sets(product)
    if expected is None:
        assert got is None
        return
    subassemblies, operations = expected
    ref_states, ref_edges = reference.state_graph(subassemblies, operations)
    subs, ops, state_sets, intentions, sequences = got
    assert subs == subassemblies
    assert ops == {children for _, children in operations}
    assert state_sets == ref_states
    ref_intentions = reference.intentions(ref_states, ref_edges)
    assert intentions == len(ref_intentions)
    initial = max(ref_states, key=len)
    assert sequences == sum(1 for path in ref_intentions if path[0] == initial)


@given(products())
@SETTINGS
def test_every_state_is_reachable_and_reaches_the_final_state(product):
    try:
        states = assembly_state_graph(and_or_graph(product))
    except NotDisassemblableError:
        return
    graph = states.to_networkx()
    import networkx as nx

    assert nx.is_directed_acyclic_graph(graph)
    assert nx.descendants(graph, states.initial) | {states.initial} == set(range(states.n_states))
    assert nx.ancestors(graph, states.final) | {states.final} == set(range(states.n_states))
    # The initial state holds every part alone, the final one the whole product.
    andor = states.andor
    assert all(andor.subassemblies[b].bit_count() == 1 for b in states.blocks[states.initial])
    assert set(states.blocks[states.final].tolist()) == {0}


@given(products(), st.data())
@SETTINGS
def test_adding_a_constraint_never_adds_anything(product, data):
    before = plan_sets(product)
    names = list(product.part_ids)
    if data.draw(st.booleans()):
        r1 = data.draw(st.sets(st.sampled_from(names), min_size=1, max_size=len(names) - 1))
        r2 = data.draw(st.sampled_from([p for p in names if p not in r1]))
        tighter = Product(product.parts, product.contacts, product.obstructions,
                          product.technical_constraints + (TechnicalConstraint(frozenset(r1), r2),))
    else:
        pairs = [(a, b) for a in names for b in names if a != b]
        if not product.obstructions:
            axis = Direction("+X", AXIS_DIRECTIONS["+X"])
            obstructions = (Obstruction(axis, (data.draw(st.sampled_from(pairs)),)),)
        else:
            k = data.draw(st.integers(0, len(product.obstructions) - 1))
            old = product.obstructions[k]
            extra = [p for p in pairs if p not in old.blocks]
            if not extra:
                return
            new = Obstruction(old.direction, old.blocks + (data.draw(st.sampled_from(extra)),))
            obstructions = product.obstructions[:k] + (new,) + product.obstructions[k + 1:]
        tighter = Product(product.parts, product.contacts, obstructions, product.technical_constraints)
    after = plan_sets(tighter)
    if after is None:
        return
    assert before is not None
    assert after[0] <= before[0] and after[1] <= before[1] and after[2] <= before[2]
    assert after[3] <= before[3] and after[4] <= before[4]


@given(products(max_parts=5))
@SETTINGS
def test_enumeration_agrees_with_the_count(product):
    try:
        states = assembly_state_graph(and_or_graph(product))
    except NotDisassemblableError:
        return
    graph = intention_graph(states)
    assert graph.n_intentions == count_intentions(states)
    assert len(graph.full_sequences()) == count_sequences(states)
    edges = set(zip(states.edge_source.tolist(), states.edge_target.tolist()))
    paths = [tuple(graph.path(i)) for i in range(graph.n_intentions)]
    assert len(set(paths)) == len(paths)
    for path in paths:
        assert path[-1] == states.final
        assert all(step in edges for step in zip(path, path[1:]))
    assert np.all(graph.operation[1:] >= 0)
