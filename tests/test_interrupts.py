"""Signals are never lost (issue 22, item 5): no handler in the source tree catches ``BaseException`` or
``KeyboardInterrupt`` to carry on (an AST check, as tests/test_architecture.py checks imports), third-party code
that would (trimesh's optional imports) runs with the signals held (:func:`planner.interrupts.held_interrupts`),
and an interrupt that something caught and ignored is raised again before an output is committed and still ends
the command with 128 + N. The signals here are sent by the process to itself at a chosen point: no timing."""
from __future__ import annotations

import ast
import os
import signal
from pathlib import Path

import pytest
from conftest import REPO

from planner import interrupts
from planner.cli import main
from planner.files import write_atomic

#: Exceptions whose handler, unless it raises again, would swallow a Ctrl-C or a SIGTERM.
SIGNAL_CATCHING = {"BaseException", "KeyboardInterrupt", "Interrupted"}
#: (file, function): why the handler there may end the interrupt.
ALLOWED = {
    ("planner/cli/__init__.py", "main"): "the top level: it prints the one line and returns 128 + N",
    ("planner/runtime/vision/frames.py", "pump"): "a worker thread (Python raises signals only in the main "
                                                   "thread); it hands the error to the consumer, which raises it",
}


def _sources() -> list[Path]:
    folders = ("planner", "freecad_aplan", "scripts", "bench", "tests")
    found = [p for folder in folders for p in (REPO / folder).rglob("*.py")]
    return sorted(found + [REPO / "Init.py", REPO / "InitGui.py"])


def _names(node: ast.expr | None) -> set[str]:
    if node is None:
        return {"BaseException"}  # a bare except
    if isinstance(node, ast.Tuple):
        return set().union(*(_names(e) for e in node.elts))
    if isinstance(node, ast.Attribute):
        return {node.attr}
    return {node.id} if isinstance(node, ast.Name) else set()


def _raises(body: list[ast.stmt]) -> bool:
    """True when the handler's own code (not a function defined in it) has a ``raise``."""
    todo = list(body)
    while todo:
        node = todo.pop()
        if isinstance(node, ast.Raise):
            return True
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            todo.extend(ast.iter_child_nodes(node))
    return False


def swallowing_handlers(source: str, name: str) -> list[tuple[str, int, str]]:
    """(file, line, function) of every ``except`` catching a signal's exception without raising again, and of
    every ``suppress(...)`` of one, in ``source``."""
    found = []

    def visit(node: ast.AST, function: str) -> None:
        for child in ast.iter_child_nodes(node):
            inner = child.name if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else function
            if isinstance(child, ast.ExceptHandler) and _names(child.type) & SIGNAL_CATCHING \
                    and not _raises(child.body):
                found.append((name, child.lineno, function))
            if isinstance(child, ast.Call) and getattr(child.func, "attr", getattr(child.func, "id", "")) \
                    == "suppress" and any(_names(a) & SIGNAL_CATCHING for a in child.args):
                found.append((name, child.lineno, function))
            visit(child, inner)

    visit(ast.parse(source), "")
    return found


def test_the_check_finds_what_swallows():
    code = ("def f():\n    try:\n        import x\n    except BaseException:\n        x = None\n"
            "def g():\n    try:\n        pass\n    except (OSError, KeyboardInterrupt):\n        return 1\n"
            "def h():\n    try:\n        pass\n    except:\n        pass\n"
            "def i():\n    with suppress(KeyboardInterrupt):\n        pass\n"
            "def ok():\n    try:\n        pass\n    except BaseException:\n        clean()\n        raise\n"
            "    except Exception:\n        pass\n")
    assert [(line, function) for _, line, function in swallowing_handlers(code, "x.py")] == [
        (4, "f"), (9, "g"), (14, "h"), (17, "i")]


def test_no_handler_swallows_a_signal():
    found = []
    for path in _sources():
        name = str(path.relative_to(REPO))
        found += [(f, line, function) for f, line, function in swallowing_handlers(path.read_text(), name)
                  if (f, function) not in ALLOWED]
    assert found == [], "handlers that catch BaseException or KeyboardInterrupt and carry on: " + ", ".join(
        f"{f}:{line} ({function})" for f, line, function in found)
    assert len(_sources()) > 200  # the whole tree was read


def _swallows(exc_type=BaseException):
    """What trimesh's optional imports do: catch everything and carry on."""
    try:
        os.kill(os.getpid(), signal.SIGTERM)
        return "carried on"
    except exc_type:
        return "swallowed"


def test_held_interrupts_deliver_the_signal_when_the_block_ends():
    with interrupts.signals_as_interrupts():
        with pytest.raises(interrupts.Interrupted) as raised:
            with interrupts.held_interrupts():
                assert _swallows() == "carried on"  # held: nothing to catch inside
        assert raised.value.signum == signal.SIGTERM
        interrupts.delivered()
        with pytest.raises(KeyboardInterrupt):  # an error in the block: the interrupt still wins
            with interrupts.held_interrupts():
                os.kill(os.getpid(), signal.SIGINT)
                raise ValueError("the block failed")
        interrupts.delivered()


def test_an_ignored_interrupt_never_commits_an_output(tmp_path):
    with interrupts.signals_as_interrupts():
        assert _swallows() == "swallowed" and interrupts.swallowed() == signal.SIGTERM
        with pytest.raises(interrupts.Interrupted):
            write_atomic(tmp_path / "out.txt", "x")
        interrupts.delivered()
        assert interrupts.swallowed() == 0
        write_atomic(tmp_path / "out.txt", "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]  # the refused one left no temporary file


def test_an_ignored_interrupt_still_ends_the_command_with_128_plus_n(tmp_path, monkeypatch, capsys):
    """A command whose library swallowed SIGTERM and which wrote nothing after it: exit 143, one line."""
    from planner.cli import plan

    def stats(args) -> int:
        assert _swallows() == "swallowed"
        return 0

    monkeypatch.setattr(plan, "_stats", stats)
    code = main(["stats", "pen"])
    err = capsys.readouterr().err
    assert code == 128 + signal.SIGTERM and err == "aplan: interrupted (SIGTERM): nothing was written\n"
    assert interrupts.swallowed() == 0


def test_a_failure_after_an_ignored_interrupt_is_the_interrupt(monkeypatch, capsys):
    """What follows a swallowed interrupt (trimesh leaves a placeholder for the module it did not import, which
    fails when used) is reported as the interrupt, not as that failure."""
    from planner.cli import plan
    from planner.errors import PlannerError

    def stats(args) -> int:
        _swallows(KeyboardInterrupt)
        raise PlannerError("the placeholder module failed")

    monkeypatch.setattr(plan, "_stats", stats)
    assert main(["stats", "pen"]) == 128 + signal.SIGTERM
    assert capsys.readouterr().err == "aplan: interrupted (SIGTERM): nothing was written\n"
    monkeypatch.setattr(plan, "_stats", lambda args: (_ for _ in ()).throw(PlannerError("a plain failure")))
    assert main(["stats", "pen"]) == 1 and "a plain failure" in capsys.readouterr().err


def test_a_signal_while_a_child_starts_kills_and_reaps_it(monkeypatch):
    """SIGTERM sent between the fork and the return of Popen (the window in which no caller can kill the child
    yet; seen as a FreeCADCmd outliving an interrupted ``aplan stats`` under load): held, then raised once the
    child exists, which is killed and reaped first."""
    import subprocess
    import sys
    import threading

    started = []
    real = subprocess.Popen

    def popen_then_signal(*args, **kwargs):
        process = real(*args, **kwargs)
        started.append(process)
        # To this thread, which holds it until start_child releases the signals (a signal to the process could
        # be taken by another thread that does not hold it: the suite's background lanes).
        signal.pthread_kill(threading.main_thread().ident, signal.SIGTERM)
        return process

    monkeypatch.setattr(interrupts.subprocess, "Popen", popen_then_signal)
    with interrupts.signals_as_interrupts():
        with pytest.raises(interrupts.Interrupted) as caught:
            interrupts.start_child([sys.executable, "-c", "import time; time.sleep(60)"])
        interrupts.delivered()
    assert caught.value.signum == signal.SIGTERM
    assert started[0].returncode == -signal.SIGKILL  # killed and reaped before the interrupt was raised


def test_a_child_starts_with_no_signal_held():
    """The signals held while it starts are released in the child before its program runs (a signal mask
    survives exec)."""
    import subprocess
    import sys

    with interrupts.signals_as_interrupts():
        process = interrupts.start_child([sys.executable, "-c", "import signal; "
                                          "print(sorted(signal.pthread_sigmask(signal.SIG_BLOCK, [])))"],
                                         stdout=subprocess.PIPE, text=True)
        out, _ = process.communicate(timeout=60)
    assert out.strip() == "[]"
