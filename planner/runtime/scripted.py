"""Scripted stand-ins for the cell, for tests, demos and dry runs: a robot that performs every instruction at
once (:class:`ScriptedRobot`) and an operator following one assembly sequence (:class:`ScriptedOperator`, an
observation source; :class:`~planner.runtime.tray.SimulatedCell` films it for the vision pipeline)."""
from __future__ import annotations

from typing import Callable, Iterable, Sequence

import numpy as np

from ..assembly.plan import Plan
from ..assembly.tags import BLANK, Observation
from ..decision.intention_model import IntentionModel
from .interfaces import Instruction, RobotReport

__all__ = ["ScriptedRobot", "ScriptedOperator", "first_completion"]


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
    taking turns with the robot as in the paper's runs) and nothing else. It follows the true assembly state
    (``state``). The robot's operation there (for an action named by a join, the join's operation at that state)
    is struck from its list when the list has it; otherwise the robot helped ahead (docs/parallel.md, The
    projected model): the rest of the sequence is projected onto the new state, the operator's other joins in
    its order (``ahead`` lists those operations). When that projection is not feasible, the robot's operation
    goes to ``off_script`` and the operator then finishes by the first completion from the new state (smallest
    state edges); an instruction of which no operation applies at the true state changes nothing and goes to
    ``off_script`` too. As an :class:`~planner.runtime.interfaces.ObservationSource` it reports
    the observation of what it did.
    """

    def __init__(self, plan: Plan, operations: Sequence[int], acts: Callable[[int], bool] | None = None):
        self.plan = plan
        self.remaining = [int(o) for o in operations]
        self.acts = acts or (lambda step: True)
        self.step = 0
        self.state = plan.states.initial
        self.done: list[int] = []
        self.off_script: list[int] = []
        self.ahead: list[int] = []  # the robot's operations off the list whose projection was feasible
        self._projector = None  # built at the first robot operation off the list

    @classmethod
    def following(cls, model: IntentionModel, intention: int,
                  acts: Callable[[int], bool] | None = None) -> "ScriptedOperator":
        """The operator whose intention is ``intention`` of the decision model ``model``."""
        return cls(model.plan, model.sequence_operations(intention), acts)

    def _edge(self, operations, state: int | None = None) -> int | None:
        """The state edge out of ``state`` (default: the true state) whose operation is one of ``operations``, or
        None."""
        states = self.plan.states
        out = np.flatnonzero(states.edge_source == (self.state if state is None else state))
        hit = out[np.isin(states.edge_operation[out], operations)]
        return int(hit[0]) if hit.size else None

    def _apply(self, operation: int) -> None:
        edge = self._edge(operation)
        if edge is not None:
            self.state = int(self.plan.states.edge_target[edge])

    def next_operation(self) -> int | None:
        """Advance one step: the operation the operator performs in it, or None."""
        self.step += 1
        if not self.remaining or not self.acts(self.step):
            return None
        operation = self.remaining.pop(0)
        self.done.append(operation)
        self._apply(operation)
        return operation

    def observation_of(self, operation: int | None) -> Observation:
        """What the camera sees of ``operation`` (BLANK for None)."""
        return BLANK if operation is None else self.plan.observations[int(self.plan.operation_observation[operation])]

    def observe(self) -> Observation | None:
        return self.observation_of(self.next_operation())

    def robot_acting(self, instruction: Instruction) -> int | None:
        """The robot performs ``instruction`` in the true state (class docstring); returns the AND/OR operation it
        did there (None: wait, or nothing of it applies)."""
        if instruction.operation is None:
            return None
        edge = self._edge(instruction.operation if instruction.performs is None else instruction.performs)
        if edge is None:
            self.off_script.append(instruction.operation)
            return None
        operation = int(self.plan.states.edge_operation[edge])
        if operation in self.remaining:
            self.remaining.remove(operation)
            self._apply(operation)
            return operation
        rest = self._projected(edge)
        self.state = int(self.plan.states.edge_target[edge])
        if rest is None:
            self.off_script.append(operation)
            rest = first_completion(self.plan.states, self.state)
        else:
            self.ahead.append(operation)
        self.remaining = [int(self.plan.states.edge_operation[e]) for e in rest]
        return operation

    def _projected(self, robot_edge: int) -> list[int] | None:
        """The projection of the rest of the sequence onto the target of ``robot_edge`` (state edges), or None."""
        from ..decision.projected import Projector, project_path

        if self._projector is None:
            self._projector = Projector(self.plan.states)
        path, state = [], self.state
        for operation in self.remaining:
            edge = self._edge(operation, state)
            if edge is None:
                return None
            path.append(edge)
            state = int(self.plan.states.edge_target[edge])
        return project_path(self._projector, path, 0, robot_edge)


def first_completion(states, state: int) -> list[int]:
    """The state edges of the first completion from ``state`` to the finished product (smallest edges first).
    Cost: O(n E)."""
    out = []
    while state != states.final:
        edge = int(np.flatnonzero(states.edge_source == state)[0])
        out.append(edge)
        state = int(states.edge_target[edge])
    return out
