"""The FreeCAD side's additions to the ``aplan`` command line (entry point ``aplan.plugins``).

- ``aplan export-freecad MODEL -o BUNDLE``: FreeCADCmd writes the meshes and B-reps of a ``.FCStd`` or STEP
  model; the diagrams stored in the document's APLAN analysis (as the designer edited them) are used when
  they cover exactly the exported components, else (or with ``--redetect``) a geometry engine fills in
  contacts and obstruction diagrams; the bundle appears only when everything succeeded.
- ``aplan stats MODEL.FCStd`` (and every command taking PRODUCT): the same export into a temporary folder.
- ``aplan analyze --engine occt``: the exact engine, run in FreeCADCmd on the bundle's B-reps (at most
  ``--pair-budget`` seconds per pair of parts; its progress lines go to standard error).
- :func:`geometry_engines`: the engines registered here, which the workbench's detection job runs too (one
  path for both front ends, :func:`freecad_aplan.workflow.analyze_bundle`).

Nothing here imports FreeCAD: FreeCAD runs as a separate program (:mod:`freecad_aplan.runner`), or, when this
runs inside FreeCADCmd already (the workbench's job without a Python for the mesh engine), in this process.
"""
from __future__ import annotations

import argparse
import atexit
import logging
import shutil
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

from planner.defaults import ANGULAR_DEFLECTION, LINEAR_DEFLECTION, LINEAR_DEFLECTION_MIN
from planner.errors import PlannerError
from planner.files import building_folder
from planner.geometry import GeometryReport, Tolerances
from planner.geometry.bundle import PRODUCT_FILE, analyse_bundle, load_bundle
from planner.product import Product, save_product
from planner.product.designer import add_directions

from .archive import SKIP_BY_EXPORT, SKIP_OPTION, check_document
from .hybrid import fallback_parts, mesh_then_occt, pair_fallbacks, to_stderr
from .runner import FreeCADError, find_freecadcmd, run_batch

__all__ = ["register", "export_bundle", "export_warnings", "occt_report", "occt_engine", "geometry_engines"]

MODEL_SUFFIXES = (".fcstd", ".step", ".stp")

log = logging.getLogger(__name__)


def export_bundle(model: str | Path, bundle: str | Path, engine: str | None = None,
                  tolerances: Tolerances | dict | None = None,
                  groups: dict[str, list[str]] | None = None, exclude: list[str] | None = None,
                  split_solids: bool = False, linear_deflection: float | None = None,
                  angular_deflection: float | None = None, freecadcmd: str | None = None,
                  overwrite: bool = False, redetect: bool = False, directions=(), skip_damaged: bool = False,
                  damaged_fix: str = SKIP_OPTION) -> Product:
    """Export ``model`` into the bundle folder ``bundle`` and analyse it with ``engine`` (or ``"none"``).

    The document's APLAN analysis (designer intent) chooses the components and adds its constraints and tags.
    Its stored connection and obstruction diagrams (as the designer edited them) are used as they are when
    they cover exactly the exported components, unless ``redetect``; ``geometry.analysis.diagrams`` of the
    product then says ``"stored in the document"`` (``", edited"`` after edits). Otherwise ``engine``
    detects them (``"engine"``; ``geometry.warnings`` says why stored diagrams were not used):
    ``engine=None`` and ``tolerances=None`` take the analysis' engine and tolerances (else mesh and the
    defaults); ``tolerances`` as a dict sets only the fields it names (``contact`` may be ``"auto"``, capped by
    ``contact_ceiling``: :func:`planner.geometry.clearances.analyze_with_clearances`; above the cap nothing is
    written).

    ``directions``: motion directions of the designer's (``X,Y,Z`` text or three numbers) added to the
    product's ``geometry.designer`` (with those the document's analysis holds) and tested at this and every
    later detection; they need a detection, so the diagrams are detected again (as with ``redetect``).

    A damaged ``.FCStd`` (a truncated archive, a corrupt Document.xml: :mod:`freecad_aplan.archive`) is an
    error naming each object that cannot be read, before FreeCAD runs; with ``skip_damaged``, a warning naming
    them, and the rest is exported (``damaged_fix``: how the error says to do that,
    :data:`~freecad_aplan.archive.SKIP_OPTION` or :data:`~freecad_aplan.archive.SKIP_BY_EXPORT`).

    The bundle is built in a temporary folder beside it and renamed into place at the end, so a failure or an
    interrupt leaves no partial bundle (and an existing one untouched). Returns the bundle's product.
    """
    model, bundle = Path(model).resolve(), Path(bundle).resolve()
    if not model.is_file():
        raise FreeCADError(f"{model}: no such file")
    if model.suffix.lower() not in MODEL_SUFFIXES:
        raise FreeCADError(f"{model}: unsupported model type {model.suffix!r}; use .FCStd, .step or .stp")
    if bundle.exists() and not overwrite:
        raise FreeCADError(f"{bundle} already exists; choose another folder or overwrite it (--force)")
    for warning in check_document(model, skip_damaged, damaged_fix):
        log.warning("%s", warning)
    bundle.parent.mkdir(parents=True, exist_ok=True)
    with building_folder(bundle) as work:  # renamed into place when everything succeeded (planner.files)
        arguments = {"model": str(model), "folder": str(work), "groups": groups or {}, "exclude": exclude or [],
                     "split_solids": split_solids, "redetect": redetect}
        if linear_deflection is not None:
            arguments["linear_deflection"] = linear_deflection
        if angular_deflection is not None:
            arguments["angular_deflection"] = angular_deflection
        given = tolerances if isinstance(tolerances, dict) else {} if tolerances is None else \
            {"face_weight": tolerances.face_weight}
        if given.get("face_weight") is not None:  # the export's fallback rules (a heavy part's ring or mesh)
            arguments["face_weight"] = given["face_weight"]
        answer = run_batch("export", arguments, freecadcmd)
        stored = answer.get("intent") or {}
        product = load_bundle(work)
        if directions:
            product, notes = add_directions(product, directions)
            product = replace(product, geometry={**product.geometry,
                                                 "warnings": list(product.geometry.get("warnings", [])) + notes})
            save_product(product, work / PRODUCT_FILE)
        engine = engine or stored.get("engine", "mesh")
        if not isinstance(tolerances, Tolerances):
            chosen = {k: stored[k] for k in ("contact", "interference", "depth", "face_weight", "prism_triangles",
                                             "time_limit") if k in stored}
            tolerances = Tolerances(**{**chosen, **(tolerances or {})})
        if engine != "none" and (not answer.get("diagrams") or directions):  # no stored diagrams that fit: detect
            analyse_bundle(product, work / PRODUCT_FILE, engine, tolerances)
    return load_bundle(bundle)


def _load_model(path: Path, tolerances: Tolerances | None = None, groups: dict[str, list[str]] | None = None,
                exclude: list[str] | None = None, prepare=None) -> Product:
    """PRODUCT given as a CAD model: export it to a temporary bundle and analyse its meshes (with
    ``tolerances`` when given, e.g. ``contact="auto"``); ``groups`` and ``exclude`` as export-freecad's.

    The product's ``source`` is the model (what headers and messages name), its parts' meshes and B-reps are
    absolute paths into the bundle, which lives until the process ends (``geometry.x-temporary-bundle``: the
    occt engine reads its B-reps there). Every warning of the export (meshes that are unreliable, overlaps,
    objects left out, structure entries dropped) is logged, as ``aplan export-freecad`` prints them.
    ``prepare(product)``, when given, runs on the product as returned (the interlock rules read its meshes)."""
    folder = Path(tempfile.mkdtemp(prefix="aplan-"))
    atexit.register(shutil.rmtree, folder, True)
    bundle = folder / "bundle"
    product = export_bundle(path, bundle, tolerances=tolerances, groups=groups, exclude=exclude,
                            redetect=tolerances is not None, damaged_fix=SKIP_BY_EXPORT)
    for warning in export_warnings(product):
        log.warning("%s: %s", Path(path).name, warning)
    model = str(Path(path).resolve())
    parts = tuple(replace(p, mesh=str(bundle / p.mesh) if p.mesh else None,
                          brep=str(bundle / p.brep) if p.brep else None) for p in product.parts)
    product = replace(product, parts=parts, source=model,
                      geometry={**product.geometry, "x-temporary-bundle": str(bundle)})
    return product if prepare is None else prepare(product)


def export_warnings(product: Product) -> list[str]:
    """The warnings of a bundle's export and analysis (``geometry.warnings`` and ``geometry.analysis.warnings``),
    each once, in order: what ``aplan export-freecad`` prints."""
    geometry = product.geometry or {}
    found = list(geometry.get("warnings", [])) + list(geometry.get("analysis", {}).get("warnings", []))
    return list(dict.fromkeys(found))


def occt_engine(product: Product, tolerances: Tolerances, progress=to_stderr) -> GeometryReport:
    """The occt engine: the meshes settle the easy pairs, OCCT the others within ``tolerances``' budget (per
    pair, and ``time_limit`` s in all), and a relation OCCT leaves undecided keeps the mesh engine's answer
    (:mod:`freecad_aplan.hybrid`); a bundle whose meshes cannot be read, or a Python without the mesh engine
    (FreeCADCmd's), goes to OCCT whole, its undecided relations counted as blocking. Both are reported per
    pair (``tolerances["pairs"]``). ``progress(text)`` is told OCCT's progress lines (default: standard error)."""
    from planner.geometry.bundle import load_part_meshes

    if product.source == "<memory>":
        raise FreeCADError("the occt engine reads a bundle's B-rep files: give it a bundle folder")
    from .dependencies import MESH_ENGINE, installed

    try:
        meshes = load_part_meshes(product) if installed("trimesh") else None
    except PlannerError:
        meshes = None
    if meshes is not None and all(installed(m) for m in MESH_ENGINE):
        return mesh_then_occt(product, meshes, tolerances, "occt",
                              lambda arguments: _run_occt(product, arguments, progress), progress)
    data = _run_occt(product, {"contact": tolerances.contact, "interference": tolerances.interference,
                               "depth": tolerances.depth, "pair_budget": tolerances.pair_budget,
                               "pair_steps": tolerances.pair_steps, "time_limit": tolerances.time_limit,
                               "face_weight": tolerances.face_weight, "prism_triangles": tolerances.prism_triangles,
                               "directions": _occt_directions(tolerances, meshes)}, progress)
    return occt_report(product, data)


def _run_occt(product: Product, arguments: dict, progress=to_stderr) -> dict:
    # A CAD model's product names the model as its source; its B-reps are in the kept temporary bundle.
    folder = (product.geometry or {}).get("x-temporary-bundle") or Path(product.source).parent
    if "FreeCAD" in sys.modules:  # inside FreeCADCmd already (a workbench job): no second FreeCADCmd
        from .occt import analyze_bundle_breps

        return analyze_bundle_breps(str(folder), **arguments, progress=progress)
    return run_batch("analyze-occt", {"folder": str(folder), **arguments}, on_note=progress)


def _mesh_engine(product: Product, tolerances: Tolerances, progress=to_stderr) -> GeometryReport:
    """The mesh engine, with the pairs of parts that have no good mesh (rule ``exact`` or ``box``) decided by
    OCCT (:mod:`freecad_aplan.hybrid`; its progress lines told to ``progress``); without FreeCAD, or without
    B-reps, the meshes decide them, with a warning."""
    from planner.geometry.bundle import ENGINES, load_part_meshes

    fallback = fallback_parts(product)
    if not fallback:
        return ENGINES["mesh"](product, tolerances)
    meshes = load_part_meshes(product)
    missing = [p.id for p in product.parts if p.id in fallback and not getattr(p, "brep", None)]
    if product.source == "<memory>" or missing:
        report = ENGINES["mesh"](product, tolerances)
        return replace(report, warnings=(f"parts {', '.join(sorted(fallback))} have no mesh within the B-rep "
                                         "tolerance and no B-rep to decide their pairs on: the meshes decide "
                                         "them", *report.warnings))
    try:
        find_freecadcmd()
    except FreeCADError as exc:
        report = ENGINES["mesh"](product, tolerances)
        return replace(report, warnings=(f"parts {', '.join(sorted(fallback))} have no mesh within the B-rep "
                                         f"tolerance; OCCT would decide their pairs, but {exc}: the meshes "
                                         "decide them", *report.warnings))
    return mesh_then_occt(product, meshes, tolerances, "mesh",
                          lambda arguments: _run_occt(product, arguments, progress), progress)


def _occt_directions(tolerances: Tolerances, meshes) -> list[list[float]]:
    """The directions besides the axes the occt engine tests when OCCT decides every pair: the designer's,
    then the candidate directions the mesh engine would find on ``meshes`` (the bundle's, or None when they
    cannot be read here: the exact engine's job being the B-reps; :func:`planner.geometry.candidate_directions`,
    at most ``tolerances.directions``). Cost: one pass over the meshes' facets."""
    import numpy as np

    from planner.geometry.mesh_engine import candidate_directions

    designer = [np.asarray(v, dtype=float) for v in tolerances.designer_directions]
    found = candidate_directions(meshes, tolerances.directions, designer) \
        if tolerances.directions > 0 and meshes is not None else []
    return [[float(c) for c in v] for v in designer + list(found)]


def occt_report(product: Product, data: dict) -> GeometryReport:
    """The :class:`GeometryReport` of the OCCT engine's JSON answer (:func:`freecad_aplan.occt.analyze_bundle_breps`)
    on every pair, its undecided pairs counted as blocking and recorded as :mod:`freecad_aplan.hybrid` records
    them (``tolerances["pairs"]``)."""
    count = len(product.part_ids) * (len(product.part_ids) - 1) // 2
    pairs = {"mesh": 0, "occt": count - len(data.get("undecided", [])), "undecided": sorted(sorted(p) for p in data.get("undecided", [])),
             "timed_out": bool(data.get("timed_out")), "time_limit": data.get("time_limit"),
             "fallbacks": pair_fallbacks(data, "blocking")}
    return GeometryReport(
        engine="occt", parts=tuple(product.part_ids), contacts=tuple(tuple(c) for c in data["contacts"]),
        interferences=tuple((i["parts"][0], i["parts"][1], float(i["volume"])) for i in data["interferences"]),
        obstructions={axis: tuple(tuple(p) for p in pairs) for axis, pairs in data["obstructions"].items()},
        tolerances={**data.get("tolerances", {}), "pairs": pairs}, warnings=tuple(data.get("warnings", ())),
        seconds=float(data.get("seconds", 0.0)),
        directions={name: tuple(float(c) for c in v) for name, v in data.get("directions", {}).items()})


def _export_command(subparsers) -> None:
    from planner.cli import add_tolerance_options
    from planner.cli.options import number, parse_group

    parser = subparsers.add_parser(
        "export-freecad", help="export a FreeCAD document or STEP file as a product bundle (runs FreeCADCmd)",
        description="Write BUNDLE/product.json, BUNDLE/meshes/*.stl and BUNDLE/breps/*.brep from MODEL, then "
                    "compute contacts and obstruction diagrams. The document's APLAN analysis (designer intent) "
                    "chooses the components, adds its constraints and tags, and gives the engine and the "
                    "tolerances not set here; its stored diagrams (as edited in the workbench) are used when "
                    "they cover exactly the exported components (else detected again, with a warning saying "
                    "why). Nothing is written when it fails.")
    parser.add_argument("model", metavar="MODEL", help="a .FCStd document or a .step/.stp file")
    parser.add_argument("-o", "--output", required=True, metavar="BUNDLE", help="the bundle folder to create")
    parser.add_argument("--engine", choices=("mesh", "occt", "none"),
                        help="geometry engine for contacts and obstructions (default: the document's APLAN "
                             "analysis, else mesh; none: export only); used when the document has no stored "
                             "diagrams that fit, or with --redetect")
    parser.add_argument("--redetect", action="store_true",
                        help="detect contacts and obstructions again even when the document's APLAN analysis "
                             "stores diagrams (possibly edited by the designer) that fit the components")
    parser.add_argument("--group", action="append", type=parse_group, default=[], metavar="NAME=A,B,...",
                        help="make one component NAME of the objects A, B, ... (labels, or shell-style patterns "
                             "such as 'bolt_*'; repeatable)")
    parser.add_argument("--exclude", action="append", default=[], metavar="LABEL",
                        help="leave out the objects with this label, or matching this shell-style pattern "
                             "('wood_screw*': quote it), e.g. fasteners (repeatable); a pattern that matches no "
                             "object is an error")
    parser.add_argument("--split-solids", action="store_true",
                        help="one part per solid of objects holding several solids (STEP files of one product)")
    parser.add_argument("--linear-deflection", type=number(LINEAR_DEFLECTION_MIN), metavar="D",
                        help="tessellation: largest distance between mesh and surface, model units, at least "
                             f"{LINEAR_DEFLECTION_MIN:g} (default {LINEAR_DEFLECTION:g})")
    parser.add_argument("--angular-deflection", type=number(0.01, 3.14), metavar="A",
                        help="tessellation: largest angle between facet normals, radians, 0.01 to 3.14 (default "
                             f"{ANGULAR_DEFLECTION:g})")
    parser.add_argument("--freecadcmd", metavar="PATH", help="the FreeCADCmd executable (default: from PATH)")
    parser.add_argument("--force", action="store_true", help="replace BUNDLE if it exists")
    parser.add_argument("--skip-damaged", action="store_true",
                        help="export a damaged .FCStd (truncated, or with a corrupt Document.xml) without the "
                             "objects that cannot be read, naming them in a warning (default: an error)")
    add_tolerance_options(parser)
    # Tolerances not given on the command line come from the document's APLAN analysis.
    parser.set_defaults(contact=None, interference=None, depth=None, occt_face_weight=None, occt_prism_triangles=None,
                        time_limit=None)

    def run(args: argparse.Namespace) -> int:
        from planner.cli.geometry import contact_choice

        given = {k: getattr(args, k) for k in ("contact", "interference", "depth", "contact_ceiling")
                 if getattr(args, k) is not None}
        product = export_bundle(args.model, args.output, args.engine,
                                {**given, "resolution": args.resolution, "directions": args.directions,
                                 "pair_budget": args.pair_budget,
                                 **{k: v for k, v in (("face_weight", args.occt_face_weight),
                                                      ("prism_triangles", args.occt_prism_triangles),
                                                      ("time_limit", args.time_limit)) if v is not None}},
                                dict(args.group),
                                args.exclude, args.split_solids, args.linear_deflection, args.angular_deflection,
                                args.freecadcmd, args.force, args.redetect, args.direction, args.skip_damaged)
        source = product.geometry.get("analysis", {}).get("diagrams", "none detected")
        print(f"{args.output}: {len(product.parts)} parts, {len(product.contacts)} contacts (diagrams: {source})")
        choice = contact_choice(product.geometry.get("analysis", {}))
        if choice:
            print(f"  {choice}")
        if source.startswith("stored") and (args.engine or set(given) - {"contact_ceiling"}):
            print("  warning: --engine and the tolerances were not applied: the diagrams stored in the document "
                  "were used; add --redetect to detect them again")
        for warning in export_warnings(product):
            print(f"  warning: {warning}")
        return 0

    parser.set_defaults(run=run)


def geometry_engines(progress=None) -> dict:
    """The geometry engines of the FreeCAD side by name: ``occt`` (:func:`occt_engine`) and ``mesh`` (the
    planner's, plus OCCT for the parts without a good mesh), telling OCCT's progress lines to ``progress(text)``
    (None: standard error, as ``aplan analyze`` shows them). What the entry point registers, and what the
    workbench's job runs, its progress going to the job's notes (one path for both front ends)."""
    tell = progress or to_stderr
    return {"occt": lambda product, tolerances: occt_engine(product, tolerances, tell),
            "mesh": lambda product, tolerances: _mesh_engine(product, tolerances, tell)}


def register(registry) -> None:
    registry.commands.append(_export_command)
    for suffix in MODEL_SUFFIXES:
        registry.loaders[suffix] = _load_model
    registry.engines.update(geometry_engines())
