"""Bounding boxes, booleans that fail quietly now and then, and point classification, on OCCT solids."""
from __future__ import annotations

__all__ = ["bounding_box", "box_gap", "common_solid", "common_volume", "inner_points", "holds_any"]



def bounding_box(shape) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The tight bounding box (min corner, max corner) of ``shape``."""
    box = shape.optimalBoundingBox()  # (False, False) crashes FreeCAD 0.20.2 on copied shapes
    return (box.XMin, box.YMin, box.ZMin), (box.XMax, box.YMax, box.ZMax)


def box_gap(a, b) -> float:
    """Largest per-axis gap between boxes ``a`` and ``b`` (<= 0 when they overlap)."""
    return max(max(b[0][k] - a[1][k], a[0][k] - b[1][k]) for k in range(3))


def common_solid(a, b, fuzzies: tuple[float, ...], overlaps=None):
    """``a & b`` computed on copies (booleans raise their arguments' tolerances), for the first fuzzy value
    that gives a plausible answer: ``0 <= volume <= min(volumes)``, and not empty when ``overlaps()``
    (an independent test, by point classification) finds that they overlap. None when none does.

    OCCT's booleans fail quietly now and then: an empty common for a screw head against a door, or for a
    screw inside a prism (their cylinders 1e-8 rad apart).
    """
    bound = min(a.Volume, b.Volume)
    known = None
    for fuzzy in fuzzies:
        try:
            first, second = a.copy(), b.copy()
            common = first.common([second], fuzzy) if fuzzy else first.common(second)
            volume = common.Volume
        except Exception:  # OCCT failures surface as plain exceptions (also a null result's volume)
            continue
        if not -1e-9 * max(1.0, bound) <= volume <= bound * (1 + 1e-6) + 1e-9:
            continue
        if volume <= 0 and overlaps is not None:
            if known is None:
                known = overlaps()
            if known:
                continue
        return common
    return None


def common_volume(a, b, fuzzies: tuple[float, ...], overlaps=None) -> float | None:
    """Volume of ``a & b`` (see :func:`common_solid`), or None."""
    common = common_solid(a, b, fuzzies, overlaps)
    return None if common is None else max(common.Volume, 0.0)


def inner_points(shape, depth: float, limit: int = 40) -> list:
    """Points strictly inside ``shape``: its solids' centres of mass and points ``depth`` below the
    middle of its faces (those that fall inside), at most ``limit``."""
    candidates = [solid.CenterOfMass for solid in shape.Solids]
    for face in shape.Faces:
        u0, u1, v0, v1 = face.ParameterRange
        u, v = (u0 + u1) / 2, (v0 + v1) / 2
        try:
            if face.isPartOfDomain(u, v):
                candidates.append(face.valueAt(u, v) - face.normalAt(u, v) * depth)
        except Exception:  # a singular point
            continue
    points = []
    for point in candidates:
        if shape.isInside(point, 1e-7, False):
            points.append(point)
            if len(points) >= limit:
                break
    return points


def holds_any(solid, box, points, tolerance: float) -> bool:
    """True when one of ``points`` lies inside ``solid`` (whose box is ``box``), deeper than ``tolerance``."""
    lo, hi = box
    for point in points:
        if all(lo[k] < point[k] < hi[k] for k in range(3)) and solid.isInside(point, tolerance, False):
            return True
    return False
