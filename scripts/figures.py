"""Write the figures shown in the README into docs/figures/ (run from the repository root, after set-up):

    .venv/bin/python scripts/figures.py [--out docs/figures]

- ``pen-sequence-57.png/.svg``: ``aplan simulate pen --policy P --sequence 57 --plot ...`` (Fig. 7);
- ``pen-session-replay.png/.svg``: a simulated cell (``aplan session pen --policy P --demo 57``, the vision
  pipeline on a rendered tray) replayed with ``aplan replay LOG --plot ...``;
- ``pen-session-online.png/.svg``: the same with the online planner (beliefs over the factored model's
  classes, plotted over assembly states);
- ``pen-andor.png``, ``pen-states.png``, ``pen-intentions.png``: the pen's graphs by level;
  ``chain10-states.png``: a 10-part chain's 512 states, summarised per level.

The policy P is solved by iterations, not seconds (150 point-based iterations, as the tests do), so the
figures are the same on any machine. Takes about two minutes on 2 cores.
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def _aplan(*args) -> None:
    print("aplan " + " ".join(map(str, args)), flush=True)
    subprocess.run([sys.executable, "-m", "planner", *map(str, args)], check=True, cwd=ROOT,
                   stdout=subprocess.DEVNULL)


def main() -> int:
    from planner import make_plan, resolve_product
    from planner.assembly.figures import draw_andor, draw_intentions, draw_states
    from planner.decision import intention_model
    from planner.decision.policy import write_policy
    from planner.decision.solvers import PointBasedSolver
    from planner.product.synthetic import chain_product

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "docs" / "figures"))
    out = Path(parser.parse_args().out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="aplan-figures."))
    try:
        pen = resolve_product("pen")
        model = intention_model(make_plan(pen))
        result = PointBasedSolver(max_iterations=150, time_limit=None, precision=1e-3).solve(model.pomdp)
        policy = work / "pen.policy"
        write_policy(result.policy, policy, model.name)
        _aplan("simulate", "pen", "--policy", policy, "--sequence", 57, "--plot", out / "pen-sequence-57")
        _aplan("session", "pen", "--policy", policy, "--demo", 57, "--log", work / "pen-57.jsonl")
        _aplan("replay", work / "pen-57.jsonl", "--plot", out / "pen-session-replay")
        _aplan("session", "pen", "--planner", "online", "--expansions", 200, "--demo", 3, "--log",
               work / "pen-online.jsonl")
        _aplan("replay", work / "pen-online.jsonl", "--plot", out / "pen-session-online")
        plan = make_plan(pen)
        for name, draw in (("andor", draw_andor), ("states", draw_states), ("intentions", draw_intentions)):
            print(draw(plan, out / f"pen-{name}.png"))
        print(draw_states(make_plan(chain_product(10)), out / "chain10-states.png"))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
