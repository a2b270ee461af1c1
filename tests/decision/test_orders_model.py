"""The orders' model (issue 23; planner/decision/orders.py): the Pitman-Yor mixture over recorded orders against its
closed form (no orders: the paper's model; one order recorded n times: its initial belief is the formula), and the
equivalence flat = factored = lumped to 1e-9 along random histories on the pen and synthetic products (the flat
model over the real graph with the mixture as its initial belief; the factored and lumped ones on the augmented
graph)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from planner import chain_product, complete_product, make_plan
from planner.decision import factored_model, intention_model, lumped_pomdp
from planner.decision.habits import HabitsError, edge_keys, habits_from_counts
from planner.decision.orders import check_orders_parameters, orders_prior, prior_inputs
from reference import filtered_histories, horizon_value

TOLERANCE = 1e-9


def _habits(plan, orders, concentration=1.0, discount=0.5):
    """Habits of ``plan`` holding ``orders`` ((state edges, count) pairs), used by the orders' model."""
    keys = edge_keys(plan)
    counts = np.ones(plan.states.n_edges)
    return replace(habits_from_counts(plan, counts), prior_model="orders", concentration=concentration,
                   discount=discount, orders=tuple((tuple(keys[e] for e in edges), n) for edges, n in orders))


def _random_orders(plan, rng, k, fractional=False):
    """``k`` distinct orders with whole counts from 1 to 19, or (``fractional``) posterior-like ones in (0, 2),
    some below the discount (docs/habits.md, Learning from logs)."""
    base = factored_model(plan)
    ranks = rng.choice(base.n_sequences, size=min(k, base.n_sequences), replace=False)
    counts = rng.uniform(0.05, 2.0, ranks.size) if fractional else rng.integers(1, 20, ranks.size)
    return [(tuple(base.sequence(int(r))), float(n)) for r, n in zip(ranks, counts)]


@pytest.fixture(scope="module", params=["pen-technical", "pen-no-technical", "chain-5", "complete-4",
                                        "chain-5-fractional", "pen-fractional"])
def ordered(request, pen):
    product, technical = {"pen-technical": (pen, True), "pen-no-technical": (pen, False),
                          "chain-5": (chain_product(5), None), "complete-4": (complete_product(4), None),
                          "chain-5-fractional": (chain_product(5), None),
                          "pen-fractional": (pen, True)}[request.param]
    plan = make_plan(product, technical)
    rng = np.random.default_rng(sum(map(ord, request.param)))
    a, d = float(rng.choice([0.3, 1.0, 4.0])), float(rng.choice([0.0, 0.5, 0.9]))
    if request.param.endswith("fractional"):
        d = 0.9  # so that some counts are below the discount
    orders = orders_prior(plan, _habits(plan, _random_orders(plan, rng, 4, request.param.endswith("fractional")),
                                        a, d))
    return plan, orders, intention_model(plan, orders=orders), factored_model(plan, orders=orders)


def test_no_orders_is_the_base_model_exactly(pen):
    plan = make_plan(pen)
    habits = _habits(plan, [])
    assert orders_prior(plan, habits) is None and prior_inputs(plan, habits) == (None, None)
    paper, same = intention_model(plan), intention_model(plan, orders=orders_prior(plan, habits))
    assert np.array_equal(paper.pomdp.initial, same.pomdp.initial)


def test_one_order_recorded_n_times_has_the_formula_belief(pen):
    """p(sigma) = (n - d) / (n + a) + (a + d) / (n + a) / N for the order, (a + d) / (n + a) / N for the others;
    a fractional n below d is discounted by n (mixture_weights): (a + n) / (n + a) = 1 goes to the base, the
    paper's model."""
    plan = make_plan(pen)
    base = factored_model(plan)
    N = base.n_sequences
    for n, a, d in ((7, 1.0, 0.5), (1, 0.2, 0.0), (20, 3.0, 0.9), (1.4, 1.0, 0.9), (0.3, 1.0, 0.9)):
        order = tuple(base.sequence(11))
        orders = orders_prior(plan, _habits(plan, [(order, float(n))], a, d))
        flat, fact = intention_model(plan, orders=orders), factored_model(plan, orders=orders)
        starts = flat.full_sequences()
        initial = flat.pomdp.initial[starts]
        ops = [flat.sequence_operations(int(i)) for i in starts]
        mine = ops.index(base.sequence_operations(list(order)))
        taken = min(n, d)
        other = (a + taken) / (n + a) / N
        assert initial[mine] == pytest.approx((n - taken) / (n + a) + other, rel=1e-12)
        assert np.allclose(np.delete(initial, mine), other, rtol=1e-12)
        for k in range(N):  # the factored model's prior of each sequence: the product of its choices
            path = fact.sequence(k)
            expected = initial[ops.index(fact.sequence_operations(path))]
            assert float(np.prod(fact.class_fraction[path])) == pytest.approx(expected, rel=1e-12)


def test_ranks_name_the_same_sequences_as_the_real_graph(ordered):
    plan, orders, _, fact = ordered
    base = factored_model(plan)
    assert fact.n_sequences == base.n_sequences
    for k in range(base.n_sequences):
        assert fact.sequence_operations(fact.sequence(k)) == base.sequence_operations(base.sequence(k))
        assert orders.augmented_path(base.sequence(k)) == fact.sequence(k)


def test_flat_factored_and_lumped_agree_along_episodes(ordered):
    """Random histories drawn from the flat model: the next step's distribution (the belief summed per real
    state edge), the expected rewards and the observation probabilities agree; the lumped POMDP's belief is
    the factored one."""
    plan, orders, flat_model, fact = ordered
    flat, lumped = flat_model.pomdp, lumped_pomdp(fact)
    E = plan.states.n_edges
    edge_of = np.append(orders.plan.states.edge_of, E)  # an augmented class's real state edge (E: finished)
    of = np.where(flat_model.graph.step_edge >= 0, flat_model.graph.step_edge, E)
    for b, belief, c in filtered_histories(flat_model, fact, lumped, np.random.default_rng(5), 10):
        dense = belief.dense(fact.n_classes)
        assert np.abs(np.bincount(of, weights=b, minlength=E + 1)
                      - np.bincount(edge_of, weights=dense, minlength=E + 1)).max() <= TOLERANCE
        assert np.abs(fact.expected_rewards(belief) - flat.reward @ b).max() <= TOLERANCE
        assert np.abs(dense - c).max() <= TOLERANCE


def test_flat_and_lumped_values_are_equal(ordered):
    """The exact three-step values at the initial belief (every history of three steps) are the same."""
    _, _, flat_model, fact = ordered
    value = horizon_value(flat_model.pomdp, 3)
    assert horizon_value(lumped_pomdp(fact), 3) == pytest.approx(value, abs=TOLERANCE)


def test_bad_orders_are_refused(pen):
    plan = make_plan(pen)
    base = factored_model(plan)
    order = tuple(base.sequence(2))
    with pytest.raises(HabitsError, match=r"orders\[0\]: count"):
        orders_prior(plan, _habits(plan, [(order, float("nan"))]))
    with pytest.raises(HabitsError, match=r"orders\[0\]: count -1"):
        orders_prior(plan, _habits(plan, [(order, -1.0)]))
    with pytest.raises(HabitsError, match="before the finished product"):
        orders_prior(plan, _habits(plan, [(order[:-1], 2.0)]))
    with pytest.raises(HabitsError, match="not a step of this product's state graph"):
        orders_prior(plan, _habits(plan, [(order[1:], 2.0)]))
    with pytest.raises(HabitsError, match="recorded twice"):
        orders_prior(plan, _habits(plan, [(order, 2.0), (order, 1.0)]))
    for a, d in ((1.0, 1.0), (1.0, -0.1), (-0.5, 0.5), (float("inf"), 0.0), (1.0, float("nan"))):
        with pytest.raises(HabitsError, match="orders' (discount|concentration)"):
            check_orders_parameters(a, d, "f.json")
    assert check_orders_parameters(-0.4, 0.5, "f.json") == (-0.4, 0.5)
    # a - d < a + min(n, d) <= 0: a negative concentration with one order weighing 0.2 < d would leave pi_0 < 0
    with pytest.raises(HabitsError, match=r"the habits: the orders. concentration -0.4 .* leave the base a weight of -0.2"):
        orders_prior(plan, _habits(plan, [(order, 0.2)], -0.4, 0.5))


def test_the_orders_model_is_built_alone(ordered):
    """A base part, a parallel model or deviations with the orders' model: refused, naming the option."""
    from planner.decision.deviations import deviations_of
    from planner.errors import PlannerError

    plan, orders, _, _ = ordered
    part = plan.andor.parts[0]
    for options, flag in (({"base_part": part}, "--base-part"), ({"parallel": True}, "--parallel"),
                          ({"deviations": deviations_of(0.05, 0.0)}, "--switch")):
        with pytest.raises(PlannerError, match=flag):
            factored_model(plan, orders=orders, **options)
    with pytest.raises(PlannerError, match="--switch"):
        intention_model(plan, orders=orders, deviations=deviations_of(0.0, 0.02))


def test_the_solver_and_its_warm_start_run_on_the_orders_model(pen):
    """The offline solver on the flat model (the mixture as its prior) and on the lumped one with the warm start
    (class-MDP and delayed-reveal bounds over the augmented classes): their certified intervals of V*(b0) overlap,
    and the recorded habit raises the value above the paper's model's."""
    from planner.decision import PointBasedSolver
    from planner.decision.solvers.warm_start import solver_bounds

    plan = make_plan(pen, True)
    base = factored_model(plan)
    orders = orders_prior(plan, _habits(plan, [(tuple(base.sequence(3)), 16.0), (tuple(base.sequence(9)), 1.0)]))
    flat, fact = intention_model(plan, orders=orders).pomdp, factored_model(plan, orders=orders)
    solver = PointBasedSolver(time_limit=None, max_iterations=60, precision=1e-6)
    Q, groups = solver_bounds(fact)
    a, b = solver.solve(flat), solver.solve(lumped_pomdp(fact), upper=Q, groups=groups)
    assert max(a.lower_bound, b.lower_bound) <= min(a.upper_bound, b.upper_bound) + 1e-9
    assert a.lower_bound > solver.solve(intention_model(plan).pomdp).upper_bound
