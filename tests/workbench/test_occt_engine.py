"""The exact OCCT engine (freecad_aplan.occt) in real FreeCAD: closed-form shapes and the four pen models.

One FreeCADCmd process runs everything (about 15 s): small solids with known answers, then the pen exported
from the simplified and complex models, as FreeCAD documents and as STEP files, against the ground truth.
"""
from __future__ import annotations

import json
import re
import shutil
import subprocess

import pytest
from background import Job, folder, run
from conftest import PEN_MODELS, REPO, require_freecadcmd, require_shared
from planner.defaults import OCCT_FACE_WEIGHT

VARIANTS = [(v, ext) for v in ("simplified", "complex") for ext in ("FCStd", "stp")]
LIAISONS = {frozenset(p) for p in [("ink_001", "cartridge_001"), ("cartridge_001", "head_001"),
                                   ("head_001", "body_001"), ("body_001", "cap_001"), ("body_001", "button_001")]}

SCRIPT = r"""
import hashlib, json, os, shutil, sys
sys.path.insert(0, REPO)
import FreeCAD, Part
from freecad_aplan.export import export_model
from freecad_aplan.occt import BrepError, analyze_bundle_breps, analyze_shapes

V = FreeCAD.Vector
out = {}

def box(lo, hi):
    return Part.makeBox(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], V(*lo))

def x_cylinder(radius, x0, x1, inner=0.0):
    solid = Part.makeCylinder(radius, x1 - x0, V(x0, 0, 0), V(1, 0, 0))
    if inner:
        solid = solid.cut(Part.makeCylinder(inner, x1 - x0 + 2, V(x0 - 1, 0, 0), V(1, 0, 0)))
    return solid

def fingerprint(shape):
    return hashlib.sha1(shape.exportBrepToString().encode()).hexdigest()

cases = {
    "stacked": [("bottom", box((0, 0, 0), (10, 10, 2))), ("top", box((2, 2, 2), (8, 8, 4)))],
    "peg": [("tube", x_cylinder(10, 0, 50, inner=4)), ("peg", x_cylinder(4, -20, 30))],
    "sheet": [("block", box((0, 0, 0), (5, 5, 5))), ("sheet", box((105, -10, -10), (105.05, 15, 15)))],
    "small_overlap": [("a", box((0, 0, 0), (10, 10, 10))), ("b", box((9.999, 0, 0), (20, 10, 10)))],
    "large_overlap": [("a", box((0, 0, 0), (10, 10, 10))), ("b", box((9, 0, 0), (20, 10, 10)))],
    "gap": [("a", box((0, 0, 0), (1, 1, 1))), ("b", box((1.05, 0, 0), (2, 1, 1)))],
    "ball_in_cup": [("cup", box((-6, -6, -6), (6, 6, 6)).cut(Part.makeSphere(5))), ("ball", Part.makeSphere(5))],
}
before = {name: [fingerprint(s) for _, s in parts] for name, parts in cases.items()}
out["cases"] = {name: analyze_shapes(parts) for name, parts in cases.items()}
out["cases"]["gap_tight"] = analyze_shapes(cases["gap"], contact=0.01)
out["untouched"] = all([fingerprint(s) for _, s in parts] == before[name] for name, parts in cases.items())

out["pen"] = {}
for key, model in MODELS.items():
    folder = os.path.join(TMP, key)
    export_model(model, folder)
    out["pen"][key] = analyze_bundle_breps(folder)

broken = os.path.join(TMP, "broken")
shutil.copytree(os.path.join(TMP, "simplified_FCStd"), broken)
os.remove(os.path.join(broken, "breps", "ink_001.brep"))
try:
    analyze_bundle_breps(broken)
    out["missing"] = None
except BrepError as exc:
    out["missing"] = str(exc)
print("APLAN-RESULT " + json.dumps(out), flush=True)
"""


def ground_truth(variant: str, axis: str) -> set[tuple[str, str]]:
    path = require_shared(PEN_MODELS / variant / "GroundTruth" / f"GeomConstraints_POS_{axis[1]}.json")
    return {(link["source"], link["target"]) for link in json.loads(path.read_text())["links"]}


def _run_probe() -> subprocess.CompletedProcess:
    tmp = folder("occt")
    models = {f"{v}_{ext}": str(PEN_MODELS / v / f"asm_bourjault_ballpoint.{ext}") for v, ext in VARIANTS}
    script = tmp / "occt_probe.py"  # not a standard module's name: FreeCADCmd imports the script by its name
    script.write_text(f"REPO = {str(REPO)!r}\nTMP = {str(tmp)!r}\nMODELS = {models!r}\n" + SCRIPT)
    return run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(script)])


#: The FreeCADCmd run the fixture reads, done in the background (tests/background.py).
BACKGROUND = (Job("the OCCT engine on shapes and the pens", _run_probe),)


@pytest.fixture(scope="module")
def occt():
    require_freecadcmd()
    for v, ext in VARIANTS:
        require_shared(PEN_MODELS / v / f"asm_bourjault_ballpoint.{ext}")
    done = BACKGROUND[0].result()
    found = re.search(r"APLAN-RESULT (.*)", done.stdout)
    assert found, f"no result from FreeCAD:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return json.loads(found.group(1))


def pairs(report: dict, axis: str) -> set[tuple[str, str]]:
    return {tuple(p) for p in report["obstructions"][axis]}


@pytest.mark.freecad
def test_report_layout(occt):
    report = occt["cases"]["stacked"]
    assert set(report) == {"engine", "parts", "contacts", "interferences", "obstructions", "tolerances",
                           "warnings", "seconds", "undecided", "pairs", "pair_budget", "pair_steps", "time_limit",
                           "timed_out", "selected", "undecided_relations", "heavy", "face_weight",
                           "prism_triangles", "sweeps_over", "sweeps_lost"}
    assert report["undecided"] == [] and report["pair_budget"] == 30.0
    assert report["heavy"] == {} and report["sweeps_over"] == report["sweeps_lost"] == []
    assert report["face_weight"] == OCCT_FACE_WEIGHT
    assert report["timed_out"] is False and report["undecided_relations"] == [] and report["selected"] is None
    assert report["engine"] == "occt" and report["parts"] == 2 and list(report["obstructions"]) == ["+X", "+Y", "+Z"]
    assert report["tolerances"]["contact"] == 0.1 and report["warnings"] == []


@pytest.mark.freecad
def test_stacked_boxes_touch_and_block_one_way(occt):
    report = occt["cases"]["stacked"]
    assert report["contacts"] == [["bottom", "top"]] and report["interferences"] == []
    assert pairs(report, "+Z") == {("bottom", "top")}
    assert pairs(report, "+X") == set() and pairs(report, "+Y") == set()


@pytest.mark.freecad
def test_peg_slides_along_its_axis_only(occt):
    report = occt["cases"]["peg"]
    assert report["contacts"] == [["tube", "peg"]] and report["interferences"] == []
    assert pairs(report, "+X") == set()
    assert pairs(report, "+Y") == pairs(report, "+Z") == {("tube", "peg"), ("peg", "tube")}


@pytest.mark.freecad
def test_ball_leaves_its_cup_nowhere(occt):
    # Curved faces seen side on are split along their silhouettes before they are swept.
    report = occt["cases"]["ball_in_cup"]
    assert report["contacts"] == [["cup", "ball"]] and report["warnings"] == []
    for axis in ("+X", "+Y", "+Z"):
        assert pairs(report, axis) == {("cup", "ball"), ("ball", "cup")}, axis


@pytest.mark.freecad
def test_thin_obstacle_far_ahead(occt):
    report = occt["cases"]["sheet"]
    assert pairs(report, "+X") == {("block", "sheet")} and report["contacts"] == []


@pytest.mark.freecad
def test_interference_is_contact_and_reported_above_the_tolerance(occt):
    small, large = occt["cases"]["small_overlap"], occt["cases"]["large_overlap"]
    assert small["contacts"] == [["a", "b"]] and small["interferences"] == []
    assert pairs(small, "+X") == {("a", "b")} and pairs(small, "+Y") == set()  # the shared sliver does not block
    ((interference),) = large["interferences"]
    assert interference["parts"] == ["a", "b"] and interference["volume"] == pytest.approx(100.0, rel=1e-6)
    assert "interpenetrate by 100 cubic units" in large["warnings"][0]
    assert pairs(large, "+Y") == set() and pairs(large, "+Z") == set()


@pytest.mark.freecad
def test_gap_within_the_contact_tolerance(occt):
    assert occt["cases"]["gap"]["contacts"] == [["a", "b"]]
    assert occt["cases"]["gap_tight"]["contacts"] == []


@pytest.mark.freecad
def test_input_shapes_are_not_modified(occt):
    assert occt["untouched"]


@pytest.mark.freecad
@pytest.mark.parametrize("variant, ext", VARIANTS)
def test_pen_models_give_the_ground_truth(occt, variant, ext):
    report = occt["pen"][f"{variant}_{ext}"]
    assert report["engine"] == "occt" and report["parts"] == 6
    assert {frozenset(c) for c in report["contacts"]} == LIAISONS
    assert report["interferences"] == [], "the button's 0.06 mm^3 overlap with the body is contact only"
    assert report["warnings"] == []
    for axis in ("+X", "+Y", "+Z"):
        assert pairs(report, axis) == ground_truth(variant, axis), axis


@pytest.mark.freecad
def test_missing_brep_names_the_part_and_the_file(occt):
    assert occt["missing"] is not None
    assert "part 'ink_001'" in occt["missing"] and "ink_001.brep" in occt["missing"]
