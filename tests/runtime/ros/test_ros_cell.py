"""The cell on ROS against a real ROS master (Debian's rosmaster on a loopback port, tests/runtime/ros/
rosgraph_fixture.py): the planner node, the vision server fed by the simulated cell's rendered frames and
its robot server assemble the pen, writing the log `aplan session --demo` writes; then the faults. Each run
is a background job (:func:`rosgraph_fixture.ros_job`, on a master of its own, started with the session);
each test asserts on what its run kept: exit statuses, outputs, logs, and the replays of the logs."""
from __future__ import annotations

import subprocess
from collections import Counter
import sys
from pathlib import Path

from planner.decision.io.habits_file import read_habits
from rosgraph_fixture import REPO, log_events, require_ros, ros_job, wait_for

MODEL = ["pen", "--expansions", "200"]  # a fixed amount of work per decision: the same actions on any machine
TIMING = ("time", "decision_ms")  # what differs between two runs of the same session


def _comparable(events: list[dict]) -> list[dict]:
    out = []
    for event in events:
        event = {k: v for k, v in event.items() if k not in TIMING}
        if event["event"] == "start":  # where the frames and the robot were: the only settings that differ
            event["settings"] = {k: v for k, v in event["settings"].items() if k not in ("source", "robot")}
        out.append(event)
    return out


def _cell(ros, *sim: str) -> None:
    ros.aplan("vision", "ros-vision", "pen")
    ros.aplan("sim", "ros-sim", *MODEL, "--demo", "0", *sim)


def _planner(ros, *extra: str) -> tuple[int, str, Path]:
    log = ros.folder / "ros.jsonl"
    # --frame-timeout: a bound on a hang (a test may lower it)
    ros.aplan("planner", "ros", *MODEL, "--log", str(log), "--frame-timeout", "120", *extra)
    status = ros.wait("planner")
    return status, ros.output("planner"), log


def _no_traceback(ran) -> None:
    """No node of the run (a :class:`rosgraph_fixture.Ran`, or a graph still running) printed a traceback."""
    names = ran.outputs if hasattr(ran, "outputs") else ran.processes
    for name in names:
        assert "Traceback" not in ran.output(name), ran.output(name)


def _replay(log: Path) -> subprocess.CompletedProcess:
    """``aplan replay LOG`` (a background job runs it; :func:`_replays` checks it)."""
    return subprocess.run([sys.executable, "-m", "planner", "replay", str(log)], capture_output=True, text=True,
                          cwd=REPO, timeout=300)


def _replays(log: Path | subprocess.CompletedProcess) -> str:
    """What ``aplan replay`` printed on ``log`` (or the replay a job ran), asserting that it succeeded."""
    done = _replay(log) if isinstance(log, Path) else log
    assert done.returncode == 0, done.stderr
    return done.stdout


def _counts(path: Path, add: Counter | None = None) -> Counter:
    """The edge counts of a habits file (plus ``add``), zeros left out."""
    counts = Counter({(a, b): n for a, b, n in read_habits(path).counts})
    counts.update(add or {})
    return +counts


def _habits(log: Path, out: Path) -> subprocess.CompletedProcess:
    """``aplan habits LOG -o OUT`` (a background job runs it; :func:`_log_counts` checks it)."""
    return subprocess.run([sys.executable, "-m", "planner", "habits", str(log), "-o", str(out)], capture_output=True,
                          text=True, cwd=REPO, timeout=300)


def _log_counts(log: Path, out: Path, done: subprocess.CompletedProcess | None = None) -> Counter:
    """The counts ``aplan habits`` learns from ``log`` (run now, or the run ``done`` a job made)."""
    done = done or _habits(log, out)
    assert done.returncode == 0, done.stderr
    return _counts(out)


def _pen_run(ros):
    demo = ros.folder / "demo.jsonl"
    ros._spawn("demo", [sys.executable, "-m", "planner", "session", *MODEL, "--demo", "0", "--log", str(demo)])
    _cell(ros)  # the in-process demo runs beside the ROS one
    status, _, log = _planner(ros, "--habits-out", str(ros.folder / "habits.json"))
    return dict(status=status, log=log, demo=demo, demo_status=ros.wait("demo"), replay=_replay(log),
                habits=_habits(log, ros.folder / "log-habits.json"))


def test_the_pen_on_ros_writes_the_demo_log_and_replays():
    require_ros()
    ran = PEN.result()
    run, output = ran.result, ran.output("planner")
    assert run["status"] == 0, output
    assert "assembled: the product is assembled" in output
    assert run["demo_status"] == 0, ran.output("demo")
    ros_events, demo_events = log_events(run["log"]), log_events(run["demo"])
    assert _comparable(ros_events) == _comparable(demo_events)
    assert ros_events[0]["settings"]["source"] == "ros /markers"
    assert ros_events[0]["settings"]["robot"] == "ros /perform"
    assert ros_events[-1]["reason"] == "assembled"
    assert f"beliefs reproduced at all {ros_events[-1]['step']} steps" in _replays(run["replay"])
    assert _counts(ran.folder / "habits.json") == _log_counts(run["log"], ran.folder / "log-habits.json",
                                                              run["habits"])  # no --habits: none
    _no_traceback(ran)


def _ended(log: Path, reason: str, step: int, replay: subprocess.CompletedProcess) -> dict:
    events = log_events(log)
    end = events[-1]
    assert end["event"] == "end" and end["reason"] == reason and end["step"] == step, end
    steps = [e["step"] for e in events if e["event"] == "belief"]
    assert steps == list(range(1, step)), steps  # every step before the fault is in the log
    _replays(replay)
    return end


def _fault_run(sim: tuple[str, ...], planner: tuple[str, ...] = ()):
    """A run of the cell with the simulation's fault ``sim`` and the planner's options ``planner``."""
    def work(ros):
        _cell(ros, *sim)
        status, _, log = _planner(ros, *planner)
        return dict(status=status, log=log, replay=_replay(log))
    return work


def test_a_robot_that_answers_failed():
    require_ros()
    ran = FAILED.result()
    output = ran.output("planner")
    assert ran.result["status"] == 1
    assert "robot failed: step 2: the robot could not" in output and "scripted failure at step 2" in output
    _ended(ran.result["log"], "robot failed", 2, ran.result["replay"])
    _no_traceback(ran)


def test_a_goal_the_robot_server_cancels_because_the_operator_changed_course():
    require_ros()
    ran = CANCELLED.result()
    output = ran.output("planner")
    assert ran.result["status"] == 1
    assert "the goal was cancelled by the robot server: the operator changed course" in output, output
    _ended(ran.result["log"], "robot failed", 2, ran.result["replay"])
    _no_traceback(ran)


def test_a_robot_that_never_answers_times_out_and_the_goal_is_cancelled():
    require_ros()
    ran = HUNG.result()
    output = ran.output("planner")
    assert ran.result["status"] == 1
    assert "gave no result within 2 s (--robot-timeout); the goal was cancelled" in output
    _ended(ran.result["log"], "robot failed", 2, ran.result["replay"])
    _no_traceback(ran)


def _step_two(log: Path) -> bool:
    return log.is_file() and any(e["event"] == "action" and e["step"] == 2 for e in log_events(log))


def _master_gone_run(ros):
    _cell(ros, "--pause-at", "2")
    log = ros.folder / "ros.jsonl"
    ros.aplan("planner", "ros", *MODEL, "--log", str(log))
    wait_for(lambda: _step_two(log), "the planner's step 2", timeout=300)
    ros.kill("master")
    return dict(status=ros.wait("planner"), log=log, replay=_replay(log))


def test_the_master_going_away_midway():
    require_ros()
    ran = MASTER_GONE.result()
    assert ran.result["status"] == 1
    output = ran.output("planner")
    assert "does not answer (it stopped, or the network is down)" in output, output
    end = log_events(ran.result["log"])[-1]
    assert end["event"] == "end" and end["reason"] == "error" and end["step"] == 2
    _replays(ran.result["replay"])
    _no_traceback(ran)


def test_the_image_topic_stopping():
    require_ros()
    ran = STOPPED.result()
    output = ran.output("planner")
    assert ran.result["status"] == 1
    assert "no marker message on /markers for 8 s (--frame-timeout) after 12 frames" in output, output
    end = log_events(ran.result["log"])[-1]
    assert end["event"] == "end" and end["reason"] == "error" and end["step"] == 1
    _replays(ran.result["replay"])
    _no_traceback(ran)


def _sigterm_run(ros):
    # a master of its own (every run has one): once, on a master shared with other tests, the planner did not
    # exit on SIGTERM (an interrupt rospy swallowed? RosRobot.perform now re-raises those)
    import os
    import signal

    _cell(ros, "--hang-at", "2")
    log = ros.folder / "ros.jsonl"
    ros.aplan("planner", "ros", *MODEL, "--log", str(log), "--frame-timeout", "120")
    wait_for(lambda: _step_two(log), "the planner's step 2", timeout=300)
    os.kill(ros.processes["planner"].pid, signal.SIGTERM)
    return dict(status=ros.wait("planner"), log=log, replay=_replay(log))


def test_sigterm_while_the_robot_works_cancels_the_goal_and_ends_the_log():
    require_ros()
    ran = SIGTERM.result()
    assert ran.result["status"] == 143
    assert "interrupted (SIGTERM): the session log" in ran.output("planner")
    end = log_events(ran.result["log"])[-1]
    assert end["event"] == "end" and end["reason"] == "interrupted" and end["step"] == 2
    _replays(ran.result["replay"])
    _no_traceback(ran)


PEN = ros_job("the pen", _pen_run)
FAILED = ros_job("robot failed", _fault_run(("--fail-at", "2")))
CANCELLED = ros_job("goal cancelled", _fault_run(("--cancel-at", "2")))
HUNG = ros_job("robot hangs", _fault_run(("--hang-at", "2"), ("--robot-timeout", "2")))
MASTER_GONE = ros_job("master gone", _master_gone_run)
STOPPED = ros_job("image topic stops", _fault_run(("--stop-after", "12"), ("--frame-timeout", "8")))
SIGTERM = ros_job("sigterm", _sigterm_run)
#: The runs, started with the session in its ROS lane (tests/background.py), in this module's order.
BACKGROUND = (PEN, FAILED, CANCELLED, HUNG, MASTER_GONE, STOPPED, SIGTERM)
