"""Fastener groups: the file section, its checks, and folding (planner.product.fasteners)."""
from __future__ import annotations

from dataclasses import replace

import pytest

from planner import ProductFormatError, product_from_dict, product_to_dict
from planner.product import (
    Direction,
    FastenerGroup,
    Obstruction,
    Part,
    Product,
    Tool,
    fold,
    fold_fasteners,
    with_fastener_mode,
)
from planner.product.synthetic import chain_product, fastened_product


def screwed_chain(screws: int = 1, tool: str | None = "screwdriver") -> Product:
    """A chain p1-p2-p3 and ``screws`` screws, each touching p1 and p2, in one group."""
    chain = chain_product(3)
    names = tuple(f"screw_{k}" for k in range(1, screws + 1))
    contacts = chain.contacts + tuple((p, s) for s in names for p in ("p1", "p2"))
    return Product(chain.parts + tuple(Part(s) for s in names), contacts,
                   tools=(Tool("screwdriver"),) if tool else (),
                   fasteners=(FastenerGroup("screws", names, tool=tool),))


def test_hosts_are_derived_from_contacts():
    folding = fold(screwed_chain(4))
    (group,) = folding.groups
    assert group.hosts == {"p1", "p2"} and group.parts == ("screw_1", "screw_2", "screw_3", "screw_4")
    assert folding.product.part_ids == ("p1", "p2", "p3")
    assert set(folding.product.contacts) == {("p1", "p2"), ("p2", "p3")}
    assert folding.added_contacts == ()
    assert folding.folded_parts == 4
    assert folding.original.fasteners and not folding.product.fasteners


def test_hosts_that_do_not_touch_get_a_contact():
    # the screw is the only liaison of p3: folded, p2-p3 becomes a contact
    product = Product(tuple(Part(p) for p in ("p1", "p2", "p3", "s")),
                      (("p1", "p2"), ("p2", "s"), ("p3", "s")),
                      fasteners=(FastenerGroup("g", ("s",)),))
    folding = fold(product)
    assert folding.added_contacts == (("p2", "p3"),)
    assert set(folding.product.contacts) == {("p1", "p2"), ("p2", "p3")}


def test_given_hosts_win_and_obstructions_drop_the_fasteners():
    up = Direction("+Z", (0.0, 0.0, 1.0))
    product = replace(screwed_chain(1), obstructions=(Obstruction(up, (("screw_1", "p1"), ("p3", "p2"))),),
                      fasteners=(FastenerGroup("screws", ("screw_1",), hosts=frozenset({"p1", "p3"})),))
    folding = fold(product)
    assert folding.groups[0].hosts == {"p1", "p3"}
    assert folding.added_contacts == (("p1", "p3"),)
    assert folding.product.obstructions[0].blocks == (("p3", "p2"),)


def test_a_product_without_fasteners_is_unchanged(pen):
    assert fold_fasteners(pen) is pen
    assert with_fastener_mode(pen, "none") is pen and with_fastener_mode(pen, "tagged") is pen


def test_modes():
    product = screwed_chain(2)
    assert with_fastener_mode(product, "none").fasteners == ()
    extra = FastenerGroup("more", ("screw_1",))
    assert with_fastener_mode(product, "auto", (extra,)) == product  # screw_1 is in a group already
    with pytest.raises(Exception, match="unknown fastener mode"):
        with_fastener_mode(product, "all")


def test_round_trip():
    product = screwed_chain(2)
    again = product_from_dict(product_to_dict(product))
    assert again == product
    proposed = replace(product, fasteners=(FastenerGroup("g", ("screw_1", "screw_2"), frozenset({"p1", "p2"}),
                                                         None, "proposed", "name ('screw')"),))
    assert product_from_dict(product_to_dict(proposed)) == proposed
    assert "fasteners" not in product_to_dict(chain_product(3))  # older files stay as they were


def _doc(fasteners: list, tools: list | None = None) -> dict:
    doc = product_to_dict(fastened_product(3, 2))
    doc["fasteners"] = fasteners
    if tools is not None:
        doc["tools"] = tools
    return doc


def test_bad_fastener_groups_are_named():
    with pytest.raises(ProductFormatError, match=r"fasteners\[0\]\.parts.*'scre_1' is not a part id.*screw_1"):
        product_from_dict(_doc([{"id": "g", "parts": ["scre_1"]}]))
    with pytest.raises(ProductFormatError, match=r"'screw_1' is in fastener groups 'a' and 'b'"):
        product_from_dict(_doc([{"id": "a", "parts": ["screw_1"]}, {"id": "b", "parts": ["screw_1", "screw_2"]}]))
    with pytest.raises(ProductFormatError, match=r"fasteners\[0\]\.tool.*'driver' is not a tool id"):
        product_from_dict(_doc([{"id": "g", "parts": ["screw_1"], "tool": "driver"}]))
    with pytest.raises(ProductFormatError, match=r"host 'screw_2' is a fastener"):
        product_from_dict(_doc([{"id": "g", "parts": ["screw_1", "screw_2"], "hosts": ["p1", "screw_2"]}]))
    with pytest.raises(ProductFormatError, match=r"fasteners\[0\]\.parts"):
        product_from_dict(_doc([{"id": "g", "parts": []}]))
    with pytest.raises(ProductFormatError, match=r"fasteners\[0\]\.part: unknown key \(did you mean 'parts'\?\)"):
        product_from_dict(_doc([{"id": "g", "part": ["screw_1"]}]))


def test_a_fastener_that_joins_one_part_or_nothing():
    one = Product((Part("a"), Part("b"), Part("s")), (("a", "b"), ("a", "s")))
    with pytest.raises(ProductFormatError, match=r"one.json.*fasteners\[0\].*'lonely' \(s\) joins only 'a': a fastener "
                                                 r"that joins nothing or only one part"):
        product_from_dict(product_to_dict(one) | {"fasteners": [{"id": "lonely", "parts": ["s"]}]}, "one.json")
    with pytest.raises(ProductFormatError, match=r"'g' \(s\) joins nothing"):
        Product((Part("a"), Part("s")), (), fasteners=(FastenerGroup("g", ("s",)),))
    with pytest.raises(ProductFormatError, match=r"joins only 'a'"):
        Product((Part("a"), Part("b"), Part("s")), (("a", "b"), ("a", "s")),
                fasteners=(FastenerGroup("g", ("s",), hosts=frozenset({"a"})),))
    # a fastener touching another group's fastener is not joined to it
    with pytest.raises(ProductFormatError, match=r"'nut' \(n\) joins only 'b'"):
        Product(tuple(Part(p) for p in ("a", "b", "s", "n")), (("a", "b"), ("a", "s"), ("b", "s"), ("s", "n"),
                                                                ("n", "b")),
                fasteners=(FastenerGroup("screw", ("s",)), FastenerGroup("nut", ("n",))))
