"""Unseen public-style CAD from the file with the default flags (issue 26, "Must show": assemblies never seen
before): per document, the parts found, the obstruction diagrams' precision and recall against the ground truth
of its construction, and the time of each stage (needs FreeCAD).

Run: ``nice -n 10 .venv/bin/python bench/bench_unseen_cad.py`` (about 5 minutes on the loaded machine).

The documents are tests/integration/unseen_documents.py's (a hinge of PartDesign Bodies, a coupling in
App::Part containers with an App::Link array of bolts, a vise of Part primitives and booleans, an 82-part bolt
circle of Draft polar arrays, a closed two-shaft gearbox whose gears float once their shafts are out, the same
gearbox on a machine's base plate with 20 brackets, planned as workstations), built by
FreeCADCmd, and the coupling exported to STEP, as it is and as one body
of ten solids. For each: ``aplan export-freecad DOC -o BUNDLE``, ``aplan stats DOC`` and ``aplan session DOC
--demo 0``, each with the default flags and from the CAD file (stats and session export it again themselves),
each timed as CPU seconds of the command and its children (FreeCADCmd) with the wall clock beside. Precision and recall count the pairs
of the +X, +Y and +Z diagrams (the reverse directions are the same pairs reversed) against
``GROUND_TRUTH``; the STEP file names the link array's elements after the object they show
(``STEP_NAMES``), and the one-body STEP file's solids are the coupling's parts in order (``ONE_BODY``).
"""
from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "tests" / "integration"))

from unseen_documents import DOCUMENTS, GROUND_TRUTH, ONE_BODY, SCRIPT, STEP_NAMES  # noqa: E402

def _timed(command: list[str], cwd: Path) -> tuple[subprocess.CompletedProcess, float, float]:
    """``command`` run to its end: (the run, CPU seconds of it and its children, wall seconds)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, timeout=1800, cwd=cwd,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return done, after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime, wall


def _precision_recall(bundle: Path, truth: dict, names: dict[str, str]) -> tuple[int, float, float]:
    """(parts, precision, recall) of the bundle's +X/+Y/+Z diagrams against ``truth`` (ids renamed by ``names``)."""
    product = json.loads((bundle / "product.json").read_text())
    found = {entry["direction"]: {(names.get(a, a), names.get(b, b)) for a, b in entry["blocks"]}
             for entry in product["obstructions"] if isinstance(entry["direction"], str)}
    hits = sum(len(found.get(axis, set()) & pairs) for axis, pairs in truth.items())
    listed = sum(len(found.get(axis, set())) for axis in truth)
    true = sum(len(pairs) for pairs in truth.values())
    return len(product["parts"]), hits / listed if listed else 1.0, hits / true if true else 1.0


def main() -> None:
    aplan = [sys.executable, "-m", "planner"]
    print("| document | parts found / built | P | R | export CPU s (wall) | stats CPU s (wall) | "
          "session --demo 0 CPU s (wall) | session |\n|---|---:|---:|---:|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory(prefix="aplan-unseen-") as tmp:
        folder = Path(tmp)
        script = folder / "unseen_build.py"
        script.write_text(f"TMP = {tmp!r}\nREPO = {str(ROOT)!r}\n" + SCRIPT)
        subprocess.run(["freecadcmd", str(script)], check=True, capture_output=True, timeout=900)
        cases = [(name, folder / f"{name}.FCStd", name, {}) for name in DOCUMENTS]
        cases += [("coupling (STEP)", folder / "coupling.step", "coupling", STEP_NAMES),
                  ("coupling (STEP, one body)", folder / "one_body.step", "coupling", ONE_BODY)]
        for label, model, truth_of, names in cases:
            truth = GROUND_TRUTH[truth_of]
            built = len({p for pairs in truth.values() for pair in pairs for p in pair})
            bundle = folder / f"{model.stem}_{model.suffix[1:]}_bundle"
            done, export_cpu, export_wall = _timed(aplan + ["export-freecad", str(model), "-o", str(bundle)], folder)
            if done.returncode != 0:
                print(f"| {label} | export failed: {done.stderr.strip()[-200:]} |", flush=True)
                continue
            parts, precision, recall = _precision_recall(bundle, truth, names)
            stats, stats_cpu, stats_wall = _timed(aplan + ["stats", str(model)], folder)
            session, session_cpu, session_wall = _timed(aplan + ["session", str(model), "--demo", "0"], folder)
            ended = next((line.split(" is assembled ")[-1] for line in session.stdout.splitlines()
                          if line.startswith("assembled:")), f"failed: {session.stderr.strip()[-160:]}")
            print(f"| {label} | {parts} / {built} | {precision:.3f} | {recall:.3f} | {export_cpu:.1f} "
                  f"({export_wall:.0f}) | {stats_cpu:.1f} ({stats_wall:.0f})"
                  f"{'' if stats.returncode == 0 else ' failed'} | {session_cpu:.1f} ({session_wall:.0f}) | "
                  f"{ended} |", flush=True)


if __name__ == "__main__":
    main()
