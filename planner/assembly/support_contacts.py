"""Support contacts: a part that rests in the cavity of another without touching it, joined to it for planning.

The AND/OR graph's subassemblies are connected in the connection diagram (:mod:`planner.assembly.andor`). In a
closed gearbox the parts come apart one by one (the screws, the cover, the bearings, a shaft pushed out
through the housing's bores, its gear lifted out), but once a shaft is out its gear touches only the other
gear, or nothing: the part set the shaft leaves is not connected, that split is refused, and the product
"cannot be disassembled". Meanwhile the gear rests on the housing's floor. A *support contact* between the
gear and the housing says so, and the split is allowed.

Definition. Part ``h`` *encloses* part ``p`` when

1. ``p``'s axis-aligned bounding box lies inside ``h``'s (within the contact tolerance), and
2. ``h`` blocks ``p`` along at least :data:`MIN_WALLED` of the six axis directions (``(p, h)`` in the ``+A``
   diagram: along ``+A``; ``(h, p)`` in it: along ``-A``), the product having diagrams along the three axes.

Why both: the bounding boxes are the only shape the planner has at plan time besides the diagrams (the
bundle's meshes: their vertices), and the diagrams say from which sides ``h`` walls ``p`` in. A box inside
another's alone holds for any part over a chassis or a base plate; walls alone for a part wedged between two
flanges. Together: ``p`` lies within ``h``'s extent and ``h`` walls it in on all sides but at most two -- a
pocket open one way (five of six: the gearbox's housing once its cover is off), a tube open at both ends
(four). A part on a plate (one or two), in a corner or in a trough open along its length and upward (three) is
not enclosed: it could be slid or lifted away, and a contact there would join parts the designer did not.

The rule, on a product drawn in CAD (every part has a mesh; a product without meshes is planned as written):
when the flat product (its fastener groups folded, as :func:`~planner.assembly.make_plan` plans it) has no
AND/OR graph because parts would float (:attr:`~planner.errors.NotDisassemblableError.floating_parts`), every
part that some part encloses without touching it gets a support contact with it (the enclosing part with the
smallest box when several do: the innermost cavity), provided the diagnosis names one of them. Every such part,
not only those the diagnosis names first: the second gear rests on the housing as the first does, and
supporting the first alone would let the plan take its shaft out first and forbid the mirror order. Contacts
only add connected part sets, hence subassemblies, so no subset of them frees a product they do not free: they
are kept when the product then has an AND/OR graph; else the product is left as it is and the planner's error
stands. Every level of a product planned as workstations sees them (members touch when parts of theirs do).
They are recorded in ``geometry.analysis.support_contacts``.

A product too large to judge flat (its AND/OR graph past :data:`CHECK_LIMIT`: a machine with a closed gearbox
as one of its workstations) is judged at its levels instead: every part some part encloses, with its host, is
recorded as a *candidate* (``geometry.analysis.support_candidates``, with the mode), and once the product's
subassemblies are chosen each level that fails only because members would float gets the candidates lying at it
as contacts, kept when the level then plans; one line names the level (:mod:`planner.assembly.level_supports`).

Cost: O(pairs of the axis diagrams); with no part walled in by one it does not touch (the usual
product), nothing more. Else at most two flat AND/OR graphs within :data:`CHECK_LIMIT` connected part sets (the
product as it is, and with the contacts), and one reading of the meshes; past the limit, one reading of the
meshes here and at most two AND/OR graphs within the limit per level where a candidate lies (module
:mod:`~planner.assembly.level_supports`).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from ..defaults import SUBASSEMBLY_LIMIT
from ..errors import LimitExceededError, NotDisassemblableError, PlannerError, SupportRefusedError
from ..product import Product, fold
from ..product.constants import AXIS_DIRECTIONS
from .andor import and_or_graph
from .interlocks import _meshes, _tolerances

__all__ = ["SupportContact", "support_contacts", "apply_support_mode", "refuse_or_say", "record_support_proposals",
           "apply_support_proposal", "SUPPORT_PROPOSALS_KEY", "SUPPORT_MODES", "MIN_WALLED", "CHECK_LIMIT",
           "CANDIDATES_KEY", "record_candidates", "candidates_of", "without_candidates"]

log = logging.getLogger(__name__)

#: ``--support-contacts``: add (the rule's contacts, one line saying so), error (name them, plan nothing), keep
#: (the contacts as they are: the planner names the parts that would float).
SUPPORT_MODES = ("add", "error", "keep")
#: The fewest axis directions (of six) along which the enclosing part blocks the enclosed one (module docstring).
MIN_WALLED = 4
#: The AND/OR graphs the rule builds to see whether the product needs its contacts stay within the planner's own
#: limit of connected part sets (and its cuts): past it the rule does not judge the product. The closed gearbox's
#: flat graph (14 parts, its four screws in) takes 0.4 CPU s, 0.8 s once it plans (bench/README.md).
CHECK_LIMIT = SUBASSEMBLY_LIMIT
#: The key of the contacts the rule proposes (not added) under ``geometry.analysis``: the workbench's detection
#: records them while the meshes exist, for the designer to accept (:func:`record_support_proposals`).
SUPPORT_PROPOSALS_KEY = "support_proposals"


@dataclass(frozen=True)
class SupportContact:
    """``part`` rests in ``host``'s cavity: ``walled`` of the six axis directions are blocked by it."""

    part: str
    host: str
    walled: int

    @property
    def text(self) -> str:
        return f"{self.part} rests in {self.host} (inside its box, walled in along {self.walled} of the 6 axis directions)"

    @property
    def record(self) -> dict:
        """What ``geometry.analysis`` records of it: ``{"parts": [part, host], "text"}``."""
        return {"parts": [self.part, self.host], "text": self.text}


def support_contacts(product: Product, meshes=None) -> tuple[Product, tuple[SupportContact, ...]]:
    """``product`` with the support contacts of the rule (module docstring) added, and those contacts; the
    product itself and ``()`` when it needs none, when none frees it, or when it cannot be judged (no meshes,
    no diagram along some axis, an AND/OR graph past :data:`CHECK_LIMIT`). ``meshes``: the parts'
    :class:`~planner.geometry.PartMesh` (default: the product's mesh files). Cost: module docstring."""
    supported, added, _ = _judged(product, meshes)
    return supported, added


def _judged(product: Product, meshes=None) -> tuple[Product, tuple[SupportContact, ...], tuple[SupportContact, ...]]:
    """:func:`support_contacts`'s answer, and the *candidates* (every part some part encloses without touching
    it, with its innermost host) when the flat product is past :data:`CHECK_LIMIT`: the levels judge those
    (:mod:`planner.assembly.level_supports`); ``()`` otherwise."""
    walled = _walled(product)
    if not walled or meshes is None and not all(p.mesh for p in product.parts):
        return product, (), ()  # no candidate, or not drawn in CAD (planned as written): no graph is built
    try:
        stuck = _floating_parts(product)
    except LimitExceededError:  # too large to judge flat: its levels will, with the candidates
        return product, (), _enclosed(product, walled, meshes, None)
    if not stuck or not any(p in stuck for p, _ in walled):
        return product, (), ()
    added = _enclosed(product, walled, meshes, stuck)
    if not added:
        return product, (), ()
    current = replace(product, contacts=product.contacts + tuple((c.part, c.host) for c in added))
    try:
        if _floating_parts(current) != ():
            return product, (), ()  # more contacts only add subassemblies: no fewer would free it
    except LimitExceededError:
        return product, (), ()
    analysis = {**current.geometry.get("analysis", {}),
                "support_contacts": [c.record for c in added]}
    return replace(current, geometry={**current.geometry, "analysis": analysis}), tuple(added), ()


def _enclosed(product: Product, walled: dict[tuple[str, str], int], meshes, stuck) -> tuple[SupportContact, ...]:
    """Every part some part encloses (module docstring) with its innermost host, in part order; ``()`` without
    meshes for every part, or when ``stuck`` (the parts the diagnosis names; None: not asked) names none of
    them. Cost: one reading of the meshes, O(walled pairs)."""
    meshes = _meshes(product) if meshes is None else meshes
    if meshes is None:
        return ()
    boxes = {m.id: (m.vertices.min(axis=0), m.vertices.max(axis=0)) for m in meshes}
    if not all(p in boxes for p in product.part_ids):
        return ()
    margin = _tolerances(product)[0].contact
    hosts = _hosts(walled, boxes, margin)
    if stuck is not None and not any(p in hosts for p in stuck):
        return ()
    return tuple(SupportContact(p, hosts[p], walled[(p, hosts[p])]) for p in product.part_ids if p in hosts)


def apply_support_mode(product: Product, mode: str = "add", meshes=None) -> Product:
    """``product`` as ``--support-contacts MODE`` plans it (:data:`SUPPORT_MODES`): ``add`` adds the rule's
    contacts (:func:`support_contacts`) and logs one line naming them and why, ``error`` raises
    :class:`~planner.errors.SupportRefusedError` naming them, ``keep`` returns it untouched (the planner's
    error names the parts that would float). A product past :data:`CHECK_LIMIT` gets the rule's candidates
    recorded instead, for its levels to judge in the same mode (:mod:`planner.assembly.level_supports`; ``keep``
    drops any). Cost: that of :func:`support_contacts`."""
    if mode not in SUPPORT_MODES:
        raise PlannerError(f"unknown support-contact mode {mode!r}; use one of {', '.join(SUPPORT_MODES)}")
    if mode == "keep":
        return without_candidates(product)
    supported, added, candidates = _judged(product, meshes)
    candidates = candidates or (() if added else candidates_of(product)[1])  # found now, or read with the product
    if candidates:  # recorded in this command's mode
        return record_candidates(product, candidates, mode)
    if not added:
        return product
    refuse_or_say(added, mode, product.name)
    return supported


#: Why the rule adds a contact, in the line that says so.
WHY = ("cannot be taken apart otherwise (once what holds such a part is out, it would touch none of the parts "
       "left, and a subassembly must be connected in the connection diagram)")


def refuse_or_say(added: tuple[SupportContact, ...], mode: str, name: str = "", level: str | None = None) -> None:
    """``--support-contacts MODE`` on the contacts ``added`` to the product ``name`` (at its level ``level``, when
    judged there): ``error`` raises :class:`~planner.errors.SupportRefusedError` naming them and what helps,
    ``add`` logs the one line that names them and why. Cost: O(contacts)."""
    where = (f"{name}: " if name else "") + (f"level {level}: " if level is not None else "")
    listed = "; ".join(c.text for c in added)
    why = ("the product " if level is None else "the level ") + WHY
    if mode == "error":
        raise SupportRefusedError(
            f"{where}{len(added)} support contact(s) refused by --support-contacts error: {listed}; {why}. "
            "Leave out --support-contacts error to add them, or make each part one component with the part it "
            f"rests in (--group NAME={added[0].host},{added[0].part} on the CAD model)",
            [(c.part, c.host) for c in added])
    log.info("support contacts: %s%s: %s; --support-contacts error to refuse instead",
             f"level {level}: " if level is not None else "", listed, why)


def record_support_proposals(product: Product, meshes=None) -> Product:
    """``product``, its diagrams as they are, with the contacts :func:`support_contacts` would add recorded as
    proposals in ``geometry.analysis.support_proposals`` (``[{"rule": "support", "parts": [part, host],
    "text"}]``); a product past :data:`CHECK_LIMIT` with the rule's candidates recorded instead (mode ``add``,
    :data:`CANDIDATES_KEY`), for its levels to judge once its subassemblies are chosen
    (:func:`~planner.assembly.level_supports.level_proposals` lists what they would add); ``product`` itself
    when it needs none. Cost: that of :func:`support_contacts`."""
    _, added, candidates = _judged(product, meshes)
    if candidates:
        return record_candidates(product, candidates, "add")
    if not added:
        return product
    analysis = {**product.geometry.get("analysis", {}), SUPPORT_PROPOSALS_KEY: [
        {"rule": "support", **c.record} for c in added]}
    return replace(product, geometry={**product.geometry, "analysis": analysis})


def apply_support_proposal(product: Product, proposal: dict) -> Product:
    """``product`` with the support contact of ``proposal`` (:func:`record_support_proposals`) added, as
    ``--support-contacts add`` adds it, and recorded in ``geometry.analysis.support_contacts``. Raises
    :class:`~planner.errors.PlannerError` naming the part when the product lacks one (the components changed).
    Cost: O(contacts)."""
    pair = tuple(proposal["parts"])
    missing = [p for p in pair if p not in set(product.part_ids)]
    if missing:
        raise PlannerError(f"the support contact {' in '.join(pair)} names {', '.join(missing)}, which is not a part "
                           "of the product (the components changed: detect again)")
    if frozenset(pair) not in {frozenset(c) for c in product.contacts}:
        product = replace(product, contacts=product.contacts + (pair,))
    record = product.geometry.get("analysis", {})
    done = [c for c in record.get("support_contacts", []) if frozenset(c["parts"]) != frozenset(pair)]
    analysis = {**record, "support_contacts": done + [{"parts": list(pair), "text": proposal["text"]}]}
    return replace(product, geometry={**product.geometry, "analysis": analysis})


#: Where the rule's candidates wait for the levels of a product past :data:`CHECK_LIMIT`, under
#: ``geometry.analysis`` (:mod:`planner.assembly.level_supports`).
CANDIDATES_KEY = "support_candidates"


def record_candidates(product: Product, candidates: tuple[SupportContact, ...], mode: str) -> Product:
    """``product`` with ``candidates`` recorded for its levels to judge in ``mode`` (``add`` or ``error``).
    Cost: O(candidates)."""
    record = {"mode": mode, "contacts": [{"parts": [c.part, c.host], "walled": c.walled} for c in candidates]}
    analysis = {**product.geometry.get("analysis", {}), CANDIDATES_KEY: record}
    return replace(product, geometry={**product.geometry, "analysis": analysis})


def candidates_of(product: Product) -> tuple[str, tuple[SupportContact, ...]]:
    """The mode and the candidates recorded on ``product`` (``("add", ())`` when none are). A record that is
    not :func:`record_candidates`' (a product file edited by hand) is a :class:`~planner.errors.PlannerError`
    naming it and the fix. Cost: O(candidates)."""
    record = product.geometry.get("analysis", {}).get(CANDIDATES_KEY)
    if record is None:
        return "add", ()
    try:
        mode, entries = record["mode"], record["contacts"]
        found = tuple(SupportContact(str(c["parts"][0]), str(c["parts"][1]), int(c["walled"])) for c in entries)
        if mode not in ("add", "error") or any(len(c["parts"]) != 2 for c in entries):
            raise ValueError(mode)
    except (KeyError, IndexError, TypeError, ValueError):
        raise PlannerError(f"{product.source}: geometry.analysis.{CANDIDATES_KEY}: expected {{\"mode\": \"add\" or "
                           f"\"error\", \"contacts\": [{{\"parts\": [part, host], \"walled\": k}}]}}, got "
                           f"{str(record)[:80]}; delete it (the support-contact rule records it again from the meshes)"
                           ) from None
    return mode, found


def without_candidates(product: Product) -> Product:
    """``product`` without the candidates record (itself when it has none)."""
    analysis = product.geometry.get("analysis", {})
    if CANDIDATES_KEY not in analysis:
        return product
    kept = {k: v for k, v in analysis.items() if k != CANDIDATES_KEY}
    return replace(product, geometry={**product.geometry, "analysis": kept})


def _walled(product: Product) -> dict[tuple[str, str], int]:
    """``(p, h) -> k``: the pairs of parts that do not touch where ``h`` blocks ``p`` along ``k >=``
    :data:`MIN_WALLED` axis directions; ``{}`` without diagrams along the three axes. Cost: O(pairs)."""
    along: dict[tuple[str, str], set[str]] = {}
    covered: set[str] = set()
    reverse = {name: ("-" if name[0] == "+" else "+") + name[1:] for name in AXIS_DIRECTIONS}
    for obstruction in product.obstructions:
        name = obstruction.direction.name
        if name not in AXIS_DIRECTIONS:
            continue
        covered |= {name, reverse[name]}
        for x, y in obstruction.blocks:
            along.setdefault((x, y), set()).add(name)          # x moving along it hits y
            along.setdefault((y, x), set()).add(reverse[name])  # y moving against it hits x
    if len(covered) < len(AXIS_DIRECTIONS):
        return {}
    touching = {frozenset(c) for c in product.contacts}
    return {pair: len(names) for pair, names in along.items()
            if len(names) >= MIN_WALLED and frozenset(pair) not in touching}


def _hosts(walled: dict[tuple[str, str], int], boxes: dict, margin: float) -> dict[str, str]:
    """``p -> h``: the part whose box holds ``p``'s (within ``margin``) among those walling ``p`` in, the one with
    the smallest box when several do (the innermost cavity; on a tie the first in the diagrams' order)."""
    found: dict[str, tuple[float, str]] = {}
    for p, h in walled:
        (lo, hi), (host_lo, host_hi) = boxes[p], boxes[h]
        if np.all(lo >= host_lo - margin) and np.all(hi <= host_hi + margin):
            size = float(np.prod(host_hi - host_lo))
            if p not in found or size < found[p][0]:
                found[p] = (size, h)
    return {p: h for p, (_, h) in found.items()}


def _floating_parts(product: Product) -> tuple[str, ...] | None:
    """The parts the planner's diagnosis says would float (:attr:`~planner.errors.NotDisassemblableError.
    floating_parts`) when ``product``, its fasteners folded, has no AND/OR graph; ``()`` when it has one, None
    when it is stuck otherwise or not connected. Raises :class:`~planner.errors.LimitExceededError` past
    :data:`CHECK_LIMIT` (not judged). Cost: one AND/OR graph within :data:`CHECK_LIMIT` connected part sets."""
    try:
        and_or_graph(fold(product).product, limit=CHECK_LIMIT)
    except NotDisassemblableError as error:
        return error.floating_parts or None
    except LimitExceededError:
        raise
    except PlannerError:  # not connected: not judged
        return None
    return ()
