"""Helpers of the tests that run FreeCAD or the command line: the pen's liaisons, ``aplan`` (run in this process),
and the answer of a FreeCADCmd script."""
from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from aplan_runner import run_aplan
from background import Job, folder, run

__all__ = ["LIAISONS", "aplan", "aplan_process", "freecad_result", "freecadcmd_job", "succeeded"]

#: The pen's connection diagram (the ground truth of the models in ../shared).
LIAISONS = {frozenset(p) for p in [("ink_001", "cartridge_001"), ("cartridge_001", "head_001"),
                                   ("head_001", "body_001"), ("body_001", "cap_001"), ("body_001", "button_001")]}


def freecad_result(done: subprocess.CompletedProcess) -> dict:
    """The JSON a FreeCADCmd script printed after ``APLAN-RESULT`` (FreeCAD's progress output surrounds it)."""
    found = re.search(r"APLAN-RESULT (.*)", done.stdout)
    assert found, f"no result from FreeCAD:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return json.loads(found.group(1))


def freecadcmd_job(name: str, script: Callable[[Path], str], files: dict[str, Path] | None = None) -> Job:
    """A background job (tests/background.py): FreeCADCmd runs the script ``script(tmp)`` in a new folder
    ``tmp``, after ``files`` (name there -> file) are copied into it; its result is ``(tmp, the run)``.
    ``name`` names the folder and the script (``NAME_probe.py``: FreeCADCmd imports a script by its name)."""

    def work() -> tuple[Path, subprocess.CompletedProcess]:
        tmp = folder(name)
        for target, source in (files or {}).items():
            shutil.copy(source, tmp / target)
        path = tmp / f"{name}_probe.py"
        path.write_text(script(tmp))
        return tmp, run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(path)])

    return Job(name, work)


def aplan(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    """Run the command line ``aplan ARGS`` (its ``main``, in this process: FreeCAD still runs in its own, as it
    does from ``python -m planner``); fails the test when it fails, if ``check``."""
    done = run_aplan(*args)
    return succeeded(done) if check else done


def aplan_process(*args: str) -> subprocess.CompletedProcess:
    """``aplan ARGS`` in a process of its own, unchecked: what a background job (tests/background.py) runs,
    since ``aplan`` in this process redirects the standard output, which only the tests' thread may do."""
    done = run([sys.executable, "-m", "planner", *args])
    return subprocess.CompletedProcess(["aplan", *args], done.returncode, done.stdout, done.stderr)


def succeeded(done: subprocess.CompletedProcess) -> subprocess.CompletedProcess:
    """``done``, when ``aplan`` succeeded; fails the test with its output otherwise."""
    if done.returncode != 0:
        raise AssertionError(f"aplan {' '.join(done.args[1:])} failed ({done.returncode}):\n{done.stdout}\n"
                             f"{done.stderr}")
    return done


# Shared by the GUI test scripts (run inside the FreeCAD window; each defines OUT, result and imports json, os,
# traceback): write the result and leave at once; run a Qt-timer step, ending the run with its traceback.
GUI_HELPERS = '''
def finish(code):
    with open(OUT, "w") as handle:
        json.dump(result, handle)
    os._exit(code)


def guarded(step):
    def run():
        try:
            step()
        except Exception:
            result["error"] = traceback.format_exc()
            finish(1)
    return run
'''
