"""Clearances and the contact tolerance: what a geometry analysis adds when parts are modelled apart.

- :func:`analyze_with_clearances` runs an engine and then, from the part meshes (:mod:`.gaps`):
  records the gaps between the groups when the contacts fall apart (``GeometryReport.gaps``, kept in the
  product file under ``geometry.analysis.gaps`` so that a later "not connected" error can name them);
  chooses the contact tolerance for ``contact="auto"`` (:func:`default_ceiling` caps it; past the cap:
  :class:`~planner.errors.ContactCeilingError`) and records the choice in the report's tolerances
  (``contact_auto``); and warns when a contact tolerance above the default adds more contacts than
  ``TOUCHING_FRACTION`` of all part pairs.
- :func:`gap_record` / :func:`explain_groups`: the recorded gaps, and the per-group explanation of a
  connection diagram that falls apart, from the record or from the meshes.
"""
from __future__ import annotations

import logging
from dataclasses import replace
from typing import Callable

import numpy as np

from ..defaults import CONTACT_CEILING_FRACTION, CONTACT_TOLERANCE, TOUCHING_FRACTION
from ..errors import ContactCeilingError, GeometryError
from .gaps import GapReport, connection_groups, contact_tolerance_for, fcl_available, gap_report, mesh_gaps, part_gaps
from .mesh_engine import GeometryReport, PartMesh, touching_pairs
from .tolerances import Tolerances

__all__ = ["analyze_with_clearances", "default_ceiling", "gap_record", "explain_groups", "touching_warning"]

log = logging.getLogger(__name__)

Engine = Callable[[Tolerances], GeometryReport]


def default_ceiling(parts: list[PartMesh]) -> float:
    """The default ceiling of ``--contact auto``: ``CONTACT_CEILING_FRACTION`` of the diagonal of the
    product's bounding box (see :mod:`planner.defaults` for why)."""
    lo = np.min([p.vertices.min(axis=0) for p in parts], axis=0)
    hi = np.max([p.vertices.max(axis=0) for p in parts], axis=0)
    return float(CONTACT_CEILING_FRACTION * np.linalg.norm(hi - lo))


def gap_record(report: GapReport) -> dict:
    """What the product file keeps of a gap report: the groups (by their first part), each group's nearest
    gap, the joining gaps, the tolerance that joins every group, and every exact gap measured."""
    return {**report.as_dict(), "measured": [g.as_list() for g in report.visited]}


def explain_groups(groups: list[list[str]], record: dict | None = None,
                   parts: list[PartMesh] | None = None) -> GapReport | None:
    """The gap report of ``groups``: from a product's recorded gaps (:func:`gap_record`) when they join every
    group, else from the meshes ``parts`` when given, else None."""
    if record and record.get("measured"):
        report = gap_report(groups, record["measured"])
        if None not in report.nearest and len(report.joining) == len(groups) - 1:
            return report
    if parts is not None:
        return _measure(parts, groups)
    return None


def _measure(parts: list[PartMesh], groups: list[list[str]]) -> GapReport:
    """:func:`mesh_gaps` over the groups (as contacts joining each group's parts in a chain)."""
    chain = [(g[k], g[k + 1]) for g in groups for k in range(len(g) - 1)]
    return mesh_gaps(parts, chain)


def touching_warning(part_ids, contacts, default_contacts, tolerance: float,
                     parts: list[PartMesh] | None = None, shown: int = 5) -> str | None:
    """The warning for a contact tolerance so large that parts apart by design touch: None unless
    ``contacts`` (found at ``tolerance``) has more than ``TOUCHING_FRACTION`` of all part pairs beyond
    ``default_contacts`` (those found at the default tolerance). Names the added pairs with the largest gaps
    (measured on ``parts`` when given)."""
    n = len(part_ids)
    pairs = n * (n - 1) // 2
    before = {frozenset(c) for c in default_contacts}
    added = [tuple(c) for c in contacts if frozenset(c) not in before]
    if pairs == 0 or len(added) <= TOUCHING_FRACTION * pairs:
        return None
    examples = ""
    if parts is not None and fcl_available():
        measured = sorted(part_gaps(parts, added).items(), key=lambda item: -item[1])[:shown]
        examples = " (the farthest apart: " + ", ".join(f"{a}/{b} {d:.3g}" for (a, b), d in measured) + ")"
    return (f"the contact tolerance {tolerance:g} adds {len(added):,} contacts to the {len(before):,} found at the "
            f"default {CONTACT_TOLERANCE:g}: {len(contacts):,} of all {pairs:,} part pairs touch "
            f"({100 * len(contacts) / pairs:.0f} %), more than {100 * TOUCHING_FRACTION:.0f} % of the pairs added"
            f"{examples}; parts that are apart by design count as touching now, and the plan grows with every "
            "contact: use a smaller --contact, or --contact auto")


def _refuse(report: GapReport, tolerance: float, ceiling: float) -> ContactCeilingError:
    above = sorted((g for g in report.joining if contact_tolerance_for(g.distance) > ceiling),
                   key=lambda g: -g.distance)
    worst = above[0]
    listed = "; ".join(f"{g.distance:.4g} between {g.a} and {g.b}" for g in above)
    return ContactCeilingError(
        f"--contact auto: the product needs a contact tolerance of {tolerance:g} to be connected, above the "
        f"ceiling of {ceiling:.3g} (1 % of the product's size unless --contact-ceiling says otherwise): the gaps "
        f"above it are {listed}. Those parts are apart by design or do not belong to the product: exclude them, "
        f"add the contacts by hand, or raise the ceiling (--contact-ceiling {tolerance:g})",
        worst.distance, (worst.a, worst.b), ceiling)


def _with_gaps(report: GeometryReport, parts: list[PartMesh] | None) -> GeometryReport:
    """The report, with its gap record when its contacts fall apart and the meshes are at hand."""
    groups = connection_groups(report.parts, report.contacts)
    if len(groups) < 2 or parts is None or not fcl_available():  # the record is a help, not a requirement
        return report
    return replace(report, gaps=gap_record(mesh_gaps(parts, report.contacts)))


def analyze_with_clearances(run: Engine, tolerances: Tolerances,
                            meshes: Callable[[], list[PartMesh]]) -> GeometryReport:
    """Run the engine ``run`` with ``tolerances``, choosing the contact tolerance when it is ``"auto"``, and add
    the gap record and the touching warning (module docstring). ``meshes`` reads the part meshes, only when
    needed (a disconnected result, auto, or a tolerance above the default): for a fixed tolerance a bundle
    without meshes, or a Python without trimesh to read them, is analysed as before, without the record.

    Auto: the engine runs at the default tolerance; when its contacts fall apart, the gaps between the groups
    are measured, the tolerance is the bottleneck (:func:`~planner.geometry.gaps.contact_tolerance_for`), the
    engine runs again with it, and ``tolerances["contact_auto"]`` of the report records ``chosen``,
    ``ceiling``, ``default`` and ``gaps_joined``. Raises :class:`ContactCeilingError` above the ceiling.
    Cost: one or two engine runs, plus :func:`~planner.geometry.gaps.mesh_gaps`.
    """
    loaded: list[list[PartMesh] | None] = []

    def parts(required: bool) -> list[PartMesh] | None:
        if not loaded:
            try:
                loaded.append(meshes())
            except (GeometryError, ImportError):  # ImportError: no trimesh here (FreeCADCmd's Python)
                if required:
                    raise
                log.debug("no meshes to measure the gaps with", exc_info=True)
                loaded.append(None)
        return loaded[0]

    if not tolerances.auto:
        report = run(tolerances)
        if len(connection_groups(report.parts, report.contacts)) > 1:
            report = _with_gaps(report, parts(False))
        if tolerances.contact > CONTACT_TOLERANCE and parts(False) is not None:
            default = touching_pairs(parts(False), report.contacts, CONTACT_TOLERANCE)
            warning = touching_warning(report.parts, report.contacts, default, tolerances.contact, parts(False))
            if warning:
                report = replace(report, warnings=report.warnings + (warning,))
        return report

    base = run(replace(tolerances, contact=CONTACT_TOLERANCE))
    measured = parts(True)
    ceiling = tolerances.contact_ceiling if tolerances.contact_ceiling is not None else default_ceiling(measured)
    gaps = mesh_gaps(measured, base.contacts)
    record = {"chosen": CONTACT_TOLERANCE, "ceiling": round(ceiling, 6), "default": CONTACT_TOLERANCE,
              "gaps_joined": []}
    if len(gaps.groups) < 2:
        return replace(base, tolerances={**base.tolerances, "contact_auto": record})
    chosen = max(CONTACT_TOLERANCE, contact_tolerance_for(gaps.bottleneck))
    if chosen > ceiling:
        raise _refuse(gaps, chosen, ceiling)
    report = run(replace(tolerances, contact=chosen))
    record.update(chosen=chosen, gaps_joined=[g.as_list() for g in gaps.joining])
    warnings = list(report.warnings)
    left = connection_groups(report.parts, report.contacts)
    if len(left) > 1:
        warnings.append(f"--contact auto chose {chosen:g} from the meshes, but the {report.engine} engine still "
                        f"finds {len(left)} groups at that tolerance; give --contact a little more")
        report = _with_gaps(report, measured)
    warning = touching_warning(report.parts, report.contacts, base.contacts, chosen, measured)
    if warning:
        warnings.append(warning)
    return replace(report, tolerances={**report.tolerances, "contact_auto": record}, warnings=tuple(warnings))
