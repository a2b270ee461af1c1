"""The point-based solver's parts, each alone: the bounds (lower.py, upper.py), the trials, the sweep rounds,
the work sharing and the BLAS threads; expected values from closed forms or direct computations."""
from __future__ import annotations

import numpy as np
import pytest
from test_pomdp_io import DOORS

from planner import make_plan
from planner.decision import intention_pomdp
from planner.decision.io.cassandra import read_cassandra
from planner.decision.solvers import PointBasedSolver
from planner.decision.solvers.belief_set import BeliefSet
from planner.decision.solvers.lower import LowerBound
from planner.decision.solvers.scheduler import WorkSharing
from planner.decision.solvers.sweeps import grow, sweep_rounds
from planner.decision.solvers.tables import Tables, fast_informed_bound
from planner.decision.solvers.threads import BLAS_VARIABLES, blas_threads, limited_blas
from planner.decision.solvers.trials import q_upper, successors, trial
from planner.decision.solvers.upper import UpperBound

GAMMA = 0.9
V0 = GAMMA / (1 - GAMMA ** 2)       # two doors, V* at the uniform belief: look, open, repeat
V_CORNER = 1 / (1 - GAMMA ** 2)     # V* where the prize is known: open it (+1), then V0


@pytest.fixture
def doors(tmp_path):
    path = tmp_path / "doors.pomdp"
    path.write_text(DOORS)
    return read_cassandra(path)


def _random_beliefs(rng, n, S, zero=0.4):
    """n beliefs over S states, each state left out with probability ``zero`` (never all of them)."""
    B = rng.random((n, S)) * (rng.random((n, S)) > zero)
    B[B.sum(axis=1) == 0, 0] = 1.0
    return B / B.sum(axis=1, keepdims=True)


def _random_upper(rng, S=5, A=3, points=40):
    """An UpperBound with a random Q and random points below the corner interpolation."""
    upper = UpperBound(rng.random((A, S)) * 10, rng.random(S))
    for b in _random_beliefs(rng, points, S):
        upper.update(b, float(b @ upper.corner) - rng.random() * 3)
    return upper


def _sawtooth(upper: UpperBound, b: np.ndarray, allowed=None) -> float:
    """The upper bound at b, straight from its definition (upper.py's module docstring)."""
    base = float(b @ upper.corner)
    value = min(float((upper.Q @ b).max()), base)
    for i, (point, excess) in enumerate(zip(upper.points.rows, upper.excess)):
        inside = point > 0
        if (allowed is None or allowed[i]) and np.all(b[inside] > 0):
            value = min(value, base + min(b[inside] / point[inside]) * excess)
    return value


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("block", [None, 0])
def test_upper_bound_is_the_sawtooth_of_its_definition(seed, block, monkeypatch):
    if block is not None:  # the path for wide beliefs over many points: candidates counted on non-zeros
        monkeypatch.setattr("planner.decision.solvers.upper.BLOCK", block)
    rng = np.random.default_rng(seed)
    upper = _random_upper(rng)
    B = np.vstack([_random_beliefs(rng, 60, 5), upper.points.rows, np.eye(5)])
    direct = [_sawtooth(upper, b) for b in B]
    assert np.allclose(upper.at(B), direct, rtol=0, atol=1e-12)
    allowed = rng.random((upper.n, len(B))) < 0.5
    direct = [_sawtooth(upper, b, allowed[:, j]) for j, b in enumerate(B)]
    assert np.allclose(upper.at(B, allowed), direct, rtol=0, atol=1e-12)
    # At a stored point the bound is at most the point's value; at a corner, at most the corner value.
    assert np.all(upper.at(upper.points.rows) <= upper.points.rows @ upper.corner + upper.excess + 1e-12)
    assert np.all(upper.at(np.eye(5)) <= upper.corner + 1e-12)


def test_upper_bound_keys_points_by_belief():
    upper = UpperBound(np.ones((2, 3)), np.array([0.3, 0.5, 0.7]))
    b = np.array([0.2, 0.3, 0.5])
    upper.update(b, 0.9)
    upper.update(b.copy(), 0.8)           # the same belief: its value is lowered, no second point
    upper.update(b[::-1].copy(), 0.95)
    assert upper.n == 2 and upper.excess.tolist() == pytest.approx([0.8 - 1.0, 0.95 - 1.0])
    assert upper.value(b) == pytest.approx(0.8)


@pytest.mark.parametrize("seed", range(5))
def test_pruning_points_never_changes_the_upper_bound(seed):
    rng = np.random.default_rng(seed)
    upper = _random_upper(rng, points=120)
    B = np.vstack([upper.points.rows, _random_beliefs(rng, 200, 5)])
    before, n = upper.at(B), upper.n
    upper.prune(chunk=16)
    assert upper.n < n  # some points were dominated
    assert np.allclose(upper.at(B), before, rtol=0, atol=1e-9)


def test_pruning_the_points_of_trials_on_the_pen(pen):
    model = intention_pomdp(make_plan(pen, True))
    m = Tables(model)
    lower, upper = LowerBound.blind(m), UpperBound(fast_informed_bound(m), np.random.default_rng(0).random(m.S))
    beliefs = BeliefSet(m.S)
    for i in range(20):
        trial(m, model.initial, lower, upper, beliefs, epsilon=1.0, follow_lower=i % 2 == 0)
    B = np.vstack([model.initial, upper.points.rows, beliefs.rows])
    before, n = upper.at(B), upper.n
    upper.prune()
    assert upper.n < n
    assert np.allclose(upper.at(B), before, rtol=0, atol=1e-9)


def test_lower_bound_pruning_keeps_the_value_at_each_belief():
    rng = np.random.default_rng(0)
    lower = LowerBound(rng.random((60, 6)), rng.integers(0, 4, 60), fixed=4)
    pairs = {(tuple(v), a) for v, a in zip(lower.vectors, lower.actions)}
    B = _random_beliefs(rng, 25, 6)
    before = lower.at(B)[0]
    fixed = lower.vectors[:4].copy()
    lower.prune(B)
    assert lower.n < 60 and np.array_equal(lower.vectors[:4], fixed)
    assert np.array_equal(lower.at(B)[0], before)
    assert {(tuple(v), a) for v, a in zip(lower.vectors, lower.actions)} <= pairs  # each keeps its action
    assert lower.n <= 4 + len(B)


def test_trials_on_two_doors_keep_the_bounds_ordered_and_bracket_the_closed_form(doors):
    m = Tables(doors)
    b0 = doors.initial
    lower, upper = LowerBound.blind(m), UpperBound(fast_informed_bound(m), np.random.default_rng(0).random(2))
    beliefs = BeliefSet(2)
    corners = np.eye(2)
    exact = np.array([V0, V_CORNER, V_CORNER])
    B = np.vstack([b0, corners])
    low, high = lower.at(B)[0], upper.at(B)
    start = high[0] - low[0]
    for i in range(40):
        epsilon = max(1e-6, (high[0] - low[0]) / 2)   # the solver's: half the gap at b0
        assert trial(m, b0, lower, upper, beliefs, epsilon, follow_lower=i % 2 == 0) > 0
        new_low, new_high = lower.at(B)[0], upper.at(B)
        assert np.all(new_low >= low - 1e-12) and np.all(new_high <= high + 1e-12)   # only ever tighter
        assert np.all(new_low <= exact + 1e-9) and np.all(exact <= new_high + 1e-9)
        assert np.all(lower.at(beliefs.rows)[0] <= upper.at(beliefs.rows) + 1e-9)
        low, high = new_low, new_high
    assert high[0] - low[0] < 1e-2 * start  # the gap at b0 closes
    # The trials went to both corners (look), and the beliefs they reached joined the set.
    reached = {tuple(b) for b in beliefs.rows.round(12)}
    assert {(1.0, 0.0), (0.0, 1.0)} <= reached <= {(1.0, 0.0), (0.0, 1.0), (0.5, 0.5)}


def test_q_upper_is_the_one_step_lookahead(doors):
    m = Tables(doors)
    b = np.array([0.7, 0.3])
    upper = UpperBound(fast_informed_bound(m), np.array([0.1, 0.9]))
    s = successors(m, b, LowerBound.blind(m), upper)
    direct = []
    for a in range(3):
        T, O = doors.dense()
        predicted = b @ T[a]
        total = doors.reward[a] @ b
        for z in range(2):
            joint = predicted * O[a][:, z]
            if joint.sum() > 0:
                total += GAMMA * joint.sum() * upper.value(joint / joint.sum())
        direct.append(total)
    assert np.allclose(q_upper(m, b, s), direct, rtol=0, atol=1e-12)


def test_growing_the_belief_set_follows_the_policy(doors):
    m = Tables(doors)
    beliefs = BeliefSet(2)
    beliefs.add(doors.initial[None], np.ones(1))
    # Every blind vector is worth 0 at b0; the first, 'look', leads to the corners with P(z) = 1/2 each.
    expanded, theta = grow(m, LowerBound.blind(m), beliefs, theta=1.0, theta_factor=3.0)
    assert expanded == 1 and theta == pytest.approx(1 / 3)
    assert beliefs.n == 3 and np.allclose(beliefs.weights, [1, GAMMA / 2, GAMMA / 2])


def test_sweep_rounds_reach_the_closed_form(doors):
    m = Tables(doors)
    lower, beliefs = LowerBound.blind(m), BeliefSet(2)
    beliefs.add(doors.initial[None], np.ones(1))
    rounds = sweep_rounds(m, lower, beliefs, fast_informed_bound(m), theta=1e-3)
    for _ in range(300):
        assert next(rounds) > 0
        assert lower.value(doors.initial) <= V0 + 1e-9
    assert lower.value(doors.initial) == pytest.approx(V0, abs=1e-6)


def test_work_sharing_gives_each_process_at_least_min_share():
    rng = np.random.default_rng(0)
    for useless in ("trials", "sweeps"):
        sharing = WorkSharing(min_share=0.2)
        largest = 0.0
        for _ in range(2000):
            process = sharing.choose()
            work = float(rng.integers(1, 100))
            largest = max(largest, work)
            sharing.record(process, 0.0 if process == useless else work * 1e-3, work)
        total = sum(sharing.done.values())
        assert sharing.done[useless] >= 0.2 * total - largest
        assert sharing.done[useless] <= 0.2 * total + largest


@pytest.mark.parametrize("ratio", [1.0, 3.0, 1 / 3])
def test_work_sharing_follows_the_rates(ratio):
    # Sweeps close the gap `ratio` times as fast per unit of work: their share is ratio / (1 + ratio).
    sharing = WorkSharing(min_share=0.1)
    for _ in range(1000):
        process = sharing.choose()
        sharing.record(process, (ratio if process == "sweeps" else 1.0) * 1e-4, 10.0)
    total = sum(sharing.done.values())
    assert sharing.done["sweeps"] / total == pytest.approx(ratio / (1 + ratio), abs=10.0 / total)


def test_work_sharing_decays_with_the_horizon():
    sharing = WorkSharing(rate_horizon=5.0)
    assert sharing.choose() == "sweeps" and sharing.share() == 0.5  # no rate known yet
    sharing.record("sweeps", 1.0, 5.0)
    sharing.record("sweeps", 0.0, 5.0)   # one half-life later: the gap closed before counts half
    assert sharing.recent["sweeps"] == [0.5, 7.5] and sharing.done["sweeps"] == 10.0


def test_any_iterate_of_the_informed_bound_is_an_upper_bound(doors):
    m = Tables(doors)
    first, converged = fast_informed_bound(m, max_sweeps=1), fast_informed_bound(m)
    assert np.all(first >= converged - 1e-12)
    result = PointBasedSolver(time_limit=None, informed_sweeps=1, max_iterations=100, precision=1e-4).solve(doors)
    assert result.lower_bound - 1e-9 <= V0 <= result.upper_bound + 1e-9 and result.gap <= 1e-4


def test_no_time_limit_depends_only_on_the_work(pen):
    model = intention_pomdp(make_plan(pen, True))
    a = PointBasedSolver(time_limit=None, max_iterations=20).solve(model)
    b = PointBasedSolver(time_limit=float("inf"), max_iterations=20, blas_threads=2).solve(model)
    assert a.iterations == b.iterations == 20
    assert (a.lower_bound, a.upper_bound) == pytest.approx((b.lower_bound, b.upper_bound), abs=1e-12)


def test_blas_threads_precedence(doors, monkeypatch):
    m = Tables(doors)
    for variable in BLAS_VARIABLES:
        monkeypatch.delenv(variable, raising=False)
    assert blas_threads(m) == 1                  # a small model: one thread
    assert blas_threads(m, requested=2) == 2     # the configuration overrides
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    assert blas_threads(m) is None               # the user's setting is left as it is
    assert blas_threads(m, requested=1) == 1


def test_limited_blas_limits_inside_the_block_only():
    threadpoolctl = pytest.importorskip("threadpoolctl")
    before = [pool["num_threads"] for pool in threadpoolctl.threadpool_info() if pool["user_api"] == "blas"]
    with limited_blas(1):
        assert all(pool["num_threads"] == 1 for pool in threadpoolctl.threadpool_info()
                   if pool["user_api"] == "blas")
    assert [pool["num_threads"] for pool in threadpoolctl.threadpool_info() if pool["user_api"] == "blas"] == before


def _groups(rng, S, sizes):
    """Corner groups over disjoint random state sets of the given sizes, random weights (values set later)."""
    states = rng.permutation(S)
    member, weight, start, first = [], [], [], 0
    for size in sizes:
        start.append(len(member))
        member += states[first:first + size].tolist()
        w = rng.random(size) + 0.1
        weight += (w / w.sum()).tolist()
        first += size
    return np.array(member), np.array(weight), np.array(start)


def _convex_bound(upper: UpperBound, b: np.ndarray) -> float:
    """The tightest bound convexity gives from the corners, the group beliefs and the points (an LP over
    the ways of writing ``b`` as a non-negative combination of them): ``upper.at`` is never below it."""
    from scipy.optimize import linprog

    S = len(b)
    columns = np.vstack([np.eye(S), upper.group_beliefs, upper.points.rows]).T
    costs = np.concatenate([upper.corner, upper.group_value, upper.points.rows @ upper.corner + upper.excess])
    result = linprog(costs, A_eq=columns, b_eq=b, bounds=(0, None), method="highs")
    assert result.status == 0
    return float(result.fun)


@pytest.mark.parametrize("seed", range(6))
def test_corner_groups_bound_a_convex_function_and_never_claim_more_than_convexity(seed):
    """Upper bounds of a convex V (max of random alpha vectors) at the corners, the group beliefs and the
    points: the bound with groups stays above V, never goes below the LP of convexity, and is at most the
    bound without groups."""
    from planner.decision.solvers.upper import CornerGroups

    rng = np.random.default_rng(seed)
    S = 8
    alphas = rng.random((5, S)) * 10

    def V(B):
        return (np.atleast_2d(B) @ alphas.T).max(axis=1)

    member, weight, start = _groups(rng, S, (3, 2, 2))
    plain = UpperBound(np.tile(V(np.eye(S)) + rng.random(S) * 4 + 1, (2, 1)), rng.random(S))
    Q = np.tile(plain.corner + 50, (2, 1))            # the informed bound never binds here
    beliefs = CornerGroups(member, weight, start, np.zeros(3)).beliefs(S)
    groups = CornerGroups(member, weight, start, V(beliefs) + rng.random(3) * 0.5)
    grouped, plain = UpperBound(Q, plain.fingerprint, groups), UpperBound(Q, plain.fingerprint)
    for b in np.vstack([_random_beliefs(rng, 30, S), 0.6 * beliefs[0] + 0.4 * beliefs[1]]):
        v = float(V(b)[0]) + rng.random() * 0.5
        grouped.update(b, v)
        plain.update(b, v)
    B = np.vstack([_random_beliefs(rng, 80, S), beliefs, 0.3 * beliefs[0] + 0.7 * beliefs[2],
                   0.5 * beliefs[0] + 0.25 * beliefs[1] + 0.25 * np.eye(S)[member[5]]])
    bound = grouped.at(B)
    assert np.all(bound >= V(B) - 1e-9)
    assert np.all(bound >= [_convex_bound(grouped, b) - 1e-9 for b in B])
    assert np.all(bound <= plain.at(B) + 1e-12)
    # A mixture of group beliefs is bounded by the mixture of their values (closed form).
    mix = 0.3 * beliefs[0] + 0.7 * beliefs[2]
    assert grouped.value(mix) <= 0.3 * grouped.group_value[0] + 0.7 * grouped.group_value[2] + 1e-12


def test_corner_groups_with_a_point_inside_a_group():
    """A point at a group's belief with a value below the group's: at an even mixture with another group the
    bound is half of each (the sawtooth term is exact when the point holds a multiple of the group)."""
    from planner.decision.solvers.upper import CornerGroups

    groups = CornerGroups(np.array([0, 1, 2, 3]), np.array([0.5, 0.5, 0.25, 0.75]), np.array([0, 2]),
                          np.array([4.0, 6.0]))
    upper = UpperBound(np.full((2, 4), 10.0), np.array([0.1, 0.2, 0.3, 0.4]), groups)
    first, second = upper.group_beliefs
    assert upper.value(0.5 * first + 0.5 * second) == pytest.approx(5.0)
    upper.update(first, 2.0)
    assert upper.value(0.5 * first + 0.5 * second) == pytest.approx(4.0)
    assert upper.lower_group(1, 3.0) and not upper.lower_group(1, 3.5)
    assert upper.value(0.5 * first + 0.5 * second) == pytest.approx(2.5)
    with pytest.raises(ValueError, match="disjoint"):
        CornerGroups(np.array([0, 0]), np.array([1.0, 1.0]), np.array([0, 1]), np.zeros(2))
