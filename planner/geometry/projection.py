"""The mesh engine's obstruction test (paper Sec. III-A): each pair of parts seen along a direction as depth maps on
one pixel grid; a part blocks another along the direction when, in their shared window, it lies ahead of it by
more than the depth tolerance. And the candidate motion directions found on the parts' planar faces."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ..product import Direction
from .meshes import _AXIS_VECTORS, AXES, PartMesh
from .tolerances import Tolerances

__all__ = ["candidate_directions"]


_MERGE_ANGLE = np.radians(2.0)   # directions closer than this are one
_STEP_SLOPE = 4.0                # a depth change of more than this many pixels between neighbours is a step
_PATCH_SHARE = 0.1               # a planar patch proposes its normal when it holds this share of its part's area


_PLANE = {0: (1, 2), 1: (2, 0), 2: (0, 1)}  # the two in-plane axes (u, v) of a projection along each axis


@dataclass
class _DepthMap:
    """A part seen along one axis: window origin (i0, j0) on the global grid, and per pixel the first and
    last depth it occupies (``+inf``/``-inf`` where it is absent)."""

    i0: int
    j0: int
    zmin: np.ndarray
    zmax: np.ndarray
    inner: np.ndarray  # covered and not within `grazing` pixels of the outline


def _rasterise(triangles: np.ndarray, axis: int, origin: np.ndarray, pixel: float, grazing: int,
               jump: float = np.inf) -> _DepthMap:
    u, v = _PLANE[axis]
    uv = (triangles[:, :, [u, v]] - origin) / pixel  # (m, 3, 2) in pixels
    depth = triangles[:, :, axis]
    i0 = int(np.floor(uv[..., 0].min())) - 1
    j0 = int(np.floor(uv[..., 1].min())) - 1
    width = int(np.ceil(uv[..., 0].max())) - i0 + 2
    height = int(np.ceil(uv[..., 1].max())) - j0 + 2
    zmin = np.full(width * height, np.inf)
    zmax = np.full(width * height, -np.inf)

    a, b, c = uv[:, 0], uv[:, 1], uv[:, 2]
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    keep = np.abs(area) > 1e-12  # faces parallel to the axis cover no line
    uv, depth, area = uv[keep], depth[keep], area[keep]
    a, b, c = uv[:, 0], uv[:, 1], uv[:, 2]
    da, db, dc = depth[:, 0], depth[:, 1], depth[:, 2]
    # Depth is affine over a triangle: gradient from the two edge vectors.
    gx = ((db - da) * (c[:, 1] - a[:, 1]) - (dc - da) * (b[:, 1] - a[:, 1])) / area
    gy = ((dc - da) * (b[:, 0] - a[:, 0]) - (db - da) * (c[:, 0] - a[:, 0])) / area

    # Rows whose pixel centres (j + 0.5) the triangle spans.
    vmin, vmax = uv[..., 1].min(axis=1), uv[..., 1].max(axis=1)
    jlo = np.ceil(vmin - 0.5).astype(np.int64)
    rows = np.maximum(np.floor(vmax - 0.5).astype(np.int64) - jlo + 1, 0)
    tri = np.repeat(np.arange(len(rows)), rows)
    y = (jlo[tri] + _ranks(rows) + 0.5)
    # Span of the triangle on each row: intersect the row with the three edges.
    left = np.full(y.shape, np.inf)
    right = np.full(y.shape, -np.inf)
    for p, q in ((a, b), (b, c), (c, a)):
        py, qy, px, qx = p[tri, 1], q[tri, 1], p[tri, 0], q[tri, 0]
        lo, hi = np.minimum(py, qy), np.maximum(py, qy)
        hit = (y >= lo) & (y <= hi) & (hi > lo)
        x = np.where(hit, px + (y - py) * (qx - px) / np.where(hi > lo, qy - py, 1.0), 0.0)
        left = np.where(hit, np.minimum(left, x), left)
        right = np.where(hit, np.maximum(right, x), right)
    ilo = np.ceil(left - 0.5).astype(np.int64)
    cols = np.maximum(np.floor(right - 0.5).astype(np.int64) - ilo + 1, 0)
    sample = np.repeat(np.arange(len(cols)), cols)
    i = ilo[sample] + _ranks(cols)
    j = (y[sample] - 0.5).astype(np.int64)
    t = tri[sample]
    z = da[t] + (i + 0.5 - a[t, 0]) * gx[t] + (j + 0.5 - a[t, 1]) * gy[t]
    index = (j - j0) * width + (i - i0)
    np.minimum.at(zmin, index, z)
    np.maximum.at(zmax, index, z)
    zmin, zmax = zmin.reshape(height, width), zmax.reshape(height, width)
    inner = _erode(zmax >= zmin, grazing)
    if np.isfinite(jump):
        inner &= ~_near_steps(zmin, zmax, inner, jump, grazing)
    return _DepthMap(i0, j0, zmin, zmax, inner)


def _near_steps(zmin: np.ndarray, zmax: np.ndarray, inner: np.ndarray, jump: float, grazing: int) -> np.ndarray:
    """The pixels within ``grazing`` of a *step*: a pixel whose first or last depth differs from a
    neighbour's by more than ``jump``. A step inside a part's outline is the rim of a bore or a stub seen
    end on (a wheel's blind bore on its axle): two coaxial surfaces tessellated differently leave the same
    slivers there as at an outline, so the same band is ignored."""
    step = np.zeros(zmin.shape, dtype=bool)
    for z in (zmin, zmax):
        finite = np.where(inner, z, np.nan)
        for dj, di in ((0, 1), (1, 0), (1, 1), (1, -1)):
            a = finite[max(dj, 0):, max(di, 0):finite.shape[1] + min(di, 0)]
            b = finite[:finite.shape[0] - dj, max(-di, 0):finite.shape[1] - max(di, 0)]
            big = np.abs(a - b) > jump                  # NaN compares False: outline pixels are already out
            step[max(dj, 0):, max(di, 0):finite.shape[1] + min(di, 0)] |= big
            step[:finite.shape[0] - dj, max(-di, 0):finite.shape[1] - max(di, 0)] |= big
    return ndimage.binary_dilation(step, structure=_SQUARE, iterations=grazing)


def _ranks(counts: np.ndarray) -> np.ndarray:
    """0, 1, ..., c - 1 for each count c, concatenated."""
    total = int(counts.sum())
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    return np.arange(total) - starts


_SQUARE = ndimage.generate_binary_structure(2, 2)  # a pixel and its 8 neighbours


def _erode(mask: np.ndarray, radius: int) -> np.ndarray:
    """Binary erosion by ``radius`` pixels (8-neighbourhood): the pixels of ``mask`` whose every pixel within
    ``radius`` (in both directions) is in ``mask``; the border counts as outside."""
    if radius < 1:  # scipy reads 0 iterations as "until nothing changes"
        return mask.copy()
    return ndimage.binary_erosion(mask, structure=_SQUARE, iterations=radius, border_value=0)


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
