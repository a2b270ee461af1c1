"""Export a FreeCAD document (or STEP file) as a product bundle: product file + one mesh and B-rep per part.

Runs inside FreeCAD (the GUI, or FreeCADCmd through ``freecad_aplan.batch``). A bundle folder holds:

- ``product.json``: the parts (id, label, mesh, brep, volume, material), no contacts yet (the geometry
  engines fill them in), and ``geometry``: the source model and the tessellation tolerances;
- ``meshes/<id>.stl``: binary STL of each part in global coordinates (model units);
- ``breps/<id>.brep``: the exact OCCT shape of each part, for the OCCT engine.

When the document holds an APLAN analysis (:mod:`freecad_aplan.intent`), its designer intent applies:
its groups and exclusions choose the components, and its technical constraints, tools and operation tags
go into ``product.json``, and so do its fastener tags and subassembly tree (:mod:`freecad_aplan.structure`,
as the ``fasteners`` and ``subassemblies`` sections with source "designer"). So do its stored connection and
obstruction diagrams (as the designer edited them), when they cover exactly the exported components;
``geometry.analysis.diagrams`` then says ``"stored in the document"`` (``", edited"`` after edits), and a
geometry engine need not run. Without a tree in the analysis, the document's structure (``App::Part``
containers, groups) becomes the product's ``subassemblies``
(:func:`~freecad_aplan.containers.document_subassemblies`). The document is never modified: shapes are copies,
and documents this module
opened are closed again.
"""
from __future__ import annotations

import json
import os
import re
from typing import TYPE_CHECKING

import FreeCAD
from planner.defaults import (ANGULAR_DEFLECTION, LINEAR_DEFLECTION, MESH_TOLERANCE, OCCT_FACE_WEIGHT, PRODUCT_FILE,
                               PRODUCT_FORMAT, PRODUCT_VERSION)
from planner.errors import GeometryError
from planner.files import write_atomic

from .analysis import structure_entries
from .containers import document_subassemblies
from .document import is_grouping, open_model, read_components
from .tessellation import box_mesh, checked_mesh

if TYPE_CHECKING:
    from .intent import Intent

__all__ = ["mesh_rule", "fallback_mesh", "export_components", "export_document", "export_model", "DEFAULT_LINEAR_DEFLECTION",
           "DEFAULT_ANGULAR_DEFLECTION"]

RULES = ("mesh", "refined", "hull", "exact", "closest", "box")  # see mesh_rule and fallback_mesh
DEFAULT_LINEAR_DEFLECTION = LINEAR_DEFLECTION  # model units (mm): the largest distance between mesh and surface
DEFAULT_ANGULAR_DEFLECTION = ANGULAR_DEFLECTION  # radians between neighbouring facet normals on curved faces


def _file_name(part_id: str, used: set[str]) -> str:
    base = re.sub(r"[^A-Za-z0-9._-]+", "_", part_id).strip("._") or "part"
    name, k = base, 1
    while name.lower() in used:
        k += 1
        name = f"{base}_{k}"
    used.add(name.lower())
    return name


def mesh_rule(check) -> str:
    """The rule a part's relations are decided by, from its :class:`~freecad_aplan.tessellation.MeshCheck`
    (before :func:`fallback_mesh`): ``mesh`` (its first mesh is within tolerance), ``refined`` (another
    method's is), ``exact`` (none is within the work bound: the closest closed mesh is kept, and the pairs of
    the part are decided on its exact shape, :mod:`freecad_aplan.hybrid`) or ``box`` (no closed mesh: its
    bounding box stands in, and its pairs are decided on its exact shape too)."""
    if check.method == "exact":
        return "exact" if check.closed else "box"
    return "mesh" if check.method == "standard" else "refined"


def fallback_mesh(shape, mesh, check, linear: float, angular: float, face_weight: int = OCCT_FACE_WEIGHT):
    """(rule, mesh) for a part: its :func:`mesh_rule` and mesh, except that a part no mesh is right for gets
    its ring hull when one is tight (rule ``hull``: a spring's tube, :mod:`freecad_aplan.hull`; its pairs are
    then decided on that mesh, which holds the part), else its bounding box when no mesh is closed.

    A part whose exact shape is *heavy* (its heaviest face weighs more than ``face_weight``,
    :mod:`freecad_aplan.occt.complexity`: OCCT would leave all its pairs undecided) gets a ring up to
    :data:`~freecad_aplan.hull.LOOSE` times its volume instead (rule ``hull``), else its closest closed mesh
    (rule ``closest``: decided on the meshes, no OCCT), else its bounding box (``box``). Cost: one
    :func:`~freecad_aplan.hull.ring_hull` (two when heavy) and one tessellation of the ring."""
    import MeshPart

    from .hull import LOOSE, TIGHT, ring_hull
    from .occt.complexity import shape_weight

    rule = mesh_rule(check)
    if rule not in ("exact", "box"):
        return rule, mesh
    points = [(p.x, p.y, p.z) for p in mesh.Points]
    heavy = shape_weight(shape)[0] > face_weight
    for tight in ((TIGHT, LOOSE) if heavy else (TIGHT,)):
        hull = ring_hull(points, shape.Volume, linear, shape, tight)
        if hull is None:
            continue
        ring = MeshPart.meshFromShape(Shape=hull, LinearDeflection=linear, AngularDeflection=angular, Relative=False)
        if ring.isSolid():
            return "hull", ring
    if rule == "exact":
        return ("closest" if heavy else "exact"), mesh
    return rule, box_mesh(shape)


def _fallback_record(shape, mesh, rule: str) -> dict:
    """What a fallback rule rests on: the exact shape's ``weight`` (:mod:`freecad_aplan.occt.complexity`),
    and for ``hull`` the ring's volume over the part's (``hull_ratio``). Empty for a part on its mesh."""
    from .occt.complexity import shape_weight

    if rule in ("mesh", "refined"):
        return {}
    record = {"weight": shape_weight(shape)[0]}
    if rule == "hull":
        record["hull_ratio"] = round(float(mesh.Volume) / float(shape.Volume), 3)
    return record


def _fallback_detail(record: dict, face_weight: int = OCCT_FACE_WEIGHT) -> str:
    """The warning's words for a heavy part (:func:`_fallback_record`): why its exact shape is not used."""
    weight = record.get("weight", 0)
    if weight <= face_weight:
        return ""
    ring = f"; its ring is {record['hull_ratio']:g} times its volume" if "hull_ratio" in record else ""
    return (f" (its exact shape is beyond the OCCT engine's bound: heaviest face weight {weight:,} > "
            f"{face_weight:,}, --occt-face-weight{ring})")


def _report_check(part_id: str, check, rule: str, tolerance: float, warnings: list[str], detail: str = "") -> None:
    """A warning for a part whose first mesh was off (re-tessellated) or that no mesher got right (with the
    fallback ``rule`` applied to it)."""
    first = next((error for _, error, _ in check.tried if error is not None), None)
    before = "no triangles" if first is None else f"{first:+.1%} in volume"
    if rule in ("exact", "box", "hull", "closest"):
        what = {"hull": "its contacts and obstructions are decided on its ring hull (the tube its section sweeps "
                        "around its axis, which holds the part: conservative for blocking)",
                "exact": "its contacts and obstructions are decided on its exact shape (OCCT), and its closest "
                         "mesh stands in for anything OCCT leaves undecided",
                "box": "its contacts and obstructions are decided on its exact shape (OCCT), and its bounding "
                       "box (no closed mesh) for anything OCCT leaves undecided",
                "closest": "its contacts and obstructions are decided on its closest mesh (within the linear "
                           "deflection of its surface; not conservative for blocking: check its pairs)"}[rule] + detail
        warnings.append(f"{part_id}: no tessellation is within {tolerance:.0%} of the B-rep within the mesh budget "
                        f"(first mesh {before}, best {check.volume_error:+.1%}; tried "
                        f"{', '.join(method for method, _, _ in check.tried)}); fallback rule {rule!r}: {what}")
    elif rule == "refined":
        warnings.append(f"{part_id}: the mesh differed from the B-rep ({before}); re-tessellated with "
                        f"{check.method}: {check.volume_error:+.2%} in volume, {check.area_error:+.2%} in area")


def export_components(components, folder: str, source: str, warnings: list[str],
                      linear_deflection: float = DEFAULT_LINEAR_DEFLECTION,
                      angular_deflection: float = DEFAULT_ANGULAR_DEFLECTION, extra: dict | None = None,
                      analysis: dict | None = None, mesh_tolerance: float = MESH_TOLERANCE,
                      designer: dict | None = None, progress=None, face_weight: int = OCCT_FACE_WEIGHT) -> dict:
    """Write meshes, B-reps and ``product.json`` for ``components`` into ``folder`` (which must exist).

    Each mesh is checked against its B-rep (:func:`~freecad_aplan.tessellation.checked_mesh`): re-tessellated
    when its volume or area is off by more than ``mesh_tolerance``; ``geometry.mesh_check`` records per part
    the errors, the method kept and the part's rule (:func:`fallback_mesh`); under ``exact`` the parts no
    mesher got right within the work bound (their pairs are decided by OCCT), and under ``rules`` the parts
    of each rule; ``geometry.warnings`` names every part that needed another method or a fallback.

    ``extra``: more top-level keys of the product file (the designer intent's constraints and tags, stored
    diagrams); ``analysis``: the ``geometry.analysis`` record of where those diagrams came from; ``designer``:
    the ``geometry.designer`` record (the designer's directions and not-blocking marks);
    ``progress(text)``, when given, is told each part before it is tessellated; ``face_weight``: the OCCT
    engine's bound that makes a part heavy (:func:`fallback_mesh`).
    """
    os.makedirs(os.path.join(folder, "meshes"), exist_ok=True)
    os.makedirs(os.path.join(folder, "breps"), exist_ok=True)
    used: set[str] = set()
    parts = []
    checks: dict[str, dict] = {}
    for k, component in enumerate(components):
        if progress is not None:
            progress(f"tessellating part {k + 1} of {len(components)}: {component.id}")
        name = _file_name(component.id, used)
        mesh, check = checked_mesh(component.shape, linear_deflection, angular_deflection, mesh_tolerance)
        if mesh is None:
            raise GeometryError(f"part {component.id!r}: tessellation produced no triangles (tried "
                                f"{', '.join(method for method, _, _ in check.tried)})")
        rule, mesh = fallback_mesh(component.shape, mesh, check, linear_deflection, angular_deflection, face_weight)
        checks[component.id] = {**check.as_dict(), "rule": rule, **_fallback_record(component.shape, mesh, rule)}
        _report_check(component.id, check, rule, mesh_tolerance, warnings,
                      _fallback_detail(checks[component.id], face_weight))
        mesh.write(os.path.join(folder, "meshes", name + ".stl"))
        component.shape.exportBrep(os.path.join(folder, "breps", name + ".brep"))
        part = {"id": component.id, "label": component.label, "mesh": f"meshes/{name}.stl",
                "brep": f"breps/{name}.brep", "volume": round(component.shape.Volume, 6)}
        if component.material:
            part["material"] = component.material
        parts.append(part)
    product = {
        "format": PRODUCT_FORMAT, "version": PRODUCT_VERSION,
        "name": os.path.splitext(os.path.basename(source))[0], "units": "mm", "parts": parts, "contacts": [], "obstructions": [],
        "geometry": {"source": os.path.basename(source),
                     "tessellation": {"linear_deflection": linear_deflection,
                                      "angular_deflection": angular_deflection},
                     "mesh_check": {"tolerance": mesh_tolerance, "parts": checks,
                                    "exact": [i for i, c in checks.items() if c["method"] == "exact"],
                                    "rules": {rule: [i for i, c in checks.items() if c["rule"] == rule]
                                              for rule in RULES}},
                     "warnings": warnings, **({"analysis": analysis} if analysis else {}),
                     **({"designer": designer} if designer else {})},
        **(extra or {}),
    }
    write_atomic(os.path.join(folder, PRODUCT_FILE), json.dumps(product, indent=1) + "\n")
    return product


def _stored_diagrams(intent, components, extra: dict) -> tuple[dict | None, str | None]:
    """The analysis' stored diagrams when they fit the exported ``components`` (with the intent's ``extra``
    keys), else None and the reason (None too when nothing is stored)."""
    from planner.errors import ProductFormatError
    from planner.product import product_from_dict

    diagrams = intent.diagrams if intent is not None else {}
    if not diagrams.get("parts"):
        return None, None
    ids, stored = sorted(c.id for c in components), sorted(diagrams["parts"])
    if ids != stored:
        missing, new = sorted(set(stored) - set(ids)), sorted(set(ids) - set(stored))
        differences = ([f"without {', '.join(missing)}"] if missing else []) + \
            ([f"with {', '.join(new)}"] if new else [])
        return None, f"they cover the components {stored}, this export has {ids} ({'; '.join(differences)})"
    objects = diagrams.get("objects") or {}
    for component in components:
        before = objects.get(component.id)
        if before is not None and sorted(before) != sorted(component.objects):
            return None, (f"component {component.id!r} was made of {sorted(before)} when they were detected, "
                          f"and is made of {sorted(component.objects)} now")
    try:
        product_from_dict({"format": PRODUCT_FORMAT, "version": PRODUCT_VERSION,
                           "parts": [{"id": i} for i in ids], "contacts": diagrams.get("contacts", []),
                           "obstructions": diagrams.get("obstructions", []), **extra}, "diagrams")
    except ProductFormatError as exc:
        return None, f"they are not valid: {exc.location}: {exc.problem}"
    return diagrams, None


def export_document(document, folder: str, source: str, groups=None, exclude=None, split_solids: bool = False,
                    linear_deflection: float = DEFAULT_LINEAR_DEFLECTION,
                    angular_deflection: float = DEFAULT_ANGULAR_DEFLECTION,
                    redetect: bool = False, progress=None, face_weight: int | None = None) -> tuple[dict, "Intent | None"]:
    """Export an open ``document`` with its stored designer intent into ``folder``.

    ``groups``, ``exclude`` and ``split_solids`` add to what the document's APLAN analysis says. The
    analysis' stored diagrams go into ``product.json`` when they cover exactly the exported components
    (same ids, made of the same objects) and ``redetect`` is False; when they do not fit, a warning in
    ``geometry.warnings`` says why, and the product has no contacts yet (a geometry engine fills them in).
    ``face_weight``: the OCCT bound of the fallback rules (:func:`fallback_mesh`; None: the analysis'
    ``OcctFaceWeight``, else the default).
    Returns the product (as written) and the intent (None without an analysis). Raises
    :class:`~freecad_aplan.intent.IntentError` when the intent names components the document does not have.
    """
    from planner.errors import ProductFormatError
    from planner.product import product_from_dict

    from .diagrams import stored_analysis
    from .intent import designer_record, find_analysis, product_intent, read_intent

    analysis = find_analysis(document)
    intent = read_intent(analysis) if analysis is not None else None
    if intent is not None:
        groups = {**intent.groups, **(groups or {})}
        exclude = list(intent.excluded) + [e for e in exclude or () if e not in intent.excluded]
        split_solids = split_solids or intent.split_solids
    result = read_components(document, groups, exclude, split_solids)
    extra = product_intent(intent) if intent is not None else {}
    if intent is not None:  # the designer's fastener tags and subassembly tree (freecad_aplan.structure)
        labels = {o.Name: o.Label for o in document.Objects}
        extra.update(structure_entries(intent, {c.id: list(c.objects) for c in result.components}, labels,
                                       result.warnings))
    ids = {c.id for c in result.components}
    if extra:
        try:  # check the intent against the components before writing anything
            product_from_dict({"format": PRODUCT_FORMAT, "version": PRODUCT_VERSION, "contacts": [],
                               "parts": [{"id": i} for i in sorted(ids)], **extra}, "product")
        except ProductFormatError as exc:
            from .intent import IntentError

            raise IntentError(f"{source}: the APLAN analysis {analysis.Label!r} does not fit the components "
                              f"{sorted(ids)}: {exc.location}: {exc.problem}; fix the constraint or tag in "
                              "the APLAN workbench") from None
    recorded = None
    if not redetect:
        diagrams, reason = _stored_diagrams(intent, result.components, extra)
        if diagrams is not None:
            extra["contacts"], extra["obstructions"] = diagrams.get("contacts", []), diagrams.get("obstructions", [])
            recorded = stored_analysis(diagrams)
        elif reason is not None:
            result.warnings.append(f"the diagrams stored in {analysis.Label!r} were not used: {reason}; contacts "
                                   "and obstructions are detected again (run APLAN > Detect contacts and "
                                   "obstructions to store new ones)")
    if "subassemblies" not in extra:  # the document's structure (App::Part containers, groups)
        tools = {t["id"] for t in extra.get("tools", [])}
        structure = document_subassemblies(document, result.components, tools)
        if structure:
            extra["subassemblies"] = structure
    else:
        compounds = [o.Label for o in document.Objects if is_grouping(o)]
        if compounds:
            result.warnings.append(f"the compounds {', '.join(compounds)} are not used as subassemblies: the APLAN "
                                   "analysis holds a subassembly tree of its own (empty it to use the document's)")
    extra["x-freecad-objects"] = {c.id: list(c.objects) for c in result.components}
    product = export_components(result.components, folder, source, result.warnings, linear_deflection,
                                angular_deflection, extra, recorded,
                                designer=designer_record(intent) if intent is not None else None, progress=progress,
                                face_weight=face_weight or (intent.occt_face_weight if intent is not None
                                                            else OCCT_FACE_WEIGHT))
    return product, intent


def export_model(model: str, folder: str, groups=None, exclude=None, split_solids: bool = False,
                 linear_deflection: float = DEFAULT_LINEAR_DEFLECTION,
                 angular_deflection: float = DEFAULT_ANGULAR_DEFLECTION,
                 redetect: bool = False, progress=None, face_weight: int | None = None) -> tuple[dict, "Intent | None"]:
    """Open ``model`` (.FCStd or STEP) and export it with its stored intent into ``folder`` (see
    :func:`export_document`); returns the product and the intent."""
    already_open = {d.FileName for d in FreeCAD.listDocuments().values()}
    document = open_model(model)
    try:
        return export_document(document, folder, model, groups, exclude, split_solids, linear_deflection,
                               angular_deflection, redetect, progress, face_weight)
    finally:
        if document.FileName not in already_open or not document.FileName:
            FreeCAD.closeDocument(document.Name)
