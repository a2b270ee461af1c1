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
    assert [e.start for e in api.simulate(model, policy, api.EpisodeChoice(every=True))] == starts
    assert [e.start for e in api.simulate(model, policy)] == starts[:1]
    drawn = [e.start for e in api.simulate(model, policy, api.EpisodeChoice(random=4, seed=3))]
    assert len(drawn) == 4 and set(drawn) <= set(starts)
    assert drawn == [e.start for e in api.simulate(model, policy, api.EpisodeChoice(random=4, seed=3))]
    with pytest.raises(PlannerError, match=r"--sequence 1 is not a full assembly sequence"):
        api.simulate(model, policy, api.EpisodeChoice(sequences=[starts[0], 1]))
    for episode in api.simulate(model, policy, api.EpisodeChoice(sequences=[starts[2]], operator="turns")):
        assert episode.steps[-1].state == model.final_state  # the operator finished the product


def test_evaluate_a_model_or_its_tables(model, policy):
    # 50 episodes are enough for a finite mean and a confidence interval (the brackets are checked with 2,000 in
    # tests/decision/test_simulate.py).
    mean, half = api.evaluate(model, policy, api.EpisodeChoice(random=50, seed=1))
    bare_mean, bare_half = api.evaluate(model.pomdp, policy, api.EpisodeChoice(random=50, seed=1))
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


# ------------------------------------------------------------------- levels (the workbench's statistics and tree)

def _two_chains(a: int, b: int):
    """A chain a1..aA and a chain b1..bB joined by the contact aA-b1, each a subassembly."""
    from planner.product import Part, Product, Subassembly

    parts = tuple(Part(f"a{i}") for i in range(1, a + 1)) + tuple(Part(f"b{i}") for i in range(1, b + 1))
    contacts = tuple((f"a{i}", f"a{i + 1}") for i in range(1, a)) + tuple((f"b{i}", f"b{i + 1}") for i in range(1, b))
    groups = (Subassembly("A", tuple(f"a{i}" for i in range(1, a + 1))),
              Subassembly("B", tuple(f"b{i}" for i in range(1, b + 1))))
    return Product(parts, contacts + ((f"a{a}", "b1"),), subassemblies=groups, name="two chains")


def _chain_intentions(n: int) -> int:
    return sum(math.comb(n - 1, j) * math.factorial(j) for j in range(n))


def test_level_report_counts_each_level_by_the_chain_formulas_and_matches_aplan_stats(tmp_path):
    import json

    from integration.freecad_tools import aplan

    product = _two_chains(3, 4)
    seen: list[str] = []
    report = api.level_report(product, progress=seen.append)
    assert [row["level"] for row in report["levels"]] == ["A", "B", "top"]
    assert [row["intentions"] for row in report["levels"]] == [_chain_intentions(n) for n in (3, 4, 2)]
    assert [row["sequences"] for row in report["levels"]] == [math.factorial(n - 1) for n in (3, 4, 2)]
    assert report["total"]["parts"] == 7 and report["total"]["sequences"] == 2 * 6 * 1
    assert report["total"]["intentions"] == sum(_chain_intentions(n) for n in (3, 4, 2))
    assert report["flat"]["intentions"] == _chain_intentions(7)  # flat, the same product is a chain of 7
    assert seen == ["level 1 of 3: A (3 members)", "level 2 of 3: B (4 members)", "level 3 of 3: top (2 members)",
                    "the product planned flat, for comparison"]
    save_product(product, tmp_path / "two.json")
    assert json.loads(aplan("stats", str(tmp_path / "two.json"), "--json").stdout) == report


def test_structure_problems_name_the_level_that_cannot_be_built():
    from dataclasses import replace

    from planner.product import Subassembly

    product = _two_chains(3, 3)
    assert api.structure_problems(product) == []
    apart = replace(product, subassemblies=(Subassembly("X", ("a1", "b2")),))
    (level, reason), = api.structure_problems(apart)
    assert level == "X" and "a1" in reason and "b2" in reason


def test_proposed_subassemblies_ignore_the_products_own():
    from planner.product.synthetic import chain_product

    chain = chain_product(12)
    proposed = api.proposed_subassemblies(chain, max_components=4)
    assert proposed and all(len(s.parts) <= 4 for s in proposed)
    from dataclasses import replace

    assert api.proposed_subassemblies(replace(chain, subassemblies=proposed), max_components=4) == proposed
