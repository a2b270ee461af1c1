"""The support contacts of a workstation, decided on in the interlocks panel's logic (freecad_aplan.interlocks),
on the machine of tests/assembly/test_level_supports.py (a closed gearbox on a base plate with 20 brackets: too
large for the support-contact rule to judge flat). In real FreeCAD without the GUI: the detection's record (the
rule's candidates) stored in an analysis whose subassembly tree makes the gearbox one workstation; the report
lists the two gears resting in the housing at that level, not decided; the plan of that level adds them, as the
command line does. Accepting both adds them to the stored diagrams in one undo step (the objects' shapes
untouched) and the report keeps them as accepted; undo takes it back. Rejecting one leaves its candidate out of
the product the planner sees: the other alone does not free the level, so none is added and the level's plan
names the gear that would float; the report keeps the rejection."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO, require_freecadcmd
from integration.freecad_tools import freecad_result

from planner import api
from planner.assembly.subassembly_proposals import with_subassemblies
from planner.product import product_to_dict

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "assembly"))
from test_floating_parts import box_meshes  # noqa: E402
from test_interlock_decisions import PREAMBLE  # noqa: E402
from test_level_supports import GEARBOX, machine, machine_boxes  # noqa: E402

#: FreeCAD-side helper (no format fields; the GUI test's script inserts it too): the workstation that holds
#: ``housing`` as the planner plans the analysis (its level's support contacts judged), with the contacts added.
LEVEL_PLAN = r"""
def level_plan(analysis, housing):
    from freecad_aplan.analysis import analysis_product
    from planner import api
    from planner.assembly.hierarchy import product_levels
    from planner.assembly.subassembly_proposals import with_subassemblies
    try:
        product = with_subassemblies(analysis_product(analysis))
        level = next(lv for lv in product_levels(product) if housing in lv.members)
        added = [r["parts"] for r in product.geometry.get("analysis", {}).get("support_contacts", [])]
        return ["planned", api.plan_statistics_of(level.product)[1].sequences, added]
    except Exception as exc:
        return [type(exc).__name__, str(exc)]
"""

SCRIPT = PREAMBLE + r"""
{level_plan}
update_intent(analysis, "detect", diagrams={diagrams!r})
update_intent(analysis, "structure", subassemblies={tree!r})
def contacts():
    return sorted(sorted(c) for c in read_intent(analysis).diagrams["contacts"])
def report():
    return [[p["rule"], p["parts"], p.get("level"), p["decision"]] for p in interlock_report(analysis)[0]]
def gearbox_plan():
    return level_plan(analysis, "housing")
out["report"], out["plan_before"], out["contacts_before"] = report(), gearbox_plan(), contacts()
out["texts"] = [p["text"] for p in interlock_report(analysis)[0]]
undo = len(doc.UndoNames)
out["lines"] = decide_interlocks(analysis, {{0: "accepted", 1: "accepted"}})
out["accepted"] = {{"undo": [len(doc.UndoNames) - undo, doc.UndoNames[0]], "contacts": contacts(),
                   "plan": gearbox_plan(), "report": report(), "same": shapes() == before}}
doc.undo()
out["undone"] = {{"contacts": contacts(), "decisions": read_intent(analysis).interlocks, "report": report()}}
out["rejected_lines"] = decide_interlocks(analysis, {{0: "rejected"}})
out["rejected"] = {{"decisions": [[d["parts"], d["rule"], d.get("level"), d["decision"]]
                                 for d in read_intent(analysis).interlocks],
                   "contacts": contacts(), "plan": gearbox_plan(), "report": report(), "same": shapes() == before}}
print("APLAN-RESULT " + json.dumps(out), flush=True)
"""


@pytest.fixture(scope="module")
def decided(tmp_path_factory) -> dict:
    freecadcmd = require_freecadcmd()
    data = product_to_dict(api.record_detection_proposals(machine(), box_meshes(machine_boxes())))
    diagrams = {"parts": [p["id"] for p in data["parts"]], "objects": {p["id"]: [p["id"]] for p in data["parts"]},
                "contacts": data["contacts"], "obstructions": data["obstructions"],
                "analysis": data["geometry"]["analysis"]}
    tree = [{"id": s.id, "parts": list(s.parts)} for s in with_subassemblies(machine(), "auto").subassemblies]
    script = tmp_path_factory.mktemp("level_supports") / "level_supports.py"
    script.write_text(SCRIPT.format(repo=str(REPO), name="machine", parts=diagrams["parts"], level_plan=LEVEL_PLAN,
                                    diagrams=json.loads(json.dumps(diagrams)), tree=tree))
    return freecad_result(subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=300))


def _level(tree_owner: str = "housing") -> str:
    """The id of the subassembly that holds the gearbox (the auto proposals' tree of the machine)."""
    return next(s.id for s in with_subassemblies(machine(), "auto").subassemblies if tree_owner in s.parts)


def test_the_report_lists_the_gears_at_the_gearbox_level_and_planning_adds_them(decided):
    level = _level()
    assert set(next(s.parts for s in with_subassemblies(machine(), "auto").subassemblies if s.id == level)) \
        == set(GEARBOX)
    assert decided["report"] == [["support", ["gear_a", "housing"], level, None],
                                 ["support", ["gear_b", "housing"], level, None]]
    assert decided["texts"][0].startswith(f"level {level}: gear_a rests in housing")
    kind, sequences, added = decided["plan_before"]  # not decided: planning adds them, as aplan does
    assert kind == "planned" and sequences > 0 and added == [["gear_a", "housing"], ["gear_b", "housing"]]


def test_accepted_they_join_the_stored_diagrams_in_one_undo_step(decided):
    level = _level()
    assert [line.split(":")[0] for line in decided["lines"]] == ["support contact accepted"] * 2
    accepted = decided["accepted"]
    assert accepted["undo"] == [1, "APLAN: decide 2 interlocks and support contacts"]
    assert accepted["contacts"] == sorted(decided["contacts_before"] + [["gear_a", "housing"], ["gear_b", "housing"]])
    assert accepted["report"] == [["support", ["gear_a", "housing"], level, "accepted"],
                                  ["support", ["gear_b", "housing"], level, "accepted"]]
    kind, sequences, added = accepted["plan"]
    assert kind == "planned" and sequences == decided["plan_before"][1] and added == []  # in the diagrams now
    assert accepted["same"] is True
    undone = decided["undone"]
    assert undone["contacts"] == decided["contacts_before"] and undone["decisions"] == []
    assert [row[3] for row in undone["report"]] == [None, None]


def test_a_rejected_one_is_left_out_and_the_level_names_the_floating_gear(decided):
    level = _level()
    assert decided["rejected_lines"] == ["support contact rejected: gear_a and housing (support): not added; the plan "
                                         "names the parts that would float"]
    rejected = decided["rejected"]
    assert rejected["decisions"] == [[["gear_a", "housing"], "support", level, "rejected"]]
    assert rejected["contacts"] == decided["contacts_before"] and rejected["same"] is True
    # gear_b alone does not free the level: the rule proposes nothing more there, the rejection is listed
    assert rejected["report"] == [["support", ["gear_a", "housing"], level, "rejected"]]
    kind, text = rejected["plan"]
    assert kind == "NotDisassemblableError" and "gear_a" in text
