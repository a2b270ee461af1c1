"""Run FreeCAD jobs from any Python: find FreeCADCmd and run ``freecad_aplan.batch`` in it.

This module does not import FreeCAD: the planner's command line uses it to reach FreeCAD as a separate
program. A job's arguments travel as JSON in the environment; its answer is one line of standard output
(:mod:`freecad_aplan.protocol`).
"""
from __future__ import annotations

import os
import shutil
import subprocess
import threading
from typing import Callable

from planner.errors import PlannerError
from planner.interrupts import start_child

from .protocol import BATCH_SCRIPT, JOB_VARIABLE, encode_job, read_answer, read_note

__all__ = ["FreeCADError", "find_freecadcmd", "run_batch"]

_NAMES = ("freecadcmd", "FreeCADCmd", "freecadcmd-daily")


class FreeCADError(PlannerError):
    """FreeCAD is missing, or a FreeCAD job failed (the message says which and why)."""


def find_freecadcmd(explicit: str | None = None) -> str:
    """The FreeCADCmd executable: ``explicit``, else ``$APLAN_FREECADCMD``, else the first on PATH."""
    for candidate in (explicit, os.environ.get("APLAN_FREECADCMD")):
        if candidate:
            found = shutil.which(candidate)
            if found is None:
                raise FreeCADError(f"FreeCADCmd {candidate!r} not found or not executable")
            return found
    for name in _NAMES:
        found = shutil.which(name)
        if found:
            return found
    raise FreeCADError("FreeCADCmd is not on PATH: install FreeCAD (Debian: apt install freecad-python3) "
                       "or pass --freecadcmd PATH")


def run_batch(action: str, arguments: dict, freecadcmd: str | None = None, timeout: float = 3600,
              on_note: Callable[[str], None] | None = None) -> dict:
    """Run ``action`` of ``freecad_aplan.batch`` in FreeCADCmd and return its JSON result; ``on_note``
    receives the job's note lines (progress for the user) as they come."""
    executable = find_freecadcmd(freecadcmd)
    env = {**os.environ, JOB_VARIABLE: encode_job({"action": action, **arguments})}
    try:
        if on_note is None:
            done = _run_captured([executable, BATCH_SCRIPT], env, timeout)
        else:
            done = _run_streaming([executable, BATCH_SCRIPT], env, timeout, on_note)
    except subprocess.TimeoutExpired:
        raise FreeCADError(f"FreeCAD job {action!r} did not finish within {timeout:g} s") from None
    answer = read_answer(done.stdout)
    if answer is not None:
        if answer.error is not None:
            raise FreeCADError(answer.error)
        return answer.result
    tail = "\n".join((done.stdout + done.stderr).strip().splitlines()[-15:])
    raise FreeCADError(f"FreeCAD job {action!r} gave no result (exit code {done.returncode}); its last output:\n{tail}")


def _run_captured(command: list[str], env: dict, timeout: float) -> subprocess.CompletedProcess:
    """``subprocess.run`` with output captured, whose child never outlives it: killed and reaped on a timeout
    or an interrupt (``run`` does not wait for it after Ctrl-C), and killed by the kernel if this process is
    (:func:`planner.interrupts.child_options`)."""
    process = start_child(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                          stdin=subprocess.DEVNULL)
    try:
        out, err = process.communicate(timeout=timeout)
    except BaseException:
        process.kill()
        process.communicate()
        raise
    return subprocess.CompletedProcess(command, process.returncode, out, err)


def _run_streaming(command: list[str], env: dict, timeout: float, on_note: Callable[[str], None]):
    """``subprocess.run`` with standard output (and error) read line by line, notes passed on at once; a
    timer kills the job after ``timeout`` seconds (then :class:`subprocess.TimeoutExpired`)."""
    process = start_child(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                          stdin=subprocess.DEVNULL)
    killed = threading.Event()

    def kill() -> None:
        killed.set()
        process.kill()

    timer = threading.Timer(timeout, kill)
    timer.start()
    lines = []
    try:
        for line in process.stdout:
            lines.append(line)
            note = read_note(line)
            if note is not None:
                on_note(note)
        process.wait()
    except BaseException:  # an interrupt (Ctrl-C, SIGTERM): the child must not outlive the command
        process.kill()
        process.wait()
        raise
    finally:
        timer.cancel()
        process.stdout.close()
    if killed.is_set():
        raise subprocess.TimeoutExpired(command, timeout)
    return subprocess.CompletedProcess(command, process.returncode, "".join(lines), "")
