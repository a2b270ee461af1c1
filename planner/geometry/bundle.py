"""Product bundles: a folder holding ``product.json`` and the part meshes (and B-reps) it names.

``aplan export-freecad`` writes bundles from FreeCAD documents; the geometry engines read the meshes (or
B-reps) of a bundle and fill in the connection and obstruction diagrams (:func:`analyze_product`).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Callable

import numpy as np

from ..defaults import PRODUCT_FILE
from ..errors import GeometryError
from ..interrupts import held_interrupts
from ..product import AXIS_DIRECTIONS, Direction, Obstruction, Product, load_product, save_product
from ..product.designer import designer_geometry, release_marked
from .clearances import analyze_with_clearances
from .mesh_engine import AXES, GeometryReport, PartMesh, analyze_meshes
from .tolerances import Tolerances

__all__ = ["PRODUCT_FILE", "bundle_product_path", "load_bundle", "is_analysed", "load_part_meshes",
           "analyze_product", "analyse_bundle", "apply_report", "ENGINES"]


def bundle_product_path(folder: str | Path) -> Path:
    """The product file of a bundle folder."""
    return Path(folder) / PRODUCT_FILE


def is_analysed(product: Product) -> bool:
    """True when a geometry engine has filled in the product's contacts and obstructions."""
    return "analysis" in product.geometry


def _base(product: Product) -> Path:
    return Path(product.source).parent if product.source != "<memory>" else Path(".")


def load_part_meshes(product: Product) -> list[PartMesh]:
    """Read the mesh of every part (paths relative to the product file); errors name the part and file.
    trimesh runs with interrupts held (:func:`planner.interrupts.held_interrupts`): it guards its optional
    imports and some computations with ``except BaseException``, which would swallow a Ctrl-C or a SIGTERM."""
    with held_interrupts():
        import trimesh

    meshes = []
    for part in product.parts:
        if not part.mesh:
            raise GeometryError(f"{product.source}: part {part.id!r} has no mesh; export the product with meshes "
                                "(aplan export-freecad) or add a 'mesh' path to the part")
        path = _base(product) / part.mesh
        if not path.is_file():
            raise GeometryError(f"{product.source}: part {part.id!r}: mesh file {path} does not exist")
        try:
            with held_interrupts():
                mesh = trimesh.load(path, force="mesh", process=False)  # processing would drop NaN vertices silently
        except Exception as exc:  # trimesh raises many types for corrupt files
            # an unreadable header sends trimesh looking for optional modules (charset_normalizer): not the cause
            why = "not a mesh file it can read (a damaged header?)" if isinstance(exc, ImportError) else exc
            raise GeometryError(f"{product.source}: part {part.id!r}: cannot read mesh {path}: {why}; re-export "
                                "the part (STL, OBJ, PLY)") from None
        if len(mesh.faces) == 0:
            raise GeometryError(f"{product.source}: part {part.id!r}: mesh {path} has no triangles")
        if not np.isfinite(np.asarray(mesh.vertices)).all():
            raise GeometryError(f"{product.source}: part {part.id!r}: mesh {path} has coordinates that are not "
                                "finite numbers (NaN or infinity); re-export the part")
        with held_interrupts():
            mesh.process()  # merge the vertices the facets share, as trimesh.load does by default
        meshes.append(PartMesh(part.id, np.asarray(mesh.vertices, dtype=np.float64),
                               np.asarray(mesh.faces, dtype=np.int64)))
    return meshes


def _mesh_engine(product: Product, tolerances: Tolerances) -> GeometryReport:
    meshes = load_part_meshes(product)
    try:
        return analyze_meshes(meshes, tolerances)
    except GeometryError as exc:  # the engine names the part; the user needs the file too
        if type(exc) is not GeometryError or str(exc).startswith(str(product.source)):
            raise
        raise GeometryError(f"{product.source}: {exc}") from None


ENGINES: dict[str, Callable[[Product, Tolerances], GeometryReport]] = {"mesh": _mesh_engine}


def analyze_product(product: Product, engine: str = "mesh", tolerances: Tolerances = Tolerances(),
                    engines: dict[str, Callable] | None = None) -> GeometryReport:
    """Run a geometry engine on the product's meshes (``mesh``) or B-reps (``occt``, from the FreeCAD side).
    ``engines``: engines by name besides the plugins' (a Python where no entry point is installed, such as
    FreeCADCmd's, passes the FreeCAD side's here).

    ``tolerances.contact`` may be ``"auto"``; the gaps between the groups are recorded when the contacts fall
    apart, and a tolerance that makes too much touch is warned about
    (:func:`~planner.geometry.clearances.analyze_with_clearances`). The product's designer directions
    (``geometry.designer``) are tested besides the axes and the candidate directions (mesh engine)."""
    from ..plugins import registry

    engines = {**ENGINES, **registry().engines, **(engines or {})}
    if engine not in engines:
        raise GeometryError(f"unknown geometry engine {engine!r}; available: {', '.join(sorted(engines))}")
    designer = designer_geometry(product).directions
    if designer:  # the designer's directions (geometry.designer) are tested at every detection
        tolerances = replace(tolerances, designer_directions=tuple(d.vector for d in designer))
    return analyze_with_clearances(lambda chosen: engines[engine](product, chosen), tolerances,
                                   lambda: load_part_meshes(product))


def analyse_bundle(product: Product, path: str | Path, engine: str = "mesh", tolerances: Tolerances = Tolerances(),
                   report: GeometryReport | None = None,
                   then: Callable[[Product], Product] | None = None,
                   engines: dict[str, Callable] | None = None) -> tuple[Product, GeometryReport]:
    """Analyse a bundle: the one way its diagrams are found and written, for the command line (``aplan
    analyze``), the workbench and the FreeCAD export. ``report``: an engine's answer found elsewhere (the
    workbench's OCCT run inside FreeCAD), else :func:`analyze_product` with ``engine``, ``tolerances`` and
    ``engines``;
    applied to ``product`` (:func:`apply_report`), then to ``then`` if given (what a caller adds while the
    meshes are at hand, e.g. the workbench's interlock proposals), and the product written to ``path``
    atomically, once. Returns the analysed product and the report. Cost: the engine's."""
    report = analyze_product(product, engine, tolerances, engines) if report is None else report
    analysed = apply_report(product, report)
    if then is not None:
        analysed = then(analysed)
    save_product(analysed, path)
    return analysed, report


def apply_report(product: Product, report: GeometryReport) -> Product:
    """A copy of ``product`` with the report's contacts and obstruction diagrams (+X/+Y/+Z, then any other
    direction the engine tested, with its vector in ``report.directions``), and the analysis recorded under
    ``geometry.analysis`` (``diagrams: "engine"``: found by a geometry engine; ``tolerances`` with
    ``contact_auto`` when the contact tolerance was chosen; ``gaps`` when the contacts fall apart).
    Technical constraints and designer tags are kept; the designer's not-blocking marks are applied
    (:func:`planner.product.designer.release_marked`: the pairs they release are recorded under
    ``geometry.analysis.designer``)."""
    if set(report.parts) != set(product.part_ids):
        raise GeometryError(f"{product.source}: the analysed parts {sorted(report.parts)} are not the product's "
                            f"parts {sorted(product.part_ids)}")
    obstructions = tuple(Obstruction(Direction(axis, AXIS_DIRECTIONS[axis]), tuple(report.obstructions[axis]))
                         for axis in AXES)
    obstructions += tuple(Obstruction(Direction(name, tuple(report.directions[name])), tuple(pairs))
                          for name, pairs in report.obstructions.items() if name not in AXES)
    summary = report.as_dict()
    analysis = {"diagrams": "engine", "engine": report.engine, "tolerances": summary["tolerances"],
                "interferences": summary["interferences"], "warnings": summary["warnings"],
                "seconds": summary["seconds"], **({"gaps": report.gaps} if report.gaps is not None else {})}
    tested = {o.direction.name for o in obstructions}
    untested = [d.name for d in designer_geometry(product).directions if d.name not in tested]
    if untested:
        analysis["warnings"] = summary["warnings"] + [
            f"the {report.engine} engine does not test the designer directions {', '.join(untested)}; use the "
            "mesh engine for them"]
    geometry = {**product.geometry, "analysis": analysis}
    # The designer's not-blocking marks, applied after every detection (they survive re-detection).
    return release_marked(replace(product, contacts=tuple(report.contacts), obstructions=obstructions,
                                  geometry=geometry))


def load_bundle(folder: str | Path) -> Product:
    """The product of a bundle folder."""
    return load_product(bundle_product_path(folder))
