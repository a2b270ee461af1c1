"""``aplan_msgs``: the messages and the action of the cell, generated from the ``.msg`` / ``.action`` files
in ``aplan_msgs/`` beside this module with Debian's genpy, without a catkin workspace.

- ``aplan_msgs/Markers``: the marker ids of one frame (the vision server's output);
- ``aplan_msgs/Belief`` (with ``Intention``): the planner's belief, next action and decision time;
- ``aplan_msgs/Perform`` (an actionlib action): one operation for the robot; result ``done`` / ``reason``.

An ``.action`` file expands into its seven messages by actionlib's convention (what catkin's genaction
does): ``PerformGoal``, ``PerformResult``, ``PerformFeedback``; ``PerformActionGoal`` (Header, GoalID,
goal), ``PerformActionResult`` and ``PerformActionFeedback`` (Header, GoalStatus, result / feedback) and
``PerformAction`` (the three). The generated modules go to a cache folder named by a hash of the definition
files and genpy's version (``$APLAN_ROS_CACHE``, default ``~/.cache/aplan/ros``), written to a temporary
folder and renamed, so concurrent first uses do not see half a package. Cost: about a second once, then an
import.
"""
from __future__ import annotations

import hashlib
import os
import sys
import tempfile
from pathlib import Path

from .system import RosUnavailable, require_ros

__all__ = ["DEFINITIONS", "PACKAGE", "generate", "messages"]

PACKAGE = "aplan_msgs"
DEFINITIONS = Path(__file__).with_name(PACKAGE)
_SEARCH = {"std_msgs": Path("/usr/share/std_msgs/msg"), "actionlib_msgs": Path("/usr/share/actionlib_msgs/msg")}


def _action_messages(name: str, text: str) -> dict[str, str]:
    """The seven message definitions of action ``name`` whose ``.action`` text is ``text``."""
    goal, result, feedback = (part.strip("\n") + "\n" for part in _split(text))
    return {f"{name}Goal": goal, f"{name}Result": result, f"{name}Feedback": feedback,
            f"{name}ActionGoal": f"Header header\nactionlib_msgs/GoalID goal_id\n{name}Goal goal\n",
            f"{name}ActionResult": f"Header header\nactionlib_msgs/GoalStatus status\n{name}Result result\n",
            f"{name}ActionFeedback": f"Header header\nactionlib_msgs/GoalStatus status\n{name}Feedback feedback\n",
            f"{name}Action": f"{name}ActionGoal action_goal\n{name}ActionResult action_result\n"
                             f"{name}ActionFeedback action_feedback\n"}


def _split(text: str) -> list[str]:
    parts, current = [], []
    for line in text.splitlines():
        if line.strip() == "---":
            parts.append("\n".join(current))
            current = []
        else:
            current.append(line)
    parts.append("\n".join(current))
    if len(parts) != 3:
        raise RosUnavailable("an .action file needs goal, result and feedback separated by two '---' lines")
    return parts


def _sources() -> dict[str, str]:
    """Message name -> definition text: the ``.msg`` files and the expansion of the ``.action`` files."""
    out = {p.stem: p.read_text() for p in sorted((DEFINITIONS / "msg").glob("*.msg"))}
    for path in sorted((DEFINITIONS / "action").glob("*.action")):
        out.update(_action_messages(path.stem, path.read_text()))
    return out


def _cache_root() -> Path:
    return Path(os.environ.get("APLAN_ROS_CACHE") or Path.home() / ".cache" / "aplan" / "ros")


def generate(root: Path | None = None) -> Path:
    """Generate ``aplan_msgs`` (Python) under ``root`` (default: the cache folder) unless it is there already;
    return the folder to put on ``sys.path``. Raises :class:`RosUnavailable` when genpy or the standard
    message definitions are missing."""
    require_ros()
    import genpy

    for package, folder in _SEARCH.items():
        if not folder.is_dir():
            raise RosUnavailable(f"{folder}: the {package} message definitions are missing; apt-get install "
                                 f"ros-{package.replace('_', '-')}")
    sources = _sources()
    digest = hashlib.sha256(repr((sorted(sources.items()), getattr(genpy, "__version__", ""))).encode()).hexdigest()
    base = (root or _cache_root()) / digest[:16]
    if (base / PACKAGE / "msg" / "__init__.py").is_file():
        return base
    base.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=base.parent) as work:
        _generate_into(Path(work), sources)
        try:
            os.rename(Path(work) / "out", base)
        except OSError:  # another process generated it meanwhile
            if not (base / PACKAGE / "msg" / "__init__.py").is_file():
                raise
    return base


def _generate_into(work: Path, sources: dict[str, str]) -> None:
    from genpy.generate_initpy import write_modules
    from genpy.generator import MsgGenerator

    definitions = work / "msg"
    definitions.mkdir()
    for name, text in sources.items():
        (definitions / f"{name}.msg").write_text(text)
    package = work / "out" / PACKAGE
    search = {PACKAGE: [str(definitions)], **{k: [str(v)] for k, v in _SEARCH.items()}}
    files = [str(definitions / f"{name}.msg") for name in sources]
    status = MsgGenerator().generate_messages(PACKAGE, files, str(package / "msg"), search)
    if status:
        raise RosUnavailable(f"genpy could not generate {PACKAGE} (status {status})")
    write_modules(str(package / "msg"))
    (package / "__init__.py").write_text("")


def messages():
    """The generated ``aplan_msgs.msg`` module (generating it first when needed)."""
    base = str(generate())
    if base not in sys.path:
        sys.path.insert(0, base)
    import aplan_msgs.msg

    return aplan_msgs.msg
