"""The workbench on a real product (the 61-part toy truck) in the real FreeCAD window under Xvfb: detection in
the background with progress, the fastener proposals accepted in the fasteners panel, the planner's
subassembly tree accepted in the tree panel, the per-level statistics computed in the background, a
screenshot (tests/artifacts/gui_truck_structure.png), and the numbers checked against the command line: the
tagged groups are those `aplan fasteners` proposes for the truck, and the levels those of `aplan stats` on the
bundle the workbench exported. Then the session panel: the smallest level chosen, its simulated camera session
run in the background to the assembled level, and its belief plot shown (tests/artifacts/gui_truck_session.png)."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from background import Job, folder
from conftest import REPO, SHARED, freecad_gui_result, freecad_gui_run, require_freecad_gui, require_shared
from integration.freecad_tools import GUI_HELPERS, LAYOUT_CHECK, WORKBENCH_HELPERS, aplan
from pictures import hue_of, read_picture
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


{workbench_helpers}


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
    detect()       # export and engine, both in background processes
    result["detect_returned"] = time.monotonic() - result["detect_started"]
    QtCore.QTimer.singleShot(200, guarded(wait_detection))


def wait_detection():
    if state().jobs:
        result["ticks"] += 1                     # the event loop runs while the jobs work
        text = progress_text()  # title, seconds, the job's last note
        if text and (not result["progress"] or result["progress"][-1] != text.splitlines()[-1]):
            result["progress"].append(text.splitlines()[-1])
        # Every note each job has sent so far (its output is kept whole): what the dialog was fed, whatever
        # the moments at which its label was sampled above.
        from freecad_aplan.protocol import read_note
        for job in state().jobs:
            notes = [read_note(line) for line in job.output.splitlines()]
            result.setdefault("notes", {{}})[job.title] = [n for n in notes if n is not None]
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
        from freecad_aplan.protocol import read_note
        for job in state().jobs:  # every note the planning job has sent so far (see wait_detection)
            notes = [read_note(line) for line in job.output.splitlines()]
            result.setdefault("plan_notes", []).extend(n for n in notes if n is not None
                                                       and n not in result["plan_notes"])
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
    # A session in the simulated camera cell: the smallest level chosen in the panel's level selector, run in
    # the background with a fixed number of expansions per decision (no clock), the belief plot shown at the end.
    FreeCADGui.runCommand("Aplan_Session")
    panel = state().panel
    window = FreeCADGui.getMainWindow()
    combo = window.findChild(QtGui.QComboBox, "AplanSessionLevel")
    entries = [(combo.itemText(k), combo.itemData(k)) for k in range(combo.count())]
    result["session_entries"] = entries
    sizes = {{c.id: len(c.members) for c in panel.levels}}
    smallest = min(sizes, key=lambda level: (sizes[level], level))
    combo.setCurrentIndex(combo.findData(smallest))
    window.findChild(QtGui.QSpinBox, "AplanSessionExpansions").setValue(50)
    result["session_level"], result["session_members"] = panel.selected_level(), sizes[smallest]
    result["session_started"] = time.monotonic()
    window.findChild(QtGui.QPushButton, "AplanRunSession").click()
    result["session_returned"] = round(time.monotonic() - result["session_started"], 2)
    result["session_cancel_enabled"] = window.findChild(QtGui.QPushButton, "AplanCancelSession").isEnabled()
    QtCore.QTimer.singleShot(200, guarded(wait_session))


def wait_session():
    panel = state().panel
    if panel.job is not None:
        text = FreeCADGui.getMainWindow().findChild(QtGui.QLabel, "AplanSessionStatus").text()
        if not result.setdefault("session_progress", []) or result["session_progress"][-1] != text:
            result["session_progress"].append(text)
        QtCore.QTimer.singleShot(200, guarded(wait_session))
        return
    result["session_seconds"] = round(time.monotonic() - result["session_started"], 1)
    result["session_result"], result["session_error"], result["session_lines"] = panel.result, panel.error, panel.lines
    window = FreeCADGui.getMainWindow()
    result["session_status"] = window.findChild(QtGui.QLabel, "AplanSessionStatus").text()
    combo = [d for d in window.findChildren(QtGui.QDockWidget) if d.widget() and "Combo" in d.windowTitle()]
    if combo:  # the task panel wide enough for the belief plot to read
        window.resizeDocks(combo[:1], [640], QtCore.Qt.Horizontal)
    if state().plan_dialog is not None:  # the levels dialog of before, out of the picture
        state().plan_dialog.close()
    for dock in window.findChildren(QtGui.QDockWidget):  # the report view too: the task view gets its height
        if dock.windowTitle() == "Report view":
            dock.hide()
    QtGui.QApplication.processEvents()
    QtCore.QTimer.singleShot(800, guarded(session_screenshot))


def session_screenshot():
    state().panel.show_plot()
    QtGui.QApplication.processEvents()
    QtCore.QTimer.singleShot(400, guarded(scroll_to_plot))  # the task view laid out with the plot's height


def scroll_to_plot():
    panel = state().panel
    scroll = panel.plot.parentWidget()
    while scroll is not None and not isinstance(scroll, QtGui.QScrollArea):
        scroll = scroll.parentWidget()
    if scroll is not None:  # the task view scrolled down to the plot's end (its heat map), as a person does
        scroll.verticalScrollBar().setValue(scroll.verticalScrollBar().maximum())
        result["session_scroll"] = [type(scroll).__name__, scroll.verticalScrollBar().value()]
    QtGui.QApplication.processEvents()
    QtCore.QTimer.singleShot(400, guarded(grab_session))


def grab_session():
    panel = state().panel
    plot = panel.plot
    result["session_plot"] = [plot.pixmap() is not None and not plot.pixmap().isNull(), plot.width(), plot.height(),
                              plot.pixmap().height()]
    corner = plot.mapToGlobal(QtCore.QPoint(0, 0))
    result["session_plot_on_screen"] = [corner.x(), corner.y(), plot.width(), plot.height()]
    QtGui.QApplication.primaryScreen().grabWindow(0).save(os.path.join(ARTIFACTS, "gui_truck_session.png"))
    plot.grab().save(os.path.join(ARTIFACTS, "gui_truck_session_plot.png"))
    # The same level from the keyboard: the picks the simulated operator made (the demo's log), typed in the
    # panel after a line it refuses.
    events = [json.loads(line) for line in open(panel.result["levels"][0]["log"])]
    seen = [e["observation"] for e in events if e["event"] == "observation"]
    typed = [" ".join(n.strip("[]") for n in observation.split("+")) for observation in seen]
    window = FreeCADGui.getMainWindow()
    source = window.findChild(QtGui.QComboBox, "AplanSessionSource")
    source.setCurrentIndex(source.findData("keyboard"))
    window.findChild(QtGui.QPushButton, "AplanRunSession").click()
    picks = window.findChild(QtGui.QLineEdit, "AplanSessionPicks")
    result["keyboard_enabled"] = [picks.isEnabled(), window.findChild(QtGui.QPushButton, "AplanSendPicks").isEnabled()]
    for line in ["cabin_roof_001 nothing"] + typed:
        picks.setText(line)
        window.findChild(QtGui.QPushButton, "AplanSendPicks").click()
    result["typed"] = typed
    QtCore.QTimer.singleShot(200, guarded(wait_keyboard))


def wait_keyboard():
    panel = state().panel
    if panel.job is not None:
        QtCore.QTimer.singleShot(200, guarded(wait_keyboard))
        return
    result["keyboard_result"], result["keyboard_error"], result["keyboard_lines"] = panel.result, panel.error, \
        panel.lines
    # Plan in 3D plans per level: the same level chosen, its sequences stepped through in the 3D view.
    FreeCADGui.runCommand("Aplan_Plan3D")
    panel = state().panel
    combo = FreeCADGui.getMainWindow().findChild(QtGui.QComboBox, "AplanPlan3DLevel")
    result["plan3d_levels"] = [combo.itemData(k) for k in range(combo.count())]
    combo.setCurrentIndex(combo.findData(result["session_level"]))
    QtGui.QApplication.processEvents()
    view = FreeCADGui.ActiveDocument.ActiveView
    steps = len(panel.exploded.steps)
    result["plan3d"] = {{"count": panel.count, "steps": steps, "members": sorted(panel.view.objects),
                        "moving": [sorted(s.moving) for s in panel.exploded.steps]}}
    for k in range(steps + 1):
        panel.show(k)
        QtGui.QApplication.processEvents()
        view.saveImage(os.path.join(ARTIFACTS, f"gui_truck_plan3d_step_{{k}}.png"), *view.getSize(), "White")
    panel.close()
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
    script.write_text(GUI_SCRIPT.format(gui_helpers=GUI_HELPERS, workbench_helpers=WORKBENCH_HELPERS, layout_check=LAYOUT_CHECK,
                                        out=str(tmp / "result.json"), copy=str(copy),
                                        bundle=str(tmp / "bundle"), artifacts=str(ARTIFACTS)))
    return tmp, freecad_gui_run(tmp, script, display=150, timeout=480)  # detection, levels and a session


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
    # The parts being tessellated reached the dialog as its job's notes, and its label showed the job's notes
    # (sampled every 200 ms: on an idle machine the tessellation can pass between two samples).
    notes = [n for job in data["notes"].values() for n in job]
    assert any(n.startswith("tessellating part ") for n in notes), data["notes"]
    assert set(data["progress"]) & set(notes), (data["progress"], data["notes"])
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
    assert any(n.startswith(("level ", "the product planned flat")) for n in data.get("plan_notes", [])), \
        data.get("plan_notes")
    assert set(data.get("plan_progress", [])) & set(data["plan_notes"]), (data.get("plan_progress"),
                                                                          data["plan_notes"])
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
    # The session panel: the levels of `aplan stats` to choose from (and all of them, bottom-up); the smallest
    # chosen, its simulated camera session run in the background to the assembled level with progress.
    assert [data for _, data in data["session_entries"]] == [lv["level"] for lv in stats["levels"]] + ["all levels"]
    smallest = min(stats["levels"], key=lambda lv: (len(lv["members"]), lv["level"]))
    assert (data["session_level"], data["session_members"]) == (smallest["level"], len(smallest["members"]))
    assert data["session_returned"] < 10 and data["session_cancel_enabled"] is True
    assert data["session_error"] is None, data["session_error"]
    session = data["session_result"]
    assert session["assembled"] is True and [d["level"] for d in session["levels"]] == [smallest["level"]]
    assert session["levels"][0]["reason"] == "assembled"
    assert session["command"].startswith("aplan session ") and f"--level {smallest['level']}" in session["command"]
    assert "--expansions 50" in session["command"]
    assert any(line.startswith("step 1 | belief ") for line in data["session_lines"]), data["session_lines"]
    assert data["session_progress"][0] == f"starting the session of {smallest['level']}"  # shown while it ran
    assert data["session_status"].startswith("assembled. ")
    # The log is one the command line replays (beliefs reproduced at every step); the belief plot written is
    # Fig. 7's heat map, and the panel shows it (viridis cells and the red line of the most probable intention).
    log = session["levels"][0]["log"]
    assert "beliefs reproduced at all" in aplan("replay", log).stdout
    # (A level of one operation: two assembly states, the belief one cell each step, viridis' top yellow;
    # measured 7.6 % viridis, 0.42 % red, 1.3 % dark in the file; 5.2 % viridis in the panel's smaller copy.)
    written = read_picture(session["levels"][0]["plot"])
    viridis = written.coloured(112.0, width=70, saturation=0.3, value=0.2)  # green to yellow
    assert written.size[0] == 1300 and written.share(viridis) >= 0.03
    assert written.share(written.coloured(5.0, width=12, saturation=0.6, value=0.5)) >= 0.002  # the red line
    assert written.share(written.dark(0.5)) >= 0.006  # its labels
    shown, width, height, picture_height = data["session_plot"]
    assert shown is True and width >= 400 and height >= picture_height >= 200  # the whole plot, 1300 px scaled
    plot = read_picture(ARTIFACTS / "gui_truck_session_plot.png")
    assert plot.share(plot.coloured(112.0, width=70, saturation=0.3, value=0.2)) >= 0.025
    screen = read_picture(ARTIFACTS / "gui_truck_session.png")
    assert screen.size == (1280, 800) and screen.colours() >= 200
    x, y, width, height = data["session_plot_on_screen"]  # the plot's part in the task view, its heat map in view
    shown = screen.crop(x, y, width, height)
    assert shown.share(shown.coloured(112.0, width=70, saturation=0.3, value=0.2)) >= 0.02, data.get("session_scroll")
    shutil.rmtree(Path(log).parents[1], ignore_errors=True)  # the panel keeps its logs and plots for the user
    # The keyboard session: the demo's picks typed in give the assembled level too; the bad line is refused.
    assert data["keyboard_enabled"] == [True, True] and data["keyboard_error"] is None, data["keyboard_error"]
    typed = data["keyboard_result"]
    assert typed["assembled"] is True and "--keyboard --robot auto" in typed["command"]
    assert typed["levels"][0]["steps"] == session["levels"][0]["steps"] == len(data["typed"])
    assert any("not a part or tool: nothing" in line for line in data["keyboard_lines"]), data["keyboard_lines"]
    # Plan in 3D on the same level: its plan (the sequences `aplan stats` counts for it), its members only, the
    # moving parts covering a tenth of the view at each step.
    assert data["plan3d_levels"] == [lv["level"] for lv in stats["levels"]]
    shown = data["plan3d"]
    assert shown["count"] == smallest["sequences"] and shown["steps"] == smallest["operations"]
    assert set(shown["members"]) <= set(smallest["members"])
    for k in range(shown["steps"]):
        step = read_picture(ARTIFACTS / f"gui_truck_plan3d_step_{k}.png")
        orange = step.coloured(hue_of((1.0, 0.55, 0.0)))  # the moving colour (freecad_aplan.plan3d.COLOURS)
        assert step.share(orange) >= 0.10, (k, step.share(orange))
