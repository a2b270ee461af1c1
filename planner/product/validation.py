"""The checks of a product that its JSON Schema cannot express: ids that must name a part or a tool,
duplicates, self-loops, directions listed twice, marker ids within their dictionary. Every failure is a
:class:`~planner.errors.ProductFormatError` naming the JSON path at fault and, for a misspelt name, the
nearest known one.

:func:`check_product` runs whenever a :class:`~planner.product.model.Product` is constructed, so products
built in code are checked as files are; the structure of files is checked before, by
:mod:`planner.product.schema`.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Iterable

from ..errors import ProductFormatError
from .constants import DEFAULT_MARKER_DICTIONARY, MARKER_DICTIONARIES, UNFAVORABLE_DEFAULTS, UNITS
from .designer import designer_geometry
from .messages import suggest

if TYPE_CHECKING:
    from .model import Product

__all__ = ["check_product", "fastener_hosts"]


def check_product(product: "Product") -> None:
    """Raise :class:`~planner.errors.ProductFormatError` for the first problem of ``product``."""
    parts = _check_parts(product)
    _check_contacts(product, parts)
    _check_obstructions(product, parts)
    _check_constraints(product, parts)
    tools = _check_tools(product, parts)
    _check_operations(product, parts, tools)
    _check_defaults(product, tools)
    _check_fasteners(product, parts, tools)
    if product.markers is not None:
        _check_markers(product, set(parts) | set(tools))
    _check_subassemblies(product, parts, tools)
    if "designer" in product.geometry:  # the designer's directions and not-blocking marks
        designer_geometry(product, check_parts=False)  # a level or a folded product holds fewer parts


def _fail(product: "Product", location: str, problem: str) -> ProductFormatError:
    return ProductFormatError(product.source, location, problem)


def _known(product: "Product", parts: Iterable[str], name: Any, location: str) -> None:
    if name not in parts:
        raise _fail(product, location, f"{name!r} is not a part id{suggest(name, parts)}")


def _check_parts(product: "Product") -> dict[str, int]:
    """Part id -> its index, after checking ids, volumes, masses and units."""
    seen: dict[str, int] = {}
    for i, part in enumerate(product.parts):
        if not isinstance(part.id, str) or not part.id.strip():
            raise _fail(product, f"parts[{i}].id", "a part id must be a non-empty string")
        if part.id in seen:
            raise _fail(product, f"parts[{i}].id",
                        f"duplicate part id {part.id!r} (also parts[{seen[part.id]}]); give every part its own id")
        seen[part.id] = i
        for key in ("volume", "mass"):
            value = getattr(part, key)
            if value is not None and not (math.isfinite(value) and value >= 0):
                raise _fail(product, f"parts[{i}].{key}", f"must be a finite number >= 0, got {value!r}")
    if not product.parts:
        raise _fail(product, "parts", "a product needs at least one part")
    if product.units not in UNITS:
        raise _fail(product, "units", f"unknown unit {product.units!r}; use one of {', '.join(UNITS)}")
    return seen


def _check_contacts(product: "Product", parts: dict[str, int]) -> None:
    pairs: dict[frozenset[str], int] = {}
    for i, (a, b) in enumerate(product.contacts):
        _known(product, parts, a, f"contacts[{i}][0]")
        _known(product, parts, b, f"contacts[{i}][1]")
        if a == b:
            raise _fail(product, f"contacts[{i}]", f"self-loop: part {a!r} in contact with itself; remove it")
        key = frozenset((a, b))
        if key in pairs:
            raise _fail(product, f"contacts[{i}]", f"duplicate contact {a!r}-{b!r} (also contacts[{pairs[key]}])")
        pairs[key] = i


def _check_obstructions(product: "Product", parts: dict[str, int]) -> None:
    directions: dict[tuple[float, ...], int] = {}
    for i, obstruction in enumerate(product.obstructions):
        name = obstruction.direction.name
        # Rounded, so that vectors a few ulps apart count as the same direction; + 0.0 drops negative zeros.
        rounded = tuple(round(c, 9) + 0.0 for c in obstruction.direction.vector)
        opposite = tuple(-c + 0.0 for c in rounded)
        if rounded in directions:
            raise _fail(product, f"obstructions[{i}].direction",
                        f"direction {name} is listed twice (also obstructions[{directions[rounded]}])")
        if opposite in directions:
            raise _fail(product, f"obstructions[{i}].direction",
                        f"direction {name} is the reverse of obstructions[{directions[opposite]}]; "
                        "list one of them only: the relation along -d is the one along d reversed")
        directions[rounded] = i
        seen: set[tuple[str, str]] = set()
        for j, (x, y) in enumerate(obstruction.blocks):
            _known(product, parts, x, f"obstructions[{i}].blocks[{j}][0]")
            _known(product, parts, y, f"obstructions[{i}].blocks[{j}][1]")
            if x == y:
                raise _fail(product, f"obstructions[{i}].blocks[{j}]",
                            f"self-loop: part {x!r} cannot block itself; remove the pair")
            if (x, y) in seen:
                raise _fail(product, f"obstructions[{i}].blocks[{j}]", f"duplicate pair [{x!r}, {y!r}]")
            seen.add((x, y))


def _check_constraints(product: "Product", parts: dict[str, int]) -> None:
    for i, constraint in enumerate(product.technical_constraints):
        location = f"technical_constraints[{i}]"
        if not constraint.parts:
            raise _fail(product, f"{location}.parts", "list at least one part")
        for name in sorted(constraint.parts):
            _known(product, parts, name, f"{location}.parts")
        _known(product, parts, constraint.requires, f"{location}.requires")
        if constraint.requires in constraint.parts:
            raise _fail(product, f"{location}.requires",
                        f"{constraint.requires!r} is also in 'parts'; a part cannot require itself")


def _check_tools(product: "Product", parts: dict[str, int]) -> dict[str, int]:
    """Tool id -> its index, after checking that ids are unique and differ from the part ids."""
    tools: dict[str, int] = {}
    for i, tool in enumerate(product.tools):
        if not isinstance(tool.id, str) or not tool.id.strip():
            raise _fail(product, f"tools[{i}].id", "a tool id must be a non-empty string")
        if tool.id in tools:
            raise _fail(product, f"tools[{i}].id", f"duplicate tool id {tool.id!r} (also tools[{tools[tool.id]}])")
        if tool.id in parts:
            raise _fail(product, f"tools[{i}].id", f"tool id {tool.id!r} is also a part id; rename one of them")
        tools[tool.id] = i
    return tools


def _known_tool(product: "Product", tools: dict[str, int], name: Any, location: str) -> None:
    if name is not None and name not in tools:
        raise _fail(product, location, f"{name!r} is not a tool id{suggest(name, tools)}; declare it in 'tools'")


def _check_operations(product: "Product", parts: dict[str, int], tools: dict[str, int]) -> None:
    tagged: dict[frozenset[frozenset[str]], int] = {}
    for i, tag in enumerate(product.operations):
        first, second = tag.inputs
        for k, side in enumerate((first, second)):
            if not side:
                raise _fail(product, f"operations[{i}].inputs[{k}]", "an input needs at least one part")
            for name in sorted(side):
                _known(product, parts, name, f"operations[{i}].inputs[{k}]")
        common = first & second
        if common:
            raise _fail(product, f"operations[{i}].inputs",
                        f"the two inputs share {sorted(common)}; an operation joins two disjoint part sets")
        key = frozenset((first, second))
        if key in tagged:
            raise _fail(product, f"operations[{i}]", f"this operation is already tagged at operations[{tagged[key]}]")
        tagged[key] = i
        _known_tool(product, tools, tag.tool, f"operations[{i}].tool")


def _check_defaults(product: "Product", tools: dict[str, int]) -> None:
    if product.defaults.unfavorable not in UNFAVORABLE_DEFAULTS:
        raise _fail(product, "defaults.unfavorable",
                    f"unknown rule {product.defaults.unfavorable!r}; use one of {', '.join(UNFAVORABLE_DEFAULTS)}")
    _known_tool(product, tools, product.defaults.tool, "defaults.tool")


def _check_markers(product: "Product", items: set[str]) -> None:
    markers = product.markers
    size = MARKER_DICTIONARIES.get(markers.dictionary)
    if size is None:
        raise _fail(product, "markers.dictionary", f"unknown marker dictionary {markers.dictionary!r}"
                    f"{suggest(markers.dictionary, MARKER_DICTIONARIES)}; use one of OpenCV's, e.g. "
                    f"{DEFAULT_MARKER_DICTIONARY}")
    owner: dict[int, str] = {}
    named: set[str] = set()
    for name, marker in markers.ids:
        location = f"markers.ids.{name}"
        if name not in items:
            raise _fail(product, location, f"{name!r} is neither a part nor a tool id{suggest(name, items)}")
        if name in named:
            raise _fail(product, location, f"{name!r} has two markers; give it one")
        named.add(name)
        if isinstance(marker, bool) or not isinstance(marker, int) or not 0 <= marker < size:
            raise _fail(product, location, f"marker id must be an integer from 0 to {size - 1} "
                        f"({markers.dictionary} holds {size} markers), got {marker!r}")
        if marker in owner:
            raise _fail(product, location, f"marker {marker} is used twice: by {owner[marker]!r} and by {name!r}; "
                        "give every part and tool its own marker")
        owner[marker] = name


def _check_subassemblies(product: "Product", parts: dict[str, int], tools: dict[str, int]) -> None:
    """A forest: ids new (not a part, tool or other subassembly), members known, each member in at most one
    subassembly, no subassembly inside itself, at least two members each."""
    ids: dict[str, int] = {}
    for i, group in enumerate(product.subassemblies):
        location = f"subassemblies[{i}].id"
        if not isinstance(group.id, str) or not group.id.strip():
            raise _fail(product, location, "a subassembly id must be a non-empty string")
        if group.id in ids:
            raise _fail(product, location,
                        f"duplicate subassembly id {group.id!r} (also subassemblies[{ids[group.id]}])")
        if group.id in parts or group.id in tools:
            raise _fail(product, location, f"subassembly id {group.id!r} is also a part or tool id; rename it")
        if group.id == "top":
            raise _fail(product, location, "'top' names the top level (what no subassembly holds); rename it")
        ids[group.id] = i
    owner: dict[str, str] = {}
    for i, group in enumerate(product.subassemblies):
        if len(group.parts) < 2:
            raise _fail(product, f"subassemblies[{i}].parts",
                        f"subassembly {group.id!r} has {len(group.parts)} member(s); a subassembly needs two or more")
        for j, member in enumerate(group.parts):
            location = f"subassemblies[{i}].parts[{j}]"
            if member not in parts and member not in ids:
                raise _fail(product, location, f"{member!r} is neither a part nor a subassembly id"
                                               f"{suggest(member, list(parts) + list(ids))}")
            if member in owner:
                raise _fail(product, location, f"{member!r} is in two subassemblies: {owner[member]!r} and "
                                               f"{group.id!r}; a part or subassembly belongs to one at most")
            owner[member] = group.id
    for i, group in enumerate(product.subassemblies):
        seen, current = [group.id], owner.get(group.id)
        while current is not None and current not in seen[1:]:  # a cycle above this one is found from its members
            if current == group.id:
                raise _fail(product, f"subassemblies[{i}]", "the subassemblies contain each other in a cycle: "
                                                            + " in ".join(seen + [group.id]) + "; break the cycle")
            seen.append(current)
            current = owner.get(current)


def fastener_hosts(product: "Product") -> tuple[frozenset[str], ...]:
    """The hosts of each fastener group of ``product``: those the group lists, or else the parts its fasteners
    touch that are in no fastener group (a fastener touching another group's fastener joins it to nothing).
    Cost: O(contacts + fastener parts)."""
    fastener_parts = product.fastener_parts
    touching: dict[str, set[str]] = {}
    for a, b in product.contacts:
        if b not in fastener_parts:
            touching.setdefault(a, set()).add(b)
        if a not in fastener_parts:
            touching.setdefault(b, set()).add(a)
    return tuple(group.hosts or frozenset(h for p in group.parts for h in touching.get(p, ()))
                 for group in product.fasteners)


def _check_fasteners(product: "Product", parts: dict[str, int], tools: dict[str, int]) -> None:
    """Fastener parts name parts, each in one group; hosts are parts and no fasteners; a group joins at least
    two parts; its tool is declared."""
    owner: dict[str, str] = {}
    ids: set[str] = set()
    for i, group in enumerate(product.fasteners):
        location = f"fasteners[{i}]"
        if not isinstance(group.id, str) or not group.id.strip():
            raise _fail(product, f"{location}.id", "a fastener group id must be a non-empty string")
        if group.id in ids:
            raise _fail(product, f"{location}.id", f"duplicate fastener group id {group.id!r}")
        ids.add(group.id)
        if not group.parts:
            raise _fail(product, f"{location}.parts", f"fastener group {group.id!r} lists no part")
        for name in group.parts:
            _known(product, parts, name, f"{location}.parts")
            if name in owner:
                raise _fail(product, f"{location}.parts", f"{name!r} is in fastener groups {owner[name]!r} and "
                            f"{group.id!r}; a fastener belongs to one group only")
            owner[name] = group.id
        _known_tool(product, tools, group.tool, f"{location}.tool")
    for i, group in enumerate(product.fasteners):
        for name in sorted(group.hosts):
            _known(product, parts, name, f"fasteners[{i}].hosts")
            if name in owner:
                raise _fail(product, f"fasteners[{i}].hosts", f"host {name!r} is a fastener (group {owner[name]!r}); "
                            "hosts are the parts the fasteners join")
    for i, (group, hosts) in enumerate(zip(product.fasteners, fastener_hosts(product))):
        if len(hosts) < 2:
            joined = f"only {sorted(hosts)[0]!r}" if hosts else "nothing"
            raise _fail(product, f"fasteners[{i}]", f"fastener group {group.id!r} ({', '.join(group.parts)}) joins "
                        f"{joined}: a fastener that joins nothing or only one part; list the parts it joins in "
                        "'hosts', or add its missing contacts, or leave it out of the fasteners")
