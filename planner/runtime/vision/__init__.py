"""Marker vision: the operator's observations from a camera watching the parts tray (the paper's Sec. IV).

The cell (Cramer et al. 2021, Fig. 6): every part and tool lies in the tray on top of its own ArUco marker,
so a marker is hidden while its item is in the tray and becomes *visible* when the item is taken. An
operation ends when the tool is grasped, i.e. when the tool's marker appears; the parts whose markers
appeared since the previous operation, with that tool, are the operation's observation
(:class:`~planner.assembly.tags.Observation`: one part + tool, two parts + tool, tool only).

Pipeline, one job per module:

- ``markers``: which marker is which item (:func:`marker_map`) and the marker ids seen in one frame
  (:class:`MarkerDetector`, OpenCV's ``ArucoDetector``);
- ``tracking``: debounced visibility (:class:`MarkerTracker`) and the tray's rules that turn marker changes
  into observations (:class:`ObservationBuilder`);
- ``source``: :class:`VisionSource`, the observation source of the decision loop;
- ``frames``: :func:`camera_frames`, :func:`video_frames`, :func:`image_frames`, :func:`in_background`.

Cost: detection dominates (about 15 ms per 1920x1080 frame on one core, see ``bench/bench_vision.py``);
tracking and building are O(markers) per frame. OpenCV is imported on first use, not with this package.
"""
from .frames import IMAGE_SUFFIXES, camera_frames, frames_for, image_frames, in_background, video_frames
from .markers import MarkerDetector, MarkerMap, VisionError, default_markers, detections, marker_map
from .source import VisionSource
from .tracking import MarkerTracker, ObservationBuilder

__all__ = [
    "VisionError", "MarkerMap", "marker_map", "default_markers", "MarkerDetector", "MarkerTracker",
    "ObservationBuilder", "VisionSource", "camera_frames", "video_frames", "image_frames", "frames_for",
    "detections", "in_background", "IMAGE_SUFFIXES",
]
