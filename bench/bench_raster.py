"""Mesh-engine benchmark: the z-buffer of the projection test (``planner.geometry.raster.rasterise``) on a ball in a closed
cage (the interlock test's caged ball, as trimesh icospheres), at the default resolution (2048 px across).

Run: ``.venv/bin/python bench/bench_raster.py`` (under a minute).

Rows: the three axes of both parts, as ``analyze_meshes`` rasterises them, and the whole refusal of the pair
(``apply_interlock_mode``: the overlap rule rasterises both parts along each direction it tries). CPU time
(``time.process_time``).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
import trimesh  # noqa: E402

from planner.assembly.interlocks import apply_interlock_mode  # noqa: E402
from planner.errors import PlannerError  # noqa: E402
from planner.geometry import Tolerances, analyze_meshes, apply_report  # noqa: E402
from planner.geometry import raster  # noqa: E402
from planner.geometry.mesh_engine import PartMesh  # noqa: E402
from planner.product import Part, Product  # noqa: E402


def main() -> None:
    cage = trimesh.creation.icosphere(5, radius=10).difference(trimesh.creation.icosphere(5, radius=6))
    ball = trimesh.creation.icosphere(5, radius=5.9)
    parts = [PartMesh(n, np.asarray(m.vertices, float), np.asarray(m.faces, np.int64))
             for n, m in (("cage", cage), ("ball", ball))]
    lo = np.array([p.vertices.min(axis=0) for p in parts]).min(axis=0)
    hi = np.array([p.vertices.max(axis=0) for p in parts]).max(axis=0)
    tol = Tolerances(directions=0)
    pixel = float((hi - lo).max()) / tol.resolution
    start = time.process_time()
    pixels = 0
    for axis in range(3):
        u, v = ((1, 2), (2, 0), (0, 1))[axis]
        for part in parts:
            depth = raster.rasterise(part.triangles, axis, lo[[u, v]], pixel, tol.grazing, 4 * pixel)
            pixels += int(np.isfinite(depth.zmin).sum())
    axes = time.process_time() - start
    start = time.process_time()
    report = analyze_meshes(parts, tol)
    product = apply_report(Product((Part("cage"), Part("ball")), ()), report)
    try:
        apply_interlock_mode(product, "resolve", parts)
        refused = "resolved (unexpected)"
    except PlannerError:
        refused = "refused"
    whole = time.process_time() - start
    print(f"{sum(len(p.faces) for p in parts)} triangles, {pixels:,} pixels covered over the 6 depth maps\n")
    print("| work | CPU s |\n|---|---:|")
    print(f"| the 6 depth maps (3 axes x 2 parts) | {axes:.2f} |")
    print(f"| analyze_meshes + the interlock rules ({refused}) | {whole:.2f} |")


if __name__ == "__main__":
    main()
