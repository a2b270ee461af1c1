"""The projected model (issue 23 item 2, docs/parallel.md "The projected model"): the robot may do any operation,
and the operator's remaining sequence is projected onto the new state (the blocks the robot joined made one).

The pairs, their ``q`` and ``e'`` against an independent enumeration over every completion of every class (the
partitions as sets of part names, joined by set union; with and without habits, with a base part); the
simulator's rewrite against the same projection; the closed forms of chains and complete products (every pair
certain, counted by Stirling numbers); switched off, the paper's tables; lumped = factored along random
histories, the class-MDP bound = value iteration on the lumped POMDP; the online planner and the solver run
on it; bad input."""
from __future__ import annotations

from math import comb, factorial

import numpy as np
import pytest

from planner import chain_product, complete_product, make_plan
from planner.decision import DiscreteUpdater, FactoredUpdater, PointBasedSolver, factored_model, lumped_pomdp
from planner.decision.delayed_reveal import delayed_reveal_bound
from planner.decision.episode_measures import episode_measures
from planner.decision.factored_simulate import PathWorld
from planner.decision.simulate import simulate_episode
from planner.decision.habits import habit_weights_from
from planner.decision.online import OnlinePlanner, class_values, revealed_state_values
from planner.decision.budget import check_parallel_memory
from planner.decision.projected import projected_bytes, projected_candidates, projected_rewrite
from planner.errors import MemoryLimitError, PlannerError
from test_parallel_model import _value_iteration, agree_along_random_histories

TOLERANCE = 1e-9


def _plan(name, pen):
    product, technical = {"pen": (pen, False), "pen-technical": (pen, True), "chain-4": (chain_product(4), None),
                          "chain-5": (chain_product(5), None), "complete-4": (complete_product(4), None)}[name]
    return make_plan(product, technical)


def _weights(plan, seed):
    rng = np.random.default_rng(seed)
    E = plan.states.n_edges
    return habit_weights_from(plan, rng.integers(1, 30, E).astype(float) * (rng.random(E) < 0.5), 1.0)


@pytest.fixture(scope="module", params=["pen", "pen-technical", "chain-4", "chain-5", "complete-4"])
def plan(request, pen):
    return _plan(request.param, pen)


# --- the independent reference: partitions as frozensets of frozensets of part names ---------------------------

class _Reference:
    """Every state as a partition (sets of part names), every state edge as a pair of partitions, and the
    projection of a sequence of partitions by set union: nothing of the module's lookups or levels."""

    def __init__(self, model):
        self.model = model
        states, andor = model.plan.states, model.plan.andor
        self.partition = [frozenset(andor.parts_of(int(b)) for b in set(states.blocks[x].tolist()))
                          for x in range(states.n_states)]
        self.states = set(self.partition)
        self.edges = {(self.partition[int(s)], self.partition[int(t)]): k
                      for k, (s, t) in enumerate(zip(states.edge_source, states.edge_target))}
        self.paths = {}

    def completions(self, state):
        """Every path of state edges from ``state`` to the final state."""
        if state not in self.paths:
            if state == self.model.final_state:
                self.paths[state] = [[]]
            else:
                self.paths[state] = [[int(e)] + rest for e in self.model.classes_from(state)
                                     for rest in self.completions(int(self.model.class_target[e]))]
        return self.paths[state]

    @staticmethod
    def join(partition, a, b):
        """The partition with the block holding part set ``a`` and the block holding ``b`` made one."""
        pa = next(x for x in partition if a <= x)
        pb = next(x for x in partition if b <= x)
        return partition if pa == pb else (partition - {pa, pb}) | {pa | pb}

    def project(self, edges, robot_edge):
        """The projection of the path ``edges`` onto the robot's edge's target, as state edges, or None."""
        a, b = self.model.plan.andor.inputs(int(self.model.class_operation[robot_edge]))
        chain = [self.partition[int(self.model.class_source[edges[0]])]] + \
            [self.partition[int(self.model.class_target[e])] for e in edges]
        joined = [self.join(p, a, b) for p in chain]
        distinct = [joined[0]] + [y for x, y in zip(joined, joined[1:]) if y != x]
        if any(p not in self.states for p in distinct):
            return None
        out = [self.edges.get((x, y)) for x, y in zip(distinct, distinct[1:])]
        return None if any(e is None for e in out) else out


def _expected_pairs(model, ref, allowed):
    """{(class, action): (q, e')} by enumeration: q the prior weight of the class's completions (the product of
    their class fractions) whose projection is feasible."""
    action_of = {int(o): a for a, o in enumerate(model.action_operations[:-1])}
    out = {}
    for c in range(model.final_class):
        s = int(model.class_source[c])
        for f in model.classes_from(s).tolist():
            op = int(model.class_operation[f])
            if f == c or op not in action_of or not allowed[f]:
                continue
            q, after = 0.0, None
            for rest in ref.completions(int(model.class_target[c])):
                projected = ref.project([c] + rest, f)
                if projected is not None:
                    q += float(np.prod(model.class_fraction[np.array(rest, dtype=np.int64)])) if rest else 1.0
                    after = projected[0]
            if q > 0:
                out[c, action_of[op]] = (q, after)
    return out


def _allowed(model):
    from planner.assembly.intentions import allowed_edges
    return allowed_edges(model.plan.states, model.base_part)


@pytest.mark.parametrize("habits", [False, True])
def test_pairs_q_and_next_class_match_an_enumeration_of_every_completion(plan, habits):
    model = factored_model(plan, weights=_weights(plan, 5) if habits else None, parallel="projected")
    ref = _Reference(model)
    expected = _expected_pairs(model, ref, _allowed(model))
    par = model.parallel
    found = {(int(c), int(a)): (float(q), int(t)) for c, a, q, t in
             zip(par.pair_class, par.action, par.fraction, par.target)}
    assert set(found) == set(expected) and len(found) == par.size
    for key, (q, after) in expected.items():
        assert found[key][0] == pytest.approx(q, rel=1e-12) and found[key][1] == after
    # the robot's edge leaves the class's state and performs the action; e' leaves the robot's target
    assert np.array_equal(model.class_source[par.robot_edge], model.class_source[par.pair_class])
    assert np.array_equal(model.class_action[par.robot_edge], par.action)
    assert np.array_equal(model.class_source[par.target], model.class_target[par.robot_edge])
    assert np.all(par.reward == model.class_match_reward[par.robot_edge])


@pytest.mark.parametrize("base_part", ["body", "button"])
def test_pairs_with_a_base_part_match_the_enumeration(pen, base_part):
    model = factored_model(make_plan(pen, True), base_part=base_part, parallel="projected")
    ref = _Reference(model)
    allowed = _allowed(model)
    expected = _expected_pairs(model, ref, allowed)
    par = model.parallel
    assert {(int(c), int(a)) for c, a in zip(par.pair_class, par.action)} == set(expected)
    assert allowed[par.robot_edge].all()


def test_the_pen_has_uncertain_pairs_and_certain_help(pen):
    """On the pen the geometry makes some projections infeasible (0 < q < 1), and some operations are certain
    help at a class (q = 1) although not the operator's next step."""
    par = factored_model(make_plan(pen, False), parallel="projected").parallel
    assert np.any(par.fraction < 1 - 1e-9) and np.any(par.fraction > 1 - 1e-9)


def _stirling2(n, k):
    return sum((-1) ** j * comb(k, j) * (k - j) ** n for j in range(k + 1)) // factorial(k)


@pytest.mark.parametrize("n", [4, 6, 8])
def test_chains_and_complete_products_every_pair_is_certain_help(n):
    """Closed forms. On a chain (states: the 2^(n-1) compositions into intervals) and a complete product (the
    partitions), every partition into connected sets is a state, so every projection is feasible: each pair has
    q = 1, there is one per (state, its out-edge e, another robot out-edge f), i.e. sum over k of (states with k
    blocks) x m (m - 1) with m the out-degree (k - 1 on a chain, C(k, 2) on a complete product), when every
    operation is the robot's."""
    for product, states_with, out in [(chain_product(n), lambda k: comb(n - 1, k - 1), lambda k: k - 1),
                                      (complete_product(n), lambda k: _stirling2(n, k), lambda k: comb(k, 2))]:
        plan = make_plan(product)
        model = factored_model(plan, parallel="projected")
        assert plan.tags.robot.all()
        par = model.parallel
        assert np.all(np.abs(par.fraction - 1) < 1e-9)
        assert par.size == sum(states_with(k) * out(k) * (out(k) - 1) for k in range(1, n + 1))


def test_switched_off_it_is_the_papers_model(plan):
    """The projected model's lumped tables differ from the paper's on the pairs' rows and rewards only; off,
    every table is the paper's."""
    paper, on = factored_model(plan), factored_model(plan, parallel="projected")
    assert paper.parallel is None and on.parallel.size > 0 and on.parallel.rule == "projected"
    a, c = lumped_pomdp(paper), lumped_pomdp(on)
    pair = np.zeros((c.n_actions, c.n_states), dtype=bool)
    pair[on.parallel.action, on.parallel.pair_class] = True
    assert np.array_equal(a.reward[~pair], c.reward[~pair])
    for act in range(c.n_actions):
        same = ~pair[act]
        assert (a.transition[act][same] != c.transition[act][same]).nnz == 0
        assert np.allclose(np.asarray(c.transition[act].sum(axis=1)).ravel(), 1.0, atol=1e-12)
    assert np.array_equal(a.initial, c.initial)
    assert all((x != y).nnz == 0 for x, y in zip(a.observation, c.observation))


@pytest.mark.parametrize("habits", [False, True])
def test_lumped_and_factored_agree_along_random_histories(plan, habits):
    fact = factored_model(plan, weights=_weights(plan, 7) if habits else None, parallel="projected")
    agree_along_random_histories(fact, seed=13, episodes=8)


def test_class_mdp_bound_is_value_iteration_and_the_solver_stays_below_the_bounds(pen):
    fact = factored_model(make_plan(pen, False), parallel="projected")
    lumped = lumped_pomdp(fact)
    V, Q = _value_iteration(lumped)
    values = class_values(fact)
    assert np.abs(values.value - V).max() <= 1e-8 and np.abs(values.q_matrix(fact) - Q).max() <= 1e-8
    revealed = revealed_state_values(fact)
    assert np.all(revealed.value <= values.value + 1e-9)
    plain = PointBasedSolver(time_limit=None, max_iterations=60, precision=1e-6).solve(lumped)
    b0 = fact.initial_belief()
    assert plain.lower_bound <= float(revealed.q_values(fact, b0).max()) + 1e-9
    assert plain.lower_bound <= delayed_reveal_bound(fact, lumped).initial_value + 1e-9
    search = OnlinePlanner(fact, 200, None).search(b0)
    assert search.lower <= plain.upper_bound + 1e-9 and plain.lower_bound <= search.upper + 1e-9


class _Script:
    def __init__(self, actions, wait):
        self.actions, self.wait = list(actions), wait

    def action(self, belief):
        return self.actions.pop(0) if self.actions else self.wait


def test_the_simulators_rewrite_is_the_projection(pen):
    """For every full sequence of the pen and every pair at its first class: right iff the reference
    projection is feasible, and then the path is the robot's edge followed by the projection."""
    model = factored_model(make_plan(pen, False), parallel="projected")
    ref = _Reference(model)
    par = model.parallel
    right = wrong = 0
    for rank in range(model.n_sequences):
        path = model.sequence(rank)
        for p in np.flatnonzero(par.pair_class == path[0]).tolist():
            f, a = int(par.robot_edge[p]), int(par.action[p])
            projected = ref.project(path, f)
            out = projected_rewrite(model, path, 0, a)
            if projected is None:
                assert out == path
                wrong += 1
            else:
                assert out == [f] + projected and len(out) == len(path)
                right += 1
    assert right and wrong


def test_a_simulated_certain_help_is_the_robots_and_right():
    """Chain 5: the robot does an operation that is not the operator's next step (q = 1): it is the robot's
    operation with its reward, no wrong action, and the operations add up to the sequence's length."""
    model = factored_model(make_plan(chain_product(5)), parallel="projected")
    path = model.sequence(0)
    par = model.parallel
    p = int(np.flatnonzero(par.pair_class == path[0])[0])
    episode = simulate_episode(PathWorld(model, path), _Script([int(par.action[p])], model.wait),
                               np.random.default_rng(0))
    first = episode.steps[0]
    assert first.robot_operation and not first.wrong_action and first.reward == par.reward[p]
    assert episode.path[0] == int(par.robot_edge[p]) and episode.finished
    measures = episode_measures(episode)
    assert measures["robot_operations"] == 1 and measures["wrong_robot_actions"] == 0
    assert measures["robot_operations"] + measures["operator_operations"] == len(path)


def test_bad_input_and_memory():
    plan = make_plan(chain_product(6))
    with pytest.raises(PlannerError, match="unknown parallel model 'sideways'"):
        factored_model(plan, parallel="sideways")
    degree = np.bincount(plan.states.edge_source, minlength=plan.states.n_states)
    assert projected_candidates(plan.states) == int((degree ** 2).sum())
    check_parallel_memory(plan, 2 ** 31, "projected")
    with pytest.raises(MemoryLimitError, match="projected model.*--projected"):
        check_parallel_memory(plan, projected_bytes(plan.states), "projected")


@pytest.mark.parametrize("product", [chain_product(11), complete_product(7)])
def test_the_memory_estimate_bounds_the_measured_peak(product):
    import tracemalloc

    from planner.decision.projected import projected_table

    plan = make_plan(product)
    model = factored_model(plan)
    tracemalloc.start()
    try:
        projected_table(model)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= projected_bytes(plan.states) <= 3 * peak


def _star(k):
    """A base part and ``k`` parts that touch only the base: every order of adding them is a sequence (the
    truck's sa4 in small)."""
    from planner.product.model import Part, Product

    parts = (Part("base", "Base"),) + tuple(Part(f"leaf{i}", f"Leaf {i}") for i in range(1, k + 1))
    return Product(parts, tuple(("base", p.id) for p in parts[1:]), name=f"star of {k}")


@pytest.mark.parametrize("k", [3, 4, 5])
def test_a_growing_subassembly_the_step_after_next_sees_nothing_the_projection_everything(k):
    """Closed form. Parts added one by one to a base: after the robot adds leaf p, no operation of the operator's
    sequence stays the same (each joins a larger block), so the step-after-next model has no pair; the projection
    is the sequence minus "add p", always feasible: with j leaves on the base (C(k, j) states) and r = k - j to
    add, r (r - 1) pairs, each certain help (q = 1)."""
    plan = make_plan(_star(k))
    assert plan.tags.robot.all()
    assert factored_model(plan, parallel=True).parallel.size == 0
    par = factored_model(plan, parallel="projected").parallel
    assert par.size == sum(comb(k, j) * (k - j) * (k - j - 1) for j in range(k + 1))
    assert np.all(np.abs(par.fraction - 1) < 1e-9)


@pytest.mark.parametrize("rule", ["projected", True])
def test_with_a_change_of_mind_the_bounds_are_value_iteration_and_lumped_agrees(pen, rule):
    """A change of mind (``--switch``) with either parallel model: the pairs' right step is followed by the
    operator's redraw, in the factored prediction and the lumped rows alike (they agree along random histories);
    the class-MDP bound is value iteration on that lumped POMDP (the pairs' Q-values included) and the revealed
    bound stays below it."""
    from planner.decision.deviations import Deviations

    fact = factored_model(make_plan(pen, False), parallel=rule, deviations=Deviations(switch=0.2))
    agree_along_random_histories(fact, seed=5, episodes=4)
    V, Q = _value_iteration(lumped_pomdp(fact))
    values = class_values(fact)
    assert np.abs(values.value - V).max() <= 1e-8 and np.abs(values.q_matrix(fact) - Q).max() <= 1e-8
    revealed = revealed_state_values(fact)
    assert np.all(revealed.value <= values.value + 1e-9)
    assert np.all(revealed.q_matrix(fact) <= Q + 1e-9)
