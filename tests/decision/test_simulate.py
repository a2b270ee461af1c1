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
from planner.decision.episode import Episode, Step
from planner.decision.episodes import EpisodeChoice, evaluate
from planner.decision.simulate import IntentionWorld, confidence_text, decision_times, simulate_episode
from planner.decision.solvers import PointBasedSolver

MEASURES = {"robot_operations", "operator_operations", "wrong_robot_actions", "first_help_step", "confident_step",
            "robot_share", "robot_capable_operations", "robot_capable_share", "switched_at_step",
            "operator_mistakes", "confident_after_switch", "resets"}  # planner.decision.episode_measures


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
        episode = simulate_episode(IntentionWorld(model, start, graph.successor, final=0), result.policy, rng)
        assert episode.steps[-1].state == 0  # the finished product
        assert episode.steps[-1].operator_operations <= 5  # the pen takes five operations in all
        assert all(abs(b.sum() - 1) < 1e-9 for b in episode.beliefs)
        moves = [s.operator_operations for s in episode.steps]
        assert moves == sorted(moves)


def test_operator_taking_turns_acts_every_step(solved, decision):
    model, result = solved
    graph = decision.graph
    wait = model.actions.index("wait")
    episode = simulate_episode(IntentionWorld(model, graph.full_sequences()[0], graph.successor, final=0),
                               result.policy, np.random.default_rng(0), operator="turns")
    for before, step in zip([None] + episode.steps, episode.steps):
        if step.action == wait:  # waiting, the operator always does its next operation
            previous = before.operator_operations if before else 0
            assert step.operator_operations == previous + 1


def test_evaluation_brackets_the_bounds(solved, decision):
    model, result = solved
    mean, half = evaluate(decision, result.policy, EpisodeChoice(random=2000, seed=1))  # to the finished product
    assert half > 0
    # The policy's value at b0 is at least its lower bound; the upper bound caps every policy.
    assert result.lower_bound - 3 * half <= mean <= result.upper_bound + 3 * half


def test_plot_files(tmp_path, solved, decision, monkeypatch):
    model, result = solved
    graph = decision.graph
    episodes = [simulate_episode(IntentionWorld(model, s, graph.successor, final=0), result.policy,
                                 np.random.default_rng(2)) for s in graph.full_sequences()[:3]]
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
    assert run("solve", "pen", "--technical", "-o", str(policy), "--trials", "20", "--quiet").returncode == 0
    done = run("simulate", "pen", "--technical", "--policy", str(policy), "--all", "--json")
    *lines, run_line = [json.loads(l) for l in done.stdout.splitlines()]
    assert done.returncode == 0 and len(lines) == 12  # the 12 sequences with the technical constraint
    assert all(set(l) == {"sequence", "operations", "confident_after_operations", "discounted_return",
                          "decision_seconds_median", "decision_seconds_p95", "decision_seconds_max"} | MEASURES
               for l in lines)
    confident = [l["confident_after_operations"] for l in lines]
    assert all(c is None or 0 <= c <= 4 for c in confident)  # five operations; the fifth finishes the pen
    assert all(0 <= l["decision_seconds_median"] <= l["decision_seconds_p95"] <= l["decision_seconds_max"]
               for l in lines)
    summary = run_line["run"]
    assert summary["episodes"] == 12 and summary["confident_episodes"] == sum(c is not None for c in confident)
    assert summary["decision_seconds_max"] == max(l["decision_seconds_max"] for l in lines)
    assert summary["decision_seconds_median"] <= summary["decision_seconds_p95"] <= summary["decision_seconds_max"]
    done = run("evaluate", "pen", "--technical", "--policy", str(policy), "--episodes", "200", "--json")
    data = json.loads(done.stdout)
    assert set(data) == {"mean_return", "ci95", "episodes"} and data["episodes"] == 200
    bad = run("simulate", "pen", "--technical", "--policy", str(policy), "--sequence", "3")
    assert bad.returncode == 1 and "is not a full assembly sequence" in bad.stderr


def _flat(p_true: list[float], states: list[int]) -> Episode:
    return Episode([Step(0, 0, p, k + 1, 0.0, state=state) for k, (p, state) in enumerate(zip(p_true, states))],
                   start=9, final=0)


def _factored(p_true: list[float], positions: list[int]) -> Episode:
    return Episode([Step(0, 0, p, k + 1, 0.0, 0.0, position=position)
                    for k, (p, position) in enumerate(zip(p_true, positions))], path=[4, 5, 6])


def test_confident_only_before_the_product_is_finished():
    """Issue 22: the belief on the true intention passing 0.9 at the last operation (the product assembled,
    the belief on it trivially 1) is not being confident; before it, the operator operations done then."""
    assert _flat([0.5, 0.95, 1.0], [3, 2, 0]).first_confident(0.9) == 2
    assert _flat([0.5, 0.6, 1.0], [3, 2, 0]).first_confident(0.9) is None  # only once assembled: never
    assert _flat([0.5, 0.9, 1.0], [3, 2, 0]).first_confident(0.9) is None  # above, not at
    assert _factored([0.5, 0.95, 1.0], [1, 2, 3]).first_confident(0.9) == 2
    assert _factored([0.5, 0.6, 1.0], [1, 2, 3]).first_confident(0.9) is None
    assert not _factored([0.5, 0.6, 1.0], [1, 2, 3]).confident_before_finished(0.9)
    assert confidence_text(None) == "belief on the true intention never above 0.9 before the product was finished"
    assert confidence_text(1).endswith("after 1 operator operation") and confidence_text(3).endswith("operations")


def test_one_episode_type_tells_finished_in_each_models_terms():
    """Issue 24: one Episode for every model; finished and unfinished read ``state`` / ``final`` over
    intentions and ``position`` / ``path`` over classes."""
    flat, factored = _flat([0.5, 1.0], [3, 0]), _factored([0.5, 0.6, 1.0], [1, 2, 3])
    assert type(flat) is type(factored) and type(flat.steps[0]) is type(factored.steps[0])
    assert flat.finished and factored.finished
    assert [flat.unfinished(s) for s in flat.steps] == [True, False]
    assert [factored.unfinished(s) for s in factored.steps] == [True, True, False]
    assert not _flat([0.5, 0.6], [3, 2]).finished and not _factored([0.5], [1]).finished
    assert Episode(start=0, final=0).finished and Episode(path=[]).finished and not Episode(start=3).finished


def test_decision_times_closed_form():
    """1 to 20 ms: median 10.5 ms, 95th percentile 19 + 0.05 ms (rank 0.95 x 19 = 18.05, linear), max 20 ms."""
    times = decision_times(k / 1000 for k in range(1, 21))
    assert times == {"decision_seconds_median": 0.0105, "decision_seconds_p95": 0.01905, "decision_seconds_max": 0.02}
    assert decision_times([]) == dict.fromkeys(times)


def test_the_pen_robot_is_confident_within_the_papers_range():
    """The online planner on the pen (work-bounded: 100 expansions per decision), the operator taking turns as in
    the paper's experiment, every sequence: confident after 2 to 4 operator operations (the paper's three runs:
    2, 2 and 4), or never before the finish (the fifth operation finishes the pen)."""
    from planner import api
    from planner.decision.factored_model import factored_model

    model = factored_model(make_plan(api.resolve_product("pen")))
    episodes = api.simulate(model, api.online_planner(model, None, 100),
                            api.EpisodeChoice(every=True, operator="turns"))
    confident = [e.first_confident(0.9) for e in episodes]
    assert len(episodes) == 24 and all(e.finished for e in episodes)
    assert {c for c in confident if c is not None} <= {2, 3, 4} and 2 in confident and 4 in confident
    for episode, operations in zip(episodes, confident):  # the step it names: the first above 0.9, unfinished
        first = next((s for s in episode.steps if s.p_true > 0.9 and s.position < 5), None)
        assert operations == (None if first is None else first.operator_operations)


def test_cli_simulate_online_reports_decision_times_and_never_none():
    """The factored model's JSON lines carry the decision times too, the run's line sums them up, and the text
    says "never above 0.9 before the product was finished" rather than "after None operator operation(s)"."""
    args = ["simulate", "pen", "--sequence", "0", "1", "--expansions", "50", "--operator", "turns"]
    done = run_aplan(*args, "--json")
    *lines, run_line = [json.loads(line) for line in done.stdout.splitlines()]
    assert done.returncode == 0 and len(lines) == 2 and set(run_line) == {"run"}
    assert all({"decision_seconds_median", "decision_seconds_p95", "decision_seconds_max", "finished"} <= set(line)
               for line in lines)
    text = run_aplan(*args)
    assert text.returncode == 0 and "None" not in text.stdout
    rows = [line for line in text.stdout.splitlines() if line[:6].strip().isdigit()]  # one per step: a decision
    assert run_line["run"]["episodes"] == 2 and run_line["run"]["decisions"] == len(rows) > 0
    said = [line for line in text.stdout.splitlines() if "belief on the true intention" in line]
    assert len(said) == 2 and all("first above 0.9 after" in line or "never above 0.9 before the product was "
                                  "finished" in line for line in said)
    assert "95th percentile" in said[0] and text.stdout.splitlines()[-1].startswith("run: 2 episode(s), ")
