"""A closed gearbox (issue 26): the parts come apart one by one, but a gear whose shaft is out rests in the
housing touching nothing, so the topological constraint refuses the split; the error says so. With the diagram
across its shafts and the parts' bounding boxes, the support-contact rule (planner.assembly.support_contacts)
lets it plan once each gear rests in the housing; a gear that sticks out of the housing's box, or a product
that plans already, keeps its contacts (and its error)."""
from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
import pytest
import trimesh

from aplan_runner import run_aplan
from planner import NotDisassemblableError, Obstruction, Part, Product, and_or_graph, resolve_product
from planner.assembly.support_contacts import apply_support_mode, support_contacts
from planner.errors import InterlockedPartsError, PlannerError, SupportRefusedError
from planner.geometry import PartMesh
from planner.product import AXIS_DIRECTIONS, Direction
from planner.product.io import save_product

GEARBOX_CONTACTS = (("housing", "shaft_a"), ("housing", "shaft_b"), ("shaft_a", "gear_a"),
                    ("shaft_b", "gear_b"), ("gear_a", "gear_b"))

#: cm^3: the housing is the largest part (the error names the parts the others would rest in by volume)
VOLUMES = {"housing": 500.0, "shaft_a": 20.0, "shaft_b": 20.0, "gear_a": 40.0, "gear_b": 40.0, "shaft": 20.0}


def gearbox(extra_contacts=()) -> Product:
    """Housing open at the top (+Z), two shafts along Y through bores in its walls, a gear keyed on each
    shaft inside, the gears meshing. Along +Z a gear hits its shaft, a shaft hits the housing (its bores) and
    its gear, the housing hits everything (its floor and bores); along +Y a gear and the housing hit each
    other (the walls) and shafts slide free. No pair blocks each other along both directions."""
    parts = tuple(Part(p, volume=v) for p, v in VOLUMES.items() if p != "shaft")
    up = Obstruction(Direction("+Z", AXIS_DIRECTIONS["+Z"]), (
        ("gear_a", "shaft_a"), ("gear_b", "shaft_b"), ("shaft_a", "housing"), ("shaft_a", "gear_a"),
        ("shaft_b", "housing"), ("shaft_b", "gear_b"), ("housing", "shaft_a"), ("housing", "shaft_b"),
        ("housing", "gear_a"), ("housing", "gear_b")))
    axis = Obstruction(Direction("+Y", AXIS_DIRECTIONS["+Y"]), (
        ("gear_a", "housing"), ("housing", "gear_a"), ("gear_b", "housing"), ("housing", "gear_b")))
    return Product(parts, GEARBOX_CONTACTS + tuple(extra_contacts), obstructions=(up, axis))


def test_the_error_names_the_smallest_stuck_subassembly_and_the_floating_gear():
    with pytest.raises(NotDisassemblableError) as info:
        and_or_graph(gearbox())
    error = info.value
    assert not isinstance(error, InterlockedPartsError)
    assert error.stuck == ["housing", "shaft_a", "shaft_b", "gear_a", "gear_b"]
    # Out goes shaft_b (along Y), then gear_b (+Z, nothing above it now): {housing, shaft_a, gear_a} is left,
    # and only shaft_a leaves it, leaving gear_a touching nothing. (Taking shaft_a out first is the mirror
    # image; the tie goes to the smaller bitmask, the one without shaft_b.)
    assert error.smallest == ["housing", "shaft_a", "gear_a"]
    assert "The smallest subassembly with no feasible split is {housing, shaft_a, gear_a}." in str(error)
    assert error.floating.startswith("taking shaft_a out would leave gear_a touching nothing inside housing")
    assert "gear_a and housing in the product's contacts" in error.floating
    assert "--group NAME=housing,gear_a" in error.floating
    assert error.floating_parts == ("gear_a",)
    assert error.summary == ("cannot be disassembled: {housing, shaft_a, gear_a} has no feasible split: "
                             + error.floating)


def test_the_advised_support_contacts_free_the_gearbox():
    andor = and_or_graph(gearbox((("gear_a", "housing"), ("gear_b", "housing"))))
    assert andor.subassemblies and andor.parts_of(0) == frozenset(gearbox().part_ids)


def test_a_stuck_product_without_a_refused_split_keeps_the_generic_advice():
    # A cycle along +X (a hits b, b hits c, c hits a): blocked, nothing floats.
    parts = tuple(Part(p) for p in ("a", "b", "c"))
    cyclic = Obstruction(Direction("+X", AXIS_DIRECTIONS["+X"]), (("a", "b"), ("b", "c"), ("c", "a")))
    with pytest.raises(NotDisassemblableError) as info:
        and_or_graph(Product(parts, (("a", "b"), ("b", "c"), ("a", "c")), obstructions=(cyclic,)))
    assert info.value.floating == "" and info.value.smallest == ["a", "b", "c"]
    assert "Check the obstruction relations" in str(info.value)


def test_parts_that_touch_only_each_other_are_named_together():
    """One shaft through the housing carrying two gears side by side: once the shaft is out (along Y), the
    gears touch only each other; nothing else leaves the product."""
    parts = tuple(Part(p, volume=VOLUMES[p]) for p in ("housing", "shaft", "gear_a", "gear_b"))
    up = Obstruction(Direction("+Z", AXIS_DIRECTIONS["+Z"]), (
        ("gear_a", "shaft"), ("gear_b", "shaft"), ("shaft", "housing"), ("shaft", "gear_a"), ("shaft", "gear_b"),
        ("housing", "shaft"), ("housing", "gear_a"), ("housing", "gear_b")))
    axis = Obstruction(Direction("+Y", AXIS_DIRECTIONS["+Y"]), (
        ("gear_a", "housing"), ("housing", "gear_a"), ("gear_b", "housing"), ("housing", "gear_b"),
        ("gear_a", "gear_b")))
    contacts = (("housing", "shaft"), ("shaft", "gear_a"), ("shaft", "gear_b"), ("gear_a", "gear_b"))
    with pytest.raises(NotDisassemblableError) as info:
        and_or_graph(Product(parts, contacts, obstructions=(up, axis)))
    assert info.value.smallest == info.value.stuck == ["housing", "shaft", "gear_a", "gear_b"]
    assert info.value.floating.startswith(
        "taking shaft out would leave gear_a, gear_b touching only each other inside housing")
    # The support contact the error advises frees it.
    and_or_graph(Product(parts, contacts + (("gear_a", "housing"),), obstructions=(up, axis)))


#: The gearbox's boxes (mm): the housing's cavity holds the gears (x 14..50 and 50..86, meshing at x = 50);
#: the shafts along Y reach out through its walls.
BOXES = {"housing": ((0, 0, 0), (100, 60, 60)), "shaft_a": ((27, -15, 25), (37, 75, 35)),
         "shaft_b": ((63, -15, 25), (73, 75, 35)), "gear_a": ((14, 25, 12), (50, 35, 48)),
         "gear_b": ((50, 25, 12), (86, 35, 48))}


def closed_gearbox() -> Product:
    """``gearbox()`` with its diagram across the shafts (+X): the housing's walls and bores hold the gears and
    the shafts both ways, a shaft holds its gear (its bore) both ways, and gear_a, shaft_a, moving +X, meet
    gear_b and shaft_b. Each gear is walled in by the housing along 5 of the 6 axis directions (all but +Z)."""
    product = gearbox()
    both = [("gear_a", "housing"), ("gear_b", "housing"), ("shaft_a", "housing"), ("shaft_b", "housing"),
            ("shaft_a", "gear_a"), ("shaft_b", "gear_b")]
    across = Obstruction(Direction("+X", AXIS_DIRECTIONS["+X"]), tuple(
        [(a, b) for a, b in both] + [(b, a) for a, b in both] +
        [("gear_a", "gear_b"), ("gear_a", "shaft_b"), ("shaft_a", "gear_b"), ("shaft_a", "shaft_b")]))
    return replace(product, obstructions=product.obstructions + (across,))


def box_meshes(boxes=BOXES) -> list[PartMesh]:
    meshes = []
    for name, (lo, hi) in boxes.items():
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        box = trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))
        meshes.append(PartMesh(name, np.asarray(box.vertices, float), np.asarray(box.faces, np.int64)))
    return meshes


def test_the_closed_gearbox_is_stuck_on_its_floating_gear():
    with pytest.raises(NotDisassemblableError) as info:
        and_or_graph(closed_gearbox())
    assert info.value.floating_parts == ("gear_a",) and info.value.smallest == ["housing", "shaft_a", "gear_a"]


def test_each_gear_gets_a_support_contact_with_the_housing_and_the_gearbox_plans():
    product, added = support_contacts(closed_gearbox(), box_meshes())
    # Both gears, not only the one the diagnosis names: the mirror order (shaft_b out first) is kept.
    assert [(c.part, c.host, c.walled) for c in added] == [("gear_a", "housing", 5), ("gear_b", "housing", 5)]
    assert set(product.contacts) - set(closed_gearbox().contacts) == {("gear_a", "housing"), ("gear_b", "housing")}
    assert product.geometry["analysis"]["support_contacts"][0]["parts"] == ["gear_a", "housing"]
    andor = and_or_graph(product)
    assert andor.parts_of(0) == frozenset(product.part_ids)
    # Every split of the housing with both shafts in: either shaft first (the mirror orders alike).
    tops = {frozenset(min(andor.inputs(k), key=len)) for k, op in enumerate(andor.operations) if op.parent == 0}
    assert {frozenset({"shaft_a"}), frozenset({"shaft_b"})} <= tops


def test_the_default_mode_says_so_in_one_line_and_error_refuses(caplog):
    with caplog.at_level(logging.INFO, logger="planner.assembly.support_contacts"):
        product = apply_support_mode(closed_gearbox(), "add", box_meshes())
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and lines[0].startswith(
        "support contacts: gear_a rests in housing (inside its box, walled in along 5 of the 6 axis directions); "
        "gear_b rests in housing")
    assert "--support-contacts error to refuse instead" in lines[0]
    assert ("gear_a", "housing") in product.contacts
    with pytest.raises(SupportRefusedError) as info:
        apply_support_mode(closed_gearbox(), "error", box_meshes())
    assert info.value.contacts == (("gear_a", "housing"), ("gear_b", "housing"))
    assert "\n" not in str(info.value) and "--group NAME=housing,gear_a" in str(info.value)
    assert apply_support_mode(closed_gearbox(), "keep", box_meshes()) == closed_gearbox()
    with pytest.raises(PlannerError, match="unknown support-contact mode 'on'; use one of add, error, keep"):
        apply_support_mode(closed_gearbox(), "on")


def test_a_gear_that_sticks_out_of_the_housing_keeps_the_error():
    # gear_a reaches above the housing's box (z 12..70): not in its cavity; the diagnosis names gear_a alone.
    boxes = {**BOXES, "gear_a": ((14, 25, 12), (50, 35, 70))}
    product, added = support_contacts(closed_gearbox(), box_meshes(boxes))
    assert added == () and product == closed_gearbox()
    with pytest.raises(NotDisassemblableError, match="taking shaft_a out would leave gear_a touching nothing"):
        and_or_graph(apply_support_mode(closed_gearbox(), "add", box_meshes(boxes)))


def test_a_product_that_plans_or_has_no_meshes_is_left_as_it_is():
    planned = closed_gearbox()
    planned = replace(planned, contacts=planned.contacts + (("gear_a", "housing"),))
    assert support_contacts(planned, box_meshes()) == (planned, ())  # already plans: nothing added
    assert support_contacts(closed_gearbox()) == (closed_gearbox(), ())  # written by hand: planned as written
    pen = resolve_product("pen")
    assert support_contacts(pen) == (pen, ())


def _bundle(folder) -> Product:
    """The closed gearbox as a bundle in ``folder``: its product file (analysed: its diagrams are read as they
    are) and a mesh file per part (its box)."""
    for mesh in box_meshes():
        trimesh.Trimesh(mesh.vertices, mesh.faces).export(folder / f"{mesh.id}.stl")
    product = closed_gearbox()
    product = replace(product, name="gearbox", parts=tuple(replace(p, mesh=f"{p.id}.stl") for p in product.parts),
                      geometry={"analysis": {"engine": "mesh"}}, source=str(folder / "product.json"))
    save_product(product, folder / "product.json")
    return product


def test_resolve_product_reads_the_meshes_beside_the_product(tmp_path):
    product = _bundle(tmp_path)
    resolved = resolve_product(product)
    assert {("gear_a", "housing"), ("gear_b", "housing")} <= set(resolved.contacts)
    assert resolve_product(product, supports="keep").contacts == product.contacts
    with pytest.raises(SupportRefusedError):
        resolve_product(product, supports="error")


def test_the_command_line_adds_them_by_default_and_refuses_them_when_asked(tmp_path):
    _bundle(tmp_path)
    done = run_aplan("stats", tmp_path)
    assert done.returncode == 0, done.stderr
    assert "aplan: support contacts: gear_a rests in housing" in done.stderr
    refused = run_aplan("stats", tmp_path, "--support-contacts", "error")
    assert refused.returncode == 1 and "2 support contact(s) refused by --support-contacts error" in refused.stderr
    kept = run_aplan("stats", tmp_path, "--support-contacts", "keep")
    assert kept.returncode == 1 and "taking shaft_a out would leave gear_a touching nothing" in kept.stderr


def test_a_part_without_three_axis_diagrams_is_not_judged():
    # The abstract gearbox of test_floating_parts has no diagram across (+X): from which sides the housing walls
    # the gears in is not known, so the rule adds nothing.
    assert support_contacts(gearbox(), box_meshes()) == (gearbox(), ())
    parts = tuple(Part(p) for p in ("a", "b"))
    assert support_contacts(Product(parts, (("a", "b"),)), box_meshes({"a": BOXES["housing"],
                                                                        "b": BOXES["gear_a"]}))[1] == ()
