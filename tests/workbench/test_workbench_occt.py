"""The workbench's occt engine is the command line's (issue 26, item 4), in real FreeCAD: Detect's job runs the
engines ``aplan analyze`` runs (freecad_aplan.plugin.geometry_engines), so the meshes settle the easy pairs,
and a pair OCCT leaves undecided keeps the mesh engine's answer; each such pair, with the answer used, is in
the job's notes, its result and the stored analysis (what the Diagrams panel shows, undecided_notes).

The document (built here): a cylinder as a B-spline (radius 5, axis Z, its centre at the origin) touching a
box (x from 5 to 15, spanning the cylinder's section in Y and Z), and a small box far away (at 100, 100, 100: in no sweep of theirs along an axis). Closed form: the cylinder moving along +X
hits the box, along no other axis. OCCT sweeps a B-spline side face as triangles (it folds with no known
silhouette), and the analysis' bound ``OcctPrismTriangles = 1`` is below any such sweep: the pair stays
undecided by a bound on work, not on the clock. Then the analysis' time limit (Detect's panel, OcctTimeLimit)
of 1 ns, the bound back at its default: the limit stops OCCT before its first call (any call takes more CPU than
that), so the pair keeps every mesh answer, and the stop is said first. Without a Python for the mesh engine
(FreeCADCmd alone), OCCT decides every pair and the undecided one counts as blocking, reported as such.
"""
from __future__ import annotations

import pytest
from conftest import REPO, require_freecadcmd
from integration.freecad_tools import aplan_process, freecad_result, freecadcmd_job, succeeded

from planner import load_product

SCRIPT = r"""
import json, os, shutil, subprocess, sys
sys.path.insert(0, REPO)
import FreeCAD, Part
from freecad_aplan import workflow
from freecad_aplan.intent import create_analysis, read_intent, update_intent
from freecad_aplan.protocol import read_note
V = FreeCAD.Vector
doc = FreeCAD.newDocument("touching")
doc.addObject("Part::Feature", "Cylinder").Shape = Part.makeCylinder(5, 10, V(0, 0, -5)).toNurbs()
doc.addObject("Part::Feature", "Block").Shape = Part.makeBox(10, 10, 10, V(5, -5, -5))
doc.addObject("Part::Feature", "Far").Shape = Part.makeBox(2, 2, 2, V(100, 100, 100))
doc.recompute()
analysis = create_analysis(doc)
update_intent(analysis, "occt engine, one triangle per sweep", engine="occt", occt_prism_triangles=1)
intent = read_intent(analysis)
out = {"intent": [intent.engine, intent.occt_prism_triangles]}

def detect(name):
    folder = os.path.join(TMP, name)
    os.mkdir(folder)
    workflow.export_for_detection(doc, folder)
    shutil.copytree(folder, folder + "-exported")  # what the command line analyses below
    command = workflow.worker_command("analyze", intent.engine)
    done = subprocess.run(command, capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, APLAN_BATCH=json.dumps(workflow.detection_job(folder, intent.engine, intent))))
    notes = [n for n in map(read_note, done.stdout.splitlines()) if n is not None]
    line = [l for l in done.stdout.splitlines() if l.startswith(("APLAN-RESULT", "APLAN-ERROR"))][-1]
    result = json.loads(line.split(" ", 1)[1]) if line.startswith("APLAN-RESULT") else line
    workflow.store_detection(analysis, folder)
    stored = read_intent(analysis).diagrams
    return {"command": command[0], "notes": notes, "result": result, "analysis": stored["analysis"],
            "obstructions": stored["obstructions"], "stderr": done.stderr[-2000:]}

out["hybrid"] = detect("hybrid")
# A tiny time limit (what Detect's panel stores), the bound on work back at its default: the limit stops OCCT
# before it decides a relation (1 ns of CPU: less than any OCCT call takes).
from planner.defaults import OCCT_PRISM_TRIANGLES, OCCT_TIME_LIMIT
update_intent(analysis, "a tiny time limit", occt_prism_triangles=OCCT_PRISM_TRIANGLES, occt_time_limit=1e-9)
intent = read_intent(analysis)
out["limit_intent"] = [intent.occt_prism_triangles, intent.occt_time_limit, analysis.OcctTimeLimit]
out["limit"] = detect("limit")
update_intent(analysis, "one triangle per sweep again", occt_prism_triangles=1, occt_time_limit=OCCT_TIME_LIMIT)
intent = read_intent(analysis)
workflow._mesh_python = lambda: None  # as in FreeCAD without the addon's .venv: FreeCADCmd alone
out["alone"] = detect("alone")
print("APLAN-RESULT " + json.dumps(out), flush=True)
"""

DETECT = freecadcmd_job("workbench_occt", lambda tmp: f"REPO = {str(REPO)!r}\nTMP = {str(tmp)!r}\n" + SCRIPT)
BACKGROUND = (DETECT,)
PAIR = ["Block", "Cylinder"]


@pytest.fixture(scope="module")
def detected():
    require_freecadcmd()
    tmp, done = DETECT.result()
    return tmp, freecad_result(done)


def _blocks(obstructions, name: str) -> set:
    return {tuple(p) for o in obstructions if o["direction"] == name for p in o["blocks"]}


@pytest.mark.freecad
def test_a_pair_occt_leaves_undecided_keeps_the_mesh_answer(detected):
    _, data = detected
    run = data["hybrid"]
    assert data["intent"] == ["occt", 1]
    assert run["command"].endswith("python"), run["stderr"]  # the mesh engine's Python: the hybrid runs
    assert isinstance(run["result"], dict), run["result"]
    pairs = run["analysis"]["tolerances"]["pairs"]
    # The far box's two pairs are easy (boxes apart, good meshes): settled on the meshes; OCCT had one pair.
    assert pairs["undecided"] == [PAIR] and pairs["mesh"] == 2 and pairs["occt"] == 0
    (fallback,) = pairs["fallbacks"]
    assert sorted(fallback["parts"]) == PAIR and fallback["answer"] == "mesh"
    assert any("Cylinder moving along +X" in what for what in fallback["relations"]), fallback
    # The mesh engine's answer for the sweep OCCT did not make: the cylinder hits the box along +X only.
    assert ("Cylinder", "Block") in _blocks(run["obstructions"], "+X")
    for axis in ("+Y", "+Z"):
        assert not _blocks(run["obstructions"], axis), axis
    # Told to the user: one note per pair in the job's notes and result, the same lines Diagrams shows.
    told = [n for n in run["notes"] if n.startswith("OCCT left 'Cylinder' and 'Block' undecided")]
    assert len(told) == 1 and told[0].endswith("the mesh engine's answer stands")
    assert run["result"]["undecided"] == told


@pytest.mark.freecad
def test_a_tiny_time_limit_leaves_the_pair_to_the_mesh_answer_and_says_so(detected):
    _, data = detected
    assert data["limit_intent"] == [20000, 1e-9, 1e-9]  # stored in the analysis (OcctTimeLimit)
    run = data["limit"]
    assert isinstance(run["result"], dict), run["result"]
    pairs = run["analysis"]["tolerances"]["pairs"]
    assert pairs["timed_out"] is True and pairs["time_limit"] == 1e-9
    assert pairs["undecided"] == [PAIR] and pairs["mesh"] == 2 and pairs["occt"] == 0
    # The limit stops OCCT before it decides anything: every relation of the pair keeps the mesh answer.
    (fallback,) = pairs["fallbacks"]
    assert fallback["answer"] == "mesh" and "the contact" in fallback["relations"]
    assert ("Cylinder", "Block") in _blocks(run["obstructions"], "+X")
    for axis in ("+Y", "+Z"):
        assert not _blocks(run["obstructions"], axis), axis
    # Progress as it went (OCCT's lines, as aplan analyze prints them), then the limit's stop and the pair.
    assert "occt: deciding 1 of 3 pairs on the exact shapes (at most 1e-09 s)" in run["notes"]
    stop = ("1 pairs not decided within the exact engine's time limit of 1e-09 s; for each, the mesh engine's answer "
            "stands (a longer time limit decides more of them)")
    assert run["result"]["undecided"][0] == stop and stop in run["notes"]
    assert run["result"]["summary"] == "1 pairs not decided within 1e-09 s, mesh answers kept"


@pytest.mark.freecad
def test_the_workbench_and_the_command_line_give_one_answer(detected):
    tmp, data = detected
    done = succeeded(aplan_process("analyze", str(tmp / "hybrid-exported"), "--engine", "occt",
                                   "--occt-prism-triangles", "1"))
    product = load_product(tmp / "hybrid-exported" / "product.json")
    cli = {o.direction.name: sorted(o.blocks) for o in product.obstructions}
    workbench = {o["direction"]: sorted(tuple(p) for p in o["blocks"]) for o in data["hybrid"]["obstructions"]}
    assert cli == workbench, done.stderr
    assert product.geometry["analysis"]["tolerances"]["pairs"]["fallbacks"] == \
        data["hybrid"]["analysis"]["tolerances"]["pairs"]["fallbacks"]


@pytest.mark.freecad
def test_without_the_mesh_engine_the_pair_counts_as_blocking(detected):
    _, data = detected
    run = data["alone"]
    assert run["command"].endswith(("freecadcmd", "FreeCADCmd")) and isinstance(run["result"], dict), run
    pairs = run["analysis"]["tolerances"]["pairs"]
    # OCCT on all three pairs (the far box's decided by boxes), the contacts falling apart: no meshes read here.
    assert pairs["undecided"] == [PAIR] and pairs["occt"] == 2 and pairs["mesh"] == 0
    assert [f["answer"] for f in pairs["fallbacks"]] == ["blocking"]
    assert ("Cylinder", "Block") in _blocks(run["obstructions"], "+X")
    assert run["result"]["undecided"] and all("counted as touching and blocking" in n for n in run["result"]["undecided"])
    assert set(run["result"]["undecided"]) <= set(run["notes"])
