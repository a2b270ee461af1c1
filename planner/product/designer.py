"""The designer's additions to the detected geometry: motion directions to test besides the axes, and
relations marked "not blocking".

Definitions
-----------
- A *designer direction* is a unit vector the geometry engines test like the six axes (a part that leaves
  along a line no face or axis of the model proposes). It stands for itself and its reverse.
- A *not-blocking mark* ``(blocked, blocking, direction)`` says that part ``blocked``, moved along
  ``direction``, does not hit part ``blocking``, whatever a detection finds (a modelling overlap, a flexible
  part, a clip that gives way). Marks are applied after every detection (:func:`release_marked`), so they
  survive re-detection; the pairs they removed are recorded under ``geometry.analysis.designer``.

Both live in the product file under ``geometry.designer`` (``docs/product-format.md``)::

    "designer": {"directions": [[0, -0.5, 0.866025]],
                 "not_blocking": [{"blocked": "peg", "blocking": "block", "direction": "+Z",
                                   "source": "designer"}]}

A mark's direction is an axis (``+X`` ... ``-Z``) or one of the designer directions (or its reverse):
marking a relation along a direction an engine proposed adds that direction to the designer's, so it is
tested again at every detection. Plain data, no geometry: cost O(marks x directions) everywhere.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Iterable, Sequence

from ..errors import GeometryError, ProductFormatError
from .constants import AXIS_DIRECTIONS
from .directions import Direction, Obstruction

if TYPE_CHECKING:
    from .model import Product

__all__ = ["MERGE_DEGREES", "NotBlocking", "DesignerGeometry", "parse_direction", "unit_vector", "designer_geometry",
           "add_directions", "mark_not_blocking", "unmark_not_blocking", "release_marked", "designer_lines"]

MERGE_DEGREES = 2.0   # two directions closer than this are one (the mesh engine merges its candidates alike)
_COS_MERGE = math.cos(math.radians(MERGE_DEGREES))
_KEY = "designer"


@dataclass(frozen=True)
class NotBlocking:
    """Part ``blocked``, moved along ``direction``, does not hit part ``blocking`` (the designer says so)."""

    blocked: str
    blocking: str
    direction: "Direction"
    source: str = "designer"

    def describe(self) -> str:
        return f"{self.blocked} not blocked by {self.blocking} along {self.direction.name}"


@dataclass(frozen=True)
class DesignerGeometry:
    """The designer's directions (unit, pairwise more than :data:`MERGE_DEGREES` apart and from the axes) and
    not-blocking marks of a product."""

    directions: tuple["Direction", ...] = ()
    not_blocking: tuple[NotBlocking, ...] = ()


def unit_vector(values: Sequence[Any], where: str = "direction") -> tuple[float, float, float]:
    """``values`` (three numbers) divided by its length; :class:`~planner.errors.GeometryError` naming ``where``
    when it is not three finite numbers or has no length."""
    try:
        vector = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise GeometryError(f"{where}: expected three numbers X,Y,Z, got {values!r}") from None
    if len(vector) != 3:
        raise GeometryError(f"{where}: expected three numbers X,Y,Z, got {len(vector)}: {values!r}")
    if not all(math.isfinite(c) for c in vector):
        raise GeometryError(f"{where}: the components must be finite numbers, got {values!r}")
    # Scaled by the largest component first: the squares of 1e308 overflow to infinity (every component then
    # divided to 0), those of 1e-200 underflow to 0; the scaled vector's length is from 1 to sqrt(3).
    largest = max(abs(c) for c in vector)
    if largest == 0:
        raise GeometryError(f"{where}: a zero vector {values!r} has no direction; give X,Y,Z with a length")
    scaled = tuple(c / largest for c in vector)
    length = math.sqrt(sum(c * c for c in scaled))
    return tuple(c / length + 0.0 for c in scaled)  # type: ignore[return-value]


def parse_direction(text: str, where: str = "direction") -> tuple[float, float, float]:
    """A unit vector from ``X,Y,Z`` (any length: normalised) or an axis name (``+X``, ``-y``, ``z``)."""
    name = text.strip().upper()
    if name.lstrip("+-") in ("X", "Y", "Z") and len(name) <= 2:
        return AXIS_DIRECTIONS[name if name[0] in "+-" else "+" + name]
    try:
        values = [float(c) for c in text.replace(";", ",").split(",") if c.strip()]
    except ValueError:
        raise GeometryError(f"{where}: expected three numbers X,Y,Z or an axis (+X ... -Z), got {text!r}") from None
    try:
        return unit_vector(values, where)
    except GeometryError as exc:  # the message names the text as typed
        raise GeometryError(str(exc).replace(repr(values), repr(text))) from None


def _direction(vector: Sequence[float]) -> "Direction":
    return Direction.from_vector(tuple(round(c, 9) + 0.0 for c in vector))  # type: ignore[arg-type]


def _same_line(u: Sequence[float], v: Sequence[float]) -> float:
    """+1 when ``u`` and ``v`` are one direction (within the merge angle), -1 when reverse, 0 otherwise."""
    dot = sum(a * b for a, b in zip(u, v))
    return 1.0 if dot >= _COS_MERGE else -1.0 if dot <= -_COS_MERGE else 0.0


def _raw(product: "Product") -> dict:
    value = product.geometry.get(_KEY, {})
    if not isinstance(value, dict):
        raise ProductFormatError(product.source, f"geometry.{_KEY}", "expected an object with 'directions' and "
                                 "'not_blocking'")
    return value


def designer_geometry(product: "Product", check_parts: bool = True) -> DesignerGeometry:
    """The designer's directions and marks of ``product`` (``geometry.designer``), checked: each direction three
    finite numbers with a length (normalised here), none along an axis or another; each mark names two
    different parts (of ``product``: with ``check_parts``; a level or a folded product holds fewer) and an axis
    or designer direction. Raises :class:`~planner.errors.ProductFormatError` with
    the JSON path at fault. Cost: O(directions^2 + marks x directions)."""
    raw = _raw(product)
    directions: list[Direction] = []
    for i, values in enumerate(raw.get("directions", [])):
        where = f"geometry.{_KEY}.directions[{i}]"
        try:
            vector = unit_vector(values, where)
        except GeometryError as exc:
            raise ProductFormatError(product.source, where, str(exc).split(": ", 1)[-1]) from None
        clash = _nearest(vector, directions)
        if clash is not None:
            raise ProductFormatError(product.source, where, f"direction {_direction(vector).name} is {clash} "
                                     "already (within 2 degrees); list it once")
        directions.append(_direction(vector))
    parts = set(product.part_ids)
    marks = []
    for i, item in enumerate(raw.get("not_blocking", [])):
        where = f"geometry.{_KEY}.not_blocking[{i}]"
        if not isinstance(item, dict) or not {"blocked", "blocking", "direction"} <= set(item):
            raise ProductFormatError(product.source, where, "expected {\"blocked\": part, \"blocking\": part, "
                                     "\"direction\": \"+X\" or [x, y, z]}")
        for key in ("blocked", "blocking"):
            if check_parts and item[key] not in parts:
                from .messages import suggest

                raise ProductFormatError(product.source, f"{where}.{key}", f"{item[key]!r} is not a part id"
                                         f"{suggest(item[key], parts)}")
        if item["blocked"] == item["blocking"]:
            raise ProductFormatError(product.source, where, f"part {item['blocked']!r} cannot block itself")
        direction = _known_direction(item["direction"], directions)
        if direction is None:
            raise ProductFormatError(product.source, f"{where}.direction", f"unknown direction {item['direction']!r}: "
                                     "use an axis (+X ... -Z) or one of the designer directions (add it first)")
        marks.append(NotBlocking(item["blocked"], item["blocking"], direction, item.get("source", "designer")))
    return DesignerGeometry(tuple(directions), tuple(marks))


def _nearest(vector: Sequence[float], directions: Iterable["Direction"]) -> str | None:
    """How ``vector`` duplicates an axis or one of ``directions`` (``"the axis +X"``), or None."""
    for name in ("+X", "+Y", "+Z"):
        if _same_line(vector, AXIS_DIRECTIONS[name]):
            return f"the axis {name}"
    for direction in directions:
        if _same_line(vector, direction.vector):
            return f"the designer direction {direction.name}"
    return None


def _known_direction(value: Any, directions: Sequence["Direction"]) -> "Direction | None":
    """The axis or designer direction (or its reverse) that ``value`` (a name or a vector) names, or None."""
    try:
        vector = parse_direction(value) if isinstance(value, str) else unit_vector(value)
    except (GeometryError, KeyError):
        return None
    for name, axis in AXIS_DIRECTIONS.items():
        if _same_line(vector, axis) > 0:
            return _direction(axis)
    for direction in directions:
        along = _same_line(vector, direction.vector)
        if along:
            return direction if along > 0 else direction.reverse
    return None


def _with_raw(product: "Product", raw: dict) -> "Product":
    raw = {k: v for k, v in raw.items() if v}
    geometry = {k: v for k, v in product.geometry.items() if k != _KEY}
    return replace(product, geometry={**geometry, **({_KEY: raw} if raw else {})})


def _direction_json(direction: "Direction") -> str | list[float]:
    return direction.name if direction.name in AXIS_DIRECTIONS else list(direction.vector)


def add_directions(product: "Product", vectors: Iterable[Sequence[float] | str]) -> tuple["Product", list[str]]:
    """``product`` with the designer directions ``vectors`` added (three numbers, or ``X,Y,Z`` text: checked and
    normalised), and notes for those merged: along an axis, or within 2 degrees of a direction already there
    (the reverse counts as the same). Raises :class:`~planner.errors.GeometryError` for a bad vector."""
    current = designer_geometry(product)
    directions = list(current.directions)
    notes = []
    for value in vectors:
        vector = parse_direction(value) if isinstance(value, str) else unit_vector(value)
        clash = _nearest(vector, directions)
        if clash is not None:
            notes.append(f"direction {_direction(vector).name} merged with {clash} (within {MERGE_DEGREES:g} "
                         "degrees; a direction stands for its reverse too)")
            continue
        directions.append(_direction(vector))
    raw = {**_raw(product), "directions": [list(d.vector) for d in directions]}
    return _with_raw(product, raw), notes


def _mark_json(mark: NotBlocking) -> dict:
    return {"blocked": mark.blocked, "blocking": mark.blocking, "direction": _direction_json(mark.direction),
            "source": mark.source}


def _same_mark(a: NotBlocking, b: NotBlocking) -> bool:
    """The same relation: (x, y) along d, or (y, x) along -d."""
    along = _same_line(a.direction.vector, b.direction.vector)
    return (along > 0 and (a.blocked, a.blocking) == (b.blocked, b.blocking)) or \
        (along < 0 and (a.blocked, a.blocking) == (b.blocking, b.blocked))


def _marks(product: "Product", marks: Iterable[tuple[str, str, Any]]) -> tuple["Product", list[NotBlocking],
                                                                                 list[str]]:
    """``marks`` as :class:`NotBlocking` over ``product``, whose designer directions gain the directions they
    name that are neither an axis nor a designer direction yet (with notes)."""
    notes: list[str] = []
    found = []
    for blocked, blocking, direction in marks:
        vector = parse_direction(direction) if isinstance(direction, str) else unit_vector(direction)
        known = _known_direction(vector, designer_geometry(product).directions)
        if known is None:
            product, _ = add_directions(product, [vector])
            known = _known_direction(vector, designer_geometry(product).directions)
            notes.append(f"direction {known.name} added to the designer directions (so that every detection tests "
                         "it)")
        found.append(NotBlocking(blocked, blocking, known))
    return product, found, notes


def mark_not_blocking(product: "Product", marks: Iterable[tuple[str, str, Any]]) -> tuple["Product", list[str]]:
    """``product`` with the designer marks ``marks`` (``(blocked, blocking, direction)``: a direction name,
    ``X,Y,Z`` text or a vector) added and applied at once (:func:`release_marked`), and notes (a mark already
    there, a direction added). Raises :class:`~planner.errors.ProductFormatError` naming the mark when it names
    an unknown part, or :class:`~planner.errors.GeometryError` for a bad direction."""
    product, new, notes = _marks(product, marks)
    current = list(designer_geometry(product).not_blocking)
    for mark in new:
        if any(_same_mark(mark, old) for old in current):
            notes.append(f"{mark.describe()}: marked already")
            continue
        current.append(mark)
    raw = {**_raw(product), "not_blocking": [_mark_json(m) for m in current]}
    return release_marked(_with_raw(product, raw)), notes


def unmark_not_blocking(product: "Product", marks: Iterable[tuple[str, str, Any]]) -> "Product":
    """``product`` without the designer marks ``marks`` (as :func:`mark_not_blocking` takes them), the obstruction
    pairs they released (``geometry.analysis.designer.released``) put back: what a detection finds again.
    Raises :class:`~planner.errors.GeometryError` for a mark that is not there."""
    current = list(designer_geometry(product).not_blocking)
    directions = designer_geometry(product).directions
    gone = []
    for blocked, blocking, direction in marks:
        value = parse_direction(direction) if isinstance(direction, str) else unit_vector(direction)
        known = _known_direction(value, directions)
        target = NotBlocking(blocked, blocking, known) if known is not None else None
        index = next((k for k, m in enumerate(current) if target is not None and _same_mark(target, m)), None)
        if index is None:
            raise GeometryError(f"{blocked} not blocked by {blocking} along {direction}: no such designer mark")
        gone.append(current.pop(index))
    unmarked = _with_raw(product, {**_raw(product), "not_blocking": [_mark_json(m) for m in current]})
    analysis = dict(product.geometry.get("analysis", {}))
    record = dict(analysis.get(_KEY, {}))
    released = [list(r) for r in record.get("released", [])]
    back = [r for r in released if any(_releases(m, r) for m in gone)]
    if not back:
        return unmarked
    obstructions = tuple(Obstruction(o.direction, o.blocks + tuple(
        (x, y) for x, y, name in back if name == o.direction.name and (x, y) not in o.blocks))
        for o in unmarked.obstructions)
    record["released"] = [r for r in released if r not in back]
    geometry = {**unmarked.geometry, "analysis": {**analysis, _KEY: record}}
    return replace(unmarked, obstructions=obstructions, geometry=geometry)


def release_marked(product: "Product") -> "Product":
    """``product`` with every pair its designer marks name taken out of its obstruction diagrams (a mark along
    ``-d`` takes the reversed pair out of the diagram along ``d``), and ``geometry.analysis.designer`` recording
    the designer directions, the pairs released (``[blocked, blocking, direction]``, as the diagrams list them)
    and the marks that matched no detected pair (``unmatched``). Idempotent. Cost: O(marks x directions +
    pairs)."""
    designer = designer_geometry(product)
    if not designer.directions and not designer.not_blocking:
        return product
    analysis = dict(product.geometry.get("analysis", {}))
    record = dict(analysis.get(_KEY, {}))
    released = [tuple(r) for r in record.get("released", [])]
    remove: dict[int, set[tuple[str, str]]] = {}
    unmatched = []
    for mark in designer.not_blocking:
        hit = False
        for k, obstruction in enumerate(product.obstructions):
            along = _same_line(mark.direction.vector, obstruction.direction.vector)
            pair = (mark.blocked, mark.blocking) if along > 0 else (mark.blocking, mark.blocked)
            if along and pair in obstruction.blocks:
                remove.setdefault(k, set()).add(pair)
                entry = (*pair, obstruction.direction.name)
                if entry not in released:
                    released.append(entry)
                hit = True
        if not hit and not any(_releases(mark, entry) for entry in released):
            unmatched.append([mark.blocked, mark.blocking, mark.direction.name])
    obstructions = tuple(Obstruction(o.direction, tuple(p for p in o.blocks if p not in remove.get(k, ())))
                         if k in remove else o for k, o in enumerate(product.obstructions))
    record = {"directions": [d.name for d in designer.directions], "released": [list(r) for r in released],
              **({"unmatched": unmatched} if unmatched else {})}
    if "analysis" not in product.geometry:  # not analysed yet: nothing detected, nothing to record
        return replace(product, obstructions=obstructions)
    geometry = {**product.geometry, "analysis": {**analysis, _KEY: record}}
    return replace(product, obstructions=obstructions, geometry=geometry)


def _releases(mark: NotBlocking, entry: tuple) -> bool:
    """True when the released pair ``entry`` (blocked, blocking, direction name) is the relation of ``mark``."""
    along = _same_line(mark.direction.vector, _vec(entry[2]))
    pair = (mark.blocked, mark.blocking) if along > 0 else (mark.blocking, mark.blocked)
    return bool(along) and pair == tuple(entry[:2])


def _vec(name: str) -> tuple[float, ...]:
    if name in AXIS_DIRECTIONS:
        return AXIS_DIRECTIONS[name]
    return tuple(float(c) for c in name.strip("[]").split(","))


def designer_lines(product: "Product") -> list[str]:
    """What the designer added, in words, for ``aplan stats`` and ``aplan analyze``: the directions and the marks,
    with the pairs each released (from ``geometry.analysis.designer``)."""
    designer = designer_geometry(product, check_parts=False)
    lines = []
    if designer.directions:
        lines.append("designer directions (tested like the axes): "
                     + ", ".join(d.name for d in designer.directions))
    record = product.geometry.get("analysis", {}).get(_KEY, {})
    released = record.get("released", [])
    unmatched = {tuple(u) for u in record.get("unmatched", [])}
    for mark in designer.not_blocking:
        state = ("matched no detected obstruction" if (mark.blocked, mark.blocking, mark.direction.name) in unmatched
                 else "released")
        lines.append(f"designer mark: {mark.describe()} ({state})")
    if released:
        lines.append(f"obstruction pairs released by designer marks: {len(released)}")
    return lines
