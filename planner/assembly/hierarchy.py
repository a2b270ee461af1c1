"""Subassemblies: a product planned as a tree of workstations (paper Sec. I and V: real products are split
over several workstations, each assembling about six parts).

Definitions
-----------
- A *subassembly* (:class:`~planner.product.Subassembly`) names its direct *members*: parts and other
  subassemblies. The subassemblies of a product form a forest; the members of no subassembly form the *top
  level*.
- A *level* is one subassembly (or the top) seen as a product of its own, whose parts are its members: a
  built subassembly is one part. Two members touch when any part of one touches any part of the other;
  member ``X`` is blocked by member ``Y`` along ``d`` when any part of ``X`` is blocked by any part of ``Y``
  along ``d``. Technical constraints and operation tags whose parts all lie in the level are kept, mapped
  onto its members; a constraint that a member already settles (``R2`` built into a member with some of
  ``R1``) is dropped, as it was checked where that member was built.
- Fasteners (:mod:`planner.product.fasteners`) are no members: the levels are those of the product without
  them, and each fastener group is installed at the lowest level that holds all its hosts, joining the
  members that hold them (a screw between the cabin and the chassis is driven where the cabin joins the
  chassis, not inside either).
- A level is planned with the flat planner (:func:`~planner.assembly.make_plan`), independently of the others;
  the levels are listed bottom-up, so the inner subassemblies are built first.

:func:`~planner.assembly.subassembly_proposals.propose_subassemblies` proposes a tree when the designer gave
none (:mod:`planner.assembly.subassembly_proposals`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from ..errors import LimitExceededError, PlannerError
from ..product import Markers, Obstruction, OperationTag, Part, Product, Subassembly, TechnicalConstraint, fold

__all__ = ["TOP", "Level", "product_levels", "SUBASSEMBLY_MODES", "PROPOSED", "level_statistics", "select_level", "check_level_constraints", "ConstraintViolationError"]

TOP = "top"  # the id of the top level (the product's own, joining the members of no subassembly)
SUBASSEMBLY_MODES = ("designer", "auto", "none")
PROPOSED = "proposed"


@dataclass(frozen=True)
class Level:
    """One workstation: ``id`` is the subassembly's id (or :data:`TOP`), ``product`` the level as a product whose
    parts are the members, ``parts`` the product's parts it holds (all of them for the top level)."""

    id: str
    product: Product
    parts: frozenset[str]

    @property
    def members(self) -> tuple[str, ...]:
        return self.product.part_ids


def _owners(product: Product) -> dict[str, str]:
    """Member -> the subassembly that holds it (members of no subassembly are absent)."""
    return {member: group.id for group in product.subassemblies for member in group.parts}


def _bottom_up(product: Product) -> list[Subassembly]:
    """The subassemblies in post-order (every subassembly after the ones it holds), in file order otherwise."""
    by_id = {g.id: g for g in product.subassemblies}
    done: list[Subassembly] = []
    seen: set[str] = set()

    def visit(group: Subassembly) -> None:
        seen.add(group.id)
        for member in group.parts:
            if member in by_id and member not in seen:
                visit(by_id[member])
        done.append(group)

    owners = _owners(product)
    for group in product.subassemblies:
        if group.id not in owners and group.id not in seen:
            visit(group)
    return done


def product_levels(product: Product) -> list[Level]:
    """Every level of ``product``, bottom-up: its subassemblies (inner ones first), then the top level.

    A product without subassemblies is one level, the product itself (unchanged). The top level is left out
    when a single subassembly holds everything. Cost: O(levels x (contacts + obstruction pairs)).
    """
    if not product.subassemblies:
        return [Level(TOP, product, frozenset(product.part_ids))]
    if product.fasteners:
        return _with_fasteners(product)
    owners = _owners(product)
    groups = _bottom_up(product)
    by_id = {g.id: g for g in groups}
    parts_of: dict[str, frozenset[str]] = {}
    for group in groups:
        parts_of[group.id] = frozenset().union(*(parts_of.get(m, frozenset((m,))) for m in group.parts))
    levels = [Level(g.id, _level_product(product, g.id, g.parts, owners, by_id, parts_of, g.label), parts_of[g.id])
              for g in groups]
    top = tuple(p for p in product.part_ids if p not in owners) + tuple(g.id for g in product.subassemblies
                                                                         if g.id not in owners)
    if len(top) > 1:
        top_product = _level_product(product, TOP, top, owners, by_id, parts_of, "")
        levels.append(Level(TOP, top_product, frozenset(product.part_ids)))
    return levels


def _with_fasteners(product: Product) -> list[Level]:
    """The levels of ``product`` without its fastener parts (they are no members, even where the designer's
    subassemblies list them), each fastener group added to the lowest level that holds all its hosts, its
    hosts mapped onto that level's members. Cost: that of the levels plus O(fastener parts x levels)."""
    folding = fold(product)
    levels = product_levels(folding.product)  # its subassemblies without the fasteners (some dissolved: fold)
    holds = {level.id: level.parts for level in levels}
    parts = {p.id: p for p in product.parts}
    markers = dict(product.markers.ids) if product.markers is not None else {}
    placed: set[str] = set()
    out = []
    for level in levels:
        here = [g for g in folding.groups if g.id not in placed and g.hosts <= level.parts]
        if not here:
            out.append(level)
            continue
        placed.update(g.id for g in here)
        member_of = {p: m for m in level.members for p in holds.get(m, frozenset((m,)))}
        groups = tuple(replace(g, hosts=frozenset(member_of[h] for h in g.hosts)) for g in here)
        added = tuple(parts[p] for g in groups for p in g.parts)
        touching = tuple((p, h) for g in groups for p in g.parts for h in sorted(g.hosts))
        level_product = level.product
        if level_product.markers is not None:
            ids = level_product.markers.ids + tuple((p.id, markers[p.id]) for p in added if p.id in markers)
            level_product = replace(level_product, markers=Markers(ids, level_product.markers.dictionary))
        level_product = replace(level_product, parts=level_product.parts + added,
                                contacts=level_product.contacts + touching, fasteners=groups)
        out.append(Level(level.id, level_product, level.parts | frozenset(p.id for p in added)))
    return out


def _level_product(product: Product, level: str, members: tuple[str, ...], owners: dict[str, str],
                   by_id: dict[str, Subassembly], holds: dict[str, frozenset[str]], label: str) -> Product:
    """The level whose direct members are ``members`` as a product (see the module's definitions)."""
    member_set = set(members)

    def member_of(part: str) -> str | None:
        # Walk up from a part to the member of this level that holds it (None: outside this level).
        current: str | None = part
        while current is not None and current not in member_set:
            current = owners.get(current)
        return current

    parts = {p.id: p for p in product.parts}
    level_parts = tuple(parts[m] if m in parts else Part(m, by_id[m].label or m) for m in members)
    contacts: dict[frozenset[str], tuple[str, str]] = {}
    for a, b in product.contacts:
        x, y = member_of(a), member_of(b)
        if x is not None and y is not None and x != y:
            contacts.setdefault(frozenset((x, y)), (x, y))
    obstructions = []
    for obstruction in product.obstructions:
        blocks: dict[tuple[str, str], None] = {}
        for a, b in obstruction.blocks:
            x, y = member_of(a), member_of(b)
            if x is not None and y is not None and x != y:
                blocks[(x, y)] = None
        obstructions.append(Obstruction(obstruction.direction, tuple(blocks)))
    constraints = []
    for c in product.technical_constraints:
        mapped = {member_of(p) for p in c.parts}
        requires = member_of(c.requires)
        if None in mapped or requires is None or requires in mapped:
            continue
        constraints.append(TechnicalConstraint(frozenset(mapped), requires, c.active, c.reason))  # type: ignore
    operations = []
    for tag in product.operations:
        sides = [{member_of(p) for p in side} for side in tag.inputs]
        # Kept when each input is whole members of this level (what is inside a member was joined before).
        if any(None in side for side in sides) or sides[0] & sides[1]:
            continue
        if any(frozenset().union(*(holds.get(m, frozenset((m,))) for m in side)) != original
               for side, original in zip(sides, tag.inputs)):
            continue
        inputs = (frozenset(sides[0]), frozenset(sides[1]))
        operations.append(OperationTag(inputs, tag.unfavorable, tag.robot, tag.tool))  # type: ignore
    markers = None
    if product.markers is not None:
        keep = member_set | {t.id for t in product.tools}
        ids = tuple((name, m) for name, m in product.markers.ids if name in keep)
        ids += tuple((m, marker) for m, marker in _subassembly_markers(product).items() if m in member_set)
        markers = Markers(ids, product.markers.dictionary)
    name = product.name if level == TOP else f"{product.name or 'product'} / {label or level}"
    return Product(level_parts, tuple(contacts.values()), tuple(obstructions), tuple(constraints), product.tools,
                   tuple(operations), product.defaults, markers, name=name, units=product.units, source=product.source)


def _subassembly_markers(product: Product) -> dict[str, int]:
    """A marker for each subassembly (a built one lies in the tray as one part): the free marker ids of the
    product's dictionary after its own, in file order; those beyond the dictionary get none (the session then
    names them)."""
    from ..product import MARKER_DICTIONARIES

    taken = {marker for _, marker in product.markers.ids}
    free = (k for k in range(MARKER_DICTIONARIES.get(product.markers.dictionary, 0)) if k not in taken)
    return {group.id: marker for group, marker in zip(product.subassemblies, free)}


class ConstraintViolationError(PlannerError):
    """A subassembly holds the parts of an active technical constraint without the part they require."""


def check_level_constraints(product: Product, level: Level) -> None:
    """Raise :class:`ConstraintViolationError` when ``level``, once built, holds every part ``R1`` of an active
    technical constraint of ``product`` but not ``R2``: no plan inside the level can respect it (the level's
    own product drops such a constraint, as ``R2`` is not one of its members). Cost: O(constraints x parts)."""
    for c in product.technical_constraints:
        if c.active and c.parts <= level.parts and c.requires not in level.parts and len(level.parts) > 1:
            raise ConstraintViolationError(
                f"subassembly {level.id} ({', '.join(sorted(level.parts))}) holds {', '.join(sorted(c.parts))} "
                f"without {c.requires}, which a technical constraint requires with them"
                f"{' (' + c.reason + ')' if c.reason else ''}; add {c.requires} to it or take "
                f"{', '.join(sorted(c.parts))} apart")


def level_statistics(product: Product, technical: bool | None = None, limits=None,
                     progress=None) -> list[tuple[Level, object]]:
    """Each level of ``product`` (bottom-up) with its figures (:func:`~planner.assembly.statistics_within`: a
    level past the size limits has the figures it reached and ``refused``), or the :class:`PlannerError` that
    stops its plan (a level that cannot be built on its own: the stuck parts are named). ``progress(text)``,
    when given, is told each level before it is planned. Cost: the sum of the levels' plans."""
    from .guards import SizeLimits
    from .stats import statistics_within

    limits = limits or SizeLimits()
    found: list[tuple[Level, object]] = []
    product = product.with_technical(technical)
    levels = product_levels(product)
    for k, level in enumerate(levels):
        if progress is not None:
            progress(f"level {k + 1} of {len(levels)}: {level.id} ({len(level.members)} members)")
        try:
            check_level_constraints(product, level)
            found.append((level, statistics_within(level.product, technical, None, limits)[1]))
        except LimitExceededError:
            raise
        except PlannerError as error:
            found.append((level, error))
    return found


def select_level(product: Product, level: str | None) -> Level:
    """The level named ``level`` (a subassembly id, or :data:`TOP`); None: the only level of a product planned
    flat. A product of several levels without ``level`` is a :class:`PlannerError` listing them; a level that
    breaks a technical constraint is a :class:`ConstraintViolationError`."""
    levels = product_levels(product)
    if level is None:
        if len(levels) == 1:
            check_level_constraints(product, levels[0])
            return levels[0]
        raise PlannerError(f"the product is planned as {len(levels)} subassemblies (workstations): "
                           f"{', '.join(lv.id for lv in levels)}; pick one with --level ID, or plan it flat "
                           "with --subassemblies none")
    for candidate in levels:
        if candidate.id == level:
            check_level_constraints(product, candidate)
            return candidate
    raise PlannerError(f"--level {level}: no such subassembly; the levels are {', '.join(lv.id for lv in levels)}")
