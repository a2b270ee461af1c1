"""What the decision loop exchanges with the cell: the robot's instruction for a step, the robot's report, and
the two protocols an adapter implements (:class:`ObservationSource`, :class:`Robot`).

They are :class:`typing.Protocol` classes, so a ROS node or a vendor SDK plugs in as any class with these
methods, without subclassing or importing anything else from the planner.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Protocol, runtime_checkable

from ..assembly.tags import Observation
from ..decision.intention_model import IntentionModel
from ..decision.joins import join_choices, join_family, join_parts, names_joins, performed

__all__ = ["Instruction", "RobotReport", "ObservationSource", "Robot", "instruction_for", "instruction_of_operation",
           "with_join"]

_JOIN_NAME = re.compile(r"a\d+:join\(")  # the name of an action named by a join (FactoredIntentionModel.actions)


@dataclass(frozen=True)
class Instruction:
    """What the robot is asked to do at one step: an operation (join ``inputs`` with ``tool``) or wait.

    ``fasteners``: the fastener parts the operation installs (its folded fastener groups); ``picks``: the
    inputs that are single parts and those fasteners, which the robot takes from the tray.

    Actions named by the parts they join (``--joins``, docs/parallel.md, In a session): ``join`` the two parts
    ``(P, Q)``: the robot joins the block that holds ``P`` to the block that holds ``Q``, whichever the assembly
    state; ``operation`` and the fields above are those at the belief's most probable state where the join
    applies (what is reported and drawn); ``same_motion``: every state of the belief where it applies has that
    operation; ``takes``: what the robot may take from the tray at any of those states (the picks of each).
    ``performs``: the AND/OR operations the action is, one per assembly state (the join's; else the operation),
    what the session's assembly state follows.
    """

    step: int
    action: int
    name: str
    operation: int | None = None
    inputs: tuple[tuple[str, ...], tuple[str, ...]] | None = None
    tool: str | None = None
    fasteners: tuple[str, ...] = ()
    join: tuple[str, str] | None = None
    same_motion: bool = True
    takes: tuple[str, ...] | None = None
    performs: int | tuple[int, ...] | None = None

    @property
    def is_wait(self) -> bool:
        return self.operation is None

    @property
    def picks(self) -> tuple[str, ...]:
        return tuple(sorted([side[0] for side in self.inputs or () if len(side) == 1] + list(self.fasteners)))

    @property
    def may_take(self) -> tuple[str, ...]:
        """What the robot may take from the tray: ``takes`` for a join, else the picks."""
        return self.picks if self.takes is None else self.takes

    @property
    def text(self) -> str:
        if self.is_wait:
            return "wait (do nothing this step)"
        first, second = ("{" + ", ".join(side) + "}" for side in self.inputs)
        fastened = f" fastened by {', '.join(self.fasteners)}" if self.fasteners else ""
        operation = f"join {first} with {second}{fastened}" + (f" using the {self.tool}" if self.tool else "")
        if self.join is None:
            return operation
        p, q = self.join
        if self.same_motion:
            return f"join {p} to {q}: {operation}"
        return f"join {p} to {q} (the block that holds {p} to the block that holds {q}; most likely {operation})"


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


def _operation_fields(plan, operation: int) -> dict:
    """The instruction's fields of AND/OR ``operation``: its inputs, tool and fasteners."""
    first, second = (tuple(sorted(side)) for side in plan.andor.inputs(operation))
    fasteners = tuple(p for group, operations in zip(plan.fasteners, plan.installs)
                      if bool((operations == operation).any()) for p in group.parts)
    return {"operation": operation, "inputs": (first, second), "tool": plan.tags.tool[operation],
            "fasteners": fasteners}


def instruction_for(model: IntentionModel, action: int, step: int, belief=None) -> Instruction:
    """The instruction of ``action`` in ``model`` at ``step``. With actions named by joins, ``belief`` (the
    factored belief the action was chosen for) gives the operation reported: the join's at the belief's most
    probable assembly state where it applies (:func:`~planner.decision.joins.join_choices`; none: the join's
    first operation). Cost: O(1), or O(E + k log k) for a join."""
    name = model.actions[action]
    operation = model.operation(action)
    if operation is None:
        return Instruction(step, action, name)
    plan = model.plan
    if not names_joins(model):
        return instruction_of_operation(plan, operation, step, action, name)
    choices = join_choices(model, action, belief) if belief is not None else []
    operations = [op for _, op, _ in choices] or [operation]
    takes = sorted({p for op in set(operations) for p in instruction_of_operation(plan, op).picks})
    return Instruction(step, action, name, join=join_parts(model, action), same_motion=len(set(operations)) == 1,
                       takes=tuple(takes), performs=performed(model, action), **_operation_fields(plan, operations[0]))


def with_join(plan, instruction: Instruction) -> Instruction:
    """``instruction`` as a ROS goal carried it (docs/ros.md: the goal has no field for the join; the action's
    name ``aK:join(P,Q)`` says it is one, ``operation`` is the one reported) with its join and the join's
    operations filled in from ``plan`` (:func:`~planner.decision.joins.join_family`); any other, as it is."""
    if instruction.join is not None or instruction.operation is None or not _JOIN_NAME.match(instruction.name):
        return instruction
    join, family = join_family(plan, instruction.operation)
    return replace(instruction, join=join, performs=family)


def instruction_of_operation(plan, operation: int, step: int = 0, action: int = -1, name: str = "") -> Instruction:
    """The instruction that performs AND/OR ``operation`` of ``plan`` (what a join is at a known assembly state:
    the simulated cell's robot takes its picks)."""
    return Instruction(step, action, name, performs=operation, **_operation_fields(plan, operation))
