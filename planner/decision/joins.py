"""Robot actions named by the parts they join (issue 23, item 2; docs/parallel.md, "Actions named by the parts
they join"): the projected model with one action per *join* instead of one per AND/OR operation.

An AND/OR operation joins two subassemblies ``A`` and ``B``. Its *join* is the pair of parts ``(P, Q)``, ``P``
in one and ``Q`` in the other, that it connects: the lowest (by part order) contact of the connection diagram
between ``A`` and ``B`` (with no contact between them, as with fastener groups, the lowest part of each). Adding
the tire ``t`` to the chassis block is the join ``(axle, t)`` however many tires are on already: one
operation per state, one join for all of them. The robot's actions are the distinct joins of the
robot-capable operations (in the order of their first operation), then ``wait``.

The action "join ``P`` to ``Q``" at an assembly state ``s`` is the state edge out of ``s`` whose operation's
join is ``(P, Q)``, if there is one (it is then unique: two operations with the same join at one state join
the same two blocks, and an operation applied to a state has one result); elsewhere it does nothing and is
wrong (the paper's wrong action). So every class ``(s, e)`` still has at most one action that performs its step
(the join of ``e``'s operation), and everything else is the projected model's (:mod:`.projected`): its pairs
(the robot's edge ``f``, the projection's next step ``e'``, the chance ``q``), rewards, transitions, the lumped
POMDP, the bounds and the simulator's rewrite, read through ``class_action`` as the operation-named model.
When each join is the join of one operation only (each join exists in one state), the actions are the
operations and the model is the projected model, table for table.

Cost of :func:`join_actions`: O(ops x n) for n parts (a bitmask per part of its contacts).
"""
from __future__ import annotations

import numpy as np

from ..assembly.andor import liaison_adjacency

__all__ = ["JOINS", "join_of", "join_actions"]

JOINS = "joins"


def _low(mask: int) -> int:
    return (mask & -mask).bit_length() - 1


def join_of(andor, adjacency: list[int], operation: int) -> tuple[int, int]:
    """The join ``(p, q)`` (part indices, ``p < q``) of ``operation`` (module docstring): the lowest contact
    between its two subassemblies, else their lowest parts. Cost: O(n)."""
    op = andor.operations[operation]
    a, b = (int(andor.subassemblies[c]) for c in op.children[:2])
    best = None
    rest = a
    while rest:
        i = _low(rest)
        rest &= rest - 1
        touching = adjacency[i] & b
        if touching:
            pair = tuple(sorted((i, _low(touching))))
            best = pair if best is None or pair < best else best
    return best if best is not None else tuple(sorted((_low(a), _low(b))))


def join_actions(plan, robot_ops: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """``(action_of_op over robot_ops, representative, names)``: the action (the join's index) of each
    robot-capable operation, the first operation of each join (what names it in the operation-named tables)
    and each join's name ``join(P,Q)`` with part ids. Cost: O(ops x n)."""
    andor = plan.andor
    adjacency = liaison_adjacency(plan.product)  # indexed as the AND/OR graph's part bits
    ids = andor.parts
    index: dict[tuple[int, int], int] = {}
    action = np.empty(len(robot_ops), dtype=np.int64)
    first = []
    for k, op in enumerate(robot_ops.tolist()):
        pair = join_of(andor, adjacency, int(op))
        if pair not in index:
            index[pair] = len(index)
            first.append(int(op))
        action[k] = index[pair]
    names = tuple(f"join({ids[p]},{ids[q]})" for p, q in index)
    return action, np.array(first, dtype=np.int64), names
