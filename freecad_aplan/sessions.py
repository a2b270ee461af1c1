"""Levels, the model choice and simulated sessions of the workbench, as plain functions (no FreeCAD, no Qt).

The workbench runs what the command line runs, so these only pick arguments and read results:

- :func:`level_choices`: the workstations of a product (:func:`planner.api.levels_of`), bottom-up, as the
  level selector lists them; one entry, the product itself, for a product planned flat;
- :func:`model_choice`: the decision model Export model and Solve build: the flat model of Alg. 3 where it fits
  (the intention limit and the memory budget, :func:`~planner.decision.intention_model.flat_model_fits`: the
  test the command line's planner choice makes), else the lumped model over the factored model's classes,
  whose policy the online planner and the offline one follow (``aplan pomdp/solve --lumped``);
  :func:`level_model` builds it;
- :func:`session_arguments` and :func:`run_simulated_session`: ``aplan session PRODUCT --demo K`` (the
  simulated camera cell: an operator following full sequence K on a rendered tray, seen through the vision
  pipeline) on one level or on every level bottom-up, run in-process through :func:`planner.cli.main`, then
  ``aplan replay LOG --plot STEM`` for each level's belief plot; or the operator's picks typed in
  (``--keyboard``), read from standard input. A background job (``batch.py session``) runs it, its output
  lines being the job's progress, the panel writing the picks to its input;
- :func:`offered_picks` and :func:`typed_pick`: the keyboard's prompt as the panel shows it (the picks the
  operator could make now, each as the line that types it);
- operator habits (issue 23, docs/habits.md): :func:`model_names` and :func:`model_label`, the named models
  (``--model``, :data:`planner.api.MODEL_PRESETS`: a preset added there is offered without a change here);
  :func:`check_habits`, what the panel checks before it starts a session with ``--habits FILE --model NAME``
  (through :func:`planner.api.session_habits`, as the session reads them); :func:`habits_path` and
  :func:`learn_session_habits`, ``aplan habits LOG...`` (:func:`planner.api.learn_habits`) on the panel's
  session logs, into a file beside the document.
"""
from __future__ import annotations

import contextlib
import io
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from planner.errors import PlannerError

__all__ = ["LevelChoice", "ModelChoice", "level_choices", "level_of", "member_parts", "base_part_in", "model_choice",
           "level_model", "session_arguments", "run_simulated_session", "offered_picks", "typed_pick",
           "is_prompt", "ALL_LEVELS", "SOURCES", "model_names", "model_label", "check_habits", "habits_path", "DEFAULT_MODEL",
           "learn_session_habits"]

#: The level selector's entry for "every level, bottom-up" (the command line without ``--level``).
ALL_LEVELS = "all levels"
#: The model choice's first entry: no ``--model``, as the command line without it.
DEFAULT_MODEL = "default: habits with a file, else paper"


@dataclass(frozen=True)
class LevelChoice:
    """One workstation in the level selector: ``id`` (a subassembly id or ``top``; None for a product planned
    flat), ``members`` (the level's parts and the subassemblies it joins), ``label`` (what the selector shows)."""

    id: str | None
    members: tuple[str, ...]

    @property
    def label(self) -> str:
        name = self.id if self.id is not None else "the product (flat)"
        return f"{name}: {len(self.members)} members"


@dataclass(frozen=True)
class ModelChoice:
    """The decision model of one level: ``kind`` ``flat`` (Alg. 3's model over intentions) or ``lumped`` (over
    the factored model's classes), ``intentions`` the level's count of intentions, ``note`` why."""

    kind: str
    intentions: int
    note: str


def level_choices(product) -> list[LevelChoice]:
    """The levels of ``product`` (a resolved :class:`~planner.product.Product`, its subassemblies as the
    designer stored them), bottom-up as :func:`planner.api.levels_of` gives them; a product planned flat is one
    entry with ``id`` None. Cost: that of ``levels_of`` (linear in levels x relations)."""
    from planner import api

    levels = api.levels_of(product)
    if len(levels) == 1:
        return [LevelChoice(None, tuple(levels[0].members))]
    return [LevelChoice(level.id, tuple(level.members)) for level in levels]


def level_of(product, level: str | None):
    """The product level ``level`` plans (:func:`planner.api.level_product`; ``None``: the product itself,
    which must then be planned flat, else a :class:`~planner.errors.PlannerError` names the levels)."""
    from planner import api

    return api.level_product(product, "designer", level)


def member_parts(product, level: str | None) -> dict[str, tuple[str, ...]]:
    """Member of the level ``level`` of ``product`` (None: the product planned flat) -> the product's parts it
    stands for: a part itself, a subassembly the parts it holds (what Plan in 3D moves as one block). Cost:
    that of :func:`planner.api.levels_of`."""
    from planner import api

    levels = {lv.id: lv for lv in api.levels_of(product)}
    here = level_of(product, level)
    return {m: tuple(sorted(levels[m].parts)) if m in levels and m != level else (m,) for m in here.part_ids}


def base_part_in(level_product, base_part: str | None) -> str | None:
    """The base part a level's plan starts from: ``base_part`` when the level holds it (or ``auto``: the level's
    most connected part), else None (the designer's base part sits in another workstation). Cost: O(parts)."""
    return base_part if base_part in ("auto", *level_product.part_ids) else None


def model_choice(product, technical: bool | None = None, base_part: str | None = None, limits=None) -> ModelChoice:
    """The model the workbench builds for ``product`` (one level): ``flat`` when the flat model fits the
    intention limit and the memory budget ``limits`` (:class:`~planner.assembly.guards.SizeLimits`, default
    the machine's), else ``lumped``. Cost: one plan and one count of intentions (no model is built)."""
    from planner import api
    from planner.assembly.guards import SizeLimits
    from planner.assembly.intentions import count_intentions
    from planner.decision.intention_model import flat_model_fits

    limits = limits or SizeLimits()
    plan = api.plan_of(product, technical)
    base = api.base_part_of(plan, base_part)
    intentions = count_intentions(plan.states, base_part=base)
    if flat_model_fits(plan, limits.memory, intentions=intentions):
        return ModelChoice("flat", intentions, f"the flat model: {intentions:,} intentions")
    return ModelChoice("lumped", intentions, f"the flat model would hold {intentions:,} intentions, more than fits: "
                                             "the lumped model over the factored model's classes")


def level_model(product, level: str | None = None, technical: bool | None = None, base_part: str | None = None):
    """The decision model Export model and Solve build for level ``level`` of ``product`` (a resolved product or
    a product file; None: the product planned flat), as :func:`model_choice` says: the flat model
    (:func:`planner.api.decision_model`) or the lumped one (``api.load_model(..., lumped=True)``, as ``aplan
    pomdp/solve --lumped``). Returns ``(model, choice)``. Cost: that of building the model."""
    from planner import api

    level_product = level_of(product if isinstance(product, api.Product) else api.resolve_product(product), level)
    base_part = base_part_in(level_product, base_part) if level is not None else base_part
    choice = model_choice(level_product, technical, base_part)
    return api.load_model(level_product, technical, base_part=base_part, lumped=choice.kind == "lumped"), choice


#: Where a session's observations come from: the simulated camera cell, or the operator's picks typed in.
SOURCES = ("demo", "keyboard")


def offered_picks(line: str) -> list[str] | None:
    """The picks the keyboard offers in ``line`` (an output line of a keyboard session: ``the operator could
    pick now: body+button+[hammer], cartridge+ink+[hammer]``, :data:`planner.runtime.console.COULD_PICK`), as
    observations in text; ``[]`` when nothing that shows can be picked; None for any other line. Cost: O(len)."""
    from planner.runtime.console import COULD_PICK

    text, head = line.strip(), COULD_PICK.strip()
    if not text.startswith(head):
        return None
    listed = text[len(head):].strip()
    return [] if listed.startswith("nothing") else [pick.strip() for pick in listed.split(", ") if pick.strip()]


def typed_pick(pick: str) -> str:
    """The line that types ``pick`` (an observation as text, ``cartridge+ink+[hammer]``) at the keyboard:
    ``cartridge ink hammer``; the blank observation (``blank``, or nothing) is the empty line."""
    if pick.strip() in ("", "blank"):
        return ""
    return " ".join(name.strip("[]") for name in pick.split("+"))


def is_prompt(line: str) -> bool:
    """Whether ``line`` is the keyboard's prompt (the session waits for the operator's picks)."""
    from planner.runtime.console import PROMPT

    return line.startswith(PROMPT.split("(")[0])


def session_arguments(product_file: str, log: str, level: str | None = None, sequence: int = 0,
                      expansions: int | None = None, max_steps: int | None = None,
                      base_part: str | None = None, source: str = "demo", habits: str | None = None,
                      model: str | None = None) -> list[str]:
    """The ``aplan session`` arguments of a session of ``product_file``: ``source`` ``demo``, the simulated
    camera cell (``--demo sequence``), or ``keyboard``, the operator's picks typed in one line a step on
    standard input, the robot's instructions confirmed at once (``--keyboard --robot auto``); ``level`` None or
    :data:`ALL_LEVELS`: every level bottom-up, each with its log ``LOG-<level>.jsonl``. With ``expansions`` the
    online planner does that many expansions per decision and nothing else (no clock: the same decisions on
    any machine); without, the command line's decision time. ``habits`` (a habits file) and ``model`` (a name of
    :func:`model_names`; None: the command line's default) are ``--habits FILE`` and ``--model NAME``."""
    if source not in SOURCES:
        raise PlannerError(f"unknown session source {source!r}; use one of {', '.join(SOURCES)}")
    if not (isinstance(sequence, int) and sequence >= 0):
        raise PlannerError(f"sequence {sequence!r}: a full sequence is a number from 0")
    if model is not None and model not in model_names():
        raise PlannerError(f"unknown model {model!r}; use one of {', '.join(model_names())}")
    picked = ["--demo", str(sequence)] if source == "demo" else ["--keyboard", "--robot", "auto"]
    arguments = ["session", str(product_file), *picked, "--log", str(log)]
    if level not in (None, ALL_LEVELS):
        arguments += ["--level", level]
    if expansions is not None:
        arguments += ["--expansions", str(int(expansions))]
    if max_steps is not None:
        arguments += ["--max-steps", str(int(max_steps))]
    if base_part:
        arguments += ["--base-part", base_part]
    if habits:
        arguments += ["--habits", str(habits)]
    if model is not None:
        arguments += ["--model", model]
    return arguments


def model_names() -> tuple[str, ...]:
    """The named models a session can run (``aplan session --model NAME``), as the planner defines them
    (:data:`planner.api.MODEL_PRESETS`), in its order."""
    from planner import api

    return tuple(api.MODEL_PRESETS)


def model_label(name: str) -> str:
    """What the model choice shows for the named model ``name``, from the preset's own fields: whether it needs
    habits, the habits' prior it uses, the act confidence it sets, the model of help before the last step it
    switches on and its observations when they are not the paper's (so a new preset is described too)."""
    from planner import api
    from planner.decision.parallel import parallel_flag
    from planner.decision.step_observations import STATE

    preset = api.MODEL_PRESETS[name]
    if not preset.habits:
        return f"{name}: the paper's model (no habits)"
    if preset.orders:
        prior = "the recorded orders"
    else:
        prior = "the file's prior" if preset.prior is None else f"prior {preset.prior:g} per {preset.prior_per}"
    acts = "" if preset.act_confidence is None else f", acts at {preset.act_confidence:g}"
    helps = "" if not preset.parallel else f", helps early ({parallel_flag(preset.parallel)})"
    sees = "" if preset.observe == STATE else f", sees each {preset.observe} (--observe {preset.observe})"
    return f"{name}: habits, {prior}{acts}{helps}{sees}"


def _session_product(product_file: str, level: str | None):
    """The product a session of ``level`` plans, as ``aplan session PRODUCT_FILE [--level LEVEL]`` resolves it."""
    from planner import api

    resolved = api.resolve_product(product_file, fasteners=api.DEFAULT_MODE, subassemblies=api.DEFAULT_MODE)
    if level in (None, ALL_LEVELS):
        levels = api.levels_of(resolved)
        if len(levels) > 1:
            return None
        return api.level_product(resolved)
    return api.level_product(resolved, "designer", level)


def check_habits(product_file: str, level: str | None, habits: str | None, model: str | None):
    """What a session with ``--habits habits --model model`` on ``level`` of ``product_file`` checks before it
    starts, checked before the panel starts one: the file read through the planner's reader and checked against
    the level's plan (:func:`planner.api.session_habits`: another product or version, a damaged file), a model
    that needs habits without a file, habits on every level at once (habits are of one workstation's plan).
    Returns the habits (None: the model uses none); raises :class:`~planner.errors.PlannerError` with the
    message to show. Cost: without ``habits`` none; with, reading the file and one plan of the level."""
    from planner import api

    habits = habits or None
    if habits is None:  # nothing to read: only whether the model needs habits (the product is not planned)
        return api.habits_for(model, None)
    product = _session_product(product_file, level)
    if product is not None:
        return api.session_habits(product, model, habits)
    if api.habits_for(model, habits) is not None:  # every level at once: one file cannot be of each
        raise PlannerError(f"{habits}: habits are of one workstation's plan; choose a level, not {ALL_LEVELS}")
    return None


def habits_path(document_file: str | None, level: str | None, folder: str) -> str:
    """Where the panel keeps the habits it learns: beside the document (``pen.FCStd`` -> ``pen-habits.json``;
    a level's ``pen-sa1-habits.json``), or in ``folder`` when the document was never saved."""
    stem = Path(document_file).with_suffix("") if document_file else Path(folder) / "product"
    return f"{stem}{'' if level in (None, ALL_LEVELS) else '-' + level}-habits.json"


def learn_session_habits(product_file: str, level: str | None, logs: list[str], output: str) -> dict:
    """``aplan habits LOG... --product LEVEL -o OUTPUT`` (:func:`planner.api.learn_habits`) on the session logs
    ``logs`` of ``level`` of ``product_file``, added to the counts ``output`` holds already (the logs counted
    before stay counted; each log is to be given once), written atomically. Returns ``{"file", "product",
    "steps", "logs", "edges", "added"}`` (``added``: to the counts of a file there before). Raises :class:`~planner.errors.PlannerError` (a log of another
    product version, no step to learn, ``output`` of another product) and writes nothing then. Cost: one replay
    per log."""
    from planner import api

    product = _session_product(product_file, level)
    if product is None:
        raise PlannerError(f"habits are of one workstation's plan; choose a level, not {ALL_LEVELS}")
    before = os.path.isfile(output)
    habits, steps = api.learn_habits(logs, product, add=output if before else None)
    api.write_habits(output, habits, len(logs))
    return {"file": output, "product": habits.product, "steps": steps, "logs": len(logs),
            "edges": len(habits.counts), "added": before}


class _Lines(io.TextIOBase):
    """A text stream that hands each complete line to ``on_line`` (and keeps them all); ``on_line`` runs with
    the streams of before (a progress callback that prints reaches the real output, not this stream)."""

    def __init__(self, on_line: Callable[[str], None] | None) -> None:
        self.on_line, self.lines, self._partial = on_line, [], ""
        self.outer = (sys.stdout, sys.stderr)

    def writable(self) -> bool:
        return True

    def isatty(self) -> bool:  # the session's status lines then end in newlines, one per step
        return False

    def flush(self) -> None:  # a prompt, flushed without its newline (the session waits for a line): a line now
        if self._partial.strip():
            text, self._partial = self._partial, ""
            self.write(text + "\n")

    def write(self, text: str) -> int:
        *done, self._partial = (self._partial + text).replace("\r", "\n").split("\n")
        for line in done:
            if line.strip():
                self.lines.append(line)
                if self.on_line is not None:
                    with contextlib.redirect_stdout(self.outer[0]), contextlib.redirect_stderr(self.outer[1]):
                        self.on_line(line)
        return len(text)


def _aplan(arguments: list[str], progress: Callable[[str], None] | None) -> tuple[int, list[str]]:
    """``aplan ARGUMENTS`` in this process: its exit status and its output lines (stdout and stderr)."""
    from planner.cli import main

    lines = _Lines(progress)
    with contextlib.redirect_stdout(lines), contextlib.redirect_stderr(lines):
        status = main(arguments)
    return status, lines.lines


def _level_logs(log: str, level: str | None, levels: list[str]) -> list[tuple[str | None, str]]:
    """(level, log path) of each level a session ran, as ``aplan session`` names them."""
    if level not in (None, ALL_LEVELS) or len(levels) <= 1:
        return [(None if level in (None, ALL_LEVELS) else level, log)]
    return [(name, str(Path(log).with_suffix("")) + f"-{name}.jsonl") for name in levels]


def run_simulated_session(product_file: str, folder: str, level: str | None = None, sequence: int = 0,
                          expansions: int | None = None, max_steps: int | None = None,
                          base_part: str | None = None, progress: Callable[[str], None] | None = None,
                          source: str = "demo", habits: str | None = None, model: str | None = None) -> dict:
    """Run ``aplan session PRODUCT --demo SEQUENCE`` (:func:`session_arguments`; ``source="keyboard"``: the picks
    read from standard input instead; ``habits``, ``model``: ``--habits FILE --model NAME``) with its logs in
    ``folder``, then ``aplan replay LOG --plot`` for each
    level that ran; ``progress(line)`` gets every output line (the level started, each step's status line,
    what ended it).

    Returns ``{"command", "assembled", "levels": [{"level", "reason", "message", "steps", "log", "plot"}]}``
    (``plot``: the PNG of the belief plot). Raises :class:`~planner.errors.PlannerError` with the command's
    message when it refuses (an unknown level, a sequence out of range). Cost: that of the session (one
    decision per step, each ``expansions`` expansions of the online planner) and one replay per level.
    """
    from planner import api
    from planner.runtime.log import read_log

    os.makedirs(folder, exist_ok=True)
    log = os.path.join(folder, "session.jsonl")
    arguments = session_arguments(product_file, log, level, sequence, expansions, max_steps, base_part, source,
                                  habits, model)
    # the levels as the command line resolves PRODUCT (its --fasteners and --subassemblies defaults)
    resolved = api.resolve_product(product_file, fasteners=api.DEFAULT_MODE, subassemblies=api.DEFAULT_MODE)
    levels = [lv.id for lv in api.levels_of(resolved)]
    status, lines = _aplan(arguments, progress)
    ran = [(name, path) for name, path in _level_logs(log, level, levels) if os.path.isfile(path)]
    if status not in (0, 1) or not ran:  # 1: a session that ended without the product assembled
        errors = [line for line in lines if line.startswith("aplan: error")]
        raise PlannerError((errors[-1] if errors else f"aplan {' '.join(arguments)} ended with status {status}")
                           .removeprefix("aplan: error: "))
    done = []
    for name, path in ran:
        end = next((e for e in reversed(read_log(path)) if e["event"] == "end"), {})
        stem = str(Path(path).with_suffix("")) + "-belief"
        replayed, replay_lines = _aplan(["replay", path, "--plot", stem], None)
        if replayed != 0:
            raise PlannerError(f"aplan replay {path}: " + (replay_lines[-1] if replay_lines else f"status {replayed}"))
        done.append({"level": name, "reason": end.get("reason"), "message": end.get("message"),
                     "steps": end.get("step"), "log": path, "plot": stem + ".png"})
    return {"command": "aplan " + " ".join(arguments), "assembled": all(d["reason"] == "assembled" for d in done),
            "levels": done}
