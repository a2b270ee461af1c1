"""The lumped POMDP over classes against the factored model (its tables, belief by belief) and against the flat
model of Alg. 3 (flat beliefs summed per class, exact finite-horizon values, the solver's bounds)."""
from __future__ import annotations

import numpy as np
import pytest

from planner import chain_product, complete_product, make_plan
from planner.decision import FactoredBelief, PointBasedSolver, factored_model, intention_model
from planner.decision.lumped_model import LUMPED_SUFFIX, advance_matrix, lumped_pomdp
from reference import horizon_value

TOLERANCE = 1e-12


@pytest.fixture(scope="module", params=["pen-no-technical", "pen-technical", "chain-5", "complete-4"])
def models(request, pen):
    product, technical = {"pen-no-technical": (pen, False), "pen-technical": (pen, True),
                          "chain-5": (chain_product(5), None), "complete-4": (complete_product(4), None)}[request.param]
    plan = make_plan(product, technical)
    fact = factored_model(plan)
    return plan, fact, lumped_pomdp(fact)


def _random_beliefs(n, rng, count=20):
    for _ in range(count):
        classes = np.sort(rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False))
        mass = rng.random(classes.size) + 1e-3
        yield FactoredBelief(classes, mass / mass.sum())


def test_tables_equal_the_factored_model(models):
    _, fact, lumped = models
    n = fact.n_classes
    assert lumped.n_states == n == fact.plan.states.n_edges + 1
    assert lumped.actions == fact.actions and lumped.observations == fact.observations
    assert lumped.name.endswith(LUMPED_SUFFIX)
    assert np.array_equal(lumped.initial, fact.initial_belief().dense(n))
    every = np.arange(n)
    for z in range(lumped.n_observations):
        for a in range(lumped.n_actions):
            assert np.abs(lumped.observation[a][:, z].toarray().ravel()
                          - fact.observation_likelihood(z)).max() <= TOLERANCE
    for a in range(lumped.n_actions):
        assert np.array_equal(lumped.reward[a], fact.rewards_of(every, a))
    for belief in _random_beliefs(n, np.random.default_rng(1)):
        dense = belief.dense(n)
        for a in range(lumped.n_actions):
            predicted = lumped.transition[a].T @ dense
            assert np.abs(predicted - fact.predict(belief, a).dense(n)).max() <= TOLERANCE
        assert np.abs(lumped.reward @ dense - fact.expected_rewards(belief)).max() <= 1e-9


def test_advance_matrix_is_stochastic_and_counts_paths(models):
    plan, fact, _ = models
    advance = advance_matrix(fact)
    assert np.allclose(np.asarray(advance.sum(axis=1)).ravel(), 1.0)
    # One step from the initial state, repeated to the end: every full sequence reaches the finished product.
    belief = fact.initial_belief().dense(fact.n_classes)
    for _ in range(len(plan.product.parts) - 1):
        belief = advance.T @ belief
    assert belief[fact.final_class] == pytest.approx(1.0)


def _class_of(flat_model, fact) -> np.ndarray:
    step = flat_model.graph.step_edge
    return np.where(step >= 0, step, fact.final_class)


def _lump(flat_belief, class_of, n):
    return np.bincount(class_of, weights=flat_belief, minlength=n)


def test_flat_beliefs_lump_to_lumped_beliefs(pen):
    """Random histories on the flat pen model: the flat belief summed per class equals the lumped belief, with the
    same observation probabilities and expected rewards, at every step."""
    plan = make_plan(pen, False)
    flat_model, fact = intention_model(plan), factored_model(plan)
    flat, lumped = flat_model.pomdp, lumped_pomdp(fact)
    class_of = _class_of(flat_model, fact)
    rng = np.random.default_rng(3)
    for _ in range(20):
        b, c = flat.initial.copy(), lumped.initial.copy()
        for _ in range(12):
            assert np.abs(_lump(b, class_of, lumped.n_states) - c).max() <= 1e-12
            assert np.abs(flat.reward @ b - lumped.reward @ c).max() <= 1e-9
            a = int(rng.integers(flat.n_actions))
            pb = flat.transition[a].T @ b
            pc = lumped.transition[a].T @ c
            zb = flat.observation[a].T @ pb
            zc = lumped.observation[a].T @ pc
            assert np.abs(zb - zc).max() <= 1e-12
            z = int(rng.choice(flat.n_observations, p=zb / zb.sum()))
            b = pb * flat.observation[a][:, z].toarray().ravel() / zb[z]
            c = pc * lumped.observation[a][:, z].toarray().ravel() / zc[z]




@pytest.mark.parametrize("technical", [True, False])
def test_finite_horizon_values_equal_the_flat_model(pen, technical):
    plan = make_plan(pen, technical)
    flat, lumped = intention_model(plan).pomdp, lumped_pomdp(factored_model(plan))
    for depth in (1, 2, 3):
        assert horizon_value(lumped, depth) == pytest.approx(horizon_value(flat, depth), abs=1e-9)


def test_solver_bounds_agree_with_the_flat_model(pen):
    """Both models solved by the same amount of work: the certified intervals of V*(b0) overlap, and are narrow."""
    plan = make_plan(pen, True)
    flat, lumped = intention_model(plan).pomdp, lumped_pomdp(factored_model(plan))
    solver = PointBasedSolver(time_limit=None, max_iterations=200, precision=1e-4)
    a, b = solver.solve(flat), solver.solve(lumped)
    assert a.gap < 0.1 and b.gap < 0.1
    assert max(a.lower_bound, b.lower_bound) <= min(a.upper_bound, b.upper_bound) + 1e-9


def test_sizes(pen):
    # Classes are the state edges plus the finished product (pen: 32 + 1; chain of 7: 192 + 1).
    assert lumped_pomdp(factored_model(make_plan(pen, False))).n_states == 33
    assert lumped_pomdp(factored_model(make_plan(chain_product(7)))).n_states == 193


def test_solver_bounds_groups_spread_over_each_state(models):
    """One group per assembly state with two or more classes out of it: those classes, by their fractions
    (summing to 1), with the "state known" value, which is at most the classes' own bound averaged."""
    from planner.decision.solvers.warm_start import solver_bounds

    plan, fact, lumped = models
    Q, groups = solver_bounds(fact)
    assert Q.shape == (lumped.n_actions, lumped.n_states)
    counts = np.diff(fact.state_class_start)
    assert groups.n == int(np.sum(counts >= 2)) and len(np.unique(groups.member)) == len(groups.member)
    sums = np.add.reduceat(groups.weight, groups.start)
    assert np.allclose(sums, 1.0, atol=1e-12)
    assert np.all(groups.beliefs(lumped.n_states) @ Q.max(axis=0) >= groups.value - 1e-9)
    assert set(fact.class_source[groups.member].tolist()) == set(np.flatnonzero(counts >= 2).tolist())


@pytest.mark.parametrize("name", ["pen-technical", "chain-5"])
def test_corner_groups_keep_the_solver_bounds_valid_and_tighter(pen, name):
    """The lumped model solved with and without the groups, by the same number of trials: both certified
    intervals contain V*(b0) (they overlap, and overlap the flat model's on the pen), and the groups'
    upper bound is the lower one."""
    from planner.decision.solvers.warm_start import solver_bounds

    product, technical = (pen, True) if name == "pen-technical" else (chain_product(5), None)
    plan = make_plan(product, technical)
    fact = factored_model(plan)
    lumped = lumped_pomdp(fact)
    solver = PointBasedSolver(time_limit=None, max_iterations=60, precision=1e-6)
    Q, groups = solver_bounds(fact)
    plain, grouped = solver.solve(lumped, upper=Q), solver.solve(lumped, upper=Q, groups=groups)
    assert max(plain.lower_bound, grouped.lower_bound) <= min(plain.upper_bound, grouped.upper_bound) + 1e-9
    assert grouped.upper_bound < plain.upper_bound
    if name == "pen-technical":
        flat = solver.solve(intention_model(plan).pomdp)
        assert max(flat.lower_bound, grouped.lower_bound) <= min(flat.upper_bound, grouped.upper_bound) + 1e-9
