"""Whole runs on a real ROS master (tests/runtime/ros/rosgraph_fixture.py): a product of several levels
through ``aplan ros`` in one run, ``cell.launch`` really started with roslaunch beside the simulated cell, and a
session with actions named by joins (``--joins``: the goal's name and instruction carry the join, the simulated
robot does it at the cell's true state) writing the in-process demo's log.
Each run is a background job (:func:`rosgraph_fixture.ros_job`); the tests assert on what it kept."""
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
from rosgraph_fixture import REPO, log_events, require_ros, ros_job
from test_ros_cell import _comparable, _counts, _habits, _log_counts, _no_traceback, _replay, _replays

LAUNCH = REPO / "planner" / "runtime" / "ros"


def _two_chains(folder: Path) -> Path:
    """Chains a1-a2-a3 and b1-b2-b3 joined by a3-b1, each a subassembly: levels A, B, then top (A + B)."""
    parts = tuple(Part(p) for p in ("a1", "a2", "a3", "b1", "b2", "b3"))
    contacts = (("a1", "a2"), ("a2", "a3"), ("b1", "b2"), ("b2", "b3"), ("a3", "b1"))
    path = folder / "two-chains.json"
    save_product(Product(parts, contacts, subassemblies=(Subassembly("A", ("a1", "a2", "a3")),
                                                         Subassembly("B", ("b1", "b2", "b3"))), name="chains"), path)
    return path


LEVELS = (("A", ["a1", "a2", "a3"]), ("B", ["b1", "b2", "b3"]), ("top", ["A", "B"]))


def _levels_run(ros):
    product = str(_two_chains(ros.folder))
    model = [product, "--expansions", "20"]
    ros.aplan("vision", "ros-vision", product)
    ros.aplan("sim", "ros-sim", *model, "--demo", "0")
    ros.aplan("planner", "ros", *model, "--log", str(ros.folder / "s.jsonl"), "--frame-timeout", "120")
    status = ros.wait("planner")
    return dict(status=status, replays={level: _replay(ros.folder / f"s-{level}.jsonl") for level, _ in LEVELS
                                        if (ros.folder / f"s-{level}.jsonl").is_file()})


def test_a_product_of_several_levels_in_one_run():
    require_ros()
    ran = LEVELS_RUN.result()
    output = ran.output("planner")
    assert ran.result["status"] == 0, output
    assert [line.split()[1] for line in output.splitlines() if line.startswith("level ")] == ["A", "B", "top"]
    for level, parts in LEVELS:
        events = log_events(ran.folder / f"s-{level}.jsonl")
        assert events[0]["settings"]["level"] == level
        assert [p["id"] for p in events[0]["product"]["parts"]] == parts
        assert events[-1]["event"] == "end" and events[-1]["reason"] == "assembled", events[-1]
        assert "beliefs reproduced" in _replays(ran.result["replays"][level])
    _no_traceback(ran)


def _launch_run(ros):
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
    status = ros.wait("roslaunch")  # the planner is required: its end ends the launch
    try:  # nothing of the launch left running: roslaunch stopped the vision server too
        os.killpg(launch.pid, 0)
        left = True
    except ProcessLookupError:
        left = False
    return dict(status=status, log=log, habits=habits, learned=learned, left=left,
                replay=_replay(log) if log.is_file() else None,
                log_habits=_habits(log, ros.folder / "log-habits.json") if log.is_file() else None)


def test_cell_launch_started_by_roslaunch_assembles_the_pen():
    require_ros()
    ran = LAUNCH_RUN.result()
    run, output = ran.result, ran.output("roslaunch")
    assert run["status"] == 0, output
    assert "assembled: the product is assembled" in output, output
    events = log_events(run["log"])
    assert events[0]["settings"]["source"] == "ros /cell/markers"
    assert events[0]["settings"]["robot"] == "ros /cell/perform"
    assert events[-1]["reason"] == "assembled"
    assert f"beliefs reproduced at all {events[-1]['step']} steps" in _replays(run["replay"])
    # ~habits: the session's model had them; ~habits_out: them plus this session's steps (aplan habits on its log)
    assert events[0]["settings"]["habits"]["file"] == str(run["habits"])
    assert _counts(run["learned"]) == _counts(run["habits"], _log_counts(run["log"], ran.folder / "log-habits.json",
                                                                        run["log_habits"]))
    assert not run["left"], "processes of the launch are still running"
    _no_traceback(ran)


JOINS_MODEL = ["pen", "--joins", "--expansions", "20"]
JOINS_DEMO = "8"  # a pen sequence whose robot joins ahead of the operator (tests/runtime/test_join_sessions.py)


def _joins_run(ros):
    demo = ros.folder / "demo.jsonl"
    ros._spawn("demo", [sys.executable, "-m", "planner", "session", *JOINS_MODEL, "--demo", JOINS_DEMO, "--log",
                        str(demo)])
    ros.aplan("vision", "ros-vision", "pen")
    ros.aplan("sim", "ros-sim", *JOINS_MODEL, "--demo", JOINS_DEMO)
    log = ros.folder / "ros.jsonl"
    ros.aplan("planner", "ros", *JOINS_MODEL, "--log", str(log), "--frame-timeout", "120")
    status = ros.wait("planner")
    return dict(status=status, log=log, demo=demo, demo_status=ros.wait("demo"), replay=_replay(log))


def test_a_session_with_joins_on_ros_writes_the_demo_log_and_replays():
    require_ros()
    ran = JOINS_RUN.result()
    run, output = ran.result, ran.output("planner")
    assert run["status"] == 0 and run["demo_status"] == 0, output + ran.output("demo")
    ros_events, demo_events = log_events(run["log"]), log_events(run["demo"])
    assert _comparable(ros_events) == _comparable(demo_events)
    joins = [e for e in ros_events if e["event"] == "action" and "join" in e]
    assert joins and all(e["instruction"].startswith("join {} to {}".format(*e["join"])) for e in joins)
    assert f"and the operations of its {len(joins)} joins reproduced" in _replays(run["replay"])
    _no_traceback(ran)


LEVELS_RUN = ros_job("several levels", _levels_run)
LAUNCH_RUN = ros_job("cell.launch", _launch_run)
JOINS_RUN = ros_job("joins", _joins_run)
#: The runs, started with the session in its ROS lane (tests/background.py).
BACKGROUND = (LEVELS_RUN, LAUNCH_RUN, JOINS_RUN)
