"""Where Debian's ROS 1 Python packages are, and how the planner's own interpreter reaches them.

Debian 12 installs ``rospy``, ``actionlib``, ``genpy`` ... for the system Python 3 in
:data:`SYSTEM_PACKAGES`. The planner runs in its virtual environment; :func:`require_ros` appends that folder
to ``sys.path`` *after* the environment's own packages, so the environment's numpy and OpenCV stay the ones
imported (the pure-Python ROS client libraries do not care which numpy they get). cv_bridge is not used:
its compiled extension is built against Debian's numpy 1.x and cannot load next to the environment's numpy
2.x; :mod:`.images` converts ``sensor_msgs/Image`` with numpy instead.
"""
from __future__ import annotations

import sys
from pathlib import Path

from ...errors import PlannerError

__all__ = ["SYSTEM_PACKAGES", "DEBIAN_PACKAGES", "RosUnavailable", "require_ros"]

SYSTEM_PACKAGES = Path("/usr/lib/python3/dist-packages")
DEBIAN_PACKAGES = ("ros-core", "python3-rospy", "python3-actionlib", "python3-actionlib-msgs",
                   "python3-sensor-msgs", "python3-genpy", "python3-genmsg", "ros-std-msgs", "ros-actionlib-msgs")


class RosUnavailable(PlannerError):
    """ROS 1's Python packages are not installed (or not for this Python version)."""


def require_ros() -> None:
    """Make ``rospy``, ``actionlib`` and ``genpy`` importable, or raise :class:`RosUnavailable` saying what
    to install. Idempotent; O(1) after the first call."""
    try:
        import actionlib  # noqa: F401
        import genpy  # noqa: F401
        import rospy  # noqa: F401
        return
    except ImportError:
        pass
    system = str(SYSTEM_PACKAGES)
    same_python = Path(f"/usr/lib/python{sys.version_info.major}.{sys.version_info.minor}").is_dir()
    if SYSTEM_PACKAGES.is_dir() and same_python and system not in sys.path:
        sys.path.append(system)  # last: the environment's numpy and OpenCV win
    try:
        import actionlib  # noqa: F401,F811
        import genpy  # noqa: F401,F811
        import rospy  # noqa: F401,F811
    except ImportError as exc:
        raise RosUnavailable(
            f"ROS 1 is not installed for this Python ({exc}); on Debian 12: apt-get install "
            f"{' '.join(DEBIAN_PACKAGES)} (or bash scripts/setup.sh --ros)") from None
