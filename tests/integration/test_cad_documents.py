"""Exports that read back, from every kind of document (issue 26, items 2 and 5).

Three documents built in FreeCAD here: a group in the document tree that holds non-part objects (a face, a
datum plane, a boolean's operand) beside the authors' compound of two parts; a bearing (an ``App::Part`` of
two rings and four balls) on a shaft in a housing; an Assembly4-style assembly whose parts are ``App::Link``s
to other ``.FCStd`` files beside it. Each runs to ``aplan session MODEL --demo 0`` with the default flags (the
grouped one from its ``.FCStd`` end to end, the others from the bundles their export wrote), and what ``aplan
export-freecad`` writes for it, for the pen, the truck and the pump, ``aplan stats`` reads, with fasteners
folded or not.
"""
from __future__ import annotations

import functools
import json
import shutil
import subprocess
import sys

import pytest
from background import Job, folder, run
from conftest import REPO, SHARED, require_freecadcmd, require_shared
from real_models import JOBS as REAL_JOBS
from real_models import real_bundle

from integration.freecad_tools import aplan, aplan_process, freecad_result, succeeded
from integration.test_cad import PEN_JOBS
from planner.api import resolve_product

BUILD = '''
import os, sys, json
import FreeCAD, Part
folder = {folder!r}
V = FreeCAD.Vector

def feature(doc, name, shape, container=None):
    f = doc.addObject("Part::Feature", name); f.Shape = shape
    if container is not None:
        container.addObject(f)
    return f

# 1. A group in the document tree holding parts and non-part objects (a sketch-like face, a datum plane, a
#    boolean's operand): a stack of three plates and a block.
doc = FreeCAD.newDocument("grouped")
group = doc.addObject("App::DocumentObjectGroup", "Plates")
feature(doc, "Bottom", Part.makeBox(40, 40, 5), group)
feature(doc, "Middle", Part.makeBox(40, 40, 5, V(0, 0, 5)), group)
face = feature(doc, "Outline", Part.makePlane(40, 40, V(0, 0, 20)), group)  # faces, no solid
plane = doc.addObject("App::Plane", "Datum"); group.addObject(plane)
base = doc.addObject("Part::Box", "TopBase"); base.Length = base.Width = 40; base.Height = 5
base.Placement.Base = V(0, 0, 10)
tool = doc.addObject("Part::Cylinder", "TopHole"); tool.Radius = 5; tool.Height = 5; tool.Placement.Base = V(20, 20, 10)
cut = doc.addObject("Part::Cut", "Top"); cut.Base = base; cut.Tool = tool
group.addObject(tool)  # the operand in the group, the cut outside it
block = feature(doc, "Block", Part.makeBox(10, 10, 10, V(15, 15, 15)))
cover = doc.addObject("Part::Compound", "Cover"); cover.Links = [cut, block]  # the authors' grouping
doc.recompute(); doc.saveAs(os.path.join(folder, "grouped.FCStd"))
# The same with an APLAN analysis whose subassembly tree names objects that are no parts (a face, an operand).
sys.path.insert(0, {repo!r})
from freecad_aplan.intent import create_analysis, update_intent
update_intent(create_analysis(doc), "tree", subassemblies=[{{"id": "stack", "parts": ["Bottom", "Middle", "Outline"]}},
                                                           {{"id": "pair", "parts": ["Top", "TopBase"]}}])
doc.saveAs(os.path.join(folder, "tree.FCStd"))

# 2. A bearing: an App::Part container of an outer ring, an inner ring and {balls} balls, on a shaft in a housing.
doc = FreeCAD.newDocument("bearing")
bearing = doc.addObject("App::Part", "Bearing")
def ring(r_in, r_out, h):
    return Part.makeCylinder(r_out, h).cut(Part.makeCylinder(r_in, h))
feature(doc, "OuterRing", ring(20, 25, 6), bearing)
feature(doc, "InnerRing", ring(8, 14, 6), bearing)
import math
for k in range({balls}):
    a = 2 * math.pi * k / {balls}
    feature(doc, f"Sphere{{k + 1:03d}}", Part.makeSphere(3, V(17 * math.cos(a), 17 * math.sin(a), 3)), bearing)
feature(doc, "Shaft", Part.makeCylinder(8, 40, V(0, 0, -17)))
feature(doc, "Housing", ring(25, 40, 6).fuse(ring(20, 40, 3).translate(V(0, 0, 6))))
doc.recompute(); doc.saveAs(os.path.join(folder, "bearing.FCStd"))

# 3. An Assembly4-style assembly: an App::Part "Model" of App::Links to parts in other documents beside it.
parts = {{}}
for name, shape in (("base", Part.makeBox(60, 30, 10)), ("post", Part.makeCylinder(5, 30)),
                    ("cap", Part.makeBox(20, 20, 5))):
    lib = FreeCAD.newDocument(name)
    body = lib.addObject("App::Part", "Part"); body.Label = name
    solid = feature(lib, "Solid", shape, body)
    lib.recompute(); lib.saveAs(os.path.join(folder, name + ".FCStd"))
    parts[name] = body
asm = FreeCAD.newDocument("linked"); asm.saveAs(os.path.join(folder, "linked.FCStd"))
model = asm.addObject("App::Part", "Model")
for label, target, at in (("Base", "base", V(0, 0, 0)), ("Post", "post", V(15, 15, 10)),
                          ("Post2", "post", V(45, 15, 10)),
                          ("Cap", "cap", V(5, 5, 40))):
    link = asm.addObject("App::Link", label); link.LinkedObject = parts[target]; link.Placement.Base = at
    model.addObject(link)
asm.recompute(); asm.save()
print("APLAN-RESULT " + json.dumps(sorted(os.listdir(folder))))
'''

DOCUMENTS = ("grouped", "bearing", "linked")
#: The bearing's balls: each joins both rings, so the fastener rule's geometry proposes it, as it did with eight;
#: four keep the bearing's session short (a ball is one operation of a simulated camera's session).
BALLS = 4
FROM_CAD = "grouped"  # the document whose session starts from the .FCStd file


@functools.cache
def _folder():
    return folder("documents")


def _build() -> tuple:
    """The three documents, built by FreeCADCmd in one folder: (folder, the run)."""
    tmp = _folder()
    script = tmp / "documents_probe.py"
    script.write_text(BUILD.format(folder=str(tmp), repo=str(REPO), balls=BALLS))
    return tmp, run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(script)])


BUILT = Job("test documents built in FreeCAD", _build)


def _export(name: str) -> tuple:
    tmp, built = BUILT.result()
    if "APLAN-RESULT" not in built.stdout:
        return tmp / name, built
    # the linked assembly with --skip-damaged: nothing is damaged, so nothing may be said to be left out
    return tmp / name, aplan_process("export-freecad", str(tmp / f"{name}.FCStd"), "-o", str(tmp / name),
                                     *(["--skip-damaged"] if name == "linked" else []))


def _session(name: str) -> subprocess.CompletedProcess:
    """``aplan session MODEL --demo 0`` with the default flags, in a folder of its own in the documents' (its logs
    are named by the second they start and the level, and FreeCAD's lane runs two jobs at once). MODEL is
    ``grouped.FCStd`` (the one run from the CAD file end to end: its export's warnings name the model), the
    bundles the export jobs wrote for the others (their exports are checked by their own tests: a session
    from the bundle checks the rest, without exporting again)."""
    tmp, built = BUILT.result()
    if "APLAN-RESULT" not in built.stdout:
        return built
    if name == FROM_CAD:
        model = tmp / f"{name}.FCStd"
    else:
        model, exported = EXPORTS[name].result()
        if exported.returncode != 0:
            return exported
    own = tmp / f"session-{name}"
    own.mkdir(exist_ok=True)
    done = run([sys.executable, "-m", "planner", "session", str(model), "--demo", "0"], cwd=own)
    return subprocess.CompletedProcess(["aplan", "session", name], done.returncode, done.stdout, done.stderr)


def _export_truck_step() -> tuple:
    bundle = folder("truck-stp") / "b"
    return bundle, aplan_process("export-freecad", str(SHARED / "models/toy_truck/asm_cement_mixer_truck.stp"),
                                 "-o", str(bundle))


EXPORTS = {name: Job(f"export {name}", functools.partial(_export, name)) for name in (*DOCUMENTS, "tree")}
SESSIONS = {name: Job(f"session {name}", functools.partial(_session, name)) for name in DOCUMENTS}
STP_TRUCK = Job("export the truck's STEP file", _export_truck_step)
BACKGROUND = (BUILT, *EXPORTS.values(), *SESSIONS.values(), *REAL_JOBS.values(), *PEN_JOBS.values(), STP_TRUCK)


def _bundle(name: str):
    require_freecadcmd()
    bundle, done = EXPORTS[name].result()
    succeeded(done)
    return bundle, done


@pytest.mark.freecad
@pytest.mark.parametrize("name", DOCUMENTS)
def test_each_document_runs_to_a_session_with_the_default_flags(name):
    require_freecadcmd()
    done = succeeded(SESSIONS[name].result())
    assert "assembled: the product is assembled" in done.stdout and "Traceback" not in done.stderr
    # every message names the model, never the temporary bundle it was read from
    assert "bundle/product.json" not in done.stdout + done.stderr


@pytest.mark.freecad
def test_a_group_with_non_part_objects_and_a_compound():
    bundle, done = _bundle("grouped")
    product = json.loads((bundle / "product.json").read_text())
    assert sorted(p["id"] for p in product["parts"]) == ["Block", "Bottom", "Middle", "Top"]
    assert [(s["id"], s["parts"]) for s in product["subassemblies"]] == [("Plates", ["Bottom", "Middle"]),
                                                                        ("Cover", ["Top", "Block"])]
    assert "1 compound (Cover) groups parts as the authors did" in done.stdout
    # the export's warnings reach the user of a command reading the CAD file, naming the model
    session = SESSIONS["grouped"].result()
    assert "aplan: warning: grouped.FCStd: Outline: has 1 faces but no solid" in session.stderr
    assert "TopBase (used by Top.Base)" in session.stderr


@pytest.mark.freecad
def test_the_analysis_tree_is_fitted_to_the_exported_parts():
    """The analysis' tree names a face and a boolean's operand (no parts): each dropped with a warning, a
    subassembly left with one member dissolved; the compound, not used then, is named in one line."""
    bundle, done = _bundle("tree")
    product = json.loads((bundle / "product.json").read_text())
    assert [(s["id"], s["parts"]) for s in product["subassemblies"]] == [("stack", ["Bottom", "Middle"])]
    warnings = product["geometry"]["warnings"]
    assert "the analysis' subassembly tree: 'stack' lists 'Outline', which is no exported part (excluded, folded, " \
           "or the input of another feature): dropped from it" in warnings
    assert "the analysis' subassembly tree: 'pair' is dissolved: it is left only 'Top', which takes its place" \
        in warnings
    assert "the compounds Cover are not used as subassemblies: the APLAN analysis holds a subassembly tree of its " \
           "own (empty it to use the document's)" in warnings
    assert all(f"warning: {w}" in done.stdout for w in warnings)


@pytest.mark.freecad
def test_bearing_balls_are_no_fasteners():
    bundle, _ = _bundle("bearing")
    product = json.loads((bundle / "product.json").read_text())
    balls = [f"Sphere{k:03d}" for k in range(1, BALLS + 1)]
    assert product["subassemblies"][0]["parts"] == ["OuterRing", "InnerRing", *balls]
    report = json.loads(aplan("fasteners", str(bundle), "--json").stdout)
    assert report["proposed"] == []
    assert {item["part"] for item in report["left_out"]} == set(balls)
    assert all("designer's subassembly 'Bearing' holds it" in item["reason"] for item in report["left_out"])


@pytest.mark.freecad
def test_linked_documents_pass_the_damage_check(tmp_path):
    """Assembly4 style: the links name documents beside the assembly (<XLink file="base.FCStd">), no archive
    member; copied alone, the assembly is refused naming each link and the missing document, with a fix the
    command accepts."""
    bundle, done = _bundle("linked")  # exported with --skip-damaged
    assert "damaged" not in done.stdout + done.stderr and "left out" not in done.stdout + done.stderr
    product = json.loads((bundle / "product.json").read_text())
    assert sorted(p["id"] for p in product["parts"]) == ["Base", "Cap", "Post", "Post2"]
    volumes = {p["id"]: p["volume"] for p in product["parts"]}
    assert volumes["Base"] == pytest.approx(60 * 30 * 10) and volumes["Cap"] == pytest.approx(20 * 20 * 5)
    shutil.copy(BUILT.result()[0] / "linked.FCStd", tmp_path)
    alone = aplan("stats", str(tmp_path / "linked.FCStd"), check=False)
    assert alone.returncode == 1
    assert "Post2: it links to post.FCStd, which is not in" in alone.stderr
    assert "aplan export-freecad MODEL -o BUNDLE --skip-damaged" in alone.stderr  # stats has no --skip-damaged
    exported = aplan("export-freecad", str(tmp_path / "linked.FCStd"), "-o", str(tmp_path / "b"), check=False)
    assert exported.returncode == 1 and "; --skip-damaged exports the rest" in exported.stderr


def _every_bundle() -> dict:
    out = {name: _bundle(name)[0] for name in EXPORTS}
    out.update({name: real_bundle(name) for name in REAL_JOBS})
    bundle, done = STP_TRUCK.result()
    out["toy_truck stp"] = succeeded(done) and bundle
    for (variant, ext), job in PEN_JOBS.items():
        require_shared(SHARED / "models" / "bourjault_pen")
        bundle, done = job.result()
        out[f"pen {variant} {ext}"] = succeeded(done) and bundle
    return out


@pytest.mark.freecad
def test_what_the_export_writes_stats_reads():
    """Every model of ../shared/models and every test document: the bundle reads back with fasteners
    folded or not, as the file has it or with the planner's proposals, and `aplan stats` takes it."""
    require_freecadcmd()
    for name, bundle in _every_bundle().items():
        for fasteners in ("tagged", "auto", "none"):
            for subassemblies in ("designer", "auto", "none"):
                resolve_product(str(bundle), fasteners=fasteners, subassemblies=subassemblies)
        done = aplan("stats", str(bundle), "--json", check=False)
        text = done.stderr
        assert "subassemblies[" not in text and "fasteners[" not in text and "Traceback" not in text, (name, text)
        assert done.returncode in (0, 3) or "block each other" in text, (name, text)  # interlocks: item 1


@pytest.mark.freecad
def test_fasteners_output_of_a_model_and_a_bundle_is_read_by_stats(tmp_path):
    """`aplan fasteners -o` writes a file that `aplan stats` reads: from a CAD model (its temporary bundle's
    paths left out, with a warning) and from the pump's bundle (its proposals folded)."""
    require_freecadcmd()
    tmp, _ = BUILT.result()
    done = aplan("fasteners", str(tmp / "grouped.FCStd"), "-o", str(tmp_path / "g.json"))
    assert "no mesh or B-rep paths: grouped.FCStd was read into a temporary bundle" in done.stderr
    assert done.stdout.startswith(f"grouped ({(tmp / 'grouped.FCStd').resolve()}): 4 parts")  # the model, named
    data = json.loads((tmp_path / "g.json").read_text())
    assert all("mesh" not in p for p in data["parts"]) and "x-temporary-bundle" not in data["geometry"]
    assert aplan("stats", str(tmp_path / "g.json"), check=False).returncode == 0
    aplan("fasteners", str(real_bundle("diaphragm_pump")), "-o", str(tmp_path / "p.json"))
    stats = aplan("stats", str(tmp_path / "p.json"), check=False)
    assert "subassemblies[" not in stats.stderr and "fasteners[" not in stats.stderr
    assert stats.returncode in (0, 3) or "block each other" in stats.stderr  # interlocks: item 1
