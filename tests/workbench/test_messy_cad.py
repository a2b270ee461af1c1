"""Messy real CAD in real FreeCAD: meshes checked against their B-reps, parts attached to parts, and the
exact engine's per-pair budget.

One FreeCADCmd process builds the documents and runs everything (about 40 s):

- a chamfered pin (Part::Cylinder + Part::Chamfer) and part 14_001 of the diaphragm pump in
  ../shared, whose cone face FreeCAD 0.20's default mesher meshes only in part (the first mesh is 30 %
  short after hole filling): after the check, every mesh is within 1 % of its B-rep and the warning names
  the part;
- an Assembly4-style document, parts attached to each other with Attacher (Support, MapMode) and placed by
  an expression, beside a real boolean and a closed shell without a solid: every part is exported (the
  shell as the solid it bounds), the operands are named in a warning;
- the OCCT engine with a zero budget for one pair: that pair is reported undecided, the others decided.
"""
from __future__ import annotations

import shutil
import subprocess

import pytest
from background import Job, folder, run
from conftest import REPO, SHARED, require_freecadcmd, require_shared
from integration.freecad_tools import freecad_result

PUMP = SHARED / "models" / "diaphragm_pump" / "asm_diaphragm_pump.FCStd"

SCRIPT = r"""
import json, os, sys
sys.path.insert(0, REPO)
import FreeCAD, Part
from freecad_aplan.document import Component, open_model, read_components
from freecad_aplan.export import export_components, export_model
from freecad_aplan.tessellation import checked_mesh
from freecad_aplan.occt import analyze_shapes
V = FreeCAD.Vector
out = {}

# 1. Meshes against B-reps.
pump = open_model(PUMP)
housing = next(c for c in read_components(pump).components if c.id == "14_001")
doc = FreeCAD.newDocument("pins")
cylinder = doc.addObject("Part::Cylinder", "Cylinder"); cylinder.Radius = 5; cylinder.Height = 30
doc.recompute()
pin = doc.addObject("Part::Chamfer", "Pin"); pin.Base = cylinder
pin.Edges = [(i + 1, 1.0, 1.0) for i, e in enumerate(cylinder.Shape.Edges) if e.Curve.TypeId == "Part::GeomCircle"]
cylinder.Visibility = False
part = doc.addObject("Part::Feature", "Part14"); part.Shape = housing.shape
doc.recompute()
result = read_components(doc)
warnings = list(result.warnings)
product = export_components(result.components, os.path.join(TMP, "pins"), "pins.FCStd", warnings)
out["ids"] = [c.id for c in result.components]
out["check"] = product["geometry"]["mesh_check"]
out["warnings"] = product["geometry"]["warnings"]
import Mesh
out["written"] = {p["id"]: Mesh.Mesh(os.path.join(TMP, "pins", p["mesh"])).Volume / p["volume"] - 1
                  for p in product["parts"]}
_, strict = checked_mesh(pin.Shape, 0.05, 0.25, tolerance=1e-9, methods=("standard", "finer"))
out["strict"] = strict.as_dict()

# 2. Parts attached to parts.
asm = FreeCAD.newDocument("attached")
base = asm.addObject("Part::Box", "Base"); base.Length = 40; base.Width = 40; base.Height = 5
previous = base
for k in range(3):
    block = asm.addObject("Part::FeaturePython", f"Block{k}")
    block.addExtension("Part::AttachExtensionPython")
    block.Shape = Part.makeBox(10, 10, 5)
    block.Support = [(previous, "Face6")]
    block.MapMode = "FlatFace"
    previous = block
peg = asm.addObject("Part::Cylinder", "Peg"); peg.Radius = 1; peg.Height = 4
peg.Support = [(base, "Face6")]; peg.MapMode = "FlatFace"
peg.AttachmentOffset = FreeCAD.Placement(V(30, 30, 0), FreeCAD.Rotation())
screw = asm.addObject("Part::Cylinder", "Screw"); screw.Radius = 0.5; screw.Height = 3
screw.setExpression(".Placement.Base.x", "Peg.Placement.Base.x + 5 mm")
plate = asm.addObject("Part::Box", "Plate"); plate.Length = 10; plate.Width = 10; plate.Height = 2
plate.Placement.Base = V(-20, 0, 0)
hole = asm.addObject("Part::Cylinder", "Hole"); hole.Radius = 2; hole.Height = 2; hole.Placement.Base = V(-15, 5, 0)
cut = asm.addObject("Part::Cut", "Drilled"); cut.Base = plate; cut.Tool = hole
shell = asm.addObject("Part::Feature", "Shell"); shell.Shape = Part.makeBox(2, 3, 4, V(-40, 0, 0)).Shells[0]
sheet = asm.addObject("Part::Feature", "Sheet"); sheet.Shape = Part.makePlane(3, 3, V(-50, 0, 0))
asm.recompute()
path = os.path.join(TMP, "attached.FCStd")
asm.saveAs(path)
out["inlists"] = {o.Name: sorted(u.Name for u in o.InList) for o in asm.Objects}
FreeCAD.closeDocument(asm.Name)
product, _ = export_model(path, os.path.join(TMP, "attached"))
out["attached"] = {p["id"]: p["volume"] for p in product["parts"]}
out["attached_warnings"] = product["geometry"]["warnings"]

# 3. The exact engine's budget: a zero budget for one pair.
def box(lo, hi):
    return Part.makeBox(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], V(*lo))
parts = [("a", box((0, 0, 0), (10, 10, 10))), ("b", box((10, 0, 0), (20, 10, 10))),
         ("c", box((20, 0, 0), (30, 10, 10))), ("far", box((100, 100, 100), (101, 101, 101)))]
lines = []
out["budget"] = analyze_shapes(parts, budgets={("a", "b"): 0.0}, progress=lines.append)
out["budget_free"] = analyze_shapes(parts)
out["progress"] = lines
print("APLAN-RESULT " + json.dumps(out), flush=True)
"""


def _run_script() -> subprocess.CompletedProcess:
    tmp = folder("messy")
    script = tmp / "messy.py"
    script.write_text(f"REPO = {str(REPO)!r}\nTMP = {str(tmp)!r}\nPUMP = {str(PUMP)!r}\n" + SCRIPT)
    return run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(script)])


#: The FreeCADCmd run the fixture reads, done in the background (tests/background.py).
BACKGROUND = (Job("messy CAD in FreeCAD", _run_script),)


@pytest.fixture(scope="module")
def messy():
    require_freecadcmd()
    require_shared(PUMP)
    return freecad_result(BACKGROUND[0].result())


@pytest.mark.freecad
def test_meshes_within_one_percent_of_their_breps(messy):
    check = messy["check"]
    assert messy["ids"] == ["Pin", "Part14"] and check["tolerance"] == 0.01
    housing, pin = check["parts"]["Part14"], check["parts"]["Pin"]
    # The housing's first mesh (FreeCAD 0.20's Standard mesher) is far off: the failure is reproduced ...
    assert housing["tried"][0][0] == "standard" and housing["tried"][0][1] < -0.05
    # ... and another method gets it within 1 %, in the file written too.
    assert housing["method"] != "standard" and abs(housing["volume_error"]) <= 0.01
    assert abs(housing["area_error"]) <= 0.01
    assert pin["method"] == "standard" and abs(pin["volume_error"]) <= 0.01
    assert all(abs(error) <= 0.01 for error in messy["written"].values()), messy["written"]
    assert check["exact"] == []
    named = [w for w in messy["warnings"] if w.startswith("Part14: the mesh differed from the B-rep")]
    assert len(named) == 1 and f"re-tessellated with {housing['method']}" in named[0]
    assert not any(w.startswith("Pin:") for w in messy["warnings"])


@pytest.mark.freecad
def test_a_part_no_mesher_gets_right_is_marked_for_the_exact_engine(messy):
    strict = messy["strict"]
    assert strict["method"] == "exact" and [tried[0] for tried in strict["tried"]] == ["standard", "finer"]
    assert strict["closed"] and 0 < abs(strict["volume_error"]) < 0.01


@pytest.mark.freecad
def test_attached_parts_are_all_exported(messy):
    inlists = messy["inlists"]
    # The failure's setting: parts that others are attached to are in their InList.
    assert inlists["Base"] == ["Block0", "Peg"] and inlists["Block0"] == ["Block1"] and inlists["Peg"] == ["Screw"]
    assert sorted(messy["attached"]) == ["Base", "Block0", "Block1", "Block2", "Drilled", "Peg", "Screw", "Shell"]
    assert messy["attached"]["Shell"] == 24  # a closed shell without a solid: the solid it bounds
    assert messy["attached"]["Base"] == 8000 and messy["attached"]["Block2"] == 500
    assert "Shell: has 6 faces in closed shells but no solid; read as the solid they bound (make it a solid in " \
        "FreeCAD to silence this)" in messy["attached_warnings"]
    assert any(w.startswith("Sheet: has 1 faces but no solid") for w in messy["attached_warnings"])
    left_out = [w for w in messy["attached_warnings"] if w.startswith("not parts of their own")]
    assert len(left_out) == 1
    assert "Plate (used by Drilled.Base)" in left_out[0] and "Hole (used by Drilled.Tool)" in left_out[0]


@pytest.mark.freecad
def test_occt_pair_budget(messy):
    budget, free = messy["budget"], messy["budget_free"]
    assert free["contacts"] == [["a", "b"], ["b", "c"]] and free["undecided"] == []
    # The pair a-b gets no time: reported undecided (counted as touching and blocking), the rest decided.
    assert budget["undecided"] == [["a", "b"]]
    assert budget["contacts"] == [["a", "b"], ["b", "c"]]
    assert budget["obstructions"]["+X"] == free["obstructions"]["+X"] == [["a", "b"], ["a", "c"], ["b", "c"]]
    assert [w for w in budget["warnings"] if w.startswith("OCCT did not decide")] == [
        "OCCT did not decide the contact, a moving along +X for 'a' and 'b' within the budget of 0 CPU s per pair "
        "(spent 0.0 s, 0 operations); counted as touching and blocking: check this pair (or raise --pair-budget, "
        "--time-limit)"]
    assert budget["pairs"]["far"] >= 3 and any("pairs" in line for line in messy["progress"])
