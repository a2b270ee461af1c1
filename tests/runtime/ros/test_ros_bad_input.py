"""What aplan ros refuses, against a real ROS master: no master, a server of another type under the robot's
name, a parameter that does not fit, an image the detector cannot read. A message each, never a traceback.
The runs on a master are background jobs in the ROS lane (:func:`rosgraph_fixture.ros_job`), each on a master of
its own; each test asserts on what its run kept."""
from __future__ import annotations

import subprocess
import sys
import textwrap

from rosgraph_fixture import REPO, log_events, require_ros, ros_cache, ros_job  # noqa: F401 - fixtures


def _no_traceback(ran) -> None:
    """No node of the run (a :class:`rosgraph_fixture.Ran`) printed a traceback."""
    for name in ran.outputs:
        assert "Traceback" not in ran.output(name), ran.output(name)


def test_no_master_is_refused_at_once(tmp_path, ros_cache):
    require_ros()
    from rosgraph_fixture import RosGraph

    graph = RosGraph(tmp_path, ros_cache)  # its master is never started
    done = subprocess.run([sys.executable, "-m", "planner", "ros", "pen", "--log", str(tmp_path / "x.jsonl")],
                          env=graph.env, capture_output=True, text=True, cwd=REPO, timeout=120)
    assert done.returncode == 1
    assert f"no ROS master answers at http://127.0.0.1:{graph.port}" in done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "x.jsonl").exists()


def _python(ros, name: str, code: str):
    return ros._spawn(name, [sys.executable, "-c", textwrap.dedent(code)])


def _impostor_run(ros) -> dict:
    _python(ros, "impostor", """
        import sys; sys.path.append('/usr/lib/python3/dist-packages')
        import rospy; from std_msgs.msg import String
        rospy.init_node('impostor'); pub = rospy.Publisher('perform/result', String, queue_size=1); rospy.spin()
    """)
    ros.aplan("vision", "ros-vision", "pen")
    log = ros.folder / "ros.jsonl"
    for _ in range(100):  # the impostor's topic registered (a bound on a hang)
        if "perform/result" in subprocess.run(["rostopic", "list"], env=ros.env, capture_output=True,
                                              text=True).stdout:
            break
    ros.aplan("planner", "ros", "pen", "--log", str(log), "--server-timeout", "5")
    return dict(status=ros.wait("planner"), log=log)


def test_a_server_of_another_type_under_the_robots_name():
    require_ros()
    ran = IMPOSTOR.result()
    assert ran.result["status"] == 1
    output = ran.output("planner")
    assert "/perform/result is published as std_msgs/String, not aplan_msgs/PerformActionResult" in output, output
    assert not ran.result["log"].exists()
    _no_traceback(ran)


def _parameter_run(ros) -> dict:
    ros.aplan("planner", "ros", "pen", "_planner:=sideways")  # a private parameter, as rospy reads it
    status = ros.wait("planner")
    ros.aplan("planner2", "ros", "_product:=no-such-product", "--node", "p2")
    return dict(status=status, status2=ros.wait("planner2"))


def test_a_parameter_that_does_not_fit():
    require_ros()
    ran = PARAMETER.result()
    assert ran.result["status"] == 2
    assert "parameter ~planner = 'sideways': use offline or online" in ran.output("planner")
    assert ran.result["status2"] == 1
    assert "no-such-product" in ran.output("planner2")
    _no_traceback(ran)


def _unreadable_run(ros) -> dict:
    _python(ros, "camera", """
        import sys, time; sys.path.append('/usr/lib/python3/dist-packages')
        import rospy; from sensor_msgs.msg import Image
        rospy.init_node('camera'); pub = rospy.Publisher('image', Image, queue_size=1)
        while not rospy.is_shutdown():
            pub.publish(Image(height=2, width=2, encoding='16UC1', step=4, data=bytes(8))); time.sleep(0.1)
    """)
    ros.aplan("vision", "ros-vision", "pen")
    ros.aplan("robot", "ros-robot", "--auto")
    log = ros.folder / "ros.jsonl"
    ros.aplan("planner", "ros", "pen", "--expansions", "50", "--log", str(log))
    return dict(status=ros.wait("planner"), log=log)


def test_an_image_the_detector_cannot_read_ends_the_session_with_that_message():
    require_ros()
    ran = UNREADABLE.result()
    assert ran.result["status"] == 1
    output = ran.output("planner")
    assert "image encoding '16UC1' cannot be read by the marker detector" in output, output
    end = log_events(ran.result["log"])[-1]
    assert end["event"] == "end" and end["reason"] == "error" and end["step"] == 1
    _no_traceback(ran)


def test_the_launch_file_starts_the_planner_and_the_vision_server_through_aplan(tmp_path):
    require_ros()
    import os
    import shutil

    roslaunch = shutil.which("roslaunch")
    assert roslaunch, "roslaunch is missing (python3-roslaunch)"
    env = {**os.environ, "ROS_PACKAGE_PATH": str(REPO / "planner" / "runtime" / "ros"), "ROS_HOME": str(tmp_path)}
    nodes = subprocess.run([roslaunch, "--nodes", "aplan_ros", "cell.launch", "product:=pen"], env=env,
                           capture_output=True, text=True, timeout=120)
    assert nodes.stdout.split() == ["/cell/vision", "/cell/planner"], nodes.stderr
    args = subprocess.run([roslaunch, "--args", "/cell/planner", "aplan_ros", "cell.launch", "product:=pen"], env=env,
                          capture_output=True, text=True, timeout=120)
    assert args.stdout.strip().endswith("aplan_ros/aplan ros --node planner __name:=planner"), args.stdout


def _unknown_marker_run(ros) -> dict:
    _python(ros, "camera", """
        import sys, time
        import numpy as np
        from planner.runtime.ros.system import require_ros; require_ros()
        import rospy; from sensor_msgs.msg import Image
        from planner.runtime.ros.images import array_to_image
        from planner.runtime.tray import marker_image
        frame = np.full((400, 400), 255, np.uint8); frame[100:300, 100:300] = marker_image('DICT_4X4_50', 40, 200)
        rospy.init_node('camera'); pub = rospy.Publisher('image', Image, queue_size=1)
        while not rospy.is_shutdown():
            pub.publish(array_to_image(frame, Image)); time.sleep(0.02)
    """)
    ros.aplan("vision", "ros-vision", "pen")
    ros.aplan("robot", "ros-robot", "--auto")
    log = ros.folder / "ros.jsonl"
    ros.aplan("planner", "ros", "pen", "--expansions", "50", "--log", str(log), "--max-steps", "1",
              "--quiet-frames", "10", "--frame-timeout", "120")
    return dict(status=ros.wait("planner"), log=log)


def test_markers_outside_the_products_map_are_a_logged_warning():
    require_ros()
    ran = UNKNOWN_MARKER.result()
    assert ran.result["status"] == 1
    events = log_events(ran.result["log"])
    warnings = [e["message"] for e in events if e["event"] == "warning"]
    assert warnings == ["marker 40 is not in the product's marker map (DICT_4X4_50); ignored"], warnings  # once
    assert events[-1]["reason"] == "step limit"
    _no_traceback(ran)


IMPOSTOR = ros_job("an impostor server", _impostor_run)
PARAMETER = ros_job("a parameter that does not fit", _parameter_run)
UNREADABLE = ros_job("an unreadable image", _unreadable_run)
UNKNOWN_MARKER = ros_job("a marker outside the map", _unknown_marker_run)
#: The runs, started with the session in its ROS lane (tests/background.py), in this module's order.
BACKGROUND = (IMPOSTOR, PARAMETER, UNREADABLE, UNKNOWN_MARKER)
