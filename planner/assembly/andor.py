"""AND/OR graph of a product by the reverse cut-set algorithm (Homem de Mello & Sanderson; Lambert & Gupta).

Definitions
-----------
A *subassembly* is a set of parts. It is *feasible* when

1. it is connected in the connection diagram (topological constraint);
2. it is technically feasible: no active constraint ``(R1, R2)`` with ``R1 <= S`` and ``R2 not in S``
   (single parts are always feasible);
3. it is a single part, or it can be split into two feasible subassemblies ``A`` and ``B = S - A`` that are
   *separable*: along some listed direction ``d`` or its reverse, one side moves away without any of its
   parts being blocked by a part of the other side (geometric constraint). An empty obstruction list
   means the geometry is not constrained.

The AND/OR graph ``H = (V, A)`` holds the feasible subassemblies reachable from the complete product by
feasible splits; each *operation* (AND hyperarc) is one unordered split ``S -> {A, B}``, listed once.

The reverse cut-set algorithm builds this bottom-up: all connected part sets are generated smallest first,
and a set is kept when one of its cuts into two connected halves joins two kept, separable subassemblies.
A final top-down pass keeps what the complete product can be disassembled into.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Iterable

from ..defaults import CUTS_PER_SUBASSEMBLY, SUBASSEMBLY_LIMIT
from ..errors import DisconnectedProductError, LimitExceededError, NotDisassemblableError
from ..product import Product
from .bitsets import bit_indices, components, connected_subsets, lowest_bit, mask_of
from .feasibility import interlock_error, interlocked_pairs
from .guards import OPTIONS, Progress, fewer_parts_hint

__all__ = ["Operation", "AndOrGraph", "and_or_graph", "liaison_adjacency", "connected_sets_bound"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Operation:
    """An AND hyperarc: subassembly ``parent`` (index) is assembled from ``children`` (two indices).

    ``children[0]`` is the child holding the parent's lowest-indexed part.
    """

    parent: int
    children: tuple[int, int]


@dataclass(frozen=True)
class AndOrGraph:
    """The AND/OR graph: ``subassemblies`` are part bitmasks (bit ``i`` = ``parts[i]``).

    Index 0 is the complete product; subassemblies are ordered by decreasing size, then by bitmask, so
    the single parts come last. ``operations`` are ordered by parent index.
    """

    parts: tuple[str, ...]
    subassemblies: tuple[int, ...]
    operations: tuple[Operation, ...]
    index: dict[int, int] = field(repr=False, compare=False)
    #: every connected part set is a subassembly and every cut of one into two connected halves an operation
    #: (no constraint removed any): then every partition of the parts into connected sets is an assembly
    #: state, and :func:`~planner.assembly.state_count.count_states` counts them before they are built.
    every_cut: bool = field(default=False, compare=False)

    def parts_of(self, subassembly: int) -> frozenset[str]:
        """The part ids of subassembly number ``subassembly``."""
        return frozenset(self.parts[i] for i in bit_indices(self.subassemblies[subassembly]))

    def inputs(self, operation: int) -> tuple[frozenset[str], frozenset[str]]:
        """The two part sets that operation number ``operation`` joins."""
        first, second = self.operations[operation].children
        return self.parts_of(first), self.parts_of(second)

    def names(self, subassembly: int) -> str:
        """``{a, b, c}``: the parts of a subassembly in product order."""
        return "{" + ", ".join(self.parts[i] for i in bit_indices(self.subassemblies[subassembly])) + "}"

    def describe(self, operation: int) -> str:
        """``{a, b} + {c}`` for an operation."""
        return " + ".join(self.names(child) for child in self.operations[operation].children)

    def to_networkx(self):
        """A ``networkx.DiGraph`` with subassembly nodes ``("S", i)`` and operation nodes ``("O", j)``.

        Edges go parent -> operation -> children (the disassembly direction of Fig. 1).
        """
        import networkx as nx

        graph = nx.DiGraph()
        for i in range(len(self.subassemblies)):
            graph.add_node(("S", i), parts=sorted(self.parts_of(i)))
        for j, op in enumerate(self.operations):
            graph.add_node(("O", j))
            graph.add_edge(("S", op.parent), ("O", j))
            for child in op.children:
                graph.add_edge(("O", j), ("S", child))
        return graph


def liaison_adjacency(product: Product) -> list[int]:
    """``adjacency[i]``: bitmask of the parts in contact with part ``i``."""
    index = {p: i for i, p in enumerate(product.part_ids)}
    adjacency = [0] * len(index)
    for a, b in product.contacts:
        adjacency[index[a]] |= 1 << index[b]
        adjacency[index[b]] |= 1 << index[a]
    return adjacency


def and_or_graph(product: Product, technical: bool | None = None, limit: int = SUBASSEMBLY_LIMIT) -> AndOrGraph:
    """Build the AND/OR graph of ``product`` by the reverse cut-set algorithm.

    Parameters
    ----------
    product : the product (parts, contacts, obstruction diagrams, technical constraints).
    technical : ``True`` applies every technical constraint, ``False`` none, ``None`` those marked active.
    limit : the most connected part sets to enumerate, and ``CUTS_PER_SUBASSEMBLY * limit`` the most cuts
        to examine; past either the build stops (its work is bounded by the limit, whatever the product).

    Returns
    -------
    AndOrGraph

    Raises
    ------
    DisconnectedProductError : the connection diagram is not connected (the groups are named).
    NotDisassemblableError : the complete product has no feasible split (the reasons are given);
        :class:`~planner.errors.InterlockedPartsError` when two parts block each other along every direction
        (:func:`~planner.assembly.feasibility.interlocked_pairs`: found before any enumeration).
    LimitExceededError : more connected part sets or cuts than the limit allows (the count reached, or a
        lower bound computed before any enumeration; the product's fastener-like parts and the options that
        help are given).

    Notes
    -----
    Cost: O(sum over connected part sets S of the connected subsets of S holding its lowest part), that is
    O(3^n) for a complete connection diagram of n parts and O(n^3) for a chain.
    """
    product = product.with_technical(technical)
    parts = product.part_ids
    n = len(parts)
    index = {p: i for i, p in enumerate(parts)}
    adjacency = liaison_adjacency(product)
    full = (1 << n) - 1
    groups = components(adjacency, full)
    if len(groups) > 1:
        raise DisconnectedProductError([[parts[i] for i in bit_indices(g)] for g in groups])

    interlocked = interlocked_pairs(product)  # a proof in O(n^2 D), before the exponential search
    if interlocked:
        raise interlock_error(product, interlocked)

    constraints = [(mask_of(index[p] for p in c.parts), 1 << index[c.requires])
                   for c in product.technical_constraints if c.active]
    separable = _separability_test(product, index)

    def technically_feasible(mask: int) -> bool:
        return all(mask & r1 != r1 or mask & r2 for r1, r2 in constraints)

    # Bottom-up: every connected set, smallest first; keep it when a cut joins two kept, separable halves.
    connected = sorted(_connected_sets(product, adjacency, limit), key=int.bit_count)
    splits: dict[int, list[tuple[int, int]]] = {1 << i: [] for i in range(n)}
    cuts_left = CUTS_PER_SUBASSEMBLY * limit  # a set's cuts are connected sets too: at most `limit` per set
    progress = Progress(log)
    every_cut = True  # no kept pair of halves was inseparable (with every set kept: no constraint acted)
    for done, subset in enumerate(connected):
        if done & 0xFFF == 0:
            progress.report("AND/OR graph: %s of %s connected part sets split, %s cuts examined", f"{done:,}",
                            f"{len(connected):,}", f"{CUTS_PER_SUBASSEMBLY * limit - cuts_left:,}")
        if subset & (subset - 1) == 0 or not technically_feasible(subset):
            continue
        root = lowest_bit(subset).bit_length() - 1
        found = []
        for first in connected_subsets(adjacency, subset, root):
            cuts_left -= 1
            second = subset ^ first
            if second and first in splits and second in splits:
                if separable(first, second):
                    found.append((first, second))
                else:
                    every_cut = False
        if cuts_left < 0:
            raise _too_many(product, "cuts (splits of a connected part set into two connected halves)",
                            CUTS_PER_SUBASSEMBLY * limit - cuts_left, CUTS_PER_SUBASSEMBLY * limit,
                            f" (over {len(connected):,} connected part sets)")
        if found:
            splits[subset] = found

    if full not in splits:
        raise _stuck(full, product, adjacency, splits, technically_feasible, separable)

    # Top-down: keep what the complete product can be disassembled into.
    subassemblies = tuple(sorted(_reachable(splits, full), key=lambda m: (-m.bit_count(), m)))
    position = {m: i for i, m in enumerate(subassemblies)}
    operations = tuple(Operation(position[s], (position[a], position[b]))
                       for s in subassemblies for a, b in sorted(splits[s]))
    every_cut = every_cut and len(splits) == len(connected)  # and every connected set was kept
    return AndOrGraph(parts, subassemblies, operations, position, every_cut)


def connected_sets_bound(adjacency: list[int]) -> int:
    """A lower bound on the connected part sets: ``sum over parts of 2^(its later neighbours)`` (a part with
    any set of its later neighbours is connected; such sets differ by their lowest part). Cost: O(n)."""
    return sum(1 << (adjacency[v] >> (v + 1)).bit_count() for v in range(len(adjacency)))


def _connected_sets(product: Product, adjacency: list[int], limit: int) -> list[int]:
    """Every connected part set, each once (by its lowest part); refused past ``limit`` of them.

    A part with any set of its later neighbours is connected, and such sets differ by their lowest part, so
    ``sum over parts of 2^(later neighbours)`` connected sets exist: past the limit, refused before any work.
    """
    bound = connected_sets_bound(adjacency)
    if bound > limit:
        hub = max(range(len(adjacency)), key=lambda v: adjacency[v].bit_count())
        raise _too_many(product, "connected part sets (candidate subassemblies)", bound, limit,
                        f" (a part with any set of its neighbours is one: {product.part_ids[hub]} alone has "
                        f"{adjacency[hub].bit_count()} neighbours)")
    full = (1 << len(adjacency)) - 1
    found = []
    progress = Progress(log)
    for r in range(len(adjacency)):
        for subset in connected_subsets(adjacency, full & ~((1 << r) - 1), r):
            if len(found) == limit:
                raise _too_many(product, "connected part sets (candidate subassemblies)", limit + 1, limit)
            found.append(subset)
            if len(found) & 0xFFFF == 0:
                progress.report("AND/OR graph: %s connected part sets so far (limit %s)", f"{len(found):,}",
                                f"{limit:,}")
    return found


def _too_many(product: Product, noun: str, count: int, limit: int, where: str = "") -> LimitExceededError:
    return LimitExceededError(
        "AND/OR graph", count, limit,
        f"The reverse cut-set algorithm enumerates every connected set of parts{where}, and each part that "
        f"joins two others can double them. {fewer_parts_hint(product)}",
        [OPTIONS[k] for k in ("subassemblies", "fasteners", "exclude", "group")], noun=noun, at_least=True)


def _reachable(splits: dict[int, list[tuple[int, int]]], full: int) -> set[int]:
    """The subassemblies that ``full`` splits into, recursively (depth-first over ``splits``)."""
    reachable = {full}
    stack = [full]
    while stack:
        for pair in splits[stack.pop()]:
            for child in pair:
                if child not in reachable:
                    reachable.add(child)
                    stack.append(child)
    return reachable


def _separability_test(product: Product, index: dict[str, int]):
    """``separable(a, b)``: along some direction or its reverse, one side leaves the other unblocked."""
    n = len(index)
    blockers = []  # per direction: blockers[d][x] = mask of the parts that x, moving along d, would hit
    for obstruction in product.obstructions:
        row = [0] * n
        for x, y in obstruction.blocks:
            row[index[x]] |= 1 << index[y]
        blockers.append(row)
    if not blockers:
        return lambda a, b: True
    cache: dict[int, tuple[int, ...]] = {}

    def hit(mask: int) -> tuple[int, ...]:
        # Per direction, the parts that some part of ``mask`` would hit moving along it.
        found = cache.get(mask)
        if found is None:
            members = bit_indices(mask)
            found = tuple(_union(row[i] for i in members) for row in blockers)
            cache[mask] = found
        return found

    def separable(a: int, b: int) -> bool:
        # a moves along d unless it hits b; b moves along d (a along -d) unless it hits a.
        return any(ha & b == 0 or hb & a == 0 for ha, hb in zip(hit(a), hit(b)))

    return separable


def _union(masks: Iterable[int]) -> int:
    out = 0
    for m in masks:
        out |= m
    return out


def _stuck(full, product, adjacency, splits, technically_feasible, separable) -> NotDisassemblableError:
    """Explain why the complete product has no feasible split, down to the smallest stuck subassembly."""
    parts = product.part_ids
    names = lambda m: "{" + ", ".join(parts[i] for i in bit_indices(m)) + "}"  # noqa: E731
    feasible_alone = lambda m: m & (m - 1) == 0 or technically_feasible(m)  # noqa: E731
    chain = [full]
    while True:
        subset = chain[-1]
        blocked, infeasible, unassemblable = [], [], []
        for first in connected_subsets(adjacency, subset, lowest_bit(subset).bit_length() - 1):
            second = subset ^ first
            if not second or len(components(adjacency, second)) != 1:
                continue
            if not (feasible_alone(first) and feasible_alone(second)):
                infeasible.append((first, second))
            elif first not in splits or second not in splits:
                unassemblable.append(next(m for m in (first, second) if m not in splits))
            elif not separable(first, second):
                blocked.append((first, second))
        if blocked or infeasible or not unassemblable:
            break
        chain.append(min(unassemblable, key=lambda m: (m.bit_count(), m)))
    reasons = []
    if blocked:
        a, b = min(blocked, key=lambda p: min(p[0].bit_count(), p[1].bit_count()))
        reasons.append(f"{len(blocked)} cut(s) blocked in every direction, e.g. {names(a)} from {names(b)}")
    if infeasible:
        a, b = infeasible[0]
        reasons.append(f"{len(infeasible)} cut(s) with a technically infeasible side, e.g. {names(a)} | {names(b)}")
    if unassemblable:
        m = min(unassemblable, key=int.bit_count)
        reasons.append(f"{len(unassemblable)} cut(s) with a side that cannot be assembled itself, e.g. {names(m)}")
    detail = "; ".join(reasons) or "no cut into two connected halves"
    if len(chain) > 1:
        detail += "; it is needed by " + " <- ".join(names(m) for m in reversed(chain[:-1]))
    smallest = _smallest_stuck(chain[-1], adjacency, splits, feasible_alone, separable)
    floating, floats = _floating(smallest, product, adjacency, separable)
    return NotDisassemblableError([parts[i] for i in bit_indices(chain[-1])], detail,
                                  [parts[i] for i in bit_indices(smallest)], floating, floats)


def _smallest_stuck(subset, adjacency, splits, feasible_alone, separable) -> int:
    """The smallest subassembly with no feasible split that the parts coming apart one by one reach from
    ``subset``: follow, while there is one, the smaller side of a separable cut into two connected, feasible
    halves that cannot be split itself. Cost: O(cuts of each set on the way)."""
    while True:
        needed = [m for first in connected_subsets(adjacency, subset, lowest_bit(subset).bit_length() - 1)
                  if (second := subset ^ first) and len(components(adjacency, second)) == 1
                  and feasible_alone(first) and feasible_alone(second) and separable(first, second)
                  for m in (first, second) if m not in splits]
        if not needed:
            return subset
        subset = min(needed, key=lambda m: (m.bit_count(), m))


def _floating(subset, product, adjacency, separable) -> tuple[str, tuple[str, ...]]:
    """The cuts of ``subset`` that the obstructions allow but the topological constraint refuses (the part
    set left behind is not connected), in words: which parts would be left touching none of the rest, inside
    which, and what helps; and the ids of those parts (:attr:`~planner.errors.NotDisassemblableError.
    floating_parts`). ``("", ())`` when there is none. The part set they rest in is the one with the largest
    known volume, then the most contacts in the product (a housing), then the first. Cost: O(connected
    subsets of ``subset`` x its parts)."""
    parts = product.part_ids
    found = []
    for root in bit_indices(subset):  # each connected part set once, by its lowest part
        for moving in connected_subsets(adjacency, subset & ~((1 << root) - 1), root):
            rest = subset ^ moving
            if not rest:
                continue
            groups = components(adjacency, rest)
            if len(groups) > 1 and separable(moving, rest):
                found.append((moving, groups))
    if not found:
        return "", ()
    moving, groups = min(found, key=lambda f: (f[0].bit_count(), f[0]))
    size = [(p.volume or 0.0, adjacency[i].bit_count(), -i) for i, p in enumerate(product.parts)]
    holds = lambda m: max(size[i] for i in bit_indices(m))  # noqa: E731
    holder = max(groups, key=holds)
    names = lambda m: ", ".join(parts[i] for i in bit_indices(m))  # noqa: E731
    floats = [g for g in groups if g != holder]
    touching = " and ".join(f"{names(g)} touching only each other" if g.bit_count() > 1 else
                            f"{names(g)} touching nothing" for g in floats)
    first = parts[bit_indices(floats[0])[0]]
    inside = parts[max(bit_indices(holder), key=size.__getitem__)]
    text = (f"taking {names(moving)} out would leave {touching} inside {names(holder)} (a subassembly must be "
            f"connected in the connection diagram). Add a support contact between each such part and the part "
            f"it rests on (e.g. {first} and {inside} in the product's contacts), or --group NAME={inside},{first} "
            "on the CAD model (it then stays in place)")
    return text, tuple(parts[i] for g in floats for i in bit_indices(g))
