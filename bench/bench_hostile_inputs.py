"""Hostile inputs are refused at once (issue 14, items 1 and 5): time and peak memory of each refusal.

Before the validation layer these cases hung, asked for TiB or ran out of memory; now each is refused
before the work, in about the time the interpreter takes to start. Each runs ``aplan`` in a child process
(wall time, and the child's own peak resident memory from ``wait4``); the table is printed in Markdown.

    .venv/bin/python bench/bench_hostile_inputs.py
"""
from __future__ import annotations

import gzip
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

APLAN = [sys.executable, "-m", "planner"]

POMDPX = """<?xml version="1.0"?>
<pomdpx version="1.0" id="big"><Discount>0.9</Discount>
<Variable><StateVar vnamePrev="s0" vnameCurr="s1"><NumValues>{states}</NumValues></StateVar>
<ObsVar vname="o"><NumValues>1</NumValues></ObsVar><ActionVar vname="a"><NumValues>1</NumValues></ActionVar>
<RewardVar vname="r"/></Variable>
<InitialStateBelief><CondProb><Var>s0</Var><Parent>null</Parent><Parameter type="TBL"><Entry><Instance>-</Instance>
<ProbTable>uniform</ProbTable></Entry></Parameter></CondProb></InitialStateBelief>
<StateTransitionFunction><CondProb><Var>s1</Var><Parent>a s0</Parent><Parameter type="TBL"><Entry>
<Instance>* - -</Instance><ProbTable>uniform</ProbTable></Entry></Parameter></CondProb></StateTransitionFunction>
<ObsFunction><CondProb><Var>o</Var><Parent>a s1</Parent><Parameter type="TBL"><Entry><Instance>* * -</Instance>
<ProbTable>1</ProbTable></Entry></Parameter></CondProb></ObsFunction>
<RewardFunction><Func><Var>r</Var><Parent>a s0</Parent><Parameter type="TBL"><Entry><Instance>* *</Instance>
<ValueTable>1</ValueTable></Entry></Parameter></Func></RewardFunction></pomdpx>"""


def _files(folder: Path) -> None:
    (folder / "big.pomdpx").write_text(POMDPX.format(states=1_000_000))
    (folder / "star.pomdp").write_text("discount: 0.9\nvalues: reward\nstates: 3000\nactions: 3\nobservations: 3000\n"
                                       "T: * : * : * 0.000333333333333333\nO: * : * : * 0.000333333333333333\n")
    with gzip.open(folder / "bomb.pomdpx.gz", "wb", compresslevel=1) as handle:  # 1 GiB of elements
        handle.write(b"<pomdpx>")
        chunk = b"<a/>" * (2 ** 22)
        for _ in range(64):
            handle.write(chunk)
    pen = (Path(__file__).resolve().parents[1] / "resources").glob("**/pen*.json")
    text = next(iter(pen)).read_text()
    (folder / "deep.json").write_text(text.rstrip()[:-1] + ', "x-deep": ' + "[" * 100_000 + "]" * 100_000 + "}")
    (folder / "digits.json").write_text(text.replace('"id": "body"', '"id": "body", "volume": ' + "9" * 5001, 1))


CASES = [
    ("POMDPX declaring 1,000,000 states, uniform transition (asked 7.3 TiB)",
     ["solve", "big.pomdpx", "-o", "p.policy"]),
    (".pomdp with '*' over 3,000 states (ran for minutes, 26.8 GiB)", ["solve", "star.pomdp", "-o", "p.policy"]),
    ("gzip bomb, 1 GiB of elements in 5 MiB (parsed without a cap)", ["solve", "bomb.pomdpx.gz", "-o",
                                                                             "p.policy"]),
    ("product nested 100,000 deep (RecursionError)", ["stats", "deep.json"]),
    ("product with a 5,001-digit integer (ValueError)", ["stats", "digits.json"]),
    ("--resolution 1000000 (20 GiB)", ["analyze", "deep.json", "--resolution", "1000000"]),
    ("--episodes 1000000000 (7 GiB)", ["evaluate", "pen", "--episodes", "1000000000"]),
]


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        _files(Path(folder))
        print("| input | exit | wall s | peak MiB | message |")
        print("|---|---:|---:|---:|---|")
        for name, argv in CASES:
            start = time.perf_counter()
            child = subprocess.Popen(APLAN + argv, cwd=folder, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            err = child.stderr.read().decode()
            _, status, usage = os.wait4(child.pid, 0)
            wall = time.perf_counter() - start
            message = err.strip().splitlines()[-1][:90] if err.strip() else ""
            print(f"| {name} | {os.waitstatus_to_exitcode(status)} | {wall:.2f} | {usage.ru_maxrss / 1024:.0f} | "
                  f"{message} |")


if __name__ == "__main__":
    main()
