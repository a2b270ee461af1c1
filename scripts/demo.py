"""The main job on the embedded example, end to end (``bash scripts/demo.sh`` runs it after the set-up):

    .venv/bin/python scripts/demo.py [--out demo] [--sequence 57] [--trials 50]

1. the plan: ``aplan stats pen`` (assembly states, operations, intentions);
2. a policy: ``aplan pomdp pen -o pen.pomdpx`` and ``aplan solve pen.pomdpx -o pen.policy --trials N``,
   bounded by trials, not seconds, so it is the same policy on any machine;
3. a session in the simulated camera cell: ``aplan session pen --policy pen.policy --demo K`` (an operator
   following full sequence K on a rendered parts tray, seen through the vision pipeline; the robot decides
   from what the camera sees);
4. the belief figure: ``aplan replay session.jsonl --plot belief`` (Fig. 7 of the paper).

Each step is the ``aplan`` command line, run in this process (one interpreter start instead of five). What they
print is kept; a few lines say what happened and where the files are. The outputs (``pen.pomdpx``,
``pen.policy``, ``session.jsonl``, ``belief.png``/``.svg``) are made in a new folder beside ``--out`` and
renamed into place at the end, replacing the previous run's: running it twice gives the same folder, and a
failed run leaves the previous one as it was. Exit status: that of the step that failed, else 0.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from planner.cli import main as aplan  # noqa: E402 (after the path: run from a clone without installing)
from planner.files import make_folder_beside  # noqa: E402

__all__ = ["run_demo", "main"]

OUTPUTS = ("pen.pomdpx", "pen.policy", "session.jsonl", "belief.png", "belief.svg")


class StepFailed(Exception):
    """An ``aplan`` step ended with a non-zero exit status (``code``); its output is in the message."""

    def __init__(self, command: str, code: int, output: str):
        super().__init__(f"demo: `{command}` failed (exit status {code}):\n{output.rstrip()}")
        self.code = code


def _run(*args: object) -> str:
    """Run ``aplan ARGS`` in this process in the current folder; return its standard output. Raises
    :class:`StepFailed` with both outputs when its exit status is not 0."""
    argv = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = aplan(argv) or 0
        except SystemExit as exc:  # argparse's usage errors
            code = exc.code if isinstance(exc.code, int) else 1
    if code:
        raise StepFailed("aplan " + " ".join(argv), code, out.getvalue() + err.getvalue())
    return out.getvalue()


def _events(log: Path) -> list[dict]:
    return [json.loads(line) for line in log.read_text(encoding="utf-8").splitlines() if line.strip()]


def _top(belief: dict) -> str:
    return ", ".join(f"i{i} {p:.2f}" for i, p in belief["top"][:3])


def _session_lines(events: list[dict]) -> list[str]:
    """One line per step of a session log (what the robot did, what the camera saw, the most probable
    intentions after it), then how it ended."""
    steps: dict[int, dict] = {}
    for event in events:
        if event["event"] in ("action", "observation", "belief"):
            steps.setdefault(event["step"], {})[event["event"]] = event
    lines = []
    for number, step in sorted(steps.items()):
        action = step.get("action")
        did = "wait" if action is None or action["name"] == "wait" else action["instruction"]
        seen = step["observation"]["observation"] if "observation" in step else "nothing (stopped)"
        belief = f"  ->  belief {_top(step['belief'])}" if "belief" in step else ""
        lines.append(f"   step {number}  robot: {did};  camera: {seen}{belief}")
    end = next((e for e in events if e["event"] == "end"), None)
    lines.append("   ended: " + (f"{end['message']}" if end else "no end event in the log"))
    return lines


def run_demo(out: Path, sequence: int = 57, trials: int = 50) -> list[str]:
    """Run the four steps into the folder ``out`` (replaced at the end) and return the lines to print.

    Cost: the pen's flat model (69 intentions), ``trials`` solver trials (0.1 s for 50), and a simulated
    session of 4 to 5 steps in which every frame of the tray is rendered and read by the vision pipeline
    (about 10 s of one core): well under a minute.
    """
    out = Path(out).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    work = make_folder_beside(out)
    here = os.getcwd()
    try:
        os.chdir(work)  # relative names in the log and the figure, valid after the rename
        stats = json.loads(_run("stats", "pen", "--json"))
        model = _run("pomdp", "pen", "-o", "pen.pomdpx").strip()
        solved = json.loads(_run("solve", "pen.pomdpx", "-o", "pen.policy", "--trials", trials, "--quiet",
                                 "--json"))
        _run("session", "pen", "--policy", "pen.policy", "--demo", sequence, "--log", "session.jsonl")
        _run("replay", "session.jsonl", "--plot", "belief")
        events = _events(Path("session.jsonl"))
    except BaseException:
        os.chdir(here)
        shutil.rmtree(work, ignore_errors=True)
        raise
    os.chdir(here)
    old = out.with_name(f".{out.name}.old")
    shutil.rmtree(old, ignore_errors=True)
    if out.exists():
        out.rename(old)
    work.rename(out)
    shutil.rmtree(old, ignore_errors=True)
    shown = os.path.relpath(out) if not os.path.relpath(out).startswith("..") else str(out)
    model_size = model.split(": ", 1)[1]
    return [
        f"APLAN demo: Bourjault's ballpoint pen, a robot deciding from what a camera sees (files in {shown}/)",
        f"1. plan     {stats['parts']} parts: {stats['states']} assembly states, {stats['operations']} operations, "
        f"{stats['intentions']} intentions ({stats['sequences']} full sequences)",
        f"2. policy   the POMDP ({model_size}) solved in {trials} trials: value between "
        f"{solved['lower_bound']:.2f} and {solved['upper_bound']:.2f}",
        f"3. session  a simulated camera cell, the operator following sequence {sequence}:",
        *_session_lines(events),
        f"4. figure   {shown}/belief.png: the belief over the {stats['intentions']} intentions at every step "
        "(Fig. 7 of the paper)",
        f"commands:   aplan stats pen; aplan pomdp pen -o pen.pomdpx; aplan solve pen.pomdpx -o pen.policy "
        f"--trials {trials};",
        f"            aplan session pen --policy pen.policy --demo {sequence} --log session.jsonl; "
        "aplan replay session.jsonl --plot belief",
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Run APLAN's main job on the pen: plan, policy, simulated "
                                     "camera session, belief figure.")
    parser.add_argument("--out", default=str(ROOT / "demo"), help="the output folder (default: demo/ in the "
                        "clone; replaced by each run)")
    parser.add_argument("--sequence", type=int, default=57, help="the full sequence the simulated operator "
                        "follows (aplan intentions pen --full; default 57)")
    parser.add_argument("--trials", type=int, default=50, help="solver trials (default 50)")
    args = parser.parse_args(argv)
    try:
        lines = run_demo(Path(args.out), args.sequence, args.trials)
    except StepFailed as exc:
        print(exc, file=sys.stderr)
        return exc.code
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
