"""The habits file (``aplan habits LOG... -o habits.json``; docs/habits.md): JSON, read strictly, written atomically.

    {"format": "aplan-habits", "version": 1, "product": "Bourjault ballpoint pen",
     "fingerprint": "3f0c...", "prior": 1.0, "sessions": 20,
     "counts": [{"state": "{ink} {cartridge} {head} {body} {cap} {button}",
                 "operation": "{ink} + {cartridge}", "count": 16}, ...]}

``product`` and ``fingerprint`` (:func:`~planner.decision.habits.state_graph_fingerprint`) name the plan the
counts belong to; ``prior`` is alpha (finite, above 0); ``prior_per`` what alpha counts, ``"edge"`` (per next
operation) or ``"state"`` (in all per state; :mod:`~planner.decision.habits`): a file of version 1 has no
``prior_per`` or ``"edge"`` (the files written before the choice existed read as they did), a file with
``"state"`` is written as version 2 so that an older planner refuses it instead of reading alpha per edge;
``sessions`` the logs counted (for the reader; never
used in the model); ``counts`` the state edges counted at least once, each a state and an operation as
``aplan stats``/``intentions`` write them and a finite count of at least 0. Whether the keys are state edges of
the product is checked when the habits are used (:func:`~planner.decision.habits.edge_counts`).

Version 3 adds the recorded *orders* (whole sequences, :mod:`~planner.decision.orders`) and their Pitman-Yor
parameters; a file with orders is written as version 3 so that an older planner refuses it:

    {..., "version": 3, "concentration": 1.0, "discount": 0.5, "prior_model": "counts",
     "orders": [{"count": 16, "steps": [{"state": "...", "operation": "{ink} + {cartridge}"}, ...]}, ...]}

``prior_model`` is what the model uses, ``"counts"`` (per state) or ``"orders"`` (``--model orders`` sets it;
a session log's copy records it for replay). Whether each order is a whole path of the product's state graph is
checked when the habits are used (:func:`~planner.decision.orders.order_edges`).
"""
from __future__ import annotations

import json
import os
from pathlib import Path

from ...defaults import HABITS_FORMAT, HABITS_VERSION
from ...files import write_atomic
from ...validation import InputError, InputLimits, json_loads
from ..habits import Habits, HabitsError, check_prior, check_prior_per
from ..orders import PRIOR_MODELS, check_orders_parameters

__all__ = ["read_habits", "write_habits", "habits_to_dict", "habits_from_dict"]

_REWRITE = "write it again with aplan habits LOG... -o FILE"
_STATE_PRIOR_VERSION = 2  # the first version that may spread alpha per state (module docstring)
_ORDERS_VERSION = 3  # the first version that may hold recorded orders
_VERSIONS = (HABITS_VERSION, _STATE_PRIOR_VERSION, _ORDERS_VERSION)


def habits_to_dict(habits: Habits, sessions: int | None = None) -> dict:
    """The file's content (module docstring)."""
    version = HABITS_VERSION if habits.prior_per == "edge" else _STATE_PRIOR_VERSION
    out = {"format": HABITS_FORMAT, "version": version, "product": habits.product,
           "fingerprint": habits.fingerprint, "prior": habits.prior, "prior_per": habits.prior_per,
           "sessions": sessions,
           "counts": [{"state": s, "operation": o, "count": _number(c)} for s, o, c in habits.counts]}
    if habits.orders or habits.prior_model != "counts":
        out.update(version=_ORDERS_VERSION, concentration=habits.concentration, discount=habits.discount,
                   prior_model=habits.prior_model,
                   orders=[{"count": _number(n), "steps": [{"state": s, "operation": o} for s, o in steps]}
                           for steps, n in habits.orders])
    return out


def _number(c: float):
    return int(c) if float(c).is_integer() else c


def _orders(data: dict, source: str) -> tuple:
    """The ``orders`` of a version-3 file, each entry's shape and count checked (module docstring)."""
    orders = data.get("orders", [])
    if not isinstance(orders, list):
        raise HabitsError(f"{source}: \"orders\" must be a list of {{count, steps}}; {_REWRITE}")
    out = []
    for k, entry in enumerate(orders):
        where = f"{source}: orders[{k}]"
        steps = entry.get("steps") if isinstance(entry, dict) else None
        if not isinstance(steps, list) or not steps or "count" not in entry or not all(
                isinstance(s, dict) and isinstance(s.get("state"), str) and isinstance(s.get("operation"), str)
                for s in steps):
            raise HabitsError(f"{where}: must be an object with a \"count\" and \"steps\", a non-empty list of "
                              f"{{state, operation}} (text); fix the entry or {_REWRITE}")
        count = _count(entry["count"], where)
        if count <= 0:
            raise HabitsError(f"{where}: count {entry['count']!r} is not above 0; remove the entry or {_REWRITE}")
        out.append((tuple((s["state"], s["operation"]) for s in steps), count))
    return tuple(out)


def _count(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != value or value in (
            float("inf"), float("-inf")) or value < 0:
        raise HabitsError(f"{where}: count {value!r} is not a finite number of at least 0; fix the entry or "
                          + _REWRITE)
    return float(value)


def habits_from_dict(data, source: str) -> Habits:
    """:class:`Habits` from the file's content, every field checked (module docstring); a
    :class:`HabitsError` names ``source``, the place and the fix."""
    if not isinstance(data, dict) or data.get("format") != HABITS_FORMAT:
        raise HabitsError(f"{source}: not a habits file (no \"format\": \"{HABITS_FORMAT}\"); {_REWRITE}")
    version = data.get("version")
    if isinstance(version, bool) or version not in _VERSIONS:
        raise HabitsError(f"{source}: habits file version {version!r}; this planner reads versions "
                          f"{', '.join(map(str, _VERSIONS))}; {_REWRITE}")
    for key in ("product", "fingerprint"):
        if not isinstance(data.get(key), str) or not data[key]:
            raise HabitsError(f"{source}: \"{key}\" must be a non-empty string; {_REWRITE}")
    prior = check_prior(data.get("prior"), f"{source}: prior")
    prior_per = check_prior_per(data.get("prior_per", "edge"), source)
    if prior_per == "state" and version == HABITS_VERSION:
        raise HabitsError(f"{source}: \"prior_per\": \"state\" needs version {_STATE_PRIOR_VERSION}; {_REWRITE}")
    counts = data.get("counts")
    if not isinstance(counts, list):
        raise HabitsError(f"{source}: \"counts\" must be a list of {{state, operation, count}}; {_REWRITE}")
    if not counts:
        raise HabitsError(f"{source}: the file holds no counts (it would be the paper's model); learn habits from "
                          "session logs that record operations, or leave out --habits")
    out = []
    for k, entry in enumerate(counts):
        where = f"{source}: counts[{k}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("state"), str) or \
                not isinstance(entry.get("operation"), str) or "count" not in entry:
            raise HabitsError(f"{where}: must be an object with a \"state\" and an \"operation\" (text) and a "
                              f"\"count\"; fix the entry or {_REWRITE}")
        out.append((entry["state"], entry["operation"], _count(entry["count"], where)))
    if version != _ORDERS_VERSION:
        if any(key in data for key in ("orders", "concentration", "discount", "prior_model")):
            raise HabitsError(f"{source}: recorded orders and their parameters need version {_ORDERS_VERSION}; "
                              + _REWRITE)
        return Habits(data["product"], data["fingerprint"], prior, tuple(out), source, prior_per)
    concentration, discount = check_orders_parameters(data.get("concentration"), data.get("discount"), source)
    prior_model = data.get("prior_model", "counts")
    if prior_model not in PRIOR_MODELS:
        raise HabitsError(f"{source}: \"prior_model\" must be \"counts\" or \"orders\", got {prior_model!r}")
    return Habits(data["product"], data["fingerprint"], prior, tuple(out), source, prior_per, _orders(data, source),
                  concentration, discount, prior_model)


def read_habits(path: str | os.PathLike, limits: InputLimits = InputLimits()) -> Habits:
    """The habits in the file at ``path``, checked (:func:`habits_from_dict`); within ``limits``' bytes and
    nesting. Raises :class:`HabitsError` naming the file and the fix."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > limits.file_bytes:
            raise HabitsError(f"{path}: {size:,} bytes, more than the limit of {limits.file_bytes:,} for a habits "
                              "file; is it the right file?")
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise HabitsError(f"{path}: cannot read the habits file: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise HabitsError(f"{path}: not a habits file (not UTF-8 text); {_REWRITE}") from None
    if not text.strip():
        raise HabitsError(f"{path}: the habits file is empty; {_REWRITE}")
    try:
        data = json_loads(text, str(path), limits.json_depth)
    except json.JSONDecodeError as exc:
        raise HabitsError(f"{path}: not JSON ({exc.msg} at line {exc.lineno}); {_REWRITE}") from None
    except InputError as exc:  # NaN, infinity, nested too deep
        raise HabitsError(f"{exc}; {_REWRITE}") from None
    return habits_from_dict(data, str(path))


def write_habits(path: str | os.PathLike, habits: Habits, sessions: int | None = None) -> None:
    """Write ``habits`` to ``path`` atomically (nothing is left behind on a failure)."""
    write_atomic(path, json.dumps(habits_to_dict(habits, sessions), indent=1, allow_nan=False) + "\n")
