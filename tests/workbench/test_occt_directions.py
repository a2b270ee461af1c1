"""The exact OCCT engine tests directions besides the axes (issue 13 item 5): a 50 x 30 x 30 block with two
parallel slots inclined by 30 degrees about X, a peg in each (the model of tests/geometry/
test_designer_directions.py). The pegs cannot leave along any axis, leave freely along the slots' direction,
and are blocked along the slots mirrored; the mesh engine's diagrams along both directions are the same."""
from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from background import Job, folder
from conftest import REPO, require_freecadcmd
from integration.freecad_tools import aplan_process, freecad_result, freecadcmd_job, succeeded

from planner import load_product
from planner.geometry import PartMesh, Tolerances, analyze_meshes
from planner.geometry.bundle import apply_report
from planner.product import AXIS_DIRECTIONS, Direction, Part, Product

SLOT = (0.0, -0.5, math.sqrt(3) / 2)      # +Z turned by 30 degrees about X: the slots' direction
MIRROR = (0.0, 0.5, math.sqrt(3) / 2)     # the slots mirrored: the pegs hit the block
PEGS = ("peg1", "peg2")

SCRIPT = r"""
import json, sys
sys.path.insert(0, REPO)
import FreeCAD, Part
from freecad_aplan.occt import analyze_shapes

V = FreeCAD.Vector

def turned_box(extents, x):
    solid = Part.makeBox(*extents, V(*(-e / 2 for e in extents)))
    solid.rotate(V(0, 0, 0), V(1, 0, 0), 30)
    solid.translate(V(x, 0, 0))
    return solid

block = Part.makeBox(50, 30, 30, V(-25, -15, -15))
for x in (-12, 12):
    block = block.cut(turned_box((10, 10, 80), x))
parts = [("block", block), ("peg1", turned_box((10, 10, 60), -12)), ("peg2", turned_box((10, 10, 60), 12))]
document = FreeCAD.newDocument("pegs")
for name, shape in parts:
    document.addObject("Part::Feature", name).Shape = shape
document.saveAs(MODEL)
print("APLAN-RESULT " + json.dumps(analyze_shapes(parts, directions=DIRECTIONS)), flush=True)
"""


PROBE = freecadcmd_job("occt_directions", lambda tmp: f"REPO = {str(REPO)!r}\nDIRECTIONS = {[SLOT, MIRROR]!r}\n"
                                                      f"MODEL = {str(tmp / 'pegs.FCStd')!r}\n" + SCRIPT)
OPTIONS = {"designer": ("--direction", ",".join(str(c) for c in SLOT), "--directions", "0"), "candidates": ()}


def _analyze(options: tuple[str, ...]) -> tuple:
    """`aplan export-freecad --engine none` of the probe's document, then `aplan analyze --engine occt OPTIONS`:
    (bundle, the export's run, the analysis' run or None)."""
    tmp, _ = PROBE.result()
    bundle = folder("pegs") / "pegs"
    exported = aplan_process("export-freecad", str(tmp / "pegs.FCStd"), "-o", str(bundle), "--engine", "none")
    analyzed = aplan_process("analyze", str(bundle), "--engine", "occt", *options) if exported.returncode == 0 \
        else None
    return bundle, exported, analyzed


ANALYSES = {name: Job(f"aplan analyze --engine occt of the pegs ({name})", functools.partial(_analyze, options))
            for name, options in OPTIONS.items()}
#: The FreeCAD runs the tests read, done in the background (tests/background.py).
BACKGROUND = (PROBE, *ANALYSES.values())


@pytest.fixture(scope="module")
def occt() -> dict:
    require_freecadcmd()
    tmp, done = PROBE.result()
    return {**freecad_result(done), "model": str(tmp / "pegs.FCStd")}


@pytest.fixture(scope="module")
def mesh() -> dict:
    trimesh = pytest.importorskip("trimesh")

    def turned_box(extents, x):
        box = trimesh.creation.box(extents=extents,
                                   transform=trimesh.transformations.rotation_matrix(np.radians(30), [1, 0, 0]))
        box.apply_translation((x, 0, 0))
        return box

    block = trimesh.creation.box(extents=(50, 30, 30))
    for x in (-12, 12):
        block = block.difference(turned_box((10, 10, 80), x))
    meshes = {"block": block, "peg1": turned_box((10, 10, 60), -12), "peg2": turned_box((10, 10, 60), 12)}
    parts = [PartMesh(n, np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)) for n, m in meshes.items()]
    return analyze_meshes(parts, Tolerances(directions=0, designer_directions=(SLOT, MIRROR), resolution=512)).as_dict()


def _pairs(report: dict, name: str) -> set[tuple[str, str]]:
    return {tuple(p) for p in report["obstructions"][name]}


@pytest.mark.freecad
def test_pegs_blocked_along_every_axis(occt):
    for axis in ("+X", "+Y", "+Z"):
        pairs = _pairs(occt, axis)
        for peg in PEGS:  # each peg hits the block moving along the axis, or the block hits it
            assert (peg, "block") in pairs or ("block", peg) in pairs, axis


@pytest.mark.freecad
def test_pegs_free_along_the_slots_and_blocked_mirrored(occt):
    slot, mirror = Direction.from_vector(SLOT).name, Direction.from_vector(MIRROR).name
    assert list(occt["obstructions"]) == ["+X", "+Y", "+Z", slot, mirror]
    assert occt["directions"][slot] == pytest.approx(SLOT) and occt["directions"][mirror] == pytest.approx(MIRROR)
    assert _pairs(occt, slot) == set()
    assert _pairs(occt, mirror) == {(p, "block") for p in PEGS} | {("block", p) for p in PEGS}
    assert occt["warnings"] == [] and occt["undecided"] == []


@pytest.mark.freecad
def test_diagrams_along_the_directions_equal_the_mesh_engines(occt, mesh):
    for vector in (SLOT, MIRROR):
        name = Direction.from_vector(vector).name
        assert _pairs(occt, name) == _pairs(mesh, name), name


@pytest.mark.freecad
def test_planner_reads_the_directions_without_a_warning(occt):
    from freecad_aplan.plugin import occt_report
    from planner.product.designer import add_directions

    product, _ = add_directions(Product(tuple(Part(n) for n in ("block", *PEGS)), (), geometry={"analysis": {}}),
                                [",".join(str(c) for c in SLOT)])
    applied = apply_report(product, occt_report(product, occt))
    along = {o.direction.name: o for o in applied.obstructions if o.direction.name not in AXIS_DIRECTIONS}
    assert along[Direction.from_vector(SLOT).name].blocks == ()
    assert not any("does not test" in w for w in applied.geometry["analysis"]["warnings"])


@pytest.mark.freecad
@pytest.mark.parametrize("options", list(OPTIONS))
def test_analyze_with_the_occt_engine_tests_the_slots(occt, options):
    """aplan analyze --engine occt: the designer's direction, or the candidate directions the mesh engine
    finds on the bundle's meshes (the slots' direction among them), are swept exactly."""
    bundle, exported, analyzed = ANALYSES[options].result()
    succeeded(exported)
    succeeded(analyzed)
    product = load_product(bundle / "product.json")
    along = {o.direction.name: o for o in product.obstructions if o.direction.name not in AXIS_DIRECTIONS}
    assert along[Direction.from_vector(SLOT).name].blocks == ()
    analysis = product.geometry["analysis"]
    assert analysis["engine"] == "occt" and not any("does not test" in w for w in analysis["warnings"])
