"""The batch job protocol: how a caller runs an action of ``freecad_aplan/batch.py`` in another process.

- The job is a JSON object ``{"action": ..., **arguments}`` in the environment variable ``APLAN_BATCH``.
- The script answers on standard output with one line ``APLAN-RESULT <json>`` or ``APLAN-ERROR <message>``
  (one line: newlines in the message become `` | ``), since FreeCADCmd's exit code is not reliable and
  FreeCAD prints its own lines around it. Before that, long jobs may print progress lines
  ``APLAN-PROGRESS <seconds> <lower bound> <upper bound>`` (the solver), or ``APLAN-NOTE <text>`` (any
  other progress, one line of text for the user).

The command line (:mod:`freecad_aplan.runner`), the workbench's background jobs
(:mod:`freecad_aplan.gui.jobs`) and the script itself speak it through this module, which imports neither
FreeCAD nor Qt.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Mapping

__all__ = ["BATCH_SCRIPT", "JOB_VARIABLE", "Answer", "encode_job", "decode_job", "result_line", "error_line",
           "progress_line", "read_progress", "note_line", "read_note", "read_answer"]

#: The script a job runs (in FreeCADCmd, or in a plain Python for the actions that need no FreeCAD).
BATCH_SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "batch.py")
#: The environment variable that carries the job.
JOB_VARIABLE = "APLAN_BATCH"

_RESULT, _ERROR, _PROGRESS, _NOTE = "APLAN-RESULT ", "APLAN-ERROR ", "APLAN-PROGRESS ", "APLAN-NOTE "


@dataclass(frozen=True)
class Answer:
    """A job's answer: its JSON ``result``, or the ``error`` message it reported (then ``result`` is None)."""

    result: Any = None
    error: str | None = None


def encode_job(job: Mapping[str, Any]) -> str:
    """The value of ``APLAN_BATCH`` for ``job``: its ``action`` and the action's arguments."""
    return json.dumps(dict(job))


def decode_job(environment: Mapping[str, str]) -> dict:
    """The job in ``environment`` (``os.environ`` in the script): a dict with its ``action``."""
    return json.loads(environment[JOB_VARIABLE])


def result_line(result: Any) -> str:
    return _RESULT + json.dumps(result)


def error_line(message: str) -> str:
    return _ERROR + message.replace("\n", " | ")


def progress_line(seconds: float, lower: float, upper: float) -> str:
    return f"{_PROGRESS}{seconds:.1f} {lower:.6f} {upper:.6f}"


def read_progress(line: str) -> tuple[str, str, str] | None:
    """(seconds, lower bound, upper bound) as printed, when ``line`` is a progress line; else None."""
    if not line.startswith(_PROGRESS):
        return None
    fields = line.split()[1:]
    return (fields[0], fields[1], fields[2]) if len(fields) == 3 else None


def note_line(text: str) -> str:
    return _NOTE + text.replace("\n", " | ")


def read_note(line: str) -> str | None:
    """The text of a note line, else None."""
    return line[len(_NOTE):].rstrip("\n") if line.startswith(_NOTE) else None


def read_answer(output: str) -> Answer | None:
    """The answer in a job's standard output (the first answer line), or None when it printed none."""
    for line in output.splitlines():
        if line.startswith(_ERROR):
            return Answer(error=line[len(_ERROR):])
        if line.startswith(_RESULT):
            return Answer(result=json.loads(line[len(_RESULT):]))
    return None
