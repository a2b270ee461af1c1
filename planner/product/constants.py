"""The fixed vocabulary of a product file: its format name and version, the length units, the axis
directions, the rules for untagged operations and the marker dictionaries a parts tray may use."""
from __future__ import annotations

from ..defaults import PRODUCT_FORMAT, PRODUCT_VERSION

__all__ = ["FORMAT", "VERSION", "UNITS", "AXIS_DIRECTIONS", "UNFAVORABLE_DEFAULTS", "MARKER_DICTIONARIES",
           "DEFAULT_MARKER_DICTIONARY", "UNIT_TOLERANCE"]

FORMAT = PRODUCT_FORMAT
VERSION = PRODUCT_VERSION
UNITS = ("mm", "cm", "m", "in")
AXIS_DIRECTIONS: dict[str, tuple[float, float, float]] = {
    "+X": (1.0, 0.0, 0.0), "-X": (-1.0, 0.0, 0.0),
    "+Y": (0.0, 1.0, 0.0), "-Y": (0.0, -1.0, 0.0),
    "+Z": (0.0, 0.0, 1.0), "-Z": (0.0, 0.0, -1.0),
}
#: How operations without a designer tag are judged (see :class:`~planner.product.model.TagDefaults`).
UNFAVORABLE_DEFAULTS = ("single-part-rule", "none", "all")
#: OpenCV's predefined ArUco/AprilTag dictionaries and how many marker ids each holds.
MARKER_DICTIONARIES: dict[str, int] = {
    **{f"DICT_{n}X{n}_{size}": size for n in (4, 5, 6, 7) for size in (50, 100, 250, 1000)},
    "DICT_ARUCO_ORIGINAL": 1024, "DICT_APRILTAG_16h5": 30, "DICT_APRILTAG_25h9": 35,
    "DICT_APRILTAG_36h10": 2320, "DICT_APRILTAG_36h11": 587, "DICT_ARUCO_MIP_36h12": 250,
}
DEFAULT_MARKER_DICTIONARY = "DICT_4X4_50"
#: A direction vector is a unit vector when its length is within this of 1; it names an axis when each of
#: its components is within this of the axis'.
UNIT_TOLERANCE = 1e-6
