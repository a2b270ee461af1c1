"""Operator habits in the decision models (issue 23): the weights' definition against closed forms (each full
sequence's prior is the product of the habit choices along it; no counts give the paper's model bit for bit), and
the equivalence of the weighted models: flat = factored = lumped to 1e-9 on small products with random habits,
along simulated episodes, after resets, and with a base part."""
from __future__ import annotations

import numpy as np
import pytest

from planner import chain_product, complete_product, make_plan
from planner.decision import (DiscreteUpdater, FactoredUpdater, factored_model, intention_model, lumped_pomdp,
                              to_flat)
from planner.decision.habits import (add_sequence, choice_probabilities, habit_weights, habit_weights_from,
                                     habits_from_counts)
from reference import filtered_histories, horizon_value

TOLERANCE = 1e-9


def _random_counts(plan, rng, fill=0.5, fractional=False):
    """Whole counts from 1 to 29 on a ``fill`` share of the edges, or (``fractional``) expected counts in (0, 3),
    as a log that several sequences explain gives (docs/habits.md, Learning from logs)."""
    E = plan.states.n_edges
    drawn = rng.uniform(0.01, 3.0, E) if fractional else rng.integers(1, 30, E).astype(float)
    return drawn * (rng.random(E) < fill)


@pytest.fixture(scope="module", params=["pen-no-technical", "pen-technical", "chain-5", "complete-4",
                                        "pen-technical-per-state", "complete-4-per-state", "chain-5-fractional"])
def weighted(request, pen):
    """Random habits on a small product; ``-per-state``: the prior alpha in all per state (docs/habits.md);
    ``-fractional``: fractional counts."""
    fractional = request.param.endswith("-fractional")
    name = request.param.removesuffix("-per-state").removesuffix("-fractional")
    product, technical = {"pen-no-technical": (pen, False), "pen-technical": (pen, True),
                          "chain-5": (chain_product(5), None), "complete-4": (complete_product(4), None)}[name]
    plan = make_plan(product, technical)
    rng = np.random.default_rng(sum(map(ord, request.param)))
    per = "state" if request.param.endswith("-per-state") else "edge"
    weights = habit_weights_from(plan, _random_counts(plan, rng, fractional=fractional),
                                 float(rng.choice([0.1, 1.0, 3.0])), per)
    return plan, weights, intention_model(plan, weights=weights), factored_model(plan, weights=weights)


def test_no_counts_give_the_papers_model_exactly(pen):
    plan = make_plan(pen)
    assert habit_weights(plan, habits_from_counts(plan, np.zeros(plan.states.n_edges))) is None
    ones = habit_weights_from(plan, np.zeros(plan.states.n_edges), 2.5)
    assert np.array_equal(ones, np.ones(plan.states.n_edges))
    paper, weighted = intention_model(plan), intention_model(plan, weights=ones)
    assert np.array_equal(paper.pomdp.initial, weighted.pomdp.initial)
    assert all((a != b).nnz == 0 for a, b in zip(paper.pomdp.transition, weighted.pomdp.transition))
    fact, fact_ones = factored_model(plan), factored_model(plan, weights=ones)
    assert np.abs(fact.class_fraction - fact_ones.class_fraction).max() <= 1e-15


def test_sequence_prior_is_the_product_of_the_choices(weighted):
    """Closed form: the flat initial belief of each full sequence is the product of p(e | s) along it, and the
    choices at each state sum to 1 (they are the Dirichlet posterior means of the module docstring)."""
    plan, weights, flat, fact = weighted
    p = weights * factored_model(plan).class_fraction[:-1]  # w(e) p0(e | s)
    assert np.abs(fact.class_fraction[:-1] - p).max() <= 1e-12  # the factored model moves by the habit choices
    for start in flat.full_sequences():
        chain, i = [], int(start)
        while flat.graph.successor[i] >= 0:
            chain.append(int(flat.graph.step_edge[i]))
            i = int(flat.graph.successor[i])
        assert flat.pomdp.initial[start] == pytest.approx(float(np.prod(p[chain])), rel=1e-12)
    assert np.allclose(np.bincount(plan.states.edge_source, weights=p)[1:], 1.0, atol=1e-12)


def test_habit_choice_is_the_dirichlet_posterior_mean(pen):
    """p(e|s) = (n(s,e) + alpha deg(s) p0(e|s)) / (n(s) + alpha deg(s)), checked at the initial state by hand,
    with p0 the paper's choice N(target)/N(s); an operation never seen keeps a probability."""
    plan = make_plan(pen)
    states = plan.states
    counts = np.zeros(states.n_edges)
    first = np.flatnonzero(states.edge_source == states.initial)
    counts[first[0]] = 7
    p = choice_probabilities(plan, counts, 0.5)
    paper = choice_probabilities(plan, np.zeros(states.n_edges), 0.5)
    d = first.size
    expected = (counts[first] + 0.5 * d * paper[first]) / (7 + 0.5 * d)
    assert np.allclose(p[first], expected, rtol=1e-12) and np.all(p[first] > 0)
    assert p[first].sum() == pytest.approx(1.0)
    assert paper[first].sum() == pytest.approx(1.0)


def _assert_same(flat_model, fact, weights, b, belief):
    assert np.max(np.abs(to_flat(belief, flat_model.graph, weights) - b)) <= TOLERANCE
    assert np.max(np.abs(fact.expected_rewards(belief) - flat_model.pomdp.reward @ b)) <= TOLERANCE


def test_flat_factored_and_lumped_beliefs_agree_along_episodes(weighted):
    """The flat filter (over intentions), the factored one (classes) and the lumped POMDP's (classes, as a bare
    POMDP) along random histories drawn from the flat model: the same beliefs, rewards and observation
    probabilities at every step."""
    plan, weights, flat_model, fact = weighted
    lumped = lumped_pomdp(fact)
    assert np.abs(lumped.initial - fact.initial_belief().dense(fact.n_classes)).max() <= 1e-15
    of = np.where(flat_model.graph.step_edge >= 0, flat_model.graph.step_edge, fact.final_class)
    for b, belief, c in filtered_histories(flat_model, fact, lumped, np.random.default_rng(5), 8, 20, TOLERANCE):
        _assert_same(flat_model, fact, weights, b, belief)
        assert np.abs(np.bincount(of, weights=b, minlength=fact.n_classes) - c).max() <= TOLERANCE
        assert np.abs(belief.dense(fact.n_classes) - c).max() <= TOLERANCE


def test_resets_spread_by_the_prior_weights(weighted):
    """Unexplained observations at beliefs along missed detections: the weighted flat reset (by the intentions'
    prior weights) equals the factored one, rule by rule."""
    _, weights, flat_model, fact = weighted
    flat, factored = DiscreteUpdater(flat_model.pomdp, reset_weights=flat_model.prior_weights), FactoredUpdater(fact)
    b, belief = flat.initialize(), factored.initialize()
    wait = len(fact.actions) - 1
    kinds = set()
    for _ in range(5):
        b, belief = flat.update(b, wait, 0), factored.update(belief, wait, 0)
        for action in range(len(fact.actions)):
            for z in range(len(fact.observations)):
                one = DiscreteUpdater(flat_model.pomdp, on_reset=lambda e: None, reset_weights=flat_model.prior_weights)
                mine = FactoredUpdater(fact, on_reset=lambda e: None)
                expected, got = one.update(b, action, z), mine.update(belief, action, z)
                assert np.max(np.abs(to_flat(got, flat_model.graph, weights) - expected)) <= TOLERANCE
                assert [e.reset_to for e in one.events] == [e.reset_to for e in mine.events]
                kinds.update(e.reset_to for e in mine.events)
    assert "reachable" in kinds


def test_base_part_with_habits(pen):
    """With a base part the prior is the habits' prior conditioned on the allowed first steps: flat = factored."""
    plan = make_plan(pen, False)
    weights = habit_weights_from(plan, _random_counts(plan, np.random.default_rng(9), 0.8), 1.0)
    flat_model = intention_model(plan, base_part="body", weights=weights)
    fact = factored_model(plan, base_part="body", weights=weights)
    flat, factored = DiscreteUpdater(flat_model.pomdp, reset_weights=flat_model.prior_weights), FactoredUpdater(fact)
    b, belief = flat.initialize(), factored.initialize()
    rng = np.random.default_rng(2)
    for _ in range(10):
        _assert_same(flat_model, fact, weights, b, belief)
        a, z = int(rng.integers(len(fact.actions))), 0
        b, belief = flat.update(b, a, z), factored.update(belief, a, z)


def test_counted_sequence_dominates_the_prior(pen):
    """Twenty sessions of one sequence: it becomes the most likely by far, yet every other keeps a probability."""
    plan = make_plan(pen)
    fact = factored_model(plan)
    chosen = fact.sequence_operations(fact.sequence(5))
    counts = np.zeros(plan.states.n_edges)
    for _ in range(20):
        assert add_sequence(plan, counts, chosen) == plan.states.final
    assert counts.sum() == 20 * (len(plan.product.parts) - 1)
    flat = intention_model(plan, weights=habit_weights_from(plan, counts, 1.0))
    initial = flat.pomdp.initial[flat.full_sequences()]
    ops = [flat.sequence_operations(int(i)) for i in flat.full_sequences()]
    top = int(np.argmax(initial))
    assert ops[top] == chosen and initial[top] > 0.5 and np.all(initial > 0)




def test_planners_run_on_the_weighted_models_with_the_same_values(pen):
    """The offline solver on the weighted flat and lumped POMDPs (the same work): the certified intervals of
    V*(b0) overlap; the exact three-step values are equal; the online planner and the lumped model's bounds
    (which read the weighted fractions) start from the same belief."""
    from planner.decision import PointBasedSolver
    from planner.decision.solvers.warm_start import solver_bounds
    from planner.decision.online import OnlinePlanner

    plan = make_plan(pen, True)
    counts = _random_counts(plan, np.random.default_rng(4), 0.7)
    for _ in range(3):  # a strong habit on top: the robot then acts early
        add_sequence(plan, counts, factored_model(plan).sequence_operations(factored_model(plan).sequence(3)))
    counts *= 10
    weights = habit_weights_from(plan, counts, 1.0)
    flat, fact = intention_model(plan, weights=weights).pomdp, factored_model(plan, weights=weights)
    lumped = lumped_pomdp(fact)
    paper = intention_model(plan).pomdp
    value = horizon_value(flat, 3)
    assert value > 0 and horizon_value(lumped, 3) == pytest.approx(value, abs=1e-9)
    solver = PointBasedSolver(time_limit=None, max_iterations=60, precision=1e-6)
    Q, groups = solver_bounds(fact)
    a, b = solver.solve(flat), solver.solve(lumped, upper=Q, groups=groups)
    assert max(a.lower_bound, b.lower_bound) <= min(a.upper_bound, b.upper_bound) + 1e-9
    c = solver.solve(paper)  # the habits raise the value: the robot knows the operator's order sooner
    assert min(a.lower_bound, b.lower_bound) > c.upper_bound
    planner = OnlinePlanner(fact, 50, None)
    assert 0 <= planner.action(fact.initial_belief()) < len(fact.actions)
