"""Detect with the occt engine in the real FreeCAD window (under Xvfb, a background job): the document of
tests/workbench/test_workbench_occt.py (a B-spline cylinder touching a box, OcctPrismTriangles = 1, so OCCT
leaves the pair undecided by a bound on work), detected through the GUI command, its task panel (the engine
chosen there; time limits that are not a finite number of seconds above 0 refused in red, then 120 s) and its
background jobs; the pair and the answer used for it are told in the report view and shown in the Diagrams
panel."""
from __future__ import annotations

import pytest
from background import Job, folder
from conftest import REPO, freecad_gui_result, freecad_gui_run, require_freecad_gui
from integration.freecad_tools import GUI_HELPERS, WORKBENCH_HELPERS
from pictures import hue_of, read_picture

from planner.defaults import OCCT_TIME_LIMIT

ARTIFACTS = REPO / "tests" / "artifacts"
ERROR_COLOUR = "#b00020"  # freecad_aplan.gui.session_habits.ERROR_COLOUR (that module needs FreeCAD's Qt)

GUI_SCRIPT = r"""
import json, os, traceback
from PySide import QtCore, QtGui
import FreeCAD, FreeCADGui, Part

OUT, COPY, ARTIFACTS = {out!r}, {copy!r}, {artifacts!r}
result = {{}}


{gui_helpers}


{workbench_helpers}


def start():
    FreeCADGui.activateWorkbench("AplanWorkbench")
    V = FreeCAD.Vector
    doc = FreeCAD.newDocument("touching")
    doc.addObject("Part::Feature", "Cylinder").Shape = Part.makeCylinder(5, 10, V(0, 0, -5)).toNurbs()
    doc.addObject("Part::Feature", "Block").Shape = Part.makeBox(10, 10, 10, V(5, -5, -5))
    doc.recompute()
    doc.saveAs(COPY)
    FreeCADGui.runCommand("Aplan_CreateAnalysis")
    from freecad_aplan.intent import find_analysis, update_intent
    update_intent(find_analysis(doc), "one triangle per sweep", occt_prism_triangles=1)
    # Detect's task panel: the engine chosen there, and the exact engine's time limit; bad limits refused.
    FreeCADGui.runCommand("Aplan_Detect")
    form = FreeCADGui.getMainWindow().findChild(QtGui.QWidget, "AplanDetectPanel")
    engine = form.findChild(QtGui.QComboBox, "AplanDetectEngine")
    field = form.findChild(QtGui.QLineEdit, "AplanDetectTimeLimit")
    message = form.findChild(QtGui.QLabel, "AplanDetectMessage")
    result["shown"] = [engine.currentText(), field.text(), message.isVisible()]
    QtGui.QApplication.processEvents()
    form.grab().save(os.path.join(ARTIFACTS, "gui_detect_panel.png"))
    engine.setCurrentIndex(engine.findText("occt"))
    result["refused"] = []
    for text in ("0", "-3", "nan", "inf"):
        field.setText(text)
        accepted = state().panel.accept()
        QtGui.QApplication.processEvents()
        result["refused"].append([text, accepted, message.text(), message.isVisible(), len(state().jobs),
                                  FreeCADGui.Control.activeDialog(), find_analysis(doc).OcctTimeLimit])
    form.grab().save(os.path.join(ARTIFACTS, "gui_detect_refused.png"))
    field.setText("120")
    result["accepted"] = state().panel.accept()
    result["closed"] = not FreeCADGui.Control.activeDialog()
    after_jobs(detected)


def detected():
    from freecad_aplan.intent import find_analysis, read_intent
    analysis = find_analysis(FreeCAD.ActiveDocument)
    intent = read_intent(analysis)
    result["stored"] = [intent.engine, intent.occt_time_limit]
    result["fallbacks"] = intent.diagrams["analysis"]["tolerances"]["pairs"]["fallbacks"]
    result["time_limit"] = intent.diagrams["analysis"]["tolerances"]["pairs"]["time_limit"]
    result["report_view"] = FreeCADGui.getMainWindow().findChild(QtGui.QDockWidget, "Report view").widget(
        ).toPlainText()
    FreeCADGui.runCommand("Aplan_Diagrams")
    form = FreeCADGui.getMainWindow().findChild(QtGui.QWidget, "AplanDiagramsPanel")
    label = form.findChild(QtGui.QLabel, "AplanUndecidedPairs") if form is not None else None
    result["panel"] = None if label is None else label.text()
    finish(0)


FreeCADGui.getMainWindow().showMaximized()
QtCore.QTimer.singleShot(1500, guarded(start))
"""


def _in_the_window():
    """The script in the FreeCAD window (a background job): its folder and FreeCAD's run."""
    tmp = folder("gui-occt")
    ARTIFACTS.mkdir(exist_ok=True)
    script = tmp / "gui_occt.py"
    script.write_text(GUI_SCRIPT.format(gui_helpers=GUI_HELPERS, workbench_helpers=WORKBENCH_HELPERS,
                                        out=str(tmp / "result.json"), copy=str(tmp / "touching.FCStd"),
                                        artifacts=str(ARTIFACTS)))
    return tmp, freecad_gui_run(tmp, script, display=196)


BACKGROUND = (Job("Detect with the occt engine in the FreeCAD window", _in_the_window),)
ERROR_PIXELS = 0.02  # measured: 5.0 % of the panel's pixels are the message's red
TOLD = "OCCT left 'Cylinder' and 'Block' undecided (Cylinder moving along +X): the mesh engine's answer stands"


@pytest.mark.freecad
def test_detect_tells_the_undecided_pair_and_its_answer():
    require_freecad_gui()
    tmp, done = BACKGROUND[0].result()
    data = freecad_gui_result(done, tmp / "result.json")
    # Detect's task panel: the analysis' engine and the command line's default time limit, no message yet.
    assert data["shown"] == ["mesh", f"{OCCT_TIME_LIMIT:g}", False]
    # A limit that is not a finite number of seconds above 0: said in the panel, which stays open; nothing runs
    # and nothing is stored.
    for text, accepted, message, visible, jobs, dialog, stored in data["refused"]:
        assert (accepted, visible, jobs, dialog, stored) == (False, True, 0, True, OCCT_TIME_LIMIT), text
        assert message.startswith("Time limit: must be a number of seconds above 0"), message
        assert message.endswith(f"got {text}; give the CPU seconds OCCT may spend on all its pairs (default "
                                f"{OCCT_TIME_LIMIT:g}); nothing was detected"), message
    # What a person sees: the refusal in red under the fields (ERROR_PIXELS), no red before.
    red = hue_of(tuple(int(ERROR_COLOUR[k:k + 2], 16) / 255 for k in (1, 3, 5)))
    before, refused = (read_picture(ARTIFACTS / f"gui_detect_{name}.png") for name in ("panel", "refused"))
    assert before.share(before.coloured(red, saturation=0.4)) == 0
    assert refused.share(refused.coloured(red, saturation=0.4)) >= ERROR_PIXELS
    # OK with 120 s: stored with the engine, and the exact engine ran with it (its record), the panel closed.
    assert data["accepted"] is True and data["closed"] is True
    assert data["stored"] == ["occt", 120.0] and data["time_limit"] == 120.0
    assert [f["answer"] for f in data["fallbacks"]] == ["mesh"]
    assert f"warning: {TOLD}" in data["report_view"]
    assert "1 pairs undecided by OCCT" in data["report_view"]
    assert data["panel"] == TOLD
