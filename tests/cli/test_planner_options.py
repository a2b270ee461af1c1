"""``--planner``, ``--decision-time`` and ``--expansions`` in simulate, evaluate and session: the online planner by
default without a policy, by itself when the flat model would not fit, and clear errors for bad budgets."""
from __future__ import annotations

import json

import pytest
from aplan_runner import run_aplan

from planner import chain_product, save_product


def _aplan(*args):
    return run_aplan(*args)


@pytest.fixture(scope="module")
def chain11(tmp_path_factory):
    path = tmp_path_factory.mktemp("chain") / "chain11.json"
    save_product(chain_product(11), path)
    return path


def test_online_by_default_without_a_policy():
    done = _aplan("simulate", "pen", "--random", 2, "--expansions", 5, "--json")
    assert done.returncode == 0, done.stderr
    assert "no --policy: using the online planner" in done.stderr
    *lines, run_line = [json.loads(line) for line in done.stdout.splitlines()]
    assert len(lines) == 2 and all(line["finished"] for line in lines) and run_line["run"]["episodes"] == 2
    assert all(len(line["operations"]) == 5 for line in lines)  # the pen's 6 parts take 5 operations


def test_online_by_itself_beyond_the_flat_model(chain11):
    done = _aplan("simulate", chain11, "--random", 1, "--expansions", 3, "--json")
    assert done.returncode == 0, done.stderr
    assert "9,864,101 intentions" in done.stderr and "using the online planner" in done.stderr
    assert json.loads(done.stdout.splitlines()[0])["finished"]
    offline = _aplan("evaluate", chain11, "--planner", "offline", "--episodes", 2)
    assert offline.returncode == 1 and "9,864,101 intentions" in offline.stderr
    assert "--planner online" in offline.stderr and "Traceback" not in offline.stderr


def test_sequences_by_rank_on_the_factored_model():
    done = _aplan("simulate", "pen", "--planner", "online", "--sequence", 0, 23, "--expansions", 2, "--json")
    assert done.returncode == 0, done.stderr
    first, last = (json.loads(line)["operations"] for line in done.stdout.splitlines()[:-1])  # then the run's line
    assert first != last
    bad = _aplan("simulate", "pen", "--planner", "online", "--sequence", 24, "--expansions", 2)
    assert bad.returncode == 1 and "numbered by rank, from 0 to 23" in bad.stderr


def test_evaluate_online_and_offline():
    online = _aplan("evaluate", "pen", "--planner", "online", "--expansions", 2, "--episodes", 20, "--json")
    assert online.returncode == 0, online.stderr
    assert json.loads(online.stdout)["episodes"] == 20


@pytest.mark.parametrize("bad", ["0", "-1", "nan", "inf", "soon", "61"])
def test_bad_decision_time(bad):
    done = _aplan("simulate", "pen", "--decision-time", bad)
    assert done.returncode == 2 and "--decision-time" in done.stderr
    assert "above 0 and at most 60" in done.stderr or "must be a number of seconds" in done.stderr


def test_the_online_planner_needs_a_product(tmp_path):
    model = tmp_path / "pen.pomdpx"
    assert _aplan("pomdp", "pen", "-o", model).returncode == 0
    done = _aplan("evaluate", model, "--planner", "online", "--episodes", 2)
    assert done.returncode == 1 and "the online planner needs a PRODUCT" in done.stderr


def test_a_policy_of_another_model_is_refused(tmp_path):
    """A policy solved for the pen without the technical constraint does not fit the model with it."""
    policy = tmp_path / "pen.policy"
    assert _aplan("solve", "pen", "-o", policy, "--trials", 20, "--quiet").returncode == 0
    done = _aplan("evaluate", "pen", "--technical", "--policy", policy, "--episodes", 2)
    assert done.returncode == 1 and "vectors of length 69" in done.stderr
    assert "belongs to another model" in done.stderr and "Traceback" not in done.stderr


def test_a_policy_over_classes_runs_on_the_factored_model(tmp_path):
    """`aplan solve --lumped` writes a policy over the classes; simulate, evaluate and the online planner (as its
    lower bound) take it on the factored model."""
    policy = tmp_path / "lumped.policy"
    assert _aplan("solve", "pen", "--lumped", "-o", policy, "--trials", 20, "--quiet").returncode == 0
    done = _aplan("evaluate", "pen", "--policy", policy, "--episodes", 30, "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["episodes"] == 30
    done = _aplan("simulate", "pen", "--policy", policy, "--sequence", 0, "--json")
    assert done.returncode == 0 and json.loads(done.stdout.splitlines()[0])["finished"], done.stderr
    done = _aplan("simulate", "pen", "--planner", "online", "--policy", policy, "--expansions", 5, "--random", 1,
                  "--json")
    assert done.returncode == 0 and json.loads(done.stdout.splitlines()[0])["finished"], done.stderr
