"""The decision model with a base part (paper Sec. V): Alg. 3 over the intentions of the sequences that start from
it, flat and factored; the factored belief equals the flat one at every step; full sequences by rank and by sampling
stay among the allowed ones."""
from __future__ import annotations

import numpy as np
import pytest
from test_factored_model import _episode, _random_actions, _right_actions, _wrong_actions

from planner import PlannerError, chain_product, complete_product, count_intentions, count_sequences, make_plan
from planner.decision import DiscreteUpdater, FactoredUpdater, factored_model, intention_model, to_flat


def _models(product, base_part, technical=None):
    plan = make_plan(product, technical)
    return intention_model(plan, base_part=base_part), factored_model(plan, base_part=base_part)


@pytest.mark.parametrize("technical", [False, True], ids=["no-technical", "technical"])
@pytest.mark.parametrize("base_part", ["body", "cartridge", "button"])
def test_pen_factored_belief_equals_flat_with_a_base_part(pen, technical, base_part):
    flat_model, fact = _models(pen, base_part, technical)
    states = flat_model.plan.states
    starts = flat_model.full_sequences()
    assert len(starts) == fact.n_sequences == count_sequences(states, base_part) > 0
    assert flat_model.pomdp.n_states == count_intentions(states, base_part=base_part)
    assert flat_model.base_part == fact.base_part == base_part
    initial = flat_model.pomdp.initial
    assert np.allclose(initial[starts], 1 / len(starts)) and initial.sum() == pytest.approx(1)
    rng = np.random.default_rng(3)
    policies = (_random_actions, _wrong_actions, _right_actions)
    steps = sum(_episode(flat_model, fact, int(s), rng, policies[k % 3](flat_model)) for k, s in enumerate(starts))
    assert steps >= 3 * len(starts)


@pytest.mark.parametrize("product, base_part", [(chain_product(6), "p3"), (complete_product(5), "p1")],
                         ids=["chain6", "complete5"])
def test_synthetic_factored_belief_equals_flat_with_a_base_part(product, base_part):
    flat_model, fact = _models(product, base_part)
    rng = np.random.default_rng(5)
    starts = rng.choice(flat_model.full_sequences(), size=4, replace=False)
    for k, start in enumerate(starts):
        policy = (_random_actions, _wrong_actions, _right_actions)[k % 3]
        _episode(flat_model, fact, int(start), rng, policy(flat_model))


def test_observations_come_from_allowed_steps_only(pen):
    """The intention 'body joined to ink+cartridge' is reachable from a sequence starting from the body, but the
    step that joins the body to ink+cartridge is not allowed: the restricted model never emits its observation
    there, and the factored one agrees (to_flat of a point belief on that class)."""
    flat_model, fact = _models(pen, "body", False)
    assert (factored_model(flat_model.plan).emit_weight != fact.emit_weight).any()  # the restriction matters here
    graph, pomdp = flat_model.graph, flat_model.pomdp
    table = pomdp.observation[0].toarray()
    for i in range(1, graph.n_intentions):
        predecessors = np.flatnonzero(graph.successor == i)
        expected = {int(flat_model.plan.operation_observation[graph.operation[p]]) for p in predecessors} - {0}
        assert set(np.flatnonzero(table[i])) - {0} == expected
    for c in range(fact.n_classes):
        flat_states = np.flatnonzero(np.where(graph.step_edge >= 0, graph.step_edge, fact.final_class) == c)
        if flat_states.size == 0:
            continue
        for z in range(len(fact.observations)):
            assert fact.observation_likelihood(z, np.array([c]))[0] == pytest.approx(table[flat_states[0], z])


def test_sequences_by_rank_and_sampled_start_from_the_base_part(pen):
    flat_model, fact = _models(pen, "body", False)
    andor = fact.plan.andor
    expected = sorted(tuple(flat_model.sequence_operations(int(s))) for s in flat_model.full_sequences())
    by_rank = sorted(tuple(fact.sequence_operations(fact.sequence(r))) for r in range(fact.n_sequences))
    assert by_rank == expected
    with pytest.raises(PlannerError, match="does not exist"):
        fact.sequence(fact.n_sequences)
    rng = np.random.default_rng(0)
    seen = {tuple(fact.sequence_operations(fact.sample_sequence(rng))) for _ in range(400)}
    assert seen == set(expected)  # 10 sequences, 400 draws: each is drawn (probability of a miss < 1e-15)
    for operations in seen:
        assert "body" in andor.describe(operations[0])


def test_factored_initial_belief_is_uniform_over_allowed_sequences(pen):
    flat_model, fact = _models(pen, "cartridge", False)
    belief = fact.initial_belief()
    assert belief.mass.sum() == pytest.approx(1, abs=1e-12)
    assert np.max(np.abs(to_flat(belief, flat_model.graph) - flat_model.pomdp.initial)) <= 1e-12


def test_bad_base_parts(pen):
    plan = make_plan(pen, False)
    with pytest.raises(PlannerError, match="base part 'lid' is not a part of the product; parts: "):
        factored_model(plan, base_part="lid")
    with pytest.raises(PlannerError, match="base part 'lid' is not a part"):
        intention_model(plan, base_part="lid")
    for build in (factored_model, intention_model):  # the cap never takes part in the first operation
        with pytest.raises(PlannerError, match="no assembly sequence starts from the base part 'cap'"):
            build(plan, base_part="cap")


@pytest.mark.parametrize("base_part", ["body", "button"])
def test_resets_stay_among_the_base_parts_intentions(pen, base_part):
    """An observation no intention of the restricted model can emit (the body picked alone with the hammer, when
    every sequence starts from the body) resets both beliefs to uniform over the restricted intentions; then an
    observation some can emit, from there."""
    flat_model, fact = _models(pen, base_part, False)
    allowed = fact.reachable(fact.initial_classes)
    impossible = [z for z in range(1, len(fact.observations)) if not (fact.observation_likelihood(z)[allowed] > 0).any()]
    assert fact.observations.index("body+[hammer]") in impossible
    flat, factored = DiscreteUpdater(flat_model.pomdp), FactoredUpdater(fact)
    b, belief = flat.initialize(), factored.initialize()
    wait = len(fact.actions) - 1
    for z in (impossible[0], 0, impossible[-1]):
        b, belief = flat.update(b, wait, z), factored.update(belief, wait, z)
        assert np.max(np.abs(to_flat(belief, flat_model.graph) - b)) <= 1e-9
    assert [e.reset_to for e in flat.events] == [e.reset_to for e in factored.events] == ["uniform", "uniform"]
