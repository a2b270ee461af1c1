"""From real CAD files to plans, through real FreeCAD: export, mesh analysis, statistics, bad input."""
from __future__ import annotations

import functools
import hashlib
import json
import shutil
import subprocess

import pytest
from background import Job, folder
from conftest import PEN_MODELS, REPO, require_freecadcmd, require_shared
from real_models import JOBS, real_bundle, real_export_output

from integration.freecad_tools import LIAISONS, aplan, aplan_process, freecad_result, freecadcmd_job, succeeded
from planner import load_product
from planner.geometry.bundle import bundle_product_path

VARIANTS = [(v, ext) for v in ("simplified", "complex") for ext in ("FCStd", "stp")]


def ground_truth(axis: str) -> set[tuple[str, str]]:
    path = require_shared(PEN_MODELS / "simplified" / "GroundTruth" / f"GeomConstraints_POS_{axis[1]}.json")
    return {(link["source"], link["target"]) for link in json.loads(path.read_text())["links"]}


def _export_pen(variant: str, ext: str) -> tuple:
    bundle = folder("pen") / f"{variant}_{ext}"
    model = PEN_MODELS / variant / f"asm_bourjault_ballpoint.{ext}"
    return bundle, aplan_process("export-freecad", str(model), "-o", str(bundle))


def _occt_analysis() -> tuple:
    """`aplan analyze --engine occt` on a copy of the simplified pen's bundle: (bundle, the run)."""
    source, exported = PEN_JOBS["simplified", "FCStd"].result()
    bundle = folder("occt-cli") / "b"
    if exported.returncode != 0:
        return bundle, exported  # the pen_bundles fixture reports it
    shutil.copytree(source, bundle)
    return bundle, aplan_process("analyze", str(bundle), "--engine", "occt")


PEN_JOBS = {(v, ext): Job(f"export the {v} pen ({ext})", functools.partial(_export_pen, v, ext)) for v, ext in VARIANTS}
OCCT_JOB = Job("the OCCT engine on the pen's bundle", _occt_analysis)


@pytest.fixture(scope="module")
def pen_bundles():
    require_freecadcmd()
    out = {}
    for variant, ext in VARIANTS:
        require_shared(PEN_MODELS / variant / f"asm_bourjault_ballpoint.{ext}")
        bundle, done = PEN_JOBS[variant, ext].result()
        succeeded(done)
        out[variant, ext] = bundle
    return out


@pytest.mark.freecad
@pytest.mark.parametrize("variant, ext", VARIANTS)
def test_pen_models_give_the_ground_truth(pen_bundles, variant, ext):
    product = load_product(bundle_product_path(pen_bundles[variant, ext]))
    assert sorted(product.part_ids) == sorted(["ink_001", "cartridge_001", "head_001", "body_001", "cap_001",
                                               "button_001"])
    assert {frozenset(c) for c in product.contacts} == LIAISONS
    assert [o.direction.name for o in product.obstructions] == ["+X", "+Y", "+Z"]
    for obstruction in product.obstructions:
        assert set(obstruction.blocks) == ground_truth(obstruction.direction.name), obstruction.direction.name
    analysis = product.geometry["analysis"]
    assert analysis["engine"] == "mesh" and analysis["interferences"] == []
    assert product.geometry["tessellation"]["linear_deflection"] > 0
    for part in product.parts:
        assert (pen_bundles[variant, ext] / part.mesh).is_file() and (pen_bundles[variant, ext] / part.brep).is_file()


@pytest.mark.freecad
def test_bundle_and_model_to_stats(pen_bundles):
    expected = {"subassemblies": 18, "states": 18, "intentions": 69, "sequences": 24}
    for target in (str(pen_bundles["simplified", "FCStd"]), str(PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd")):
        stats = json.loads(aplan("stats", target, "--json").stdout)
        assert {k: stats[k] for k in expected} == expected


@pytest.mark.freecad
def test_export_never_touches_the_model(tmp_path):
    require_freecadcmd()
    model = PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"
    before = hashlib.sha256(model.read_bytes()).hexdigest()
    aplan("export-freecad", str(model), "-o", str(tmp_path / "b"), "--engine", "none")
    assert hashlib.sha256(model.read_bytes()).hexdigest() == before
    product = load_product(tmp_path / "b" / "product.json")
    assert product.contacts == () and "analysis" not in product.geometry
    # An unanalysed bundle is analysed in memory when planned.
    assert json.loads(aplan("stats", str(tmp_path / "b"), "--json").stdout)["intentions"] == 69


PLACEMENTS = """
import json, os, sys, tempfile
sys.path.insert(0, {repo!r})
import FreeCAD
from freecad_aplan.document import open_model, read_components
from freecad_aplan.export import export_components
doc = open_model({model!r})
def snapshot():
    return {{o.Name: [list(o.Placement.Base), list(o.Placement.Rotation.Q), round(o.Shape.Volume, 6),
                      list(o.Shape.Placement.Base)] for o in doc.Objects if hasattr(o, "Shape")}}
before = snapshot()
result = read_components(doc, groups={{"refill": ["ink_001", "cartridge_001"]}}, exclude=["button_001"])
for c in result.components:
    c.shape.translate(FreeCAD.Vector(1000, 0, 0))  # moving the copies must not move the document's parts
export_components(result.components, tempfile.mkdtemp(), {model!r}, result.warnings)
print("APLAN-RESULT " + json.dumps({{"same": snapshot() == before, "ids": sorted(c.id for c in result.components)}}))
"""


PLACEMENTS_JOB = freecadcmd_job("placements", lambda tmp: PLACEMENTS.format(
    repo=str(REPO), model=str(PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd")))


@pytest.mark.freecad
def test_placements_unchanged_and_groups():
    require_freecadcmd()
    data = freecad_result(PLACEMENTS_JOB.result()[1])
    assert data["same"] is True
    assert data["ids"] == ["body_001", "cap_001", "head_001", "refill"]


@pytest.mark.freecad
def test_group_and_exclude_from_the_command_line(tmp_path):
    require_freecadcmd()
    model = PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"
    aplan("export-freecad", str(model), "-o", str(tmp_path / "b"), "--group", "refill=ink_001,cartridge_001",
          "--exclude", "button_001")
    product = load_product(tmp_path / "b" / "product.json")
    assert sorted(product.part_ids) == ["body_001", "cap_001", "head_001", "refill"]
    assert {frozenset(c) for c in product.contacts} == {frozenset(p) for p in [("refill", "head_001"),
                                                                               ("head_001", "body_001"),
                                                                               ("body_001", "cap_001")]}


@pytest.mark.freecad
@pytest.mark.parametrize("model, parts, contacts, interferences, shells, planned", [
    ("toy_truck", 61, 113, 0, {},
     (3, "AND/OR graph: at least 2,131,194 connected part sets")),
    ("diaphragm_pump", 53, 87, 18, {"16_001": 110, "21_001": 54},
     (1, "block each other along every direction tried (+/-X, +/-Y, +/-Z), so no disassembly can separate them: "
         "1_001 and 8_002; 1_001 and 8_007; 21_001 and 26_001.")),
])
def test_truck_and_pump(model, parts, contacts, interferences, shells, planned):
    """Parts from SOURCE.txt (61 and 51 solids), and the pump's two closed shells without a solid (16_001,
    21_001) read as the solids they bound, named in a warning: 53 parts. The contacts and interference
    counts are this engine's own figures, printed for the record (the OCCT engine finds the same 87 contacts
    on the pump; without the two shells SOURCE.txt reports 68 touching pairs). ``aplan stats`` on the
    bundle: the truck's AND/OR graph would explode (its chassis touches 21 parts: 2^21 connected sets hold it
    and its neighbours alone; 39 wood screws each join two parts), so it is refused at once with that bound,
    naming the screws (no two of its parts block each other in every direction: its tires leave their axles
    outwards). The pump, now connected (with the two shells it no longer falls apart), has three pairs of
    parts that block each other along every axis: two screws (8_002, 8_007) in the body 1_001, and the shell
    21_001 with 26_001, which it overlaps by 1,434 mm^3 (one of its interferences). The bundles are those of
    ``real_models`` (exported once per session with the default settings)."""
    bundle = real_bundle(model)
    print(real_export_output(model))
    product = load_product(bundle / "product.json")
    found = product.geometry["analysis"]["interferences"]
    print(f"{model}: {len(product.parts)} parts, {len(product.contacts)} contacts, {len(found)} interferences")
    assert (len(product.parts), len(product.contacts), len(found)) == (parts, contacts, interferences)
    for name, faces in shells.items():
        assert f"{name}: has {faces} faces in closed shells but no solid; read as the solid they bound (make it " \
            "a solid in FreeCAD to silence this)" in product.geometry["warnings"]
    for item in found:
        assert item["volume"] > 1.0
    # Planned as the file has it (without the default proposals and interlock rules), past the size limit or
    # interlocked.
    stats = aplan("stats", str(bundle), "--json", "--fasteners", "tagged", "--subassemblies", "designer",
                  "--interlocks", "keep", "--verbose", check=False)
    status, message = planned
    assert stats.returncode == status and message in (stats.stdout + stats.stderr)
    assert "support contacts" not in stats.stderr  # nothing floats in a cavity: the rule leaves them as they are
    if status == 3:
        figures = json.loads(stats.stdout)
        assert (figures["parts"], figures["contacts"], figures["subassemblies"]) == (parts, contacts, None)
        if parts == 61:
            assert "39 part(s) look like fasteners by name (wood_screw_001" in figures["not_computed"]["reason"]


@pytest.mark.freecad
def test_the_pump_plans_every_level_with_no_flag():
    """With the default flags the pump's three interlocked pairs (above), all overlaps in the model, are inserted
    along their overlaps' axes, one line each, and every workstation plans (before, level sa3 stopped on 21_001
    and 26_001 unless --group outlet=21_001,26_001 was given)."""
    done = aplan("stats", str(real_bundle("diaphragm_pump")), "--json")
    figures = json.loads(done.stdout)
    assert figures["total"]["parts"] == 53 and all(level["sequences"] >= 1 for level in figures["levels"])
    for pair in ("1_001 and 8_002", "1_001 and 8_007", "21_001 and 26_001"):
        assert f"interlock: {pair} overlap by" in done.stderr
    assert "support contacts" not in done.stderr  # it plans without: the rule leaves it as it is


@pytest.mark.freecad
def test_bad_models_leave_nothing(tmp_path):
    require_freecadcmd()
    missing = aplan("export-freecad", str(tmp_path / "nope.FCStd"), "-o", str(tmp_path / "b"), check=False)
    assert missing.returncode == 1 and "no such file" in missing.stderr
    corrupt = tmp_path / "corrupt.FCStd"
    corrupt.write_bytes(b"this is not a zip archive")
    bad = aplan("export-freecad", str(corrupt), "-o", str(tmp_path / "b"), check=False)
    assert bad.returncode == 1 and "corrupt.FCStd" in bad.stderr
    (tmp_path / "b").mkdir()
    exists = aplan("export-freecad", str(PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"), "-o",
                   str(tmp_path / "b"), check=False)
    assert exists.returncode == 1 and "already exists" in exists.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b", "corrupt.FCStd"]  # no partial bundles


NO_SOLIDS = """
import FreeCAD, Part
doc = FreeCAD.newDocument("flat")
face = doc.addObject("Part::Feature", "Sheet")
face.Shape = Part.makePlane(10, 10)
doc.saveAs({path!r})
print("APLAN-RESULT {{}}")
"""


@pytest.mark.freecad
def test_document_without_solids(tmp_path):
    freecadcmd = require_freecadcmd()
    script = tmp_path / "make.py"
    script.write_text(NO_SOLIDS.format(path=str(tmp_path / "flat.FCStd")))
    subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=120)
    done = aplan("export-freecad", str(tmp_path / "flat.FCStd"), "-o", str(tmp_path / "b"), check=False)
    assert done.returncode == 1
    assert "the document has no solids to plan with" in done.stderr
    assert not (tmp_path / "b").exists()


DOCUMENT_TYPES = """
import json, os, sys, tempfile
sys.path.insert(0, {repo!r})
import FreeCAD, Part
folder = tempfile.mkdtemp()
# A library document with one box, linked from the assembly.
lib = FreeCAD.newDocument("lib")
libbox = lib.addObject("Part::Box", "LibBox"); libbox.Length = libbox.Width = libbox.Height = 2
lib.recompute(); lib.saveAs(os.path.join(folder, "lib.FCStd"))
doc = FreeCAD.newDocument("asm"); doc.saveAs(os.path.join(folder, "asm.FCStd"))
body = doc.addObject("PartDesign::Body", "Body")
feature = doc.addObject("PartDesign::AdditiveBox", "Box")
body.addObject(feature); feature.Length = feature.Width = feature.Height = 10
a = doc.addObject("Part::Box", "CutBase"); a.Length = a.Width = a.Height = 10; a.Placement.Base = FreeCAD.Vector(20, 0, 0)
b = doc.addObject("Part::Box", "CutTool"); b.Length = b.Width = b.Height = 5; b.Placement.Base = FreeCAD.Vector(20, 0, 0)
cut = doc.addObject("Part::Cut", "Cut"); cut.Base = a; cut.Tool = b
container = doc.addObject("App::Part", "Sub"); container.Placement.Base = FreeCAD.Vector(0, 50, 0)
inner = doc.addObject("Part::Cylinder", "Pin"); inner.Radius = 1; inner.Height = 4; container.addObject(inner)
link = doc.addObject("App::Link", "LinkedBox"); link.LinkedObject = libbox; link.Placement.Base = FreeCAD.Vector(0, 0, 30)
sketchy = doc.addObject("Part::Feature", "Face"); sketchy.Shape = Part.makePlane(3, 3)
doc.recompute()
from freecad_aplan.document import read_components
result = read_components(doc)
out = {{c.id: [round(c.shape.Volume, 3), [round(v, 3) for v in (c.shape.BoundBox.XMin, c.shape.BoundBox.YMin, c.shape.BoundBox.ZMin)]] for c in result.components}}
print("APLAN-RESULT " + json.dumps({{"components": out, "warnings": result.warnings}}))
"""


# The script is document_types_probe.py: types.py would shadow the standard module.
DOCUMENT_TYPES_JOB = freecadcmd_job("document_types", lambda tmp: DOCUMENT_TYPES.format(repo=str(REPO)))


@pytest.mark.freecad
def test_document_object_types():
    """PartDesign bodies, booleans, App::Part containers and links to other documents, built in FreeCAD."""
    require_freecadcmd()
    data = freecad_result(DOCUMENT_TYPES_JOB.result()[1])
    assert data["components"] == {
        "Body": [1000.0, [0.0, 0.0, 0.0]],      # the body, not its feature
        "Cut": [875.0, [20.0, 0.0, 0.0]],       # the boolean, not its operands
        "Pin": [12.566, [-1.0, 49.0, 0.0]],     # inside an App::Part placed at y = 50
        "LinkedBox": [8.0, [0.0, 0.0, 30.0]],   # a link to another document, with the link's placement
    }
    assert data["warnings"] == ["Face: has 1 faces but no solid (an open or unsewn shell); skipped "
                                "(make it a solid in FreeCAD to include it)",
                                "not parts of their own (inputs of another feature, or shown by a link): Box (used "
                                "by Body.Group, Body.Tip); CutBase (used by Cut.Base); CutTool (used by Cut.Tool); "
                                "the features and links using them are the parts"]


@pytest.mark.freecad
def test_occt_engine_through_the_command_line(pen_bundles):
    """aplan analyze --engine occt: the exact engine, run in FreeCADCmd on the bundle's B-reps."""
    bundle, done = OCCT_JOB.result()
    succeeded(done)
    assert "(occt engine" in done.stdout
    product = load_product(bundle / "product.json")
    assert product.geometry["analysis"]["engine"] == "occt"
    assert {frozenset(c) for c in product.contacts} == LIAISONS
    for obstruction in product.obstructions:
        assert set(obstruction.blocks) == ground_truth(obstruction.direction.name), obstruction.direction.name


@pytest.mark.freecad
def test_occt_pair_budget_through_the_command_line(pen_bundles, tmp_path):
    """--pair-budget 0: every pair OCCT would measure is reported undecided, with progress on standard error,
    and keeps the mesh engine's answer (freecad_aplan/hybrid.py): the contacts are still the liaisons; the
    pairs the meshes settle (apart) are not given to OCCT."""
    bundle = tmp_path / "b"
    shutil.copytree(pen_bundles["simplified", "FCStd"], bundle)
    done = aplan("analyze", str(bundle), "--engine", "occt", "--pair-budget", "0", "--json")
    assert "occt: contacts 15/15" in done.stderr and "occt: obstructions +Z" in done.stderr
    report = json.loads(done.stdout)
    undecided = [w for w in report["warnings"] if w.startswith("OCCT did not decide")]
    assert {frozenset(c) for c in report["contacts"]} == LIAISONS
    pairs = report["tolerances"]["pairs"]
    assert pairs["mesh"] + pairs["occt"] + len(pairs["undecided"]) == 15 and pairs["mesh"] > 0
    assert LIAISONS <= {frozenset(p) for p in pairs["undecided"]}
    assert undecided and all("within the budget of 0 CPU s and 400 operations per pair" in w for w in undecided)


@pytest.mark.freecad
def test_a_time_limit_that_is_not_positive_is_a_usage_error(pen_bundles):
    for value in ("0", "-1", "nan"):
        done = aplan("analyze", str(pen_bundles["simplified", "FCStd"]), "--engine", "occt", "--time-limit", value,
                     check=False)
        assert done.returncode == 2 and "--time-limit" in done.stderr, done.stderr


IMPORT_PREFERENCE = """
import json, sys
sys.path.insert(0, {repo!r})
import FreeCAD, Import
from freecad_aplan.document import DocumentError, open_model
group = FreeCAD.ParamGet("User parameter:BaseApp/Preferences/Mod/Import")
during = []
insert = Import.insert
def spy(*args):
    during.append("UseLinkGroup" in group.GetBools() and group.GetBool("UseLinkGroup"))
    return insert(*args)
Import.insert = spy
out = {{}}
for setting in (True, False, None):
    if setting is None:
        group.RemBool("UseLinkGroup")
    else:
        group.SetBool("UseLinkGroup", setting)
    for model in ({model!r}, {corrupt!r}):
        try:
            FreeCAD.closeDocument(open_model(model).Name)
            failed = False
        except DocumentError:
            failed = True
        names = group.GetBools()
        out[f"{{setting}} {{'corrupt' if failed else 'pen'}}"] = (
            group.GetBool("UseLinkGroup") if "UseLinkGroup" in names else None)
out["during"] = during
print("APLAN-RESULT " + json.dumps(out))
"""


@pytest.mark.freecad
def test_step_import_restores_the_link_group_preference(tmp_path):
    """STEP files are imported without link groups (they can crash FreeCADCmd); the user's preference is
    put back afterwards, as it was (also unset), when the import fails too."""
    freecadcmd = require_freecadcmd()
    corrupt = tmp_path / "corrupt.step"
    corrupt.write_text("ISO-10303-21;\nnot a step file\n")
    script = tmp_path / "preference_probe.py"
    script.write_text(IMPORT_PREFERENCE.format(repo=str(REPO), corrupt=str(corrupt),
                                               model=str(PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.stp")))
    home = tmp_path / "home"  # FreeCAD saves its preferences there on exit
    home.mkdir()
    done = subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=300,
                          env={"HOME": str(home), "PATH": "/usr/bin:/bin", "LANG": "C.UTF-8"})
    data = freecad_result(done)
    assert data.pop("during") == [False] * 6  # every import ran without link groups
    assert data == {"True pen": True, "True corrupt": True, "False pen": False, "False corrupt": False,
                    "None pen": None, "None corrupt": None}


#: The exports and FreeCAD runs the tests read, done in the background (tests/background.py), in the order the
#: tests need them.
BACKGROUND = (*PEN_JOBS.values(), PLACEMENTS_JOB, *JOBS.values(), DOCUMENT_TYPES_JOB, OCCT_JOB)


@pytest.mark.freecad
def test_a_part_without_a_good_mesh_is_decided_on_its_exact_shape(pen_bundles, tmp_path):
    """The mesh engine on a bundle where one part's rule is ``exact`` (set here: the pen's meshes are all
    right): OCCT decides the pairs with that part (freecad_aplan/hybrid.py), and the diagrams still match the
    ground truth; the pairs without it are settled on the meshes."""
    bundle = tmp_path / "b"
    shutil.copytree(pen_bundles["simplified", "FCStd"], bundle)
    data = json.loads((bundle / "product.json").read_text())
    part = data["parts"][0]["id"]
    data["geometry"]["mesh_check"]["parts"][part]["rule"] = "exact"
    (bundle / "product.json").write_text(json.dumps(data))
    done = aplan("analyze", str(bundle), "--engine", "mesh", "--json")
    report = json.loads(done.stdout)
    pairs = report["tolerances"]["pairs"]
    assert pairs["fallback"] == {part: "exact"} and pairs["mesh"] == 15 - 5 and pairs["occt"] == 5
    assert f"parts decided on their exact shape: {part} (exact)" in report["warnings"][0]
    assert {frozenset(c) for c in report["contacts"]} == LIAISONS
    for name in ("+X", "+Y", "+Z"):
        assert {tuple(p) for p in report["obstructions"][name]} == ground_truth(name), name
