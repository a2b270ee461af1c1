"""Exceptions raised by the planner.

Every error the planner raises on bad input derives from :class:`PlannerError`, and its message names the
object at fault, shows the offending values and says how to fix it, so the CLI can print it as is.
"""
from __future__ import annotations

from collections.abc import Sequence

__all__ = [
    "PlannerError",
    "ProductFormatError",
    "UnknownProductError",
    "DisconnectedProductError",
    "NotDisassemblableError",
    "InterlockedPartsError",
    "LimitExceededError",
    "MemoryLimitError",
    "FileLimitError",
    "gib",
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


class InterlockedPartsError(NotDisassemblableError):
    """Some parts block each other along every direction (:mod:`planner.assembly.feasibility`): found
    before any enumeration."""

    def __init__(self, stuck: list[str], detail: str):
        self.stuck = stuck
        PlannerError.__init__(self, f"the product cannot be disassembled: {detail}.")


class LimitExceededError(PlannerError):
    """Something would be larger than the caller allowed, so it was not built (nothing was written).

    ``count`` is the size found (a lower bound when ``at_least``: the work stopped at the limit), ``limit``
    the limit, ``hint`` what helps, in words. ``options`` are the command-line options that help, each as
    ``(option, advice)``, e.g. ``("--max-memory", "--max-memory GIB raises the budget")``: the command line
    names those its command has, and the commands that have the others, so the library need not know which
    command called it.
    """

    def __init__(self, what: str, count: int, limit: int, hint: str, options: Sequence[tuple[str, str]] = (),
                 noun: str = "", at_least: bool = False):
        self.what = what
        self.count = count
        self.limit = limit
        self.hint = hint
        self.options = tuple(options)
        size = f"{'at least ' if at_least else ''}{count:,}{' ' + noun if noun else ''}"
        super().__init__(self._message(size))

    def _message(self, size: str) -> str:
        return f"{self.what}: {size} would be enumerated, more than the limit of {self.limit:,}. {self.hint}"


class MemoryLimitError(LimitExceededError):
    """A graph or model would take more memory than the budget; ``count`` and ``limit`` are bytes, ``detail``
    says what the estimate counts (the sizes it comes from)."""

    def __init__(self, what: str, needed: int, budget: int, detail: str, hint: str,
                 options: Sequence[tuple[str, str]] = ()):
        self.detail = detail
        super().__init__(what, needed, budget, hint, options)

    def _message(self, size: str) -> str:
        return (f"{self.what} would need about {gib(self.count)} ({self.detail}), more than the memory budget "
                f"of {gib(self.limit)}. {self.hint}")


class FileLimitError(MemoryLimitError):
    """A file would be larger than allowed: more than the file budget, or than the free space of its disk
    (``budget_name`` says which); ``count`` and ``limit`` are bytes."""

    def __init__(self, what: str, needed: int, budget: int, detail: str, hint: str,
                 options: Sequence[tuple[str, str]] = (), budget_name: str = "the file size budget"):
        self.budget_name = budget_name
        super().__init__(what, needed, budget, detail, hint, options)

    def _message(self, size: str) -> str:
        return (f"{self.what} would take about {gib(self.count)} ({self.detail}), more than {self.budget_name} "
                f"of {gib(self.limit)}. {self.hint}")


def gib(size: int) -> str:
    """``1.5 GiB``, ``12.0 MiB``: a byte count for messages."""
    return f"{size / 2 ** 30:,.1f} GiB" if size >= 2 ** 30 else f"{size / 2 ** 20:,.1f} MiB"


class GeometryError(PlannerError):
    """A part's geometry cannot be analysed (a mesh that is not closed, no volume, an unreadable file), or a
    geometry engine was given bad tolerances."""
