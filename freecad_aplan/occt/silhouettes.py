"""Where the normal of a face turns across a direction (its silhouette seen along it), and the faces that cut
a face there, so that each piece projects one-to-one along the direction and can be swept into a prism."""
from __future__ import annotations

import math

import FreeCAD
import Part

__all__ = ["facing", "revolution_axis", "silhouette_cutters", "split_face"]

_SAMPLES = 13  # samples per parameter direction when checking where a face's normal turns


def _face_samples(face, samples: int = _SAMPLES):
    """(u, v) parameters spread over ``face`` (its boundary parameters included), inside its domain; a
    finer grid when a narrow face holds none of the first."""
    u0, u1, v0, v1 = face.ParameterRange
    for n in (samples, 4 * samples):
        out = []
        for a in range(n):
            u = u0 + (u1 - u0) * (a + 1e-6 if a == 0 else a - 1e-6 if a == n - 1 else a) / (n - 1)
            for b in range(n):
                v = v0 + (v1 - v0) * (b + 1e-6 if b == 0 else b - 1e-6 if b == n - 1 else b) / (n - 1)
                if face.isPartOfDomain(u, v):
                    out.append((u, v))
        if out:
            return out
    return out


def facing(face, d) -> tuple[float, float]:
    """Smallest and largest ``normal . d`` over samples of ``face`` (outward normals); (-1, 1), as if it
    folded, when no sample could be taken. A plane has one normal: no samples (most faces of real parts are
    planes; sampling them took a fifth of the truck's analysis)."""
    if isinstance(face.Surface, Part.Plane):
        u0, u1, v0, v1 = face.ParameterRange
        value = face.normalAt((u0 + u1) / 2, (v0 + v1) / 2).dot(d)
        return value, value
    low, high = math.inf, -math.inf
    for u, v in _face_samples(face):
        try:
            value = face.normalAt(u, v).dot(d)
        except Exception:  # a singular point (the apex of a cone, the pole of a sphere)
            continue
        low, high = min(low, value), max(high, value)
    return (low, high) if low <= high else (-1.0, 1.0)


def _plane(point, normal, size: float):
    """A square planar face of side ``2 * size`` through ``point``, perpendicular to ``normal``."""
    normal = FreeCAD.Vector(normal).normalize()
    helper = FreeCAD.Vector(1, 0, 0) if abs(normal.x) < 0.9 else FreeCAD.Vector(0, 1, 0)
    first = normal.cross(helper).normalize()
    second = normal.cross(first).normalize()
    corners = [point + first * (sx * size) + second * (sy * size) for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return Part.Face(Part.makePolygon(corners + corners[:1]))


def _tube(centre, axis, radius: float, size: float):
    """A cylindrical face of ``radius`` around the line (``centre``, ``axis``), ``size`` long each way."""
    axis = FreeCAD.Vector(axis).normalize()
    return Part.makeCylinder(radius, 2 * size, centre - axis * size, axis).Faces[0]


def _roots(function, low: float, high: float, samples: int = 73) -> list[float]:
    """Parameters in [low, high] where ``function`` changes sign (bisection to machine precision)."""
    roots = []
    ts = [low + (high - low) * k / (samples - 1) for k in range(samples)]
    values = [function(t) for t in ts]
    for (a, fa), (b, fb) in zip(zip(ts, values), zip(ts[1:], values[1:])):
        if fa == 0 or fb == 0 or (fa < 0) == (fb < 0):
            continue
        for _ in range(60):
            m = (a + b) / 2
            fm = function(m)
            if (fm < 0) == (fa < 0):
                a, fa = m, fm
            else:
                b = m
        roots.append((a + b) / 2)
    return roots


def revolution_axis(surface):
    """(axis point, unit axis) of a surface of revolution, or None."""
    kind = type(surface).__name__
    if kind in ("Cylinder", "Cone", "Sphere", "Toroid"):
        return FreeCAD.Vector(surface.Center), FreeCAD.Vector(surface.Axis).normalize()
    if kind == "SurfaceOfRevolution":
        return FreeCAD.Vector(surface.Location), FreeCAD.Vector(surface.Direction).normalize()
    return None


def silhouette_cutters(face, d, size: float) -> list:
    """Faces (planes, cylinders) that cut ``face`` along its silhouette seen along ``d``; empty when unknown.

    The silhouette is where the normal is perpendicular to ``d``. Cylinders and cones: generators (lines
    through the axis's plane); spheres: the great circle perpendicular to ``d``; other surfaces of
    revolution seen along their axis: parallels where the profile turns (planes across the axis); seen
    across it: the meridian perpendicular to ``d`` and parallels where the normal is along the axis (cut by
    cylinders around the axis, which cross the face at right angles there).
    """
    surface = face.Surface
    kind = type(surface).__name__
    revolution = revolution_axis(surface)
    if revolution is None:
        return []
    centre, axis = revolution
    u0, u1, v0, v1 = face.ParameterRange
    um, vm = (u0 + u1) / 2, (v0 + v1) / 2
    if kind == "Sphere":
        return [_plane(centre, d, size)]
    if kind in ("Cylinder", "Cone"):
        cutters = []
        for u in _roots(lambda t: surface.normal(t, vm).dot(d), u0, u1):
            radial = surface.value(u, vm) - centre
            radial = radial - axis * radial.dot(axis)
            if radial.Length > 1e-9:
                cutters.append(_plane(centre, axis.cross(radial), size))
        return cutters
    along = axis.dot(d)
    if abs(abs(along) - 1) < 1e-6:  # (models assembled by constraints have axes 1e-8 rad off)
        return [_plane(surface.value(um, v), axis, size)
                for v in _roots(lambda t: surface.normal(um, t).dot(d), v0, v1)]
    if abs(along) < 1e-6:
        cutters = [_plane(centre, d, size)]
        radial = surface.value(um, vm) - centre
        radial = (radial - axis * radial.dot(axis))
        if radial.Length > 1e-9:
            radial.normalize()
            for v in _roots(lambda t: surface.normal(um, t).dot(radial), v0, v1):
                point = surface.value(um, v) - centre
                radius = (point - axis * point.dot(axis)).Length
                if radius > 1e-9:
                    cutters.append(_tube(centre, axis, radius, size))
        return cutters
    return []


def _same_cutter(a, b) -> bool:
    if type(a.Surface).__name__ != type(b.Surface).__name__ or type(a.Surface).__name__ != "Plane":
        return False
    na, nb = a.normalAt(0, 0), b.normalAt(0, 0)
    return abs(abs(na.dot(nb)) - 1) < 1e-9 and abs(na.dot(a.Vertexes[0].Point - b.Vertexes[0].Point)) < 1e-7


def split_face(face, cutters) -> list:
    """The pieces of ``face`` cut by ``cutters`` (the face itself when they miss it)."""
    unique = []
    for cutter in cutters:
        if not any(_same_cutter(cutter, other) for other in unique):
            unique.append(cutter)
    if not unique:
        return [face]
    try:
        _, images = face.generalFuse(unique)
        pieces = [p for p in images[0] if p.ShapeType == "Face"]
    except Exception:  # OCCT raises plain exceptions; the caller checks the pieces anyway
        return [face]
    return pieces or [face]
