"""The camera as an observation source: frames -> observations, one per decision step.

:class:`VisionSource` runs the pipeline of :mod:`planner.runtime.vision` (detect, debounce, build) until the
operator closes an operation (its observation), or ``quiet_frames`` frames pass without any marker change
(:data:`~planner.assembly.tags.BLANK`: the operator did nothing this step; parts already taken stay pending).
Unknown marker ids are ignored with one warning each.
"""
from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Callable, Iterable

import numpy as np

from ...assembly.tags import Observation
from .markers import MarkerDetector, MarkerMap, VisionError
from .tracking import MarkerTracker, ObservationBuilder

if TYPE_CHECKING:
    from ..interfaces import Instruction

__all__ = ["VisionSource"]

log = logging.getLogger(__name__)


class VisionSource:
    """An observation source (:class:`planner.runtime.interfaces.ObservationSource`) over a stream of frames.

    ``frames`` yields ``(H, W[, 3]) uint8`` images. :meth:`observe` reads frames until the operator closes an
    operation (its observation), or ``quiet_frames`` frames pass without a marker change (BLANK), or the
    frames end (None, or BLANK first when frames were read in this call).
    ``robot_uses_tray_tools``: the robot takes its tool from the tray too (the paper's setup), so one tool
    event per robot operation is the robot's; False when the robot has tools of its own.
    ``on_warning`` receives each warning (an unknown marker id, once per id; a robot pick that never showed);
    default: a warning on the ``planner.runtime.vision.source`` logger. ``detections`` replaces ``frames`` by
    the marker ids of each frame.
    """

    def __init__(self, frames: Iterable[np.ndarray], markers: MarkerMap, detector: MarkerDetector | None = None,
                 debounce: int = 3, quiet_frames: int = 45, close_without_tool: bool = False,
                 on_warning: Callable[[str], None] | None = None, detections: Iterable[set[int]] | None = None,
                 robot_uses_tray_tools: bool = True):
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
        self._warn = on_warning or log.warning
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
            # a join (--joins) may take what any of its operations at the belief's states takes: all are the robot's
            builder.expect_robot(instruction.may_take, instruction.tool if self.robot_uses_tray_tools else None)

    def observe(self) -> Observation | None:
        """The operator's next operation, BLANK after a quiet period, None when the frames have ended."""
        if self._queued:
            return self._queued.pop(0)
        quiet = 0
        read = 0
        for detected in self._detections:
            self.frames_read += 1
            read += 1
            self._warn_unknown(detected)
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
        """Close the stream of frames (releases a camera)."""
        close = getattr(self._detections, "close", None)
        if close is not None:
            close()

    def _warn_unknown(self, detected: set[int]) -> None:
        """One warning for each marker id outside the map, the first time it is seen."""
        for marker in sorted(detected - self.markers.items.keys() - self.unknown):
            self.unknown.add(marker)
            self._warn(f"marker {marker} is not in the product's marker map ({self.markers.dictionary}); ignored")
