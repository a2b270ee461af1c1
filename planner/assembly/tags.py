"""Designer tags per operation and the observation each operation gives (``m_Omega`` of Alg. 3).

Each operation of the AND/OR graph gets three tags: unfavorable to humans, robot-capable, and the tool it
needs. A tag in the product's ``operations`` list applies to the operation that joins exactly its two part
sets; untagged operations take the product's defaults (``single-part-rule``: unfavorable when exactly one
of the two inputs is a single part, the rule of the authors' code).

A folded fastener group (:mod:`planner.product.fasteners`) is installed by every operation that first brings
all its hosts together (:func:`fastener_installs`); such an operation needs the group's tool (an explicit
operation tag still wins).

The *observation* of an operation is what the operator is seen picking from the parts tray: the inputs
that are single parts (one part extends a subassembly, two parts start one, none joins two subassemblies)
and the fasteners it installs, together with the tool. The *blank* observation (nothing picked) is what
waiting looks like; an operation that joins two subassemblies without a tool or fasteners looks the same as
waiting.

The *join* observation of an operation (:func:`join_observation_table`, ``--observe join``) is what a camera
that also sees the pieces being joined reports: the same loose parts, fasteners and tool, and the parts of each
input that is a subassembly (``pieces``). Two operations never share it (an operation is its two inputs), so it
names the operation.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..product import FastenerGroup, Product
from .andor import AndOrGraph

__all__ = ["Observation", "BLANK", "OperationTags", "fastener_installs", "operation_tags", "observation_table",
           "join_observation_table"]


@dataclass(frozen=True, order=True)
class Observation:
    """The parts and tool the operator picks for one operation; ``BLANK`` when nothing is picked. ``pieces``:
    the parts of each subassembly the operation joins, in a join observation only (module docstring)."""

    parts: tuple[str, ...] = ()
    tool: str | None = None
    pieces: tuple[tuple[str, ...], ...] = ()

    def __str__(self) -> str:
        if self == BLANK:
            return "blank"
        pieces = ["{" + " ".join(piece) + "}" for piece in self.pieces]
        return "+".join(pieces + list(self.parts) + ([f"[{self.tool}]"] if self.tool else []))


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


def _children(andor: AndOrGraph) -> tuple[np.ndarray, np.ndarray]:
    """The two children (subassembly indices) of every operation."""
    count = len(andor.operations)
    first = np.fromiter((op.children[0] for op in andor.operations), dtype=np.int64, count=count)
    second = np.fromiter((op.children[1] for op in andor.operations), dtype=np.int64, count=count)
    return first, second


def _single_part(andor: AndOrGraph) -> np.ndarray:
    """Per subassembly: the index of its part when it is a single part, else -1."""
    return np.fromiter(((m.bit_length() - 1) if m & (m - 1) == 0 else -1 for m in andor.subassemblies),
                       dtype=np.int64, count=len(andor.subassemblies))


def _tagged(andor: AndOrGraph, product: Product) -> dict[int, int]:
    """Operation index -> index in ``product.operations`` of the tag that names exactly its two inputs."""
    index = {p: i for i, p in enumerate(andor.parts)}
    parents = np.fromiter((op.parent for op in andor.operations), dtype=np.int64, count=len(andor.operations))
    found = {}
    for k, tag in enumerate(product.operations):
        if not all(p in index for side in tag.inputs for p in side):
            continue
        a, b = (sum(1 << index[p] for p in side) for side in tag.inputs)
        parent = andor.index.get(a | b)
        if parent is None or a & b:
            continue
        lo, hi = np.searchsorted(parents, [parent, parent + 1])  # operations are ordered by parent
        for j in range(int(lo), int(hi)):
            first, second = (andor.subassemblies[c] for c in andor.operations[j].children)
            if {first, second} == {a, b}:
                found.setdefault(j, k)
    return found


def _masks(values, parts: int) -> np.ndarray:
    """Part bitmasks as a numpy array: int64 when they fit, else Python integers (object)."""
    return np.array(list(values), dtype=np.int64 if parts < 63 else object)


def fastener_installs(andor: AndOrGraph, groups: tuple[FastenerGroup, ...]) -> tuple[np.ndarray, ...]:
    """Per fastener group, the indices of the operations that install it: those with inputs ``L``, ``R`` such
    that the group's hosts ``H <= L | R`` and neither ``H <= L`` nor ``H <= R`` (they first bring all its hosts
    together). A group whose hosts are not all parts of ``andor`` is installed by no operation.

    Cost: O(groups x operations) in numpy.
    """
    if not groups:
        return ()
    index = {p: i for i, p in enumerate(andor.parts)}
    count = len(andor.parts)
    subassemblies = _masks(andor.subassemblies, count)
    first, second = _children(andor)
    left, right = subassemblies[first], subassemblies[second]
    union = left | right
    installs = []
    for group in groups:
        if not all(h in index for h in group.hosts):
            installs.append(np.zeros(0, dtype=np.int64))
            continue
        hosts = _masks([sum(1 << index[h] for h in group.hosts)], count)[0]
        joins = ((union & hosts) == hosts) & ((left & hosts) != hosts) & ((right & hosts) != hosts)
        installs.append(np.flatnonzero(joins).astype(np.int64))
    return tuple(installs)


def operation_tags(andor: AndOrGraph, product: Product, groups: tuple[FastenerGroup, ...] = (),
                   installs: tuple[np.ndarray, ...] = ()) -> OperationTags:
    """Resolve the designer tags of every operation of ``andor``: explicit tags, else the tool of the fastener
    groups it installs (``installs``: :func:`fastener_installs` of ``groups``; the first group's that has one),
    else the defaults.

    Cost: O(operations) in numpy, plus O(tags x operations of the tagged subassembly).
    """
    defaults = product.defaults
    count = len(andor.operations)
    first, second = _children(andor)
    single = _single_part(andor) >= 0
    if defaults.unfavorable == "single-part-rule":
        unfavorable = single[first] != single[second]
    else:
        unfavorable = np.full(count, defaults.unfavorable == "all")
    robot = np.full(count, bool(defaults.robot))
    tools: list[str | None] = [defaults.tool] * count
    for group, operations in reversed(list(zip(groups, installs))):  # reversed: the first group's tool wins
        if group.tool is not None:
            for j in operations.tolist():
                tools[j] = group.tool
    tagged = _tagged(andor, product)
    for j, k in tagged.items():
        tag = product.operations[k]
        if tag.unfavorable is not None:
            unfavorable[j] = tag.unfavorable
        if tag.robot is not None:
            robot[j] = tag.robot
        if tag.tool is not None:
            tools[j] = tag.tool
    used = set(tagged.values())
    unmatched = tuple(k for k in range(len(product.operations)) if k not in used)
    return OperationTags(unfavorable, robot, tuple(tools), unmatched)


def observation_table(andor: AndOrGraph, tags: OperationTags, groups: tuple[FastenerGroup, ...] = (),
                      installs: tuple[np.ndarray, ...] = ()) -> tuple[list[Observation], np.ndarray]:
    """The distinct observations (``BLANK`` first, then sorted) and each operation's observation index.

    An operation's observation holds its single-part inputs and the parts of the fastener groups it installs
    (``installs``: :func:`fastener_installs` of ``groups``), and its tool.

    Cost: O(operations log operations) in numpy (the distinct (single parts, fasteners, tool) keys are found by
    one sort), plus O(operations) per fastener group.
    """
    count = len(andor.operations)
    if count == 0:
        return [BLANK], np.zeros(0, dtype=np.int64)
    first, second = _children(andor)
    single = _single_part(andor)
    tool_names = sorted({t for t in tags.tool if t is not None})
    tool_code = {None: -1, **{t: i for i, t in enumerate(tool_names)}}
    fastened, fastener_sets = _fastener_codes(count, groups, installs)
    keys = np.stack([single[first], single[second], np.fromiter((tool_code[t] for t in tags.tool), dtype=np.int64,
                                                                  count=count), fastened], axis=1)
    distinct, inverse = np.unique(keys, axis=0, return_inverse=True)
    per_key = []
    for a, b, tool, fasteners in distinct.tolist():
        singles = sorted([andor.parts[i] for i in (a, b) if i >= 0] + list(fastener_sets[fasteners]))
        per_key.append(Observation(tuple(singles), None if tool < 0 else tool_names[tool]))
    others = sorted(set(per_key) - {BLANK}, key=lambda o: (len(o.parts), o.parts, o.tool or ""))
    observations = [BLANK] + others
    position = {o: i for i, o in enumerate(observations)}
    lookup = np.array([position[o] for o in per_key], dtype=np.int64)
    return observations, lookup[np.asarray(inverse).reshape(-1)]


def join_observation_table(andor: AndOrGraph, tags: OperationTags, groups: tuple[FastenerGroup, ...] = (),
                           installs: tuple[np.ndarray, ...] = ()) -> tuple[list[Observation], np.ndarray]:
    """:func:`observation_table` for a camera that also sees the pieces joined: ``BLANK``, then one observation
    per operation in operation order (its :func:`observation_table` observation with the parts of each input
    that is a subassembly as ``pieces``), and ``operation j -> j + 1``. Cost: O(operations x parts)."""
    observations, seen = observation_table(andor, tags, groups, installs)
    single = _single_part(andor)
    joined = [BLANK]
    for j, operation in enumerate(andor.operations):
        base = observations[seen[j]]
        pieces = tuple(sorted(tuple(sorted(andor.parts_of(c))) for c in operation.children if single[c] < 0))
        joined.append(Observation(base.parts, base.tool, pieces))
    return joined, np.arange(1, len(andor.operations) + 1, dtype=np.int64)


def _fastener_codes(count: int, groups: tuple[FastenerGroup, ...],
                    installs: tuple[np.ndarray, ...]) -> tuple[np.ndarray, list[tuple[str, ...]]]:
    """Per operation, the number of the set of fastener parts it installs, and those sets (by number).

    Each operation's groups are a bitmask (bit ``k``: group ``k``), numbered by one sort. Cost: O(operations
    log operations) in numpy."""
    bits = np.zeros(count, dtype=np.int64 if len(installs) < 63 else object)
    for k, operations in enumerate(installs):
        bits[operations] |= 1 << k
    distinct, codes = np.unique(bits, return_inverse=True)
    names = [tuple(p for k, group in enumerate(groups) if (int(b) >> k) & 1 for p in group.parts)
             for b in distinct.tolist()]
    return np.asarray(codes, dtype=np.int64).reshape(-1), names
