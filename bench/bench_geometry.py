"""Geometry benchmarks: contacts + obstruction diagrams of real CAD models (needs FreeCAD for the export).

Run: ``.venv/bin/python bench/bench_geometry.py [--occt]`` (about a minute; with --occt, longer).
The export (FreeCADCmd: tessellation, STL/BREP writing) is not timed; the analysis is, median of 3 runs.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from freecad_aplan.plugin import export_bundle  # noqa: E402
from planner.geometry import Tolerances, analyze_meshes  # noqa: E402
from planner.geometry.bundle import analyze_product, load_bundle, load_part_meshes  # noqa: E402

MODELS = ROOT.parent / "shared" / "models"
CASES = [
    ("pen (simplified)", MODELS / "bourjault_pen/simplified/asm_bourjault_ballpoint.FCStd"),
    ("pen (complex)", MODELS / "bourjault_pen/complex/asm_bourjault_ballpoint.FCStd"),
    ("toy truck", MODELS / "toy_truck/asm_cement_mixer_truck.FCStd"),
    ("diaphragm pump", MODELS / "diaphragm_pump/asm_diaphragm_pump.FCStd"),
]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--occt", action="store_true", help="also time the OCCT engine (runs FreeCADCmd)")
    args = parser.parse_args()
    print("| model | parts | triangles | contacts | interferences | obstruction pairs +X/+Y/+Z | mesh engine s |"
          + (" occt engine s |" if args.occt else ""))
    print("|---|---:|---:|---:|---:|---|---:|" + ("---:|" if args.occt else ""))
    with tempfile.TemporaryDirectory() as folder:
        for name, model in CASES:
            product = export_bundle(model, Path(folder) / name.replace(" ", "_"), engine="none")
            meshes = load_part_meshes(product)
            times = []
            for _ in range(3):
                start = time.perf_counter()
                report = analyze_meshes(meshes, Tolerances())
                times.append(time.perf_counter() - start)
            pairs = "/".join(str(len(report.obstructions[a])) for a in ("+X", "+Y", "+Z"))
            row = (f"| {name} | {len(meshes)} | {sum(len(m.faces) for m in meshes):,} | {len(report.contacts)} | "
                   f"{len(report.interferences)} | {pairs} | {statistics.median(times):.2f} |")
            if args.occt:
                occt = analyze_product(load_bundle(product.source and Path(product.source).parent), "occt")
                row += f" {occt.seconds:.1f} |"
            print(row, flush=True)


if __name__ == "__main__":
    main()
