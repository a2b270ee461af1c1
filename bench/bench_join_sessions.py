"""Sessions with actions named by joins (issue 23, "In the workbench and the cell"; docs/parallel.md, In a session):
``aplan session PRODUCT --demo K`` in the simulated camera cell (the rendered tray seen through the vision pipeline)
for every full sequence K of a product, with the paper's model, with ``--joins`` and with ``--model helpful``
(habits learned by ``aplan habits`` from 3 scripted sessions of the operator who does K, the robot waiting), and
with ``--model camera`` (``helpful`` with observations of the step, docs/camera.md). Per model: the sessions
assembled, the logs ``aplan replay`` reproduces, the robot's share of the operations, the joins it did ahead of the
operator (its operation was not the operator's, and the operator went on with its sequence projected onto the new
state), and its wrong actions (a robot operation off the operator's sequence whose projection was not feasible, or
one no operation of the state was). The operator is replayed through each log as the cell ran it
(:class:`~planner.runtime.scripted.ScriptedOperator`), checked observation by observation against the log.

Run: ``.venv/bin/python bench/bench_join_sessions.py [--product pen] [--expansions 20] [--models
paper,joins,helpful,camera] [--sequences K,K,...]`` (default: every full sequence; the online planner at a fixed
number of expansions per decision: the same actions on any machine).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from planner import api, make_plan  # noqa: E402
from planner.decision.factored_model import factored_model  # noqa: E402
from planner.decision.joins import names_joins, performed  # noqa: E402
from planner.decision.presets import PRESETS  # noqa: E402
from planner.runtime.interfaces import Instruction  # noqa: E402
from planner.runtime.log import EventLog  # noqa: E402
from planner.runtime.scripted import ScriptedOperator, ScriptedRobot  # noqa: E402
from planner.runtime.session import run_session  # noqa: E402

MODELS = {"paper": ["--model", "paper"], "joins": ["--joins"], "helpful": ["--model", "helpful"],
          "camera": ["--model", "camera"]}


def _aplan(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "planner", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT)


class _Wait:
    def __init__(self, model):
        self.wait = model.wait

    def action(self, belief) -> int:
        return self.wait


def _habits(model, rank: int, folder: Path) -> Path:
    """``aplan habits`` of 3 sessions in which the operator did sequence ``rank`` alone."""
    out = folder / f"habits-{rank}.json"
    if out.exists():  # learned for another preset of the same run: the same 3 sessions
        return out
    logs = []
    for k in range(3):
        operator = ScriptedOperator(model.plan, model.sequence_operations(model.sequence(rank)))
        path = folder / f"learn-{rank}-{k}.jsonl"
        run_session(model, _Wait(model), operator, ScriptedRobot(), EventLog(path))
        logs.append(path)
    done = _aplan("habits", *logs, "-o", out)
    if done.returncode:
        raise SystemExit(done.stderr)
    return out


def _world(model, rank: int, events: list[dict]) -> ScriptedOperator:
    """The cell's operator replayed through the logged robot actions (module docstring)."""
    joins = names_joins(model)
    operator = ScriptedOperator(model.plan, model.sequence_operations(model.sequence(rank)))
    for event in events:
        if event["event"] == "action" and event["name"] != "wait":
            action = event["action"]
            operation = event["operation"] if joins else model.operation(action)
            operator.robot_acting(Instruction(event["step"], action, event["name"], operation,
                                              join=tuple(event["join"]) if joins else None,
                                              performs=performed(model, action)))
        elif event["event"] == "observation" and str(operator.observe()) != event["observation"]:
            raise SystemExit(f"sequence {rank}: the replayed operator's observation differs at step {event['step']}")
    return operator


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--product", default="pen")
    parser.add_argument("--expansions", type=int, default=20)
    parser.add_argument("--models", default="paper,joins,helpful")
    parser.add_argument("--sequences", default=None, help="K,K,... (default: every full sequence)")
    args = parser.parse_args()
    plan = make_plan(api.resolve_product(args.product))
    base, joins = factored_model(plan), factored_model(plan, parallel="joins")
    ranks = [int(k) for k in args.sequences.split(",")] if args.sequences else list(range(base.n_sequences))
    needed = len(plan.product.parts) - 1
    print(f"{args.product}: {len(ranks)} sequences, {needed} operations each, {args.expansions} expansions")
    print(f"{'model':<8} {'assembled':>9} {'replayed':>8} {'robot share':>11} {'ahead':>5} {'wrong':>5}")
    with tempfile.TemporaryDirectory() as work:
        folder = Path(work)
        for name in args.models.split(","):
            assembled = replayed = robot = ahead = wrong = 0
            for rank in ranks:
                log = folder / f"{name}-{rank}.jsonl"
                extra = ["--habits", _habits(base, rank, folder)] if name in PRESETS and PRESETS[name].habits else []
                done = _aplan("session", args.product, "--demo", rank, "--expansions", args.expansions, "--log",
                              log, *MODELS[name], *extra)
                assembled += done.returncode == 0
                replayed += _aplan("replay", log).returncode == 0
                events = [json.loads(line) for line in log.read_text().splitlines()]
                robot += sum(e["event"] == "action" and e["name"] != "wait" for e in events)
                operator = _world(joins if name != "paper" else base, rank, events)
                ahead += len(operator.ahead)
                wrong += len(operator.off_script)
            share = robot / (needed * len(ranks))
            print(f"{name:<8} {assembled:>9} {replayed:>8} {share:>10.1%} {ahead:>5} {wrong:>5}", flush=True)


if __name__ == "__main__":
    main()
