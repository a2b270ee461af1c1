"""Fastener proposals (planner.product.fastener_proposals): names, geometry, grouping, and the real models
against the fasteners counted by hand (fastener_ground_truth.json)."""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
from real_models import BACKGROUND, real_bundles  # noqa: F401  (the exports, done in the background; a fixture)

from planner import load_product, resolve_product
from planner.product import FastenerGroup, Part, Product, fastener_proposals, propose_fasteners

GROUND_TRUTH = json.loads((Path(__file__).with_name("fastener_ground_truth.json")).read_text())


def _product(parts: dict[str, float | None], contacts: list[tuple[str, str]], labels: dict | None = None) -> Product:
    labels = labels or {}
    return Product(tuple(Part(p, labels.get(p, ""), volume=v) for p, v in parts.items()), tuple(contacts))


@pytest.mark.parametrize("name, found", [
    ("wood_screw_001", "screw"), ("HexBolt", "bolt"), ("M6 nut", "nut"), ("washers_2", "washer"),
    ("dowelPin", "pin"), ("Rivet", "rivet"), ("spring_clip", "clip"),
    ("spindle", None), ("walnut_panel", None), ("pinion", None), ("clipboard", None), ("nutshell", None)])
def test_names(name, found):
    product = _product({"a": None, "b": None, name: None}, [("a", "b"), ("a", name), ("b", name)])
    groups = propose_fasteners(product)
    if found is None:
        assert groups == []
    else:
        (group,) = groups
        assert group.parts == (name,) and group.hosts == {"a", "b"} and group.source == "proposed"
        assert f"name ({found!r})" in group.reason


def test_a_label_counts_too():
    product = _product({"a": None, "b": None, "x1": None}, [("a", "b"), ("a", "x1"), ("b", "x1")], {"x1": "Screw M4"})
    assert [g.parts for g in propose_fasteners(product)] == [("x1",)]


def test_geometry_and_grouping_by_hosts():
    volumes = {"plate": 1000.0, "frame": 800.0, "wheel": 500.0, "s1": 5.0, "s2": 5.0, "s3": 5.0, "s4": 5.0,
               "t1": 5.0, "spacer": 300.0, "clamp": 60.0}
    contacts = [("plate", "frame"), ("frame", "wheel"), ("plate", "spacer"), ("spacer", "wheel"),
                ("clamp", "wheel"), ("clamp", "spacer")]
    contacts += [(s, h) for s in ("s1", "s2", "s3", "s4") for h in ("frame", "wheel")]
    contacts += [("t1", "plate"), ("t1", "frame")]
    found = {g.id: g for g in propose_fasteners(_product(volumes, contacts))}
    # four screws on one wheel are one group; the spacer is large and the clamp not ten times smaller than
    # the spacer (300 < 10 x 60)
    assert set(found) == {"fasteners_frame+wheel", "fasteners_frame+plate"}
    assert found["fasteners_frame+wheel"].parts == ("s1", "s2", "s3", "s4")
    assert found["fasteners_frame+wheel"].reason.startswith("s1: geometry (volume 5") and "(and 3 more)" in \
        found["fasteners_frame+wheel"].reason
    assert found["fasteners_frame+plate"].parts == ("t1",)


def test_touching_fasteners_are_one_fastener_and_one_host_is_left_out():
    volumes = {"a": 100.0, "b": 100.0, "bolt": 1.0, "nut": 1.0, "washer": 1.0, "lone_screw": 1.0}
    contacts = [("a", "b"), ("bolt", "a"), ("bolt", "nut"), ("nut", "b"), ("washer", "nut"), ("lone_screw", "a")]
    proposals = fastener_proposals(_product(volumes, contacts))
    (group,) = proposals.groups
    assert group.parts == ("bolt", "nut", "washer") and group.hosts == {"a", "b"}
    assert proposals.left_out == (("lone_screw", "name ('screw'), but it joins only a: left as a part "
                                                 "(check its contacts)"),)


def test_tagged_parts_are_neither_proposed_nor_hosts():
    product = _product({"a": None, "b": None, "screw": None, "nut": None},
                       [("a", "b"), ("a", "screw"), ("b", "screw"), ("screw", "nut"), ("nut", "b"), ("nut", "a")])
    tagged = Product(product.parts, product.contacts, fasteners=(FastenerGroup("s", ("screw",)),))
    assert [g.parts for g in propose_fasteners(tagged)] == [("nut",)]


def test_the_pen_has_no_fasteners():
    assert fastener_proposals(resolve_product("pen")).groups == ()


@pytest.mark.freecad
@pytest.mark.parametrize("model", ["toy_truck", "diaphragm_pump"])
def test_real_models_against_the_hand_count(real_bundles, model):  # noqa: F811
    truth = GROUND_TRUTH[model]
    product = load_product(real_bundles[model] / "product.json")
    assert len(product.parts) == truth["parts"]
    fasteners = set(truth["fasteners"])
    assert fasteners <= set(product.part_ids)
    proposals = fastener_proposals(product)
    proposed = {p for group in proposals.groups for p in group.parts}
    measured = truth["measured"]
    assert len(proposed & fasteners) == measured["proposed_fasteners"]
    assert len(proposed - fasteners) == measured["wrong_proposals"]
    assert len(proposals.groups) == measured["groups"]
    assert sorted(fasteners - proposed) == measured["missed"]
    # every proposal is a valid group: accepted, the product still checks and folds
    accepted = resolve_product(product, fasteners="auto")
    assert len(accepted.fasteners) == measured["groups"]


def _bolt_through_a_bore(bore: bool) -> Product:
    """A motor held on a body by a long bolt through the motor's bore (clearance: no contact), a washer under
    its head: the washer touches the motor and the bolt, the bolt the washer and the body (the pump's 11_001,
    12_*, 13_*, 1_001; no fastener words in the ids). With ``bore``, the motor blocks the bolt both ways along Y
    and Z."""
    from planner.product import Direction, Obstruction

    volumes = {"body": 600000.0, "motor": 130000.0, "ring": 200.0, "shank": 4000.0, "cover": 9000.0}
    contacts = [("body", "motor"), ("ring", "motor"), ("ring", "shank"), ("shank", "body"), ("cover", "body")]
    around = (("shank", "motor"), ("motor", "shank")) if bore else ()
    obstructions = (Obstruction(Direction.from_vector((1.0, 0.0, 0.0)), (("shank", "body"),)),
                    Obstruction(Direction.from_vector((0.0, 1.0, 0.0)), around),
                    Obstruction(Direction.from_vector((0.0, 0.0, 1.0)), around))
    return Product(tuple(Part(p, volume=v) for p, v in volumes.items()), tuple(contacts), obstructions)


def test_a_bolt_through_a_bore_held_by_a_washer_joins_what_the_washer_clamps():
    (group,) = propose_fasteners(_bolt_through_a_bore(bore=True))
    assert group.parts == ("ring", "shank") and group.hosts == {"motor", "body"}
    # without the bore the bolt is a host of the washer, as before (and the washer joins the motor and the bolt)
    (group,) = propose_fasteners(_bolt_through_a_bore(bore=False))
    assert group.parts == ("ring",) and group.hosts == {"motor", "shank"}


def test_a_shaft_needs_a_single_other_part_and_large_hosts():
    product = _bolt_through_a_bore(bore=True)
    # the bolt also touches the cover: not a shaft screwed into one part
    touching_two = replace(product, contacts=product.contacts + (("shank", "cover"),))
    assert [g.parts for g in propose_fasteners(touching_two)] == [("ring",)]
    # a motor not ten times the bolt's volume
    small_motor = replace(product, parts=tuple(replace(p, volume=30000.0) if p.id == "motor" else p
                                               for p in product.parts))
    assert [g.parts for g in propose_fasteners(small_motor)] == [("ring",)]


@pytest.mark.parametrize("name", ["Ball001", "ball_3", "NeedleRoller", "taper rollers"])
def test_rolling_elements_are_no_fasteners(name):
    """A bearing's balls, rollers, needles are small parts between two larger ones, yet no fasteners."""
    product = _product({"inner": 1000.0, "outer": 1000.0, name: 5.0}, [("inner", name), ("outer", name)])
    proposals = fastener_proposals(product)
    assert proposals.groups == ()
    assert [(p, r.split(":")[1].strip()) for p, r in proposals.left_out] == [
        (name, "a rolling element, not a fastener")]


def _bearing(balls_in_bearing_with_rings: bool) -> Product:
    """Two rings and three balls numbered as the pump numbers its parts (no word says what they are), the
    balls touching both rings; the designer's subassembly 'bearing' holds the balls, with both rings or with
    the inner one only."""
    volumes = {"inner": 1000.0, "outer": 1000.0, "4_001": 5.0, "4_002": 5.0, "4_003": 5.0}
    contacts = [(b, r) for b in ("4_001", "4_002", "4_003") for r in ("inner", "outer")]
    members = ("inner", "outer", "4_001", "4_002", "4_003") if balls_in_bearing_with_rings else \
        ("inner", "4_001", "4_002", "4_003")
    product = _product(volumes, contacts)
    from planner.product import Subassembly

    return replace(product, subassemblies=(Subassembly("bearing", members),))


def test_the_designers_own_joint_is_not_folded():
    """Balls that the designer's subassembly holds with every part they touch stay parts (said why); balls
    whose hosts are outside it are proposed, saying that folding takes them out of the subassembly."""
    proposals = fastener_proposals(_bearing(True))
    assert proposals.groups == ()
    assert [p for p, _ in proposals.left_out] == ["4_001", "4_002", "4_003"]
    assert all("the designer's subassembly 'bearing' holds it with every part it touches" in r
               for _, r in proposals.left_out)
    (group,) = fastener_proposals(_bearing(False)).groups
    assert group.parts == ("4_001", "4_002", "4_003")
    assert "folding takes it out of the designer's subassembly 'bearing'" in group.reason


def test_folding_a_subassemblys_members_reads_back(caplog):
    """Folded balls leave the subassembly 'bearing' with the inner ring only: it is dissolved with a warning
    naming it and the fasteners, and the product reads back (issue 26: '4_003' is neither a part nor ...)."""
    product = _bearing(False)
    folded = resolve_product(product, fasteners="auto", subassemblies="designer")
    assert sorted(folded.fastener_parts) == ["4_001", "4_002", "4_003"]
    from planner.product import fold_fasteners

    assert fold_fasteners(folded).subassemblies == ()
    assert "subassembly 'bearing' is dissolved: folding the fasteners 4_001, 4_002, 4_003 leaves it only " \
           "inner, which takes its place" in caplog.text
    assert "the proposed fastener group fasteners_inner+outer folds 4_001, 4_002, 4_003, members of the " \
           "designer's subassembly bearing; --fasteners tagged keeps them parts" in caplog.text
