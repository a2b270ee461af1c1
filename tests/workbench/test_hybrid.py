"""The merge of the mesh engine's and OCCT's answers (freecad_aplan/hybrid.py, no FreeCAD needed): OCCT's
answer is taken relation by relation for the pairs it was asked, the mesh engine's kept for everything else
and for every relation OCCT left undecided."""
from __future__ import annotations

import pytest

from freecad_aplan.hybrid import (exact_pairs, fallback_parts, merge_reports, mesh_then_occt, time_limit_note,
                                  undecided_notes, undecided_summary)
from freecad_aplan.plugin import occt_report
from planner.errors import GeometryError
from planner.geometry import Tolerances
from planner.geometry.mesh_engine import analyze_meshes
from planner.product import product_from_dict
from test_budgets import box_meshes


def _mesh():
    return analyze_meshes(box_meshes(), Tolerances(directions=0))


def test_easy_pairs_are_the_far_ones_between_good_meshes():
    meshes = box_meshes()
    # a-b, b-c touch (boxes within the contact tolerance); a-c and the far box are apart.
    assert exact_pairs(meshes, {}, 0.01, near=True) == [("a", "b"), ("b", "c")]
    assert exact_pairs(meshes, {}, 0.01, near=False) == []
    assert exact_pairs(meshes, {"far": "exact"}, 0.01, near=False) == [("a", "far"), ("b", "far"), ("c", "far")]
    assert exact_pairs(meshes, {}, 0.01, near=True, hulls={"b": "hull"}) == []  # decided on the hull's mesh


def test_occt_decides_relation_by_relation():
    mesh = _mesh()
    assert ("a", "b") in mesh.obstructions["+X"] and ("b", "c") in mesh.obstructions["+X"]
    # OCCT (made up, to tell the sources apart): a and b do not touch, a moving along +X is undecided, b moving
    # along +X does not hit c; the pair b-c keeps its contact.
    occt = {"contacts": [["b", "c"]], "interferences": [], "undecided": [["a", "b"]],
            "undecided_relations": [["a", "b", "a moving along +X"]], "timed_out": True, "time_limit": 1.0,
            "obstructions": {"+X": [], "+Y": [], "+Z": []}, "warnings": ["w"]}
    merged = merge_reports(mesh, occt, [("a", "b"), ("b", "c")], "occt", {})
    assert {frozenset(c) for c in merged.contacts} == {frozenset(("b", "c"))}
    assert ("a", "b") in merged.obstructions["+X"]      # undecided: the mesh answer
    assert ("b", "c") not in merged.obstructions["+X"]  # decided by OCCT
    record = merged.tolerances["pairs"]
    assert record == {"mesh": 6 - 2, "occt": 1, "undecided": [["a", "b"]], "undecided_relations": 1,
                      "timed_out": True, "time_limit": 1.0, "fallback": {},
                      "fallbacks": [{"parts": ["a", "b"], "relations": ["a moving along +X"], "answer": "mesh"}]}
    assert merged.engine == "occt" and "w" in merged.warnings
    # Told per pair to the user (the workbench's job notes and Diagrams panel, undecided_notes).
    # The time limit's stop first: how many pairs it left, within how long, and what was kept for them.
    assert undecided_notes(merged.tolerances) == [
        "1 pairs not decided within the exact engine's time limit of 1 s; for each, the mesh engine's answer "
        "stands (a longer time limit decides more of them)",
        "OCCT left 'a' and 'b' undecided (a moving along +X): the mesh engine's answer stands"]
    assert undecided_summary(merged.tolerances) == "1 pairs not decided within 1 s, mesh answers kept"
    # Not stopped by the limit (a bound on one pair's work): the pairs alone.
    bounded = {"pairs": {**record, "timed_out": False}}
    assert time_limit_note(bounded) is None and len(undecided_notes(bounded)) == 1
    assert undecided_summary(bounded) == "1 pairs undecided by OCCT"


def test_without_the_mesh_engine_undecided_pairs_count_as_blocking():
    # OCCT on every pair (FreeCADCmd's Python has no trimesh): its undecided pair is recorded as blocking.
    product = product_from_dict({"format": "aplan-product", "version": 1, "contacts": [],
                                 "parts": [{"id": "a"}, {"id": "b"}, {"id": "c"}]}, "t")
    occt = {"contacts": [["a", "b"]], "interferences": [], "obstructions": {"+X": [["a", "b"]], "+Y": [], "+Z": []},
            "undecided": [["a", "b"]], "undecided_relations": [["a", "b", "the contact"]]}
    report = occt_report(product, occt)
    assert report.tolerances["pairs"]["occt"] == 3 - 1
    assert undecided_notes(report.tolerances) == [
        "OCCT left 'a' and 'b' undecided (the contact): counted as touching and blocking (no mesh engine's answer "
        "to fall back to)"]
    assert undecided_summary(report.tolerances) == "1 pairs undecided by OCCT"
    assert undecided_notes({}) == [] and undecided_notes(_mesh().tolerances) == []
    assert undecided_summary({}) == "" and undecided_summary(_mesh().tolerances) == ""


def test_fallback_parts_come_from_the_bundle_rules():
    product = product_from_dict({"format": "aplan-product", "version": 1, "parts": [{"id": "a"}, {"id": "s"},
                                 {"id": "h"}, {"id": "old"}], "contacts": [],
                                 "geometry": {"mesh_check": {"parts": {"a": {"method": "standard", "rule": "mesh"},
                                                                       "s": {"method": "exact", "rule": "exact"},
                                                                       "h": {"method": "exact", "rule": "hull"},
                                                                       "old": {"method": "exact"}}}}}, "t")
    assert fallback_parts(product) == {"s": "exact", "old": "exact"}


def test_the_occt_bounds_reach_the_exact_engine_and_the_record():
    # --occt-face-weight and --occt-prism-triangles (Tolerances) go to the analyze-occt job with the pairs it
    # decides; what they left undecided (a sweep that lost a face) is kept in the record beside them.
    product = product_from_dict({"format": "aplan-product", "version": 1, "contacts": [],
                                 "parts": [{"id": m.id} for m in box_meshes()]}, "t")
    asked = []

    def run_occt(arguments):
        asked.append(arguments)
        return {"contacts": [["a", "b"], ["b", "c"]], "interferences": [], "obstructions": {"+X": [], "+Y": [], "+Z": []},
                "undecided": [["a", "b"]], "undecided_relations": [["a", "b", "a moving along +X"]],
                "face_weight": 7, "prism_triangles": 9, "sweeps_lost": [["a", "+X", 1]], "sweeps_over": []}

    merged = mesh_then_occt(product, box_meshes(), Tolerances(directions=0, face_weight=7, prism_triangles=9), "occt",
                            run_occt)
    (arguments,) = asked
    assert (arguments["face_weight"], arguments["prism_triangles"]) == (7, 9)
    assert arguments["pairs"] == [["a", "b"], ["b", "c"]]
    record = merged.tolerances["pairs"]
    assert (record["face_weight"], record["prism_triangles"], record["sweeps_lost"]) == (7, 9, [["a", "+X", 1]])
    assert "sweeps_over" not in record  # empty: not recorded
    assert ("a", "b") in merged.obstructions["+X"]  # the lost sweep's relation: the mesh answer


def test_the_occt_bounds_are_whole_numbers_of_at_least_one():
    for name in ("face_weight", "prism_triangles"):
        for bad in (0, -1, 2.5, True):
            with pytest.raises(GeometryError, match=f"{name} must be a whole number >= 1"):
                Tolerances(**{name: bad})


def test_the_face_weight_reaches_the_export(monkeypatch, tmp_path):
    # export-freecad --occt-face-weight: the export job gets it too (its fallback rules: freecad_aplan.export).
    from conftest import PEN_MODELS, require_shared

    from freecad_aplan import plugin
    from freecad_aplan.runner import FreeCADError

    model = require_shared(PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd")
    jobs = []

    def run_batch(action, arguments, freecadcmd=None):
        jobs.append((action, arguments))
        raise FreeCADError("stopped here")

    monkeypatch.setattr(plugin, "run_batch", run_batch)
    for tolerances in ({"face_weight": 123}, Tolerances(face_weight=456)):
        with pytest.raises(FreeCADError, match="stopped here"):
            plugin.export_bundle(model, tmp_path / "b", "occt", tolerances)
    assert [(action, arguments["face_weight"]) for action, arguments in jobs] == [("export", 123), ("export", 456)]
    assert list(tmp_path.iterdir()) == []  # nothing written
