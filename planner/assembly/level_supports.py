"""Support contacts judged at the levels (workstations) of a product too large to judge flat.

The support-contact rule (:mod:`planner.assembly.support_contacts`) judges the flat product: does it need its
contacts, do they free it? Past :data:`~planner.assembly.support_contacts.CHECK_LIMIT` connected part sets it
cannot say, and such a product is planned as workstations anyway: a machine with a closed gearbox as one of
its subassemblies. Its gearbox's level then stops on the gears that would float.

Definition. The rule's *candidates* are every part some part encloses without touching it (the module's
definition, on the whole product's diagrams and boxes), each with its innermost host: found while the meshes
exist, and recorded in ``geometry.analysis.support_candidates`` (``{"mode": "add"|"error", "contacts":
[{"parts": [part, host], "walled": k}]}``, in memory). A candidate *lies at* the level where its part and its
host are in two different members (the lowest level that holds both: one level per candidate). A level whose
AND/OR graph, its fasteners folded, fails with floating members (:attr:`~planner.errors.
NotDisassemblableError.floating_parts`) one of which holds the part of a candidate lying there gets a support
contact for every candidate lying there (members touch when parts of theirs do), kept when the level then has
an AND/OR graph, as the flat rule keeps its contacts. Added contacts are recorded in
``geometry.analysis.support_contacts``, each with its ``level``; ``add`` says so in one line naming the level,
``error`` refuses naming the level, the pairs and the option. The levels are judged once the product's
subassemblies are chosen (:func:`~planner.assembly.subassembly_proposals.with_subassemblies`, which
``resolve_product`` and every level of the API go through); the proposals count a group as buildable when its
candidates free it (:func:`freeing_contacts`).

Cost: nothing without candidates. Else, per level where some candidate lies, at most two AND/OR graphs within
:data:`~planner.assembly.support_contacts.CHECK_LIMIT` connected part sets (a level past it is not judged: its
own plan refuses it with an estimate), plus one :func:`~planner.assembly.hierarchy.product_levels`.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Mapping

from ..errors import LimitExceededError
from ..product import Product
from .hierarchy import Level, product_levels
from .support_contacts import (CANDIDATES_KEY, SupportContact, _floating_parts, candidates_of, record_candidates,
                               refuse_or_say, without_candidates)

__all__ = ["CANDIDATES_KEY", "freeing_contacts", "level_needs", "level_proposals", "with_level_supports", "onto_level"]


def freeing_contacts(level: Product, candidates: tuple[SupportContact, ...],
                     member_of: Mapping[str, str] | None = None) -> tuple[SupportContact, ...]:
    """The candidates lying at the level whose product is ``level`` when they free it (module docstring), else
    ``()`` (it plans, it is stuck otherwise, none lies there, they do not free it, it is past the limit).
    ``member_of``: the product's parts -> the level's members that hold them (default: the level's members are
    the candidates' parts). Cost: at most two AND/OR graphs within the limit, when a candidate lies there."""
    member_of = {m: m for m in level.part_ids} if member_of is None else member_of
    here = tuple(c for c in candidates if c.part in member_of and c.host in member_of
                 and member_of[c.part] != member_of[c.host])
    if not here:
        return ()
    try:
        floating = _floating_parts(level)
        if not floating or not any(member_of[c.part] in floating for c in here):
            return ()
        touching = {frozenset(pair) for pair in level.contacts}
        added = tuple(dict.fromkeys((member_of[c.part], member_of[c.host]) for c in here
                                    if frozenset((member_of[c.part], member_of[c.host])) not in touching))
        if not added or _floating_parts(replace(level, contacts=level.contacts + added)) != ():
            return ()
    except LimitExceededError:  # not judged: the level's own plan refuses it with an estimate
        return ()
    return here


def _member_map(level: Level, levels: list[Level]) -> dict[str, str]:
    """The product's parts that ``level`` holds -> its member that holds each (a part, or a subassembly)."""
    holds = {lv.id: lv.parts for lv in levels}
    return {p: m for m in level.members for p in holds.get(m, frozenset((m,)))}


def level_needs(product: Product) -> tuple[tuple[str, SupportContact], ...]:
    """The ``(level id, candidate)`` pairs :func:`with_level_supports` would add to ``product`` (its
    subassemblies chosen), in level order, whatever the candidates' mode; ``()`` without candidates. Cost:
    module docstring."""
    _, candidates = candidates_of(product)
    if not candidates:
        return ()
    product = without_candidates(product)
    levels = product_levels(product)
    return tuple((level.id, c) for level in levels
                 for c in freeing_contacts(level.product, candidates, _member_map(level, levels)))


def level_proposals(product: Product) -> list[dict]:
    """:func:`level_needs` as the workbench's interlocks panel lists proposals: ``{"rule": "support", "parts":
    [part, host], "level": id, "text"}``, the parts the product's (not the level's members). Cost: that of
    :func:`level_needs`."""
    return [{"rule": "support", "parts": [c.part, c.host], "level": level, "text": f"level {level}: {c.text}"}
            for level, c in level_needs(product)]


def with_level_supports(product: Product) -> Product:
    """``product`` (its subassemblies chosen) with the support contacts its levels need (module docstring),
    its candidates record consumed; ``product`` itself without candidates. Raises
    :class:`~planner.errors.SupportRefusedError` for the first level that needs some in mode ``error``.
    Cost: module docstring."""
    mode, candidates = candidates_of(product)
    if not candidates:
        return product
    found = level_needs(product)
    product = without_candidates(product)
    for level in dict.fromkeys(level for level, _ in found):
        refuse_or_say(tuple(c for lv, c in found if lv == level), mode, product.name, level)
    if not found:
        return product
    analysis = dict(product.geometry.get("analysis", {}))
    analysis["support_contacts"] = list(analysis.get("support_contacts", [])) + [
        {**c.record, "level": level} for level, c in found]
    return replace(product, contacts=product.contacts + tuple((c.part, c.host) for _, c in found),
                   geometry={**product.geometry, "analysis": analysis})


def onto_level(product: Product, level: Level, levels: list[Level]) -> Product:
    """``level``'s product with ``product``'s candidates that lie at it recorded on it, named by its members
    (the proposals' next round plans it as a product of its own). Cost: O(candidates + parts)."""
    mode, candidates = candidates_of(product)
    if not candidates:
        return level.product
    member_of = _member_map(level, levels)
    mapped = tuple(SupportContact(member_of[c.part], member_of[c.host], c.walled) for c in candidates
                   if c.part in member_of and c.host in member_of and member_of[c.part] != member_of[c.host])
    return record_candidates(level.product, mapped, mode) if mapped else level.product
