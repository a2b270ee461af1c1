"""The workbench in the real FreeCAD window (under Xvfb): activate APLAN, run its commands on the pen up to
the statistics, take screenshots (tests/artifacts/), and check that the user's parts did not move; open every
task panel and dialog at FreeCAD's default size, save a picture of each (tests/artifacts/gui_panel_*.png) and
check that nothing in them is cut off. The window runs as a background job (tests/background.py)."""
from __future__ import annotations

import json
import shutil

import pytest
from background import Job, folder
from conftest import PEN_MODELS, REPO, freecad_gui_result, freecad_gui_run, require_freecad_gui, require_shared
from integration.freecad_tools import GUI_HELPERS, LAYOUT_CHECK, WORKBENCH_HELPERS, aplan
from pictures import read_picture

ARTIFACTS = REPO / "tests" / "artifacts"

GUI_SCRIPT = r"""
import json, os, sys, traceback
from PySide import QtCore, QtGui
import FreeCAD, FreeCADGui

OUT, COPY, ARTIFACTS = {out!r}, {copy!r}, {artifacts!r}
result = {{"ticks": 0, "cancel_ticks": 0}}


{gui_helpers}

{layout_check}


def status():
    return FreeCADGui.getMainWindow().statusBar().currentMessage()


{workbench_helpers}


def snapshot(doc):
    return {{o.Name: [list(o.Placement.Base), list(o.Placement.Rotation.Q)]
            for o in doc.Objects if o.isDerivedFrom("Part::Feature")}}


def start():
    FreeCADGui.activateWorkbench("AplanWorkbench")
    result["workbench"] = FreeCADGui.activeWorkbench().name()
    from freecad_aplan.gui.commands import COMMANDS
    result["commands"] = {{c.name: sorted(FreeCADGui.Command.get(c.name).getInfo()) != [] for c in COMMANDS}}
    # Bad input first: no document open. The toolbar greys the command out (IsActive); run it anyway, as a
    # macro could.
    from freecad_aplan.gui import commands
    result["active_without_document"] = [c().IsActive() for c in COMMANDS]
    commands.Detect().Activated()
    result["no_document"] = status()
    doc = FreeCAD.openDocument(COPY)
    FreeCADGui.SendMsgToActiveView("ViewFit")
    result["before"] = snapshot(doc)
    count = len(doc.Objects)
    FreeCADGui.Selection.clearSelection()
    result["active_without_analysis"] = [c.name for c in COMMANDS if c().IsActive()]
    commands.Detect().Activated()                    # no analysis yet
    result["no_analysis"] = status()
    result["no_analysis_unchanged"] = len(doc.Objects) == count
    FreeCADGui.runCommand("Aplan_CreateAnalysis")
    FreeCADGui.runCommand("Aplan_ExcludeParts")      # nothing selected
    result["nothing_selected"] = status()
    FreeCADGui.runCommand("Aplan_Plan")              # nothing detected yet
    result["not_detected"] = status()
    detect()                                         # the mesh engine, in a background process
    QtCore.QTimer.singleShot(100, guarded(wait_detection))


def wait_detection():
    if state().jobs:
        result["ticks"] += 1                          # the event loop runs while the engine works
        QtCore.QTimer.singleShot(100, guarded(wait_detection))
        return
    from freecad_aplan.intent import find_analysis, read_intent
    doc = FreeCAD.ActiveDocument
    analysis = find_analysis(doc)
    result["detected"] = status()
    result["diagrams"] = read_intent(analysis).diagrams
    # Cancel a second detection half-way: the stored diagrams stay as they are.
    detect()
    result["cancel_started"] = len(state().jobs)
    QtCore.QTimer.singleShot(300, guarded(lambda: [job.cancel() for job in list(state().jobs)]))
    QtCore.QTimer.singleShot(400, guarded(wait_cancel))


def wait_cancel():
    if state().jobs:
        result["cancel_ticks"] += 1
        QtCore.QTimer.singleShot(100, guarded(wait_cancel))
        return
    from freecad_aplan.intent import find_analysis, read_intent
    doc = FreeCAD.ActiveDocument
    result["cancelled"] = status()
    result["diagrams_after_cancel"] = read_intent(find_analysis(doc)).diagrams == result["diagrams"]
    # The diagrams panel: selecting a relation selects its two parts.
    FreeCADGui.runCommand("Aplan_Diagrams")
    panel = FreeCADGui.getMainWindow().findChild(QtGui.QTableWidget, "AplanDiagramsTable")
    result["diagram_rows"] = panel.rowCount()
    panel.selectRow(0)
    result["row0"] = [panel.item(0, c).text() for c in range(3)]
    result["selected"] = sorted(o.Label for o in FreeCADGui.Selection.getSelection())
    FreeCADGui.Control.closeDialog()
    FreeCADGui.Selection.clearSelection()
    # The README's picture shows the plan's line only: the bad inputs above (red, on purpose) and the sample's
    # A2plus proxies (FreeCAD refuses to import them without A2plus: red, with this script's path) are cleared,
    # and so is the red FreeCAD leaves on the status bar after an error message.
    FreeCADGui.getMainWindow().findChild(QtGui.QDockWidget, "Report view").widget().clear()
    FreeCADGui.getMainWindow().statusBar().setStyleSheet("")
    FreeCADGui.runCommand("Aplan_Plan")
    result["plan"] = state().plan
    dialog = FreeCADGui.getMainWindow().findChild(QtGui.QDialog, "AplanPlanDialog")
    table = dialog.findChild(QtGui.QTableWidget, "AplanStatisticsTable")
    result["shown"] = {{table.item(r, 0).text(): table.item(r, 1).text() for r in range(table.rowCount())}}
    view = FreeCADGui.ActiveDocument.ActiveView
    view.viewIsometric()
    FreeCADGui.SendMsgToActiveView("ViewFit")  # the whole pen
    view.saveImage(os.path.join(ARTIFACTS, "gui_3d_view.png"), 800, 600, "White")
    # For the window's screenshot: the dialog on the right, the fitted pen centred in the 3D view left of it.
    dialog.setGeometry(800, 100, 470, 640)
    QtGui.QApplication.processEvents()
    overhang = dialog.frameGeometry().right() - QtGui.QApplication.primaryScreen().geometry().right()
    if overhang > 0:  # wider than asked (its minimum size): keep its right edge on the screen
        dialog.move(dialog.x() - overhang - 4, dialog.y())
        QtGui.QApplication.processEvents()
    frame_left_of(dialog.frameGeometry().x())
    QtCore.QTimer.singleShot(800, guarded(screenshots))


def frame_left_of(right):
    # Pan (and zoom by 1.25) the fitted camera: the pen's centre in the middle of the 3D view's part left of
    # the screen column `right`.
    from pivy import coin
    view = FreeCADGui.ActiveDocument.ActiveView
    widget = FreeCADGui.getMainWindow().findChild(QtGui.QMdiArea).currentSubWindow().widget()
    left = widget.mapToGlobal(QtCore.QPoint(0, 0)).x()
    width, height = view.getSize()
    camera = view.getCameraNode()
    camera.height.setValue(camera.height.getValue() * 0.8)
    shift = (left + width / 2 - (left + right) / 2) * camera.height.getValue() / height  # pixels to model units
    sideways = camera.orientation.getValue().multVec(coin.SbVec3f(1, 0, 0))
    camera.position.setValue(camera.position.getValue() + sideways * shift)


def settle():
    for _ in range(5):
        QtGui.QApplication.processEvents()


def panels_at_default_width():
    # Every task panel and dialog of the workbench at FreeCAD's default size (the combo view as a fresh FreeCAD
    # shows it): a picture of each (the whole panel at the task view's width) and what is cut off (cut_off).
    from dataclasses import replace
    from planner.api import level_report
    from planner.product import Subassembly
    from freecad_aplan import workflow
    from freecad_aplan.intent import find_analysis
    from freecad_aplan.gui.panels import ImageDialog, PlanDialog
    from freecad_aplan.gui.structure import LevelsDialog
    window = FreeCADGui.getMainWindow()
    combo = window.findChild(QtGui.QDockWidget, "Combo View")
    result["combo_view_width"] = combo.width()
    result["cut_off"], result["task_view_width"] = {{}}, {{}}
    for name, command in (("detect", "Aplan_Detect"), ("diagrams", "Aplan_Diagrams"), ("intent", "Aplan_Intent"),
                          ("fasteners", "Aplan_Fasteners"), ("subassemblies", "Aplan_Subassemblies"),
                          ("plan3d", "Aplan_Plan3D")):
        FreeCADGui.runCommand(command)
        settle()
        viewport = task_view_viewport()
        result["task_view_width"][name] = viewport.width()
        result["cut_off"][name] = cut_off(viewport)
        viewport.parentWidget().widget().grab().save(os.path.join(ARTIFACTS, f"gui_panel_{{name}}.png"))
        FreeCADGui.Control.closeDialog()
    settle()
    plan = state().plan
    product = workflow.analysis_product(find_analysis(FreeCAD.ActiveDocument))
    levels = replace(product, subassemblies=(Subassembly("writing unit", ("ink_001", "cartridge_001", "head_001")),))
    # Simulate with a policy over the lumped model's classes (aplan solve --lumped; 20 trials, no clock): played
    # on the factored model as aplan simulate --policy plays it, its belief plot in the dialog.
    from planner import api as planner_api
    from planner.decision.policy import write_policy
    lumped = planner_api.lumped_model(product)
    state().policy = os.path.join(os.path.dirname(COPY), "lumped.policy")
    write_policy(planner_api.solve(lumped, None, iterations=20).policy, state().policy, lumped.pomdp.name)
    ask, QtGui.QInputDialog.getInt = QtGui.QInputDialog.getInt, lambda *args, **kwargs: (3, True)
    FreeCADGui.runCommand("Aplan_Simulate")
    QtGui.QInputDialog.getInt = ask
    settle()
    shown = getattr(state(), "belief_dialog", None)
    result["simulate"] = [status(), shown.findChild(QtGui.QLabel).text() if shown else None]
    if shown:
        shown.grab().save(os.path.join(ARTIFACTS, "gui_simulate_lumped.png"))
        shown.close()
    caption = "The AND/OR graph, in the belief dialog of Simulate (a picture with its caption)."
    for name, dialog in (("plan", PlanDialog(product.name, plan["statistics"], plan["images"], window)),
                         ("levels", LevelsDialog(product.name, level_report(levels), window)),
                         ("image", ImageDialog("APLAN belief", caption, plan["images"]["andor"], window))):
        dialog.show()
        settle()
        result["cut_off"][name] = cut_off(dialog)
        dialog.grab().save(os.path.join(ARTIFACTS, f"gui_panel_{{name}}.png"))
        dialog.close()


def screenshots():
    doc = FreeCAD.ActiveDocument
    screen = QtGui.QApplication.primaryScreen().grabWindow(0)
    screen.save(os.path.join(ARTIFACTS, "gui_main_window.png"))
    result["report_view"] = FreeCADGui.getMainWindow().findChild(QtGui.QDockWidget, "Report view").widget(
        ).toPlainText()
    result["after"] = snapshot(doc)
    panels_at_default_width()
    # Designer intent in the task panel: the pen's technical constraint and a tag (body + button needs a
    # screwdriver and is left to the human), then the plan again.
    FreeCADGui.getMainWindow().findChild(QtGui.QDialog, "AplanPlanDialog").close()
    FreeCADGui.runCommand("Aplan_Intent")
    window = FreeCADGui.getMainWindow()
    constraints = window.findChild(QtGui.QTableWidget, "AplanConstraintsTable")
    tags = window.findChild(QtGui.QTableWidget, "AplanTagsTable")
    constraints.insertRow(0)
    constraints.setItem(0, 0, QtGui.QTableWidgetItem("ink_001, cartridge_001"))
    constraints.setItem(0, 1, QtGui.QTableWidgetItem("head_001"))
    active = QtGui.QTableWidgetItem()
    active.setCheckState(QtCore.Qt.Checked)
    constraints.setItem(0, 2, active)
    row = [r for r in range(tags.rowCount()) if tags.item(r, 0).text() == "{{body_001}} + {{button_001}}"][0]
    tags.item(row, 2).setCheckState(QtCore.Qt.Unchecked)
    tags.item(row, 3).setText("screwdriver")
    result["tag_rows"] = tags.rowCount()
    state().panel.accept()
    from freecad_aplan.intent import find_analysis, read_intent, update_intent
    intent = read_intent(find_analysis(doc))
    result["stored"] = [intent.technical_constraints, intent.operations, intent.tools]
    FreeCADGui.runCommand("Aplan_Plan")
    result["tagged_plan"] = state().plan["statistics"]
    doc.undo()
    result["undone"] = read_intent(find_analysis(doc)).operations
    # Components: group the selected ink and cartridge, then ungroup; exclude the cap, then include it.
    analysis = find_analysis(doc)
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(doc.Name, "b_ink_001_")
    FreeCADGui.Selection.addSelection(doc.Name, "b_cartridge_001_")
    FreeCADGui.runCommand("Aplan_GroupComponent")
    result["grouped"] = read_intent(analysis).groups
    FreeCADGui.runCommand("Aplan_GroupComponent")
    result["ungrouped"] = read_intent(analysis).groups
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(doc.Name, "b_cap_001_")
    FreeCADGui.runCommand("Aplan_ExcludeParts")
    result["excluded"] = read_intent(analysis).excluded
    FreeCADGui.runCommand("Aplan_ExcludeParts")
    result["included"] = read_intent(analysis).excluded
    FreeCADGui.Selection.clearSelection()
    # Diagrams panel: remove the first relation (a contact), OK; then undo.
    FreeCADGui.runCommand("Aplan_Diagrams")
    table = FreeCADGui.getMainWindow().findChild(QtGui.QTableWidget, "AplanDiagramsTable")
    table.selectRow(0)
    state().panel.remove_selected()
    state().panel.accept()
    result["contacts_after_remove"] = len(read_intent(analysis).diagrams["contacts"])
    doc.undo()
    result["contacts_after_undo"] = len(read_intent(analysis).diagrams["contacts"])
    # Diagrams panel: add a relation with the panel's own fields and button. Bad ones first: a message in
    # the panel, no new row; then a new contact, OK (one undoable step); then undo.
    FreeCADGui.runCommand("Aplan_Diagrams")
    form = FreeCADGui.getMainWindow().findChild(QtGui.QWidget, "AplanDiagramsPanel")
    table = form.findChild(QtGui.QTableWidget, "AplanDiagramsTable")
    kind, first, second = (form.findChild(QtGui.QComboBox, name)
                           for name in ("AplanRelationKind", "AplanRelationFirst", "AplanRelationSecond"))
    add = form.findChild(QtGui.QPushButton, "AplanAddRelation")
    message = form.findChild(QtGui.QLabel, "AplanDiagramsMessage")

    def fill_and_add(relation):
        kind.setCurrentIndex(kind.findText(relation[0]))
        first.setEditText(relation[1])
        second.setEditText(relation[2])
        add.click()
        return message.text()

    rows, steps = table.rowCount(), len(doc.UndoNames)
    result["add_messages"] = [fill_and_add(r) for r in (("blocks -Y", "cap_001", "ink_001"),
                                                        ("contact", "ink_01", "body_001"),
                                                        ("contact", "body_001", "body_001"))]
    result["rows_after_bad"] = table.rowCount() - rows
    result["add_message"] = fill_and_add(("contact", "ink_001", "body_001"))
    result["added_row"] = [table.item(table.rowCount() - 1, c).text() for c in range(3)]
    result["stored_before_ok"] = len(read_intent(analysis).diagrams["contacts"])
    state().panel.accept()
    stored = read_intent(analysis).diagrams
    result["after_add"] = [stored["contacts"], stored.get("edits"), doc.UndoNames[0], len(doc.UndoNames) - steps]
    doc.undo()
    undone = read_intent(analysis).diagrams
    result["after_add_undo"] = [len(undone["contacts"]), "edits" in undone]
    FreeCADGui.Selection.clearSelection()
    # Save, close and reopen in the GUI: the analysis, its intent and its view provider come back.
    from dataclasses import asdict
    update_intent(analysis, "tag", tools=["screwdriver"], operations=[{{"inputs": [["body_001"], ["button_001"]],
                                                                      "robot": False, "tool": "screwdriver"}}])
    saved = asdict(read_intent(analysis))
    path = os.path.join(os.path.dirname(COPY), "reopened.FCStd")
    doc.saveAs(path)
    FreeCAD.closeDocument(doc.Name)
    doc = FreeCAD.openDocument(path)
    analysis = find_analysis(doc)
    result["reopened_same"] = asdict(read_intent(analysis)) == saved
    result["reopened_view"] = type(FreeCADGui.getDocument(doc.Name).getObject(analysis.Name).Proxy).__name__
    result["reopened_placements"] = snapshot(doc) == result["before"]
    # An analysis from a newer APLAN: refused with a message, nothing changes.
    analysis.FormatVersion = 2
    names = list(analysis.Excluded)
    FreeCADGui.runCommand("Aplan_Plan")
    result["newer"] = status()
    FreeCADGui.Selection.addSelection(doc.Name, "b_cap_001_")
    FreeCADGui.runCommand("Aplan_ExcludeParts")
    result["newer_unchanged"] = list(analysis.Excluded) == names
    # A document without solids.
    import Part
    flat = FreeCAD.newDocument("flat")
    flat.addObject("Part::Feature", "Sheet").Shape = Part.makePlane(10, 10)
    flat.recompute()
    FreeCADGui.runCommand("Aplan_CreateAnalysis")
    FreeCADGui.runCommand("Aplan_Detect")
    result["no_solids"] = status()
    result["no_solids_jobs"] = len(state().jobs)
    finish(0)


FreeCADGui.getMainWindow().showMaximized()
QtCore.QTimer.singleShot(1500, guarded(start))
"""


PEN = PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"


def _in_the_window():
    """The script in the FreeCAD window on a copy of the pen (a background job): its folder and FreeCAD's run."""
    tmp_path = folder("gui")
    shutil.copy(PEN, tmp_path / "pen.FCStd")
    ARTIFACTS.mkdir(exist_ok=True)
    script = tmp_path / "gui_test.py"
    script.write_text(GUI_SCRIPT.format(gui_helpers=GUI_HELPERS, workbench_helpers=WORKBENCH_HELPERS,
                                        layout_check=LAYOUT_CHECK, out=str(tmp_path / "result.json"),
                                        copy=str(tmp_path / "pen.FCStd"), artifacts=str(ARTIFACTS)))
    return tmp_path, freecad_gui_run(tmp_path, script, display=160)


#: The window's run, done in the background (tests/background.py).
BACKGROUND = (Job("the pen in the FreeCAD window", _in_the_window),)


@pytest.mark.freecad
def test_workbench_in_the_real_freecad_window():
    require_shared(PEN)
    require_freecad_gui()
    tmp_path, done = BACKGROUND[0].result()
    copy = tmp_path / "pen.FCStd"
    data = freecad_gui_result(done, tmp_path / "result.json")
    assert data["workbench"] == "AplanWorkbench" and all(data["commands"].values())
    # Bad input: one clear line each, and the document untouched.
    assert data["active_without_document"] == [False] * len(data["commands"])
    assert data["active_without_analysis"] == ["Aplan_CreateAnalysis"]
    assert "no document is open" in data["no_document"]
    assert "no APLAN analysis; create one first" in data["no_analysis"] and data["no_analysis_unchanged"]
    assert "nothing is selected" in data["nothing_selected"]
    assert "run APLAN > Detect contacts and obstructions first" in data["not_detected"]
    # Detection ran in the background (the event loop kept running) and found the pen's five liaisons.
    assert data["ticks"] >= 2, data
    diagrams = data["diagrams"]
    assert sorted(diagrams["parts"]) == sorted(["ink_001", "cartridge_001", "head_001", "body_001", "cap_001",
                                                "button_001"])
    assert len(diagrams["contacts"]) == 5 and "5 contacts" in data["detected"]
    assert data["cancel_started"] == 1 and "cancelled; nothing was changed" in data["cancelled"]
    assert data["diagrams_after_cancel"] is True
    # Diagrams table: contacts plus the +X/+Y/+Z obstruction pairs; a row selects its two parts.
    assert data["diagram_rows"] == 5 + sum(len(o["blocks"]) for o in diagrams["obstructions"])
    assert data["row0"][0] == "contact" and data["selected"] == sorted(data["row0"][1:])
    # Statistics: the figures of `aplan stats` for the pen (README / paper: 69 intentions).
    stats = data["plan"]["statistics"]
    assert stats == json.loads(aplan("stats", str(copy), "--json").stdout)
    assert (stats["subassemblies"], stats["states"], stats["intentions"], stats["sequences"]) == (18, 18, 69, 24)
    assert data["shown"]["intentions"] == "69"
    assert all(path.endswith(".png") for path in data["plan"]["images"].values())
    assert data["after"] == data["before"]
    # Intent edited in the task panel: stored as product-format entries, used by the next plan, undoable.
    constraints, operations, tools = data["stored"]
    assert constraints == [{"parts": ["ink_001", "cartridge_001"], "requires": "head_001", "active": True}]
    assert operations == [{"inputs": [["body_001"], ["button_001"]], "unfavorable": False, "robot": False,
                           "tool": "screwdriver"}] and tools == ["screwdriver"]
    assert data["tag_rows"] == 21
    tagged = data["tagged_plan"]
    assert (tagged["intentions"], tagged["states"], tagged["actions"]) == (39, 14, 18 - 1)
    assert data["undone"] == []
    assert data["grouped"] == {"ink_001+cartridge_001": ["b_ink_001_", "b_cartridge_001_"]}
    assert data["ungrouped"] == {} and data["excluded"] == ["b_cap_001_"] and data["included"] == []
    assert (data["contacts_after_remove"], data["contacts_after_undo"]) == (4, 5)
    # Adding a relation in the panel: refused with a message (duplicate, unknown, self), else one undoable step.
    duplicate, unknown, itself = data["add_messages"]
    assert duplicate == ("cannot add cap_001 blocked by ink_001 along -Y: the diagrams already hold it "
                         "(as ink_001 blocked by cap_001 along +Y)")
    assert "'ink_01' is not a component (did you mean 'ink_001'?)" in unknown
    assert "a component cannot be related to itself" in itself
    assert data["rows_after_bad"] == 0
    assert data["add_message"] == "added contact ink_001 - body_001 (stored on OK)"
    assert data["added_row"] == ["contact", "ink_001", "body_001"] and data["stored_before_ok"] == 5
    contacts, edits, undo_name, steps = data["after_add"]
    assert {frozenset(c) for c in contacts} == {frozenset(c) for c in diagrams["contacts"]} | {
        frozenset(("ink_001", "body_001"))}
    assert edits == [{"added": ["contact", "ink_001", "body_001"]}]
    assert (undo_name, steps) == ("APLAN: add contact ink_001 - body_001", 1)
    assert data["after_add_undo"] == [5, False]
    assert data["reopened_same"] is True and data["reopened_view"] == "AnalysisViewProvider"
    assert data["reopened_placements"] is True
    assert "written by a newer APLAN" in data["newer"] and data["newer_unchanged"] is True
    assert "the document has no solids to plan with" in data["no_solids"] and data["no_solids_jobs"] == 0
    # What they show: the pen drawn large in the 3D view (measured: 9 % of the view, 59 % of its width), the
    # window's text (dark: 2.2 % of the screen, 584 colours).
    view = read_picture(ARTIFACTS / "gui_3d_view.png")
    assert view.share(view.differs_from((255, 255, 255))) >= 0.04 and view.share(view.dark()) >= 0.01
    assert max(view.extent(view.differs_from((255, 255, 255)))) >= 0.4
    window = read_picture(ARTIFACTS / "gui_main_window.png")
    assert window.size == (1280, 800) and window.share(window.dark()) >= 0.01 and window.colours() >= 200
    # The README's picture (docs/workbench.png is a copy of gui_main_window.png): the plan's line, no red lines
    # of the sample's A2plus proxies, no path of the test's temporary folder.
    assert "APLAN: parts 6, contacts 5" in data["report_view"], data["report_view"]
    assert "ImportError" not in data["report_view"] and "a2p_" not in data["report_view"], data["report_view"]
    assert str(tmp_path) not in data["report_view"] and "/tmp/" not in data["report_view"], data["report_view"]
    # Every task panel and dialog at FreeCAD's default size: nothing cut off (the panels before issue 15 each
    # had a dozen problems: a right edge at 300 to 480 px in a task view of 244, columns beyond the table).
    assert 200 <= data["combo_view_width"] <= 300, data["combo_view_width"]
    assert set(data["task_view_width"]) == {"detect", "diagrams", "intent", "fasteners", "subassemblies", "plan3d"}
    assert all(width <= data["combo_view_width"] for width in data["task_view_width"].values())
    assert data["cut_off"] == {name: [] for name in ("detect", "diagrams", "intent", "fasteners", "subassemblies",
                                                     "plan3d", "plan", "levels", "image")}, data["cut_off"]
    # Simulate ran the lumped policy (before issue 24 it was refused, naming the session panel).
    assert data["simulate"][1].startswith("Sequence 3 (lumped model): belief on the true intention"), data["simulate"]
    belief = read_picture(ARTIFACTS / "gui_simulate_lumped.png")
    assert belief.share(belief.dark()) >= 0.002 and belief.colours() >= 30
    for name in data["cut_off"]:
        # Text a person can read, not a blank or one-colour grab (measured: 0.37 to 3.5 % dark, 46 to 185 colours).
        panel = read_picture(ARTIFACTS / f"gui_panel_{name}.png")
        assert panel.share(panel.dark()) >= 0.002 and panel.colours() >= 30, name
