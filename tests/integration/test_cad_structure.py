"""A FreeCAD document's structure becomes the product's subassemblies (issue 13, item 2): App::Part containers
nesting Part::Box parts, built in real FreeCAD, exported, then planned one workstation at a time."""
from __future__ import annotations

import json
import subprocess

import pytest
from conftest import REPO, require_freecadcmd

from integration.freecad_tools import aplan, freecad_result

STRUCTURED = """
import json, os, sys
sys.path.insert(0, {repo!r})
import FreeCAD
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
doc.recompute(); doc.save()
from freecad_aplan.document import document_subassemblies, read_components
result = read_components(doc)
print("APLAN-RESULT " + json.dumps(document_subassemblies(doc, result.components)))
"""


@pytest.mark.freecad
def test_app_part_containers_become_subassemblies(tmp_path):
    freecadcmd = require_freecadcmd()
    model = tmp_path / "asm.FCStd"
    script = tmp_path / "structured.py"
    script.write_text(STRUCTURED.format(repo=str(REPO), path=str(model)))
    done = subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=300, check=False)
    assert freecad_result(done) == [
        {"id": "Wheel", "parts": ["A", "B"], "label": "Wheel", "source": "designer"},
        {"id": "Frame", "parts": ["Wheel", "C"], "label": "Frame", "source": "designer"}]
    # Exported and planned: Wheel (a chain of 2), Frame (Wheel - C), top (Frame - D - E, a chain of 3).
    aplan("export-freecad", str(model), "-o", str(tmp_path / "b"))
    product = json.loads((tmp_path / "b" / "product.json").read_text())
    assert [g["id"] for g in product["subassemblies"]] == ["Wheel", "Frame"]
    data = json.loads(aplan("stats", str(tmp_path / "b"), "--json").stdout)
    assert [(level["level"], level["members"]) for level in data["levels"]] == [
        ("Wheel", ["A", "B"]), ("Frame", ["Wheel", "C"]), ("top", ["D", "E", "Frame"])]
    assert [(level["subassemblies"], level["operations"], level["sequences"]) for level in data["levels"]] == [
        (3, 1, 1), (3, 1, 1), (6, 4, 2)]  # chains of 2, 2 and 3: n(n+1)/2, C(n+1, 3), (n-1)!
    assert data["flat"]["sequences"] == 24  # a chain of 5 planned flat: 4!
    # --subassemblies none plans it flat; --level picks one workstation.
    flat = json.loads(aplan("stats", str(tmp_path / "b"), "--subassemblies", "none", "--json").stdout)
    assert flat["sequences"] == 24 and "levels" not in flat
    top = json.loads(aplan("stats", str(tmp_path / "b"), "--level", "top", "--json").stdout)
    assert top["parts"] == 3 and top["sequences"] == 2
