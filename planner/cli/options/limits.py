"""The size and input limits bundles: ``--max-subassemblies``, ``--max-memory`` (:class:`~planner.assembly.guards.SizeLimits`)
and ``--max-input``, ``--max-declared``, ``--max-cells`` (:class:`~planner.validation.InputLimits`)."""
from __future__ import annotations

import argparse

from ...assembly.guards import SizeLimits, default_memory_budget
from ...defaults import CUTS_PER_SUBASSEMBLY, DECLARED_LIMIT, INPUT_FILE_LIMIT, SPREAD_CELL_LIMIT, SUBASSEMBLY_LIMIT
from ...validation import InputLimits

from .values import gibibytes, number, positive

__all__ = ["add_size_options", "limits_from", "add_input_options", "inputs_from"]


def add_size_options(parser) -> None:
    """The size limits every command that builds a plan or a model refuses past (with the estimate)."""
    budget = default_memory_budget() / 2 ** 30
    group = parser.add_argument_group("size limits (past them the command refuses at once, saying why)")
    group.add_argument("--max-subassemblies", type=positive, default=SUBASSEMBLY_LIMIT, metavar="N",
                       help=f"the AND/OR graph enumerates at most N connected part sets and examines at most "
                            f"{CUTS_PER_SUBASSEMBLY} N cuts (default {SUBASSEMBLY_LIMIT:,}: about 2 s)")
    group.add_argument("--max-memory", type=gibibytes, default=budget, metavar="GIB",
                       help=f"the memory one graph or model may take, estimated before it is built (default "
                            f"{budget:g} GiB: 4 GiB or a quarter of this machine's memory, if less)")


def limits_from(args: argparse.Namespace) -> SizeLimits:
    return SizeLimits(args.max_subassemblies, int(args.max_memory * 2 ** 30))


def add_input_options(parser) -> None:
    """The input limits a model, policy or session log file is read within (README, "Exit status"), for the
    user whose real file is larger: one option per limit that a real file may pass, named in the refusal.
    (JSON nesting has none: a real product or log is a few levels deep.)"""
    group = parser.add_argument_group("input limits (a model, policy or session log file past them is refused at "
                                      "once, naming the option)")
    group.add_argument("--max-input", type=gibibytes, default=INPUT_FILE_LIMIT / 2 ** 30, metavar="GIB",
                       help=f"bytes read from a model, policy or session log file, a .gz counted decompressed "
                            f"(default {INPUT_FILE_LIMIT / 2 ** 30:g} GiB)")
    group.add_argument("--max-declared", type=number(1, 10 ** 9, integer=True), default=DECLARED_LIMIT, metavar="N",
                       help=f"states, actions or observations a model file declares, and the length of a policy's "
                            f"vectors (default {DECLARED_LIMIT:,}; about 60 bytes each)")
    group.add_argument("--max-cells", type=number(1, 10 ** 10, integer=True), default=SPREAD_CELL_LIMIT,
                       metavar="N", help=f"cells a model file's entries spread over per table ('*', uniform, rows, "
                                         f"identity), and the combinations a reward depending on the next state or "
                                         f"observation is evaluated over per action (default {SPREAD_CELL_LIMIT:,}; "
                                         f"about 150 bytes each while the table is built)")


def inputs_from(args: argparse.Namespace) -> InputLimits:
    """The :class:`~planner.validation.InputLimits` of ``args`` (:func:`add_input_options`; defaults without)."""
    d = InputLimits()
    max_input = getattr(args, "max_input", None)
    return InputLimits(int(max_input * 2 ** 30) if max_input is not None else d.file_bytes,
                       getattr(args, "max_declared", d.declared), getattr(args, "max_cells", d.spread_cells))
