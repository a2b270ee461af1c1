"""The geometry bundles: the engines' tolerances (``aplan analyze``, ``export-freecad``) and ``--contact`` for a
PRODUCT analysed again in memory."""
from __future__ import annotations

import argparse

from ...defaults import CONTACT_CEILING_FRACTION, RESOLUTION_LIMIT
from ...errors import PlannerError
from ...geometry.mesh_engine import Tolerances

from .values import (_direction_count, contact_tolerance, designer_direction, number, positive, positive_length,
                     positive_seconds)

__all__ = ["add_tolerance_options", "tolerances_from", "add_contact_options", "contact_tolerances_from"]


def add_tolerance_options(parser: argparse.ArgumentParser) -> None:
    """The geometry engines' tolerances as options (shared by analyze and export-freecad)."""
    d = Tolerances()
    group = parser.add_argument_group("geometry tolerances (model units)")
    group.add_argument("--contact", type=contact_tolerance, default=d.contact, metavar="T",
                       help=f"surfaces closer than this touch (default {d.contact:g}); auto: the smallest tolerance "
                            f"that connects the product (from the gaps between the part meshes, at least "
                            f"{d.contact:g}, at most --contact-ceiling), recorded in the product file")
    group.add_argument("--contact-ceiling", type=positive_length, default=None, metavar="T",
                       help=f"--contact auto refuses to go above this, naming the gap (default "
                            f"{100 * CONTACT_CEILING_FRACTION:g} %% of the diagonal of the product's bounding box)")
    group.add_argument("--interference", type=number(0), default=d.interference, metavar="V",
                       help=f"report overlaps above this volume (default {d.interference:g})")
    group.add_argument("--depth", type=number(0), default=d.depth, metavar="T",
                       help=f"overlaps shallower than this along the motion do not block (default {d.depth:g})")
    group.add_argument("--resolution", type=number(16, RESOLUTION_LIMIT, integer=True), default=d.resolution,
                       metavar="N", help=f"mesh engine: pixels across the product for the projection test, 16 to "
                                         f"{RESOLUTION_LIMIT:,} (default {d.resolution})")
    group.add_argument("--pair-budget", type=number(0), default=d.pair_budget, metavar="S",
                       help="occt engine: CPU seconds of work per pair of parts, at least 0; a pair not decided in "
                            "time is reported and keeps the mesh engine's answer (counted as touching and blocking "
                            f"when the bundle has no meshes) (default {d.pair_budget:g})")
    group.add_argument("--time-limit", type=positive_seconds, default=d.time_limit, metavar="S",
                       help="occt engine (and the pairs of parts without a good mesh): CPU seconds for all the pairs "
                            "OCCT decides, above 0; the pairs left then keep the mesh engine's answer and are reported "
                            f"(default {d.time_limit:g})")
    group.add_argument("--occt-face-weight", type=positive, default=d.face_weight, metavar="N",
                       help="occt engine: no OCCT call on a part whose heaviest face weighs more than N (a B-spline's "
                            "poles x (degree + 1) squared; a helical spring's sweep 54,600): its pairs keep the mesh "
                            "engine's answer, reported, and the export gives it a ring hull or its closest mesh; a "
                            f"whole number >= 1 (default {d.face_weight:,})")
    group.add_argument("--occt-prism-triangles", type=positive, default=d.prism_triangles, metavar="N",
                       help="occt engine: a face it cannot sweep exactly is swept as its triangles, at most N of "
                            "them; past N the pairs of that sweep keep the mesh engine's answer, reported; a whole "
                            f"number >= 1 (default {d.prism_triangles:,})")
    group.add_argument("--directions", type=_direction_count, default=d.directions, metavar="N",
                       help="mesh and occt engines: motion directions besides the axes to find on the parts' faces and "
                            f"axes and test like the axes, 0 to 64 (default {d.directions}; 0: the axes only)")
    group.add_argument("--direction", action="append", type=designer_direction, default=[], metavar="X,Y,Z",
                       help="a motion direction of the designer's, tested like the axes at this and every later "
                            "detection (recorded in the product's geometry.designer; normalised; one along an "
                            "axis or within 2 degrees of another is merged, with a note); repeatable")


def add_contact_options(parser) -> None:
    """``--contact T|auto`` and ``--contact-ceiling T`` for commands taking a PRODUCT: its geometry is analysed
    again with them, in memory (the parts need meshes: a bundle, a CAD model)."""
    group = parser.add_argument_group("geometry (a bundle or CAD model, analysed again in memory)")
    group.add_argument("--contact", type=contact_tolerance, default=None, metavar="T",
                       help="analyse the geometry with this contact tolerance (model units) or auto (the smallest "
                            "that connects the product, below --contact-ceiling); default: the product's analysis")
    group.add_argument("--contact-ceiling", type=positive_length, default=None, metavar="T",
                       help=f"--contact auto refuses to go above this (default {100 * CONTACT_CEILING_FRACTION:g} "
                            "%% of the diagonal of the product's bounding box)")


def contact_tolerances_from(args: argparse.Namespace) -> Tolerances | None:
    """The tolerances of :func:`add_contact_options` (None: keep the product's analysis)."""
    if args.contact is None:
        if args.contact_ceiling is not None:
            raise PlannerError("--contact-ceiling only applies with --contact auto")
        return None
    return Tolerances(contact=args.contact, contact_ceiling=args.contact_ceiling)


def tolerances_from(args: argparse.Namespace) -> Tolerances:
    return Tolerances(contact=args.contact, interference=args.interference, depth=args.depth,
                      resolution=args.resolution, directions=args.directions,
                      contact_ceiling=args.contact_ceiling, pair_budget=args.pair_budget, time_limit=args.time_limit,
                      face_weight=args.occt_face_weight, prism_triangles=args.occt_prism_triangles)
