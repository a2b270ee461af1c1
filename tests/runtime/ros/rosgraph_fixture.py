"""A real ROS 1 master (Debian's rosmaster) for one test, on a free loopback port, and the aplan nodes run
against it as processes of their own; everything is stopped after the test (each process group killed).

Without ROS the tests skip, unless APLAN_REQUIRE_ROS=1 (CI), where they fail.
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

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

    def __init__(self, folder: Path, cache: Path, port: int | None = None):
        self.folder = folder
        self.port = port or _free_port()
        home = folder / "ros_home"
        home.mkdir()
        self.env = {**os.environ, "ROS_MASTER_URI": f"http://127.0.0.1:{self.port}", "ROS_IP": "127.0.0.1",
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
        process = subprocess.Popen(command, env=self.env, cwd=self.folder, stdout=out, stderr=subprocess.STDOUT,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
        self.processes[name] = process
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


@pytest.fixture(scope="module")
def ros_master(tmp_path_factory, ros_cache):
    """One master for a module's tests (each starts its own master takes ~1 s and a process); the tests' nodes
    are stopped after each (:func:`ros_shared`). Not for a test that stops the master."""
    require_ros()
    graph = RosGraph(tmp_path_factory.mktemp("rosmaster"), ros_cache)
    graph.start_master()
    try:
        yield graph
    finally:
        graph.stop()


@pytest.fixture
def ros_shared(tmp_path, ros_cache, ros_master):
    """The nodes of one test on the module's master (:func:`ros_master`); stopped after the test."""
    graph = RosGraph(tmp_path, ros_cache, port=ros_master.port)
    try:
        yield graph
    finally:
        graph.stop()


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
