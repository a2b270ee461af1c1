"""Contacts, interferences and obstruction diagrams from exact B-rep shapes (the OCCT geometry engine).

Runs inside FreeCAD (``Part``). It computes what :mod:`planner.geometry` computes from meshes, with the same
definitions (see that module), on the exact shapes:

- *contact*: the two parts' surfaces are closer than ``contact`` (``distToShape``), or they overlap (one
  inside the other, a press fit, a small modelling interference such as the pen's button, 0.06 mm^3);
- *interference*: the common volume of the two parts (``common``) exceeds ``interference`` cubic units;
- *obstruction* along ``d``: part ``x``, moved along ``+d`` without limit, would collide with part ``y``.

Method
------
Obstruction is tested continuously, on exact sweeps: ``x`` swept along ``+d`` to beyond the scene is the
union of the prisms (extrusions along ``d``) of its faces that face backwards (outward normal . d < 0), since
every point of the sweep lies ahead of such a face on a line parallel to ``d``. ``x`` is *blocked* by ``y``
when one prism ``P`` takes more than ``depth ** 3`` of ``y`` outside ``x``: ``volume(P & y) - volume(P & x & y)``.
What the parts already share does not count, and surfaces that touch or slide along each other (a peg in
its hole, moving along its axis) have a common volume of zero.

OCCT needs some help to get there:

- A prism is valid only for a face that projects one-to-one along ``d``. Faces whose normal turns across
  ``d`` (a cylinder seen side on, a sphere) are split along their silhouettes, exactly: by planes through
  the axis of cylinders and cones, through the centre of spheres, across or through the axis of tori and
  surfaces of revolution, and by cylinders around the axis where a profile's normal is along it. A piece
  that still folds (B-splines, a torus in a general position), or whose prism OCCT cannot build, is swept as
  the polyhedral prism of its tessellation (within ``contact / 2``), and the warnings say so. A piece that
  cannot be swept that way either (the prism of its triangles comes out with the wrong volume: a torus as one
  closed B-spline, whose patch overlaps itself along ``d``, or such a sphere) leaves a hole in the sweep, so a pair it misses is not shown free: every candidate pair of that
  sweep is undecided (the mesh engine's answer stands, :mod:`freecad_aplan.hybrid`).
- Planar sides of prisms that OCCT makes as extrusion surfaces are rebuilt as planes, and faces whose
  normal or axis is within 1e-6 rad of ``d`` (models assembled by constraints are 1e-8 rad off) are swept
  along that normal or axis: booleans do not match an extrusion surface with a coplanar plane or a coaxial
  cylinder, and return wrong volumes, or never finish.
- Booleans run on copies (OCCT raises its arguments' tolerances in place) and fail quietly now and then
  (an empty common for a door moving onto its screws). The prisms are tested one by one rather than fused;
  a positive volume is evidence, while an empty one must be confirmed by the prism built both ways (along
  the face's axis and along ``d``) with two fuzzy values, and by rays from the face through ``y`` (point
  classification, no boolean). A pair OCCT cannot decide counts as blocked, with a warning.

Broad phase: contact pairs whose bounding boxes are farther apart than ``contact`` are never measured; for
the obstruction along ``d``, ``y`` must overlap ``x``'s box in the two directions across ``d`` by more than
``contact`` (narrower contacts only graze) and reach more than ``depth`` beyond the start of ``x`` along
``d``; a prism is only tested against ``y`` when their boxes overlap. Prisms are built once per part and
direction, only when a candidate needs them.

Directions: the three axes, then any unit vectors given (``directions``: the designer's and the candidate
directions the mesh engine finds on the bundle's meshes, :func:`planner.geometry.mesh_engine.candidate_directions`),
tested the same way. Along a direction other than an axis the boxes above are seen in a frame ``(u, v, d)``:
the box of a box's eight corners (:mod:`.frames`), which holds the box, so the culling never drops a pair that
could block; along an axis it is the box itself.

Modules: :mod:`.analyze` (the entry points), :mod:`.contacts`, :mod:`.obstructions` (the sweeps' verdicts
and their cross-checks), :mod:`.prisms` (the sweeps), :mod:`.silhouettes` (splitting faces so that they can
be swept), :mod:`.frames` (boxes seen along a direction), :mod:`.solids` (boxes, booleans, point
classification).
"""
from __future__ import annotations

from .analyze import BrepError, analyze_bundle_breps, analyze_shapes
from .obstructions import AXES

__all__ = ["analyze_shapes", "analyze_bundle_breps", "BrepError", "AXES"]
