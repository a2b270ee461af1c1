"""The workbench's commands without the GUI (freecad_aplan.workflow) in FreeCADCmd, on a copy of the pen:
detection through the background job, plan, bundle, POMDPX/.pomdp, solve through the background job,
simulation with its belief plot."""
from __future__ import annotations

import json

import pytest
from conftest import PEN_MODELS, REPO, require_freecadcmd, require_shared
from integration.freecad_tools import LIAISONS, aplan, freecad_result, freecadcmd_job
from pictures import assert_belief_plot

from planner import load_product, make_plan, plan_statistics
from planner.api import load_model

PEN = PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"

SCRIPT = """
import json, os, subprocess, sys
sys.path.insert(0, {repo!r})
import FreeCAD
from freecad_aplan import workflow
from freecad_aplan.intent import IntentError, create_analysis, update_intent
TMP = {tmp!r}
out = {{}}
doc = FreeCAD.openDocument(os.path.join(TMP, "pen.FCStd"))
try:
    workflow.require_analysis(doc)
except IntentError as exc:
    out["no_analysis"] = str(exc)
analysis = create_analysis(doc)
try:
    workflow.analysis_product(analysis)
except IntentError as exc:
    out["not_detected"] = str(exc)

def job(action, arguments, engine=None):
    command = workflow.worker_command(action, engine)
    done = subprocess.run(command, capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, APLAN_BATCH=json.dumps({{"action": action, **arguments}})))
    line = [l for l in done.stdout.splitlines() if l.startswith(("APLAN-RESULT", "APLAN-ERROR"))][-1]
    return command, line

folder = os.path.join(TMP, "detect")
os.mkdir(folder)
exported = workflow.export_for_detection(doc, folder)
out["objects"] = exported["x-freecad-objects"]
out["mesh_job"], line = job("analyze", {{"folder": folder, "engine": "mesh"}}, "mesh")
out["mesh_result"] = json.loads(line.split(" ", 1)[1])
workflow.store_detection(analysis, folder)
product = workflow.analysis_product(analysis)
_, stats, images = workflow.plan_report(product, TMP)
out["stats"] = stats.as_dict()
out["images"] = images
workflow.export_analysis_bundle(doc, analysis, os.path.join(TMP, "bundle"))
out["pomdpx"] = workflow.export_decision_model(product, os.path.join(TMP, "pen.pomdpx"))
workflow.export_decision_model(product, os.path.join(TMP, "pen.pomdp"))
from planner.product import save_product
save_product(product, os.path.join(TMP, "product.json"))
out["solve_job"], line = job("solve", {{"product": os.path.join(TMP, "product.json"),
                                        "output": os.path.join(TMP, "pen.policy"), "time_limit": 3}})
out["solve"] = json.loads(line.split(" ", 1)[1])
out["simulate"] = workflow.simulate_sequence(product, os.path.join(TMP, "pen.policy"), os.path.join(TMP, "belief"))
_, out["bad_job"] = job("analyze", {{"folder": os.path.join(TMP, "missing"), "engine": "occt"}}, "occt")
# Without a Python for the mesh engine: FreeCADCmd when FreeCAD's Python has trimesh, else a clear error.
import importlib.util
workflow._mesh_python = lambda: None
out["freecad_has_mesh"] = all(importlib.util.find_spec(m) for m in ("trimesh", "manifold3d"))
try:
    out["no_mesh"] = workflow.worker_command("analyze", "mesh")
except Exception as exc:
    out["no_mesh"] = str(exc)
print("APLAN-RESULT " + json.dumps(out))
"""


@pytest.mark.freecad
def test_workbench_workflow_without_gui():
    require_freecadcmd()
    require_shared(PEN)
    tmp, done = BACKGROUND[0].result()
    data = freecad_result(done)
    assert "no APLAN analysis; create one first" in data["no_analysis"]
    assert "run APLAN > Detect contacts and obstructions first" in data["not_detected"]
    assert data["objects"]["ink_001"] == ["b_ink_001_"]
    assert data["mesh_job"][0].endswith("python") and data["mesh_result"]["contacts"] == 5
    assert data["solve_job"][0].endswith("freecadcmd")
    # The plan from the stored diagrams equals the plan of the bundle it writes, read by the planner.
    bundle = load_product(tmp / "bundle" / "product.json")
    assert {frozenset(c) for c in bundle.contacts} == LIAISONS
    assert bundle.geometry["analysis"]["diagrams"] == "stored in the document"
    assert data["stats"] == plan_statistics(make_plan(bundle)).as_dict()
    assert data["stats"]["intentions"] == 69
    assert sorted(data["images"]) == ["andor", "intentions", "states"]
    # Decision model files: 69 intentions (states), 22 actions (README), both formats read back the same.
    assert (data["pomdpx"]["states"], data["pomdpx"]["actions"]) == (69, 22)
    first, second = load_model(tmp / "pen.pomdpx"), load_model(tmp / "pen.pomdp")
    assert (first.n_states, first.n_actions) == (second.n_states, second.n_actions) == (69, 22)
    assert data["solve"]["lower_bound"] <= data["solve"]["upper_bound"]
    assert (tmp / "pen.policy").is_file()
    simulate = data["simulate"]
    assert simulate["steps"] and all(p.endswith((".png", ".svg")) for p in simulate["plots"])
    assert_belief_plot(tmp / "belief.png")
    assert data["bad_job"].startswith("APLAN-ERROR ") and "Traceback" not in data["bad_job"]
    if data["freecad_has_mesh"]:
        assert data["no_mesh"][0].endswith("freecadcmd")
    else:
        assert "the mesh engine needs the Python packages trimesh and manifold3d" in data["no_mesh"]


EDIT = """
import json, os, subprocess, sys
sys.path.insert(0, {repo!r})
import FreeCAD
from freecad_aplan import workflow
from freecad_aplan.diagrams import RelationError
from freecad_aplan.intent import create_analysis, find_analysis, read_intent
TMP = {tmp!r}
out = {{}}
doc = FreeCAD.openDocument(os.path.join(TMP, "pen.FCStd"))
doc.UndoMode = 1
analysis = create_analysis(doc)
folder = os.path.join(TMP, "detect")
os.mkdir(folder)
workflow.export_for_detection(doc, folder)
done = subprocess.run(workflow.worker_command("analyze", "mesh"), capture_output=True, text=True, timeout=300,
                      env=dict(os.environ, APLAN_BATCH=json.dumps({{"action": "analyze", "folder": folder}})))
assert "APLAN-RESULT" in done.stdout, done.stdout + done.stderr
workflow.store_detection(analysis, folder)
out["detected"] = read_intent(analysis).diagrams
# Bad additions (the panel's Add and OK go through the same function): a message, no change, no undo step.
steps, stored = len(doc.UndoNames), analysis.Diagrams
out["bad"] = {{}}
for name, relation in {bad!r}.items():
    try:
        workflow.edit_analysis_diagrams(analysis, add=[relation])
    except RelationError as exc:
        out["bad"][name] = str(exc)
out["bad_unchanged"] = (len(doc.UndoNames), analysis.Diagrams == stored) == (steps, True)
# A good addition is one undoable step.
workflow.edit_analysis_diagrams(analysis, add=[{added!r}])
out["added"] = read_intent(analysis).diagrams
out["undo_name"] = doc.UndoNames[0]
doc.undo()
out["after_undo"] = read_intent(analysis).diagrams
# The edit batch mode must see: remove one relation, save.
workflow.edit_analysis_diagrams(analysis, remove=[{removed!r}])
doc.save()
print("APLAN-RESULT " + json.dumps(out))
"""
# head_001, moved along +X, hits body_001: without this relation the head leaves the body along +X, which
# changes the plan (more feasible subassemblies), so the statistics show whether the edit arrived.
REMOVED = ("blocks +X", "head_001", "body_001")
ADDED = ("blocks -Z", "button_001", "cap_001")  # stored as cap_001 blocked by button_001 along +Z
BAD = {"unknown": ("contact", "ink_01", "body_001"), "self": ("contact", "ink_001", "ink_001"),
       "duplicate": ("contact", "cartridge_001", "ink_001"), "reverse": ("blocks -X", "body_001", "head_001")}


#: The FreeCADCmd runs the tests read, done in the background (tests/background.py).
BACKGROUND = (freecadcmd_job("workflow", lambda tmp: SCRIPT.format(repo=str(REPO), tmp=str(tmp)), {"pen.FCStd": PEN}),
              freecadcmd_job("edit", lambda tmp: EDIT.format(repo=str(REPO), tmp=str(tmp), bad=BAD, added=ADDED,
                                                             removed=REMOVED), {"pen.FCStd": PEN}))


@pytest.mark.freecad
def test_edited_diagrams_reach_batch_export(tmp_path):
    """Detect, add (validated, undone) and remove relations in the document; `aplan export-freecad` uses the
    edited diagrams and says so, `aplan stats` plans with them, `--redetect` brings the engine's back, and
    diagrams that no longer fit the components are detected again with a warning."""
    from freecad_aplan.diagrams import edited_diagrams
    from planner.product import product_from_dict, product_to_dict

    require_freecadcmd()
    require_shared(PEN)
    tmp, done = BACKGROUND[1].result()
    data = freecad_result(done)
    detected = data["detected"]
    assert {frozenset(c) for c in detected["contacts"]} == LIAISONS
    bad = data["bad"]
    assert "'ink_01' is not a component (did you mean 'ink_001'?)" in bad["unknown"]
    assert "a component cannot be related to itself" in bad["self"]
    assert "cannot add contact cartridge_001 - ink_001: the diagrams already hold it" in bad["duplicate"]
    assert "already hold it (as head_001 blocked by body_001 along +X)" in bad["reverse"]
    assert data["bad_unchanged"] is True
    plus_z = lambda d: [o["blocks"] for o in d["obstructions"] if o["direction"] == "+Z"][0]  # noqa: E731
    assert ["cap_001", "button_001"] not in plus_z(detected)
    assert plus_z(data["added"]) == plus_z(detected) + [["cap_001", "button_001"]]
    assert data["added"]["edits"] == [{"added": list(ADDED)}]
    assert data["undo_name"] == "APLAN: add button_001 blocked by cap_001 along -Z"
    assert data["after_undo"] == detected

    model = str(tmp / "pen.FCStd")  # edited and saved by the script
    done = aplan("export-freecad", model, "-o", str(tmp_path / "stored"))
    assert "(diagrams: stored in the document, edited)" in done.stdout
    stored = load_product(tmp_path / "stored" / "product.json")
    assert [list(b) for o in stored.obstructions if o.direction.name == "+X" for b in o.blocks
            if b == REMOVED[1:]] == []
    assert stored.geometry["analysis"]["diagrams"] == "stored in the document, edited"
    assert stored.geometry["analysis"]["edits"] == [{"removed": list(REMOVED)}]
    # An engine named on the command line does not silently replace the designer's diagrams.
    done = aplan("export-freecad", model, "-o", str(tmp_path / "named"), "--engine", "occt")
    assert "(diagrams: stored in the document, edited)" in done.stdout
    assert "warning: --engine and the tolerances were not applied" in done.stdout and "--redetect" in done.stdout
    aplan("export-freecad", model, "-o", str(tmp_path / "again"), "--redetect")
    again = load_product(tmp_path / "again" / "product.json")
    assert again.geometry["analysis"]["diagrams"] == "engine"
    assert REMOVED[1:] in [o.blocks for o in again.obstructions if o.direction.name == "+X"][0]
    # The expected statistics: the planner on the engine's product with the relation removed.
    engine = product_to_dict(again)
    edited = edited_diagrams({"parts": list(again.part_ids), "contacts": engine["contacts"],
                              "obstructions": engine["obstructions"]}, remove=[REMOVED])
    expected = plan_statistics(make_plan(product_from_dict(
        {**engine, "contacts": edited["contacts"], "obstructions": edited["obstructions"]}))).as_dict()
    shown = json.loads(aplan("stats", str(tmp_path / "stored"), "--json").stdout)
    assert shown == expected
    assert json.loads(aplan("stats", str(tmp_path / "again"), "--json").stdout) != expected
    # Components that differ from those of the detection: detected again, and the warning says why.
    done = aplan("export-freecad", model, "-o", str(tmp_path / "fewer"), "--exclude", "button_001")
    assert "(diagrams: engine)" in done.stdout
    assert ("warning: the diagrams stored in 'APLAN analysis' were not used: they cover the components "
            "['body_001', 'button_001', 'cap_001', 'cartridge_001', 'head_001', 'ink_001'], this export has "
            "['body_001', 'cap_001', 'cartridge_001', 'head_001', 'ink_001'] (without button_001)") in done.stdout
