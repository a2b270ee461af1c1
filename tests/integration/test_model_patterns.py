"""--exclude and --group patterns match labels, never FreeCAD's internal names (issue 22, item 8): an A2plus
document names its parts ``b_LABEL_``, so ``--exclude 'b*'`` matched every part and then said "the document
has no solids". A small document built in FreeCADCmd with such names, read with each pattern. And the first
command on the truck (item 10): `aplan stats` without an option gives figures."""
from __future__ import annotations

import json
import os

import pytest
from conftest import PEN_MODELS, REPO, require_freecadcmd, require_shared
from real_models import JOBS, real_bundle

from integration.freecad_tools import aplan, freecad_result, freecadcmd_job

SCRIPT = """
import json, sys
sys.path.insert(0, {repo!r})
import FreeCAD
from freecad_aplan.document import DocumentError, read_components
doc = FreeCAD.newDocument("patterns")
# Three boxes in a row, named as A2plus names its parts (b_LABEL_), labelled plate, bracket, screw_1.
for k, label in enumerate(("plate", "bracket", "screw_1")):
    box = doc.addObject("Part::Box", "b_" + label + "_"); box.Label = label
    box.Placement.Base = FreeCAD.Vector(10 * k, 0, 0)
doc.recompute()
cases = {{"b*": {{"exclude": ["b*"]}}, "exact name": {{"exclude": ["b_plate_"]}}, "all": {{"exclude": ["*"]}},
         "all, two patterns": {{"exclude": ["p*", "[bs]*"]}}, "names only": {{"exclude": ["b_*"]}},
         "group of names": {{"groups": {{"g": ["b_*"]}}}}, "group": {{"groups": {{"g": ["plate", "b*"]}}}}}}
out = {{}}
for name, options in cases.items():
    try:
        out[name] = sorted(c.id for c in read_components(doc, **options).components)
    except DocumentError as exc:
        out[name] = "error: " + str(exc)
print("APLAN-RESULT " + json.dumps(out))
"""

JOB = freecadcmd_job("patterns", lambda tmp: SCRIPT.format(repo=str(REPO)))
#: The FreeCADCmd run the tests read, done in the background (tests/background.py).
BACKGROUND = (JOB, JOBS["toy_truck"])


@pytest.fixture(scope="module")
def read() -> dict:
    require_freecadcmd()
    _, done = JOB.result()
    return freecad_result(done)


@pytest.mark.freecad
def test_patterns_match_labels_not_internal_names(read):
    assert read["b*"] == ["plate", "screw_1"]         # bracket only, not every b_..._ object
    assert read["exact name"] == ["bracket", "screw_1"]  # an exact internal name still names its object
    assert read["group"] == ["g", "screw_1"]
    for case, pattern in (("names only", "exclude 'b_*'"), ("group of names", "group 'g': 'b_*'")):
        assert read[case].startswith("error: ") and f"{pattern} matches no object" in read[case], read[case]
        assert "labels" in read[case]


@pytest.mark.freecad
def test_patterns_that_leave_nothing_say_which_left_out_what(read):
    assert "no solid is left to plan with: --exclude '*' leaves out 3 (plate, bracket, screw_1)" in read["all"]
    two = read["all, two patterns"]
    assert "--exclude 'p*' leaves out 1 (plate)" in two and "--exclude '[bs]*' leaves out 2 (bracket, screw_1)" in two
    assert "has no solids" not in read["all"] and "\n" not in read["all"]



@pytest.mark.freecad
def test_the_first_command_on_the_truck_gives_figures():
    """No option: the truck (no fastener tags, no containers) is planned with the planner's proposals, says so
    in one note, and every workstation's figures are computed: the same as asking for the proposals."""
    bundle = str(real_bundle("toy_truck"))
    done = aplan("stats", bundle, "--json")
    notes = [line for line in done.stderr.splitlines() if "planning with the planner's proposals" in line]
    assert len(notes) == 1 and "--fasteners tagged --subassemblies designer turns this off" in notes[0]
    report = json.loads(done.stdout)
    assert len(report["levels"]) > 1 and all(row["intentions"] for row in report["levels"])
    assert report["total"]["parts"] == 61 and report["total"]["intentions"] is not None
    asked = aplan("stats", bundle, "--json", "--fasteners", "auto", "--subassemblies", "auto")
    assert json.loads(asked.stdout) == report


@pytest.mark.freecad
def test_a_pattern_that_leaves_nothing_on_the_command_line(tmp_path):
    """`aplan stats MODEL.FCStd --exclude '*'`: exit 1, one line naming the file, the pattern and the fix, no
    traceback, nothing printed on standard output."""
    require_freecadcmd()
    pen = str(require_shared(PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"))
    done = aplan("stats", pen, "--exclude", "*", check=False)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 1 and "Traceback" not in done.stderr and len(lines) == 1, done.stderr
    named = os.path.realpath(pen)  # the reader names the document by its real path (../shared may be a link)
    assert lines[0].startswith(f"aplan: error: {named}: no solid is left to plan with: --exclude '*' leaves out 6")
    assert "exclude fewer objects" in lines[0] and done.stdout == ""
