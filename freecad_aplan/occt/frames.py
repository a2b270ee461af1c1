"""Boxes seen along a direction: the frame of a unit vector, and the boxes of boxes in it (the culling of the
sweeps along directions other than the axes). Plain numpy: no FreeCAD, so that it is tested without it."""
from __future__ import annotations

import numpy as np

__all__ = ["direction_frame", "frame_boxes"]

_CORNERS = np.array([[(k >> m) & 1 for m in range(3)] for k in range(8)], dtype=bool)  # which corner takes max


def direction_frame(d) -> np.ndarray:
    """Rows ``(u, v, d)``: two unit vectors across the unit vector ``d``, then ``d`` (an orthonormal frame).
    Along an axis, the other two axes in order, so that :func:`frame_boxes` only permutes coordinates
    (exactly). Cost O(1)."""
    d = np.asarray(d, dtype=float)
    d = d / np.linalg.norm(d)
    for k in range(3):
        if abs(d[k]) == 1.0 and np.count_nonzero(d) == 1:
            across = [np.eye(3)[m] for m in range(3) if m != k]
            return np.array([*across, d])
    helper = np.eye(3)[int(np.argmin(np.abs(d)))]
    u = np.cross(helper, d)
    u /= np.linalg.norm(u)
    return np.array([u, np.cross(d, u), d])


def frame_boxes(boxes: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """The boxes, in the coordinates of ``frame`` (rows: unit vectors), of the 8 corners of each box of
    ``boxes`` (``(n, 2, 3)``, min and max corners): each contains every point of its box, in frame
    coordinates (a box is the hull of its corners), so a culling test on them never drops a pair that could
    meet. Exact for a frame of the axes (coordinates are only permuted). Cost O(n)."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 2, 3)
    if len(boxes) == 0:
        return boxes
    corners = np.where(_CORNERS[None], boxes[:, None, 1, :], boxes[:, None, 0, :])  # (n, 8, 3)
    turned = corners @ np.asarray(frame, dtype=float).T
    return np.stack([turned.min(axis=1), turned.max(axis=1)], axis=1)
