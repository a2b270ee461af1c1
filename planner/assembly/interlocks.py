"""Interlocked pairs resolved from the part meshes, before any enumeration.

Two parts that block each other along every direction of the obstruction diagrams prove that the product
cannot be taken apart (:mod:`planner.assembly.feasibility`). In a CAD model that is almost always a modelling
convention or a direction the diagrams lack. Each interlocked pair is tried against three rules, in order:

1. *overlap*: the two solids share more than ``Tolerances.interference`` of volume (a press fit, a spline or a
   thread modelled overlapping). Candidate insertion directions come from the overlap's shape (the axis its
   surface normals turn around: that of a pin's annulus or a spline's teeth; its longest principal axis),
   then the parts' own axes and faces, then the directions of the diagrams. Along each, the pair is tested
   with the overlap taken out of one of them (``x - y`` against ``y``, then ``x`` against ``y - x``); the
   first direction along which they no longer block each other both ways is the insertion direction, and the
   pair's relation along it becomes that of the parts without the overlap.
2. *direction*: parts that leave along a direction the diagrams do not have (a cylinder's axis, a slot that
   is not along an axis): the pair's axes and planar faces, and the directions of its slots (cross products
   of two of its faces' normals), are tested on the pair; the first that frees it is added to the product as
   a whole obstruction diagram (every part rasterised along it, as the mesh engine does).
3. *component*: nothing frees the pair (a part captured in a cover, a ball in a closed cage): the two become
   one component (:func:`planner.product.merge.merge_parts`), unless one is a fastener or the component would
   be the whole product; then the pair is *unresolved*.

Every change is one :class:`InterlockDecision` with a one-line text, recorded in the product's
``geometry.analysis.interlocks``. Cost: per pair, one mesh boolean and at most ``2 x candidates`` rasters of two
parts; per added direction, one raster of every part (the mesh engine's cost for one direction).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import GeometryError
from .feasibility import InterlockedPair, interlocked_pairs
from ..product import Direction, Obstruction, Product
from ..product.merge import merge_parts
from ..geometry.meshes import PartMesh, _manifold
from ..geometry.projection import (_MERGE_ANGLE, _PATCH_SHARE, _blocking_pairs, _canonical, _facet_normals, _frame,
                                  candidate_directions)
from ..geometry.tolerances import Tolerances

__all__ = ["InterlockDecision", "Unresolved", "resolve_interlocks", "apply_interlock_mode", "RULES", "INTERLOCK_MODES",
           "drawn_in_cad"]

log = logging.getLogger(__name__)

RULES = ("overlap", "direction", "component")
#: ``--interlocks``: resolve (apply the rules, one line per decision), error (name the proposals, plan
#: nothing), keep (plan the diagrams as they are: the planner names the pairs).
INTERLOCK_MODES = ("resolve", "error", "keep")
_PAIR_CANDIDATES = 12   # directions tried per pair besides those of the diagrams


@dataclass(frozen=True)
class InterlockDecision:
    """What a rule did to the interlocked pair ``parts``: ``rule`` one of :data:`RULES`, ``direction`` the
    direction that frees it (rules overlap and direction), ``component`` the part that holds both (rule
    component), ``text`` the line the user reads."""

    rule: str
    parts: tuple[str, str]
    text: str
    direction: Direction | None = None
    component: str | None = None

    def as_dict(self) -> dict:
        return {"rule": self.rule, "parts": list(self.parts), "text": self.text,
                **({"direction": list(self.direction.vector)} if self.direction else {}),
                **({"component": self.component} if self.component else {})}


@dataclass(frozen=True)
class Unresolved:
    """An interlocked pair no rule frees: ``tried`` the directions tried (names), ``why`` what each rule found."""

    pair: InterlockedPair
    tried: tuple[str, ...]
    why: str

    @property
    def line(self) -> str:
        """One line: the pair, the directions tried, and what helps."""
        a, b = self.pair.first, self.pair.second
        return (f"{a} and {b} block each other along every direction tried ({', '.join(self.tried)}) and no rule "
                f"frees them ({self.why}): add the direction one leaves along (aplan export-freecad --direction "
                f"X,Y,Z, or the workbench's diagrams panel), or mark a relation that does not block "
                f"(--not-blocking {a} {b} DIRECTION)")


def resolve_interlocks(product: Product, meshes: list[PartMesh] | None = None, components: bool = True) \
        -> tuple[Product, tuple[InterlockDecision, ...], tuple[Unresolved, ...]]:
    """``product`` with its interlocked pairs resolved by the rules of the module docstring, the decisions
    taken, and the pairs no rule resolves (or every pair, untouched, when the parts have no meshes to read).
    ``meshes``: the parts' meshes (default: read from the product's mesh files); ``components``: whether rule 3
    may merge parts (off: its pairs are unresolved). A product with no interlocked pair is returned as it is,
    without reading a mesh. Cost: module docstring."""
    pairs = interlocked_pairs(product)
    if not pairs:
        return product, (), ()
    if meshes is None:
        meshes = _meshes(product)
    if meshes is None:
        return product, (), tuple(Unresolved(p, _names(p.directions), "the parts have no meshes to look at")
                                  for p in pairs)
    tol, pixel = _tolerances(product)
    if pixel <= 0:  # not recorded: the mesh engine's own choice, the scene's extent over the resolution
        extent = float(np.ptp(np.vstack([m.vertices for m in meshes]), axis=0).max())
        pixel = extent / tol.resolution if extent > 0 else 1.0
    by_id = {m.id: m for m in meshes}
    decisions: list[InterlockDecision] = []
    tried: dict[tuple[str, str], tuple[list[str], str]] = {}
    for pair in pairs:
        if not _still_interlocked(product, pair):
            continue  # freed by a direction another pair added
        x, y = by_id[pair.first], by_id[pair.second]
        found = _overlap_rule(product, x, y, tol, pixel, meshes)
        if isinstance(found, tuple):
            product, decision = found
            decisions.append(decision)
            continue
        overlap_note = found
        found = _direction_rule(product, x, y, tol, pixel, meshes)
        if isinstance(found, tuple):
            product, decision = found
            decisions.append(decision)
            continue
        tried[(pair.first, pair.second)] = (found, overlap_note)
    unresolved: list[Unresolved] = []
    while True:
        left = [p for p in interlocked_pairs(product) if not any(p.first == u.pair.first and p.second ==
                                                                 u.pair.second for u in unresolved)]
        if not left:
            break
        pair = left[0]
        directions, note = tried.get((pair.first, pair.second), (list(_names(pair.directions)), ""))
        why = "; ".join(filter(None, [note, "no direction found on their geometry frees them"]))
        blocker = _component_refused(product, pair) if components else "one component of them is turned off"
        if blocker:
            unresolved.append(Unresolved(pair, tuple(directions), f"{why}; {blocker}"))
            continue
        name = _component_name(product, pair)
        product = merge_parts(product, name, (pair.first, pair.second))
        decisions.append(InterlockDecision(
            "component", (pair.first, pair.second),
            f"{pair.first} and {pair.second}: one component {name} ({why}: a part captured by the other, planned "
            f"as bought or built together; --interlocks error to refuse instead)", component=name))
    if decisions:
        analysis = dict(product.geometry.get("analysis", {}))
        analysis["interlocks"] = list(analysis.get("interlocks", [])) + [d.as_dict() for d in decisions]
        product = replace(product, geometry={**product.geometry, "analysis": analysis})
    return product, tuple(decisions), tuple(unresolved)


def apply_interlock_mode(product: Product, mode: str = "resolve", meshes: list[PartMesh] | None = None) -> Product:
    """``product`` as ``--interlocks MODE`` plans it (:data:`INTERLOCK_MODES`): ``resolve`` applies the rules
    and logs one line per decision, ``error`` raises :class:`~planner.errors.InterlockRefusedError` naming what
    the rules would do, ``keep`` returns it untouched (the planner names the pairs). A pair no rule frees,
    in a product drawn in CAD, is an :class:`~planner.errors.InterlockRefusedError` in one line
    (:attr:`Unresolved.line`) in both of the first modes, and so is a pair whose proposal the designer refused
    (:func:`~planner.assembly.interlock_refusals.refusal_error`); a product without meshes is planned as written.
    Cost: that of :func:`resolve_interlocks`."""
    from ..errors import InterlockRefusedError, PlannerError

    if mode not in INTERLOCK_MODES:
        raise PlannerError(f"unknown interlock mode {mode!r}; use one of {', '.join(INTERLOCK_MODES)}")
    if mode == "keep":
        return product
    from .interlock_refusals import refusal_error, refusal_message

    refused = refusal_error(product, interlocked_pairs(product))  # the designer turned these down: never applied
    if refused is not None:
        raise refused
    resolved, decisions, unresolved = resolve_interlocks(product, meshes)
    unresolved = tuple(u for u in unresolved if "no meshes" not in u.why)
    pairs = [(d.parts[0], d.parts[1]) for d in decisions] + [(u.pair.first, u.pair.second) for u in unresolved]
    where = f"{product.name}: " if product.name else ""
    if unresolved:
        others = ", ".join(f"{u.pair.first} and {u.pair.second}" for u in unresolved[1:])
        more = f" (and {len(unresolved) - 1} more pairs: {others})" if others else ""
        raise InterlockRefusedError(where + unresolved[0].line + more, pairs)
    if mode == "error" and decisions:
        listed = [d.text.split(" (")[0] if d.rule == "component" else d.text for d in decisions]
        raise InterlockRefusedError(refusal_message(
            where, listed, "--interlocks error", "Leave out --interlocks error to apply this, or resolve them in "
            "the CAD model (the workbench's diagrams panel)"), pairs)
    for decision in decisions:
        log.info("interlock: %s", decision.text)
    return resolved


def drawn_in_cad(product: Product) -> bool:
    """Every part has a mesh, or is a component the interlock rules made of parts that had (a product drawn
    in CAD, whose structure the planner may propose)."""
    made = {d.get("component") for d in product.geometry.get("analysis", {}).get("interlocks", [])}
    return bool(product.parts) and all(p.mesh or p.id in made for p in product.parts)


# ------------------------------------------------------------------------------------------------ rules

def _overlap_rule(product, x: PartMesh, y: PartMesh, tol: Tolerances, pixel: float, meshes):
    """(product, decision) when the pair overlaps and a direction frees it without the overlap; else a note."""
    try:
        sx, sy = _manifold(x), _manifold(y)
    except GeometryError as error:  # no boolean on an open mesh: the other rules still apply
        return f"their overlap cannot be measured ({error})"
    common = sx ^ sy
    volume = float(common.volume())
    if volume <= tol.interference:
        return "they do not overlap"
    shape = _mesh_of(common, "_overlap")
    own = [np.asarray(o.direction.vector, dtype=float) for o in product.obstructions]
    candidates = _merged(_snapped(_overlap_axes(shape) + candidate_directions([x, y], _PAIR_CANDIDATES), own) + own)
    variants = [(m, y) for m in [_mesh_of(sx - sy, x.id)] if m is not None] + \
               [(x, m) for m in [_mesh_of(sy - sx, y.id)] if m is not None]
    for direction in candidates:
        for first, second in variants:
            relation = _pair_relation(first, second, direction, pixel, tol)
            if len(relation) < 2:
                leaving = _leaving(x.id, y.id, relation, direction)
                product = _with_relation(product, x.id, y.id, direction, relation, meshes, pixel, tol)
                name = Direction.from_vector(tuple(direction)).name
                return product, InterlockDecision(
                    "overlap", (x.id, y.id),
                    f"{x.id} and {y.id} overlap by {volume:.4g} cubic units (a press fit, spline or thread modelled "
                    f"overlapping): inserted along {name}, {leaving}; their relation along it is taken without the "
                    "overlap", Direction.from_vector(tuple(direction)))
    return f"they overlap by {volume:.4g} cubic units, but no direction frees them without the overlap"


def _direction_rule(product, x: PartMesh, y: PartMesh, tol: Tolerances, pixel: float, meshes):
    """(product, decision) when a direction found on the pair's geometry frees it; else the names tried."""
    taken = [np.asarray(o.direction.vector, dtype=float) for o in product.obstructions]
    candidates = _merged(candidate_directions([x, y], _PAIR_CANDIDATES, taken) + _slot_directions([x, y]), taken)
    tried = [*_names(tuple(o.direction.name for o in product.obstructions))]
    for direction in candidates[:_PAIR_CANDIDATES]:
        name = Direction.from_vector(tuple(direction)).name
        tried.append(f"{name} and its reverse")
        relation = _pair_relation(x, y, direction, pixel, tol)
        if len(relation) < 2:
            product = _with_relation(product, x.id, y.id, direction, relation, meshes, pixel, tol)
            return product, InterlockDecision(
                "direction", (x.id, y.id),
                f"{x.id} and {y.id}: tested direction {name} found on their geometry (an axis, a face or a slot): "
                f"{_leaving(x.id, y.id, relation, direction)}", Direction.from_vector(tuple(direction)))
    return tried


def _component_refused(product: Product, pair: InterlockedPair) -> str:
    """Why the pair may not become one component ('' when it may)."""
    fasteners = [p for p in (pair.first, pair.second) if p in product.fastener_parts]
    if fasteners:
        return f"{fasteners[0]} is a fastener"
    if len(product.parts) <= 2:
        return "one component of them would be the whole product"
    owners = {m: g.id for g in product.subassemblies for m in g.parts}
    if owners.get(pair.first) != owners.get(pair.second):
        return (f"they are in different subassemblies of the document ({owners.get(pair.first, 'the top level')} and "
                f"{owners.get(pair.second, 'the top level')})")
    return ""


def _component_name(product: Product, pair: InterlockedPair) -> str:
    taken = set(product.part_ids) | {g.id for g in product.subassemblies} | {t.id for t in product.tools}
    base = f"{pair.first}+{pair.second}"
    return next(n for n in (base, *(f"{base}_{k}" for k in range(2, 10 ** 6))) if n not in taken)


# --------------------------------------------------------------------------------------------- geometry

def _pair_relation(x: PartMesh, y: PartMesh, direction: np.ndarray, pixel: float, tol: Tolerances):
    """The obstruction pairs of ``x`` and ``y`` alone along ``+direction`` (``(x, y)``: x moving hits y)."""
    frame = _frame(direction)
    turned = [x.triangles @ frame.T, y.triangles @ frame.T]
    lo = np.array([t.reshape(-1, 3).min(axis=0) for t in turned])
    hi = np.array([t.reshape(-1, 3).max(axis=0) for t in turned])
    found = _blocking_pairs([x, y], turned, lo, hi, 2, lo.min(axis=0), pixel, tol)
    return found


def _with_relation(product: Product, a: str, b: str, direction: np.ndarray, relation, meshes, pixel: float,
                   tol: Tolerances) -> Product:
    """``product`` with the pair's obstruction pairs along ``direction`` set to ``relation`` (None: as the
    meshes give them); a direction the product lacks is added with every part's relation along it."""
    vector = tuple(float(c) for c in direction)
    name = Direction.from_vector(vector).name
    existing = next((o for o in product.obstructions if o.direction.name == name), None)
    if existing is None:
        frame = _frame(direction)
        turned = [m.triangles @ frame.T for m in meshes]
        lo = np.array([t.reshape(-1, 3).min(axis=0) for t in turned])
        hi = np.array([t.reshape(-1, 3).max(axis=0) for t in turned])
        ids = set(product.part_ids)
        blocks = [p for p in _blocking_pairs(meshes, turned, lo, hi, 2, lo.min(axis=0), pixel, tol)
                  if p[0] in ids and p[1] in ids]
        existing = Obstruction(Direction.from_vector(vector), tuple(blocks))
        obstructions = product.obstructions + (existing,)
    else:
        obstructions = product.obstructions
    if relation is not None:
        kept = tuple(p for p in existing.blocks if set(p) != {a, b}) + tuple(relation)
        obstructions = tuple(replace(o, blocks=kept) if o.direction.name == name else o for o in obstructions)
    return replace(product, obstructions=obstructions)


def _overlap_axes(shape: PartMesh | None) -> list[np.ndarray]:
    """The overlap's axis (its normals turn around it) and its longest principal axis."""
    if shape is None:
        return []
    normals, areas = _facet_normals(shape)
    if not len(areas):
        return []
    scatter = (normals * areas[:, None]).T @ normals / areas.sum()
    axes = [np.linalg.eigh(scatter)[1][:, 0]]
    t = shape.triangles
    keep = np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1) > 0  # as _facet_normals
    centres = t[keep].mean(axis=1)
    mean = (centres * areas[:, None]).sum(axis=0) / areas.sum()
    spread = ((centres - mean) * areas[:, None]).T @ (centres - mean) / areas.sum()
    values, vectors = np.linalg.eigh(spread)
    if values[2] > 1.5 * values[1]:  # clearly elongated (a thread along a bolt)
        axes.append(vectors[:, 2])
    return axes


def _slot_directions(parts: list[PartMesh], per_part: int = 4) -> list[np.ndarray]:
    """The directions of slots: cross products of two planar faces' normals (the floor and a wall), per part
    its ``per_part`` largest planar patches."""
    out = []
    for part in parts:
        normals, areas = _facet_normals(part)
        if not len(areas):
            continue
        keys, inverse = np.unique(np.round(normals * 60).astype(np.int64), axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        patch = np.bincount(inverse, weights=areas, minlength=len(keys))
        big = [k for k in np.argsort(-patch)[:per_part] if patch[k] >= _PATCH_SHARE * areas.sum() / 4]
        means = [(normals[inverse == k] * areas[inverse == k, None]).sum(axis=0) for k in big]
        for i in range(len(means)):
            for j in range(i + 1, len(means)):
                cross = np.cross(means[i], means[j])
                if np.linalg.norm(cross) > 1e-6 * np.linalg.norm(means[i]) * np.linalg.norm(means[j]):
                    out.append(cross)
    return out


def _snapped(directions: list[np.ndarray], own: list[np.ndarray]) -> list[np.ndarray]:
    """Each direction, or the product's direction within the merge angle of it (no new diagram for a
    direction the product has, give or take the mesh's faceting)."""
    out = []
    for d in directions:
        d = d / np.linalg.norm(d)
        near = next((o for o in own if abs(float(o @ d)) >= np.cos(_MERGE_ANGLE)), None)
        out.append(d if near is None else near)
    return out


def _merged(directions: list[np.ndarray], taken: list[np.ndarray] = ()) -> list[np.ndarray]:
    """Unit, canonical, without repeats within the mesh engine's merge angle (nor of ``taken``)."""
    kept: list[np.ndarray] = []
    for d in directions:
        norm = float(np.linalg.norm(d))
        if not np.isfinite(norm) or norm == 0:
            continue
        d = np.where(np.abs(d / norm) < 1e-6, 0.0, d / norm)
        d = _canonical(d / np.linalg.norm(d)) + 0.0
        others = list(taken) + kept
        if not others or np.all(np.abs(np.vstack(others) @ d) < np.cos(_MERGE_ANGLE)):
            kept.append(d)
    return kept


def _leaving(a: str, b: str, relation, direction: np.ndarray) -> str:
    name = Direction.from_vector(tuple(float(c) for c in direction))
    if (a, b) not in relation:
        return f"{a} leaves {b} along {name.name}" + ("" if (b, a) in relation else " and its reverse")
    return f"{b} leaves {a} along {name.name}"


def _mesh_of(solid, name: str) -> PartMesh | None:
    mesh = solid.to_mesh()
    vertices = np.asarray(mesh.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(mesh.tri_verts, dtype=np.int64)
    return PartMesh(name, vertices, faces) if len(faces) else None


def _still_interlocked(product: Product, pair: InterlockedPair) -> bool:
    return any(p.first == pair.first and p.second == pair.second for p in interlocked_pairs(product))


def _names(directions: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(f"+/-{d.lstrip('+-')}" if d[:1] in "+-" else f"{d} and its reverse" for d in directions)


def _meshes(product: Product) -> list[PartMesh] | None:
    from ..geometry.bundle import load_part_meshes

    if not product.parts or not all(p.mesh for p in product.parts):
        return None
    base = Path(product.source).parent
    if not all((base / p.mesh).is_file() for p in product.parts):
        return None
    return load_part_meshes(product)


def _tolerances(product: Product) -> tuple[Tolerances, float]:
    """The tolerances the product's diagrams were found with (its ``geometry.analysis``), and their pixel."""
    used = product.geometry.get("analysis", {}).get("tolerances", {}) or {}
    fields = {k: used[k] for k in ("contact", "interference", "depth", "resolution", "grazing")
              if isinstance(used.get(k), (int, float)) and not isinstance(used.get(k), bool)}
    try:
        tol = Tolerances(**fields)
    except GeometryError:  # a hand-written record out of range: the engine's defaults
        tol = Tolerances()
    pixel = used.get("pixel")
    return tol, float(pixel) if isinstance(pixel, (int, float)) and pixel > 0 and np.isfinite(pixel) else 0.0

