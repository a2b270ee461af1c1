"""Gaps between the groups of a connection diagram that falls apart, and the contact tolerance that joins them.

Definitions
-----------
- The *gap* between two parts is the smallest distance between their surfaces (their closed triangle meshes);
  0 when they touch or cross.
- The *groups* are the connected components of the connection diagram (parts joined by a chain of contacts).
- A group's *nearest gap* is the smallest gap between one of its parts and a part of another group: the
  contact tolerance that joins the group to the rest.
- The *joining gaps* are the edges of a minimum spanning tree over the groups (Kruskal on the part gaps); the
  largest of them, the *bottleneck*, is the smallest contact tolerance that makes the diagram connected.

Method
------
Pairs of parts in different groups are visited in increasing order of their gap, lazily: every pair first
enters a priority queue keyed by the distance between the bounding boxes (a lower bound of the gap); the
exact gap is computed only when a pair reaches the front of the queue, and the pair re-enters with it. A pair
leaving the queue with its exact gap is the smallest gap not seen yet. The visit stops when every group has
its nearest gap and the groups are joined, so the exact gap is computed only for pairs whose boxes are
closer than the bottleneck. Exact gaps come from FCL (python-fcl: bounding-volume hierarchies over the
triangles, exact triangle-triangle distance in double precision): the distance between the meshes, which
lie within the tessellation's linear deflection of the B-rep surfaces (so the gap between the B-reps is within
twice the deflection of it; exact for planar faces).
"""
from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import GeometryError
from .meshes import PartMesh

__all__ = ["Gap", "GapReport", "connection_groups", "mesh_gaps", "gap_report", "contact_tolerance_for",
           "part_gaps", "fcl_available"]


@dataclass(frozen=True)
class Gap:
    """The gap ``distance`` between part ``a`` and part ``b`` (model units)."""

    a: str
    b: str
    distance: float

    def as_list(self) -> list:
        return [self.a, self.b, round(self.distance, 6)]


@dataclass(frozen=True)
class GapReport:
    """The groups of a connection diagram, the nearest gap of each (``nearest[k]``: its part first, then the
    other group's part), the joining gaps (a minimum spanning tree over the groups, in increasing order) and
    the exact gaps visited (``visited``, in increasing order: enough to recompute the report)."""

    groups: tuple[tuple[str, ...], ...]
    nearest: tuple[Gap, ...]
    joining: tuple[Gap, ...]
    visited: tuple[Gap, ...] = ()
    queries: int = 0

    @property
    def bottleneck(self) -> float:
        """The smallest contact tolerance that connects the diagram (0 when it is connected)."""
        return max((g.distance for g in self.joining), default=0.0)

    def group_of(self, part: str) -> int:
        return next(k for k, group in enumerate(self.groups) if part in group)

    def as_dict(self) -> dict:
        return {"groups": [list(g) for g in self.groups], "nearest": [g.as_list() for g in self.nearest],
                "joining": [g.as_list() for g in self.joining], "tolerance": contact_tolerance_for(self.bottleneck)}


def connection_groups(parts: list[str] | tuple[str, ...], contacts) -> list[list[str]]:
    """The connected components of the connection diagram, each in the order of ``parts``, ordered by their
    first part. Cost: O(parts + contacts) (union-find)."""
    parent = {p: p for p in parts}

    def root(p: str) -> str:
        while parent[p] != p:
            parent[p] = parent[parent[p]]
            p = parent[p]
        return p

    for a, b in contacts:
        parent[root(a)] = root(b)
    groups: dict[str, list[str]] = {}
    for p in parts:
        groups.setdefault(root(p), []).append(p)
    return list(groups.values())


def contact_tolerance_for(gap: float) -> float:
    """The contact tolerance to give for ``gap``: the gap rounded up to three significant digits, and strictly
    above it (``--contact 6.16`` for a gap of 6.1595), so that the engines' test ``gap <= tolerance`` holds
    with room for rounding."""
    if gap <= 0:
        return 0.0
    step = 10.0 ** (math.floor(math.log10(gap)) - 2)
    return round(math.floor(gap / step + 1) * step, 12)


def gap_report(groups: list[list[str]], gaps) -> GapReport:
    """The report of ``groups`` from part gaps (``(a, b, distance)`` triples or :class:`Gap`s, e.g. those a
    bundle recorded): each group's nearest gap and a minimum spanning tree over the groups (Kruskal).
    Pairs inside one group are ignored. When the gaps do not join every group, ``joining`` joins what they
    can and a group without any gap has ``nearest`` None. Cost: O(gaps log gaps)."""
    gaps = sorted((g if isinstance(g, Gap) else Gap(str(g[0]), str(g[1]), float(g[2])) for g in gaps),
                  key=lambda g: g.distance)
    home = {p: k for k, group in enumerate(groups) for p in group}
    gaps = [g for g in gaps if g.a in home and g.b in home and home[g.a] != home[g.b]]
    nearest: list[Gap | None] = [None] * len(groups)
    parent = list(range(len(groups)))

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    joining = []
    for gap in gaps:
        ka, kb = home[gap.a], home[gap.b]
        if nearest[ka] is None:
            nearest[ka] = gap
        if nearest[kb] is None:
            nearest[kb] = Gap(gap.b, gap.a, gap.distance)
        ra, rb = root(ka), root(kb)
        if ra != rb:
            parent[ra] = rb
            joining.append(gap)
    return GapReport(tuple(tuple(g) for g in groups), tuple(nearest), tuple(joining), tuple(gaps))


def fcl_available() -> bool:
    """True when python-fcl can be imported (FreeCAD's own Python may lack it)."""
    import importlib.util

    try:
        return importlib.util.find_spec("fcl") is not None
    except (ImportError, ValueError):  # a finder that refuses it (an import hook, a broken install)
        return False


def _bvh(part: PartMesh):
    try:
        import fcl
    except ImportError:  # a dependency of the project: an incomplete installation
        raise GeometryError("measuring gaps between parts needs python-fcl: pip install python-fcl "
                            "(or reinstall APLAN: pip install -e .)") from None
    model = fcl.BVHModel()
    model.beginModel(len(part.vertices), len(part.faces))
    model.addSubModel(np.ascontiguousarray(part.vertices, dtype=np.float64),
                      np.ascontiguousarray(part.faces, dtype=np.int32))
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


def _gap(first, second) -> float:
    import fcl

    return max(float(fcl.distance(first, second, fcl.DistanceRequest(), fcl.DistanceResult())), 0.0)


def part_gaps(parts: list[PartMesh], pairs, objects: dict | None = None) -> dict[tuple[str, str], float]:
    """The exact gap of each pair of part ids in ``pairs`` (FCL). Cost: one BVH per part named (kept in
    ``objects`` when given, for later calls), and a branch-and-bound distance query per pair (sub-millisecond
    for meshes of 10^4 triangles)."""
    index = {p.id: p for p in parts}
    objects = {} if objects is None else objects
    result = {}
    for a, b in pairs:
        for name in (a, b):
            if name not in objects:
                objects[name] = _bvh(index[name])
        result[a, b] = _gap(objects[a], objects[b])
    return result


def _box_distances(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n, n) Euclidean distance between the axis-aligned bounding boxes: a lower bound of the gap."""
    apart = np.maximum(0.0, np.maximum(lo[:, None, :] - hi[None, :, :], lo[None, :, :] - hi[:, None, :]))
    return np.sqrt((apart ** 2).sum(axis=2))


def mesh_gaps(parts: list[PartMesh], contacts) -> GapReport:
    """The groups of the connection diagram ``contacts`` over ``parts``, each group's nearest gap and the
    joining gaps, from the meshes (see the module's method).

    Returns a report with one group (nothing to join) when the diagram is connected. Cost: O(n^2) box
    distances and heap entries for n parts, plus one exact distance query per pair whose boxes are closer
    than the bottleneck; the report's ``queries`` says how many were computed.
    """
    ids = [p.id for p in parts]
    groups = connection_groups(ids, contacts)
    if len(groups) < 2:
        return GapReport(tuple(tuple(g) for g in groups), (None,) * len(groups), ())
    home = {p: k for k, group in enumerate(groups) for p in group}
    lo = np.array([p.vertices.min(axis=0) for p in parts])
    hi = np.array([p.vertices.max(axis=0) for p in parts])
    bound = _box_distances(lo, hi)
    queue = [(float(bound[i, j]), False, i, j) for i in range(len(parts)) for j in range(i + 1, len(parts))
             if home[ids[i]] != home[ids[j]]]
    heapq.heapify(queue)
    objects: dict[int, object] = {}
    seen: list[Gap] = []
    missing = set(range(len(groups)))  # groups without their nearest gap yet
    parent = list(range(len(groups)))
    joined = 1
    queries = 0

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    while queue and (missing or joined < len(groups)):
        key, exact, i, j = heapq.heappop(queue)
        if not exact:
            for k in (i, j):
                if k not in objects:
                    objects[k] = _bvh(parts[k])
            heapq.heappush(queue, (_gap(objects[i], objects[j]), True, i, j))
            queries += 1
            continue
        seen.append(Gap(ids[i], ids[j], key))
        ka, kb = home[ids[i]], home[ids[j]]
        missing -= {ka, kb}
        ra, rb = root(ka), root(kb)
        if ra != rb:
            parent[ra] = rb
            joined += 1
    return replace(gap_report(groups, seen), queries=queries)
