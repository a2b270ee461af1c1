"""A real ROS 1 master (Debian's rosmaster) for one test, on a free loopback port, and the aplan nodes run
against it as processes of their own; everything is stopped after the test (each process group killed).
The whole runs of the cell are background jobs (:func:`ros_job`, tests/background.py): each on a master of
its own, in the session's ROS lane, started with the session; the test asserts on what the job kept.

Without ROS the tests skip, unless APLAN_REQUIRE_ROS=1 (CI), where they fail.
"""
from __future__ import annotations

import functools
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import background
import pytest

REPO = Path(__file__).resolve().parents[3]


def require_ros() -> str:
    """The rosmaster executable; skip (or fail under APLAN_REQUIRE_ROS=1) when ROS 1 is missing."""
    master = shutil.which("rosmaster")
    try:
        from planner.runtime.ros.system import require_ros as importable

        importable()
    except Exception as exc:  # noqa: BLE001 - the reason goes into the skip
        master = None
        why = str(exc)
    else:
        why = "rosmaster is not on PATH"
    if master is None:
        if os.environ.get("APLAN_REQUIRE_ROS") == "1":
            pytest.fail(f"APLAN_REQUIRE_ROS=1 but ROS 1 is missing: {why}; bash scripts/setup.sh --ros")
        pytest.skip(f"ROS 1 is not installed: {why}")
    return master


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class RosGraph:
    """The master and the nodes of one test (``env``: the environment every node gets)."""

    def __init__(self, folder: Path, cache: Path, port: int | None = None, environment=None, tracked: bool = False):
        self.folder = folder
        self.port = port or _free_port()
        self.tracked = tracked  # a background job's: background.stop() ends its processes with the session
        home = folder / "ros_home"
        home.mkdir()
        self.env = {**(os.environ if environment is None else environment),
                    "ROS_MASTER_URI": f"http://127.0.0.1:{self.port}", "ROS_IP": "127.0.0.1",
                    "ROS_HOSTNAME": "127.0.0.1", "ROS_HOME": str(home), "ROS_LOG_DIR": str(home / "log"),
                    "APLAN_ROS_CACHE": str(cache), "PYTHONUNBUFFERED": "1"}
        self.env.pop("ROS_NAMESPACE", None)
        self.processes: dict[str, subprocess.Popen] = {}
        self.master: subprocess.Popen | None = None

    def start_master(self) -> None:
        self.master = self._spawn("master", [require_ros(), "--core", "-p", str(self.port), "-w", "2"])
        from planner.runtime.ros.adapters import MasterWatch

        watch = MasterWatch(self.env["ROS_MASTER_URI"], seconds=1.0)
        for _ in range(200):  # 20 s at most: a bound on a hang, not a result
            if watch.online():
                return
            if self.master.poll() is not None:
                break
            time.sleep(0.1)
        raise AssertionError(f"rosmaster did not start: {self.output('master')}")

    def aplan(self, name: str, *arguments: str) -> subprocess.Popen:
        """Start ``aplan ARGUMENTS`` (this repository's, under this Python) as node process ``name``."""
        return self._spawn(name, [sys.executable, "-m", "planner", *arguments])

    def _spawn(self, name: str, command: list[str]) -> subprocess.Popen:
        out = open(self.folder / f"{name}.out", "w")
        process = background.Popen(command, env=self.env, cwd=self.folder, stdout=out, stderr=subprocess.STDOUT,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
        self.processes[name] = process
        if self.tracked:
            background.track(process)
        return process

    def output(self, name: str) -> str:
        return (self.folder / f"{name}.out").read_text()

    def wait(self, name: str, timeout: float = 240) -> int:
        """The exit status of node ``name`` (``timeout``: only turns a hang into a failure)."""
        try:
            return self.processes[name].wait(timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"{name} still runs after {timeout} s:\n{self.output(name)}") from None

    def kill(self, name: str) -> None:
        process = self.processes[name]
        if process.poll() is None:
            try:
                os.killpg(process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            process.wait(10)

    def stop(self) -> None:
        """SIGTERM to every node still running at once, then SIGKILL to what is left after 5 s (each waited for
        in turn would add their shutdowns up)."""
        running = [name for name, process in self.processes.items() if process.poll() is None]
        for name in running:
            try:
                os.killpg(self.processes[name].pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
        deadline = time.monotonic() + 5
        for name in running:
            try:
                self.processes[name].wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                self.kill(name)
        if self.tracked:
            for process in self.processes.values():
                background.track(process, running=False)


class Ran:
    """What a background run of the cell (:func:`ros_job`) kept: its graph (``folder``: the nodes' files), each
    node's output as it was when the run ended (before its nodes were stopped), and what the run returned."""

    def __init__(self, graph: RosGraph, outputs: dict[str, str], result):
        self.graph, self.folder, self.outputs, self.result = graph, graph.folder, outputs, result

    def output(self, name: str) -> str:
        return self.outputs[name]


def ros_job(name: str, work, lane: str = "ros") -> background.Job:
    """A background job: ``work(graph)`` on a master of its own (a :class:`RosGraph` in a folder of the job's,
    in the session start's environment), its nodes stopped afterwards; the job's result is a :class:`Ran`. A
    test calls :func:`require_ros` before it asks for the result (a job never started runs then, in the test)."""
    def run() -> Ran:
        graph = RosGraph(background.folder(re.sub(r"[^a-z0-9]+", "-", name.lower())), _session_cache(),
                         environment=background.ENVIRONMENT, tracked=True)
        graph.start_master()
        try:
            result = work(graph)
            return Ran(graph, {n: graph.output(n) for n in graph.processes}, result)
        finally:
            graph.stop()
    return background.Job(f"ros: {name}", run, lane=lane)


@functools.cache
def _session_cache() -> Path:
    """The background jobs' folder of generated aplan_msgs (one per session: the first job generates them)."""
    return background.folder("aplan_msgs")


def log_events(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def wait_for(predicate, what: str, timeout: float = 120) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)


@pytest.fixture(scope="session")
def ros_cache(tmp_path_factory):
    """One folder of generated aplan_msgs for the test session."""
    return tmp_path_factory.mktemp("aplan_msgs")


@pytest.fixture
def ros(tmp_path, ros_cache):
    """A running ROS master on a free loopback port; stopped after the test with every node."""
    require_ros()
    graph = RosGraph(tmp_path, ros_cache)
    graph.start_master()
    try:
        yield graph
    finally:
        graph.stop()
