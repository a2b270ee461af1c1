"""Pieces of the error messages about product files: how a JSON value is described, JSON paths, and the
"did you mean" suggestion of a near name."""
from __future__ import annotations

import difflib
import json
from typing import Any, Iterable

__all__ = ["describe", "json_path", "suggest"]


def describe(value: Any) -> str:
    """A JSON value as a message shows it: ``the number 7``, ``the string 'ink'``, ``an array``, ``null``."""
    if isinstance(value, bool):
        return f"the boolean {json.dumps(value)}"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    if isinstance(value, str):
        return f"the string {value!r}"
    names = {dict: "an object", list: "an array", type(None): "null"}
    return names.get(type(value), type(value).__name__)


def json_path(steps: Iterable[str | int]) -> str:
    """The JSON path of a sequence of keys and indices: ``["parts", 3, "id"]`` -> ``parts[3].id``."""
    out = ""
    for step in steps:
        if isinstance(step, int):
            out += f"[{step}]"
        else:
            out += f".{step}" if out else str(step)
    return out


def suggest(name: Any, choices: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the choice nearest to ``name``, or an empty string when none is near."""
    if not isinstance(name, str):
        return ""
    close = difflib.get_close_matches(name, list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""
