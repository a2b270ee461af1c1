"""Sessions with learned habits (issue 23, "In the workbench and the cell"): habits learned by ``aplan habits``
from session logs of an operator who always assembles one sequence, then a session in the simulated camera
cell (``--demo``) and one from the keyboard, both with ``--habits``: the robot takes over operations of that
sequence, the log records the habits, and ``aplan replay`` reproduces every belief. With the paper's model the
same cell session leaves the robot fewer operations (it cannot know the operator's order)."""
from __future__ import annotations

import json

import pytest

from aplan_runner import run_aplan
from planner.assembly import make_plan
from planner.decision.factored_model import factored_model
from planner.decision.habits import habit_weights, state_graph_fingerprint
from planner.decision.io.habits_file import read_habits
from planner.decision.online import OnlinePlanner
from planner.runtime.log import EventLog
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
from planner.runtime.session import run_session

RANK = 5  # the operator's sequence, numbered by rank on the factored model (--planner online)
EXPANSIONS = 20  # no clock: the same decisions in the test's own run and in the command's


class _Wait:
    def __init__(self, model):
        self.wait = model.wait

    def action(self, belief) -> int:
        return self.wait


def learn_habits(product, folder, rank: int, sessions: int):
    """The factored model of ``product`` and the habits ``aplan habits`` learns from ``sessions`` logged sessions
    (in ``folder``) in which the operator did sequence ``rank`` alone (the robot waits)."""
    model = factored_model(make_plan(product))
    logs = []
    for k in range(sessions):
        operator = ScriptedOperator(model.plan, model.sequence_operations(model.sequence(rank)))
        assert run_session(model, _Wait(model), operator, ScriptedRobot(), EventLog(folder / f"s{k}.jsonl")).assembled
        logs.append(folder / f"s{k}.jsonl")
    habits = folder / "habits.json"
    done = run_aplan("habits", *logs, "-o", habits)
    assert done.returncode == 0, done.stderr
    return model, habits


@pytest.fixture(scope="module")
def learned(pen, tmp_path_factory):
    """Habits of an operator who did sequence RANK in 6 logged sessions alone, learned by ``aplan habits``."""
    return learn_habits(pen, tmp_path_factory.mktemp("habit-sessions"), RANK, 6)


def _events(path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def _robot_operations(events) -> int:
    return sum(e["event"] == "action" and e["name"] != "wait" for e in events)


def _replays(log) -> None:
    replay = run_aplan("replay", log)
    assert replay.returncode == 0 and "beliefs reproduced" in replay.stdout, replay.stdout + replay.stderr


def test_a_cell_session_with_habits_helps_and_replays(learned, tmp_path):
    model, habits = learned
    runs = {}
    for name, extra in (("habits", ["--habits", habits]), ("paper", [])):
        log = tmp_path / f"{name}.jsonl"
        done = run_aplan("session", "pen", "--demo", RANK, "--planner", "online", "--expansions", EXPANSIONS,
                         "--log", log, *extra)
        assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stdout + done.stderr
        _replays(log)
        runs[name] = _events(log)
    settings = runs["habits"][0]["settings"]
    assert settings["habits"]["fingerprint"] == state_graph_fingerprint(model.plan)
    assert runs["paper"][0]["settings"]["habits"] is None
    assert _robot_operations(runs["habits"]) > _robot_operations(runs["paper"])


def test_a_keyboard_session_with_habits_helps_and_replays(learned, pen, tmp_path):
    """The keyboard's lines are what the operator picked in the same session run here (the same model and
    planner, no clock): the command's robot does the same operations, and the log replays."""
    model, habits = learned
    weighted = factored_model(model.plan, weights=habit_weights(model.plan, read_habits(habits)))
    operator = ScriptedOperator(model.plan, model.sequence_operations(model.sequence(RANK)))
    here = run_session(weighted, OnlinePlanner(weighted, expansions=EXPANSIONS), operator,
                       ScriptedRobot(on_perform=operator.robot_acting), EventLog(tmp_path / "here.jsonl"))
    assert here.assembled
    expected = _robot_operations(_events(tmp_path / "here.jsonl"))
    assert expected >= 1  # the habits let the robot help
    picks = []  # one line per step: the parts and tool seen, an empty line for nothing (the robot finished)
    for event in _events(tmp_path / "here.jsonl"):
        if event["event"] == "observation":
            seen = model.plan.observations[event["index"]]
            picks.append(" ".join(seen.parts + ((seen.tool,) if seen.tool else ())))
    log = tmp_path / "keyboard.jsonl"
    done = run_aplan("session", "pen", "--keyboard", "--robot", "auto", "--habits", habits, "--planner", "online",
                     "--expansions", EXPANSIONS, "--log", log, stdin="\n".join(picks) + "\n")
    assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stdout + done.stderr
    events = _events(log)
    assert events[0]["settings"]["habits"]["fingerprint"] == state_graph_fingerprint(model.plan)
    assert _robot_operations(events) == expected
    _replays(log)
