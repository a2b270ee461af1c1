"""The operator-intent POMDP (Alg. 3): sizes, stochastic tables, POMDPX round trip, and the authors' models."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import PEN_MODELS, require_shared
from modelmatch import renumbering

from planner import PlannerError, make_plan
from planner.decision import Rewards, intention_pomdp
from planner.decision.io.pomdpx import read_pomdpx, write_pomdpx


@pytest.fixture(scope="module", params=[False, True], ids=["no-technical", "technical"])
def pen_model(request, pen):
    return request.param, intention_pomdp(make_plan(pen, request.param))


def test_pen_sizes(pen):
    model = intention_pomdp(make_plan(pen))
    assert (model.n_states, model.n_actions, model.n_observations) == (69, 22, 12)
    assert model.actions[-1] == "wait" and model.observations[0] == "blank"
    technical = intention_pomdp(make_plan(pen, True))
    assert (technical.n_states, technical.n_actions, technical.n_observations) == (39, 18, 10)


def test_rows_sum_to_one(pen_model):
    _, model = pen_model
    T, O = model.dense()
    assert np.allclose(T.sum(axis=2), 1) and np.allclose(O.sum(axis=2), 1)
    assert model.initial.sum() == pytest.approx(1)


@pytest.mark.parametrize("technical, name", [(False, "pen_no_technical"), (True, "pen_technical")])
def test_the_authors_models(pen, technical, name):
    reference = read_pomdpx(require_shared(PEN_MODELS / "reference_pomdp" / f"{name}.pomdpx.gz"))
    ours = intention_pomdp(make_plan(pen, technical))
    perm = renumbering(ours, reference)
    assert perm is not None, "no renumbering makes the tables equal"
    assert sorted(perm["s"]) == list(range(ours.n_states))  # a bijection
    # Spelled out on the dense tables (renumbering() checks the same before returning).
    T1, O1 = ours.dense()
    T2, O2 = reference.dense()
    s, a, z = perm["s"], perm["a"], perm["z"]
    assert np.allclose(T1, T2[a][:, s][:, :, s], atol=1e-6)
    assert np.allclose(O1, O2[a][:, s][:, :, z], atol=1e-6)
    assert np.array_equal(ours.reward, reference.reward[a][:, s])
    assert np.allclose(ours.initial, reference.initial[s], atol=1e-6)
    assert ours.actions[-1] == "wait" and np.all(reference.reward[a[-1]] == 0)


def test_pomdpx_round_trip_and_size(tmp_path, pen_model):
    _, model = pen_model
    path = tmp_path / "pen.pomdpx"
    write_pomdpx(model, path)
    again = read_pomdpx(path)
    T1, O1 = model.dense()
    T2, O2 = again.dense()
    assert np.allclose(T1, T2, atol=1e-12) and np.allclose(O1, O2, atol=1e-12)
    assert np.array_equal(model.reward, again.reward) and np.allclose(model.initial, again.initial)
    assert again.discount == model.discount
    assert path.stat().st_size < 300_000  # the authors' dense files: 5 and 18 MB
    # A name with XML's special characters is escaped in the file and reads back as it was.
    import dataclasses

    named = dataclasses.replace(model, name="pen <v2> & co")
    write_pomdpx(named, tmp_path / "named.pomdpx")
    assert "<Description>pen &lt;v2&gt; &amp; co</Description>" in (tmp_path / "named.pomdpx").read_text()
    assert read_pomdpx(tmp_path / "named.pomdpx").name == "pen <v2> & co"


def test_eagerness_is_configurable(pen):
    model = intention_pomdp(make_plan(pen), Rewards(unfavorable=5, favorable=-1, wrong=-100, wait=-0.5))
    assert set(np.unique(model.reward)) == {5, -1, -100, -0.5}


def test_the_model_says_what_each_action_does(pen):
    """Each action but wait performs the robot-capable operation its name describes; the POMDP is the same
    whether built alone or inside the model."""
    from planner.decision import intention_model

    plan = make_plan(pen)
    model = intention_model(plan)
    robot_operations = [int(o) for o in np.flatnonzero(plan.tags.robot)]
    assert [model.operation(a) for a in range(len(model.actions) - 1)] == robot_operations
    assert model.operation(len(model.actions) - 1) is None and model.actions[-1] == "wait"
    for action, operation in enumerate(robot_operations):
        assert model.actions[action] == f"a{action}:" + plan.andor.describe(operation).replace(" ", "")
    alone = intention_pomdp(plan)
    assert alone.states == model.pomdp.states and np.array_equal(alone.reward, model.pomdp.reward)
    assert model.final_state == 0 and model.graph.successor[model.final_state] < 0


def test_full_sequences_and_their_operations(pen):
    """The full sequences are the intentions at the initial state, each with one operation per join (parts - 1),
    joining every part exactly once in all; other intentions are refused, naming the range."""
    from planner.decision import intention_model

    model = intention_model(make_plan(pen))
    starts = model.full_sequences()
    assert len(starts) == 24  # the paper's 24 assembly sequences of the pen
    andor = model.plan.andor
    for start in starts:
        operations = model.sequence_operations(int(start))
        assert len(operations) == len(pen.parts) - 1
        assert len(model.describe_operations(int(start))) == len(operations)
        # Undoing the operations from the finished product ends with single parts: each split used once.
        sizes = sorted(len(andor.parts_of(andor.operations[o].parent)) for o in operations)
        assert sizes[-1] == len(pen.parts)
        assert model.full_sequence(int(start)) == int(start)
    inner = int(np.setdiff1d(np.arange(model.pomdp.n_states), starts)[0])
    with pytest.raises(PlannerError, match=rf"--demo {inner} is not a full assembly sequence; the sequences are "
                                            rf"the intentions {starts[0]}\.\.{starts[-1]}"):
        model.full_sequence(inner, "--demo")
    assert model.sequence_operations(model.final_state) == []
