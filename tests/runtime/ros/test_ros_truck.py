"""One level of the real toy truck (../shared/models, exported with FreeCAD) on ROS with the online planner:
the log equals the one `aplan session --demo` writes, and replays."""
from __future__ import annotations

import sys

from real_models import BACKGROUND, real_bundle  # noqa: F401 - BACKGROUND: the export runs beside the tests
from rosgraph_fixture import log_events, ros, ros_cache  # noqa: F401 - fixtures
from test_ros_cell import _comparable, _no_traceback, _replays


def test_the_trucks_top_level_on_ros_with_the_online_planner(ros, tmp_path):
    bundle = str(real_bundle("toy_truck"))
    model = [bundle, "--level", "top", "--planner", "online", "--expansions", "50"]
    demo = tmp_path / "demo.jsonl"  # the in-process demo beside the ROS run: two processes on two cores
    ros._spawn("demo", [sys.executable, "-m", "planner", "session", *model, "--demo", "0", "--log", str(demo)])
    ros.aplan("vision", "ros-vision", bundle)
    ros.aplan("sim", "ros-sim", *model, "--demo", "0")
    log = ros.folder / "ros.jsonl"
    ros.aplan("planner", "ros", *model, "--log", str(log), "--server-timeout", "600",
               "--frame-timeout", "300")  # both build the model first; bounds on a hang, not results
    assert ros.wait("planner", timeout=900) == 0, ros.output("planner")
    assert ros.wait("demo", timeout=900) == 0, ros.output("demo")
    events = log_events(log)
    assert events[0]["settings"]["level"] == "top" and events[0]["settings"]["planner"] == "online"
    assert events[-1]["reason"] == "assembled"
    assert _comparable(events) == _comparable(log_events(demo))
    assert "beliefs reproduced" in _replays(log)
    _no_traceback(ros)
