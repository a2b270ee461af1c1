"""A FreeCAD document's structure becomes the product's subassemblies (issue 13, item 2): App::Part containers
nesting Part::Box parts and an object of two solids split into parts, built in real FreeCAD, exported, then
planned one workstation at a time; the truck's proposed workstations."""
from __future__ import annotations

import json
import shutil
from dataclasses import replace

import pytest
from background import Job, folder, run
from conftest import REPO, require_freecadcmd
from real_models import JOBS, real_bundle

from integration.freecad_tools import aplan, aplan_process, freecad_result, succeeded
from planner.api import resolve_product
from planner.assembly.hierarchy import level_statistics
from planner.assembly.subassembly_proposals import propose_subassemblies
from planner.product import Obstruction

STRUCTURED = """
import json, os, sys
sys.path.insert(0, {repo!r})
import FreeCAD, Part
doc = FreeCAD.newDocument("asm"); doc.saveAs({path!r})
def box(name, x, container=None):
    b = doc.addObject("Part::Box", name); b.Length = b.Width = b.Height = 10; b.Placement.Base = FreeCAD.Vector(x, 0, 0)
    if container is not None:
        container.addObject(b)
# Five boxes in a row along X (each touches the next): A and B in Wheel, Wheel and C in Frame; D alone in
# Lonely (a container of one part is no subassembly); E at the top.
frame = doc.addObject("App::Part", "Frame"); frame.Label = "Frame"
wheel = doc.addObject("App::Part", "Wheel"); frame.addObject(wheel)
lonely = doc.addObject("App::Part", "Lonely")
spare = doc.addObject("App::DocumentObjectGroup", "Spare")  # an empty group: no subassembly
box("A", 0, wheel); box("B", 10, wheel); box("C", 20, frame); box("D", 30, lonely); box("E", 40)
# One object holding two solids (as an A2plus sub-assembly import does): split, a subassembly of its own.
pair = doc.addObject("Part::Feature", "Pair")
pair.Shape = Part.makeCompound([Part.makeBox(10, 10, 10, FreeCAD.Vector(x, 0, 0)) for x in (50, 60)])
doc.recompute(); doc.save()
from freecad_aplan.containers import document_subassemblies
from freecad_aplan.document import read_components
result = read_components(doc, split_solids=True)
print("APLAN-RESULT " + json.dumps(document_subassemblies(doc, result.components)))
"""


def _structured_export() -> tuple:
    """The document of STRUCTURED built in FreeCADCmd, then `aplan export-freecad --split-solids`: (folder,
    the script's run, the export's run or None); the bundle in folder/b."""
    tmp = folder("structured")
    script = tmp / "structured.py"
    script.write_text(STRUCTURED.format(repo=str(REPO), path=str(tmp / "asm.FCStd")))
    built = run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(script)])
    exported = aplan_process("export-freecad", str(tmp / "asm.FCStd"), "-o", str(tmp / "b"), "--split-solids") \
        if "APLAN-RESULT" in built.stdout else None
    return tmp, built, exported


#: The exports the tests read, done in the background (tests/background.py).
BACKGROUND = (Job("a document with App::Part containers, built and exported", _structured_export), *JOBS.values())


@pytest.mark.freecad
def test_app_part_containers_become_subassemblies():
    require_freecadcmd()
    tmp, done, exported = BACKGROUND[0].result()
    assert freecad_result(done) == [
        {"id": "Wheel", "parts": ["A", "B"], "label": "Wheel", "source": "designer"},
        {"id": "Frame", "parts": ["Wheel", "C"], "label": "Frame", "source": "designer"},
        {"id": "Pair", "parts": ["Pair_001", "Pair_002"], "label": "Pair", "source": "designer"}]
    # Exported and planned: Wheel (a chain of 2), Frame (Wheel - C), Pair (a chain of 2), top (Frame - D - E -
    # Pair, a chain of 4).
    succeeded(exported)
    product = json.loads((tmp / "b" / "product.json").read_text())
    assert [g["id"] for g in product["subassemblies"]] == ["Wheel", "Frame", "Pair"]
    data = json.loads(aplan("stats", str(tmp / "b"), "--json").stdout)
    assert [(level["level"], level["members"]) for level in data["levels"]] == [
        ("Wheel", ["A", "B"]), ("Frame", ["Wheel", "C"]), ("Pair", ["Pair_001", "Pair_002"]),
        ("top", ["D", "E", "Frame", "Pair"])]
    assert [(level["subassemblies"], level["operations"], level["sequences"]) for level in data["levels"]] == [
        (3, 1, 1), (3, 1, 1), (3, 1, 1), (10, 10, 6)]  # chains of 2, 2, 2 and 4: n(n+1)/2, C(n+1, 3), (n-1)!
    assert data["flat"]["sequences"] == 720  # a chain of 7 planned flat: 6!
    # --subassemblies none plans it flat; --level picks one workstation.
    flat = json.loads(aplan("stats", str(tmp / "b"), "--subassemblies", "none", "--json").stdout)
    assert flat["sequences"] == 720 and "levels" not in flat
    top = json.loads(aplan("stats", str(tmp / "b"), "--level", "top", "--json").stdout)
    assert top["parts"] == 4 and top["sequences"] == 6


def _without_screws(product):
    """The product without its wood screws (item 1 of issue 13 folds them into operations instead)."""
    ids = {p.id for p in product.parts if not p.id.startswith("wood_screw")}
    return replace(product, parts=tuple(p for p in product.parts if p.id in ids),
                   contacts=tuple(c for c in product.contacts if set(c) <= ids),
                   obstructions=tuple(Obstruction(o.direction, tuple(b for b in o.blocks if set(b) <= ids))
                                      for o in product.obstructions))


@pytest.mark.freecad
def test_truck_workstations():
    """The truck without its 39 screws (22 parts, 36 contacts) has no structure in its document (A2plus: a flat
    list of parts); the proposal cuts it into workstations of at most 8 members from the connection diagram,
    and the cabin's workstation is counted in seconds (the flat product is refused by the size guard)."""
    exported = resolve_product(real_bundle("toy_truck"))  # analysed by the export (the mesh engine)
    assert exported.subassemblies == ()
    product = _without_screws(exported)
    assert (len(product.parts), len(product.contacts)) == (22, 36)
    groups = propose_subassemblies(product, 8)
    assert [set(g.parts) for g in groups] == [
        {"chassis_001", "cabin_door_001", "cabin_door_002", "cabin_back_001", "cabin_hood_001", "cabin_bumper_001",
         "wheel_arch_001", "wheel_arch_002"},
        {"cabin_roof_001", "cabin_flashlight_001"},
        {"drum_support_bottom_001", "drum_support_side_001", "drum_support_side_002", "drum_support_back_001",
         "drum_support_front_001", "drum_001"},
        {"tire_001", "tire_002", "tire_003", "tire_004", "tire_005", "tire_006", "sa1", "sa2"}]
    figures = {level.id: stats for level, stats in level_statistics(replace(product, subassemblies=groups))}
    assert list(figures) == ["sa3", "sa1", "sa2", "sa4", "top"]
    cabin = figures["sa1"]
    assert (cabin.subassemblies, cabin.operations, cabin.states, cabin.state_edges, cabin.intentions,
            cabin.sequences) == (186, 1280, 1048, 5511, 437579, 164270)
