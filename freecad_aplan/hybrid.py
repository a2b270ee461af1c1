"""Both engines on one bundle: the meshes settle the easy pairs, OCCT the rest, within a budget.

Definitions
-----------
- A part's *rule* (``geometry.mesh_check.parts[id].rule`` of the bundle, :func:`freecad_aplan.export.mesh_rule`)
  says how its relations are decided: ``mesh`` and ``refined`` (a mesh within 1 % of its B-rep) on the
  meshes; ``exact`` and ``box`` (no mesh within 1 % in the tessellation's work bound: springs, helices) on
  its exact shape. A bundle without that record (written by hand, older) has every part on the meshes.
- An *easy* pair, for the occt engine, is one whose two parts are on the meshes and whose meshes' bounding
  boxes are apart by more than the contact tolerance: the surfaces cannot touch, and the mesh engine's
  projection test errs only where surfaces touch or slide along each other (the slivers of two
  tessellations, :mod:`planner.geometry.mesh_engine`), so its answer stands. Every other pair is an
  *exact* pair: the mesh engine first, then OCCT on the exact pairs only
  (:func:`freecad_aplan.occt.analyze_shapes` with ``pairs``), at most ``pair_budget`` CPU s and
  ``pair_steps`` operations per pair, ``time_limit`` s in all.
- The mesh engine decides every pair on the meshes, then OCCT decides the pairs of parts whose rule is
  ``exact`` or ``box`` (only those), within the same bounds.
- A pair OCCT leaves undecided (bounds, time limit) keeps the mesh engine's answer, and is reported: in the
  warnings, and in ``tolerances["pairs"]`` of the report (``mesh``: pairs settled on the meshes, ``occt``:
  decided by OCCT, ``undecided``: the pairs, ``timed_out``).

This module does not import FreeCAD: OCCT runs in FreeCADCmd (:mod:`freecad_aplan.runner`).
"""
from __future__ import annotations

import sys
from dataclasses import replace
from typing import Callable

import numpy as np

from planner.geometry import GeometryReport, Tolerances
from planner.geometry.mesh_engine import PartMesh, analyze_meshes
from planner.product import Product

__all__ = ["fallback_parts", "exact_pairs", "merge_reports", "mesh_then_occt"]

EXACT_RULES = ("exact", "box")


def fallback_parts(product: Product) -> dict[str, str]:
    """The parts of ``product`` whose rule is ``exact`` or ``box`` (module docstring), with their rule."""
    parts = (product.geometry.get("mesh_check") or {}).get("parts") or {}
    found = {}
    for part_id, check in parts.items():
        rule = check.get("rule") or ("exact" if check.get("method") == "exact" else "mesh")
        if rule in EXACT_RULES and part_id in product.part_ids:
            found[part_id] = rule
    return found


def exact_pairs(meshes: list[PartMesh], fallback, contact: float, near: bool) -> list[tuple[str, str]]:
    """The pairs OCCT decides: every pair with a part of ``fallback``, and with ``near``, every pair whose
    meshes' bounding boxes are within ``contact`` of each other (module docstring). Cost O(parts^2)."""
    lo = np.array([m.vertices.min(axis=0) for m in meshes])
    hi = np.array([m.vertices.max(axis=0) for m in meshes])
    gaps = np.maximum(lo[:, None, :] - hi[None, :, :], lo[None, :, :] - hi[:, None, :]).max(axis=2)
    pairs = []
    for i in range(len(meshes)):
        for j in range(i + 1, len(meshes)):
            if meshes[i].id in fallback or meshes[j].id in fallback or (near and gaps[i, j] <= contact):
                pairs.append((meshes[i].id, meshes[j].id))
    return pairs


def merge_reports(mesh: GeometryReport, occt: dict, pairs, engine: str, fallback: dict[str, str]) -> GeometryReport:
    """The mesh engine's report with the pairs of ``pairs`` that OCCT decided (``occt``: the answer of
    :func:`freecad_aplan.occt.analyze_bundle_breps`) taken from OCCT: their contacts, interferences and
    obstructions along every direction the mesh engine tested. Undecided pairs keep the mesh answer."""
    undecided = {frozenset(p) for p in occt.get("undecided", [])}
    decided = {frozenset(p) for p in pairs} - undecided

    def ours(pair) -> bool:
        return frozenset(pair) in decided

    contacts = [c for c in mesh.contacts if not ours(c)] + [tuple(c) for c in occt["contacts"] if ours(c)]
    interferences = [i for i in mesh.interferences if not ours(i[:2])] + \
        [(i["parts"][0], i["parts"][1], float(i["volume"])) for i in occt["interferences"] if ours(i["parts"])]
    obstructions = {}
    for name, found in mesh.obstructions.items():
        exact = occt["obstructions"].get(name)
        if exact is None:  # a direction OCCT did not test: the meshes decide it
            obstructions[name] = tuple(found)
            continue
        obstructions[name] = tuple([p for p in found if not ours(p)] + [tuple(p) for p in exact if ours(p)])
    record = {"mesh": len(mesh.parts) * (len(mesh.parts) - 1) // 2 - len({frozenset(p) for p in pairs}),
              "occt": len(decided), "undecided": sorted(sorted(p) for p in undecided),
              "timed_out": bool(occt.get("timed_out")), "time_limit": occt.get("time_limit"),
              "fallback": dict(sorted(fallback.items()))}
    tolerances = {**mesh.tolerances, "pairs": record,
                  **({"occt": occt["tolerances"]} if engine == "occt" and "tolerances" in occt else {})}
    summary = (f"{engine} engine: {record['mesh']} pairs settled on the meshes, {record['occt']} decided by OCCT"
               f"{f', {len(undecided)} undecided (the mesh answer kept)' if undecided else ''}"
               + (f"; parts decided on their exact shape: "
                  f"{', '.join(f'{p} ({r})' for p, r in sorted(fallback.items()))}" if fallback else ""))
    return replace(mesh, engine=engine, contacts=tuple(contacts), interferences=tuple(interferences),
                   obstructions=obstructions, tolerances=tolerances,
                   warnings=(summary, *mesh.warnings, *occt.get("warnings", ())),
                   seconds=mesh.seconds + float(occt.get("seconds", 0.0)))


def mesh_then_occt(product: Product, meshes: list[PartMesh], tolerances: Tolerances, engine: str,
                   run_occt: Callable[[dict], dict]) -> GeometryReport:
    """The report of ``engine`` (``mesh`` or ``occt``) decided as the module docstring says: the mesh engine
    on ``meshes``, then ``run_occt(arguments)`` (the ``analyze-occt`` batch job) on the exact pairs. With
    the mesh engine and no part of rule ``exact``/``box``, OCCT does not run. Cost: the mesh engine's, plus
    at most ``tolerances.time_limit`` s of OCCT."""
    report = analyze_meshes(meshes, tolerances)
    fallback = fallback_parts(product)
    if engine == "mesh" and not fallback:
        return report
    pairs = exact_pairs(meshes, fallback, float(tolerances.contact), near=engine == "occt")
    if not pairs:
        return merge_reports(report, {"contacts": [], "interferences": [], "obstructions": {}}, [], engine, fallback)
    arguments = {"contact": tolerances.contact, "interference": tolerances.interference, "depth": tolerances.depth,
                 "pair_budget": tolerances.pair_budget, "pair_steps": tolerances.pair_steps,
                 "time_limit": tolerances.time_limit, "pairs": [list(p) for p in pairs],
                 "directions": [list(v) for v in report.directions.values()]}
    print(f"occt: deciding {len(pairs)} of {len(meshes) * (len(meshes) - 1) // 2} pairs on the exact shapes "
          f"(at most {tolerances.time_limit:g} s)", file=sys.stderr, flush=True)
    return merge_reports(report, run_occt(arguments), pairs, engine, fallback)
