"""The connection and obstruction diagrams an APLAN analysis stores, as relations the designer edits.

The analysis' ``Diagrams`` property (:mod:`freecad_aplan.intent`) holds what the last detection found, in
product-format JSON (``docs/product-format.md``): ``parts`` (component ids), ``contacts`` (pairs),
``obstructions`` (``{"direction": "+X", "blocks": [[x, y], ...]}``), ``objects`` (component id -> object
names), ``analysis`` (the engine's summary) and, once the designer edited them, ``edits``.

A *relation* is one row of the diagrams panel, a triple of strings:

- ``("contact", a, b)``: components ``a`` and ``b`` touch (a liaison; unordered);
- ``("blocks +X", x, y)``: component ``x``, moved along +X without limit, hits ``y`` ("x blocked by y along
  +X"). The reverse direction is implied, so ``("blocks -X", x, y)`` is the same relation as
  ``("blocks +X", y, x)``; an obstruction along a direction the diagrams do not list yet is stored along
  the positive axis. Directions given as unit vectors appear as ``blocks [1, 0, 0]``.

Plain data and no FreeCAD: :func:`freecad_aplan.workflow.edit_analysis_diagrams` applies an edit to an
analysis as one undoable transaction, the diagrams panel and the tests call it.
"""
from __future__ import annotations

import difflib
import json
from collections.abc import Iterable, Sequence

from planner.errors import PlannerError
from planner.product import AXIS_DIRECTIONS

__all__ = ["RELATION_KINDS", "RelationError", "relation_rows", "edited_diagrams", "diagrams_source",
           "stored_analysis", "describe_relation", "relation_direction"]

#: The kinds of relation the designer can add: a contact, or an obstruction along one of the six axes.
RELATION_KINDS: tuple[str, ...] = ("contact",) + tuple(f"blocks {axis}" for axis in AXIS_DIRECTIONS)

Relation = tuple[str, str, str]


class RelationError(PlannerError):
    """A relation cannot be added to or removed from the diagrams (unknown component, a part related to
    itself, a duplicate, a relation that is not there); the diagrams are left as they were."""


def _direction_name(direction) -> str:
    return direction if isinstance(direction, str) else json.dumps(direction)


def relation_rows(diagrams: dict) -> list[Relation]:
    """The relations of ``diagrams`` in table order: contacts, then obstructions direction by direction."""
    rows = [("contact", a, b) for a, b in diagrams.get("contacts", [])]
    for obstruction in diagrams.get("obstructions", []):
        name = _direction_name(obstruction["direction"])
        rows += [(f"blocks {name}", x, y) for x, y in obstruction["blocks"]]
    return rows


def describe_relation(relation: Relation) -> str:
    """A relation in words: ``contact a - b`` or ``x blocked by y along +X``."""
    kind, a, b = relation
    return f"contact {a} - {b}" if kind == "contact" else f"{a} blocked by {b} along {kind[len('blocks '):]}"


def _vector(direction) -> tuple[float, ...] | None:
    if isinstance(direction, str):
        return AXIS_DIRECTIONS.get(direction)
    if isinstance(direction, (list, tuple)) and len(direction) == 3:
        return tuple(float(v) for v in direction)
    return None


def _positive(vector: tuple[float, ...]) -> bool:
    """True when the first non-zero coordinate is positive (one of each pair of opposite directions)."""
    return next((v > 0 for v in vector if v != 0), True)


def _key(relation: Relation) -> tuple:
    """The same key for the same relation however it is written (contact order, reversed direction)."""
    kind, a, b = relation
    if kind == "contact":
        return ("contact", frozenset((a, b)))
    text = kind[len("blocks "):] if kind.startswith("blocks ") else None
    vector = None
    if text is not None:
        try:
            vector = _vector(text if text in AXIS_DIRECTIONS else json.loads(text))
        except json.JSONDecodeError:
            vector = None
    if vector is None:
        raise RelationError(f"unknown relation {kind!r}; use one of {', '.join(RELATION_KINDS)}")
    if not _positive(vector):
        return ("blocks", tuple(-v + 0.0 for v in vector), (b, a))
    return ("blocks", tuple(v + 0.0 for v in vector), (a, b))


def _check_new(relation: Relation, parts: Sequence[str], present: dict) -> None:
    kind, a, b = relation
    if kind not in RELATION_KINDS:
        raise RelationError(f"cannot add the relation {kind!r}: use one of {', '.join(RELATION_KINDS)}")
    for name in (a, b):
        if name not in parts:
            close = difflib.get_close_matches(str(name), list(parts), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise RelationError(f"cannot add {describe_relation(relation)}: {name!r} is not a component{hint}; "
                                f"the components are {', '.join(parts)}")
    if a == b:
        raise RelationError(f"cannot add {describe_relation(relation)}: a component cannot be related to itself; "
                            "choose two different components")
    existing = present.get(_key(relation))
    if existing is not None:
        same = "" if existing == relation else f" (as {describe_relation(existing)})"
        raise RelationError(f"cannot add {describe_relation(relation)}: the diagrams already hold it{same}")


def _add(diagrams: dict, relation: Relation) -> None:
    kind, a, b = relation
    if kind == "contact":
        diagrams["contacts"].append([a, b])
        return
    vector = AXIS_DIRECTIONS[kind[len("blocks "):]]
    opposite = tuple(-v + 0.0 for v in vector)
    for obstruction in diagrams["obstructions"]:
        along = _vector(obstruction["direction"])
        if along == vector:
            obstruction["blocks"].append([a, b])
            return
        if along == opposite:
            obstruction["blocks"].append([b, a])
            return
    name = next(n for n, v in AXIS_DIRECTIONS.items() if v == (vector if _positive(vector) else opposite))
    diagrams["obstructions"].append({"direction": name, "blocks": [[a, b] if _positive(vector) else [b, a]]})


def edited_diagrams(diagrams: dict, remove: Iterable[Relation] = (), add: Iterable[Relation] = ()) -> dict:
    """A copy of ``diagrams`` without the relations ``remove`` and with the relations ``add``.

    Removals apply first. Each addition must name two different components of ``diagrams["parts"]`` and must
    not be there already (in either order for a contact, or as the reversed relation along the opposite
    direction); each removal must be there. The copy's ``edits`` lists every edit so far
    (``{"removed": [kind, a, b]}``, ``{"added": [kind, a, b]}``). Raises :class:`RelationError`, naming the
    relation and the fix, before anything changes. Cost: O(relations) per edit.
    """
    remove, add = [tuple(r) for r in remove], [tuple(r) for r in add]
    parts = list(diagrams.get("parts", []))
    out = json.loads(json.dumps(diagrams))  # a deep copy of plain JSON data
    out.setdefault("contacts", [])
    out.setdefault("obstructions", [])
    edits = out.setdefault("edits", [])
    gone = set()
    for relation in remove:
        key = _key(relation)
        if key not in {_key(r) for r in relation_rows(diagrams)} or key in gone:
            raise RelationError(f"cannot remove {describe_relation(relation)}: the diagrams do not hold it")
        gone.add(key)
        edits.append({"removed": list(relation)})
    out["contacts"] = [c for c in out["contacts"] if _key(("contact", *c)) not in gone]
    for obstruction in out["obstructions"]:
        name = _direction_name(obstruction["direction"])
        obstruction["blocks"] = [p for p in obstruction["blocks"] if _key((f"blocks {name}", *p)) not in gone]
    present = {_key(r): r for r in relation_rows(out)}
    for relation in add:
        _check_new(relation, parts, present)
        _add(out, relation)
        present[_key(relation)] = relation
        edits.append({"added": list(relation)})
    if not edits:
        del out["edits"]
    return out


def diagrams_source(diagrams: dict) -> str:
    """Where stored diagrams came from, as recorded in a product's ``geometry.analysis.diagrams``."""
    return "stored in the document, edited" if diagrams.get("edits") else "stored in the document"


def stored_analysis(diagrams: dict) -> dict:
    """The ``geometry.analysis`` of a product built from stored diagrams: the engine's summary of the
    detection, where the diagrams came from (:func:`diagrams_source`) and the designer's edits."""
    out = {**diagrams.get("analysis", {}), "diagrams": diagrams_source(diagrams)}
    if diagrams.get("edits"):
        out["edits"] = list(diagrams["edits"])
    return out


def relation_direction(kind: str) -> tuple[float, float, float] | None:
    """The direction of a relation kind (``blocks +X``, or ``blocks [x, y, z]`` for a designer direction) as a
    vector; None for a contact or a kind that names no direction."""
    if not kind.startswith("blocks "):
        return None
    name = kind[len("blocks "):].strip()
    if name in AXIS_DIRECTIONS:
        return tuple(float(c) for c in AXIS_DIRECTIONS[name])
    try:
        vector = json.loads(name)
    except ValueError:
        return None
    if not (isinstance(vector, list) and len(vector) == 3 and all(isinstance(c, (int, float)) for c in vector)):
        return None
    return tuple(float(c) for c in vector)
