"""The one validation layer for what a user hands in: numbers, output paths and sizes.

Every command-line option that takes a number, every number read from a file, every output path and every
size a file declares goes through these checks before any work starts, so bad input stops with one line that
names the option or file, the value and the fix (a :class:`~planner.errors.PlannerError`), never a traceback
or a NaN in an output. The limits are in :mod:`planner.defaults`.
"""
from __future__ import annotations

import io
import json
import math
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .defaults import DECLARED_LIMIT, INPUT_FILE_LIMIT, JSON_DEPTH_LIMIT, SPREAD_CELL_LIMIT
from .errors import PlannerError
from .files import check_output as check_writable

__all__ = ["InputError", "InputLimitError", "OutputExistsError", "not_regular", "check_number", "check_finite_array",
           "check_count", "check_output", "CappedReader", "json_loads", "describe_range", "InputLimits",
           "INPUT_OPTION", "DECLARED_OPTION", "CELLS_OPTION"]

# The options that raise the input limits (on every command that reads a model, policy or session log file),
# named in the refusals so that the fix is in the message.
INPUT_OPTION = "--max-input GIB"
DECLARED_OPTION = "--max-declared N"
CELLS_OPTION = "--max-cells N"


@dataclass(frozen=True)
class InputLimits:
    """What a file a command reads may hold before it is refused, checked before the memory is taken (README,
    "Exit status"); defaults in :mod:`planner.defaults`.

    ``file_bytes``: bytes read from a model, policy or session log file (a ``.gz`` counted decompressed;
    ``--max-input GIB``); ``declared``: states, actions or observations a model file declares, and a policy's
    vector length (``--max-declared N``); ``spread_cells``: cells a model file's entries may spread over per
    table (``*``, uniform, rows, identities), and the combinations a next-state or observation dependent reward
    is evaluated over per action (``--max-cells N``); ``json_depth``: nesting of JSON (products, logs), with
    no option (a real product is a few levels deep)."""

    file_bytes: int = INPUT_FILE_LIMIT
    declared: int = DECLARED_LIMIT
    spread_cells: int = SPREAD_CELL_LIMIT
    json_depth: int = JSON_DEPTH_LIMIT


class InputError(PlannerError):
    """A number, path or file the user gave is out of range, not finite, or unreadable."""


class InputLimitError(InputError):
    """A file declares or holds more than a size limit allows (the message names the limit and the option)."""


class OutputExistsError(InputError):
    """An output exists and ``--force`` was not given (the overwrite rule: nothing is replaced silently)."""


def describe_range(low: float | None, high: float | None, low_open: bool, high_open: bool, integer: bool) -> str:
    """``a finite number above 0``, ``a whole number from 1 to 64``: the range in words, for messages."""
    noun = "a whole number" if integer else "a finite number"
    show = lambda x: f"{int(x):,}" if float(x).is_integer() else f"{x:g}"  # noqa: E731
    parts = []
    if low is not None:
        parts.append(f"{'above' if low_open else 'at least'} {show(low)}")
    if high is not None:
        parts.append(f"{'below' if high_open else 'at most'} {show(high)}")
    return noun + (" " + " and ".join(parts) if parts else "")


def check_number(value: float | int | str, name: str, low: float | None = None, high: float | None = None,
                 low_open: bool = False, high_open: bool = False, integer: bool = False) -> float | int:
    """``value`` as a number if it is finite and within ``[low, high]`` (open ends with ``low_open`` and
    ``high_open``), else an :class:`InputError` naming ``name`` (an option, or ``file: place``), the value
    and the range. Text is parsed first (``1e9`` is accepted as a whole number when ``integer``). O(1)."""
    wanted = describe_range(low, high, low_open, high_open, integer)
    try:
        number = float(value) if not isinstance(value, (int, np.integer)) else int(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name}: must be {wanted}, got {value!r}") from None
    if isinstance(number, float) and not math.isfinite(number):
        raise InputError(f"{name}: must be {wanted}, got {value}")
    if integer:
        if isinstance(number, float) and not number.is_integer():
            raise InputError(f"{name}: must be {wanted}, got {value}")
        number = int(number)
    below = low is not None and (number <= low if low_open else number < low)
    above = high is not None and (number >= high if high_open else number > high)
    if below or above:
        raise InputError(f"{name}: must be {wanted}, got {value}")
    return number


def check_finite_array(values, where: str) -> None:
    """Raise :class:`InputError` when ``values`` (an array, or a scipy sparse matrix's ``data``) holds a NaN
    or an infinity, naming ``where`` and the first bad position. O(n)."""
    data = np.asarray(getattr(values, "data", values) if hasattr(values, "nnz") else values, dtype=float)
    bad = np.flatnonzero(~np.isfinite(data.ravel()))
    if bad.size:
        raise InputError(f"{where}: {bad.size} value(s) are not finite numbers (the first: {data.ravel()[bad[0]]}); "
                         "every number must be finite: fix or regenerate the file")


def check_count(count: int, limit: int, what: str, where: str, option: str = "") -> None:
    """Raise :class:`InputLimitError` when ``count`` (e.g. the states a file declares) passes ``limit``: the
    message names ``where``, ``what``, both numbers and ``option`` (the option that raises the limit), if any."""
    if count > limit:
        fix = f" ({option} raises the limit)" if option else ""
        raise InputLimitError(f"{where}: {count:,} {what}, more than the limit of {limit:,}{fix}")


def check_output(path: str | os.PathLike, force: bool = False, option: str = "-o", replaceable: bool = True,
                 noun: str = "file") -> Path:
    """The output ``path``, checked before any work starts: its folder exists and is writable and it is not a
    folder (:func:`planner.files.check_output`, which raises :class:`~planner.files.OutputError`), and it does
    not exist unless ``force`` (the overwrite rule: an existing output is replaced only with ``--force``, and
    then atomically; else :class:`OutputExistsError`)."""
    path = Path(path)
    check_writable(path)  # the folder exists, is a folder and is writable; the path is no folder (OutputError)
    if path.exists() and not (force and replaceable):
        how = "pass --force to replace it, or choose another path" if replaceable else \
            "it is never replaced; choose another path"
        raise OutputExistsError(f"{option} {path}: the {noun} exists already; {how}")
    return path


_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def not_regular(path: str | os.PathLike, what: str = "input") -> str | None:
    """Why ``path`` cannot be read as an input file, when it exists but is not a regular file (a device such as
    ``/dev/zero`` reads forever, a FIFO blocks, and both report size 0, so the input limits cannot see them):
    ``"PATH: not a regular file (a character device); give the path of a WHAT file"``. None for a regular
    file or a path that does not exist (the reader says so). Cost: one ``stat``."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None
    if stat.S_ISREG(mode):
        return None
    kind = next((name for test, name in _KINDS if test(mode)), "not a file")
    return f"{path}: not a regular file ({kind}); give the path of a {what} file"


class CappedReader(io.RawIOBase):
    """A readable stream over ``stream`` (e.g. a gzip file, decompressed as it is read) that raises
    :class:`InputLimitError` once more than ``limit`` bytes were read, so a compressed bomb never fills the disk,
    the memory or the time. Cost: O(1) per read beyond the wrapped stream's."""

    def __init__(self, stream, limit: int, source: str, option: str = ""):
        super().__init__()
        self.stream, self.limit, self.source, self.option, self.total = stream, limit, source, option, 0

    def readable(self) -> bool:
        return True

    def read(self, size: int = -1) -> bytes:
        data = self.stream.read(self.limit + 1 - self.total if size is None or size < 0 else size)
        self.total += len(data)
        if self.total > self.limit:
            fix = f" ({self.option} raises it)" if self.option else ""
            raise InputLimitError(f"{self.source}: more than {self.limit:,} bytes (decompressed), the limit for an "
                                  f"input file{fix}")
        return data

    def readinto(self, buffer) -> int:
        data = self.read(len(buffer))
        buffer[:len(data)] = data
        return len(data)

    def close(self) -> None:
        self.stream.close()
        super().close()


_STRING = re.compile(r'"(?:[^"\\]|\\.)*"')
_NOT_BRACKET = re.compile(r"[^\[\]{}]+")


def _nesting(text: str) -> int:
    """The bracket nesting depth of JSON ``text`` outside strings: strings and everything but brackets removed
    by regular expressions, then a running sum. O(len(text))."""
    brackets = _NOT_BRACKET.sub("", _STRING.sub("", text)).encode("ascii")
    if not brackets:
        return 0
    codes = np.frombuffer(brackets, dtype=np.uint8)
    steps = np.where((codes == ord("[")) | (codes == ord("{")), 1, -1)
    return int(np.cumsum(steps).max())


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"the number {text[:40]} is too large (not a finite number)")
    return value


def _bounded_int(text: str) -> int:
    if len(text.lstrip("-")) > 300:  # far beyond any count or id; int() refuses past 4,300 digits anyway
        raise ValueError(f"an integer of {len(text.lstrip('-')):,} digits")
    return int(text)


def _no_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows")


class _DuplicateKey(Exception):
    def __init__(self, key: str, others: list[str]):
        super().__init__(key)
        self.key, self.others = key, others


def _unique_keys(pairs: list[tuple[str, object]]) -> dict:
    """A JSON object, refusing a key given twice (``json`` would keep the second value without a word)."""
    data: dict = {}
    for key, value in pairs:
        if key in data:
            raise _DuplicateKey(key, [k for k in data if k != key][:3])
        data[key] = value
    return data


def json_loads(text: str, source: str, depth_limit: int = JSON_DEPTH_LIMIT):
    """Parse JSON ``text`` strictly: nesting at most ``depth_limit`` deep (checked before parsing, so never a
    RecursionError), every number finite (``1e400``, ``NaN`` and ``Infinity`` are refused), integers of at
    most 300 digits and no key twice in one object (JSON itself would keep the last value silently). Raises
    :class:`InputError` naming ``source``; ``json.JSONDecodeError`` (a ``ValueError``)
    for text that is not JSON, for the caller to place. O(len(text))."""
    depth = _nesting(text)
    if depth > depth_limit:
        raise InputLimitError(f"{source}: nested {depth} levels deep, more than the limit of {depth_limit}; "
                              "is it the right file?")
    try:
        return json.loads(text, parse_float=_finite_float, parse_int=_bounded_int, parse_constant=_no_constant,
                          object_pairs_hook=_unique_keys)
    except json.JSONDecodeError:
        raise
    except _DuplicateKey as exc:
        raise InputError(f"{source}: the key {exc.key!r} appears twice in one object (beside "
                         f"{', '.join(map(repr, exc.others)) or 'no other key'}); JSON keeps only one of the two "
                         "values: remove or rename the other") from None
    except (ValueError, RecursionError) as exc:
        raise InputError(f"{source}: {exc}; every number must be finite and of a sensible size") from None
