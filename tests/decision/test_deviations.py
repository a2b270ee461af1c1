"""Change of mind and mistakes in the decision models (issue 23 item 3, planner/decision/deviations.py): the flat
tables against a literal construction (loops over intentions), flat = factored = lumped to 1e-9 along random
histories (with habits and a base part too), no reset with mistakes, the paper's tables byte for byte when both
probabilities are 0, and the bounds of the online planner and the solver above the exact finite-horizon value."""
from __future__ import annotations

import numpy as np
import pytest

from planner import chain_product, complete_product, make_plan
from planner.decision import (DiscreteUpdater, FactoredUpdater, factored_model, intention_model, lumped_pomdp,
                              to_flat)
from planner.decision.deviations import Deviations, check_probability, deviations_of
from planner.decision.habits import habit_weights_from
from planner.errors import PlannerError
from reference import horizon_value

TOLERANCE = 1e-9


@pytest.fixture(scope="module", params=["pen-technical", "chain-5-habits", "complete-4", "pen-base-part"])
def deviating(request, pen):
    product, technical, habits, base = {"pen-technical": (pen, True, False, None),
                                        "chain-5-habits": (chain_product(5), None, True, None),
                                        "complete-4": (complete_product(4), None, False, None),
                                        "pen-base-part": (pen, False, True, "body")}[request.param]
    plan = make_plan(product, technical)
    rng = np.random.default_rng(sum(map(ord, request.param)))
    weights = None
    if habits:
        E = plan.states.n_edges
        weights = habit_weights_from(plan, rng.integers(1, 30, E) * (rng.random(E) < 0.6), 1.0)
    deviations = Deviations(float(rng.choice([0.05, 0.3])), float(rng.choice([0.02, 0.2])))
    return (plan, weights, deviations, intention_model(plan, base_part=base, weights=weights, deviations=deviations),
            factored_model(plan, base_part=base, weights=weights, deviations=deviations))


def _literal_flat(flat, deviations):
    """T and O of the flat model with deviations, built intention by intention from the paper's tables (module
    docstring of deviations.py): wait = S W, a performing row = step then S W, O' = (1 - mu) O + mu / Z."""
    paper = flat.world
    n = paper.n_states
    W = paper.transition[-1].toarray()
    prior = np.ones(n) if flat.prior_weights is None else flat.prior_weights
    S = np.zeros((n, n))
    for i in range(n):
        same = [j for j in range(n) if flat.graph.first_state[j] == flat.graph.first_state[i]]
        total = sum(prior[j] for j in same)
        for j in same:
            S[i, j] += deviations.switch * prior[j] / total
        S[i, i] += 1 - deviations.switch
    tables = []
    for a in range(paper.n_actions - 1):
        T = np.eye(n)
        base = paper.transition[a].toarray()
        for i in range(n):
            if base[i, i] != 1.0:  # the action performs i's next step
                T[i] = (S @ W)[flat.graph.successor[i]]
        tables.append(T)
    tables.append(S @ W)
    O = paper.observation[0].toarray() * (1 - deviations.mistake) + deviations.mistake / paper.n_observations
    return tables, O


def test_flat_tables_match_the_literal_definition(deviating):
    _, _, deviations, flat, _ = deviating
    tables, O = _literal_flat(flat, deviations)
    for a, T in enumerate(tables):
        assert np.abs(flat.pomdp.transition[a].toarray() - T).max() <= 1e-12
    assert np.abs(flat.pomdp.observation[0].toarray() - O).max() <= 1e-12
    assert np.all(O > 0)  # every observation is possible in every intention: no reset


def test_flat_factored_and_lumped_agree_along_random_histories(deviating):
    """Any action and any observation (every one is possible with mistakes): the flat, factored and lumped
    beliefs, expected rewards and observation probabilities are the same at every step, and nothing resets."""
    _, weights, _, flat_model, fact = deviating
    flat, lumped = flat_model.pomdp, lumped_pomdp(fact)
    of = np.where(flat_model.graph.step_edge >= 0, flat_model.graph.step_edge, fact.final_class)
    assert np.abs(lumped.initial - np.bincount(of, weights=flat.initial, minlength=fact.n_classes)).max() <= 1e-15
    rng = np.random.default_rng(3)
    up_flat, up_fact, up_lump = DiscreteUpdater(flat), FactoredUpdater(fact), DiscreteUpdater(lumped)
    for episode in range(6):
        b, belief, c = up_flat.initialize(), up_fact.initialize(), up_lump.initialize()
        for _ in range(15):
            assert np.abs(to_flat(belief, flat_model.graph, weights) - b).max() <= TOLERANCE
            assert np.abs(np.bincount(of, weights=b, minlength=fact.n_classes) - c).max() <= TOLERANCE
            assert np.abs(fact.expected_rewards(belief) - flat.reward @ b).max() <= TOLERANCE
            a = int(rng.integers(flat.n_actions)) if episode % 2 else flat.n_actions - 1
            z = int(rng.integers(flat.n_observations))
            zb = flat.observation[a].T @ (flat.transition[a].T @ b)
            zc = lumped.observation[a].T @ (lumped.transition[a].T @ c)
            assert np.abs(zb - zc).max() <= TOLERANCE
            b, belief, c = up_flat.update(b, a, z), up_fact.update(belief, a, z), up_lump.update(c, a, z)
    assert not up_flat.events and not up_fact.events and not up_lump.events


def test_a_change_of_mind_alone_keeps_the_models_equal_after_resets(pen):
    """Switch without mistakes: an observation no class explains still resets, and the flat and factored resets
    agree (a redraw reaches the classes of the belief's states)."""
    plan = make_plan(pen, True)
    d = Deviations(0.2, 0.0)
    flat_model, fact = intention_model(plan, deviations=d), factored_model(plan, deviations=d)
    b, belief = DiscreteUpdater(flat_model.pomdp).initialize(), FactoredUpdater(fact).initialize()
    wait = len(fact.actions) - 1
    kinds = set()
    for _ in range(4):
        b = DiscreteUpdater(flat_model.pomdp).update(b, wait, 0)
        belief = FactoredUpdater(fact).update(belief, wait, 0)
        for action in range(len(fact.actions)):
            for z in range(len(fact.observations)):
                one = DiscreteUpdater(flat_model.pomdp, on_reset=lambda e: None)
                mine = FactoredUpdater(fact, on_reset=lambda e: None)
                expected, got = one.update(b, action, z), mine.update(belief, action, z)
                assert np.abs(to_flat(got, flat_model.graph) - expected).max() <= TOLERANCE
                assert [e.reset_to for e in one.events] == [e.reset_to for e in mine.events]
                kinds.update(e.reset_to for e in mine.events)
    assert kinds  # some observation is still unexplained without mistakes


def test_a_redraw_spreads_a_known_class_over_its_state_by_the_prior(pen):
    """Closed form: from one class c at state s, waiting gives every other class c' of s the mass
    sigma share(c') / 2 (redrawn, then stayed), and c itself (1 - sigma) / 2 + sigma share(c) / 2."""
    from planner.decision.factored_model import FactoredBelief

    plan = make_plan(pen, True)
    sigma = 0.3
    model = factored_model(plan, deviations=Deviations(sigma, 0.0))
    classes = model.classes_from(plan.states.initial)
    assert classes.size >= 2
    c = int(classes[0])
    predicted = model.predict(FactoredBelief(np.array([c]), np.ones(1)), model.wait)
    dense = predicted.dense(model.n_classes)
    share = model.class_fraction[classes]
    expected = sigma * share / 2
    expected[0] += (1 - sigma) / 2
    assert np.abs(dense[classes] - expected).max() <= 1e-15
    assert dense.sum() == pytest.approx(1.0, abs=1e-15)


def test_mistakes_move_the_belief_where_the_paper_resets(pen):
    """An observation no class can emit after the first operation: the paper's filter resets, the mistake
    model's does not and keeps the belief it predicted (a wrong part says nothing about the intention)."""
    plan = make_plan(pen, True)
    paper, model = factored_model(plan), factored_model(plan, deviations=Deviations(0.0, 0.05))
    first = paper.sequence(0)[0]
    z_first = int(plan.operation_observation[paper.class_operation[first]])
    up_paper, up_model = FactoredUpdater(paper, on_reset=lambda e: None), FactoredUpdater(model)
    b_paper = up_paper.update(up_paper.initialize(), paper.wait, z_first)
    b_model = up_model.update(up_model.initialize(), model.wait, z_first)
    predicted = paper.predict(b_paper, paper.wait)
    odd = next(z for z in range(1, len(plan.observations))
               if not (paper.observation_likelihood(z, predicted.classes) > 0).any())
    up_paper.update(b_paper, paper.wait, odd)
    assert up_paper.events
    after = up_model.update(b_model, model.wait, odd)
    assert not up_model.events
    expected = model.predict(b_model, model.wait)
    assert np.abs(after.dense(model.n_classes) - expected.dense(model.n_classes)).max() <= 1e-12


def test_both_zero_is_the_papers_model_byte_for_byte(pen):
    plan = make_plan(pen, True)
    assert deviations_of(0.0, 0.0) is None
    paper, again = intention_model(plan), intention_model(plan, deviations=deviations_of(0, 0))
    for a, b in zip(paper.pomdp.transition + paper.pomdp.observation, again.pomdp.transition + again.pomdp.observation):
        assert (a != b).nnz == 0
    fp, fa = lumped_pomdp(factored_model(plan)), lumped_pomdp(factored_model(plan, deviations=deviations_of()))
    for a, b in zip(fp.transition + fp.observation, fa.transition + fa.observation):
        assert a.shape == b.shape and (a != b).nnz == 0


@pytest.mark.parametrize("bad", [-0.1, 1.0, 1.5, float("nan"), float("inf"), "0.1", True])
def test_probabilities_outside_zero_one_are_refused(bad):
    with pytest.raises(PlannerError, match=r"in \[0, 1\)"):
        check_probability(bad, "--switch")
    with pytest.raises(PlannerError):
        Deviations(bad if not isinstance(bad, str) else 2.0, 0.0)


def test_bounds_stay_above_the_exact_values(pen):
    """The online planner's class values (QMDP with the redraw's fixed point) and the revealed-state bound are
    upper bounds: at the initial belief above the exact 4-step value of the lumped POMDP (no value exceeds
    the discounted tail's largest reward, bounded here by the certified solver's upper bound); the solver on
    the flat and the lumped models (its start from those bounds) gives overlapping intervals."""
    from planner.decision import PointBasedSolver
    from planner.decision.solvers.warm_start import solver_bounds
    from planner.decision.online import OnlinePlanner, class_values, revealed_state_values

    plan = make_plan(pen, True)
    d = Deviations(0.3, 0.05)
    fact = factored_model(plan, deviations=d)
    flat, lumped = intention_model(plan, deviations=d).pomdp, lumped_pomdp(fact)
    exact = horizon_value(lumped, 3)
    assert horizon_value(flat, 3) == pytest.approx(exact, abs=1e-9)
    solver = PointBasedSolver(time_limit=None, max_iterations=80, precision=1e-6)
    a = solver.solve(flat)
    Q, groups = solver_bounds(fact)
    b = solver.solve(lumped, upper=Q, groups=groups)
    assert max(a.lower_bound, b.lower_bound) <= min(a.upper_bound, b.upper_bound) + 1e-9
    b0 = fact.initial_belief()
    qmdp, revealed = class_values(fact), revealed_state_values(fact)
    for values in (qmdp, revealed):
        assert values.q_values(fact, b0).max() >= a.lower_bound - 1e-9
    # Class by class: the revealed bound at a single class is above the solver's lower bound there.
    for c in range(fact.n_classes):
        corner = np.zeros(fact.n_classes)
        corner[c] = 1.0
        assert revealed.value[c] >= float(np.max(b.policy.alphas @ corner)) - 1e-6
    planner = OnlinePlanner(fact, 200, None)
    report = planner.search(b0)
    assert report.lower <= report.upper + 1e-9
    assert report.upper >= a.lower_bound - 1e-6 and report.lower <= a.upper_bound + 1e-6


def test_class_values_are_the_lumped_mdps_values(pen):
    """The online planner's QMDP values with a change of mind (a fixed point per state, from above) equal
    plain value iteration on the lumped POMDP's tables (an independent computation), to 1e-9."""
    from planner.decision.online import class_values

    plan = make_plan(pen, True)
    fact = factored_model(plan, deviations=Deviations(0.3, 0.1))
    lumped = lumped_pomdp(fact)
    T = [t.toarray() for t in lumped.transition]
    V = np.zeros(lumped.n_states)
    for _ in range(3000):  # 0.9 ** 3000: converged far below the tolerance
        V = np.max([lumped.reward[a] + lumped.discount * T[a] @ V for a in range(lumped.n_actions)], axis=0)
    values = class_values(fact)
    assert np.abs(V - values.value).max() <= 1e-9
    assert np.all(values.value >= V - 1e-9)


def test_the_flat_models_redraw_tables_are_refused_past_the_budget(pen):
    """The flat redraw is dense per state: its entries are estimated from the intentions per state before any
    table is built, and a budget between the paper's model and that estimate refuses it, naming the factored
    model; the factored model needs no such table."""
    from planner.decision.deviations import flat_deviation_entries
    from planner.decision.intention_model import flat_model_bytes
    from planner.errors import MemoryLimitError

    plan = make_plan(pen, True)
    d = Deviations(0.1, 0.0)
    paper = intention_model(plan)
    n = np.bincount(paper.graph.first_state)
    robot = len(paper.actions) - 1
    entries = flat_deviation_entries(paper.graph, robot, len(plan.observations), d)
    assert entries == (1 + robot) * int((2 * n * n).sum())  # closed form of the docstring
    budget = max(flat_model_bytes(plan), 24 * entries // 2)
    intention_model(plan, max_bytes=budget)  # the paper's model fits
    with pytest.raises(MemoryLimitError, match="--planner online"):
        intention_model(plan, max_bytes=budget, deviations=d)
    factored_model(plan, deviations=d)


def test_the_online_split_with_mistakes_is_the_exhaustive_one(pen):
    """The online planner's split by observation with mistakes: each branch's probability and posterior equal
    those computed observation by observation from the likelihoods, and the one branch that stands for the
    observations the belief does not emit carries all of their probability (their posteriors are equal)."""
    from planner.decision.online import observation_split

    plan = make_plan(pen, True)
    model = factored_model(plan, deviations=Deviations(0.1, 0.05))
    updater = FactoredUpdater(model)
    belief = updater.update(updater.initialize(), model.wait, 0)
    predicted = model.predict(belief, model.wait)
    Z = len(model.observations)
    p = np.array([float(predicted.mass @ model.observation_likelihood(z, predicted.classes)) for z in range(Z)])
    assert p.sum() == pytest.approx(1.0, abs=1e-12)
    branches = observation_split(model, predicted)
    assert sum(q for _, q, _ in branches) == pytest.approx(1.0, abs=1e-12)
    for z, q, posterior in branches[:-1]:
        assert q == pytest.approx(p[z], abs=1e-12)
        expected = updater.update(belief, model.wait, z)
        assert np.abs(posterior.dense(model.n_classes) - expected.dense(model.n_classes)).max() <= 1e-12
    z, q, posterior = branches[-1]
    emitted = {b[0] for b in branches[:-1]}
    rest = [y for y in range(Z) if y not in emitted]
    assert z == rest[0] and q == pytest.approx(p[rest].sum(), abs=1e-12)
    for y in rest:
        assert np.abs(updater.update(belief, model.wait, y).dense(model.n_classes)
                      - posterior.dense(model.n_classes)).max() <= 1e-12


def test_model_paper_forces_both_to_zero_in_the_written_model(tmp_path):
    """``--model paper`` ignores --switch and --mistakes: the written POMDP is the paper's byte for byte, and
    the one with them differs (a dense observation table)."""
    from aplan_runner import run_aplan

    paper, forced, deviating = (tmp_path / f"{name}.pomdp" for name in ("paper", "forced", "deviating"))
    assert run_aplan("pomdp", "pen", "-o", paper).returncode == 0
    assert run_aplan("pomdp", "pen", "-o", forced, "--switch", "0.2", "--mistakes", "0.1", "--model",
                     "paper").returncode == 0
    assert run_aplan("pomdp", "pen", "-o", deviating, "--switch", "0.2", "--mistakes", "0.1").returncode == 0
    assert forced.read_bytes() == paper.read_bytes() != deviating.read_bytes()


class _Waiting:
    """A robot that always waits (the observer of bench/bench_change_of_mind.py)."""

    def __init__(self, wait: int):
        self.wait = wait

    def action(self, belief) -> int:
        return self.wait


@pytest.mark.parametrize("kind", ["flat", "factored"])
def test_a_change_of_mind_moves_no_belief_while_the_robot_waits(pen, kind):
    """Within an assembly state the belief is the prior over its completions (observations depend on the state
    only), and a redraw draws from that prior: so while the robot never rules a completion out, ``--switch``
    leaves every belief as the paper's (seeded paired episodes of a changing operator, switched ones among
    them); it does move mass after a wrong robot action (the ruled-out class comes back)."""
    from planner.decision.episodes import EpisodeChoice, simulate
    from planner.decision.operators import parse_operator

    plan = make_plan(pen, True)
    build = intention_model if kind == "flat" else factored_model
    paper, switching = build(plan), build(plan, deviations=Deviations(0.3, 0.0))
    wait = len(paper.actions) - 1
    choice = EpisodeChoice(random=40, seed=3, operator_model=parse_operator("uniform,changing:0.3"))
    played = [simulate(m, _Waiting(wait), choice) for m in (paper, switching)]
    assert sum(e.switched_at is not None for e in played[0]) >= 5
    for one, two in zip(*played):
        assert [s.observation for s in one.steps] == [s.observation for s in two.steps]
        assert np.abs(np.array([s.p_true for s in one.steps]) - [s.p_true for s in two.steps]).max() <= 1e-12
    if kind == "factored":  # a wrong robot action rules the performing class out; the redraw brings it back
        c = int(paper.classes_from(plan.states.initial)[0])
        action = int(paper.class_action[c])
        assert action >= 0
        after = []
        for m in (paper, switching):  # the robot does c's operation, then waits; the camera sees blanks
            up = FactoredUpdater(m)
            after.append(up.update(up.update(up.initialize(), action, 0), m.wait, 0).dense(m.n_classes))
        assert after[0][c] == 0.0 < after[1][c]

