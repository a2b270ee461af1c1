"""The assembly state a session follows from the operations done (planner/runtime/progress.py), on the pen
(whose operations and observations are listed by ``aplan stats pen``: 21 operations, 12 observations)."""
from __future__ import annotations

import pytest

from planner import BLANK, Observation, chain_product, make_plan
from planner.runtime.progress import AssemblyProgress


@pytest.fixture(scope="module")
def plan(pen):
    return make_plan(pen)


def _operation(plan, first: set[str], second: set[str]) -> int:
    andor = plan.andor
    sides = {frozenset(first), frozenset(second)}
    return next(j for j in range(len(andor.operations)) if set(andor.inputs(j)) == sides)


def _seen(plan, parts, tool="hammer") -> int:
    return plan.observations.index(Observation(tuple(sorted(parts)), tool))


def test_one_sequence_done_by_both(plan):
    progress = AssemblyProgress(plan)
    assert not progress.may_be_finished
    assert progress.step(None, _seen(plan, ("body", "button"))).explained
    assert progress.step(_operation(plan, {"cartridge"}, {"head"}), plan.observations.index(BLANK)).robot
    out = progress.step(None, _seen(plan, ("ink",)))  # ink onto {cartridge, head}: one operation explains it
    assert out.explained and progress.operations == 3 and len(progress.states) == 1
    progress.step(None, _seen(plan, ()))  # the tool alone: {ink, cartridge, head} joins {body, button}
    assert not progress.finished and progress.possible() == ["cap+[hammer]"]
    progress.step(None, _seen(plan, ("cap",)))
    assert progress.finished and progress.operations == 5


def test_unexplained_steps_change_nothing(plan):
    progress = AssemblyProgress(plan)
    progress.step(None, _seen(plan, ("body", "button")))
    before = set(progress.states)
    cap = progress.step(None, _seen(plan, ("cap",)))  # the cap cannot go onto the body and button alone
    assert not cap.explained and cap.applied == [] and progress.states == before
    assert not progress.step(None, None).explained  # picks no operation shows
    impossible = progress.step(_operation(plan, {"ink"}, {"cartridge", "head"}), None)
    assert impossible.robot is False and progress.states == before and progress.operations == 1
    assert progress.possible() == ["cartridge+head+[hammer]", "cartridge+ink+[hammer]"]


def test_a_robot_operation_waits_for_the_operators_step(plan):
    """The robot inserts the ink into {cartridge, head} in the step in which the operator joins them: applied
    after the operator's operation."""
    progress = AssemblyProgress(plan)
    ink = _operation(plan, {"ink"}, {"cartridge", "head"})
    out = progress.step(ink, _seen(plan, ("cartridge", "head")))
    assert out.robot and out.explained and out.applied == [("operator", _seen(plan, ("cartridge", "head"))),
                                                            ("robot", ink)]
    assert progress.describe() == "{ink, cartridge, head} {body} {cap} {button}"


def test_a_blank_may_hide_an_operation_without_tool():
    plan = make_plan(chain_product(4))
    progress = AssemblyProgress(plan)
    progress.step(None, plan.observations.index(Observation(("p1", "p2"), None)))
    progress.step(None, plan.observations.index(Observation(("p3", "p4"), None)))
    assert progress.step(None, plan.observations.index(BLANK)).explained
    assert progress.may_be_finished and not progress.finished and len(progress.states) == 2
    assert progress.operations == 2  # the blank one is not known to be done


def test_a_session_warns_of_a_robot_operation_the_state_does_not_allow(plan):
    from planner.decision import intention_model
    from planner.runtime.log import EventLog
    from planner.runtime.scripted import ScriptedRobot
    from planner.runtime.session import run_session

    model = intention_model(plan)
    ink = _operation(plan, {"ink"}, {"cartridge", "head"})

    class Eager:  # inserts the ink before anything was built
        def action(self, belief) -> int:
            return next(a for a in range(len(model.actions)) if model.operation(a) == ink)

    class Blank:
        def __init__(self):
            self.left = 2

        def observe(self):
            self.left -= 1
            return BLANK if self.left >= 0 else None

        def robot_acting(self, instruction):
            pass

    log = EventLog()
    result = run_session(model, Eager(), Blank(), ScriptedRobot(), log)
    assert result.reason == "source ended" and result.operations == 0
    warnings = [e["message"] for e in log.events if e["event"] == "warning"]
    assert warnings[0] == ("the robot's operation {ink} + {cartridge, head} is not possible in the assembly state "
                           "({ink} {cartridge} {head} {body} {cap} {button}); it does not count")
    assert len(warnings) == 2


def test_the_picks_offered_beside_the_robots_operation(plan):
    """The keyboard is offered what the operator could pick beside the robot's operation of the step: the
    states after it (the robot acts first), so not the robot's own operation; a robot operation possible
    nowhere yet leaves the picks of the states held (it is tried again after the operator's step)."""
    progress = AssemblyProgress(plan)
    progress.step(None, _seen(plan, ("body", "button")))
    alone = progress.possible()
    assert alone == ["cartridge+head+[hammer]", "cartridge+ink+[hammer]"]
    robot = _operation(plan, {"cartridge"}, {"head"})
    beside = progress.possible(robot)
    assert "cartridge+head+[hammer]" not in beside and beside == ["ink+[hammer]"]
    assert progress.possible(_operation(plan, {"ink"}, {"cartridge", "head"})) == alone
    assert progress.possible() == alone  # asking changes nothing
