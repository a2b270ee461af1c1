"""Slow FreeCAD work of the test session, done beside the tests instead of in front of them.

A *job* is a function without arguments that runs one command (FreeCADCmd on a script, ``python -m planner
export-freecad``, the FreeCAD window under Xvfb) through :func:`run` and returns what a fixture reads. A test
module lists the jobs its fixtures read in a module attribute ``BACKGROUND``; tests/conftest.py runs those
modules after the others, and starts their jobs when the session starts, in threads of their own, in the
order the modules will need them. FreeCAD then works in its own processes on the machine's second core while
the tests of the other modules run on the first (the suite itself runs on one core). A job's ``lane`` names
its threads: the ROS sessions (tests/runtime/ros), which mostly wait on each other's messages, run in a lane
of their own beside FreeCAD's.

Nothing is checked in the thread: a fixture calls :meth:`Job.result`, which waits for the job (or runs it at
once, when it was not started or not begun yet), and makes the same checks as before on what it returns.
FreeCAD's lane has two threads, the others one (:data:`WORKERS`): a FreeCAD job spends about half of its wall
time off the CPU (start-up, the window's timers, Xvfb), so two at once keep that core busy.
``APLAN_TEST_BACKGROUND=0`` turns this off: every job runs when a fixture first asks for it, as before.
"""
from __future__ import annotations

import atexit
import concurrent.futures
import os
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path

__all__ = ["CPU", "ENVIRONMENT", "LANES", "SECONDS", "SPANS", "WAITED", "WORKERS", "WORKING_FOLDER", "Job", "Popen", "enabled", "folder", "run", "start",
           "stop", "track"]

#: The environment and working folder of the session's start, for every command run here: a test may change
#: its own for a while (a fault-injection variable, ``monkeypatch.chdir``) while a job starts.
ENVIRONMENT = dict(os.environ)
WORKING_FOLDER = os.getcwd()

#: Threads per lane (one when not named). FreeCAD's: the lane's jobs used 258 CPU s in 741 s of wall time one
#: at a time (load 6, bench/README.md: the suite's lanes), so a second thread runs one while another waits.
WORKERS = {"freecad": 2}
_executors: dict[str, concurrent.futures.ThreadPoolExecutor] = {}  # lane -> its threads
_running: set[subprocess.Popen] = set()
_lock = threading.Lock()


def enabled() -> bool:
    """False when ``APLAN_TEST_BACKGROUND=0``: jobs then run only when asked for, in the test's thread."""
    return os.environ.get("APLAN_TEST_BACKGROUND", "1") != "0"


class Job:
    """A named piece of slow work (``work``: no arguments, returns the result), done once per session."""

    def __init__(self, name: str, work: Callable[[], object], lane: str = "freecad") -> None:
        self.name, self.work, self.lane = name, _timed(name, work), lane
        LANES[name] = lane
        self._future: concurrent.futures.Future | None = None
        self._lock = threading.Lock()

    def __repr__(self) -> str:
        return f"Job({self.name!r})"

    def submit(self, executor: concurrent.futures.ThreadPoolExecutor) -> None:
        with self._lock:
            if self._future is None:
                self._future = executor.submit(self.work)

    def result(self) -> object:
        """The job's result: waits for the background run, or does the work now when the job was not
        started, or is still queued behind others (then it is taken off the queue). An exception of the
        work is raised here, in the test."""
        with self._lock:
            mine = self._future is None or self._future.cancel()
            if mine:  # this thread does the work; others asking meanwhile wait for it
                self._future = concurrent.futures.Future()
                self._future.set_running_or_notify_cancel()
            future = self._future
        if mine:
            try:
                future.set_result(self.work())
            except Exception as exc:  # noqa: BLE001  (raised again by future.result(), in every waiting test)
                future.set_exception(exc)
        begun = time.monotonic()
        try:
            return future.result()
        finally:
            WAITED[self.name] = WAITED.get(self.name, 0.0) + time.monotonic() - begun


SECONDS: dict[str, float] = {}  # each finished job's wall seconds (a report only: no test reads it)
#: Each finished job's CPU seconds: its thread's own and those of the commands it ran and waited for (with what
#: they waited for: xvfb-run's FreeCAD). A report only, as SECONDS: on a loaded machine the wall time is inflated
#: by the others' work, the CPU time is not.
CPU: dict[str, float] = {}
LANES: dict[str, str] = {}  # each job's lane, by its name (for the report's sums)
#: Each finished job's begin and end (time.monotonic()): a lane's span, from its first job's begin to its last
#: one's end, is its wall time with two jobs at once.
SPANS: dict[str, tuple[float, float]] = {}
#: The wall seconds the tests spent waiting for each job run elsewhere (a report: where the lanes set the pace).
WAITED: dict[str, float] = {}
_reaped = threading.local()  # .seconds: CPU seconds of the commands this thread reaped (Popen below)


class Popen(subprocess.Popen):
    """``subprocess.Popen`` that adds the CPU seconds of the command (and of what it waited for) to the job
    of the thread that reaps it: ``os.wait4`` in place of ``os.waitpid`` (the one wait that returns them)."""

    def _try_wait(self, wait_flags):  # subprocess.Popen's one call of os.waitpid (CPython 3.3 on, POSIX)
        try:
            pid, status, usage = os.wait4(self.pid, wait_flags)
        except ChildProcessError:  # as Popen's own: a child no one can wait for any more
            return self.pid, 0
        if pid == self.pid:
            _reaped.seconds = getattr(_reaped, "seconds", 0.0) + usage.ru_utime + usage.ru_stime
        return pid, status


def _timed(name: str, work: Callable[[], object]) -> Callable[[], object]:
    def timed() -> object:
        begun, thread_begun, reaped = time.monotonic(), time.thread_time(), getattr(_reaped, "seconds", 0.0)
        try:
            return work()
        finally:
            SECONDS[name] = time.monotonic() - begun
            SPANS[name] = (begun, time.monotonic())
            CPU[name] = time.thread_time() - thread_begun + getattr(_reaped, "seconds", 0.0) - reaped
    return timed


def start(jobs: Iterable[Job]) -> None:
    """Queue ``jobs`` (each once, in this order) on the background threads of each one's lane."""
    if not enabled():
        return
    for job in jobs:
        if job.lane not in _executors:
            _executors[job.lane] = concurrent.futures.ThreadPoolExecutor(
                max_workers=WORKERS.get(job.lane, 1), thread_name_prefix=f"aplan-tests-{job.lane}")
        job.submit(_executors[job.lane])


def stop() -> None:
    """End of the session: drop the queued jobs and end the commands of the running ones."""
    for executor in _executors.values():
        executor.shutdown(wait=False, cancel_futures=True)
    _executors.clear()
    with _lock:
        for process in list(_running):
            _kill(process)


def track(process: subprocess.Popen, running: bool = True) -> None:
    """Count ``process`` (started in a session of its own) among the commands :func:`stop` ends, or no longer
    (``running`` False): for a job that starts processes itself, as the ROS sessions' nodes."""
    with _lock:
        (_running.add if running else _running.discard)(process)


def _kill(process: subprocess.Popen) -> None:
    """End ``process`` and what it started (xvfb-run starts Xvfb and FreeCAD): its whole process group."""
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def folder(name: str) -> Path:
    """A new folder for a job's files (a job runs before pytest's ``tmp_path`` exists), removed at exit."""
    path = Path(tempfile.mkdtemp(prefix=f"aplan-{name}-"))
    atexit.register(shutil.rmtree, path, True)
    return path


def run(command: list[str], timeout: float = 600, **options) -> subprocess.CompletedProcess:
    """``subprocess.run(command, capture_output=True, text=True, timeout=timeout, **options)``, with standard
    input closed, the environment and working folder of the session's start (unless ``options`` give them),
    in a process group of its own that :func:`stop` ends when the session ends first (and a
    timeout ends, failing the test that reads the job)."""
    options = {"env": ENVIRONMENT, "cwd": WORKING_FOLDER, **options}
    with Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                          text=True, start_new_session=True, **options) as process:
        with _lock:
            _running.add(process)
        try:
            stdout, stderr = process.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            _kill(process)
            stdout, stderr = process.communicate()
            raise AssertionError(f"{command[0]} ran longer than {timeout} s:\n{stdout[-3000:]}\n{stderr[-3000:]}")
        finally:
            with _lock:
                _running.discard(process)
    return subprocess.CompletedProcess(command, process.returncode, stdout, stderr)
