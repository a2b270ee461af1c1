"""The mesh engine's z-buffer: a part's triangles seen along one axis, as the first and last depth it occupies on
every line parallel to the axis through a pixel centre (:func:`rasterise`), and the band of lines near its
outline and its steps that the projection test ignores (module docstring of :mod:`.mesh_engine`).

Cost: O(triangles + rows spanned + pixels covered), the pixels covered counted once per triangle covering them
(a sphere's are covered twice, a hollow one's four times), in chunks of about :data:`_CHUNK` samples so that
the work stays in cache and no array of the whole count is held.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DepthMap", "rasterise", "erode", "dilate", "near_steps"]

_PLANE = {0: (1, 2), 1: (2, 0), 2: (0, 1)}  # the two in-plane axes (u, v) of a projection along each axis
_CHUNK = 1 << 18   # samples (pixels of one triangle) handled at once


@dataclass
class DepthMap:
    """A part seen along one axis: window origin (i0, j0) on the global grid, and per pixel the first and
    last depth it occupies (``+inf``/``-inf`` where it is absent)."""

    i0: int
    j0: int
    zmin: np.ndarray
    zmax: np.ndarray
    inner: np.ndarray  # covered and not within `grazing` pixels of the outline


def rasterise(triangles: np.ndarray, axis: int, origin: np.ndarray, pixel: float, grazing: int,
              jump: float = np.inf) -> DepthMap:
    """The depth map of ``triangles`` ``(m, 3, 3) float`` along ``axis`` (0, 1, 2) on the grid of ``pixel``
    units whose corner is ``origin`` ``(2,)`` (the in-plane coordinates), with ``inner`` the covered pixels
    farther than ``grazing`` pixels from the outline and from a step deeper than ``jump`` (:func:`near_steps`).

    A pixel is sampled by each triangle whose projection holds its centre (edges included), at the depth of
    the triangle's plane there; ``zmin`` and ``zmax`` are the least and the greatest of those samples."""
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
    # Per row, the terms of the depth that do not change along it; the depth of pixel i of row j of triangle t
    # is da[t] + (i + 0.5 - a[t, 0]) * gx[t] + (j + 0.5 - a[t, 1]) * gy[t], summed in that order.
    j = (y - 0.5).astype(np.int64)
    row_depth, row_x, row_gx = da[tri], a[tri, 0], gx[tri]
    row_y = (j + 0.5 - a[tri, 1]) * gy[tri]
    row_index = (j - j0) * width - i0  # the flat index of pixel (i, j) is row_index + i
    ends = np.cumsum(cols)
    for start, stop in _chunks(ends):
        n = cols[start:stop]
        begun = int(ends[start - 1]) if start else 0
        i = np.arange(int(ends[stop - 1]) - begun) + np.repeat(ilo[start:stop] - (ends[start:stop] - n - begun), n)
        z = (np.repeat(row_depth[start:stop], n) + (i + 0.5 - np.repeat(row_x[start:stop], n))
             * np.repeat(row_gx[start:stop], n) + np.repeat(row_y[start:stop], n))
        index = i + np.repeat(row_index[start:stop], n)
        _extreme(zmin, index, z, np.less)
        _extreme(zmax, index, z, np.greater)
    zmin, zmax = zmin.reshape(height, width), zmax.reshape(height, width)
    inner = erode(zmax >= zmin, grazing)
    if np.isfinite(jump):
        inner &= ~near_steps(zmin, zmax, inner, jump, grazing)
    return DepthMap(i0, j0, zmin, zmax, inner)


def _chunks(ends: np.ndarray):
    """``(start, stop)`` ranges of rows holding about :data:`_CHUNK` samples each (at least one row), given
    the running total ``ends`` of the samples per row."""
    start, total = 0, len(ends)
    while start < total:
        begun = int(ends[start - 1]) if start else 0
        stop = max(int(np.searchsorted(ends, begun + _CHUNK, side="right")), start + 1)
        yield start, min(stop, total)
        start = stop


def _extreme(out: np.ndarray, index: np.ndarray, z: np.ndarray, better=np.less) -> None:
    """``out[k] = min(out[k], z)`` for every sample ``(k, z)`` of ``index`` and ``z``, repeated indices included
    (``np.minimum.at``'s result, bit for bit: each value written is one of the samples, copied); the maximum
    with ``better=np.greater``.

    An indexed assignment with repeated indices writes one of their values: the samples still better than what
    was written are assigned again, until none is; each pass leaves at least one sample per index behind, so
    there are at most as many passes as samples share a pixel (2 for a sphere). Cost: O(samples) per pass,
    against ``ufunc.at``'s much larger constant."""
    kept = better(z, out[index])
    while True:
        index, z = index[kept], z[kept]
        if not len(index):
            return
        out[index] = z
        kept = better(z, out[index])


def _ranks(counts: np.ndarray) -> np.ndarray:
    """0, 1, ..., c - 1 for each count c, concatenated."""
    total = int(counts.sum())
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    return np.arange(total) - starts


def erode(mask: np.ndarray, radius: int) -> np.ndarray:
    """Binary erosion by ``radius`` pixels (8-neighbourhood): the pixels of ``mask`` whose every pixel within
    ``radius`` (in both directions) is in ``mask``; the border counts as outside. Cost: O(pixels x radius)
    (a pixel and its two neighbours along one axis, then along the other: the 3 x 3 square, ``radius`` times)."""
    out = mask.copy()
    for _ in range(radius):
        for axis in (0, 1):
            out = _shifted(out, axis, np.logical_and, False)
    return out


def dilate(mask: np.ndarray, radius: int) -> np.ndarray:
    """Binary dilation by ``radius`` pixels (8-neighbourhood): the pixels within ``radius`` (in both directions)
    of a pixel of ``mask``; nothing beyond the border is set. Cost: as :func:`erode`."""
    out = mask.copy()
    for _ in range(radius):
        for axis in (0, 1):
            out = _shifted(out, axis, np.logical_or, True)
    return out


def _shifted(mask: np.ndarray, axis: int, combine, keep_edges: bool) -> np.ndarray:
    """Each pixel combined (``np.logical_and`` or ``or``) with its two neighbours along ``axis``; a pixel on the
    border has a missing neighbour: kept as combined with its one neighbour (``keep_edges``) or cleared."""
    out = mask.copy()
    n = mask.shape[axis]
    if n < 2:
        if not keep_edges:
            out[...] = False
        return out
    def cut(lo, hi):
        return (slice(lo, hi), slice(None)) if axis == 0 else (slice(None), slice(lo, hi))
    combine(out[cut(0, n - 1)], mask[cut(1, n)], out=out[cut(0, n - 1)])   # the neighbour after
    combine(out[cut(1, n)], mask[cut(0, n - 1)], out=out[cut(1, n)])       # the neighbour before
    if not keep_edges:
        out[cut(0, 1)] = False
        out[cut(n - 1, n)] = False
    return out


def near_steps(zmin: np.ndarray, zmax: np.ndarray, inner: np.ndarray, jump: float, grazing: int) -> np.ndarray:
    """The pixels within ``grazing`` of a *step*: a pixel whose first or last depth differs from a
    neighbour's by more than ``jump``. A step inside a part's outline is the rim of a bore or a stub seen
    end on (a wheel's blind bore on its axle): two coaxial surfaces tessellated differently leave the same
    slivers there as at an outline, so the same band is ignored. Cost: O(pixels x (8 + grazing)), in bands of
    :data:`_BAND` rows (each with the row above it: its pairs with the band's first row) that stay in cache."""
    step = np.zeros(zmin.shape, dtype=bool)
    rows = zmin.shape[0]
    for first in range(0, rows, _BAND):
        top = max(first - 1, 0)
        band = slice(top, min(first + _BAND, rows))
        _steps(zmin[band], zmax[band], inner[band], jump, step[band])
    return dilate(step, grazing)


_BAND = 64  # rows of a band of :func:`near_steps`


def _steps(zmin: np.ndarray, zmax: np.ndarray, inner: np.ndarray, jump: float, step: np.ndarray) -> None:
    """``step |=`` the pixels of these rows that differ by more than ``jump`` from one of their 8 neighbours in
    these rows, in first or in last depth (pixels outside ``inner`` never do)."""
    rows, columns = zmin.shape
    difference = np.empty(zmin.shape)
    big = np.empty(zmin.shape, dtype=bool)
    for z in (zmin, zmax):
        finite = np.where(inner, z, np.nan)
        for dj, di in ((0, 1), (1, 0), (1, 1), (1, -1)):
            here = (slice(max(dj, 0), None), slice(max(di, 0), columns + min(di, 0)))
            there = (slice(0, rows - dj), slice(max(-di, 0), columns - max(di, 0)))
            d, over = difference[here], big[here]
            np.subtract(finite[here], finite[there], out=d)
            np.abs(d, out=d)
            np.greater(d, jump, out=over)              # NaN compares False: outline pixels are already out
            step[here] |= over
            step[there] |= over
