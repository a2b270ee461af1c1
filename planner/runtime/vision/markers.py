"""Which marker is which item, and which markers a frame shows.

- :class:`MarkerMap` / :func:`marker_map`: marker id -> part or tool id, from the product file's ``markers``
  (or :func:`default_markers`: parts then tools numbered 0, 1, ... in file order).
- :class:`MarkerDetector`: the marker ids seen in one frame (OpenCV's ``ArucoDetector``, imported on first
  use); :func:`detections` maps it over a stream of frames.

Cost: detection dominates the vision pipeline (about 15 ms per 1920x1080 frame on one core, see
``bench/bench_vision.py``); most of it goes to the contours of the grain in the frame's uniform areas, which a
detector told where the scene is (:meth:`MarkerDetector.within`: the demo's tray) no longer looks at.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Iterator, Sequence

import numpy as np

from ...errors import PlannerError
from ...product import DEFAULT_MARKER_DICTIONARY, MARKER_DICTIONARIES, Markers, Product

__all__ = ["VisionError", "MarkerMap", "default_markers", "dictionary_size", "marker_map",
           "MarkerDetector", "detections"]


class VisionError(PlannerError):
    """A camera, video or image cannot be opened or read, or the markers do not cover the product."""


@dataclass(frozen=True)
class MarkerMap:
    """Marker id -> part or tool id, for one dictionary; ``tools`` says which items are tools."""

    dictionary: str
    items: dict[int, str]
    tools: frozenset[str]

    def id_of(self, item: str) -> int:
        return next(marker for marker, name in self.items.items() if name == item)


#: The default dictionary's family, smallest first: a product without a 'markers' map gets the first that holds
#: all its items (an 82-part assembly needs DICT_4X4_100: 50 ids are not enough).
_DEFAULT_FAMILY = tuple(sorted((name for name in MARKER_DICTIONARIES
                                if name.rsplit("_", 1)[0] == DEFAULT_MARKER_DICTIONARY.rsplit("_", 1)[0]),
                               key=MARKER_DICTIONARIES.get))


def default_markers(product: Product) -> Markers:
    """Markers numbered 0, 1, ... in the product file's order: the parts, then the tools; in
    :data:`~planner.product.DEFAULT_MARKER_DICTIONARY`, or the first larger one of its family (4x4 bits) that
    holds them all (the largest when none does: :func:`marker_map` then says what to do)."""
    names = [p.id for p in product.parts] + [t.id for t in product.tools]
    dictionary = next((d for d in _DEFAULT_FAMILY if MARKER_DICTIONARIES[d] >= len(names)), _DEFAULT_FAMILY[-1])
    return Markers(tuple((name, k) for k, name in enumerate(names)), dictionary)


def dictionary_size(dictionary: str) -> int | None:
    """How many markers the OpenCV ArUco ``dictionary`` holds (``DICT_4X4_50``: 50), None if OpenCV does not
    know it (:class:`MarkerDetector` says so). O(1) after OpenCV's own lookup."""
    import cv2

    code = getattr(cv2.aruco, dictionary, None) if dictionary in MARKER_DICTIONARIES else None
    if code is None:
        return None
    return int(cv2.aruco.getPredefinedDictionary(code).bytesList.shape[0])


def marker_map(product: Product, require_all: bool = True) -> MarkerMap:
    """The product's marker map (its ``markers``, else :func:`default_markers`).

    With ``require_all``, every part and every tool the operations use must have a marker, since the camera
    cannot see an item without one: :class:`VisionError` lists the missing ones.
    """
    markers = product.markers if product.markers is not None else default_markers(product)
    items = markers.by_id()
    capacity = dictionary_size(markers.dictionary)
    beyond = sorted(k for k in items if not 0 <= k < capacity) if capacity else []
    if beyond:
        how = ("give the product a 'markers' map with a larger dictionary, e.g. DICT_4X4_250 or DICT_5X5_1000"
               if product.markers is None else "choose a larger dictionary in its 'markers' map, or smaller ids")
        raise VisionError(f"{product.source or product.name}: {len(items)} markers, ids up to {max(items)}, but "
                          f"{markers.dictionary} has {capacity} (ids 0 to {capacity - 1}); {how} (see "
                          "docs/product-format.md)")
    if require_all:
        used_tools = {t.id for t in product.tools}
        missing = [name for name in list(product.part_ids) + sorted(used_tools) if markers.of(name) is None]
        if missing:
            raise VisionError(f"{product.source}: no marker for {', '.join(missing)}; add them to the product's "
                              "'markers.ids' (see docs/product-format.md)")
    return MarkerMap(markers.dictionary, items, frozenset(t.id for t in product.tools))


class MarkerDetector:
    """ArUco marker detection in one frame (grey or BGR ``(H, W[, 3]) uint8``).

    ``threshold_windows``: the adaptive-threshold window sizes (pixels, odd, evenly spaced) tried on each
    frame. OpenCV's default tries 3, 13 and 23; every window costs a thresholding and a contour pass, and the
    single window 23 finds markers 40 pixels wide and more under blur, noise and perspective at more than
    twice OpenCV's default frame rate (``bench/bench_vision.py``); ``(13, 23)`` reaches down to about 32
    pixels. ``downscale``: detect on the frame shrunk by this factor (1: full size).

    ``region`` ``(x0, y0, x1, y1)``: the box of the frame outside which every frame shows only a uniform
    ``background`` (a BGR colour, or a grey level), give or take noise: the simulated tray's
    (:func:`planner.runtime.tray.scene_box`). The pixels farther than two threshold windows from the box are
    then set to the background's grey before detection, and cost nothing more. The markers found and their
    corners are those of the whole frame (the same image size, coordinates and parameters; the threshold of
    a pixel reads one window around it), as long as no marker lies out there: a uniform area has no contour.
    One detector per thread (it keeps that image between frames).
    """

    def __init__(self, dictionary: str = DEFAULT_MARKER_DICTIONARY, threshold_windows: Sequence[int] = (23,),
                 downscale: float = 1.0, region: tuple[int, int, int, int] | None = None,
                 background: int | tuple[int, int, int] = 0):
        import cv2

        if dictionary not in MARKER_DICTIONARIES or not hasattr(cv2.aruco, dictionary):
            raise VisionError(f"unknown marker dictionary {dictionary!r}; use one of OpenCV's, e.g. "
                              f"{DEFAULT_MARKER_DICTIONARY}")
        if downscale < 1:
            raise VisionError(f"downscale must be at least 1, got {downscale}")
        windows = sorted(int(w) for w in threshold_windows)
        steps = {b - a for a, b in zip(windows, windows[1:])}
        if not windows or windows[0] < 3 or any(w % 2 == 0 for w in windows) or len(steps) > 1 or 0 in steps:
            raise VisionError("threshold windows must be distinct odd sizes >= 3, evenly spaced; "
                              f"got {threshold_windows}")
        if region is not None and not (0 <= region[0] < region[2] and 0 <= region[1] < region[3]):
            raise VisionError(f"region must be (x0, y0, x1, y1) with 0 <= x0 < x1 and 0 <= y0 < y1; got {region}")
        self.dictionary = dictionary
        self.threshold_windows = tuple(windows)
        self.downscale = downscale
        self.region = None if region is None else tuple(int(v) for v in region)
        self.background = background
        if region is not None:
            colour = np.array(background if isinstance(background, tuple) else (background,) * 3, np.uint8)
            self._background = int(cv2.cvtColor(colour.reshape(1, 1, 3), cv2.COLOR_BGR2GRAY)[0, 0])
            self._canvas = np.empty((0, 0), np.uint8)
        parameters = cv2.aruco.DetectorParameters()
        parameters.adaptiveThreshWinSizeMin = windows[0]
        parameters.adaptiveThreshWinSizeMax = windows[-1]
        parameters.adaptiveThreshWinSizeStep = steps.pop() if steps else 10
        self._detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary)),
                                                 parameters)
        self._cv2 = cv2

    def within(self, region: tuple[int, int, int, int], background: int | tuple[int, int, int]) -> MarkerDetector:
        """This detector's settings, looking at ``region`` of a ``background`` frame only (see the class)."""
        return MarkerDetector(self.dictionary, self.threshold_windows, self.downscale, region, background)

    def detect(self, frame: np.ndarray) -> set[int]:
        """The ids of the markers found in ``frame``."""
        return {marker for marker, _ in self.found(frame)}

    def found(self, frame: np.ndarray) -> list[tuple[int, np.ndarray]]:
        """Each marker found in ``frame``: its id and its four corners, ``(4, 2) float32`` pixels of ``frame``
        (of the shrunk frame with ``downscale``), in OpenCV's order."""
        cv2 = self._cv2
        grey = self._grey(frame)
        if self.downscale > 1:
            height, width = grey.shape
            grey = cv2.resize(grey, (round(width / self.downscale), round(height / self.downscale)),
                              interpolation=cv2.INTER_AREA)
        corners, ids, _ = self._detector.detectMarkers(grey)
        return [] if ids is None else [(int(i), c.reshape(4, 2)) for i, c in zip(ids.ravel(), corners)]

    def _grey(self, frame: np.ndarray) -> np.ndarray:
        """``frame`` in grey; with a region, the background's grey beyond two threshold windows from it (the
        pixels within them are read by the thresholds of the pixels within one window of the region)."""
        cv2 = self._cv2
        if self.region is None:
            return frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        height, width = frame.shape[:2]
        reach = 2 * self.threshold_windows[-1]
        x0, y0, x1, y1 = self.region
        rows = slice(max(y0 - reach, 0), min(y1 + reach, height))
        columns = slice(max(x0 - reach, 0), min(x1 + reach, width))
        if self._canvas.shape != (height, width):
            self._canvas = np.full((height, width), self._background, np.uint8)
        part = frame[rows, columns]
        self._canvas[rows, columns] = part if frame.ndim == 2 else cv2.cvtColor(part, cv2.COLOR_BGR2GRAY)
        return self._canvas


def detections(frames: Iterable[np.ndarray], detector: MarkerDetector) -> Iterator[set[int]]:
    """The marker ids of each frame."""
    for frame in frames:
        yield detector.detect(frame)
