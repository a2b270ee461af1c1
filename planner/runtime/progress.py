"""The assembly state of a session, followed from the operations actually done (issue 22, item 6).

The belief is a model of the operator's intention; whether the product is finished is a fact of the
operations done. :class:`AssemblyProgress` keeps the *assembly states* (of the plan's state graph) that the
operations done so far can have led to: the robot's confirmed operations and the operator's observations that
an operation explains. A blank observation leaves it open whether the operator did nothing or an operation
that shows as blank (one joining two subassemblies without a tool), so the set can hold more than one state.

An observation that no operation explains in these states (parts that cannot be joined now, a combination no
operation shows, the tool alone before two subassemblies exist) changes nothing: the step counts as blank,
and :meth:`AssemblyProgress.possible` names what the operator could do instead. Within one step the robot
acts first (the decision model's order); a robot operation not possible before the operator's is tried again
after it (the operator may have built what the robot joins), else it changes nothing either. A robot action
named by the parts it joins (``--joins``) is the tuple of the join's operations: at each state held, the one
that applies there (at most one does).

Cost per step: O(E) over the state graph's edges for each state held (one or a few).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..assembly.plan import Plan
from ..assembly.tags import BLANK

__all__ = ["AssemblyProgress", "StepOutcome"]


@dataclass
class StepOutcome:
    """What one step did to the assembly state: ``robot``: the robot's operation was possible (None: no
    operation this step); ``explained``: the observation was explained by an operation (a blank one always
    is); ``applied``: ``("robot", operation)`` and ``("operator", observation index)`` in the order they were
    applied (what :func:`planner.runtime.logged_sequence.explain_steps` explains)."""

    robot: bool | None
    explained: bool
    applied: list[tuple[str, int]] = field(default_factory=list)


class AssemblyProgress:
    """The assembly states the operations done can have led to (module docstring), from the initial state."""

    def __init__(self, plan: Plan):
        self.plan = plan
        states = plan.states
        self.blank = plan.observations.index(BLANK)
        self.states = {states.initial}
        self.operations = 0  # operations known to be done (a blank one that may have happened is not counted)

    @property
    def finished(self) -> bool:
        """Every state the operations can have led to is the finished product."""
        return self.states == {self.plan.states.final}

    @property
    def may_be_finished(self) -> bool:
        """The finished product is one of the states (a blank observation may have hidden the last operation)."""
        return self.plan.states.final in self.states

    def _out(self, state: int) -> np.ndarray:
        return np.flatnonzero(self.plan.states.edge_source == state)

    def _after(self, operation: int | tuple[int, ...]) -> set[int]:
        """The states ``operation`` (a join's tuple: the one at each state) leads to from those held; empty
        where it applies at none."""
        states = self.plan.states
        return {int(states.edge_target[e]) for s in self.states for e in self._out(s)
                if np.isin(states.edge_operation[e], operation)}

    def _robot(self, operation: int | tuple[int, ...]) -> bool:
        reached = self._after(operation)
        if reached:
            self.states = reached
            self.operations += 1
        return bool(reached)

    def _operator(self, observation: int | None) -> bool:
        if observation is None:
            return False
        states, seen = self.plan.states, self.plan.operation_observation
        reached = {int(states.edge_target[e]) for s in self.states for e in self._out(s)
                   if seen[states.edge_operation[e]] == observation}
        if observation == self.blank:  # nothing done, or an operation that shows as blank
            self.states |= reached
            return True
        if reached:
            self.states = reached
            self.operations += 1
        return bool(reached)

    def robot(self, operation: int | tuple[int, ...]) -> bool:
        """Apply the robot's confirmed ``operation`` alone (a step whose observation was a step undone)."""
        return self._robot(operation)

    def set_states(self, states: set[int]) -> None:
        """The assembly states after a step undone (:mod:`planner.runtime.undo`); the operations known done are
        those of the most assembled of them (parts - subassemblies)."""
        self.states = set(states)
        blocks = [len(self.plan.states.subassemblies_of(s)) for s in self.states]
        self.operations = len(self.plan.andor.parts) - min(blocks)

    def step(self, operation: int | tuple[int, ...] | None, observation: int | None) -> StepOutcome:
        """Apply one step: the robot's confirmed ``operation`` (None: wait, or not confirmed; a tuple: a join's
        operations, of which the one at each state applies there), then the operator's ``observation`` (an
        index of ``plan.observations``; None: one the plan does not have)."""
        outcome = StepOutcome(None, False)
        deferred = operation is not None and not self._robot(operation)
        if operation is not None and not deferred:
            outcome.robot = True
            outcome.applied.append(("robot", operation))
        outcome.explained = self._operator(observation)
        if outcome.explained:
            outcome.applied.append(("operator", observation))
        if deferred:
            outcome.robot = self._robot(operation)
            if outcome.robot:
                outcome.applied.append(("robot", operation))
        return outcome

    def describe(self) -> str:
        """The assembly state, e.g. ``{body, button} {cap} ...``; several joined by `` or ``."""
        return " or ".join(self.plan.states.describe(s) for s in sorted(self.states))

    def possible(self, robot: int | tuple[int, ...] | None = None) -> list[str]:
        """What the operator could be seen picking now: the observations of the operations possible in these
        states (blank ones left out), sorted. With the robot's ``robot`` operation of this step (a join's
        tuple), the states after it where it applies (the robot acts first: the operator picks beside what the
        robot is doing, so the robot's own operation is not offered); where it applies nowhere yet, these
        states (it is tried again after the operator's step)."""
        plan, states = self.plan, self.plan.states
        held = self._after(robot) if robot is not None else set()
        held = held or self.states  # no robot operation, or one that applies nowhere yet
        seen = {int(plan.operation_observation[states.edge_operation[e]]) for s in held for e in self._out(s)}
        return sorted(str(plan.observations[z]) for z in seen if z != self.blank)
