"""The sequence a session log recorded (planner.runtime.logged_sequence): pen sessions with a scripted operator
and a robot that performs one operation, read back from their logs."""
from __future__ import annotations

import json

import pytest

from planner import api
from planner.assembly import make_plan
from planner.assembly.explode import SequenceError, sequence_at
from planner.decision.intention_model import intention_model
from planner.runtime.log import EventLog, SessionError
from planner.runtime.logged_sequence import complete_sequence, explain_steps, logged_sequence
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
from planner.runtime.session import run_session


class _OneRobotOperation:
    """A policy that waits, except at decision ``at`` where it has the robot do the operator's next operation."""

    def __init__(self, model, operator, at: int):
        self.model, self.operator, self.at, self.calls = model, operator, at, 0
        self.wait = len(model.actions) - 1

    def action(self, belief) -> int:
        self.calls += 1
        if self.calls != self.at or not self.operator.remaining:
            return self.wait
        return int(list(self.model.action_operations).index(self.operator.remaining[0]))


@pytest.fixture(scope="module")
def model(pen):
    return intention_model(make_plan(pen))


def _session(model, rank, path, at=2, max_steps=500):
    operations = sequence_at(model.plan, rank)
    operator = ScriptedOperator(model.plan, operations)
    done = []
    robot = ScriptedRobot(on_perform=lambda instruction: done.extend([] if instruction.is_wait
                                                                     else [instruction.operation]))
    original = operator.next_operation

    def next_operation():
        operation = original()
        if operation is not None:
            done.append(operation)
        return operation

    operator.next_operation = next_operation
    result = run_session(model, _OneRobotOperation(model, operator, at), operator, robot, EventLog(path),
                         max_steps=max_steps)
    return operations, done, result


@pytest.mark.parametrize("rank", [0, 11, 23])
def test_a_logged_session_gives_back_its_sequence(model, tmp_path, rank):
    operations, done, result = _session(model, rank, tmp_path / "session.jsonl")
    assert result.assembled and sorted(done) == sorted(operations)
    logged = logged_sequence(tmp_path / "session.jsonl")
    assert list(logged.operations) == done and logged.complete
    assert logged.by.count("robot") == 1 and len(logged.by) == 5
    again, _ = api.sequence_from_log(tmp_path / "session.jsonl", model.plan)
    assert again == done
    assert api.plan_in_3d(model.plan, again).steps[-1].operation == done[-1]


def test_a_session_stopped_early_is_completed(model, tmp_path):
    _, done, result = _session(model, 5, tmp_path / "short.jsonl", max_steps=2)
    assert result.reason == "step limit"
    logged = logged_sequence(tmp_path / "short.jsonl")
    assert list(logged.operations) == done and len(done) == 3 and not logged.complete  # 2 by the operator, 1 robot
    full, _ = api.sequence_from_log(tmp_path / "short.jsonl")
    assert full[:3] == done and full == complete_sequence(model.plan, done) and len(full) == 5


def test_ambiguous_observations_are_resolved_by_what_follows(model):
    plan = model.plan
    seen = plan.operation_observation
    # Two operations the operator can be seen doing alike from the same state: the later steps decide.
    for rank in range(24):
        operations = sequence_at(plan, rank)
        steps = [("operator", int(seen[o])) for o in operations]
        found, ambiguous = explain_steps(plan, steps)
        assert [o for o, _ in found] == operations and not ambiguous  # the pen: every observation names one
    with pytest.raises(SequenceError, match="no assembly sequence of the product explains"):
        explain_steps(plan, [("robot", operations[-1])])


def test_blank_observations_may_hide_an_operation(pen):
    """Without a tool, joining two subassemblies is seen as blank (nothing picked): the explanations that
    finish the product come first, and the log is ambiguous."""
    from dataclasses import replace

    plan = make_plan(replace(pen, defaults=replace(pen.defaults, tool=None)))
    seen, blank = plan.operation_observation, 0
    hidden = [r for r in range(24) if any(int(seen[o]) == blank for o in sequence_at(plan, r))]
    assert hidden, "some pen sequence joins two subassemblies"
    for rank in hidden:
        operations = sequence_at(plan, rank)
        steps = [("operator", int(seen[o])) for o in operations] + [("operator", blank)]  # and a wait
        found, _ = explain_steps(plan, steps)
        assert [o for o, _ in found] == operations  # the explanation that finishes the product
        # Cut after the first blank operation: it was done, or nothing was: both explain the log.
        cut = next(k for k, o in enumerate(operations) if int(seen[o]) == blank) + 1
        found, ambiguous = explain_steps(plan, steps[:cut])
        assert ambiguous and [o for o, _ in found] == operations[:cut]


def test_a_log_of_another_product_is_refused(model, tmp_path):
    _session(model, 0, tmp_path / "session.jsonl")
    other = api.plan_of(api.resolve_product("pen").__class__(
        parts=model.plan.product.parts[:2], contacts=(("ink", "cartridge"),)))
    with pytest.raises(api.PlannerError, match="is not an operation of .* the log was recorded for Bourjault"):
        api.sequence_from_log(tmp_path / "session.jsonl", other)
    (tmp_path / "bad.jsonl").write_text(json.dumps({"event": "action"}) + "\n")
    with pytest.raises(SessionError, match="not a session log"):
        api.sequence_from_log(tmp_path / "bad.jsonl")
