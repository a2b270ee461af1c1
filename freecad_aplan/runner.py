"""Run FreeCAD jobs from any Python: find FreeCADCmd and run ``freecad_aplan.batch`` in it.

This module does not import FreeCAD: the planner's command line uses it to reach FreeCAD as a separate
program. A job's arguments travel as JSON in the environment; its answer is one ``APLAN-RESULT`` line.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

from planner.errors import PlannerError

__all__ = ["FreeCADError", "find_freecadcmd", "run_batch"]

BATCH_SCRIPT = Path(__file__).resolve().parent / "batch.py"
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


def run_batch(action: str, arguments: dict, freecadcmd: str | None = None, timeout: float = 3600) -> dict:
    """Run ``action`` of ``freecad_aplan.batch`` in FreeCADCmd and return its JSON result."""
    executable = find_freecadcmd(freecadcmd)
    env = dict(os.environ, APLAN_BATCH=json.dumps({"action": action, **arguments}))
    try:
        done = subprocess.run([executable, str(BATCH_SCRIPT)], capture_output=True, text=True, env=env,
                              timeout=timeout, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise FreeCADError(f"FreeCAD job {action!r} did not finish within {timeout:g} s") from None
    for line in done.stdout.splitlines():
        if line.startswith("APLAN-ERROR "):
            raise FreeCADError(line[len("APLAN-ERROR "):])
        if line.startswith("APLAN-RESULT "):
            return json.loads(line[len("APLAN-RESULT "):])
    tail = "\n".join((done.stdout + done.stderr).strip().splitlines()[-15:])
    raise FreeCADError(f"FreeCAD job {action!r} gave no result (exit code {done.returncode}); its last output:\n{tail}")
