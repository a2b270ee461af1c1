"""Marker vision: the operator's observations from a camera watching the parts tray (the paper's Sec. IV).

The cell (Cramer et al. 2021, Fig. 6): every part and tool lies in the tray on top of its own ArUco marker,
so a marker is hidden while its item is in the tray and becomes *visible* when the item is taken. An
operation ends when the tool is grasped, i.e. when the tool's marker appears; the parts whose markers
appeared since the previous operation, with that tool, are the operation's observation
(:class:`~planner.tags.Observation`: one part + tool, two parts + tool, tool only).

Pipeline, one job per piece:

- :class:`MarkerDetector`: the marker ids seen in one frame (OpenCV's ``ArucoDetector``).
- :class:`MarkerTracker`: debounced visibility; a marker changes state only after ``debounce``
  consecutive frames disagree with it, so a hand passing over a marker or a missed detection is ignored.
- :class:`ObservationBuilder`: debounced marker changes -> observations. A part's marker appearing adds the
  part to the pending operation (hidden again before the operation closes: the part was put back); the tool's
  marker appearing closes the operation. Parts and tool events announced for the robot
  (:meth:`ObservationBuilder.expect_robot`) are the robot's, not the operator's. Items start in the tray
  (every marker hidden).
- :class:`VisionSource`: frames -> observations, one per decision step: the next operation the operator
  closes, or :data:`~planner.tags.BLANK` after ``quiet_frames`` frames without any marker change (the
  operator did nothing this step; parts already taken stay pending). Unknown marker ids are ignored with
  one warning each.
- Frame sources: :func:`camera_frames`, :func:`video_frames`, :func:`image_frames`; each raises
  :class:`VisionError` with the cause when it cannot be opened or read.

Cost: detection dominates (about 15 ms per 1920x1080 frame on one core, see ``bench/bench_vision.py``);
tracking and building are O(markers) per frame.
"""
from __future__ import annotations

import queue
import threading
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Iterator, Sequence

import numpy as np

from ..assembly.tags import BLANK, Observation
from ..errors import PlannerError
from ..product.model import (
    DEFAULT_MARKER_DICTIONARY,
    MARKER_DICTIONARIES,
    Markers,
    Product,
)

if TYPE_CHECKING:
    from .session import Instruction

__all__ = [
    "VisionError", "MarkerMap", "marker_map", "default_markers", "MarkerDetector", "MarkerTracker",
    "ObservationBuilder", "VisionSource", "camera_frames", "video_frames", "image_frames", "frames_for",
    "detections", "in_background", "IMAGE_SUFFIXES",
]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")


class VisionError(PlannerError):
    """A camera, video or image cannot be opened or read, or the markers do not cover the product."""


# ---------------------------------------------------------------------------------------------- markers


@dataclass(frozen=True)
class MarkerMap:
    """Marker id -> part or tool id, for one dictionary; ``tools`` says which items are tools."""

    dictionary: str
    items: dict[int, str]
    tools: frozenset[str]

    def id_of(self, item: str) -> int:
        return next(marker for marker, name in self.items.items() if name == item)


def default_markers(product: Product) -> Markers:
    """Markers numbered 0, 1, ... in the product file's order: the parts, then the tools."""
    names = [p.id for p in product.parts] + [t.id for t in product.tools]
    return Markers(tuple((name, k) for k, name in enumerate(names)), DEFAULT_MARKER_DICTIONARY)


def marker_map(product: Product, require_all: bool = True) -> MarkerMap:
    """The product's marker map (its ``markers``, else :func:`default_markers`).

    With ``require_all``, every part and every tool the operations use must have a marker, since the camera
    cannot see an item without one: :class:`VisionError` lists the missing ones.
    """
    markers = product.markers if product.markers is not None else default_markers(product)
    items = markers.by_id()
    if require_all:
        used_tools = {t.id for t in product.tools}
        missing = [name for name in list(product.part_ids) + sorted(used_tools) if markers.of(name) is None]
        if missing:
            raise VisionError(f"{product.source}: no marker for {', '.join(missing)}; add them to the product's "
                              "'markers.ids' (see docs/product-format.md)")
    return MarkerMap(markers.dictionary, items, frozenset(t.id for t in product.tools))


# ---------------------------------------------------------------------------------------------- detection


class MarkerDetector:
    """ArUco marker detection in one frame (grey or BGR ``(H, W[, 3]) uint8``).

    ``threshold_windows``: the adaptive-threshold window sizes (pixels, odd, evenly spaced) tried on each
    frame. OpenCV's default tries 3, 13 and 23; every window costs a thresholding and a contour pass, and the
    single window 23 finds markers 40 pixels wide and more under blur, noise and perspective at more than
    twice OpenCV's default frame rate (``bench/bench_vision.py``); ``(13, 23)`` reaches down to about 32
    pixels. ``downscale``: detect on the frame shrunk by this factor (1: full size).
    """

    def __init__(self, dictionary: str = DEFAULT_MARKER_DICTIONARY, threshold_windows: Sequence[int] = (23,),
                 downscale: float = 1.0):
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
        self.dictionary = dictionary
        self.downscale = downscale
        parameters = cv2.aruco.DetectorParameters()
        parameters.adaptiveThreshWinSizeMin = windows[0]
        parameters.adaptiveThreshWinSizeMax = windows[-1]
        parameters.adaptiveThreshWinSizeStep = steps.pop() if steps else 10
        self._detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary)),
                                                 parameters)
        self._cv2 = cv2

    def detect(self, frame: np.ndarray) -> set[int]:
        """The ids of the markers found in ``frame``."""
        cv2 = self._cv2
        grey = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        if self.downscale > 1:
            height, width = grey.shape
            grey = cv2.resize(grey, (round(width / self.downscale), round(height / self.downscale)),
                              interpolation=cv2.INTER_AREA)
        _, ids, _ = self._detector.detectMarkers(grey)
        return set() if ids is None else {int(i) for i in ids.ravel()}


class MarkerTracker:
    """Debounced visibility of a fixed set of marker ids; all start hidden.

    A marker's state flips after ``debounce`` consecutive frames that disagree with it; shorter flickers
    (a hand passing over, a missed detection, a false one) change nothing.
    """

    def __init__(self, ids: Iterable[int], debounce: int = 3):
        if debounce < 1:
            raise VisionError(f"debounce must be at least 1 frame, got {debounce}")
        self.debounce = debounce
        self.visible: dict[int, bool] = {int(i): False for i in ids}
        self._disagree: dict[int, int] = {i: 0 for i in self.visible}

    def update(self, detected: set[int]) -> list[tuple[int, bool]]:
        """Feed one frame's detections (unknown ids are the caller's business); return the changes
        ``(marker id, now visible)`` this frame confirms, in id order."""
        changes = []
        for marker, visible in self.visible.items():
            if (marker in detected) != visible:
                self._disagree[marker] += 1
                if self._disagree[marker] >= self.debounce:
                    self.visible[marker] = not visible
                    self._disagree[marker] = 0
                    changes.append((marker, not visible))
            else:
                self._disagree[marker] = 0
        return changes


@dataclass
class ObservationBuilder:
    """Debounced marker changes -> the operator's observations (rules in the module docstring).

    ``close_without_tool``: at a quiet period, pending parts form an operation without a tool (for products
    whose operations need none); otherwise they wait for the tool.
    """

    markers: MarkerMap
    close_without_tool: bool = False
    pending: list[str] = field(default_factory=list)
    taken: set[str] = field(default_factory=set)
    robot_parts: set[str] = field(default_factory=set)
    robot_tools: list[str] = field(default_factory=list)

    def expect_robot(self, parts: Iterable[str], tool: str | None) -> None:
        """The robot is about to take ``parts`` and use ``tool``: those marker events are not the operator's."""
        self.robot_parts.update(parts)
        if tool is not None:
            self.robot_tools.append(tool)

    def change(self, marker: int, visible: bool) -> Observation | None:
        """Apply one debounced change; the observation when it closes an operator operation."""
        item = self.markers.items[marker]
        if item in self.markers.tools:
            if not visible:
                return None  # the tool is back in the tray
            if item in self.robot_tools:
                self.robot_tools.remove(item)
                return None
            return self._close(item)
        if visible:
            if item in self.taken:
                return None  # shown again after an occlusion
            self.taken.add(item)
            if item in self.robot_parts:
                self.robot_parts.discard(item)
            else:
                self.pending.append(item)
        elif item in self.pending:  # put back before the operation closed
            self.pending.remove(item)
            self.taken.discard(item)
        return None

    def quiet(self) -> Observation:
        """A quiet period passed: blank, or the pending parts without a tool (``close_without_tool``)."""
        if self.close_without_tool and self.pending:
            return self._close(None)
        return BLANK

    def _close(self, tool: str | None) -> Observation:
        observation = Observation(tuple(sorted(self.pending)), tool)
        self.pending.clear()
        return observation


# ---------------------------------------------------------------------------------------------- sources


class VisionSource:
    """An observation source (:class:`planner.session.ObservationSource`) over a stream of frames.

    ``frames`` yields ``(H, W[, 3]) uint8`` images. :meth:`observe` reads frames until the operator closes an
    operation (its observation), or ``quiet_frames`` frames pass without a marker change (BLANK), or the
    frames end (None, or BLANK first when frames were read in this call).
    ``robot_uses_tray_tools``: the robot takes its tool from the tray too (the paper's setup), so one tool
    event per robot operation is the robot's; False when the robot has tools of its own.
    ``on_warning`` receives each warning (an unknown marker id, once per id; a robot pick that never showed);
    default: :func:`warnings.warn`. ``detections`` replaces ``frames`` by the marker ids of each frame.
    """

    def __init__(self, frames: Iterable[np.ndarray], markers: MarkerMap, detector: MarkerDetector | None = None,
                 debounce: int = 3, quiet_frames: int = 45, close_without_tool: bool = False,
                 on_warning=None, detections: Iterable[set[int]] | None = None, robot_uses_tray_tools: bool = True):
        if quiet_frames <= debounce:
            raise VisionError(f"quiet_frames ({quiet_frames}) must exceed debounce ({debounce})")
        self.markers = markers
        self.detector = detector or MarkerDetector(markers.dictionary)
        self.tracker = MarkerTracker(markers.items, debounce)
        self.builder = ObservationBuilder(markers, close_without_tool)
        self.quiet_frames = quiet_frames
        self.robot_uses_tray_tools = robot_uses_tray_tools
        self.frames_read = 0
        self.unknown: set[int] = set()
        self._warn = on_warning or (lambda message: warnings.warn(message, RuntimeWarning, stacklevel=3))
        self._detections = iter(detections) if detections is not None else (self.detector.detect(f) for f in frames)
        self._queued: list[Observation] = []

    def robot_acting(self, instruction: Instruction) -> None:
        """The robot is about to perform ``instruction``: its parts and tool are not the operator's.

        What the robot's previous step should have shown and did not is dropped, with a warning, so a missed
        robot event cannot swallow the operator's later ones."""
        builder = self.builder
        left = sorted(builder.robot_parts) + builder.robot_tools
        if left:
            self._warn(f"the robot's previous operation never showed {', '.join(left)} leaving the tray "
                       "(taken earlier, or not seen); no longer expected")
            builder.robot_parts.clear()
            builder.robot_tools.clear()
        if instruction.operation is not None:
            builder.expect_robot(instruction.picks, instruction.tool if self.robot_uses_tray_tools else None)

    def observe(self) -> Observation | None:
        """The operator's next operation, BLANK after a quiet period, None when the frames have ended."""
        if self._queued:
            return self._queued.pop(0)
        quiet = 0
        read = 0
        for detected in self._detections:
            self.frames_read += 1
            read += 1
            unknown = detected - self.markers.items.keys() - self.unknown
            for marker in sorted(unknown):
                self.unknown.add(marker)
                self._warn(f"marker {marker} is not in the product's marker map ({self.markers.dictionary}); "
                           "ignored")
            changes = self.tracker.update(detected & self.markers.items.keys())
            closed = [o for o in (self.builder.change(m, v) for m, v in changes) if o is not None]
            if closed:
                self._queued.extend(closed[1:])
                return closed[0]
            quiet = 0 if changes else quiet + 1
            if quiet >= self.quiet_frames:
                return self.builder.quiet()
        return self.builder.quiet() if read else None

    def close(self) -> None:
        close = getattr(self._detections, "close", None)
        if close is not None:
            close()


def _open_capture(target, what: str, fix: str):
    import cv2

    capture = cv2.VideoCapture(target)
    if not capture.isOpened():
        capture.release()
        raise VisionError(f"{what} cannot be opened; {fix}")
    return capture


def _read_all(capture, what: str, must_read: bool) -> Iterator[np.ndarray]:
    try:
        count = 0
        while True:
            ok, frame = capture.read()
            if not ok or frame is None:
                if count == 0 and must_read:
                    raise VisionError(f"{what} delivers no frames; check the file or device")
                return
            count += 1
            yield frame
    finally:
        capture.release()


def camera_frames(index: int) -> Iterator[np.ndarray]:
    """Frames from camera ``index`` (OpenCV's numbering: /dev/video<index> on Linux) until it stops."""
    capture = _open_capture(index, f"camera {index}",
                            "check the index (ls /dev/video*), the cable, and that no other program uses it")
    return _read_all(capture, f"camera {index}", True)


def video_frames(path: str | Path) -> Iterator[np.ndarray]:
    """The frames of a video file, in order."""
    path = Path(path)
    if not path.is_file():
        raise VisionError(f"{path}: no such video file")
    capture = _open_capture(str(path), f"{path}", "it is not a video OpenCV can decode (try an .mp4 or .avi)")
    return _read_all(capture, str(path), True)


def image_frames(folder: str | Path) -> Iterator[np.ndarray]:
    """The images of ``folder`` (``IMAGE_SUFFIXES``) in file-name order; an unreadable one is an error."""
    import cv2

    folder = Path(folder)
    if not folder.is_dir():
        raise VisionError(f"{folder}: no such folder of images")
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise VisionError(f"{folder}: holds no images ({', '.join(IMAGE_SUFFIXES)})")

    def read() -> Iterator[np.ndarray]:
        for path in files:
            frame = cv2.imread(str(path), cv2.IMREAD_COLOR)
            if frame is None:
                raise VisionError(f"{path}: cannot be read as an image (damaged or not an image); remove or "
                                  "replace it")
            yield frame

    return read()


def in_background(items: Iterator, maxsize: int = 0) -> Iterator:
    """Run ``items`` in a thread and yield what it yields (errors re-raised here), so a live camera keeps
    being read and detected while the loop waits for the robot; closing the iterator stops the thread."""
    channel: queue.Queue = queue.Queue(maxsize)
    stop = threading.Event()
    done = object()

    def put(message) -> bool:
        while not stop.is_set():
            try:
                channel.put(message, timeout=0.05)
                return True
            except queue.Full:
                continue
        return False

    def pump() -> None:
        try:
            for item in items:
                if not put(("item", item)):
                    return
        except BaseException as exc:  # handed to the consumer, which re-raises it
            put(("error", exc))
            return
        finally:
            close = getattr(items, "close", None)
            if close is not None:
                close()  # releases the camera
        put(("done", done))

    thread = threading.Thread(target=pump, name="aplan-vision", daemon=True)
    thread.start()

    def consume() -> Iterator:
        try:
            while True:
                kind, item = channel.get()
                if kind == "item":
                    yield item
                elif kind == "error":
                    raise item
                else:
                    return
        finally:
            stop.set()

    return consume()


def detections(frames: Iterable[np.ndarray], detector: MarkerDetector) -> Iterator[set[int]]:
    """The marker ids of each frame."""
    for frame in frames:
        yield detector.detect(frame)


def frames_for(camera: int | None = None, video: str | None = None, images: str | None = None) -> Iterator[np.ndarray]:
    """The frame source named by exactly one of ``camera``, ``video``, ``images``."""
    chosen = [x is not None for x in (camera, video, images)]
    if sum(chosen) != 1:
        raise VisionError("give exactly one of a camera index, a video file or a folder of images")
    if camera is not None:
        return camera_frames(camera)
    return video_frames(video) if video is not None else image_frames(images)
