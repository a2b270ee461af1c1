"""Contacts (surfaces closer than the contact tolerance, or one part inside the other) and the overlap of
parts in contact."""
from __future__ import annotations

from .budget import PairClock, face_gap
from .solids import box_gap, common_solid, holds_any

__all__ = ["find_contacts"]


def _nested(inner, outer) -> bool:
    """True when ``inner`` lies inside ``outer`` (their surfaces being apart): test one vertex of it."""
    for vertex in inner.Vertexes[:1]:
        return outer.isInside(vertex.Point, 1e-7, True)
    return False


def find_contacts(ids, shapes, boxes, faces, points, contact: float, fuzzies, warnings: list[str],
                  clock: PairClock):
    """Contact pairs (i < j), and {(i, j) and (j, i): (volume, common solid)} for pairs that overlap.

    Pairs are decided cheaply first: part boxes farther apart than ``contact``, then face boxes
    (``faces[i]``, :func:`~.budget.face_boxes`) farther apart with neither part inside the other; only the
    rest are measured (``distToShape``, then ``common``), within ``clock``'s budget per pair: a pair out of
    time is counted as a contact without overlap and reported. ``points(j)``: points inside part j (to catch
    booleans that fail quietly)."""
    pairs, overlap = [], {}
    n = len(shapes)
    total, done = n * (n - 1) // 2, 0
    for i in range(n):
        for j in range(i + 1, n):
            done += 1
            clock.tick("contacts", done, total)
            if not clock.wanted(i, j):  # decided elsewhere (the mesh engine: freecad_aplan.hybrid)
                continue
            gap = box_gap(boxes[i], boxes[j])
            if gap > contact:
                clock.counts["far"] += 1
                continue
            apart = face_gap(faces[i], faces[j]) > contact  # the surfaces are
            nested = apart and gap < 0 and (_nested(shapes[i], shapes[j]) or _nested(shapes[j], shapes[i]))
            if apart and not nested:
                clock.counts["far_faces"] += 1
                continue
            clock.counts["exact"] += 1
            if clock.exhausted(i, j):
                clock.give_up(i, j, "the contact")
                pairs.append((i, j))
                continue
            clock.start(i, j)
            distance = 0.0 if nested else shapes[i].distToShape(shapes[j])[0]
            if distance > contact:
                # Apart, unless one lies inside the other (the surfaces never meet then).
                if gap < 0 and (_nested(shapes[i], shapes[j]) or _nested(shapes[j], shapes[i])):
                    distance = 0.0
                else:
                    clock.stop()
                    continue
            pairs.append((i, j))
            if distance <= contact * 1e-3:
                if clock.exhausted(i, j):
                    clock.give_up(i, j, "the overlap")
                    continue
                common = common_solid(shapes[i], shapes[j], fuzzies,
                                      lambda i=i, j=j: holds_any(shapes[i], boxes[i], points(j), fuzzies[-1]))
                if common is None:
                    warnings.append(f"OCCT cannot compute the overlap of {ids[i]!r} and {ids[j]!r}; "
                                    "counted as contact without overlap")
                elif common.Volume > 0:
                    overlap[i, j] = overlap[j, i] = (common.Volume, common)
            clock.stop()
    return pairs, overlap
