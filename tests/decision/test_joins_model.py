"""Robot actions named by the parts they join (``parallel="joins"``, docs/parallel.md "Actions named by the parts
they join"): the joins of chains and stars in closed form; table by table, the projected model with the
operations of one join made one action (at a state at most one operation has a given join; where none has, the
join is wrong and stays); lumped = factored along random histories, the class-MDP bound = value iteration; a
simulated join the operator's sequence needs later is the robot's operation (sessions with joins:
tests/runtime/test_join_sessions.py)."""
from __future__ import annotations

import numpy as np
import pytest

from planner import chain_product, make_plan
from planner.decision import factored_model, lumped_pomdp
from planner.decision.factored_simulate import PathWorld
from planner.decision.joins import join_actions
from planner.decision.online import class_values
from planner.decision.simulate import simulate_episode
from test_parallel_model import _value_iteration, agree_along_random_histories
from test_projected_model import _Script, _plan, _star


def test_a_chain_has_one_join_per_contact_and_a_star_one_per_leaf():
    plan = make_plan(chain_product(6))
    model = factored_model(plan, parallel="joins")
    assert model.actions[:-1] == tuple(f"a{k}:join(p{k + 1},p{k + 2})" for k in range(5))
    star = factored_model(make_plan(_star(4)), parallel="joins")
    assert sorted(name.split(":")[1] for name in star.actions[:-1]) == [f"join(base,leaf{k})" for k in range(1, 5)]


@pytest.mark.parametrize("name", ["pen", "pen-technical", "chain-5"])
def test_it_is_the_projected_model_with_the_operations_of_a_join_made_one_action(pen, name):
    plan = _plan(name, pen)
    proj, joins = factored_model(plan, parallel="projected"), factored_model(plan, parallel="joins")
    robot_ops = np.flatnonzero(plan.tags.robot)
    join_of_op, _, _ = join_actions(plan, robot_ops)
    a, b = lumped_pomdp(proj), lumped_pomdp(joins)
    assert b.n_actions < a.n_actions and np.array_equal(a.initial, b.initial)
    assert all((x != y).nnz == 0 for x, y in zip(a.observation, b.observation))
    Ta, Tb = [t.tocsr() for t in a.transition], [t.tocsr() for t in b.transition]
    assert (Ta[-1] != Tb[-1]).nnz == 0 and np.array_equal(a.reward[-1], b.reward[-1])  # wait
    states = plan.states
    for c in range(proj.final_class):
        out = np.flatnonzero(states.edge_source == states.edge_source[c])
        ops = states.edge_operation[out]
        for j in range(b.n_actions - 1):
            here = [int(np.searchsorted(robot_ops, o)) for o in ops if plan.tags.robot[o]
                    and join_of_op[np.searchsorted(robot_ops, o)] == j]
            assert len(here) <= 1  # one operation of a join at a state
            if here:
                assert b.reward[j, c] == pytest.approx(a.reward[here[0], c], abs=1e-12)
                assert abs(Tb[j].getrow(c) - Ta[here[0]].getrow(c)).max() <= 1e-12
            else:
                assert b.reward[j, c] == joins.rewards.wrong
                assert Tb[j].getrow(c).toarray().ravel().tolist() == np.eye(b.n_states)[c].tolist()


@pytest.mark.parametrize("name", ["pen", "chain-5"])
def test_lumped_and_factored_agree_and_the_class_bound_is_value_iteration(pen, name):
    fact = factored_model(_plan(name, pen), parallel="joins")
    agree_along_random_histories(fact, seed=3, episodes=6)
    V, Q = _value_iteration(lumped_pomdp(fact))
    values = class_values(fact)
    assert np.abs(values.value - V).max() <= 1e-8 and np.abs(values.q_matrix(fact) - Q).max() <= 1e-8


def test_a_join_the_sequence_needs_later_is_the_robots_operation():
    """The star of 4 (the truck's sa4 in small): the operator adds the leaves in the sequence's order; the robot
    adds the sequence's last leaf first, by the one action of that leaf: right, the robot's operation."""
    model = factored_model(make_plan(_star(4)), parallel="joins")
    path = model.sequence(0)
    last = int(model.class_action[path[-1]])
    episode = simulate_episode(PathWorld(model, path), _Script([last], model.wait), np.random.default_rng(0))
    first = episode.steps[0]
    assert first.robot_operation and not first.wrong_action and episode.finished
    assert int(model.class_action[episode.path[0]]) == last and len(episode.path) == len(path)
