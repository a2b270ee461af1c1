"""Interlocked pairs resolved from the meshes (planner.assembly.interlocks): a press fit and a spline modelled
overlapping are inserted along their axis, a captured part becomes one component with its cover, a ball in a
closed cage is refused in one line. Expected directions and volumes in closed form."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from planner import make_plan, plan_statistics
from planner.assembly.feasibility import interlocked_pairs
from planner.errors import InterlockedPartsError, PlannerError
from planner.geometry import PartMesh, Tolerances, analyze_meshes
from planner.geometry.bundle import apply_report
from planner.assembly.interlocks import apply_interlock_mode, resolve_interlocks
from planner.product import FastenerGroup, Obstruction, Direction, Part, Product
from planner.product.merge import merge_parts

SECTIONS = 64
TURN = np.radians(30)
AXIS = np.array([0.0, -np.sin(TURN), np.cos(TURN)])   # +Z turned by 30 degrees about X
TILT = trimesh.transformations.rotation_matrix(TURN, [1, 0, 0])


def _move(x=0.0, y=0.0, z=0.0):
    return trimesh.transformations.translation_matrix((x, y, z))


def _cylinder(radius, z0, z1, x=0.0, y=0.0):
    return trimesh.creation.cylinder(radius=radius, height=z1 - z0, sections=SECTIONS,
                                     transform=_move(x, y, (z0 + z1) / 2))


def _box(lo, hi):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=_move(*(lo + hi) / 2))


def _analysed(meshes: dict[str, trimesh.Trimesh]) -> tuple[Product, list[PartMesh]]:
    parts = [PartMesh(n, np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)) for n, m in meshes.items()]
    report = analyze_meshes(parts, Tolerances(directions=0))
    return apply_report(Product(tuple(Part(n) for n in meshes), ()), report), parts


def _press_fit():
    block = _box((0, 0, 0), (40, 40, 20)).difference(_cylinder(5, 5, 21, 20, 20))
    return _analysed({"block": block, "pin": _cylinder(5.1, 5, 30, 20, 20)})


def test_a_press_fit_pin_is_inserted_along_its_axis():
    product, parts = _press_fit()
    assert [(p.first, p.second) for p in interlocked_pairs(product)] == [("block", "pin")]
    resolved, decisions, unresolved = resolve_interlocks(product, parts)
    assert unresolved == () and [d.rule for d in decisions] == ["overlap"]
    decision = decisions[0]
    assert decision.direction.name == "+Z" and "pin leaves block along +Z" in decision.text
    # The overlap: the annulus between two regular 64-gons (radii 5.1 and 5) over the bore's 15 mm.
    annulus = SECTIONS / 2 * np.sin(2 * np.pi / SECTIONS) * (5.1 ** 2 - 5 ** 2) * 15
    volume = float(decision.text.split("overlap by ")[1].split(" ")[0])
    assert volume == pytest.approx(annulus, rel=0.01)
    plus_z = next(o for o in resolved.obstructions if o.direction.name == "+Z")
    assert ("block", "pin") in plus_z.blocks and ("pin", "block") not in plus_z.blocks  # the pin leaves upwards
    assert plan_statistics(make_plan(resolved)).sequences == 1
    assert resolved.geometry["analysis"]["interlocks"][0]["rule"] == "overlap"


def test_a_spline_modelled_overlapping_slides_along_its_inclined_axis():
    """Six teeth 4 mm wide in keyways 3.6 mm wide, the shaft turned 30 degrees about X: no axis frees the hub,
    the overlap's axis (its normals turn around it) does, and it is the shaft's."""
    shaft, hub = _cylinder(8, -30, 30), _cylinder(20, -10, 10).difference(_cylinder(8, -11, 11))
    for k in range(6):
        turn = trimesh.transformations.rotation_matrix(np.radians(60 * k), [0, 0, 1])
        shaft = shaft.union(_box((7, -2, -30), (10, 2, 30)).apply_transform(turn))
        hub = hub.difference(_box((6.5, -1.8, -11), (10, 1.8, 11)).apply_transform(turn))
    product, parts = _analysed({"shaft": shaft.apply_transform(TILT), "hub": hub.apply_transform(TILT)})
    assert interlocked_pairs(product)
    resolved, decisions, unresolved = resolve_interlocks(product, parts)
    assert unresolved == () and [d.rule for d in decisions] == ["overlap"]
    angle = np.degrees(np.arccos(min(1.0, abs(float(np.dot(decisions[0].direction.vector, AXIS))))))
    assert angle < 2.0
    assert not interlocked_pairs(resolved) and plan_statistics(make_plan(resolved)).sequences == 1


def test_a_peg_in_an_inclined_slot_leaves_along_a_direction_found_on_the_pair():
    """No overlap, and the diagrams have the axes only: the pair's own faces give the slot's direction, tested
    on the pair, then added to the product as a whole diagram."""
    turned = trimesh.transformations.rotation_matrix(TURN, [1, 0, 0])
    block = trimesh.creation.box(extents=(30, 30, 30)).difference(trimesh.creation.box((10, 10, 80), turned))
    product, parts = _analysed({"block": block, "peg": trimesh.creation.box((10, 10, 60), turned)})
    assert [o.direction.name for o in product.obstructions] == ["+X", "+Y", "+Z"] and interlocked_pairs(product)
    resolved, decisions, unresolved = resolve_interlocks(product, parts)
    assert unresolved == () and [d.rule for d in decisions] == ["direction"]
    assert abs(abs(float(np.dot(decisions[0].direction.vector, AXIS))) - 1) < 1e-6
    added = resolved.obstructions[-1]
    assert added.direction == decisions[0].direction and added.blocks == ()   # sliding out: nothing blocks
    assert plan_statistics(make_plan(resolved)).sequences == 1


def _captured():
    """A knob whose collar lies under a cover and whose head sits on it, the cover on a housing."""
    housing = _box((0, 0, 0), (60, 60, 20)).difference(_box((10, 10, 10), (50, 50, 21)))
    cover = _box((0, 0, 20), (60, 60, 25)).difference(_cylinder(4, 19, 26, 30, 30))
    knob = _cylinder(10, 16, 20, 30, 30).union(_cylinder(4, 19.5, 25.5, 30, 30)).union(_cylinder(8, 25, 28, 30, 30))
    return _analysed({"housing": housing, "cover": cover, "knob": knob})


def test_a_part_captured_by_a_cover_becomes_one_component_with_it():
    product, parts = _captured()
    assert [(p.first, p.second) for p in interlocked_pairs(product)] == [("cover", "knob")]
    resolved, decisions, unresolved = resolve_interlocks(product, parts)
    assert unresolved == () and [(d.rule, d.component) for d in decisions] == [("component", "cover+knob")]
    assert resolved.part_ids == ("housing", "cover+knob") and resolved.contacts == (("housing", "cover+knob"),)
    assert plan_statistics(make_plan(resolved)).sequences == 1
    # Refused on request: the proposal named, nothing planned.
    with pytest.raises(InterlockedPartsError) as refused:
        apply_interlock_mode(product, "error", parts)
    assert "refused by --interlocks error" in refused.value.summary
    assert "cover and knob: one component cover+knob" in refused.value.summary
    with pytest.raises(InterlockedPartsError):  # kept: the planner's own proof
        make_plan(apply_interlock_mode(product, "keep", parts))


def test_a_pair_no_rule_frees_is_one_line():
    cage = trimesh.creation.icosphere(4, radius=10).difference(trimesh.creation.icosphere(4, radius=6))
    product, parts = _analysed({"cage": cage, "ball": trimesh.creation.icosphere(4, radius=5.9)})
    with pytest.raises(InterlockedPartsError) as caught:
        apply_interlock_mode(product, "resolve", parts)
    line = caught.value.summary
    assert "\n" not in line and line.startswith("cage and ball block each other along every direction tried "
                                                "(+/-X, +/-Y, +/-Z")
    assert "one component of them would be the whole product" in line
    assert "--direction X,Y,Z" in line and "diagrams panel" in line and "--not-blocking cage ball" in line


def test_a_product_without_interlocks_is_left_as_it_is(pen):
    assert apply_interlock_mode(pen) is pen
    assert resolve_interlocks(pen) == (pen, (), ())


def test_a_product_without_meshes_is_planned_as_written():
    blocks = (("b", "c"), ("c", "b"))
    product = Product((Part("a"), Part("b"), Part("c")), (("a", "b"), ("b", "c")),
                      tuple(Obstruction(Direction.from_vector(v), blocks) for v in np.eye(3)))
    assert apply_interlock_mode(product) is product
    with pytest.raises(PlannerError, match="unknown interlock mode"):
        apply_interlock_mode(product, "later")


def test_merged_parts_keep_every_relation_with_the_others():
    product = Product((Part("a", volume=1.0), Part("b", volume=2.0), Part("c"), Part("s")),
                      (("a", "b"), ("b", "c"), ("a", "c"), ("s", "c"), ("s", "a")),
                      (Obstruction(Direction.from_vector((1.0, 0.0, 0.0)), (("a", "b"), ("c", "a"), ("c", "b"))),),
                      fasteners=(FastenerGroup("g", ("s",)),))
    merged = merge_parts(product, "ab", ("a", "b"))
    assert merged.part_ids == ("ab", "c", "s") and merged.parts[0].volume == 3.0
    assert merged.contacts == (("ab", "c"), ("s", "c"), ("s", "ab")) and merged.obstructions[0].blocks == (("c", "ab"),)
    with pytest.raises(PlannerError, match="s is a fastener"):
        merge_parts(product, "cs", ("c", "s"))
