"""Operator habits from session logs (issue 23): ``aplan habits LOG... -o FILE`` counts each logged step once
(closed form: sessions x steps of the sequences played), ``--habits FILE`` changes the models of every command
and ``--model paper`` gives today's, a session records its habits so that replay rebuilds its beliefs, and bad
input (another product, another version, NaN or negative counts, an empty file, a log of another version) is
one clear error naming the file, with nothing written."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from aplan_runner import run_aplan
from planner.assembly import make_plan
from planner.assembly.explode import sequence_at
from planner.decision.habits import edge_counts, state_graph_fingerprint
from planner.decision.intention_model import intention_model
from planner.decision.io.habits_file import read_habits
from planner.product import product_to_dict
from planner.runtime.log import EventLog
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
from planner.runtime.session import run_session


class _Wait:
    def __init__(self, model):
        self.wait = len(model.actions) - 1

    def action(self, belief) -> int:
        return self.wait


def _log(model, rank: int, path, settings=None) -> list[int]:
    """A session in which the operator assembles full sequence ``rank`` alone (the robot waits)."""
    operations = sequence_at(model.plan, rank)
    operator = ScriptedOperator(model.plan, operations)
    result = run_session(model, _Wait(model), operator, ScriptedRobot(), EventLog(path), settings=settings)
    assert result.assembled
    return operations


@pytest.fixture(scope="module")
def logs(pen, tmp_path_factory):
    folder = tmp_path_factory.mktemp("habit-logs")
    model = intention_model(make_plan(pen))
    played = {}
    for k, rank in enumerate([3, 3, 3, 17]):
        path = folder / f"s{k}.jsonl"
        played[path] = _log(model, rank, path)
    return model, played


def test_counts_are_the_logged_steps(logs, tmp_path):
    model, played = logs
    out = tmp_path / "habits.json"
    done = run_aplan("habits", *played, "-o", out, "--json")
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["steps"] == 4 * (len(model.plan.product.parts) - 1) and summary["logs"] == 4
    habits = read_habits(out)
    assert habits.fingerprint == state_graph_fingerprint(model.plan) and habits.prior == 1.0
    counts = edge_counts(model.plan, habits)
    states = model.plan.states
    # Closed form: rank 3 three times, rank 17 once; the edges they share count 4.
    expected = np.zeros(states.n_edges)
    for operations in played.values():
        state = states.initial
        for op in operations:
            edge = int(np.flatnonzero((states.edge_source == state) & (states.edge_operation == op))[0])
            expected[edge] += 1
            state = int(states.edge_target[edge])
    assert np.array_equal(counts, expected)
    # One sequence explains each pen log: whole counts, the orders 3 and 1 exactly (docs/habits.md).
    assert sorted(count for _, count in habits.orders) == [1.0, 3.0]
    again = run_aplan("habits", *list(played)[:1], "-o", tmp_path / "more.json", "--product", "pen", "--add", out)
    assert again.returncode == 0, again.stderr
    assert np.array_equal(edge_counts(model.plan, read_habits(tmp_path / "more.json")),
                          expected + _one(model, played))


def test_a_log_past_the_cap_records_no_order_and_says_so(logs, monkeypatch, capsys):
    """More explanations than the cap (here a cap of 0): the per-state counts are the same, no order is recorded,
    and a note names the log."""
    from planner.runtime import habits_logs

    model, played = logs
    path = next(iter(played))
    counts, orders = np.zeros(model.plan.states.n_edges), {}
    habits_logs.count_log(model.plan, counts, path, orders=orders)
    monkeypatch.setattr(habits_logs, "ORDERS_CAP", 0)
    capped, none, notes = np.zeros_like(counts), {}, []
    assert habits_logs.count_log(model.plan, capped, path, orders=none, notes=notes) == len(played[path])
    assert np.array_equal(capped, counts) and len(orders) == 1 and none == {}
    assert len(notes) == 1 and str(path) in notes[0] and "more than 0 sequences" in notes[0]

    from planner.cli import main

    out = path.parent / "capped-habits.json"
    assert main(["habits", str(path), "-o", str(out), "--json"]) == 0  # in process: the cap patched
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["unrecorded"] == 1 and summary["orders"] == 0
    assert main(["habits", str(path), "-o", str(out), "--force"]) == 0
    assert capsys.readouterr().out.startswith(f"note: {path}: more than 0 sequences explain")


def _one(model, played):
    states = model.plan.states
    first = next(iter(played.values()))
    out, state = np.zeros(states.n_edges), states.initial
    for op in first:
        edge = int(np.flatnonzero((states.edge_source == state) & (states.edge_operation == op))[0])
        out[edge] += 1
        state = int(states.edge_target[edge])
    return out


def test_habits_change_the_model_and_paper_ignores_them(logs, tmp_path):
    _, played = logs
    habits = tmp_path / "habits.json"
    assert run_aplan("habits", *played, "-o", habits).returncode == 0
    files = {}
    for name, extra in (("paper", []), ("habits", ["--habits", habits]),
                        ("explicit", ["--habits", habits, "--model", "paper"])):
        files[name] = tmp_path / f"{name}.pomdp"
        done = run_aplan("pomdp", "pen", "-o", files[name], *extra)
        assert done.returncode == 0, done.stderr
    assert files["paper"].read_bytes() == files["explicit"].read_bytes()
    assert files["paper"].read_bytes() != files["habits"].read_bytes()
    lumped = run_aplan("pomdp", "pen", "--lumped", "-o", tmp_path / "lumped.pomdpx", "--habits", habits)
    assert lumped.returncode == 0, lumped.stderr
    online = run_aplan("simulate", "pen", "--habits", habits, "--planner", "online", "--expansions", "30",
                       "--random", "2", "--json")
    assert online.returncode == 0, online.stderr


def test_a_session_with_habits_replays_its_beliefs_and_adds_its_steps(logs, tmp_path):
    """A keyboard session on the habits' model whose robot never acts (every robot operation costs -1000): it
    logs its habits, replays to the same beliefs, and --habits-out adds exactly its sequence's state edges."""
    model, played = logs
    habits = tmp_path / "habits.json"
    assert run_aplan("habits", *played, "-o", habits).returncode == 0
    learned = read_habits(habits)
    operations = sequence_at(model.plan, 5)
    picks = []
    for op in operations:
        seen = model.plan.observations[int(model.plan.operation_observation[op])]
        picks.append(" ".join(seen.parts + ((seen.tool,) if seen.tool else ())))
    log = tmp_path / "session.jsonl"
    session = ["session", "pen", "--habits", habits, "--keyboard", "--planner", "online", "--expansions", "20",
               "--reward-unfavorable", "-1000", "--reward-favorable", "-1000", "--log", log, "--habits-out", habits]
    done = run_aplan(*session, stdin="\n".join(picks) + "\n")
    assert done.returncode == 1 and "exists already" in done.stderr and not log.exists()  # the overwrite rule
    done = run_aplan(*session, "--force", stdin="\n".join(picks) + "\n")
    assert done.returncode == 0, done.stderr
    events = [json.loads(line) for line in log.read_text().splitlines()]
    assert events[0]["settings"]["habits"]["fingerprint"] == state_graph_fingerprint(model.plan)
    assert all(e["name"] == "wait" for e in events if e["event"] == "action")
    replay = run_aplan("replay", log)
    assert replay.returncode == 0 and "beliefs reproduced" in replay.stdout, replay.stdout + replay.stderr
    added = edge_counts(model.plan, read_habits(habits)) - edge_counts(model.plan, learned)
    states, expected, state = model.plan.states, np.zeros(model.plan.states.n_edges), model.plan.states.initial
    for op in operations:
        edge = int(np.flatnonzero((states.edge_source == state) & (states.edge_operation == op))[0])
        expected[edge] += 1
        state = int(states.edge_target[edge])
    assert np.array_equal(added, expected)


def _write(path, data) -> str:
    path.write_text(json.dumps(data) if not isinstance(data, str) else data)
    return str(path)


@pytest.mark.parametrize("fault, message", [
    ("product", "habits of the product 'a truck', not of"),
    ("fingerprint", "another version of"),
    ("nan", "NaN is not a number JSON allows"),
    ("negative", "is not a finite number of at least 0"),
    ("empty", "the habits file is empty"),
    ("no counts", "holds no counts"),
    ("unknown key", "has no operation"),
    ("prior", "the prior (alpha) must be a finite number above 0"),
])
def test_bad_habits_files_are_refused(logs, tmp_path, fault, message):
    _, played = logs
    good = tmp_path / "habits.json"
    assert run_aplan("habits", *played, "-o", good).returncode == 0
    data = json.loads(good.read_text())
    bad = tmp_path / "bad.json"
    if fault == "product":
        data["product"] = "a truck"
    elif fault == "fingerprint":
        data["fingerprint"] = "0" * 16
    elif fault == "nan":
        data = re.sub(r'"count": [0-9]+', '"count": NaN', good.read_text(), count=1)
    elif fault == "negative":
        data["counts"][0]["count"] = -1
    elif fault == "empty":
        data = ""
    elif fault == "no counts":
        data["counts"] = []
    elif fault == "unknown key":
        data["counts"][0]["operation"] = "{ink} + {cap}"
    elif fault == "prior":
        data["prior"] = 0
    _write(bad, data)
    out = tmp_path / "model.pomdpx"
    done = run_aplan("pomdp", "pen", "-o", out, "--habits", bad)
    assert done.returncode == 1 and message in done.stderr and str(bad) in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_a_log_of_another_version_is_refused(logs, pen, tmp_path):
    """The pen with its technical constraint made part of the design (active) has another state graph: its log
    is refused, naming it, and no habits file is written."""
    model, played = logs
    changed = product_to_dict(pen)
    for constraint in changed["technical_constraints"]:
        constraint["active"] = True
    other = tmp_path / "pen2.json"
    other.write_text(json.dumps(changed))
    from planner import api

    plan2 = make_plan(api.resolve_product(other))
    assert state_graph_fingerprint(plan2) != state_graph_fingerprint(model.plan)
    log2 = tmp_path / "other.jsonl"
    _log(intention_model(plan2), 0, log2)
    out = tmp_path / "habits.json"
    done = run_aplan("habits", *played, log2, "-o", out)
    assert done.returncode == 1 and str(log2) in done.stderr and "another version" in done.stderr, done.stderr
    assert not out.exists()


@pytest.mark.parametrize("prior", ["0", "-1", "nan", "inf"])
def test_a_prior_out_of_range_is_a_usage_error(logs, tmp_path, prior):
    _, played = logs
    out = tmp_path / "habits.json"
    done = run_aplan("habits", *played, "-o", out, "--prior", prior)
    assert done.returncode == 2 and "--prior" in done.stderr and not out.exists()


def test_model_habits_needs_a_file_and_model_files_take_none(tmp_path, logs):
    _, played = logs
    done = run_aplan("pomdp", "pen", "-o", tmp_path / "m.pomdpx", "--model", "habits")
    assert done.returncode == 1 and "--habits FILE" in done.stderr
    habits = tmp_path / "habits.json"
    assert run_aplan("habits", *played, "-o", habits).returncode == 0
    assert run_aplan("pomdp", "pen", "-o", tmp_path / "m.pomdpx").returncode == 0
    done = run_aplan("solve", tmp_path / "m.pomdpx", "-o", tmp_path / "m.policy", "--habits", habits)
    assert done.returncode == 1 and "--habits applies to a PRODUCT" in done.stderr
    assert not (tmp_path / "m.policy").exists()
