"""Exceptions raised by the planner.

Every error the planner raises on bad input derives from :class:`PlannerError`, and its message names the
object at fault, shows the offending values and says how to fix it, so the CLI can print it as is.
"""
from __future__ import annotations

__all__ = [
    "PlannerError",
    "ProductFormatError",
    "UnknownProductError",
    "DisconnectedProductError",
    "NotDisassemblableError",
    "LimitExceededError",
    "GeometryError",
]


class PlannerError(Exception):
    """Base class of every error the planner raises on bad input or impossible requests."""


class ProductFormatError(PlannerError):
    """A product file is malformed: bad JSON, unknown version, wrong type, or a name that refers to nothing.

    ``source`` is the file (or ``<memory>``), ``location`` a JSON path such as ``parts[3].id``.
    """

    def __init__(self, source: str, location: str, problem: str):
        self.source = source
        self.location = location
        self.problem = problem
        where = f"{source}: {location}" if location else source
        super().__init__(f"{where}: {problem}")


class UnknownProductError(PlannerError):
    """A PRODUCT argument is neither an existing file nor the name of an embedded example."""


class DisconnectedProductError(PlannerError):
    """The connection diagram (liaison graph) of a product falls apart into separate groups."""

    def __init__(self, groups: list[list[str]]):
        self.groups = groups
        shown = " | ".join("{" + ", ".join(g) + "}" for g in groups)
        super().__init__(
            f"the connection diagram is not connected: it falls apart into {len(groups)} groups: {shown}. "
            "Add the missing contacts between the groups, or exclude the parts that do not belong to the product."
        )


class NotDisassemblableError(PlannerError):
    """Some subassembly that the product needs cannot be split under the constraints (it is stuck)."""

    def __init__(self, stuck: list[str], detail: str):
        self.stuck = stuck
        super().__init__(
            "the product cannot be disassembled: subassembly {" + ", ".join(stuck) + "} has no feasible split "
            f"({detail}). Check the obstruction relations and technical constraints of these parts."
        )


class LimitExceededError(PlannerError):
    """An enumeration would produce more items than the caller allowed."""

    def __init__(self, what: str, count: int, limit: int, hint: str):
        self.count = count
        self.limit = limit
        super().__init__(f"{what}: {count:,} would be enumerated, more than the limit of {limit:,}. {hint}")


class GeometryError(PlannerError):
    """A part's geometry cannot be analysed (a mesh that is not closed, no volume, an unreadable file), or a
    geometry engine was given bad tolerances."""
