"""What the decision loop exchanges with the cell: the robot's instruction for a step, the robot's report, and
the two protocols an adapter implements (:class:`ObservationSource`, :class:`Robot`).

They are :class:`typing.Protocol` classes, so a ROS node or a vendor SDK plugs in as any class with these
methods, without subclassing or importing anything else from the planner.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from ..assembly.tags import Observation
from ..decision.intention_model import IntentionModel

__all__ = ["Instruction", "RobotReport", "ObservationSource", "Robot", "instruction_for"]


@dataclass(frozen=True)
class Instruction:
    """What the robot is asked to do at one step: an operation (join ``inputs`` with ``tool``) or wait.

    ``fasteners``: the fastener parts the operation installs (its folded fastener groups); ``picks``: the
    inputs that are single parts and those fasteners, which the robot takes from the tray.
    """

    step: int
    action: int
    name: str
    operation: int | None = None
    inputs: tuple[tuple[str, ...], tuple[str, ...]] | None = None
    tool: str | None = None
    fasteners: tuple[str, ...] = ()

    @property
    def is_wait(self) -> bool:
        return self.operation is None

    @property
    def picks(self) -> tuple[str, ...]:
        return tuple(sorted([side[0] for side in self.inputs or () if len(side) == 1] + list(self.fasteners)))

    @property
    def text(self) -> str:
        if self.is_wait:
            return "wait (do nothing this step)"
        first, second = ("{" + ", ".join(side) + "}" for side in self.inputs)
        fastened = f" fastened by {', '.join(self.fasteners)}" if self.fasteners else ""
        return f"join {first} with {second}{fastened}" + (f" using the {self.tool}" if self.tool else "")


@dataclass(frozen=True)
class RobotReport:
    """Whether the robot performed an instruction; ``message`` says why not."""

    ok: bool
    message: str = ""


@runtime_checkable
class ObservationSource(Protocol):
    """Where the operator's observations come from (a camera, a keyboard, a script, a ROS topic)."""

    def observe(self) -> Observation | None:
        """The operator's operation in this step (BLANK when none); None when the source has ended; a
        :class:`~planner.runtime.undo.Apart` when a piece came apart (a step undone)."""

    def robot_acting(self, instruction: Instruction) -> None:
        """Called before the robot performs ``instruction``, so the robot's own picks are not the operator's."""


@runtime_checkable
class Robot(Protocol):
    """Performs instructions; reports whether it succeeded (``RobotReport(False, why)`` otherwise)."""

    def perform(self, instruction: Instruction) -> RobotReport:
        ...


def instruction_for(model: IntentionModel, action: int, step: int) -> Instruction:
    """The instruction of ``action`` in ``model`` at ``step``."""
    name = model.actions[action]
    operation = model.operation(action)
    if operation is None:
        return Instruction(step, action, name)
    plan = model.plan
    first, second = (tuple(sorted(side)) for side in plan.andor.inputs(operation))
    fasteners = tuple(p for group, operations in zip(plan.fasteners, plan.installs)
                      if bool((operations == operation).any()) for p in group.parts)
    return Instruction(step, action, name, operation, (first, second), plan.tags.tool[operation], fasteners)
