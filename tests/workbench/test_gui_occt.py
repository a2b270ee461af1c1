"""Detect with Engine = occt in the real FreeCAD window (under Xvfb, a background job): the document of
tests/workbench/test_workbench_occt.py (a B-spline cylinder touching a box, OcctPrismTriangles = 1, so OCCT
leaves the pair undecided by a bound on work), detected through the GUI command and its background jobs; the
pair and the answer used for it are told in the report view and shown in the Diagrams panel."""
from __future__ import annotations

import pytest
from background import Job, folder
from conftest import freecad_gui_result, freecad_gui_run, require_freecad_gui
from integration.freecad_tools import GUI_HELPERS, WORKBENCH_HELPERS

GUI_SCRIPT = r"""
import json, os, traceback
from PySide import QtCore, QtGui
import FreeCAD, FreeCADGui, Part

OUT, COPY = {out!r}, {copy!r}
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
    update_intent(find_analysis(doc), "occt engine, one triangle per sweep", engine="occt", occt_prism_triangles=1)
    FreeCADGui.runCommand("Aplan_Detect")
    after_jobs(detected)


def detected():
    from freecad_aplan.intent import find_analysis, read_intent
    analysis = find_analysis(FreeCAD.ActiveDocument)
    result["fallbacks"] = read_intent(analysis).diagrams["analysis"]["tolerances"]["pairs"]["fallbacks"]
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
    script = tmp / "gui_occt.py"
    script.write_text(GUI_SCRIPT.format(gui_helpers=GUI_HELPERS, workbench_helpers=WORKBENCH_HELPERS,
                                        out=str(tmp / "result.json"), copy=str(tmp / "touching.FCStd")))
    return tmp, freecad_gui_run(tmp, script, display=196)


BACKGROUND = (Job("Detect with the occt engine in the FreeCAD window", _in_the_window),)
TOLD = "OCCT left 'Cylinder' and 'Block' undecided (Cylinder moving along +X): the mesh engine's answer stands"


@pytest.mark.freecad
def test_detect_tells_the_undecided_pair_and_its_answer():
    require_freecad_gui()
    tmp, done = BACKGROUND[0].result()
    data = freecad_gui_result(done, tmp / "result.json")
    assert [f["answer"] for f in data["fallbacks"]] == ["mesh"]
    assert f"warning: {TOLD}" in data["report_view"]
    assert "1 pairs undecided by OCCT" in data["report_view"]
    assert data["panel"] == TOLD
