"""An assembly sequence as an exploded view that collapses step by step (what the workbench shows in 3D).

Definitions
-----------
A *full assembly sequence* is a path of the assembly state graph from the initial state (every part on its
own) to the final state, written as its operations (AND/OR operation indices). Sequences are *ranked* in
lexicographic order of their state edges (edge indices out of each state, smallest first), so rank ``r`` is
found without enumerating the others (:func:`sequence_at`).

At each operation one side *moves* and the other stays: the side without the base part when one is given
and one side holds it; otherwise the side with fewer parts; on a tie the side of smaller total volume (when
every part has a volume); else the operation's second child. The moving side is inserted along the reverse
of a *free direction* ``d``: moved along ``d``, none of its parts hits a part of the side that stays (the
obstruction diagrams: ``(x, y)`` along ``d`` blocks ``x`` moving along ``d``; along ``-d`` it blocks ``y``).
Among the free directions the first of the product's directions, each followed by its reverse, that also
leaves every other part of the product unhit; failing that, the first free one.

The *exploded offset* of part ``p`` before step ``k`` is ``spacing * sum(w_j d_j)`` over the steps ``j >= k``
whose moving side holds ``p``, with the weight ``w_j = 1 + j / K`` for ``K`` steps: every part sits away
along the directions it has still to be inserted along, those that go in later farther out (so that two
sides leaving the same way do not end up inside each other), and the view collapses one operation at a time
to the assembled product (all offsets zero).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import PlannerError
from ..product import Product
from ..product.model import Direction
from .intentions import base_part_first_edges, paths_to_final
from .plan import Plan
from .states import AssemblyStateGraph

__all__ = [
    "FALLBACK_DIRECTION",
    "ExplodedStep",
    "ExplodedView",
    "SequenceError",
    "check_sequence",
    "exploded_view",
    "free_direction",
    "moving_side",
    "sequence_at",
    "sequence_count",
]

#: The direction used when the product lists no obstruction diagrams (its geometry is not constrained).
FALLBACK_DIRECTION = Direction("+Z", (0.0, 0.0, 1.0))


class SequenceError(PlannerError):
    """A sequence that is not one of the plan's full assembly sequences, or a rank out of range."""


@dataclass(frozen=True)
class ExplodedStep:
    """One operation of the sequence: ``operation`` (AND/OR index) joins ``moving`` to ``fixed``; ``moving`` is
    inserted along ``-direction`` (``direction`` is free: moved along it, ``moving`` hits nothing of ``fixed``)."""

    operation: int
    description: str
    moving: frozenset[str]
    fixed: frozenset[str]
    direction: Direction


@dataclass(frozen=True)
class ExplodedView:
    """A sequence's steps and, for ``k`` in ``0..len(steps)``, ``offsets[k]``: each part's displacement
    (product units) before step ``k`` (``offsets[len(steps)]``: the assembled product, all zero)."""

    parts: tuple[str, ...]
    steps: tuple[ExplodedStep, ...]
    offsets: tuple[dict[str, tuple[float, float, float]], ...]
    spacing: float

    def roles(self, k: int) -> dict[str, str]:
        """Before step ``k``: ``moving``, ``fixed`` (the side it joins) or ``idle`` per part (all ``idle`` at
        the end)."""
        step = self.steps[k] if k < len(self.steps) else None
        return {p: "moving" if step and p in step.moving else "fixed" if step and p in step.fixed else "idle"
                for p in self.parts}


class _Ranking:
    """What ranking needs, computed once per plan: paths to the final state per state, and the edges out of
    each state in increasing order (CSR). Cost: O(E log E) time, O(S + E) memory."""

    def __init__(self, states: AssemblyStateGraph):
        self.states = states
        paths = paths_to_final(states)
        exact = any(counts.dtype == object for counts in paths)  # counts past 2**52 are Python ints
        self.paths = np.zeros(states.n_states, dtype=object if exact else np.int64)
        for level, counts in enumerate(paths):  # levels are contiguous state ranges, most assembled first
            start = int(states.level_start[level])
            self.paths[start:start + counts.shape[0]] = counts
        self.order = np.argsort(states.edge_source, kind="stable")
        self.start = np.searchsorted(states.edge_source[self.order], np.arange(states.n_states + 1))

    def out(self, state: int, base_part: str | None) -> np.ndarray:
        """The edges out of ``state`` in increasing order (from the initial state, those joining ``base_part``)."""
        if base_part is not None and state == self.states.initial:
            return base_part_first_edges(self.states, base_part)
        return self.order[self.start[state]:self.start[state + 1]]

    def count(self, base_part: str | None) -> int:
        states = self.states
        if states.initial == states.final:
            return 1
        return sum(int(self.paths[states.edge_target[e]]) for e in self.out(states.initial, base_part))

    def at(self, rank: int, base_part: str | None) -> list[int]:
        states, operations, state = self.states, [], self.states.initial
        while state != states.final:
            for edge in self.out(state, base_part):
                below = int(self.paths[states.edge_target[edge]])
                if rank < below:
                    operations.append(int(states.edge_operation[edge]))
                    state = int(states.edge_target[edge])
                    break
                rank -= below
        return operations


def sequence_count(plan: Plan, base_part: str | None = None) -> int:
    """The number of full assembly sequences (those whose first operation joins ``base_part``, if given).
    Cost: O(E log E) for E state edges."""
    return _Ranking(plan.states).count(base_part)


def sequences_at(plan: Plan, ranks, base_part: str | None = None) -> list[list[int]]:
    """The operations of the full assembly sequences of ``ranks`` (module docstring), each from 0.

    Raises :class:`SequenceError` for a rank not in ``0..count - 1``. Cost: O(E log E) once, then
    O(n b) per sequence for n parts and at most b edges out of a state, whatever the number of sequences.
    """
    ranking = _Ranking(plan.states)
    total = ranking.count(base_part)
    out = []
    for rank in ranks:
        if not 0 <= int(rank) < total:
            raise SequenceError(f"sequence rank {rank} is out of range: the plan has {total:,} full assembly "
                                f"sequences, ranked 0..{total - 1:,}; choose a rank in that range")
        out.append(ranking.at(int(rank), base_part))
    return out


def first_sequences(plan: Plan, limit: int, base_part: str | None = None) -> tuple[int, list[list[int]]]:
    """The number of full assembly sequences and the first ``limit`` of them by rank, with one ranking
    (:func:`sequences_at`). Cost: O(E log E) plus O(n b) per sequence listed."""
    ranking = _Ranking(plan.states)
    count = ranking.count(base_part)
    return count, [ranking.at(rank, base_part) for rank in range(min(count, max(int(limit), 0)))]


def sequence_at(plan: Plan, rank: int, base_part: str | None = None) -> list[int]:
    """The operations of the full assembly sequence of rank ``rank`` (:func:`sequences_at`)."""
    return sequences_at(plan, [rank], base_part)[0]


def check_sequence(plan: Plan, operations: list[int]) -> list[int]:
    """The states a sequence of operations passes through, from the initial state; raises
    :class:`SequenceError` naming the first operation that does not apply. A prefix is accepted (the list of
    states then ends before the final state). Cost: O(k E) for k operations."""
    states = plan.states
    state, visited = states.initial, [states.initial]
    for position, operation in enumerate(operations):
        edges = np.flatnonzero((states.edge_source == state) & (states.edge_operation == int(operation)))
        if not (0 <= int(operation) < len(plan.andor.operations)) or edges.size == 0:
            what = plan.andor.describe(int(operation)) if 0 <= int(operation) < len(plan.andor.operations) \
                else f"operation {operation}"
            raise SequenceError(f"step {position + 1} ({what}) cannot follow the state {states.describe(state)}; "
                                "a sequence must join two subassemblies of the current state")
        state = int(states.edge_target[edges[0]])
        visited.append(state)
    return visited


def _volume(product: Product, parts: frozenset[str]) -> float | None:
    volumes = {p.id: p.volume for p in product.parts}
    if any(volumes.get(p) is None for p in parts):
        return None
    return float(sum(volumes[p] for p in parts))


def moving_side(plan: Plan, operation: int, base_part: str | None = None) -> tuple[frozenset[str], frozenset[str]]:
    """``(moving, fixed)`` of an operation (the rule of the module docstring). Cost: O(n)."""
    first, second = plan.andor.inputs(operation)
    if base_part is not None and (base_part in first) != (base_part in second):
        return (second, first) if base_part in first else (first, second)
    if len(first) != len(second):
        return (first, second) if len(first) < len(second) else (second, first)
    a, b = _volume(plan.product, first), _volume(plan.product, second)
    if a is not None and b is not None and a != b:
        return (first, second) if a < b else (second, first)
    return second, first


def _hits(product: Product, moving: frozenset[str], others: frozenset[str]) -> list[tuple[Direction, bool]]:
    """Per candidate direction (each listed direction, then its reverse): whether ``moving`` hits ``others``."""
    out = []
    for obstruction in product.obstructions:
        forward = any(x in moving and y in others for x, y in obstruction.blocks)
        backward = any(y in moving and x in others for x, y in obstruction.blocks)
        out += [(obstruction.direction, forward), (obstruction.direction.reverse, backward)]
    return out


def free_direction(product: Product, moving: frozenset[str], fixed: frozenset[str]) -> Direction:
    """A direction along which ``moving`` leaves ``fixed`` without hitting it (module docstring: one that also
    leaves the rest of the product unhit comes first). :data:`FALLBACK_DIRECTION` when the product has no
    obstruction diagrams. Raises :class:`SequenceError` when every direction is blocked. Cost: O(D B) for D
    directions of B pairs."""
    if not product.obstructions:
        return FALLBACK_DIRECTION
    rest = frozenset(product.part_ids) - moving
    clear = [d for d, hit in _hits(product, moving, rest) if not hit]
    if clear:
        return clear[0]
    free = [d for d, hit in _hits(product, moving, fixed) if not hit]
    if not free:
        raise SequenceError(f"{{{', '.join(sorted(moving))}}} cannot leave {{{', '.join(sorted(fixed))}}} along any "
                            "direction of the obstruction diagrams; the operation is not feasible")
    return free[0]


def exploded_view(plan: Plan, operations: list[int], spacing: float = 1.0,
                  base_part: str | None = None) -> ExplodedView:
    """The exploded view of a full assembly sequence (module docstring). ``spacing``: how far the first moving
    side sits away (say the product's bounding-box diagonal; the last one sits about twice as far). Raises
    :class:`SequenceError` when ``operations`` is not a full sequence of ``plan``. Cost: O(k E + k D B) for k
    operations."""
    visited = check_sequence(plan, operations)
    if visited[-1] != plan.states.final:
        raise SequenceError(f"the sequence stops at the state {plan.states.describe(visited[-1])}, before the "
                            "product is complete; give every operation of a full assembly sequence")
    steps = []
    for operation in operations:
        moving, fixed = moving_side(plan, operation, base_part)
        steps.append(ExplodedStep(int(operation), plan.andor.describe(operation), moving, fixed,
                                  free_direction(plan.product, moving, fixed)))
    parts = plan.andor.parts
    offsets = [{p: (0.0, 0.0, 0.0) for p in parts}]
    for j in range(len(steps) - 1, -1, -1):
        before, away = dict(offsets[0]), spacing * (1.0 + j / len(steps))
        for p in steps[j].moving:
            before[p] = tuple(a + away * c for a, c in zip(before[p], steps[j].direction.vector))
        offsets.insert(0, before)
    return ExplodedView(parts, tuple(steps), tuple(offsets), float(spacing))
