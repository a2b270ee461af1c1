"""Assemblies in the styles public CAD comes in, built by FreeCAD here (tests/integration/unseen_documents.py),
from the file with the default flags (issue 26, "Must show": assemblies never seen before):

- every part found: PartDesign Bodies (the hinge), App::Part containers with nested placements and an
  App::Link array of bolts (the coupling: one part per element, placed by the containers above the array;
  also with the elements not shown as objects),
  Part primitives and booleans (the vise, a closed gearbox), Draft polar arrays of 40 bolts and 40 nuts (the bolt circle: one
  part per element, 82 parts), the coupling exported to STEP and read back, and a STEP file of the coupling as
  one body of ten solids (one part per solid: one part leaves nothing to assemble);
- the obstruction diagrams equal the ground truth derived from the construction (exactly touching faces and
  0.05 mm clearances included);
- a container of parts that do not touch each other (``Bolts``, ``Nuts``) is no subassembly: the coupling's
  session runs from its ``.FCStd`` to the assembled product, and says so in one line per container;
- a closed gearbox whose gears float once their shafts are out: its session runs from its ``.FCStd`` to the
  assembled product with a support contact per gear, said in one line;
- the same gearbox on a machine's base plate with 20 brackets (35 parts, too large for the support-contact rule
  to judge flat): planned as workstations with the default flags, the gearbox's workstation gets the support
  contacts (one line naming it) and every workstation's session runs to its assembled product.

One FreeCADCmd process builds the documents, ``aplan export-freecad`` exports each (about 3 s each); the
coupling's, the gearbox's and the machine's sessions run from their ``.FCStd`` (exporting it themselves), each in a process and
a folder of its own; all in the background.
"""
from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from aplan_runner import run_aplan
from background import ENVIRONMENT, Job, folder, run
from conftest import REPO, require_freecadcmd

from integration.freecad_tools import freecad_result
from integration.unseen_documents import DOCUMENTS, GEARBOX, GROUND_TRUTH, MACHINE, ONE_BODY, STEP_NAMES

def _build() -> tuple[Path, subprocess.CompletedProcess]:
    """FreeCAD builds the documents; then ``aplan export-freecad`` with the default flags exports each (and the
    STEP file) to ``NAME_bundle``, as a user would; the first run that fails is the result."""
    from integration.unseen_documents import SCRIPT

    tmp = folder("unseen-docs")
    script = tmp / "unseen_docs.py"
    script.write_text(f"TMP = {str(tmp)!r}\nREPO = {str(REPO)!r}\n" + SCRIPT)
    done = run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(script)])
    (tmp / "build.out").write_text(done.stdout)
    models = [(tmp / f"{name}.FCStd", tmp / f"{name}_bundle") for name in DOCUMENTS]
    steps = [(tmp / "coupling.step", tmp / "step_bundle"), (tmp / "one_body.step", tmp / "one_body_bundle"),
             (tmp / "coupling_hidden.FCStd", tmp / "hidden_bundle")]
    for model, bundle in models + steps:
        if done.returncode != 0:
            break
        done = run([sys.executable, "-m", "planner", "export-freecad", str(model), "-o", str(bundle)], cwd=tmp,
                   env={**ENVIRONMENT, "PYTHONPATH": str(REPO)})
    return tmp, done


def _session(name: str) -> tuple[Path, subprocess.CompletedProcess]:
    """``aplan session NAME.FCStd --demo 0`` with no flags, in a folder of its own."""
    documents, built = BACKGROUND[0].result()
    here = folder(f"unseen-{name}")
    if built.returncode != 0:
        return here, built
    done = run([sys.executable, "-m", "planner", "session", str(documents / f"{name}.FCStd"), "--demo", "0"],
               cwd=here, env={**ENVIRONMENT, "PYTHONPATH": str(REPO)})
    return here, done


BACKGROUND = (Job("unseen documents in FreeCAD", _build),
              Job("aplan session coupling.FCStd", lambda: _session("coupling")),
              Job("aplan session gearbox.FCStd", lambda: _session(GEARBOX)),
              Job("aplan session machine.FCStd", lambda: _session(MACHINE)))


@pytest.fixture(scope="module")
def built() -> Path:
    require_freecadcmd()
    tmp, done = BACKGROUND[0].result()
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return tmp


@pytest.mark.freecad
def test_link_array_elements_are_grouped_and_excluded_by_their_labels(built):
    result = freecad_result(subprocess.CompletedProcess([], 0, (built / "build.out").read_text(), ""))
    assert result["coupling_grouped"] == {"FA": 1, "FB": 1, "Nut1": 1, "Nut2": 1, "Nut3": 1, "bolts": 4}


def _diagrams(bundle: Path, names: dict[str, str] | None = None) -> tuple[list[str], dict[str, set]]:
    product = json.loads((bundle / "product.json").read_text())
    name = (names or {}).get
    found = {entry["direction"]: {(name(a, a), name(b, b)) for a, b in entry["blocks"]}
             for entry in product["obstructions"] if isinstance(entry["direction"], str)}
    return [name(p["id"], p["id"]) for p in product["parts"]], found


@pytest.mark.freecad
@pytest.mark.parametrize("name", DOCUMENTS)
def test_every_part_found_and_the_diagrams_equal_the_ground_truth(built, name):
    parts, found = _diagrams(built / f"{name}_bundle")
    truth = GROUND_TRUTH[name]
    assert sorted(parts) == sorted({p for pairs in truth.values() for pair in pairs for p in pair})
    assert {axis: found.get(axis, set()) for axis in truth} == truth


@pytest.mark.freecad
@pytest.mark.parametrize("bundle, names", [("step_bundle", STEP_NAMES), ("hidden_bundle", {})],
                         ids=["STEP", "link array elements not shown"])
def test_the_coupling_read_back_from_step_and_with_hidden_link_elements(built, bundle, names):
    parts, found = _diagrams(built / bundle, names)
    assert sorted(parts) == sorted(_diagrams(built / "coupling_bundle")[0])
    assert {axis: found.get(axis, set()) for axis in GROUND_TRUTH["coupling"]} == GROUND_TRUTH["coupling"]


@pytest.mark.freecad
def test_a_step_file_of_one_body_of_many_solids_is_one_part_per_solid(built):
    parts, found = _diagrams(built / "one_body_bundle", ONE_BODY)
    assert sorted(parts) == sorted(ONE_BODY.values())
    assert {axis: found.get(axis, set()) for axis in GROUND_TRUTH["coupling"]} == GROUND_TRUTH["coupling"]
    warnings = json.loads((built / "one_body_bundle" / "product.json").read_text())["geometry"]["warnings"]
    assert "Coupling: the document's only part holds 10 solids: read as one part per solid (one part leaves " \
        "nothing to assemble); group them in FreeCAD to plan them otherwise" in warnings
    assert not any("solids are read as one part" in w for w in warnings)


@pytest.mark.freecad
def test_containers_of_parts_that_do_not_touch_are_no_subassemblies(built):
    product = json.loads((built / "coupling_bundle" / "product.json").read_text())
    # The document's structure as written: the link array (its elements) and the nuts' container.
    assert {s["id"]: len(s["parts"]) for s in product["subassemblies"]} == {"Bolt": 4, "Nuts": 4}
    done = run_aplan("stats", built / "coupling_bundle")
    assert done.returncode == 0, done.stderr
    for container, first in (("Bolt", "Bolt_i0"), ("Nuts", "Nut1")):
        assert (f"the document's container {container} holds members that do not touch each other (4 groups: "
                f"{{{first}}};") in done.stderr
    # The Draft arrays of the bolt circle: each a container of its 40 elements, dissolved the same way.
    done = run_aplan("stats", built / "bolt_circle_bundle")
    assert done.returncode == 0, done.stderr
    assert "fasteners folded: 80 parts in 1 groups" in done.stdout
    for container in ("Bolts", "Nuts"):
        assert f"the document's container {container} holds members that do not touch each other (40 groups: " \
            in done.stderr


@pytest.mark.freecad
def test_the_coupling_session_from_its_document_with_the_default_flags(built):
    here, done = BACKGROUND[1].result()
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert re.search(r"^assembled: the product is assembled", done.stdout, re.M), done.stdout[-2000:]
    assert len(re.findall(r"container \w+ holds members that do not touch", done.stderr)) == 2
    assert any(p.suffix == ".jsonl" for p in here.iterdir())


@pytest.mark.freecad
def test_the_closed_gearbox_session_adds_a_support_contact_per_gear(built):
    here, done = BACKGROUND[2].result()
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert re.search(r"^assembled: the product is assembled", done.stdout, re.M), done.stdout[-2000:]
    lines = [line for line in done.stderr.splitlines() if line.startswith("aplan: support contacts: ")]
    assert len(lines) == 1, done.stderr[-3000:]
    # Each gear sits in the housing's cavity (open at the top once the cover is off: 5 of the 6 directions).
    assert lines[0].startswith("aplan: support contacts: GearA rests in Housing (inside its box, walled in along 5 "
                               "of the 6 axis directions); GearB rests in Housing (")
    assert "cannot be disassembled" not in done.stderr


@pytest.mark.freecad
def test_the_machine_plans_the_gearbox_workstation_with_its_support_contacts(built):
    here, done = BACKGROUND[3].result()
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    levels = re.findall(r"^level (\S+) \(\d+ of (\d+)\): (.*)$", done.stdout, re.M)
    assert len(levels) == int(levels[0][1]) > 1, done.stdout[-2000:]  # planned as workstations
    assert len(re.findall(r"^assembled: the product is assembled", done.stdout, re.M)) == len(levels)
    # The gearbox is one workstation: its 14 parts (the screws installed there), nothing of the plate's.
    gearbox = [(level, members.split(", ")) for level, _, members in levels if "Housing" in members.split(", ")]
    assert len(gearbox) == 1 and sorted(gearbox[0][1]) == sorted(
        {p for pairs in GROUND_TRUTH[GEARBOX].values() for pair in pairs for p in pair})
    lines = [line for line in done.stderr.splitlines() if line.startswith("aplan: support contacts: ")]
    assert len(lines) == 1, done.stderr[-3000:]
    assert lines[0].startswith(f"aplan: support contacts: level {gearbox[0][0]}: GearA rests in Housing (inside its "
                               "box, walled in along 5 of the 6 axis directions); GearB rests in Housing (")
    assert "cannot be disassembled" not in done.stderr and "cannot be built on its own" not in done.stderr
    assert len([p for p in here.iterdir() if p.suffix == ".jsonl"]) == len(levels)  # a log per workstation
