"""The delayed-reveal upper bound (the state told one step late) against an independent expectimax of the same
relaxed problem, against the exact finite-horizon values of the lumped model, and inside the solver."""
from __future__ import annotations

import numpy as np
import pytest

from planner import chain_product, complete_product, make_plan
from planner.decision import PointBasedSolver, factored_model, intention_model
from planner.decision.delayed_reveal import delayed_reveal_bound, reveal_graph, reveal_values
from planner.decision.lumped_model import LumpedModel, lumped_pomdp
from planner.decision.solvers.warm_start import solver_bounds, solver_start
from planner.decision.online import revealed_state_values
from planner.decision.solvers.upper import UpperBound


@pytest.fixture(scope="module", params=["pen-technical", "pen-no-technical", "chain-4", "complete-3"])
def models(request, pen):
    product, technical = {"pen-technical": (pen, True), "pen-no-technical": (pen, False),
                          "chain-4": (chain_product(4), None), "complete-3": (complete_product(3), None)}[request.param]
    fact = factored_model(make_plan(product, technical))
    return fact, lumped_pomdp(fact)


def _relaxed_value(fact, pomdp, depth: int) -> float:
    """The relaxed problem's ``depth``-step value at the initial belief by plain expectimax over *every*
    action (dense tables, no graph): after waiting the state is told, after a robot action every class."""
    T = [t.toarray() for t in pomdp.transition]
    O = pomdp.observation[0].toarray()
    R, g, wait = pomdp.reward, pomdp.discount, pomdp.n_actions - 1
    state = fact.class_source

    def value(b, d):
        if d == 0:
            return 0.0
        best = -np.inf
        for a in range(pomdp.n_actions):
            support = np.flatnonzero(b)
            if a == wait:
                cells = [np.where(state == s, b, 0.0) for s in np.unique(state[support])]
            else:
                cells = [np.where(np.arange(len(b)) == c, b, 0.0) for c in support]
            future = 0.0
            for cell in cells:
                predicted = cell @ T[a]
                for z in range(O.shape[1]):
                    joint = predicted * O[:, z]
                    if joint.sum() > 1e-15:
                        future += joint.sum() * value(joint / joint.sum(), d - 1)
            best = max(best, float(R[a] @ b) + g * future)
        return best

    return value(np.asarray(pomdp.initial, dtype=float), depth)


def _horizon_value(model, depth: int, start: np.ndarray | None = None) -> np.ndarray | float:
    """The lumped model's own optimal ``depth``-step value (exact expectimax, unnormalised beliefs) at the
    initial belief, or at each row of ``start``."""
    T = [t.toarray() for t in model.transition]
    O = [o.toarray() for o in model.observation]

    def value(B, d):
        if d == 1:
            return (B @ model.reward.T).max(axis=1)
        q = np.empty((len(B), model.n_actions))
        for a in range(model.n_actions):
            nxt = (B @ T[a])[:, None, :] * O[a].T[None]
            q[:, a] = B @ model.reward[a] + model.discount * value(nxt.reshape(-1, model.n_states), d - 1).reshape(
                len(B), -1).sum(axis=1)
        return q.max(axis=1)
    if start is not None:
        return value(start, depth)
    return float(value(model.initial[None], depth)[0])


def test_the_graph_gives_the_relaxed_problems_finite_horizon_values(models):
    """``H`` sweeps from zero equal an expectimax of the relaxed problem that tries every action (so the one
    probe stands rightly for all robot actions that perform nothing), and bound the lumped model's own
    ``H``-step value from above."""
    fact, pomdp = models
    graph = reveal_graph(fact, pomdp)
    for depth in (1, 2):
        relaxed = reveal_values(graph, 0.0, depth)[graph.initial[0]]
        assert relaxed == pytest.approx(_relaxed_value(fact, pomdp, depth), abs=1e-9)
        assert relaxed >= _horizon_value(pomdp, depth) - 1e-9


def test_the_graph_is_closed_and_its_rows_are_distributions(models):
    fact, pomdp = models
    graph = reveal_graph(fact, pomdp)
    assert np.allclose(np.asarray(graph.beliefs.sum(axis=1)).ravel(), 1.0)
    assert np.allclose(np.asarray(graph.successors.sum(axis=1)).ravel(), 1.0)
    assert np.array_equal(np.unique(graph.owner), np.arange(graph.n))      # every belief has its rows
    dense = graph.beliefs.toarray()
    assert np.allclose(dense[graph.initial[0]], pomdp.initial)
    assert np.array_equal(dense[graph.corner[0]], np.eye(pomdp.n_states))


@pytest.mark.parametrize("name", ["pen-technical", "chain-5", "complete-4"])
def test_the_bound_lies_between_the_value_and_the_state_known_bound(pen, name):
    """Above the solver's certified lower bound at b0, below the "state known" start bound; the certified
    interval with the relaxation's start contains the one without it (both contain V*(b0)); on the pen it
    overlaps the flat model's."""
    product, technical = {"pen-technical": (pen, True), "chain-5": (chain_product(5), None),
                          "complete-4": (complete_product(4), None)}[name]
    plan = make_plan(product, technical)
    fact = factored_model(plan)
    pomdp = lumped_pomdp(fact)
    reveal = delayed_reveal_bound(fact, pomdp)
    b0 = np.asarray(pomdp.initial)
    state_known = float(revealed_state_values(fact).q_matrix(fact).max(axis=0) @ b0)
    solver = PointBasedSolver(time_limit=None, max_iterations=60, precision=1e-6)
    plain = solver.solve(pomdp, upper=solver_bounds(fact)[0], groups=solver_bounds(fact)[1])
    started = solver.solve(pomdp, **solver_start(LumpedModel(fact, pomdp)).solve_options)
    assert plain.lower_bound - 1e-9 <= reveal.initial_value <= state_known + 1e-9
    assert max(plain.lower_bound, started.lower_bound) <= min(plain.upper_bound, started.upper_bound) + 1e-9
    assert started.upper_bound <= reveal.initial_value + 1e-9
    if name == "pen-technical":
        flat = solver.solve(intention_model(plan).pomdp)
        assert max(flat.lower_bound, started.lower_bound) <= min(flat.upper_bound, started.upper_bound) + 1e-9


def test_the_bound_is_far_below_the_state_known_one_on_larger_products():
    """Complete 5 (V*(b0) about 0.018): the state known gives 2.74, one step late 0.43."""
    fact = factored_model(make_plan(complete_product(5)))
    pomdp = lumped_pomdp(fact)
    reveal = delayed_reveal_bound(fact, pomdp)
    state_known = float(revealed_state_values(fact).q_matrix(fact).max(axis=0) @ pomdp.initial)
    assert reveal.initial_value < 0.2 * state_known
    assert reveal.initial_value == pytest.approx(0.4296, abs=1e-3)


def test_a_deadline_gives_no_bound():
    fact = factored_model(make_plan(chain_product(5)))
    assert delayed_reveal_bound(fact, lumped_pomdp(fact), deadline=0.0, clock=lambda: 1.0) is None


@pytest.mark.parametrize("finest", [1, 2])
def test_relaxed_q_values_bound_every_belief(models, finest):
    """The relaxed Q-values' bound (one action for the whole belief) equals the relaxed value at the initial
    belief (a spread), and lies above the lumped model's exact 2-step value at random beliefs and at the
    beliefs two steps from b0 (V* is at least that: waiting earns 0 from then on)."""
    fact, pomdp = models
    start = solver_start(LumpedModel(fact, pomdp), finest=finest, points=False)
    n = pomdp.n_states
    upper = UpperBound(start.upper, np.random.default_rng(0).random(n), start.groups, start.relaxed)
    b0 = np.asarray(pomdp.initial, dtype=float)
    assert upper.value(b0) == pytest.approx(start.reveal.initial_value, abs=1e-6)
    rng = np.random.default_rng(3)
    B = rng.random((40, n)) * (rng.random((40, n)) < 0.3)
    B[:, 0] += 1e-3
    B /= B.sum(axis=1, keepdims=True)
    reached = b0[None]
    for _ in range(2):  # every successor under every action and observation
        T = [t.toarray() for t in pomdp.transition]
        O = pomdp.observation[0].toarray()
        nxt = np.concatenate([(reached @ T[a])[:, None, :] * O.T[None] for a in range(pomdp.n_actions)], axis=1)
        nxt = nxt.reshape(-1, n)
        nxt = nxt[nxt.sum(axis=1) > 1e-12]
        reached = nxt / nxt.sum(axis=1, keepdims=True)
        reached = np.unique(np.round(reached, 12), axis=0)[:200]
    for beliefs in (B, reached):
        assert np.all(upper.at(beliefs) >= _horizon_value(pomdp, 2, beliefs) - 1e-9)
