"""``--base-part [PART]`` on every command that builds intentions or a decision model (paper Sec. V): the counts
against the unrestricted intentions filtered by hand, the models' sizes, episodes that start from the base part,
a session whose log replays the same model, and the errors."""
from __future__ import annotations

import json
import re

import pytest
from aplan_runner import run_aplan

from planner import make_plan
from planner.cli import main
from planner.decision import intention_model
from planner.decision.policy import write_policy
from planner.decision.solvers import PointBasedSolver
from planner.runtime.log import replay
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
from planner.runtime.session import run_session


def run(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def _aplan(*args, stdin=""):
    return run_aplan(*args, stdin=stdin)


def _joins(part: str, operation: str) -> bool:
    """Whether an operation as printed (``{head} + {body}``) involves ``part``."""
    return part in re.findall(r"[\w-]+", operation)


def _by_hand(capsys, part, *options):
    """From the unrestricted full sequences (aplan intentions --full): those whose first operation joins ``part``,
    and every suffix of them (the intentions they pass through)."""
    _, out, _ = run(capsys, "intentions", "pen", "--full", "--json", *options)
    rows = [json.loads(line) for line in out.splitlines()]
    sequences = [tuple(r["states"]) for r in rows if _joins(part, r["operations"][0])]
    return len(sequences), len({s[k:] for s in sequences for k in range(len(s))})


@pytest.mark.parametrize("options", [(), ("--technical",)], ids=["file", "technical"])
def test_stats_and_intentions_count_what_filtering_by_hand_gives(capsys, options):
    sequences, intentions = _by_hand(capsys, "body", *options)
    code, out, _ = run(capsys, "stats", "pen", "--json", "--base-part", *options)  # body: the most connected part
    assert code == 0
    assert (json.loads(out)["sequences"], json.loads(out)["intentions"]) == (sequences, intentions)
    _, out, _ = run(capsys, "intentions", "pen", "--json", "--base-part", "body", *options)
    assert len(out.splitlines()) == intentions
    _, out, _ = run(capsys, "intentions", "pen", "--full", "--base-part", *options)
    assert len(out.splitlines()) == sequences
    _, out, _ = run(capsys, "stats", "pen", "--base-part", *options)
    assert "only the sequences that start from the base part 'body'" in out
    assert f"x {sequences} sequences instead of {intentions} intentions" in out


def test_the_pen_without_technical_constraints_by_hand(capsys):
    """Every sequence starts by joining two single parts: over the six parts, each sequence is counted twice."""
    total = sum(_by_hand(capsys, part)[0] for part in ("ink", "cartridge", "head", "body", "cap", "button"))
    assert total == 2 * 24


@pytest.fixture(scope="module")
def body_model(pen):
    model = intention_model(make_plan(pen), base_part="body")
    policy = PointBasedSolver(max_iterations=200, time_limit=None, precision=1e-3, seed=0).solve(model.pomdp).policy
    return model, policy


@pytest.fixture(scope="module")
def body_policy(body_model, tmp_path_factory):
    path = tmp_path_factory.mktemp("policy") / "pen-body.policy"
    write_policy(body_model[1], path)
    return path


def test_pomdp_solve_simulate_evaluate(capsys, tmp_path, body_model, body_policy):
    model, _ = body_model
    n = model.pomdp.n_states
    code, out, _ = run(capsys, "pomdp", "pen", "--base-part", "-o", tmp_path / "pen.pomdp")
    assert code == 0 and f"{n} states" in out
    code, out, _ = run(capsys, "solve", "pen", "--base-part", "body", "-o", tmp_path / "pen.policy", "--json",
                       "--trials", "20", "--precision", "1000")
    assert code == 0 and "lower_bound" in out
    code, out, _ = run(capsys, "simulate", "pen", "--base-part", "--policy", body_policy, "--all", "--json")
    episodes = [json.loads(line) for line in out.splitlines()[:-1]]  # then the run's line
    assert code == 0 and len(episodes) == len(model.full_sequences())
    assert all(_joins("body", e["operations"][0]) for e in episodes)
    code, out, _ = run(capsys, "evaluate", "pen", "--base-part", "--policy", body_policy, "--episodes", 20, "--json")
    assert code == 0 and json.loads(out)["episodes"] == 20
    # The policy of the restricted model does not fit the whole model.
    code, _, err = run(capsys, "evaluate", "pen", "--policy", body_policy, "--episodes", 2)
    assert code == 1 and err


def test_bad_base_parts(capsys, tmp_path):
    for command in (("stats", "pen"), ("intentions", "pen"), ("pomdp", "pen", "-o", tmp_path / "x.pomdpx"),
                    ("evaluate", "pen", "--episodes", 1, "--time-limit", 0.1)):
        code, _, err = run(capsys, *command, "--base-part", "lid")
        assert code == 1 and "base part 'lid' is not a part of the product; parts: ink, cartridge" in err, command
    assert not (tmp_path / "x.pomdpx").exists()
    code, _, err = run(capsys, "stats", "pen", "--base-part", "ink", "--technical")
    assert code == 0  # counting zero sequences is an answer ...
    code, _, err = run(capsys, "pomdp", "pen", "--technical", "--base-part", "ink", "-o", tmp_path / "x.pomdpx")
    assert code == 1 and "no assembly sequence starts from the base part 'ink'" in err  # ... a model is not
    run(capsys, "pomdp", "pen", "-o", tmp_path / "pen.pomdpx")
    for command in ("solve", "evaluate"):
        code, _, err = run(capsys, command, tmp_path / "pen.pomdpx", "--base-part", "-o", tmp_path / "p.policy")\
            if command == "solve" else run(capsys, command, tmp_path / "pen.pomdpx", "--base-part", "--episodes", 1)
        assert code == 1 and "a base part applies to products only" in err
    done = _aplan("session", tmp_path / "pen.pomdpx", "--base-part", "--keyboard", "--log", tmp_path / "s.jsonl")
    assert done.returncode == 1 and "needs a PRODUCT" in done.stderr and "--base-part, too, applies to products only" \
        in done.stderr and not (tmp_path / "s.jsonl").exists()


def test_session_logs_the_base_part_and_replay_rebuilds_the_model(body_model, body_policy, tmp_path):
    model, policy = body_model
    start = int(model.full_sequences()[-1])
    operator = ScriptedOperator.following(model, start)
    expected = run_session(model, policy, operator, ScriptedRobot(on_perform=operator.robot_acting))
    lines = []
    for action, z in zip(expected.actions, expected.observations):
        if model.actions[action] != "wait":
            lines.append("")  # the person standing in for the robot presses Enter
        observation = model.plan.observations[z]
        lines.append(" ".join(observation.parts + ((observation.tool,) if observation.tool else ())))
    log = tmp_path / "k.jsonl"
    done = _aplan("session", "pen", "--base-part", "--policy", body_policy, "--keyboard", "--log", log,
                  stdin="\n".join(lines) + "\n")
    assert done.returncode == 0, done.stderr
    first = json.loads(log.read_text().splitlines()[0])
    assert first["settings"]["base_part"] == "body" and first["n_intentions"] == model.pomdp.n_states
    replayed = replay(log)
    assert replayed.model.base_part == "body" and replayed.model.pomdp.n_states == model.pomdp.n_states
    assert replayed.observations == expected.observations and not replayed.mismatches
    shown = _aplan("replay", log)
    assert shown.returncode == 0 and "beliefs reproduced" in shown.stdout
