"""aplan ros's command line without a ROS master: ROS arguments go to rospy, the rest to argparse; without a
master the command stops at once with one message."""
from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

from planner.cli import build_parser
from planner.cli.ros import REMAPS, split_remaps

REPO = Path(__file__).resolve().parents[2]


def test_ros_arguments_go_to_rospy_and_the_rest_to_argparse():
    argv = split_remaps(["ros", "pen", "markers:=/camera/aruco", "__name:=planner", "--expansions", "5"])
    assert argv == ["ros", "pen", "--expansions", "5"]
    assert REMAPS == ["markers:=/camera/aruco", "__name:=planner"]
    args = build_parser().parse_args(argv)
    assert (args.product, args.expansions, args.max_steps, args.robot_timeout) == ("pen", 5, None, 300.0)
    # other commands keep every argument (a file name may hold ':=')
    assert split_remaps(["stats", "a:=b.json"]) == ["stats", "a:=b.json"]


def test_no_master_is_one_message_and_no_log(tmp_path):
    with socket.socket() as s:  # a loopback port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {**os.environ, "ROS_MASTER_URI": f"http://127.0.0.1:{port}", "ROS_HOME": str(tmp_path)}
    done = subprocess.run([sys.executable, "-m", "planner", "ros", "pen", "--log", str(tmp_path / "s.jsonl")],
                          env=env, capture_output=True, text=True, cwd=REPO, timeout=120)
    assert done.returncode == 1
    assert "Traceback" not in done.stderr
    assert (f"no ROS master answers at http://127.0.0.1:{port}" in done.stderr
            or "ROS 1 is not installed" in done.stderr), done.stderr
    assert not (tmp_path / "s.jsonl").exists()
