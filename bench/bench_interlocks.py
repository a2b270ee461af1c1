"""Interlocks found and resolved (issue 26, item 1): for each interlock test document (built by FreeCAD, as
tests/integration/test_interlock_documents.py builds them) and each model in ../shared/models, the export
(``aplan export-freecad DOC -o BUNDLE``, wall seconds), then the pairs that block each other along every
direction and what the rules did with them (:func:`planner.assembly.interlocks.resolve_interlocks`: overlap,
direction, component, unresolved), with the rules' wall seconds. Prints a Markdown table for bench/README.md.

    .venv/bin/python bench/bench_interlocks.py          # about 2 minutes on a loaded machine
"""
from __future__ import annotations


import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT.parent / "shared" / "models"
sys.path.insert(0, str(ROOT / "tests"))

from integration.interlock_documents import DOCUMENTS, SCRIPT  # noqa: E402

from planner import load_product  # noqa: E402
from planner.assembly.feasibility import interlocked_pairs  # noqa: E402
from planner.assembly.interlocks import resolve_interlocks  # noqa: E402

MODEL_FILES = [("pen (simplified)", MODELS / "bourjault_pen" / "simplified" / "asm_bourjault_ballpoint.FCStd"),
               ("toy truck", MODELS / "toy_truck" / "asm_cement_mixer_truck.FCStd"),
               ("diaphragm pump", MODELS / "diaphragm_pump" / "asm_diaphragm_pump.FCStd")]


def _row(name: str, model: Path, folder: Path) -> str:
    bundle = folder / re.sub(r"\W+", "_", name)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "planner", "export-freecad", str(model), "-o", str(bundle)],
                          capture_output=True, text=True, env={**os.environ, "OMP_NUM_THREADS": "1"})
    export = time.perf_counter() - start
    if done.returncode != 0:
        return f"| {name} | export failed: {done.stderr.strip().splitlines()[-1][:120]} | | | | | |"
    product = load_product(bundle / "product.json")
    found = interlocked_pairs(product)
    start = time.perf_counter()
    _, decisions, unresolved = resolve_interlocks(product)
    seconds = time.perf_counter() - start
    rules = Counter(d.rule for d in decisions)
    return (f"| {name} | {len(product.parts)} | {export:.1f} | {len(found)} | {rules['overlap']} | "
            f"{rules['direction']} | {rules['component']} | {len(unresolved)} | {seconds:.2f} |")


def main() -> None:
    freecad = shutil.which("freecadcmd") or shutil.which("FreeCADCmd")
    print("| document | parts | export s | interlocked | overlap | direction | component | unresolved | rules s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory(prefix="aplan-interlocks-") as tmp:
        folder = Path(tmp)
        script = folder / "interlock_docs.py"
        script.write_text(f"TMP = {str(folder)!r}\n" + SCRIPT)
        built = subprocess.run([freecad, str(script)], capture_output=True, text=True)
        assert "APLAN-RESULT" in built.stdout, built.stdout[-2000:] + built.stderr[-2000:]
        cases = [(name, folder / f"{name}.FCStd") for name in DOCUMENTS] + \
                [(name, path) for name, path in MODEL_FILES if path.is_file()]
        for name, path in cases:
            print(_row(name, path, folder), flush=True)



if __name__ == "__main__":
    main()
