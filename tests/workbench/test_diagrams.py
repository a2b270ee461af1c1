"""Editing stored connection and obstruction diagrams as relations (freecad_aplan.diagrams; plain data)."""
from __future__ import annotations

import re

import pytest

from freecad_aplan.diagrams import (
    RELATION_KINDS,
    RelationError,
    diagrams_source,
    edited_diagrams,
    relation_rows,
    stored_analysis,
)
from planner.product import product_from_dict

# Three parts in a row along X: a | b | c; a and c only meet b.
ROW = {"parts": ["a", "b", "c"], "contacts": [["a", "b"], ["b", "c"]],
       "obstructions": [{"direction": "+X", "blocks": [["a", "b"], ["a", "c"], ["b", "c"]]}],
       "analysis": {"engine": "mesh"}}


def product(diagrams: dict):
    return product_from_dict({"format": "aplan-product", "version": 1, "parts": [{"id": p} for p in diagrams["parts"]],
                              "contacts": diagrams["contacts"], "obstructions": diagrams["obstructions"]})


def test_rows_and_kinds():
    assert relation_rows(ROW) == [("contact", "a", "b"), ("contact", "b", "c"), ("blocks +X", "a", "b"),
                                  ("blocks +X", "a", "c"), ("blocks +X", "b", "c")]
    assert RELATION_KINDS == ("contact", "blocks +X", "blocks -X", "blocks +Y", "blocks -Y", "blocks +Z", "blocks -Z")


def test_add_and_remove_keep_a_valid_product_and_log_the_edits():
    edited = edited_diagrams(ROW, remove=[("contact", "c", "b")],
                             add=[("contact", "a", "c"), ("blocks -Y", "a", "b"), ("blocks +Z", "c", "a")])
    assert edited["contacts"] == [["a", "b"], ["a", "c"]]
    # Along -Y: stored as the reverse relation along +Y (the format lists one of two opposite directions).
    assert edited["obstructions"][1:] == [{"direction": "+Y", "blocks": [["b", "a"]]},
                                          {"direction": "+Z", "blocks": [["c", "a"]]}]
    assert edited["edits"] == [{"removed": ["contact", "c", "b"]}, {"added": ["contact", "a", "c"]},
                               {"added": ["blocks -Y", "a", "b"]}, {"added": ["blocks +Z", "c", "a"]}]
    product(edited)  # still a valid product
    assert ROW["contacts"] == [["a", "b"], ["b", "c"]] and "edits" not in ROW  # the input is not changed
    assert diagrams_source(ROW) == "stored in the document"
    assert stored_analysis(edited) == {"engine": "mesh", "diagrams": "stored in the document, edited",
                                       "edits": edited["edits"]}
    # An addition along a direction listed the other way round goes there, reversed.
    down = {**ROW, "obstructions": [{"direction": "-Z", "blocks": [["a", "b"]]}]}
    assert edited_diagrams(down, add=[("blocks +Z", "c", "b")])["obstructions"] == \
        [{"direction": "-Z", "blocks": [["a", "b"], ["b", "c"]]}]
    with pytest.raises(RelationError, match=r"already hold it \(as a blocked by b along -Z\)"):
        edited_diagrams(down, add=[("blocks +Z", "b", "a")])


@pytest.mark.parametrize("relation, message", [
    (("contact", "a", "d"), "cannot add contact a - d: 'd' is not a component; the components are a, b, c"),
    (("contact", "bb", "a"), "'bb' is not a component (did you mean 'b'?)"),
    (("contact", "a", "a"), "cannot add contact a - a: a component cannot be related to itself"),
    (("contact", "b", "a"), "cannot add contact b - a: the diagrams already hold it (as contact a - b)"),
    (("blocks -X", "c", "a"), "cannot add c blocked by a along -X: the diagrams already hold it "
                              "(as a blocked by c along +X)"),
    (("blocks +W", "a", "b"), "cannot add the relation 'blocks +W': use one of contact, blocks +X"),
])
def test_bad_additions_are_refused(relation, message):
    with pytest.raises(RelationError, match=re.escape(message)):
        edited_diagrams(ROW, add=[relation])


def test_duplicate_within_one_edit_and_missing_removal():
    with pytest.raises(RelationError, match="already hold it"):
        edited_diagrams(ROW, add=[("contact", "a", "c"), ("contact", "c", "a")])
    with pytest.raises(RelationError, match=r"cannot remove contact a - c: the diagrams do not hold it"):
        edited_diagrams(ROW, remove=[("contact", "a", "c")])
    # Removed, then added again in the same edit: allowed (removals apply first).
    assert edited_diagrams(ROW, remove=[("contact", "a", "b")], add=[("contact", "b", "a")])["contacts"] == \
        [["b", "c"], ["b", "a"]]
