"""``aplan`` run inside the test process: the command line's ``main`` with its arguments, standard input and
output, and exit status, without the second or so a new interpreter spends importing the planner (the suite
runs ``aplan`` about a hundred times). ``main`` is made to run in-process (it undoes its logging set-up);
FreeCAD still runs in a process of its own, and tests/cli/test_cli.py starts ``python -m planner`` itself."""
from __future__ import annotations

import contextlib
import io
import subprocess
import sys

from planner.cli import main

__all__ = ["run_aplan"]


def run_aplan(*args: object, stdin: str = "") -> subprocess.CompletedProcess:
    """Run ``aplan ARGS`` in this process, with ``stdin`` as its standard input, and return what a finished
    ``subprocess.run(..., capture_output=True, text=True)`` would: arguments, exit status (argparse's 2 for a
    usage error included), standard output and error. An exception ``main`` does not turn into a message is
    raised, not hidden (a subprocess would show it as a traceback)."""
    argv = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    saved_stdin = sys.stdin
    sys.stdin = io.StringIO(stdin)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:  # argparse's usage errors, --help
                code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    finally:
        sys.stdin = saved_stdin
    return subprocess.CompletedProcess(["aplan", *argv], code or 0, out.getvalue(), err.getvalue())
