"""Designer intent stored in the document (freecad_aplan.intent), in real FreeCAD, and used by batch export."""
from __future__ import annotations

import functools
import json
import shutil
import subprocess

import pytest
from background import Job, folder, run
from conftest import PEN_MODELS, REPO, require_freecadcmd, require_shared
from integration.freecad_tools import aplan, aplan_process, freecad_result, freecadcmd_job, succeeded

from planner import load_product
from planner.defaults import OCCT_PRISM_TRIANGLES, OCCT_TIME_LIMIT

PEN = PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"
# The pen's technical constraint (paper Sec. V): ink and cartridge only together with the head.
CONSTRAINT = {"parts": ["cartridge_001", "ink_001"], "requires": "head_001", "active": True}
TAG = {"inputs": [["body_001"], ["button_001"]], "robot": False, "tool": "screwdriver", "unfavorable": False}

ROUND_TRIP = """
import json, sys
sys.path.insert(0, {repo!r})
import FreeCAD
from dataclasses import asdict
from freecad_aplan.intent import (IntentError, create_analysis, find_analysis, read_intent, update_intent)
out = {{}}
doc = FreeCAD.openDocument({copy!r})
doc.UndoMode = 1
def snapshot(d):
    return {{o.Name: [list(o.Placement.Base), list(o.Placement.Rotation.Q), round(o.Shape.Volume, 6)]
            for o in d.Objects if hasattr(o, "Shape") and not o.Shape.isNull()}}
before = snapshot(doc)
analysis = create_analysis(doc)
try:
    create_analysis(doc)
except IntentError as exc:
    out["second"] = str(exc)
update_intent(analysis, "group refill", groups={{"refill": ["b_ink_001_", "b_cartridge_001_"]}})
update_intent(analysis, "exclude cap", excluded=["b_cap_001_"])
update_intent(analysis, "tag", tools=["screwdriver"], operations=[{tag!r}])
update_intent(analysis, "constraint", technical_constraints=[{constraint!r}], engine="occt", contact=0.05,
              occt_face_weight=5000)
out["undo_names"] = list(doc.UndoNames)
doc.undo()
out["after_undo"] = [analysis.TechnicalConstraints, analysis.Engine]
doc.redo()
try:
    update_intent(analysis, "bad", engine="magic")
except IntentError as exc:
    out["bad_engine"] = str(exc)
try:
    update_intent(analysis, "bad", occt_prism_triangles=0)
except IntentError as exc:
    out["bad_bound"] = str(exc)
out["bad_limits"] = []
for bad in (0.0, -2.0, float("nan"), float("inf")):
    try:
        update_intent(analysis, "bad", occt_time_limit=bad)
    except IntentError as exc:
        out["bad_limits"].append(str(exc))
out["limit_unchanged"] = analysis.OcctTimeLimit
analysis.OcctFaceWeight = 0  # as the property editor may leave it
try:
    read_intent(analysis)
except IntentError as exc:
    out["zero_bound"] = str(exc)
analysis.OcctFaceWeight = 5000
written = asdict(read_intent(analysis))
analysis.removeProperty("OcctPrismTriangles")  # an analysis saved before it: back with its default, not 0
analysis.removeProperty("OcctTimeLimit")  # likewise
doc.save()
FreeCAD.closeDocument(doc.Name)
doc = FreeCAD.openDocument({copy!r})
again = find_analysis(doc)
out["same"] = asdict(read_intent(again)) == written
out["intent"] = written
out["placements_same"] = snapshot(doc) == before
# An analysis written by a newer APLAN: refused, and nothing changes.
again.FormatVersion = 2
doc.saveAs({newer!r})
FreeCAD.closeDocument(doc.Name)
doc = FreeCAD.openDocument({newer!r})
newer = find_analysis(doc)
for what, call in (("read", lambda: read_intent(newer)),
                   ("update", lambda: update_intent(newer, "x", excluded=[]))):
    try:
        call()
    except IntentError as exc:
        out["newer_" + what] = str(exc)
out["newer_unchanged"] = list(newer.Excluded) == ["b_cap_001_"]
newer.FormatVersion = 1
newer.OperationTags = ["not json"]
try:
    read_intent(newer)
except IntentError as exc:
    out["bad_json"] = str(exc)
print("APLAN-RESULT " + json.dumps(out))
"""


ROUND_TRIP_JOB = freecadcmd_job("round_trip", lambda tmp: ROUND_TRIP.format(
    repo=str(REPO), copy=str(tmp / "pen.FCStd"), newer=str(tmp / "newer.FCStd"), tag=TAG, constraint=CONSTRAINT),
    {"pen.FCStd": PEN})


@pytest.mark.freecad
def test_intent_round_trip_undo_and_newer_format():
    require_freecadcmd()
    require_shared(PEN)
    data = freecad_result(ROUND_TRIP_JOB.result()[1])
    assert "already holds the APLAN analysis" in data["second"]
    assert data["undo_names"][:2] == ["APLAN: constraint", "APLAN: tag"]
    assert data["after_undo"] == [[], "mesh"]
    assert "unknown engine 'magic'" in data["bad_engine"]
    assert data["same"] is True and data["placements_same"] is True
    intent = data["intent"]
    assert intent["groups"] == {"refill": ["b_ink_001_", "b_cartridge_001_"]}
    assert intent["excluded"] == ["b_cap_001_"]
    assert intent["operations"] == [TAG] and intent["tools"] == ["screwdriver"]
    assert intent["technical_constraints"] == [CONSTRAINT]
    assert (intent["engine"], intent["contact"]) == ("occt", 0.05)
    assert (intent["occt_face_weight"], intent["occt_prism_triangles"]) == (5000, OCCT_PRISM_TRIANGLES)
    assert "OcctPrismTriangles must be a whole number >= 1, got 0" in data["bad_bound"]
    # The exact engine's time limit: refused unless a finite number of seconds above 0, as --time-limit; an
    # analysis saved before it reads the command line's default.
    assert intent["occt_time_limit"] == OCCT_TIME_LIMIT and data["limit_unchanged"] == OCCT_TIME_LIMIT
    assert len(data["bad_limits"]) == 4
    for message, bad in zip(data["bad_limits"], ("0.0", "-2.0", "nan", "inf")):
        assert message.startswith("APLAN analysis.OcctTimeLimit: must be a number of seconds above 0"), message
        assert f"got {bad};" in message, message
    assert "OcctFaceWeight must be a whole number >= 1, got 0 (default 20,000)" in data["zero_bound"]
    for key in ("newer_read", "newer_update"):
        assert "format version 2, written by a newer APLAN" in data[key] and "update the APLAN workbench" in data[key]
    assert data["newer_unchanged"] is True
    assert "OperationTags[0]: not valid JSON" in data["bad_json"]


STORE = """
import sys
sys.path.insert(0, {repo!r})
import FreeCAD
from freecad_aplan.intent import create_analysis, update_intent
doc = FreeCAD.openDocument({path!r})
analysis = create_analysis(doc)
update_intent(analysis, "intent", **{changes!r})
doc.save()
print("APLAN-RESULT {{}}")
"""


def _store_intent(tmp_path, name: str, **changes) -> str:
    freecadcmd = require_freecadcmd()
    path = tmp_path / f"{name}.FCStd"
    shutil.copy(require_shared(PEN), path)
    script = tmp_path / f"store_{name}.py"
    script.write_text(STORE.format(repo=str(REPO), path=str(path), changes=changes))
    freecad_result(subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=300))
    return str(path)


#: Intents stored in the pen and exported, by name.
INTENTS = {"tagged": {"tools": ["screwdriver"], "operations": [TAG], "technical_constraints": [CONSTRAINT]},
           "grouped": {"groups": {"refill": ["b_ink_001_", "b_cartridge_001_"]}, "excluded": ["b_button_001_"],
                       "engine": "occt", "contact": 0.05, "occt_time_limit": 60.0}}


def _store_and_export(name: str) -> tuple:
    """The pen with the intent ``INTENTS[name]`` stored (FreeCADCmd), then exported by `aplan export-freecad`:
    (folder, the store's run, the export's run or None); the bundle in folder/b."""
    tmp = folder(name)
    path = tmp / f"{name}.FCStd"
    shutil.copy(PEN, path)
    script = tmp / f"store_{name}.py"
    script.write_text(STORE.format(repo=str(REPO), path=str(path), changes=INTENTS[name]))
    stored = run([shutil.which("freecadcmd") or shutil.which("FreeCADCmd"), str(script)])
    exported = aplan_process("export-freecad", str(path), "-o", str(tmp / "b")) if "APLAN-RESULT" in stored.stdout \
        else None
    return tmp, stored, exported


STORED = {name: Job(f"the pen's {name} intent stored and exported", functools.partial(_store_and_export, name))
          for name in INTENTS}
#: The FreeCAD runs the tests read, done in the background (tests/background.py).
BACKGROUND = (ROUND_TRIP_JOB, *STORED.values())


@pytest.mark.freecad
def test_export_uses_the_stored_intent():
    """Tag and constrain in the document, save; `aplan export-freecad` carries them into product.json, and
    `aplan stats` gives the pen's figures with the technical constraint (README: 39 intentions) and one
    robot-capable operation fewer (the tagged one)."""
    require_freecadcmd()
    require_shared(PEN)
    tmp, stored, exported = STORED["tagged"].result()
    freecad_result(stored)
    succeeded(exported)
    data = json.loads((tmp / "b" / "product.json").read_text())
    assert data["technical_constraints"] == [CONSTRAINT]
    assert data["tools"] == [{"id": "screwdriver"}]
    assert data["operations"] == [TAG]
    stats = json.loads(aplan("stats", str(tmp / "b"), "--json").stdout)
    assert (stats["subassemblies"], stats["states"], stats["intentions"], stats["sequences"]) == (17, 14, 39, 12)
    assert stats["actions"] == 18 - 1


@pytest.mark.freecad
def test_export_uses_stored_components_engine_and_rejects_bad_intent(tmp_path):
    require_freecadcmd()
    require_shared(PEN)
    grouped, stored, exported = STORED["grouped"].result()
    freecad_result(stored)
    succeeded(exported)
    product = load_product(grouped / "b" / "product.json")
    assert sorted(product.part_ids) == ["body_001", "cap_001", "head_001", "refill"]
    assert product.geometry["analysis"]["engine"] == "occt"
    assert product.geometry["analysis"]["tolerances"]["contact"] == 0.05
    # The document's time limit (Detect's panel) bounds the command line's exact engine too.
    assert product.geometry["analysis"]["tolerances"]["pairs"]["time_limit"] == 60.0
    # A tag naming a part the components do not have: a clear error, no bundle.
    bad = _store_intent(tmp_path, "bad", excluded=["b_button_001_"], operations=[TAG])
    done = aplan("export-freecad", bad, "-o", str(tmp_path / "c"), check=False)
    assert done.returncode == 1 and "does not fit the components" in done.stderr
    assert "'button_001' is not a part id" in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "c").exists()
