"""Fastener tags and the subassembly tree in the analysis (freecad_aplan.structure), in real FreeCAD without
the GUI: each change one undo step, bad input refused with the parts named, restored on reopen, and exported
into the product's ``fasteners`` and ``subassemblies`` sections (source "designer") that the planner folds
and plans by level."""
from __future__ import annotations

import json
import subprocess

import pytest
from conftest import REPO, require_freecadcmd
from integration.freecad_tools import freecad_result

from planner import api
from planner.product import fold

SCRIPT = r"""
import json, os, sys, tempfile
sys.path.insert(0, {repo!r})
import FreeCAD, Part
from freecad_aplan import structure, workflow
from freecad_aplan.export import export_document
from freecad_aplan.intent import IntentError, create_analysis, find_analysis, read_intent, update_intent

out = {{}}
doc = FreeCAD.newDocument("tags")
doc.UndoMode = 1
for name, size, at in (("Base", (100, 100, 10), (0, 0, 0)), ("Lid", (100, 100, 10), (0, 0, 10)),
                       ("Side", (10, 100, 20), (100, 0, 0)), ("Screw1", (2, 2, 20), (10, 10, 0)),
                       ("Screw2", (2, 2, 20), (80, 80, 0)), ("Nut", (4, 4, 2), (50, 50, 20))):
    box = doc.addObject("Part::Box", name)
    box.Length, box.Width, box.Height = size
    box.Placement.Base = FreeCAD.Vector(*at)
doc.recompute()
product = workflow.export_for_detection(doc, tempfile.mkdtemp())
objects = product["x-freecad-objects"]
ids = {{names[0]: component for component, names in objects.items()}}
B, L, S, s1, s2, n = (ids[k] for k in ("Base", "Lid", "Side", "Screw1", "Screw2", "Nut"))
out["ids"] = [B, L, S, s1, s2, n]
analysis = create_analysis(doc)
try:
    structure.tag_fasteners(analysis, ["Screw1"])
except IntentError as exc:
    out["not_detected"] = str(exc)
# The diagrams a detection would store (by hand: the test is about the structure, not the engines).
volumes = {{B: 1e5, L: 1e5, S: 2e4, s1: 80.0, s2: 80.0, n: 32.0}}
diagrams = {{"parts": out["ids"], "objects": objects, "labels": {{k: k for k in out["ids"]}}, "volumes": volumes,
            "contacts": [[B, L], [L, S], [s1, B], [s1, L], [s2, B], [s2, L], [n, L]], "obstructions": []}}
update_intent(analysis, "detect", diagrams=diagrams)


def refused(call):
    try:
        call()
    except IntentError as exc:
        return str(exc)
    return None


steps = len(doc.UndoNames)
out["unknown"] = refused(lambda: structure.tag_fasteners(analysis, ["Nope"]))
out["one_host"] = refused(lambda: structure.tag_fasteners(analysis, ["Nut"]))
out["steps_after_refused"] = len(doc.UndoNames) - steps
intent = structure.tag_fasteners(analysis, ["Screw1"], "screwdriver")
out["tagged"] = [intent.fasteners, intent.tools, doc.UndoNames[0], len(doc.UndoNames) - steps]
designed, proposals = structure.fastener_report(analysis)
out["designed"] = [[g.id, list(g.parts), sorted(g.hosts), g.tool] for g in designed]
out["proposed"] = [[g.id, list(g.parts), sorted(g.hosts)] for g in proposals.groups]
out["left_out"] = [list(x) for x in proposals.left_out]
steps = len(doc.UndoNames)
intent = structure.accept_fastener_proposals(analysis)
out["accepted"] = [intent.fasteners, len(doc.UndoNames) - steps]
first = read_intent(analysis).fasteners[0]["id"]
intent = structure.accept_fastener_proposals(analysis, [], kept_tools={{first: "hex key"}})
out["retooled"] = [[g.get("tool") for g in intent.fasteners], intent.tools, doc.UndoNames[0]]
doc.undo()
out["untag_none"] = refused(lambda: structure.untag_fasteners(analysis, ["Side"]))
structure.untag_fasteners(analysis, ["Screw1"])
out["untagged"] = [g["objects"] for g in read_intent(analysis).fasteners]
doc.undo()
out["untag_undone"] = [g["objects"] for g in read_intent(analysis).fasteners]
# The subassembly tree: refused with the parts named, nothing stored; then a good one, one undo step.
steps = len(doc.UndoNames)
out["cycle"] = refused(lambda: structure.set_subassemblies(analysis, [{{"id": "a", "parts": ["b", S]}},
                                                                      {{"id": "b", "parts": ["a", B]}}]))
out["twice"] = refused(lambda: structure.set_subassemblies(analysis, [{{"id": "a", "parts": [B, L]}},
                                                                      {{"id": "b", "parts": [L, S]}}]))
out["apart"] = refused(lambda: structure.set_subassemblies(analysis, [{{"id": "apart", "parts": [B, S]}}]))
out["unknown_member"] = refused(lambda: structure.set_subassemblies(analysis, [{{"id": "x", "parts": [B, "ghost"]}}]))
out["steps_after_bad_tree"] = len(doc.UndoNames) - steps
# Lid and Side blocking each other along every axis (as overlapping geometry would): no tree builds them.
update_intent(analysis, "interlock", diagrams=dict(diagrams, obstructions=[
    {{"direction": d, "blocks": [[L, S], [S, L]]}} for d in ("+X", "+Y", "+Z")]))
out["stuck"] = refused(lambda: structure.set_subassemblies(analysis, [{{"id": "stuck", "parts": [L, S]}}]))
doc.undo()
steps = len(doc.UndoNames)
out["document_structure"] = structure.document_structure(analysis)
out["proposed_2"] = structure.proposed_structure(analysis, max_components=2)
# The panel's edits, as plain data (checked when stored).
body = [{{"id": "body", "parts": [B, L], "label": "body"}}]
outer = structure.add_subassembly(body, "outer", ["body", S])
out["edits"] = [outer, structure.move_member(outer, L, None), structure.delete_subassembly(outer, "body"),
                refused(lambda: structure.add_subassembly(body, "body", [S])),
                refused(lambda: structure.move_member(body, S, "nowhere"))]
out["cycle_by_move"] = refused(lambda: structure.set_subassemblies(analysis,
                                                                   structure.move_member(outer, "outer", "body")))
structure.set_subassemblies(analysis, body)
out["tree"] = [read_intent(analysis).subassemblies, doc.UndoNames[0], len(doc.UndoNames) - steps]
out["current"] = structure.current_structure(analysis)
# Export: the tags and the tree become the product's sections (source designer), with the stored diagrams.
folder = tempfile.mkdtemp()
export_document(doc, folder, "tags.FCStd")
out["folder"] = folder
# Saved and reopened: the same tags and tree.
path = os.path.join(tempfile.mkdtemp(), "tags.FCStd")
saved = read_intent(analysis)
doc.saveAs(path)
FreeCAD.closeDocument(doc.Name)
doc = FreeCAD.openDocument(path)
again = read_intent(find_analysis(doc))
out["reopened"] = [again.fasteners == saved.fasteners, again.subassemblies == saved.subassemblies]
print("APLAN-RESULT " + json.dumps(out))
"""


@pytest.mark.freecad
def test_fastener_tags_and_subassembly_tree(tmp_path):
    freecadcmd = require_freecadcmd()
    script = tmp_path / "structure.py"
    script.write_text(SCRIPT.format(repo=str(REPO)))
    data = freecad_result(subprocess.run([freecadcmd, str(script)], capture_output=True, text=True, timeout=300))
    base, lid, side, screw1, screw2, nut = data["ids"]
    assert "no contacts and obstructions yet" in data["not_detected"]
    # Bad tags: refused, naming the object or the one part joined; nothing stored.
    assert "'Nope'" in data["unknown"] and "no such object" in data["unknown"]
    assert data["one_host"] == (f"the fasteners {nut} join only {lid}: a fastener that joins nothing or only one "
                                "part is left as a part (check its contacts in the diagrams panel)")
    assert data["steps_after_refused"] == 0
    tagged, tools, undo_name, steps = data["tagged"]
    group_id = f"fasteners_{base}+{lid}"
    assert tagged == [{"id": group_id, "objects": ["Screw1"], "hosts": ["Base", "Lid"], "tool": "screwdriver"}]
    assert tools == ["screwdriver"] and undo_name == f"APLAN: tag fasteners {group_id}" and steps == 1
    # The planner's report (the call behind `aplan fasteners`): the tagged group, and Screw2 proposed by name;
    # the nut joins one part only, so it is not proposed.
    assert data["designed"] == [[group_id, [screw1], sorted([base, lid]), "screwdriver"]]
    assert [p[1:] for p in data["proposed"]] == [[[screw2], sorted([base, lid])]]
    assert [x[0] for x in data["left_out"]] == [nut]
    accepted, steps = data["accepted"]
    assert [g["objects"] for g in accepted] == [["Screw1"], ["Screw2"]] and steps == 1
    assert accepted[1]["id"] != accepted[0]["id"]
    assert data["retooled"] == [["hex key", None], ["screwdriver", "hex key"], "APLAN: edit fasteners"]
    assert "is tagged as a fastener" in data["untag_none"]
    assert data["untagged"] == [["Screw2"]] and data["untag_undone"] == [["Screw1"], ["Screw2"]]
    # Bad trees: refused with the reason and the parts, nothing stored.
    assert "cycle" in data["cycle"] and "nothing was changed" in data["cycle"]
    assert lid in data["twice"] and "nothing was changed" in data["twice"]
    assert "subassembly apart cannot be built on its own" in data["apart"]
    assert "subassembly stuck cannot be built on its own" in data["stuck"]
    assert lid in data["stuck"].split("built on its own")[1] and side in data["stuck"].split("built on its own")[1]
    assert "ghost" in data["unknown_member"]
    assert data["steps_after_bad_tree"] == 0
    assert data["document_structure"] == []  # no containers
    outer, moved, deleted, duplicate, nowhere = data["edits"]
    assert outer == [{"id": "body", "parts": [base, lid], "label": "body"},
                     {"id": "outer", "parts": ["body", side], "label": "outer"}]
    assert moved[0]["parts"] == [base] and deleted == [{"id": "outer", "parts": [base, lid, side], "label": "outer"}]
    assert "use a new, non-empty name" in duplicate and "no subassembly 'nowhere'" in nowhere
    assert "cycle" in data["cycle_by_move"]
    # Max 2 members per workstation: the planner's own proposal, as --subassemblies auto would plan it.
    assert data["proposed_2"] and all(len(s["parts"]) <= 2 for s in data["proposed_2"])
    tree, undo_name, steps = data["tree"]
    assert tree == [{"id": "body", "parts": [base, lid], "label": "body"}]
    assert (undo_name, steps) == ("APLAN: edit subassemblies", 1)
    assert data["current"] == [tree, "analysis"]
    assert data["reopened"] == [True, True]
    # The export: designer sections the planner uses by default (--fasteners tagged, --subassemblies designer).
    written = json.loads((__import__("pathlib").Path(data["folder"]) / "product.json").read_text())
    assert [(g["parts"], sorted(g["hosts"]), g["source"]) for g in written["fasteners"]] == [
        ([screw1], sorted([base, lid]), "designer"), ([screw2], sorted([base, lid]), "designer")]
    assert {"id": "screwdriver"} in written["tools"]
    assert written["subassemblies"] == [{"id": "body", "parts": [base, lid], "label": "body", "source": "designer"}]
    product = api.resolve_product(data["folder"])
    assert sorted(fold(product).product.part_ids) == sorted([base, lid, side, nut])
    assert [level.id for level in api.levels_of(product)] == ["body", "top"]
