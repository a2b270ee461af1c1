"""``aplan sequence``: a full assembly sequence step by step (by rank or from a session log), as the workbench's
Plan in 3D shows it; the same answers as planner.api, bad input one clear line."""
from __future__ import annotations

import json

from aplan_runner import run_aplan

from planner import api
from planner.assembly.explode import sequence_at
from planner.decision.intention_model import intention_model
from planner.runtime.log import EventLog
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
from planner.runtime.session import run_session


class _Waits:
    def __init__(self, actions):
        self.wait = len(actions) - 1

    def action(self, belief) -> int:
        return self.wait


def test_a_sequence_by_rank():
    plan = api.plan_of("pen")
    done = run_aplan("sequence", "pen", "--rank", "3")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == ("Bourjault ballpoint pen: sequence 3, 5 operations; the moving side goes in along the reverse "
                        "of its free direction")
    view = api.plan_in_3d(plan, 3)
    assert [line.split(". ", 1)[1].split(":")[0] for line in lines[1:]] == [s.description for s in view.steps]
    assert lines[1] == "  1. {head} + {body}: head moves in along +X (free along -X)"
    data = json.loads(run_aplan("sequence", "pen", "--rank", "3", "--spacing", "10", "--json").stdout)
    assert [s["operation"] for s in data["steps"]] == sequence_at(plan, 3)
    assert data["steps"][0]["offsets"] == {p: list(v) for p, v in api.plan_in_3d(plan, 3, 10.0).offsets[0].items()}


def test_a_sequence_from_a_session_log(tmp_path):
    model = intention_model(api.plan_of("pen"))
    operations = sequence_at(model.plan, 17)
    log = tmp_path / "session.jsonl"
    run_session(model, _Waits(model.actions), ScriptedOperator(model.plan, operations), ScriptedRobot(), EventLog(log))
    data = json.loads(run_aplan("sequence", "pen", "--log", log, "--json").stdout)
    assert [s["operation"] for s in data["steps"]] == operations and data["sequence"] is None
    assert f"the sequence {log} recorded, 5 operations" in run_aplan("sequence", "pen", "--log", log).stdout
    # The log is read within the input limits, and the refusal names the option that raises them.
    small = str(log.stat().st_size // 2 / 2 ** 30)
    done = run_aplan("sequence", "pen", "--log", log, "--max-input", small)
    assert done.returncode == 1 and "--max-input GIB" in done.stderr and "Traceback" not in done.stderr, done.stderr
    bigger = str(2 * log.stat().st_size / 2 ** 30)
    assert run_aplan("sequence", "pen", "--log", log, "--max-input", bigger).returncode == 0


def test_bad_input_is_one_line():
    done = run_aplan("sequence", "pen", "--rank", "24")
    assert done.returncode == 1 and done.stderr.strip() == (
        "aplan: error: sequence rank 24 is out of range: the plan has 24 full assembly sequences, ranked 0..23; "
        "choose a rank in that range")
    done = run_aplan("sequence", "pen", "--rank", "2", "--log", "x.jsonl")
    assert done.returncode == 2 and "not allowed with argument" in done.stderr
    done = run_aplan("sequence", "pen", "--log", "/nonexistent/session.jsonl")
    assert done.returncode == 1 and "cannot read the log" in done.stderr and "Traceback" not in done.stderr
    assert run_aplan("sequence", "pen", "--spacing", "0").returncode == 2
