"""The tolerances of the geometry engines (the mesh engine here, the OCCT engine in FreeCAD): how close two
surfaces must be to touch, how large an overlap must be to be reported or to block a motion, and the raster
of the projection test. Their defaults are in :mod:`planner.defaults`."""
from __future__ import annotations

from dataclasses import dataclass

from ..defaults import BLOCKING_DEPTH, CONTACT_TOLERANCE, INTERFERENCE_VOLUME, OCCT_PAIR_BUDGET, RASTER_RESOLUTION
from ..errors import GeometryError

__all__ = ["Tolerances"]


@dataclass(frozen=True)
class Tolerances:
    """Tolerances of the geometry analysis, in model units (lengths) and cubic units (volumes).

    ``contact``: surfaces closer than this touch. ``interference``: overlap volumes above this are reported.
    ``depth``: along the motion, overlaps shallower than this do not block (modelling interferences).
    ``resolution``: pixels across the largest dimension of the product for the projection test.
    ``grazing``: pixels next to a part's outline that are ignored (at least 1).
    ``pair_budget``: OCCT engine: seconds of work per pair of parts before the pair is reported undecided.
    """

    contact: float = CONTACT_TOLERANCE
    interference: float = INTERFERENCE_VOLUME
    depth: float = BLOCKING_DEPTH
    resolution: int = RASTER_RESOLUTION
    grazing: int = 1
    pair_budget: float = OCCT_PAIR_BUDGET

    def __post_init__(self) -> None:
        for name in ("contact", "interference", "depth", "pair_budget"):
            if not getattr(self, name) >= 0:
                raise GeometryError(f"tolerance {name} must be >= 0, got {getattr(self, name)!r}")
        if self.resolution < 16:
            raise GeometryError(f"resolution must be at least 16 pixels, got {self.resolution}")
        if self.grazing < 1:
            raise GeometryError(f"grazing must be at least 1 pixel, got {self.grazing}")
