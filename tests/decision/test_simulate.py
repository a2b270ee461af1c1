"""Simulation and evaluation against a policy; the Fig. 7 plot."""
from __future__ import annotations

import json

import numpy as np
import pytest
from aplan_runner import run_aplan
from figure_support import pyplot_untouched

from planner import make_plan
from planner.decision import intention_model
from planner.decision.belief_plot import episode_trace, plot_beliefs
from planner.decision.simulate import evaluate_policy, simulate_episode
from planner.decision.solvers import PointBasedSolver

MEASURES = {"robot_operations", "operator_operations", "wrong_robot_actions", "first_help_step", "confident_step",
            "robot_share", "switched_at_step", "operator_mistakes"}  # planner.decision.episode_measures


@pytest.fixture(scope="module")
def decision(pen):
    return intention_model(make_plan(pen, True))


@pytest.fixture(scope="module")
def solved(decision):
    model = decision.pomdp
    # No clock: the same policy on any machine; 150 trials bring its lower bound within the optimum's bracket.
    return model, PointBasedSolver(max_iterations=150, time_limit=None, precision=1e-3).solve(model)


def test_episodes_reach_the_finished_product(solved, decision):
    model, result = solved
    graph = decision.graph
    rng = np.random.default_rng(0)
    for start in graph.full_sequences():
        episode = simulate_episode(model, result.policy, int(start), rng, successor=graph.successor, final=0)
        assert episode.steps[-1].state == 0  # the finished product
        assert episode.steps[-1].operator_operations <= 5  # the pen takes five operations in all
        assert all(abs(b.sum() - 1) < 1e-9 for b in episode.beliefs)
        moves = [s.operator_operations for s in episode.steps]
        assert moves == sorted(moves)


def test_operator_taking_turns_acts_every_step(solved, decision):
    model, result = solved
    graph = decision.graph
    wait = model.actions.index("wait")
    episode = simulate_episode(model, result.policy, int(graph.full_sequences()[0]), np.random.default_rng(0),
                               successor=graph.successor, final=0, operator="turns")
    for before, step in zip([None] + episode.steps, episode.steps):
        if step.action == wait:  # waiting, the operator always does its next operation
            previous = before.operator_operations if before else 0
            assert step.operator_operations == previous + 1


def test_evaluation_brackets_the_bounds(solved):
    model, result = solved
    mean, half, returns = evaluate_policy(model, result.policy, 2000, seed=1, final=0)
    assert len(returns) == 2000 and half > 0
    # The policy's value at b0 is at least its lower bound; the upper bound caps every policy.
    assert result.lower_bound - 3 * half <= mean <= result.upper_bound + 3 * half


def test_plot_files(tmp_path, solved, decision, monkeypatch):
    model, result = solved
    graph = decision.graph
    episodes = [simulate_episode(model, result.policy, int(s), np.random.default_rng(2), successor=graph.successor,
                                 final=0) for s in graph.full_sequences()[:3]]
    with pyplot_untouched(monkeypatch):
        written = plot_beliefs([episode_trace(model, e, f"sequence {e.start}") for e in episodes],
                               str(tmp_path / "fig7"), "pen")
    assert [p.rsplit(".", 1)[1] for p in written] == ["png", "svg"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig7.png", "fig7.svg"]  # no temporary file left
    assert (tmp_path / "fig7.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert b"<svg" in (tmp_path / "fig7.svg").read_bytes()[:400]


def test_cli_simulate_and_evaluate(tmp_path):
    policy = tmp_path / "p.policy"
    run = run_aplan
    assert run("solve", "pen", "--technical", "-o", str(policy), "--time-limit", "3", "--quiet").returncode == 0
    done = run("simulate", "pen", "--technical", "--policy", str(policy), "--all", "--json")
    lines = [json.loads(l) for l in done.stdout.splitlines()]
    assert done.returncode == 0 and len(lines) == 12  # the 12 sequences with the technical constraint
    assert all(set(l) == {"sequence", "operations", "confident_after_operations", "discounted_return"} | MEASURES
               for l in lines)
    done = run("evaluate", "pen", "--technical", "--policy", str(policy), "--episodes", "200", "--json")
    data = json.loads(done.stdout)
    assert set(data) == {"mean_return", "ci95", "episodes"} and data["episodes"] == 200
    bad = run("simulate", "pen", "--technical", "--policy", str(policy), "--sequence", "3")
    assert bad.returncode == 1 and "is not a full assembly sequence" in bad.stderr
