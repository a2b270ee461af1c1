"""How much work one OCCT call on a shape may take, estimated before any call: the weight of its faces.

Definition: a face's *weight* is 1 for a surface without poles (plane, cylinder, cone, sphere, torus,
extrusion or revolution of an analytic curve), and ``poles_u * poles_v * (degree_u + 1) * (degree_v + 1)``
for a B-spline or Bézier surface: the poles that meshing, distances and booleans visit, times the work of
one evaluation. A shape's weight is that of its heaviest face (the calls that cannot be interrupted work
face by face; a shape of many light faces is bounded by the pair's steps and seconds between calls).

Measured on this machine: a helical spring swept in FreeCAD (Part::Sweep of a circle along a Part::Helix:
one B-spline face of 6 x 130 poles of degree 6 x 9, weight 54,600) takes 10-15 CPU s to tessellate at 0.05
(371,000 triangles) and its polyhedral sweep 11 GB; the diaphragm pump's heaviest face (weight 3,472)
0.03 s (1,992 triangles). A pair with a part over :data:`~planner.defaults.OCCT_FACE_WEIGHT` is not given
to OCCT at all (:class:`~.budget.PairClock`).

Cost: O(faces) attribute reads, no geometry computed. Does not import FreeCAD (works on any object with
the attributes of ``Part.Face`` and its ``Surface``).
"""
from __future__ import annotations

__all__ = ["face_weight", "shape_weight", "describe_face"]


def face_weight(face) -> int:
    """The weight of ``face`` (module docstring): 1 without poles, else poles times (degree + 1) squared."""
    surface = face.Surface
    poles = int(getattr(surface, "NbUPoles", 0) or 0) * int(getattr(surface, "NbVPoles", 0) or 0)
    if poles <= 0:
        return 1
    return poles * (int(getattr(surface, "UDegree", 0) or 0) + 1) * (int(getattr(surface, "VDegree", 0) or 0) + 1)


def shape_weight(shape) -> tuple[int, int]:
    """(weight, index of the heaviest face) of ``shape``: the largest :func:`face_weight` of its faces (1 and
    -1 for a shape without faces)."""
    best, index = 1, -1
    for k, face in enumerate(shape.Faces):
        weight = face_weight(face)
        if weight > best:
            best, index = weight, k
    return best, index


def describe_face(face) -> str:
    """``'a B-spline face of 6 x 130 poles of degree 6 x 9'`` (for the messages)."""
    surface = face.Surface
    kind = {"BSplineSurface": "B-spline", "BezierSurface": "Bezier"}.get(type(surface).__name__,
                                                                       type(surface).__name__)
    return (f"a {kind} face of {getattr(surface, 'NbUPoles', 0)} x {getattr(surface, 'NbVPoles', 0)} poles of "
            f"degree {getattr(surface, 'UDegree', 0)} x {getattr(surface, 'VDegree', 0)}")
