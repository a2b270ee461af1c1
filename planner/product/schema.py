"""The structure of a product file, checked with its JSON Schema (``schema.json`` beside this module).

jsonschema finds every structural mistake and the JSON path of each; :func:`check_document` turns the first
one into a :class:`~planner.errors.ProductFormatError` whose location is that path (``parts[3].id``) and
whose message says how to fix it. In the schema, ``title`` names a value in these messages ("unknown unit
'furlong'", "expected a pair of two part ids") and the extra keyword ``x-hint`` says how to fix it.

What the schema cannot express (ids that must name a part, duplicates, unit vectors) is checked afterwards
by :mod:`planner.product.validation` and :mod:`planner.product.io`.
"""
from __future__ import annotations

import functools
import json
import re
from pathlib import Path
from typing import Any

try:
    import jsonschema
except ImportError:  # FreeCAD's Python from the Addon Manager may lack it (not on FreeCAD's allowed list)
    jsonschema = None

from ..errors import ProductFormatError
from .constants import FORMAT, VERSION
from .messages import describe, json_path, suggest

__all__ = ["SCHEMA_PATH", "product_schema", "check_document", "schema_checks"]

#: Said when a product file is refused without jsonschema, whose checks name the place of the mistake.
WITHOUT_JSONSCHEMA = "install jsonschema (pip install jsonschema) for the JSON path of the mistake"

SCHEMA_PATH = Path(__file__).with_name("schema.json")

# How a message names each JSON type (jsonschema's names of types).
_TYPES = {"string": "a string", "number": "a number", "integer": "an integer", "boolean": "true or false",
          "array": "an array", "object": "an object", "null": "null"}


@functools.lru_cache(maxsize=1)
def product_schema() -> dict:
    """The JSON Schema of product files (format version :data:`~planner.product.constants.VERSION`)."""
    return json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))


@functools.lru_cache(maxsize=1)
def _validator() -> jsonschema.Draft202012Validator:
    return jsonschema.Draft202012Validator(product_schema())


def check_document(data: Any, source: str = "<memory>") -> None:
    """Raise :class:`~planner.errors.ProductFormatError` when ``data`` (parsed JSON) is not a product file
    of this version, naming ``source``, the JSON path of the first mistake and how to fix it."""
    _check_header(data, source)
    if not schema_checks():
        _check_outline(data, source)
        return
    errors = sorted(_validator().iter_errors(data), key=_order)
    if errors:
        location, problem = _explain(errors[0])
        raise ProductFormatError(source, location, problem)


def schema_checks() -> bool:
    """True when jsonschema is installed: :func:`check_document` checks the whole structure and names the JSON
    path of the first mistake. Without it (FreeCAD's Python, say) the outline is checked and the rest by the
    planner's own checks (:func:`planner.product.io.product_from_dict`), which refuse a malformed file with a
    less precise message."""
    return jsonschema is not None


def _check_outline(data: Any, source: str) -> None:
    """Without jsonschema: the top level is an object of the schema's keys (or ``x-`` extensions) whose
    ``parts`` and ``contacts`` are arrays."""
    if not isinstance(data, dict):
        raise ProductFormatError(source, "top level", f"expected an object, got {describe(data)}")
    allowed = list(product_schema()["properties"])
    for key in data:
        if key not in allowed and not str(key).startswith("x-"):
            raise ProductFormatError(source, json_path([key]), f"unknown key{suggest(key, allowed)}; allowed keys: "
                                     f"{', '.join(allowed)} (keys starting with 'x-' are kept as extensions)")
    for key in ("parts", "contacts"):
        if key not in data:
            raise ProductFormatError(source, "top level", f"missing required key {key!r}")
        if not isinstance(data[key], list):
            raise ProductFormatError(source, key, f"expected an array, got {describe(data[key])}")


def _check_header(data: Any, source: str) -> None:
    """``format`` and ``version`` are checked first: a file of another kind, or written by a newer APLAN, is
    named as such rather than by the first key this version does not know."""
    if not isinstance(data, dict):
        return  # the schema says what it should be
    if "format" in data and data["format"] != FORMAT:
        raise ProductFormatError(source, "format", f"expected {FORMAT!r}, got {describe(data['format'])}; "
                                 "this is not an APLAN product file")
    version = data.get("version", VERSION)
    if isinstance(version, bool) or not isinstance(version, int):
        raise ProductFormatError(source, "version", f"expected an integer, got {describe(version)}")
    if version != VERSION:
        newer = " written by a newer APLAN; upgrade aplan" if version > VERSION else ""
        raise ProductFormatError(source, "version",
                                 f"unknown format version {version}{newer} (this planner reads version {VERSION})")


def _order(error: jsonschema.ValidationError) -> tuple:
    """Errors in the order of their paths (keys alphabetically, indices in order, an object before what it
    holds), so the one reported does not depend on the order in which jsonschema walks the schema."""
    return tuple((0, step, "") if isinstance(step, int) else (1, 0, step) for step in error.absolute_path), \
        error.validator


def _explain(error: jsonschema.ValidationError) -> tuple[str, str]:
    """(JSON path, problem and fix) of a validation error."""
    error = _branch(error)
    path = list(error.absolute_path)
    schema, value, kind = error.schema, error.instance, error.validator
    if kind == "additionalProperties":
        return _unknown_key(path, schema, value)
    if kind == "required":
        missing = next(key for key in error.validator_value if key not in value)
        return json_path(path) or "top level", f"missing required key {missing!r}"
    return json_path(path) or "top level", _problem(error, schema, value)


def _branch(error: jsonschema.ValidationError) -> jsonschema.ValidationError:
    """For a value that matches no branch of a ``oneOf`` (a direction: a name or a vector), the error of the
    branch of the value's type; the ``oneOf`` error itself when no branch has that type."""
    while error.validator in ("oneOf", "anyOf"):
        # A branch whose own type differs from the value's is not the one the writer meant.
        relevant = sorted((e for e in error.context if e.validator != "type" or e.path), key=_order)
        if not relevant:
            return error
        error = relevant[0]
    return error


def _unknown_key(path: list, schema: dict, value: dict) -> tuple[str, str]:
    allowed = list(schema.get("properties", {}))
    patterns = list(schema.get("patternProperties", {}))
    key = next(k for k in value if k not in allowed and not any(re.search(p, k) for p in patterns))
    return json_path(path + [key]), (f"unknown key{suggest(key, allowed)}; allowed keys: {', '.join(allowed)} "
                                     "(keys starting with 'x-' are kept as extensions)")


def _problem(error: jsonschema.ValidationError, schema: dict, value: Any) -> str:
    """The message of a failed keyword, from the schema's ``title`` (what the value is) and ``x-hint``."""
    kind, expected = error.validator, error.validator_value
    title = schema.get("title")
    hint = f"; {schema['x-hint']}" if "x-hint" in schema else ""
    if kind in ("oneOf", "anyOf"):
        return f"expected {title or 'one of the forms the schema allows'}, got {describe(value)}{hint}"
    if kind == "type":
        types = expected if isinstance(expected, list) else [expected]
        wanted = title or " or ".join(_TYPES.get(t, t) for t in types)
        return f"expected {wanted}, got {describe(value)}{hint}"
    if kind in ("minItems", "maxItems"):
        items = f"{len(value)} item{'' if len(value) == 1 else 's'}"
        if title:
            return f"expected {title}, got {items}{hint}"
        bound = "at least" if kind == "minItems" else "at most"
        return f"expected {bound} {expected} item{'' if expected == 1 else 's'}, got {len(value) or 'none'}{hint}"
    if kind == "enum":
        return f"unknown {title or 'value'} {value!r}{suggest(value, expected)}; use one of {', '.join(expected)}"
    if kind == "pattern":
        return f"unknown {title or 'value'} {value!r}" + (hint or f"; it must match {expected}")
    if kind == "const":
        return f"expected {expected!r}, got {describe(value)}{hint}"
    if kind == "minimum":
        return f"must be >= {expected}, got {value!r}{hint}"
    if kind == "minLength":
        return f"expected a non-empty string{hint}" if expected == 1 else \
            f"expected at least {expected} characters, got {value!r}{hint}"
    if kind == "uniqueItems":
        twice = next(item for k, item in enumerate(value) if item in value[:k])
        return f"{twice!r} is listed twice in {value}; list it once"
    return error.message + hint  # a keyword this schema does not use yet: jsonschema's own words
