"""A step undone and one the product cannot recover from (issue 23 item 3, planner/runtime/undo.py): sessions
with a scripted source on the flat and factored models (the belief goes back to the prior of the earlier
state, closed form), the unrecoverable report, the log and its replay, and the keyboard's ``apart``."""
from __future__ import annotations

import json

import numpy as np
import pytest
from aplan_runner import run_aplan
from listed_source import ListedSource

from planner import BLANK, make_plan
from planner.decision import factored_model, intention_model
from planner.decision.deviations import Deviations
from planner.runtime.log import EventLog, replay
from planner.runtime.scripted import ScriptedRobot
from planner.runtime.session import run_session
from planner.runtime.undo import Apart, apart_state


class Waiting:
    """A policy that always waits: the operator does every step (the test decides each observation)."""

    def __init__(self, model):
        self.wait = len(model.actions) - 1

    def action(self, belief):
        return self.wait


def _first_step(plan):
    """The operator's first operation of sequence 0 and its observation, and the pieces it joined."""
    states = plan.states
    edge = int(np.flatnonzero(states.edge_source == states.initial)[0])
    operation = int(states.edge_operation[edge])
    first, second = plan.andor.inputs(operation)
    return plan.observations[int(plan.operation_observation[operation])], sorted(first), int(states.edge_target[edge])


@pytest.mark.parametrize("kind", ["flat", "factored", "factored-deviations"])
def test_a_step_undone_goes_back_to_the_prior_of_the_earlier_state(pen, tmp_path, kind):
    plan = make_plan(pen)
    model = intention_model(plan) if kind == "flat" else factored_model(
        plan, deviations=Deviations(0.1, 0.05) if kind == "factored-deviations" else None)
    seen, piece, _ = _first_step(plan)
    path = tmp_path / "undo.jsonl"
    log = EventLog(path)
    result = run_session(model, Waiting(model), ListedSource([seen, Apart(tuple(piece)), BLANK]), ScriptedRobot(), log)
    log.close()
    assert result.reason == "source ended" and result.operations == 0
    apart = [e for e in log.events if e["event"] == "apart"]
    assert len(apart) == 1 and apart[0]["moves"] == [[int(next(iter(_moves_from(plan, seen)))), plan.states.initial]]
    after = result.beliefs[2]
    initial = model.pomdp.initial if kind == "flat" else model.initial_belief().dense(model.n_classes)
    got = after if kind == "flat" else after.dense(model.n_classes)
    assert np.abs(got - initial).max() <= 1e-12  # back at the start: the prior over the full sequences
    done = replay(path)
    assert done.mismatches == [] and done.undone == {2: "apart " + " ".join(piece)}
    assert len(done.beliefs) == len(result.beliefs)


def _moves_from(plan, seen):
    z = plan.observations.index(seen)
    states = plan.states
    return {int(states.edge_target[e]) for e in np.flatnonzero(states.edge_source == states.initial)
            if plan.operation_observation[states.edge_operation[e]] == z}


def _unrecoverable(plan):
    """The least assembled state (not the finished product) with a part whose coming off leaves a partition
    outside the state graph, and that part."""
    states = plan.states
    for s in range(states.n_states - 1, states.final, -1):
        for block in states.subassemblies_of(s):
            for p in sorted(plan.andor.parts_of(block)):
                if apart_state(plan, s, (p,))[0] is None:
                    return s, (p,)
    return None


def test_a_step_the_product_cannot_recover_from_stops_and_replays(pen, tmp_path):
    plan = make_plan(pen)
    model = factored_model(plan)
    found = _unrecoverable(plan)
    assert found is not None
    state, parts = found
    # Reach ``state`` by the operator's observations along the first path there, then the piece comes off.
    path_ops = _path_to(plan, state)
    seen = [plan.observations[int(plan.operation_observation[o])] for o in path_ops]
    path = tmp_path / "lost.jsonl"
    log = EventLog(path)
    result = run_session(model, Waiting(model), ListedSource(seen + [Apart(parts), BLANK]), ScriptedRobot(), log)
    log.close()
    assert result.reason == "unrecoverable" and "\n" not in result.message
    assert "cannot be finished from here by any plan" in result.message and f"apart {parts[0]}" in result.message
    events = [json.loads(line) for line in path.read_text().splitlines()]
    lost = [e for e in events if e["event"] == "unrecoverable"]
    assert len(lost) == 1 and lost[0]["message"] == result.message and events[-1]["reason"] == "unrecoverable"
    done = replay(path)
    assert done.unrecoverable == result.message and done.end["reason"] == "unrecoverable" and not done.mismatches
    shown = run_aplan("replay", path)
    assert shown.returncode == 0 and f"unrecoverable: {result.message}" in shown.stdout


def test_the_person_is_told_when_the_product_cannot_be_finished(pen, tmp_path):
    """From the keyboard (the person's own session): the step that leaves no plan is told on one line, the
    session exits with status 1 and logs it, and ``aplan replay`` shows the same line after the same beliefs."""
    plan = make_plan(pen)
    state, parts = _unrecoverable(plan)
    picks = []
    for operation in _path_to(plan, state):
        seen = plan.observations[int(plan.operation_observation[operation])]
        picks.append(" ".join(seen.parts + ((seen.tool,) if seen.tool else ())))
    log = tmp_path / "told.jsonl"
    done = run_aplan("session", "pen", "--keyboard", "--robot", "auto", "--planner", "online", "--expansions", "20",
                     "--log", log, stdin="\n".join(picks + ["apart " + " ".join(parts), ""]) + "\n")
    told = [line for line in done.stdout.splitlines() if line.startswith("unrecoverable: ")]
    assert done.returncode == 1 and len(told) == 1, done.stdout + done.stderr
    assert f"step {len(picks) + 1}: apart {' '.join(parts)}" in told[0] and "start a new session" in told[0]
    events = [json.loads(line) for line in log.read_text().splitlines()]
    assert [e["message"] for e in events if e["event"] == "unrecoverable"] == [told[0].removeprefix("unrecoverable: ")]
    shown = run_aplan("replay", log)
    assert shown.returncode == 0 and told[0] in shown.stdout and f"reproduced at all {len(picks)} steps" in shown.stdout


def _path_to(plan, target):
    """The operations of a path from the initial state to ``target`` (breadth first over the state edges)."""
    states = plan.states
    previous = {states.initial: None}
    todo = [states.initial]
    while todo:
        s = todo.pop(0)
        if s == target:
            break
        for e in np.flatnonzero(states.edge_source == s):
            t = int(states.edge_target[e])
            if t not in previous:
                previous[t] = (s, int(states.edge_operation[e]))
                todo.append(t)
    ops, s = [], target
    while previous[s] is not None:
        s, op = previous[s]
        ops.append(op)
    return ops[::-1]


def test_an_apart_that_does_not_apply_counts_as_blank(pen):
    plan = make_plan(pen)
    model = intention_model(plan)
    log = EventLog()
    result = run_session(model, Waiting(model), ListedSource([Apart(("ink",)), BLANK]), ScriptedRobot(), log)
    warnings = [e["message"] for e in log.events if e["event"] == "warning"]
    assert len(warnings) == 1 and warnings[0].startswith("apart ink ignored: they are a whole subassembly")
    assert result.observations == [0, 0] and not [e for e in log.events if e["event"] == "apart"]


def test_keyboard_apart_session_and_replay(pen, tmp_path):
    """``apart PART...`` typed in, with the change-of-mind model on the online planner: the log records the
    model's deviations, and aplan replay reproduces every belief."""
    plan = make_plan(pen)
    seen, piece, _ = _first_step(plan)
    typed = " ".join(seen.parts + ((seen.tool,) if seen.tool else ()))
    log = tmp_path / "k.jsonl"
    lines = [typed, "apart " + " ".join(piece), typed, "q"]
    done = run_aplan("session", "pen", "--keyboard", "--robot", "auto", "--planner", "online", "--expansions", "30",
                     "--switch", "0.1", "--mistakes", "0.05", "--log", log, stdin="\n".join(lines) + "\n")
    assert done.returncode == 1 and "source ended" in done.stdout, done.stderr
    start = json.loads(log.read_text().splitlines()[0])
    assert start["settings"]["deviations"] == {"switch": 0.1, "mistake": 0.05}
    assert any(json.loads(line)["event"] == "apart" for line in log.read_text().splitlines())
    shown = run_aplan("replay", log, "--json")
    assert shown.returncode == 0, shown.stderr
    assert any(json.loads(line).get("undone") == "apart " + " ".join(piece) for line in shown.stdout.splitlines())


@pytest.mark.parametrize("option", ["--switch", "--mistakes"])
@pytest.mark.parametrize("value", ["1", "-0.1", "nan", "2"])
def test_a_probability_outside_zero_one_is_a_usage_error(option, value):
    done = run_aplan("simulate", "pen", "--random", "1", option, value)
    assert done.returncode == 2 and f"argument {option}" in done.stderr and "below 1" in done.stderr


@pytest.mark.parametrize("command", [("pomdp", "pen", "-o"), ("session", "pen", "--demo", "0", "--log")])
def test_a_probability_outside_zero_one_writes_nothing(command, tmp_path):
    out = tmp_path / "out"
    done = run_aplan(*command, out, "--switch", "0.5", "--mistakes", "1")
    assert done.returncode == 2 and "argument --mistakes" in done.stderr and not out.exists()


@pytest.mark.parametrize("recorded", [{"switch": 1.5, "mistake": 0.0}, {"switch": "0.1", "mistake": 0.0},
                                      {"switch": 0.1}, [0.1, 0.0]])
def test_a_log_with_damaged_deviations_is_refused(pen, tmp_path, recorded):
    from planner.runtime.log import SessionError

    plan = make_plan(pen)
    model = factored_model(plan, deviations=Deviations(0.1, 0.0))
    path = tmp_path / "d.jsonl"
    log = EventLog(path)
    run_session(model, Waiting(model), ListedSource([BLANK]), ScriptedRobot(), log)
    log.close()
    events = [json.loads(line) for line in path.read_text().splitlines()]
    assert events[0]["settings"]["deviations"] == {"switch": 0.1, "mistake": 0.0}
    assert replay(path).mismatches == []
    events[0]["settings"]["deviations"] = recorded
    path.write_text("".join(json.dumps(e) + "\n" for e in events))
    with pytest.raises(SessionError, match=r"d\.jsonl: the start event's deviations.*the log is damaged"):
        replay(path)
