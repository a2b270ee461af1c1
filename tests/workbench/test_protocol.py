"""The batch job protocol (freecad_aplan.protocol; no FreeCAD needed): a job in the environment, one answer
line among FreeCAD's own output, progress lines."""
from __future__ import annotations

import os
import subprocess
import sys

from freecad_aplan.protocol import (
    BATCH_SCRIPT,
    JOB_VARIABLE,
    decode_job,
    encode_job,
    error_line,
    progress_line,
    read_answer,
    read_progress,
    result_line,
)


def test_job_travels_in_the_environment():
    job = {"action": "analyze", "folder": "/tmp/b", "contact": 0.1}
    assert decode_job({JOB_VARIABLE: encode_job(job)}) == job


def test_the_answer_is_found_among_other_output():
    output = "FreeCAD 0.20\n(50 %)\n" + progress_line(1.25, 3.5, 4.0) + "\n" + result_line({"parts": 6}) + "\nbye\n"
    answer = read_answer(output)
    assert answer.result == {"parts": 6} and answer.error is None
    failed = read_answer("noise\n" + error_line("part 'ink': no B-rep\nre-export the bundle") + "\n")
    assert failed.error == "part 'ink': no B-rep | re-export the bundle" and failed.result is None
    assert read_answer("FreeCAD crashed\n") is None


def test_progress_lines():
    assert read_progress(progress_line(12.04, 3.930581, 4.0033)) == ("12.0", "3.930581", "4.003300")
    assert read_progress("APLAN-PROGRESS 12.0") is None and read_progress("(12 %)") is None


def test_the_script_answers_an_unknown_action_with_one_error_line():
    """batch.py in a plain Python (no FreeCAD): a bad job is told in one APLAN-ERROR line."""
    env = {**os.environ, JOB_VARIABLE: encode_job({"action": "fly"})}
    done = subprocess.run([sys.executable, BATCH_SCRIPT], capture_output=True, text=True, timeout=60, env=env)
    answer = read_answer(done.stdout)
    assert answer is not None and answer.error == "unknown batch action 'fly'"
