"""The tolerances of the geometry engines (the mesh engine here, the OCCT engine in FreeCAD): how close two
surfaces must be to touch, how large an overlap must be to be reported or to block a motion, and the raster
of the projection test. Their defaults are in :mod:`planner.defaults`."""
from __future__ import annotations

from dataclasses import dataclass

import math

from ..defaults import (BLOCKING_DEPTH, CANDIDATE_DIRECTIONS, CONTACT_TOLERANCE, INTERFERENCE_VOLUME, OCCT_FACE_WEIGHT,
                        OCCT_PAIR_BUDGET, OCCT_PAIR_STEPS, OCCT_PRISM_TRIANGLES, OCCT_TIME_LIMIT, RASTER_RESOLUTION)
from ..errors import GeometryError

__all__ = ["AUTO", "Tolerances"]

AUTO = "auto"  # Tolerances.contact: the smallest tolerance that connects the product (geometry.auto_contact)


@dataclass(frozen=True)
class Tolerances:
    """Tolerances of the geometry analysis, in model units (lengths) and cubic units (volumes).

    ``contact``: surfaces closer than this touch; ``"auto"``: the default, raised to the smallest tolerance that
    connects the product, up to ``contact_ceiling`` (None: a fraction of the product's size,
    :func:`planner.geometry.auto_contact.default_ceiling`); engines take a number, resolved by
    :func:`planner.geometry.analyze_product`. ``interference``: overlap volumes above this are reported.
    ``depth``: along the motion, overlaps shallower than this do not block (modelling interferences).
    ``resolution``: pixels across the largest dimension of the product for the projection test.
    ``grazing``: pixels next to a part's outline that are ignored (at least 1).
    ``directions``: at most this many motion directions besides the axes, found on the parts' geometry and
    tested like the axes (0: the axes only).
    ``designer_directions``: unit vectors the designer added (``geometry.designer`` of the product,
    :mod:`planner.product.designer`), tested like the axes besides the ``directions`` found on the geometry.
    ``pair_budget``: OCCT engine: seconds of work per pair of parts before the pair is reported undecided;
    ``pair_steps``: OCCT operations per pair likewise; ``time_limit``: seconds over all the pairs OCCT
    decides, after which the pairs left keep the mesh engine's answer (:mod:`freecad_aplan.hybrid`);
    ``face_weight``: no OCCT call on a part whose heaviest face weighs more (poles x (degree + 1) squared of a
    B-spline, :mod:`freecad_aplan.occt.complexity`): its pairs keep the mesh answer, and the export gives it a
    fallback mesh (:func:`freecad_aplan.export.fallback_mesh`); ``prism_triangles``: no face swept as more
    triangles than this (the sweep's pairs keep the mesh answer). Both whole numbers >= 1.
    """

    contact: float | str = CONTACT_TOLERANCE
    interference: float = INTERFERENCE_VOLUME
    depth: float = BLOCKING_DEPTH
    resolution: int = RASTER_RESOLUTION
    grazing: int = 1
    directions: int = CANDIDATE_DIRECTIONS
    pair_budget: float = OCCT_PAIR_BUDGET
    pair_steps: int = OCCT_PAIR_STEPS
    time_limit: float = OCCT_TIME_LIMIT
    face_weight: int = OCCT_FACE_WEIGHT
    prism_triangles: int = OCCT_PRISM_TRIANGLES
    contact_ceiling: float | None = None
    designer_directions: tuple[tuple[float, float, float], ...] = ()

    @property
    def auto(self) -> bool:
        """True when the contact tolerance is to be chosen (``contact="auto"``)."""
        return self.contact == AUTO

    def __post_init__(self) -> None:
        if isinstance(self.contact, str) and not self.auto:
            raise GeometryError(f"tolerance contact must be a number or {AUTO!r}, got {self.contact!r}")
        if self.contact_ceiling is not None and not self.contact_ceiling > 0:
            raise GeometryError(f"the contact ceiling must be > 0, got {self.contact_ceiling!r}")
        for name in (() if self.auto else ("contact",)) + ("interference", "depth", "pair_budget"):
            if not getattr(self, name) >= 0:
                raise GeometryError(f"tolerance {name} must be >= 0, got {getattr(self, name)!r}")
        if not (isinstance(self.time_limit, (int, float)) and self.time_limit > 0 and math.isfinite(self.time_limit)):
            raise GeometryError(f"the OCCT time limit must be a finite number of seconds above 0, got {self.time_limit!r}")
        for name in ("pair_steps", "face_weight", "prism_triangles"):
            value = getattr(self, name)
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= 1):
                raise GeometryError(f"{name} must be a whole number >= 1, got {value!r}")
        if self.resolution < 16:
            raise GeometryError(f"resolution must be at least 16 pixels, got {self.resolution}")
        if not (isinstance(self.directions, int) and 0 <= self.directions <= 64):
            raise GeometryError(f"directions must be a whole number from 0 to 64, got {self.directions!r}")
        for vector in self.designer_directions:
            if len(vector) != 3 or abs(sum(c * c for c in vector) - 1) > 1e-6:
                raise GeometryError(f"a designer direction must be a unit vector X,Y,Z, got {vector!r}")
        if self.grazing < 1:
            raise GeometryError(f"grazing must be at least 1 pixel, got {self.grazing}")
