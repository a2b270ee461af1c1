"""The toy truck planned as workstations (issue 13, item 2): its wood screws left out (item 1 folds them into
operations; here they are simply removed), subassemblies proposed from the connection diagram, and the figures
of each level.

    .venv/bin/aplan export-freecad ../shared/models/toy_truck/asm_cement_mixer_truck.FCStd -o /tmp/sa-truck
    timeout 600 prlimit --as=8000000000 .venv/bin/python bench/bench_subassemblies.py /tmp/sa-truck [--save FILE]

(The tessellation slivers that once blocked each tire on its axle pin are ignored by the mesh engine since
its depth-step rule: see bench/README.md.)
"""
from __future__ import annotations

import sys
import time
from dataclasses import replace

from planner import api
from planner.assembly.hierarchy import level_statistics, product_levels
from planner.assembly.subassembly_proposals import propose_subassemblies
from planner.product import Obstruction, Product, save_product


def without(product: Product, prefix: str) -> Product:
    """``product`` without the parts whose id starts with ``prefix`` (and their contacts and obstructions)."""
    keep = [p for p in product.parts if not p.id.startswith(prefix)]
    ids = {p.id for p in keep}
    contacts = tuple(c for c in product.contacts if set(c) <= ids)
    obstructions = tuple(Obstruction(o.direction, tuple(b for b in o.blocks if set(b) <= ids))
                         for o in product.obstructions)
    return replace(product, parts=tuple(keep), contacts=contacts, obstructions=obstructions, operations=(),
                   markers=None, technical_constraints=())


def main() -> None:
    folder = sys.argv[1]
    product = without(api.resolve_product(folder), "wood_screw")
    print(f"{len(product.parts)} parts, {len(product.contacts)} contacts")
    if "--save" in sys.argv:  # the product without screws, for aplan stats FILE --subassemblies auto
        save_product(product, sys.argv[sys.argv.index("--save") + 1])
    start = time.perf_counter()
    groups = propose_subassemblies(product)
    print(f"proposed in {time.perf_counter() - start:.2f} s:")
    for g in groups:
        print(f"  {g.id}: {', '.join(g.parts)}")
    arranged = replace(product, subassemblies=groups)
    print(f"levels: {[level.id for level in product_levels(arranged)]}")
    start = time.perf_counter()
    for level, stats in level_statistics(arranged):
        shown = stats.as_dict() if hasattr(stats, "as_dict") else f"cannot be built: {stats}"
        print(f"  {level.id:<6} {shown}  {getattr(stats, 'refused', None) or ''}")
    print(f"stats of every level in {time.perf_counter() - start:.2f} s")


if __name__ == "__main__":
    main()
