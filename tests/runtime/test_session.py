"""The decision loop: end to end on rendered frames, the robot and source interfaces, failures, the JSON-lines
log and its replay."""
from __future__ import annotations

import json
import os
import logging

import numpy as np
import pytest
from aplan_runner import run_aplan
from listed_source import ListedSource
from pictures import assert_belief_plot

from planner import BLANK, Observation, make_plan
from planner.decision import intention_model
from planner.decision.solvers import PointBasedSolver
from planner.runtime.console import ConsoleRobot, KeyboardSource
from planner.runtime.interfaces import ObservationSource, Robot, instruction_for
from planner.runtime.log import EventLog, SessionError, replay
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot
from planner.runtime.session import run_session
from planner.runtime.tray import CameraModel, SimulatedCell, tray_layout
from planner.runtime.vision import VisionError, VisionSource, marker_map


@pytest.fixture(scope="module")
def setup(pen):
    plan = make_plan(pen)
    model = intention_model(plan)
    # A fixed amount of work and no clock, so the policy is the same on any machine (lower bound within 0.006
    # of the optimum: a policy that assembles every sequence).
    policy = PointBasedSolver(max_iterations=200, time_limit=None, precision=1e-3, seed=0).solve(model.pomdp).policy
    return plan, model, policy, model.graph


def _true_intentions(model, graph, start, log_events, operator_done):
    """The true intention after each step: the sequence's start moved one successor per operation done,
    checking that the operations were done in the sequence's order."""
    sequence = model.sequence_operations(start)
    done, truth, operator = [], [], iter(operator_done)
    for event in log_events:
        if event["event"] == "action" and model.actions[event["action"]] != "wait":
            done.append(model.operation(event["action"]))
        elif event["event"] == "observation" and event["observation"] != "blank":
            done.append(next(operator))
        elif event["event"] == "belief":
            assert sorted(done) == sorted(sequence[:len(done)])  # nobody left the operator's sequence
            j = start
            for _ in done:
                j = int(graph.successor[j])
            truth.append(j)
    return truth


def _vision_session(setup, start, camera, tmp_path=None):
    plan, model, policy, graph = setup
    markers = marker_map(plan.product)
    operator = ScriptedOperator.following(model, start)
    cell = SimulatedCell(tray_layout(markers, (960, 540), 48), operator, camera)
    robot = ScriptedRobot(on_perform=cell.robot)
    log = EventLog(tmp_path / "session.jsonl" if tmp_path else None)
    result = run_session(model, policy, VisionSource(cell, markers, quiet_frames=20), robot, log)
    log.close()
    return result, log, operator, robot


def test_end_to_end_on_rendered_frames(setup, tmp_path):
    """The pen, a scripted operator following one sequence, frames rendered per step: the loop ends with
    the product assembled and the belief on the true intention above 0.9; the vision changes nothing."""
    plan, model, policy, graph = setup
    start = int(graph.full_sequences()[10])
    result, log, operator, robot = _vision_session(setup, start, CameraModel(blur=1.2, noise=6, perspective=0.04,
                                                                       hands=True, seed=7), tmp_path)
    assert result.assembled, result.message
    assert result.operations == 5 and operator.remaining == [] and operator.off_script == []
    assert any(not i.is_wait for i in robot.performed)  # the robot did help
    truth = _true_intentions(model, graph, start, log.events, operator.done)
    p_true = [float(b[t]) for b, t in zip(result.beliefs[1:], truth)]
    assert truth[-1] == 0 and p_true[-1] > 0.9  # the finished product
    assert max(p_true[:-1]) > 0.9  # as in the paper: sure of the intention before the end

    # The same session with the operator's observations handed over directly gives the same beliefs.
    direct_operator = ScriptedOperator.following(model, start)
    direct = run_session(model, policy, direct_operator,
                         ScriptedRobot(on_perform=direct_operator.robot_acting))
    assert direct.actions == result.actions and direct.observations == result.observations
    assert all(np.allclose(a, b) for a, b in zip(direct.beliefs, result.beliefs))

    # The log replays to the same beliefs.
    replayed = replay(tmp_path / "session.jsonl")
    assert replayed.mismatches == [] and replayed.end["reason"] == "assembled"
    assert len(replayed.beliefs) == len(result.beliefs)
    assert all(np.allclose(a, b) for a, b in zip(replayed.beliefs, result.beliefs))


@pytest.mark.parametrize("k", range(0, 24, 5))
def test_every_kind_of_sequence_gets_assembled(setup, k):
    plan, model, policy, graph = setup
    start = int(graph.full_sequences()[k])
    operator = ScriptedOperator.following(model, start)
    log = EventLog()
    result = run_session(model, policy, operator, ScriptedRobot(), log)
    assert result.assembled and operator.off_script == []
    truth = _true_intentions(model, graph, start, log.events, operator.done)
    assert result.beliefs[-1][truth[-1]] > 0.9


def test_protocols(setup):
    plan, _, _, graph = setup
    markers = marker_map(plan.product)
    assert isinstance(VisionSource([], markers), ObservationSource)
    assert isinstance(ScriptedOperator(plan, []), ObservationSource)
    assert isinstance(KeyboardSource(plan.product), ObservationSource)
    assert isinstance(ScriptedRobot(), Robot) and isinstance(ConsoleRobot(), Robot)


def test_robot_failure_stops_cleanly(setup, tmp_path):
    plan, model, policy, graph = setup
    operator = ScriptedOperator.following(model, int(graph.full_sequences()[0]))
    log = EventLog(tmp_path / "fail.jsonl")
    result = run_session(model, policy, operator, ScriptedRobot(fail_at={3}), log)
    assert result.reason == "robot failed" and "step 3: the robot could not" in result.message
    assert "scripted failure at step 3" in result.message
    assert result.steps == 3 and len(result.beliefs) == 3  # b0 and the beliefs after steps 1 and 2
    assert np.array_equal(result.belief, result.beliefs[-1])
    lines = [json.loads(line) for line in (tmp_path / "fail.jsonl").read_text().splitlines()]
    assert [e["event"] for e in lines[-3:]] == ["action", "robot", "end"]
    assert lines[-1]["reason"] == "robot failed"
    assert replay(tmp_path / "fail.jsonl").mismatches == []


def test_observation_no_operation_explains(setup):
    """Picks no operation shows (two parts never joined directly) are ignored with a warning naming them and
    what the operator could pick; the step counts as blank and the session goes on (README, decision loop)."""
    plan, model, policy, _ = setup
    source = ListedSource([BLANK, Observation(("body", "ink"), "hammer")])
    log = EventLog()
    result = run_session(model, policy, source, ScriptedRobot(), log)
    assert result.reason == "source ended" and "ended at step 3" in result.message
    observation = [e for e in log.events if e["event"] == "observation"][1]
    assert observation["index"] is None and observation["ignored"] is True
    warnings = [e["message"] for e in log.events if e["event"] == "warning"]
    assert len(warnings) == 1 and warnings[0].startswith("body+ink+[hammer] ignored: no operation of the product "
                                                         "shows these picks")
    assert "the operator could pick: body+button+[hammer]," in warnings[0]
    assert result.observations == [0, 0]  # both counted as blank
    assert all(abs(b.sum() - 1) < 1e-9 for b in result.beliefs)


def test_impossible_observation_is_ignored_and_goes_on(setup, caplog):
    plan, model, policy, _ = setup
    # The hammer alone joins two subassemblies: impossible before anything was built. No operation explains it
    # in the initial assembly state, so it counts as blank: no belief reset.
    source = ListedSource([Observation((), "hammer"), BLANK])
    log = EventLog()
    with caplog.at_level(logging.WARNING, logger="planner"):
        result = run_session(model, policy, source, ScriptedRobot(), log)
    assert result.reason == "source ended" and "ended at step 3" in result.message
    warnings = [e for e in log.events if e["event"] == "warning"]
    assert len(warnings) == 1 and warnings[0]["message"].startswith(
        "[hammer] ignored: no operation explains it in the assembly state ({ink} {cartridge} {head} {body} {cap} "
        "{button})")
    assert caplog.records == []  # the session's log holds the warning; no second report through logging
    assert [e["reset"] for e in log.events if e["event"] == "belief"] == [None, None]
    assert all(abs(b.sum() - 1) < 1e-9 and np.isfinite(b).all() for b in result.beliefs)


def test_source_error_stops_cleanly(setup):
    plan, model, policy, _ = setup
    markers = marker_map(plan.product)

    def frames():
        yield np.zeros((540, 960, 3), np.uint8)
        raise VisionError("tray/0002.png: cannot be read as an image")

    result = run_session(model, policy, VisionSource(frames(), markers), ScriptedRobot())
    assert result.reason == "error" and "0002.png" in result.message


def test_interrupt_and_step_limit_stop_cleanly(setup):
    plan, model, policy, graph = setup

    class Interrupted(ListedSource):
        def observe(self):
            if not self.observations:
                raise KeyboardInterrupt
            return super().observe()

    log = EventLog()
    with pytest.raises(KeyboardInterrupt):  # never swallowed: the log ends, then the interrupt goes on
        run_session(model, policy, Interrupted([BLANK]), ScriptedRobot(), log)
    end = log.events[-1]
    assert end["event"] == "end" and end["reason"] == "interrupted" and end["message"] == "interrupted at step 2"
    assert sum(e["event"] == "belief" for e in log.events) == 1  # after step 1, the one step done
    operator = ScriptedOperator.following(model, int(graph.full_sequences()[0]), acts=lambda step: False)
    result = run_session(model, policy, operator, ScriptedRobot(), max_steps=3)
    assert result.reason == "step limit" and result.steps == 3 and len(result.beliefs) == 4


def test_console_robot_and_keyboard(setup):
    plan, model, policy, _ = setup
    shown = []
    answers = iter(["", "f gripper jammed"])
    robot = ConsoleRobot(read=lambda prompt: next(answers), write=shown.append)
    join = instruction_for(model, 0, 1)
    assert robot.perform(join).ok and "join {" in shown[-1] and "using the hammer" in shown[-1]
    report = robot.perform(join)
    assert not report.ok and report.message == "gripper jammed"
    wait = instruction_for(model, model.actions.index("wait"), 2)
    assert robot.perform(wait).ok  # waiting needs no confirmation

    def eof(prompt):
        raise EOFError

    assert not ConsoleRobot(read=eof, write=shown.append).perform(join).ok

    lines = iter(["ink, cartridge hammer", "pen", "ink hammer hammer2", "", "q"])
    said = []
    keyboard = KeyboardSource(plan.product, read=lambda prompt: next(lines), write=said.append)
    assert keyboard.observe() == Observation(("cartridge", "ink"), "hammer")
    assert keyboard.observe() == BLANK and "not a part or tool: pen" in said[0]
    assert keyboard.observe() is None
    # What the person at the keyboard is shown before the prompt: the robot acting by itself, the picks.
    shown = []
    keyboard = KeyboardSource(plan.product, read=lambda prompt: "", write=shown.append, show_robot=True)
    keyboard.robot_acting(join)
    keyboard.offer(["cartridge+ink+[hammer]"])
    keyboard.offer([])
    assert shown[0] == f"robot, step 1: {join.text}" and shown[1].endswith("could pick now: cartridge+ink+[hammer]")
    assert "nothing that shows" in shown[2]
    assert KeyboardSource(plan.product, write=shown.append).robot_acting(join) is None and len(shown) == 3


def test_log_is_never_overwritten_and_replay_checks(setup, tmp_path):
    plan, model, policy, graph = setup
    path = tmp_path / "s.jsonl"
    operator = ScriptedOperator.following(model, int(graph.full_sequences()[5]))
    log = EventLog(path)
    run_session(model, policy, operator, ScriptedRobot(on_perform=operator.robot_acting), log)
    log.close()
    with pytest.raises(SessionError, match="the log exists already"):
        EventLog(path)
    lines = path.read_text().splitlines()
    assert all(json.loads(line)["event"] for line in lines)
    # A line cut short by a crash is ignored; a tampered belief is reported.
    path.write_text("\n".join(lines) + '\n{"event": "act')
    assert replay(path).mismatches == []
    events = [json.loads(line) for line in lines]
    belief = next(e for e in events if e["event"] == "belief")
    belief["top"][0][1] = round(belief["top"][0][1] / 2, 6)
    path.write_text("".join(json.dumps(e) + "\n" for e in events))
    assert replay(path).mismatches == [belief["step"]]
    path.write_text("".join(json.dumps(e) + "\n" for e in events if e["event"] != "action"))
    with pytest.raises(SessionError, match=r"event \d+ \('observation'\): malformed or out of order"):
        replay(path)
    path.write_text('{"event": "robot"}\n')
    with pytest.raises(SessionError, match="not a session log"):
        replay(path)
    path.write_text('not json\n{"event": "start"}\n')
    with pytest.raises(SessionError, match="line 1: not JSON"):
        replay(path)


# ---------------------------------------------------------------------------------------------- command line


def _aplan(*args, stdin=""):
    return run_aplan(*args, stdin=stdin)


@pytest.fixture(scope="module")
def policy_file(setup, tmp_path_factory):
    from planner.decision.policy import write_policy

    path = tmp_path_factory.mktemp("policy") / "pen.policy"
    write_policy(setup[2], path)
    return path


def test_cli_session_on_a_recorded_video_and_replay(setup, policy_file, tmp_path):
    """Record the frames of a session (operator and robot in the same cell), then run `aplan session
    --video` on the recording with a robot that confirms at once: the same beliefs, assembled."""
    import cv2

    plan, model, policy, graph = setup
    markers = marker_map(plan.product)
    start = int(graph.full_sequences()[3])
    operator = ScriptedOperator.following(model, start)
    cell = SimulatedCell(tray_layout(markers, (960, 540), 48), operator, CameraModel(blur=1.0, noise=4, seed=3))
    recorded = []

    def frames():
        for frame in cell:
            recorded.append(frame)
            yield frame

    result = run_session(model, policy, VisionSource(frames(), markers, quiet_frames=20),
                         ScriptedRobot(on_perform=cell.robot))
    assert result.assembled
    video = tmp_path / "session.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 30, (960, 540))
    for frame in recorded + recorded[-1:] * 30:
        writer.write(frame)
    writer.release()
    log = tmp_path / "cli.jsonl"
    done = _aplan("session", "pen", "--policy", policy_file, "--video", video, "--robot", "auto", "--log", log,
                  "--quiet-frames", 20)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("assembled: the product is assembled after")
    assert "step 1 | belief" in done.stderr
    replayed = replay(log)
    assert replayed.observations == result.observations and replayed.actions == result.actions
    shown = _aplan("replay", log, "--plot", tmp_path / "fig7")
    assert shown.returncode == 0 and f"beliefs reproduced at all {len(result.actions)} steps" in shown.stdout
    assert_belief_plot(tmp_path / "fig7.png")
    steps = [json.loads(line) for line in _aplan("replay", log, "--json").stdout.splitlines()]
    assert [s["observation"] for s in steps] == [model.observations[z] for z in result.observations]


def test_cli_session_keyboard_and_console_robot(setup, policy_file, tmp_path):
    """The operator's picks typed in and a person confirming the robot's instructions with Enter."""
    plan, model, policy, graph = setup
    operator = ScriptedOperator.following(model, int(graph.full_sequences()[0]))
    robot = ScriptedRobot(on_perform=operator.robot_acting)
    expected = run_session(model, policy, operator, robot)
    lines = []
    for action, z in zip(expected.actions, expected.observations):
        if model.actions[action] != "wait":
            lines.append("")  # the person standing in for the robot presses Enter
        observation = plan.observations[z]
        lines.append(" ".join(observation.parts + ((observation.tool,) if observation.tool else ())))
    log = tmp_path / "k.jsonl"
    done = _aplan("session", "pen", "--policy", policy_file, "--keyboard", "--log", log, stdin="\n".join(lines) + "\n")
    assert done.returncode == 0, done.stderr
    assert "ROBOT, step" in done.stderr and "press Enter when done" in done.stderr
    assert replay(log).observations == expected.observations
    # Before each prompt, what the operator could pick in the assembly state (the pen's first four operations
    # from its six parts, at step 1); the robot's instructions once, by the person standing in for it.
    offered = [line for line in done.stderr.splitlines() if "could pick now: " in line]
    assert len(offered) == len(expected.actions) and offered[0].endswith(
        "body+button+[hammer], body+head+[hammer], cartridge+head+[hammer], cartridge+ink+[hammer]"), offered
    assert "robot, step" not in done.stderr


def test_cli_session_errors(policy_file, tmp_path):
    missing = _aplan("session", "pen", "--policy", policy_file, "--images", tmp_path / "nowhere",
                     "--log", tmp_path / "x.jsonl")
    assert missing.returncode == 1 and "no such folder of images" in missing.stderr
    assert not (tmp_path / "x.jsonl").exists()  # nothing ran, nothing logged
    camera = _aplan("session", "pen", "--policy", policy_file, "--camera", 97, "--log", tmp_path / "x.jsonl")
    assert camera.returncode == 1 and "camera 97 cannot be opened" in camera.stderr
    assert not (tmp_path / "x.jsonl").exists()
    usage = _aplan("session", "pen", "--policy", policy_file)
    assert usage.returncode == 2
    assert "one of the arguments --camera --video --images --keyboard --demo is required" in usage.stderr
    (tmp_path / "x.jsonl").write_text("")
    exists = _aplan("session", "pen", "--policy", policy_file, "--keyboard", "--log", tmp_path / "x.jsonl")
    assert exists.returncode == 1 and "the log exists already" in exists.stderr
    failed = _aplan("session", "pen", "--policy", policy_file, "--keyboard", "--log", tmp_path / "f.jsonl",
                    stdin="body ink hammer\n")
    assert failed.returncode == 1 and failed.stdout.startswith("source ended: the observations ended at step 2")
    assert "aplan: warning: step 1: body+ink+[hammer] ignored" in failed.stderr
    events = [json.loads(line)["event"] for line in (tmp_path / "f.jsonl").read_text().splitlines()]
    assert events[0] == "start" and events[-1] == "end"
    broken = _aplan("replay", tmp_path / "x.jsonl")
    assert broken.returncode == 1 and "not a session log" in broken.stderr


def test_cli_reports_an_ignored_observation_once(policy_file, tmp_path):
    """An observation no operation explains in the assembly state (the hammer alone before anything was built)
    is a warning event in the log, shown once on standard error; replaying the log reports nothing again."""
    log = tmp_path / "r.jsonl"
    done = _aplan("session", "pen", "--policy", policy_file, "--keyboard", "--robot", "auto", "--log", log,
                  stdin="hammer\n")
    assert done.returncode == 1 and done.stdout.startswith("source ended")
    shown = [line for line in done.stderr.splitlines() if "ignored" in line]
    assert len(shown) == 1 and "aplan: warning: step 1: [hammer] ignored: " in shown[0], done.stderr
    assert "robot, step 1: " in done.stderr  # a robot acting by itself: the keyboard says what it does
    assert [e["event"] for e in map(json.loads, log.read_text().splitlines())].count("warning") == 1
    replayed = _aplan("replay", log)
    assert replayed.returncode == 0 and replayed.stderr == "" and "[hammer] (ignored)" in replayed.stdout


def test_cli_demo(policy_file, tmp_path):
    """A simulated cell at 1080p through the whole pipeline, in one command."""
    done = _aplan("session", "pen", "--policy", policy_file, "--demo", 57, "--log", tmp_path / "d.jsonl")
    assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stderr
    assert replay(tmp_path / "d.jsonl").mismatches == []
    bad = _aplan("session", "pen", "--policy", policy_file, "--demo", 3, "--log", tmp_path / "e.jsonl")
    assert bad.returncode == 2 and "--demo 3 is not a full assembly sequence" in bad.stderr  # a usage error
    assert not (tmp_path / "e.jsonl").exists()
    both = _aplan("session", "pen", "--policy", policy_file, "--demo", 57, "--robot", "auto")
    assert both.returncode == 2 and "leave out --robot" in both.stderr


def test_cli_markers(tmp_path):
    done = _aplan("markers", "pen", "-o", tmp_path / "sheet.pdf")
    assert done.returncode == 0 and "7 markers (DICT_4X4_50, 40 mm)" in done.stdout
    bad = _aplan("markers", "pen", "-o", tmp_path / "sheet.jpg")
    assert bad.returncode == 1 and ".pdf or .png" in bad.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sheet.pdf"]


def test_cli_demo_on_a_product_without_tools(tmp_path):
    """Operations without a tool end when the tray goes quiet: the simulated operator pauses that long, so a
    synthetic chain (no tools) is assembled through the vision pipeline, every operation seen as it was done."""
    from planner import chain_product, save_product
    from planner.decision.policy import write_policy

    product = chain_product(4)
    save_product(product, tmp_path / "chain4.json")
    model = intention_model(make_plan(product))
    policy = PointBasedSolver(max_iterations=100, time_limit=None, precision=1e-3, seed=0).solve(model.pomdp).policy
    write_policy(policy, tmp_path / "chain4.policy")
    start = int(model.full_sequences()[0])
    done = _aplan("session", tmp_path / "chain4.json", "--policy", tmp_path / "chain4.policy", "--demo", start,
                  "--log", tmp_path / "d.jsonl", "--quiet-frames", 20)
    assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stderr
    events = [json.loads(line) for line in (tmp_path / "d.jsonl").read_text().splitlines()]
    seen = [e["observation"] for e in events if e["event"] == "observation" and e["observation"] != "blank"]
    truth = [str(model.plan.observations[model.plan.operation_observation[o]])
             for o in model.sequence_operations(start)]
    assert seen == truth[:len(seen)] and "unexplained" not in done.stdout
    assert replay(tmp_path / "d.jsonl").mismatches == []


def test_online_session_on_the_factored_model_and_its_replay(tmp_path):
    """A session decided by the online planner on the factored model (beliefs over classes): assembled, every
    decision timed in the log, and the replay rebuilds the factored model and reproduces every belief."""
    from planner import chain_product
    from planner.decision import factored_model
    from planner.decision.online import OnlinePlanner

    model = factored_model(make_plan(chain_product(6)))
    operator = ScriptedOperator(model.plan, model.sequence_operations(model.sequence(7)))
    log = EventLog(tmp_path / "online.jsonl")
    result = run_session(model, OnlinePlanner(model, expansions=5), operator,
                         ScriptedRobot(on_perform=operator.robot_acting), log)
    log.close()
    assert result.assembled and not operator.off_script
    events = [json.loads(line) for line in (tmp_path / "online.jsonl").read_text().splitlines()]
    assert events[0]["belief_over"] == "classes" and events[0]["n_intentions"] == 326  # chain 6: closed form
    assert all(e["decision_ms"] >= 0 for e in events if e["event"] == "action")
    again = replay(tmp_path / "online.jsonl")
    assert again.mismatches == [] and len(again.actions) == result.steps
    assert type(again.model).__name__ == "FactoredIntentionModel"
    shown = _aplan("replay", tmp_path / "online.jsonl", "--plot", tmp_path / "online")  # over assembly states
    assert shown.returncode == 0, shown.stderr
    assert "most probable assembly state" in (tmp_path / "online.svg").read_text()


def test_cli_demo_with_the_online_planner(tmp_path):
    """`aplan session PRODUCT --demo K` without a policy: the online planner decides, on a tool-less chain."""
    from planner import chain_product, save_product

    save_product(chain_product(4), tmp_path / "chain4.json")
    done = _aplan("session", tmp_path / "chain4.json", "--demo", 2, "--expansions", 5, "--log", tmp_path / "d.jsonl",
                  "--quiet-frames", 20)
    assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stderr
    assert "using the online planner" in done.stderr
    start = json.loads((tmp_path / "d.jsonl").read_text().splitlines()[0])
    assert start["settings"]["planner"] == "online" and start["settings"]["expansions"] == 5
    assert replay(tmp_path / "d.jsonl").mismatches == []


def test_default_logs_of_two_sessions_in_one_second_differ(policy_file, tmp_path, monkeypatch):
    """Without --log, two sessions started in one folder within the same second (here: one clock reading) keep
    two logs, each replayable; before, the second refused the first's ``session-DATE-TIME.jsonl``."""
    import time
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(time, "strftime", lambda fmt, *rest: "20261203-101500")
    for _ in range(2):  # the operator types one pick and stops: a short session, logged
        done = _aplan("session", "pen", "--policy", policy_file, "--keyboard", stdin="body button hammer\n")
        assert "refuse" not in done.stderr and "exists" not in done.stderr, done.stderr
    logs = sorted(p.name for p in tmp_path.glob("session-*.jsonl"))
    pid = os.getpid()
    assert logs == [f"session-20261203-101500-{pid}-2.jsonl", f"session-20261203-101500-{pid}.jsonl"], logs
    assert all(replay(tmp_path / name).observations for name in logs)
