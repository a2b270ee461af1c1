"""Designer tags per operation and the observation each operation gives (``m_Omega`` of Alg. 3).

Each operation of the AND/OR graph gets three tags: unfavorable to humans, robot-capable, and the tool it
needs. A tag in the product's ``operations`` list applies to the operation that joins exactly its two part
sets; untagged operations take the product's defaults (``single-part-rule``: unfavorable when exactly one
of the two inputs is a single part, the rule of the authors' code).

The *observation* of an operation is what the operator is seen picking from the parts tray: the inputs
that are single parts (one part extends a subassembly, two parts start one, none joins two subassemblies)
together with the tool. The *blank* observation (nothing picked) is what waiting looks like; an operation
that joins two subassemblies without a tool looks the same as waiting.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..product import Product
from .andor import AndOrGraph

__all__ = ["Observation", "BLANK", "OperationTags", "operation_tags", "observation_table"]


@dataclass(frozen=True, order=True)
class Observation:
    """The parts and tool the operator picks for one operation; ``BLANK`` when nothing is picked."""

    parts: tuple[str, ...] = ()
    tool: str | None = None

    def __str__(self) -> str:
        if self == BLANK:
            return "blank"
        return "+".join(list(self.parts) + ([f"[{self.tool}]"] if self.tool else []))


BLANK = Observation()


@dataclass(frozen=True)
class OperationTags:
    """Resolved tags, one entry per operation of the AND/OR graph.

    ``unmatched`` lists the indices (in ``product.operations``) of tags that match no operation of this
    AND/OR graph (for instance an operation removed by a technical constraint).
    """

    unfavorable: np.ndarray
    robot: np.ndarray
    tool: tuple[str | None, ...]
    unmatched: tuple[int, ...]


def operation_tags(andor: AndOrGraph, product: Product) -> OperationTags:
    """Resolve the designer tags of every operation of ``andor`` (explicit tags, else the defaults)."""
    by_inputs = {frozenset(tag.inputs): i for i, tag in enumerate(product.operations)}
    defaults = product.defaults
    count = len(andor.operations)
    unfavorable = np.zeros(count, dtype=bool)
    robot = np.zeros(count, dtype=bool)
    tools: list[str | None] = []
    used = set()
    for j in range(count):
        first, second = andor.inputs(j)
        k = by_inputs.get(frozenset((first, second)))
        tag = product.operations[k] if k is not None else None
        if k is not None:
            used.add(k)
        if tag is not None and tag.unfavorable is not None:
            unfavorable[j] = tag.unfavorable
        elif defaults.unfavorable == "single-part-rule":
            unfavorable[j] = (len(first) == 1) != (len(second) == 1)
        else:
            unfavorable[j] = defaults.unfavorable == "all"
        robot[j] = tag.robot if tag is not None and tag.robot is not None else defaults.robot
        tools.append(tag.tool if tag is not None and tag.tool is not None else defaults.tool)
    unmatched = tuple(k for k in range(len(product.operations)) if k not in used)
    return OperationTags(unfavorable, robot, tuple(tools), unmatched)


def observation_table(andor: AndOrGraph, tags: OperationTags) -> tuple[list[Observation], np.ndarray]:
    """The distinct observations (``BLANK`` first, then sorted) and each operation's observation index."""
    per_operation = []
    for j in range(len(andor.operations)):
        singles = sorted(next(iter(side)) for side in andor.inputs(j) if len(side) == 1)
        per_operation.append(Observation(tuple(singles), tags.tool[j]))
    others = sorted(set(per_operation) - {BLANK}, key=lambda o: (len(o.parts), o.parts, o.tool or ""))
    observations = [BLANK] + others
    position = {o: i for i, o in enumerate(observations)}
    return observations, np.array([position[o] for o in per_operation], dtype=np.int64)
