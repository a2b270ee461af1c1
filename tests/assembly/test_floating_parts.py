"""A closed gearbox (issue 26): the parts come apart one by one, but a gear whose shaft is out rests in the
housing touching nothing, so the topological constraint refuses the split; the error says so."""
from __future__ import annotations

import pytest

from planner import NotDisassemblableError, Obstruction, Part, Product, and_or_graph
from planner.errors import InterlockedPartsError
from planner.product import AXIS_DIRECTIONS, Direction

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
