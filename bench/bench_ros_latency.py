"""Round-trip latency on ROS from an observation to the robot's next goal, over pen sessions.

A real rosmaster on a loopback port, `aplan ros-vision`, `aplan ros-sim pen --demo K` (the rendered tray, in
step with the planner) and `aplan ros pen --expansions 200`, all as processes of their own, as in
tests/runtime/ros. This script is one more node: it listens to `markers` and `perform/goal`. The latency of
a goal (steps 2 on) is its arrival minus the arrival of the last marker message before it: the frame that
closed the step's observation (the simulated camera renders a frame only when the planner waits for one, so
no later frame exists then). It covers the planner's tracking, the Bayes update, the online decision (200
expansions), the log's fsynced lines, the belief message and the goal's trip through actionlib.

    .venv/bin/python bench/bench_ros_latency.py --sessions 6   # about 5 minutes
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "tests" / "runtime" / "ros"))

from rosgraph_fixture import RosGraph, log_events  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=3, help="pen sessions, full sequences 0, 1, ... (default 3)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        graph = RosGraph(Path(folder), Path(folder) / "cache")
        graph.start_master()
        import os

        os.environ.update({k: v for k, v in graph.env.items() if k.startswith(("ROS_", "APLAN_"))})
        try:
            return _measure(graph, args.sessions)
        finally:
            graph.stop()


def _measure(graph: RosGraph, sessions: int) -> int:
    from planner.runtime.ros.adapters import connect
    from planner.runtime.ros.interfaces import messages

    msgs = messages()
    import rospy

    connect("aplan_bench", ["bench"])
    lock = threading.Lock()
    arrivals: list[tuple[float, str]] = []

    def note(kind):
        def callback(_message):
            with lock:
                arrivals.append((time.monotonic(), kind))
        return callback

    rospy.Subscriber("markers", msgs.Markers, note("markers"), queue_size=None, tcp_nodelay=True)
    rospy.Subscriber("perform/goal", msgs.PerformActionGoal, note("goal"), queue_size=None, tcp_nodelay=True)
    graph.aplan("vision", "ros-vision", "pen")
    latencies = []
    for k in range(sessions):
        with lock:
            arrivals.clear()
        graph.aplan(f"sim{k}", "ros-sim", "pen", "--expansions", "200", "--demo", str(k))
        log = graph.folder / f"ros{k}.jsonl"
        graph.aplan(f"planner{k}", "ros", "pen", "--expansions", "200", "--log", str(log))
        if graph.wait(f"planner{k}", timeout=600) != 0:
            print(graph.output(f"planner{k}"))
            return 1
        graph.kill(f"sim{k}")
        with lock:
            seen = list(arrivals)
        last_markers, goals = None, 0
        for at, kind in seen:
            if kind == "markers":
                last_markers = at
            else:
                goals += 1
                if goals > 1 and last_markers is not None:
                    latencies.append(at - last_markers)
        steps = log_events(log)[-1]["step"]
        print(f"session {k}: {steps} steps, {goals} goals")
    rospy.signal_shutdown("done")
    ms = sorted(1000 * x for x in latencies)
    p95 = ms[min(len(ms) - 1, round(0.95 * (len(ms) - 1)))]
    print(f"observation -> robot goal over {len(ms)} goals: median {statistics.median(ms):.1f} ms, "
          f"p95 {p95:.1f} ms, max {ms[-1]:.1f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
