"""The swept hull of a part whose mesh cannot be made right: the ring that the part's cross-section sweeps
around its axis (a helical spring's hull is a tube from its inner to its outer radius).

Definition: for a unit axis ``a`` through a point ``c``, the *ring hull* is the set of points whose distance
from the axis lies in ``[r_min - pad, r_max + pad]`` and whose coordinate along ``a`` lies in
``[z_min - pad, z_max + pad]``, the ranges taken over the mesh's vertices; ``r_min`` is set to 0 (a full
cylinder) when it is below ``pad``. The vertices of a chordal mesh lie on the surface and the surface is
within the linear deflection of the facets, so with ``pad`` = the linear deflection the ring holds the part:
whatever the part blocks along any direction the ring blocks too (conservative for blocking), while the bore
stays free (a rod through a spring is not interlocked with it).

The axis is the one of the three principal axes of the vertices (and the three coordinate axes) whose ring
is smallest, centred by a least-squares circle fit of the vertices seen along it. The ring is used only when
it is *tight*: at most :data:`TIGHT` times the part's volume (springs: 1.5 to 3.5); a looser ring would make
the part block what it does not, and the part falls back to its exact shape instead. When that exact shape
is itself beyond the OCCT engine's bound (:mod:`freecad_aplan.occt.complexity`: a spring of a larger pitch,
whose ring is about ``2 pitch / (pi wire radius)`` times its volume: 4.2 at pitch 4 and wire 0.6), a ring up
to :data:`LOOSE` times the volume is taken (:func:`freecad_aplan.export.fallback_mesh`): still conservative for
blocking, and bounded.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["ring_hull", "TIGHT", "LOOSE"]

TIGHT = 4.0
LOOSE = 8.0  # a coil of a pitch up to about 6 wire diameters


def _ring(points: np.ndarray, axis: np.ndarray, pad: float):
    """(volume, centre, r_min, r_max, z_min, z_max) of the ring of ``points`` around ``axis`` (unit)."""
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    u, v, z = points @ e1, points @ e2, points @ axis
    # Kasa's circle fit: u^2 + v^2 = 2 a u + 2 b v + c, least squares.
    system = np.column_stack([2 * u, 2 * v, np.ones_like(u)])
    (a, b, _), *_ = np.linalg.lstsq(system, u * u + v * v, rcond=None)
    r = np.hypot(u - a, v - b)
    r_min, r_max = float(r.min()) - pad, float(r.max()) + pad
    r_min = 0.0 if r_min < pad else r_min
    z_min, z_max = float(z.min()) - pad, float(z.max()) + pad
    volume = math.pi * (r_max ** 2 - r_min ** 2) * (z_max - z_min)
    centre = a * e1 + b * e2
    return volume, centre, r_min, r_max, z_min, z_max


def _exact_ranges(shape, centre: np.ndarray, axis: np.ndarray, rough) -> tuple[float, float, float, float]:
    """(r_min, r_max, z_min, z_max) of ``shape`` around the axis through ``centre``, measured on the exact
    shape (four ``distToShape``: from the axis, from a cylinder outside it, from planes beyond its ends), so
    that the ring touches what the part touches without overlapping it; ``rough`` (the vertices' ranges) is
    the starting point."""
    import FreeCAD
    import Part

    r_min, r_max, z_min, z_max = rough
    vec = FreeCAD.Vector
    a, c = vec(*map(float, axis)), vec(*map(float, centre))
    far = 1.0 + (z_max - z_min) + r_max
    line = Part.LineSegment(c + a * (z_min - far), c + a * (z_max + far)).toShape()
    r_min = float(shape.distToShape(line)[0])
    outside = Part.makeCylinder(r_max + far, z_max - z_min + 2 * far, c + a * (z_min - far), a).Faces[0]
    r_max = r_max + far - float(shape.distToShape(outside)[0])
    big = 2 * (r_max + far)
    for sign in (-1, 1):
        end = z_min - far if sign < 0 else z_max + far
        plane = Part.makeCircle(big, c + a * end, a)
        gap = float(shape.distToShape(Part.Face(Part.Wire(plane)))[0])
        if sign < 0:
            z_min = end + gap
        else:
            z_max = end - gap
    return r_min, r_max, z_min, z_max


def ring_hull(points, volume: float, pad: float, shape=None, tight: float = TIGHT):
    """The ring hull (module docstring) of a part with mesh vertices ``points`` ((n, 3)) and B-rep ``volume``,
    as a ``Part`` solid, or None when no ring is within ``tight`` times ``volume``. With ``shape`` (the exact part), the ranges are
    measured on it (no ``pad``). Cost O(n) per axis tried (six), plus four distance queries."""
    import FreeCAD
    import Part

    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(points) < 4 or not volume > 0:
        return None
    centred = points - points.mean(axis=0)
    _, vectors = np.linalg.eigh(centred.T @ centred)
    axes = [vectors[:, k] for k in range(3)] + list(np.eye(3))
    best = min((_ring(points, axis / np.linalg.norm(axis), pad) + (axis,) for axis in axes), key=lambda r: r[0])
    ring_volume, centre, r_min, r_max, z_min, z_max, axis = best
    if ring_volume > tight * volume:
        return None
    if shape is not None:
        r_min, r_max, z_min, z_max = _exact_ranges(shape, centre, axis, (r_min + pad, r_max - pad, z_min + pad,
                                                                          z_max - pad))
        r_min = 0.0 if r_min < pad else r_min
        # Checked again on the exact ranges: a coarse mesh's vertices need not sample the surface (the 12
        # corners of an L of two bars lie near one circle, a 3.7 times ring; measured exactly, 41 times).
        if math.pi * (r_max ** 2 - r_min ** 2) * (z_max - z_min) > tight * volume:
            return None
    direction = FreeCAD.Vector(*(float(c) for c in axis))
    base = FreeCAD.Vector(*(float(c) for c in centre + z_min * axis))
    solid = Part.makeCylinder(r_max, z_max - z_min, base, direction)
    if r_min > 0:
        solid = solid.cut(Part.makeCylinder(r_min, z_max - z_min, base, direction))
    return solid
