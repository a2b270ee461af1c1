"""``--projected`` on the command line (docs/parallel.md, The projected model): with ``--model paper`` the files are
the paper model's byte for byte; on, the lumped model holds the projected model's tables; with ``--parallel`` a
usage error (exit 2, nothing written); the flat model is refused naming it; a session in the simulated cell
records it and its log replays."""
from __future__ import annotations

import json

import numpy as np
import pytest

from aplan_runner import run_aplan
from planner import make_plan
from planner.decision import factored_model, lumped_pomdp
from planner.decision.intention_model import Rewards
from planner.decision.io.pomdpx import read_pomdpx
from planner.decision.presets import wrong_for_confidence
from planner.decision.projected import PROJECTED_CONFIDENCE


def test_model_paper_is_the_papers_file_and_on_the_projected_tables(pen, tmp_path):
    a, b, c = (tmp_path / f"{name}.pomdpx" for name in "abc")
    assert run_aplan("pomdp", "pen", "--lumped", "-o", a).returncode == 0
    assert run_aplan("pomdp", "pen", "--lumped", "--projected", "--model", "paper", "-o", b).returncode == 0
    assert a.read_bytes() == b.read_bytes()
    done = run_aplan("pomdp", "pen", "--projected", "-o", c)  # the lumped model, without --lumped
    assert done.returncode == 0, done.stderr
    read = read_pomdpx(c)
    # the projected model's own act confidence (0.98: -490) unless --reward-wrong or --act-confidence is given
    rewards = Rewards(wrong=wrong_for_confidence(PROJECTED_CONFIDENCE))
    assert rewards.wrong == pytest.approx(-490, rel=1e-12)
    expected = lumped_pomdp(factored_model(make_plan(pen), rewards, parallel="projected"))
    assert np.abs(np.asarray(read.reward) - expected.reward).max() <= 1e-9
    for x, y in zip(read.transition, expected.transition):
        assert abs(x - y).max() <= 1e-9


def test_with_parallel_it_is_a_usage_error_and_the_flat_model_is_refused(tmp_path):
    out = tmp_path / "x.pomdpx"
    done = run_aplan("pomdp", "pen", "--projected", "--parallel", "-o", out)
    assert done.returncode == 2 and "--parallel and --projected" in done.stderr and not out.exists()
    done = run_aplan("simulate", "pen", "--projected", "--planner", "offline", "--random", "1")
    assert done.returncode == 1 and "--projected is a model over the factored model's classes" in done.stderr


def test_a_demo_session_records_the_projected_model_and_replays(tmp_path):
    log = tmp_path / "session.jsonl"
    done = run_aplan("session", "pen", "--projected", "--demo", "0", "--expansions", "20", "--log", log)
    assert done.returncode == 0, done.stderr
    events = [json.loads(line) for line in log.read_text().splitlines()]
    assert events[0]["settings"]["parallel"] == "projected"
    replay = run_aplan("replay", log)
    assert replay.returncode == 0 and "beliefs reproduced" in replay.stdout, replay.stdout + replay.stderr
