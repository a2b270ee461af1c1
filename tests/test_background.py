"""The session's background jobs (tests/background.py): each done once, in the background or by the test that
asks first, its exception raised in the test; a job still queued is taken off the queue and done at once."""
from __future__ import annotations

import concurrent.futures
import sys
import threading

import background
import pytest


def _counting(value: object = "done"):
    calls: list[str] = []

    def work() -> object:
        calls.append(threading.current_thread().name)
        return value

    return work, calls


def test_a_job_not_started_is_done_once_by_the_test():
    work, calls = _counting()
    job = background.Job("count", work)
    assert job.result() == job.result() == "done"
    assert calls == [threading.current_thread().name]


def test_a_started_job_is_done_in_the_background_once():
    work, calls = _counting()
    job = background.Job("count", work)
    with concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="bg") as executor:
        job.submit(executor)
        job.submit(executor)  # queued once
        assert job.result() == "done" and job.result() == "done"
    assert len(calls) == 1 and calls[0].startswith("bg")


def test_a_queued_job_is_taken_off_the_queue_and_done_at_once():
    release = threading.Event()
    # The bound only keeps a broken Job from hanging the suite: it would then wait here and fail below.
    blocker = background.Job("blocker", lambda: release.wait(60))
    work, calls = _counting()
    queued = background.Job("queued", work)
    with concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="bg") as executor:
        blocker.submit(executor)
        queued.submit(executor)
        assert queued.result() == "done"  # without waiting for the blocker
        assert calls == [threading.current_thread().name]
        release.set()
        assert blocker.result() is True
    assert calls == [threading.current_thread().name]  # the cancelled run never happened


def test_the_exception_of_a_job_is_raised_in_every_test_that_asks():
    def work():
        raise ValueError("the model is missing")

    job = background.Job("failing", work)
    with concurrent.futures.ThreadPoolExecutor(1) as executor:
        job.submit(executor)
        for _ in range(2):
            with pytest.raises(ValueError, match="the model is missing"):
                job.result()


def test_run_returns_what_subprocess_run_would():
    script = "import sys; print('out'); print('err', file=sys.stderr); sys.exit(3)"
    done = background.run([sys.executable, "-c", script])
    assert (done.returncode, done.stdout, done.stderr) == (3, "out\n", "err\n")


def test_commands_run_in_the_environment_and_folder_of_the_session_start(monkeypatch, tmp_path):
    """A test changing its environment or folder for a while (fault injection, monkeypatch.chdir) does not
    reach a job that starts meanwhile."""
    monkeypatch.setenv("APLAN_FAULT_DISK_FULL", "0")
    monkeypatch.chdir(tmp_path)
    script = "import os; print(os.environ.get('APLAN_FAULT_DISK_FULL', 'unset')); print(os.getcwd())"
    done = background.run([sys.executable, "-c", script])
    assert done.stdout.splitlines() == [background.ENVIRONMENT.get("APLAN_FAULT_DISK_FULL", "unset"),
                                        background.WORKING_FOLDER]
    assert background.WORKING_FOLDER != str(tmp_path)


def test_each_lane_has_a_thread_of_its_own():
    """A job of one lane (the ROS sessions) runs while another lane's (FreeCAD's) is still busy."""
    if not background.enabled():
        pytest.skip("APLAN_TEST_BACKGROUND=0: jobs run in the tests")
    release, ran = threading.Event(), threading.Event()
    names: list[str] = []

    def other() -> str:
        names.append(threading.current_thread().name)
        ran.set()
        return "done"

    # The bounds only keep a broken lane from hanging the suite: it would then fail below.
    blocker = background.Job("lane blocker", lambda: release.wait(60), lane="test-one")
    job = background.Job("other lane", other, lane="test-two")
    background.start([blocker, job])
    try:
        assert ran.wait(60), "the second lane's job did not run while the first lane was busy"
        assert job.result() == "done" and names[0].startswith("aplan-tests-test-two")
    finally:
        release.set()
    assert blocker.result() is True


def test_a_lane_of_two_threads_runs_two_jobs_at_once(monkeypatch):
    """A job starts while another of its lane is still busy, in a lane of two threads (background.WORKERS, as
    FreeCAD's; a lane of its own: FreeCAD's is busy with the session's jobs)."""
    if not background.enabled():
        pytest.skip("APLAN_TEST_BACKGROUND=0: jobs run in the tests")
    assert background.WORKERS["freecad"] == 2
    monkeypatch.setitem(background.WORKERS, "test-pair", 2)
    release, ran = threading.Event(), threading.Event()
    # The bounds only keep a broken lane from hanging the suite: it would then fail below.
    blocker = background.Job("pair blocker", lambda: release.wait(60), lane="test-pair")
    job = background.Job("second of the pair", lambda: ran.set() or "done", lane="test-pair")
    background.start([blocker, job])
    try:
        assert ran.wait(60), "the lane's second job did not start while the first was busy"
        assert job.result() == "done"
    finally:
        release.set()
    assert blocker.result() is True
