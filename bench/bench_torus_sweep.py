"""The OCCT engine on a torus made with ``toNurbs()`` beside a box that blocks it along +X (issue 26, item 3):
CPU seconds of :func:`freecad_aplan.occt.analyze_shapes` with the default bounds, and its answer (needs FreeCAD).

Run: ``.venv/bin/python bench/bench_torus_sweep.py [--tree PATH ...] [--repeat N]``. Each ``--tree`` is a checkout
whose ``freecad_aplan`` is imported (default: this one), e.g. ``git archive main freecad_aplan planner | tar -x
-C /tmp/main`` for the figure before a change. One FreeCADCmd per run; the CPU time is ``time.process_time``
around the call. The torus' one face, swept as triangles, overlaps itself seen along +X, so its sweep is lost
and the pair keeps the mesh engine's answer: the time is what it costs to find that out.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

SCRIPT = r"""
import json, os, sys, time
sys.path.insert(0, os.environ["TREE"])
import FreeCAD, Part
from freecad_aplan.occt import analyze_shapes
V = FreeCAD.Vector
parts = [("Torus", Part.makeTorus(8, 3, V(0, 100, 0)).toNurbs()), ("TorusBlock", Part.makeBox(10, 4, 2, V(11.05, 98, -1)))]
start = time.process_time()
report = analyze_shapes(parts)
with open(os.environ["OUT"], "w") as handle:
    json.dump({"cpu": time.process_time() - start, "undecided": report["undecided_relations"],
               "lost": report["sweeps_lost"], "plus_x": report["obstructions"]["+X"]}, handle)
"""


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--tree", action="append", help="a checkout to import freecad_aplan from (repeatable)")
    parser.add_argument("--repeat", type=int, default=2, help="runs per tree (default 2)")
    args = parser.parse_args()
    print("| tree | CPU s | undecided | sweeps lost | +X blocks |\n|---|---:|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        script, out = Path(folder) / "torus_probe.py", Path(folder) / "out.json"
        script.write_text(SCRIPT)
        for tree in args.tree or [str(ROOT)]:
            for _ in range(args.repeat):
                subprocess.run(["freecadcmd", str(script)], check=True, capture_output=True, timeout=1800,
                               env={**os.environ, "TREE": tree, "OUT": str(out)})
                found = json.loads(out.read_text())
                print(f"| {tree} | {found['cpu']:.2f} | {found['undecided']} | {found['lost']} | {found['plus_x']} |",
                      flush=True)


if __name__ == "__main__":
    main()
