"""Meshes and the exact engine within a budget (issue 26, items 3 and 4), in real FreeCAD.

One FreeCADCmd process builds the helical spring test document (tests/workbench/spring_document.py: a
Part::Helix swept with a circle around a rod, on a plate, under a washer) and checks:

- the mesh check's work is bounded: at most 1 + MESH_REFINEMENTS methods tried, ``finer`` not run when the
  first mesh times FINER_GROWTH is over the triangle budget; the spring falls back to the rule ``hull``, its
  ring hull holds it and leaves the rod's bore free;
- the exact engine on boxes: a work bound of 0 operations per pair leaves every pair that needs OCCT
  undecided (the far box is decided by its box), an unlimited one none; a time limit certainly exceeded
  (an injected clock that advances a second per reading, a limit of 0.5 s) leaves every selected pair
  undecided, and the merge then keeps the mesh engine's answers for them (content, not timings);
- ``pairs`` restricts the engine to the pairs asked for.

Then ``aplan session SPRING.FCStd --demo 0`` with the default flags, on the document the script built, runs to
the assembled product, and its export names the fallback rule.
"""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from background import Job, folder, run
from conftest import REPO, require_freecadcmd
from integration.freecad_tools import aplan_process, freecad_result

from freecad_aplan.hybrid import merge_reports
from planner.defaults import MESH_REFINEMENTS, MESH_TRIANGLE_BUDGET
from planner.geometry import Tolerances
from planner.geometry.mesh_engine import PartMesh, analyze_meshes
from spring_document import COIL_RADIUS, ROD_RADIUS, WIRE

SCRIPT = r"""
import json, os, sys
sys.path.insert(0, REPO); sys.path.insert(0, os.path.join(REPO, "tests", "workbench"))
import FreeCAD, Part
from spring_document import build_spring_document
from freecad_aplan.document import open_model, read_components
from freecad_aplan.export import export_model
from freecad_aplan.tessellation import FINER_GROWTH
from freecad_aplan.occt import analyze_shapes
V = FreeCAD.Vector
out = {}
path = os.path.join(TMP, "spring_rod.FCStd")
build_spring_document(path)
doc = open_model(path)
shapes = {c.id: c.shape for c in read_components(doc).components}
import MeshPart
out["first_facets"] = MeshPart.meshFromShape(Shape=shapes["Spring"], LinearDeflection=0.05, AngularDeflection=0.25,
                                             Relative=False).CountFacets
out["finer_growth"] = FINER_GROWTH
product, _ = export_model(path, os.path.join(TMP, "spring_bundle"))
out["spring_check"] = product["geometry"]["mesh_check"]["parts"]["Spring"]
out["rules"] = product["geometry"]["mesh_check"]["rules"]
out["warnings"] = product["geometry"]["warnings"]
import Mesh
hull = Mesh.Mesh(os.path.join(TMP, "spring_bundle", "meshes", "Spring.stl"))
radii = [(p.x ** 2 + p.y ** 2) ** 0.5 for p in hull.Points]
out["hull"] = {"r": [min(radii), max(radii)], "z": [min(p.z for p in hull.Points), max(p.z for p in hull.Points)],
               "closed": hull.isSolid()}
# The spring's extent along its axis, exactly: the plate's top and the washer's bottom touch it.
out["spring_z"] = [shapes["Plate"].BoundBox.ZMax, shapes["Washer"].BoundBox.ZMin]
out["spring_volume"] = shapes["Spring"].Volume
out["hull_volume"] = hull.Volume

def box(lo, hi):
    return Part.makeBox(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], V(*lo))
BOXES = [("a", box((0, 0, 0), (10, 10, 10))), ("b", box((10, 0, 0), (20, 10, 10))),
         ("c", box((20, 0, 0), (30, 10, 10))), ("far", box((100, 100, 100), (101, 101, 101)))]
out["steps0"] = analyze_shapes(BOXES, pair_steps=0)
out["steps_free"] = analyze_shapes(BOXES)
ticks = iter(range(10 ** 6))
out["timed"] = analyze_shapes(BOXES, pairs=[("a", "b"), ("b", "c")], time_limit=0.5, clock=lambda: float(next(ticks)))
out["selected"] = analyze_shapes(BOXES, pairs=[("a", "b")])
print("APLAN-RESULT " + json.dumps(out), flush=True)
"""


def _run_script() -> tuple:
    """The budgets script's run and its folder, which holds the spring document the session reads."""
    tmp = folder("budgets")
    script = tmp / "budgets.py"
    script.write_text(f"REPO = {str(REPO)!r}\nTMP = {str(tmp)!r}\n" + SCRIPT)
    return tmp, run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(script)], timeout=1500)


def _session() -> subprocess.CompletedProcess:
    """``aplan session SPRING.FCStd --demo 0`` on the document the budgets script built (built once: the
    session exports it itself, and its warnings are the export's)."""
    documents, built = BACKGROUND[0].result()
    if "APLAN-RESULT" not in built.stdout:
        return built
    tmp = folder("budgets-session")
    return aplan_process("session", str(documents / "spring_rod.FCStd"), "--demo", "0", "--log", str(tmp / "log.jsonl"))


#: The FreeCADCmd runs the fixtures read, done in the background (tests/background.py).
BACKGROUND = (Job("budgets in FreeCAD", _run_script), Job("spring session", _session))


@pytest.fixture(scope="module")
def budgets():
    require_freecadcmd()
    return freecad_result(BACKGROUND[0].result()[1])


def _pairs(report) -> set:
    return {frozenset(p) for p in report}


@pytest.mark.freecad
def test_the_mesh_check_is_bounded_by_work(budgets):
    tried = budgets["spring_check"]["tried"]
    assert len(tried) <= 1 + MESH_REFINEMENTS
    assert [t[0] for t in tried] == ["standard", "finer", "mefisto"][:len(tried)]
    # finer would be over the budget: not run (error None, no time), as the closed-form estimate says.
    assert budgets["first_facets"] * budgets["finer_growth"] > MESH_TRIANGLE_BUDGET
    assert tried[1][1] is None and tried[1][2] == 0.0
    assert budgets["spring_check"]["method"] == "exact"
    assert abs(tried[0][1]) > 0.01  # the spring's first mesh is off by more than 1 %


@pytest.mark.freecad
def test_the_spring_falls_back_to_its_ring_hull(budgets):
    rules = budgets["rules"]
    assert rules["hull"] == ["Spring"] and sorted(rules["mesh"]) == ["Plate", "Rod", "Washer"]
    assert rules["exact"] == [] and rules["box"] == []
    named = [w for w in budgets["warnings"] if w.startswith("Spring:")]
    assert len(named) == 1 and "fallback rule 'hull'" in named[0]
    # The hull holds the spring (conservative for blocking): the wire's radial range around the axis is
    # COIL_RADIUS -/+ WIRE (closed form), its axial range touches the plate and the washer; and the hull
    # leaves the rod's bore free.
    hull, (low, high) = budgets["hull"], budgets["spring_z"]
    assert hull["closed"]
    assert ROD_RADIUS < hull["r"][0] <= COIL_RADIUS - WIRE + 1e-6 and hull["r"][1] >= COIL_RADIUS + WIRE - 1e-6
    assert abs(hull["z"][0] - low) < 1e-4 and abs(hull["z"][1] - high) < 1e-4
    assert budgets["spring_volume"] < budgets["hull_volume"] < 4 * budgets["spring_volume"]


@pytest.mark.freecad
def test_the_exact_engine_is_bounded_per_pair_by_work(budgets):
    # a-b and b-c touch (their contact and overlap need OCCT), a moving along +X meets c (a prism's test);
    # the far box is decided by boxes alone.
    none, free = budgets["steps0"], budgets["steps_free"]
    assert _pairs(none["undecided"]) == {frozenset(("a", "b")), frozenset(("b", "c")), frozenset(("a", "c"))}
    assert free["undecided"] == [] and _pairs(free["contacts"]) == {frozenset(("a", "b")), frozenset(("b", "c"))}
    assert none["pair_steps"] == 0 and not none["timed_out"]


@pytest.mark.freecad
def test_a_time_limit_passed_leaves_pairs_to_the_mesh_answer(budgets):
    timed = budgets["timed"]
    assert timed["timed_out"] and timed["selected"] == 2
    assert _pairs(timed["undecided"]) == {frozenset(("a", "b")), frozenset(("b", "c"))}
    assert any("time limit of 0.5 s" in w for w in timed["warnings"])
    # The merge keeps the mesh engine's answer for the undecided pairs: the same as the meshes alone.
    mesh = analyze_meshes(box_meshes(), Tolerances(directions=0))
    merged = merge_reports(mesh, timed, [("a", "b"), ("b", "c")], "occt", {})
    assert _pairs(merged.contacts) == _pairs(mesh.contacts)
    assert {d: set(p) for d, p in merged.obstructions.items()} == {d: set(p) for d, p in mesh.obstructions.items()}
    record = merged.tolerances["pairs"]
    assert record["occt"] == 0 and record["timed_out"] and record["mesh"] == 6 - 2
    assert sorted(map(tuple, record["undecided"])) == [("a", "b"), ("b", "c")]


@pytest.mark.freecad
def test_only_the_pairs_asked_for_are_decided(budgets):
    selected = budgets["selected"]
    assert selected["selected"] == 1 and selected["contacts"] == [["a", "b"]]
    assert all(_pairs(pairs) <= {frozenset(("a", "b"))} for pairs in selected["obstructions"].values())


def box_meshes() -> list[PartMesh]:
    def box(name, lo, hi):
        lo, hi = np.array(lo, float), np.array(hi, float)
        corners = np.array([[hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]]
                            for i in range(8)])
        faces = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7],
                          [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]])
        return PartMesh(name, corners, faces)
    return [box("a", (0, 0, 0), (10, 10, 10)), box("b", (10, 0, 0), (20, 10, 10)),
            box("c", (20, 0, 0), (30, 10, 10)), box("far", (100, 100, 100), (101, 101, 101))]


@pytest.mark.freecad
def test_the_spring_document_runs_to_the_assembled_product():
    require_freecadcmd()
    session = BACKGROUND[1].result()
    assert session.returncode == 0, session.stdout + session.stderr
    # the session's export names the fallback rule, for the model
    assert "aplan: warning: spring_rod.FCStd: Spring: no tessellation is within 1%" in session.stderr
    assert "fallback rule 'hull'" in session.stderr
    assert "assembled: the product is assembled" in session.stdout
