"""The analysis' base part (paper Sec. V) in real FreeCAD: stored in the document (``BasePart``), checked against
the components, kept on save and reopen, added to an analysis saved before it existed, and passed by the workflow
to the planner (statistics, decision model, solve job, simulation); in the GUI, the task panel's field."""
from __future__ import annotations

import json
import re
import shutil

import pytest
from background import Job, folder
from conftest import (
    PEN_MODELS,
    REPO,
    freecad_gui_result,
    freecad_gui_run,
    require_freecad_gui,
    require_freecadcmd,
    require_shared,
)
from integration.freecad_tools import GUI_HELPERS, freecad_result, freecadcmd_job
from pictures import read_picture

from planner import api, product_to_dict

PEN = PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"
ARTIFACTS = REPO / "tests" / "artifacts"


def _pen_diagrams() -> dict:
    """The embedded pen's diagrams over the document's component ids (ink -> ink_001, ...): the same plan as the
    detection on this document gives (18 subassemblies, 69 intentions; tests/workbench/test_gui.py)."""
    data = product_to_dict(api.resolve_product("pen"))
    text = json.dumps({"parts": [p["id"] for p in data["parts"]], "contacts": data["contacts"],
                       "obstructions": data["obstructions"]})
    for part in data["parts"]:
        text = text.replace(f'"{part["id"]}"', f'"{part["id"]}_001"')
    return json.loads(text)


GRAPH_KEYS = ("parts", "contacts", "subassemblies", "operations", "states", "state_edges", "intentions", "sequences")


def _expected(base_part: str | None) -> dict:
    """The planner's figures of the graphs for the embedded pen with that base part (tested against brute force in
    tests/assembly/test_base_part.py); the embedded pen's tools add observations the diagrams alone do not have."""
    _, stats = api.plan_statistics_of("pen", base_part=base_part)
    return {k: stats.as_dict()[k] for k in GRAPH_KEYS}


def _graph(figures: dict) -> dict:
    return {k: figures[k] for k in GRAPH_KEYS}


HEADLESS = """
import json, os, subprocess, sys
sys.path.insert(0, {repo!r})
import FreeCAD
from dataclasses import asdict
from freecad_aplan import workflow
from freecad_aplan.intent import IntentError, create_analysis, find_analysis, read_intent, update_intent
TMP = {tmp!r}
out = {{}}
doc = FreeCAD.openDocument(os.path.join(TMP, "pen.FCStd"))
doc.UndoMode = 1
analysis = create_analysis(doc)
out["default"] = [analysis.BasePart, workflow.analysis_base_part(analysis)]
update_intent(analysis, "diagrams", diagrams={diagrams!r})
try:
    update_intent(analysis, "bad base part", base_part="lid")
except IntentError as exc:
    out["bad"] = str(exc)
out["bad_unchanged"] = analysis.BasePart
update_intent(analysis, "base part", base_part="body_001")
out["undo_name"] = doc.UndoNames[0]
product = workflow.analysis_product(analysis)
base = workflow.analysis_base_part(analysis)
_, stats, _ = workflow.plan_report(product, base_part=base)
out["stats"] = [stats.as_dict(), stats.base_part]
out["model"] = workflow.export_decision_model(product, os.path.join(TMP, "pen.pomdpx"), base_part=base)
from planner.product import save_product
save_product(product, os.path.join(TMP, "product.json"))
job = {{"action": "solve", "product": os.path.join(TMP, "product.json"), "output": os.path.join(TMP, "pen.policy"),
        "time_limit": 3, "base_part": base}}
done = subprocess.run(workflow.worker_command("solve"), capture_output=True, text=True, timeout=300,
                      env=dict(os.environ, APLAN_BATCH=json.dumps(job)))
out["solve"] = [l for l in done.stdout.splitlines() if l.startswith(("APLAN-RESULT", "APLAN-ERROR"))][-1]
simulated = workflow.simulate_sequence(product, os.path.join(TMP, "pen.policy"), os.path.join(TMP, "belief"),
                                       base_part=base)
from planner import api
model = api.decision_model(product, base_part=base)
out["simulated_first"] = model.describe_operations(simulated["sequence"])[0]
try:  # the policy of the restricted model does not fit the whole one
    workflow.simulate_sequence(product, os.path.join(TMP, "pen.policy"), os.path.join(TMP, "b2"))
except Exception as exc:
    out["mismatch"] = type(exc).__name__
update_intent(analysis, "auto", base_part="auto")
_, stats, _ = workflow.plan_report(product, base_part=workflow.analysis_base_part(analysis))
out["auto"] = [stats.as_dict(), stats.base_part]
written = asdict(read_intent(analysis))
doc.save()
FreeCAD.closeDocument(doc.Name)
doc = FreeCAD.openDocument(os.path.join(TMP, "pen.FCStd"))
analysis = find_analysis(doc)
out["reopened"] = asdict(read_intent(analysis)) == written and analysis.BasePart == "auto"
# An analysis saved before BasePart existed: read as no base part; restored and written with the property.
analysis.removeProperty("BasePart")
out["old_read"] = read_intent(analysis).base_part
doc.saveAs(os.path.join(TMP, "old.FCStd"))
FreeCAD.closeDocument(doc.Name)
doc = FreeCAD.openDocument(os.path.join(TMP, "old.FCStd"))
analysis = find_analysis(doc)
out["old_restored"] = "BasePart" in analysis.PropertiesList and analysis.BasePart == ""
print("APLAN-RESULT " + json.dumps(out))
"""


@pytest.mark.freecad
def test_base_part_in_the_analysis_headless():
    require_freecadcmd()
    require_shared(PEN)
    data = freecad_result(BACKGROUND[0].result()[1])
    assert data["default"] == ["", None]
    assert "BasePart: 'lid' is not a component; use one of ink_001" in data["bad"] and data["bad_unchanged"] == ""
    assert data["undo_name"] == "APLAN: base part"
    body = _expected("body")
    assert [_graph(data["stats"][0]), data["stats"][1]] == [body, "body_001"]
    assert body["sequences"] < 24 and body["intentions"] < 69
    assert [_graph(data["auto"][0]), data["auto"][1]] == [body, "body_001"]  # the body is the most connected part
    assert data["model"]["states"] == body["intentions"]
    assert data["solve"].startswith("APLAN-RESULT "), data["solve"]
    assert "body_001" in re.findall(r"[\w-]+", data["simulated_first"])
    assert data["mismatch"] == "PolicyError"
    assert data["reopened"] and data["old_read"] == "" and data["old_restored"]


GUI = r"""
import json, os, sys, traceback
from PySide import QtCore, QtGui
import FreeCAD, FreeCADGui

OUT, COPY, ARTIFACTS = {out!r}, {copy!r}, {artifacts!r}
result = {{}}


{gui_helpers}


def start():
    FreeCADGui.activateWorkbench("AplanWorkbench")
    from freecad_aplan.intent import create_analysis, read_intent, update_intent
    doc = FreeCAD.openDocument(COPY)
    doc.UndoMode = 1
    analysis = create_analysis(doc)
    update_intent(analysis, "diagrams", diagrams={diagrams!r})
    FreeCADGui.runCommand("Aplan_Intent")
    window = FreeCADGui.getMainWindow()
    field = window.findChild(QtGui.QComboBox, "AplanBasePart")
    result["choices"] = [field.itemText(k) for k in range(field.count())]
    state = FreeCADGui.getWorkbench("AplanWorkbench").state
    field.setEditText("lid")
    result["bad_accepted"] = state.panel.accept()
    result["bad_stored"] = read_intent(analysis).base_part
    field.setEditText("auto")
    QtGui.QApplication.processEvents()
    window.grab().save(os.path.join(ARTIFACTS, "gui_base_part_panel.png"))
    result["accepted"] = state.panel.accept()
    result["stored"] = read_intent(analysis).base_part
    FreeCADGui.runCommand("Aplan_Plan")
    result["plan"] = state.plan["statistics"]
    result["message"] = window.statusBar().currentMessage()
    QtGui.QApplication.processEvents()
    state.plan_dialog.grab().save(os.path.join(ARTIFACTS, "gui_base_part_plan.png"))
    finish(0)


FreeCADGui.getMainWindow().showMaximized()
QtCore.QTimer.singleShot(1500, guarded(start))
"""


def _panel_in_the_window() -> tuple:
    """The GUI script's run on a copy of the pen: (folder, FreeCAD's run); the result in folder/result.json."""
    tmp = folder("gui-base-part")
    copy = tmp / "pen.FCStd"
    shutil.copy(PEN, copy)
    ARTIFACTS.mkdir(exist_ok=True)
    script = tmp / "gui_base_part.py"
    script.write_text(GUI.format(gui_helpers=GUI_HELPERS, out=str(tmp / "result.json"), copy=str(copy),
                                 artifacts=str(ARTIFACTS), diagrams=_pen_diagrams()))
    return tmp, freecad_gui_run(tmp, script, display=150)


#: The FreeCAD runs the tests read, done in the background (tests/background.py).
BACKGROUND = (freecadcmd_job("base_part", lambda tmp: HEADLESS.format(repo=str(REPO), tmp=str(tmp),
                                                                      diagrams=_pen_diagrams()), {"pen.FCStd": PEN}),
              Job("the base part panel in the FreeCAD window", _panel_in_the_window))


@pytest.mark.freecad
def test_base_part_field_in_the_task_panel():
    require_freecad_gui()
    require_shared(PEN)
    tmp, done = BACKGROUND[1].result()
    data = freecad_gui_result(done, tmp / "result.json")
    assert data["choices"][:2] == ["", "auto"] and "body_001" in data["choices"]
    assert data["bad_accepted"] is False and data["bad_stored"] == ""
    assert data["accepted"] is True and data["stored"] == "auto"
    body = _expected("body")
    assert _graph(data["plan"]) == body and data["plan"]["base part"] == "body_001"
    assert f"sequences {body['sequences']}" in data["message"] and "base part body_001" in data["message"]
    screen = read_picture(ARTIFACTS / "gui_base_part_panel.png")  # measured: 0.6 % dark (text), 543 colours
    assert screen.size == (1280, 800) and screen.share(screen.dark()) >= 0.003 and screen.colours() >= 200
