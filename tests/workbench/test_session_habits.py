"""Operator habits in the workbench's session panel (issue 23), without FreeCAD: the arguments the panel passes
(``--habits FILE --model NAME``, the command line's), the named models it offers (the planner's presets, so a
new one appears without a change to the panel), the check before a session starts (the planner's habits reader
and its product check: each refusal the command line's message) and learning habits from the panel's session
logs (``aplan habits``). Expected counts are closed forms: a session of the pen is its 6 - 1 = 5 operations."""
from __future__ import annotations

import io
import json
import re
import sys
from dataclasses import replace

import pytest

from freecad_aplan.sessions import (
    ALL_LEVELS,
    check_habits,
    habits_path,
    learn_session_habits,
    model_label,
    model_names,
    run_simulated_session,
    session_arguments,
)
from planner import api
from planner.assembly import make_plan
from planner.assembly.explode import sequence_at
from planner.decision.habits import edge_counts
from planner.decision.intention_model import intention_model
from planner.decision.presets import CAMERA, CONFIDENT, HELPFUL, ORDERS, PRESETS, ModelPreset
from planner.errors import PlannerError
from planner.product import Subassembly, save_product
from planner.product.synthetic import chain_product
from planner.runtime.log import EventLog
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
from planner.runtime.session import run_session


class _Wait:
    def __init__(self, model):
        self.wait = len(model.actions) - 1

    def action(self, belief) -> int:
        return self.wait


def _log(product, rank: int, path, max_steps: int = 500) -> None:
    """A session of ``product`` in which the operator assembles full sequence ``rank`` alone (the robot waits),
    stopped after ``max_steps`` steps."""
    model = intention_model(make_plan(product))
    operator = ScriptedOperator(model.plan, sequence_at(model.plan, rank))
    done = run_session(model, _Wait(model), operator, ScriptedRobot(), EventLog(path), max_steps=max_steps)
    assert done.assembled == (max_steps >= len(product.parts) - 1)


@pytest.fixture()
def pen_file(pen, tmp_path):
    path = tmp_path / "product.json"
    save_product(pen, path)
    return str(path)


def test_session_arguments_pass_habits_and_model_as_the_command_line():
    assert session_arguments("p.json", "s.jsonl", source="keyboard", habits="h.json", model="confident") == [
        "session", "p.json", "--keyboard", "--robot", "auto", "--log", "s.jsonl", "--habits", "h.json",
        "--model", "confident"]
    assert session_arguments("p.json", "s.jsonl") == ["session", "p.json", "--demo", "0", "--log", "s.jsonl"]
    with pytest.raises(PlannerError, match="unknown model 'eager'; use one of paper, habits, confident, orders, "
                                           "helpful, camera"):
        session_arguments("p.json", "s.jsonl", model="eager")


def test_the_models_offered_are_the_planners_presets(monkeypatch):
    """The choice lists PRESETS in order, each described by its own fields; a preset added to the planner is
    offered and passed on with no change to the workbench."""
    assert model_names() == tuple(PRESETS)
    assert model_label("paper") == "paper: the paper's model (no habits)"
    assert model_label("habits") == "habits: habits, the file's prior"
    assert model_label("confident") == (f"confident: habits, prior {CONFIDENT.prior:g} per {CONFIDENT.prior_per}, "
                                        f"acts at {CONFIDENT.act_confidence:g}")
    assert model_label("orders") == f"orders: habits, the recorded orders, acts at {ORDERS.act_confidence:g}"
    assert model_label("helpful") == (f"helpful: habits, prior {HELPFUL.prior:g} per {HELPFUL.prior_per}, acts at "
                                      f"{HELPFUL.act_confidence:g}, helps early (--joins)")
    assert session_arguments("p.json", "s.jsonl", habits="h.json", model="helpful")[-2:] == ["--model", "helpful"]
    assert model_label("camera") == (f"camera: habits, prior {CAMERA.prior:g} per {CAMERA.prior_per}, acts at "
                                     f"{CAMERA.act_confidence:g}, helps early (--joins), sees each step (--observe "
                                     "step)")
    monkeypatch.setitem(PRESETS, "eager", ModelPreset("eager", True, act_confidence=0.7))
    assert model_names()[-1] == "eager" and model_label("eager") == "eager: habits, the file's prior, acts at 0.7"
    assert session_arguments("p.json", "s.jsonl", habits="h.json", model="eager")[-2:] == ["--model", "eager"]


def test_learned_habits_are_checked_and_added_to(pen, pen_file, tmp_path):
    """Learn from two of the panel's logs, then from a third added to the same file: the counts are the logs'
    steps (5 each), the check before a session gives the habits the session reads."""
    logs = [tmp_path / f"s{k}.jsonl" for k in range(3)]
    for path, rank in zip(logs, (3, 3, 17)):
        _log(pen, rank, path)
    out = habits_path(str(tmp_path / "pen.FCStd"), None, str(tmp_path))
    assert out == str(tmp_path / "pen-habits.json")
    first = learn_session_habits(pen_file, None, [str(p) for p in logs[:2]], out)
    assert (first["steps"], first["logs"], first["added"], first["product"]) == (10, 2, False, pen.name)
    second = learn_session_habits(pen_file, None, [str(logs[2])], out)
    assert second["steps"] == 5 and second["added"] is True
    habits = check_habits(pen_file, None, out, None)
    assert edge_counts(make_plan(pen), habits).sum() == 15  # 3 sessions of 5 operations
    confident = check_habits(pen_file, None, out, "confident")
    assert (confident.prior, confident.prior_per) == (CONFIDENT.prior, CONFIDENT.prior_per)
    helpful = check_habits(pen_file, None, out, "helpful")  # the joins preset reads the habits as confident does
    assert helpful == confident
    with pytest.raises(PlannerError, match="--model helpful needs the habits"):
        check_habits(pen_file, None, None, "helpful")
    assert check_habits(pen_file, None, out, "paper") is None and check_habits(pen_file, None, "", None) is None
    with pytest.raises(PlannerError, match="no operation"):  # a log without a step: nothing learned, nothing written
        empty = tmp_path / "empty.jsonl"
        _log(pen, 3, empty, max_steps=0)
        learn_session_habits(pen_file, None, [str(empty)], str(tmp_path / "none.json"))
    assert not (tmp_path / "none.json").exists()
    assert habits_path(None, "sa1", str(tmp_path)) == str(tmp_path / "product-sa1-habits.json")


def test_bad_habits_are_refused_before_a_session_starts(pen, pen_file, tmp_path):
    """Each refusal names the file and says what to do, as aplan session says it."""
    chain = chain_product(4)
    chain_log, other = tmp_path / "chain.jsonl", tmp_path / "chain-habits.json"
    _log(chain, 0, chain_log)
    chain_file = tmp_path / "chain.json"
    save_product(chain, chain_file)
    learn_session_habits(str(chain_file), None, [str(chain_log)], str(other))
    with pytest.raises(PlannerError, match=re.escape(f"{other}: habits of the product {chain.name!r}, not of "
                                                     f"{pen.name!r}; learn them again")):
        check_habits(pen_file, None, str(other), "habits")
    damaged = tmp_path / "damaged.json"
    damaged.write_text(other.read_text()[:40])
    with pytest.raises(PlannerError, match=f"{damaged}: not JSON"):
        check_habits(pen_file, None, str(damaged), None)
    with pytest.raises(PlannerError, match="--model confident needs the habits: --habits FILE"):
        check_habits(pen_file, None, None, "confident")
    with pytest.raises(PlannerError, match="cannot read the habits file"):
        check_habits(pen_file, None, str(tmp_path / "missing.json"), None)
    # another version of the pen: one more part, the same name
    grown = replace(chain_product(5), name=chain.name)
    grown_file = tmp_path / "grown.json"
    save_product(grown, grown_file)
    with pytest.raises(PlannerError, match="habits of another version of"):
        check_habits(str(grown_file), None, str(other), None)
    with pytest.raises(PlannerError, match="a log of another version"):  # learning from the old version's log
        learn_session_habits(str(grown_file), None, [str(chain_log)], str(tmp_path / "grown-habits.json"))
    assert not (tmp_path / "grown-habits.json").exists()


def test_a_keyboard_session_with_learned_habits_replays(tmp_path, monkeypatch):
    """s1 of a chain with a level: a keyboard session, its habits learned, then a keyboard session with them and
    the confident model. Its log records the habits it used (with the model's prior) and replays (the panel's
    run replays every log); every level at once is refused (habits are of one workstation)."""
    product = replace(chain_product(4), subassemblies=(Subassembly("s1", ("p1", "p2")),))
    path = tmp_path / "product.json"
    save_product(product, path)
    monkeypatch.setattr(sys, "stdin", io.StringIO("p1 p2\n"))
    first = run_simulated_session(str(path), str(tmp_path / "a"), "s1", expansions=20, source="keyboard")
    out = str(tmp_path / "s1-habits.json")
    assert learn_session_habits(str(path), "s1", [first["levels"][0]["log"]], out)["steps"] == 1
    assert check_habits(str(path), "s1", out, "confident").prior_per == "state"
    with pytest.raises(PlannerError, match="habits are of one workstation's plan; choose a level"):
        check_habits(str(path), ALL_LEVELS, out, "habits")
    assert check_habits(str(path), ALL_LEVELS, None, None) is None
    with pytest.raises(PlannerError, match=r"habits of the product .* / s1', not of"):  # not the top level's
        check_habits(str(path), "top", out, "habits")
    monkeypatch.setattr(sys, "stdin", io.StringIO("p1 p2\n"))
    second = run_simulated_session(str(path), str(tmp_path / "b"), "s1", expansions=20, source="keyboard",
                                   habits=out, model="confident")
    assert second["assembled"] is True and "--habits" in second["command"]
    start = json.loads(open(second["levels"][0]["log"]).readline())
    used = start["settings"]["habits"]
    saved = json.loads(open(out).read())
    assert used["counts"] == saved["counts"] and used["prior_per"] == "state" and used["file"] == out
    assert api.read_habits(out).counts == check_habits(str(path), "s1", out, None).counts
