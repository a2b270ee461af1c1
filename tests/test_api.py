"""planner.api, the steps every front end takes: resolving products, plans, decision models and their files,
solving, simulating and evaluating."""
from __future__ import annotations

import math

import numpy as np
import pytest

from planner import (
    PlannerError,
    UnknownProductError,
    api,
    count_intentions,
    example_path,
    intention_graph,
    save_product,
)
from planner.decision import POMDP, IntentionModel


@pytest.fixture(scope="module")
def model():
    return api.decision_model("pen")


@pytest.fixture(scope="module")
def policy(model):
    # A fixed amount of work, no clock: the same policy on any machine.
    return api.solve(model, time_limit=math.inf, precision=1e-9, iterations=20).policy


def test_resolve_product(tmp_path, pen):
    assert api.resolve_product("pen") == pen
    assert api.resolve_product(example_path("pen")).part_ids == pen.part_ids
    save_product(pen, tmp_path / "copy.json")
    assert api.resolve_product(tmp_path / "copy.json").part_ids == pen.part_ids
    with pytest.raises(UnknownProductError, match="is a folder without product.json, so not a product bundle"):
        api.resolve_product(tmp_path)
    with pytest.raises(UnknownProductError, match=r"no-such: no such file, and no embedded example of that name "
                                                  r"\(embedded: pen\)"):
        api.resolve_product("no-such")


def test_plan_statistics_with_a_base_part():
    """The paper's Sec. V: only the sequences whose first operation joins the base part (the pen's body), and their
    intentions (the counts against the intention graph filtered by hand)."""
    plan, stats = api.plan_statistics_of("pen", technical=True, base_part="auto")
    graph = intention_graph(plan.states)
    body = plan.andor.parts.index("body")
    allowed = [tuple(graph.path(int(i))) for i in graph.full_sequences()
               if plan.andor.subassemblies[plan.andor.operations[graph.operations(int(i))[0]].parent] >> body & 1]
    suffixes = {path[k:] for path in allowed for k in range(len(path))}
    assert stats.base_part == "body" and (stats.intentions, stats.sequences) == (len(suffixes), len(allowed)) == (22, 5)
    _, whole = api.plan_statistics_of(plan)
    assert (whole.intentions, whole.sequences) == (39, 12) and whole.base_part is None
    assert api.base_part_of(plan, None) is None and api.base_part_of(plan, "") is None
    assert api.base_part_of(plan, "auto") == "body" == api.base_part_of(plan, "body")
    with pytest.raises(PlannerError, match="base part 'lid' is not a part of the product; parts: ink"):
        api.base_part_of(plan, "lid")


def test_decision_model_with_a_base_part(tmp_path):
    model = api.decision_model("pen", base_part="auto")
    assert model.base_part == "body" and model.pomdp.n_states == count_intentions(model.plan.states, base_part="body")
    path = tmp_path / "pen.pomdp"
    api.save_model(model, path)
    assert api.load_model(path).n_states == model.pomdp.n_states
    with pytest.raises(PlannerError, match="a base part applies to products only"):
        api.load_model(path, base_part="auto")


def test_models_from_products_and_files(tmp_path, model):
    assert isinstance(model, IntentionModel) and api.tables(model) is model.pomdp
    for name in ("m.pomdpx", "m.pomdp"):
        api.save_model(model, tmp_path / name)
        loaded = api.load_model(tmp_path / name)
        assert isinstance(loaded, POMDP) and api.tables(loaded) is loaded
        assert loaded.n_states == model.pomdp.n_states and np.allclose(loaded.reward, model.pomdp.reward)
    with pytest.raises(PlannerError, match=r"m\.txt: unknown model file type; use \.pomdpx or \.pomdp"):
        api.save_model(model, tmp_path / "m.txt")
    assert not (tmp_path / "m.txt").exists()
    technical = api.load_model("pen", technical=True)
    assert technical.pomdp.n_states == 39  # the paper's pen with its technical constraint


def test_solver_choice(model):
    with pytest.raises(PlannerError, match="unknown solver engine 'fast'; use one of builtin, sarsop"):
        api.solve(model, engine="fast")
    first = api.solve(model, time_limit=math.inf, precision=1e-9, iterations=5)
    second = api.solve(model, time_limit=math.inf, precision=1e-9, iterations=5)
    assert first.iterations == 5 and first.lower_bound <= first.upper_bound
    assert np.array_equal(first.policy.alphas, second.policy.alphas)


def test_policy_from_a_file_or_solved(tmp_path, model, policy):
    from planner.decision.policy import write_policy

    write_policy(policy, tmp_path / "p.policy")
    read, result = api.policy_for(model, tmp_path / "p.policy")
    assert result is None and np.allclose(read.alphas, policy.alphas, atol=1e-9)


def test_simulate_chooses_and_checks_sequences(model, policy):
    starts = [int(s) for s in model.full_sequences()]
    assert [e.start for e in api.simulate(model, policy, every=True)] == starts
    assert [e.start for e in api.simulate(model, policy)] == starts[:1]
    drawn = [e.start for e in api.simulate(model, policy, random=4, seed=3)]
    assert len(drawn) == 4 and set(drawn) <= set(starts)
    assert drawn == [e.start for e in api.simulate(model, policy, random=4, seed=3)]
    with pytest.raises(PlannerError, match=r"--sequence 1 is not a full assembly sequence"):
        api.simulate(model, policy, [starts[0], 1])
    for episode in api.simulate(model, policy, [starts[2]], operator="turns"):
        assert episode.steps[-1].state == model.final_state  # the operator finished the product


def test_evaluate_a_model_or_its_tables(model, policy):
    # 50 episodes are enough for a finite mean and a confidence interval (the brackets are checked with 2,000 in
    # tests/decision/test_simulate.py).
    mean, half = api.evaluate(model, policy, 50, seed=1)
    bare_mean, bare_half = api.evaluate(model.pomdp, policy, 50, seed=1)
    assert math.isfinite(mean) and half > 0 and math.isfinite(bare_mean) and bare_half > 0


def test_lumped_model(tmp_path):
    from planner.decision.lumped_model import LumpedModel

    lumped = api.load_model("pen", technical=True, lumped=True)
    assert isinstance(lumped, LumpedModel) and api.tables(lumped) is lumped.pomdp
    plan = api.plan_of("pen", True)
    assert lumped.pomdp.n_states == plan.states.n_edges + 1 == lumped.factored.n_classes
    assert np.array_equal(lumped.pomdp.initial, lumped.factored.initial_belief().dense(lumped.factored.n_classes))
    # The same value as the flat model: a fixed amount of work brackets V*(b0) from both, and the brackets meet.
    a = api.solve(lumped, time_limit=math.inf, precision=1e-9, iterations=150)
    b = api.solve(api.decision_model(plan), time_limit=math.inf, precision=1e-9, iterations=150)
    assert max(a.lower_bound, b.lower_bound) <= min(a.upper_bound, b.upper_bound) + 1e-9
    api.save_model(lumped, tmp_path / "pen.pomdp")
    assert api.load_model(tmp_path / "pen.pomdp").n_states == lumped.pomdp.n_states
    with pytest.raises(PlannerError, match="--lumped builds the lumped model of a PRODUCT"):
        api.load_model(tmp_path / "pen.pomdp", lumped=True)
