"""The plan in 3D without the GUI (freecad_aplan.plan3d in FreeCADCmd, on a copy of the pen): a step of the
exploded view moves the parts by the planner's offsets, and restoring puts every placement back bit for bit,
with no undo step and no recompute mark left. Colours need the GUI: tests/workbench/test_gui_plan3d.py."""
from __future__ import annotations

import json
import shutil
import subprocess

import pytest
from conftest import PEN_MODELS, REPO, require_freecadcmd, require_shared
from integration.freecad_tools import freecad_result

from planner import api, product_to_dict

PEN = PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"


def pen_diagrams() -> dict:
    """The embedded pen's diagrams over the document's component ids (ink -> ink_001, ...) and objects
    (b_ink_001_, ...): the plan the detection on this document gives (tests/workbench/test_gui.py)."""
    data = product_to_dict(api.resolve_product("pen"))
    text = json.dumps({"parts": [p["id"] for p in data["parts"]], "contacts": data["contacts"],
                       "obstructions": data["obstructions"],
                       "volumes": {p["id"]: p["volume"] for p in data["parts"]}})
    for part in data["parts"]:
        text = text.replace(f'"{part["id"]}"', f'"{part["id"]}_001"')
    diagrams = json.loads(text)
    diagrams["objects"] = {p: [f"b_{p}_"] for p in diagrams["parts"]}
    return diagrams


SCRIPT = """
import json, os, sys
sys.path.insert(0, {repo!r})
import FreeCAD
from planner import api
from freecad_aplan import workflow
from freecad_aplan.intent import create_analysis, update_intent
from freecad_aplan.plan3d import SceneChanges, component_objects, extent, step_looks
out = {{}}
doc = FreeCAD.openDocument({model!r})
doc.UndoMode = 1
analysis = create_analysis(doc)
update_intent(analysis, "diagrams", diagrams={diagrams!r})
doc.recompute()
steps = len(doc.UndoNames)


def placements():
    return {{o.Name: [list(o.Placement.Base), list(o.Placement.Rotation.Q)] for o in doc.Objects
            if hasattr(o, "Placement") and o.Name.startswith("b_")}}


before = placements()
objects = component_objects(doc, {diagrams!r})
out["objects"] = {{p: [o.Name for o in objs] for p, objs in objects.items()}}
unrecorded = dict({diagrams!r}, objects={{}}, parts={diagrams!r}["parts"] + ["lid_001"])
out["by_label"] = {{p: [o.Name for o in objs] for p, objs in component_objects(doc, unrecorded).items()}}
plan = api.plan_of(workflow.analysis_product(analysis))
spacing = extent([o for objs in objects.values() for o in objs])
view = api.plan_in_3d(plan, 0, spacing)
out["spacing"] = spacing
out["offsets"] = view.offsets[0]
out["offsets3"] = view.offsets[3]
scene = SceneChanges(doc)
scene.apply(objects, view.offsets[0], step_looks(view.roles(0)))
out["moved"] = placements()
out["undo_while_shown"] = len(doc.UndoNames) - steps
scene.apply(objects, view.offsets[3], step_looks(view.roles(3)))
out["moved3"] = placements()
status = {{o.Name: o.getPropertyStatus("Placement") for o in doc.Objects if o.Name.startswith("b_")}}
scene.restore()
scene.restore()
out["status_kept"] = status == {{o.Name: o.getPropertyStatus("Placement") for o in doc.Objects if o.Name.startswith("b_")}}
out["restored"] = placements() == before
out["undo_after"] = len(doc.UndoNames) - steps
out["touched"] = [o.Name for o in doc.Objects if hasattr(o, "isTouched") and o.isTouched()]
out["before"] = before
from freecad_aplan.plan3d import orthographic_fit
V = FreeCAD.Vector
corners = [V(x, y, z) for x in (0, 4) for y in (0, 1) for z in (0, 2)]  # 4 wide, 1 high, 2 deep
fits = [orthographic_fit([V(1, 0, 0), V(0, 1, 0), V(0, 0, 1)], corners, aspect) for aspect in (2, 0.5, 8)]
out["fits"] = [[list(position), focal, height] for position, focal, height in fits]
print("APLAN-RESULT " + json.dumps(out))
"""


@pytest.mark.freecad
def test_a_step_moves_the_parts_and_restore_puts_them_back(tmp_path):
    freecadcmd = require_freecadcmd()
    copy = tmp_path / "pen.FCStd"
    shutil.copy(require_shared(PEN), copy)
    script = tmp_path / "plan3d.py"
    script.write_text(SCRIPT.format(repo=str(REPO), model=str(copy), diagrams=pen_diagrams()))
    done = subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=120, check=False)
    data = freecad_result(done)
    assert data["objects"] == {p: [f"b_{p}_"] for p in pen_diagrams()["parts"]}
    assert data["by_label"] == data["objects"]  # without the detection's record: by label; no object, left out
    # The pen is about 250 mm long: the exploded parts sit one bounding-box diagonal away per step to come.
    assert 200 < data["spacing"] < 300
    for moved, offsets in ((data["moved"], data["offsets"]), (data["moved3"], data["offsets3"])):
        for part, objects in data["objects"].items():
            (name,) = objects
            shift = [a - b for a, b in zip(moved[name][0], data["before"][name][0])]
            assert shift == pytest.approx(offsets[part], abs=1e-9), part
            assert moved[name][1] == data["before"][name][1]  # moved, never turned
    assert any(any(abs(c) > 1 for c in v) for v in data["offsets"].values())
    assert data["undo_while_shown"] == 0 and data["undo_after"] == 0
    assert data["restored"] is True and data["touched"] == [] and data["status_kept"] is True
    # The camera fit, closed form on a box 4 x 1 x 2 seen along -z: centred, in front, the larger projected side
    # fitting (width 4 over aspect 2 = 2 > height 1; on a view twice as high the height goes on the width: 4).
    wide, tall, flat = data["fits"]
    assert wide[0] == pytest.approx([2, 0.5, 4]) and wide[1:] == pytest.approx([3, 2.2])
    assert tall[2] == pytest.approx(4.4)
    assert flat[2] == pytest.approx(1.1)  # aspect 8: the height 1 decides
