"""The session log (JSON lines) and its replay.

Format, version :data:`LOG_VERSION`: one JSON object per line, each with ``event`` and ``time`` (Unix
seconds, to the millisecond):

- ``start``: ``version``, ``product`` (the product itself, in the product file format), ``settings``
  (``base_part``: the part the model's sequences start from, or null; ``habits``: the operator habits the model
  used, as the habits file holds them, or null; ``parallel``: the parallel model (true, "projected" or "joins"),
  docs/parallel.md; ``deviations``: ``{"switch": P, "mistake": Q}`` or null, docs/deviations.md; ``observe``:
  "state" or "step", docs/camera.md, absent in older logs: "state"; replay
  rebuilds the same model),
  ``n_intentions``, ``actions`` and ``observations`` (the model's names), ``top``;
- per step: ``action`` (``step``, ``action``, ``name``, ``instruction``, ``decision_ms``: the milliseconds the
  policy took to choose it; for an action named by a join, ``join``: its two parts ``[P, Q]``, ``operation``:
  the AND/OR operation reported, the join's at the belief's most probable assembly state where it applies, and
  ``same_motion``: whether it is the join's operation at every state of the belief where it applies; replay
  recomputes the operation), ``robot`` (``step``, ``ok``,
  ``message``), ``observation`` (``step``, ``observation``, ``index``: null when no operation of the product
  shows it, ``ignored``: true when no operation explains it in the assembly state, so the belief was updated
  with the blank observation),
  any ``warning`` (``step``, ``message``); instead of ``observation`` when a piece came apart (a step undone,
  docs/deviations.md), ``apart`` (``step``, ``parts``, ``moves``: ``[[state before, state after], ...]``) or
  ``unrecoverable`` (``step``, ``parts``, ``message``: the line shown to the person; the end event follows);
  ``belief`` (``step``, ``top``, ``p_finished``, ``operations``,
  ``reset``: null, or how an observation of probability 0 reset the belief);
- ``end``: ``step``, ``reason``, ``message``, ``operations``, ``top``.

``top``: the five most probable intentions, ``[[intention, probability], ...]``, probabilities rounded to
6 digits; on the factored model (``belief_over``: ``classes`` in the start event; the online planner or a
policy over classes) the five most probable classes instead (class ``c`` < the number of state edges: the
world is at state edge ``c``'s source and the operator's next step is that edge; the last class: finished). Each line is written with one ``write``, then flushed and fsynced, so a crash loses at most the line
being written; :func:`replay` ignores such a cut last line.
"""
from __future__ import annotations

import errno
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..assembly.tags import BLANK
from ..decision.factored_model import FactoredIntentionModel, factored_model
from ..decision.intention_model import IntentionModel, intention_model
from ..decision.models import BELIEF_OVER, belief_at, top_intentions, updater_for
from ..decision.step_observations import OBSERVE, STATE
from ..errors import PlannerError
from ..files import with_faults
from ..product import Product, product_from_dict
from ..validation import INPUT_OPTION, InputError, InputLimits, json_loads, not_regular

# top_intentions, belief_at and updater_for live in planner.decision.models; still importable from here
__all__ = ["LOG_VERSION", "SessionError", "EventLog", "top_intentions", "belief_at", "updater_for", "Replay", "read_log", "replay"]

LOG_VERSION = 1


class SessionError(PlannerError):
    """A session cannot start or go on: a log that cannot be written or read, a model that does not fit."""


class EventLog:
    """Session events as JSON lines. Each event is one line written with one ``write``, then flushed and
    fsynced. ``path`` None keeps the events in memory only (``events`` always holds them); ``on_event`` sees
    every event as it is written. A log is never overwritten: an existing ``path`` is an error.

    A write the system refuses (a full disk: ENOSPC, EIO, a quota) is a :class:`SessionError` naming the log;
    the file is cut back to the last complete event, so ``aplan replay`` reads every event before it, and every
    later write raises the same error (the session stops; its end cannot be logged)."""

    def __init__(self, path: str | os.PathLike | None = None, on_event: Callable[[dict], None] | None = None):
        self.path = Path(path) if path is not None else None
        self.events: list[dict] = []
        self.on_event = on_event
        self._handle = None
        self._complete = 0  # bytes of the complete events written
        self._failure: str | None = None  # why the log cannot be written any more
        if self.path is not None:
            try:
                # unbuffered: what the disk refused is never written later by a flush, and the cut below holds
                self._handle = with_faults(open(self.path, "xb", buffering=0))
            except FileExistsError:
                raise SessionError(f"{self.path}: the log exists already; choose another file name "
                                   "(a log is never overwritten)") from None
            except OSError as exc:
                raise SessionError(f"{self.path}: cannot create the log: {exc}") from None

    def write(self, event: str, **fields) -> dict:
        """Append the event ``event`` with ``fields`` (and the time); returns the record."""
        record = {"event": event, "time": round(time.time(), 3), **fields}
        self.events.append(record)
        if self._failure is not None:
            raise SessionError(self._failure)
        if self._handle is not None:
            line = memoryview((json.dumps(record) + "\n").encode("utf-8"))
            size = len(line)
            try:
                while line:  # an unbuffered write may take part of it
                    line = line[self._handle.write(line):]
                os.fsync(self._handle.fileno())
            except OSError as exc:
                raise SessionError(self._fail(exc)) from None
            self._complete += size
        if self.on_event is not None:
            self.on_event(record)
        return record

    def _fail(self, exc: OSError) -> str:
        """Cut the file back to its complete events, close it, and say why it failed (kept for later writes)."""
        handle, self._handle = self._handle, None
        try:
            handle.truncate(self._complete)  # drop a partial line (a full disk leaves part of the write)
        except OSError:
            pass  # the file system refuses that too: replay drops a last line cut short anyway
        try:
            handle.close()
        except OSError:
            pass  # the file is gone bad: nothing is buffered (unbuffered), so nothing is lost here
        fix = "free some space on that disk or log to another (--log FILE)" if exc.errno in (
            errno.ENOSPC, errno.EDQUOT) else "check the disk, or log to another (--log FILE)"
        kept = len(self.events) - 1  # the events before the one that failed
        self._failure = (f"{self.path}: cannot write the session log ({exc.strerror or exc}); the session stopped. "
                         f"The log keeps the {kept} event{'s' if kept != 1 else ''} before, which aplan replay "
                         f"reads; {fix}")
        return self._failure

    def close(self) -> None:
        if self._handle is not None:
            try:
                self._handle.close()
            except OSError as exc:  # a file system that reports a failure only at close (e.g. NFS)
                self._fail(exc)
            self._handle = None


@dataclass
class Replay:
    """A session log replayed: the product, the beliefs recomputed from its actions and observations (the
    initial one first), the steps whose logged belief differs from the recomputed one, and the steps whose
    observation the session ignored (counted as blank: ``observations`` holds the blank one there);
    ``reported``: the steps of actions named by joins whose logged operation (the one reported and drawn) is
    not the one the recomputed belief gives."""

    product: Product
    model: IntentionModel | FactoredIntentionModel
    actions: list[int]
    observations: list[int]
    beliefs: list[np.ndarray]
    end: dict | None
    mismatches: list[int]
    events: list[dict]
    ignored: dict[int, str] = field(default_factory=dict)  # step (from 1) -> the observation counted as blank
    undone: dict[int, str] = field(default_factory=dict)  # step (from 1) -> the piece that came apart
    unrecoverable: str | None = None  # the message of a step the product could not recover from
    reported: list[int] = field(default_factory=list)  # steps whose logged join operation differs (recomputed)


def read_log(path: str | os.PathLike, limits: InputLimits = InputLimits()) -> list[dict]:
    """The events of the session log at ``path``, checked to be a log of this version; a last line cut
    short (the one being written when the session died) is dropped. ``limits``: the file's bytes and the
    JSON nesting at most. Raises :class:`SessionError`."""
    path = Path(path)
    if not_regular(path, "session log"):
        raise SessionError(not_regular(path, "session log"))
    try:
        if path.stat().st_size > limits.file_bytes:
            raise SessionError(f"{path}: {path.stat().st_size:,} bytes, more than the limit of "
                               f"{limits.file_bytes:,} for a session log ({INPUT_OPTION} raises it)")
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise SessionError(f"{path}: cannot read the log: {exc}") from None
    except UnicodeDecodeError:
        raise SessionError(f"{path}: not a session log (not UTF-8 text: a binary file?)") from None
    events = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            event = json_loads(line, f"{path}: line {number}", limits.json_depth)
        except json.JSONDecodeError as exc:
            if number == len(lines):  # the line being written when the session died
                break
            raise SessionError(f"{path}: line {number}: not JSON ({exc.msg}); the log is damaged") from None
        except InputError as exc:  # nested too deep, a number that is not finite
            raise SessionError(f"{exc}; the log is damaged") from None
        if not isinstance(event, dict) or "event" not in event:
            raise SessionError(f"{path}: line {number}: not a session event")
        events.append(event)
    if not events or events[0]["event"] != "start":
        raise SessionError(f"{path}: not a session log (it must start with a 'start' event)")
    if events[0].get("version") != LOG_VERSION:
        raise SessionError(f"{path}: log version {events[0].get('version')!r}; this planner reads version "
                           f"{LOG_VERSION}")
    return events


def _habit_weights(path: Path, plan, recorded) -> tuple:
    """``(edge weights, orders)`` of the operator habits a session's model used (its start event's
    ``settings.habits``: the habits file's content, with the prior model it used), or ``(None, None)`` (the
    paper's model)."""
    from ..decision.io.habits_file import habits_from_dict
    from ..decision.orders import prior_inputs

    if recorded is None:
        return None, None
    return prior_inputs(plan, habits_from_dict(recorded, f"{path} (start event, settings.habits)"))


def _deviations(path: Path, recorded):
    """The change of mind and mistakes a session's model used (``settings.deviations``), or None."""
    from ..decision.deviations import deviations_of

    if recorded is None:
        return None
    if not isinstance(recorded, dict) or set(recorded) != {"switch", "mistake"}:
        raise SessionError(f"{path}: the start event's deviations {recorded!r} are not {{'switch': P, 'mistake': Q}}; "
                           "the log is damaged")
    try:
        return deviations_of(recorded["switch"], recorded["mistake"])
    except PlannerError as exc:
        raise SessionError(f"{path}: the start event's deviations: {exc}; the log is damaged") from None


def _model_of(path: Path, start: dict) -> tuple[Product, IntentionModel | FactoredIntentionModel]:
    """The product stored in the start event and its decision model (flat, or factored when the session's
    beliefs were over classes), checked against the logged names."""
    from ..assembly.plan import make_plan

    if not isinstance(start.get("product"), dict):
        raise SessionError(f"{path}: the start event has no 'product' (an object); the log is damaged or was not "
                           "written by aplan session")
    product = product_from_dict(start["product"], f"{path} (start event)")
    settings = start.get("settings") if isinstance(start.get("settings"), dict) else {}
    base_part = settings.get("base_part")  # the part resolved at the start, never "auto"
    if base_part is not None and not isinstance(base_part, str):
        raise SessionError(f"{path}: the start event's base part {base_part!r} is not a part name; the log is damaged")
    plan = make_plan(product)
    weights, orders = _habit_weights(path, plan, settings.get("habits"))
    parallel = settings.get("parallel", False)  # logs before the parallel model have none: the paper's
    if not (isinstance(parallel, bool) or parallel in ("projected", "joins")):
        raise SessionError(f"{path}: the start event's 'parallel' setting {parallel!r} is not true, false, "
                           "\"projected\" or \"joins\"; the log is damaged")
    deviations = _deviations(path, settings.get("deviations"))
    observe = settings.get("observe", STATE)  # logs before observations of the step have none: the paper's
    if observe not in OBSERVE:
        raise SessionError(f"{path}: the start event's 'observe' setting {observe!r} is not one of "
                           f"{', '.join(OBSERVE)}; the log is damaged")
    model = (factored_model(plan, base_part=base_part, weights=weights, parallel=parallel, deviations=deviations,
                            orders=orders, observe=observe)
             if start.get("belief_over") == BELIEF_OVER["factored"]
             else intention_model(plan, base_part=base_part, weights=weights, deviations=deviations, orders=orders))
    if list(model.observations) != start.get("observations") or list(model.actions) != start.get("actions"):
        raise SessionError(f"{path}: the product in the log no longer gives the logged actions and observations "
                           "(the log was written by another planner version)")
    return product, model


def _in_the_log(event) -> None:
    """A reset met again while replaying: the session logged it as a warning event already."""


def replay(path: str | os.PathLike, tolerance: float = 1e-6, limits: InputLimits = InputLimits()) -> Replay:
    """Recompute the beliefs of the session logged at ``path`` (the product is stored in the log).

    Beliefs depend on the model's transitions and observations only, not on rewards or the policy. A logged
    belief whose top intentions differ from the recomputed ones by more than ``tolerance`` is a mismatch.
    Cost: one model build and one belief update per step. Raises :class:`SessionError` for a file that is
    not a session log; ``limits``: :func:`read_log`'s.
    """
    path = Path(path)
    events = read_log(path, limits)
    product, model = _model_of(path, events[0])
    updater = updater_for(model, on_reset=_in_the_log)
    belief = updater.initialize()
    done = Replay(product, model, [], [], [belief], None, [], events)
    blank = model.plan.observations.index(BLANK)
    pending: dict[int, int] = {}  # step -> the action logged for it
    for number, event in enumerate(events[1:], start=2):
        kind = event["event"]
        if done.end is not None:
            raise SessionError(f"{path}: event {number} ({kind!r}) comes after the 'end' event; the log is damaged")
        try:
            if kind == "action":
                pending[event["step"]] = _in_range(int(event["action"]), model.actions, "action")
                if "join" in event and _reported(model, pending[event["step"]], belief) != event["operation"]:
                    done.reported.append(event["step"])
            elif kind == "observation" and (event.get("index") is not None or event.get("ignored") is True):
                action = pending[event["step"]]
                if event.get("ignored") is True:  # no operation explained it: the session counted it as blank
                    observation = blank
                    done.ignored[len(done.actions) + 1] = str(event.get("observation", ""))
                else:
                    observation = _in_range(int(event["index"]), model.observations, "observation")
                belief = updater.update(belief, action, observation)
                done.actions.append(action)
                done.observations.append(observation)
                done.beliefs.append(belief)
            elif kind == "apart":  # a step undone: the belief moves to the earlier states (runtime/undo.py)
                from .undo import belief_after_apart, predicted

                action = pending[event["step"]]
                moves = [(int(a), int(b)) for a, b in event["moves"]]
                if not moves or any(not 0 <= t < model.plan.states.n_states for _, t in moves):
                    raise ValueError(f"apart moves {event['moves']!r} out of range")
                belief = belief_after_apart(model, predicted(model, updater, belief, action), moves)
                done.undone[len(done.actions) + 1] = "apart " + " ".join(map(str, event.get("parts", [])))
                done.actions.append(action)
                done.observations.append(blank)
                done.beliefs.append(belief)
            elif kind == "unrecoverable":
                done.unrecoverable = str(event["message"])
            elif kind == "belief":
                if any(not abs(belief_at(belief, int(i)) - float(p)) <= tolerance for i, p in event["top"]):
                    done.mismatches.append(event["step"])  # a NaN is a mismatch too
            elif kind == "end":
                done.end = {"reason": str(event.get("reason", "")), "message": str(event.get("message", "")),
                            **{k: v for k, v in event.items() if k not in ("reason", "message")}}
        except (KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
            detail = str(exc) if type(exc) is ValueError and "out of range" in str(exc) else repr(exc)
            raise SessionError(f"{path}: event {number} ({kind!r}): malformed or out of order ({detail}); "
                               "the log is damaged") from None
    return done


def _reported(model, action: int, belief) -> int | None:
    """The operation a session reports for the join ``action`` at ``belief`` (the belief's most probable state
    where it applies: :func:`~planner.runtime.interfaces.instruction_for`)."""
    from .interfaces import instruction_for

    return instruction_for(model, action, 0, belief).operation


def _in_range(index: int, names, what: str) -> int:
    """``index`` if it numbers one of ``names`` (from 0), else a ``ValueError`` (a damaged log): a negative
    index would otherwise wrap around to the last names."""
    if not 0 <= index < len(names):
        raise ValueError(f"{what} {index} out of range: the model has {len(names)} {what}s, numbered from 0")
    return index
