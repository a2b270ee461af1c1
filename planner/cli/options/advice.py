"""How the command line words a refusal: the options of this command (and of others) that help, in one line or in
full with ``--verbose``."""
from __future__ import annotations

import argparse

from ...errors import LimitExceededError, PlannerError

__all__ = ["offer_options", "advice", "add_verbose", "explain", "LONG_MESSAGE"]


def offer_options(parser: argparse.ArgumentParser, commands) -> None:
    """Let :func:`advice` know which options each command has (``commands``: the subparsers' action)."""
    parser.set_defaults(offered_options={name: frozenset(sub._option_string_actions)
                                         for name, sub in commands.choices.items()})


# Options worth naming when another command has them (they do the job differently there); the others
# (a limit of this command) help only where the refusal happened.
_ELSEWHERE = ("--exclude", "--group", "--planner")


_CAD_ONLY = ("--exclude", "--group")


_CAD_SUFFIXES = (".fcstd", ".step", ".stp")


def _reads_cad(args: argparse.Namespace) -> bool:
    """Whether the command's PRODUCT (or MODEL) is a CAD model (a FreeCAD document or STEP file), or unknown."""
    argument = getattr(args, "model", None) or getattr(args, "product", None)
    return argument is None or str(argument).lower().endswith(_CAD_SUFFIXES)


def _applying(error: LimitExceededError, args: argparse.Namespace) -> list[tuple[str, str]]:
    """``error.options`` that apply to this command's PRODUCT: ``--exclude`` and ``--group`` choose a CAD
    model's parts, so only for a CAD model."""
    return [(option, text) for option, text in error.options if option not in _CAD_ONLY or _reads_cad(args)]


def _offered_here(args: argparse.Namespace) -> frozenset:
    """The options this command has."""
    return getattr(args, "offered_options", {}).get(getattr(args, "command", None), frozenset())


def advice(error: LimitExceededError, args: argparse.Namespace) -> str:
    """The options of ``error`` that help, as one sentence: those of this command, then those of other
    commands that do the job another way (``--planner online`` in simulate, ...), with their command."""
    offered = getattr(args, "offered_options", {})
    here = _offered_here(args)
    found = []
    for option, text in _applying(error, args):
        if option in here:
            found.append(text)
        elif option in _ELSEWHERE:
            others = [name for name, options in offered.items() if option in options]
            if others:
                found.append(f"aplan {'/'.join(others)} {text}")
    return ("What helps: " + "; ".join(found) + ".") if found else ""


def add_verbose(parser) -> None:
    """``--verbose``: errors and refusals in full (by default one line each, :func:`explain`)."""
    parser.add_argument("--verbose", action="store_true",
                        help="explain errors and refusals in full: why, and what each option that helps does "
                             "(by default one line each)")


def _spelled(text: str) -> str:
    """The option as an advice text spells it: ``--fasteners auto`` of "--fasteners auto folds ...",
    ``--max-memory GIB`` of "--max-memory GIB raises ..." (the option and its value, without the verb)."""
    words = text.split()
    value = words[1] if len(words) > 1 else ""
    return " ".join(words[:2]) if value and (not value.isalpha() or not value.islower() or
                                             value in ("auto", "online", "none")) else words[0]


#: A message longer than this (characters) is printed in its one-line form, the whole of it with --verbose.
LONG_MESSAGE = 200


def explain(error: PlannerError, args: argparse.Namespace, options: bool = True) -> str:
    """``error`` as the command line prints it: its one line (:attr:`~planner.errors.PlannerError.summary`) and,
    for a size limit, the options of this command that help, by name; with ``--verbose`` its whole message and
    what each option does (:func:`advice`); without ``options``, no option is named (a figure only compared)."""
    helps = advice(error, args) if options and isinstance(error, LimitExceededError) else ""
    whole = f"{error} {helps}".strip()
    if getattr(args, "verbose", False) or (len(whole) <= LONG_MESSAGE and "\n" not in whole):
        return whole
    text = error.summary
    if options and isinstance(error, LimitExceededError):
        here = _offered_here(args)
        names = [_spelled(said) for option, said in _applying(error, args) if option in here]
        if names:
            text += f"; try {', '.join(names)}"
    return text + (" (--verbose says why)" if error.summary != str(error) else "")
