"""Export a FreeCAD document (or STEP file) as a product bundle: product file + one mesh and B-rep per part.

Runs inside FreeCAD (the GUI, or FreeCADCmd through ``freecad_aplan.batch``). A bundle folder holds:

- ``product.json``: the parts (id, label, mesh, brep, volume, material), no contacts yet (the geometry
  engines fill them in), and ``geometry``: the source model and the tessellation tolerances;
- ``meshes/<id>.stl``: binary STL of each part in global coordinates (model units);
- ``breps/<id>.brep``: the exact OCCT shape of each part, for the OCCT engine.

The document is never modified: shapes are copies, and documents this module opened are closed again.
"""
from __future__ import annotations

import json
import os
import re

import FreeCAD
import MeshPart

from .document import open_model, read_components

__all__ = ["export_components", "export_model", "DEFAULT_LINEAR_DEFLECTION", "DEFAULT_ANGULAR_DEFLECTION"]

DEFAULT_LINEAR_DEFLECTION = 0.05  # model units (mm): the largest distance between mesh and surface
DEFAULT_ANGULAR_DEFLECTION = 0.25  # radians between neighbouring facet normals on curved faces


def _file_name(part_id: str, used: set[str]) -> str:
    base = re.sub(r"[^A-Za-z0-9._-]+", "_", part_id).strip("._") or "part"
    name, k = base, 1
    while name.lower() in used:
        k += 1
        name = f"{base}_{k}"
    used.add(name.lower())
    return name


def export_components(components, folder: str, source: str, warnings: list[str],
                      linear_deflection: float = DEFAULT_LINEAR_DEFLECTION,
                      angular_deflection: float = DEFAULT_ANGULAR_DEFLECTION) -> dict:
    """Write meshes, B-reps and ``product.json`` for ``components`` into ``folder`` (which must exist)."""
    os.makedirs(os.path.join(folder, "meshes"), exist_ok=True)
    os.makedirs(os.path.join(folder, "breps"), exist_ok=True)
    used: set[str] = set()
    parts = []
    for component in components:
        name = _file_name(component.id, used)
        mesh = MeshPart.meshFromShape(Shape=component.shape, LinearDeflection=linear_deflection,
                                      AngularDeflection=angular_deflection, Relative=False)
        if mesh.CountFacets == 0:
            raise ValueError(f"part {component.id!r}: tessellation produced no triangles")
        if not mesh.isSolid():
            # Points on face boundaries come once per face: merge them first.
            mesh.removeDuplicatedPoints()
        if not mesh.isSolid():
            # OCCT's mesher can leave cracks where neighbouring faces are discretised differently.
            mesh.fillupHoles(1000, 1)
            warnings.append(f"{component.id}: the tessellation had cracks, filled "
                            f"({'closed now' if mesh.isSolid() else 'still open'})")
        mesh.write(os.path.join(folder, "meshes", name + ".stl"))
        component.shape.exportBrep(os.path.join(folder, "breps", name + ".brep"))
        part = {"id": component.id, "label": component.label, "mesh": f"meshes/{name}.stl",
                "brep": f"breps/{name}.brep", "volume": round(component.shape.Volume, 6)}
        if component.material:
            part["material"] = component.material
        parts.append(part)
    product = {
        "format": "aplan-product", "version": 1, "name": os.path.splitext(os.path.basename(source))[0],
        "units": "mm", "parts": parts, "contacts": [], "obstructions": [],
        "geometry": {"source": os.path.basename(source),
                     "tessellation": {"linear_deflection": linear_deflection,
                                      "angular_deflection": angular_deflection},
                     "warnings": warnings},
    }
    with open(os.path.join(folder, "product.json"), "w", encoding="utf-8") as handle:
        json.dump(product, handle, indent=1)
        handle.write("\n")
    return product


def export_model(model: str, folder: str, groups=None, exclude=None, split_solids: bool = False,
                 linear_deflection: float = DEFAULT_LINEAR_DEFLECTION,
                 angular_deflection: float = DEFAULT_ANGULAR_DEFLECTION) -> dict:
    """Open ``model`` (.FCStd or STEP), read its components and export them into ``folder``."""
    already_open = {d.FileName for d in FreeCAD.listDocuments().values()}
    document = open_model(model)
    try:
        result = read_components(document, groups, exclude, split_solids)
        return export_components(result.components, folder, model, result.warnings,
                                 linear_deflection, angular_deflection)
    finally:
        if document.FileName not in already_open or not document.FileName:
            FreeCAD.closeDocument(document.Name)
