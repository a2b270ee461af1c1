"""Contacts (surfaces closer than the contact tolerance, or one part inside the other) and the overlap of
parts in contact."""
from __future__ import annotations

from .solids import box_gap, common_solid, holds_any

__all__ = ["find_contacts"]


def _nested(inner, outer) -> bool:
    """True when ``inner`` lies inside ``outer`` (their surfaces being apart): test one vertex of it."""
    for vertex in inner.Vertexes[:1]:
        return outer.isInside(vertex.Point, 1e-7, True)
    return False


def find_contacts(ids, shapes, boxes, points, contact: float, fuzzies, warnings: list[str]):
    """Contact pairs (i < j), and {(i, j) and (j, i): (volume, common solid)} for pairs that overlap.

    ``points(j)``: points inside part j (to catch booleans that fail quietly)."""
    pairs, overlap = [], {}
    n = len(shapes)
    for i in range(n):
        for j in range(i + 1, n):
            gap = box_gap(boxes[i], boxes[j])
            if gap > contact:
                continue
            distance = shapes[i].distToShape(shapes[j])[0]
            if distance > contact:
                # Apart, unless one lies inside the other (the surfaces never meet then).
                if gap < 0 and (_nested(shapes[i], shapes[j]) or _nested(shapes[j], shapes[i])):
                    distance = 0.0
                else:
                    continue
            pairs.append((i, j))
            if distance <= contact * 1e-3:
                common = common_solid(shapes[i], shapes[j], fuzzies,
                                      lambda i=i, j=j: holds_any(shapes[i], boxes[i], points(j), fuzzies[-1]))
                if common is None:
                    warnings.append(f"OCCT cannot compute the overlap of {ids[i]!r} and {ids[j]!r}; "
                                    "counted as contact without overlap")
                elif common.Volume > 0:
                    overlap[i, j] = overlap[j, i] = (common.Volume, common)
    return pairs, overlap
