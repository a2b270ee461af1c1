"""The factored intention model (paper Sec. V) against the flat model of Alg. 3: the same beliefs at every step of
simulated episodes (missed detections, random and wrong robot actions), the same expected rewards, the same
resets; its size by closed forms; complete 11 built without enumerating intentions."""
from __future__ import annotations

import time

import numpy as np
import pytest

from planner import PlannerError, chain_product, complete_product, count_intentions, intention_graph, make_plan
from planner.decision import (DiscreteUpdater, FactoredUpdater, UnexplainedObservation, factored_model,
                              intention_model, to_flat)

TOLERANCE = 1e-9


def _models(product, technical=None):
    plan = make_plan(product, technical)
    return intention_model(plan), factored_model(plan)


@pytest.fixture(scope="module", params=[False, True], ids=["no-technical", "technical"])
def pen_models(request, pen):
    return _models(pen, request.param)


def _assert_same(flat_model, fact, flat_belief, belief):
    assert np.max(np.abs(to_flat(belief, flat_model.graph) - flat_belief)) <= TOLERANCE
    expected = flat_model.pomdp.reward @ flat_belief
    assert np.max(np.abs(fact.expected_rewards(belief) - expected)) <= TOLERANCE
    for action in range(len(fact.actions)):
        assert fact.expected_reward(belief, action) == pytest.approx(expected[action], abs=TOLERANCE)


def _episode(flat_model, fact, start, rng, choose, max_steps=60):
    """Run the true intention by the flat model's dynamics from ``start``, both filters side by side; returns the
    number of steps compared."""
    pomdp = flat_model.pomdp
    transition = [t.tocsr() for t in pomdp.transition]
    observation = pomdp.observation[0].tocsr()
    flat, factored = DiscreteUpdater(pomdp), FactoredUpdater(fact)
    b, belief = flat.initialize(), factored.initialize()
    _assert_same(flat_model, fact, b, belief)
    state, steps = start, 0
    while state != flat_model.final_state and steps < max_steps:
        action = choose(state, rng)
        row = transition[action].getrow(state)
        state = int(rng.choice(row.indices, p=row.data / row.data.sum()))
        orow = observation.getrow(state)
        z = int(rng.choice(orow.indices, p=orow.data / orow.data.sum()))
        b, belief = flat.update(b, action, z), factored.update(belief, action, z)
        _assert_same(flat_model, fact, b, belief)
        steps += 1
    assert not flat.events and not factored.events  # the true intention explains every observation
    return steps


def _random_actions(model):
    n = len(model.actions)
    return lambda state, rng: int(rng.integers(n))


def _wrong_actions(model):
    """An action that is not the true intention's next step (wait included), at random."""
    operations = model.graph.operation

    def choose(state, rng):
        allowed = [a for a in range(len(model.actions)) if model.operation(a) != operations[state]]
        return int(rng.choice(allowed))
    return choose


def _right_actions(model):
    """The robot performs the true intention's next step whenever it can (the model's fastest progress)."""
    operations = model.graph.operation

    def choose(state, rng):
        right = [a for a in range(len(model.actions) - 1) if model.operation(a) == operations[state]]
        return right[0] if right else len(model.actions) - 1
    return choose


@pytest.mark.parametrize("policy", [_random_actions, _wrong_actions, _right_actions])
def test_pen_every_sequence_same_belief_and_rewards(pen_models, policy):
    flat_model, fact = pen_models
    starts = flat_model.full_sequences()
    assert len(starts) == fact.n_sequences in (24, 12)
    rng = np.random.default_rng(12)
    steps = sum(_episode(flat_model, fact, int(s), rng, policy(flat_model)) for s in starts)
    assert steps >= 3 * len(starts)


@pytest.mark.parametrize("product, episodes", [(chain_product(7), 6), (complete_product(6), 4)],
                         ids=["chain7", "complete6"])
def test_synthetic_random_sequences(product, episodes):
    flat_model, fact = _models(product)
    rng = np.random.default_rng(7)
    starts = rng.choice(flat_model.full_sequences(), size=episodes, replace=False)
    for k, start in enumerate(starts):
        policy = (_random_actions, _wrong_actions, _right_actions)[k % 3](flat_model)
        _episode(flat_model, fact, int(start), rng, policy)


def test_same_tables_per_intention(pen_models):
    """Transitions of one class at a time and the observation table, against the flat tables themselves."""
    flat_model, fact = pen_models
    pomdp, graph = flat_model.pomdp, flat_model.graph
    E = graph.states.n_edges
    of = np.where(graph.step_edge >= 0, graph.step_edge, E)
    size = np.bincount(of, minlength=E + 1)
    for c in range(fact.n_classes):
        members = of == c
        flat = members / members.sum()
        belief = type(fact.initial_belief())(np.array([c]), np.array([1.0]))
        for action in range(len(fact.actions)):
            expected = pomdp.transition[action].T @ flat
            got = to_flat(fact.predict(belief, action), graph)
            assert np.max(np.abs(got - expected)) <= TOLERANCE
    table = pomdp.observation[0].toarray()
    for z in range(len(fact.observations)):
        assert np.array_equal(fact.observation_likelihood(z)[of], table[:, z])
    assert size.sum() == graph.n_intentions
    for state in range(graph.states.n_states):
        zs, p = fact.state_observations(state)
        row = table[np.flatnonzero(graph.first_state == state)[0]]
        assert p.sum() == pytest.approx(1) and np.array_equal(p, row[zs]) and np.count_nonzero(row) == len(zs)


def test_same_names_as_the_flat_model(pen_models):
    flat_model, fact = pen_models
    assert fact.actions == flat_model.actions and fact.observations == flat_model.observations
    assert [fact.operation(a) for a in range(len(fact.actions))] == \
        [flat_model.operation(a) for a in range(len(flat_model.actions))]
    flat_sequences = sorted(tuple(flat_model.sequence_operations(int(i))) for i in flat_model.full_sequences())
    ours = sorted(tuple(fact.sequence_operations(fact.sequence(k))) for k in range(fact.n_sequences))
    assert ours == flat_sequences
    with pytest.raises(Exception, match="does not exist"):
        fact.sequence(fact.n_sequences)


@pytest.mark.parametrize("product", [chain_product(9), complete_product(7)], ids=["chain9", "complete7"])
def test_sizes_closed_forms(product):
    plan = make_plan(product)
    fact = factored_model(plan)
    assert fact.n_classes == plan.states.n_edges + 1
    assert sum(int(x) for x in fact.class_sizes()) == count_intentions(plan.states)
    assert np.allclose(np.bincount(fact.class_source, weights=fact.class_fraction), 1)
    initial = fact.initial_belief()
    assert initial.mass.sum() == pytest.approx(1)
    # The initial classes hold N(target) of the N(initial) sequences each: (n-1)! for the chain.
    n = len(plan.andor.parts)
    if "chain" in (product.name or ""):
        assert fact.n_sequences == np.prod(np.arange(1, n), dtype=np.int64)


def test_unexplained_observations_reset_like_the_flat_filter(pen_models):
    """Every (action, observation) at beliefs along an episode: where the flat filter resets, the factored one
    resets to the same belief, names the same rule and reports it through on_reset."""
    flat_model, fact = pen_models
    pomdp, graph = flat_model.pomdp, flat_model.graph
    rng = np.random.default_rng(3)
    flat, factored = DiscreteUpdater(pomdp), FactoredUpdater(fact)
    beliefs = [(flat.initialize(), factored.initialize())]
    wait = len(fact.actions) - 1
    for _ in range(12):  # missed detections only: the belief spreads to the end of assembly
        b, belief = beliefs[-1]
        beliefs.append((flat.update(b, wait, 0), factored.update(belief, wait, 0)))
    final = type(belief)(np.array([fact.final_class]), np.array([1.0]))
    beliefs.append((np.eye(pomdp.n_states)[0], final))
    kinds = set()
    for b, belief in beliefs:
        for action in rng.choice(len(fact.actions), size=4, replace=False):
            for z in range(len(fact.observations)):
                reported: list[UnexplainedObservation] = []
                one = DiscreteUpdater(pomdp, on_reset=lambda e: None)
                mine = FactoredUpdater(fact, on_reset=reported.append)
                expected = one.update(b, int(action), z)
                got = mine.update(belief, int(action), z)
                assert np.max(np.abs(to_flat(got, graph) - expected)) <= TOLERANCE
                assert got.mass.sum() == pytest.approx(1)
                assert [e.reset_to for e in one.events] == [e.reset_to for e in mine.events]
                assert reported == mine.events
                kinds.update(e.reset_to for e in mine.events)
    assert kinds == {"reachable", "emitting"}


@pytest.mark.slow
def test_complete_11_without_enumerating_intentions():
    """678,570 states and 7,841,108 state edges (3.7e11 intentions): built in seconds, belief updates work."""
    plan = make_plan(complete_product(11))
    begin = time.perf_counter()
    fact = factored_model(plan)
    built = time.perf_counter() - begin
    assert (plan.states.n_states, fact.n_classes - 1) == (678_570, 7_841_108)
    assert built < 30
    assert sum(int(x) for x in fact.class_sizes()) == count_intentions(plan.states) == 371_943_215_227
    updater = FactoredUpdater(fact)
    belief = updater.initialize()
    assert belief.classes.size == 55  # C(11, 2) first operations
    rng = np.random.default_rng(0)
    edges = fact.sample_sequence(rng)
    zs = [int(fact.plan.operation_observation[fact.class_operation[e]]) for e in edges[:3]]
    for z in zs:
        belief = updater.update(belief, fact.wait, z)
        assert belief.mass.sum() == pytest.approx(1) and not updater.events


def test_to_flat_refuses_nothing_on_small_graphs(pen):
    """to_flat gives a probability vector over the intention graph's numbering."""
    plan = make_plan(pen)
    fact = factored_model(plan)
    flat = to_flat(fact.initial_belief(), intention_graph(plan.states))
    assert flat.sum() == pytest.approx(1) and np.count_nonzero(flat) == fact.n_sequences


def test_one_intention_moves_as_the_flat_model_says(pen_models):
    """position_transition along each full sequence equals the flat transition rows of its intentions."""
    flat_model, fact = pen_models
    graph, transition = flat_model.graph, flat_model.pomdp.transition
    for start in flat_model.full_sequences():
        chain = [int(start)]
        while graph.successor[chain[-1]] >= 0:
            chain.append(int(graph.successor[chain[-1]]))
        path = [int(graph.step_edge[i]) for i in chain[:-1]]
        assert fact.sequence_operations(path) == flat_model.sequence_operations(int(start))
        for position, intention in enumerate(chain):
            for action in range(len(fact.actions)):
                row = transition[action].getrow(intention)
                expected = dict(zip(row.indices.tolist(), row.data.tolist()))
                got = {}
                for q, p in fact.position_transition(path, position, action):
                    got[chain[q]] = got.get(chain[q], 0) + p
                assert got == expected


def test_bad_actions_and_observations_are_refused(pen):
    fact = factored_model(make_plan(pen))
    updater = FactoredUpdater(fact)
    belief = updater.initialize()
    for action, z in ((len(fact.actions), 0), (-1, 0), (0, len(fact.observations)), (0, -1)):
        with pytest.raises(PlannerError, match="is not one of the model's"):
            updater.update(belief, action, z)
