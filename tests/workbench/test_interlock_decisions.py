"""The designer's decisions on interlock proposals in the analysis (freecad_aplan.interlocks), in real FreeCAD
without the GUI, on a knob captured by a cover over a housing (tests/assembly/test_interlocks.py): accepting the
one-component proposal groups the two objects and merges their diagrams in one undo step (the objects' shapes
and placements untouched), undo takes it back, a rejection makes the plan refuse the pair in the words of
``--interlocks error`` and goes into the product every export writes."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO, require_freecadcmd
from integration.freecad_tools import freecad_result

from planner.assembly.interlock_proposals import record_proposals
from planner.product import product_to_dict

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "assembly"))
from test_interlocks import _captured  # noqa: E402

#: The FreeCADCmd script's start (formatted with repo, the document's name, its box objects' names and the
#: diagrams to store): a document of boxes, an analysis, ``shapes()`` (the user's geometry, to compare) and
#: ``plan()`` (the workbench's plan, or the error's type and message). Shared with test_support_decisions.py.
PREAMBLE = r"""
import json, sys
sys.path.insert(0, {repo!r})
import FreeCAD, Part
from planner import api
from freecad_aplan import workflow
from freecad_aplan.intent import IntentError, create_analysis, designer_record, read_intent, update_intent
from freecad_aplan.interlocks import decide_interlocks, interlock_report

out = {{}}
doc = FreeCAD.newDocument({name!r})
doc.UndoMode = 1
for name in {parts!r}:
    doc.addObject("Part::Box", name)
doc.recompute()
def shapes():
    return {{o.Name: [o.Shape.exportBrepToString(), list(o.Placement.Base), list(o.Placement.Rotation.Q)]
            for o in doc.Objects if o.TypeId == "Part::Box"}}
before = shapes()
analysis = create_analysis(doc)
def plan():
    try:
        return ["planned", api.plan_statistics_of(workflow.analysis_product(analysis))[1].sequences]
    except Exception as exc:
        return [type(exc).__name__, str(exc)]
"""

SCRIPT = PREAMBLE + r"""
try:
    interlock_report(analysis)
except IntentError as exc:
    out["not_detected"] = str(exc)
update_intent(analysis, "detect", diagrams={diagrams!r})
proposals, lines = interlock_report(analysis)
out["report"] = [[p["rule"], p["parts"], p.get("component"), p["decision"]] for p in proposals]
out["plan_before"] = plan()
try:
    decide_interlocks(analysis, {{0: "later"}})
except IntentError as exc:
    out["bad_decision"] = str(exc)
undo = len(doc.UndoNames)
out["lines"] = decide_interlocks(analysis, {{0: "accepted"}})
intent = read_intent(analysis)
out["accepted"] = {{"undo": [len(doc.UndoNames) - undo, doc.UndoNames[0]], "groups": intent.groups,
                   "parts": intent.diagrams["parts"], "objects": intent.diagrams["objects"],
                   "contacts": intent.diagrams["contacts"], "decisions": intent.interlocks, "plan": plan(),
                   "report": [p["decision"] for p in interlock_report(analysis)[0]],
                   "again": decide_interlocks(analysis, {{0: "rejected"}}), "same": shapes() == before}}
doc.undo()
intent = read_intent(analysis)
out["undone"] = {{"groups": intent.groups, "parts": intent.diagrams["parts"], "decisions": intent.interlocks,
                 "plan": plan()}}
decide_interlocks(analysis, {{0: "rejected"}})
intent = read_intent(analysis)
out["rejected"] = {{"decisions": intent.interlocks, "groups": intent.groups, "plan": plan(),
                   "record": designer_record(intent), "same": shapes() == before}}
print("APLAN-RESULT " + json.dumps(out), flush=True)
"""


@pytest.fixture(scope="module")
def decided(tmp_path_factory) -> dict:
    freecadcmd = require_freecadcmd()
    product, parts = _captured()
    data = product_to_dict(record_proposals(product, parts))
    diagrams = {"parts": [p["id"] for p in data["parts"]], "objects": {p["id"]: [p["id"]] for p in data["parts"]},
                "contacts": data["contacts"], "obstructions": data["obstructions"],
                "analysis": data["geometry"]["analysis"]}
    script = tmp_path_factory.mktemp("decisions") / "decisions.py"
    script.write_text(SCRIPT.format(repo=str(REPO), name="captured", parts=diagrams["parts"],
                                    diagrams=json.loads(json.dumps(diagrams))))
    return freecad_result(subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=300))


def test_a_one_component_proposal_accepted_is_a_group_and_undone(decided):
    assert "no contacts and obstructions yet" in decided["not_detected"]
    assert decided["report"] == [["component", ["cover", "knob"], "cover+knob", None]]
    kind, text = decided["plan_before"]
    assert kind == "InterlockedPartsError" and "cover and knob" in text
    assert "decision 'later' not one of accepted, rejected" in decided["bad_decision"]
    accepted = decided["accepted"]
    assert accepted["undo"] == [1, "APLAN: accept interlock cover and knob"]
    assert accepted["groups"] == {"cover+knob": ["cover", "knob"]}
    assert accepted["parts"] == ["housing", "cover+knob"] and accepted["contacts"] == [["housing", "cover+knob"]]
    assert accepted["objects"] == {"housing": ["housing"], "cover+knob": ["cover", "knob"]}
    assert [(d["parts"], d["decision"]) for d in accepted["decisions"]] == [(["cover", "knob"], "accepted")]
    assert accepted["plan"] == ["planned", 1] and accepted["report"] == ["accepted"]
    assert accepted["again"] == [] and accepted["same"] is True  # an accepted one stays; the shapes untouched
    assert decided["lines"] == ["interlock accepted: " + decided["lines"][0].split("accepted: ")[1]]
    undone = decided["undone"]
    assert undone == {"groups": {}, "parts": ["housing", "cover", "knob"], "decisions": [],
                      "plan": undone["plan"]} and undone["plan"][0] == "InterlockedPartsError"


def test_a_rejected_proposal_is_refused_when_planning(decided):
    rejected = decided["rejected"]
    assert rejected["groups"] == {} and rejected["same"] is True
    assert [(d["parts"], d["rule"], d["decision"]) for d in rejected["decisions"]] == [
        (["cover", "knob"], "component", "rejected")]
    kind, text = rejected["plan"]
    assert kind == "InterlockRefusedError" and "refused by the designer" in text
    assert "the rules would resolve them so: cover and knob: one component cover+knob" in text
    # Every export writes it into the product (geometry.designer): `aplan` refuses the pair as well.
    assert [r["parts"] for r in rejected["record"]["refused_interlocks"]] == [["cover", "knob"]]
