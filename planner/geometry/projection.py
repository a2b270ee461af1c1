"""The mesh engine's obstruction test (paper Sec. III-A): each pair of parts seen along a direction as depth maps on
one pixel grid; a part blocks another along the direction when, in their shared window, it lies ahead of it by
more than the depth tolerance. And the candidate motion directions found on the parts' planar faces."""
from __future__ import annotations

import numpy as np

from ..product import Direction
from .meshes import _AXIS_VECTORS, AXES, PartMesh
# The z-buffer (a part's first and last depth on every line along an axis) is :mod:`.raster`'s.
from .raster import DepthMap as _DepthMap
from .raster import _PLANE
from .raster import erode as _erode  # noqa: F401 (the name tests use)
from .raster import rasterise as _rasterise
from .tolerances import Tolerances

__all__ = ["candidate_directions"]


_MERGE_ANGLE = np.radians(2.0)   # directions closer than this are one
_STEP_SLOPE = 4.0                # a depth change of more than this many pixels between neighbours is a step
_PATCH_SHARE = 0.1               # a planar patch proposes its normal when it holds this share of its part's area


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
