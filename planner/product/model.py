"""The product model (the designer intent the planner needs), as immutable dataclasses.

A *product* holds:

- parts (components) with optional mesh path, volume, mass and material;
- contacts: the connection diagram (liaison graph), an undirected graph over the parts;
- obstruction relations per motion direction: ``(x, y)`` along ``d`` means part ``x``, moved along ``d``
  without limit, collides with part ``y``; the relation along ``-d`` is the one along ``d`` reversed and is
  never listed separately;
- technical constraints ``(R1, R2)``: a subassembly ``S`` of two or more parts is infeasible when
  ``R1 <= S`` and ``R2 not in S`` (a constraint can be kept in the file but switched off: ``active``);
- designer tags on operations: unfavorable to humans, robot-capable, the tool the operation needs, plus
  product-wide defaults for operations that carry no tag;
- subassemblies: a tree of named groups of parts (and of other subassemblies), each built at a workstation
  of its own and then handled as one part (:mod:`planner.assembly.hierarchy`).
- fastener groups: parts (screws, nuts, washers, ...) that are installed by the operation that joins their
  hosts, with the tool they need, rather than planned as parts (:mod:`planner.product.fasteners`).

Constructing a :class:`Product` checks it (:mod:`planner.product.validation`). Its JSON file format is in
:mod:`planner.product.io` and ``docs/product-format.md``.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Mapping

from .constants import DEFAULT_MARKER_DICTIONARY
from .directions import Direction, Obstruction
from .validation import check_product

__all__ = ["Part", "Direction", "Obstruction", "TechnicalConstraint", "Tool", "OperationTag", "TagDefaults",
           "Markers", "Subassembly", "FastenerGroup", "Product"]


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
    covers in ``dictionary`` (one of :data:`~planner.product.constants.MARKER_DICTIONARIES`). A marker id
    names one item only."""

    ids: tuple[tuple[str, int], ...]
    dictionary: str = DEFAULT_MARKER_DICTIONARY

    def by_id(self) -> dict[int, str]:
        """Marker id -> part or tool id."""
        return {marker: name for name, marker in self.ids}

    def of(self, name: str) -> int | None:
        """The marker id of part or tool ``name`` (None when it has none)."""
        return next((marker for item, marker in self.ids if item == name), None)


@dataclass(frozen=True)
class Subassembly:
    """A subassembly the designer (``source="designer"``) or the planner (``"proposed"``) names: ``parts``
    holds part ids and ids of other subassemblies, its direct members. It is built on its own, then joins the
    level above as one part. The subassemblies of a product form a forest: each part or subassembly is a
    member of at most one, and none contains itself."""

    id: str
    parts: tuple[str, ...]
    label: str = ""
    source: str = "designer"


@dataclass(frozen=True)
class FastenerGroup:
    """Fasteners installed together (say the four screws of one wheel): ``parts`` are part ids of the product,
    ``hosts`` the parts they join (empty: the parts the fasteners touch that are not fasteners themselves),
    ``tool`` the tool the installing operation needs. ``source``: ``designer`` (from the file or the
    workbench's tags) or ``proposed`` (by :func:`planner.product.fastener_proposals.propose_fasteners`, which
    says why in ``reason``)."""

    id: str
    parts: tuple[str, ...]
    hosts: frozenset[str] = frozenset()
    tool: str | None = None
    source: str = "designer"
    reason: str = ""


@dataclass(frozen=True)
class Product:
    """A product: parts, connection diagram, obstruction diagrams, technical constraints and designer tags.

    Constructing a ``Product`` checks it (unique ids, names that refer to parts, no self-loops, ...) and
    raises :class:`~planner.errors.ProductFormatError` with the JSON path at fault.
    """

    parts: tuple[Part, ...]
    contacts: tuple[tuple[str, str], ...]
    obstructions: tuple[Obstruction, ...] = ()
    technical_constraints: tuple[TechnicalConstraint, ...] = ()
    tools: tuple[Tool, ...] = ()
    operations: tuple[OperationTag, ...] = ()
    defaults: TagDefaults = TagDefaults()
    markers: Markers | None = None
    subassemblies: tuple[Subassembly, ...] = ()
    fasteners: tuple[FastenerGroup, ...] = ()
    name: str = ""
    units: str = "mm"
    geometry: Mapping[str, Any] = field(default_factory=dict, compare=False)
    extensions: Mapping[str, Any] = field(default_factory=dict, compare=False)
    source: str = field(default="<memory>", compare=False)

    def __post_init__(self) -> None:
        check_product(self)

    @property
    def part_ids(self) -> tuple[str, ...]:
        return tuple(p.id for p in self.parts)

    @property
    def fastener_parts(self) -> frozenset[str]:
        """The parts listed in a fastener group."""
        return frozenset(p for group in self.fasteners for p in group.parts)

    def with_technical(self, technical: bool | None) -> "Product":
        """A copy with every technical constraint switched on (True) or off (False); None keeps the file's."""
        if technical is None:
            return self
        constraints = tuple(replace(c, active=technical) for c in self.technical_constraints)
        return replace(self, technical_constraints=constraints)
