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

In a session (docs/parallel.md, "In a session") the robot is told the join: "join the block that holds ``P`` to
the block that holds ``Q``". :func:`performed` gives the AND/OR operations an action may be (for a join, one per
state where it applies: what the session's assembly state follows), :func:`join_choices` the operation of the join
at each assembly state of the belief where it applies, most probable state first: the first is the one reported
and drawn (its moving parts, direction, tool). When every such state has the same operation the physical motion
is the same whatever the state.
"""
from __future__ import annotations

import numpy as np

from ..assembly.andor import liaison_adjacency

__all__ = ["JOINS", "join_of", "join_actions", "names_joins", "join_parts", "performed", "join_choices", "join_family"]

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


def names_joins(model) -> bool:
    """Whether ``model``'s actions are named by the parts they join (the joins model), not by operations."""
    return getattr(model, "action_names", None) is not None


def join_parts(model, action: int) -> tuple[str, str]:
    """The part ids ``(P, Q)`` of the join ``action`` of the joins model (its first operation's join). Cost:
    the contact bitmasks, O(n + contacts)."""
    op = model.operation(action)
    andor = model.plan.andor
    p, q = join_of(andor, liaison_adjacency(model.plan.product), op)
    return andor.parts[p], andor.parts[q]


def performed(model, action: int) -> int | tuple[int, ...] | None:
    """The AND/OR operations ``action`` performs: None for ``wait``; its operation on a model whose actions are
    operations (flat or factored); for a join, every operation with that join, sorted (at most one applies at
    each assembly state, module docstring). Cost: O(E) for a join, O(1) otherwise."""
    operation = model.operation(action)
    if operation is None or not names_joins(model):
        return operation
    E = model.final_class
    return tuple(np.unique(model.class_operation[:E][model.class_action[:E] == action]).tolist())


def join_choices(model, action: int, belief) -> list[tuple[int, int, float]]:
    """``(state, operation, mass)`` for each assembly state of the (factored) ``belief`` where the join ``action``
    applies: the state edge out of it whose operation has that join, and the belief's mass on the state; most
    probable state first (ties: the lower state index). Empty when no state of the belief has the join. Cost:
    O(E + k log k) for k classes of the belief."""
    E = model.final_class
    edges = np.flatnonzero(model.class_action[:E] == action)
    by_state = dict(zip(model.class_source[edges].tolist(), model.class_operation[edges].tolist()))
    states, inverse = np.unique(model.class_source[belief.classes], return_inverse=True)
    mass = np.bincount(inverse, weights=belief.mass, minlength=states.size)
    found = [(int(s), int(by_state[int(s)]), float(m)) for s, m in zip(states.tolist(), mass.tolist())
             if m > 0 and int(s) in by_state]
    return sorted(found, key=lambda x: (-x[2], x[0]))


def join_family(plan, operation: int) -> tuple[tuple[str, str], tuple[int, ...]]:
    """The join ``(P, Q)`` (part ids) of AND/OR ``operation`` and every robot-capable operation with that join,
    sorted: what a join is when only its reported operation is known (a ROS goal: docs/ros.md). Cost:
    O(ops x n)."""
    andor = plan.andor
    adjacency = liaison_adjacency(plan.product)
    pair = join_of(andor, adjacency, operation)
    family = tuple(int(op) for op in np.flatnonzero(plan.tags.robot) if join_of(andor, adjacency, int(op)) == pair)
    return (andor.parts[pair[0]], andor.parts[pair[1]]), family
