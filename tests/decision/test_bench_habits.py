"""bench/bench_habits.py with ``--parallel joins`` (issue 23 "Habits help" with help before the last step): the
variants it adds, their rewards (the act confidence's closed form), the paper-rewards return and paired
difference, and the offline policy built on the same parallel model. Tiny runs on the pen (a few logs and
episodes, a fixed number of expansions or solver trials: no clock)."""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import pytest

from planner import api
from planner.decision.factored_model import factored_model
from planner.decision.lumped_model import lumped_model
from planner.decision.presets import wrong_for_confidence
from planner.decision.solvers import PointBasedSolver

REPO = Path(__file__).resolve().parents[2]
BENCH = REPO / "bench" / "bench_habits.py"


def _bench(*options: str) -> list[dict]:
    done = subprocess.run([sys.executable, str(BENCH), "pen", "--logs", "2", "--json", *options], cwd=REPO,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return [json.loads(line) for line in done.stdout.splitlines()]


def test_parallel_joins_adds_the_paper_prior_and_the_habits_at_each_confidence():
    (row,) = _bench("--episodes", "4", "--model", "confident", "--parallel", "joins", "--planner", "online",
                    "--expansions", "20", "--act-confidence", "0.9,0.98")
    assert row["labels"] == ["paper", "habits C=0.9", "habits C=0.98", "joins C=0.9", "state+joins C=0.9",
                             "joins C=0.98", "state+joins C=0.98"]
    for label in row["labels"][1:]:
        m = row[label]
        c = float(label.split("C=")[1])
        assert m["wrong_reward"] == pytest.approx(wrong_for_confidence(c, 10.0, 0.0))  # -10 C / (1 - C)
        # Scored with the paper's rewards: only a wrong action's reward differs from the model's own.
        if m["wrong_robot_actions"] == 0:
            assert m["mean_return"] == pytest.approx(m["own_return"], abs=1e-4)
        else:
            assert m["mean_return"] > m["own_return"]
        assert m["paired_difference"]["mean"] == pytest.approx(m["mean_return"] - row["paper"]["mean_return"],
                                                               abs=2e-4)
        assert m["targets"]["share_30"] == (m["robot_capable_share"] >= 0.30)
        assert m["robot_operations"] <= m["robot_capable_operations"] == row["paper"]["robot_capable_operations"]


def test_the_default_confidence_is_the_projected_models_own_and_orders_get_no_joins():
    (row,) = _bench("--episodes", "2", "--model", "orders", "--parallel", "joins", "--parallel", "joins",
                    "--planner", "online", "--expansions", "5")
    assert row["labels"] == ["paper", "state", "orders", "joins", "state+joins"]  # repeated: once; no orders+joins
    assert row["joins"]["wrong_reward"] == row["state+joins"]["wrong_reward"] == pytest.approx(-490.0)  # C = 0.98


def test_a_parallel_rule_it_does_not_know_is_refused():
    done = subprocess.run([sys.executable, str(BENCH), "pen", "--parallel", "joins,next"], cwd=REPO,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "--parallel takes projected or joins" in done.stderr and not done.stdout


def test_the_offline_policy_is_solved_on_the_parallel_model(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH.parent))
    import bench_habits

    plan = api.plan_of(api.resolve_product("pen"))
    model = factored_model(plan, parallel="joins")
    assert len(model.actions) < len(factored_model(plan).actions)  # one action per join: the tables differ
    args = argparse.Namespace(planner="offline", max_classes=10_000, trials=40, max_gap=0.5, expansions=10)
    policy, how = bench_habits._policy(args, plan, model, {"weights": None, "parallel": "joins"})
    assert how.startswith("offline") and int(policy.actions.max()) < len(model.actions)
    alone = PointBasedSolver(max_iterations=40, time_limit=None, precision=1e-3).solve(
        lumped_model(plan, model.rewards, parallel="joins").pomdp)
    assert f"bounds {alone.lower_bound:.3f} to {alone.upper_bound:.3f}" in how
