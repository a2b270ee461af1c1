"""Detect's settings without FreeCAD (issue 26, item 4): the engine and the exact engine's time limit that its
task panel takes (freecad_aplan.workflow.detection_settings, what the panel calls on OK) are checked as the command
line checks --time-limit, and reach the same engine code as ``aplan analyze --engine occt --time-limit S``: the
limit goes to OCCT, its progress lines to the job's notes, and the pairs it did not decide keep the mesh engine's
answers, reported with the limit's stop first.

OCCT itself is replaced here by a stand-in that stops at once, as the limit makes it (the real engine under a
tiny limit, in FreeCAD: tests/workbench/test_workbench_occt.py); the bundle is three boxes of
tests/geometry/test_bundle.py (base, peg on it, lid on the peg: base and lid far apart, an easy pair)."""
from __future__ import annotations

import json
import math

import pytest
from geometry.test_bundle import make_bundle

from freecad_aplan import plugin, workflow
from freecad_aplan.hybrid import checked_time_limit
from planner.cli.options import positive_seconds
from planner.defaults import OCCT_TIME_LIMIT, TIME_LIMIT_MAX
from planner.errors import PlannerError

BAD = ["0", "-5", "nan", "inf", "-inf", "", "abc", "1e7", "  "]


@pytest.mark.parametrize("text", BAD)
def test_a_time_limit_that_is_not_positive_and_finite_is_refused_naming_the_field(text):
    with pytest.raises(PlannerError) as caught:
        workflow.detection_settings("occt", text)
    message = str(caught.value)
    assert message.startswith("Time limit: must be a number of seconds")
    assert message.endswith("nothing was detected") and f"(default {OCCT_TIME_LIMIT:g})" in message


@pytest.mark.parametrize("text", ["180", " 2.5 ", "1e-9", str(TIME_LIMIT_MAX)])
def test_a_good_time_limit_is_taken_as_the_command_line_takes_it(text):
    settings = workflow.detection_settings("mesh", text)
    assert settings == {"engine": "mesh", "occt_time_limit": positive_seconds(text.strip())}
    assert settings["occt_time_limit"] == float(text)


def test_the_time_limit_check_is_the_command_lines():
    # A number (the analysis' stored OcctTimeLimit) is checked like the text typed in the panel.
    assert checked_time_limit(OCCT_TIME_LIMIT) == OCCT_TIME_LIMIT
    for value in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(PlannerError, match="must be a number of seconds above 0"):
            checked_time_limit(value)


class _Intent:  # the fields of freecad_aplan.intent.Intent the job reads (that module needs FreeCAD)
    contact, interference, depth, occt_face_weight, occt_prism_triangles = 0.01, 0.1, 0.01, 7, 9
    occt_time_limit = 0.5


def test_the_job_carries_the_time_limit():
    job = workflow.detection_job("/b", "occt", _Intent())
    assert job["time_limit"] == 0.5 and (job["face_weight"], job["prism_triangles"]) == (7, 9)
    assert job["action"] == "analyze" and job["engine"] == "occt"


def _stopped_occt(asked):
    """A stand-in for the ``analyze-occt`` job that the time limit stops before any pair is decided."""
    def run(product, arguments, progress):
        asked.append(arguments)
        progress(f"occt: contacts 0/{len(arguments['pairs'])} (0 s, {len(arguments['pairs'])} pairs undecided)")
        pairs = [list(p) for p in arguments["pairs"]]
        relations = [[a, b, what] for a, b in pairs for what in
                     ["the contact"] + [f"{mover} moving along {d}" for mover in (a, b) for d in ("+X", "+Y", "+Z")]]
        return {"contacts": [], "interferences": [], "obstructions": {"+X": [], "+Y": [], "+Z": []},
                "undecided": pairs, "undecided_relations": relations, "timed_out": True,
                "time_limit": arguments["time_limit"], "warnings": []}
    return run


def test_detect_runs_the_command_lines_engine_with_the_limit_and_keeps_the_mesh_answers(tmp_path, monkeypatch):
    asked, told = [], []
    monkeypatch.setattr(plugin, "_run_occt", _stopped_occt(asked))
    mesh = make_bundle(tmp_path / "mesh")
    workflow.analyze_bundle(str(mesh), "mesh")
    exact = make_bundle(tmp_path / "exact")
    job = workflow.detection_job(str(exact), "occt", _Intent())
    result = workflow.analyze_bundle(**{k: v for k, v in job.items() if k != "action"}, progress=told.append)
    (arguments,) = asked
    assert arguments["time_limit"] == 0.5
    # The exact pairs: the two that touch (base-peg, peg-lid); base and lid are far apart, settled on the meshes.
    assert sorted(sorted(p) for p in arguments["pairs"]) == [["base", "peg"], ["lid", "peg"]]
    # Progress: OCCT's lines, as aplan analyze prints them on standard error, then the undecided pairs.
    assert told[0] == "occt: deciding 2 of 3 pairs on the exact shapes (at most 0.5 s)"
    assert told[1] == "occt: contacts 0/2 (0 s, 2 pairs undecided)"
    assert told[2:] == result["undecided"]
    stop, *pairs = result["undecided"]
    assert stop == ("2 pairs not decided within the exact engine's time limit of 0.5 s; for each, the mesh engine's "
                    "answer stands (a longer time limit decides more of them)")
    assert len(pairs) == 2 and all(p.endswith("+Z): the mesh engine's answer stands") for p in pairs)
    assert result["summary"] == "2 pairs not decided within 0.5 s, mesh answers kept"
    # Every relation is the mesh engine's: OCCT decided none.
    written, reference = (json.loads((b / "product.json").read_text()) for b in (exact, mesh))
    assert written["contacts"] == reference["contacts"] and written["obstructions"] == reference["obstructions"]
    assert len(reference["contacts"]) == 2 and any(o["blocks"] for o in reference["obstructions"])  # not empty
    record = written["geometry"]["analysis"]["tolerances"]["pairs"]
    assert record["timed_out"] is True and record["time_limit"] == 0.5 and record["mesh"] == 1
