"""Sessions with actions named by the parts they join (``aplan session --joins``, issue 23, docs/parallel.md "In
a session"): in the simulated camera cell (``--demo K``) the robot joins two parts the operator's sequence joins
only later (not its next step), its action event names the join and the operation reported (the join's at the
belief's most probable state), the operator goes on with its sequence projected onto the new state, and ``aplan
replay`` recomputes every belief and every reported operation; the same session run here (the same model and
planner, no clock) makes the same decisions. With habits learned from scripted logs (``--model confident
--joins``, and the preset ``--model helpful`` that names them) the robot does more; from the keyboard the typed
picks give the same decisions. The preset is refused where joins cannot go."""
from __future__ import annotations

import json

import numpy as np
import pytest

from aplan_runner import run_aplan
from planner.assembly import make_plan
from planner.decision.factored_model import FactoredBelief, factored_model
from planner.decision.habits import habit_weights
from planner.decision.intention_model import Rewards
from planner.decision.io.habits_file import read_habits
from planner.decision.joins import performed
from planner.decision.online import OnlinePlanner
from planner.decision.presets import CONFIDENT, HELPFUL, preset_habits, wrong_for_confidence
from planner.decision.projected import PROJECTED_CONFIDENCE
from planner.runtime.interfaces import Instruction, instruction_for, instruction_of_operation, with_join
from planner.runtime.log import EventLog
from planner.runtime.progress import AssemblyProgress
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
from planner.runtime.session import run_session
from test_habit_sessions import learn_habits

EXPANSIONS = 20  # no clock: the same decisions in the test's own run and in the command's
EARLY = 8  # the rank of a pen sequence whose robot joins ahead of the operator under the uniform prior
HABIT_RANK = 1  # the operator of the habits: under the uniform prior its robot never joins ahead
ROBOT_WRONG = wrong_for_confidence(PROJECTED_CONFIDENCE)  # the joins model's own default (-490)


def _events(path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def _actions(events) -> list[int]:
    return [e["action"] for e in events if e["event"] == "action"]


def _robot(events) -> int:
    return sum(e["event"] == "action" and e["name"] != "wait" for e in events)


def _replays(log) -> str:
    replay = run_aplan("replay", log)
    assert replay.returncode == 0 and "beliefs and the operations of its" in replay.stdout, \
        replay.stdout + replay.stderr
    return replay.stdout


def _world(model, rank: int, events) -> ScriptedOperator:
    """The operator of sequence ``rank`` replayed through the logged robot actions and told each join as the
    session told it: the observations it makes must be the logged ones (the cell showed them)."""
    operator = ScriptedOperator(model.plan, model.sequence_operations(model.sequence(rank)))
    for event in events:
        if event["event"] == "action" and event["name"] != "wait":
            operator.robot_acting(Instruction(event["step"], event["action"], event["name"], event["operation"],
                                              join=tuple(event["join"]), performs=performed(model, event["action"])))
        elif event["event"] == "observation":
            assert str(operator.observe()) == event["observation"]
    return operator


def _here(model, rank: int, tmp_path, name: str):
    """The session run in-process: the scripted operator as the source, the same planner."""
    operator = ScriptedOperator(model.plan, model.sequence_operations(model.sequence(rank)))
    done = run_session(model, OnlinePlanner(model, expansions=EXPANSIONS), operator, ScriptedRobot(),
                       EventLog(tmp_path / f"{name}.jsonl"))
    assert done.assembled
    return operator, _events(tmp_path / f"{name}.jsonl")


def _habit_sessions(learned, tmp_path, **models: list[str]) -> dict[str, list[dict]]:
    """Per name, the events of ``aplan session pen --demo HABIT_RANK --habits LEARNED`` with that name's model
    options; each session assembles and its log replays."""
    runs = {}
    for name, model in models.items():
        log = tmp_path / f"{name}.jsonl"
        done = run_aplan("session", "pen", "--demo", HABIT_RANK, "--habits", learned, *model, "--expansions",
                         EXPANSIONS, "--log", log)
        assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stdout + done.stderr
        _replays(log)
        runs[name] = _events(log)
    return runs


@pytest.fixture(scope="module")
def joins(pen):
    plan = make_plan(pen)
    return factored_model(plan, Rewards(wrong=ROBOT_WRONG), parallel="joins")


@pytest.fixture(scope="module")
def learned(pen, tmp_path_factory):
    """Habits of an operator who did sequence HABIT_RANK in 3 logged sessions alone, learned by ``aplan
    habits``."""
    return learn_habits(pen, tmp_path_factory.mktemp("join-habits"), HABIT_RANK, 3)[1]


@pytest.fixture(scope="module")
def cell_log(tmp_path_factory):
    """``aplan session pen --joins --demo EARLY``'s log."""
    log = tmp_path_factory.mktemp("join-cell") / "cell.jsonl"
    done = run_aplan("session", "pen", "--joins", "--demo", EARLY, "--expansions", EXPANSIONS, "--log", log)
    assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stdout + done.stderr
    return log


def test_a_cell_session_joins_ahead_of_the_operator_and_replays(joins, cell_log, tmp_path):
    log = cell_log
    events = _events(log)
    assert events[0]["settings"]["parallel"] == "joins"
    assert events[0]["settings"]["rewards"]["wrong"] == pytest.approx(ROBOT_WRONG)
    robot = [e for e in events if e["event"] == "action" and e["name"] != "wait"]
    assert robot and all(e["instruction"].startswith("join {} to {}".format(*e["join"])) for e in robot)
    operator = _world(joins, EARLY, events)
    assert operator.ahead and not operator.off_script and not operator.remaining  # a join early, none wrong
    assert f"its {len(robot)} joins reproduced" in _replays(log)
    habits = tmp_path / "habits.json"  # a log of joins teaches habits: the robot's joins walked at the true state
    done = run_aplan("habits", log, "-o", habits)
    assert done.returncode == 0, done.stderr
    assert sum(n for _, _, n in read_habits(habits).counts) == pytest.approx(5 - len(robot))  # the operator's steps
    shown = run_aplan("sequence", "pen", "--log", log)  # what the 3-D panel shows of the log
    assert shown.returncode == 0 and "recorded, 5 operations" in shown.stdout, shown.stdout + shown.stderr
    _, here = _here(joins, EARLY, tmp_path, "here")
    assert _actions(here) == _actions(events)
    assert [e.get("operation") for e in here if e["event"] == "action"] == \
        [e.get("operation") for e in events if e["event"] == "action"]


def test_with_habits_the_robot_does_more_and_the_preset_is_the_same_model(joins, learned, tmp_path):
    uniform, plain = _here(joins, HABIT_RANK, tmp_path, "uniform")
    runs = _habit_sessions(learned, tmp_path, confident=["--model", "confident", "--joins"],
                           helpful=["--model", "helpful"])
    start = runs["helpful"][0]["settings"]
    assert start["parallel"] == "joins" and start["rewards"]["wrong"] == pytest.approx(ROBOT_WRONG)
    assert (start["habits"]["prior"], start["habits"]["prior_per"]) == (HELPFUL.prior, HELPFUL.prior_per)
    assert _actions(runs["helpful"]) == _actions(runs["confident"])
    operator = _world(joins, HABIT_RANK, runs["helpful"])
    assert operator.ahead and not operator.off_script
    assert not uniform.ahead  # without the habits the robot joins nothing ahead for this operator
    assert _robot(runs["helpful"]) > _robot(plain)


def test_the_camera_preset_is_helpful_observing_steps(learned, tmp_path):
    """``--model camera`` is ``--model helpful --observe step`` (the same decisions, recorded as such, the log
    replays); contradicting its observations is a usage error."""
    runs = _habit_sessions(learned, tmp_path, camera=["--model", "camera"],
                           helpful=["--model", "helpful", "--observe", "step"])
    start = runs["camera"][0]["settings"]
    assert (start["observe"], start["parallel"]) == ("step", "joins")
    assert start["rewards"]["wrong"] == pytest.approx(ROBOT_WRONG)
    assert _actions(runs["camera"]) == _actions(runs["helpful"]) and _robot(runs["camera"]) > 0
    bad = run_aplan("session", "pen", "--demo", HABIT_RANK, "--habits", learned, "--model", "camera", "--observe",
                    "state", "--log", tmp_path / "bad.jsonl")
    assert bad.returncode == 2 and "--model camera reads observations of the step" in bad.stderr, bad.stderr
    assert not (tmp_path / "bad.jsonl").exists()


@pytest.mark.parametrize("model", ["uniform", "confident"])
def test_a_keyboard_session_with_joins_makes_the_same_decisions(joins, learned, model, tmp_path):
    """The keyboard's lines are what the operator was seen picking in the same session run here (without habits,
    and with ``--habits H --model confident``): the command's robot does the same joins, reported as the same
    operations, one of them ahead of the operator, and the log replays."""
    if model == "uniform":
        here_model, rank, extra = joins, EARLY, []
    else:
        habits = preset_habits(CONFIDENT, read_habits(learned))
        here_model = factored_model(joins.plan, joins.rewards, weights=habit_weights(joins.plan, habits),
                                    parallel="joins")
        rank, extra = HABIT_RANK, ["--habits", learned, "--model", "confident"]
    operator, here = _here(here_model, rank, tmp_path, "here")
    assert operator.ahead
    picks = []  # one line per step: the parts and tool seen, an empty line for nothing
    for event in here:
        if event["event"] == "observation":
            seen = joins.plan.observations[event["index"]]
            picks.append(" ".join(seen.parts + ((seen.tool,) if seen.tool else ())))
    log = tmp_path / "keyboard.jsonl"
    done = run_aplan("session", "pen", "--keyboard", "--robot", "auto", "--joins", *extra,
                     "--expansions", EXPANSIONS, "--log", log, stdin="\n".join(picks) + "\n")
    assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stdout + done.stderr
    events = _events(log)
    assert _actions(events) == _actions(here)
    told = [e["instruction"] for e in events if e["event"] == "action"]
    assert told == [e["instruction"] for e in here if e["event"] == "action"]
    assert all(f"robot, step {k}: {text}" in done.stderr + done.stdout for k, text in enumerate(told, start=1)
               if text.startswith("join "))  # the person at the keyboard sees what the robot joins
    _replays(log)


def test_the_preset_is_refused_where_joins_cannot_go(learned, tmp_path):
    model_file = tmp_path / "pen.pomdpx"
    assert run_aplan("pomdp", "pen", "-o", model_file).returncode == 0
    done = run_aplan("evaluate", model_file, "--model", "helpful", "--habits", learned)
    assert done.returncode == 1 and "--model helpful" in done.stderr and "give the PRODUCT" in done.stderr
    done = run_aplan("simulate", "pen", "--model", "helpful", "--habits", learned, "--planner", "offline",
                     "--random", "1")
    assert done.returncode == 1 and "--model helpful" in done.stderr and "--planner online" in done.stderr
    done = run_aplan("simulate", "pen", "--model", "helpful", "--habits", learned, "--projected", "--random", "1")
    assert done.returncode == 2 and "--model helpful is the model of --joins" in done.stderr
    done = run_aplan("session", "pen", "--model", "helpful", "--demo", "0", "--log", tmp_path / "x.jsonl")
    assert done.returncode != 0 and "needs the habits" in done.stderr and not (tmp_path / "x.jsonl").exists()


def _spread(model, action: int):
    """Two state edges of the join ``action`` at different states, and a belief of 0.7 and 0.3 on those states."""
    E = model.final_class
    edges = np.flatnonzero(model.class_action[:E] == action)
    first = int(edges[0])
    second = int(next(e for e in edges if model.class_source[e] != model.class_source[first]))
    classes = np.array(sorted([first, second]))
    mass = np.where(classes == first, 0.7, 0.3)
    return first, second, FactoredBelief(classes, mass)


def test_a_join_unsure_of_the_state_reports_the_most_probable_states_operation(joins):
    """A belief of 0.7 and 0.3 on two states where ink to cartridge applies as two operations: the one at the 0.7
    state is reported, the motion is not the same, the robot may take what either takes, and the session's
    assembly state follows each state's own operation."""
    action = next(k for k, name in enumerate(joins.actions) if name.endswith(":join(ink,cartridge)"))
    first, second, belief = _spread(joins, action)
    ops = [int(joins.class_operation[e]) for e in (first, second)]
    assert ops[0] != ops[1]
    told = instruction_for(joins, action, 1, belief)
    assert told.join == ("ink", "cartridge") and told.operation == ops[0] and not told.same_motion
    assert "the block that holds ink to the block that holds cartridge; most likely join {" in told.text
    assert set(told.takes) == set().union(*(instruction_of_operation(joins.plan, op).picks for op in ops))
    assert set(ops) <= set(told.performs)
    sure = instruction_for(joins, action, 1, FactoredBelief(belief.classes[belief.classes == first], belief.mass[:1]))
    assert sure.same_motion and sure.text.startswith("join ink to cartridge: join {")
    progress = AssemblyProgress(joins.plan)
    progress.set_states({int(joins.class_source[e]) for e in (first, second)})
    assert progress.robot(told.performs)
    assert progress.states == {int(joins.class_target[e]) for e in (first, second)}


def test_replay_refuses_a_log_whose_reported_join_operation_was_changed(cell_log, tmp_path):
    events = _events(cell_log)
    step = next(e for e in events if e["event"] == "action" and "join" in e)
    step["operation"] += 1
    changed = tmp_path / "changed.jsonl"
    changed.write_text("".join(json.dumps(e) + "\n" for e in events))
    done = run_aplan("replay", changed)
    assert done.returncode == 1 and f"joins differ from the ones the recomputed beliefs give at steps {step['step']}" \
        in done.stderr, done.stderr


def test_a_join_is_done_at_the_true_state_also_when_a_goal_carried_it(joins):
    """The ROS goal has no field for the join: its name says it (``aK:join(P,Q)``) and its operation is the
    reported one; :func:`with_join` gives back the join's operations, and the simulated cell's operator does
    the one of its true state, whichever state the report was of."""
    action = next(k for k, name in enumerate(joins.actions) if name.endswith(":join(ink,cartridge)"))
    first, second, _ = _spread(joins, action)
    plan = joins.plan
    reported = int(joins.class_operation[second])  # the report is of the second state, the truth the first
    goal = with_join(plan, Instruction(1, action, joins.actions[action], reported))
    assert goal.join == ("ink", "cartridge") and goal.performs == performed(joins, action)
    assert with_join(plan, Instruction(1, joins.wait, "wait")).join is None
    operator = ScriptedOperator(plan, [])
    operator.state = int(joins.class_source[first])
    done = operator.robot_acting(goal)
    assert done == int(joins.class_operation[first]) and done != reported


def test_a_robot_that_could_not_join_stops_the_session_as_for_any_action(joins, tmp_path):
    """The robot answers "failed" at its first join: the session ends ``robot failed`` with the belief of the step
    before, as for any action, and the log replays."""
    _, here = _here(joins, EARLY, tmp_path, "here")
    first = next(e["step"] for e in here if e["event"] == "action" and "join" in e)
    operator = ScriptedOperator(joins.plan, joins.sequence_operations(joins.sequence(EARLY)))
    done = run_session(joins, OnlinePlanner(joins, expansions=EXPANSIONS), operator, ScriptedRobot(fail_at={first}),
                       EventLog(tmp_path / "failed.jsonl"), settings={"parallel": "joins"})  # what replay rebuilds
    assert done.reason == "robot failed" and f"step {first}: the robot could not join" in done.message
    assert len(done.beliefs) == first and done.belief is done.beliefs[-1]
    _replays(tmp_path / "failed.jsonl")
