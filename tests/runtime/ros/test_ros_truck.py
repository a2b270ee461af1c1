"""One level of the real toy truck (../shared/models, exported with FreeCAD) on ROS with the online planner:
the log equals the one `aplan session --demo` writes, and replays."""
from __future__ import annotations

import sys

from real_models import JOBS, real_bundle
from rosgraph_fixture import log_events, require_ros, ros_job
from test_ros_cell import _comparable, _no_traceback, _replay, _replays


def _truck_run(ros):
    bundle = str(real_bundle("toy_truck"))  # waits for the export (FreeCAD's lane)
    model = [bundle, "--level", "top", "--planner", "online", "--expansions", "50"]
    demo = ros.folder / "demo.jsonl"  # the in-process demo beside the ROS run: two processes on two cores
    ros._spawn("demo", [sys.executable, "-m", "planner", "session", *model, "--demo", "0", "--log", str(demo)])
    ros.aplan("vision", "ros-vision", bundle)
    ros.aplan("sim", "ros-sim", *model, "--demo", "0")
    log = ros.folder / "ros.jsonl"
    ros.aplan("planner", "ros", *model, "--log", str(log), "--server-timeout", "600",
               "--frame-timeout", "300")  # both build the model first; bounds on a hang, not results
    return dict(status=ros.wait("planner", timeout=900), demo_status=ros.wait("demo", timeout=900), log=log,
                demo=demo, replay=_replay(log))


def test_the_trucks_top_level_on_ros_with_the_online_planner():
    require_ros()
    real_bundle("toy_truck")  # skips (or fails under APLAN_REQUIRE_FREECAD=1) without FreeCAD
    ran = TRUCK.result()
    run = ran.result
    assert run["status"] == 0, ran.output("planner")
    assert run["demo_status"] == 0, ran.output("demo")
    events = log_events(run["log"])
    assert events[0]["settings"]["level"] == "top" and events[0]["settings"]["planner"] == "online"
    assert events[-1]["reason"] == "assembled"
    assert _comparable(events) == _comparable(log_events(run["demo"]))
    assert "beliefs reproduced" in _replays(run["replay"])
    _no_traceback(ran)


TRUCK = ros_job("the truck's top level", _truck_run)
#: The truck's export (FreeCAD's lane), then the run (ROS's lane, where it comes last: it waits for the export).
BACKGROUND = (JOBS["toy_truck"], TRUCK)
