"""Part meshes checked against their B-rep: tessellate, compare volume and area, re-tessellate when they differ.

FreeCAD 0.20's default mesher (MeshPart's Standard, OCCT's BRepMesh) drops parts of faces now and then (seen
on cone faces whose seam sits at u = +-pi, in part 14_001 of a diaphragm pump: 70 % of one cone's area missing).
The mesh is then open, or, after hole filling closes it, has the wrong volume (-30 % there), and the mesh
engine invents interferences and misses contacts. So every mesh is compared with its exact shape:

- *volume error* ``(mesh volume - B-rep volume) / B-rep volume`` and *area error* likewise; a mesh passes
  when it is closed and both are within ``tolerance`` (a chordal mesh of a curved part is a little smaller
  than the part: -0.1 % to -0.6 % at the default deflection);
- the methods, tried in order until one passes: ``standard`` (the given deflections), ``finer`` (Standard
  with a fifth of the linear and half the angular deflection), ``mefisto`` (MeshPart's Mefisto mesher,
  edges at most 1/32 of the part's diagonal), ``nurbs`` (Standard on ``Shape.toNurbs()``: every face as a
  B-spline, which BRepMesh meshes by another code path), ``netgen`` (when FreeCAD was built with it).
  The order is by cost and by what worked: on that part, finer took 2 s (-29 %, the same faces
  missing), Mefisto 2.5 s (+0.56 %), toNurbs 26 s (-20 %, open; its B-splines also change the volume by 9 %);
- when none passes, the closest mesh is kept and the part is marked ``exact``; the export then gives it a
  fallback (:func:`freecad_aplan.export.fallback_mesh`): its ring hull when that is tight (a spring's tube,
  :mod:`freecad_aplan.hull`), else its pairs are decided on its exact shape (:mod:`freecad_aplan.hybrid`),
  with its bounding box as its mesh when no closed mesh was made.

The work is bounded, not timed: at most ``refinements`` methods after the first (default
:data:`~planner.defaults.MESH_REFINEMENTS`), and no mesh of more than ``triangle_budget`` facets (default
:data:`~planner.defaults.MESH_TRIANGLE_BUDGET`): ``finer`` is not even run when the first mesh times
:data:`FINER_GROWTH` is over it (measured: 5 to 7 times the facets), and a mesh over it is not kept;
``mefisto`` is not run when its edges (1/32 of the diagonal) are longer than the part's mean thickness
(:func:`mean_thickness`): a facet then spans the wire (a spring's Mefisto mesh is 16 % to 59 % short). A
helical spring is the usual case: its first mesh is 2.7 % short, ``finer`` gets within 1 % with 99,000
facets, Mefisto is 16 % short.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import MeshPart

from planner.defaults import MESH_REFINEMENTS, MESH_TOLERANCE, MESH_TRIANGLE_BUDGET

__all__ = ["MeshCheck", "checked_mesh", "box_mesh", "mean_thickness", "mefisto_edge", "METHODS", "FINER_GROWTH"]

METHODS = ("standard", "finer", "mefisto", "nurbs", "netgen")
FINER_GROWTH = 5  # facets of a ``finer`` mesh over those of the first (5 to 7 measured on springs and pins)


@dataclass
class MeshCheck:
    """How a part's mesh compares with its B-rep: errors as fractions, the method that made the kept mesh
    (``exact`` when none was within tolerance), and each method tried with its volume error (None: failed)
    and its seconds."""

    volume_error: float
    area_error: float
    method: str
    closed: bool
    tried: list[tuple[str, float | None, float]] = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"volume_error": round(self.volume_error, 6), "area_error": round(self.area_error, 6),
                "method": self.method, "closed": self.closed,
                "tried": [[name, None if error is None else round(error, 6), round(seconds, 3)]
                          for name, error, seconds in self.tried]}


def _mesh(shape, method: str, linear: float, angular: float):
    if method == "standard":
        return MeshPart.meshFromShape(Shape=shape, LinearDeflection=linear, AngularDeflection=angular, Relative=False)
    if method == "nurbs":
        return MeshPart.meshFromShape(Shape=shape.toNurbs(), LinearDeflection=linear, AngularDeflection=angular,
                                      Relative=False)
    if method == "finer":
        return MeshPart.meshFromShape(Shape=shape, LinearDeflection=linear / 5, AngularDeflection=angular / 2,
                                      Relative=False)
    if method == "mefisto":
        return MeshPart.meshFromShape(Shape=shape, MaxLength=shape.BoundBox.DiagonalLength / 32)
    if method == "netgen":
        return MeshPart.meshFromShape(Shape=shape, Fineness=2, SecondOrder=0, Optimize=1, AllowQuad=0)
    raise ValueError(f"unknown tessellation method {method!r}")


def _closed(mesh) -> bool:
    """Merge the points that come once per face, then fill the cracks left where neighbouring faces are
    discretised differently; True when the mesh is closed."""
    if not mesh.isSolid():
        mesh.removeDuplicatedPoints()
    if not mesh.isSolid():
        mesh.fillupHoles(1000, 1)
    return mesh.isSolid()


def box_mesh(shape):
    """A closed mesh of ``shape``'s bounding box (12 facets): the stand-in of a part without a closed mesh."""
    import FreeCAD
    import Mesh
    import Part

    box = shape.BoundBox
    solid = Part.makeBox(max(box.XLength, 1e-6), max(box.YLength, 1e-6), max(box.ZLength, 1e-6),
                         FreeCAD.Vector(box.XMin, box.YMin, box.ZMin))
    return Mesh.Mesh(solid.tessellate(1.0))


def mean_thickness(volume: float, area: float) -> float:
    """``4 volume / area``: a wire's or a rod's diameter, twice a plate's thickness (inf without area)."""
    return 4.0 * volume / area if area > 0 else float("inf")


def mefisto_edge(shape) -> float:
    """The longest edge Mefisto is asked for (:func:`_mesh`): 1/32 of the part's diagonal."""
    return shape.BoundBox.DiagonalLength / 32


def checked_mesh(shape, linear: float, angular: float, tolerance: float = MESH_TOLERANCE,
                 methods: tuple[str, ...] = METHODS, refinements: int = MESH_REFINEMENTS,
                 triangle_budget: int = MESH_TRIANGLE_BUDGET):
    """The mesh of ``shape`` (closed, global coordinates) and its :class:`MeshCheck`.

    Tries ``methods`` in order, at most ``1 + refinements`` of them, and keeps the first closed mesh of at
    most ``triangle_budget`` facets whose volume and area are within ``tolerance`` (a fraction) of the
    B-rep's, else the closed (or any) mesh with the smallest volume error, marked ``exact`` (a method
    skipped for the budget is listed in ``tried`` with error None and 0 s). Cost: one tessellation when
    the first passes (0.01-0.3 s a part); at most ``refinements`` more for a part whose mesh failed (seconds
    each: Mefisto about 4 s on a 64 mm part of 18 faces, 9 s on a spring of 10 turns).
    """
    volume, area = shape.Volume, shape.Area
    best = None  # (closed, -|volume error|) largest is best
    tried: list[tuple[str, float | None, float]] = []
    first_facets = None
    for method in methods[:1 + max(int(refinements), 0)]:
        if method == "finer" and first_facets is not None and first_facets * FINER_GROWTH > triangle_budget:
            tried.append((method, None, 0.0))  # it would be over the budget: not run
            continue
        if method == "mefisto" and mefisto_edge(shape) > mean_thickness(volume, area):
            tried.append((method, None, 0.0))  # its edges are longer than the part is thick: not run
            continue
        start = time.perf_counter()
        try:
            mesh = _mesh(shape, method, linear, angular)
        except Exception:  # a mesher missing from this build (Netgen), or failing on this shape
            mesh = None
        if mesh is None or mesh.CountFacets == 0 or (first_facets is not None and mesh.CountFacets > triangle_budget):
            tried.append((method, None, time.perf_counter() - start))
            continue
        if first_facets is None:
            first_facets = mesh.CountFacets
        closed = _closed(mesh)
        volume_error = (mesh.Volume - volume) / volume
        area_error = (mesh.Area - area) / area
        tried.append((method, volume_error, time.perf_counter() - start))
        if closed and abs(volume_error) <= tolerance and abs(area_error) <= tolerance:
            return mesh, MeshCheck(volume_error, area_error, method, True, tried)
        rank = (closed, -abs(volume_error))
        if best is None or rank > best[0]:
            best = (rank, mesh, volume_error, area_error, closed)
    if best is None:
        return None, MeshCheck(float("nan"), float("nan"), "exact", False, tried)
    _, mesh, volume_error, area_error, closed = best
    return mesh, MeshCheck(volume_error, area_error, "exact", closed, tried)
