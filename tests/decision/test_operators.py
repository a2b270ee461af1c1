"""Simulated operators (issue 23 item 4): the uniform operator plays today's episodes draw for draw, a habitual
operator of strength 1 always does its sequence, a changing one with p = 0 is its base operator, a switch keeps
the operations done and takes another completion, and the per-episode measures add up (robot + operator
operations = the sequence's length; wrong actions = the steps the reward table scores as wrong)."""
from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from aplan_runner import run_aplan

from planner import api, make_plan
from planner.decision import factored_model, intention_model
from planner.decision.episode_measures import episode_measures, run_totals
from planner.decision.habits import habit_weights_from
from planner.decision.intention_model import Rewards
from planner.decision.online import OnlinePlanner
from planner.decision.operators import (ChangingOperator, HabitualOperator, UniformOperator, parse_operator,
                                        switch_path, switch_points)
from planner.decision.episodes import EpisodeChoice
from planner.decision.simulate import IntentionWorld, simulate_episode
from planner.decision.solvers import PointBasedSolver
from planner.errors import PlannerError

PEN_OPERATIONS = 5  # the pen's six parts take five operations in every full sequence


@pytest.fixture(scope="module")
def plan(pen):
    return make_plan(pen, True)


@pytest.fixture(scope="module")
def flat(plan):
    model = intention_model(plan)
    # Bounded by trials, not the clock: the same policy on any machine.
    policy = PointBasedSolver(max_iterations=40, time_limit=None, precision=1e-3).solve(model.pomdp).policy
    return model, policy


@pytest.fixture(scope="module")
def factored(plan):
    model = factored_model(plan)
    return model, OnlinePlanner(model, expansions=40)


class RandomActions:
    """A policy that acts at random (seeded): it makes wrong actions, to count them."""

    def __init__(self, n_actions: int, seed: int):
        self.n, self.rng = n_actions, np.random.default_rng(seed)

    def action(self, belief) -> int:
        return int(self.rng.integers(self.n))


class Waiting:
    def __init__(self, wait: int):
        self.wait = wait

    def action(self, belief) -> int:
        return self.wait


def _trace(episodes) -> list:
    return [[(s.action, s.observation, s.operator_operations, s.reward) for s in e.steps] for e in episodes]


def test_uniform_operator_plays_todays_flat_episodes(flat):
    model, policy = flat
    for seed in (0, 7):
        rng = np.random.default_rng(seed)  # today's recipe: the starts drawn at once, then the episodes
        starts = rng.choice(model.full_sequences(), size=6)
        today = [simulate_episode(IntentionWorld(model.pomdp, s, model.graph.successor, model.final_state), policy, rng)
                 for s in starts]
        played = api.simulate(model, policy, EpisodeChoice(random=6, seed=seed, operator_model=UniformOperator()))
        assert [e.start for e in played] == [int(s) for s in starts]
        assert _trace(played) == _trace(today) == \
            _trace(api.simulate(model, policy, EpisodeChoice(random=6, seed=seed)))


def test_uniform_operator_plays_todays_factored_episodes(factored):
    model, planner = factored
    today = api.simulate(model, planner, EpisodeChoice(random=4, seed=3))  # no operator model: today's code
    played = api.simulate(model, planner, EpisodeChoice(random=4, seed=3, operator_model=UniformOperator()))
    assert [e.path for e in played] == [e.path for e in today]
    assert _trace(played) == _trace(today)


def test_uniform_operator_ignores_the_robots_habits(plan):
    """Whatever the robot's model assumes, the uniform operator draws the same sequences (the same calls)."""
    weights = habit_weights_from(plan, np.random.default_rng(1).integers(0, 20, plan.states.n_edges).astype(float))
    paper, habits = factored_model(plan), factored_model(plan, weights=weights)
    draw = [UniformOperator().plans(m, 50, np.random.default_rng(5), np.random.default_rng(6)) for m in (paper, habits)]
    assert [p.sequence for p in draw[0]] == [p.sequence for p in draw[1]]


@pytest.mark.parametrize("kind", ["flat", "factored"])
def test_habitual_operator_of_strength_one_always_does_its_sequence(kind, flat, factored):
    model, policy = flat if kind == "flat" else factored
    habit = int(model.full_sequences()[3]) if kind == "flat" else 3
    played = api.simulate(model, policy, EpisodeChoice(random=5, seed=2, operator_model=HabitualOperator(habit, 1.0)))
    if kind == "flat":
        assert [e.start for e in played] == [habit] * 5
        assert all(e.steps[-1].state == model.final_state for e in played)
    else:
        assert all(e.path == model.sequence(3) and e.finished for e in played)


def test_habitual_operator_follows_with_the_closed_form_frequency(factored):
    """P(the habit's sequence) = strength + (1 - strength) / sequences; 4000 draws, within 4 standard errors."""
    model, _ = factored
    strength, draws = 0.6, 4000
    plans = HabitualOperator(7, strength).plans(model, draws, np.random.default_rng(0), np.random.default_rng(1))
    p = strength + (1 - strength) / model.n_sequences
    seen = np.mean([plan.sequence == model.sequence(7) for plan in plans])
    assert abs(seen - p) <= 4 * np.sqrt(p * (1 - p) / draws)


@pytest.mark.parametrize("kind", ["flat", "factored"])
def test_changing_operator_with_p_zero_is_its_base(kind, flat, factored):
    model, policy = flat if kind == "flat" else factored
    habit = int(model.full_sequences()[0]) if kind == "flat" else 0
    base = api.simulate(model, policy, EpisodeChoice(random=5, seed=4, operator_model=HabitualOperator(habit, 0.5)))
    changing = api.simulate(model, policy, EpisodeChoice(
        random=5, seed=4, operator_model=ChangingOperator(0.0, HabitualOperator(habit, 0.5))))
    assert _trace(changing) == _trace(base) and all(e.switched_at is None for e in changing)


def test_a_switch_keeps_the_operations_done_and_takes_another_completion(factored):
    model, planner = factored
    operator = ChangingOperator(0.99)
    played = api.simulate(model, planner, EpisodeChoice(random=6, seed=1, operator_model=operator))
    plans = operator.plans(model, 6, np.random.default_rng(1), np.random.default_rng([1, 1]))  # as simulate draws
    # A switch happens where the state has another completion: at ``after`` operations, or at a later state.
    assert 1 <= sum(e.switched_at is not None for e in played) <= sum(p.switch is not None for p in plans)
    for episode, plan in zip(played, plans):
        if episode.switched_at is None:
            assert episode.path == plan.sequence
            continue
        done = episode.steps[episode.switched_at - 2].position if episode.switched_at > 1 else 0
        assert done >= plan.switch.after >= 1 and episode.path[:done] == plan.sequence[:done]
        assert int(model.paths[model.class_source[plan.sequence[done]]]) > 1 and episode.path != plan.sequence
        state = model.plan.states.initial
        for c in episode.path:  # still a full sequence: each edge starts where the previous one ended
            assert model.class_source[c] == state
            state = model.class_target[c]
        assert state == model.final_state
    # The completion by rank skips its own: every draw gives another one, sharing the prefix; none when alone.
    path = model.sequence(0)
    for position in range(1, len(path)):
        alone = int(model.paths[model.class_source[path[position]]]) == 1
        for draw in (0.0, 0.5, 0.999):
            other = switch_path(model, path, position, draw)
            assert other[:position] == path[:position] and (other == path) == alone


def test_a_changing_operator_switches_in_a_share_p_of_the_episodes(flat, factored):
    """p is the share of episodes with a switch (issue 23: "switches sequence once per episode with probability
    0.3") whose sequence has a switch point (11 of the technical pen's 12: so p 11 / 12 of all episodes); the
    switch comes at one of them, and the flat and factored models find the same points for the same sequence
    (matched by their operations)."""
    (flat_model, _), (model, _) = flat, factored
    points = {}
    for start in flat_model.full_sequences():
        ops = tuple(flat_model.graph.operations(int(start)))
        points[ops] = switch_points(flat_model, int(start))
    for rank in range(model.n_sequences):
        path = model.sequence(rank)
        mine = switch_points(model, path)
        assert mine == points[tuple(model.sequence_operations(path))]
        assert mine == [q for q in range(1, len(path)) if switch_path(model, path, q, 0.5) != path]
    assert (model.n_sequences, sum(not v for v in points.values())) == (12, 1)
    draws, p = 4000, 0.3 * 11 / 12
    plans = ChangingOperator(0.3).plans(model, draws, np.random.default_rng(5), np.random.default_rng([5, 1]))
    switched = [plan for plan in plans if plan.switch is not None]
    assert abs(len(switched) / draws - p) <= 4 * np.sqrt(p * (1 - p) / draws)
    assert all(plan.switch.after in switch_points(model, plan.sequence) for plan in switched)


@pytest.mark.parametrize("kind", ["flat", "factored"])
def test_measures_add_up(kind, flat, factored):
    model, _ = flat if kind == "flat" else factored
    policy = RandomActions(len(model.actions), 11)
    played = api.simulate(model, policy,
                          EpisodeChoice(random=8, seed=5, max_steps=400, operator_model=ChangingOperator(0.5)))
    wrong_reward = Rewards().wrong
    measures = [episode_measures(e) for e in played]
    for episode, m in zip(played, measures):
        assert m["robot_operations"] + m["operator_operations"] == PEN_OPERATIONS
        assert m["wrong_robot_actions"] == sum(s.reward == wrong_reward for s in episode.steps)
        helped = [k for k, s in enumerate(episode.steps, 1) if s.reward in (Rewards().favorable, Rewards().unfavorable)]
        assert m["first_help_step"] == (helped[0] if helped else None) and len(helped) == m["robot_operations"]
    assert sum(m["wrong_robot_actions"] for m in measures) > 0  # the random policy does err
    assert all(m["robot_capable_operations"] == PEN_OPERATIONS for m in measures)  # the robot can do each
    totals = run_totals(measures)
    robot = sum(m["robot_operations"] for m in measures)
    assert totals["robot_share"] == pytest.approx(robot / (PEN_OPERATIONS * 8), abs=1e-6)
    assert totals["wrong_share"] == pytest.approx(totals["wrong_robot_actions"] / (robot + totals["wrong_robot_actions"]),
                                                  abs=1e-6)
    assert totals["robot_capable_operations"] == PEN_OPERATIONS * 8
    assert totals["robot_capable_share"] == totals["robot_share"]


@pytest.mark.parametrize("kind", ["flat", "factored"])
def test_robot_capable_operations_follow_the_tags(kind, plan):
    """With the operations that bring the ink in tagged not robot-capable, an episode's robot-capable operations are
    the tagged ones of the sequence it did (after a switch too), counted from the plan's tags."""
    robot = plan.tags.robot.copy()
    for j in range(len(plan.andor.operations)):
        if frozenset({"ink"}) in plan.andor.inputs(j):
            robot[j] = False
    assert 0 < robot.sum() < robot.size
    tagged = replace(plan, tags=replace(plan.tags, robot=robot))
    model = intention_model(tagged) if kind == "flat" else factored_model(tagged)
    played = api.simulate(model, RandomActions(len(model.actions), 3),
                          EpisodeChoice(random=12, seed=2, max_steps=400, operator_model=ChangingOperator(0.5)))
    seen = set()
    for episode in played:
        m = episode_measures(episode)
        capable = sum(bool(robot[o]) for o in _operations_done(model, episode))
        assert m["robot_capable_operations"] == capable == PEN_OPERATIONS - 1  # the ink comes in once per sequence
        assert m["robot_operations"] <= capable
        assert m["robot_capable_share"] == pytest.approx(m["robot_operations"] / capable, abs=1e-6)
        seen.add(m["robot_operations"])
    assert len(seen) > 1  # the random robot does some of them, not always as many


def _operations_done(model, episode) -> list[int]:
    """The AND/OR operations of the sequence an episode did (after a switch, the one it switched to)."""
    if episode.path is not None:  # an episode over classes
        return model.sequence_operations(episode.path)
    ops = model.sequence_operations(episode.start)
    if episode.switched_to is None:
        return ops
    after = model.sequence_operations(episode.switched_to)
    return ops[:len(ops) - len(after)] + after


@pytest.mark.parametrize("kind", ["flat", "factored"])
def test_mistakes_change_only_the_observations(kind, flat, factored):
    """q = 0 plays the base's episodes; with q > 0 the mistaken steps see another non-blank observation, the
    assembly goes on by the same draws until the robot acts otherwise, and the operations still add up."""
    model, policy = flat if kind == "flat" else factored
    base = api.simulate(model, policy, EpisodeChoice(random=4, seed=9, operator_model=parse_operator("uniform")))
    assert _trace(api.simulate(model, policy,
                               EpisodeChoice(random=4, seed=9, operator_model=parse_operator("mistakes:0")))) == \
        _trace(base)
    waiting = Waiting(model.actions.index("wait"))  # the robot never acts: the world's draws stay aligned
    calm = api.simulate(model, waiting, EpisodeChoice(random=4, seed=9, operator_model=parse_operator("uniform")))
    mistaken = api.simulate(model, waiting,
                            EpisodeChoice(random=4, seed=9, operator_model=parse_operator("mistakes:0.3")))
    made = 0
    for a, b in zip(calm, mistaken):
        assert [s.operator_operations for s in a.steps] == [s.operator_operations for s in b.steps]
        for s, t in zip(a.steps, b.steps):
            assert (s.observation == t.observation) != t.mistake and (not t.mistake or t.observation != 0)
        made += episode_measures(b)["operator_mistakes"]
        assert episode_measures(b)["operator_operations"] == PEN_OPERATIONS
    assert made > 0


def test_parse_operator_spellings():
    assert repr(parse_operator("uniform")) == "uniform"
    assert repr(parse_operator("habitual:4:0.8")) == "habitual:4:0.8"
    assert repr(parse_operator("habitual:4:0.8,changing:0.1")) == "habitual:4:0.8,changing:0.1"
    assert repr(parse_operator("changing:0")) == "uniform,changing:0"
    assert repr(parse_operator("habitual:4:0.8,changing:0.1,mistakes:0.05")) == "habitual:4:0.8,changing:0.1,mistakes:0.05"
    assert parse_operator("mistakes:0.2").mistakes == 0.2
    for bad in ("habitual:4:1.5", "habitual:4:nan", "habitual:-1:0.5", "habitual:1.5:0.5", "changing:1",
                "changing:-0.1", "uniform:3", "sometimes", "habitual:4", "uniform,uniform", "changing:0.1,changing:0.2",
                "mistakes:1", "mistakes:0.1,changing:0.1", "changing:0.1,uniform"):
        with pytest.raises(PlannerError):
            parse_operator(bad)


def test_cli_operator_sequence(tmp_path):
    bad = run_aplan("simulate", "pen", "--random", "2", "--operator-sequence", "changing:1")
    assert bad.returncode == 2 and "P of changing:P must be in [0, 1)" in bad.stderr
    fixed = run_aplan("simulate", "pen", "--sequence", "0", "--operator-sequence", "uniform", "--planner", "online",
                      "--expansions", "5")
    assert fixed.returncode == 1 and "give --random N" in fixed.stderr and "Traceback" not in fixed.stderr
    model_file = run_aplan("evaluate", str(tmp_path / "m.pomdp"), "--operator-sequence", "uniform")
    assert model_file.returncode == 1 and "needs a PRODUCT" in model_file.stderr  # refused before reading it
    out = run_aplan("simulate", "pen", "--random", "3", "--seed", "4", "--json", "--planner", "online",
                    "--expansions", "5", "--operator-sequence", "habitual:2:1")
    assert out.returncode == 0, out.stderr
    lines = [json.loads(line) for line in out.stdout.splitlines()]
    episodes = [line for line in lines if "totals" not in line and "run" not in line]
    totals = next(line["totals"] for line in lines if "totals" in line)
    assert len(episodes) == 3 and totals["episodes"] == 3 and totals["operator"] == "habitual:2:1"
    assert len({tuple(e["operations"]) for e in episodes}) == 1  # strength 1: one sequence
    assert totals["robot_operations"] == sum(e["robot_operations"] for e in episodes)
    assert all(e["robot_operations"] + e["operator_operations"] == PEN_OPERATIONS for e in episodes)
    evaluated = run_aplan("evaluate", "pen", "--episodes", "3", "--seed", "4", "--json", "--planner", "online",
                          "--expansions", "5", "--operator-sequence", "habitual:2:1")
    assert evaluated.returncode == 0, evaluated.stderr
    summary = json.loads(evaluated.stdout)  # the same episodes as simulate --random 3
    assert summary["robot_operations"] == totals["robot_operations"]
    assert summary["mean_return"] == pytest.approx(np.mean([e["discounted_return"] for e in episodes]), abs=1e-5)


def test_a_habit_that_is_no_sequence_is_refused(flat, factored):
    with pytest.raises(PlannerError, match="numbered by rank, from 0 to 11"):  # the technical pen: 12 sequences
        HabitualOperator(12, 0.5).plans(factored[0], 3, np.random.default_rng(0), np.random.default_rng(1))
    with pytest.raises(PlannerError, match="is not a full assembly sequence"):
        HabitualOperator(int(flat[0].final_state), 0.5).plans(flat[0], 3, np.random.default_rng(0),
                                                               np.random.default_rng(1))
