"""A step undone, and one the product cannot recover from (issue 23 item 3; docs/deviations.md).

A source reports :class:`Apart` instead of an observation when a joined piece came apart (the keyboard's
``apart PART...``; a tracker that sees joints could report it too): the listed parts come off the subassembly
that holds them as one piece, and the rest of that subassembly stays together. In each assembly state the
session holds (:class:`~planner.runtime.progress.AssemblyProgress`) that gives a partition of the parts:

- when it is an assembly state of the plan (both pieces are subassemblies of the AND/OR graph and the partition
  is a state of the state graph), the session goes on from there, and the belief moves to the completions of
  that state by the prior (:func:`~planner.decision.deviations.belief_at_states`: the classes out of it by
  their prior share, or its intentions by their prior weights), each state weighted by the belief's mass,
  after the step's action, on the state it came from: not the uniform belief from scratch;
- when no state it gives is one (a piece no operation makes, or a partition no sequence reaches), the product
  cannot be finished from it by any plan: the session reports it in one line, logs an ``unrecoverable`` event
  and stops (reason ``unrecoverable``).

An ``apart`` naming parts that are not all in one subassembly, or all of it, changes nothing (a warning; the
step counts as blank). Cost: O(S n) per report for S states and n parts (a lookup of the partition).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..assembly.plan import Plan
from ..decision.deviations import belief_at_states
from ..decision.models import is_flat, predict, state_mass

__all__ = ["Apart", "apart_state", "belief_after_apart", "state_mass", "in_model", "predicted"]


@dataclass(frozen=True)
class Apart:
    """What a source reports when the ``parts`` (one piece) came off the subassembly that held them."""

    parts: tuple[str, ...]

    def __str__(self) -> str:
        return "apart " + " ".join(self.parts)


def apart_state(plan: Plan, state: int, parts: tuple[str, ...]) -> tuple[int | None, str]:
    """The assembly state after ``parts`` came off their subassembly in ``state``: ``(state, "")``, or ``(None,
    why)`` when the partition is not a state of the plan (``why`` says so), or ``(-1, why)`` when the report
    does not apply (the parts are not in one subassembly, or are all of it). Cost: O(S n)."""
    states, andor = plan.states, plan.andor
    index = {name: k for k, name in enumerate(andor.parts)}
    members = [index[p] for p in parts if p in index]
    if not members:
        return -1, "none of them is a part of the plan"
    row = states.blocks[state].copy()
    holder = {int(row[k]) for k in members}
    if len(holder) != 1:
        return -1, "they are not in one subassembly"
    whole = andor.subassemblies[holder.pop()]
    piece = sum(1 << k for k in members)
    rest = whole & ~piece
    if rest == 0:
        return -1, "they are a whole subassembly (nothing came apart)"
    lookup = {mask: k for k, mask in enumerate(andor.subassemblies)}
    if piece not in lookup or rest not in lookup:
        missing = andor.names(lookup[whole]) if whole in lookup else "it"
        return None, (f"{missing} came apart into pieces no operation of the plan makes")
    for bit, value in ((piece, lookup[piece]), (rest, lookup[rest])):
        for k in range(len(andor.parts)):
            if bit >> k & 1:
                row[k] = value
    found = np.flatnonzero((states.blocks == row).all(axis=1))
    if found.size == 0:
        return None, "no assembly sequence of the plan goes through the state left"
    return int(found[0]), ""


def belief_after_apart(model, predicted, moves: list[tuple[int, int]]):
    """The belief after a step undone (module docstring): the prior over the completions of each new state of
    ``moves`` (``(from state, to state)`` pairs), weighted by ``predicted``'s mass on the state it came from
    (equal weights when that mass is 0 everywhere). Cost: O(E) or O(I) per state."""
    weights = [state_mass(model, predicted, s) for s, _ in moves]
    if sum(weights) <= 0:
        weights = [1.0] * len(moves)
    targets: dict[int, float] = {}
    for (_, t), w in zip(moves, weights):
        targets[t] = targets.get(t, 0.0) + w
    kept = [(t, w) for t, w in targets.items() if w > 0] or list(targets.items())
    return belief_at_states(model, [t for t, _ in kept], [w if w > 0 else 1.0 for _, w in kept])


def in_model(model, state: int) -> bool:
    """Whether the decision model holds completions of ``state`` (with a base part, only the states its
    sequences reach). Cost: O(I) or O(S + E)."""
    if is_flat(model):
        return bool((model.graph.first_state == state).any())
    if model.base_part is None:
        return True
    return bool(model.reachable(model.initial_classes)[model.classes_from(state)].any())


def predicted(model, updater, belief, action: int):
    """The belief after ``action`` before any observation (flat or factored): :func:`planner.decision.models.predict`."""
    return predict(model, updater, belief, action)
