"""The support contacts the detection proposes, decided on in the interlocks panel's logic
(freecad_aplan.interlocks), on the closed gearbox whose gears would float in the housing
(tests/assembly/test_floating_parts.py): the detection records what ``--support-contacts add`` would add
without adding it; in real FreeCAD without the GUI, accepting both adds them to the stored diagrams in one
undo step and the plan is made (the objects' shapes untouched), undo takes it back, and a rejection adds
nothing: the plan names the floating gear as with ``--support-contacts keep``, and the planner gets no refusal."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO, require_freecadcmd
from integration.freecad_tools import freecad_result

from planner import api
from planner.assembly.support_contacts import apply_support_proposal, support_contacts
from planner.product import product_to_dict

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "assembly"))
from test_floating_parts import box_meshes, closed_gearbox  # noqa: E402
from test_interlock_decisions import PREAMBLE  # noqa: E402

SCRIPT = PREAMBLE + r"""
update_intent(analysis, "detect", diagrams={diagrams!r})
def contacts():
    return sorted(sorted(c) for c in read_intent(analysis).diagrams["contacts"])
out["report"] = [[p["rule"], p["parts"], p["text"], p["decision"]] for p in interlock_report(analysis)[0]]
out["plan_before"], out["contacts_before"] = plan(), contacts()
undo = len(doc.UndoNames)
out["lines"] = decide_interlocks(analysis, {{0: "accepted", 1: "accepted"}})
out["accepted"] = {{"undo": [len(doc.UndoNames) - undo, doc.UndoNames[0]], "contacts": contacts(), "plan": plan(),
                   "report": [p["decision"] for p in interlock_report(analysis)[0]], "same": shapes() == before,
                   "record": read_intent(analysis).diagrams["analysis"]["support_contacts"]}}
doc.undo()
out["undone"] = {{"contacts": contacts(), "decisions": read_intent(analysis).interlocks, "plan": plan()}}
out["rejected_lines"] = decide_interlocks(analysis, {{0: "rejected"}})
intent = read_intent(analysis)
out["rejected"] = {{"decisions": [[d["parts"], d["rule"], d["decision"]] for d in intent.interlocks],
                   "contacts": contacts(), "plan": plan(), "record": designer_record(intent),
                   "report": [p["decision"] for p in interlock_report(analysis)[0]], "same": shapes() == before}}
print("APLAN-RESULT " + json.dumps(out), flush=True)
"""


def test_the_detection_records_the_support_contacts_without_adding_them():
    product = closed_gearbox()
    recorded = api.record_detection_proposals(product, box_meshes())
    assert recorded.contacts == product.contacts and recorded.obstructions == product.obstructions
    proposals = recorded.geometry["analysis"]["support_proposals"]
    supported, added = support_contacts(product, box_meshes())  # what --support-contacts add adds
    assert [p["parts"] for p in proposals] == [[c.part, c.host] for c in added] == [["gear_a", "housing"],
                                                                                     ["gear_b", "housing"]]
    assert [p["text"] for p in proposals] == [c.text for c in added]
    applied = recorded
    for proposal in proposals:
        applied = apply_support_proposal(applied, proposal)
    assert applied.contacts == supported.contacts
    assert applied.geometry["analysis"]["support_contacts"] == supported.geometry["analysis"]["support_contacts"]
    assert api.record_detection_proposals(supported, box_meshes()) == supported  # plans already: nothing proposed


@pytest.fixture(scope="module")
def decided(tmp_path_factory) -> dict:
    freecadcmd = require_freecadcmd()
    data = product_to_dict(api.record_detection_proposals(closed_gearbox(), box_meshes()))
    diagrams = {"parts": [p["id"] for p in data["parts"]], "objects": {p["id"]: [p["id"]] for p in data["parts"]},
                "contacts": data["contacts"], "obstructions": data["obstructions"],
                "analysis": data["geometry"]["analysis"]}
    script = tmp_path_factory.mktemp("supports") / "supports.py"
    script.write_text(SCRIPT.format(repo=str(REPO), name="gearbox", parts=diagrams["parts"], diagrams=json.loads(json.dumps(diagrams))))
    return freecad_result(subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=300))


def test_accepted_support_contacts_join_the_gears_to_the_housing_and_the_gearbox_plans(decided):
    _, added = support_contacts(closed_gearbox(), box_meshes())
    assert decided["report"] == [["support", [c.part, c.host], c.text, None] for c in added]
    kind, text = decided["plan_before"]
    assert kind == "NotDisassemblableError" and "gear_a" in text
    assert decided["lines"] == [f"support contact accepted: {c.text}" for c in added]
    accepted = decided["accepted"]
    assert accepted["undo"] == [1, "APLAN: decide 2 interlocks and support contacts"]
    assert accepted["contacts"] == sorted(decided["contacts_before"] + [["gear_a", "housing"], ["gear_b", "housing"]])
    assert accepted["plan"][0] == "planned" and accepted["plan"][1] > 0
    assert accepted["report"] == ["accepted", "accepted"] and accepted["same"] is True
    assert [r["parts"] for r in accepted["record"]] == [["gear_a", "housing"], ["gear_b", "housing"]]
    undone = decided["undone"]
    assert undone["contacts"] == decided["contacts_before"] and undone["decisions"] == []
    assert undone["plan"][0] == "NotDisassemblableError"


def test_a_rejected_support_contact_is_not_added_and_refuses_nothing(decided):
    assert decided["rejected_lines"] == ["support contact rejected: gear_a and housing (support): not added; the plan "
                                         "names the parts that would float"]
    rejected = decided["rejected"]
    assert rejected["decisions"] == [[["gear_a", "housing"], "support", "rejected"]]
    assert rejected["contacts"] == decided["contacts_before"] and rejected["same"] is True
    assert rejected["report"] == ["rejected", None]
    kind, text = rejected["plan"]
    assert kind == "NotDisassemblableError" and "gear_a" in text  # as --support-contacts keep plans it
    assert "refused_interlocks" not in rejected["record"]
