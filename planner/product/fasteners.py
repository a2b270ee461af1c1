"""Folding fasteners into the operations that install them.

Definition
----------
A fastener group ``G`` (screws, nuts, washers, ...; :class:`~planner.product.model.FastenerGroup`) joins its
*hosts* ``H``. Folding ``G`` removes its parts from the product and makes ``H`` connected: every two hosts that
do not touch get a contact (the fastener is their liaison). Obstructions, technical constraints, operation
tags and markers keep only the remaining parts: a fastener goes in last in its operation, so it never blocks
the parts being joined. The group is then installed by every AND/OR operation with inputs ``L``, ``R`` that
first brings all its hosts together: ``H <= L | R``, ``H`` not ``<= L``, ``H`` not ``<= R``
(:func:`planner.assembly.tags.fastener_installs`).

Why: a screw that touches two parts doubles the connected part sets holding that joint, so 39 screws
multiply the AND/OR graph by up to 2^39; folded, they add nothing to it.

Cost: O(parts + contacts + obstruction pairs + hosts^2 per group).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from itertools import combinations

from .model import FastenerGroup, Markers, OperationTag, Product, TechnicalConstraint
from .validation import fastener_hosts

__all__ = ["FASTENER_MODES", "Folding", "dissolve_small", "fold", "fold_fasteners", "with_fastener_mode"]

log = logging.getLogger(__name__)

# tagged: the product's 'fasteners' section; auto: that and the planner's proposals; none: no folding.
FASTENER_MODES = ("tagged", "auto", "none")


@dataclass(frozen=True)
class Folding:
    """A product with its fastener groups folded.

    ``original``: the product as given (with its ``fasteners`` section); ``product``: without the fastener
    parts; ``groups``: the groups with their hosts resolved (never empty); ``added_contacts``: the host-host
    contacts folding added (the fasteners are those liaisons).
    """

    original: Product
    product: Product
    groups: tuple[FastenerGroup, ...]
    added_contacts: tuple[tuple[str, str], ...]

    @property
    def folded_parts(self) -> int:
        return sum(len(group.parts) for group in self.groups)


def fold(product: Product) -> Folding:
    """Fold every fastener group of ``product`` (see the module's definition); a product without fastener
    groups is returned as it is."""
    if not product.fasteners:
        return Folding(product, product, (), ())
    groups = tuple(replace(group, hosts=hosts) for group, hosts in zip(product.fasteners, fastener_hosts(product)))
    gone = product.fastener_parts
    contacts = [(a, b) for a, b in product.contacts if a not in gone and b not in gone]
    touching = {frozenset(c) for c in contacts}
    added = []
    for group in groups:
        for a, b in combinations(sorted(group.hosts), 2):
            if frozenset((a, b)) not in touching:
                touching.add(frozenset((a, b)))
                added.append((a, b))
    obstructions = tuple(replace(o, blocks=tuple((x, y) for x, y in o.blocks if x not in gone and y not in gone))
                         for o in product.obstructions)
    folded = replace(product, parts=tuple(p for p in product.parts if p.id not in gone),
                     contacts=tuple(contacts + added), obstructions=obstructions,
                     technical_constraints=_constraints(product.technical_constraints, gone),
                     operations=_operations(product.operations, gone), markers=_markers(product.markers, gone),
                     subassemblies=_structure(product, gone), fasteners=())
    return Folding(product, folded, groups, tuple(added))


def _structure(product: Product, gone: frozenset[str]) -> tuple:
    """The subassemblies without the fasteners folded (``gone``): a fastener a subassembly lists is installed by
    the operation that joins its hosts, no member of its own. A subassembly left with fewer than two members is
    dissolved (its member, if any, takes its place in the subassembly holding it), with a warning naming it and
    the fasteners. Cost: O(members x nesting depth)."""
    groups = {g.id: g for g in product.subassemblies}
    members = {g.id: [m for m in g.parts if m not in gone] for g in product.subassemblies}
    dissolved = dissolve_small(members)
    for sid, stands in dissolved.items():
        folded = [m for m in groups[sid].parts if m in gone]
        log.warning("subassembly %r is dissolved: folding the fastener%s %s leaves it %s", sid,
                    "s" if len(folded) > 1 else "", ", ".join(folded) or "(none of its own)",
                    f"only {stands}, which takes its place" if stands else "empty")
    return tuple(replace(g, parts=tuple(members[g.id])) if tuple(members[g.id]) != g.parts else g
                 for g in product.subassemblies if g.id not in dissolved)


def dissolve_small(members: dict[str, list[str]]) -> dict[str, str | None]:
    """Dissolve, in place, every subassembly of ``members`` (subassembly id -> its member ids) left with fewer
    than two members: its member, if any, takes its place in the subassembly holding it, which may be left too
    small in turn. Returns each dissolved subassembly and what stands for it now (None: nothing), in the order
    they were dissolved. Cost: O(members x nesting depth)."""
    dissolved: dict[str, str | None] = {}
    changed = True
    while changed:  # a dissolved subassembly can leave the one holding it with too few members in turn
        changed = False
        for sid, inner in members.items():
            if sid in dissolved:
                continue
            inner[:] = [x for m in inner for x in ([dissolved[m]] if m in dissolved else [m]) if x is not None]
            if len(inner) < 2:
                dissolved[sid] = inner[0] if inner else None
                changed = True
    return dissolved


def fold_fasteners(product: Product) -> Product:
    """``product`` without its fastener parts, their hosts connected (:func:`fold`)."""
    return fold(product).product


def with_fastener_mode(product: Product, mode: str, proposals: tuple[FastenerGroup, ...] = ()) -> Product:
    """``product`` with the fastener groups ``mode`` folds: ``tagged`` its own, ``auto`` its own and
    ``proposals`` (those whose parts no group of it holds), ``none`` no group."""
    if mode == "tagged":
        return product
    if mode == "none":
        return replace(product, fasteners=()) if product.fasteners else product
    if mode != "auto":
        from ..errors import PlannerError

        raise PlannerError(f"unknown fastener mode {mode!r}; use one of {', '.join(FASTENER_MODES)}")
    taken = product.fastener_parts
    ids = {group.id for group in product.fasteners}
    extra = tuple(group for group in proposals if not taken & set(group.parts) and group.id not in ids)
    return replace(product, fasteners=product.fasteners + extra) if extra else product


def _constraints(constraints: tuple[TechnicalConstraint, ...], gone: frozenset[str]) -> tuple:
    kept = []
    for constraint in constraints:
        parts = constraint.parts - gone
        if constraint.requires in gone or not parts:
            log.warning("a technical constraint on %s requiring %r names fasteners only; it is dropped with them",
                        sorted(constraint.parts), constraint.requires)
            continue
        kept.append(replace(constraint, parts=parts))
    return tuple(kept)


def _operations(tags: tuple[OperationTag, ...], gone: frozenset[str]) -> tuple:
    kept = []
    for tag in tags:
        first, second = (side - gone for side in tag.inputs)
        if first and second:
            kept.append(replace(tag, inputs=(first, second)))
    return tuple(kept)


def _markers(markers: Markers | None, gone: frozenset[str]) -> Markers | None:
    if markers is None:
        return None
    return replace(markers, ids=tuple((name, marker) for name, marker in markers.ids if name not in gone))
