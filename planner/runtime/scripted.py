"""Scripted stand-ins for the cell, for tests, demos and dry runs: a robot that performs every instruction at
once (:class:`ScriptedRobot`) and an operator following one assembly sequence (:class:`ScriptedOperator`, an
observation source; :class:`~planner.runtime.tray.SimulatedCell` films it for the vision pipeline)."""
from __future__ import annotations

from typing import Callable, Iterable, Sequence

from ..assembly.plan import Plan
from ..assembly.tags import BLANK, Observation
from ..decision.intention_model import IntentionModel
from .interfaces import Instruction, RobotReport

__all__ = ["ScriptedRobot", "ScriptedOperator"]


class ScriptedRobot:
    """Performs every instruction at once, failing at the steps in ``fail_at``; ``on_perform`` (e.g. a
    simulated cell taking the robot's parts from a synthetic tray) is called for each performed one."""

    def __init__(self, fail_at: Iterable[int] = (), on_perform: Callable[[Instruction], None] | None = None):
        self.fail_at = set(fail_at)
        self.on_perform = on_perform
        self.performed: list[Instruction] = []

    def perform(self, instruction: Instruction) -> RobotReport:
        if instruction.step in self.fail_at:
            return RobotReport(False, f"scripted failure at step {instruction.step}")
        self.performed.append(instruction)
        if self.on_perform is not None:
            self.on_perform(instruction)
        return RobotReport(True)


class ScriptedOperator:
    """An operator following one assembly sequence (``operations``, AND/OR operation indices in order).

    Each step it performs its next operation when ``acts(step)`` says so (default: always, the operator
    taking turns with the robot as in the paper's runs) and nothing else; an operation the robot performs
    is struck from its list. As an :class:`~planner.runtime.interfaces.ObservationSource` it reports the
    observation of what it did. ``off_script`` lists the robot's operations that were not in the sequence.
    """

    def __init__(self, plan: Plan, operations: Sequence[int], acts: Callable[[int], bool] | None = None):
        self.plan = plan
        self.remaining = [int(o) for o in operations]
        self.acts = acts or (lambda step: True)
        self.step = 0
        self.done: list[int] = []
        self.off_script: list[int] = []

    @classmethod
    def following(cls, model: IntentionModel, intention: int,
                  acts: Callable[[int], bool] | None = None) -> "ScriptedOperator":
        """The operator whose intention is ``intention`` of the decision model ``model``."""
        return cls(model.plan, model.sequence_operations(intention), acts)

    def next_operation(self) -> int | None:
        """Advance one step: the operation the operator performs in it, or None."""
        self.step += 1
        if not self.remaining or not self.acts(self.step):
            return None
        operation = self.remaining.pop(0)
        self.done.append(operation)
        return operation

    def observation_of(self, operation: int | None) -> Observation:
        """What the camera sees of ``operation`` (BLANK for None)."""
        return BLANK if operation is None else self.plan.observations[int(self.plan.operation_observation[operation])]

    def observe(self) -> Observation | None:
        return self.observation_of(self.next_operation())

    def robot_acting(self, instruction: Instruction) -> None:
        if instruction.operation is None:
            return
        if instruction.operation in self.remaining:
            self.remaining.remove(instruction.operation)
        else:
            self.off_script.append(instruction.operation)
