"""The readings of "the belief on the new true sequence" after a change of mind (planner/decision/mind_measures.py,
docs/deviations.md) and the crossing operator of reading (c) (planner/decision/operators.py): closed forms of
the paper's prior checked step by step, the order of the readings, and a crossing operator that does what it
says (the two sequences meet at one state, and a switched episode ends with the first's start and the second's
completion)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from planner import make_plan
from planner.decision import factored_model
from planner.decision.episodes import EpisodeChoice, simulate
from planner.decision.mind_measures import READINGS, passes_after_switch, step_readings, switch_totals
from planner.decision.operators import CrossingOperator, crossing_pair, parse_operator
from planner.errors import PlannerError


class _Waiting:
    def __init__(self, wait: int):
        self.wait = wait

    def action(self, belief) -> int:
        return self.wait


@pytest.fixture(scope="module")
def model(pen):
    return factored_model(make_plan(pen, True))


@pytest.fixture(scope="module")
def played(model):
    changing = parse_operator("uniform,changing:0.3")
    return simulate(model, _Waiting(model.wait), EpisodeChoice(random=30, seed=5, operator_model=changing))


def _steps(episode):
    for k in range(1, len(episode.steps) + 1):
        if not episode.unfinished(episode.steps[k - 1]):
            return
        yield k


def test_readings_follow_the_paper_prior_while_the_robot_waits(model, played):
    """Under the paper's prior, with no completion ruled out: the intention's belief is its class's mass over
    the class's N(target) intentions, and the class's mass is its state's mass times N(target) / N(state)."""
    checked = 0
    for episode in played:
        for k in _steps(episode):
            r = step_readings(model, episode, k)
            e = episode.path[episode.steps[k - 1].position]
            size, state = int(model.paths[model.class_target[e]]), int(model.paths[model.class_source[e]])
            assert r["intention"] == pytest.approx(r["next_class"] / size, abs=1e-12)
            assert r["next_class"] == pytest.approx(r["state"] * size / state, abs=1e-12)
            assert r["intention"] <= r["next_class"] + 1e-12 <= r["next_operation"] + 2e-12
            checked += 1
    assert checked > 60


def test_passes_after_switch_counts_from_the_switch_to_the_end(model, played):
    switched = [e for e in played if e.switched_at is not None]
    assert switched and any(e.switched_at is None for e in played)
    for episode in played:
        passed = passes_after_switch(model, episode)
        if episode.switched_at is None:
            assert passed is None
            continue
        steps = [k for k in _steps(episode) if k >= episode.switched_at]
        for name in READINGS:  # an independent loop over the same steps
            assert passed[name] == any(step_readings(model, episode, k)[name] > 0.9 for k in steps)
    totals = switch_totals(model, played)
    assert totals["switched"] == len(switched)
    assert totals["intention"] <= totals["next_class"] <= totals["next_operation"]
    assert totals["resets"] == totals["reset_episodes"] == 0


def test_crossing_pair_meets_at_one_state_and_parts(model):
    first, second, q = crossing_pair(model, np.random.default_rng(1))
    assert len(first) == len(second) == 5 and 1 <= q < 5
    assert model.class_source[first[q]] == model.class_source[second[q]]
    assert first[q:] != second[q:]
    for path in (first, second):  # each a full sequence: consecutive edges, initial to final state
        assert model.class_source[path[0]] == model.plan.states.initial
        assert all(model.class_target[a] == model.class_source[b] for a, b in zip(path, path[1:]))
        assert model.class_target[path[-1]] == model.final_state


def test_crossing_operator_switches_to_the_other_completion(model):
    first, second, q = crossing_pair(model, np.random.default_rng(1))
    operator = CrossingOperator(first, second, q, 0.5)
    episodes = simulate(model, _Waiting(model.wait), EpisodeChoice(random=40, seed=2, operator_model=operator))
    plans = operator.plans(model, 40, np.random.default_rng(2), np.random.default_rng([2, 1]))
    switched = sum(p.switch is not None for p in plans)
    assert 0 < switched < 40
    assert {tuple(p.sequence) for p in plans} == {tuple(first), tuple(second)}
    for plan, episode in zip(plans, episodes):  # the observer never jumps over the crossing
        assert episode.path == operator.done(plan)
        assert (episode.switched_at is not None) == (plan.switch is not None)
    mixed = [e.path for e in episodes if e.switched_at is not None]
    assert all(p in (first[:q] + second[q:], second[:q] + first[q:]) for p in mixed)
    with pytest.raises(PlannerError, match=r"\[0, 1\)"):
        CrossingOperator(first, second, q, 1.0)
    assert math.isclose(operator.p, 0.5)
