"""The toy truck planned as workstations (issue 13, item 2): its wood screws left out (item 1 folds them into
operations; here they are simply removed), subassemblies proposed from the connection diagram, and the figures
of each level.

    .venv/bin/aplan export-freecad ../shared/models/toy_truck/asm_cement_mixer_truck.FCStd -o /tmp/sa-truck
    timeout 600 prlimit --as=8000000000 .venv/bin/python bench/bench_subassemblies.py /tmp/sa-truck [--fix-pins] [--save FILE]

``--fix-pins`` drops the obstruction pairs that tessellation slivers invent between each tire's axle pin
and the chassis bore it sits in (see bench/README.md): the tire then leaves its bore along -X or +X.
"""
from __future__ import annotations

import sys
import time
from dataclasses import replace

from planner import api
from planner.assembly.hierarchy import level_statistics, product_levels, propose_subassemblies
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


def free_pins(product: Product) -> Product:
    """Drop the pairs that block a tire from leaving the chassis along the axis pointing away from it."""
    obstructions = []
    for o in product.obstructions:
        if o.direction.name == "+X":  # tires with x < 0 leave along -X, those with x > 0 along +X
            blocks = tuple(b for b in o.blocks if not ({b[0], b[1]} & _TIRES and "chassis_001" in b))
            # A pair (x, y) along +X: x moving along +X hits y. A tire on the -X side moving along +X hits the
            # chassis; on the +X side, the chassis moving along +X hits it (the tire moving along -X).
            left = tuple((t, "chassis_001") for t in sorted(_TIRES - _RIGHT))
            right = tuple(("chassis_001", t) for t in sorted(_RIGHT))
            obstructions.append(Obstruction(o.direction, blocks + left + right))
        else:
            obstructions.append(o)
    return replace(product, obstructions=tuple(obstructions))


_TIRES = {f"tire_00{k}" for k in range(1, 7)}
_RIGHT: set[str] = set()  # filled in main: the tires on the +X side


def main() -> None:
    folder = sys.argv[1]
    product = without(api.resolve_product(folder), "wood_screw")
    if "--fix-pins" in sys.argv:
        import trimesh

        for tire in _TIRES:
            mesh = trimesh.load(f"{folder}/meshes/{tire}.stl")
            if mesh.bounds.mean(axis=0)[0] > 0:
                _RIGHT.add(tire)
        product = free_pins(product)
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
