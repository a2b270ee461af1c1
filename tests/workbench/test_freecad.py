"""The addon inside real FreeCAD: installed as a Mod folder, its packages import and the planner runs."""
from __future__ import annotations

import json
import subprocess

from conftest import REPO, require_freecadcmd

PROBE = """
import json
import FreeCAD
import freecad_aplan, planner   # no sys.path changes: FreeCAD puts the Mod folder on it
from planner import make_plan, plan_statistics, resolve_product
stats = plan_statistics(make_plan(resolve_product("pen"))).as_dict()
# Messages about bad files come from FreeCAD's own jsonschema (Debian's) as they do from the venv's.
from planner import ProductFormatError, example_path, product_from_dict
messages = []
for key, value in (("contacts", [["ink"]]), ("obstructions", [{"direction": "+W", "blocks": []}]),
                   ("units", "furlong")):
    doc = json.loads(example_path("pen").read_text())
    doc[key] = value
    try:
        product_from_dict(doc, "pen.json")
    except ProductFormatError as exc:
        messages.append(str(exc))
# Every exception class of the workbench derives from the planner's root (one except clause catches them).
import importlib, inspect, pkgutil
from planner.errors import PlannerError
errors = {}
for info in pkgutil.walk_packages(freecad_aplan.__path__, "freecad_aplan."):
    if info.name == "freecad_aplan.batch" or info.name.startswith("freecad_aplan.gui"):
        continue  # batch runs a job when imported; the GUI needs the GUI
    module = importlib.import_module(info.name)
    for name, value in vars(module).items():
        if inspect.isclass(value) and issubclass(value, Exception) and value.__module__ == info.name:
            errors[f"{info.name}.{name}"] = issubclass(value, PlannerError)
print("APLAN-RESULT " + json.dumps({"version": FreeCAD.Version()[:2], "planner": planner.__file__,
                                     "stats": stats, "messages": messages, "errors": errors}))
"""


def test_planner_runs_in_freecad_from_the_mod_folder(tmp_path):
    freecadcmd = require_freecadcmd()
    home = tmp_path / "home"
    for mod in (home / ".local" / "share" / "FreeCAD" / "Mod", home / ".FreeCAD" / "Mod"):
        mod.mkdir(parents=True)
        (mod / "APLAN").symlink_to(REPO, target_is_directory=True)
    script = tmp_path / "probe.py"
    script.write_text(PROBE)
    result = subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=120,
                            env={"HOME": str(home), "PATH": "/usr/bin:/bin", "LANG": "C.UTF-8"})
    lines = [line for line in result.stdout.splitlines() if line.startswith("APLAN-RESULT ")]
    assert lines, f"no result from FreeCAD:\n{result.stdout[-2000:]}\n{result.stderr[-2000:]}"
    data = json.loads(lines[-1].split(" ", 1)[1])
    assert data["version"] == ["0", "20"]
    assert "/Mod/APLAN/" in data["planner"]
    assert data["stats"]["intentions"] == 69 and data["stats"]["subassemblies"] == 18
    assert data["messages"] == [
        "pen.json: contacts[0]: expected a pair of two part ids, got 1 item",
        "pen.json: obstructions[0].direction: unknown direction '+W'; use +X, -X, +Y, -Y, +Z, -Z or a unit vector "
        "[x, y, z]",
        "pen.json: units: unknown unit 'furlong'; use one of mm, cm, m, in"]
    assert data["errors"] == {"freecad_aplan.archive.DamagedDocumentError": True,
                              "freecad_aplan.diagrams.RelationError": True, "freecad_aplan.document.DocumentError": True,
                              "freecad_aplan.intent.IntentError": True, "freecad_aplan.occt.analyze.BrepError": True,
                                 "freecad_aplan.occt.prisms.SweepStopped": True,
                                 "freecad_aplan.occt.prisms.SweepTooLarge": True,
                              "freecad_aplan.runner.FreeCADError": True}
