"""The assembly sequence a session log recorded: the robot's operations and the operator's, in the order done.

The log names the robot's operations (its actions) but only what the operator was seen picking (an
observation), which several operations of a state may explain, and a blank observation may hide one (an
operation that takes no single part and no tool). The sequence is the first, in the order of the state
graph's edges, that explains every logged event, preferring one that finishes the product
(:func:`explain_steps`); ``ambiguous`` says whether another one explains the log too. That one sequence is what
a log shows (``aplan sequence``, the 3-D panel); the habits learn from every explanation, weighted by its
posterior (:mod:`~planner.runtime.log_posterior`).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..assembly.explode import SequenceError, check_sequence
from ..assembly.plan import Plan
from ..assembly.tags import BLANK
from ..decision.joins import performed
from ..decision.orders import real_plan
from ..product import Product
from ..validation import InputLimits
from .log import SessionError, replay
from .progress import AssemblyProgress
from .scripted import first_completion

__all__ = ["LoggedSequence", "complete_sequence", "explain_steps", "logged_sequence", "logged_steps", "read_steps"]


@dataclass(frozen=True)
class LoggedSequence:
    """``operations`` (AND/OR indices of ``plan``) in the order they were done, ``by`` who did each (``robot``
    or ``operator``); ``complete``: the product was finished; ``ambiguous``: another sequence explains the
    log too."""

    product: Product
    plan: Plan
    operations: tuple[int, ...]
    by: tuple[str, ...]
    complete: bool
    ambiguous: bool


def logged_steps(events: list[dict], model) -> list[tuple[str, int]]:
    """The log's steps that changed the assembly state, as ``("robot", operation)`` for each robot operation
    reported done (for an action named by a join, the tuple of the join's operations:
    :func:`~planner.decision.joins.performed`; the one at the state applies) and ``("operator", observation
    index)`` for each observation, in the order they were applied
    (:class:`~planner.runtime.progress.AssemblyProgress`, the session's rule): an observation no operation
    explains in the assembly state (the session ignored it and counted the step as blank; a log written before
    that rule kept it) and a robot operation the state does not allow are left out; a step undone ends them
    (the steps before it are the sequence). A blank observation: the
    operator did nothing, or an operation that shows as blank. Cost: O(events E)."""
    progress, blank = AssemblyProgress(model.plan), model.plan.observations.index(BLANK)
    steps, pending = [], {}
    for event in events:
        kind = event.get("event")
        if kind in ("apart", "unrecoverable"):  # a step undone: the sequence counted is the one before it
            return steps
        if kind == "action":
            pending[event.get("step")] = [performed(model, int(event["action"])), False]
        elif kind == "robot" and event.get("ok") and event.get("step") in pending:
            pending[event.get("step")][1] = True
        elif kind == "observation":
            operation, confirmed = pending.pop(event.get("step"), [None, False])
            index = event.get("index")
            observation = None if event.get("ignored") is True or index is None else int(index)
            steps += progress.step(operation if confirmed else None, observation).applied
    for operation, confirmed in pending.values():  # done, then the source ended before the step's observation
        if confirmed and operation is not None:
            steps += progress.step(operation, blank).applied[:1]
    return steps


#: How many explanations of a log :func:`explain_steps` collects before it chooses.
EXPLANATIONS = 64


def explain_steps(plan: Plan, steps: list[tuple[str, int]]) -> tuple[list[tuple[int, str]], bool]:
    """A sequence of ``(operation, who)`` (``robot`` or ``operator``) that explains ``steps``
    (:func:`logged_steps`), and whether another one does.

    Explanations are searched depth first over the state edges, smallest first (a blank observation: an
    operation it explains first, then nothing); of the first :data:`EXPLANATIONS`, the first that finishes
    the product is chosen, else the first. Raises :class:`SequenceError` when none explains the steps.
    Cost: O(b^k E) for k steps with at most b candidates each (b is 1 when every observation names one
    operation and none is blank)."""
    states, seen = plan.states, plan.operation_observation
    blank = plan.observations.index(BLANK)
    found: list[tuple[list[tuple[int, str]], bool]] = []

    def search(state: int, at: int, done: list[int]) -> None:
        if len(found) == EXPLANATIONS:
            return
        if at == len(steps):
            found.append((list(done), state == states.final))
            return
        who, value = steps[at]
        out = np.flatnonzero(states.edge_source == state)
        ops = states.edge_operation[out]
        match = out[np.isin(ops, value)] if who == "robot" else out[seen[ops] == value]
        for edge in match:
            search(int(states.edge_target[edge]), at + 1, done + [(int(states.edge_operation[edge]), who)])
        if who == "operator" and value == blank:
            search(state, at + 1, done)

    search(states.initial, 0, [])
    if not found:  # not for steps from logged_steps, whose every step the state it reached allows
        raise SequenceError("no assembly sequence of the product explains the logged operations and observations "
                            f"({', '.join(f'{who} {value}' for who, value in steps)})")
    chosen = next((ops for ops, finished in found if finished), found[0][0])
    return chosen, len({tuple(op for op, _ in ops) for ops, _ in found}) > 1


def complete_sequence(plan: Plan, operations: list[int]) -> list[int]:
    """``operations`` (a prefix of a full sequence) followed by the first continuation (smallest state edges)
    to the finished product. Cost: O(n E)."""
    states = plan.states
    rest = first_completion(states, check_sequence(plan, operations)[-1])
    return list(operations) + [int(states.edge_operation[e]) for e in rest]


def read_steps(path: str | os.PathLike, limits: InputLimits = InputLimits()) -> tuple[Product, Plan, list]:
    """The product the session log at ``path`` stores, its real plan (the orders' model is on an augmented graph:
    the log is about the real one) and the log's :func:`logged_steps`. Raises
    :class:`~planner.runtime.log.SessionError` for a file that is not a session log. Cost: the replay (one
    model build and one belief update per step)."""
    done = replay(Path(path), limits=limits)
    return done.product, real_plan(done.model.plan), logged_steps(done.events, done.model)


def logged_sequence(path: str | os.PathLike, limits: InputLimits = InputLimits()) -> LoggedSequence:
    """The sequence the session log at ``path`` recorded (module docstring), over the plan of the product
    the log stores; ``limits``: what the log is read within (:func:`~planner.runtime.log.read_log`). Raises :class:`~planner.runtime.log.SessionError` for a file that is not a session log
    and when no sequence of that product explains it. Cost: :func:`read_steps` and :func:`explain_steps`."""
    product, plan, steps = read_steps(path, limits)
    try:
        explained, ambiguous = explain_steps(plan, steps)
    except SequenceError as exc:
        raise SessionError(f"{path}: {exc}") from None
    operations = [op for op, _ in explained]
    state = check_sequence(plan, operations)[-1]
    return LoggedSequence(product, plan, tuple(operations), tuple(who for _, who in explained),
                          state == plan.states.final, ambiguous)
