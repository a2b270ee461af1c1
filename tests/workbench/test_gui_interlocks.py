"""The interlocks panel in the real FreeCAD window (under Xvfb), on the press-fit document of issue 26
(tests/integration/interlock_documents.py: a pin of radius 5.1 in a blind bore of radius 5): the designer
detects, opens the panel, selects the proposal (inserted along +Z, the overlap's axis) and sees the pin orange,
the block blue and an arrow up from the pin (pixels of tests/artifacts/gui_interlocks_proposal.png), accepts it
(one undo step: the analysis carries the mark, the plan has its one sequence, the user's shapes, placements
and colours as they were), undoes it, then rejects it (the plan refuses the pair in the ``--interlocks error``
words). Then the captured knob of the same tests: its one-component proposal shows the cover and the knob
together (tests/artifacts/gui_interlocks_component.png), Cancel restores the view. Then the closed gearbox of
tests/integration/unseen_documents.py: its support contacts listed ("GearA rests in Housing"), the first shows the
gear and the housing orange together (tests/artifacts/gui_interlocks_support.png). Then the machine of the same
tests (the gearbox on a plate with 20 brackets, too large to judge flat), the gearbox one workstation: the panel
lists that level's support contacts ("GearA rests in Housing / at level sa2"), the first shows the gear and the housing orange
together (tests/artifacts/gui_interlocks_level_support.png), rejected there and stored on OK the level's plan
names the gear that would float. The panel fits the default task view (tests/artifacts/gui_panel_interlocks.png)."""
from __future__ import annotations

import shutil

import numpy as np
import pytest
from background import Job, folder
from conftest import REPO, freecad_gui_result, freecad_gui_run, require_freecad_gui
from integration.freecad_tools import GUI_HELPERS, LAYOUT_CHECK, WORKBENCH_HELPERS
from integration.test_interlock_documents import BACKGROUND as INTERLOCK_JOBS
from integration.test_unseen_documents import BACKGROUND as UNSEEN_JOBS
from integration.unseen_documents import GEARBOX, MACHINE
from test_level_support_decisions import LEVEL_PLAN
from pictures import hue_of, read_picture

#: The jobs that build the documents this window opens (they run once for both modules).
INTERLOCK_DOCUMENTS, UNSEEN_DOCUMENTS = INTERLOCK_JOBS[0], UNSEEN_JOBS[0]

ARTIFACTS = REPO / "tests" / "artifacts"
ORANGE, BLUE = (1.0, 0.55, 0.0), (0.1, 0.35, 0.9)

GUI_SCRIPT = r"""
import hashlib, json, os, time, traceback
from PySide import QtCore, QtGui
import FreeCAD, FreeCADGui

OUT, COPY, CAPTURED, GEARBOX, MACHINE, ARTIFACTS = ({out!r}, {copy!r}, {captured!r}, {gearbox!r}, {machine!r},
                                                     {artifacts!r})
result = {{}}
PARTS = ("Block", "Pin")
MATERIALS = {{}}


{gui_helpers}

{layout_check}


{workbench_helpers}


def settle(seconds=0.3):
    until = time.monotonic() + seconds
    while time.monotonic() < until:
        QtGui.QApplication.processEvents()


def geometry():
    # The user's shapes and placements, bit for bit, and their colours.
    doc = FreeCAD.ActiveDocument
    out = {{}}
    for name in PARTS:
        o = doc.getObject(name)
        out[name] = [hashlib.sha1(o.Shape.exportBrepToString().encode()).hexdigest(), list(o.Placement.Base),
                     list(o.Placement.Rotation.Q), list(o.ViewObject.ShapeColor), o.ViewObject.Transparency]
    return out


def looks():
    # The face colour and transparency (percent) the 3D view paints each part with (its materials, found once
    # by their colours before anything is painted).
    from freecad_aplan.plan3d import face_materials
    if not MATERIALS:
        MATERIALS.update({{n: face_materials(FreeCAD.ActiveDocument.getObject(n))[0] for n in PARTS}})
    out = {{}}
    for name in PARTS:
        material = MATERIALS[name]
        out[name] = [list(material.diffuseColor[0]), round(100 * material.transparency[0])]
    return out


def arrows():
    from freecad_aplan.gui.plan3d import ARROW_NAME
    graph = FreeCADGui.ActiveDocument.ActiveView.getSceneGraph()
    return [graph.getChild(i) for i in range(graph.getNumChildren()) if graph.getChild(i).getName() == ARROW_NAME]


def on_screen(name):
    # The part's bounding box projected on the 3D view (pixels; the view's y runs up).
    view = FreeCADGui.ActiveDocument.ActiveView
    box = FreeCAD.ActiveDocument.getObjectsByLabel(name)[0].Shape.BoundBox
    return [list(view.getPointOnScreen(box.getPoint(i))) for i in range(8)]


def intent():
    from freecad_aplan.intent import find_analysis, read_intent
    found = read_intent(find_analysis(FreeCAD.ActiveDocument))
    plus_z = [o for o in found.diagrams["obstructions"] if o["direction"] == "+Z"]
    return {{"interlocks": found.interlocks, "not_blocking": found.not_blocking, "directions": found.directions,
            "plus_z": sorted(map(list, plus_z[0]["blocks"])) if plus_z else None}}


def plan():
    from planner import api
    from freecad_aplan import workflow
    from freecad_aplan.intent import find_analysis
    try:
        product = workflow.analysis_product(find_analysis(FreeCAD.ActiveDocument))
        return ["planned", api.plan_statistics_of(product)[1].sequences]
    except Exception as exc:
        return [type(exc).__name__, str(exc)]


def start():
    FreeCADGui.activateWorkbench("AplanWorkbench")
    doc = FreeCAD.openDocument(COPY)
    doc.UndoMode = 1
    # Saved by FreeCADCmd (no view data): FreeCAD 0.20 opens the parts hidden; shown, as a designer does.
    result["opened_visible"] = [doc.getObject(n).ViewObject.Visibility for n in PARTS]
    for name in PARTS:
        doc.getObject(name).ViewObject.Visibility = True
    FreeCADGui.ActiveDocument.ActiveView.viewIsometric()
    FreeCADGui.SendMsgToActiveView("ViewFit")
    settle(2.0)  # the turn is animated
    result["before"] = geometry()
    result["home_looks"] = looks()
    FreeCADGui.runCommand("Aplan_CreateAnalysis")
    detect()
    after_jobs(panel)


def panel():
    result["plan_detected"] = plan()
    FreeCADGui.runCommand("Aplan_Interlocks")
    settle()
    window = FreeCADGui.getMainWindow()
    viewport = task_view_viewport()
    result["cut_off"] = cut_off(viewport) + broken_words(viewport)
    listed = window.findChild(QtGui.QListWidget, "AplanInterlocksList")
    result["entries"] = [listed.item(r).text() for r in range(listed.count())]
    listed.setCurrentRow(0)
    settle()
    does = window.findChild(QtGui.QPlainTextEdit, "AplanInterlockDoes")
    result["details"] = [window.findChild(QtGui.QLabel, n).text() for n in
                         ("AplanInterlockPair", "AplanInterlockRule", "AplanInterlockDecision")] + [
                         does.toPlainText(), does.verticalScrollBar().maximum()]
    result["cut_off_selected"] = cut_off(viewport) + broken_words(viewport)
    result["task_view_width"] = viewport.width()  # settled: with its scroll bar (the panel is taller than the view)
    view = FreeCADGui.ActiveDocument.ActiveView
    FreeCADGui.SendMsgToActiveView("ViewFit")  # as a person does: the two parts and the arrow in the view
    settle()
    result["view_size"] = list(view.getSize())
    view.saveImage(os.path.join(ARTIFACTS, "gui_interlocks_proposal.png"), *view.getSize(), "White")
    viewport.parentWidget().widget().grab().save(os.path.join(ARTIFACTS, "gui_panel_interlocks.png"))
    QtGui.QApplication.primaryScreen().grabWindow(0).save(os.path.join(ARTIFACTS, "gui_interlocks_screen.png"))
    result["selected"] = {{"looks": looks(), "arrows": len(arrows()), "geometry": geometry(),
                          "screen": {{n: on_screen(n) for n in PARTS}}}}
    found = arrows()
    if found:
        from pivy import coin
        (points,) = [found[0].getChild(i) for i in range(found[0].getNumChildren())
                     if found[0].getChild(i).isOfType(coin.SoCoordinate3.getClassTypeId())]
        result["arrow"] = [list(points.point[0].getValue()), list(points.point[1].getValue())]
        box = FreeCAD.ActiveDocument.getObject("Pin").Shape.BoundBox
        result["pin_centre"] = [box.Center.x, box.Center.y, box.Center.z]
        result["arrow_screen"] = [list(view.getPointOnScreen(FreeCAD.Vector(*p))) for p in result["arrow"]]
    undo_before = len(FreeCAD.ActiveDocument.UndoNames)
    window.findChild(QtGui.QPushButton, "AplanAcceptInterlock").click()
    result["entry_accepted"] = listed.item(0).text()
    state().panel.accept()  # OK
    settle()
    result["accepted"] = {{"intent": intent(), "undo": len(FreeCAD.ActiveDocument.UndoNames) - undo_before,
                          "undo_name": FreeCAD.ActiveDocument.UndoNames[0], "geometry": geometry(),
                          "looks": looks(), "arrows": len(arrows()), "plan": plan(),
                          "report": [line for line in window.findChild(QtGui.QDockWidget, "Report view").widget(
                              ).toPlainText().splitlines() if "APLAN: interlock" in line]}}
    FreeCAD.ActiveDocument.undo()
    settle()
    result["undone"] = {{"intent": intent(), "geometry": geometry(), "plan": plan()}}
    # Rejected: nothing applied, the plan refuses the pair.
    FreeCADGui.runCommand("Aplan_Interlocks")
    settle()
    window.findChild(QtGui.QPushButton, "AplanRejectInterlock").click()
    state().panel.accept()
    settle()
    result["rejected"] = {{"intent": intent(), "geometry": geometry(), "plan": plan(), "arrows": len(arrows()),
                          "looks": looks()}}
    captured()


def shown_looks(materials):
    return {{n: [list(m.diffuseColor[0]), round(100 * m.transparency[0])] for n, m in materials.items()}}


def opened(path, then):
    # The document at path with its parts shown (not the booleans' tools), seen isometric; their materials by
    # label; an analysis created and detected, then `then`.
    from freecad_aplan.plan3d import face_materials
    doc = FreeCAD.openDocument(path)
    solids = [o for o in doc.Objects if not o.InList and hasattr(o, "Shape")]
    for o in solids:
        o.ViewObject.Visibility = True
    FreeCADGui.ActiveDocument.ActiveView.viewIsometric()
    FreeCADGui.SendMsgToActiveView("ViewFit")
    settle(2.0)
    MATERIALS.clear()
    MATERIALS.update({{o.Label: face_materials(o)[0] for o in solids}})
    home = shown_looks(MATERIALS)
    FreeCADGui.runCommand("Aplan_CreateAnalysis")
    detect()
    after_jobs(then)
    return home


def first_proposal(picture, names):
    # first_selected, then Cancel (the view as it was, nothing stored).
    shown = first_selected(picture, names)
    state().panel.reject()
    settle()
    return shown


def first_selected(picture, names):
    # The interlocks panel opened, its first proposal selected: what it lists and what the 3D view shows (the
    # view saved as `picture`, the screen boxes of `names`); the panel left open.
    FreeCADGui.runCommand("Aplan_Interlocks")
    settle()
    window = FreeCADGui.getMainWindow()
    listed = window.findChild(QtGui.QListWidget, "AplanInterlocksList")
    listed.setCurrentRow(0)
    FreeCADGui.SendMsgToActiveView("ViewFit")
    settle()
    view = FreeCADGui.ActiveDocument.ActiveView
    view.saveImage(os.path.join(ARTIFACTS, picture), *view.getSize(), "White")
    return {{"entries": [listed.item(r).text() for r in range(listed.count())],
            "summary": window.findChild(QtGui.QLabel, "AplanInterlocksSummary").text(),
            "does": window.findChild(QtGui.QPlainTextEdit, "AplanInterlockDoes").toPlainText(),
            "looks": shown_looks(MATERIALS), "arrows": len(arrows()), "screen": {{n: on_screen(n) for n in names}},
            "cut_off": cut_off(task_view_viewport()) + broken_words(task_view_viewport())}}


def captured():
    # A one-component proposal: the knob captured by the cover, both highlighted together, no arrow.
    result["captured_home"] = opened(CAPTURED, captured_panel)


def captured_panel():
    result["captured"] = first_proposal("gui_interlocks_component.png", ("Cover", "Knob", "Housing"))
    from freecad_aplan.intent import find_analysis, read_intent
    result["captured_closed"] = [shown_looks(MATERIALS), len(arrows()),
                                 read_intent(find_analysis(FreeCAD.ActiveDocument)).interlocks]
    # The support contacts of the closed gearbox: its gears would float in the housing once their shafts are out.
    opened(GEARBOX, gearbox_panel)


def gearbox_panel():
    result["support"] = first_proposal("gui_interlocks_support.png", ("GearA", "Housing"))
    # The machine: the same gearbox on a plate with 20 brackets, too large to judge flat; its workstations do.
    result["machine_home"] = opened(MACHINE, machine_panel)


{level_plan}

def machine_panel():
    # The designer's tree: the planner's proposals (the gearbox one workstation), as the structure panel takes
    # them; then the interlocks panel lists the gearbox level's support contacts, the first is shown in 3D and
    # rejected there, OK stores it: the level's plan then names the gear that would float.
    from freecad_aplan.analysis import analysis_product
    from freecad_aplan.intent import find_analysis, read_intent, update_intent
    from planner.assembly.subassembly_proposals import with_subassemblies
    analysis = find_analysis(FreeCAD.ActiveDocument)
    record = read_intent(analysis).diagrams.get("analysis", {{}})
    result["machine_candidates"] = [c["parts"] for c in record.get("support_candidates", {{}}).get("contacts", [])]
    tree = with_subassemblies(analysis_product(analysis), "auto").subassemblies
    update_intent(analysis, "structure", subassemblies=[{{"id": s.id, "parts": list(s.parts)}} for s in tree])
    result["machine_tree"] = [[s.id, sorted(s.parts)] for s in tree]
    result["level_plan_before"] = level_plan(analysis, "Housing")
    shown = first_selected("gui_interlocks_level_support.png", ("GearA", "Housing"))
    window = FreeCADGui.getMainWindow()
    listed = window.findChild(QtGui.QListWidget, "AplanInterlocksList")
    window.findChild(QtGui.QPushButton, "AplanRejectInterlock").click()
    settle()
    shown["after_reject"] = listed.item(0).text()
    state().panel.accept()
    settle()
    shown["decisions"] = [[d["parts"], d.get("level"), d["decision"]] for d in read_intent(analysis).interlocks]
    shown["plan"] = level_plan(analysis, "Housing")
    shown["closed_looks"] = shown_looks(MATERIALS)
    result["level_support"] = shown
    finish(0)


FreeCADGui.getMainWindow().showMaximized()
QtCore.QTimer.singleShot(1500, guarded(start))
"""


def _in_the_window() -> tuple:
    """The documents the integration tests' jobs build in FreeCADCmd (the press fit and the captured knob:
    tests/integration/interlock_documents.py; the gearbox and the machine: unseen_documents.py), copied here,
    then the GUI script runs on them: (folder, FreeCAD's run); the script's result in folder/result.json. Built
    once for both modules (this job built them again before)."""
    tmp = folder("gui-interlocks")
    for job, names in ((INTERLOCK_DOCUMENTS, ("press_fit", "captured")), (UNSEEN_DOCUMENTS, (GEARBOX, MACHINE))):
        documents, built = job.result()
        for name in names:
            if not (documents / f"{name}.FCStd").is_file():
                return tmp, built
            shutil.copy(documents / f"{name}.FCStd", tmp / f"{name}.FCStd")  # a copy: the window opens it read-write
    ARTIFACTS.mkdir(exist_ok=True)
    script = tmp / "gui_interlocks.py"
    script.write_text(GUI_SCRIPT.format(gui_helpers=GUI_HELPERS, workbench_helpers=WORKBENCH_HELPERS, layout_check=LAYOUT_CHECK,
                                        out=str(tmp / "result.json"), copy=str(tmp / "press_fit.FCStd"),
                                        captured=str(tmp / "captured.FCStd"), gearbox=str(tmp / f"{GEARBOX}.FCStd"),
                                        machine=str(tmp / f"{MACHINE}.FCStd"), artifacts=str(ARTIFACTS),
                                        level_plan=LEVEL_PLAN))
    return tmp, freecad_gui_run(tmp, script, display=170)


#: FreeCAD builds the document and runs the window in the background (tests/background.py).
BACKGROUND = (Job("the interlocks panel in the FreeCAD window", _in_the_window),)


def _region(corners, size) -> tuple[int, int, int, int]:
    """The box (x0, y0, x1, y1) in picture pixels around projected points (the view's y runs up, the picture's
    down)."""
    width, height = size
    xs = [x for x, _ in corners]
    ys = [height - 1 - y for _, y in corners]
    return (max(0, int(min(xs))), max(0, int(min(ys))), min(width, int(max(xs)) + 1), min(height, int(max(ys)) + 1))


def _share(mask, box) -> float:
    x0, y0, x1, y1 = box
    return float(mask[y0:y1, x0:x1].mean())


@pytest.mark.freecad
def test_an_interlock_proposal_shown_accepted_undone_and_rejected():
    require_freecad_gui()
    tmp, done = BACKGROUND[0].result()
    if (tmp / "result.json").is_file():
        shutil.copy(tmp / "result.json", ARTIFACTS / "gui_interlocks_result.json")
    data = freecad_gui_result(done, tmp / "result.json")
    # Detected: the pin and block are interlocked, the plan refuses them until the designer decides.
    kind, text = data["plan_detected"]
    assert kind == "InterlockedPartsError" and "Block and Pin" in text, data["plan_detected"]
    # The panel at the default width: one proposal, the overlap's axis, nothing cut off.
    assert data["cut_off"] == [] and data["task_view_width"] <= 250, data["cut_off"]
    assert data["entries"] == ["Block\n+ Pin\noverlap axis: not decided"]
    pair, rule, decision, does, scroll = data["details"]
    assert pair == "Block\nPin" and rule == "overlap axis" and decision == "not decided"
    assert scroll == 0 and data["cut_off_selected"] == []  # the rule's sentence shows whole
    assert "Pin leaves Block along +Z" in does and "overlap by" in does
    # Selected: the pin orange, the block blue (see-through: it holds the pin), an arrow up from the pin's centre.
    selected = data["selected"]
    assert selected["looks"]["Pin"] == [pytest.approx(list(ORANGE)), 0]
    assert selected["looks"]["Block"] == [pytest.approx(list(BLUE)), 50]
    assert selected["arrows"] == 1 and selected["geometry"] == data["before"]
    start, end = data["arrow"]
    assert start == pytest.approx(data["pin_centre"], abs=1e-6)
    assert end[:2] == pytest.approx(start[:2], abs=1e-6) and end[2] > start[2]
    _assert_proposal_picture(data)
    # Accepted (OK): one undo step; the analysis carries the decision and the mark (the pin moved up does not
    # hit the block), the +Z diagram without it; the plan has its one sequence; the user's document as it was.
    assert data["entry_accepted"] == "Block\n+ Pin\noverlap axis: accepted"
    accepted = data["accepted"]
    assert accepted["undo"] == 1 and accepted["undo_name"] == "APLAN: accept interlock Block and Pin"
    intent = accepted["intent"]
    assert [(d["parts"], d["rule"], d["decision"]) for d in intent["interlocks"]] == [
        (["Block", "Pin"], "overlap", "accepted")]
    assert [(m["blocked"], m["blocking"], m["direction"]) for m in intent["not_blocking"]] == [
        ("Pin", "Block", "+Z")]
    assert intent["directions"] == [] and intent["plus_z"] == [["Block", "Pin"]]
    assert accepted["plan"] == ["planned", 1]
    assert len(accepted["report"]) == 1 and "APLAN: interlock accepted: Block and Pin overlap by" in \
        accepted["report"][0]  # one line (after the report view's time), as the command line says it
    assert accepted["geometry"] == data["before"] and accepted["arrows"] == 0
    assert accepted["looks"] == data["home_looks"]
    # Undone: no decision, no mark, interlocked again; the document as it was.
    undone = data["undone"]
    assert undone["intent"]["interlocks"] == [] and undone["intent"]["not_blocking"] == []
    assert undone["intent"]["plus_z"] == sorted([["Block", "Pin"], ["Pin", "Block"]])
    assert undone["plan"][0] == "InterlockedPartsError" and undone["geometry"] == data["before"]
    # Rejected: recorded, nothing applied, the plan refuses the pair in the words of --interlocks error.
    rejected = data["rejected"]
    assert [d["decision"] for d in rejected["intent"]["interlocks"]] == ["rejected"]
    assert rejected["intent"]["not_blocking"] == [] and rejected["geometry"] == data["before"]
    kind, text = rejected["plan"]
    assert kind == "InterlockRefusedError" and "1 interlocked pair(s), refused by the designer" in text
    assert "the rules would resolve them so: Block and Pin overlap by" in text
    assert rejected["arrows"] == 0 and rejected["looks"] == data["home_looks"]
    _assert_component(data)
    _assert_support(data)
    _assert_level_support(data)


def _assert_level_support(data) -> None:
    """The machine (too large to judge flat): the detection recorded the rule's candidates (the two gears in the
    housing); with the gearbox one workstation, the panel lists its support contacts at that level, the first
    shows the gear and the housing orange together (tests/artifacts/gui_interlocks_level_support.png); rejected
    in the panel and stored on OK, the level's plan names the gear that would float (before: planning added
    both, as the command line does)."""
    assert data["machine_candidates"] == [["GearA", "Housing"], ["GearB", "Housing"]]
    gearbox = next(parts for _, parts in data["machine_tree"] if "Housing" in parts)
    assert len(gearbox) == 14 and not any(p.startswith(("Bracket", "Plate")) for p in gearbox)
    level = next(sid for sid, parts in data["machine_tree"] if parts == gearbox)
    kind, sequences, added = data["level_plan_before"]
    assert kind == "planned" and sequences > 0 and added == [["GearA", "Housing"], ["GearB", "Housing"]]
    shown = data["level_support"]
    assert shown["entries"] == [f"Gear{g} rests in Housing\nat level {level}\nsupport contact: not decided"
                                for g in "AB"]
    assert shown["does"].startswith(f"level {level}: GearA rests in Housing")
    _assert_gear_in_housing(shown, "gui_interlocks_level_support.png")
    assert shown["after_reject"] == f"GearA rests in Housing\nat level {level}\nsupport contact: rejected"
    assert shown["decisions"] == [[["GearA", "Housing"], level, "rejected"]]
    kind, text = shown["plan"][:2]
    assert kind == "NotDisassemblableError" and "GearA" in text, shown["plan"]
    assert shown["closed_looks"] == data["machine_home"]  # the view restored when the panel closed


def _assert_support(data) -> None:
    """The closed gearbox: each gear's support contact listed as "GearA rests in Housing", the first selected
    shows the gear and the housing orange together, the other parts dimmed, no arrow."""
    support = data["support"]
    assert support["entries"] == [f"Gear{g} rests in Housing\nsupport contact: not decided" for g in "AB"]
    _assert_gear_in_housing(support, "gui_interlocks_support.png")


def _assert_gear_in_housing(shown: dict, picture_name: str) -> None:
    """Two support contacts listed, the panel not cut off, and the first shown: GearA and the Housing orange
    together, every other part dimmed, no arrow; in the picture a person sees, the housing's box mostly orange."""
    assert shown["summary"].startswith("2 support contacts for parts that would float; select one")
    assert shown["cut_off"] == [], shown["cut_off"]
    looks = shown["looks"]
    assert looks["GearA"] == looks["Housing"] == [pytest.approx(list(ORANGE)), 0] and shown["arrows"] == 0
    assert all(t == 85 for name, (_, t) in looks.items() if name not in ("GearA", "Housing")), looks
    picture = read_picture(ARTIFACTS / picture_name)
    orange = picture.coloured(hue_of(ORANGE), saturation=0.3)
    housing = _region(shown["screen"]["Housing"], picture.size)
    # The housing orange, the cover see-through over it: measured 0.65 of its projected box; about half of that.
    assert _share(orange, housing) >= 0.3, _share(orange, housing)


def _assert_component(data) -> None:
    """The captured knob: one proposal, one component with the cover; both orange together, the housing and the
    bolts dimmed, no arrow; Cancel puts the view back and stores nothing."""
    captured = data["captured"]
    assert captured["entries"] == ["Cover\n+ Knob\none component: not decided"] and captured["cut_off"] == []
    looks = captured["looks"]
    assert looks["Cover"] == looks["Knob"] == [pytest.approx(list(ORANGE)), 0] and captured["arrows"] == 0
    assert all(t == 85 for name, (_, t) in looks.items() if name not in ("Cover", "Knob"))
    assert data["captured_closed"] == [data["captured_home"], 0, []]
    picture = read_picture(ARTIFACTS / "gui_interlocks_component.png")
    orange = picture.coloured(hue_of(ORANGE), saturation=0.3)
    cover = _region(captured["screen"]["Cover"], picture.size)
    # The cover's (and knob's) orange fills about half its projected box (measured 0.51): about half of that.
    assert _share(orange, cover) >= 0.25, _share(orange, cover)


def _assert_proposal_picture(data) -> None:
    """What a person sees (tests/artifacts/gui_interlocks_proposal.png, white background): the pin's screen
    region mostly orange, the block's mostly blue, and the arrow, thin orange pixels above the pin."""
    picture = read_picture(ARTIFACTS / "gui_interlocks_proposal.png")
    size = picture.size
    assert list(size) == data["view_size"], (size, data["view_size"])
    orange = picture.coloured(hue_of(ORANGE), saturation=0.3)
    blue = picture.coloured(hue_of(BLUE), width=22, saturation=0.2)
    screen = data["selected"]["screen"]
    pin, block = _region(screen["Pin"], size), _region(screen["Block"], size)
    # A box's projected bounding box holds the box's hexagon (3/4 of it, seen isometric) and the white corners;
    # the pin's holds its cylinder (orange above the block, brown seen through it) and the block around it.
    # Thresholds about half of what was measured (orange 0.43 of the pin's region, blue 0.56 of the block's).
    assert _share(orange, pin) >= 0.2, _share(orange, pin)
    assert _share(blue, block) >= 0.3, _share(blue, block)
    # The arrow: from the pin's centre up, drawn over the parts; its screen segment carries orange pixels
    # outside the pin's region (above it).
    (x0, y0), (x1, y1) = data["arrow_screen"]
    height = size[1]
    ys = np.linspace(height - 1 - y0, height - 1 - y1, 50).astype(int)
    xs = np.linspace(x0, x1, 50).astype(int)
    above = [(x, y) for x, y in zip(xs, ys) if y < pin[1] and 0 <= y < height and 0 <= x < size[0]]
    assert len(above) >= 5, (pin, data["arrow_screen"])
    near = [orange[max(0, y - 3):y + 4, max(0, x - 3):x + 4].any() for x, y in above]
    assert np.mean(near) >= 0.8, np.mean(near)
