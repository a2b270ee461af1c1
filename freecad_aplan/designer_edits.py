"""The designer's edits of an analysis' stored diagrams, each one undoable transaction: relations removed and
added (the diagrams panel), designer directions added, obstructions marked not blocking and unmarked (paper
Sec. III-A: the designer corrects what the geometry engines found). Re-exported by :mod:`freecad_aplan.workflow`.

Like the workflow's, these functions import the modules that read FreeCAD objects themselves, so that the
background jobs, which import the workflow in a plain Python, never load FreeCAD.
"""
from __future__ import annotations

import json

from planner.defaults import PRODUCT_FORMAT, PRODUCT_VERSION
from planner.product import product_from_dict, product_to_dict
from planner.product.designer import add_directions, mark_not_blocking as mark, unmark_not_blocking as unmark

__all__ = ["edit_analysis_diagrams", "add_analysis_direction", "mark_not_blocking", "unmark_not_blocking"]


def edit_analysis_diagrams(analysis, remove=(), add=()) -> dict:
    """Remove and add relations of the analysis' stored diagrams in one undoable transaction.

    Relations are ``(kind, a, b)`` triples (:mod:`freecad_aplan.diagrams`: ``("contact", a, b)``,
    ``("blocks +X", x, y)`` for x blocked by y along +X). The diagrams panel calls this on OK. Raises
    :class:`~freecad_aplan.diagrams.RelationError` (unknown component, a component related to itself, a
    duplicate, a relation that is not there) or :class:`~freecad_aplan.intent.IntentError` (nothing detected
    yet, a newer format) before anything changes. Returns the new diagrams.
    """
    from .diagrams import describe_relation, edited_diagrams
    from .intent import IntentError, read_intent, update_intent

    remove, add = [tuple(r) for r in remove], [tuple(r) for r in add]
    diagrams = read_intent(analysis).diagrams
    if not diagrams.get("parts"):
        raise IntentError(f"{analysis.Label}: no contacts and obstructions yet; run APLAN > Detect contacts "
                          "and obstructions first")
    new = edited_diagrams(diagrams, remove, add)
    if len(remove) + len(add) == 1:
        description = ("remove " if remove else "add ") + describe_relation((remove or add)[0])
    else:
        description = f"edit diagrams ({len(remove)} removed, {len(add)} added)"
    if remove or add:
        update_intent(analysis, description, diagrams=new)
    return new


def _designer_product(analysis):
    """The stored diagrams as a product with the analysis' designer directions and marks (``geometry.designer``)
    and the detection's record (``geometry.analysis``), and the intent. Parts: the components, or one stand-in
    before any detection (directions need no parts)."""
    from .intent import designer_record, read_intent

    intent = read_intent(analysis)
    diagrams = intent.diagrams
    record = designer_record(intent)
    data = {"format": PRODUCT_FORMAT, "version": PRODUCT_VERSION,
            "parts": [{"id": p} for p in diagrams.get("parts") or ["-"]], "contacts": diagrams.get("contacts", []),
            "obstructions": diagrams.get("obstructions", []),
            "geometry": {"analysis": diagrams.get("analysis", {}), **({"designer": record} if record else {})}}
    return product_from_dict(data, analysis.Label), intent


def _store_designer(analysis, intent, product, description: str) -> None:
    """Keep the designer record of ``product`` in the analysis, and its diagrams when something was detected:
    one undoable transaction."""
    from .intent import update_intent

    record = product.geometry.get("designer", {})
    changes = {"directions": [list(v) for v in record.get("directions", [])],
               "not_blocking": [dict(m) for m in record.get("not_blocking", [])]}
    if intent.diagrams.get("parts"):
        data = product_to_dict(product)
        changes["diagrams"] = {**intent.diagrams, "obstructions": data["obstructions"],
                               "analysis": product.geometry.get("analysis", {})}
    update_intent(analysis, description, **changes)


def add_analysis_direction(analysis, direction) -> list[str]:
    """Add a designer direction (``X,Y,Z`` text or three numbers: checked and normalised) to the analysis, in
    one undoable transaction; the next detection tests it like the axes. Returns notes: a direction along an
    axis or within 2 degrees of one already there is merged (nothing changes). Raises
    :class:`~planner.errors.GeometryError` for a bad vector, before anything changes."""
    product, intent = _designer_product(analysis)
    added, notes = add_directions(product, [direction])
    if not notes:
        name = added.geometry["designer"]["directions"][-1]
        _store_designer(analysis, intent, added, f"add direction {', '.join(f'{c:g}' for c in name)}")
    return notes


def _marks(relations) -> list[tuple[str, str, object]]:
    """Diagram rows ``("blocks D", x, y)`` as marks ``(x, y, D)``; D an axis name or a JSON vector."""
    from .diagrams import RelationError

    marks = []
    for kind, x, y in relations:
        if not kind.startswith("blocks "):
            raise RelationError(f"{kind} {x} - {y}: only an obstruction can be marked not blocking")
        name = kind[len("blocks "):]
        marks.append((x, y, name if not name.startswith("[") else json.loads(name)))
    return marks


def mark_not_blocking(analysis, relations) -> list[str]:
    """Mark obstruction relations of the stored diagrams (rows ``("blocks +X", x, y)``: x blocked by y along
    +X) not blocking, in one undoable transaction: they leave the diagrams now and after every detection (the
    analysis' ``NotBlocking``). A mark along a direction that is neither an axis nor a designer direction adds
    it to the designer directions. Returns notes. Raises :class:`~freecad_aplan.diagrams.RelationError` for a
    relation the diagrams do not hold or a contact, :class:`~freecad_aplan.intent.IntentError` before any
    detection; nothing changes then."""
    from .diagrams import RelationError, _key, describe_relation, relation_rows
    from .intent import IntentError

    product, intent = _designer_product(analysis)
    if not intent.diagrams.get("parts"):
        raise IntentError(f"{analysis.Label}: no contacts and obstructions yet; run APLAN > Detect contacts "
                          "and obstructions first")
    relations = [tuple(r) for r in relations]
    held = {_key(r) for r in relation_rows(intent.diagrams)}
    for relation in relations:
        if relation[0].startswith("blocks ") and _key(relation) not in held:
            raise RelationError(f"cannot mark {describe_relation(relation)} not blocking: the diagrams do not hold it")
    marked, notes = mark(product, _marks(relations))
    what = describe_relation(relations[0]) if len(relations) == 1 else f"{len(relations)} relations"
    _store_designer(analysis, intent, marked, f"mark {what} not blocking")
    return notes


def unmark_not_blocking(analysis, relations) -> None:
    """Take designer marks back (rows ``("blocks +X", x, y)`` as :func:`mark_not_blocking` takes them), in one
    undoable transaction: the relations they released return to the stored diagrams. Raises
    :class:`~planner.errors.GeometryError` for a relation that is not marked; nothing changes then."""
    from .diagrams import describe_relation

    product, intent = _designer_product(analysis)
    relations = [tuple(r) for r in relations]
    unmarked = unmark(product, _marks(relations))
    what = describe_relation(relations[0]) if len(relations) == 1 else f"{len(relations)} relations"
    _store_designer(analysis, intent, unmarked, f"unmark {what}")
