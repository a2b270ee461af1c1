"""The solver's time limit is a limit (issue 14, item 9): it covers the upper bound's set-up and is checked
inside long steps. Tested with an injected clock (a counter), so by work, never by the machine's speed."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from planner import api
from planner.decision.solvers.lower import LowerBound
from planner.decision.solvers.point_based import PointBasedSolver
from planner.decision.solvers.tables import SolveStopped, Tables, fast_informed_bound, mdp_upper_bound
from planner.decision.solvers.trials import descend, trial
from planner.decision.solvers.upper import UpperBound


@pytest.fixture(scope="module")
def slow_pen():
    """The pen with a discount of 0.99999: value iteration needs over 100,000 sweeps to converge."""
    return api.tables(api.load_model("pen", discount=0.99999))


class Counter:
    """A clock that advances one unit per reading."""

    def __init__(self):
        self.readings = itertools.count()

    def __call__(self) -> float:
        return float(next(self.readings))


def _counting_expect(monkeypatch) -> list:
    calls = []
    original = Tables.expect

    def expect(self, W):
        calls.append(1)
        return original(self, W)

    monkeypatch.setattr(Tables, "expect", expect)
    return calls


def test_mdp_bound_stops_at_the_deadline(slow_pen, monkeypatch):
    calls = _counting_expect(monkeypatch)
    m = Tables(slow_pen)
    clock = Counter()
    Q = mdp_upper_bound(m, deadline=10, clock=clock)
    assert len(calls) == 11  # one sweep per reading, readings 0..10
    calls.clear()
    full = mdp_upper_bound(m, max_sweeps=200)
    assert len(calls) == 200  # without a deadline it would go on (to 100,000 sweeps)
    assert np.all(Q >= full - 1e-9)  # an earlier iterate, and a larger (still valid) upper bound


def test_informed_bound_drops_an_unfinished_sweep(slow_pen):
    m = Tables(slow_pen)
    mdp = mdp_upper_bound(m, max_sweeps=2)
    # Readings 0 and 1: two MDP sweeps, the second reaching the deadline; reading 2, inside the first informed
    # sweep, is past it: that sweep is dropped and the MDP bound kept.
    Q = fast_informed_bound(m, deadline=1, clock=Counter())
    assert np.array_equal(Q, mdp)


def test_solver_time_limit_covers_the_set_up(slow_pen, monkeypatch):
    calls = _counting_expect(monkeypatch)
    limit = 40
    result = PointBasedSolver(time_limit=limit, clock=Counter()).solve(slow_pen)
    # A quarter of the limit (10 readings) for the set-up's value iteration, then a few steps; without the
    # limit on the set-up, value iteration alone would make 100,000 products.
    assert len(calls) < 100
    assert result.lower_bound <= result.upper_bound
    assert result.seconds <= limit + 20  # readings after the limit: bookkeeping only, no further step


def test_a_deep_trial_stops_at_the_limit(slow_pen):
    m = Tables(slow_pen)
    b0 = np.asarray(slow_pen.initial, dtype=float)
    lower = LowerBound.blind(m)
    upper = UpperBound(mdp_upper_bound(m, max_sweeps=3), np.random.default_rng(0).random(m.S))
    deep = descend(m, b0, lower, upper, epsilon=1e-3, max_depth=50)
    assert len(deep) > 10  # with a discount near 1 a trial goes deep
    assert descend(m, b0, lower, upper, epsilon=1e-3, max_depth=50, stop=lambda: True) == []  # not even one step
    # The limit passing inside a step (the k-th reading of the clock) drops that step: the path is the deep
    # one's first steps, each complete.
    for k in (1, 5, 40):
        readings = itertools.count()
        stopped = descend(m, b0, lower, upper, epsilon=1e-3, max_depth=50, stop=lambda: next(readings) >= k)
        assert 0 < len(stopped) < len(deep)
        assert all(np.array_equal(a.belief, b.belief) for a, b in zip(stopped, deep))
        assert all(len(a.successors.action) == len(b.successors.action) for a, b in zip(stopped, deep))


def test_a_step_stopped_on_a_large_model(slow_pen, monkeypatch):
    """Per action on a large model (past SUCCESSOR_BLOCK): the limit passing between two actions stops the
    step (SolveStopped), and a trial then backs up only the steps it finished, so both bounds at b0 stay
    bounds (the lower at most, the upper at least, the unstopped trial's)."""
    import planner.decision.solvers.tables as tables

    monkeypatch.setattr(tables, "SUCCESSOR_BLOCK", 0)
    m = Tables(slow_pen)
    b0 = np.asarray(slow_pen.initial, dtype=float)
    readings = itertools.count()
    with pytest.raises(SolveStopped):
        m.successors(b0, None, stop=lambda: next(readings) >= 3)
    lower = LowerBound.blind(m)
    upper = UpperBound(mdp_upper_bound(m, max_sweeps=3), np.random.default_rng(0).random(m.S))
    readings = itertools.count()
    trial(m, b0, lower, upper, None, 1e-3, max_depth=50, stop=lambda: next(readings) >= 60)
    cut_low, cut_high = lower.value(b0), upper.value(b0)
    lower_full = LowerBound.blind(m)
    upper_full = UpperBound(mdp_upper_bound(m, max_sweeps=3), np.random.default_rng(0).random(m.S))
    trial(m, b0, lower_full, upper_full, None, 1e-3, max_depth=50)
    assert cut_low <= lower_full.value(b0) + 1e-9 and cut_high >= upper_full.value(b0) - 1e-9
    assert cut_low <= cut_high


def test_large_model_successors_are_the_same(slow_pen, monkeypatch):
    """Past SUCCESSOR_BLOCK numbers, the successors are computed per action (no (A, Z, S) product): the same
    pairs, probabilities and beliefs as the one-product path."""
    import planner.decision.solvers.tables as tables

    m = Tables(slow_pen)
    b = np.asarray(slow_pen.initial, dtype=float)
    for actions in (None, np.array([0, 3, 7])):
        whole = m.successors(b, actions)
        monkeypatch.setattr(tables, "SUCCESSOR_BLOCK", 0)
        blocked = m.successors(b, actions)
        monkeypatch.undo()
        assert [np.array_equal(x, y) for x, y in zip(whole[:2], blocked[:2])] == [True, True]
        assert np.allclose(whole[2], blocked[2], rtol=1e-12) and np.allclose(whole[3], blocked[3], rtol=1e-12)


def _beliefs_of(slow_pen, count: int = 40) -> tuple[Tables, np.ndarray, np.ndarray]:
    """The pen's tables, ``count`` beliefs reachable from b0 (a trial's successors) and the blind vectors."""
    m = Tables(slow_pen)
    b0 = np.asarray(slow_pen.initial, dtype=float)
    beliefs = m.successors(b0)[3][:count]
    return m, np.vstack([b0, beliefs]), LowerBound.blind(m).vectors


def test_a_sweep_stops_between_its_back_ups(slow_pen):
    """A sweep of the belief set (36 s of one step on the flat chain of 9, the overshoot of --time-limit 60)
    stops between blocks of back-ups: it returns the vectors of the actions backed up so far, each the value of
    a policy (no higher than the full sweep's best at any of the beliefs), and backs up fewer pairs."""
    from planner.decision.solvers.belief_set import sweep

    m, beliefs, alphas = _beliefs_of(slow_pen)
    q = mdp_upper_bound(m, max_sweeps=3)
    full = sweep(m, beliefs, alphas, q)
    assert full[3] > 0 and len(full[0]) > 0
    with pytest.raises(SolveStopped):  # before the first back-up: the current values' products stop it
        sweep(m, beliefs, alphas, q, stop=lambda: True)
    readings = itertools.count()
    # The limit passes at the 14th reading: the first actions (up to 12, the first that improves) backed up.
    cut = sweep(m, beliefs, alphas, q, stop=lambda: next(readings) >= 14)
    assert 0 < cut[3] < full[3] and cut[1].tolist() == [12] and sorted(full[1].tolist()) == [12, 13]
    best_full = (full[0] @ beliefs.T).max(axis=0)
    assert np.all((cut[0] @ beliefs.T).max(axis=0) <= best_full + 1e-9)


def test_belief_growth_stops_at_the_limit(slow_pen):
    from planner.decision.solvers.belief_set import policy_successors

    m, beliefs, _ = _beliefs_of(slow_pen)
    actions = np.arange(len(beliefs)) % m.A
    weights = np.ones(len(beliefs))
    whole = policy_successors(m, beliefs, actions, weights)
    assert policy_successors(m, beliefs, actions, weights, stop=lambda: True)[0].shape == (0, m.S)
    readings = itertools.count()
    some = policy_successors(m, beliefs, actions, weights, stop=lambda: next(readings) >= 3)
    assert 0 < len(some[0]) < len(whole[0])
    assert np.array_equal(some[0], whole[0][:len(some[0])])  # the first products' successors, as they were


def test_the_sweeps_stop_at_the_limit(slow_pen):
    """The solver's lower-bound process under a limit that passes inside its steps: no step runs on past it
    (with a counter clock, the readings after the limit are a handful of checks, not a step's thousands)."""
    from planner.decision.solvers.belief_set import BeliefSet
    from planner.decision.solvers.sweeps import sweep_rounds

    m, beliefs, _ = _beliefs_of(slow_pen)
    lower = LowerBound.blind(m)
    q = mdp_upper_bound(m, max_sweeps=3)
    belief_set = BeliefSet(m.S)
    belief_set.add(beliefs, np.ones(len(beliefs)))
    readings = itertools.count()
    steps = sweep_rounds(m, lower, belief_set, q, stop=lambda: next(readings) >= 5)
    work = [next(steps) for _ in range(6)]
    assert work[-1] == 0.0  # stopped steps do no work
    before = next(readings)
    next(steps)
    assert next(readings) - before <= 3  # a stopped step reads the clock once or twice and returns


def test_products_of_many_beliefs_stop_between_blocks_of_work(slow_pen, monkeypatch):
    """Both bounds at many beliefs (a trial's successors on a large model: 7 s for the lower bound's products
    at the 9-part chain's b0) are computed in blocks of about WORK multiply-adds, the limit checked between
    them: the same values in blocks, and a limit passing midway stops the product."""
    import planner.decision.solvers.tables as tables
    import planner.decision.solvers.upper as upper_module
    from planner.decision.solvers.tables import best_products

    m, beliefs, vectors = _beliefs_of(slow_pen)
    upper = UpperBound(mdp_upper_bound(m, max_sweeps=3), np.random.default_rng(0).random(m.S))
    for b in beliefs[:5]:  # points for the sawtooth
        upper.update(b, upper.value(b) - 0.1)
    whole_lower, whole_upper = best_products(beliefs, vectors), upper.at(beliefs)
    monkeypatch.setattr(tables, "WORK", 1)  # one belief per block
    monkeypatch.setattr(upper_module, "WORK", 1)
    readings = itertools.count()
    blocked_lower = best_products(beliefs, vectors, stop=lambda: next(readings) < 0)
    assert next(readings) == len(beliefs)  # checked before every block, one belief each
    assert np.array_equal(blocked_lower[1], whole_lower[1]) and np.allclose(blocked_lower[0], whole_lower[0])
    assert np.allclose(upper.at(beliefs, stop=lambda: False), whole_upper)
    for product in (lambda stop: best_products(beliefs, vectors, stop), lambda stop: upper.at(beliefs, stop=stop)):
        readings = itertools.count()
        with pytest.raises(SolveStopped):
            product(lambda: next(readings) >= 10)
        assert next(readings) == 11  # stopped at the tenth block of 41, not after all of them


def test_a_policy_no_better_than_blind_is_refused(slow_pen):
    """Issue 22 item 4: a limit the set-up uses up leaves the blind policies (or their floor); the result says
    so (``improved``) and :func:`planner.api.check_solved` refuses it, naming the bound and what helps."""
    from planner.errors import SolveTimeError

    result = PointBasedSolver(time_limit=4, clock=Counter()).solve(slow_pen)
    assert result.iterations == 0 and not result.improved()
    with pytest.raises(SolveTimeError, match=r"blind policies.*--time-limit 34"):
        api.check_solved(result, 1e-3, 4)
    # work-bounded, the same model improves on them, and the policy is kept
    done = PointBasedSolver(time_limit=None, max_iterations=5).solve(api.tables(api.load_model("pen")))
    assert done.improved(1e-3) and api.check_solved(done, 1e-3, 60) is None


def test_known_points_stop_at_the_set_up_deadline(slow_pen):
    """The warm start's points are optional: past the set-up's deadline none is added (the bound holds without
    them), before it every one that lies below the bound is."""
    from planner.decision.solvers.point_based import _add_points

    m = Tables(slow_pen)
    Q = mdp_upper_bound(m, max_sweeps=3)
    B = np.random.default_rng(1).dirichlet(np.ones(m.S), 300)
    values = UpperBound(Q, np.ones(m.S)).at(B) - 1.0  # one below the bound: every point is worth storing
    late = UpperBound(Q, np.random.default_rng(0).random(m.S))
    _add_points(late, B, values, 10 ** 9, lambda: True)
    assert late.n == 0
    kept = UpperBound(Q, np.random.default_rng(0).random(m.S))
    _add_points(kept, B, values, 10 ** 9, lambda: False)
    assert kept.n == len(B)
