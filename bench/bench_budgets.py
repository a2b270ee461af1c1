"""Meshes and the exact engine within a budget (issue 26, items 3 and 4; needs FreeCAD).

Run: ``.venv/bin/python bench/bench_budgets.py [--engines mesh,occt] [--only NAME]`` (several minutes).

For each document: the helical spring test document and a synthetic 100-part document (both built here in
FreeCAD: tests/workbench/spring_document.py, :data:`GRID_SCRIPT`), the toy truck and the diaphragm pump of
../shared/models. Per engine, ``aplan export-freecad MODEL -o BUNDLE --engine E`` with the default flags,
timed: wall clock, and the CPU seconds of the command and its FreeCAD children (the figure for "one core":
the machine is shared). Then the parts per fallback rule (``geometry.mesh_check.rules``) and, for the occt
engine, the pairs settled on the meshes, decided by OCCT and left undecided (``geometry.analysis``).
"""
from __future__ import annotations

import argparse
import json
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT.parent / "shared" / "models"
APLAN = ROOT / ".venv" / "bin" / "aplan"

GRID_SCRIPT = r"""
import sys
import FreeCAD, Part
V = FreeCAD.Vector
doc = FreeCAD.newDocument("grid")
# 20 modules of 5 parts: a drilled base, two pins in its holes, a drilled cover on the base, a cap on a pin.
for k in range(20):
    x, y = 60.0 * (k % 5), 60.0 * (k // 5)
    base = Part.makeBox(40, 40, 10, V(x, y, 0))
    cover = Part.makeBox(40, 40, 5, V(x, y, 10))
    for hx in (10, 30):
        hole = Part.makeCylinder(3, 15, V(x + hx, y + 20, 0))
        base, cover = base.cut(hole), cover.cut(hole)
    doc.addObject("Part::Feature", f"Base{k}").Shape = base
    doc.addObject("Part::Feature", f"Cover{k}").Shape = cover
    for n, hx in enumerate((10, 30)):
        doc.addObject("Part::Feature", f"Pin{k}_{n}").Shape = Part.makeCylinder(3, 15, V(x + hx, y + 20, 0))
    doc.addObject("Part::Feature", f"Cap{k}").Shape = Part.makeCylinder(5, 2, V(x + 10, y + 20, 15))
doc.recompute()
doc.saveAs(OUT)
"""

SPRING_SCRIPT = r"""
import sys
sys.path.insert(0, ROOT + "/tests/workbench")
from spring_document import build_spring_document
build_spring_document(OUT)
"""


def _build(script: str, out: Path) -> None:
    file = out.with_suffix(".py")
    file.write_text(f"ROOT = {str(ROOT)!r}\nOUT = {str(out)!r}\n" + script)
    subprocess.run([shutil.which("freecadcmd"), str(file)], check=True, capture_output=True, timeout=900)


def _export(model: Path, bundle: Path, engine: str) -> dict:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run([str(APLAN), "export-freecad", str(model), "-o", str(bundle), "--force",
                           "--engine", engine], capture_output=True, text=True, timeout=3600)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if done.returncode != 0:
        return {"error": (done.stderr or done.stdout).strip().splitlines()[-1:], "wall": wall, "cpu": cpu}
    product = json.loads((bundle / "product.json").read_text())
    rules = product["geometry"].get("mesh_check", {}).get("rules", {})
    analysis = product["geometry"].get("analysis", {})
    pairs = analysis.get("tolerances", {}).get("pairs", {})
    return {"wall": wall, "cpu": cpu, "parts": len(product["parts"]),
            "rules": {rule: len(ids) for rule, ids in rules.items() if ids},
            "pairs": {k: (len(v) if isinstance(v, list) else v) for k, v in pairs.items()
                      if k in ("mesh", "occt", "undecided", "timed_out")}}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default="mesh,occt")
    parser.add_argument("--only", default=None, help="one document: spring, grid100, truck, pump")
    args = parser.parse_args()
    if shutil.which("freecadcmd") is None:
        print("needs FreeCAD (freecadcmd)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="aplan-budgets-") as folder:
        tmp = Path(folder)
        cases = [("spring", tmp / "spring_rod.FCStd", SPRING_SCRIPT), ("grid100", tmp / "grid100.FCStd", GRID_SCRIPT),
                 ("truck", MODELS / "toy_truck" / "asm_cement_mixer_truck.FCStd", None),
                 ("pump", MODELS / "diaphragm_pump" / "asm_diaphragm_pump.FCStd", None)]
        print(f"{'document':10} {'engine':6} {'parts':>5} {'wall s':>7} {'CPU s':>7}  rules; pairs")
        for name, model, script in cases:
            if args.only and name != args.only:
                continue
            if script is not None:
                _build(script, model)
            for engine in args.engines.split(","):
                row = _export(model, tmp / f"{name}-{engine}", engine)
                if "error" in row:
                    print(f"{name:10} {engine:6} error after {row['wall']:.0f} s: {row['error']}", flush=True)
                    continue
                print(f"{name:10} {engine:6} {row['parts']:5d} {row['wall']:7.1f} {row['cpu']:7.1f}  "
                      f"{row['rules']}; {row['pairs'] or '-'}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
