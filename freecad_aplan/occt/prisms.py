"""Sweeps: a part moved along a direction to beyond the scene, as the prisms of its backward-facing faces,
built exactly where OCCT can, else from the faces' tessellation."""
from __future__ import annotations

import ctypes
import os
import sys
from contextlib import contextmanager

import FreeCAD
import Part

from planner.errors import PlannerError

from .silhouettes import facing, revolution_axis, silhouette_cutters, split_face
from .solids import bounding_box

__all__ = ["Prism", "SweepTooLarge", "SweepStopped", "sweep_direction", "exact_prism", "mesh_prism", "sweep_prisms",
           "self_intersecting"]

_FLAT = 1e-7  # |normal . d| below this: the face is parallel to d there
_FOLD = 1e-3  # a face whose normal turns past the silhouette by less than this (radians) is not split
#: Prisms of more facets than this are checked for self-intersection before they are built (about 1 ms of OCCT
#: per facet). Smaller ones are built and checked as before: a sliver of a few triangles along a silhouette may
#: cross itself and still give OCCT's solid its (near zero) volume, which never blocks (the pump's 17_001).
_CHECKED_FACETS = 1000


def sweep_direction(face, d):
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
        revolution = revolution_axis(surface)
        if revolution is None:
            return d
        axis = revolution[1]
    axis = FreeCAD.Vector(axis).normalize()
    along = axis.dot(d)
    if 1 - abs(along) < 5e-13:  # within 1e-6 rad: 1 - cos(1e-6) = 5e-13
        return axis * (1.0 if along > 0 else -1.0)
    return d


def exact_prism(face, vector, flatness: float):
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


class SweepTooLarge(PlannerError):
    """A face's polyhedral prism would have more triangles than its bound (``triangles``: the face's). Caught by
    the engine (the pair is undecided); a :class:`PlannerError`, as every workbench error, should one escape."""

    def __init__(self, triangles: int) -> None:
        super().__init__(f"{triangles} triangles")
        self.triangles = triangles


class SweepStopped(PlannerError):
    """The sweep was abandoned between two faces: its ``stop`` said so (the time limit passed). Caught by the
    engine, as :class:`SweepTooLarge` is."""


def mesh_prism(face, d, length: float, deflection: float, triangles_bound: int | None = None):
    """One polyhedral prism sweeping the backward-facing triangles of ``face``'s tessellation along ``d``
    (for pieces OCCT cannot sweep exactly); None when it cannot be built. Raises :class:`SweepTooLarge`,
    before any face of the prism is made, when the tessellation has more than ``triangles_bound`` triangles
    (building one ``Part.Face`` per triangle is what exhausts memory: 11 GB for a spring's 371,000)."""
    points, triangles = face.tessellate(deflection)
    if triangles_bound is not None and len(triangles) > triangles_bound:
        raise SweepTooLarge(len(triangles))
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
    if len(facets) > _CHECKED_FACETS and self_intersecting(facets):
        return None  # the patch overlaps itself seen along d: no one prism holds its sweep
    shell = Part.Shell([Part.Face(Part.makePolygon([a, b, c, a])) for a, b, c in facets])
    shell.sewShape()  # our own shape; Shape.makeShapeFromMesh would print progress bars on stdout
    solid = Part.Solid(shell.Shells[0])
    # Checked before removeSplitter, which keeps the volume and is the slow step (20 of 27 CPU s for a torus as
    # NURBS, whose patch overlaps itself seen along d, so that its volume is wrong and it is refused anyway).
    if abs(abs(solid.Volume) - area * length) > 1e-6 * area * length:
        return None
    solid = solid.removeSplitter()
    if solid.Volume < 0:
        solid.reverse()
    return solid


@contextmanager
def _quiet_stdout():
    """Standard output (file descriptor 1) sent to the null device: FreeCAD's mesh module prints progress bars
    there, without newlines, which would run into the batch protocol's lines (:mod:`freecad_aplan.protocol`)."""
    try:  # C's buffered output flushed on each side of the swap (no C library by that name on Windows)
        flush = ctypes.CDLL(None).fflush
    except (OSError, AttributeError):
        flush = lambda _: None  # noqa: E731
    sys.stdout.flush()
    flush(None)
    saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    try:
        yield
    finally:
        flush(None)
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


def self_intersecting(facets) -> bool:
    """True when the closed triangle surface ``facets`` (point triples) intersects itself
    (``Mesh.hasSelfIntersections``: a grid over the triangles, in C++).

    Why: :func:`mesh_prism` builds one ``Part.Face`` per facet and sews them, about 1 ms of OCCT per facet,
    then refuses the solid whose volume is wrong, as it is for a patch that overlaps itself seen along the
    direction (a torus or a sphere made with ``toNurbs()``: one closed B-spline patch). Such a patch's walls
    cut through it, so its prism's surface intersects itself: known here in 0.03 CPU s instead of 6 to 9
    (the torus of tests/workbench/test_heavy_shapes.py, 14,612 facets, bench/README.md). A surface that does
    not intersect itself goes on to be built and checked as before, so no verdict comes from this test alone
    but that the piece cannot be swept (its pairs undecided: the mesh engine's answer stands). Asked only for
    prisms of more than :data:`_CHECKED_FACETS` facets, where it saves seconds."""
    import Mesh

    with _quiet_stdout():
        return bool(Mesh.Mesh([[tuple(p) for p in facet] for facet in facets]).hasSelfIntersections())


class Prism:
    """One prism of a sweep: its solid and box, and on demand other constructions of it (cross-checks)."""

    def __init__(self, piece, d, length: float, flatness: float, deflection: float, solid, exact: bool):
        self.piece, self.d, self.length = piece, d, length
        self.flatness, self.deflection = flatness, deflection
        self.solid, self.exact_built = solid, exact
        self.box = bounding_box(solid)
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
        if self.exact_built and sweep_direction(self.piece, self.d) is not self.d:
            try:
                yield exact_prism(self.piece, self.d * self.length, self.flatness)
            except Exception:  # OCCT construction errors are plain exceptions
                pass

    def meshed(self):
        """The polyhedral prism of the face's tessellation (within ``deflection``), or None."""
        if not self.exact_built:
            return self.solid
        try:
            return mesh_prism(self.piece, self.d, self.length, self.deflection)
        except Exception:  # OCCT cannot mesh or sew it
            return None


def _piece_prisms(piece, d, length: float, flatness: float, deflection: float,
                  triangles_bound: int | None = None) -> tuple[list, int]:
    """The prism (a :class:`Prism`) sweeping ``piece`` along ``d`` in a list, and 1 when the piece had to
    be swept as triangles.

    A piece that still folds (no known silhouette: B-splines, tori in general positions) or whose prism
    OCCT cannot build sensibly (edges with large tolerances in imported models) is swept as the polyhedral
    prism of its backward-facing tessellation triangles (within ``deflection``). A prism that BRepCheck
    rejects is kept when its volume is plausible (positive, at most length x area): imported models are
    full of edges whose tolerances overlap, and the booleans cope with them.
    """
    try:
        low, high = facing(piece, d)
        if low > -_FLAT:
            return [], 0
        if high <= _FOLD:
            prism = exact_prism(piece, sweep_direction(piece, d) * length, flatness)
            if prism.isValid() or 0 < prism.Volume <= length * piece.Area * (1 + 1e-6):
                return [Prism(piece, d, length, flatness, deflection, prism, True)], 0
    except Exception:  # OCCT construction errors ("Courbes non jointives", ...) are plain exceptions
        pass
    try:
        prism = mesh_prism(piece, d, length, deflection, triangles_bound)
    except SweepTooLarge:
        raise
    except Exception:  # OCCT cannot mesh or sew it
        prism = None
    return ([] if prism is None else [Prism(piece, d, length, flatness, deflection, prism, False)]), 1


def sweep_prisms(shape, d, length: float, deflection: float, flatness: float,
                 triangles_bound: int | None = None, stop=None) -> tuple[list, int]:
    """Prisms (:class:`Prism`) whose union is ``shape`` swept along ``d`` by ``length``, and the number
    of pieces swept as triangles. Raises :class:`SweepTooLarge` when a piece swept as triangles has more
    than ``triangles_bound`` of them (None: no bound), and :class:`SweepStopped` when ``stop()`` (asked
    before each face: a part of 1,000 faces takes minutes to sweep) returns True."""
    size = shape.BoundBox.DiagonalLength + 1.0
    prisms, trouble = [], 0
    for face in shape.copy().Faces:
        if stop is not None and stop():
            raise SweepStopped()
        low, high = facing(face, d)
        if low > -_FLAT:
            continue  # faces forwards or lies along d: the backward faces' prisms cover its prism
        pieces = [face] if high <= _FOLD else split_face(face, silhouette_cutters(face, d, size))
        for piece in pieces:
            more, bad = _piece_prisms(piece, d, length, flatness, deflection, triangles_bound)
            prisms += more
            trouble += bad
    return prisms, trouble
