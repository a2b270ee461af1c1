"""Subassemblies the planner proposes when the designer gave none (``--subassemblies auto``), and the product
with the subassemblies a mode asks for (:func:`with_subassemblies`).

Definition. :func:`propose_subassemblies` proposes a tree: connected groups of at most ``max_components``
members from the connection diagram, each checked to be buildable on its own, nested until the top level has
at most ``max_components`` members; a group that would interlock the level holding it is dissolved
(:mod:`planner.assembly.untangle`). The levels they make are :func:`~planner.assembly.hierarchy.product_levels`'.
"""
from __future__ import annotations

import logging
from dataclasses import replace

from ..defaults import MAX_COMPONENTS, SUBASSEMBLY_LIMIT
from ..errors import LimitExceededError, NotDisassemblableError, PlannerError
from ..product import Product, Subassembly, fold
from .andor import and_or_graph
from .feasibility import interlocked_pairs
from .hierarchy import PROPOSED, SUBASSEMBLY_MODES, ConstraintViolationError, check_level_constraints, product_levels
from .level_supports import candidates_of, freeing_contacts, onto_level, with_level_supports
from .untangle import untangled

__all__ = ["propose_subassemblies", "with_subassemblies", "SUBASSEMBLY_MODES"]

log = logging.getLogger(__name__)


def with_subassemblies(product: Product, mode: str = "designer", max_components: int = MAX_COMPONENTS) -> Product:
    """``product`` with the subassemblies ``mode`` asks for: ``designer`` its own (none if absent), ``auto`` its
    own or, when it has none, :func:`propose_subassemblies`, ``none`` none (planned flat); then with the support
    contacts its levels need, when the support-contact rule left them candidates (a product too large to judge
    flat: :func:`~planner.assembly.level_supports.with_level_supports`)."""
    if mode not in SUBASSEMBLY_MODES:
        raise PlannerError(f"unknown subassembly mode {mode!r}; use one of {', '.join(SUBASSEMBLY_MODES)}")
    if mode == "none":
        product = replace(product, subassemblies=()) if product.subassemblies else product
    elif mode == "auto" and not product.subassemblies:
        proposed = propose_subassemblies(product, max_components)
        product = replace(product, subassemblies=proposed) if proposed else product
    return with_level_supports(product)


def propose_subassemblies(product: Product, max_components: int = MAX_COMPONENTS) -> tuple[Subassembly, ...]:
    """A tree of workstation-sized subassemblies for ``product``, from its connection diagram.

    Definition: the parts are grouped into connected groups of at most ``max_components`` members by greedy
    agglomeration (Lance-Williams average linkage on the connection diagram: the two adjacent groups with the
    most contacts per pair of members merge first, while their union fits); each group of two or more becomes
    a subassembly, one member of the next round; rounds repeat until at most ``max_components`` members are
    left, which form the top level. A group is kept only if it can be built on its own (its level has a
    feasible AND/OR graph, :func:`~planner.assembly.and_or_graph`, or the support contacts the product's
    candidates would add there free it, :mod:`planner.assembly.level_supports`); a group that cannot is merged with the
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
        levels = product_levels(replace(product, subassemblies=tuple(found)))
        current = onto_level(product, levels[-1], levels)  # the candidates named by its members
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
    except ConstraintViolationError as error:
        return error
    except NotDisassemblableError as error:  # buildable all the same when support contacts free it
        return None if error.floating_parts and freeing_contacts(level.product, candidates_of(product)[1]) else error
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
