"""Size guards: the limits a plan is built within, and what to tell the user when a product exceeds them.

Every builder counts what it makes while it makes it (connected part sets, cuts, state edges) or estimates
it from counts first (bytes of a table), and raises :class:`~planner.errors.LimitExceededError` (or
:class:`~planner.errors.MemoryLimitError`) as soon as a limit is passed: the refusal costs at most the
limit's worth of work, whatever the product. The error names the size reached, what would help in words
(with the product's own part names) and the command-line options that help (``OPTIONS``); the command
line keeps those the command has.
"""
from __future__ import annotations

import logging
import os
import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from ..defaults import MEMORY_LIMIT, SUBASSEMBLY_LIMIT
from ..product import Product

__all__ = ["SizeLimits", "physical_memory", "default_memory_budget", "memory_options", "OPTIONS", "fastener_like",
           "fewer_parts_hint", "Progress"]


def physical_memory() -> int | None:
    """The machine's physical memory in bytes (None where the system does not say)."""
    try:
        physical = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):  # not a POSIX system
        return None
    return physical if physical > 0 else None


def default_memory_budget() -> int:
    """The bytes one graph or model may take by default: ``MEMORY_LIMIT`` (4 GiB), or a quarter of the
    machine's physical memory when that is less."""
    physical = physical_memory()
    return MEMORY_LIMIT if physical is None else min(MEMORY_LIMIT, physical // 4)


def memory_options(needed: int) -> list[tuple[str, str]]:
    """``--max-memory`` when raising the budget could help: ``needed`` is at most half the machine's memory."""
    physical = physical_memory()
    return [OPTIONS["memory"]] if physical is None or needed <= physical // 2 else []


@dataclass(frozen=True)
class SizeLimits:
    """``subassemblies``: connected part sets the AND/OR build may enumerate (and
    ``CUTS_PER_SUBASSEMBLY`` times as many cuts); ``memory``: bytes the plan and what a command builds on it
    may take together; ``reserve(states, edges, actions)``: the bytes the command builds on the plan (its
    decision model, its planner's values), from the plan's counts, named by ``reserve_for``: the plan is
    refused as soon as it and they would not fit (None: the plan alone)."""

    subassemblies: int = SUBASSEMBLY_LIMIT
    memory: int = field(default_factory=default_memory_budget)
    reserve: Callable[[int, int, int], int] | None = None
    reserve_for: str = ""


#: Command-line options that help when a limit is passed, by name: ``(option, advice)``.
OPTIONS = {
    "subassemblies": ("--max-subassemblies",
                      "--max-subassemblies N raises the AND/OR graph's limit (time and memory grow with it)"),
    "memory": ("--max-memory", "--max-memory GIB raises the memory budget (if the machine has the memory)"),
    "intentions": ("--limit", "--limit N raises the intention limit"),
    "fasteners": ("--fasteners", "--fasteners auto folds the fasteners the planner proposes into the operations "
                                 "that install them (aplan fasteners PRODUCT lists them)"),
    "exclude": ("--exclude", "--exclude LABEL leaves a part (a fastener) out of a CAD model"),
    "group": ("--group", "--group NAME=A,B makes one part of several in a CAD model (a fastener and a part it "
                         "holds)"),
    "base_part": ("--base-part", "--base-part [PART] keeps only the sequences that start from the base part"),
    "online": ("--planner", "--planner online decides by lookahead, without the flat model"),
}

_FASTENER = re.compile(r"screw|bolt|(?<![a-z])nut|washer|rivet|dowel|nail|stud|fastener|(?<![a-z])pins?(?![a-z])",
                       re.IGNORECASE)


def fastener_like(product: Product) -> tuple[list[str], list[str]]:
    """The parts whose id or label names a fastener (screw, bolt, nut, washer, rivet, pin, ...), and the
    parts with exactly two contacts (what a fastener joining two parts looks like in the connection
    diagram). Each such part doubles the connected part sets it can join. Cost: O(parts + contacts)."""
    degree = {p: 0 for p in product.part_ids}
    for a, b in product.contacts:
        degree[a] += 1
        degree[b] += 1
    named = [p.id for p in product.parts if _FASTENER.search(p.id) or _FASTENER.search(p.label or "")]
    return named, [p for p in product.part_ids if degree[p] == 2]


def _names(parts: list[str], shown: int = 5) -> str:
    return ", ".join(parts[:shown]) + (f", ... ({len(parts)} in all)" if len(parts) > shown else "")


def fewer_parts_hint(product: Product) -> str:
    """What makes a product's plan smaller, with its own part names: fewer parts (fasteners left out or
    grouped with the part they hold), or one subassembly at a time."""
    named, two = fastener_like(product)
    found = []
    if named:
        found.append(f"{len(named)} part(s) look like fasteners by name ({_names(named)})")
    if two:
        found.append(f"{len(two)} part(s) have exactly two contacts ({_names(two)})")
    seen = ("; ".join(found) + ". ") if found else ""
    return (f"The product has {len(product.parts)} parts and {len(product.contacts)} contacts; {seen}Plan with "
            "fewer parts: fold the fasteners into the operations that install them, or leave them out, or group "
            "each with a part it holds, or plan one subassembly "
            "(one workstation) at a time.")


class Progress:
    """Tells the user how far a long step has got: ``report(text)`` logs ``text`` (at INFO, through
    ``logger``) once the step has run ``after`` seconds, then at most every ``every`` seconds. The clock only
    decides when to speak, never what is computed; callers call it now and then (every few thousand items)."""

    def __init__(self, logger: logging.Logger, after: float = 2.0, every: float = 5.0):
        self.logger = logger
        self.every = every
        self.next = time.monotonic() + after

    def report(self, text: str, *args) -> None:
        now = time.monotonic()
        if now >= self.next:
            self.logger.info(text, *args)
            self.next = now + self.every
