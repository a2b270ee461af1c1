"""The designer's directions and not-blocking marks in the diagrams panel, in the real FreeCAD window (under
Xvfb): a block with a peg in a slot inclined by 30 degrees is detected, the panel adds the slot's direction and
marks a relation not blocking (one undo step each), and a second detection keeps both. Screenshot:
tests/artifacts/gui_designer_directions.png. The window runs as a background job (tests/background.py)."""
from __future__ import annotations

import pytest
from background import Job, folder
from conftest import REPO, freecad_gui_result, freecad_gui_run, require_freecad_gui
from integration.freecad_tools import GUI_HELPERS, WORKBENCH_HELPERS
from pictures import read_picture

ARTIFACTS = REPO / "tests" / "artifacts"

GUI_SCRIPT = r"""
import json, os, traceback
from PySide import QtCore, QtGui
import FreeCAD, FreeCADGui, Part

OUT, COPY, ARTIFACTS = {out!r}, {copy!r}, {artifacts!r}
result = {{}}


{gui_helpers}


{workbench_helpers}


def turned(x, y, z):
    box = Part.makeBox(x, y, z, FreeCAD.Vector(-x / 2, -y / 2, -z / 2))
    turn = FreeCAD.Placement(FreeCAD.Vector(0, 0, 0), FreeCAD.Rotation(FreeCAD.Vector(1, 0, 0), 30))
    return box.transformGeometry(turn.toMatrix())


def start():
    FreeCADGui.activateWorkbench("AplanWorkbench")
    doc = FreeCAD.newDocument("wedge")
    block = doc.addObject("Part::Feature", "Block")
    block.Shape = Part.makeBox(30, 30, 30, FreeCAD.Vector(-15, -15, -15)).cut(turned(10, 10, 80))
    block.Label = "block"
    peg = doc.addObject("Part::Feature", "Peg")
    peg.Shape = turned(10, 10, 60)
    peg.Label = "peg"
    doc.recompute()
    doc.saveAs(COPY)
    FreeCADGui.SendMsgToActiveView("ViewFit")
    FreeCADGui.activeDocument().activeView().viewIsometric()
    FreeCADGui.runCommand("Aplan_CreateAnalysis")
    detect()
    after_jobs(panel)


def panel():
    from freecad_aplan.intent import find_analysis, read_intent
    doc = FreeCAD.ActiveDocument
    analysis = find_analysis(doc)
    result["detected_rows"] = len(read_intent(analysis).diagrams["obstructions"])
    FreeCADGui.runCommand("Aplan_Diagrams")
    form = FreeCADGui.getMainWindow().findChild(QtGui.QWidget, "AplanDiagramsPanel")
    table = form.findChild(QtGui.QTableWidget, "AplanDiagramsTable")
    field = form.findChild(QtGui.QLineEdit, "AplanDirectionField")
    add = form.findChild(QtGui.QPushButton, "AplanAddDirection")
    mark = form.findChild(QtGui.QPushButton, "AplanMarkNotBlocking")
    marks = form.findChild(QtGui.QListWidget, "AplanNotBlockingList")
    message = form.findChild(QtGui.QLabel, "AplanDiagramsMessage")
    shown = form.findChild(QtGui.QLabel, "AplanDesignerDirections")
    steps = len(doc.UndoNames)
    # A direction: a bad one first (a message, nothing stored), then the slot's, typed in the field.
    field.setText("0, 0, 0")
    add.click()
    result["bad_direction"] = [message.text(), len(doc.UndoNames) - steps]
    field.setText("0, -0.5, 0.8660254")
    add.click()
    result["direction"] = [message.text(), shown.text(), doc.UndoNames[0], len(doc.UndoNames) - steps,
                           read_intent(analysis).directions]
    # Mark: nothing selected, then the first row along +Z.
    mark.click()
    result["nothing_selected"] = message.text()
    rows = [[table.item(r, c).text() for c in range(3)] for r in range(table.rowCount())]
    row = next(r for r, relation in enumerate(rows) if relation[0] == "blocks +Z")
    result["marked_relation"] = rows[row]
    table.selectRow(row)
    mark.click()
    result["mark"] = [message.text(), table.rowCount() - len(rows), marks.count(), doc.UndoNames[0],
                      len(doc.UndoNames) - steps]
    window = FreeCADGui.getMainWindow()
    dock = window.findChild(QtGui.QDockWidget, "Combo View")
    if dock is not None:  # wide enough to show the panel's rows and its designer fields
        window.resizeDocks([dock], [620], QtCore.Qt.Horizontal)
    QtGui.QApplication.processEvents()
    scroll = form.parentWidget()
    while scroll is not None and not isinstance(scroll, QtGui.QScrollArea):
        scroll = scroll.parentWidget()
    if scroll is not None:  # the marks and the direction field, at the bottom of the panel
        scroll.ensureWidgetVisible(shown)
    QtGui.QApplication.processEvents()
    screen = QtGui.QApplication.primaryScreen().grabWindow(0)
    screen.save(os.path.join(ARTIFACTS, "gui_designer_directions.png"))
    doc.undo()
    result["undo"] = [read_intent(analysis).not_blocking, read_intent(analysis).directions != []]
    doc.redo()
    result["redo"] = read_intent(analysis).not_blocking
    state().panel.accept()
    detect()
    after_jobs(redetected)


def redetected():
    from freecad_aplan.diagrams import relation_rows
    from freecad_aplan.intent import find_analysis, read_intent
    analysis = find_analysis(FreeCAD.ActiveDocument)
    intent = read_intent(analysis)
    result["after"] = {{"rows": [list(r) for r in relation_rows(intent.diagrams)], "marks": intent.not_blocking,
                       "released": intent.diagrams["analysis"]["designer"]["released"],
                       "directions": [o["direction"] for o in intent.diagrams["obstructions"]]}}
    finish(0)


FreeCADGui.getMainWindow().showMaximized()
QtCore.QTimer.singleShot(1500, guarded(start))
"""


def _in_the_window():
    """The script in the FreeCAD window (a background job): its folder and FreeCAD's run."""
    tmp = folder("gui-designer")
    ARTIFACTS.mkdir(exist_ok=True)
    script = tmp / "gui_designer.py"
    script.write_text(GUI_SCRIPT.format(gui_helpers=GUI_HELPERS, workbench_helpers=WORKBENCH_HELPERS,
                                        out=str(tmp / "result.json"), copy=str(tmp / "wedge.FCStd"),
                                        artifacts=str(ARTIFACTS)))
    return tmp, freecad_gui_run(tmp, script, display=190)


#: The window's run, done in the background (tests/background.py).
BACKGROUND = (Job("the designer's directions in the FreeCAD window", _in_the_window),)


@pytest.mark.freecad
def test_diagrams_panel_adds_a_direction_and_marks_a_relation():
    require_freecad_gui()
    tmp, done = BACKGROUND[0].result()
    data = freecad_gui_result(done, tmp / "result.json")
    assert "zero vector" in data["bad_direction"][0] and data["bad_direction"][1] == 0
    text, shown, step, steps, directions = data["direction"]
    assert text == "added direction 0, -0.5, 0.8660254 (stored; detect again to test it)"
    assert "0, -0.5, 0.866025" in shown and step == "APLAN: add direction 0, -0.5, 0.866025" and steps == 1
    assert directions[0] == pytest.approx([0, -0.5, 0.8660254], abs=1e-6)
    assert data["nothing_selected"] == "select the obstructions to mark not blocking first"
    kind, blocked, blocking = data["marked_relation"]
    message, rows, marks, step, steps = data["mark"]
    assert message.startswith(f"marked {blocked} blocked by {blocking} along +Z not blocking (stored")
    assert (rows, marks, steps) == (-1, 1, 2)
    assert step == f"APLAN: mark {blocked} blocked by {blocking} along +Z not blocking"
    assert data["undo"] == [[], True]
    mark = {"blocked": blocked, "blocking": blocking, "direction": "+Z", "source": "designer"}
    assert data["redo"] == [mark]
    # Detected again: the mark holds (the relation is detected, then released), the direction is tested.
    after = data["after"]
    assert after["marks"] == [mark] and after["released"] == [[blocked, blocking, "+Z"]]
    assert [kind, blocked, blocking] not in after["rows"]
    assert any(isinstance(d, list) and d == pytest.approx([0, -0.5, 0.8660254], abs=1e-6) for d in after["directions"])
    screen = read_picture(ARTIFACTS / "gui_designer_directions.png")  # measured: 1.7 % dark (text), 468 colours
    assert screen.size == (1280, 800) and screen.share(screen.dark()) >= 0.008 and screen.colours() >= 200
