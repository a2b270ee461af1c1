"""The camera world (``--world camera``, planner/decision/camera_world.py): its camera reports the operation the
operator did (blank with probability 1/5, blank when it did nothing, the operator's when both act), in the flat
and the factored worlds alike; every observation it emits is in the support of the model's filter at the true
state (so no reset without mistakes); the default world is untouched."""
from __future__ import annotations

import numpy as np
import pytest
from aplan_runner import run_aplan

from planner import api, complete_product, make_plan
from planner.decision import factored_model, intention_model
from planner.decision.camera_world import CAMERA_BLANK, camera_observation
from planner.decision.episodes import EpisodeChoice, world_of
from planner.decision.factored_simulate import PathWorld
from planner.decision.operators import parse_operator
from planner.decision.simulate import IntentionWorld, simulate_episode
from planner.errors import PlannerError, UsageError


class Script:
    """A robot that does the listed actions, then waits."""

    def __init__(self, actions, wait: int):
        self.actions, self.wait = list(actions), wait

    def action(self, belief) -> int:
        return self.actions.pop(0) if self.actions else self.wait


class RandomActions:
    """A robot that acts at random (seeded): right and wrong actions, robot and operator steps together."""

    def __init__(self, n_actions: int, seed: int):
        self.n, self.rng = n_actions, np.random.default_rng(seed)

    def action(self, belief) -> int:
        return int(self.rng.integers(self.n))


@pytest.fixture(scope="module")
def plan(pen):
    return make_plan(pen, True)


@pytest.fixture(scope="module")
def models(plan):
    return intention_model(plan), factored_model(plan)


def _flat_start(flat, factored, path) -> int:
    """The flat model's full sequence doing ``path``'s operations (the factored sequence)."""
    ops = factored.sequence_operations(path)
    return next(int(s) for s in flat.full_sequences() if flat.sequence_operations(int(s)) == ops)


def _expected(plan, operations, draws) -> list[int]:
    """The closed form: operation k's observation when draw k is at least 1/5, else blank."""
    return [0 if u < CAMERA_BLANK else int(plan.operation_observation[op]) for op, u in zip(operations, draws)]


def test_the_blank_share_is_the_models_for_a_state_with_one_operation_into_it(plan):
    """1/5 = (1/4) / (1 + 1/4): the paper's row of a state with one in-edge observation, blank at a quarter."""
    model = factored_model(plan)
    rows = [model.state_observations(s) for s in range(plan.states.n_states)]
    lone = [p for z, p in rows if z.size == 2]
    assert lone and all(p[0] == pytest.approx(CAMERA_BLANK, abs=1e-15) for p in lone)
    assert CAMERA_BLANK == pytest.approx(0.2, abs=1e-15)
    rng = np.random.default_rng(0)
    assert camera_observation(None, rng) == 0  # nothing done: blank, one draw spent all the same
    assert rng.random() == np.random.default_rng(0).random(2)[1]


@pytest.mark.parametrize("rank", [0, 5, 11])
def test_each_step_reports_the_operation_done_in_closed_form(plan, models, rank):
    """An operator taking turns (one operation per step) and a waiting robot: the camera world's observations
    are the sequence's operations' observations, each blank where the step's one draw fell below 1/5; the flat
    and the factored worlds give the same ones on the same stream."""
    flat, factored = models
    path = factored.sequence(rank)
    ops = factored.sequence_operations(path)
    draws = np.random.default_rng(rank).random(len(ops))
    expected = _expected(plan, ops, draws)
    if rank == 0:  # this seed's draws show both cases
        assert 0 < sum(z == 0 for z in expected) < len(expected)
    played = simulate_episode(PathWorld(factored, path, camera=True), Script([], factored.wait),
                              np.random.default_rng(rank), operator="turns")
    start = _flat_start(flat, factored, path)
    flat_world = world_of(flat, start, "camera")
    assert isinstance(flat_world, IntentionWorld)
    flat_played = simulate_episode(flat_world, Script([], len(flat.actions) - 1), np.random.default_rng(rank),
                                   operator="turns")
    assert [s.observation for s in played.steps] == expected == [s.observation for s in flat_played.steps]
    assert [s.operator_operations for s in played.steps] == list(range(1, len(ops) + 1))


def test_the_robots_and_the_operators_operation_in_one_step_shows_the_operators(plan, models):
    """The robot does the sequence's first operation, the operator (taking turns) its second in the same step:
    the camera reports the second (the robot's own is not the camera's to see), then one per step."""
    flat, factored = models
    path = factored.sequence(3)
    ops = factored.sequence_operations(path)
    first = int(factored.class_action[path[0]])
    assert first >= 0
    draws = np.random.default_rng(1).random(len(ops) - 1)
    played = simulate_episode(PathWorld(factored, path, camera=True), Script([first], factored.wait),
                              np.random.default_rng(1), operator="turns")
    assert played.steps[0].robot_operation and played.steps[0].operator_operations == 1
    assert [s.observation for s in played.steps] == _expected(plan, ops[1:], draws)
    start = _flat_start(flat, factored, path)
    flat_action = list(flat.action_operations).index(ops[0])
    flat_played = simulate_episode(world_of(flat, start, "camera"), Script([flat_action], len(flat.actions) - 1),
                                   np.random.default_rng(1), operator="turns")
    assert [s.observation for s in flat_played.steps] == _expected(plan, ops[1:], draws)


@pytest.mark.parametrize("kind", ["flat", "factored"])
def test_a_step_without_an_operator_operation_is_blank(kind, models):
    """The operator's timing drawn from the model (1/2 per step): every step in which it did nothing is blank,
    and every other observation is the one of the operation it did (robots acting at random among them)."""
    flat, factored = models
    model = flat if kind == "flat" else factored
    choice = EpisodeChoice(random=12, seed=4, max_steps=200, operator_model=parse_operator("uniform,changing:0.5"),
                           world="camera")
    played = api.simulate(model, RandomActions(len(model.actions), 2), choice)
    idle = acted = 0
    for episode in played:
        done = [0] + [s.operator_operations for s in episode.steps]
        for k, step in enumerate(episode.steps):
            if done[k + 1] == done[k]:
                idle += 1
                assert step.observation == 0
            else:
                acted += 1
    assert idle > 20 and acted > 20


def _true_state(model, path, step) -> int:
    """The factored world's true assembly state after ``step`` (``path``: the sequence done; a switch keeps the
    prefix done, so the state at every earlier position is read from it too)."""
    return int(model.class_source[path[step.position]]) if step.position < len(path) else model.final_state


def _in_support(model, kind: str, path, step) -> bool:
    """Whether ``step``'s observation has positive probability under the model's filter at its true state."""
    if kind == "flat":
        return model.pomdp.observation[step.action][step.state, step.observation] > 0
    return bool(np.isin(step.observation, model.state_observations(_true_state(model, path, step))[0]))


@pytest.mark.parametrize("product", ["pen", "complete:4"])
@pytest.mark.parametrize("kind", ["flat", "factored"])
def test_every_camera_observation_is_in_the_filters_support(product, kind, pen):
    """Random robots, switching operators: each observation has positive probability at the world's true state
    (so the filter never resets), while the observation of the operation the operator does *next*, what a world
    that reported the wrong edge would emit, is outside that support at some steps: the check can fail."""
    plan = make_plan(pen, True) if product == "pen" else make_plan(complete_product(4), False)
    model = intention_model(plan) if kind == "flat" else factored_model(plan)
    choice = EpisodeChoice(random=15, seed=8, max_steps=300, operator_model=parse_operator("uniform,changing:0.5"),
                           world="camera")
    played = api.simulate(model, RandomActions(len(model.actions), 5), choice)
    assert sum(e.resets for e in played) == 0 and sum(e.switched_at is not None for e in played) > 0
    outside = 0
    for episode in played:
        for step in episode.steps:
            assert _in_support(model, kind, episode.path, step), (episode.path, step)
            if kind == "factored" and step.position < len(episode.path):
                ahead = int(plan.operation_observation[model.class_operation[episode.path[step.position]]])
                outside += not np.isin(ahead, model.state_observations(_true_state(model, episode.path, step))[0])
    assert kind == "flat" or outside > 0


def test_the_same_seed_plays_the_same_episodes_and_the_default_world_is_todays(models):
    flat, factored = models
    for model in (flat, factored):
        policy = Script([], len(model.actions) - 1)
        trace = [[(s.observation, s.operator_operations) for s in e.steps]
                 for e in api.simulate(model, policy, EpisodeChoice(random=6, seed=2, world="camera"))]
        again = [[(s.observation, s.operator_operations) for s in e.steps]
                 for e in api.simulate(model, policy, EpisodeChoice(random=6, seed=2, world="camera"))]
        today = [[(s.observation, s.operator_operations) for s in e.steps]
                 for e in api.simulate(model, policy, EpisodeChoice(random=6, seed=2))]
        named = [[(s.observation, s.operator_operations) for s in e.steps]
                 for e in api.simulate(model, policy, EpisodeChoice(random=6, seed=2, world="model"))]
        assert trace == again and named == today and trace != today
    mean, half = api.evaluate(flat, Script([], len(flat.actions) - 1), EpisodeChoice(random=5, seed=1, world="camera"))
    assert mean == 0.0 and half == 0.0  # a waiting robot earns nothing, in the flat camera world of evaluate


def test_bad_worlds_are_refused(models, tmp_path):
    with pytest.raises(UsageError, match="unknown world 'cam'"):
        EpisodeChoice(world="cam")
    flat, _ = models
    with pytest.raises(PlannerError, match="--world camera needs a PRODUCT"):
        world_of(flat.pomdp, 1, "camera")
    refused = run_aplan("evaluate", str(tmp_path / "m.pomdp"), "--world", "camera")
    assert refused.returncode == 1 and "--world camera needs a PRODUCT" in refused.stderr
    bad = run_aplan("simulate", "pen", "--random", "2", "--world", "video")
    assert bad.returncode == 2 and "invalid choice: 'video'" in bad.stderr
