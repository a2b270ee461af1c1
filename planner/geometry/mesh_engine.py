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
occupies on every line parallel to the axis (a z-buffer holding the minimum and the maximum, :mod:`.raster`),
on a grid of ``scene size / Tolerances.resolution``. ``x`` is blocked by ``y`` along ``+a`` when on some line
through both ``max depth(y) > min depth(x) + depth tolerance``. Lines are infinite, so no obstacle is stepped over,
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
from dataclasses import dataclass, field

import numpy as np

from ..defaults import CONTACT_TOLERANCE
from ..errors import GeometryError
from ..product import Direction
from .raster import DepthMap as _DepthMap
from .raster import _PLANE
from .raster import erode as _erode
from .raster import rasterise as _rasterise
from .tolerances import Tolerances

__all__ = ["Tolerances", "GeometryReport", "PartMesh", "GeometryError", "analyze_meshes", "candidate_directions",
           "AXES", "touching_pairs"]

AXES = ("+X", "+Y", "+Z")
_AXIS_VECTORS = np.eye(3)
_MERGE_ANGLE = np.radians(2.0)   # directions closer than this are one
_STEP_SLOPE = 4.0                # a depth change of more than this many pixels between neighbours is a step
_PATCH_SHARE = 0.1               # a planar patch proposes its normal when it holds this share of its part's area


@dataclass(frozen=True)
class PartMesh:
    """A closed triangle mesh of one part: ``vertices`` (v, 3) float64, ``faces`` (f, 3) int64."""

    id: str
    vertices: np.ndarray
    faces: np.ndarray

    @property
    def triangles(self) -> np.ndarray:
        """(f, 3, 3) float64."""
        return self.vertices[self.faces]


@dataclass(frozen=True)
class GeometryReport:
    """What an engine found: contacts, interferences (a, b, volume) and obstructions per direction (the
    positive axes, named ``+X`` ..., and any other direction by its name, with its unit vector in
    ``directions``)."""

    engine: str
    parts: tuple[str, ...]
    contacts: tuple[tuple[str, str], ...]
    interferences: tuple[tuple[str, str, float], ...]
    obstructions: dict[str, tuple[tuple[str, str], ...]]
    tolerances: dict = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    seconds: float = 0.0
    directions: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    gaps: dict | None = None  # when the contacts fall apart: planner.geometry.clearances.gap_record

    def as_dict(self) -> dict:
        return {"engine": self.engine, "parts": len(self.parts), "contacts": [list(c) for c in self.contacts],
                "interferences": [{"parts": [a, b], "volume": round(v, 6)} for a, b, v in self.interferences],
                "obstructions": {d: [list(p) for p in pairs] for d, pairs in self.obstructions.items()},
                "tolerances": self.tolerances, "warnings": list(self.warnings), "seconds": round(self.seconds, 3),
                **({"directions": {k: list(v) for k, v in self.directions.items()}} if self.directions else {}),
                **({"gaps": self.gaps} if self.gaps is not None else {})}


# ------------------------------------------------------------------------------------------- contacts


# Coordinates farther from the origin than this lose their millimetres in the engines' single precision.
_FARTHEST = 1e7


def _manifold(part: PartMesh):
    try:
        import manifold3d
    except ImportError:  # FreeCAD's Python, installed by the Addon Manager, may lack it: not on its allowed list
        raise GeometryError("the mesh engine needs the Python package manifold3d: pip install manifold3d, or use "
                            "the occt engine (aplan export-freecad --engine occt; in FreeCAD, Engine = occt)") from None

    if not np.isfinite(part.vertices).all():
        raise GeometryError(f"part {part.id!r}: its mesh has coordinates that are not finite numbers (NaN or "
                            "infinity); re-export it from the CAD model")
    farthest = float(np.abs(part.vertices).max()) if part.vertices.size else 0.0
    if farthest > _FARTHEST:
        raise GeometryError(f"part {part.id!r}: its mesh reaches {farthest:.3g} model units from the origin, beyond "
                            f"{_FARTHEST:g} where single precision loses the tolerances; move the product near the "
                            "origin or check its units")
    mesh = manifold3d.Mesh(vert_properties=np.ascontiguousarray(part.vertices, dtype=np.float32),
                           tri_verts=np.ascontiguousarray(part.faces, dtype=np.uint32))
    solid = manifold3d.Manifold(mesh)
    if solid.status() != manifold3d.Error.NoError:
        raise GeometryError(f"part {part.id!r}: its mesh is not a closed, consistently oriented surface "
                            f"({solid.status().name}); re-export it or repair the solid in the CAD model")
    if solid.volume() <= 0:
        raise GeometryError(f"part {part.id!r}: its mesh encloses no volume ({solid.volume():g}); "
                            "check the part in the CAD model")
    return solid


def touching_pairs(parts: list[PartMesh], pairs, tolerance: float) -> list[tuple[str, str]]:
    """The pairs of ``pairs`` (part ids) whose meshes are closer than ``tolerance`` or overlap: the contact
    test of :func:`analyze_meshes` on those pairs only. Cost: one manifold per part named, one gap query per pair."""
    index = {p.id: p for p in parts}
    solids: dict[str, object] = {}
    found = []
    for a, b in pairs:
        for name in (a, b):
            if name not in solids:
                solids[name] = _manifold(index[name])
        if solids[a].min_gap(solids[b], tolerance * 2 + 1e-9) <= tolerance:
            found.append((a, b))
    return found


def _bbox_gaps(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n, n) largest per-axis gap between the bounding boxes (<= 0 when they overlap)."""
    gap = np.maximum(lo[:, None, :] - hi[None, :, :], lo[None, :, :] - hi[:, None, :])
    return gap.max(axis=2)


def _surface_gaps(parts: list[PartMesh]):
    """``gap(i, j)``: the exact distance between the surfaces of parts i and j (FCL, BVHs built on demand)."""
    from .gaps import part_gaps

    def gap(i: int, j: int) -> float:
        return part_gaps(parts, [(parts[i].id, parts[j].id)], cache)[parts[i].id, parts[j].id]

    cache: dict = {}
    return gap


def _nested(lo: np.ndarray, hi: np.ndarray, i: int, j: int) -> bool:
    """True when one bounding box holds the other: one part may lie inside the other."""
    return bool(np.all(lo[i] <= lo[j]) and np.all(hi[j] <= hi[i]) or np.all(lo[j] <= lo[i]) and np.all(hi[i] <= hi[j]))


def _contacts(parts, solids, lo, hi, tol: Tolerances):
    from .gaps import fcl_available

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


# ---------------------------------------------------------------------------------------- obstruction

def _window(first: _DepthMap, second: _DepthMap):
    """The common window of two depth maps as slices into each, or None."""
    j0 = max(first.j0, second.j0)
    i0 = max(first.i0, second.i0)
    j1 = min(first.j0 + first.zmin.shape[0], second.j0 + second.zmin.shape[0])
    i1 = min(first.i0 + first.zmin.shape[1], second.i0 + second.zmin.shape[1])
    if j1 <= j0 or i1 <= i0:
        return None
    def cut(m: _DepthMap):
        return (slice(j0 - m.j0, j1 - m.j0), slice(i0 - m.i0, i1 - m.i0))
    return cut(first), cut(second)


def _frame(direction: np.ndarray) -> np.ndarray:
    """(3, 3): rows e1, e2, d, an orthonormal frame whose third axis is the unit ``direction``."""
    helper = _AXIS_VECTORS[int(np.argmin(np.abs(direction)))]
    e1 = np.cross(direction, helper)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(direction, e1), direction])


def _facet_normals(part: PartMesh) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (f, 3) and areas (f,) of the facets with an area."""
    t = part.triangles
    cross = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    double = np.linalg.norm(cross, axis=1)
    keep = double > 0
    return cross[keep] / double[keep, None], double[keep] / 2


def _canonical(v: np.ndarray) -> np.ndarray:
    """``v`` or ``-v``, whichever has its largest component positive (a direction and its reverse are one)."""
    return v if v[int(np.argmax(np.abs(v)))] > 0 else -v


def candidate_directions(parts: list[PartMesh], limit: int, taken: list[np.ndarray] = ()) -> list[np.ndarray]:
    """At most ``limit`` unit directions besides the axes (and the unit vectors ``taken``: the designer's) that
    parts of ``parts`` may leave along (module docstring), the best backed first; each stands for itself and
    its reverse, and names its vector with components below 1e-6 set to zero. Cost: O(facets)."""
    proposals: list[tuple[float, np.ndarray]] = []   # (area behind it, direction)
    for part in parts:
        normals, areas = _facet_normals(part)
        total = float(areas.sum())
        if total <= 0:
            continue
        # Planar patches: facets whose normals agree to about a degree, a face and the face opposite as one.
        flip = np.sign(normals[np.arange(len(normals)), np.argmax(np.abs(normals), axis=1)])
        normals = normals * flip[:, None]
        keys, inverse = np.unique(np.round(normals * 60).astype(np.int64), axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        patch_area = np.bincount(inverse, weights=areas, minlength=len(keys))
        for k in np.flatnonzero(patch_area >= _PATCH_SHARE * total):
            mean = (normals[inverse == k] * areas[inverse == k, None]).sum(axis=0)
            proposals.append((float(patch_area[k]), mean / np.linalg.norm(mean)))
        # A part turned around one line: its normals' scatter is flat along that line.
        scatter = (normals * areas[:, None]).T @ normals / total
        values, vectors = np.linalg.eigh(scatter)
        if values[0] < 0.5 * values[1] and values[1] > 0.7 * values[2]:
            proposals.append((total * (1 - values[0]), vectors[:, 0]))
    kept: list[np.ndarray] = []
    for _, direction in sorted(proposals, key=lambda p: -p[0]):
        if len(kept) >= limit:
            break
        direction = np.where(np.abs(direction) < 1e-6, 0.0, direction)
        direction = _canonical(direction / np.linalg.norm(direction)) + 0.0
        near = np.vstack([_AXIS_VECTORS, *taken] + kept) @ direction
        if np.all(np.abs(near) < np.cos(_MERGE_ANGLE)):
            kept.append(direction)
    return kept


def _blocking_pairs(parts, triangles, lo, hi, axis, origin3, pixel, tol: Tolerances) -> list[tuple[str, str]]:
    """The pairs ``(x, y)`` with x, moving along ``+axis`` of the frame ``triangles`` are given in, hitting y."""
    u, v = _PLANE[axis]
    origin = origin3[[u, v]]
    maps = [_rasterise(t, axis, origin, pixel, tol.grazing, max(tol.depth, _STEP_SLOPE * pixel)) for t in triangles]
    pairs = []
    margin = 2 * tol.grazing * pixel
    for i in range(len(parts)):
        for j in range(i + 1, len(parts)):
            # Broad phase: the projections' boxes must overlap by more than the grazing band.
            if (min(hi[i, u], hi[j, u]) - max(lo[i, u], lo[j, u]) <= margin or
                    min(hi[i, v], hi[j, v]) - max(lo[i, v], lo[j, v]) <= margin):
                continue
            cut = _window(maps[i], maps[j])
            if cut is None:
                continue
            a, b = maps[i], maps[j]
            both = a.inner[cut[0]] & b.inner[cut[1]]
            if not both.any():
                continue
            amin, amax = a.zmin[cut[0]][both], a.zmax[cut[0]][both]
            bmin, bmax = b.zmin[cut[1]][both], b.zmax[cut[1]][both]
            if np.any(bmax > amin + tol.depth):
                pairs.append((parts[i].id, parts[j].id))  # i moving along +axis hits j
            if np.any(amax > bmin + tol.depth):
                pairs.append((parts[j].id, parts[i].id))
    return pairs


def _obstructions(parts, lo, hi, tol: Tolerances):
    """Obstruction pairs per direction (the axes, then the candidate directions), the directions' vectors
    (candidates only) and the pixel size."""
    extent = float((hi.max(axis=0) - lo.min(axis=0)).max())
    pixel = extent / tol.resolution if extent > 0 else 1.0
    triangles = [p.triangles for p in parts]
    result: dict[str, list[tuple[str, str]]] = {}
    for axis, name in enumerate(AXES):
        result[name] = _blocking_pairs(parts, triangles, lo, hi, axis, lo.min(axis=0), pixel, tol)
    vectors: dict[str, tuple[float, float, float]] = {}
    designer = [np.asarray(v, dtype=float) for v in tol.designer_directions]
    for direction in designer + candidate_directions(parts, tol.directions, designer):
        frame = _frame(direction)
        turned = [t @ frame.T for t in triangles]
        tlo = np.array([t.reshape(-1, 3).min(axis=0) for t in turned])
        thi = np.array([t.reshape(-1, 3).max(axis=0) for t in turned])
        vector = tuple(float(c) for c in direction)
        name = Direction.from_vector(vector).name
        vectors[name] = vector
        result[name] = _blocking_pairs(parts, turned, tlo, thi, 2, tlo.min(axis=0), pixel, tol)
    return result, vectors, pixel


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
