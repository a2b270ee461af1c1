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

:func:`propose_subassemblies` proposes a tree when the designer gave none: connected groups of at most
``max_components`` members from the connection diagram, each checked to be buildable on its own, nested until
the top level has at most ``max_components`` members.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace

from ..defaults import MAX_COMPONENTS, SUBASSEMBLY_LIMIT
from ..errors import LimitExceededError, NotDisassemblableError, PlannerError
from ..product import Markers, Obstruction, OperationTag, Part, Product, Subassembly, TechnicalConstraint, fold
from .andor import and_or_graph
from .feasibility import interlocked_pairs

__all__ = ["TOP", "Level", "product_levels", "propose_subassemblies", "with_subassemblies", "SUBASSEMBLY_MODES",
           "level_statistics", "select_level", "check_level_constraints", "ConstraintViolationError"]

log = logging.getLogger(__name__)

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


def with_subassemblies(product: Product, mode: str = "designer", max_components: int = MAX_COMPONENTS) -> Product:
    """``product`` with the subassemblies ``mode`` asks for: ``designer`` its own (none if absent), ``auto`` its
    own or, when it has none, :func:`propose_subassemblies`, ``none`` none (planned flat)."""
    if mode not in SUBASSEMBLY_MODES:
        raise PlannerError(f"unknown subassembly mode {mode!r}; use one of {', '.join(SUBASSEMBLY_MODES)}")
    if mode == "none":
        return replace(product, subassemblies=()) if product.subassemblies else product
    if mode == "auto" and not product.subassemblies:
        proposed = propose_subassemblies(product, max_components)
        return replace(product, subassemblies=proposed) if proposed else product
    return product


def propose_subassemblies(product: Product, max_components: int = MAX_COMPONENTS) -> tuple[Subassembly, ...]:
    """A tree of workstation-sized subassemblies for ``product``, from its connection diagram.

    Definition: the parts are grouped into connected groups of at most ``max_components`` members by greedy
    agglomeration (Lance-Williams average linkage on the connection diagram: the two adjacent groups with the
    most contacts per pair of members merge first, while their union fits); each group of two or more becomes
    a subassembly, one member of the next round; rounds repeat until at most ``max_components`` members are
    left, which form the top level. A group is kept only if it can be built on its own (its level has a
    feasible AND/OR graph, :func:`~planner.assembly.and_or_graph`); a group that cannot is merged with the
    neighbouring group it shares most contacts with whose union can be built, allowing the union up to 1.5 x
    ``max_components`` members (the agglomeration already merged every pair that fits), else it is left as it
    is and a warning names its stuck parts (its level's plan will then fail with the same reason).

    Two groups of one round that would block each other along every direction once built are merged into
    one, or when their union would pass 1.5 x ``max_components`` members, one member is taken out of them
    (:func:`_separable_groups`), so the level above can take its members apart.

    Fasteners are left out of the groups (the connection diagram is that of the folded product, its fasteners'
    hosts joined: :func:`~planner.product.fold`); :func:`product_levels` installs each group where its hosts
    come together.

    Returns the subassemblies (``source="proposed"``, ids ``sa1``, ``sa2``, ... unless a part has that id),
    inner ones first; () when the product, fasteners left out, has at most ``max_components`` parts.

    Cost: O(rounds x n^3) for the agglomeration of n members per round, plus one AND/OR graph of at most
    ``max_components`` members per group (at most 2^max_components connected sets each).
    """
    if max_components < 2:
        raise PlannerError(f"a subassembly holds two or more members; max_components must be at least 2, got "
                           f"{max_components}")
    used = set(product.part_ids) | {t.id for t in product.tools}
    product = fold(product).product   # fasteners are installed between members, never members themselves
    counter = iter(range(1, 10 ** 9))
    found: list[Subassembly] = []
    current = product
    while len(current.parts) > max_components:
        groups = _agglomerate(current, max_components)
        if all(len(g) == 1 for g in groups):  # cannot happen on a connected diagram; never loop forever
            break
        groups = _separable_groups(product, found, groups, current, max_components)
        if all(len(g) == 1 for g in groups):  # peeled down to single members: nothing to group this round
            break
        added = []
        for group in groups:
            if len(group) < 2:
                continue
            name = next(f"sa{k}" for k in counter if f"sa{k}" not in used)
            used.add(name)
            label = " + ".join(group[:3]) + (f" + {len(group) - 3} more" if len(group) > 3 else "")
            added.append(Subassembly(name, tuple(group), label, PROPOSED))
        found.extend(added)
        current = product_levels(replace(product, subassemblies=tuple(found)))[-1].product
    from .untangle import untangled  # imports this module

    return untangled(product, tuple(found))


def _separable_groups(product: Product, found: list[Subassembly], groups: list[list[str]], current: Product,
                      cap: int) -> list[list[str]]:
    """``groups`` (one round's members of ``current``, grouped) changed until the level above could take them
    apart: two groups that, built, would block each other along every direction (:func:`~planner.assembly.
    feasibility.interlocked_pairs`) are

    - merged into one when their union has at most 1.5 ``cap`` members (a workstation a little too large is
      better than a product that cannot be taken apart), else
    - *peeled*: the member of the two whose removal leaves the fewest interlocked pairs above (fewer than
      before) is taken out and left to the level above, its group split into its connected pieces, each
      buildable on its own (the pump's head 9_001, which holds the outlet manifold on one side while the
      inlet manifold spans both heads), else
    - merged anyway.

    Two single members that block each other stay as they are: no grouping separates them (the level's plan
    names them). Cost: per change, one level product and one O(n^2 D) test per member of the two groups (a
    peel), and one AND/OR graph of at most ``cap`` members per piece kept; at most 2 x ``len(groups)`` changes.
    """
    groups = [list(g) for g in groups]
    for _ in range(2 * len(groups) + 1):
        names, pairs = _interlocked_groups(product, found, groups)
        pair = next(((a, b) for a, b in pairs if a in names or b in names), None)
        if pair is None:
            break
        first, second = (names[p] if p in names else next(g for g in groups if g == [p]) for p in pair)
        rest = [g for g in groups if g is not first and g is not second]
        if len(first) + len(second) > cap + cap // 2:
            peeled = _peeled(product, found, current, rest, first, second, len(pairs))
            if peeled is not None:
                groups = peeled
                continue
        if len(groups) <= 2:  # merged, one group would hold everything: the round would never end
            break
        groups = rest + [first + second]
    return groups


def _interlocked_groups(product: Product, found: list[Subassembly], groups: list[list[str]]) \
        -> tuple[dict[str, list[str]], list[tuple[str, str]]]:
    """The trial names of the groups of two or more, and the interlocked pairs of the level above them."""
    names = {f"_group{k}": group for k, group in enumerate(groups) if len(group) > 1}
    trial = tuple(found) + tuple(Subassembly(name, tuple(group)) for name, group in names.items())
    above = product_levels(replace(product, subassemblies=trial))[-1].product
    return names, [(p.first, p.second) for p in interlocked_pairs(above)]


def _peeled(product: Product, found: list[Subassembly], current: Product, rest: list[list[str]], first: list[str],
            second: list[str], before: int) -> list[list[str]] | None:
    """The groups with one member of ``first`` or ``second`` taken out (see :func:`_separable_groups`), or None
    when no member's removal leaves fewer than ``before`` interlocked pairs with buildable pieces."""
    best = None
    for member in first + second:
        pieces = [piece for group in (first, second) for piece in _pieces(current, [m for m in group if m != member])]
        trial = rest + pieces + [[member]]
        count = len(_interlocked_groups(product, found, trial)[1])
        if count < before and (best is None or count < best[0]) \
                and all(len(piece) < 2 or _stuck_parts(current, piece) is None for piece in pieces):
            best = (count, trial)
    return None if best is None else best[1]


def _pieces(product: Product, members: list[str]) -> list[list[str]]:
    """``members`` split into the sets connected by ``product``'s contacts among them, in member order."""
    inside = set(members)
    touching: dict[str, set[str]] = {m: set() for m in members}
    for a, b in product.contacts:
        if a in inside and b in inside:
            touching[a].add(b)
            touching[b].add(a)
    seen: set[str] = set()
    out = []
    for start in members:
        if start in seen:
            continue
        piece, stack = [], [start]
        seen.add(start)
        while stack:
            part = stack.pop()
            piece.append(part)
            stack.extend(sorted(touching[part] - seen))
            seen.update(touching[part])
        out.append(sorted(piece, key=members.index))
    return out


def _agglomerate(product: Product, cap: int) -> list[list[str]]:
    """Connected groups of at most ``cap`` parts of ``product``, each buildable alone when it can be."""
    ids = product.part_ids
    weight: dict[frozenset[str], int] = {}
    for a, b in product.contacts:
        weight[frozenset((a, b))] = weight.get(frozenset((a, b)), 0) + 1
    groups: dict[str, list[str]] = {p: [p] for p in ids}  # representative -> members, in product order
    links: dict[frozenset[str], int] = dict(weight)  # contacts between two groups, by representatives

    def merge(a: str, b: str) -> None:
        groups[a] = sorted(groups[a] + groups.pop(b), key=ids.index)
        for key in [k for k in links if b in k]:
            other = next(iter(key - {b}))
            count = links.pop(key)
            if other != a:
                links[frozenset((a, other))] = links.get(frozenset((a, other)), 0) + count
            else:
                pass  # the link between a and b is now inside the group

    while True:
        best = None
        for key, count in links.items():
            a, b = sorted(key, key=ids.index)
            size = len(groups[a]) + len(groups[b])
            if size > cap:
                continue
            score = (count / (len(groups[a]) * len(groups[b])), -size, -ids.index(a), -ids.index(b))
            if best is None or score > best[0]:
                best = (score, a, b)
        if best is None:
            break
        merge(best[1], best[2])
    for rep in list(groups):
        if rep in groups and len(groups[rep]) > 1:
            _repair(product, rep, groups, links, cap, merge)
    return [groups[rep] for rep in sorted(groups, key=ids.index)]


def _stuck_parts(product: Product, members: list[str]) -> PlannerError | None:
    """The reason the group of ``members`` cannot be built on its own, or None when it can."""
    probe = replace(product, subassemblies=(Subassembly("_probe", tuple(members)),))
    level = next(level for level in product_levels(probe) if level.id == "_probe")
    try:
        check_level_constraints(product, level)
        and_or_graph(level.product, limit=SUBASSEMBLY_LIMIT)
    except (NotDisassemblableError, ConstraintViolationError) as error:
        return error
    except LimitExceededError:
        return None  # not decided cheaply: the level's own plan will say
    return None


def _repair(product: Product, rep: str, groups: dict[str, list[str]], links: dict[frozenset[str], int], cap: int,
            merge) -> None:
    """Merge the group ``rep`` with a neighbour when it cannot be built alone (the union within 1.5 ``cap``), else
    warn naming its stuck parts."""
    error = _stuck_parts(product, groups[rep])
    if error is None:
        return
    neighbours = sorted(((count, next(iter(key - {rep}))) for key, count in links.items() if rep in key),
                        reverse=True)
    for _, other in neighbours:
        union = groups[rep] + groups[other]
        if len(union) <= cap + cap // 2 and _stuck_parts(product, union) is None:
            merge(rep, other)
            return
    log.warning("proposed subassembly {%s} cannot be built on its own: %s", ", ".join(groups[rep]), error.summary)
    if error.summary != str(error):
        log.debug("why: %s", error)  # the whole explanation (aplan --verbose)


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
