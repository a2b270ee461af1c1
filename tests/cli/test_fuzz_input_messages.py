"""Messages that must not mislead (issue 22, item 8): ``aplan sequence --log`` reads every log ``aplan replay``
reproduces; huge ``--direction`` components are not a zero vector; a key given twice in a JSON input is named;
an input that is not a regular file (a device, a named pipe, a folder) is refused at once. Each case runs the
real command line and asserts the exit status, a one-line message naming the file or option, no traceback, and
nothing left behind."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from aplan_runner import run_aplan

from planner.errors import GeometryError
from planner.product.designer import parse_direction
from planner.runtime.log import replay, top_intentions


def _one_error(done, fragment: str, code: int = 1) -> None:
    assert done.returncode == code, done.stderr
    assert "Traceback" not in done.stderr
    lines = [line for line in done.stderr.splitlines() if line.startswith("aplan: error:")]
    assert len(lines) == 1 and fragment in lines[0], done.stderr


def _write_events(path: Path, events: list[dict]) -> None:
    path.write_text("".join(json.dumps(e) + "\n" for e in events))


def test_sequence_reads_a_log_written_before_observations_were_ignored(tmp_path):
    """A log of the earlier rule: the cap seen before the body was finished, the belief reset (the observation
    not marked ignored). aplan replay reproduces it; aplan sequence called it damaged and now leaves the
    observation out, as the session does now."""
    new = tmp_path / "new.jsonl"
    done = run_aplan("session", "pen", "--keyboard", "--robot", "auto", "--expansions", 2, "--log", new,
                     stdin="body button hammer\ncap hammer\n")
    assert done.returncode == 1, done.stderr
    events = [json.loads(line) for line in new.read_text().splitlines()]
    for event in events:
        event.pop("ignored", None)  # the earlier format
    old = tmp_path / "old.jsonl"
    _write_events(old, events)
    beliefs = replay(old).beliefs  # the Bayes filter's own update, with its reset: what the earlier rule logged
    for event in events:
        if event["event"] == "belief":
            event["top"] = top_intentions(beliefs[event["step"]])
    _write_events(old, events)
    assert run_aplan("replay", old).returncode == 0
    shown = run_aplan("sequence", "pen", "--log", old)
    assert shown.returncode == 0, shown.stderr
    assert "recorded (1 operation, then the first way to finish)" in shown.stdout


def test_sequence_of_a_log_of_another_product(tmp_path):
    log = tmp_path / "chain.jsonl"
    run_aplan("synth", "chain", 3, "-o", tmp_path / "chain3.json")
    done = run_aplan("session", tmp_path / "chain3.json", "--keyboard", "--robot", "auto", "--expansions", 2,
                     "--log", log, stdin="p1 p2\n")
    assert done.returncode == 1 and log.exists(), done.stderr
    _one_error(run_aplan("sequence", "pen", "--log", log), f"{log}: the logged operation {{p1}} + {{p2}} is not an "
               "operation of Bourjault ballpoint pen; the log was recorded for")


@pytest.mark.parametrize("text, expected", [
    ("1e308,1e308,0", (2 ** -0.5, 2 ** -0.5, 0.0)),   # the squares overflow: before, "a zero vector"
    ("-1e308,0,1e308", (-(2 ** -0.5), 0.0, 2 ** -0.5)),
    ("1e-200,0,0", (1.0, 0.0, 0.0)),                   # the squares underflow to 0
    ("5e-324,5e-324,0", (2 ** -0.5, 2 ** -0.5, 0.0)),  # the smallest numbers there are
])
def test_huge_and_tiny_directions_are_normalised(text, expected):
    assert parse_direction(text, "--direction") == pytest.approx(expected, abs=1e-15)


@pytest.mark.parametrize("text, why", [("0,0,0", "a zero vector"), ("1e309,0,0", "must be finite"),
                                       ("nan,0,1", "must be finite")])
def test_directions_refused_for_the_right_reason(text, why):
    with pytest.raises(GeometryError, match=why):
        parse_direction(text, "--direction")


def test_a_huge_direction_on_the_command_line(tmp_path):
    """The option is parsed (no usage error); the command then stops at the missing bundle, naming it."""
    done = run_aplan("analyze", tmp_path / "nowhere", "--direction", "1e308,1e308,0")
    assert done.returncode == 1 and "zero vector" not in done.stderr and "nowhere" in done.stderr


def test_a_key_given_twice_in_a_product_file(tmp_path, pen):
    text = (Path(pen.source).read_text().replace('"name": "Bourjault ballpoint pen"',
                                                 '"name": "Bourjault ballpoint pen", "name": "other pen"', 1))
    path = tmp_path / "twice.json"
    path.write_text(text)
    _one_error(run_aplan("stats", path), f"{path}: the key 'name' appears twice in one object")
    nested = tmp_path / "nested.json"  # in an inner object too
    nested.write_text(Path(pen.source).read_text().replace('{"id": "ink",', '{"id": "ink", "id": "ink2",', 1))
    _one_error(run_aplan("stats", nested), f"{nested}: the key 'id' appears twice in one object")


def test_a_key_given_twice_in_a_session_log(tmp_path):
    log = tmp_path / "s.jsonl"
    run_aplan("session", "pen", "--keyboard", "--robot", "auto", "--expansions", 2, "--log", log, stdin="\n")
    lines = log.read_text().splitlines()
    lines[1] = lines[1].replace('"step": 1,', '"step": 1, "step": 7,', 1)
    log.write_text("\n".join(lines) + "\n")
    _one_error(run_aplan("replay", log), f"{log}: line 2: the key 'step' appears twice in one object")


@pytest.fixture
def fifo(tmp_path) -> Path:
    path = tmp_path / "pipe.json"
    os.mkfifo(path)
    return path


@pytest.mark.parametrize("command, what", [
    (["stats", "{dev}"], "product"), (["stats", "{fifo}"], "product"), (["replay", "{dev}"], "session log"),
    (["replay", "{fifo}"], "session log"), (["replay", "{dir}"], "session log"),
    (["sequence", "pen", "--log", "{dev}"], "session log"),
    (["simulate", "pen", "--planner", "offline", "--policy", "{dev}"], "policy"),
    (["simulate", "pen", "--planner", "offline", "--policy", "{fifo}"], "policy"),
    (["evaluate", "{fifo}"], "model"),
])
def test_inputs_that_are_not_regular_files(tmp_path, fifo, command, what):
    """/dev/zero reads forever and reports size 0 (the input limits cannot see it), a named pipe blocks: both
    are refused before anything is read (before: "no such file" for a product, memory filling for a log)."""
    if command[0] == "evaluate":  # a model file is told by its name
        fifo = fifo.rename(tmp_path / "pipe.pomdp")
    where = {"dev": "/dev/zero", "fifo": str(fifo), "dir": str(tmp_path)}
    args = [a.format(**where) for a in command]
    path = next(a for a in args if a in where.values())
    kinds = {"/dev/zero": "a character device", str(fifo): "a named pipe", str(tmp_path): "a folder"}
    done = run_aplan(*args)
    _one_error(done, f"{path}: not a regular file ({kinds[path]}); give the path of a {what} file")
    assert sorted(p.name for p in tmp_path.iterdir()) == [fifo.name]
