"""Both engines on one bundle: the meshes settle the easy pairs, OCCT the rest, within a budget.

Definitions
-----------
- A part's *rule* (``geometry.mesh_check.parts[id].rule`` of the bundle, :func:`freecad_aplan.export.mesh_rule`)
  says how its relations are decided: ``mesh`` and ``refined`` (a mesh within 1 % of its B-rep) on the
  meshes; ``exact`` and ``box`` (no mesh within 1 % in the tessellation's work bound: springs, helices) on
  its exact shape; ``hull`` on its ring hull's mesh, by both engines (a spring's exact shape is what OCCT
  cannot sweep within a bound); ``closest`` on its closest mesh, by both engines (its exact shape is over
  the OCCT bound, :mod:`freecad_aplan.occt.complexity`, and no ring holds it tightly enough). A bundle
  without that record (written by hand, older) has every part on the meshes.
- An *easy* pair, for the occt engine, is one whose two parts are on the meshes and whose meshes' bounding
  boxes are apart by more than the contact tolerance: the surfaces cannot touch, and the mesh engine's
  projection test errs only where surfaces touch or slide along each other (the slivers of two
  tessellations, :mod:`planner.geometry.mesh_engine`), so its answer stands. Every other pair is an
  *exact* pair: the mesh engine first, then OCCT on the exact pairs only
  (:func:`freecad_aplan.occt.analyze_shapes` with ``pairs``), at most ``pair_budget`` CPU s and
  ``pair_steps`` operations per pair, ``time_limit`` s in all.
- The mesh engine decides every pair on the meshes, then OCCT decides the pairs of parts whose rule is
  ``exact`` or ``box`` (only those), within the same bounds.
- A relation OCCT leaves undecided (bounds, time limit) keeps the mesh engine's answer, relation by
  relation (a pair's contact; each motion of one part along one direction), and is reported: in the
  warnings, and in ``tolerances["pairs"]`` of the report (``mesh``: pairs settled on the meshes, ``occt``:
  wholly decided by OCCT, ``undecided``: the pairs with a relation left, ``timed_out``; and OCCT's bounds
  ``face_weight``, ``prism_triangles`` with what they left undecided: ``heavy`` parts, ``sweeps_over`` their
  triangle bound, ``sweeps_lost``: sweeps that lost a face OCCT could not sweep at all, e.g. a sphere or a
  torus as NURBS, whose every pair along that direction keeps the mesh answer), and ``fallbacks``: per
  undecided pair, the relations OCCT left and the answer that stands for them (:func:`pair_fallbacks`).
- Without the mesh engine (a bundle whose meshes cannot be read, FreeCAD's Python without trimesh), OCCT
  decides every pair, and a relation it leaves undecided counts as touching and blocking (answer
  ``blocking``); :func:`undecided_notes` says which, for the command line, the workbench's job and its panel.

This module does not import FreeCAD: OCCT runs in FreeCADCmd (:mod:`freecad_aplan.runner`).
"""
from __future__ import annotations

import sys
from dataclasses import replace
from typing import Callable

import numpy as np

from planner.defaults import OCCT_TIME_LIMIT
from planner.errors import PlannerError
from planner.geometry import GeometryReport, Tolerances
from planner.geometry.mesh_engine import PartMesh, analyze_meshes
from planner.product import Product

__all__ = ["fallback_parts", "exact_pairs", "merge_reports", "mesh_then_occt", "pair_fallbacks",
           "undecided_notes", "time_limit_note", "undecided_summary", "to_stderr", "checked_time_limit"]

EXACT_RULES = ("exact", "box")
#: What stands for a relation OCCT left undecided: the mesh engine's answer, or blocking (no meshes to ask).
ANSWERS = (("mesh", "the mesh engine's answer stands"),
           ("blocking", "counted as touching and blocking (no mesh engine's answer to fall back to)"))


def fallback_parts(product: Product, rules=EXACT_RULES) -> dict[str, str]:
    """The parts of ``product`` whose rule is one of ``rules`` (module docstring), with their rule."""
    parts = (product.geometry.get("mesh_check") or {}).get("parts") or {}
    found = {}
    for part_id, check in parts.items():
        rule = check.get("rule") or ("exact" if check.get("method") == "exact" else "mesh")
        if rule in rules and part_id in product.part_ids:
            found[part_id] = rule
    return found


def exact_pairs(meshes: list[PartMesh], fallback, contact: float, near: bool, hulls=()) -> list[tuple[str, str]]:
    """The pairs OCCT decides: every pair with a part of ``fallback``, and with ``near``, every pair whose
    meshes' bounding boxes are within ``contact`` of each other (module docstring), except the pairs with a
    part of ``hulls`` (rule ``hull`` or ``closest``: decided on its mesh, its exact shape being what OCCT
    cannot sweep within a bound). Cost O(parts^2)."""
    lo = np.array([m.vertices.min(axis=0) for m in meshes])
    hi = np.array([m.vertices.max(axis=0) for m in meshes])
    gaps = np.maximum(lo[:, None, :] - hi[None, :, :], lo[None, :, :] - hi[:, None, :]).max(axis=2)
    pairs = []
    for i in range(len(meshes)):
        for j in range(i + 1, len(meshes)):
            if meshes[i].id in hulls or meshes[j].id in hulls:
                continue
            if meshes[i].id in fallback or meshes[j].id in fallback or (near and gaps[i, j] <= contact):
                pairs.append((meshes[i].id, meshes[j].id))
    return pairs


def _open_relations(occt: dict) -> tuple[set, set]:
    """The pairs whose contact OCCT left undecided ({a, b}) and the motions it left undecided ((mover, other,
    direction name)), from ``undecided_relations`` (else every relation of an ``undecided`` pair)."""
    contacts, motions = set(), set()
    relations = occt.get("undecided_relations")
    if relations is None:
        return {frozenset(p) for p in occt.get("undecided", [])}, None
    for a, b, what in relations:
        if what in ("the contact", "the overlap"):
            contacts.add(frozenset((a, b)))
        else:
            mover, _, name = what.rpartition(" moving along ")
            motions.add((mover, b if mover == a else a, name))
    return contacts, motions


def pair_fallbacks(occt: dict, answer: str, asked=None) -> list[dict]:
    """Per pair OCCT left (partly) undecided in ``occt`` (an answer of
    :func:`freecad_aplan.occt.analyze_shapes`), only those of ``asked`` when given: ``{"parts": [a, b],
    "relations": [what, ...], "answer": answer}`` (``answer``: a name in :data:`ANSWERS`), in the order of
    ``undecided``. A pair without ``undecided_relations`` has every relation undecided (``["all"]``).
    Cost O(undecided relations)."""
    relations: dict[frozenset, list[str]] = {}
    for a, b, what in occt.get("undecided_relations") or ():
        relations.setdefault(frozenset((a, b)), []).append(what)
    chosen = None if asked is None else {frozenset(p) for p in asked}
    return [{"parts": list(pair), "relations": relations.get(frozenset(pair), ["all"]), "answer": answer}
            for pair in occt.get("undecided", []) if chosen is None or frozenset(pair) in chosen]


def undecided_notes(tolerances: dict) -> list[str]:
    """One line per pair the exact engine left undecided, from a report's ``tolerances`` (or a stored
    analysis' ``tolerances``): the pair, the relations left and the answer used for them; first, when the
    time limit stopped it, :func:`time_limit_note`. Empty when every pair was decided or the mesh engine alone
    ran."""
    record = (tolerances or {}).get("pairs") or {}
    lines = [f"OCCT left '{f['parts'][0]}' and '{f['parts'][1]}' undecided ({', '.join(f['relations'])}): "
             f"{dict(ANSWERS).get(f['answer'], f['answer'])}" for f in record.get("fallbacks", ())]
    stop = time_limit_note(tolerances)
    return ([stop] if stop and lines else []) + lines


def checked_time_limit(value) -> float:
    """The exact engine's time limit ``value`` (as typed in Detect's task panel, or a number) in CPU seconds:
    a finite number above 0 and at most :data:`~planner.defaults.TIME_LIMIT_MAX`, checked as the command line
    checks ``--time-limit`` (:func:`planner.cli.options.positive_seconds`). Raises
    :class:`~planner.errors.PlannerError` saying what was given and what is allowed (the caller names the field)."""
    import argparse

    from planner.cli.options import positive_seconds

    try:
        return positive_seconds(str(value).strip())
    except argparse.ArgumentTypeError as exc:
        raise PlannerError(f"{exc}; give the CPU seconds OCCT may spend on all its pairs (default "
                           f"{OCCT_TIME_LIMIT:g})") from None


def time_limit_note(tolerances: dict) -> str | None:
    """The line that says the exact engine's time limit stopped it (``tolerances["pairs"]["timed_out"]``): how
    many pairs it left undecided, within how many seconds, and the answer kept for them; None when it was not
    stopped. Undecided pairs are counted whatever left them (the limit, or a bound on one pair's work)."""
    record = (tolerances or {}).get("pairs") or {}
    if not record.get("timed_out"):
        return None
    answers = dict(ANSWERS)
    kept = "; ".join(dict.fromkeys(answers.get(f["answer"], f["answer"]) for f in record.get("fallbacks", ())))
    return (f"{len(record.get('fallbacks', ()))} pairs not decided within the exact engine's time limit of "
            f"{float(record.get('time_limit')):g} s; for each, {kept or 'nothing to keep'} (a longer time limit "
            "decides more of them)")


def undecided_summary(tolerances: dict) -> str:
    """What the end of a detection says of the exact engine's undecided pairs, in a few words: empty when there
    are none, else ``N pairs undecided by OCCT``, or ``N pairs not decided within S s, mesh answers kept`` when
    its time limit stopped it (the answer ``blocking`` says so instead)."""
    record = (tolerances or {}).get("pairs") or {}
    fallbacks = record.get("fallbacks", ())
    if not fallbacks:
        return ""
    if not record.get("timed_out"):
        return f"{len(fallbacks)} pairs undecided by OCCT"
    kept = "mesh answers kept" if all(f["answer"] == "mesh" for f in fallbacks) else "counted as blocking"
    return f"{len(fallbacks)} pairs not decided within {float(record.get('time_limit')):g} s, {kept}"


def merge_reports(mesh: GeometryReport, occt: dict, pairs, engine: str, fallback: dict[str, str]) -> GeometryReport:
    """The mesh engine's report with what OCCT decided (``occt``: the answer of
    :func:`freecad_aplan.occt.analyze_bundle_breps`) on the pairs of ``pairs`` taken from OCCT, relation by
    relation: a pair's contact and interference, and each motion (mover, direction) along every direction
    the mesh engine tested. A relation OCCT left undecided keeps the mesh answer."""
    asked = {frozenset(p) for p in pairs}
    open_contacts, open_motions = _open_relations(occt)
    undecided = {frozenset(p) for p in occt.get("undecided", [])} & asked

    def contact_ours(pair) -> bool:
        return frozenset(pair) in asked and frozenset(pair) not in open_contacts

    def motion_ours(pair, name: str) -> bool:
        key = frozenset(pair)
        if key not in asked:
            return False
        if open_motions is None:
            return key not in open_contacts
        return (pair[0], pair[1], name) not in open_motions

    contacts = [c for c in mesh.contacts if not contact_ours(c)] + \
        [tuple(c) for c in occt["contacts"] if contact_ours(c)]
    interferences = [i for i in mesh.interferences if not contact_ours(i[:2])] + \
        [(i["parts"][0], i["parts"][1], float(i["volume"])) for i in occt["interferences"] if contact_ours(i["parts"])]
    obstructions = {}
    for name, found in mesh.obstructions.items():
        exact = occt["obstructions"].get(name)
        if exact is None:  # a direction OCCT did not test: the meshes decide it
            obstructions[name] = tuple(found)
            continue
        obstructions[name] = tuple([tuple(p) for p in found if not motion_ours(tuple(p), name)] +
                                   [tuple(p) for p in exact if motion_ours(tuple(p), name)])
    record = {"mesh": len(mesh.parts) * (len(mesh.parts) - 1) // 2 - len(asked),
              "occt": len(asked - undecided), "undecided": sorted(sorted(p) for p in undecided),
              "undecided_relations": len(occt.get("undecided_relations", [])),
              "timed_out": bool(occt.get("timed_out")), "time_limit": occt.get("time_limit"),
              "fallback": dict(sorted(fallback.items())), "fallbacks": pair_fallbacks(occt, "mesh", asked),
              **{k: occt[k] for k in ("face_weight", "prism_triangles", "sweeps_over", "sweeps_lost", "heavy")
                 if occt.get(k)}}
    tolerances = {**mesh.tolerances, "pairs": record,
                  **({"occt": occt["tolerances"]} if engine == "occt" and "tolerances" in occt else {})}
    summary = (f"{engine} engine: {record['mesh']} pairs settled on the meshes, {record['occt']} decided by OCCT"
               f"{f', {len(undecided)} partly undecided (the mesh answer kept for what OCCT did not decide)' if undecided else ''}"
               + (f"; parts decided on their exact shape: "
                  f"{', '.join(f'{p} ({r})' for p, r in sorted(fallback.items()))}" if fallback else ""))
    return replace(mesh, engine=engine, contacts=tuple(contacts), interferences=tuple(interferences),
                   obstructions=obstructions, tolerances=tolerances,
                   warnings=(summary, *mesh.warnings, *occt.get("warnings", ())),
                   seconds=mesh.seconds + float(occt.get("seconds", 0.0)))


def to_stderr(text: str) -> None:
    """A progress line on standard error (where ``aplan analyze`` prints the exact engine's progress)."""
    print(text, file=sys.stderr, flush=True)


def mesh_then_occt(product: Product, meshes: list[PartMesh], tolerances: Tolerances, engine: str,
                   run_occt: Callable[[dict], dict], progress: Callable[[str], None] = to_stderr) -> GeometryReport:
    """The report of ``engine`` (``mesh`` or ``occt``) decided as the module docstring says: the mesh engine
    on ``meshes``, then ``run_occt(arguments)`` (the ``analyze-occt`` batch job) on the exact pairs, which
    ``progress(text)`` is told first. With the mesh engine and no part of rule ``exact``/``box``, OCCT does not
    run. Cost: the mesh engine's, plus at most ``tolerances.time_limit`` s of OCCT."""
    report = analyze_meshes(meshes, tolerances)
    fallback = fallback_parts(product)
    if engine == "mesh" and not fallback:
        return report
    pairs = exact_pairs(meshes, fallback, float(tolerances.contact), near=engine == "occt",
                        hulls=fallback_parts(product, ("hull", "closest")))
    if not pairs:
        return merge_reports(report, {"contacts": [], "interferences": [], "obstructions": {}}, [], engine, fallback)
    arguments = {"contact": tolerances.contact, "interference": tolerances.interference, "depth": tolerances.depth,
                 "pair_budget": tolerances.pair_budget, "pair_steps": tolerances.pair_steps,
                 "time_limit": tolerances.time_limit, "face_weight": tolerances.face_weight,
                 "prism_triangles": tolerances.prism_triangles, "pairs": [list(p) for p in pairs],
                 "directions": [list(v) for v in report.directions.values()]}
    progress(f"occt: deciding {len(pairs)} of {len(meshes) * (len(meshes) - 1) // 2} pairs on the exact shapes "
             f"(at most {tolerances.time_limit:g} s)")
    return merge_reports(report, run_occt(arguments), pairs, engine, fallback)
