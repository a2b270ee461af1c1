"""Gap benchmarks: the gaps between the groups of a connection diagram, and --contact auto, on real CAD models
(needs FreeCAD for the export, which is not timed).

Run: ``.venv/bin/python bench/bench_gaps.py`` (about two minutes). For each model: the groups at the default
contact tolerance; the lazy gap search (:func:`planner.geometry.gaps.mesh_gaps`: exact gaps measured, median
of 3 runs); every pair's exact gap by brute force, for comparison; and ``analyze_product`` with
``--contact auto`` (the mesh engine once at the default tolerance, and once more at the chosen tolerance when
the product falls apart; the ceiling raised to 40 mm so that the pump is analysed rather than refused).
"""
from __future__ import annotations

import itertools
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from freecad_aplan.plugin import export_bundle  # noqa: E402
from planner.geometry import Tolerances  # noqa: E402
from planner.geometry.bundle import analyze_product, load_part_meshes  # noqa: E402
from planner.geometry.gaps import connection_groups, mesh_gaps, part_gaps  # noqa: E402

MODELS = ROOT.parent / "shared" / "models"
CASES = [
    ("toy truck", MODELS / "toy_truck/asm_cement_mixer_truck.FCStd"),
    ("diaphragm pump", MODELS / "diaphragm_pump/asm_diaphragm_pump.FCStd"),
]


def _seconds(job, runs: int = 3) -> tuple[float, object]:
    times, result = [], None
    for _ in range(runs):
        start = time.perf_counter()
        result = job()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def main() -> None:
    print("| model | parts | triangles | groups at 0.1 | gap search: pairs measured | gap search s | "
          "every pair (brute force) s | auto: tolerance | auto: contacts | auto s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as folder:
        for name, model in CASES:
            product = export_bundle(model, Path(folder) / name.replace(" ", "_"))
            meshes = load_part_meshes(product)
            triangles = sum(len(m.faces) for m in meshes)
            groups = connection_groups(product.part_ids, product.contacts)
            search, report = _seconds(lambda: mesh_gaps(meshes, product.contacts))
            every = list(itertools.combinations(product.part_ids, 2))
            brute, _ = _seconds(lambda: part_gaps(meshes, every), runs=1)
            auto, analysed = _seconds(lambda: analyze_product(product, "mesh", Tolerances(contact="auto",
                                                                                          contact_ceiling=40)),
                                      runs=1)
            chosen = analysed.tolerances["contact_auto"]["chosen"]
            print(f"| {name} | {len(meshes)} | {triangles:,} | {len(groups)} | {report.queries} of "
                  f"{sum(1 for a, b in every if not any(a in g and b in g for g in groups)):,} | {search:.3f} | "
                  f"{brute:.2f} ({len(every):,} pairs) | {chosen:g} | {len(analysed.contacts)} | {auto:.1f} |",
                  flush=True)


if __name__ == "__main__":
    main()
