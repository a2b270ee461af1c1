"""The culling of the exact engine's sweeps along any direction (freecad_aplan.occt.frames), against brute force:
the box of a box's corners in the direction's frame. Plain numpy: the module is loaded without FreeCAD."""
from __future__ import annotations

import importlib.util
import itertools

import numpy as np
import pytest
from conftest import REPO

_spec = importlib.util.spec_from_file_location("occt_frames", REPO / "freecad_aplan" / "occt" / "frames.py")
frames = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(frames)


def _random_boxes(rng, n: int, spread: float = 50.0) -> np.ndarray:
    lo = rng.uniform(-spread, spread, (n, 3))
    return np.stack([lo, lo + rng.uniform(0, 20, (n, 3))], axis=1)


@pytest.mark.parametrize("d", [(1, 0, 0), (0, 1, 0), (0, 0, 1), (0, -0.5, 0.75 ** 0.5), (1, 2, -3), (-1e-9, 0, 1)])
def test_frame_is_orthonormal_and_ends_with_the_direction(d):
    frame = frames.direction_frame(d)
    assert frame @ frame.T == pytest.approx(np.eye(3), abs=1e-12)
    assert frame[2] == pytest.approx(np.asarray(d, float) / np.linalg.norm(d), abs=1e-12)


def test_frame_boxes_equal_the_corners_brute_force_and_hold_every_point():
    rng = np.random.default_rng(13)
    boxes = _random_boxes(rng, 40)
    for d in rng.normal(size=(20, 3)):
        frame = frames.direction_frame(d)
        got = frames.frame_boxes(boxes, frame)
        for box, turned in zip(boxes, got):
            picks = itertools.product((0, 1), repeat=3)
            corners = np.array([[box[c][k] for k, c in enumerate(pick)] for pick in picks])
            seen = corners @ frame.T
            assert turned[0] == pytest.approx(seen.min(axis=0), abs=1e-12)
            assert turned[1] == pytest.approx(seen.max(axis=0), abs=1e-12)
            inside = (box[0] + rng.uniform(0, 1, (50, 3)) * (box[1] - box[0])) @ frame.T
            assert np.all(inside >= turned[0] - 1e-9) and np.all(inside <= turned[1] + 1e-9)


def test_axis_frames_only_permute_coordinates():
    boxes = _random_boxes(np.random.default_rng(5), 10)
    for axis in range(3):
        got = frames.frame_boxes(boxes, frames.direction_frame(np.eye(3)[axis]))
        across = [k for k in range(3) if k != axis]
        assert np.array_equal(got, boxes[:, :, across + [axis]])


def test_no_pair_that_meets_is_culled():
    """Pairs of random boxes: when a point of the first, moved along d, enters the second (brute force on
    sample points), their frame boxes overlap across d and the second reaches beyond the first's start."""
    rng = np.random.default_rng(7)
    met = 0
    for _ in range(300):
        a, b = _random_boxes(rng, 2, spread=15.0)
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        frame = frames.direction_frame(d)
        (alo, ahi), (blo, bhi) = frames.frame_boxes(np.array([a, b]), frame)
        points = a[0] + rng.uniform(0, 1, (200, 3)) * (a[1] - a[0])
        moved = points[:, None, :] + np.linspace(0, 200, 80)[None, :, None] * d
        meets = np.any(np.all((moved > b[0]) & (moved < b[1]), axis=2))
        if meets:
            met += 1
            assert all(min(ahi[k], bhi[k]) > max(alo[k], blo[k]) for k in (0, 1)) and bhi[2] > alo[2]
    assert met > 50  # the check ran on pairs that meet
