"""``--force`` and the outputs a command checks before it starts (the overwrite rule)."""
from __future__ import annotations

import argparse

from ...files import check_output as check_writable
from ...validation import check_output

__all__ = ["add_force", "check_outputs"]


def add_force(parser, outputs: tuple[str, ...] = ("output",), stems: tuple[str, ...] = ()) -> None:
    """``--force`` and the outputs :func:`check_outputs` checks before the command starts: the options
    ``outputs`` (a file each) and ``stems`` (``STEM.png`` and ``STEM.svg``), by their ``dest``. The overwrite
    rule: an existing output is replaced only with ``--force`` (atomically); without it the command stops
    before any work, naming the file (:func:`planner.validation.check_output`)."""
    parser.add_argument("--force", action="store_true", help="replace the output if it exists (without it, an "
                                                             "existing output is an error and nothing is done)")
    parser.set_defaults(outputs=outputs, output_stems=stems)


def check_outputs(args: argparse.Namespace) -> None:
    """Check every output of ``args`` (:func:`add_force`) before any work: its folder exists and is writable,
    and it does not exist unless ``--force``. Raises :class:`~planner.validation.InputError`."""
    force = getattr(args, "force", False)
    outputs, stems = getattr(args, "outputs", ()), getattr(args, "output_stems", ())
    for dest in outputs:
        if getattr(args, dest, None):
            check_output(getattr(args, dest), force, "--" + dest.replace("_", "-"))
    for dest in stems:
        stem = getattr(args, dest, None)
        if stem:
            for suffix in (".png", ".svg"):
                check_output(f"{stem}{suffix}", force, "--" + dest.replace("_", "-"))
    # Outputs of commands without --force (a session's --log, appended to by design): their folders at least.
    # export-freecad makes its bundle's parent folders itself.
    if getattr(args, "command", None) == "export-freecad":
        return
    for dest, suffix in (("output", ""), ("plot", ".png"), ("log", "")):
        if dest == "log" and getattr(args, "command", None) != "session":
            continue  # aplan replay's LOG is its input
        value = getattr(args, dest, None)
        if dest not in outputs and dest not in stems and isinstance(value, str) and value and value != "-":
            check_writable(value + suffix)
