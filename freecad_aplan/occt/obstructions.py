"""Obstruction diagrams: for each axis (and each other direction asked for), the pairs (x, y) such that x swept
along it takes volume from y, with the verdict of each boolean confirmed by the cross-checks OCCT needs."""
from __future__ import annotations

import FreeCAD
import numpy as np

from planner.product import AXIS_DIRECTIONS

from .budget import PairClock, sweep_meets
from .frames import direction_frame, frame_boxes
from .prisms import SweepStopped, SweepTooLarge, sweep_prisms
from .solids import common_volume

__all__ = ["AXES", "find_obstructions"]

AXES = ("+X", "+Y", "+Z")


def find_obstructions(ids, shapes, boxes, faces, overlap, contact: float, depth: float, fuzzies,
                      warnings: list[str], clock: PairClock, directions=(), prism_triangles: int | None = None,
                      over: list | None = None, lost: list | None = None):
    """Per direction (the axes, then ``directions``: (name, unit vector) pairs), the pairs (i, j): part i
    moving along it collides with part j.

    Candidates are the pairs whose boxes meet along the sweep, then whose face boxes do
    (:func:`~.budget.sweep_meets`), both seen in the frame of the direction (:func:`~.frames.frame_boxes`:
    exact along an axis, a box around the box along another direction, so no pair that could block is
    dropped). Each candidate pair is worked on within ``clock``'s budget for its two parts (contacts
    included); a pair out of time is counted as blocking and reported. A candidate with a heavy part
    (``clock.heavy``) is undecided before any prism is built; a sweep with a face of more than
    ``prism_triangles`` triangles (:class:`~.prisms.SweepTooLarge`) leaves every candidate of its part along
    that direction undecided, appended to ``over`` as (i, name, triangles); so does a sweep that lost a face
    (a piece OCCT could not sweep, neither exactly nor as triangles: a closed B-spline patch), appended to
    ``lost`` as (i, name, pieces), since a sweep with a hole cannot show that a pair is free; the time limit
    is checked between the faces of a sweep too."""
    volume_tolerance = depth ** 3
    result = {}
    tested = [(name, AXIS_DIRECTIONS[name]) for name in AXES] + list(directions)
    part_boxes = np.array(boxes, dtype=float).reshape(-1, 2, 3)
    for name, vector in tested:
        frame = direction_frame(vector)
        d = FreeCAD.Vector(*(float(c) for c in frame[2]))
        turned = frame_boxes(part_boxes, frame)
        turned_faces = [frame_boxes(f, frame) for f in faces]
        scene_hi = float(turned[:, 1, 2].max())
        pairs = []
        for i, (lo, hi) in enumerate(turned):
            clock.tick(f"obstructions {name}", i + 1, len(boxes))
            candidates = [j for j, (lo2, hi2) in enumerate(turned) if j != i and clock.wanted(i, j)
                          and all(min(hi[k], hi2[k]) - max(lo[k], lo2[k]) > contact for k in (0, 1))
                          and hi2[2] > lo[2] + depth]
            clock.counts["sweep_candidates"] += len(candidates)
            candidates = [j for j in candidates if sweep_meets(turned_faces[i], turned_faces[j], 2, contact, depth)]
            clock.counts["sweep_exact"] += len(candidates)
            for j in [j for j in candidates if clock.too_heavy(i, j)]:  # no call on them, not even a sweep
                clock.give_up(i, j, f"{ids[i]} moving along {name}")
                pairs.append((i, j))
            candidates = [j for j in candidates if not clock.too_heavy(i, j)]
            if not candidates:
                continue
            if clock.out_of_time():  # no prisms built: every candidate left is undecided
                for j in candidates:
                    clock.give_up(i, j, f"{ids[i]} moving along {name}")
                    pairs.append((i, j))
                continue
            length = scene_hi - float(lo[2]) + 1.0
            try:
                prisms, meshed = sweep_prisms(shapes[i], d, length, contact / 2, contact * 1e-3, prism_triangles,
                                              clock.out_of_time)
            except SweepStopped:  # the time limit passed while the sweep was built
                for j in candidates:
                    clock.give_up(i, j, f"{ids[i]} moving along {name}")
                    pairs.append((i, j))
                continue
            except SweepTooLarge as too_large:
                reason = (f"the sweep of {ids[i]!r} along {name} needs a face swept as {too_large.triangles:,} "
                          f"triangles, over the bound of {prism_triangles:,}")
                if over is not None:
                    over.append((i, name, too_large.triangles))
                for j in candidates:
                    clock.give_up(i, j, f"{ids[i]} moving along {name}", reason)
                    pairs.append((i, j))
                continue
            if meshed:
                warnings.append(f"part {ids[i]!r}: {meshed} face piece(s) swept along {name} as triangles within "
                                f"{contact / 2:g} (no exact silhouette, or OCCT could not build their prism)")
            missing = meshed - sum(1 for prism in prisms if not prism.exact_built)
            if missing:  # e.g. a closed B-spline face (a sphere, a torus as NURBS): the sweep has a hole, so a
                # "free" from it proves nothing: every candidate is undecided (the mesh answer, or blocking)
                reason = (f"the sweep of {ids[i]!r} along {name} lost {missing} face piece(s) that OCCT could not "
                          "sweep, neither exactly nor as triangles")
                if lost is not None:
                    lost.append((i, name, missing))
                for j in candidates:
                    clock.give_up(i, j, f"{ids[i]} moving along {name}", reason)
                    pairs.append((i, j))
                continue
            for j in candidates:
                if clock.exhausted(i, j):
                    clock.give_up(i, j, f"{ids[i]} moving along {name}")
                    pairs.append((i, j))
                    continue
                clock.start(i, j)
                verdict = _blocks(prisms, shapes[j], turned[j], overlap.get((i, j)), frame, volume_tolerance,
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


def _blocks(prisms, other, other_box, shared, frame, volume_tolerance: float, fuzzies,
            late=lambda: False) -> bool | None | str:
    """True when one of the prisms takes more than ``volume_tolerance`` of ``other`` outside ``shared``
    (the (volume, solid) the moving part already shares with it); None when no prism decided because
    booleans failed; ``"late"`` when ``late()`` said the time was up before a prism was tested.
    ``other_box`` is ``other``'s box in the coordinates of ``frame`` (rows u, v, d:
    :func:`~.frames.frame_boxes`)."""
    lo, hi = other_box
    unsure = False
    for prism in prisms:
        plo, phi = frame_boxes(np.array(prism.box, dtype=float), frame)[0]
        if phi[2] <= lo[2] or any(min(phi[k], hi[k]) - max(plo[k], lo[k]) <= 0 for k in (0, 1)):
            continue
        if late():
            return "late"
        verdict = _prism_blocks(prism, other, other_box, shared, frame, volume_tolerance, fuzzies)
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


def _prism_blocks(prism, other, other_box, shared, frame, volume_tolerance: float, fuzzies) -> bool | None:
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
    rays = not shared and _ray_hits(prism, other, other_box, frame, fuzzies[-1])
    if empty or rays:
        return rays
    meshed = prism.meshed()
    gained = None if meshed is None else _gained(meshed, other, shared, fuzzies[0])
    return None if gained is None else gained > volume_tolerance


def _ray_hits(prism, other, other_box, frame, tolerance: float, steps: int = 4) -> bool:
    """True when a ray along the sweep from a sample point of the prism's face (away from its edges)
    passes through the inside of ``other``, deeper than ``tolerance`` (``steps`` points per ray, spread over
    ``other``'s box ``other_box``, in the coordinates of ``frame``: rows u, v, d): then the prism and
    ``other`` overlap, whatever a boolean says."""
    lo, hi = other_box
    d = FreeCAD.Vector(*(float(c) for c in frame[2]))
    for start in prism.points:
        local = frame @ np.array([start.x, start.y, start.z])
        if not all(lo[k] < local[k] < hi[k] for k in (0, 1)):
            continue
        begin = max(lo[2], local[2])
        if begin >= hi[2]:
            continue
        for step in range(steps):
            position = begin + (hi[2] - begin) * (step + 0.5) / steps
            point = FreeCAD.Vector(start) + d * float(position - local[2])
            if other.isInside(point, tolerance, False):
                return True
    return False
