"""The product model and its JSON file format (the contract between the FreeCAD side and the planner).

A *product* is the designer intent the planner needs:

- parts (components) with optional mesh path, volume, mass and material;
- contacts: the connection diagram (liaison graph), an undirected graph over the parts;
- obstruction relations per motion direction: ``(x, y)`` along ``d`` means part ``x``, moved along ``d``
  without limit, collides with part ``y``; the relation along ``-d`` is the one along ``d`` reversed and is
  never listed separately;
- technical constraints ``(R1, R2)``: a subassembly ``S`` of two or more parts is infeasible when
  ``R1 <= S`` and ``R2 not in S`` (a constraint can be kept in the file but switched off: ``active``);
- designer tags on operations: unfavorable to humans, robot-capable, the tool the operation needs, plus
  product-wide defaults for operations that carry no tag.

The file format is documented in ``docs/product-format.md`` and described by ``product.schema.json``
(JSON Schema) beside this module. :func:`load_product` checks a file and raises
:class:`~planner.errors.ProductFormatError` naming the file, the JSON path and the fix.
"""
from __future__ import annotations

import difflib
import json
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Mapping

from ..defaults import PRODUCT_FORMAT, PRODUCT_VERSION
from ..errors import ProductFormatError
from ..files import write_atomic

__all__ = [
    "FORMAT",
    "VERSION",
    "UNITS",
    "AXIS_DIRECTIONS",
    "Part",
    "Direction",
    "Obstruction",
    "TechnicalConstraint",
    "Tool",
    "OperationTag",
    "TagDefaults",
    "Markers",
    "MARKER_DICTIONARIES",
    "DEFAULT_MARKER_DICTIONARY",
    "Product",
    "product_from_dict",
    "product_to_dict",
    "load_product",
    "save_product",
    "loads_product",
    "write_atomic",
]

FORMAT = PRODUCT_FORMAT
VERSION = PRODUCT_VERSION
UNITS = ("mm", "cm", "m", "in")
AXIS_DIRECTIONS: dict[str, tuple[float, float, float]] = {
    "+X": (1.0, 0.0, 0.0), "-X": (-1.0, 0.0, 0.0),
    "+Y": (0.0, 1.0, 0.0), "-Y": (0.0, -1.0, 0.0),
    "+Z": (0.0, 0.0, 1.0), "-Z": (0.0, 0.0, -1.0),
}
UNFAVORABLE_DEFAULTS = ("single-part-rule", "none", "all")
#: OpenCV's predefined ArUco/AprilTag dictionaries and how many marker ids each holds.
MARKER_DICTIONARIES: dict[str, int] = {
    **{f"DICT_{n}X{n}_{size}": size for n in (4, 5, 6, 7) for size in (50, 100, 250, 1000)},
    "DICT_ARUCO_ORIGINAL": 1024, "DICT_APRILTAG_16h5": 30, "DICT_APRILTAG_25h9": 35,
    "DICT_APRILTAG_36h10": 2320, "DICT_APRILTAG_36h11": 587, "DICT_ARUCO_MIP_36h12": 250,
}
DEFAULT_MARKER_DICTIONARY = "DICT_4X4_50"
_UNIT_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Part:
    """A component of the product. ``mesh`` and ``brep`` are paths relative to the product file (a closed
    triangle mesh, and the exact OCCT shape); ``volume`` is in cubic ``units``, ``mass`` in kg."""

    id: str
    label: str = ""
    mesh: str | None = None
    brep: str | None = None
    volume: float | None = None
    mass: float | None = None
    material: str | None = None


@dataclass(frozen=True)
class Direction:
    """A unit motion direction; ``name`` is ``+X`` ... ``-Z`` for the axes, else the vector written out."""

    name: str
    vector: tuple[float, float, float]

    @property
    def reverse(self) -> "Direction":
        vector = (-self.vector[0] + 0.0, -self.vector[1] + 0.0, -self.vector[2] + 0.0)
        return _direction_from_vector(vector)


@dataclass(frozen=True)
class Obstruction:
    """The obstruction diagram along one direction: ``blocks`` holds pairs ``(x, y)``: x moving hits y."""

    direction: Direction
    blocks: tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class TechnicalConstraint:
    """``parts`` (R1) may only be together in a subassembly that also holds ``requires`` (R2)."""

    parts: frozenset[str]
    requires: str
    active: bool = True
    reason: str = ""


@dataclass(frozen=True)
class Tool:
    """A tool the operator picks up to perform an operation (it carries a marker in the cell)."""

    id: str
    label: str = ""


@dataclass(frozen=True)
class OperationTag:
    """Designer tags of the operation that joins the two part sets of ``inputs``.

    ``None`` means "not tagged": the product's :class:`TagDefaults` apply.
    """

    inputs: tuple[frozenset[str], frozenset[str]]
    unfavorable: bool | None = None
    robot: bool | None = None
    tool: str | None = None


@dataclass(frozen=True)
class TagDefaults:
    """Tags of operations the designer did not tag.

    ``unfavorable``: ``"single-part-rule"`` (the authors' rule: unfavorable to humans when exactly one of the
    two inputs is a single part), ``"none"`` or ``"all"``. ``robot``: whether the robot can perform them.
    ``tool``: the tool they need (``None``: no tool).
    """

    unfavorable: str = "single-part-rule"
    robot: bool = True
    tool: str | None = None


@dataclass(frozen=True)
class Markers:
    """The fiducial markers of the parts tray: ``ids`` pairs each part or tool with the id of the marker it
    covers in ``dictionary`` (one of :data:`MARKER_DICTIONARIES`). A marker id names one item only."""

    ids: tuple[tuple[str, int], ...]
    dictionary: str = DEFAULT_MARKER_DICTIONARY

    def by_id(self) -> dict[int, str]:
        """Marker id -> part or tool id."""
        return {marker: name for name, marker in self.ids}

    def of(self, name: str) -> int | None:
        """The marker id of part or tool ``name`` (None when it has none)."""
        return next((marker for item, marker in self.ids if item == name), None)


@dataclass(frozen=True)
class Product:
    """A product: parts, connection diagram, obstruction diagrams, technical constraints and designer tags.

    Constructing a ``Product`` checks it (unique ids, names that refer to parts, no self-loops, unit
    directions, ...) and raises :class:`~planner.errors.ProductFormatError` with the JSON path at fault.
    """

    parts: tuple[Part, ...]
    contacts: tuple[tuple[str, str], ...]
    obstructions: tuple[Obstruction, ...] = ()
    technical_constraints: tuple[TechnicalConstraint, ...] = ()
    tools: tuple[Tool, ...] = ()
    operations: tuple[OperationTag, ...] = ()
    defaults: TagDefaults = TagDefaults()
    markers: Markers | None = None
    name: str = ""
    units: str = "mm"
    geometry: Mapping[str, Any] = field(default_factory=dict, compare=False)
    extensions: Mapping[str, Any] = field(default_factory=dict, compare=False)
    source: str = field(default="<memory>", compare=False)

    def __post_init__(self) -> None:
        _check_product(self)

    @property
    def part_ids(self) -> tuple[str, ...]:
        return tuple(p.id for p in self.parts)

    def with_technical(self, technical: bool | None) -> "Product":
        """A copy with every technical constraint switched on (True) or off (False); None keeps the file's."""
        if technical is None:
            return self
        constraints = tuple(replace(c, active=technical) for c in self.technical_constraints)
        return replace(self, technical_constraints=constraints)


# ---------------------------------------------------------------------------------------------- checks


def _fail(product_or_source: Any, location: str, problem: str) -> ProductFormatError:
    source = product_or_source if isinstance(product_or_source, str) else product_or_source.source
    return ProductFormatError(source, location, problem)


def _check_product(product: Product) -> None:
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

    def known(name: Any, location: str) -> None:
        if name not in seen:
            raise _fail(product, location, f"{name!r} is not a part id{_suggest(name, seen)}")

    pairs: dict[frozenset[str], int] = {}
    for i, (a, b) in enumerate(product.contacts):
        known(a, f"contacts[{i}][0]")
        known(b, f"contacts[{i}][1]")
        if a == b:
            raise _fail(product, f"contacts[{i}]", f"self-loop: part {a!r} in contact with itself; remove it")
        key = frozenset((a, b))
        if key in pairs:
            raise _fail(product, f"contacts[{i}]", f"duplicate contact {a!r}-{b!r} (also contacts[{pairs[key]}])")
        pairs[key] = i

    directions: dict[tuple[float, float, float], int] = {}
    for i, obstruction in enumerate(product.obstructions):
        vector = obstruction.direction.vector
        rounded = tuple(round(c, 9) + 0.0 for c in vector)
        opposite = tuple(-c + 0.0 for c in rounded)
        if rounded in directions:
            raise _fail(product, f"obstructions[{i}].direction",
                        f"direction {obstruction.direction.name} is listed twice (also obstructions[{directions[rounded]}])")
        if opposite in directions:
            raise _fail(product, f"obstructions[{i}].direction",
                        f"direction {obstruction.direction.name} is the reverse of obstructions[{directions[opposite]}]; "
                        "list one of them only: the relation along -d is the one along d reversed")
        directions[rounded] = i
        seen_blocks: set[tuple[str, str]] = set()
        for j, (x, y) in enumerate(obstruction.blocks):
            known(x, f"obstructions[{i}].blocks[{j}][0]")
            known(y, f"obstructions[{i}].blocks[{j}][1]")
            if x == y:
                raise _fail(product, f"obstructions[{i}].blocks[{j}]",
                            f"self-loop: part {x!r} cannot block itself; remove the pair")
            if (x, y) in seen_blocks:
                raise _fail(product, f"obstructions[{i}].blocks[{j}]", f"duplicate pair [{x!r}, {y!r}]")
            seen_blocks.add((x, y))

    for i, constraint in enumerate(product.technical_constraints):
        if not constraint.parts:
            raise _fail(product, f"technical_constraints[{i}].parts", "list at least one part")
        for name in sorted(constraint.parts):
            known(name, f"technical_constraints[{i}].parts")
        known(constraint.requires, f"technical_constraints[{i}].requires")
        if constraint.requires in constraint.parts:
            raise _fail(product, f"technical_constraints[{i}].requires",
                        f"{constraint.requires!r} is also in 'parts'; a part cannot require itself")

    tool_ids: dict[str, int] = {}
    for i, tool in enumerate(product.tools):
        if not isinstance(tool.id, str) or not tool.id.strip():
            raise _fail(product, f"tools[{i}].id", "a tool id must be a non-empty string")
        if tool.id in tool_ids:
            raise _fail(product, f"tools[{i}].id", f"duplicate tool id {tool.id!r} (also tools[{tool_ids[tool.id]}])")
        if tool.id in seen:
            raise _fail(product, f"tools[{i}].id", f"tool id {tool.id!r} is also a part id; rename one of them")
        tool_ids[tool.id] = i

    def known_tool(name: Any, location: str) -> None:
        if name is not None and name not in tool_ids:
            raise _fail(product, location, f"{name!r} is not a tool id{_suggest(name, tool_ids)}; declare it in 'tools'")

    tagged: dict[frozenset[frozenset[str]], int] = {}
    for i, tag in enumerate(product.operations):
        first, second = tag.inputs
        for k, side in enumerate((first, second)):
            if not side:
                raise _fail(product, f"operations[{i}].inputs[{k}]", "an input needs at least one part")
            for name in sorted(side):
                known(name, f"operations[{i}].inputs[{k}]")
        common = first & second
        if common:
            raise _fail(product, f"operations[{i}].inputs",
                        f"the two inputs share {sorted(common)}; an operation joins two disjoint part sets")
        key = frozenset((first, second))
        if key in tagged:
            raise _fail(product, f"operations[{i}]", f"this operation is already tagged at operations[{tagged[key]}]")
        tagged[key] = i
        known_tool(tag.tool, f"operations[{i}].tool")

    if product.defaults.unfavorable not in UNFAVORABLE_DEFAULTS:
        raise _fail(product, "defaults.unfavorable",
                    f"unknown rule {product.defaults.unfavorable!r}; use one of {', '.join(UNFAVORABLE_DEFAULTS)}")
    known_tool(product.defaults.tool, "defaults.tool")
    if product.markers is not None:
        _check_markers(product, set(seen) | set(tool_ids))


def _check_markers(product: Product, items: set[str]) -> None:
    markers = product.markers
    size = MARKER_DICTIONARIES.get(markers.dictionary)
    if size is None:
        raise _fail(product, "markers.dictionary", f"unknown marker dictionary {markers.dictionary!r}"
                    f"{_suggest(markers.dictionary, MARKER_DICTIONARIES)}; use one of OpenCV's, e.g. "
                    f"{DEFAULT_MARKER_DICTIONARY}")
    owner: dict[int, str] = {}
    named: set[str] = set()
    for name, marker in markers.ids:
        location = f"markers.ids.{name}"
        if name not in items:
            raise _fail(product, location, f"{name!r} is neither a part nor a tool id{_suggest(name, items)}")
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


def _suggest(name: Any, choices: Iterable[str]) -> str:
    if not isinstance(name, str):
        return ""
    close = difflib.get_close_matches(name, list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


# ---------------------------------------------------------------------------------------------- parsing


class _Reader:
    """Typed access to a JSON document that reports the JSON path of every problem."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, location: str, problem: str) -> ProductFormatError:
        return ProductFormatError(self.source, location, problem)

    def obj(self, value: Any, location: str, required: tuple[str, ...], optional: tuple[str, ...]) -> dict:
        if not isinstance(value, dict):
            raise self.fail(location, f"expected an object, got {_kind(value)}")
        for key in value:
            if key not in required and key not in optional and not key.startswith("x-"):
                allowed = required + optional
                raise self.fail(_join(location, key),
                                f"unknown key{_suggest(key, allowed)}; allowed keys: {', '.join(allowed)} "
                                "(keys starting with 'x-' are kept as extensions)")
        for key in required:
            if key not in value:
                raise self.fail(location or "top level", f"missing required key {key!r}")
        return value

    def array(self, value: Any, location: str) -> list:
        if not isinstance(value, list):
            raise self.fail(location, f"expected an array, got {_kind(value)}")
        return value

    def string(self, value: Any, location: str, optional: bool = False) -> str | None:
        if value is None and optional:
            return None
        if not isinstance(value, str):
            raise self.fail(location, f"expected a string, got {_kind(value)}")
        return value

    def boolean(self, value: Any, location: str, optional: bool = False) -> bool | None:
        if value is None and optional:
            return None
        if not isinstance(value, bool):
            raise self.fail(location, f"expected true or false, got {_kind(value)}")
        return value

    def number(self, value: Any, location: str, optional: bool = False) -> float | None:
        if value is None and optional:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(location, f"expected a number, got {_kind(value)}")
        return float(value)

    def names(self, value: Any, location: str) -> list[str]:
        return [self.string(v, f"{location}[{i}]") for i, v in enumerate(self.array(value, location))]

    def pair(self, value: Any, location: str) -> tuple[str, str]:
        items = self.names(value, location)
        if len(items) != 2:
            raise self.fail(location, f"expected a pair of two part ids, got {len(items)} items")
        return items[0], items[1]


def _kind(value: Any) -> str:
    names = {dict: "an object", list: "an array", str: "a string", bool: "a boolean", type(None): "null"}
    if isinstance(value, bool):
        return f"the boolean {json.dumps(value)}"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    if isinstance(value, str):
        return f"the string {value!r}"
    return names.get(type(value), type(value).__name__)


def _join(location: str, key: str) -> str:
    return f"{location}.{key}" if location else key


def _direction_from_vector(vector: tuple[float, float, float]) -> Direction:
    for name, axis in AXIS_DIRECTIONS.items():
        if all(abs(a - b) <= _UNIT_TOLERANCE for a, b in zip(axis, vector)):
            return Direction(name, axis)
    return Direction("[" + ", ".join(f"{c:g}" for c in vector) + "]", vector)


def _parse_direction(reader: _Reader, value: Any, location: str) -> Direction:
    if isinstance(value, str):
        name = value.strip().upper()
        if not name.startswith(("+", "-")):
            name = "+" + name
        if name not in AXIS_DIRECTIONS:
            raise reader.fail(location, f"unknown direction {value!r}; use +X, -X, +Y, -Y, +Z, -Z or a unit vector [x, y, z]")
        return Direction(name, AXIS_DIRECTIONS[name])
    items = reader.array(value, location)
    if len(items) != 3:
        raise reader.fail(location, f"a direction vector needs 3 components, got {len(items)}")
    vector = tuple(reader.number(c, f"{location}[{i}]") for i, c in enumerate(items))
    length = math.sqrt(sum(c * c for c in vector))
    if not math.isfinite(length) or abs(length - 1.0) > _UNIT_TOLERANCE:
        raise reader.fail(location, f"not a unit vector (length {length:g}); divide it by its length")
    return _direction_from_vector(vector)  # type: ignore[arg-type]


def product_from_dict(data: Any, source: str = "<memory>") -> Product:
    """Build a :class:`Product` from the parsed JSON of a product file, checking every field.

    Raises :class:`~planner.errors.ProductFormatError` naming ``source`` and the JSON path at fault.
    """
    r = _Reader(source)
    top = r.obj(data, "", ("format", "version", "parts", "contacts"),
                ("name", "units", "obstructions", "technical_constraints", "tools", "operations", "defaults",
                 "markers", "geometry"))
    if top["format"] != FORMAT:
        raise r.fail("format", f"expected {FORMAT!r}, got {_kind(top['format'])}; this is not an APLAN product file")
    version = top["version"]
    if isinstance(version, bool) or not isinstance(version, int):
        raise r.fail("version", f"expected an integer, got {_kind(version)}")
    if version != VERSION:
        newer = " written by a newer APLAN; upgrade aplan" if version > VERSION else ""
        raise r.fail("version", f"unknown format version {version}{newer} (this planner reads version {VERSION})")

    parts = []
    for i, item in enumerate(r.array(top["parts"], "parts")):
        loc = f"parts[{i}]"
        r.obj(item, loc, ("id",), ("label", "mesh", "brep", "volume", "mass", "material"))
        parts.append(Part(
            id=r.string(item["id"], f"{loc}.id"),
            label=r.string(item.get("label", ""), f"{loc}.label"),
            mesh=r.string(item.get("mesh"), f"{loc}.mesh", optional=True),
            brep=r.string(item.get("brep"), f"{loc}.brep", optional=True),
            volume=r.number(item.get("volume"), f"{loc}.volume", optional=True),
            mass=r.number(item.get("mass"), f"{loc}.mass", optional=True),
            material=r.string(item.get("material"), f"{loc}.material", optional=True),
        ))

    contacts = tuple(r.pair(c, f"contacts[{i}]") for i, c in enumerate(r.array(top["contacts"], "contacts")))

    obstructions = []
    for i, item in enumerate(r.array(top.get("obstructions", []), "obstructions")):
        loc = f"obstructions[{i}]"
        r.obj(item, loc, ("direction", "blocks"), ())
        direction = _parse_direction(r, item["direction"], f"{loc}.direction")
        blocks = tuple(r.pair(b, f"{loc}.blocks[{j}]") for j, b in enumerate(r.array(item["blocks"], f"{loc}.blocks")))
        obstructions.append(Obstruction(direction, blocks))

    constraints = []
    for i, item in enumerate(r.array(top.get("technical_constraints", []), "technical_constraints")):
        loc = f"technical_constraints[{i}]"
        r.obj(item, loc, ("parts", "requires"), ("active", "reason"))
        names = r.names(item["parts"], f"{loc}.parts")
        if len(set(names)) != len(names):
            raise r.fail(f"{loc}.parts", f"a part is listed twice in {names}")
        constraints.append(TechnicalConstraint(
            parts=frozenset(names),
            requires=r.string(item["requires"], f"{loc}.requires"),
            active=r.boolean(item.get("active", True), f"{loc}.active"),
            reason=r.string(item.get("reason", ""), f"{loc}.reason"),
        ))

    tools = []
    for i, item in enumerate(r.array(top.get("tools", []), "tools")):
        loc = f"tools[{i}]"
        r.obj(item, loc, ("id",), ("label",))
        tools.append(Tool(r.string(item["id"], f"{loc}.id"), r.string(item.get("label", ""), f"{loc}.label")))

    operations = []
    for i, item in enumerate(r.array(top.get("operations", []), "operations")):
        loc = f"operations[{i}]"
        r.obj(item, loc, ("inputs",), ("unfavorable", "robot", "tool"))
        sides = r.array(item["inputs"], f"{loc}.inputs")
        if len(sides) != 2:
            raise r.fail(f"{loc}.inputs", f"an operation joins exactly two inputs (part lists), got {len(sides)}")
        first, second = (frozenset(r.names(s, f"{loc}.inputs[{k}]")) for k, s in enumerate(sides))
        operations.append(OperationTag(
            inputs=_ordered_inputs(first, second),
            unfavorable=r.boolean(item.get("unfavorable"), f"{loc}.unfavorable", optional=True),
            robot=r.boolean(item.get("robot"), f"{loc}.robot", optional=True),
            tool=r.string(item.get("tool"), f"{loc}.tool", optional=True),
        ))

    raw_defaults = r.obj(top.get("defaults", {}), "defaults", (), ("unfavorable", "robot", "tool"))
    defaults = TagDefaults(
        unfavorable=r.string(raw_defaults.get("unfavorable", "single-part-rule"), "defaults.unfavorable"),
        robot=r.boolean(raw_defaults.get("robot", True), "defaults.robot"),
        tool=r.string(raw_defaults.get("tool"), "defaults.tool", optional=True),
    )
    markers = None
    if "markers" in top:
        raw = r.obj(top["markers"], "markers", ("ids",), ("dictionary",))
        ids = r.obj(raw["ids"], "markers.ids", (), tuple(raw["ids"]) if isinstance(raw["ids"], dict) else ())
        for name, marker in ids.items():
            if isinstance(marker, bool) or not isinstance(marker, int):
                raise r.fail(f"markers.ids.{name}", f"expected an integer marker id, got {_kind(marker)}")
        markers = Markers(tuple(ids.items()),
                          r.string(raw.get("dictionary", DEFAULT_MARKER_DICTIONARY), "markers.dictionary"))
    geometry = r.obj(top.get("geometry", {}), "geometry", (), ("source", "tessellation", "analysis", "warnings"))
    extensions = {k: v for k, v in top.items() if k.startswith("x-")}
    return Product(
        parts=tuple(parts), contacts=contacts, obstructions=tuple(obstructions),
        technical_constraints=tuple(constraints), tools=tuple(tools), operations=tuple(operations),
        defaults=defaults, markers=markers, name=r.string(top.get("name", ""), "name"),
        units=r.string(top.get("units", "mm"), "units"),
        geometry=geometry, extensions=extensions, source=source,
    )


def _ordered_inputs(first: frozenset[str], second: frozenset[str]) -> tuple[frozenset[str], frozenset[str]]:
    return (first, second) if sorted(first) <= sorted(second) else (second, first)


def product_to_dict(product: Product) -> dict:
    """The JSON document of ``product`` (inverse of :func:`product_from_dict`; optional fields left out)."""

    def part(p: Part) -> dict:
        out: dict[str, Any] = {"id": p.id}
        if p.label:
            out["label"] = p.label
        for key in ("mesh", "brep", "volume", "mass", "material"):
            if getattr(p, key) is not None:
                out[key] = getattr(p, key)
        return out

    def direction(d: Direction) -> Any:
        return d.name if d.name in AXIS_DIRECTIONS else list(d.vector)

    doc: dict[str, Any] = {"format": FORMAT, "version": VERSION}
    if product.name:
        doc["name"] = product.name
    doc["units"] = product.units
    doc["parts"] = [part(p) for p in product.parts]
    doc["contacts"] = [list(c) for c in product.contacts]
    doc["obstructions"] = [{"direction": direction(o.direction), "blocks": [list(b) for b in o.blocks]}
                           for o in product.obstructions]
    if product.technical_constraints:
        doc["technical_constraints"] = [
            {"parts": sorted(c.parts), "requires": c.requires, "active": c.active, **({"reason": c.reason} if c.reason else {})}
            for c in product.technical_constraints]
    if product.tools:
        doc["tools"] = [{"id": t.id, **({"label": t.label} if t.label else {})} for t in product.tools]
    if product.operations:
        doc["operations"] = [
            {"inputs": [sorted(s) for s in tag.inputs],
             **{k: getattr(tag, k) for k in ("unfavorable", "robot", "tool") if getattr(tag, k) is not None}}
            for tag in product.operations]
    if product.defaults != TagDefaults():
        d = product.defaults
        doc["defaults"] = {"unfavorable": d.unfavorable, "robot": d.robot, **({"tool": d.tool} if d.tool else {})}
    if product.markers is not None:
        doc["markers"] = {"dictionary": product.markers.dictionary, "ids": dict(product.markers.ids)}
    if product.geometry:
        doc["geometry"] = dict(product.geometry)
    doc.update(product.extensions)
    return doc


# ---------------------------------------------------------------------------------------------- files


def loads_product(text: str, source: str = "<memory>") -> Product:
    """Parse the text of a product file; a JSON syntax error names the line and column."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ProductFormatError(source, f"line {exc.lineno} column {exc.colno}",
                                 f"malformed JSON: {exc.msg}") from None
    return product_from_dict(data, source)


def load_product(path: str | os.PathLike) -> Product:
    """Read and check a product file (``*.json``). Mesh paths stay as written, relative to the file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ProductFormatError(str(path), "", "no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ProductFormatError(str(path), "", f"cannot read the file: {exc}") from None
    return loads_product(text, str(path))


def save_product(product: Product, path: str | os.PathLike) -> None:
    """Write ``product`` as a version-1 product file (atomically)."""
    write_atomic(path, json.dumps(product_to_dict(product), indent=2) + "\n")
