"""The synthetic products of Table I at 11 parts (exact figures) and exact counting beyond 64-bit floats."""
from __future__ import annotations

from math import comb, factorial

import numpy as np
import pytest

from planner import (
    and_or_graph,
    assembly_state_graph,
    chain_product,
    complete_product,
    count_intentions,
    count_sequences,
    make_plan,
    plan_statistics,
)
from planner.assembly.intentions import _sum_by


def test_chain_of_11():
    stats = plan_statistics(make_plan(chain_product(11)))
    assert (stats.subassemblies, stats.operations, stats.states, stats.state_edges, stats.intentions,
            stats.sequences, stats.complexity) == (66, 220, 1024, 5120, 9_864_101, 3_628_800, 1.82)


@pytest.mark.slow
def test_complete_graph_of_11():
    stats = plan_statistics(make_plan(complete_product(11)))
    assert (stats.subassemblies, stats.operations, stats.states, stats.state_edges, stats.intentions,
            stats.sequences, stats.complexity) == (2047, 86_526, 678_570, 7_841_108, 371_943_215_227,
                                                   141_455_160_000, 10.0)


def test_chain_of_19_counts_exactly_beyond_2_to_the_52():
    # 19 parts need two 64-bit words per state key, and 18! > 2**52 needs Python integers.
    states = assembly_state_graph(and_or_graph(chain_product(19)))
    assert states.n_states == 2 ** 18 and states.n_edges == 18 * 2 ** 17
    assert count_sequences(states) == factorial(18) > 2 ** 52
    assert count_intentions(states) == sum(comb(18, j) * factorial(j) for j in range(19))


def test_exact_group_sums():
    index = np.array([0, 2, 2, 1, 2])
    small = _sum_by(index, np.array([1, 2, 3, 4, 5], dtype=np.int64), 4)
    assert small.dtype == np.int64 and small.tolist() == [1, 4, 10, 0]
    big = np.array([2 ** 51, 2 ** 51, 2 ** 51 + 1, 3, 1], dtype=np.int64)
    exact = _sum_by(index, big, 4)
    assert exact.dtype == object and exact.tolist() == [2 ** 51, 3, 2 ** 52 + 2, 0]
    huge = np.array([10 ** 30, 1, 10 ** 30, 7, 1], dtype=object)
    assert _sum_by(index, huge, 3).tolist() == [10 ** 30, 7, 10 ** 30 + 2]
