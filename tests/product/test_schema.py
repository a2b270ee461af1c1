"""The structure of product files, checked with the JSON Schema: jsonschema's errors become messages that name
the JSON path and say how to fix it, the same with any jsonschema version."""
from __future__ import annotations

import copy
import json

import jsonschema
import pytest

from planner import ProductFormatError, example_path, product_from_dict
from planner.product.schema import check_document, product_schema

PEN = json.loads(example_path("pen").read_text())


def _with(path: list, value) -> dict:
    doc = copy.deepcopy(PEN)
    target = doc
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    return doc


STRUCTURE = [
    # (mutation path, value, location, message)
    (["parts", 0, "volume"], -1, "parts[0].volume", "must be >= 0, got -1"),
    (["parts", 0, "mesh"], 5, "parts[0].mesh", "expected a string or null, got the number 5"),
    (["parts", 0, "id"], "", "parts[0].id", "expected a non-empty string"),
    (["parts"], [], "parts", "expected at least 1 item, got none; a product needs at least one part"),
    (["parts", 0, "colour"], "red", "parts[0].colour",
     "unknown key; allowed keys: id, label, mesh, brep, volume, mass, material (keys starting with 'x-' are kept "
     "as extensions)"),
    (["contacts"], "none", "contacts", "expected an array, got the string 'none'"),
    (["contacts", 0], "ink", "contacts[0]", "expected a pair of two part ids, got the string 'ink'"),
    (["contacts", 0, 0], 1, "contacts[0][0]", "expected a string, got the number 1"),
    (["obstructions", 0, "direction"], 5, "obstructions[0].direction",
     "expected a direction (+X, -X, +Y, -Y, +Z, -Z or a unit vector [x, y, z]), got the number 5"),
    (["obstructions", 0, "direction"], [1, 0], "obstructions[0].direction",
     "expected a unit vector [x, y, z] of 3 numbers, got 2 items"),
    (["obstructions", 0, "direction"], ["a", 0, 0], "obstructions[0].direction[0]",
     "expected a number, got the string 'a'"),
    (["technical_constraints", 0, "parts"], ["ink", "ink"], "technical_constraints[0].parts",
     "'ink' is listed twice in ['ink', 'ink']; list it once"),
    (["operations"], [{"inputs": [["ink"], ["cap"], ["body"]]}], "operations[0].inputs",
     "expected two inputs (part lists), got 3 items; an operation joins exactly two inputs"),
    (["operations"], [{"inputs": [["ink"], []]}], "operations[0].inputs[1]",
     "expected at least 1 item, got none; an input needs at least one part"),
    (["version"], "1", "version", "expected an integer, got the string '1'"),
    (["markers", "ids", "cap"], -1, "markers.ids.cap", "must be >= 0, got -1"),
    (["markers", "dictionary"], "foo", "markers.dictionary",
     "unknown marker dictionary 'foo'; use one of OpenCV's, e.g. DICT_4X4_50"),
    (["defaults", "unfavorable"], "al", "defaults.unfavorable",
     "unknown rule 'al' (did you mean 'all'?); use one of single-part-rule, none, all"),
]


@pytest.mark.parametrize("path, value, location, message", STRUCTURE, ids=[s[2] for s in STRUCTURE])
def test_schema_errors_name_the_path_and_the_fix(path, value, location, message):
    doc = _with(path, value)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(doc, product_schema())  # the schema alone rejects it too
    with pytest.raises(ProductFormatError) as info:
        product_from_dict(doc, "pen.json")
    assert (info.value.location, info.value.problem) == (location, message)


def test_not_an_object():
    with pytest.raises(ProductFormatError) as info:
        check_document([1], "x.json")
    assert str(info.value) == "x.json: top level: expected an APLAN product file (format version 1), got an array"


def _first_mistake(doc: dict) -> str:
    with pytest.raises(ProductFormatError) as info:
        check_document(doc)
    return info.value.location


def test_mistakes_are_reported_in_the_order_of_their_paths():
    """Of several mistakes, the first in path order (keys alphabetically, indices in order, an object before
    what it holds) is reported, whatever order jsonschema finds them in."""
    doc = _with(["parts", 3, "id"], 7)
    doc["parts"][1]["mass"] = "heavy"
    doc["contacts"][2] = ["ink"]
    doc["extra"] = True
    assert _first_mistake(doc) == "extra"
    del doc["extra"]
    assert _first_mistake(doc) == "contacts[2]"
    doc["contacts"][2] = PEN["contacts"][2]
    assert _first_mistake(doc) == "parts[1].mass"
    doc["parts"][1]["mass"] = 1.5
    assert _first_mistake(doc) == "parts[3].id"


def test_header_comes_before_structure():
    """A file from a newer APLAN is named as such, not by the keys this version does not know."""
    doc = _with(["version"], 3)
    doc["assemblies"] = []
    with pytest.raises(ProductFormatError, match=r"version: unknown format version 3 written by a newer APLAN"):
        check_document(doc)


def test_every_title_and_hint_is_a_phrase():
    """Titles name values in messages ("expected <title>", "unknown <title> 'x'"), hints follow a "; "."""
    found = []

    def walk(node):
        if isinstance(node, dict):
            for key, value in node.items():
                if key in ("title", "x-hint"):
                    found.append((key, value))
                walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)

    walk(product_schema())
    assert len(found) >= 10
    for key, value in found:
        assert isinstance(value, str) and value == value.strip() and not value.endswith((".", ";")), (key, value)
