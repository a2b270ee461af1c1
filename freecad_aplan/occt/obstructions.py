"""Obstruction diagrams: for each axis, the pairs (x, y) such that x swept along the axis takes volume from
y, with the verdict of each boolean confirmed by the cross-checks OCCT needs."""
from __future__ import annotations

import FreeCAD

from planner.product import AXIS_DIRECTIONS

from .budget import PairClock, sweep_meets
from .prisms import sweep_prisms
from .solids import common_volume

__all__ = ["AXES", "find_obstructions"]

AXES = ("+X", "+Y", "+Z")


def find_obstructions(ids, shapes, boxes, faces, overlap, contact: float, depth: float, fuzzies,
                      warnings: list[str], clock: PairClock):
    """Per axis, the pairs (i, j): part i moving along the axis collides with part j.

    Candidates are the pairs whose boxes meet along the sweep, then whose face boxes do
    (:func:`~.budget.sweep_meets`). Each candidate pair is worked on within ``clock``'s budget for its two
    parts (contacts included); a pair out of time is counted as blocking and reported."""
    scene_hi = [max(b[1][k] for b in boxes) for k in range(3)]
    volume_tolerance = depth ** 3
    result = {}
    for axis, name in enumerate(AXES):
        d = FreeCAD.Vector(*AXIS_DIRECTIONS[name])
        across = [k for k in range(3) if k != axis]
        pairs = []
        for i, (lo, hi) in enumerate(boxes):
            clock.tick(f"obstructions {name}", i + 1, len(boxes))
            candidates = [j for j, (lo2, hi2) in enumerate(boxes) if j != i
                          and all(min(hi[k], hi2[k]) - max(lo[k], lo2[k]) > contact for k in across)
                          and hi2[axis] > lo[axis] + depth]
            clock.counts["sweep_candidates"] += len(candidates)
            candidates = [j for j in candidates if sweep_meets(faces[i], faces[j], axis, contact, depth)]
            clock.counts["sweep_exact"] += len(candidates)
            if not candidates:
                continue
            length = scene_hi[axis] - lo[axis] + 1.0
            prisms, meshed = sweep_prisms(shapes[i], d, length, contact / 2, contact * 1e-3)
            if meshed:
                warnings.append(f"part {ids[i]!r}: {meshed} face piece(s) swept along {name} as triangles within "
                                f"{contact / 2:g} (no exact silhouette, or OCCT could not build their prism)")
            for j in candidates:
                if clock.exhausted(i, j):
                    clock.give_up(i, j, f"{ids[i]} moving along {name}")
                    pairs.append((i, j))
                    continue
                clock.start(i, j)
                verdict = _blocks(prisms, shapes[j], boxes[j], overlap.get((i, j)), axis, volume_tolerance,
                                  fuzzies, lambda i=i, j=j: clock.exhausted(i, j))
                if verdict == "late":
                    clock.give_up(i, j, f"{ids[i]} moving along {name}")
                    pairs.append((i, j))
                    continue
                clock.stop()
                if verdict is None:
                    warnings.append(f"{name}: OCCT cannot tell whether {ids[i]!r} moving along {name} hits "
                                    f"{ids[j]!r}; assumed it does")
                if verdict is not False:
                    pairs.append((i, j))
        result[name] = sorted(pairs)
    return result


def _blocks(prisms, other, other_box, shared, axis: int, volume_tolerance: float, fuzzies,
            late=lambda: False) -> bool | None | str:
    """True when one of the prisms takes more than ``volume_tolerance`` of ``other`` outside ``shared``
    (the (volume, solid) the moving part already shares with it); None when no prism decided because
    booleans failed; ``"late"`` when ``late()`` said the time was up before a prism was tested."""
    lo, hi = other_box
    unsure = False
    for prism in prisms:
        plo, phi = prism.box
        if phi[axis] <= lo[axis] or any(min(phi[k], hi[k]) - max(plo[k], lo[k]) <= 0 for k in range(3) if k != axis):
            continue
        if late():
            return "late"
        verdict = _prism_blocks(prism, other, other_box, shared, axis, volume_tolerance, fuzzies)
        if verdict:
            return True
        unsure = unsure or verdict is None
    return None if unsure else False


def _gained(solid, other, shared, fuzzy: float) -> float | None:
    """Volume of ``solid & other`` outside ``shared`` (or None when a boolean fails)."""
    volume = common_volume(solid, other, (fuzzy,))
    if volume is not None and shared and volume > 0:
        inside = common_volume(solid, shared[1], (fuzzy,))
        volume = None if inside is None else volume - inside
    return volume


def _prism_blocks(prism, other, other_box, shared, axis: int, volume_tolerance: float, fuzzies) -> bool | None:
    """Whether ``prism`` takes more than ``volume_tolerance`` of ``other`` outside ``shared``.

    OCCT's booleans fail quietly now and then: an empty common for a door moving onto its screws, or for a
    screw inside a prism, their cylinders 1e-8 rad apart. So a volume is positive evidence, and an empty
    result needs agreement: the prism built two ways (along the face's axis and along ``d``) times two
    fuzzy values, then rays from the face through ``other`` (point classification, no boolean). Only when
    every exact boolean fails does the tessellated prism decide.
    """
    empty = False
    for solid in prism.exact():
        for fuzzy in fuzzies[:2]:
            gained = _gained(solid, other, shared, fuzzy)
            if gained is None:
                continue
            if gained > volume_tolerance:
                return True
            empty = True
    rays = not shared and _ray_hits(prism, other, other_box, axis, fuzzies[-1])
    if empty or rays:
        return rays
    meshed = prism.meshed()
    gained = None if meshed is None else _gained(meshed, other, shared, fuzzies[0])
    return None if gained is None else gained > volume_tolerance


def _ray_hits(prism, other, other_box, axis: int, tolerance: float, steps: int = 4) -> bool:
    """True when a ray along the sweep from a sample point of the prism's face (away from its edges)
    passes through the inside of ``other``, deeper than ``tolerance`` (``steps`` points per ray, spread over
    ``other``'s box): then the prism and ``other`` overlap, whatever a boolean says."""
    lo, hi = other_box
    across = [k for k in range(3) if k != axis]
    for start in prism.points:
        if not all(lo[k] < start[k] < hi[k] for k in across):
            continue
        begin = max(lo[axis], start[axis])
        if begin >= hi[axis]:
            continue
        for step in range(steps):
            position = begin + (hi[axis] - begin) * (step + 0.5) / steps
            point = FreeCAD.Vector(start)
            point[axis] = position
            if other.isInside(point, tolerance, False):
                return True
    return False
