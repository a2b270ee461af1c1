"""argparse types: numbers in a range, lengths, seconds, directions; a value out of range is a usage error naming
the option (exit status 2)."""
from __future__ import annotations

import argparse

from ...defaults import DECISION_TIME_MAX, TIME_LIMIT_MAX
from ...errors import PlannerError
from ...geometry.tolerances import AUTO
from ...validation import InputError, check_number

__all__ = ["number", "finite", "positive", "whole", "index", "gibibytes", "contact_tolerance", "positive_length",
           "positive_seconds", "decision_seconds", "designer_direction"]


def number(low: float | None = None, high: float | None = None, low_open: bool = False, high_open: bool = False,
           integer: bool = False):
    """An argparse type: a finite number in the range (:func:`planner.validation.check_number`); out of range,
    NaN or infinite is a usage error naming the option (exit status 2)."""
    def parse(text: str):
        try:
            return check_number(text, "value", low, high, low_open, high_open, integer)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc).removeprefix("value: ")) from None
    parse.__name__ = "whole number" if integer else "number"  # argparse names the type in its messages
    return parse


finite = number()                                  # any finite number (rewards)


positive = number(1, integer=True)                  # a whole number of at least 1


whole = number(integer=True)                        # any whole number (seeds)


index = number(0, integer=True)                     # a whole number of at least 0 (cameras, sequences)


def contact_tolerance(text: str) -> float | str:
    """A contact tolerance: a number >= 0, or ``auto`` (an argparse type)."""
    if text.strip().lower() == AUTO:
        return AUTO
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a length or {AUTO!r}, got {text!r}") from None
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite length >= 0, got {text}")
    return value


def positive_length(text: str) -> float:
    """A finite length above 0 (an argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a length, got {text!r}") from None
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite length above 0, got {text}")
    return value


def designer_direction(text: str) -> tuple[float, float, float]:
    """``X,Y,Z`` (or an axis name) as a unit vector (an argparse type)."""
    from ...product.designer import parse_direction

    try:
        return parse_direction(text, "--direction")
    except PlannerError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _direction_count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number from 0 to 64, got {text!r}") from None
    if not 0 <= value <= 64:
        raise argparse.ArgumentTypeError(f"must be a whole number from 0 to 64, got {value}")
    return value


def positive_seconds(text: str, high: float = TIME_LIMIT_MAX) -> float:
    """A finite number of seconds above 0 and at most ``high`` (an argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number of seconds, got {text!r}") from None
    if not (value > 0 and value <= high):
        raise argparse.ArgumentTypeError(f"must be a number of seconds above 0 and at most {high:,}, got {text}")
    return value


def decision_seconds(text: str) -> float:
    """Seconds per online decision: above 0, at most :data:`~planner.defaults.DECISION_TIME_MAX`."""
    return positive_seconds(text, DECISION_TIME_MAX)


gibibytes = number(0, 2 ** 20, low_open=True)  # a positive, finite number of GiB (at most 1 PiB)


_probability = number(0, 1, high_open=True)  # [0, 1): outside is a usage error naming the option (exit 2)
