"""The workbench's commands without the GUI (freecad_aplan.workflow) in FreeCADCmd, on a copy of the pen:
detection through the background job, plan, bundle, POMDPX/.pomdp, solve through the background job,
simulation with its belief plot."""
from __future__ import annotations

import json
import shutil
import subprocess

import pytest

from conftest import PEN_MODELS, REPO, require_freecadcmd, require_shared
from planner import load_product, make_plan, plan_statistics
from planner.models import load_model
from test_cad import LIAISONS, aplan, freecad_result

SCRIPT = """
import json, os, subprocess, sys
sys.path.insert(0, {repo!r})
import FreeCAD
from freecad_aplan import workflow
from freecad_aplan.intent import IntentError, create_analysis, update_intent
TMP = {tmp!r}
out = {{}}
doc = FreeCAD.openDocument(os.path.join(TMP, "pen.FCStd"))
try:
    workflow.require_analysis(doc)
except IntentError as exc:
    out["no_analysis"] = str(exc)
analysis = create_analysis(doc)
try:
    workflow.analysis_product(analysis)
except IntentError as exc:
    out["not_detected"] = str(exc)

def job(action, arguments, engine=None):
    command = workflow.worker_command(action, engine)
    done = subprocess.run(command, capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, APLAN_BATCH=json.dumps({{"action": action, **arguments}})))
    line = [l for l in done.stdout.splitlines() if l.startswith(("APLAN-RESULT", "APLAN-ERROR"))][-1]
    return command, line

folder = os.path.join(TMP, "detect")
os.mkdir(folder)
exported = workflow.export_for_detection(doc, folder)
out["objects"] = exported["x-freecad-objects"]
out["mesh_job"], line = job("analyze", {{"folder": folder, "engine": "mesh"}}, "mesh")
out["mesh_result"] = json.loads(line.split(" ", 1)[1])
workflow.store_detection(analysis, folder)
product = workflow.analysis_product(analysis)
_, stats, images = workflow.plan_report(product, TMP)
out["stats"] = stats.as_dict()
out["images"] = images
workflow.export_analysis_bundle(doc, analysis, os.path.join(TMP, "bundle"))
out["pomdpx"] = workflow.export_decision_model(product, os.path.join(TMP, "pen.pomdpx"))
workflow.export_decision_model(product, os.path.join(TMP, "pen.pomdp"))
from planner.product import save_product
save_product(product, os.path.join(TMP, "product.json"))
out["solve_job"], line = job("solve", {{"product": os.path.join(TMP, "product.json"),
                                        "output": os.path.join(TMP, "pen.policy"), "time_limit": 3}})
out["solve"] = json.loads(line.split(" ", 1)[1])
out["simulate"] = workflow.simulate_sequence(product, os.path.join(TMP, "pen.policy"), os.path.join(TMP, "belief"))
_, out["bad_job"] = job("analyze", {{"folder": os.path.join(TMP, "missing"), "engine": "occt"}}, "occt")
# Without a Python for the mesh engine: FreeCADCmd when FreeCAD's Python has trimesh, else a clear error.
import importlib.util
workflow._mesh_python = lambda: None
out["freecad_has_mesh"] = all(importlib.util.find_spec(m) for m in ("trimesh", "manifold3d"))
try:
    out["no_mesh"] = workflow.worker_command("analyze", "mesh")
except Exception as exc:
    out["no_mesh"] = str(exc)
print("APLAN-RESULT " + json.dumps(out))
"""


@pytest.mark.freecad
def test_workbench_workflow_without_gui(tmp_path):
    freecadcmd = require_freecadcmd()
    shutil.copy(require_shared(PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"), tmp_path / "pen.FCStd")
    script = tmp_path / "workflow_probe.py"
    script.write_text(SCRIPT.format(repo=str(REPO), tmp=str(tmp_path)))
    data = freecad_result(subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=600))
    assert "no APLAN analysis; create one first" in data["no_analysis"]
    assert "run APLAN > Detect contacts and obstructions first" in data["not_detected"]
    assert data["objects"]["ink_001"] == ["b_ink_001_"]
    assert data["mesh_job"][0].endswith("python") and data["mesh_result"]["contacts"] == 5
    assert data["solve_job"][0].endswith("freecadcmd")
    # The plan from the stored diagrams equals the plan of the bundle it writes, read by the planner.
    bundle = load_product(tmp_path / "bundle" / "product.json")
    assert {frozenset(c) for c in bundle.contacts} == LIAISONS
    assert data["stats"] == plan_statistics(make_plan(bundle)).as_dict()
    assert data["stats"]["intentions"] == 69
    assert sorted(data["images"]) == ["andor", "intentions", "states"]
    # Decision model files: 69 intentions (states), 22 actions (README), both formats read back the same.
    assert (data["pomdpx"]["states"], data["pomdpx"]["actions"]) == (69, 22)
    first, second = load_model(tmp_path / "pen.pomdpx"), load_model(tmp_path / "pen.pomdp")
    assert (first.n_states, first.n_actions) == (second.n_states, second.n_actions) == (69, 22)
    assert data["solve"]["lower_bound"] <= data["solve"]["upper_bound"]
    assert (tmp_path / "pen.policy").is_file()
    simulate = data["simulate"]
    assert simulate["steps"] and all(p.endswith((".png", ".svg")) for p in simulate["plots"])
    assert (tmp_path / "belief.png").stat().st_size > 1000
    assert data["bad_job"].startswith("APLAN-ERROR ") and "Traceback" not in data["bad_job"]
    if data["freecad_has_mesh"]:
        assert data["no_mesh"][0].endswith("freecadcmd")
    else:
        assert "the mesh engine needs the Python packages trimesh and manifold3d" in data["no_mesh"]
