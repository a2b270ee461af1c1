"""The mesh engine's z-buffer (planner/geometry/raster.py) against computations by hand: each pixel centre tested
against each triangle, ``np.minimum.at`` for repeated pixels, scipy's morphology for erosion and dilation."""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from planner.geometry import raster

SQUARE = ndimage.generate_binary_structure(2, 2)


def _by_hand(triangles: np.ndarray, origin: np.ndarray, pixel: float, i0: int, j0: int, shape: tuple[int, int]):
    """zmin, zmax along +Z: every pixel centre tested against every triangle (barycentric coordinates)."""
    zmin, zmax = np.full(shape, np.inf), np.full(shape, -np.inf)
    jj, ii = np.mgrid[0:shape[0], 0:shape[1]]
    x = (ii + i0 + 0.5) * pixel + origin[0]
    y = (jj + j0 + 0.5) * pixel + origin[1]
    for a, b, c in triangles:
        det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
        if abs(det) < 1e-9:
            continue
        s = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / det
        t = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / det
        inside = (s >= 0) & (t >= 0) & (s + t <= 1)
        z = a[2] + s * (b[2] - a[2]) + t * (c[2] - a[2])
        zmin = np.where(inside, np.minimum(zmin, z), zmin)
        zmax = np.where(inside, np.maximum(zmax, z), zmax)
    return zmin, zmax


def test_the_depth_map_equals_each_pixel_tested_against_each_triangle(monkeypatch):
    monkeypatch.setattr(raster, "_CHUNK", 64)  # many chunks, some of one row, on a small raster
    rng = np.random.default_rng(11)
    for trial in range(20):
        triangles = rng.uniform(0, 10, (int(rng.integers(5, 30)), 3, 3))  # overlapping, every orientation
        origin, pixel = np.array([-0.3, 0.1]), float(rng.uniform(0.15, 0.5))
        got = raster.rasterise(triangles, 2, origin, pixel, grazing=1)
        zmin, zmax = _by_hand(triangles, origin, pixel, got.i0, got.j0, got.zmin.shape)
        covered = np.isfinite(zmin)
        assert covered.sum() > 20, trial
        assert np.array_equal(np.isfinite(got.zmin), covered), trial
        assert np.allclose(got.zmin[covered], zmin[covered], rtol=0, atol=1e-9), trial
        assert np.allclose(got.zmax[covered], zmax[covered], rtol=0, atol=1e-9), trial
        assert np.array_equal(got.inner, ndimage.binary_erosion(covered, SQUARE, border_value=0)), trial


def test_the_least_and_greatest_sample_per_pixel_equal_ufunc_at_bit_for_bit():
    rng = np.random.default_rng(5)
    for size in (1, 7, 1000):
        index = rng.integers(0, max(1, size // 4), 4 * size)  # every pixel sampled several times
        z = rng.normal(size=index.shape)
        for better, at, start in ((np.less, np.minimum, np.inf), (np.greater, np.maximum, -np.inf)):
            out, expected = np.full(size, start), np.full(size, start)
            out[::3] = expected[::3] = 0.25  # some pixels hold a value already
            raster._extreme(out, index, z, better)
            at.at(expected, index, z)
            assert out.tobytes() == expected.tobytes()


def test_erosion_and_dilation_equal_scipys():
    rng = np.random.default_rng(9)
    for trial in range(300):
        shape = tuple(int(n) for n in rng.integers(1, 30, size=2))
        mask = rng.random(shape) < rng.choice([0.05, 0.5, 0.95])
        radius = int(rng.integers(1, 4))
        assert np.array_equal(raster.erode(mask, radius),
                              ndimage.binary_erosion(mask, SQUARE, iterations=radius, border_value=0)), trial
        assert np.array_equal(raster.dilate(mask, radius), ndimage.binary_dilation(mask, SQUARE, iterations=radius)), \
            trial


def test_steps_inside_the_outline_are_found_in_every_band(monkeypatch):
    """A plateau 5 deep on a plane of depth 0: the pixels within one of its rim are near a step; bands of 3 rows
    (the rim crossing several) find the same pixels as one band of all the rows."""
    zmin = np.zeros((20, 16))
    zmin[4:13, 3:9] = 5.0
    inner = np.ones(zmin.shape, bool)
    inner[0] = False
    whole = raster.near_steps(zmin, zmin, inner, 1.0, 1)
    monkeypatch.setattr(raster, "_BAND", 3)
    assert np.array_equal(raster.near_steps(zmin, zmin, inner, 1.0, 1), whole)
    rim = ndimage.binary_dilation(zmin > 0, SQUARE) & ~ndimage.binary_erosion(zmin > 0, SQUARE)
    assert np.array_equal(whole, ndimage.binary_dilation(rim, SQUARE))
