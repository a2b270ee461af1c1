"""Size guards: the AND/OR build stops at its limits of connected part sets and cuts, the state graph at its
memory budget, and the figures are counted as far as the limits allow. Counts are closed forms; no clock."""
from __future__ import annotations

import pytest

from planner import (
    LimitExceededError,
    MemoryLimitError,
    SizeLimits,
    and_or_graph,
    assembly_state_graph,
    chain_product,
    complete_product,
    make_plan,
    plan_statistics,
)
from planner.assembly.guards import OPTIONS, Progress, fastener_like, fewer_parts_hint, memory_options, physical_memory
from planner.assembly.stats import statistics_within
from planner.defaults import CUTS_PER_SUBASSEMBLY
from planner.product.synthetic import fastened_product


@pytest.mark.parametrize("screws", [0, 1, 5, 9])
def test_fastened_product_closed_form(screws):
    """Two parts and m screws: 3 * 2^m + m connected part sets, all of them subassemblies."""
    andor = and_or_graph(fastened_product(2, screws))
    assert len(andor.subassemblies) == 3 * 2 ** screws + screws


def test_connected_sets_limit_is_sharp():
    """Two parts and 8 screws: 3 * 2^8 + 8 = 776 connected sets; the build refuses at one less."""
    product = fastened_product(2, 8)
    count = 3 * 2 ** 8 + 8
    with pytest.raises(LimitExceededError, match=f"AND/OR graph: at least {count:,} connected part sets") as info:
        and_or_graph(product, limit=count - 1)
    error = info.value
    assert (error.count, error.limit) == (count, count - 1)
    assert "8 part(s) look like fasteners by name (screw_1, screw_2" in str(error)
    assert [option for option, _ in error.options] == ["--max-subassemblies", "--fasteners", "--exclude", "--group"]


def test_cut_limit_is_sharp():
    """Two parts A, B and m screws: a set of both parts and t screws has 2^(t+1) connected subsets holding A,
    a set of one part and t >= 1 screws 2^t, so there are 2 * 3^m + 2 * (3^m - 1) = 4 * 3^m - 2 cuts (26,242
    for m = 8); the cut budget is CUTS_PER_SUBASSEMBLY times the limit."""
    def smallest_limit(cuts: int) -> int:
        return -(-cuts // CUTS_PER_SUBASSEMBLY)

    product = fastened_product(2, 8)
    cuts = 4 * 3 ** 8 - 2
    assert len(and_or_graph(product, limit=smallest_limit(cuts)).subassemblies) == 3 * 2 ** 8 + 8
    with pytest.raises(LimitExceededError, match=rf"at least {cuts:,} cuts \(splits of a connected part set"):
        and_or_graph(product, limit=smallest_limit(cuts) - 1)
    # Few sets, many cuts: the complete graph of 8 parts, 255 sets and (3^8 - 1)/2 - 8 = 3,272 cuts.
    assert len(and_or_graph(complete_product(8), limit=smallest_limit(3272)).subassemblies) == 255
    with pytest.raises(LimitExceededError, match="cuts"):
        and_or_graph(complete_product(8), limit=smallest_limit(3272) - 1)


def test_exploding_product_is_refused_before_any_work():
    """A part with any set of its later neighbours is a connected set: for two parts and 40 screws that lower
    bound, 2^41 + 2^40 + 40, is the exact count, and far past the limit, so nothing is enumerated."""
    count = 3 * 2 ** 40 + 40
    with pytest.raises(LimitExceededError, match=f"at least {count:,} connected part sets .* limit of 2,000. .*"
                                                 r"\(a part with any set of its neighbours is one: p1 alone has 41"):
        and_or_graph(fastened_product(2, 40), limit=2000)
    # Past the bound, the enumeration itself stops at the limit: a chain's bound is 2n - 1, its count n(n+1)/2.
    with pytest.raises(LimitExceededError, match="at least 101 connected part sets .* limit of 100"):
        and_or_graph(chain_product(20), limit=100)


def test_state_graph_memory_budget():
    andor = and_or_graph(complete_product(7))
    built = assembly_state_graph(andor)
    assert (built.n_states, built.n_edges) == (877, 4802)  # Bell(7) states
    with pytest.raises(MemoryLimitError, match="assembly state graph would need about .* more than the memory "
                                               "budget of 0.1 MiB") as info:
        assembly_state_graph(andor, max_bytes=100_000)
    assert info.value.count > info.value.limit == 100_000
    assert [option for option, _ in info.value.options] == ["--max-memory", "--fasteners", "--exclude", "--group"]
    # Refused within a level: the states built so far are named.
    with pytest.raises(MemoryLimitError, match=r"\d states"):
        assembly_state_graph(andor, max_bytes=400_000)
    same = assembly_state_graph(andor, max_bytes=64 * 2 ** 20)
    assert (same.edge_source == built.edge_source).all() and (same.blocks == built.blocks).all()


def test_statistics_within_limits():
    product = complete_product(9)
    _, full = statistics_within(product)
    assert full.refused is None and full == plan_statistics(make_plan(product))
    plan, partial = statistics_within(product, limits=SizeLimits(memory=2 ** 20))
    assert plan is None and isinstance(partial.refused, MemoryLimitError)
    # Refused before the AND/OR graph: no constraint, so its states (Bell(9)) are counted on the diagram.
    assert (partial.parts, partial.contacts, partial.states, partial.subassemblies) == (9, 36, 21147, None)
    assert partial.not_computed == ("subassemblies", "operations", "actions", "state_edges", "intentions",
                                    "observations", "sequences")
    _, early = statistics_within(fastened_product(2, 30), limits=SizeLimits(subassemblies=100))
    assert early.not_computed == ("subassemblies", "operations", "actions", "states", "state_edges",
                                  "intentions", "observations", "sequences")
    assert (early.parts, early.contacts, early.complexity) == (32, 61, 3.81)


def test_fastener_hint_names_the_parts():
    named, two = fastener_like(fastened_product(3, 4))
    assert named == ["screw_1", "screw_2", "screw_3", "screw_4"] and two == named
    hint = fewer_parts_hint(complete_product(3))
    assert "fasteners by name" not in hint and "3 parts and 3 contacts" in hint


def test_a_larger_budget_is_offered_only_when_it_could_help():
    assert memory_options(2 ** 20) == [OPTIONS["memory"]]
    physical = physical_memory()
    assert memory_options(2 ** 60) == ([] if physical else [OPTIONS["memory"]])


def test_progress_speaks_once_per_period(caplog):
    import logging

    logger = logging.getLogger("planner.test_progress")
    progress = Progress(logger, after=0.0, every=3600.0)
    with caplog.at_level(logging.INFO, logger="planner.test_progress"):
        progress.report("step %s", "one")
        progress.report("step %s", "two")  # within the hour: silent
    assert [r.getMessage() for r in caplog.records] == ["step one"]
