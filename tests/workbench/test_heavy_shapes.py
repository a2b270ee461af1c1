"""Helical springs of pitch 4 (issue 26, items 3 and 4): the export and the exact engine bounded by work, in
real FreeCAD.

A spring of pitch 4 (10 and 20 turns, tests/workbench/spring_document.py) made ``aplan export-freecad`` run
past 10 minutes and reach 11 GB: its ring hull is 4.4 times its volume (looser than
:data:`freecad_aplan.hull.TIGHT`), so its pairs went to OCCT, which swept its B-spline face as 371,000
triangles, one ``Part.Face`` each. One FreeCADCmd process (a background job, tests/background.py) builds
both documents, exports them and runs the OCCT engine on the 10-turn one, and checks the work, not the clock:

- the mesh check runs one tessellation: ``finer`` over the triangle budget, ``mefisto`` whose edges are
  longer than the wire is thick (closed form: the mean thickness 4 V / A of a wire is its diameter);
- the spring's exact shape is over the OCCT bound (:mod:`freecad_aplan.occt.complexity`), so it falls back to
  its ring hull up to :data:`~freecad_aplan.hull.LOOSE` (rule ``hull``, reported), the ring's volume ratio
  matching its closed form;
- the OCCT engine makes no call on the spring's pairs (undecided at once, the reason named), and decides
  the other pairs exactly as without the spring;
- a sweep over its triangle bound (a cylinder as a B-spline, bound 1) leaves its pair undecided, named;
- a sweep asks its ``stop`` (the time limit) before each face, and is abandoned when it says so;
- a patch swept as triangles that overlaps itself seen along the direction (the torus as NURBS) is refused
  before any face of its prism is built (counted: no ``Part.Face``), a one-to-one patch built as before;
- an open coil (pitch 12) whose ring is looser than :data:`~freecad_aplan.hull.LOOSE` (closed form) is
  exported on its closest mesh (rule ``closest``, named in the warnings), and ``aplan analyze --engine occt``
  decides its pairs on that mesh, none undecided;
- a face OCCT cannot sweep at all (a sphere and a torus as B-splines, in a document built here, each beside a
  box that blocks it along +X) leaves its pairs along that direction undecided, so ``aplan analyze --engine
  occt`` keeps the mesh engine's answer for them, reported per pair: the diagram shows the blocking (before,
  OCCT called them free with a warning only); the run's OCCT bounds come from ``--occt-face-weight`` and
  ``--occt-prism-triangles``.
"""
from __future__ import annotations

import math

import pytest
from background import Job
from conftest import REPO, require_freecadcmd
from integration.freecad_tools import aplan_process, freecad_result, freecadcmd_job, succeeded

from planner import load_product
from planner.defaults import MESH_REFINEMENTS, OCCT_FACE_WEIGHT
from spring_document import COIL_RADIUS, WIRE

PITCH = 4.0
TURNS = (10, 20)
OPEN_PITCH, OPEN_TURNS = 12.0, 5  # an open coil: its ring 13 times its volume (closed form, _ring_ratio)
TIGHT, LOOSE = 4.0, 8.0  # freecad_aplan.hull (it imports FreeCAD)

SCRIPT = r"""
import json, os, sys
sys.path.insert(0, REPO); sys.path.insert(0, os.path.join(REPO, "tests", "workbench"))
import FreeCAD, Part
from spring_document import build_spring_document
from freecad_aplan.document import open_model, read_components
from freecad_aplan.export import export_model
from freecad_aplan.occt import analyze_shapes
from freecad_aplan.occt.complexity import shape_weight
from freecad_aplan.tessellation import mean_thickness, mefisto_edge
V = FreeCAD.Vector
out = {}
# Ball (radius 5) and Torus (radii 8 and 3, 100 mm away along Y), each 0.05 from a box that spans its section
# across +X (closed form: the box's face at x = 5.05 or 11.05 lies within the part's reach across it, so the part
# moving along +X hits it, and along no other axis: no point of the part lies in the box's x range).
NURBS = (("Ball", Part.makeSphere(5).toNurbs()), ("BallBlock", Part.makeBox(10, 4, 4, V(5.05, -2, -2))),
         ("Torus", Part.makeTorus(8, 3, V(0, 100, 0)).toNurbs()), ("TorusBlock", Part.makeBox(10, 4, 2, V(11.05, 98, -1))))
for turns in TURNS:
    path = os.path.join(TMP, f"spring{turns}.FCStd")
    build_spring_document(path, pitch=PITCH, height=PITCH * turns)
    product, _ = export_model(path, os.path.join(TMP, f"bundle{turns}"))
    check = product["geometry"]["mesh_check"]
    doc = open_model(path)
    shapes = {c.id: c.shape for c in read_components(doc).components}
    spring = shapes["Spring"]
    out[str(turns)] = {"check": check["parts"]["Spring"], "rules": check["rules"],
                       "warnings": product["geometry"]["warnings"],
                       "thickness": mean_thickness(spring.Volume, spring.Area), "mefisto_edge": mefisto_edge(spring),
                       "weight": shape_weight(spring)[0]}
    if turns == 10:
        parts = sorted(shapes.items())
        out["occt"] = analyze_shapes(parts)
        out["occt_without"] = analyze_shapes([p for p in parts if p[0] != "Spring"])
        out["occt_asked"] = analyze_shapes(parts, pairs=[["Plate", "Rod"], ["Rod", "Washer"]])
    FreeCAD.closeDocument(doc.Name)
# An open coil (pitch OPEN_PITCH, 10 wire diameters): no mesh within 1 %, its exact shape heavy and its ring looser
# than LOOSE, so it is decided on its closest mesh (rule closest); exported here, analysed by aplan (OPEN_COIL).
from freecad_aplan.hull import LOOSE, ring_hull
from freecad_aplan.tessellation import checked_mesh
path = os.path.join(TMP, "open_coil.FCStd")
build_spring_document(path, pitch=OPEN_PITCH, height=OPEN_PITCH * OPEN_TURNS)
product, _ = export_model(path, os.path.join(TMP, "open_coil"))
doc = open_model(path)
spring = {c.id: c.shape for c in read_components(doc).components}["Spring"]
mesh, _ = checked_mesh(spring, 0.05, 0.25, 0.01)
points = [(p.x, p.y, p.z) for p in mesh.Points]
rings = [ring_hull(points, spring.Volume, 0.05, spring, bound) for bound in (LOOSE, 100.0)]
out["open"] = {"check": product["geometry"]["mesh_check"]["parts"]["Spring"],
               "rules": product["geometry"]["mesh_check"]["rules"], "warnings": product["geometry"]["warnings"],
               "weight": shape_weight(spring)[0], "loose_ring": rings[0] is not None,
               "ring_ratio": rings[1].Volume / spring.Volume if rings[1] is not None else None}
FreeCAD.closeDocument(doc.Name)
# A cylinder as a B-spline: its side face folds with no known silhouette, so it is swept as triangles.
cylinder, block = Part.makeCylinder(5, 10, V(0, 0, -5)).toNurbs(), Part.makeBox(10, 10, 10, V(6, -5, -5))
out["bounded"] = analyze_shapes([("cylinder", cylinder), ("block", block)], prism_triangles=1)
out["free"] = analyze_shapes([("cylinder", cylinder), ("block", block)])
# A sphere and a torus as B-splines, each touching a box that blocks it along +X: OCCT cannot sweep their one
# face along +X (neither exactly nor as triangles); a document, exported here, analysed by aplan (NURBS below).
nurbs = FreeCAD.newDocument("nurbs")
for name, shape in NURBS:
    nurbs.addObject("Part::Feature", name).Shape = shape
nurbs.recompute()
nurbs.saveAs(os.path.join(TMP, "nurbs.FCStd"))
FreeCAD.closeDocument(nurbs.Name)
export_model(os.path.join(TMP, "nurbs.FCStd"), os.path.join(TMP, "nurbs"))
# A part no mesh is right for, whose ring is loose (an L of two thin bars): on its closest mesh when heavy.
import MeshPart
from freecad_aplan.export import fallback_mesh
from freecad_aplan.tessellation import MeshCheck
bars = Part.makeBox(100, 1, 1).fuse(Part.makeBox(1, 100, 1)).removeSplitter()
closest = MeshPart.meshFromShape(Shape=bars, LinearDeflection=0.05, AngularDeflection=0.25, Relative=False)
failed = MeshCheck(-0.02, -0.02, "exact", True, [])
out["bars"] = [fallback_mesh(bars, closest, failed, 0.05, 0.25, face_weight=face)[0] for face in (0, 20000)]
# A sweep is abandoned between two faces once its stop says so (the time limit, in the engine).
from freecad_aplan.occt.prisms import SweepStopped, sweep_prisms
asked = []
try:
    sweep_prisms(block, V(1, 0, 0), 20.0, 0.05, 1e-4, stop=lambda: asked.append(1) or len(asked) > 2)
    out["stopped"] = None
except SweepStopped:
    out["stopped"] = len(asked)
out["unstopped"] = len(sweep_prisms(block, V(1, 0, 0), 20.0, 0.05, 1e-4, stop=lambda: False)[0])
# A patch that overlaps itself along +X (the torus as NURBS) is refused before any face of its prism is built;
# a B-spline cylinder's half is built (one face per facet), as before.
from freecad_aplan.occt.prisms import mesh_prism
built, face_type = [], Part.Face
Part.Face = lambda *arguments: built.append(1) or face_type(*arguments)
out["faces_built"] = {}
for name, shape in (("Torus", NURBS[2][1]), ("cylinder", cylinder)):
    del built[:]
    prism = mesh_prism(shape.Faces[0], V(1, 0, 0), 20.0, 0.025)
    out["faces_built"][name] = [prism is not None, len(built)]
Part.Face = face_type
print("APLAN-RESULT " + json.dumps(out), flush=True)
"""

HEAVY = freecadcmd_job("heavy", lambda tmp: f"REPO = {str(REPO)!r}\nTMP = {str(tmp)!r}\nPITCH = {PITCH!r}\n"
                                            f"TURNS = {TURNS!r}\nOPEN_PITCH = {OPEN_PITCH!r}\n"
                                            f"OPEN_TURNS = {OPEN_TURNS!r}\n" + SCRIPT)
# Bounds above the ball's and the torus' (face weights 270 and 324; 3,288 and 7,044 triangles at 0.05), so
# that they are swept, and below the defaults, so that the run shows they were applied.
BOUNDS = {"face_weight": 1000, "prism_triangles": 10000}


def _analyze_nurbs():
    """`aplan analyze --engine occt` of the NURBS document's bundle (exported by the heavy job): its run."""
    tmp, _ = HEAVY.result()
    return tmp / "nurbs", aplan_process("analyze", str(tmp / "nurbs"), "--engine", "occt", "--directions", "0",
                                        "--occt-face-weight", str(BOUNDS["face_weight"]),
                                        "--occt-prism-triangles", str(BOUNDS["prism_triangles"]))


NURBS_ANALYSIS = Job("aplan analyze --engine occt of a sphere and a torus as NURBS", _analyze_nurbs)
OPEN_COIL = Job("aplan analyze --engine occt of the open coil",
                lambda: aplan_process("analyze", str(HEAVY.result()[0] / "open_coil"), "--engine", "occt",
                                      "--directions", "0"))
BACKGROUND = (HEAVY, NURBS_ANALYSIS, OPEN_COIL)


@pytest.fixture(scope="module")
def heavy():
    require_freecadcmd()
    return freecad_result(HEAVY.result()[1])


def _ring_ratio(turns: int, pitch: float = PITCH) -> float:
    """The ring hull's volume over the spring's, closed form: the ring from COIL_RADIUS - WIRE to + WIRE over
    the height plus the wire's diameter; the spring the circle of radius WIRE in a plane through the axis
    (spring_document) swept along the helix, whose volume is the circle's area times the path of its centre
    around the axis, 2 pi COIL_RADIUS per turn (the pitch moves it along the axis, within its own plane)."""
    height = pitch * turns + 2 * WIRE
    ring = math.pi * ((COIL_RADIUS + WIRE) ** 2 - (COIL_RADIUS - WIRE) ** 2) * height
    tube = math.pi * WIRE ** 2 * turns * 2 * math.pi * COIL_RADIUS
    return ring / tube


@pytest.mark.freecad
@pytest.mark.parametrize("turns", TURNS)
def test_the_mesh_check_runs_one_tessellation(heavy, turns):
    found = heavy[str(turns)]
    tried = found["check"]["tried"]
    assert len(tried) <= 1 + MESH_REFINEMENTS and [t[0] for t in tried] == ["standard", "finer", "mefisto"]
    assert tried[1][1:] == [None, 0.0] and tried[2][1:] == [None, 0.0]  # neither run
    assert abs(found["thickness"] - 2 * WIRE) < 0.01 * 2 * WIRE  # a wire's mean thickness is its diameter
    assert found["mefisto_edge"] > found["thickness"]


@pytest.mark.freecad
@pytest.mark.parametrize("turns", TURNS)
def test_a_heavy_spring_falls_back_to_its_loose_ring(heavy, turns):
    found = heavy[str(turns)]
    check = found["check"]
    assert found["rules"]["hull"] == ["Spring"] and sorted(found["rules"]["mesh"]) == ["Plate", "Rod", "Washer"]
    assert check["weight"] == found["weight"] > OCCT_FACE_WEIGHT
    assert TIGHT < check["hull_ratio"] <= LOOSE
    assert abs(check["hull_ratio"] - _ring_ratio(turns)) < 0.02 * _ring_ratio(turns)
    named = [w for w in found["warnings"] if w.startswith("Spring:")]
    assert len(named) == 1 and "fallback rule 'hull'" in named[0] and f"weight {found['weight']:,}" in named[0]


@pytest.mark.freecad
def test_occt_makes_no_call_on_a_heavy_part(heavy):
    occt, without = heavy["occt"], heavy["occt_without"]
    assert occt["heavy"] == {"Spring": heavy["10"]["weight"]}
    # Every pair of the spring is left to the mesh answer, with the reason, and no other pair.
    assert sorted(map(tuple, occt["undecided"])) == [("Plate", "Spring"), ("Rod", "Spring"), ("Spring", "Washer")]
    relations = {tuple(r) for r in occt["undecided_relations"]}
    assert ("Rod", "Spring", "the contact") in relations and ("Rod", "Spring", "Spring moving along +Z") in relations
    assert len(occt["warnings"]) == 3 and all(f"weight {heavy['10']['weight']:,}, over the bound" in w for w in occt["warnings"])
    # The other pairs are decided as without the spring.
    others = {"Plate", "Rod", "Washer"}
    assert [c for c in occt["contacts"] if set(c) <= others] == without["contacts"]
    for name, pairs in without["obstructions"].items():
        assert [p for p in occt["obstructions"][name] if set(p) <= others] == pairs
    # Asked only for pairs without the spring, it is not heavy for the run.
    asked = heavy["occt_asked"]
    assert asked["heavy"] == {} and asked["undecided"] == [] and asked["contacts"] == [["Plate", "Rod"]]


@pytest.mark.freecad
def test_a_sweep_over_its_triangle_bound_is_undecided(heavy):
    bounded, free = heavy["bounded"], heavy["free"]
    assert free["obstructions"]["+X"] == [["cylinder", "block"]] and free["undecided"] == []
    (part, direction, triangles), = bounded["sweeps_over"]
    assert (part, direction) == ("cylinder", "+X") and triangles > 1
    assert bounded["undecided_relations"] == [["cylinder", "block", "cylinder moving along +X"]]
    assert any(f"{triangles:,} triangles, over the bound of 1" in w for w in bounded["warnings"])
    assert bounded["obstructions"]["+X"] == [["cylinder", "block"]]  # undecided counts as blocking


@pytest.mark.freecad
def test_a_sweep_stops_between_faces(heavy):
    assert heavy["stopped"] == 3  # asked before each of the box's six faces, stopped at the third
    assert heavy["unstopped"] == 1  # a box along +X: the prism of its one face facing backwards


@pytest.mark.freecad
def test_a_patch_that_overlaps_itself_is_refused_before_its_faces_are_built(heavy):
    # The torus' backward half along +X is two bands whose projections overlap (the outer one on the -X side,
    # the inner one on the +X side of the hole): its prism's walls cut through it, found on its triangles
    # (Mesh.hasSelfIntersections) before one Part.Face is made. The cylinder's half projects one-to-one.
    assert heavy["faces_built"]["Torus"] == [False, 0]
    swept, faces = heavy["faces_built"]["cylinder"]
    assert swept and faces > 0


@pytest.mark.freecad
def test_an_open_coil_is_exported_on_its_closest_mesh(heavy):
    # The export of a document, end to end: no mesh within 1 %, heavier than the OCCT bound, and its ring
    # (the closed form, measured within 2 %) looser than LOOSE, so none is taken: rule closest, named.
    found = heavy["open"]
    assert found["rules"]["closest"] == ["Spring"] and sorted(found["rules"]["mesh"]) == ["Plate", "Rod", "Washer"]
    assert found["check"]["rule"] == "closest" and found["check"]["method"] == "exact"
    assert found["check"]["weight"] == found["weight"] > OCCT_FACE_WEIGHT
    ratio = _ring_ratio(OPEN_TURNS, OPEN_PITCH)
    assert ratio > LOOSE and not found["loose_ring"]
    assert abs(found["ring_ratio"] - ratio) < 0.02 * ratio
    named = [w for w in found["warnings"] if w.startswith("Spring:")]
    assert len(named) == 1 and "fallback rule 'closest'" in named[0] and "not conservative for blocking" in named[0]


@pytest.mark.freecad
def test_the_open_coil_s_pairs_are_decided_on_its_mesh_by_both_engines(heavy):
    # Rule closest: OCCT is never asked about the coil's pairs (hybrid.exact_pairs), so none is undecided.
    done = succeeded(OPEN_COIL.result())
    product = load_product(HEAVY.result()[0] / "open_coil" / "product.json")
    pairs = product.geometry["analysis"]["tolerances"]["pairs"]
    assert pairs["mesh"] >= 3 and not [p for p in pairs["undecided"] if "Spring" in p], done.stderr
    assert all("Spring" not in f["parts"] for f in pairs["fallbacks"])
    assert any(c for c in product.contacts if "Spring" in c)  # on its mesh: it rests on the plate


@pytest.mark.freecad
def test_a_heavy_part_without_a_ring_is_decided_on_its_closest_mesh(heavy):
    # bound 0: every face is over it; the default bound: the bars' planes weigh 1, so OCCT decides them.
    # No ring: the L's 12 vertices lie near one circle (a ring 3.7 times its volume), measured exactly 41 times.
    assert heavy["bars"] == ["closest", "exact"]


@pytest.mark.freecad
def test_a_sweep_that_lost_a_face_keeps_the_mesh_answer(heavy):
    bundle, done = NURBS_ANALYSIS.result()
    succeeded(done)
    product = load_product(bundle / "product.json")
    diagrams = {o.direction.name: set(o.blocks) for o in product.obstructions}
    blocked = {("Ball", "BallBlock"), ("Torus", "TorusBlock")}
    assert blocked <= diagrams["+X"]  # each part hits its box moving along +X, and along no other axis
    for axis in ("+Y", "+Z", "-Y", "-Z"):
        assert not diagrams.get(axis, set()) & (blocked | {(b, a) for a, b in blocked}), axis
    analysis = product.geometry["analysis"]
    pairs = analysis["tolerances"]["pairs"]
    assert analysis["engine"] == "occt" and sorted(map(tuple, pairs["undecided"])) == sorted(blocked)
    assert sorted(map(tuple, pairs["sweeps_lost"])) == [("Ball", "+X", 1), ("Torus", "+X", 1)]
    assert {k: pairs[k] for k in BOUNDS} == BOUNDS
    for part, box in sorted(blocked):  # reported per pair, with the reason
        assert any(w.startswith(f"OCCT did not decide {part} moving along +X for '{part}' and '{box}': the sweep "
                                f"of '{part}' along +X lost 1 face piece(s)") and "the mesh engine's answer stands" in w
                   for w in analysis["warnings"]), part
