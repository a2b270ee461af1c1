"""The interlock rules' decisions as proposals a designer accepts or rejects (the workbench's interlocks panel).

:func:`~planner.assembly.interlocks.resolve_interlocks` applies its decisions to a product that has meshes. A
designer who decides on them later, on the product's diagrams only (the workbench keeps no meshes), needs each
decision as data that applies without the geometry:

Definition. A *proposal* is a JSON object ``{"rule", "parts": [a, b], "text", ...}`` for one decision
(:data:`~planner.assembly.interlocks.RULES`), with, for the rules *overlap* and *direction*:

- ``direction``: the unit vector ``[x, y, z]`` that frees the pair, ``direction_name`` its name (an axis or
  ``[x, y, z]``), ``leaving``: the part that leaves the other along it;
- ``obstruction``: ``[[blocked, blocking], ...]``, every part's obstruction pairs along the direction as a
  detection finds them, when the product had no diagram along it (else absent);
- ``not_blocking``: ``[[blocked, blocking], ...]`` along the direction: the pair's obstruction pairs the rule
  takes away (those of the overlap itself); designer marks (:mod:`planner.product.designer`), so that every
  later detection applies them too;

and for the rule *component*: ``component``, the id of the part that holds both (:func:`~planner.product.merge.
merge_parts`). :func:`apply_proposal` applies one to a product: the designer directions and marks it stands
for, the diagram along its direction, or the merge: what ``resolve_interlocks`` did to the pair.

A *refusal* is a proposal the designer rejected, kept in the product's ``geometry.designer.refused_interlocks``
(``[{"parts": [a, b], "rule", "text"}]``): while the pair is interlocked, planning it raises the
:class:`~planner.errors.InterlockRefusedError` of ``--interlocks error`` (:func:`refusal_error`), and
``--interlocks resolve`` does not apply the rule to it: nothing is applied that the designer turned down.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..product import Direction, Obstruction, Product
from ..product.merge import merge_parts
from .feasibility import interlocked_pairs
from .interlock_refusals import REFUSED_KEY, refusal_error, refusal_message, refused_interlocks
from .interlocks import _meshes, _pair_relation, _tolerances, resolve_interlocks

__all__ = ["interlock_proposals", "record_proposals", "PROPOSALS_KEY", "apply_proposal", "refused_interlocks", "refusal_message", "refusal_error",
           "REFUSED_KEY"]

#: The key of the proposals (and of the lines of the pairs no rule frees) under ``geometry.analysis``.
PROPOSALS_KEY = "interlock_proposals"


def interlock_proposals(product: Product, meshes=None) -> tuple[list[dict], list[str]]:
    """The decisions :func:`~planner.assembly.interlocks.resolve_interlocks` takes on ``product`` as proposals
    (module docstring), in its order, and one line per pair no rule frees (:attr:`~planner.assembly.interlocks.
    Unresolved.line`). ``meshes``: the parts' meshes (default: the product's mesh files); none: no proposals,
    and the lines say so. Applying every proposal in order (:func:`apply_proposal`) gives the product that
    ``resolve_interlocks`` returns, up to its ``geometry.analysis.interlocks`` record.
    Cost: that of ``resolve_interlocks``, plus one raster of two parts per overlap decision."""
    if not interlocked_pairs(product):
        return [], []
    if meshes is None:
        meshes = _meshes(product)
    resolved, decisions, unresolved = resolve_interlocks(product, meshes)
    lines = [u.line for u in unresolved]
    if not decisions:
        return [], lines
    by_id = {m.id: m for m in meshes}
    tol, pixel = _tolerances(product)
    if pixel <= 0:  # as resolve_interlocks chooses it
        extent = float(np.ptp(np.vstack([m.vertices for m in meshes]), axis=0).max())
        pixel = extent / tol.resolution if extent > 0 else 1.0
    # The pair's pairs along each overlap decision's direction as a detection finds them (the overlap in): the
    # product's diagram along it, else the pair's raster.
    had = {o.direction.name: o for o in product.obstructions}
    raw: dict[tuple[str, str, str], set] = {}
    for d in decisions:
        if d.rule == "overlap":
            a, b = d.parts
            name = d.direction.name
            raw[(a, b, name)] = ({p for p in had[name].blocks if set(p) == {a, b}} if name in had else set(
                _pair_relation(by_id[a], by_id[b], np.asarray(d.direction.vector, dtype=float), pixel, tol)))
    proposals = []
    for d in decisions:
        entry = {"rule": d.rule, "parts": list(d.parts), "text": d.text}
        if d.rule == "component":
            entry["component"] = d.component
            proposals.append(entry)
            continue
        a, b = d.parts
        name = d.direction.name
        now = next(o for o in resolved.obstructions if o.direction.name == name)
        kept = {p for p in now.blocks if set(p) == {a, b}}
        found = raw.get((a, b, name), kept)
        entry.update(direction=list(d.direction.vector), direction_name=name,
                     leaving=a if (a, b) not in kept else b, not_blocking=sorted([list(p) for p in found - kept]))
        if name not in had:  # every proposal along it carries it: any one of them may be accepted alone
            decided = {frozenset(k[:2]): v for k, v in raw.items() if k[2] == name}
            blocks = [p for p in now.blocks if frozenset(p) not in decided]
            blocks += sorted(p for v in decided.values() for p in v)
            entry["obstruction"] = [list(p) for p in blocks]
        proposals.append(entry)
    return proposals, lines


def record_proposals(product: Product, meshes=None) -> Product:
    """``product`` with its interlock proposals (:func:`interlock_proposals`) recorded in its
    ``geometry.analysis``: ``interlock_proposals`` and ``interlock_unresolved`` (the lines); ``product`` itself
    when nothing is interlocked. Its diagrams as they are. A detection calls this while the meshes exist (the
    workbench's Detect). Cost: that of :func:`interlock_proposals`."""
    proposals, lines = interlock_proposals(product, meshes)
    if not proposals and not lines:
        return product
    analysis = {**product.geometry.get("analysis", {}), PROPOSALS_KEY: proposals, "interlock_unresolved": lines}
    return replace(product, geometry={**product.geometry, "analysis": analysis})


def apply_proposal(product: Product, proposal: dict) -> Product:
    """``product`` with ``proposal`` (module docstring) applied: the component made, or the diagram along the
    proposal's direction added when it lacks it, that direction added to the designer directions (an axis
    needs none) and the pair's relations it takes away marked not blocking
    (:func:`~planner.product.designer.mark_not_blocking`). Raises :class:`~planner.errors.PlannerError`
    naming the part when the proposal names parts the product does not have. Cost: O(size of the product)."""
    from ..errors import PlannerError
    from ..product.designer import add_directions, mark_not_blocking

    parts = tuple(proposal["parts"])
    missing = [p for p in parts if p not in set(product.part_ids)]
    if missing:
        raise PlannerError(f"the interlock proposal for {' and '.join(parts)} names {', '.join(missing)}, which is "
                           "not a part of the product (the components changed: detect again)")
    if proposal["rule"] == "component":
        return merge_parts(product, proposal["component"], parts)
    direction = Direction.from_vector(tuple(float(c) for c in proposal["direction"]))
    if direction.name not in {o.direction.name for o in product.obstructions}:
        blocks = tuple(tuple(p) for p in proposal.get("obstruction", ()))
        product = replace(product, obstructions=product.obstructions + (Obstruction(direction, blocks),))
    if direction.name[:1] == "[":  # not an axis: every later detection tests it too
        product, _ = add_directions(product, [direction.vector])
    marks = [(x, y, list(direction.vector)) for x, y in proposal.get("not_blocking", ())]
    if marks:
        product, _ = mark_not_blocking(product, marks)
    return product
