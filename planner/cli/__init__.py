"""The ``aplan`` command line: ``stats``, ``intentions``, ``synth`` (:mod:`.plan`), ``analyze``
(:mod:`.geometry`), ``pomdp``, ``solve``, ``simulate``, ``evaluate`` (:mod:`.decision`), ``session``,
``replay``, ``markers`` (:mod:`.runtime`), ``ros``, ``ros-vision``, ``ros-robot``, ``ros-sim`` (:mod:`.ros`), ``habits`` (:mod:`.habits`), and the commands plugins add (``export-freecad``).

Each module only parses arguments and prints; the work is done by :mod:`planner.api`. Messages for the user
(notes, warnings) go through :mod:`logging` to standard error; results go to standard output.
Exit status: 0 on success, 1 when the input is bad (the message says what, where and how to fix it) or
what it would build exceeds a size limit (the message gives the estimate and the options that help), 2 on
a usage error (argparse's, or :class:`~planner.errors.UsageError`: options that do not go together), 3 when
``aplan stats`` printed only some figures (the others would exceed a size limit),
128 + N when signal N ended it (130: Ctrl-C, 143: SIGTERM). Nothing is written when a command fails or is
interrupted (output folders are checked before any work), except by ``aplan solve``, which writes the best
policy so far on an interrupt and says so, and ``aplan session``, whose log keeps the steps before it. A numeric option that is not finite or out of range is a usage
error naming the option. The overwrite rule: outputs are checked before any work
(:func:`.options.check_outputs`): their folder must exist and be writable, and an existing output is
replaced only with ``--force`` (atomically).
"""
from __future__ import annotations

import argparse
import logging
import signal
import sys
from typing import Sequence

from ..errors import LimitExceededError, PlannerError, UsageError
from ..interrupts import Interrupted, delivered, exit_status, signal_number, signals_as_interrupts, swallowed
from ..plugins import registry
from . import decision, geometry, habits, plan, ros, runtime
from .options import add_tolerance_options, add_verbose, check_outputs, explain, offer_options, tolerances_from

__all__ = ["main", "build_parser", "add_tolerance_options", "tolerances_from"]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="aplan", description="APLAN: assembly plans and operator intentions "
                                     "for human-robot collaborative assembly (Cramer et al., RA-L 2021).")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for group in (plan, geometry, decision, runtime, habits, ros):
        group.add_commands(commands)
    for add in registry().commands:
        add(commands)
    for command in commands.choices.values():  # every command, the plugins' too
        add_verbose(command)
    offer_options(parser, commands)
    return parser


class _Format(logging.Formatter):
    """``aplan: MESSAGE`` for notes, ``aplan: warning: MESSAGE`` for warnings and errors."""

    def format(self, record: logging.LogRecord) -> str:
        message = record.getMessage()
        return f"aplan: {message}" if record.levelno < logging.WARNING else f"aplan: warning: {message}"


class _Once(logging.Filter):
    """Each warning once per command: a product is folded, checked or read at several steps of one command,
    and a warning about it (a dissolved subassembly, say) would be repeated as often."""

    def __init__(self) -> None:
        super().__init__()
        self.said: set[str] = set()

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno < logging.WARNING:
            return True
        message = record.getMessage()
        if message in self.said:
            return False
        self.said.add(message)
        return True


def _configure_logging(verbose: bool = False) -> logging.Handler:
    """Notes and warnings to standard error (each warning once); with ``verbose`` the details too (DEBUG: the
    whole explanation of a warning the library gave in one line)."""
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_Format())
    handler.addFilter(_Once())
    for name in ("planner", "freecad_aplan"):
        logger = logging.getLogger(name)
        logger.addHandler(handler)
        logger.setLevel(logging.DEBUG if verbose else logging.INFO)
        logger.propagate = False
    return handler


def _restore_logging(handler: logging.Handler) -> None:
    for name in ("planner", "freecad_aplan"):
        logger = logging.getLogger(name)
        logger.removeHandler(handler)
        logger.setLevel(logging.NOTSET)
        logger.propagate = True


def _named(error: PlannerError, args, text: str) -> str:
    """``text`` (the error as printed) of a refusal past a size limit with the PRODUCT (or MODEL) it concerns
    first, unless it names it already."""
    argument = getattr(args, "model", None) or getattr(args, "product", None)
    if isinstance(error, LimitExceededError) and isinstance(argument, str) and argument not in text:
        return f"{argument}: {text}"
    return text


def main(argv: Sequence[str] | None = None) -> int:
    # ROS arguments (name:=value, roslaunch's __name:=) go to rospy, not argparse
    args = build_parser().parse_args(ros.split_remaps(list(sys.argv[1:] if argv is None else argv)))
    # Undone at the end: main() also runs inside tests and other programs.
    handler = _configure_logging(getattr(args, "verbose", False))
    try:
        with signals_as_interrupts():  # SIGTERM too unwinds: temporary files go, children are killed
            try:
                check_outputs(args)  # the overwrite rule and writable folders, before any work
                status = args.run(args)
            except (PlannerError, OSError):
                if swallowed():  # a failure after an interrupt that was caught and ignored: the interrupt it is
                    raise Interrupted(swallowed()) from None
                raise
            if swallowed():  # caught and ignored on the way (outputs refuse to commit after one): still an interrupt
                raise Interrupted(swallowed())
            return status
    except PlannerError as exc:
        text = explain(exc, args)
        print(f"aplan: error: {_named(exc, args, text)}", file=sys.stderr)
        return 2 if isinstance(exc, UsageError) else 1
    except BrokenPipeError:  # e.g. `aplan intentions pen | head`
        return 0
    except OSError as exc:  # one no check foresaw (a file vanished, a device failed): a message, no traceback
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"aplan: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM, SIGHUP: what was unfinished was removed
        delivered()
        kept = getattr(exc, "kept", None)  # what a command keeps on an interrupt (a session's log)
        print(f"aplan: interrupted ({signal.Signals(signal_number(exc)).name}): {kept or 'nothing was written'}",
              file=sys.stderr)
        return exit_status(signal_number(exc))
    finally:
        _restore_logging(handler)
