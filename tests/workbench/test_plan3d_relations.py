"""The direction of a diagrams-table relation (freecad_aplan.diagrams.relation_direction; plain data): what the
3D view's arrow points along."""
from __future__ import annotations

import pytest

from freecad_aplan.diagrams import relation_direction, relation_rows


@pytest.mark.parametrize("kind, vector", [
    ("blocks +X", (1.0, 0.0, 0.0)), ("blocks -Z", (0.0, 0.0, -1.0)),
    ("blocks [0, -0.5, 0.866]", (0.0, -0.5, 0.866)),
    ("contact", None), ("blocks sideways", None), ("blocks [1, 2]", None), ('blocks ["a", 0, 0]', None),
])
def test_relation_direction(kind, vector):
    assert relation_direction(kind) == vector


def test_every_row_of_the_table_has_its_direction():
    diagrams = {"parts": ["a", "b"], "contacts": [["a", "b"]],
                "obstructions": [{"direction": "+Y", "blocks": [["a", "b"]]},
                                 {"direction": [0.6, 0.8, 0.0], "blocks": [["b", "a"]]}]}
    assert [relation_direction(kind) for kind, _, _ in relation_rows(diagrams)] == [None, (0.0, 1.0, 0.0),
                                                                                   (0.6, 0.8, 0.0)]
