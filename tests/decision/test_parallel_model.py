"""The parallel model (issue 23 item 2, docs/parallel.md): the robot may do the operator's step after next.

Its pairs and their ``q`` against an independent count over the enumerated full sequences; switched off, the
paper's tables; lumped = factored to 1e-9 along random histories (with and without habits); the class-MDP bound
equals value iteration on the lumped POMDP and the revealed bound stays above what the solver certifies; the
online planner and the solver run on it; a simulated episode in which the robot's step after next is right."""
from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from planner import chain_product, complete_product, make_plan
from planner.decision import DiscreteUpdater, FactoredUpdater, PointBasedSolver, factored_model, lumped_pomdp
from planner.decision.delayed_reveal import delayed_reveal_bound
from planner.decision.episode_measures import episode_measures
from planner.decision.factored_simulate import PathWorld
from planner.decision.simulate import simulate_episode
from planner.decision.habits import habit_weights_from
from planner.decision.solvers.warm_start import solver_bounds
from planner.decision.online import OnlinePlanner, class_values, revealed_state_values

TOLERANCE = 1e-9


def _plan(name, pen):
    product, technical = {"pen": (pen, False), "pen-technical": (pen, True), "chain-5": (chain_product(5), None),
                          "complete-4": (complete_product(4), None)}[name]
    return make_plan(product, technical)


def _weights(plan, seed):
    rng = np.random.default_rng(seed)
    E = plan.states.n_edges
    return habit_weights_from(plan, rng.integers(1, 30, E).astype(float) * (rng.random(E) < 0.5), 1.0)


@pytest.fixture(scope="module", params=["pen", "pen-technical", "chain-5", "complete-4"])
def plan(request, pen):
    return _plan(request.param, pen)


def test_pairs_and_q_match_a_count_over_the_full_sequences(plan):
    """Independent: enumerate every full sequence (as operations). A pair (class c = the sequence's k-th edge,
    the action doing its (k+1)-th operation o) exists iff swapping steps k and k+1 gives a full sequence too and
    the robot can do o; q is the share of the sequences through c whose next operation is o."""
    model = factored_model(plan, parallel=True)
    paths = [model.sequence(r) for r in range(model.n_sequences)]
    ops = {tuple(model.sequence_operations(p)) for p in paths}
    action_of = {int(o): a for a, o in enumerate(model.action_operations[:-1])}
    through, then = Counter(), Counter()
    expected = set()
    for p in paths:
        seq = model.sequence_operations(p)
        for k in range(len(p) - 1):
            through[p[k]] += 1
            then[p[k], seq[k + 1]] += 1
            swapped = tuple(seq[:k] + [seq[k + 1], seq[k]] + seq[k + 2:])
            if swapped in ops and seq[k + 1] in action_of:
                expected.add((p[k], action_of[seq[k + 1]]))
    par = model.parallel
    found = {(int(c), int(a)) for c, a in zip(par.pair_class, par.action)}
    assert found == expected and len(found) == par.size
    for c, a, q in zip(par.pair_class, par.action, par.fraction):
        o = int(model.action_operations[a])
        assert q == pytest.approx(then[int(c), o] / through[int(c)], rel=1e-12)
    # the right action's class: the robot did o, the operator still does e, and the state is where e2 led
    assert np.array_equal(model.class_operation[par.target], model.class_operation[par.pair_class])
    assert np.array_equal(model.class_target[par.target], model.class_target[par.step])
    assert np.array_equal(model.class_source[par.robot_edge], model.class_source[par.pair_class])


def test_switched_off_it_is_the_papers_model(plan):
    """The parallel model's lumped tables differ from the paper's on the pairs' rows and rewards only; without
    it every table is the paper's."""
    paper, off, on = factored_model(plan), factored_model(plan, parallel=False), factored_model(plan, parallel=True)
    assert off.parallel is None and on.parallel.size > 0
    a, b, c = lumped_pomdp(paper), lumped_pomdp(off), lumped_pomdp(on)
    assert np.array_equal(a.reward, b.reward)
    assert all((x != y).nnz == 0 for x, y in zip(a.transition, b.transition))
    pair = np.zeros((c.n_actions, c.n_states), dtype=bool)
    pair[on.parallel.action, on.parallel.pair_class] = True
    assert np.array_equal(a.reward[~pair], c.reward[~pair]) and not np.any(a.reward[pair] == c.reward[pair])
    for act in range(c.n_actions):
        same = ~pair[act]
        assert (a.transition[act][same] != c.transition[act][same]).nnz == 0
        assert np.allclose(np.asarray(c.transition[act].sum(axis=1)).ravel(), 1.0, atol=1e-12)


@pytest.mark.parametrize("habits", [False, True])
def test_lumped_and_factored_agree_along_random_histories(plan, habits):
    """The factored filter and the lumped POMDP's, on the parallel model, along random histories drawn from the
    lumped model (robot actions drawn among the pairs' half the time): the same beliefs, expected rewards and
    observation probabilities at every step."""
    weights = _weights(plan, 7) if habits else None
    agree_along_random_histories(factored_model(plan, weights=weights, parallel=True), seed=11, episodes=10)


def agree_along_random_histories(fact, seed: int, episodes: int) -> None:
    """Assert that the factored model ``fact`` (with a parallel model) and its lumped POMDP give the same beliefs,
    expected rewards, rewards, predictions and updates along ``episodes`` random histories drawn from the lumped
    model, robot actions drawn among the pairs' half the time; and that some pair was taken."""
    lumped = lumped_pomdp(fact)
    T = [t.tocsr() for t in lumped.transition]
    O = lumped.observation[0].tocsr()
    rng = np.random.default_rng(seed)
    used = 0
    for _ in range(episodes):
        up_fact, up_lump = FactoredUpdater(fact), DiscreteUpdater(lumped)
        belief, c = up_fact.initialize(), up_lump.initialize()
        state = int(rng.choice(lumped.n_states, p=lumped.initial))
        for _ in range(25):
            assert np.abs(belief.dense(fact.n_classes) - c).max() <= TOLERANCE
            assert np.abs(fact.expected_rewards(belief) - lumped.reward @ c).max() <= TOLERANCE
            if state == fact.final_class:
                break
            pairs = np.flatnonzero(fact.parallel.pair_class == state)
            if pairs.size and rng.random() < 0.5:
                a = int(fact.parallel.action[rng.choice(pairs)])
                used += 1
            else:
                a = int(rng.integers(lumped.n_actions))
            assert fact.rewards_of(np.array([state]), a)[0] == pytest.approx(lumped.reward[a, state], abs=1e-12)
            row = T[a].getrow(state)
            state = int(rng.choice(row.indices, p=row.data / row.data.sum()))
            orow = O.getrow(state)
            z = int(rng.choice(orow.indices, p=orow.data / orow.data.sum()))
            predicted = fact.predict(belief, a)
            assert np.abs(predicted.dense(fact.n_classes) - lumped.transition[a].T @ c).max() <= TOLERANCE
            belief, c = up_fact.update(belief, a, z), up_lump.update(c, a, z)
        assert not up_fact.events and not up_lump.events
    assert used > 0


def _value_iteration(pomdp, sweeps=3000):
    V = np.zeros(pomdp.n_states)
    for _ in range(sweeps):
        Q = np.array([pomdp.reward[a] + pomdp.discount * (pomdp.transition[a] @ V) for a in range(pomdp.n_actions)])
        V = Q.max(axis=0)
    return V, Q


@pytest.mark.parametrize("habits", [False, True])
def test_class_mdp_bound_is_value_iteration_on_the_lumped_model(plan, habits):
    """QMDP on the classes (:func:`class_values`) is the lumped POMDP's fully observed MDP: equal to value
    iteration on its tables, the pairs' Q-values included; the revealed bound is below it."""
    fact = factored_model(plan, weights=_weights(plan, 3) if habits else None, parallel=True)
    V, Q = _value_iteration(lumped_pomdp(fact))
    values = class_values(fact)
    assert np.abs(values.value - V).max() <= 1e-8
    assert np.abs(values.q_matrix(fact) - Q).max() <= 1e-8
    revealed = revealed_state_values(fact)
    assert np.all(revealed.value <= values.value + 1e-9)
    assert np.all(revealed.q_matrix(fact) <= Q + 1e-9)


@pytest.mark.parametrize("name", ["pen", "chain-5"])
def test_bounds_stay_above_what_the_solver_certifies(pen, name):
    """The solver on the parallel lumped POMDP (bounded by trials), started without the model's bounds: its
    certified lower bound at the initial belief is below the revealed bound, the delayed-reveal bound and the
    online planner's upper bound; started from them, its interval overlaps its own."""
    plan = _plan(name, pen)
    fact = factored_model(plan, parallel=True)
    lumped = lumped_pomdp(fact)
    solver = PointBasedSolver(time_limit=None, max_iterations=80, precision=1e-6)
    plain = solver.solve(lumped)
    b0 = fact.initial_belief()
    revealed = revealed_state_values(fact)
    assert plain.lower_bound <= float(revealed.q_values(fact, b0).max()) + 1e-9
    reveal = delayed_reveal_bound(fact, lumped)
    assert plain.lower_bound <= reveal.initial_value + 1e-9
    Q, groups = solver_bounds(fact, reveal)
    started = solver.solve(lumped, upper=Q, groups=groups)
    assert max(plain.lower_bound, started.lower_bound) <= min(plain.upper_bound, started.upper_bound) + 1e-9
    search = OnlinePlanner(fact, 300, None).search(b0)
    assert search.lower <= plain.upper_bound + 1e-9 and plain.lower_bound <= search.upper + 1e-9
    assert 0 <= search.action < len(fact.actions)


def _right_pair(model):
    """A full sequence and a pair at its first class whose step is the sequence's second edge."""
    par = model.parallel
    for rank in range(model.n_sequences):
        path = model.sequence(rank)
        for p in np.flatnonzero(par.pair_class == path[0]):
            if int(par.step[p]) == path[1]:
                return path, int(p)
    raise AssertionError("no sequence whose first class has a right pair")


class _Script:
    def __init__(self, actions, wait):
        self.actions, self.wait = list(actions), wait

    def action(self, belief):
        return self.actions.pop(0) if self.actions else self.wait


def test_a_simulated_step_after_next_is_the_robots_and_right(pen):
    """The robot does the operator's second operation at once: the step is right (the robot's operation, its
    reward, no wrong action), the sequence continues with it done, and the operations add up to the length."""
    model = factored_model(make_plan(pen, False), parallel=True)
    path, p = _right_pair(model)
    a = int(model.parallel.action[p])
    episode = simulate_episode(PathWorld(model, path), _Script([a], model.wait), np.random.default_rng(0))
    first = episode.steps[0]
    assert first.robot_operation and not first.wrong_action
    assert first.reward == model.parallel.reward[p]
    assert episode.path[:2] == [int(model.parallel.robot_edge[p]), int(model.parallel.target[p])]
    assert episode.path[2:] == path[2:] and episode.finished
    measures = episode_measures(episode)
    assert measures["robot_operations"] == 1 and measures["wrong_robot_actions"] == 0
    assert measures["robot_operations"] + measures["operator_operations"] == len(path)


def test_a_simulated_step_after_next_the_operator_does_not_take_is_wrong(pen):
    model = factored_model(make_plan(pen, False), parallel=True)
    path, p = _right_pair(model)
    par = model.parallel
    other = next(int(q) for q in range(par.size) if par.pair_class[q] == path[0] and int(par.step[q]) != path[1])
    episode = simulate_episode(PathWorld(model, path), _Script([int(par.action[other])], model.wait),
                               np.random.default_rng(0))
    first = episode.steps[0]
    assert first.wrong_action and not first.robot_operation and first.reward == model.rewards.wrong
    assert episode.path == path and first.position == 0


def test_the_pairs_memory_is_estimated_from_counts_and_refused_past_the_budget(pen):
    """The candidates are nnz(M) of the advance matrix (counted independently); past the budget, a clear
    refusal before anything is built."""
    from planner.decision.lumped_model import advance_matrix
    from planner.decision.budget import check_parallel_memory
    from planner.decision.parallel import parallel_bytes, parallel_candidates
    from planner.errors import MemoryLimitError

    plan = make_plan(chain_product(6))
    model = factored_model(plan)
    assert parallel_candidates(plan.states) == advance_matrix(model)[:-1, :-1].nnz  # to classes, not finished
    check_parallel_memory(plan, 2 ** 31)
    with pytest.raises(MemoryLimitError, match="parallel model"):
        check_parallel_memory(plan, parallel_bytes(plan.states))


@pytest.mark.parametrize("base_part", ["body", "button"])
def test_pairs_with_a_base_part_keep_the_sequences_allowed(pen, base_part):
    """With a base part, the pairs of the classes on the allowed full sequences are those whose swap is an allowed
    full sequence too (at the initial state: the robot's edge must join the base part); the lumped and factored
    filters still agree."""
    plan = make_plan(pen, True)
    model = factored_model(plan, base_part=base_part, parallel=True)
    paths = [model.sequence(r) for r in range(model.n_sequences)]
    ops = {tuple(model.sequence_operations(p)) for p in paths}
    action_of = {int(o): a for a, o in enumerate(model.action_operations[:-1])}
    expected, seen = set(), set()
    for p in paths:
        seq = model.sequence_operations(p)
        for k in range(len(p) - 1):
            seen.add(p[k])
            swapped = tuple(seq[:k] + [seq[k + 1], seq[k]] + seq[k + 2:])
            if swapped in ops and seq[k + 1] in action_of:
                expected.add((p[k], action_of[seq[k + 1]]))
    par = model.parallel
    found = {(int(c), int(a)) for c, a in zip(par.pair_class, par.action) if int(c) in seen}
    assert found == expected
    lumped = lumped_pomdp(model)
    up_fact, up_lump = FactoredUpdater(model), DiscreteUpdater(lumped)
    belief, c = up_fact.initialize(), up_lump.initialize()
    for a in par.action[np.isin(par.pair_class, list(seen))][:6]:
        z = 0
        belief, c = up_fact.update(belief, int(a), z), up_lump.update(c, int(a), z)
        assert np.abs(belief.dense(model.n_classes) - c).max() <= TOLERANCE
