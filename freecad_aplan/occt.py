"""Contacts, interferences and obstruction diagrams from exact B-rep shapes (the OCCT geometry engine).

Runs inside FreeCAD (``Part``). It computes what :mod:`planner.geometry` computes from meshes, with the same
definitions (see that module), on the exact shapes:

- *contact*: the two parts' surfaces are closer than ``contact`` (``distToShape``), or they overlap (one
  inside the other, a press fit, a small modelling interference such as the pen's button, 0.06 mm^3);
- *interference*: the common volume of the two parts (``common``) exceeds ``interference`` cubic units;
- *obstruction* along ``d``: part ``x``, moved along ``+d`` without limit, would collide with part ``y``.

Method
------
Obstruction is tested continuously, on exact sweeps: ``x`` swept along ``+d`` to beyond the scene is the
union of the prisms (extrusions along ``d``) of its faces that face backwards (outward normal . d < 0), since
every point of the sweep lies ahead of such a face on a line parallel to ``d``. ``x`` is *blocked* by ``y``
when one prism ``P`` takes more than ``depth ** 3`` of ``y`` outside ``x``: ``volume(P & y) - volume(P & x & y)``.
What the parts already share does not count, and surfaces that touch or slide along each other (a peg in
its hole, moving along its axis) have a common volume of zero.

OCCT needs some help to get there:

- A prism is valid only for a face that projects one-to-one along ``d``. Faces whose normal turns across
  ``d`` (a cylinder seen side on, a sphere) are split along their silhouettes, exactly: by planes through
  the axis of cylinders and cones, through the centre of spheres, across or through the axis of tori and
  surfaces of revolution, and by cylinders around the axis where a profile's normal is along it. A piece
  that still folds (B-splines, a torus in a general position), or whose prism OCCT cannot build, is swept as
  the polyhedral prism of its tessellation (within ``contact / 2``), and the warnings say so.
- Planar sides of prisms that OCCT makes as extrusion surfaces are rebuilt as planes, and faces whose
  normal or axis is within 1e-6 rad of ``d`` (models assembled by constraints are 1e-8 rad off) are swept
  along that normal or axis: booleans do not match an extrusion surface with a coplanar plane or a coaxial
  cylinder, and return wrong volumes, or never finish.
- Booleans run on copies (OCCT raises its arguments' tolerances in place) and fail quietly now and then
  (an empty common for a door moving onto its screws). The prisms are tested one by one rather than fused;
  a positive volume is evidence, while an empty one must be confirmed by the prism built both ways (along
  the face's axis and along ``d``) with two fuzzy values, and by rays from the face through ``y`` (point
  classification, no boolean). A pair OCCT cannot decide counts as blocked, with a warning.

Broad phase: contact pairs whose bounding boxes are farther apart than ``contact`` are never measured; for
the obstruction along ``d``, ``y`` must overlap ``x``'s box in the two directions across ``d`` by more than
``contact`` (narrower contacts only graze) and reach more than ``depth`` beyond the start of ``x`` along
``d``; a prism is only tested against ``y`` when their boxes overlap. Prisms are built once per part and
axis, only when a candidate needs them.
"""
from __future__ import annotations

import json
import math
import os
import time

import FreeCAD
import Part

from planner.defaults import (
    BLOCKING_DEPTH,
    CONTACT_TOLERANCE,
    INTERFERENCE_VOLUME,
    PRODUCT_FILE,
)

from .document import DocumentError

__all__ = ["analyze_shapes", "analyze_bundle_breps", "BrepError", "AXES"]

AXES = ("+X", "+Y", "+Z")
_DIRECTIONS = {"+X": (1.0, 0.0, 0.0), "+Y": (0.0, 1.0, 0.0), "+Z": (0.0, 0.0, 1.0)}
_SAMPLES = 13  # samples per parameter direction when checking where a face's normal turns
_FLAT = 1e-7  # |normal . d| below this: the face is parallel to d there
_FOLD = 1e-3  # a face whose normal turns past the silhouette by less than this (radians) is not split


class BrepError(DocumentError):
    """A part's B-rep cannot be used: missing or unreadable file, no solid, no volume."""


# ----------------------------------------------------------------------------------------------- boxes


def _box(shape) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The tight bounding box (min corner, max corner) of ``shape``."""
    box = shape.optimalBoundingBox()  # (False, False) crashes FreeCAD 0.20.2 on copied shapes
    return (box.XMin, box.YMin, box.ZMin), (box.XMax, box.YMax, box.ZMax)


def _box_gap(a, b) -> float:
    """Largest per-axis gap between boxes ``a`` and ``b`` (<= 0 when they overlap)."""
    return max(max(b[0][k] - a[1][k], a[0][k] - b[1][k]) for k in range(3))


# -------------------------------------------------------------------------------------------- contacts


def _nested(inner, outer) -> bool:
    """True when ``inner`` lies inside ``outer`` (their surfaces being apart): test one vertex of it."""
    for vertex in inner.Vertexes[:1]:
        return outer.isInside(vertex.Point, 1e-7, True)
    return False


def _contacts(ids, shapes, boxes, points, contact: float, fuzzies, warnings: list[str]):
    """Contact pairs (i < j), and {(i, j) and (j, i): (volume, common solid)} for pairs that overlap.

    ``points(j)``: points inside part j (to catch booleans that fail quietly)."""
    pairs, overlap = [], {}
    n = len(shapes)
    for i in range(n):
        for j in range(i + 1, n):
            gap = _box_gap(boxes[i], boxes[j])
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
                common = _common(shapes[i], shapes[j], fuzzies,
                                 lambda i=i, j=j: _holds_any(shapes[i], boxes[i], points(j), fuzzies[-1]))
                if common is None:
                    warnings.append(f"OCCT cannot compute the overlap of {ids[i]!r} and {ids[j]!r}; "
                                    "counted as contact without overlap")
                elif common.Volume > 0:
                    overlap[i, j] = overlap[j, i] = (common.Volume, common)
    return pairs, overlap


# ----------------------------------------------------------------------------------------------- sweeps


def _vector(t) -> "FreeCAD.Vector":
    return FreeCAD.Vector(*t)


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


def _facing(face, d) -> tuple[float, float]:
    """Smallest and largest ``normal . d`` over samples of ``face`` (outward normals); (-1, 1), as if it
    folded, when no sample could be taken."""
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


def _revolution(surface):
    """(axis point, unit axis) of a surface of revolution, or None."""
    kind = type(surface).__name__
    if kind in ("Cylinder", "Cone", "Sphere", "Toroid"):
        return FreeCAD.Vector(surface.Center), FreeCAD.Vector(surface.Axis).normalize()
    if kind == "SurfaceOfRevolution":
        return FreeCAD.Vector(surface.Location), FreeCAD.Vector(surface.Direction).normalize()
    return None


def _silhouette_cutters(face, d, size: float) -> list:
    """Faces (planes, cylinders) that cut ``face`` along its silhouette seen along ``d``; empty when unknown.

    The silhouette is where the normal is perpendicular to ``d``. Cylinders and cones: generators (lines
    through the axis's plane); spheres: the great circle perpendicular to ``d``; other surfaces of
    revolution seen along their axis: parallels where the profile turns (planes across the axis); seen
    across it: the meridian perpendicular to ``d`` and parallels where the normal is along the axis (cut by
    cylinders around the axis, which cross the face at right angles there).
    """
    surface = face.Surface
    kind = type(surface).__name__
    revolution = _revolution(surface)
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


def _split(face, cutters) -> list:
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


def _direction(face, d):
    """``d``, or the face's own normal or axis when that is within 1e-6 rad of ``d``.

    Models assembled by constraints hold planes and axes a few 1e-8 rad off the model's axes. Swept along
    ``d`` exactly, their circles become extrusion surfaces instead of cylinders, which booleans do not
    match with the cylinders of a mating part (a door's screw holes: the common volume came out as 0).
    Swept along their own axis, they become cylinders; the prism moves sideways by 1e-6 of its length.
    """
    surface = face.Surface
    if type(surface).__name__ == "Plane":
        axis = FreeCAD.Vector(surface.Axis)
    else:
        revolution = _revolution(surface)
        if revolution is None:
            return d
        axis = revolution[1]
    axis = FreeCAD.Vector(axis).normalize()
    along = axis.dot(d)
    if 1 - abs(along) < 5e-13:  # within 1e-6 rad: 1 - cos(1e-6) = 5e-13
        return axis * (1.0 if along > 0 else -1.0)
    return d


def _prism(face, vector, flatness: float):
    """The prism of ``face`` along ``vector``, its planar sides as planes (not extrusion surfaces).

    OCCT sweeps a circular edge into a planar ``SurfaceOfExtrusion``; booleans do not recognise such a face
    as coplanar with a plane (the cartridge's end faces) and return wrong volumes with huge tolerances, or
    never finish. Sides within ``flatness`` of a plane (a circle whose axis is 1e-8 rad off an axis of the
    model, swept 500 mm) become planes, their edges' tolerances raised to cover the difference.
    """
    prism = face.extrude(vector)
    faces, changed = [], False
    for side in prism.Faces:
        if type(side.Surface).__name__ == "SurfaceOfExtrusion":
            plane = side.findPlane(flatness)
            if plane is not None:
                flat = Part.Face(plane, side.Wires)
                u0, u1, v0, v1 = side.ParameterRange
                u, v = (u0 + u1) / 2, (v0 + v1) / 2
                if flat.normalAt(*flat.Surface.parameter(side.valueAt(u, v))).dot(side.normalAt(u, v)) < 0:
                    flat.reverse()
                off = max((abs((p - plane.Position).dot(plane.Axis)) for e in side.Edges
                           for p in e.discretize(5)), default=0.0)
                if off > 1e-7:
                    flat.fixTolerance(2 * off)
                faces.append(flat)
                changed = True
                continue
        faces.append(side)
    if not changed:
        return prism
    solid = Part.Solid(Part.Shell(faces))
    if not solid.isValid() or abs(solid.Volume - prism.Volume) > 1e-6 * max(1.0, abs(prism.Volume)):
        return prism
    return solid


def _mesh_prism(face, d, length: float, deflection: float):
    """One polyhedral prism sweeping the backward-facing triangles of ``face``'s tessellation along ``d``
    (for pieces OCCT cannot sweep exactly); None when it cannot be built."""
    points, triangles = face.tessellate(deflection)
    kept, area = [], 0.0
    for a, b, c in triangles:
        normal = (points[b] - points[a]).cross(points[c] - points[a])
        if normal.Length > 1e-12 and normal.dot(d) / normal.Length < -_FLAT:
            kept.append((a, b, c))
            area -= normal.dot(d) / 2
    if not kept:
        return None
    uses: dict[tuple[int, int], int] = {}
    for a, b, c in kept:
        for edge in ((a, b), (b, c), (c, a)):
            uses[edge] = uses.get(edge, 0) + 1
    if any(uses.get((q, p), 0) + n > 2 for (p, q), n in uses.items()):
        return None  # not a surface patch (a fold or a seam the tessellation repeats)
    up = d * length
    facets = []
    for a, b, c in kept:
        facets.append((points[a], points[b], points[c]))  # the patch, facing backwards
        facets.append((points[a] + up, points[c] + up, points[b] + up))  # its copy, facing forwards
    for p, q in uses:
        if (q, p) not in uses:  # a boundary edge: one side wall, wound against the patch's
            facets.append((points[q], points[p], points[p] + up))
            facets.append((points[q], points[p] + up, points[q] + up))
    shell = Part.Shell([Part.Face(Part.makePolygon([a, b, c, a])) for a, b, c in facets])
    shell.sewShape()  # our own shape; Shape.makeShapeFromMesh would print progress bars on stdout
    solid = Part.Solid(shell.Shells[0]).removeSplitter()
    if abs(abs(solid.Volume) - area * length) > 1e-6 * area * length:
        return None
    if solid.Volume < 0:
        solid.reverse()
    return solid


class _Prism:
    """One prism of a sweep: its solid and box, and on demand other constructions of it (cross-checks)."""

    def __init__(self, piece, d, length: float, flatness: float, deflection: float, solid, exact: bool):
        self.piece, self.d, self.length = piece, d, length
        self.flatness, self.deflection = flatness, deflection
        self.solid, self.exact_built = solid, exact
        self.box = _box(solid)
        self._points = None

    @property
    def points(self) -> list:
        """Sample points of the face (rays start there)."""
        if self._points is None:
            u0, u1, v0, v1 = self.piece.ParameterRange
            grid = [(u0 + (u1 - u0) * (a + 0.5) / 5, v0 + (v1 - v0) * (b + 0.5) / 5)
                    for a in range(5) for b in range(5)]
            self._points = [self.piece.valueAt(u, v) for u, v in grid if self.piece.isPartOfDomain(u, v)]
        return self._points

    def exact(self):
        """The prism, then (when it was swept along the face's own axis) the prism swept along ``d``
        exactly: two constructions whose booleans fail in different cases."""
        yield self.solid
        if self.exact_built and _direction(self.piece, self.d) is not self.d:
            try:
                yield _prism(self.piece, self.d * self.length, self.flatness)
            except Exception:  # OCCT construction errors are plain exceptions
                pass

    def meshed(self):
        """The polyhedral prism of the face's tessellation (within ``deflection``), or None."""
        if not self.exact_built:
            return self.solid
        try:
            return _mesh_prism(self.piece, self.d, self.length, self.deflection)
        except Exception:  # OCCT cannot mesh or sew it
            return None


def _piece_prisms(piece, d, length: float, flatness: float, deflection: float) -> tuple[list, int]:
    """The prism (a :class:`_Prism`) sweeping ``piece`` along ``d`` in a list, and 1 when the piece had to
    be swept as triangles.

    A piece that still folds (no known silhouette: B-splines, tori in general positions) or whose prism
    OCCT cannot build sensibly (edges with large tolerances in imported models) is swept as the polyhedral
    prism of its backward-facing tessellation triangles (within ``deflection``). A prism that BRepCheck
    rejects is kept when its volume is plausible (positive, at most length x area): imported models are
    full of edges whose tolerances overlap, and the booleans cope with them.
    """
    try:
        low, high = _facing(piece, d)
        if low > -_FLAT:
            return [], 0
        if high <= _FOLD:
            prism = _prism(piece, _direction(piece, d) * length, flatness)
            if prism.isValid() or 0 < prism.Volume <= length * piece.Area * (1 + 1e-6):
                return [_Prism(piece, d, length, flatness, deflection, prism, True)], 0
    except Exception:  # OCCT construction errors ("Courbes non jointives", ...) are plain exceptions
        pass
    try:
        prism = _mesh_prism(piece, d, length, deflection)
    except Exception:  # OCCT cannot mesh or sew it
        prism = None
    return ([] if prism is None else [_Prism(piece, d, length, flatness, deflection, prism, False)]), 1


def _prisms(shape, d, length: float, deflection: float, flatness: float) -> tuple[list, int]:
    """Prisms (:class:`_Prism`) whose union is ``shape`` swept along ``d`` by ``length``, and the number
    of pieces swept as triangles."""
    size = shape.BoundBox.DiagonalLength + 1.0
    prisms, trouble = [], 0
    for face in shape.copy().Faces:
        low, high = _facing(face, d)
        if low > -_FLAT:
            continue  # faces forwards or lies along d: the backward faces' prisms cover its prism
        pieces = [face] if high <= _FOLD else _split(face, _silhouette_cutters(face, d, size))
        for piece in pieces:
            more, bad = _piece_prisms(piece, d, length, flatness, deflection)
            prisms += more
            trouble += bad
    return prisms, trouble


def _inner_points(shape, depth: float, limit: int = 40) -> list:
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


def _holds_any(solid, box, points, tolerance: float) -> bool:
    """True when one of ``points`` lies inside ``solid`` (whose box is ``box``), deeper than ``tolerance``."""
    lo, hi = box
    for point in points:
        if all(lo[k] < point[k] < hi[k] for k in range(3)) and solid.isInside(point, tolerance, False):
            return True
    return False


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


def _common(a, b, fuzzies: tuple[float, ...], overlaps=None):
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


def _common_volume(a, b, fuzzies: tuple[float, ...], overlaps=None) -> float | None:
    """Volume of ``a & b`` (see :func:`_common`), or None."""
    common = _common(a, b, fuzzies, overlaps)
    return None if common is None else max(common.Volume, 0.0)


# ------------------------------------------------------------------------------------------ obstructions


def _obstructions(ids, shapes, boxes, overlap, contact: float, depth: float, fuzzies,
                  warnings: list[str]):
    """Per axis, the pairs (i, j): part i moving along the axis collides with part j."""
    scene_hi = [max(b[1][k] for b in boxes) for k in range(3)]
    volume_tolerance = depth ** 3
    result = {}
    for axis, name in enumerate(AXES):
        d = _vector(_DIRECTIONS[name])
        across = [k for k in range(3) if k != axis]
        pairs = []
        for i, (lo, hi) in enumerate(boxes):
            candidates = [j for j, (lo2, hi2) in enumerate(boxes) if j != i
                          and all(min(hi[k], hi2[k]) - max(lo[k], lo2[k]) > contact for k in across)
                          and hi2[axis] > lo[axis] + depth]
            if not candidates:
                continue
            length = scene_hi[axis] - lo[axis] + 1.0
            prisms, meshed = _prisms(shapes[i], d, length, contact / 2, contact * 1e-3)
            if meshed:
                warnings.append(f"part {ids[i]!r}: {meshed} face piece(s) swept along {name} as triangles within "
                                f"{contact / 2:g} (no exact silhouette, or OCCT could not build their prism)")
            for j in candidates:
                verdict = _blocks(prisms, shapes[j], boxes[j], overlap.get((i, j)), axis, volume_tolerance,
                                  fuzzies)
                if verdict is None:
                    warnings.append(f"{name}: OCCT cannot tell whether {ids[i]!r} moving along {name} hits "
                                    f"{ids[j]!r}; assumed it does")
                if verdict is not False:
                    pairs.append((i, j))
        result[name] = sorted(pairs)
    return result


def _blocks(prisms, other, other_box, shared, axis: int, volume_tolerance: float, fuzzies) -> bool | None:
    """True when one of the prisms takes more than ``volume_tolerance`` of ``other`` outside ``shared``
    (the (volume, solid) the moving part already shares with it); None when no prism decided because
    booleans failed."""
    lo, hi = other_box
    unsure = False
    for prism in prisms:
        plo, phi = prism.box
        if phi[axis] <= lo[axis] or any(min(phi[k], hi[k]) - max(plo[k], lo[k]) <= 0 for k in range(3) if k != axis):
            continue
        verdict = _prism_blocks(prism, other, other_box, shared, axis, volume_tolerance, fuzzies)
        if verdict:
            return True
        unsure = unsure or verdict is None
    return None if unsure else False


def _gained(solid, other, shared, fuzzy: float) -> float | None:
    """Volume of ``solid & other`` outside ``shared`` (or None when a boolean fails)."""
    volume = _common_volume(solid, other, (fuzzy,))
    if volume is not None and shared and volume > 0:
        inside = _common_volume(solid, shared[1], (fuzzy,))
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


# ---------------------------------------------------------------------------------------------- public


def analyze_shapes(parts: list[tuple[str, "Part.Shape"]], contact: float = CONTACT_TOLERANCE,
                   interference: float = INTERFERENCE_VOLUME, depth: float = BLOCKING_DEPTH) -> dict:
    """Contacts, interferences and the +X, +Y, +Z obstruction diagrams of exact part shapes.

    ``parts``: (id, shape) pairs, shapes holding solids in global coordinates (they are not modified).
    Returns the layout of :meth:`planner.geometry.GeometryReport.as_dict` with engine ``"occt"``; contact and
    interference pairs follow the order of ``parts``; obstruction pair ``(x, y)`` along ``+d`` means ``x``
    moving along ``+d`` collides with ``y``.

    Tolerances: ``contact`` (model units) for contacts, and the grazing width of the obstruction broad
    phase; ``interference`` (cubic units) for reporting overlaps; ``depth`` (model units) for obstruction:
    ``y`` must reach more than ``depth`` beyond the start of ``x``, and ``x``'s sweep must take more than
    ``depth ** 3`` of ``y`` outside what they already share. Raises :class:`BrepError` naming the part when
    a shape holds no solid or no volume, ``ValueError`` for a negative tolerance.

    >>> import Part
    >>> report = analyze_shapes([("a", Part.makeBox(1, 1, 1)), ("b", Part.makeBox(1, 1, 1, FreeCAD.Vector(1, 0, 0)))])
    >>> report["contacts"], report["obstructions"]["+X"]
    ([['a', 'b']], [['a', 'b']])

    Cost: one ``distToShape`` per pair whose boxes are within ``contact`` and one ``common`` per pair that
    touches; per axis, the prisms of each part's backward faces (one ``generalFuse`` per face split at its
    silhouette) and, per candidate pair, one to four ``common`` per prism whose box meets the other part
    (an empty result is cross-checked) plus up to 100 point classifications. Booleans take 0.01-1 s each;
    the pen takes about 2 s, a 61-part toy truck about 90 s.
    """
    start = time.perf_counter()
    for name, value in (("contact", contact), ("interference", interference), ("depth", depth)):
        if not value >= 0:
            raise ValueError(f"tolerance {name} must be >= 0, got {value!r}")
    if not parts:
        raise BrepError("no parts to analyse")
    ids = [str(p[0]) for p in parts]
    shapes = []
    for part_id, shape in parts:
        if shape is None or shape.isNull() or not shape.Solids:
            raise BrepError(f"part {part_id!r}: its shape holds no solid")
        if not shape.Volume > 0:
            raise BrepError(f"part {part_id!r}: its solid has no volume ({shape.Volume:g})")
        shapes.append(shape.copy())  # booleans may raise the tolerances of their arguments
    boxes = [_box(s) for s in shapes]
    warnings: list[str] = []
    fuzzies = (0.0, contact * 1e-4, contact * 1e-3)
    cache: dict[int, list] = {}

    def points(j: int) -> list:
        if j not in cache:
            cache[j] = _inner_points(shapes[j], min(contact, 0.01 * shapes[j].BoundBox.DiagonalLength))
        return cache[j]

    contacts, overlap = _contacts(ids, shapes, boxes, points, contact, fuzzies, warnings)
    interferences = [(i, j, overlap[i, j][0]) for i, j in contacts if overlap.get((i, j), (0.0,))[0] > interference]
    for i, j, volume in interferences:
        warnings.append(f"parts {ids[i]!r} and {ids[j]!r} interpenetrate by {volume:.4g} cubic units "
                        f"(more than the interference tolerance {interference:g})")
    obstructions = _obstructions(ids, shapes, boxes, overlap, contact, depth, fuzzies, warnings)
    return {
        "engine": "occt", "parts": len(ids),
        "contacts": [[ids[i], ids[j]] for i, j in contacts],
        "interferences": [{"parts": [ids[i], ids[j]], "volume": round(v, 6)} for i, j, v in interferences],
        "obstructions": {name: [[ids[i], ids[j]] for i, j in pairs] for name, pairs in obstructions.items()},
        "tolerances": {"contact": contact, "interference": interference, "depth": depth,
                       "volume": depth ** 3},
        "warnings": warnings, "seconds": round(time.perf_counter() - start, 3),
    }


def analyze_bundle_breps(folder: str, **tolerances) -> dict:
    """:func:`analyze_shapes` on the B-reps of a bundle: ``folder/product.json`` and its ``breps/*.brep``.

    ``tolerances``: ``contact``, ``interference``, ``depth`` as in :func:`analyze_shapes`.
    Raises :class:`BrepError` naming the part and the file when a B-rep is missing or unreadable.
    Cost: reading the files, then that of :func:`analyze_shapes`.
    """
    path = os.path.join(folder, PRODUCT_FILE)
    try:
        with open(path, encoding="utf-8") as handle:
            product = json.load(handle)
    except (OSError, ValueError) as exc:
        raise BrepError(f"{path}: cannot read the bundle's product file ({exc})") from None
    parts = []
    for index, part in enumerate(product.get("parts", [])):
        part_id = part.get("id", f"parts[{index}]")
        relative = part.get("brep")
        if not relative:
            raise BrepError(f"part {part_id!r}: no B-rep file in {path} (re-export the bundle)")
        brep = os.path.join(folder, relative)
        if not os.path.isfile(brep):
            raise BrepError(f"part {part_id!r}: B-rep file {brep} is missing (re-export the bundle)")
        shape = Part.Shape()
        try:
            shape.read(brep)
        except Exception as exc:
            raise BrepError(f"part {part_id!r}: B-rep file {brep} cannot be read ({exc})") from None
        if shape.isNull():
            raise BrepError(f"part {part_id!r}: B-rep file {brep} holds no shape")
        parts.append((part_id, shape))
    return analyze_shapes(parts, **tolerances)
