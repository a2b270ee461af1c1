"""The mesh engine's data: a part's closed triangle mesh (:class:`PartMesh`), what an engine reports
(:class:`GeometryReport`), the axes, and the part as a manifold solid (``manifold3d``)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import GeometryError

__all__ = ["PartMesh", "GeometryReport", "AXES", "touching_pairs"]

AXES = ("+X", "+Y", "+Z")
_AXIS_VECTORS = np.eye(3)


@dataclass(frozen=True)
class PartMesh:
    """A closed triangle mesh of one part: ``vertices`` (v, 3) float64, ``faces`` (f, 3) int64."""

    id: str
    vertices: np.ndarray
    faces: np.ndarray

    @property
    def triangles(self) -> np.ndarray:
        """(f, 3, 3) float64."""
        return self.vertices[self.faces]


@dataclass(frozen=True)
class GeometryReport:
    """What an engine found: contacts, interferences (a, b, volume) and obstructions per direction (the
    positive axes, named ``+X`` ..., and any other direction by its name, with its unit vector in
    ``directions``)."""

    engine: str
    parts: tuple[str, ...]
    contacts: tuple[tuple[str, str], ...]
    interferences: tuple[tuple[str, str, float], ...]
    obstructions: dict[str, tuple[tuple[str, str], ...]]
    tolerances: dict = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    seconds: float = 0.0
    directions: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    gaps: dict | None = None  # when the contacts fall apart: planner.geometry.clearances.gap_record

    def as_dict(self) -> dict:
        return {"engine": self.engine, "parts": len(self.parts), "contacts": [list(c) for c in self.contacts],
                "interferences": [{"parts": [a, b], "volume": round(v, 6)} for a, b, v in self.interferences],
                "obstructions": {d: [list(p) for p in pairs] for d, pairs in self.obstructions.items()},
                "tolerances": self.tolerances, "warnings": list(self.warnings), "seconds": round(self.seconds, 3),
                **({"directions": {k: list(v) for k, v in self.directions.items()}} if self.directions else {}),
                **({"gaps": self.gaps} if self.gaps is not None else {})}


# Coordinates farther from the origin than this lose their millimetres in the engines' single precision.
_FARTHEST = 1e7


def _manifold(part: PartMesh):
    try:
        import manifold3d
    except ImportError:  # FreeCAD's Python, installed by the Addon Manager, may lack it: not on its allowed list
        raise GeometryError("the mesh engine needs the Python package manifold3d: pip install manifold3d, or use "
                            "the occt engine (aplan export-freecad --engine occt; in FreeCAD, Engine = occt)") from None

    if not np.isfinite(part.vertices).all():
        raise GeometryError(f"part {part.id!r}: its mesh has coordinates that are not finite numbers (NaN or "
                            "infinity); re-export it from the CAD model")
    farthest = float(np.abs(part.vertices).max()) if part.vertices.size else 0.0
    if farthest > _FARTHEST:
        raise GeometryError(f"part {part.id!r}: its mesh reaches {farthest:.3g} model units from the origin, beyond "
                            f"{_FARTHEST:g} where single precision loses the tolerances; move the product near the "
                            "origin or check its units")
    mesh = manifold3d.Mesh(vert_properties=np.ascontiguousarray(part.vertices, dtype=np.float32),
                           tri_verts=np.ascontiguousarray(part.faces, dtype=np.uint32))
    solid = manifold3d.Manifold(mesh)
    if solid.status() != manifold3d.Error.NoError:
        raise GeometryError(f"part {part.id!r}: its mesh is not a closed, consistently oriented surface "
                            f"({solid.status().name}); re-export it or repair the solid in the CAD model")
    if solid.volume() <= 0:
        raise GeometryError(f"part {part.id!r}: its mesh encloses no volume ({solid.volume():g}); "
                            "check the part in the CAD model")
    return solid


def touching_pairs(parts: list[PartMesh], pairs, tolerance: float) -> list[tuple[str, str]]:
    """The pairs of ``pairs`` (part ids) whose meshes are closer than ``tolerance`` or overlap: the contact
    test of :func:`analyze_meshes` on those pairs only. Cost: one manifold per part named, one gap query per pair."""
    index = {p.id: p for p in parts}
    solids: dict[str, object] = {}
    found = []
    for a, b in pairs:
        for name in (a, b):
            if name not in solids:
                solids[name] = _manifold(index[name])
        if solids[a].min_gap(solids[b], tolerance * 2 + 1e-9) <= tolerance:
            found.append((a, b))
    return found
