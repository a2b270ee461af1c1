"""Product files read without jsonschema, as in FreeCAD's Python installed by the Addon Manager (jsonschema is not
on FreeCAD's allowed list): the same products, and every bad document of the format tests still refused with a
ProductFormatError (never another exception), most with the same place, the others saying how to get it."""
from __future__ import annotations

import pytest
from test_product import BAD, _mutate, pen_doc

from planner import ProductFormatError, product_from_dict, product_to_dict
from planner.product import schema


@pytest.fixture
def without_jsonschema(monkeypatch):
    monkeypatch.setattr(schema, "jsonschema", None)
    assert not schema.schema_checks()


def test_the_pen_reads_the_same_without_jsonschema(monkeypatch):
    expected = product_to_dict(product_from_dict(pen_doc(), "pen.json"))  # with jsonschema
    monkeypatch.setattr(schema, "jsonschema", None)
    assert product_to_dict(product_from_dict(pen_doc(), "pen.json")) == expected


@pytest.mark.parametrize("path, value, location, fragment", BAD, ids=[b[2] + ":" + b[3][:20] for b in BAD])
def test_bad_documents_are_refused_without_jsonschema(without_jsonschema, path, value, location, fragment):
    with pytest.raises(ProductFormatError) as info:
        product_from_dict(_mutate(path, value), "pen.json")
    message = str(info.value)
    if info.value.location:  # the planner's own checks found it: the same place as with the schema
        assert info.value.location == location and message.startswith(f"pen.json: {location}"), message
    else:  # a wrong type only jsonschema names the place of: the message says how to get it
        assert message.startswith("pen.json: malformed product file (") and "pip install jsonschema" in message


def test_most_mistakes_keep_their_place_without_jsonschema(without_jsonschema):
    placed = 0
    for path, value, location, _ in BAD:
        with pytest.raises(ProductFormatError) as info:
            product_from_dict(_mutate(path, value), "pen.json")
        placed += info.value.location == location
    assert placed >= len(BAD) - 3, placed  # measured: 23 of 25 (a one-item contact, an unknown direction not)
