"""The product file format (JSON, ``docs/product-format.md``): reading a file into a :class:`Product` with
precise errors, and writing a product back.

Reading checks the document in three steps, each raising :class:`~planner.errors.ProductFormatError` that
names the file, the JSON path at fault and the fix: the structure against the JSON Schema
(:mod:`planner.product.schema`), the direction vectors while building the product, and the cross-references
when the :class:`Product` is constructed (:mod:`planner.product.validation`).
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

from ..errors import ProductFormatError
from ..files import write_atomic
from ..validation import InputError, json_loads, not_regular
from .constants import AXIS_DIRECTIONS, DEFAULT_MARKER_DICTIONARY, FORMAT, UNIT_TOLERANCE, VERSION
from .model import (
    Direction,
    FastenerGroup,
    Markers,
    Obstruction,
    OperationTag,
    Part,
    Product,
    Subassembly,
    TagDefaults,
    TechnicalConstraint,
    Tool,
)
from .schema import WITHOUT_JSONSCHEMA, check_document, schema_checks

__all__ = ["product_from_dict", "product_to_dict", "loads_product", "load_product", "save_product"]

# ---------------------------------------------------------------------------------------------- reading


def product_from_dict(data: Any, source: str = "<memory>") -> Product:
    """Build a :class:`Product` from the parsed JSON of a product file, checking every field.

    Raises :class:`~planner.errors.ProductFormatError` naming ``source`` and the JSON path at fault.
    """
    check_document(data, source)
    if schema_checks():
        return _product(data, source)
    try:  # without jsonschema the structure is checked only in outline: a wrong type shows up here
        return _product(data, source)
    except ProductFormatError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError, IndexError) as exc:
        raise ProductFormatError(source, "", f"malformed product file ({type(exc).__name__}: {exc}); "
                                 f"{WITHOUT_JSONSCHEMA}") from None


def _product(data: dict, source: str) -> Product:
    defaults = data.get("defaults", {})
    product = Product(
        parts=tuple(_part(item) for item in data["parts"]),
        contacts=tuple((a, b) for a, b in data["contacts"]),
        obstructions=tuple(_obstruction(item, f"obstructions[{i}]", source)
                           for i, item in enumerate(data.get("obstructions", []))),
        technical_constraints=tuple(_constraint(item) for item in data.get("technical_constraints", [])),
        tools=tuple(Tool(item["id"], item.get("label", "")) for item in data.get("tools", [])),
        operations=tuple(_operation(item) for item in data.get("operations", [])),
        defaults=TagDefaults(unfavorable=defaults.get("unfavorable", "single-part-rule"),
                             robot=defaults.get("robot", True), tool=defaults.get("tool")),
        markers=_markers(data["markers"]) if "markers" in data else None,
        subassemblies=tuple(Subassembly(item["id"], tuple(item["parts"]), item.get("label", ""),
                                        item.get("source", "designer")) for item in data.get("subassemblies", [])),
        fasteners=tuple(_fastener(item) for item in data.get("fasteners", [])),
        name=data.get("name", ""), units=data.get("units", "mm"),
        geometry=dict(data.get("geometry", {})),
        extensions={k: v for k, v in data.items() if k.startswith("x-")},
        source=source,
    )
    if "designer" in product.geometry:  # a file's marks name its parts (checked on construction: the rest)
        from .designer import designer_geometry

        designer_geometry(product)
    return product


def _number(value: Any) -> float | None:
    return None if value is None else float(value)


def _part(item: dict) -> Part:
    return Part(id=item["id"], label=item.get("label", ""), mesh=item.get("mesh"), brep=item.get("brep"),
                volume=_number(item.get("volume")), mass=_number(item.get("mass")), material=item.get("material"))


def _direction(value: str | list, location: str, source: str) -> Direction:
    """An axis name (``x``, ``+X``, ``-z``: the schema checked its form) or a vector that must be a unit one."""
    if isinstance(value, str):
        name = value.strip().upper()
        name = name if name.startswith(("+", "-")) else "+" + name
        return Direction(name, AXIS_DIRECTIONS[name])
    vector = tuple(float(c) for c in value)
    length = math.sqrt(sum(c * c for c in vector))
    if not math.isfinite(length) or abs(length - 1.0) > UNIT_TOLERANCE:
        raise ProductFormatError(source, location, f"not a unit vector (length {length:g}); divide it by its length")
    return Direction.from_vector(vector)  # type: ignore[arg-type]


def _obstruction(item: dict, location: str, source: str) -> Obstruction:
    direction = _direction(item["direction"], f"{location}.direction", source)
    return Obstruction(direction, tuple((x, y) for x, y in item["blocks"]))


def _constraint(item: dict) -> TechnicalConstraint:
    return TechnicalConstraint(parts=frozenset(item["parts"]), requires=item["requires"],
                               active=item.get("active", True), reason=item.get("reason", ""))


def _operation(item: dict) -> OperationTag:
    first, second = (frozenset(side) for side in item["inputs"])
    # The inputs in a fixed order, so that a tag compares equal however the file lists them.
    inputs = (first, second) if sorted(first) <= sorted(second) else (second, first)
    return OperationTag(inputs=inputs, unfavorable=item.get("unfavorable"), robot=item.get("robot"),
                        tool=item.get("tool"))


def _fastener(item: dict) -> FastenerGroup:
    return FastenerGroup(id=item["id"], parts=tuple(item["parts"]), hosts=frozenset(item.get("hosts", ())),
                         tool=item.get("tool"), source=item.get("source", "designer"), reason=item.get("reason", ""))


def _markers(item: dict) -> Markers:
    return Markers(tuple(item["ids"].items()), item.get("dictionary", DEFAULT_MARKER_DICTIONARY))


# ---------------------------------------------------------------------------------------------- writing


def product_to_dict(product: Product) -> dict:
    """The JSON document of ``product`` (inverse of :func:`product_from_dict`; optional fields left out)."""
    doc: dict[str, Any] = {"format": FORMAT, "version": VERSION}
    if product.name:
        doc["name"] = product.name
    doc["units"] = product.units
    doc["parts"] = [_part_dict(p) for p in product.parts]
    doc["contacts"] = [list(c) for c in product.contacts]
    doc["obstructions"] = [{"direction": _direction_json(o.direction), "blocks": [list(b) for b in o.blocks]}
                           for o in product.obstructions]
    if product.technical_constraints:
        doc["technical_constraints"] = [_constraint_dict(c) for c in product.technical_constraints]
    if product.tools:
        doc["tools"] = [{"id": t.id, **({"label": t.label} if t.label else {})} for t in product.tools]
    if product.operations:
        doc["operations"] = [_operation_dict(tag) for tag in product.operations]
    if product.defaults != TagDefaults():
        d = product.defaults
        doc["defaults"] = {"unfavorable": d.unfavorable, "robot": d.robot, **({"tool": d.tool} if d.tool else {})}
    if product.fasteners:
        doc["fasteners"] = [_fastener_dict(group) for group in product.fasteners]
    if product.markers is not None:
        doc["markers"] = {"dictionary": product.markers.dictionary, "ids": dict(product.markers.ids)}
    if product.subassemblies:
        doc["subassemblies"] = [{"id": g.id, "parts": list(g.parts), **({"label": g.label} if g.label else {}),
                                 "source": g.source} for g in product.subassemblies]
    if product.geometry:
        doc["geometry"] = dict(product.geometry)
    doc.update(product.extensions)
    return doc


def _part_dict(part: Part) -> dict:
    out: dict[str, Any] = {"id": part.id}
    if part.label:
        out["label"] = part.label
    for key in ("mesh", "brep", "volume", "mass", "material"):
        if getattr(part, key) is not None:
            out[key] = getattr(part, key)
    return out


def _direction_json(direction: Direction) -> str | list[float]:
    return direction.name if direction.name in AXIS_DIRECTIONS else list(direction.vector)


def _constraint_dict(constraint: TechnicalConstraint) -> dict:
    out = {"parts": sorted(constraint.parts), "requires": constraint.requires, "active": constraint.active}
    if constraint.reason:
        out["reason"] = constraint.reason
    return out


def _operation_dict(tag: OperationTag) -> dict:
    out: dict[str, Any] = {"inputs": [sorted(side) for side in tag.inputs]}
    out.update({k: getattr(tag, k) for k in ("unfavorable", "robot", "tool") if getattr(tag, k) is not None})
    return out


def _fastener_dict(group: FastenerGroup) -> dict:
    out: dict[str, Any] = {"id": group.id, "parts": list(group.parts)}
    if group.hosts:
        out["hosts"] = sorted(group.hosts)
    if group.tool is not None:
        out["tool"] = group.tool
    if group.source != "designer":
        out["source"] = group.source
    if group.reason:
        out["reason"] = group.reason
    return out


# ---------------------------------------------------------------------------------------------- files


def loads_product(text: str, source: str = "<memory>") -> Product:
    """Parse the text of a product file; a JSON syntax error names the line and column."""
    try:
        data = json_loads(text, source)
    except json.JSONDecodeError as exc:
        raise ProductFormatError(source, f"line {exc.lineno} column {exc.colno}",
                                 f"malformed JSON: {exc.msg}") from None
    except InputError as exc:  # too deep, a number that is not finite or far too long
        raise ProductFormatError(source, "", str(exc).removeprefix(f"{source}: ")) from None
    return product_from_dict(data, source)


def load_product(path: str | os.PathLike) -> Product:
    """Read and check a product file (``*.json``). Mesh paths stay as written, relative to the file."""
    path = Path(path)
    if not_regular(path, "product"):
        raise ProductFormatError(str(path), "", not_regular(path, "product").removeprefix(f"{path}: "))
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
