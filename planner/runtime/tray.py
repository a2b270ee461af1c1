"""The parts tray: marker images and synthetic camera views of the tray (the printable sheet: ``sheet``).

A *tray layout* places one slot per part and tool on a grid; each slot holds the item's ArUco marker, and
the item, while it lies in the tray, covers it (the paper's Fig. 6). :func:`render_tray` draws what an
overhead camera sees, with optional blur, sensor noise, a perspective tilt and occluders (hands);
:class:`SimulatedCell` films a scripted operator and a scripted robot working from the tray. Tests, demos
and benchmarks render their frames with them, so the vision pipeline runs on images whose truth is known.
:func:`scene_box` bounds what such frames show besides the bench top (a detector need look nowhere else).
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np

from ..errors import PlannerError
from .interfaces import Instruction, instruction_of_operation
from .scripted import ScriptedOperator
from .vision.markers import MarkerMap

__all__ = ["marker_image", "TrayLayout", "tray_layout", "render_tray", "Occluder", "CameraModel", "SimulatedCell",
           "scene_box", "BENCH"]


BENCH = (70, 90, 110)  # BGR of the bench top around the tray (and beyond a tilted camera's frame)


def marker_image(dictionary: str, marker: int, pixels: int) -> np.ndarray:
    """The ``(pixels, pixels) uint8`` image of marker ``marker`` (black border included, no white margin)."""
    import cv2

    return cv2.aruco.generateImageMarker(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary)),
                                         marker, pixels)


@dataclass(frozen=True)
class TrayLayout:
    """Slot of each item: the top-left corner ``(x, y)`` of its marker, in pixels of a ``size`` frame."""

    markers: MarkerMap
    size: tuple[int, int]  # (width, height)
    marker_px: int
    slots: dict[str, tuple[int, int]]


def tray_layout(markers: MarkerMap, size: tuple[int, int] = (1920, 1080), marker_px: int = 96,
                columns: int | None = None, margin: float = 0.0) -> TrayLayout:
    """A grid of slots centred in the frame, ``2.2 * marker_px`` apart, items in marker-id order. ``margin``: the
    fraction of the frame's width and height kept free on each side (a tilted camera moves the frame's corners;
    a marker at the edge then flickers), ``marker_px`` made smaller where the grid would reach into it."""
    names = [markers.items[k] for k in sorted(markers.items)]
    columns = columns or math.ceil(math.sqrt(len(names) * size[0] / size[1]))
    rows = math.ceil(len(names) / columns)
    if margin > 0:
        room = min(size[0] * (1 - 2 * margin) / columns, size[1] * (1 - 2 * margin) / rows)
        marker_px = max(1, min(marker_px, int(room / 2.2)))
    pitch = int(2.2 * marker_px)
    x0 = (size[0] - columns * pitch) // 2 + (pitch - marker_px) // 2
    y0 = (size[1] - rows * pitch) // 2 + (pitch - marker_px) // 2
    if x0 < 0 or y0 < 0:
        raise PlannerError(f"{len(names)} markers of {marker_px} px do not fit a {size[0]}x{size[1]} frame")
    slots = {name: (x0 + (k % columns) * pitch, y0 + (k // columns) * pitch) for k, name in enumerate(names)}
    return TrayLayout(markers, size, marker_px, slots)


@dataclass(frozen=True)
class Occluder:
    """An ellipse (a hand or an arm) drawn over the tray: centre, half-axes in pixels, angle in degrees."""

    center: tuple[int, int]
    axes: tuple[int, int]
    angle: float = 0.0


def render_tray(layout: TrayLayout, in_tray: Iterable[str], blur: float = 0.0, noise: float = 0.0,
                perspective: float = 0.0, occluders: Sequence[Occluder] = (), seed: int = 0,
                camera_seed: int = 0) -> np.ndarray:
    """The ``(H, W, 3) uint8`` BGR view of the tray with the items ``in_tray`` covering their markers.

    ``blur``: Gaussian sigma in pixels; ``noise``: standard deviation of additive Gaussian noise (grey
    levels): the frame's window, at an offset drawn from ``seed``, of the camera's grain (:func:`_grain`, drawn
    once from ``camera_seed``); ``perspective``: each frame corner moves by up to this fraction of the frame
    size (a tilted camera, drawn from ``camera_seed``: the same for every frame of one camera); ``occluders``
    are drawn over everything else. Cost: the scene without occluders is drawn, tilted and blurred once per
    set of items in the tray (the last few are kept), and again around each occluder; then each frame costs
    two saturated additions of its grain.
    """
    import cv2

    present = frozenset(in_tray) & frozenset(layout.slots)
    if occluders:
        frame = _scene(layout, present, blur, perspective, occluders, camera_seed)
    else:
        frame = _cached(layout, (present, blur, perspective, camera_seed),
                        lambda: _scene(layout, present, blur, perspective, (), camera_seed))
    if noise > 0:
        height, width = frame.shape[:2]
        up, down = _grain(layout, (height, width), noise, camera_seed)
        row, column = (int(k) for k in np.random.default_rng(seed).integers(0, _ROLL + 1, 2))
        window = (slice(row, row + height), slice(column, column + width))
        # frame + grain saturated to 0..255: the grain's positive part added, its negative part subtracted,
        # each saturated (one of them is 0 at every pixel): numpy's clip of the sum, bytes for bytes
        return cv2.subtract(cv2.add(frame, up[window]), down[window])
    return frame.copy()


_SCENES: dict[int, tuple] = {}  # id(layout) -> (layout, {key: frame}): drawn scenes, the last few
_GRAINS: dict[int, tuple] = {}  # id(layout) -> (layout, {key: arrays}): the cameras' grains and maps, the last few
_ROLL = 64  # the grain is this many pixels taller and wider than the frame: (_ROLL + 1) ** 2 windows


def _cached(layout: TrayLayout, key: tuple, make, store: dict = _SCENES, keep: int = 12):
    """``make()`` for ``layout`` and ``key``, kept in ``store`` with the ``keep`` latest of the layout (the
    arrays are only read)."""
    cache = store.setdefault(id(layout), (layout, {}))
    if cache[0] is not layout:   # another layout took a freed one's id
        store[id(layout)] = cache = (layout, {})
    kept = cache[1]
    if key not in kept:
        if len(kept) >= keep:
            kept.pop(next(iter(kept)))
        kept[key] = make()
    return kept[key]


def _grain(layout: TrayLayout, size: tuple[int, int], noise: float, camera_seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A camera's sensor grain: Gaussian noise of standard deviation ``noise`` grey levels, drawn once by OpenCV
    from ``camera_seed`` (``cv2.setRNGSeed``, ``cv2.randn`` into ``int16``) for ``(H + _ROLL, W + _ROLL)``
    pixels and the same on the three channels (luminance noise: what survives the grey conversion), as its
    positive and its negative part in ``uint8`` (clipped at 255: the sum saturates anyway). Each frame adds a
    window of it: drawing fresh noise for every frame cost more than the rest of the frame."""
    def draw():
        import cv2

        cv2.setRNGSeed(camera_seed)
        grain = np.empty((size[0] + _ROLL, size[1] + _ROLL), np.int16)
        cv2.randn(grain, 0, noise)
        up = np.clip(grain, 0, 255).astype(np.uint8)
        down = np.clip(-grain.astype(np.int32), 0, 255).astype(np.uint8)
        return cv2.merge((up, up, up)), cv2.merge((down, down, down))
    return _cached(layout, (size, noise, camera_seed), draw, _GRAINS, keep=4)


def _drawn(layout: TrayLayout, present: frozenset) -> np.ndarray:
    """The tray, flat and sharp, with the items ``present`` covering their markers (kept: only read)."""
    return _cached(layout, ("drawn", present), lambda: _draw(layout, present))


def _draw(layout: TrayLayout, present: frozenset) -> np.ndarray:
    import cv2

    width, height = layout.size
    frame = np.empty((height, width, 3), np.uint8)
    frame[:] = BENCH
    px = layout.marker_px
    margin = px // 3
    xs = [x for x, _ in layout.slots.values()]
    ys = [y for _, y in layout.slots.values()]
    cv2.rectangle(frame, (min(xs) - 2 * margin, min(ys) - 2 * margin), (max(xs) + px + 2 * margin,
                  max(ys) + px + 2 * margin), (150, 160, 165), -1)  # the tray
    for k, (name, (x, y)) in enumerate(layout.slots.items()):
        cv2.rectangle(frame, (x - margin // 2, y - margin // 2), (x + px + margin // 2, y + px + margin // 2),
                      (255, 255, 255), -1)
        image = marker_image(layout.markers.dictionary, layout.markers.id_of(name), px)
        frame[y:y + px, x:x + px] = image[:, :, None]
        if name in present:  # the item covers its marker
            colour = tuple(int(c) for c in np.random.default_rng(k).integers(40, 220, 3))
            cv2.rectangle(frame, (x - margin, y - margin), (x + px + margin, y + px + margin), colour, -1)
            cv2.putText(frame, name, (x - margin + 4, y + px // 2), cv2.FONT_HERSHEY_SIMPLEX, px / 200, (0, 0, 0), 2)
    return frame


def _scene(layout: TrayLayout, present: frozenset, blur: float, perspective: float,
           occluders: Sequence[Occluder], camera_seed: int) -> np.ndarray:
    """The frame of :func:`render_tray` before its noise: the drawn tray, its occluders drawn over it, seen by
    the tilted camera (:func:`_tilt`), blurred. With occluders, only the pixels they can reach are computed
    again, on the scene without them: each occluder's box, tilted, grown by the interpolation's pixel and the
    blur's reach (every step is local, so the pixels are those of the whole frame computed anew)."""
    import cv2

    drawn = _drawn(layout, present)
    if not occluders:
        return _blurred(_tilt(layout, perspective, camera_seed, drawn), blur)
    bare = _cached(layout, (present, blur, perspective, camera_seed),
                   lambda: _scene(layout, present, blur, perspective, (), camera_seed))
    frame, drawn = bare.copy(), drawn.copy()
    for occluder in occluders:
        cv2.ellipse(drawn, occluder.center, occluder.axes, occluder.angle, 0, 360, (120, 150, 200), -1)
    width, height = layout.size
    reach = math.ceil(4 * blur) + 1 if blur > 0 else 0   # beyond OpenCV's kernel radius (3 sigma for uint8)
    for occluder in occluders:
        x0, y0, x1, y1 = _tilted_box(layout, perspective, camera_seed, _ellipse_box(occluder))
        out = (slice(max(y0 - reach, 0), min(y1 + reach, height)), slice(max(x0 - reach, 0), min(x1 + reach, width)))
        if out[0].start >= out[0].stop or out[1].start >= out[1].stop:
            continue
        ys = slice(max(out[0].start - reach, 0), min(out[0].stop + reach, height))
        xs = slice(max(out[1].start - reach, 0), min(out[1].stop + reach, width))
        part = _blurred(_tilt(layout, perspective, camera_seed, drawn, (ys, xs)), blur)
        frame[out] = part[out[0].start - ys.start:out[0].stop - ys.start,
                          out[1].start - xs.start:out[1].stop - xs.start]
    return frame


def _blurred(frame: np.ndarray, blur: float) -> np.ndarray:
    import cv2

    return cv2.GaussianBlur(frame, (0, 0), blur) if blur > 0 else frame


def _ellipse_box(occluder: Occluder) -> tuple[int, int, int, int]:
    """``(x0, y0, x1, y1)``: pixels ``x0 <= x < x1``, ``y0 <= y < y1`` hold every pixel the ellipse fills (the
    turned ellipse's box; OpenCV fills a polygon of points on it rounded to pixels: two pixels to spare)."""
    a, b = occluder.axes
    turn = math.radians(occluder.angle)
    half_x = math.hypot(a * math.cos(turn), b * math.sin(turn))
    half_y = math.hypot(a * math.sin(turn), b * math.cos(turn))
    x, y = occluder.center
    return (math.floor(x - half_x) - 2, math.floor(y - half_y) - 2, math.ceil(x + half_x) + 3,
            math.ceil(y + half_y) + 3)


def _camera(layout: TrayLayout, perspective: float, camera_seed: int):
    """The tilted camera's homography (frame -> view) and its view -> frame maps for ``cv2.remap``, in OpenCV's
    fixed point (drawn from ``camera_seed``: each corner moves by up to ``perspective`` of the frame's size)."""
    def make():
        import cv2

        width, height = layout.size
        corners = np.float32([[0, 0], [width, 0], [width, height], [0, height]])
        shift = np.random.default_rng(camera_seed).uniform(-perspective, perspective, (4, 2))
        shift *= np.float32([width, height])
        homography = cv2.getPerspectiveTransform(corners, (corners + shift).astype(np.float32))
        inverse = np.linalg.inv(homography)
        ys, xs = np.mgrid[0:height, 0:width].astype(np.float64)
        w = inverse[2, 0] * xs + inverse[2, 1] * ys + inverse[2, 2]
        mx = ((inverse[0, 0] * xs + inverse[0, 1] * ys + inverse[0, 2]) / w).astype(np.float32)
        my = ((inverse[1, 0] * xs + inverse[1, 1] * ys + inverse[1, 2]) / w).astype(np.float32)
        return (homography, *cv2.convertMaps(mx, my, cv2.CV_16SC2))
    return _cached(layout, ("camera", perspective, camera_seed), make, _GRAINS, keep=4)


def _tilt(layout: TrayLayout, perspective: float, camera_seed: int, frame: np.ndarray, window=None) -> np.ndarray:
    """``frame`` as the tilted camera sees it (:func:`_camera`; bilinear, the bench top beyond the frame), or
    the ``window`` ``(rows, columns)`` of that view (the same pixels: each is read from its own map entry)."""
    import cv2

    if perspective <= 0:
        return frame if window is None else frame[window]
    _, xy, fraction = _camera(layout, perspective, camera_seed)
    if window is not None:
        xy, fraction = xy[window], fraction[window]
    return cv2.remap(frame, xy, fraction, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                     borderValue=BENCH)


def _tilted_box(layout: TrayLayout, perspective: float, camera_seed: int, box: tuple[int, int, int, int]):
    """The pixels of the tilted view that read a pixel of ``box`` (``x0, y0, x1, y1``), as such a box: the
    corners' images, with the interpolation's pixel to spare."""
    if perspective <= 0:
        return box
    homography = _camera(layout, perspective, camera_seed)[0]
    x0, y0, x1, y1 = box
    corners = np.array([[x0 - 1, y0 - 1, 1], [x1 + 1, y0 - 1, 1], [x1 + 1, y1 + 1, 1], [x0 - 1, y1 + 1, 1]], float)
    seen = corners @ homography.T
    seen = seen[:, :2] / seen[:, 2:]
    return (int(np.floor(seen[:, 0].min())) - 2, int(np.floor(seen[:, 1].min())) - 2,
            int(np.ceil(seen[:, 0].max())) + 3, int(np.ceil(seen[:, 1].max())) + 3)


@dataclass(frozen=True)
class CameraModel:
    """Image degradations of one camera: Gaussian blur sigma, noise std (grey levels), perspective tilt
    (fraction of the frame), and whether hands pass over the tray."""

    blur: float = 0.0
    noise: float = 0.0
    perspective: float = 0.0
    hands: bool = False
    seed: int = 0


class SimulatedCell:
    """A cell filmed from above, as an iterator of frames, for tests and demos without a camera.

    When its queue of frames runs dry it is the operator's turn: the operator performs its next operation
    (takes the operation's single parts, grasps the tool, puts it back) or idles for ``idle`` frames.
    ``robot(instruction)`` (a :class:`~planner.runtime.scripted.ScriptedRobot` hook) renders the robot taking its
    parts and using the tool, and strikes the operation from the operator's list (a join: the picks of its
    operation at the operator's true state). Each change is held for
    ``hold`` frames; ``operator_observations`` is the truth, in order. After an operation without a tool the
    operator spends ``settle`` frames joining the parts: the quiet period by which a camera tells that such an
    operation is over (give it more frames than the vision source's ``quiet_frames``).
    """

    def __init__(self, layout: TrayLayout, operator: ScriptedOperator, camera: CameraModel = CameraModel(),
                 hold: int = 8, idle: int = 24, settle: int = 0):
        self.layout = layout
        self.operator = operator
        self.camera = camera
        self.hold = hold
        self.idle = idle
        self.settle = settle
        self.in_tray = set(layout.slots)
        self.queue: deque = deque()
        self.frames = 0
        self.operator_observations = []  # the truth, in order

    def __iter__(self):
        return self

    def __next__(self):
        if not self.queue:
            self._operator_turn()
        return self.queue.popleft()

    def robot(self, instruction: Instruction) -> None:
        done = self.operator.robot_acting(instruction)
        if instruction.join is not None:  # a join: what its operation at the true state takes (none: nothing)
            if done is None:
                return
            instruction = instruction_of_operation(self.operator.plan, done)
        for part in instruction.picks:
            self._take(part)
        if instruction.tool is not None:
            self._use_tool(instruction.tool)

    def _operator_turn(self) -> None:
        operation = self.operator.next_operation()
        if operation is None:
            self._show(self.idle)
            return
        observation = self.operator.observation_of(operation)
        self.operator_observations.append(observation)
        for part in observation.parts:
            self._take(part)
        if observation.tool is not None:
            self._use_tool(observation.tool)
        elif self.settle:
            self._show(self.settle)

    def _take(self, item: str) -> None:
        self.in_tray.discard(item)
        self._show(self.hold, reach=item)

    def _use_tool(self, tool: str) -> None:
        self.in_tray.discard(tool)
        self._show(self.hold, reach=tool)
        self.in_tray.add(tool)
        self._show(self.hold, reach=tool)

    def _show(self, count: int, reach: str | None = None) -> None:
        for k in range(count):
            occluders = ()
            if self.camera.hands and reach is not None and k < 2:
                # a hand over the slot just reached into, and an arm across the tray, for two frames
                occluders = (_hand(self.layout, reach), _arm(self.layout))
            elif self.camera.hands and k == count // 2 + 1:
                # a corner of every slot covered, for one frame (a marker flickers)
                occluders = tuple(_corner(self.layout, item) for item in self.layout.slots)
            self.frames += 1
            self.queue.append(render_tray(self.layout, self.in_tray, self.camera.blur, self.camera.noise,
                                          self.camera.perspective, occluders,
                                          seed=self.camera.seed * 100_003 + self.frames,
                                          camera_seed=self.camera.seed))


def _hand(layout: TrayLayout, item: str) -> Occluder:
    """A hand over ``item``'s slot."""
    x, y = layout.slots[item]
    px = layout.marker_px
    return Occluder((x + px // 2, y + px // 2), (px // 2, px // 3), 30.0)


def _arm(layout: TrayLayout) -> Occluder:
    """An arm across the middle of the tray."""
    px = layout.marker_px
    return Occluder((layout.size[0] // 2, layout.size[1] // 2), (px * 3, px // 4), 10.0)


def _corner(layout: TrayLayout, item: str) -> Occluder:
    """Something over the top-left corner of ``item``'s marker."""
    px = layout.marker_px
    return Occluder(layout.slots[item], (px // 3, px // 3))


def scene_box(layout: TrayLayout, camera: CameraModel = CameraModel()) -> tuple[int, int, int, int]:
    """``(x0, y0, x1, y1)``: every frame of a :class:`SimulatedCell` on ``layout`` filmed by ``camera`` shows the
    bench top alone (:data:`BENCH`, plus the camera's grain) at each pixel outside ``x0 <= x < x1``,
    ``y0 <= y < y1``, within the frame.

    The box holds every pixel the tray's drawing changes (each slot with its marker or with its item, named),
    and every hand and arm the cell can draw, seen through the tilted camera (:func:`_tilted_box`) and grown
    by the blur's reach (as :func:`_scene` redraws an occluder). Cost: the tray drawn twice, once per layout.
    """
    boxes = [_changed(_draw(layout, frozenset(layout.slots))), _changed(_draw(layout, frozenset()))]
    if camera.hands:
        occluders = [_arm(layout)] + [f(layout, item) for item in layout.slots for f in (_hand, _corner)]
        boxes += [_ellipse_box(occluder) for occluder in occluders]
    box = (min(b[0] for b in boxes), min(b[1] for b in boxes), max(b[2] for b in boxes), max(b[3] for b in boxes))
    x0, y0, x1, y1 = _tilted_box(layout, camera.perspective, camera.seed, box)
    reach = math.ceil(4 * camera.blur) + 1 if camera.blur > 0 else 0
    width, height = layout.size
    return max(x0 - reach, 0), max(y0 - reach, 0), min(x1 + reach, width), min(y1 + reach, height)


def _changed(frame: np.ndarray) -> tuple[int, int, int, int]:
    """The box ``(x0, y0, x1, y1)`` of the pixels of ``frame`` that are not the bench top's."""
    rows, columns = np.nonzero(np.any(frame != np.uint8(BENCH), axis=2))
    return int(columns.min()), int(rows.min()), int(columns.max()) + 1, int(rows.max()) + 1
