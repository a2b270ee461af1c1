"""The interlock rules' decisions as proposals that apply without meshes (planner.assembly.interlock_proposals):
what the workbench's interlocks panel lists, stores when the designer accepts one, and refuses when the designer
rejects one. Each proposal, applied to the product's diagrams alone, gives what resolve_interlocks gives with the
meshes; a rejected one raises the one-line refusal of ``--interlocks error`` instead of being applied."""
from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import trimesh
from test_interlocks import AXIS, _analysed, _captured, _press_fit

from planner import make_plan, plan_statistics
from planner.assembly.feasibility import interlocked_pairs
from planner.assembly.interlock_proposals import (REFUSED_KEY, apply_proposal, interlock_proposals,
                                                  record_proposals, refused_interlocks)
from planner.assembly.interlocks import apply_interlock_mode, resolve_interlocks
from planner.errors import InterlockRefusedError, PlannerError
from planner.product import product_from_dict, product_to_dict
from planner.product.designer import designer_geometry


def _without_meshes(product):
    """``product`` as the workbench holds it: its diagrams and parts, no mesh files (through JSON, as stored)."""
    data = product_to_dict(product)
    for part in data["parts"]:
        part.pop("mesh", None)
    return product_from_dict(json.loads(json.dumps(data)))


def _blocks(product, name):
    return set(next(o for o in product.obstructions if o.direction.name == name).blocks)


def _refused(product, proposal):
    designer = {**product.geometry.get("designer", {}), REFUSED_KEY: [
        {k: proposal[k] for k in ("parts", "rule", "text")}]}
    return replace(product, geometry={**product.geometry, "designer": designer})


def test_a_press_fit_proposal_is_the_insertion_axis_and_the_overlaps_marks():
    product, parts = _press_fit()
    (proposal,), lines = interlock_proposals(product, parts)
    assert lines == [] and proposal["rule"] == "overlap" and proposal["parts"] == ["block", "pin"]
    assert proposal["direction"] == [0.0, 0.0, 1.0] and proposal["direction_name"] == "+Z"
    assert proposal["leaving"] == "pin" and "pin leaves block along +Z" in proposal["text"]
    assert "obstruction" not in proposal  # the diagrams have +Z already
    # The marks: what the overlap adds along +Z: the pin moved up hits the block (through the overlap).
    assert proposal["not_blocking"] == [["pin", "block"]] and ("pin", "block") in _blocks(product, "+Z")
    stored = _without_meshes(product)
    applied = apply_proposal(stored, proposal)
    resolved, _, _ = resolve_interlocks(product, parts)
    assert _blocks(applied, "+Z") == _blocks(resolved, "+Z") and not interlocked_pairs(applied)
    assert [(m.blocked, m.blocking, m.direction.name) for m in designer_geometry(applied).not_blocking] == [
        ("pin", "block", "+Z")]
    assert designer_geometry(applied).directions == ()  # an axis: no designer direction
    assert plan_statistics(make_plan(applied)).sequences == 1


def test_a_spline_proposal_adds_its_inclined_axis_and_every_parts_diagram_along_it():
    """The shaft turned 30 degrees about X (as tests/assembly/test_interlocks.py): the direction is none of the
    diagrams', so the proposal carries the diagram along it and adds it to the designer directions."""
    from test_interlocks import TILT, _box, _cylinder

    shaft, hub = _cylinder(8, -30, 30), _cylinder(20, -10, 10).difference(_cylinder(8, -11, 11))
    for k in range(6):
        turn = trimesh.transformations.rotation_matrix(np.radians(60 * k), [0, 0, 1])
        shaft = shaft.union(_box((7, -2, -30), (10, 2, 30)).apply_transform(turn))
        hub = hub.difference(_box((6.5, -1.8, -11), (10, 1.8, 11)).apply_transform(turn))
    product, parts = _analysed({"shaft": shaft.apply_transform(TILT), "hub": hub.apply_transform(TILT)})
    (proposal,), _ = interlock_proposals(product, parts)
    assert proposal["rule"] == "overlap"
    assert np.degrees(np.arccos(min(1.0, abs(float(np.dot(proposal["direction"], AXIS)))))) < 2.0
    # Along the axis, as a detection finds it, the overlapping teeth block both ways: both are marked.
    assert sorted(map(tuple, proposal["obstruction"])) == [("hub", "shaft"), ("shaft", "hub")]
    assert sorted(map(tuple, proposal["not_blocking"])) == [("hub", "shaft"), ("shaft", "hub")]
    applied = apply_proposal(_without_meshes(product), proposal)
    assert len(designer_geometry(applied).directions) == 1 and not interlocked_pairs(applied)
    assert plan_statistics(make_plan(applied)).sequences == 1


def test_a_captured_part_proposal_is_one_component():
    product, parts = _captured()
    (proposal,), _ = interlock_proposals(product, parts)
    assert proposal == {"rule": "component", "parts": ["cover", "knob"], "text": proposal["text"],
                        "component": "cover+knob"}
    applied = apply_proposal(_without_meshes(product), proposal)
    assert applied.part_ids == ("housing", "cover+knob") and applied.contacts == (("housing", "cover+knob"),)
    with pytest.raises(PlannerError, match="names cover, knob, which is not a part"):  # applied already
        apply_proposal(applied, proposal)


def test_a_rejected_proposal_is_the_error_it_is_and_never_applied():
    product, parts = _press_fit()
    (proposal,), _ = interlock_proposals(product, parts)
    refused = _refused(_without_meshes(product), proposal)
    assert refused_interlocks(refused) == [{k: proposal[k] for k in ("parts", "rule", "text")}]
    with pytest.raises(InterlockRefusedError) as caught:   # the workbench's plan (diagrams only)
        make_plan(refused)
    line = caught.value.summary
    assert "\n" not in line and "1 interlocked pair(s), refused by the designer" in line
    assert "the rules would resolve them so: block and pin overlap by" in line and "APLAN > Interlocks" in line
    assert caught.value.pairs == (("block", "pin"),)
    # With the meshes, --interlocks resolve does not apply it either.
    with pytest.raises(InterlockRefusedError, match="refused by the designer"):
        apply_interlock_mode(_refused(product, proposal), "resolve", parts)
    # Accepted, the refusal no longer applies: the pair is not interlocked.
    assert plan_statistics(make_plan(apply_proposal(refused, proposal))).sequences == 1


def test_no_interlock_no_proposal(pen):
    assert interlock_proposals(pen) == ([], [])


def test_a_pair_no_rule_frees_is_a_line_not_a_proposal():
    cage = trimesh.creation.icosphere(4, radius=10).difference(trimesh.creation.icosphere(4, radius=6))
    product, parts = _analysed({"cage": cage, "ball": trimesh.creation.icosphere(4, radius=5.9)})
    proposals, (line,) = interlock_proposals(product, parts)
    assert proposals == [] and line.startswith("cage and ball block each other along every direction tried")



def test_recorded_with_the_diagrams_only_when_something_is_interlocked(pen):
    assert record_proposals(pen) is pen
    product, parts = _press_fit()
    recorded = record_proposals(product, parts)
    assert recorded.obstructions == product.obstructions
    assert recorded.geometry["analysis"]["interlock_proposals"] == interlock_proposals(product, parts)[0]
    assert recorded.geometry["analysis"]["interlock_unresolved"] == []
