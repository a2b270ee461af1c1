"""The OCCT engine's entry points: exact part shapes, or the B-reps of a bundle, to the report of contacts,
interferences and obstruction diagrams."""
from __future__ import annotations

import json
import math
import os
import time
from typing import Callable

import Part

from planner.defaults import (BLOCKING_DEPTH, CONTACT_TOLERANCE, INTERFERENCE_VOLUME, OCCT_FACE_WEIGHT, OCCT_PAIR_BUDGET,
                              OCCT_PRISM_TRIANGLES, PRODUCT_FILE)
from planner.errors import GeometryError
from planner.product import AXIS_DIRECTIONS, Direction

from ..document import DocumentError
from .budget import PairClock, face_boxes
from .complexity import describe_face, shape_weight
from .contacts import find_contacts
from .obstructions import find_obstructions
from .solids import bounding_box, inner_points

__all__ = ["BrepError", "analyze_shapes", "analyze_bundle_breps"]


class BrepError(DocumentError):
    """A part's B-rep cannot be used: missing or unreadable file, no solid, no volume."""


def analyze_shapes(parts: list[tuple[str, "Part.Shape"]], contact: float = CONTACT_TOLERANCE,
                   interference: float = INTERFERENCE_VOLUME, depth: float = BLOCKING_DEPTH,
                   pair_budget: float = OCCT_PAIR_BUDGET, budgets: dict | None = None,
                   progress: Callable[[str], None] | None = None, directions=(), pairs=None,
                   pair_steps: int | None = None, time_limit: float | None = None,
                   clock: Callable[[], float] = time.process_time, face_weight: int | None = OCCT_FACE_WEIGHT,
                   prism_triangles: int | None = OCCT_PRISM_TRIANGLES) -> dict:
    """Contacts, interferences and the +X, +Y, +Z obstruction diagrams of exact part shapes, and those along
    the unit vectors ``directions`` (the designer's, the candidate directions of
    :func:`planner.geometry.mesh_engine.candidate_directions`), tested like the axes.

    ``parts``: (id, shape) pairs, shapes holding solids in global coordinates (they are not modified).
    Returns the layout of :meth:`planner.geometry.GeometryReport.as_dict` with engine ``"occt"``; contact and
    interference pairs follow the order of ``parts``; obstruction pair ``(x, y)`` along ``+d`` means ``x``
    moving along ``+d`` collides with ``y``.

    Tolerances: ``contact`` (model units) for contacts, and the grazing width of the obstruction broad
    phase; ``interference`` (cubic units) for reporting overlaps; ``depth`` (model units) for obstruction:
    ``y`` must reach more than ``depth`` beyond the start of ``x``, and ``x``'s sweep must take more than
    ``depth ** 3`` of ``y`` outside what they already share.

    Time: OCCT works at most ``pair_budget`` seconds on a pair of parts (``budgets`` maps pairs of ids to
    other budgets, checked between booleans); a pair it cannot decide in time counts as touching and
    blocking, is listed under ``undecided`` and named in a warning, and the others go on. Work too:
    ``pair_steps`` OCCT operations per pair at most (None: no bound; :class:`~.budget.PairClock`), and
    ``time_limit`` seconds of ``clock`` (CPU seconds of this process) over the whole run, after which every pair left is
    undecided (``timed_out`` is then True); ``undecided_relations`` lists ``[a, b, what]``, ``what`` being
    ``"the contact"``, ``"the overlap"`` or ``"X moving along D"``. ``pairs``: the pairs of ids to decide (None: all): the others
    are neither measured nor reported (:mod:`freecad_aplan.hybrid` decides them on the meshes). ``progress``
    receives a line every few seconds. ``pairs`` counts the contact pairs decided by part boxes (``far``), by
    face boxes (``far_faces``) and those measured exactly (``exact``), and the obstruction candidates (over
    all the directions) by part boxes (``sweep_candidates``) and those left by face boxes (``sweep_exact``).

    Bounded inside a call too: a part whose heaviest face weighs more than ``face_weight``
    (:mod:`.complexity`; None: no bound) gets no OCCT call at all, its pairs (past the box culls) being
    undecided at once and listed under ``heavy`` (id: weight); and a face swept as triangles may have at
    most ``prism_triangles`` of them (None: no bound), else every pair of its part along that direction is
    undecided (listed under ``sweeps_over``: [id, direction, triangles]). Decided pairs are decided as
    without these bounds. A sweep that lost a face (one OCCT can sweep neither exactly nor as triangles, e.g. a
    closed B-spline patch: a sphere or a torus as NURBS) leaves every pair of its part along that direction
    undecided too (listed under ``sweeps_lost``: [id, direction, face pieces]): with a hole in the sweep, no
    pair can be shown free.

    Raises :class:`BrepError` naming the part when
    a shape holds no solid or no volume, :class:`~planner.errors.GeometryError` for a negative tolerance.

    >>> import FreeCAD, Part
    >>> report = analyze_shapes([("a", Part.makeBox(1, 1, 1)), ("b", Part.makeBox(1, 1, 1, FreeCAD.Vector(1, 0, 0)))])
    >>> report["contacts"], report["obstructions"]["+X"]
    ([['a', 'b']], [['a', 'b']])

    Cost: one ``distToShape`` per pair whose boxes are within ``contact`` and one ``common`` per pair that
    touches; per axis, the prisms of each part's backward faces (one ``generalFuse`` per face split at its
    silhouette) and, per candidate pair, one to four ``common`` per prism whose box meets the other part
    (an empty result is cross-checked) plus up to 100 point classifications. Booleans take 0.01-1 s each;
    the pen takes about 2 s, a 61-part toy truck about 90 s.
    """
    start = time.perf_counter()
    for name, value in (("contact", contact), ("interference", interference), ("depth", depth)):
        if not value >= 0:
            raise GeometryError(f"tolerance {name} must be >= 0, got {value!r}")
    if not parts:
        raise BrepError("no parts to analyse")
    ids = [str(p[0]) for p in parts]
    shapes = []
    for part_id, shape in parts:
        if shape is None or shape.isNull() or not shape.Solids:
            raise BrepError(f"part {part_id!r}: its shape holds no solid")
        if not shape.Volume > 0:
            raise BrepError(f"part {part_id!r}: its solid has no volume ({shape.Volume:g})")
        shapes.append(shape.copy())  # booleans may raise the tolerances of their arguments
    boxes = [bounding_box(s) for s in shapes]
    warnings: list[str] = []
    fuzzies = (0.0, contact * 1e-4, contact * 1e-3)
    cache: dict[int, list] = {}

    def points(j: int) -> list:
        if j not in cache:
            cache[j] = inner_points(shapes[j], min(contact, 0.01 * shapes[j].BoundBox.DiagonalLength))
        return cache[j]

    if not pair_budget >= 0:
        raise GeometryError(f"pair_budget must be >= 0 seconds, got {pair_budget!r}")
    if time_limit is not None and not (time_limit > 0 and math.isfinite(time_limit)):
        raise GeometryError(f"time_limit must be a finite number of seconds above 0, got {time_limit!r}")
    if pair_steps is not None and not (isinstance(pair_steps, int) and pair_steps >= 0):
        raise GeometryError(f"pair_steps must be a whole number >= 0, got {pair_steps!r}")
    clock = PairClock(ids, pair_budget, budgets, progress, steps=pair_steps, time_limit=time_limit, clock=clock)
    if pairs is not None:
        index = {part_id: k for k, part_id in enumerate(ids)}
        unknown = sorted({p for pair in pairs for p in pair} - set(index))
        if unknown:
            raise BrepError(f"pairs name parts that are not given: {', '.join(unknown)}")
        clock.selected = {(min(index[a], index[b]), max(index[a], index[b])) for a, b in pairs if a != b}
    if face_weight is not None and not (isinstance(face_weight, int) and face_weight >= 1):
        raise GeometryError(f"face_weight must be a whole number >= 1, got {face_weight!r}")
    heavy = {}  # the parts of the pairs asked for that no OCCT call is made on (their weight)
    asked = None if clock.selected is None else {k for pair in clock.selected for k in pair}
    for k, shape in enumerate(shapes):
        weight, face = shape_weight(shape)
        if face_weight is not None and weight > face_weight and (asked is None or k in asked):
            heavy[ids[k]] = weight
            clock.heavy[k] = (f"{ids[k]!r} has {describe_face(shape.Faces[face])} (weight {weight:,}, over the "
                              f"bound of {face_weight:,}: one OCCT call on it cannot be bounded)")
    faces = [face_boxes(s) for s in shapes]
    contacts, overlap = find_contacts(ids, shapes, boxes, faces, points, contact, fuzzies, warnings, clock)
    interferences = [(i, j, overlap[i, j][0]) for i, j in contacts if overlap.get((i, j), (0.0,))[0] > interference]
    for i, j, volume in interferences:
        warnings.append(f"parts {ids[i]!r} and {ids[j]!r} interpenetrate by {volume:.4g} cubic units "
                        f"(more than the interference tolerance {interference:g})")
    extra = _named_directions(directions)
    over: list = []
    lost: list = []
    obstructions = find_obstructions(ids, shapes, boxes, faces, overlap, contact, depth, fuzzies, warnings, clock,
                                     list(extra.items()), prism_triangles, over, lost)
    warnings.extend(clock.warnings() if pairs is None else clock.warnings("the mesh engine's answer stands"))
    return {
        "engine": "occt", "parts": len(ids),
        "contacts": [[ids[i], ids[j]] for i, j in contacts],
        "interferences": [{"parts": [ids[i], ids[j]], "volume": round(v, 6)} for i, j, v in interferences],
        "obstructions": {name: [[ids[i], ids[j]] for i, j in pairs] for name, pairs in obstructions.items()},
        **({"directions": {name: list(v) for name, v in extra.items()}} if extra else {}),
        "tolerances": {"contact": contact, "interference": interference, "depth": depth,
                       "volume": depth ** 3},
        "undecided": [[ids[i], ids[j]] for i, j in sorted(clock.undecided)], "pairs": dict(clock.counts),
        "undecided_relations": [[ids[i], ids[j], what] for (i, j), whats in sorted(clock.undecided.items())
                                for what in whats],
        "pair_budget": pair_budget, "pair_steps": pair_steps, "time_limit": time_limit,
        "timed_out": clock.timed_out, "selected": None if clock.selected is None else len(clock.selected),
        "heavy": heavy, "face_weight": face_weight, "prism_triangles": prism_triangles,
        "sweeps_over": [[ids[i], name, count] for i, name, count in over],
        "sweeps_lost": [[ids[i], name, count] for i, name, count in lost],
        "warnings": warnings, "seconds": round(time.perf_counter() - start, 3),
    }


def _named_directions(directions) -> dict[str, tuple[float, float, float]]:
    """The unit vectors ``directions`` by their names (:meth:`planner.product.Direction.from_vector`), the
    axes and repeated names left out (the axes are always tested). Raises GeometryError for a vector that
    is not three finite numbers of positive length."""
    named: dict[str, tuple[float, float, float]] = {}
    for vector in directions:
        values = [float(c) for c in vector]
        length = math.sqrt(sum(c * c for c in values))
        if len(values) != 3 or not math.isfinite(length) or length == 0:
            raise GeometryError(f"direction {list(vector)!r} is not three finite numbers of positive length")
        unit = tuple(c / length for c in values)
        name = Direction.from_vector(unit).name
        if name not in AXIS_DIRECTIONS and name not in named:
            named[name] = unit
    return named


def analyze_bundle_breps(folder: str, budgets: list | None = None, **tolerances) -> dict:
    """:func:`analyze_shapes` on the B-reps of a bundle: ``folder/product.json`` and its ``breps/*.brep``.

    ``tolerances``: ``contact``, ``interference``, ``depth``, ``pair_budget``, ``progress`` and
    ``directions`` as in :func:`analyze_shapes`; ``budgets``: ``[[id, id, seconds], ...]`` (JSON has no
    tuple keys).
    Raises :class:`BrepError` naming the part and the file when a B-rep is missing or unreadable.
    Cost: reading the files, then that of :func:`analyze_shapes`.
    """
    path = os.path.join(folder, PRODUCT_FILE)
    try:
        with open(path, encoding="utf-8") as handle:
            product = json.load(handle)
    except (OSError, ValueError) as exc:
        raise BrepError(f"{path}: cannot read the bundle's product file ({exc})") from None
    parts = []
    for index, part in enumerate(product.get("parts", [])):
        part_id = part.get("id", f"parts[{index}]")
        relative = part.get("brep")
        if not relative:
            raise BrepError(f"part {part_id!r}: no B-rep file in {path} (re-export the bundle)")
        brep = os.path.join(folder, relative)
        if not os.path.isfile(brep):
            raise BrepError(f"part {part_id!r}: B-rep file {brep} is missing (re-export the bundle)")
        shape = Part.Shape()
        try:
            shape.read(brep)
        except Exception as exc:
            raise BrepError(f"part {part_id!r}: B-rep file {brep} cannot be read ({exc})") from None
        if shape.isNull():
            raise BrepError(f"part {part_id!r}: B-rep file {brep} holds no shape")
        parts.append((part_id, shape))
    pair_budgets = {(a, b): seconds for a, b, seconds in budgets or ()}
    return analyze_shapes(parts, budgets=pair_budgets, **tolerances)
