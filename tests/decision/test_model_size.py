"""The flat decision model's size, estimated from counts before it is built, and refused past the budget."""
from __future__ import annotations

import pytest

from planner import LimitExceededError, MemoryLimitError, SizeLimits, api, chain_product, complete_product, make_plan
from planner.decision.intention_model import check_flat_model, flat_model_bytes, flat_model_fits, intention_model
from planner.decision.io import write_cassandra, write_pomdpx
from planner.decision.io.size import model_file_bytes
from planner.errors import FileLimitError


def table_bytes(model) -> int:
    """The bytes of the model's arrays: transition and observation tables, rewards, initial belief, graph."""
    pomdp, graph = model.pomdp, model.graph
    sparse = sum(t.data.nbytes + t.indices.nbytes + t.indptr.nbytes for t in pomdp.transition)
    shared = {id(o): o for o in pomdp.observation}.values()  # one table for every action
    sparse += sum(t.data.nbytes + t.indices.nbytes + t.indptr.nbytes for t in shared)
    arrays = pomdp.reward.nbytes + pomdp.initial.nbytes
    return sparse + arrays + graph.first_state.nbytes + graph.successor.nbytes + graph.step_edge.nbytes


@pytest.mark.parametrize("product", [chain_product(7), complete_product(5), chain_product(4)],
                         ids=["chain7", "complete5", "chain4"])
def test_estimate_bounds_the_tables(pen, product):
    """The estimate covers the model's arrays, and is not more than twice them plus the names' strings."""
    for plan in (make_plan(pen), make_plan(product)):
        model = intention_model(plan)
        estimate = flat_model_bytes(plan)
        intentions = model.pomdp.n_states
        assert estimate == flat_model_bytes(plan, intentions)
        assert table_bytes(model) <= estimate <= 2 * table_bytes(model) + 100 * intentions


def test_model_refused_past_the_budget():
    plan = make_plan(chain_product(6))
    needed = flat_model_bytes(plan)
    assert intention_model(plan, max_bytes=needed).pomdp.n_states == 326
    assert flat_model_fits(plan, needed) and not flat_model_fits(plan, needed - 1)
    assert not flat_model_fits(plan, limit=325)
    with pytest.raises(MemoryLimitError, match=r"flat decision model would need about .* \(326 intentions x 36 "
                                               r"actions\), more than the memory budget") as info:
        intention_model(plan, max_bytes=needed - 1)
    assert [option for option, _ in info.value.options] == ["--planner", "--base-part", "--max-memory"]
    with pytest.raises(LimitExceededError, match="flat decision model: 326 intentions would be enumerated, more "
                                                 "than the limit of 325") as info:
        check_flat_model(plan, limit=325)
    assert "--limit" not in [option for option, _ in info.value.options]  # the model commands have no --limit


def test_eleven_part_chain_is_refused_from_counts():
    """9,864,101 intentions x 221 actions: tens of GiB, refused before anything is enumerated."""
    plan = make_plan(chain_product(11))
    assert flat_model_bytes(plan) > 9_864_101 * 221 * 24  # at least a float64 reward and a sparse row each
    with pytest.raises(MemoryLimitError, match=r"9,864,101 intentions x 221 actions"):
        intention_model(plan, max_bytes=4 * 2 ** 30)


@pytest.mark.parametrize("kind, write", [("pomdpx", write_pomdpx), ("cassandra", write_cassandra)])
def test_file_size_estimate(tmp_path, pen, kind, write):
    """Within 5 % of the bytes the writer writes (pen, a chain of 6, a complete graph of 5)."""
    for product in (pen, chain_product(6), complete_product(5)):
        model = intention_model(make_plan(product)).pomdp
        path = tmp_path / f"model.{kind}"
        write(model, path)
        assert abs(model_file_bytes(model, kind) - path.stat().st_size) <= 0.05 * path.stat().st_size


def test_file_refused_past_the_budget(tmp_path):
    model = intention_model(make_plan(chain_product(6)))
    target = tmp_path / "chain6.pomdpx"
    needed = api.check_model_file(model, target)
    with pytest.raises(FileLimitError, match=r"chain6.pomdpx would take about 1.1 MiB \(326 states, 36 actions, "
                                             r"[\d,]+ non-zero transitions\), more than the file size budget of "
                                             r"1.0 MiB") as info:
        api.save_model(model, target, max_bytes=2 ** 20)
    assert info.value.count == needed and not target.exists()
    assert [option for option, _ in info.value.options] == ["--max-file", "--base-part"]
    api.save_model(model, target, max_bytes=needed)
    assert abs(target.stat().st_size - needed) <= 0.05 * needed


def test_reading_a_model_file_is_estimated_first(tmp_path, pen):
    target = tmp_path / "pen.pomdpx"
    api.save_model(api.decision_model(pen), target)
    size = target.stat().st_size
    assert api.load_model(target, limits=SizeLimits(memory=3 * size)).n_states == 69
    with pytest.raises(MemoryLimitError, match=r"reading .*pen.pomdpx would need about 0.5 MiB \(3 x its 0.2 MiB\)"):
        api.load_model(target, limits=SizeLimits(memory=3 * size - 1))
