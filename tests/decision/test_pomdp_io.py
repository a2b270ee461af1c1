"""POMDP files, policies, the belief filter and the solver on problems with known answers."""
from __future__ import annotations

import json
import logging

import numpy as np
import pytest
from aplan_runner import run_aplan
from conftest import PEN_MODELS, require_shared

from planner import make_plan
from planner.decision import intention_pomdp
from planner.decision.belief import DiscreteUpdater
from planner.decision.io.cassandra import CassandraError, read_cassandra, write_cassandra
from planner.decision.io.pomdpx import PomdpxError, read_pomdpx
from planner.decision.policy import AlphaVectorPolicy, PolicyError, read_policy, write_policy
from planner.decision.solvers import PointBasedSolver

# Two doors, the prize behind one: 'look' (reward 0) shows where it is for sure; opening the right door gives
# +1, the wrong one -1, and the prize is hidden again. Best: look, open, repeat: V* = gamma / (1 - gamma^2).
DOORS = """
discount: 0.9
values: reward
states: left right
actions: look open-left open-right
observations: saw-left saw-right
start: uniform
T: look
identity
T: open-left
uniform
T: open-right : * : * 0.5
O: look : left : saw-left 1.0
O: look : right : saw-right 1.0
O: open-left
uniform
O: open-right
0.5 0.5
0.5 0.5
R: open-left : left : * : * 1
R: open-left : right : * : * -1
R: open-right : left : * : * -1
R: open-right : right : * : * 1
"""


@pytest.fixture
def doors(tmp_path):
    path = tmp_path / "doors.pomdp"
    path.write_text(DOORS)
    return read_cassandra(path)


def test_cassandra_reader(doors):
    assert doors.states == ("left", "right") and doors.n_actions == 3
    T, O = doors.dense()
    assert np.allclose(T[0], np.eye(2)) and np.allclose(T[1], 0.5) and np.allclose(T[2], 0.5)
    assert np.allclose(O[0], np.eye(2)) and np.allclose(O[2], 0.5)
    assert np.allclose(doors.reward, [[0, 0], [1, -1], [-1, 1]])


def test_solver_brackets_the_closed_form(doors):
    result = PointBasedSolver(time_limit=None, max_iterations=100, precision=1e-4).solve(doors)
    exact = 0.9 / (1 - 0.9 ** 2)
    assert result.lower_bound - 1e-9 <= exact <= result.upper_bound + 1e-9
    assert result.gap <= 1e-4
    assert result.policy.action(doors.initial) == 0  # look first


def test_solver_is_deterministic(doors):
    first = PointBasedSolver(max_iterations=5, time_limit=None).solve(doors)
    second = PointBasedSolver(max_iterations=5, time_limit=None).solve(doors)
    assert np.array_equal(first.policy.alphas, second.policy.alphas)


def test_pen_round_trips_through_cassandra(tmp_path, pen):
    model = intention_pomdp(make_plan(pen))
    write_cassandra(model, tmp_path / "pen.pomdp")
    again = read_cassandra(tmp_path / "pen.pomdp")
    T1, O1 = model.dense()
    T2, O2 = again.dense()
    assert np.allclose(T1, T2) and np.allclose(O1, O2) and np.allclose(model.reward, again.reward)


def test_policy_round_trip_and_mismatch(tmp_path, doors):
    policy = AlphaVectorPolicy(np.array([[1.0, 2.0], [3.0, 0.5]]), np.array([0, 2]))
    write_policy(policy, tmp_path / "p.policy")
    again = read_policy(tmp_path / "p.policy", doors)
    assert np.array_equal(again.alphas, policy.alphas) and np.array_equal(again.actions, policy.actions)
    assert again.action(np.array([1.0, 0.0])) == 2 and again.value(np.array([0.0, 1.0])) == 2.0
    wrong = AlphaVectorPolicy(np.zeros((1, 3)), np.array([0]))
    write_policy(wrong, tmp_path / "w.policy")
    with pytest.raises(PolicyError, match="vectors of length 3, but the model has 2 states"):
        read_policy(tmp_path / "w.policy", doors)
    (tmp_path / "t.policy").write_text("<Policy><AlphaVector vectorLength='2'><Vector action='0'>1 2")
    with pytest.raises(PolicyError, match="malformed XML"):
        read_policy(tmp_path / "t.policy")


def test_belief_update_and_unexplained_observation(pen, caplog):
    model = intention_pomdp(make_plan(pen))
    updater = DiscreteUpdater(model)
    belief = updater.initialize()
    wait = model.actions.index("wait")
    blank = model.observations.index("blank")
    belief = updater.update(belief, wait, blank)
    assert belief.sum() == pytest.approx(1) and np.all(belief >= 0)
    # One step from the start, the operator can only have joined two single parts: "ink+[hammer]" (ink added to
    # a subassembly) is unexplained.
    impossible = model.observations.index("ink+[hammer]")
    with caplog.at_level(logging.WARNING, logger="planner.decision.belief"):
        reset = updater.update(model.initial, wait, impossible)
    assert [r.getMessage() for r in caplog.records] == [str(updater.events[-1])]
    assert "has probability 0 under the belief" in caplog.records[0].getMessage()
    assert not np.isnan(reset).any() and reset.sum() == pytest.approx(1)
    assert updater.events and updater.events[-1].reset_to in ("reachable", "emitting")
    likelihood = updater.observation_likelihood(wait, impossible)
    assert np.all(likelihood[reset > 0] > 0)


def test_bad_pomdpx_files(tmp_path):
    truncated = tmp_path / "t.pomdpx"
    truncated.write_text("<?xml version='1.0'?>\n<pomdpx>\n<Discount>0.9</Discount>\n<Variable>")
    with pytest.raises(PomdpxError, match=r"t.pomdpx: line \d+: malformed XML"):
        read_pomdpx(truncated)
    bomb = tmp_path / "bomb.pomdpx"
    bomb.write_text('<?xml version="1.0"?>\n<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;">]>\n'
                    "<pomdpx><Description>&lol2;</Description></pomdpx>")
    with pytest.raises(PomdpxError) as info:
        read_pomdpx(bomb)
    assert "lollol" not in str(info.value)
    external = tmp_path / "ext.pomdpx"
    external.write_text('<?xml version="1.0"?>\n<!DOCTYPE x [<!ENTITY e SYSTEM "http://example.invalid/x">]>\n'
                        "<pomdpx><Description>&e;</Description></pomdpx>")
    with pytest.raises(PomdpxError):
        read_pomdpx(external)


def test_probabilities_must_sum_to_one(tmp_path):
    bad = tmp_path / "bad.pomdp"
    bad.write_text(DOORS.replace("T: open-right : * : * 0.5", "T: open-right : * : * 0.4"))
    with pytest.raises(CassandraError, match=r"transition probabilities of action 'open-right' from state 'left' "
                                             r"sum to 0.8, not 1"):
        read_cassandra(bad)
    with pytest.raises(CassandraError, match=r"line 3: values must be reward or cost"):
        (tmp_path / "v.pomdp").write_text("discount: 0.9\n\nvalues: gain\n")
        read_cassandra(tmp_path / "v.pomdp")


def test_cli_pomdp_and_solve(tmp_path):
    model = tmp_path / "pen.pomdpx"
    done = run_aplan("pomdp", "pen", "--technical", "-o", model)
    assert done.returncode == 0 and "39 states, 18 actions, 10 observations" in done.stdout
    done = run_aplan("solve", model, "-o", tmp_path / "p.policy", "--trials", "20", "--json")
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert {"lower_bound", "upper_bound", "alpha_vectors", "seconds"} <= set(result)
    assert result["lower_bound"] <= result["upper_bound"]
    policy = read_policy(tmp_path / "p.policy", read_pomdpx(model))
    assert policy.alphas.shape[0] == result["alpha_vectors"]


def test_solver_on_the_reference_file_and_on_ours_agree(pen):
    reference = read_pomdpx(require_shared(PEN_MODELS / "reference_pomdp" / "pen_technical.pomdpx.gz"))
    ours = intention_pomdp(make_plan(pen, True))
    a = PointBasedSolver(max_iterations=3, time_limit=None).solve(reference)
    b = PointBasedSolver(max_iterations=3, time_limit=None).solve(ours)
    # Same model up to renumbering and 6-digit rounding: the same bounds after the same trials.
    assert a.lower_bound == pytest.approx(b.lower_bound, abs=1e-4)
    assert a.upper_bound == pytest.approx(b.upper_bound, abs=1e-4)
