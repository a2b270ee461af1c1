"""The camera that sees the pieces joined (``--observe join``; planner/assembly/tags.py
``join_observation_table``, planner/decision/step_observations.py): one observation per operation, each naming
its two inputs; with no missed detection the filter knows the assembly state after every step (where the tray
camera's alphabet, ``--observe step``, leaves states it cannot tell apart); a session refuses it (its camera
and keyboard report the loose parts and tool only); the simulated camera world runs it without a reset.
The filter's exactness over every completion, and the POMDP over (class, seen) pairs, are checked with the
step model's in test_step_observations.py (parametrised over both alphabets)."""
from __future__ import annotations

import json
from argparse import Namespace

import numpy as np
import pytest
from aplan_runner import run_aplan

from planner import chain_product, complete_product, make_plan
from planner.assembly.plan import with_join_observations
from planner.assembly.tags import BLANK
from planner.decision import FactoredUpdater, factored_model
from planner.decision.online import OnlinePlanner
from planner.cli.options.models import observe_from
from planner.decision.step_observations import JOIN, STEP
from planner.errors import UsageError


@pytest.fixture(scope="module")
def plans(pen):
    return {"pen": make_plan(pen, True), "chain 5": make_plan(chain_product(5)),
            "complete 4": make_plan(complete_product(4))}


@pytest.mark.parametrize("product", ["pen", "chain 5", "complete 4"])
def test_each_operation_has_its_own_observation_naming_its_inputs(plans, product):
    plan = with_join_observations(plans[product])
    andor = plan.andor
    assert plan.observations[0] == BLANK and len(plan.observations) == len(andor.operations) + 1
    assert len(set(plan.observations)) == len(plan.observations)  # distinct: the observation names the operation
    assert np.array_equal(plan.operation_observation, np.arange(1, len(andor.operations) + 1))
    for j in range(len(andor.operations)):
        seen = plan.observations[plan.operation_observation[j]]
        first, second = andor.inputs(j)
        assert seen != BLANK
        assert set(seen.parts) | {p for piece in seen.pieces for p in piece} == first | second
        assert set(map(frozenset, seen.pieces)) == {s for s in (first, second) if len(s) > 1}
        assert seen.tool == plan.tags.tool[j]
    # the tray camera's alphabet is the paper's, unchanged beside it
    assert plans[product].observations[0] == BLANK and not any(o.pieces for o in plans[product].observations)


def _true_state_mass(model, belief, state: int) -> float:
    return float(belief.mass[model.class_source[belief.classes] == state].sum())


def _known_after_every_step(model, sequence) -> list[float]:
    """The operator does ``sequence`` (state edges) one per step while the robot waits, every step seen: the
    belief on the true assembly state after each step."""
    updater = FactoredUpdater(model)
    belief, known = updater.initialize(), []
    for edge in sequence:
        z = int(model.plan.operation_observation[model.class_operation[edge]])
        belief = updater.update(belief, model.wait, z)
        known.append(_true_state_mass(model, belief, int(model.class_target[edge])))
    assert updater.events == []
    return known


@pytest.mark.parametrize("product", ["chain 5", "complete 4"])
def test_with_every_step_seen_the_state_is_known_after_each(plans, product):
    """Closed form: each seen operation names its inputs, so the history of operations from the initial state
    names the state (mass 1 on it, to rounding). The tray camera's alphabet does not: on these products some
    operations join two subassemblies without a tool (blank to it), and some states share every history."""
    join, step = factored_model(plans[product], observe=JOIN), factored_model(plans[product], observe=STEP)
    least_step = 1.0
    for r in range(join.n_sequences):
        sequence = join.sequence(r)
        assert min(_known_after_every_step(join, sequence)) == pytest.approx(1.0, abs=1e-12)
        least_step = min(least_step, min(_known_after_every_step(step, step.sequence(r))))
    assert least_step < 0.9


def test_the_camera_world_runs_it_without_a_reset(plans):
    from planner import api
    from planner.decision.operators import parse_operator

    model = factored_model(plans["pen"], parallel="joins", observe=JOIN)
    choice = api.EpisodeChoice(random=6, seed=3, operator_model=parse_operator("uniform,changing:0.3"),
                               world="camera")
    episodes = api.simulate(model, OnlinePlanner(model, expansions=40), choice)
    assert all(e.finished for e in episodes) and sum(e.resets for e in episodes) == 0


def test_a_camera_session_refuses_it_and_the_presets_take_it(tmp_path):
    log = tmp_path / "s.jsonl"
    done = run_aplan("session", "pen", "--demo", "1", "--observe", "join", "--log", log)
    assert done.returncode == 2 and "--observe join needs a camera that sees the pieces" in done.stderr, done.stderr
    assert "--keyboard (a person types which pieces were joined)" in done.stderr
    assert not log.exists()
    paper = run_aplan("simulate", "pen", "--random", "1", "--observe", "join", "--model", "paper")
    assert paper.returncode == 2 and "--model paper is Alg. 3 as published" in paper.stderr, paper.stderr
    # the camera preset reads either camera's observations, not the paper's
    assert observe_from(Namespace(observe=JOIN, habit_model="camera")) == JOIN
    assert observe_from(Namespace(observe=None, habit_model="camera")) == STEP
    with pytest.raises(UsageError, match="--model camera reads observations of the step"):
        observe_from(Namespace(observe="state", habit_model="camera"))


def test_at_the_keyboard_the_person_tells_the_pieces_and_the_log_replays(pen, tmp_path):
    """``aplan session pen --keyboard --observe join``: the choices are numbered and name the pieces; the person
    types the number of the first each step (a number past the list, and loose parts that name no piece, are
    asked again); the product is assembled, every operator step the log records is one of the join alphabet
    (one that joins a subassembly names it), and the log replays."""
    log = tmp_path / "k.jsonl"
    # 9: past the list; head: loose parts that name no piece (both asked again); then the first choice each step,
    # and Enter once nothing shows (the robot did the last operation: the online planner at 20 expansions)
    lines = ["9", "head", "1", "1", "1", "", "", ""]
    done = run_aplan("session", "pen", "--keyboard", "--robot", "auto", "--observe", "join", "--joins",
                     "--expansions", "20", "--log", log, stdin="\n".join(lines) + "\n")
    assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stdout + done.stderr
    assert "not one of the choices: 9" in done.stderr and "which pieces did these join?" in done.stderr
    assert "the operator could pick now: 1. " in done.stderr
    events = [json.loads(line) for line in log.read_text().splitlines()]
    assert events[0]["settings"]["observe"] == JOIN
    plan = with_join_observations(make_plan(pen))
    seen = [e for e in events if e["event"] == "observation" and e["index"]]
    assert seen and all(plan.observations[e["index"]] != BLANK and not e["ignored"] for e in seen)
    assert any("{" in e["observation"] for e in seen)  # a step that joined a subassembly names its parts
    replay = run_aplan("replay", log)
    assert replay.returncode == 0 and "beliefs and the operations of its" in replay.stdout, replay.stderr


def test_the_keyboard_takes_a_number_a_choice_as_shown_or_loose_parts_that_name_no_piece(pen):
    from planner.runtime.console import KeyboardSource

    plan = with_join_observations(make_plan(pen))  # the file's technical constraints, as aplan session pen
    typed, said = iter(["2", "{body button}+{cartridge head ink}+[hammer]", "cartridge ink hammer", ""]), []
    source = KeyboardSource(pen, read=lambda prompt: next(typed), write=said.append, joins=plan.observations)
    choices = ["cartridge+head+[hammer]", "cartridge+ink+[hammer]", "{body button}+{cartridge head ink}+[hammer]"]
    source.offer(choices)
    assert said[-1].endswith("1. cartridge+head+[hammer], 2. cartridge+ink+[hammer], 3. {body button}+"
                             "{cartridge head ink}+[hammer]")
    first, second, third, fourth = (source.observe() for _ in range(4))
    assert str(first) == "cartridge+ink+[hammer]" and first in plan.observations
    assert second.pieces == (("body", "button"), ("cartridge", "head", "ink")) and second.tool == "hammer"
    assert str(third) == "cartridge+ink+[hammer]"  # loose parts alone: as typed, a choice of the alphabet
    assert fourth == BLANK


def test_seeing_the_pieces_is_worth_more_and_the_solver_certifies_it(tmp_path):
    """Blackwell: the tray camera's observation of a step is a function of the join camera's (drop the pieces),
    so the optimal value with the join camera's cannot be lower. On the pen (the paper's rewards and robot, the
    POMDPs over (class, seen) pairs), 200 trials of the solver certify more: the join camera's lower bound lies
    above the tray camera's upper bound."""
    bounds = {}
    for observe in (STEP, JOIN):
        model, policy = tmp_path / f"{observe}.pomdpx", tmp_path / f"{observe}.policy"
        assert run_aplan("pomdp", "pen", "--lumped", "--observe", observe, "-o", model).returncode == 0
        done = run_aplan("solve", model, "-o", policy, "--trials", "200", "--time-limit", "600", "--json")
        assert done.returncode == 0, done.stderr
        bounds[observe] = json.loads(done.stdout.strip().splitlines()[-1])
    assert bounds[JOIN]["lower_bound"] > bounds[STEP]["upper_bound"], bounds
