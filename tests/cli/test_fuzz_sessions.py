"""Sessions that must not mislead (issue 22, items 6, 7 and the signals of 8): the end follows from the assembly
state, never from the belief alone; an observation no operation explains is ignored with a warning and the
session goes on; every level's log is checked before the first level starts; usage refusals exit 2 and leave
no log; a session stopped by SIGINT or SIGTERM exits 128 + N with its log complete. Each case runs the real
command line and asserts the exit status, a one-line message, no traceback and nothing left behind."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from aplan_runner import run_aplan
from conftest import REPO
from listed_source import ListedSource

from planner import BLANK, Observation, chain_product, make_plan
from planner.decision import intention_model
from planner.decision.policy import write_policy
from planner.decision.solvers import PointBasedSolver
from planner.product import Part, Product, Subassembly, save_product
from planner.runtime.log import EventLog, replay
from planner.runtime.scripted import ScriptedRobot
from planner.runtime.session import run_session


@pytest.fixture(scope="module")
def pen_policy(tmp_path_factory, pen) -> Path:
    """A policy for the pen from a fixed amount of solver work (no clock)."""
    model = intention_model(make_plan(pen))
    path = tmp_path_factory.mktemp("policy") / "pen.policy"
    write_policy(PointBasedSolver(max_iterations=50, time_limit=None, seed=0).solve(model.pomdp).policy, path)
    return path


def _events(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def _one_error(err: str, fragment: str) -> None:
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.startswith("aplan: error:")]
    assert len(lines) == 1 and fragment in lines[0], err


def test_the_cap_before_the_body_is_finished_does_not_end_the_session(pen_policy, tmp_path):
    """The issue's command: body and button joined, then the cap seen with the hammer. No operation mounts the
    cap on the body and button alone, so the observation is ignored (before: the belief was reset to the
    finished product and the session said "assembled after 2 steps", exit 0)."""
    log = tmp_path / "s.jsonl"
    done = run_aplan("session", "pen", "--policy", pen_policy, "--keyboard", "--robot", "auto", "--log", log,
                     stdin="body button hammer\ncap hammer\n")
    assert done.returncode == 1 and done.stdout.startswith("source ended: the observations ended at step 3, with "
                                                           "1 of 5 operations done"), done.stdout
    warning = [line.partition("aplan: warning: ")[2] for line in done.stderr.splitlines() if "warning" in line]
    assert len(warning) == 1 and warning[0].startswith("step 2: cap+[hammer] ignored: no operation explains it in "
                                                       "the assembly state (")
    assert "{body, button}" in warning[0]
    assert "could pick: cartridge+head+[hammer], cartridge+ink+[hammer]" in warning[0]
    events = _events(log)
    assert [e["ignored"] for e in events if e["event"] == "observation"] == [False, True]
    assert [e["operations"] for e in events if e["event"] == "belief"] == [1, 1]
    assert all(e["p_finished"] == 0 for e in events if e["event"] == "belief")
    assert events[-1]["event"] == "end" and events[-1]["reason"] == "source ended"
    replayed = run_aplan("replay", log)
    assert replayed.returncode == 0 and "cap+[hammer] (ignored)" in replayed.stdout, replayed.stderr
    assert replay(log).mismatches == [] and replay(log).ignored == {2: "cap+[hammer]"}
    shown = run_aplan("sequence", "pen", "--log", log)  # the logged operation, then the first way to finish
    assert shown.returncode == 0, shown.stderr
    assert "recorded (1 operation, then the first way to finish), 5 operations" in shown.stdout
    assert "  1. {body} + {button}:" in shown.stdout


class _Waits:
    """A policy that always waits: every operation is the operator's."""

    def __init__(self, model):
        self.wait = len(model.actions) - 1

    def action(self, belief) -> int:
        return self.wait


def test_the_session_ends_when_the_assembly_state_is_finished(pen):
    """The operator's five operations of one pen sequence, with ignored picks between them: assembled exactly
    at the fifth explained operation (N - 1 for N parts), never before."""
    model = intention_model(make_plan(pen))
    steps = [Observation(("body", "button"), "hammer"), Observation(("cap",), "hammer"),  # not yet possible
             Observation(("cartridge", "head"), "hammer"), Observation(("body", "ink"), "hammer"),  # no operation
             Observation(("ink",), "hammer"), Observation((), "hammer"), BLANK, Observation(("cap",), "hammer"),
             BLANK]
    log = EventLog()
    result = run_session(model, _Waits(model), ListedSource(steps), ScriptedRobot(), log)
    assert result.reason == "assembled" and result.steps == 8 and result.operations == 5, result.message
    observed = [e for e in log.events if e["event"] == "observation"]
    assert [e["step"] for e in observed if e["ignored"]] == [2, 4]
    assert [e["operations"] for e in log.events if e["event"] == "belief"] == [1, 1, 2, 2, 3, 4, 4, 5]


def test_a_last_operation_that_shows_as_blank(tmp_path):
    """A chain of 4 without tools: {p1, p2} and {p3, p4} joined shows as blank, so the assembly state leaves
    open whether it was done; the belief on the finished product decides, within what the state allows."""
    model = intention_model(make_plan(chain_product(4)))
    steps = [Observation(("p1", "p2"), None), Observation(("p3", "p4"), None)] + [BLANK] * 10
    result = run_session(model, _Waits(model), ListedSource(steps), ScriptedRobot(), EventLog())
    assert result.reason == "assembled" and result.operations == 3
    assert result.steps > 3  # the first blank gives the finished product 1/2, not 0.99
    # A blank before those two subassemblies exist cannot be the last operation: the state is not finished.
    early = [Observation(("p1", "p2"), None)] + [BLANK] * 10
    result = run_session(model, _Waits(model), ListedSource(early), ScriptedRobot(), EventLog())
    assert result.reason == "source ended"


def _two_chains(tmp_path: Path) -> Path:
    parts = tuple(Part(p) for p in ("a1", "a2", "a3", "b1", "b2", "b3"))
    contacts = (("a1", "a2"), ("a2", "a3"), ("b1", "b2"), ("b2", "b3"), ("a3", "b1"))
    product = Product(parts, contacts, subassemblies=(Subassembly("A", ("a1", "a2", "a3")),
                                                      Subassembly("B", ("b1", "b2", "b3"))), name="two chains")
    path = tmp_path / "chains.json"
    save_product(product, path)
    return path


def test_every_level_log_is_checked_before_the_first_level(tmp_path):
    """LOG-top.jsonl exists: the session of three levels is refused before level A starts (before: A and B ran
    and wrote their logs, then top was refused, and the same command was then refused at A)."""
    chains = _two_chains(tmp_path)
    (tmp_path / "LOG-top.jsonl").write_text("")
    for _ in range(2):  # the same answer the second time: nothing was written the first
        done = run_aplan("session", chains, "--demo", 0, "--log", tmp_path / "LOG.jsonl")
        assert done.returncode == 1
        _one_error(done.stderr, "LOG-top.jsonl: the log exists already; it is never replaced; choose another path")
        assert sorted(p.name for p in tmp_path.iterdir()) == ["LOG-top.jsonl", "chains.json"]
        assert "level A" not in done.stdout


@pytest.mark.parametrize("args, fragment", [
    (["--demo", 0, "--debounce", 50], "--quiet-frames 45 must be more than --debounce 50"),
    (["--demo", 0, "--quiet-frames", 3], "--quiet-frames 3 must be more than --debounce 3"),
    (["--demo", 0, "--robot", "auto"], "--demo simulates the robot too; leave out --robot"),
    (["--demo", 99, "--expansions", 2], "--demo 99: on the factored model (--planner online) sequences are numbered"),
])
def test_usage_refusals_exit_2_and_leave_no_log(tmp_path, args, fragment):
    """Before, --debounce above --quiet-frames was found after the log was created: an empty log and exit 1."""
    done = run_aplan("session", "pen", *args, "--log", tmp_path / "s.jsonl")
    assert done.returncode == 2, done.stderr
    _one_error(done.stderr, fragment)
    assert list(tmp_path.iterdir()) == []


def test_a_level_log_gives_its_sequence_without_level(tmp_path):
    """A session of one level (--level A) logs its level: aplan sequence reads it from the log."""
    chains = _two_chains(tmp_path)
    log = tmp_path / "a.jsonl"
    done = run_aplan("session", chains, "--level", "A", "--keyboard", "--robot", "auto", "--expansions", 2,
                     "--log", log, stdin="a2 a3\na1\n")
    assert done.returncode == 0 and done.stdout.startswith("assembled"), done.stdout + done.stderr
    shown = run_aplan("sequence", chains, "--log", log)
    assert shown.returncode == 0, shown.stderr
    assert "two chains / A: the sequence" in shown.stdout and "  1. {a2} + {a3}:" in shown.stdout
    both = run_aplan("sequence", chains, "--log", log, "--rank", 0)  # before: accepted, the rank ignored
    assert both.returncode == 2 and "argument --rank: not allowed with argument --log" in both.stderr


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_session_stopped_by_a_signal_exits_128_plus_n(tmp_path, signum):
    """A keyboard session waiting for its second step's picks gets the signal: exit 130 or 143 (before: 1), the
    log ends with its end event and replays. The test waits for the second prompt, never for a time."""
    log = tmp_path / "s.jsonl"
    process = subprocess.Popen([sys.executable, "-m", "planner", "session", "pen", "--keyboard", "--robot", "auto",
                                "--expansions", "2", "--log", str(log)], cwd=REPO, stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        process.stdin.write("body button hammer\n")
        process.stdin.flush()
        seen = ""
        while seen.count("operator picked") < 2:
            char = process.stderr.read(1)
            assert char, seen  # the command ended before asking twice
            seen += char
        process.send_signal(signum)
        out, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 128 + signum, out + err
    assert f"aplan: interrupted ({signal.Signals(signum).name}): the session log {log} holds every step" in err
    assert "Traceback" not in err
    events = _events(log)
    assert events[-1]["event"] == "end" and events[-1]["reason"] == "interrupted"
    assert replay(log).mismatches == [] and len(replay(log).actions) == 1
