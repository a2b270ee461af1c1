"""From the marker ids of each frame to the operator's operations: debounce, then the tray's rules.

- :class:`MarkerTracker`: debounced visibility; a marker changes state only after ``debounce``
  consecutive frames disagree with it, so a hand passing over a marker or a missed detection is ignored.
- :class:`ObservationBuilder`: debounced marker changes -> observations. A part's marker appearing adds the
  part to the pending operation (hidden again before the operation closes: the part was put back); the tool's
  marker appearing closes the operation. Parts and tool events announced for the robot
  (:meth:`ObservationBuilder.expect_robot`) are the robot's, not the operator's. Items start in the tray
  (every marker hidden).

Cost: O(markers) per frame.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable

from ...assembly.tags import BLANK, Observation
from .markers import MarkerMap, VisionError

__all__ = ["MarkerTracker", "ObservationBuilder"]


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
        """The robot is about to take ``parts`` and use ``tool``: those marker events are not the operator's. A
        part taken already is in an assembly, not in the tray: it is not expected again."""
        self.robot_parts.update(p for p in parts if p not in self.taken)
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
