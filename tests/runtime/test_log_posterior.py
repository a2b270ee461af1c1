"""The posterior over the sequences that explain a log (planner.runtime.log_posterior), against closed forms and a
brute-force enumeration: under the paper's prior the k full sequences done by the operator that give the same
observations weigh 1/k each (every full sequence has the prior 1/N); under any per-state prior an explanation
weighs the product of the operator's choices along it; a log that one sequence explains counts exactly 1."""
from __future__ import annotations

import numpy as np
import pytest

from planner import chain_product, complete_product, make_plan
from planner.assembly.explode import SequenceError
from planner.assembly.tags import BLANK
from planner.decision import factored_model
from planner.decision.habits import add_sequence, choice_probabilities
from planner.runtime.habits_logs import log_prior
from planner.runtime.log_posterior import explanations


def _observed(plan, edges, robot=()):
    """The steps a log of the sequence ``edges`` (state edges) shows; the steps at ``robot`` done by the robot."""
    states, seen = plan.states, plan.operation_observation
    return [("robot", int(states.edge_operation[e])) if k in robot else ("operator", int(seen[states.edge_operation[e]]))
            for k, e in enumerate(edges)]


def _brute(plan, steps, choice):
    """Every distinct sequence explaining ``steps`` (the finished ones if any), weighed by the product of the
    operator's choices, normalised; and the operator's expected edge counts. By enumeration of all alignments."""
    states, seen = plan.states, plan.operation_observation
    blank = plan.observations.index(BLANK)
    found = {}

    def walk(state, t, path, operator):
        if t == len(steps):
            found[tuple(path)] = (state, tuple(operator))
            return
        who, value = steps[t]
        for e in np.flatnonzero(states.edge_source == state):
            op = int(states.edge_operation[e])
            if (op == value) if who == "robot" else (seen[op] == value):
                walk(int(states.edge_target[e]), t + 1, path + [int(e)], operator + [who == "operator"])
        if who == "operator" and value == blank:
            walk(state, t + 1, path, operator)

    walk(states.initial, 0, [], [])
    if any(state == states.final for state, _ in found.values()):
        found = {p: v for p, v in found.items() if v[0] == states.final}
    weights = {p: float(np.prod([choice[e] for e, mine in zip(p, v[1]) if mine])) for p, v in found.items()}
    total = sum(weights.values())
    counts = np.zeros(states.n_edges)
    for p, v in found.items():
        for e, mine in zip(p, v[1]):
            counts[e] += weights[p] / total if mine else 0.0
    return {p: w / total for p, w in weights.items()}, counts


@pytest.mark.parametrize("product", [chain_product(5), complete_product(5)], ids=["chain-5", "complete-5"])
def test_same_observations_share_the_uniform_posterior(product):
    """Each group of k full sequences with the same observations: each gets 1/k, and the expected count of an
    edge is the share of the group that takes it."""
    plan = make_plan(product)
    base = factored_model(plan)
    groups = {}
    for k in range(base.n_sequences):
        edges = tuple(base.sequence(k))
        groups.setdefault(tuple(_observed(plan, edges)), []).append(edges)
    assert max(map(len, groups.values())) > 1  # the product has ambiguous logs
    p0 = log_prior(plan)
    for steps, members in groups.items():
        found = explanations(plan, list(steps), p0)
        assert found.finished and found.number == len(members)
        assert dict(found.orders) == pytest.approx({m: 1 / len(members) for m in members}, rel=1e-12)
        share = np.zeros(plan.states.n_edges)
        for m in members:
            np.add.at(share, list(m), 1 / len(members))
        assert found.counts == pytest.approx(share, abs=1e-12)


def test_one_explanation_counts_exactly_one(pen):
    """The pen: every full sequence's log is explained by it alone (with and without robot steps), and counts
    what add_sequence counts, bit for bit, with one order of weight exactly 1."""
    plan = make_plan(pen)
    base = factored_model(plan)
    for k in range(base.n_sequences):
        edges = tuple(base.sequence(k))
        for robot in ((), (1,), (0, len(edges) - 1)):
            counts = np.zeros(plan.states.n_edges)
            add_sequence(plan, counts, [int(plan.states.edge_operation[e]) for e in edges],
                         counted=[j not in robot for j in range(len(edges))])
            found = explanations(plan, _observed(plan, edges, robot), log_prior(plan))
            assert np.array_equal(found.counts, counts) and found.orders == ((edges, 1.0),)


@pytest.mark.parametrize("product", [chain_product(5), complete_product(5)], ids=["chain-5", "complete-5"])
def test_any_prior_robot_steps_blanks_and_early_stops_match_the_enumeration(pen, product):
    """Random per-state priors, logs with robot steps, blank observations added anywhere (nothing done, or a
    hidden operation: chain 6 has runs of blanks whose hidden operation could take either step, counted once)
    and sessions stopped early: the forward-backward counts and the enumerated orders are the brute-force
    posterior's."""
    rng = np.random.default_rng(7)
    for plan, tries in ((make_plan(product), 40), (make_plan(pen), 40), (make_plan(chain_product(6)), 300)):
        base = factored_model(plan)
        blank = plan.observations.index(BLANK)
        for _ in range(tries):
            choice = choice_probabilities(plan, rng.integers(0, 4, plan.states.n_edges).astype(float), 0.7)
            edges = tuple(base.sequence(int(rng.integers(base.n_sequences))))
            robot = set(np.flatnonzero(rng.random(len(edges)) < 0.3).tolist())
            steps = _observed(plan, edges, robot)[:int(rng.integers(1, len(edges) + 1))]
            for at in sorted(rng.integers(0, len(steps) + 1, int(rng.integers(0, 5))).tolist(), reverse=True):
                steps.insert(at, ("operator", blank))
            posterior, counts = _brute(plan, steps, choice)
            found = explanations(plan, steps, choice)
            assert found.counts == pytest.approx(counts, abs=1e-12)
            if found.finished:
                assert dict(found.orders) == pytest.approx(posterior, rel=1e-12)
            else:
                assert found.orders == () and found.number == 0


def test_past_the_cap_no_order_is_recorded():
    plan = make_plan(chain_product(5))
    base = factored_model(plan)
    groups = {}
    for k in range(base.n_sequences):
        edges = tuple(base.sequence(k))
        groups.setdefault(tuple(_observed(plan, edges)), []).append(edges)
    steps, members = max(groups.items(), key=lambda item: len(item[1]))
    p0 = log_prior(plan)
    assert explanations(plan, list(steps), p0, cap=len(members)).orders is not None
    cut = explanations(plan, list(steps), p0, cap=len(members) - 1)
    assert cut.orders is None and cut.number == len(members)
    assert np.array_equal(cut.counts, explanations(plan, list(steps), p0).counts)  # the counts still carry it


def test_steps_no_sequence_explains_are_refused(pen):
    plan = make_plan(pen)
    edges = tuple(factored_model(plan).sequence(0))
    with pytest.raises(SequenceError, match="no assembly sequence"):
        explanations(plan, _observed(plan, edges)[1:2] * 2 + [("robot", int(plan.states.edge_operation[edges[0]]))],
                     log_prior(plan))
