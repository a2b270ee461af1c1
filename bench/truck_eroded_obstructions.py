"""Re-analyse a bundle with the projection test's blocking lines opened (eroded) by the grazing band, and list the
obstruction pairs that drop out (issue 13: the truck's tire pins). An experiment, not the engine:

    .venv/bin/python bench/truck_eroded_obstructions.py /tmp/sa-truck/product.json [OUT.json]
"""
from __future__ import annotations

import sys
import time

from scipy import ndimage

from planner.geometry import mesh_engine as me
from planner.geometry.bundle import analyze_product, apply_report
from planner.product import load_product, save_product


def patched(parts, lo, hi, tol):
    """The engine's ``_obstructions`` with one change: a pair blocks only where its blocking lines survive an
    erosion by ``tol.grazing`` pixels (a sliver narrower than the grazing band never does)."""
    extent = float((hi.max(axis=0) - lo.min(axis=0)).max())
    pixel = extent / tol.resolution if extent > 0 else 1.0
    origin3 = lo.min(axis=0)
    result = {}
    for axis, name in enumerate(me.AXES):
        u, v = me._PLANE[axis]
        origin = origin3[[u, v]]
        maps = [me._rasterise(p.triangles, axis, origin, pixel, tol.grazing) for p in parts]
        pairs = []
        for i in range(len(parts)):
            for j in range(i + 1, len(parts)):
                margin = 2 * tol.grazing * pixel
                if (min(hi[i, u], hi[j, u]) - max(lo[i, u], lo[j, u]) <= margin or
                        min(hi[i, v], hi[j, v]) - max(lo[i, v], lo[j, v]) <= margin):
                    continue
                cut = me._window(maps[i], maps[j])
                if cut is None:
                    continue
                a, b = maps[i], maps[j]
                both = a.inner[cut[0]] & b.inner[cut[1]]
                if not both.any():
                    continue
                plus = both & (b.zmax[cut[1]] > a.zmin[cut[0]] + tol.depth)
                minus = both & (a.zmax[cut[0]] > b.zmin[cut[1]] + tol.depth)
                if ndimage.binary_erosion(plus, iterations=tol.grazing).any():
                    pairs.append((parts[i].id, parts[j].id))
                if ndimage.binary_erosion(minus, iterations=tol.grazing).any():
                    pairs.append((parts[j].id, parts[i].id))
        result[name] = pairs
    return result, pixel

product = load_product(sys.argv[1])
before = analyze_product(product)
me._obstructions = patched
start = time.perf_counter()
after = analyze_product(product)
print(f"re-analysed in {time.perf_counter() - start:.1f} s")
for d in before.obstructions:
    b, a = set(before.obstructions[d]), set(after.obstructions[d])
    print(d, "dropped:", sorted(b - a), "added:", sorted(a - b))
if len(sys.argv) > 2:
    save_product(apply_report(product, after), sys.argv[2])
