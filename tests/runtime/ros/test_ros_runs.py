"""Whole runs on one real ROS master (tests/runtime/ros/rosgraph_fixture.py): a product of several levels
through ``aplan ros`` in one run, and ``cell.launch`` really started with roslaunch beside the simulated cell."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from planner import api
from planner.assembly import make_plan
from planner.decision.habits import habits_from_counts
from planner.decision.io.habits_file import write_habits
from planner.product import Part, Product, Subassembly, save_product
from rosgraph_fixture import REPO, log_events, ros_cache, ros_master, ros_shared  # noqa: F401 - fixtures
from test_ros_cell import _counts, _log_counts, _no_traceback, _replays

LAUNCH = REPO / "planner" / "runtime" / "ros"


def _two_chains(folder: Path) -> Path:
    """Chains a1-a2-a3 and b1-b2-b3 joined by a3-b1, each a subassembly: levels A, B, then top (A + B)."""
    parts = tuple(Part(p) for p in ("a1", "a2", "a3", "b1", "b2", "b3"))
    contacts = (("a1", "a2"), ("a2", "a3"), ("b1", "b2"), ("b2", "b3"), ("a3", "b1"))
    path = folder / "two-chains.json"
    save_product(Product(parts, contacts, subassemblies=(Subassembly("A", ("a1", "a2", "a3")),
                                                         Subassembly("B", ("b1", "b2", "b3"))), name="chains"), path)
    return path


def test_a_product_of_several_levels_in_one_run(ros_shared):
    ros = ros_shared
    product = str(_two_chains(ros.folder))
    model = [product, "--expansions", "20"]
    ros.aplan("vision", "ros-vision", product)
    ros.aplan("sim", "ros-sim", *model, "--demo", "0")
    ros.aplan("planner", "ros", *model, "--log", str(ros.folder / "s.jsonl"), "--frame-timeout", "120")
    assert ros.wait("planner") == 0, ros.output("planner")
    output = ros.output("planner")
    assert [line.split()[1] for line in output.splitlines() if line.startswith("level ")] == ["A", "B", "top"]
    for level, parts in (("A", ["a1", "a2", "a3"]), ("B", ["b1", "b2", "b3"]), ("top", ["A", "B"])):
        events = log_events(ros.folder / f"s-{level}.jsonl")
        assert events[0]["settings"]["level"] == level
        assert [p["id"] for p in events[0]["product"]["parts"]] == parts
        assert events[-1]["event"] == "end" and events[-1]["reason"] == "assembled", events[-1]
        assert "beliefs reproduced" in _replays(ros.folder / f"s-{level}.jsonl")
    _no_traceback(ros)


def test_cell_launch_started_by_roslaunch_assembles_the_pen(ros_shared):
    ros = ros_shared
    aplan = ros.folder / "aplan"  # the shim's $APLAN: this repository's aplan under this Python
    aplan.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m planner "$@"\n')
    aplan.chmod(0o755)
    ros.env.update(ROS_PACKAGE_PATH=str(LAUNCH), APLAN=str(aplan))
    log = ros.folder / "launch.jsonl"
    model = ["pen", "--planner", "online", "--expansions", "50"]
    ros.env["ROS_NAMESPACE"] = "cell"  # the simulated cell where the launch file's nodes look: cell/image, cell/perform
    ros.aplan("sim", "ros-sim", *model, "--demo", "0")
    del ros.env["ROS_NAMESPACE"]
    habits, learned = ros.folder / "habits.json", ros.folder / "learned.json"
    plan = make_plan(api.resolve_product("pen"))
    write_habits(habits, habits_from_counts(plan, np.arange(plan.states.n_edges, dtype=float) % 3))  # any counts
    launch = ros._spawn("roslaunch", ["roslaunch", "aplan_ros", "cell.launch", "product:=pen", "planner:=online",
                                      "expansions:=50", f"log:={log}", f"habits:={habits}",
                                      f"habits_out:={learned}"])
    assert ros.wait("roslaunch") == 0, ros.output("roslaunch")  # the planner is required: its end ends the launch
    output = ros.output("roslaunch")
    assert "assembled: the product is assembled" in output, output
    events = log_events(log)
    assert events[0]["settings"]["source"] == "ros /cell/markers"
    assert events[0]["settings"]["robot"] == "ros /cell/perform"
    assert events[-1]["reason"] == "assembled"
    assert f"beliefs reproduced at all {events[-1]['step']} steps" in _replays(log)
    # ~habits: the session's model had them; ~habits_out: them plus this session's steps (aplan habits on its log)
    assert events[0]["settings"]["habits"]["file"] == str(habits)
    assert _counts(learned) == _counts(habits, _log_counts(log, ros.folder / "log-habits.json"))
    try:  # nothing of the launch left running: roslaunch stopped the vision server too
        os.killpg(launch.pid, 0)
        left = True
    except ProcessLookupError:
        left = False
    assert not left, "processes of the launch are still running"
    _no_traceback(ros)
