"""``--parallel`` on the command line (docs/parallel.md): off, or with ``--model paper``, the files are the paper
model's byte for byte; on, the lumped model is built (its tables the parallel model's); the flat model and model
files are refused naming what helps; a session records it and its log replays."""
from __future__ import annotations

import json

import numpy as np

from aplan_runner import run_aplan
from planner import make_plan
from planner.decision import factored_model, lumped_pomdp
from planner.decision.io.pomdpx import read_pomdpx


def test_off_and_model_paper_write_the_papers_files_byte_for_byte(tmp_path):
    for suffix in (".pomdpx", ".pomdp"):
        a, b, c = (tmp_path / f"{name}{suffix}" for name in "abc")
        assert run_aplan("pomdp", "pen", "--lumped", "-o", a).returncode == 0
        assert run_aplan("pomdp", "pen", "--lumped", "--parallel", "--model", "paper", "-o", b).returncode == 0
        assert a.read_bytes() == b.read_bytes()
        done = run_aplan("pomdp", "pen", "--parallel", "-o", c)  # the lumped model, without --lumped
        assert done.returncode == 0, done.stderr
        assert a.read_bytes() != c.read_bytes()


def test_parallel_file_holds_the_parallel_models_tables(pen, tmp_path):
    path = tmp_path / "p.pomdpx"
    assert run_aplan("pomdp", "pen", "--parallel", "-o", path).returncode == 0
    read = read_pomdpx(path)
    expected = lumped_pomdp(factored_model(make_plan(pen), parallel=True))
    assert np.abs(np.asarray(read.reward) - expected.reward).max() <= 1e-9
    for x, y in zip(read.transition, expected.transition):
        assert abs(x - y).max() <= 1e-9


def test_the_flat_model_and_model_files_are_refused(tmp_path):
    done = run_aplan("simulate", "pen", "--parallel", "--planner", "offline", "--random", "1")
    assert done.returncode == 1 and "--planner online" in done.stderr and "--parallel" in done.stderr
    model = tmp_path / "m.pomdpx"
    assert run_aplan("pomdp", "pen", "--lumped", "-o", model).returncode == 0
    done = run_aplan("solve", model, "--parallel", "-o", tmp_path / "x.policy")
    assert done.returncode == 1 and "--parallel applies to a PRODUCT" in done.stderr
    assert not (tmp_path / "x.policy").exists()


def test_simulate_runs_on_the_parallel_model():
    done = run_aplan("simulate", "pen", "--parallel", "--expansions", "30", "--random", "2", "--json")
    assert done.returncode == 0, done.stderr


def test_a_session_records_the_parallel_model_and_replays(pen, tmp_path):
    plan = make_plan(pen)
    model = factored_model(plan)
    picks = []
    for op in model.sequence_operations(model.sequence(5)):
        seen = plan.observations[int(plan.operation_observation[op])]
        picks.append(" ".join(seen.parts + ((seen.tool,) if seen.tool else ())))
    log = tmp_path / "session.jsonl"
    done = run_aplan("session", "pen", "--parallel", "--keyboard", "--planner", "online", "--expansions", "20",
                     "--reward-unfavorable", "-1000", "--reward-favorable", "-1000",  # the robot waits
                     "--log", log, stdin="\n".join(picks) + "\n")
    assert done.returncode == 0, done.stderr
    events = [json.loads(line) for line in log.read_text().splitlines()]
    assert events[0]["settings"]["parallel"] is True
    replay = run_aplan("replay", log)
    assert replay.returncode == 0 and "beliefs reproduced" in replay.stdout, replay.stdout + replay.stderr
    events[0]["settings"]["parallel"] = "yes"
    damaged = tmp_path / "damaged.jsonl"
    damaged.write_text("".join(json.dumps(e) + "\n" for e in events))
    replay = run_aplan("replay", damaged)
    assert replay.returncode == 1 and "'parallel' setting" in replay.stderr
