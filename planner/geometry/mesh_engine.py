"""Connection and obstruction diagrams from part meshes (the FreeCAD-free geometry engine).

Definitions
-----------
- Two parts are in *contact* when their surfaces are closer than ``Tolerances.contact``, or when they
  overlap (a press fit, or a small modelling interference such as the pen's button, which overlaps the
  body by about 0.06 mm^3). Overlaps of more than ``Tolerances.interference`` in volume and more than
  ``Tolerances.contact`` in mean thickness (twice the volume over the surface area) are reported as
  *interferences*; thinner ones are slivers between surfaces tessellated differently (the thickness
  threshold stays at the default contact tolerance when a larger one is given).
- Part ``x`` is *blocked* by part ``y`` along ``d`` when ``x``, moved along ``d`` without limit, would
  collide with ``y``: some point of ``y`` lies ahead (along ``d``) of some point of ``x`` on a common line
  parallel to ``d``. The relation along ``-d`` is the one along ``d`` reversed.

Method
------
Contacts and interferences use manifold3d (exact mesh booleans and gap queries). The obstruction test is a
continuous projection test: each part is rasterised along each axis into the first and last depth it
occupies on every line parallel to the axis (a z-buffer holding the minimum and the maximum), on a grid of
``scene size / Tolerances.resolution``. ``x`` is blocked by ``y`` along ``+a`` when on some line through both
``max depth(y) > min depth(x) + depth tolerance``. Lines are infinite, so no obstacle is stepped over,
whatever its thickness along the motion. Lines within ``Tolerances.grazing`` pixels of a part's outline are
ignored, so surfaces that only slide along each other (a peg in its hole, with slivers from tessellating the
two cylinders differently) do not block; an overlap narrower than that is not seen.

Besides the axes, up to ``Tolerances.directions`` *candidate directions* found on the parts' geometry are
tested the same way, in a frame turned so that the direction is its third axis (a wheel leaves along its
axle, a part on an inclined face along the face's normal): per part, the normal of every planar patch that
holds at least a tenth of its area, and the axis of a part whose normals turn around one line (a pin, a
wheel, a screw: the eigenvector of the smallest eigenvalue of the area-weighted scatter ``sum a n n^T`` of
its facet normals, when the two others are close). Directions within 2 degrees of an axis or of one already
kept are merged; the ones backed by the most area come first (:func:`candidate_directions`). The designer's
directions (``Tolerances.designer_directions``) are tested first, always, and candidates along them merged.

Broad phase: pairs whose bounding boxes are farther apart than the contact tolerance, or whose projections
do not overlap, are never tested.
"""
from __future__ import annotations

import time

import numpy as np

from ..defaults import CONTACT_TOLERANCE
from ..errors import GeometryError
from .gaps import fcl_available, part_gaps
from .meshes import AXES, GeometryReport, PartMesh, _manifold, touching_pairs
from .projection import _obstructions, candidate_directions
from .tolerances import Tolerances

__all__ = ["Tolerances", "GeometryReport", "PartMesh", "GeometryError", "analyze_meshes", "candidate_directions",
           "AXES", "touching_pairs"]


def _bbox_gaps(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n, n) largest per-axis gap between the bounding boxes (<= 0 when they overlap)."""
    gap = np.maximum(lo[:, None, :] - hi[None, :, :], lo[None, :, :] - hi[:, None, :])
    return gap.max(axis=2)


def _surface_gaps(parts: list[PartMesh]):
    """``gap(i, j)``: the exact distance between the surfaces of parts i and j (FCL, BVHs built on demand)."""
    def gap(i: int, j: int) -> float:
        return part_gaps(parts, [(parts[i].id, parts[j].id)], cache)[parts[i].id, parts[j].id]

    cache: dict = {}
    return gap


def _nested(lo: np.ndarray, hi: np.ndarray, i: int, j: int) -> bool:
    """True when one bounding box holds the other: one part may lie inside the other."""
    return bool(np.all(lo[i] <= lo[j]) and np.all(hi[j] <= hi[i]) or np.all(lo[j] <= lo[i]) and np.all(hi[i] <= hi[j]))


def _contacts(parts, solids, lo, hi, tol: Tolerances):
    contacts, interferences = [], []
    gaps = _bbox_gaps(lo, hi)
    n = len(parts)
    # Above the default tolerance manifold's gap query slows down with its search length (all triangle pairs
    # within it: 28 s on the pump at 30 mm); FCL's distance is exact and fast at any distance, but measures
    # between surfaces only, so it decides the pairs that are apart and not nested.
    surface_gap = _surface_gaps(parts) if tol.contact > CONTACT_TOLERANCE and fcl_available() else None
    for i in range(n):
        for j in range(i + 1, n):
            if gaps[i, j] > tol.contact:
                continue
            gap = surface_gap(i, j) if surface_gap is not None else 0.0
            if gap == 0.0 or _nested(lo, hi, i, j):
                gap = solids[i].min_gap(solids[j], tol.contact * 2 + 1e-9)
            if gap > tol.contact:
                continue
            contacts.append((parts[i].id, parts[j].id))
            if gap == 0:
                common = solids[i] ^ solids[j]
                volume = common.volume()
                # Mean thickness of the overlap: slivers between surfaces tessellated differently are thin (as
                # thin at any contact tolerance: a tolerance raised to bridge clearances hides no interference).
                thickness = 2 * volume / common.surface_area() if volume > 0 else 0.0
                if volume > tol.interference and thickness > min(tol.contact, CONTACT_TOLERANCE):
                    interferences.append((parts[i].id, parts[j].id, float(volume)))
    return contacts, interferences


def analyze_meshes(parts: list[PartMesh], tolerances: Tolerances = Tolerances()) -> GeometryReport:
    """Contacts, interferences and the obstruction diagrams (+X, +Y, +Z and the candidate directions) of closed
    part meshes.

    Raises :class:`GeometryError` naming the part when a mesh is not closed or encloses no volume.
    Cost: contacts O(pairs near each other x mesh size); obstructions O(pixels covered + triangles) per
    part and axis, plus O(pixels in common) per pair whose projections overlap.
    """
    start = time.perf_counter()
    warnings: list[str] = []
    if not parts:
        raise GeometryError("no parts to analyse")
    solids = [_manifold(p) for p in parts]
    lo = np.array([p.vertices.min(axis=0) for p in parts])
    hi = np.array([p.vertices.max(axis=0) for p in parts])
    contacts, interferences = _contacts(parts, solids, lo, hi, tolerances)
    obstructions, directions, pixel = _obstructions(parts, lo, hi, tolerances)
    for a, b, volume in interferences:
        warnings.append(f"parts {a!r} and {b!r} interpenetrate by {volume:.4g} cubic units "
                        f"(more than the interference tolerance {tolerances.interference:g})")
    used = {"contact": tolerances.contact, "interference": tolerances.interference, "depth": tolerances.depth,
            "resolution": tolerances.resolution, "grazing": tolerances.grazing, "pixel": pixel,
            "directions": tolerances.directions,
            **({"designer_directions": [list(v) for v in tolerances.designer_directions]}
               if tolerances.designer_directions else {})}
    return GeometryReport("mesh", tuple(p.id for p in parts), tuple(contacts), tuple(interferences),
                          {k: tuple(v) for k, v in obstructions.items()}, used, tuple(warnings),
                          time.perf_counter() - start, directions)
