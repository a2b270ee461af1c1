"""The product file format: the embedded pen, round trips, the JSON schema, and precise errors on bad input."""
from __future__ import annotations

import json
import os
import secrets
import stat

import jsonschema
import pytest
from conftest import PEN_MODELS, REPO, require_shared

from planner import (
    ProductFormatError,
    UnknownProductError,
    example_path,
    load_product,
    loads_product,
    product_from_dict,
    product_to_dict,
    resolve_product,
    save_product,
)
from planner.files import write_atomic

SCHEMA = json.loads((REPO / "planner" / "product" / "schema.json").read_text())


def pen_doc() -> dict:
    return json.loads(example_path("pen").read_text())


def test_pen_parts_contacts_and_tags(pen):
    assert pen.part_ids == ("ink", "cartridge", "head", "body", "cap", "button")
    assert {frozenset(c) for c in pen.contacts} == {
        frozenset(c) for c in [("ink", "cartridge"), ("cartridge", "head"), ("head", "body"),
                               ("body", "cap"), ("body", "button")]}
    (constraint,) = pen.technical_constraints
    assert constraint.parts == {"ink", "cartridge"} and constraint.requires == "head" and not constraint.active
    assert pen.defaults.tool == "hammer"


@pytest.mark.parametrize("variant", ["simplified", "complex"])
def test_pen_obstructions_equal_ground_truth(pen, variant):
    for obstruction in pen.obstructions:
        axis = obstruction.direction.name
        assert axis in ("+X", "+Y", "+Z")
        path = require_shared(PEN_MODELS / variant / "GroundTruth" / f"GeomConstraints_POS_{axis[1]}.json")
        truth = {(link["source"].removesuffix("_001"), link["target"].removesuffix("_001"))
                 for link in json.loads(path.read_text())["links"]}
        assert set(obstruction.blocks) == truth
    assert sorted(o.direction.name for o in pen.obstructions) == ["+X", "+Y", "+Z"]


def test_round_trip(tmp_path, pen):
    out = tmp_path / "pen.json"
    save_product(pen, out)
    again = load_product(out)
    assert again == pen
    assert product_to_dict(again) == product_to_dict(pen)


def test_extensions_are_kept(tmp_path):
    doc = pen_doc()
    doc["x-freecad"] = {"document": "pen.FCStd"}
    doc["parts"][0]["x-note"] = "ignored"
    product = product_from_dict(doc)
    assert product_to_dict(product)["x-freecad"] == {"document": "pen.FCStd"}


def test_schema_accepts_what_the_planner_writes(pen):
    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    jsonschema.validate(pen_doc(), SCHEMA)
    jsonschema.validate(product_to_dict(pen), SCHEMA)


def _mutate(path, value):
    doc = pen_doc()
    target = doc
    for key in path[:-1]:
        target = target[key]
    if value is _DELETE:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return doc


_DELETE = object()

BAD = [
    # (mutation path, value, location, message fragment)
    (["version"], 2, "version", "unknown format version 2 written by a newer APLAN"),
    (["format"], "something", "format", "not an APLAN product file"),
    (["parts"], _DELETE, "top level", "missing required key 'parts'"),
    (["parts", 1, "id"], "ink", "parts[1].id", "duplicate part id 'ink' (also parts[0])"),
    (["parts", 1, "id"], 7, "parts[1].id", "expected a string, got the number 7"),
    (["contacts", 0], ["ink", "cartrige"], "contacts[0][1]", "'cartrige' is not a part id (did you mean 'cartridge'?)"),
    (["contacts", 0], ["ink", "ink"], "contacts[0]", "self-loop"),
    (["contacts", 0], ["ink"], "contacts[0]", "expected a pair of two part ids"),
    (["contacts", 1], ["ink", "cartridge"], "contacts[1]", "duplicate contact"),
    (["obstructions", 0, "blocks", 0], ["cap", "cap"], "obstructions[0].blocks[0]", "self-loop"),
    (["obstructions", 0, "blocks", 0], ["cap", "pen"], "obstructions[0].blocks[0][1]", "'pen' is not a part id"),
    (["obstructions", 1, "direction"], "-X", "obstructions[1].direction", "reverse of obstructions[0]"),
    (["obstructions", 1, "direction"], "+X", "obstructions[1].direction", "listed twice"),
    (["obstructions", 1, "direction"], [1, 1, 0], "obstructions[1].direction", "not a unit vector (length 1.41421)"),
    (["obstructions", 1, "direction"], "+W", "obstructions[1].direction", "unknown direction '+W'"),
    (["technical_constraints", 0, "requires"], "ink", "technical_constraints[0].requires", "cannot require itself"),
    (["defaults", "tool"], "spanner", "defaults.tool", "'spanner' is not a tool id"),
    (["defaults", "unfavorable"], "most", "defaults.unfavorable", "unknown rule 'most'"),
    (["units"], "furlong", "units", "unknown unit 'furlong'"),
    (["contact"], [], "contact", "unknown key (did you mean 'contacts'?)"),
    (["markers", "ids", "cap"], 3, "markers.ids.cap", "marker 3 is used twice: by 'body' and by 'cap'"),
    (["markers", "ids", "cap"], 50, "markers.ids.cap", "marker id must be an integer from 0 to 49"),
    (["markers", "ids", "cap"], "4", "markers.ids.cap", "expected an integer marker id, got the string '4'"),
    (["markers", "ids", "hamer"], 9, "markers.ids.hamer", "neither a part nor a tool id (did you mean 'hammer'?)"),
    (["markers", "dictionary"], "DICT_4X4_5", "markers.dictionary", "unknown marker dictionary 'DICT_4X4_5'"),
]


@pytest.mark.parametrize("path, value, location, fragment", BAD, ids=[b[2] + ":" + b[3][:20] for b in BAD])
def test_bad_documents_name_the_place(path, value, location, fragment):
    doc = _mutate(path, value)
    with pytest.raises(ProductFormatError) as info:
        product_from_dict(doc, "pen.json")
    assert info.value.location == location
    assert fragment in str(info.value)
    assert str(info.value).startswith(f"pen.json: {location}")


def test_malformed_json_names_line_and_column():
    with pytest.raises(ProductFormatError, match=r"x\.json: line 3 column 1: malformed JSON"):
        loads_product('{"format": "aplan-product",\n "version": 1,\n}', "x.json")


def test_operation_tags_are_checked():
    doc = pen_doc()
    doc["operations"] = [{"inputs": [["ink"], ["ink", "cartridge"]]}]
    with pytest.raises(ProductFormatError, match=r"operations\[0\]\.inputs: the two inputs share \['ink'\]"):
        product_from_dict(doc)
    doc["operations"] = [{"inputs": [["ink"], ["cartridge"]], "tool": "spanner"}]
    with pytest.raises(ProductFormatError, match=r"operations\[0\]\.tool: 'spanner' is not a tool id"):
        product_from_dict(doc)
    doc["operations"] = [{"inputs": [["ink"], ["cartridge"]]}, {"inputs": [["cartridge"], ["ink"]]}]
    with pytest.raises(ProductFormatError, match=r"operations\[1\]: this operation is already tagged at operations\[0\]"):
        product_from_dict(doc)


def test_bad_documents_are_rejected_by_the_schema_too():
    """The schema and the checker agree on the structural mistakes (the schema cannot see cross-references)."""
    structural = [b for b in BAD if b[2] in ("version", "format", "top level", "units", "contact")
                  or "expected" in b[3] or "unknown direction" in b[3] or "unknown rule" in b[3]]
    assert len(structural) >= 6
    for path, value, _, _ in structural:
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(_mutate(path, value), SCHEMA)


def test_missing_file_and_unknown_product(tmp_path):
    with pytest.raises(ProductFormatError, match="no such file"):
        load_product(tmp_path / "nope.json")
    with pytest.raises(UnknownProductError, match=r"no such file, and no embedded example of that name \(embedded: pen\)"):
        resolve_product(str(tmp_path / "nope.json"))


def test_write_atomic_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "out.json"

    with pytest.raises(TypeError):
        write_atomic(target, 12345)  # not text: the write fails
    assert list(tmp_path.iterdir()) == []
    write_atomic(target, "ok\n")
    assert target.read_text() == "ok\n" and [p.name for p in tmp_path.iterdir()] == ["out.json"]


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_write_atomic_gives_the_usual_permissions(tmp_path, umask):
    """Outputs get 0o666 less the umask, like any new file, also when they replace a file."""
    target = tmp_path / "out.json"
    target.write_text("old\n")
    target.chmod(0o600)
    old = os.umask(umask)
    try:
        write_atomic(target, "new\n")
        write_atomic(tmp_path / "fresh.json", "new\n")
    finally:
        os.umask(old)
    for path in (target, tmp_path / "fresh.json"):
        assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask
        assert path.read_text() == "new\n"


def test_write_atomic_never_touches_the_umask(tmp_path, monkeypatch):
    """The umask is process-wide: setting it, even to read it, races with threads that create files."""

    def umask(_):
        raise AssertionError("write_atomic changed the process' umask")

    monkeypatch.setattr(os, "umask", umask)
    write_atomic(tmp_path / "out.json", "ok\n")
    assert (tmp_path / "out.json").read_text() == "ok\n"


def test_write_atomic_skips_a_temporary_name_in_use(tmp_path, monkeypatch):
    names = iter(["aaaa", "aaaa", "bbbb"])
    monkeypatch.setattr(secrets, "token_hex", lambda _: next(names))
    (tmp_path / ".out.json.aaaa.tmp").write_text("someone else's\n")
    write_atomic(tmp_path / "out.json", "ok\n")
    assert (tmp_path / ".out.json.aaaa.tmp").read_text() == "someone else's\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == [".out.json.aaaa.tmp", "out.json"]
