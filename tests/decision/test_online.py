"""The online planner on the factored model: its bounds against independent computations (value iteration on
the class MDP, the flat model's solver), its observation split against the Bayes filter, reproducibility at a
fixed amount of work, and that it helps (a return above never acting) and finishes products too large for the
flat model."""
from __future__ import annotations

import numpy as np
import pytest

from planner import PlannerError, chain_product, count_intentions, make_plan
from planner.decision import FactoredUpdater, factored_model, intention_model
from planner.decision.factored_model import FactoredBelief
from planner.decision.episodes import EpisodeChoice, evaluate
from planner.decision.factored_simulate import PathWorld
from planner.decision.simulate import simulate_episode
from planner.decision.online import OnlinePlanner, class_values, observation_split
from planner.decision.solvers import PointBasedSolver


@pytest.fixture(scope="module", params=[False, True], ids=["no-technical", "technical"])
def pen_factored(request, pen):
    return factored_model(make_plan(pen, request.param))


def _one_hot(model, c):
    return FactoredBelief(np.array([c]), np.array([1.0]))


def _value_iteration(model, sweeps=400):
    """The class MDP solved by plain value iteration over the tables the factored filter itself predicts."""
    n, A = model.n_classes, len(model.actions)
    moves = [[model.predict(_one_hot(model, c), a) for a in range(A)] for c in range(n)]
    reward = np.array([[model.expected_reward(_one_hot(model, c), a) for a in range(A)] for c in range(n)])
    value = np.zeros(n)
    for _ in range(sweeps):
        q = reward + model.discount * np.array([[m.mass @ value[m.classes] for m in row] for row in moves])
        value = q.max(axis=1)
    return value


def test_class_values_equal_value_iteration(pen_factored):
    values = class_values(pen_factored)
    assert np.max(np.abs(values.value - _value_iteration(pen_factored))) < 1e-6
    chain = factored_model(make_plan(chain_product(5)))
    assert np.max(np.abs(class_values(chain).value - _value_iteration(chain))) < 1e-6


def test_bounds_bracket_the_flat_models_value(pen):
    """The planner's root bounds contain the flat POMDP's value at the initial belief (the solver's bounds,
    at a fixed amount of work)."""
    plan = make_plan(pen)
    flat = PointBasedSolver(max_iterations=300, time_limit=None, precision=1e-3, seed=0).solve(
        intention_model(plan).pomdp)
    planner = OnlinePlanner(factored_model(plan), expansions=300)
    report = planner.search(planner.model.initial_belief())
    assert report.lower <= flat.upper_bound + 1e-9 and flat.lower_bound <= report.upper + 1e-9
    assert report.upper - report.lower < class_values(planner.model).value.max()  # the search tightened them


def test_observation_split_is_the_bayes_filter(pen_factored):
    model = pen_factored
    updater = FactoredUpdater(model)
    rng = np.random.default_rng(0)
    belief = updater.initialize()
    for _ in range(12):
        action = int(rng.integers(len(model.actions)))
        branches = observation_split(model, model.predict(belief, action))
        assert sum(p for _, p, _ in branches) == pytest.approx(1.0, abs=1e-12)
        for z, p, posterior in branches:
            expected = updater.update(belief, action, z)
            assert np.array_equal(posterior.classes, expected.classes)
            assert np.max(np.abs(posterior.mass - expected.mass)) < 1e-12
        z, _, belief = branches[int(rng.integers(len(branches)))]
    assert not updater.events


def test_reproducible_at_a_fixed_amount_of_work(pen_factored):
    def actions():
        planner = OnlinePlanner(pen_factored, expansions=30)
        rng = np.random.default_rng(7)
        episode = simulate_episode(PathWorld(pen_factored, pen_factored.sample_sequence(rng)), planner, rng)
        return [s.action for s in episode.steps], [s.observation for s in episode.steps]

    assert actions() == actions()


def test_the_planner_helps(pen):
    """On the pen, acting by the planner earns more than never acting (return 0) beyond the 95 % interval."""
    model = factored_model(make_plan(pen))
    mean, half = evaluate(model, OnlinePlanner(model, expansions=3), EpisodeChoice(random=150, seed=3))
    assert mean - half > 0


def test_finishes_a_product_beyond_the_flat_model():
    """A chain of 11 parts (9,864,101 intentions, beyond the flat model's limit): every episode ends with the
    product assembled, and the filter never rules out the true intention."""
    plan = make_plan(chain_product(11))
    assert count_intentions(plan.states) == 9_864_101
    model = factored_model(plan)
    planner = OnlinePlanner(model, expansions=4)
    rng = np.random.default_rng(0)
    for _ in range(2):
        episode = simulate_episode(PathWorld(model, model.sample_sequence(rng)), planner, rng, max_steps=200)
        assert episode.finished and episode.resets == 0
        assert all(step.p_true > 0 for step in episode.steps)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_decision_time(pen_factored, bad):
    with pytest.raises(PlannerError, match="decision time must be a positive number"):
        OnlinePlanner(pen_factored, decision_time=bad)
    with pytest.raises(PlannerError, match="expansions must be a positive integer"):
        OnlinePlanner(pen_factored, expansions=0)


def test_an_offline_policy_is_the_lower_bound_it_starts_from(pen):
    """With the lumped model's policy as its lower bound, the planner's bound at the initial belief is at least
    that policy's value there (and still below the flat model's upper bound): it only improves on it."""
    from planner.decision import lumped_model

    lumped = lumped_model(make_plan(pen))
    result = PointBasedSolver(max_iterations=100, time_limit=None, precision=1e-3, seed=0).solve(lumped.pomdp)
    start = lumped.factored.initial_belief()
    offline = result.policy.value(start)
    assert offline == pytest.approx(result.policy.value(lumped.pomdp.initial))
    planner = OnlinePlanner(lumped.factored, expansions=20, lower=result.policy)
    report = planner.search(start)
    assert offline - 1e-9 <= report.lower <= result.upper_bound + 1e-9
    with pytest.raises(PlannerError, match="needs a policy over the model's 33 classes"):
        OnlinePlanner(lumped.factored, lower=type(result.policy)(np.zeros((1, 69)), np.array([0])))


def test_revealed_state_bound_is_an_upper_bound_below_qmdp(pen):
    """The "states revealed" bound lies between QMDP and the value: at every class it is at most QMDP's, and at
    least what the lumped model's lower-bound alpha vectors guarantee at that class (a lower bound on the value
    there), and at the initial belief at least the solver's lower bound."""
    from planner.decision import lumped_model
    from planner.decision.online import revealed_state_values

    for product in (pen, chain_product(6)):
        lumped = lumped_model(make_plan(product))
        qmdp, revealed = class_values(lumped.factored), revealed_state_values(lumped.factored)
        assert np.all(revealed.value <= qmdp.value + 1e-9)
        result = PointBasedSolver(max_iterations=150, time_limit=None, precision=1e-3, seed=0).solve(lumped.pomdp)
        assert np.all(result.policy.alphas.max(axis=0) <= revealed.value + 1e-9)
        start = lumped.factored.initial_belief()
        assert result.lower_bound <= revealed.q_values(lumped.factored, start).max() + 1e-9
        matrix = revealed.q_matrix(lumped.factored)
        assert np.allclose((matrix @ start.dense(lumped.factored.n_classes)),
                           revealed.q_values(lumped.factored, start))


def test_a_deadline_already_past_gives_the_best_lower_bound_at_once(pen_factored):
    """Issue 22 item 4: with no time left for any step, the root gets only its lower bounds ("act, then wait")
    and the action is their best (ties to wait); nothing is expanded."""
    from planner.decision.online import _argmax_prefer_last

    planner = OnlinePlanner(pen_factored, decision_time=1e-9)
    belief = pen_factored.initial_belief()
    report = planner.search(belief)
    g, r = pen_factored.discount, pen_factored.rewards
    lower = pen_factored.expected_rewards(belief) + g * r.wait / (1 - g)
    assert report.expansions == 0 and report.action == _argmax_prefer_last(lower)
    assert report.lower == pytest.approx(lower.max()) and report.upper >= report.lower


def test_the_search_tree_is_capped(pen_factored):
    """The tree holds at most about ``max_numbers`` numbers whatever ``expansions`` says (the search stops
    with the best action so far), by work: the same action and bounds each time."""
    belief = pen_factored.initial_belief()
    capped = [OnlinePlanner(pen_factored, expansions=1_000_000, max_numbers=20_000).search(belief) for _ in range(2)]
    first, second = ((r.action, r.lower, r.upper, r.expansions) for r in capped)
    assert first == second
    assert 0 < capped[0].expansions < 1_000_000
    planner = OnlinePlanner(pen_factored, expansions=capped[0].expansions + 50, max_numbers=10 ** 9)
    assert planner.search(belief).expansions > capped[0].expansions  # the cap, not the work, stopped it


def test_a_predicted_size_bounds_the_waiting_prediction():
    """The estimate a step is timed by: for waiting it is at least the prediction's support (each class
    moving to the classes out of its target, counted with repeats)."""
    from planner.decision.online_steps import StepTimes

    model = factored_model(make_plan(chain_product(6)))
    steps = StepTimes(model)
    updater = FactoredUpdater(model, on_reset=lambda event: None)
    belief = updater.initialize()
    for _ in range(4):
        assert steps.predicted_size(belief, model.wait) >= model.predict(belief, model.wait).classes.size
        for action in range(len(model.action_operations) - 1):
            assert steps.predicted_size(belief, action) >= belief.classes.size
        belief = updater.update(belief, model.wait, 0)
