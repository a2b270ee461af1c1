"""The workbench's levels, model choice and simulated sessions (freecad_aplan.sessions), without FreeCAD: the
session panel only calls these. Expected values: the chain's levels from its definition, the pen's 69
intentions (the paper, Sec. VI), and the command line's own run of the same session."""
from __future__ import annotations

import io
import json
import subprocess
import sys
from dataclasses import replace

import pytest
from conftest import REPO

from freecad_aplan.sessions import (
    ALL_LEVELS,
    base_part_in,
    is_prompt,
    level_choices,
    level_model,
    level_of,
    member_parts,
    model_choice,
    offered_picks,
    run_simulated_session,
    session_arguments,
    typed_pick,
)
from planner import api
from planner.assembly.guards import SizeLimits
from planner.errors import PlannerError
from planner.product import Subassembly, save_product
from planner.product.synthetic import chain_product


def _chain_with_levels():
    """p1-p2-p3-p4 in a chain, with the subassembly s1 = {p1, p2}: two workstations, s1 then the top level
    {s1, p3, p4}."""
    return replace(chain_product(4), subassemblies=(Subassembly("s1", ("p1", "p2")),))


def test_level_choices_bottom_up_with_members():
    choices = level_choices(_chain_with_levels())
    assert [(c.id, sorted(c.members)) for c in choices] == [("s1", ["p1", "p2"]), ("top", ["p3", "p4", "s1"])]
    assert [c.label for c in choices][0] == "s1: 2 members"


def test_a_flat_product_is_one_choice_without_an_id():
    pen = api.resolve_product("pen")
    choices = level_choices(pen)
    assert len(choices) == 1 and choices[0].id is None and sorted(choices[0].members) == sorted(pen.part_ids)
    assert level_of(pen, None).part_ids == pen.part_ids


def test_level_of_names_the_levels_when_several():
    product = _chain_with_levels()
    assert sorted(level_of(product, "s1").part_ids) == ["p1", "p2"]
    with pytest.raises(PlannerError, match="s1"):
        level_of(product, None)


def test_model_choice_flat_where_it_fits_else_lumped():
    pen = api.resolve_product("pen")
    flat = model_choice(pen)
    assert (flat.kind, flat.intentions) == ("flat", 69)  # the pen's 69 intentions (paper, Sec. VI)
    # the same rule as the command line's planner choice: a memory budget the flat model passes
    tiny = model_choice(pen, limits=SizeLimits(memory=1))
    assert tiny.kind == "lumped" and "69 intentions" in tiny.note


def test_session_arguments_are_the_command_lines():
    assert session_arguments("p.json", "s.jsonl", "s1", 2, 40, 9, "p1") == [
        "session", "p.json", "--demo", "2", "--log", "s.jsonl", "--level", "s1", "--expansions", "40",
        "--max-steps", "9", "--base-part", "p1"]
    assert session_arguments("p.json", "s.jsonl", ALL_LEVELS) == ["session", "p.json", "--demo", "0", "--log",
                                                                   "s.jsonl"]
    with pytest.raises(PlannerError, match="from 0"):
        session_arguments("p.json", "s.jsonl", sequence=-1)


def test_simulated_session_of_one_level_is_the_command_lines(tmp_path):
    """s1 of the chain in the simulated cell, with a fixed number of expansions (no clock): assembled, its
    belief plot written, and the same decisions as ``aplan session`` run as a command."""
    product = tmp_path / "product.json"
    save_product(_chain_with_levels(), product)
    lines = []
    result = run_simulated_session(str(product), str(tmp_path / "gui"), "s1", 0, expansions=20, progress=lines.append)
    assert result["assembled"] is True and len(result["levels"]) == 1
    done, = result["levels"]
    assert done["level"] == "s1" and done["reason"] == "assembled" and done["steps"] >= 1
    png = (tmp_path / "gui" / "session-belief.png").read_bytes()
    assert done["plot"].endswith("session-belief.png") and png[:8] == b"\x89PNG\r\n\x1a\n"
    assert any(line.startswith("step 1 | belief") for line in lines), lines
    assert any(line.startswith("assembled: ") for line in lines)
    log = tmp_path / "cli.jsonl"
    subprocess.run([sys.executable, "-m", "planner", "session", str(product), "--demo", "0", "--level", "s1",
                    "--expansions", "20", "--log", str(log)], cwd=REPO, check=True, capture_output=True)

    def decisions(path):
        return [(e["event"], e.get("action"), e.get("observation")) for e in map(json.loads, open(path))
                if e["event"] in ("action", "observation")]

    assert decisions(done["log"]) == decisions(log) and decisions(log)


def test_simulated_session_refusal_is_the_command_lines_message(tmp_path):
    product = tmp_path / "product.json"
    save_product(_chain_with_levels(), product)
    with pytest.raises(PlannerError, match="nowhere"):
        run_simulated_session(str(product), str(tmp_path / "gui"), "nowhere", 0, expansions=5)


def test_member_parts_of_a_level():
    """The top level of the chain moves s1 as one block: its parts p1 and p2."""
    product = _chain_with_levels()
    assert member_parts(product, "top") == {"s1": ("p1", "p2"), "p3": ("p3",), "p4": ("p4",)}
    assert member_parts(product, "s1") == {"p1": ("p1",), "p2": ("p2",)}
    pen = api.resolve_product("pen")
    assert member_parts(pen, None) == {p: (p,) for p in pen.part_ids}


def test_level_model_is_the_flat_model_where_it_fits(tmp_path):
    """Export model and Solve on a level: the level's flat model (as `aplan pomdp` on it), the lumped one only
    past the limits; the pen (flat) gives the paper's model: 69 intentions, 22 actions."""
    model, choice = level_model(api.resolve_product("pen"))
    assert choice.kind == "flat" and (model.pomdp.n_states, model.pomdp.n_actions) == (69, 22)
    product = tmp_path / "product.json"
    save_product(_chain_with_levels(), product)
    model, choice = level_model(str(product), "top")
    assert choice.kind == "flat" and model.pomdp.n_states == choice.intentions
    with pytest.raises(PlannerError, match="s1"):
        level_model(str(product))  # several levels: one must be named


def test_keyboard_session_reads_the_picks_from_standard_input(tmp_path, monkeypatch):
    """The panel's keyboard session: the operator's picks one line a step on standard input (the panel writes
    them to the job's input), the robot's instructions confirmed at once; s1 of the chain is one operation."""
    product = tmp_path / "product.json"
    save_product(_chain_with_levels(), product)
    assert session_arguments("p.json", "s.jsonl", "s1", source="keyboard") == [
        "session", "p.json", "--keyboard", "--robot", "auto", "--log", "s.jsonl", "--level", "s1"]
    monkeypatch.setattr(sys, "stdin", io.StringIO("p1 nothing\np1 p2\n"))  # a bad line is asked again
    lines = []
    result = run_simulated_session(str(product), str(tmp_path / "kb"), "s1", expansions=20, source="keyboard",
                                   progress=lines.append)
    assert result["assembled"] is True and result["levels"][0]["steps"] == 1
    assert any("not a part or tool: nothing" in line for line in lines), lines
    with pytest.raises(PlannerError, match="unknown session source"):
        session_arguments("p.json", "s.jsonl", source="camera")
    # What the panel shows of the prompt: the robot's step, the one pick s1 allows (p1 joined to p2: the
    # chain's single operation), then the prompt, a line of its own although printed without a newline; asked
    # twice (the bad line refused), once offered per step.
    robot = [k for k, line in enumerate(lines) if line.startswith("robot, step 1: ")]
    offered = [(k, offered_picks(line)) for k, line in enumerate(lines) if offered_picks(line) is not None]
    prompts = [k for k, line in enumerate(lines) if is_prompt(line)]
    assert len(robot) == 1 and offered == [(robot[0] + 1, ["p1+p2"])] and prompts[:1] == [robot[0] + 2], lines
    assert len(prompts) == 2 and all(lines[k].rstrip().endswith("q: stop):") for k in prompts)


def test_offered_picks_and_the_lines_that_type_them():
    """The keyboard's line of picks as the panel reads it, and each pick as the line that types it (what
    KeyboardSource reads back as the same observation)."""
    from planner.runtime.console import COULD_PICK, KeyboardSource

    picks = offered_picks(COULD_PICK + "body+button+[hammer], cartridge+ink")
    assert picks == ["body+button+[hammer]", "cartridge+ink"]
    assert offered_picks(COULD_PICK + "nothing that shows (Enter)") == [] and offered_picks("step 1 | x") is None
    assert [typed_pick(p) for p in picks] == ["body button hammer", "cartridge ink"] and typed_pick("blank") == ""
    typed = iter([typed_pick(p) for p in picks])
    keyboard = KeyboardSource(api.resolve_product("pen"), read=lambda prompt: next(typed), write=print)
    assert [str(keyboard.observe()), str(keyboard.observe())] == picks


def test_a_base_part_applies_to_the_levels_that_hold_it():
    product = _chain_with_levels()
    top = level_of(product, "top")
    assert base_part_in(top, "p3") == "p3" and base_part_in(top, "auto") == "auto"
    assert base_part_in(top, "p1") is None  # p1 is built in s1, not at the top level
    model, _ = level_model(product, "top", base_part="p1")  # not refused: the top level starts anywhere
    assert model.pomdp.n_states == level_model(product, "top")[0].pomdp.n_states
