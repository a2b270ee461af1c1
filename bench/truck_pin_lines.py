"""Why the mesh engine finds a part blocked by another along an axis: the pixel lines of its projection test
that block, with the two parts' depth ranges on them (issue 13: the truck's tires and chassis).

    .venv/bin/python bench/truck_pin_lines.py /tmp/sa-truck tire_001 chassis_001

For each axis and sense: how many lines of the projection grid block the first part's motion, and the
depth ranges [min, max] of both parts on a sample of them (the engine's ``_rasterise`` and ``_window``, with
the bundle's recorded pixel size and tolerances).
"""
from __future__ import annotations

import sys

import numpy as np
import trimesh

from planner.geometry import projection
from planner.product import load_product


def blocking_lines(folder: str, moving: str, other: str) -> None:
    product = load_product(f"{folder}/product.json")
    used = product.geometry["analysis"]["tolerances"]
    pixel, depth, grazing = used["pixel"], used["depth"], used["grazing"]
    meshes = [trimesh.load(f"{folder}/meshes/{name}.stl") for name in (moving, other)]
    corner = np.vstack([m.vertices for m in meshes]).min(axis=0)
    for axis, name in enumerate("XYZ"):
        u, v = projection._PLANE[axis]
        a, b = (projection._rasterise(m.triangles, axis, corner[[u, v]], pixel, grazing) for m in meshes)
        window = projection._window(a, b)
        if window is None:
            print(f"{name}: the projections do not overlap")
            continue
        both = a.inner[window[0]] & b.inner[window[1]]
        amin, amax = a.zmin[window[0]], a.zmax[window[0]]
        bmin, bmax = b.zmin[window[1]], b.zmax[window[1]]
        for sense, lines in (("+", both & (bmax > amin + depth)), ("-", both & (amax > bmin + depth))):
            count = int(lines.sum())
            print(f"{moving} moving {sense}{name}: {count} blocking lines of {int(both.sum())} shared")
            for j, i in np.argwhere(lines)[:: max(1, count // 3)][:3]:
                print(f"    {moving} [{amin[j, i]:.3f}, {amax[j, i]:.3f}]  {other} [{bmin[j, i]:.3f}, {bmax[j, i]:.3f}]")


if __name__ == "__main__":
    blocking_lines(*sys.argv[1:4])
