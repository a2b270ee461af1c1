"""The workbench on a real product (the 61-part toy truck) in the real FreeCAD window under Xvfb: detection in
the background with progress, the fastener proposals accepted in the fasteners panel, the planner's
subassembly tree accepted in the tree panel, the per-level statistics computed in the background, a
screenshot (tests/artifacts/gui_truck_structure.png), and the numbers checked against the command line: the
tagged groups are those `aplan fasteners` proposes for the truck, and the levels those of `aplan stats` on the
bundle the workbench exported."""
from __future__ import annotations

import json
import shutil

import pytest
from background import Job, folder
from conftest import REPO, SHARED, freecad_gui_result, freecad_gui_run, require_freecad_gui, require_shared
from integration.freecad_tools import GUI_HELPERS, LAYOUT_CHECK, aplan
from pictures import read_picture
from real_models import JOBS, real_bundles  # noqa: F401  (fixture: the truck exported once per session)

ARTIFACTS = REPO / "tests" / "artifacts"
TRUCK = SHARED / "models" / "toy_truck" / "asm_cement_mixer_truck.FCStd"

GUI_SCRIPT = r"""
import json, os, time, traceback
from PySide import QtCore, QtGui
import FreeCAD, FreeCADGui

OUT, COPY, BUNDLE, ARTIFACTS = {out!r}, {copy!r}, {bundle!r}, {artifacts!r}
result = {{"ticks": 0, "progress": [], "plan_ticks": 0}}


{gui_helpers}

{layout_check}


def at_default_width(name):
    # The task panel in the combo view as a fresh FreeCAD shows it: what is cut off, and a picture of it.
    for _ in range(5):
        QtGui.QApplication.processEvents()
    viewport = task_view_viewport()
    viewport.parentWidget().widget().grab().save(os.path.join(ARTIFACTS, f"gui_panel_{{name}}_truck.png"))
    return cut_off(viewport)


def state():
    return FreeCADGui.getWorkbench("AplanWorkbench").state


def status():
    return FreeCADGui.getMainWindow().statusBar().currentMessage()


def progress_text():
    shown = [d for d in FreeCADGui.getMainWindow().findChildren(QtGui.QProgressDialog, "AplanJobProgress")
             if d.isVisible()]  # the dialogs of finished jobs are closed, not deleted
    return shown[0].labelText() if shown else None


def start():
    FreeCADGui.activateWorkbench("AplanWorkbench")
    doc = FreeCAD.openDocument(COPY)
    FreeCADGui.SendMsgToActiveView("ViewFit")
    FreeCADGui.runCommand("Aplan_CreateAnalysis")
    result["detect_started"] = time.monotonic()
    FreeCADGui.runCommand("Aplan_Detect")       # export and engine, both in background processes
    result["detect_returned"] = time.monotonic() - result["detect_started"]
    QtCore.QTimer.singleShot(200, guarded(wait_detection))


def wait_detection():
    if state().jobs:
        result["ticks"] += 1                     # the event loop runs while the jobs work
        text = progress_text()  # title, seconds, the job's last note
        if text and (not result["progress"] or result["progress"][-1] != text.splitlines()[-1]):
            result["progress"].append(text.splitlines()[-1])
        QtCore.QTimer.singleShot(200, guarded(wait_detection))
        return
    from freecad_aplan.intent import find_analysis, read_intent
    doc = FreeCAD.ActiveDocument
    analysis = find_analysis(doc)
    result["detected"] = status()
    result["detect_seconds"] = round(time.monotonic() - result["detect_started"], 1)
    result["parts"] = len(read_intent(analysis).diagrams["parts"])
    # Fasteners: the panel lists the planner's proposals; all ticked, OK accepts them (one undo step).
    FreeCADGui.runCommand("Aplan_Fasteners")
    panel = state().panel
    result["fasteners_cut_off"] = at_default_width("fasteners")
    window = FreeCADGui.getMainWindow()
    groups = window.findChild(QtGui.QListWidget, "AplanFastenersList")
    shown, broken = [], broken_words(task_view_viewport())
    headings = []
    for r in range(groups.count()):  # each group as a designer reads it: clicked in the list, shown below it
        if not groups.item(r).flags() & QtCore.Qt.ItemIsUserCheckable:
            headings.append(groups.item(r).text())
            continue
        groups.setCurrentRow(r)
        QtGui.QApplication.processEvents()
        labels = [window.findChild(QtGui.QLabel, n).text() for n in ("AplanFastenerParts", "AplanFastenerHosts",
                                                                      "AplanFastenerWhy")]
        shown.append([groups.item(r).text(), groups.item(r).toolTip(), *labels])  # the id: the entry's tooltip
        broken += broken_words(task_view_viewport())
    result["fastener_shown"], result["fasteners_broken"] = shown, sorted(set(broken))
    result["fastener_headings"] = headings
    result["fasteners_width"] = task_view_viewport().width()
    groups.setCurrentRow(0)
    # Bad input in the panel: wood_screw_004 touches one part only; tagging it is refused with a message.
    steps = len(doc.UndoNames)
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(doc.Name, "b_wood_screw_001_003")
    FreeCADGui.getMainWindow().findChild(QtGui.QPushButton, "AplanTagFasteners").click()
    result["tag_one_part"] = [FreeCADGui.getMainWindow().findChild(QtGui.QLabel, "AplanFastenersMessage").text(),
                              len(doc.UndoNames) - steps]
    FreeCADGui.Selection.clearSelection()
    for k in range(len(panel.rows)):  # wood screws: a screwdriver, typed in each group's tool field
        panel.set_tool(k, "screwdriver")
    result["fastener_accepted"] = panel.accept()
    intent = read_intent(analysis)
    result["tagged"] = [len(intent.fasteners), doc.UndoNames[0], len(doc.UndoNames) - steps]
    # The subassembly tree: the planner's proposal, accepted (checked by the planner, one undo step).
    FreeCADGui.runCommand("Aplan_Subassemblies")
    panel = state().panel
    panel.propose()
    result["tree_cut_off"] = at_default_width("subassemblies")
    tree = FreeCADGui.getMainWindow().findChild(QtGui.QTreeWidget, "AplanSubassemblyTree")
    top = tree.topLevelItem(0)
    result["tree_top"] = sorted(top.child(k).text(0) for k in range(top.childCount()))
    result["tree_kinds"] = sorted({{top.child(k).text(1).split(":")[0] for k in range(top.childCount())}})
    # The panel's own edits: delete sa2 (its members go up), a new one of the roof and its lamp, the lamp moved
    # to the top level; then the planner's proposal again.
    window = FreeCADGui.getMainWindow()

    def select(*names):
        tree.clearSelection()
        for name in names:
            tree.findItems(name, QtCore.Qt.MatchExactly | QtCore.Qt.MatchRecursive, 0)[0].setSelected(True)

    select("sa2")
    window.findChild(QtGui.QPushButton, "AplanDeleteSubassembly").click()
    edits = [sorted(s["id"] for s in panel.entries)]
    select("cabin_roof_001", "cabin_flashlight_001")
    window.findChild(QtGui.QLineEdit, "AplanSubassemblyName").setText("roof")
    window.findChild(QtGui.QPushButton, "AplanNewSubassembly").click()
    edits.append([s["parts"] for s in panel.entries if s["id"] == "roof"])
    select("cabin_flashlight_001")
    target = window.findChild(QtGui.QComboBox, "AplanMoveTarget")
    target.setCurrentIndex(target.findText("sa1"))
    window.findChild(QtGui.QPushButton, "AplanMoveMember").click()
    edits.append([[s["id"], s["parts"]] for s in panel.entries if "cabin_flashlight_001" in s["parts"]])
    result["tree_edits"] = edits
    panel.propose()
    steps = len(doc.UndoNames)
    # Bad input: a subassembly of two parts that do not touch (a tire and the drum); OK refuses it, naming them.
    good = [dict(s) for s in panel.entries]
    loose = ("tire_001", "drum_001")
    panel.entries = [dict(s, parts=[m for m in s["parts"] if m not in loose]) for s in good] + [
        {{"id": "loose", "parts": list(loose)}}]
    message = FreeCADGui.getMainWindow().findChild(QtGui.QLabel, "AplanSubassembliesMessage")
    result["tree_bad"] = [panel.accept(), message.text(), len(doc.UndoNames) - steps]
    panel.entries = good
    result["tree_accepted"] = panel.accept()
    result["tree"] = [read_intent(analysis).subassemblies, doc.UndoNames[0], len(doc.UndoNames) - steps]
    # Statistics per level, in the background.
    result["plan_started"] = time.monotonic()
    FreeCADGui.runCommand("Aplan_Plan")
    result["plan_returned"] = round(time.monotonic() - result["plan_started"], 2)
    result["plan_jobs"] = len(state().jobs)
    QtCore.QTimer.singleShot(200, guarded(wait_plan))


def wait_plan():
    if state().jobs:
        result["plan_ticks"] += 1
        text = progress_text()
        if text:
            result.setdefault("plan_progress", []).append(text.splitlines()[-1])
        QtCore.QTimer.singleShot(200, guarded(wait_plan))
        return
    result["plan"] = state().plan
    result["plan_seconds"] = round(time.monotonic() - result["plan_started"], 1)
    dialog = FreeCADGui.getMainWindow().findChild(QtGui.QDialog, "AplanLevelsDialog")
    table = dialog.findChild(QtGui.QTableWidget, "AplanLevelsTable")
    result["shown"] = [[table.item(r, c).text() for c in range(table.columnCount())] for r in range(table.rowCount())]
    # The screenshot: the stored tree in the task panel, the levels beside it.
    FreeCADGui.runCommand("Aplan_Subassemblies")
    window = FreeCADGui.getMainWindow()
    combo = [d for d in window.findChildren(QtGui.QDockWidget) if d.widget() and "Combo" in d.windowTitle()]
    if combo:  # a wider task panel, so that the tree's names show
        window.resizeDocks(combo[:1], [470], QtCore.Qt.Horizontal)
    dialog.setGeometry(560, 300, 715, 470)
    view = FreeCADGui.ActiveDocument.ActiveView
    view.viewIsometric()
    FreeCADGui.SendMsgToActiveView("ViewFit")
    QtGui.QApplication.processEvents()
    QtCore.QTimer.singleShot(800, guarded(screenshot))


def screenshot():
    QtGui.QApplication.primaryScreen().grabWindow(0).save(os.path.join(ARTIFACTS, "gui_truck_structure.png"))
    FreeCADGui.Control.closeDialog()
    from freecad_aplan import workflow
    from freecad_aplan.intent import find_analysis
    doc = FreeCAD.ActiveDocument
    workflow.export_analysis_bundle(doc, find_analysis(doc), BUNDLE)
    finish(0)


FreeCADGui.getMainWindow().showMaximized()
QtCore.QTimer.singleShot(1500, guarded(start))
"""


def _truck_in_the_window() -> tuple:
    """The GUI script's run on a copy of the truck: (folder, FreeCAD's run); the workbench's bundle is in
    folder/bundle, the script's result in folder/result.json."""
    tmp = folder("gui-truck")
    copy = tmp / "truck.FCStd"
    shutil.copy(TRUCK, copy)
    ARTIFACTS.mkdir(exist_ok=True)
    script = tmp / "gui_truck.py"
    script.write_text(GUI_SCRIPT.format(gui_helpers=GUI_HELPERS, layout_check=LAYOUT_CHECK,
                                        out=str(tmp / "result.json"), copy=str(copy),
                                        bundle=str(tmp / "bundle"), artifacts=str(ARTIFACTS)))
    return tmp, freecad_gui_run(tmp, script, display=150)


#: The truck's export (for `aplan fasteners`) and the window's run, done in the background (tests/background.py).
BACKGROUND = (*JOBS.values(), Job("the truck in the FreeCAD window", _truck_in_the_window))


@pytest.mark.freecad
def test_truck_structure_in_the_workbench(real_bundles):  # noqa: F811
    require_freecad_gui()
    require_shared(TRUCK)
    tmp, done = BACKGROUND[-1].result()
    data = freecad_gui_result(done, tmp / "result.json")
    bundle = tmp / "bundle"
    # Detection stayed in the background: the command returned at once (the quick component check and a copy
    # of the document), the event loop kept running, the dialog showed the parts being tessellated.
    assert data["detect_returned"] < 10, data["detect_returned"]
    assert data["ticks"] >= 10
    assert any(p.startswith("tessellating part ") for p in data["progress"]), data["progress"]
    assert data["parts"] == 61 and "61 parts, 113 contacts" in data["detected"]
    # The fastener groups the panel listed and accepted are those `aplan fasteners` proposes for the truck.
    proposals = json.loads(aplan("fasteners", str(real_bundles["toy_truck"]), "--json").stdout)["proposed"]
    expected = sorted([g["id"], ", ".join(g["parts"]), ", ".join(g["hosts"])] for g in proposals)
    assert data["fastener_headings"] == ["Proposed by the planner"]  # nothing tagged yet
    rows = [[name.replace("\n+ ", "+"), parts.replace("\n", ", "), hosts.replace("\n", ", ")]
            for _, name, parts, hosts, _ in data["fastener_shown"]]
    assert sorted(rows) == expected and len(expected) == 22
    # the list names each group by the parts it joins, one per line
    assert [entry.replace("\n+ ", ", ") for entry, *_ in data["fastener_shown"]] == [", ".join(g["hosts"])
                                                                                    for g in proposals]
    assert [why for *_, why in data["fastener_shown"]] == [g["reason"] for g in proposals]
    # The panel reads at the default width (the six-column table broke names as "cabi / n_d / oor_ / 001"): one
    # name per line, no word wider than its label, no entry wider than the list, for every group selected.
    assert data["fasteners_broken"] == [], data["fasteners_broken"]
    panel = read_picture(ARTIFACTS / "gui_panel_fasteners_truck.png")
    width, height = panel.size  # the panel's widget: a few pixels wider than the task view's visible part
    assert 200 <= data["fasteners_width"] <= 300, data["fasteners_width"]
    text = panel.dark()
    x0, y0, x1, y1 = panel.box(text)
    assert x1 < data["fasteners_width"] - 4, (x1, data["fasteners_width"])  # measured: 220 of 244 px
    # text in the list and in the group shown below it: dark pixels in both halves (measured: 5.0 % and 2.7 %)
    assert panel.share(text[:height // 2]) >= 0.01
    assert panel.share(text[height // 2:]) >= 0.01
    message, steps = data["tag_one_part"]
    assert message.startswith("the fasteners wood_screw_004 join only ") and "joins nothing or only one part" in message
    assert steps == 0
    assert data["fastener_accepted"] is True
    # Both panels, filled with the truck's 22 proposals and its subassembly tree, fit the default combo view.
    assert data["fasteners_cut_off"] == [] and data["tree_cut_off"] == [], (data["fasteners_cut_off"],
                                                                           data["tree_cut_off"])
    assert data["tagged"] == [22, "APLAN: accept 22 proposed fastener groups", 1]
    designer = json.loads(aplan("fasteners", str(bundle), "--json").stdout)
    assert sorted([g["id"], ", ".join(g["parts"]), ", ".join(g["hosts"])] for g in designer["designer"]) == expected
    assert designer["proposed"] == [] and all(g["source"] == "designer" for g in designer["designer"])
    assert {g["tool"] for g in designer["designer"]} == {"screwdriver"}
    # The subassembly tree: the planner's proposal (as --subassemblies auto), stored in one undo step.
    deleted, roof, moved = data["tree_edits"]
    assert "sa2" not in deleted and len(deleted) == len(data["tree"][0]) - 1
    assert roof == [["cabin_roof_001", "cabin_flashlight_001"]]
    assert moved[0][0] == "sa1" and moved[0][1][-1] == "cabin_flashlight_001" and len(moved) == 1
    accepted, message, steps = data["tree_bad"]
    assert accepted is False and steps == 0
    assert "subassembly loose cannot be built on its own" in message and "nothing was changed" in message
    assert data["tree_accepted"] is True
    tree, undo_name, steps = data["tree"]
    assert (undo_name, steps) == ("APLAN: edit subassemblies", 1) and len(tree) >= 2
    roots = {s["id"] for s in tree if s["id"] not in {m for t in tree for m in t["parts"]}}
    assert roots <= set(data["tree_top"]) and "fastener" not in data["tree_kinds"]  # fasteners are no members
    written = json.loads((bundle / "product.json").read_text())
    assert [(s["id"], s["parts"], s["source"]) for s in written["subassemblies"]] == [
        (s["id"], s["parts"], "designer") for s in tree]
    # The per-level statistics, computed in the background, are those of `aplan stats` on the exported bundle
    # with the defaults (--fasteners tagged --subassemblies designer).
    assert data["plan_jobs"] == 1 and data["plan_ticks"] >= 1
    assert any(p.startswith(("level ", "the product planned flat")) for p in data.get("plan_progress", [])), \
        data.get("plan_progress")
    report = data["plan"]["levels"]
    stats = json.loads(aplan("stats", str(bundle), "--json", "--fasteners", "tagged", "--subassemblies",
                             "designer").stdout)
    assert report["levels"] == stats["levels"] and report["total"] == stats["total"]
    assert report["flat"] == stats["flat"]
    assert len(report["fasteners"]) == 22 and sum(len(g["parts"]) for g in report["fasteners"]) == 38
    assert [row[0] for row in data["shown"]] == [lv["level"] for lv in stats["levels"]] + ["total"] + (
        ["flat"] if stats["flat"] else [])
    assert data["shown"][-1 if not stats["flat"] else -2][6] == f"{stats['total']['intentions']:,}"
    screen = read_picture(ARTIFACTS / "gui_truck_structure.png")  # measured: 2.7 % dark (text), 565 colours
    assert screen.size == (1280, 800) and screen.share(screen.dark()) >= 0.01 and screen.colours() >= 200
