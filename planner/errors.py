"""Exceptions raised by the planner.

Every error the planner raises on bad input derives from :class:`PlannerError`, and its message names the
object at fault, shows the offending values and says how to fix it, so the CLI can print it as is.
"""
from __future__ import annotations

import re

from collections.abc import Sequence

__all__ = [
    "PlannerError",
    "UsageError",
    "ProductFormatError",
    "UnknownProductError",
    "DisconnectedProductError",
    "NotDisassemblableError",
    "InterlockedPartsError",
    "InterlockRefusedError",
    "SupportRefusedError",
    "LimitExceededError",
    "SolveTimeError",
    "MemoryLimitError",
    "FileLimitError",
    "gib",
    "GeometryError",
    "ContactCeilingError",
]


class PlannerError(Exception):
    """Base class of every error the planner raises on bad input or impossible requests.

    ``str(error)`` is the whole message; :attr:`summary` its one-line form (the command line prints it, and the
    whole message with ``--verbose``). An error whose message is long sets ``self.brief``."""

    brief: str = ""

    @property
    def summary(self) -> str:
        """One line saying what is wrong, where, and the fix; the whole message when no shorter one was set."""
        return self.brief or str(self)


class UsageError(PlannerError):
    """Options that do not go together, or a value out of its range that argparse cannot see alone (one
    option's range set by another): exit status 2, as argparse's usage errors. The message names the options."""


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


class SolveTimeError(PlannerError):
    """The solver's time limit passed before it had a policy worth keeping (no better than the blind policies
    it starts from) or before it could start; nothing is written, and the message says what helps."""


class UnknownProductError(PlannerError):
    """A PRODUCT argument is neither an existing file nor the name of an embedded example."""


class DisconnectedProductError(PlannerError):
    """The connection diagram (liaison graph) of a product falls apart into separate groups.

    ``gaps`` (when the part meshes were measured), one per group in the order of ``groups``: the group's
    nearest gap as ``(its part, the other group's part, distance, contact tolerance that joins them)``, or
    None; ``tolerance``: the contact tolerance that joins every group; ``units``: the model's length unit.
    """

    def __init__(self, groups: list[list[str]], gaps: Sequence[tuple[str, str, float, float] | None] | None = None,
                 tolerance: float | None = None, units: str = "", source: str = ""):
        self.groups = groups
        self.gaps = list(gaps) if gaps is not None else None
        self.tolerance = tolerance
        self.units = units
        self.source = source  # the product file, named first when known
        shown = " | ".join("{" + ", ".join(g) + "}" for g in groups)
        message = (f"{source}: " if source else "") + \
            f"the connection diagram is not connected: it falls apart into {len(groups)} groups: {shown}."
        if self.gaps:
            unit = f" {units}" if units else ""
            lines = []
            for k, (group, gap) in enumerate(zip(groups, self.gaps), 1):
                name = "{" + ", ".join(group) + "}" if len(group) <= 3 else \
                    "{" + ", ".join(group[:3]) + f", ... ({len(group)} parts)" + "}"
                if gap is None:
                    lines.append(f"group {k} {name}: no gap measured")
                    continue
                part, other, distance, joins = gap
                lines.append(f"group {k} {name}: {distance:.4g}{unit} between {part} and {other} "
                             f"(--contact {joins:g} joins them)")
            message += "\nThe nearest gaps between the groups (part meshes):\n  " + "\n  ".join(lines) + "\n"
            if tolerance is not None:
                message += (f"--contact {tolerance:g} joins every group (--contact auto chooses the smallest "
                            "tolerance that does, below a ceiling).")
            message += (" Raise the contact tolerance (aplan analyze or export-freecad --contact), add the missing "
                        "contacts between the groups, or exclude the parts that do not belong to the product.")
        else:
            message += (" Add the missing contacts between the groups, or exclude the parts that do not belong to "
                        "the product.")
        super().__init__(message)
        sizes = ", ".join(str(len(g)) for g in groups[:6]) + (", ..." if len(groups) > 6 else "")
        fix = (f"--contact {tolerance:g} joins them (or --contact auto)" if tolerance is not None else
               "add the missing contacts or exclude the parts that do not belong")
        self.brief = ((f"{source}: " if source else "") + f"the connection diagram is not connected: {len(groups)} "
                      f"groups of {sizes} parts (the smallest: {{{', '.join(min(groups, key=len)[:3])}}}); {fix}")


class NotDisassemblableError(PlannerError):
    """Some subassembly that the product needs cannot be split under the constraints (it is stuck)."""

    floating_parts: tuple[str, ...] = ()

    def __init__(self, stuck: list[str], detail: str, smallest: Sequence[str] = (), floating: str = "",
                 floating_parts: Sequence[str] = ()):
        """``smallest``: the smallest subassembly that the parts coming apart one by one reach and that has
        no feasible split; ``floating``: why it has none when a split is refused only because a side is not
        connected (which parts would float, and what helps), in words; ``floating_parts``: the ids of those
        parts (the support-contact rule's candidates, :mod:`planner.assembly.support_contacts`)."""
        self.stuck = stuck
        self.smallest = list(smallest)
        self.floating = floating
        self.floating_parts = tuple(floating_parts)
        where = ""
        if self.smallest and self.smallest != stuck:
            where = " The smallest subassembly with no feasible split is {" + ", ".join(self.smallest) + "}."
        super().__init__(
            "the product cannot be disassembled: subassembly {" + ", ".join(stuck) + "} has no feasible split "
            f"({detail}).{where}" + (f" {floating}" if floating else
                                     " Check the obstruction relations and technical constraints of these parts.")
        )
        if floating:
            self.brief = ("cannot be disassembled: {" + ", ".join(self.smallest or stuck) + "} has no feasible "
                          "split: " + floating)


class InterlockedPartsError(NotDisassemblableError):
    """Some parts block each other along every direction (:mod:`planner.assembly.feasibility`): found
    before any enumeration. ``pairs``: the interlocked pairs ``(first, second)``; ``directions``: the
    directions tried, as the message shows them."""

    def __init__(self, stuck: list[str], detail: str, pairs: Sequence[tuple[str, str]] = (), directions: str = ""):
        self.stuck = stuck
        self.pairs = tuple(pairs)
        PlannerError.__init__(self, f"the product cannot be disassembled: {detail}.")
        if self.pairs:
            listed = "; ".join(f"{a} and {b}" for a, b in self.pairs[:3]) + \
                (f" (and {len(self.pairs) - 3} more)" if len(self.pairs) > 3 else "")
            a, b = self.pairs[0]
            self.brief = (f"cannot be disassembled: {listed} block each other along every direction tried "
                          f"({directions}); make {'each pair' if len(self.pairs) > 1 else 'them'} one component "
                          f"(--group NAME={a},{b} on the CAD model)")


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
        self.brief = self._brief(size)

    def _brief(self, size: str) -> str:
        return f"{self.what}: {size} would be enumerated, more than the limit of {self.limit:,}"

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

    def _brief(self, size: str) -> str:
        # The counts, when they fit in one line: the detail's first clause (before its reasons and parts).
        first = re.split(r"[:;(]", self.detail, maxsplit=1)[0].strip().rstrip(",")
        counts = f" ({first})" if first and len(first) <= 100 else ""
        return (f"{self.what} would need about {gib(self.count)}{counts}, more than the memory budget of "
                f"{gib(self.limit)}")


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

    def _brief(self, size: str) -> str:
        return f"{self.what} would take about {gib(self.count)}, more than {self.budget_name} of {gib(self.limit)}"


def gib(size: int) -> str:
    """``1.5 GiB``, ``12.0 MiB``: a byte count for messages."""
    return f"{size / 2 ** 30:,.1f} GiB" if size >= 2 ** 30 else f"{size / 2 ** 20:,.1f} MiB"


class GeometryError(PlannerError):
    """A part's geometry cannot be analysed (a mesh that is not closed, no volume, an unreadable file), or a
    geometry engine was given bad tolerances."""


class ContactCeilingError(GeometryError):
    """``--contact auto`` would need a contact tolerance above its ceiling: the parts are apart by design, or
    do not belong to the product. ``gap`` is the gap that needs it, between ``parts``; ``ceiling`` the ceiling."""

    def __init__(self, message: str, gap: float, parts: tuple[str, str], ceiling: float):
        self.gap = gap
        self.parts = parts
        self.ceiling = ceiling
        super().__init__(message)


class SupportRefusedError(NotDisassemblableError):
    """Parts that would float inside the part that holds them (:mod:`planner.assembly.support_contacts`), whose
    support contacts ``--support-contacts error`` refuses. The message is one line; ``contacts`` the support
    contacts ``(part, host)`` the rule would add."""

    def __init__(self, message: str, contacts: Sequence[tuple[str, str]]):
        self.contacts = tuple(contacts)
        self.stuck = sorted({p for pair in self.contacts for p in pair})
        self.smallest, self.floating = [], ""
        self.floating_parts = tuple(p for p, _ in self.contacts)
        PlannerError.__init__(self, message)


class InterlockRefusedError(InterlockedPartsError):
    """Interlocked pairs in a product drawn in CAD that the interlock rules (:mod:`planner.assembly.interlocks`)
    do not resolve: no rule frees them, or ``--interlocks error`` refuses what the rules would do. The message
    is one line; ``pairs`` the pairs ``(first, second)``."""

    def __init__(self, message: str, pairs: Sequence[tuple[str, str]]):
        self.pairs = tuple(pairs)
        self.stuck = sorted({p for pair in self.pairs for p in pair})
        PlannerError.__init__(self, message)
