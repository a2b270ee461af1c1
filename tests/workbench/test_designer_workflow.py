"""The designer's directions and not-blocking marks in the workbench without the GUI (freecad_aplan.workflow) in
FreeCADCmd: a block with a peg in a slot inclined by 30 degrees. Each change is one undo step, re-detection
keeps the marks (applied after the detection), and the document reopens with them."""
from __future__ import annotations

import json
import math

import pytest
from conftest import REPO, require_freecadcmd
from integration.freecad_tools import aplan, freecad_result, freecadcmd_job

from planner import load_product

SCRIPT = r"""
import json, os, subprocess, sys
sys.path.insert(0, {repo!r})
import FreeCAD, Part
from freecad_aplan import workflow
from freecad_aplan.diagrams import relation_rows
from freecad_aplan.intent import create_analysis, find_analysis, read_intent
from planner.errors import PlannerError
TMP = {tmp!r}
out = {{}}

# A 30 mm block with a 10 x 10 slot along (0, -sin 30, cos 30), and a 10 x 10 x 60 peg in it.
turn = FreeCAD.Placement(FreeCAD.Vector(0, 0, 0), FreeCAD.Rotation(FreeCAD.Vector(1, 0, 0), 30))
def turned(x, y, z):
    box = Part.makeBox(x, y, z, FreeCAD.Vector(-x / 2, -y / 2, -z / 2))
    return box.transformGeometry(turn.toMatrix())
doc = FreeCAD.newDocument("wedge")
block = doc.addObject("Part::Feature", "Block")
block.Shape = Part.makeBox(30, 30, 30, FreeCAD.Vector(-15, -15, -15)).cut(turned(10, 10, 80))
block.Label = "block"
peg = doc.addObject("Part::Feature", "Peg")
peg.Shape = turned(10, 10, 60)
peg.Label = "peg"
doc.recompute()
doc.UndoMode = 1
analysis = create_analysis(doc)

def undo_names():
    return list(doc.UndoNames)

def error(call):
    steps = len(doc.UndoNames)
    try:
        call()
    except PlannerError as exc:
        return [type(exc).__name__, str(exc), len(doc.UndoNames) == steps]
    return None

def job(folder):
    command = workflow.worker_command("analyze", "mesh")
    done = subprocess.run(command, capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, APLAN_BATCH=json.dumps({{"action": "analyze", "folder": folder,
                                                                        "engine": "mesh"}})))
    return [l for l in done.stdout.splitlines() if l.startswith(("APLAN-RESULT", "APLAN-ERROR"))][-1]

def detect(name):
    folder = os.path.join(TMP, name)
    os.mkdir(folder)
    workflow.export_for_detection(doc, folder)
    out[name + "_job"] = job(folder)
    workflow.store_detection(analysis, folder)
    return json.load(open(os.path.join(folder, "product.json")))

# Directions: bad ones refused with nothing changed; one added is one undo step; a duplicate is merged.
out["zero"] = error(lambda: workflow.add_analysis_direction(analysis, "0,0,0"))
out["nan"] = error(lambda: workflow.add_analysis_direction(analysis, "1,nan,0"))
out["added"] = workflow.add_analysis_direction(analysis, "0,-1,1.7320508")
out["directions"] = read_intent(analysis).directions
out["add_step"] = undo_names()[0]
out["duplicate"] = workflow.add_analysis_direction(analysis, "0,1,-1.7320508")
doc.undo()
out["after_undo"] = read_intent(analysis).directions
doc.redo()
out["after_redo"] = read_intent(analysis).directions
# Detection with the candidate directions switched off in the engine? No: the designer direction is tested
# besides them (the slot's, merged with the candidate found on the peg).
first = detect("first")
out["first_designer"] = first["geometry"]["designer"]
out["first_obstructions"] = first["obstructions"]
out["not_detected_mark"] = None
rows = [r for r in relation_rows(read_intent(analysis).diagrams) if r[0] == "blocks +Z"]
out["z_rows"] = rows
out["contact_mark"] = error(lambda: workflow.mark_not_blocking(analysis, [("contact", "block", "peg")]))
out["missing_mark"] = error(lambda: workflow.mark_not_blocking(analysis, [("blocks +Y", "peg", "nothing")]))
before = len(relation_rows(read_intent(analysis).diagrams))
out["mark_notes"] = workflow.mark_not_blocking(analysis, [rows[0]])
out["mark_step"] = undo_names()[0]
out["rows_after_mark"] = len(relation_rows(read_intent(analysis).diagrams)) - before
out["marks"] = read_intent(analysis).not_blocking
doc.undo()
out["undo_mark"] = [read_intent(analysis).not_blocking, len(relation_rows(read_intent(analysis).diagrams)) - before]
doc.redo()
# Detected again: the marked relation stays out, and the analysis says it was released.
second = detect("second")
out["second_designer"] = [second["geometry"]["designer"], second["geometry"]["analysis"]["designer"]]
out["second_rows"] = len(relation_rows(read_intent(analysis).diagrams)) - before
product = workflow.analysis_product(analysis)
out["product_designer"] = [dict(product.geometry.get("designer", {{}})),
                           dict(product.geometry.get("analysis", {{}}).get("designer", {{}}))]
# Unmarked: the relation is back (one step); undo marks it again.
workflow.unmark_not_blocking(analysis, [rows[0]])
out["unmark"] = [read_intent(analysis).not_blocking, len(relation_rows(read_intent(analysis).diagrams)) - before,
                 undo_names()[0]]
out["unmark_again"] = error(lambda: workflow.unmark_not_blocking(analysis, [rows[0]]))
doc.undo()
# Saved and reopened: the directions and marks come back.
saved = [read_intent(analysis).directions, read_intent(analysis).not_blocking]
path = os.path.join(TMP, "wedge.FCStd")
doc.saveAs(path)
FreeCAD.closeDocument(doc.Name)
doc = FreeCAD.openDocument(path)
analysis = find_analysis(doc)
out["reopened"] = [read_intent(analysis).directions, read_intent(analysis).not_blocking] == saved
print("APLAN-RESULT " + json.dumps(out))
"""


#: The FreeCADCmd run the test reads, done in the background (tests/background.py).
BACKGROUND = (freecadcmd_job("designer", lambda tmp: SCRIPT.format(repo=str(REPO), tmp=str(tmp))),)


@pytest.mark.freecad
def test_directions_and_marks_in_the_workflow(tmp_path):
    require_freecadcmd()
    tmp, done = BACKGROUND[0].result()
    data = freecad_result(done)
    slot = [0.0, -0.5, math.sqrt(3) / 2]
    assert data["zero"][0] == "GeometryError" and "zero vector" in data["zero"][1] and data["zero"][2]
    assert "finite" in data["nan"][1] and data["nan"][2]
    assert data["added"] == [] and data["directions"] == [pytest.approx(slot)]
    assert data["add_step"] == "APLAN: add direction 0, -0.5, 0.866025"
    assert data["duplicate"] == ["direction [0, 0.5, -0.866025] merged with the designer direction "
                                 "[0, -0.5, 0.866025] (within 2 degrees; a direction stands for its reverse too)"]
    assert data["after_undo"] == [] and data["after_redo"] == [pytest.approx(slot)]
    # The detection tested the designer's direction: nothing blocks along the slot.
    assert data["first_designer"]["directions"] == [pytest.approx(slot)]
    along = [o for o in data["first_obstructions"] if isinstance(o["direction"], list)]
    assert along[0]["direction"] == pytest.approx(slot) and along[0]["blocks"] == []   # the designer's first
    assert all(abs(sum(a * b for a, b in zip(o["direction"], slot))) < 0.99 for o in along[1:])  # none repeats it
    # Marks: a contact or a relation the diagrams do not hold is refused, nothing changed.
    assert data["contact_mark"][:2] == ["RelationError", "contact block - peg: only an obstruction can be marked "
                                                         "not blocking"] and data["contact_mark"][2]
    assert "the diagrams do not hold it" in data["missing_mark"][1] and data["missing_mark"][2]
    z = data["z_rows"][0]
    assert data["mark_notes"] == [] and data["rows_after_mark"] == -1
    assert data["mark_step"] == f"APLAN: mark {z[1]} blocked by {z[2]} along +Z not blocking"
    assert data["marks"] == [{"blocked": z[1], "blocking": z[2], "direction": "+Z", "source": "designer"}]
    assert data["undo_mark"] == [[], 0]
    # Re-detection keeps the mark: the relation is detected, then released.
    designer, record = data["second_designer"]
    assert designer["not_blocking"] == data["marks"] and record["released"] == [[z[1], z[2], "+Z"]]
    assert data["second_rows"] == -1
    assert data["product_designer"][0]["not_blocking"] == data["marks"]
    assert data["product_designer"][1]["released"] == [[z[1], z[2], "+Z"]]
    assert data["unmark"] == [[], 0, f"APLAN: unmark {z[1]} blocked by {z[2]} along +Z"]
    assert "no such designer mark" in data["unmark_again"][1] and data["unmark_again"][2]
    assert data["reopened"] is True
    assert load_product(tmp / "second" / "product.json").geometry["designer"]["not_blocking"] == data["marks"]
    # The saved document through aplan export-freecad: its analysis' direction and mark go into the product
    # (geometry.designer), the detection (candidate directions off) tests the direction and applies the mark.
    bundle = tmp_path / "bundle"
    done = aplan("export-freecad", str(tmp / "wedge.FCStd"), "-o", str(bundle), "--directions", "0",
                 "--resolution", "512", "--direction", "0,0,1")
    assert "direction +Z merged with the axis +Z" in done.stdout
    exported = load_product(bundle / "product.json")
    assert exported.geometry["designer"]["directions"] == [pytest.approx(slot, abs=1e-6)]
    assert exported.geometry["designer"]["not_blocking"] == data["marks"]
    assert exported.geometry["analysis"]["designer"]["released"] == [[z[1], z[2], "+Z"]]
    figures = json.loads(aplan("stats", str(bundle), "--json").stdout)
    assert figures["sequences"] == 1 and figures["designer"]["released"] == [[z[1], z[2], "+Z"]]
