"""Stage 2 of the API: the plan of a product (AND/OR graph, assembly states, tags), its figures, the base part every
sequence starts from (paper Sec. V), the sequences a chooser lists and their exploded views, and the sequence a
session log recorded."""
from __future__ import annotations

import os
from contextlib import contextmanager
from typing import Sequence

import numpy as np

from ..assembly.explode import ExplodedView, exploded_view, first_sequences, sequence_at
from ..assembly.guards import SizeLimits
from ..assembly.intentions import base_part_first_edges, most_connected_part
from ..assembly.plan import Plan, make_plan
from ..assembly.stats import PlanStatistics, plan_statistics, statistics_within
from ..errors import DisconnectedProductError, PlannerError
from ..product import Product, fold
from ..runtime.logged_sequence import LoggedSequence, complete_sequence, logged_sequence
from ..validation import InputLimits

from .products import resolve_product

__all__ = ["explain_disconnected", "plan_of", "base_part_of", "sequence_choices", "plan_in_3d", "sequence_from_log",
           "plan_statistics_of", "AUTO_BASE_PART"]


def explain_disconnected(product: Product, error: DisconnectedProductError) -> DisconnectedProductError:
    """``error`` with the gaps between its groups: those the product's analysis recorded
    (``geometry.analysis.gaps``), else measured on the part meshes when the product has them; ``error`` itself
    when neither can say."""
    from ..geometry.bundle import load_part_meshes
    from ..geometry.clearances import explain_groups
    from ..geometry.gaps import contact_tolerance_for

    if error.gaps is not None:
        return error
    report = explain_groups(error.groups, product.geometry.get("analysis", {}).get("gaps"))
    if report is None and product.parts and all(p.mesh for p in product.parts):
        try:
            report = explain_groups(error.groups, None, load_part_meshes(product))
        except PlannerError:  # unreadable meshes: the error without gaps is still right
            return error
    if report is None:
        return error
    gaps = [(g.a, g.b, g.distance, contact_tolerance_for(g.distance)) if g is not None else None
            for g in report.nearest]
    return DisconnectedProductError(error.groups, gaps, contact_tolerance_for(report.bottleneck), product.units)


@contextmanager
def _gaps_explained(product: Product):
    """Re-raise a :class:`DisconnectedProductError` with the gaps between its groups (:func:`explain_disconnected`)."""
    try:
        yield
    except DisconnectedProductError as error:
        explained = explain_disconnected(product, error)
        if not explained.source and product.source and product.source != "<memory>":  # name the file
            explained = DisconnectedProductError(explained.groups, explained.gaps, explained.tolerance,
                                                 explained.units, product.source)
        if explained is error:
            raise
        raise explained from None


def plan_of(product: str | os.PathLike | Product, technical: bool | None = None,
            limits: SizeLimits = SizeLimits()) -> Plan:
    """The plan (AND/OR graph, assembly states, tags) of a product or PRODUCT argument; ``technical``:
    ``True``/``False`` switches every technical constraint on/off, ``None`` keeps the file's; ``limits``: the
    size limits the plan is built within (past them: :class:`~planner.errors.LimitExceededError`). A product
    that falls apart is refused with the gaps between its groups (:func:`explain_disconnected`)."""
    product = product if isinstance(product, Product) else resolve_product(product)
    with _gaps_explained(product):
        return make_plan(product, technical, limits)


def _decidable(plan: Plan) -> Plan:
    """``plan`` if a decision model can be built on it: at least one assembly operation (two parts), else a
    :class:`PlannerError` saying so (a model of nothing to do would have no action to choose)."""
    if len(plan.product.parts) < 2:
        raise PlannerError(f"{plan.product.source or plan.product.name or 'the product'}: "
                           f"{len(plan.product.parts)} part, so nothing to assemble: a decision model needs a "
                           "product of at least two parts (aplan stats still describes it)")
    return plan


AUTO_BASE_PART = "auto"


def base_part_of(plan: Plan, base_part: str | None) -> str | None:
    """The base part that sequences start from (paper Sec. V): None (every sequence), ``"auto"`` (the most
    connected part, :func:`~planner.assembly.intentions.most_connected_part`) or a part id, checked: a
    :class:`PlannerError` that lists the parts when it is not one. The one place ``"auto"`` is resolved."""
    if base_part is None or base_part == "":
        return None
    base = most_connected_part(plan.product) if base_part == AUTO_BASE_PART else str(base_part)
    base_part_first_edges(plan.states, base)  # raises for a part the product does not have
    return base


def sequence_choices(plan: Plan, base_part: str | None = None, limit: int = 200) -> tuple[int, list[list[int]]]:
    """The number of full assembly sequences (from ``base_part``, ``"auto"`` resolved) and the first ``limit``
    of them by rank (:func:`~planner.assembly.explode.sequence_at`): what a sequence chooser lists; past the
    limit a chooser asks for a rank."""
    return first_sequences(plan, limit, base_part_of(plan, base_part))


def plan_in_3d(plan: Plan, sequence: int | Sequence[int], spacing: float = 1.0,
               base_part: str | None = None) -> ExplodedView:
    """The exploded view of a full assembly sequence (:mod:`planner.assembly.explode`): ``sequence`` is a rank
    (among the sequences from ``base_part``) or the operations themselves; the base part (``"auto"``
    resolved) also decides which side of each operation moves."""
    base = base_part_of(plan, base_part)
    operations = sequence_at(plan, sequence, base) if isinstance(sequence, (int, np.integer)) else list(sequence)
    return exploded_view(plan, operations, spacing, base)


def sequence_from_log(path: str | os.PathLike, plan: Plan | None = None,
                      inputs: InputLimits = InputLimits()) -> tuple[list[int], LoggedSequence]:
    """The sequence a session log recorded (:func:`~planner.runtime.logged_sequence.logged_sequence`), completed
    by the first continuation when the session stopped early, as operations of ``plan`` (default: the plan of
    the product the log stores). Raises :class:`PlannerError` when the log's operations are not operations
    of ``plan`` (a log of another product). ``inputs``: the limits the log is read within."""
    logged = logged_sequence(path, inputs)
    operations = complete_sequence(logged.plan, list(logged.operations))
    if plan is None:
        return operations, logged
    index = {frozenset(plan.andor.inputs(j)): j for j in range(len(plan.andor.operations))}
    mapped = []
    for operation in operations:
        inputs = logged.plan.andor.inputs(operation)
        if frozenset(inputs) not in index:
            raise PlannerError(f"{path}: the logged operation {logged.plan.andor.describe(operation)} is not an "
                               f"operation of {plan.product.name or 'this product'}; the log was recorded for "
                               f"{logged.product.name or 'another product'} (parts: {', '.join(logged.plan.andor.parts)})")
        mapped.append(index[frozenset(inputs)])
    return mapped, logged


def plan_statistics_of(product: str | os.PathLike | Product | Plan, technical: bool | None = None,
                       base_part: str | None = None, limits: SizeLimits = SizeLimits(),
                       partial: bool = False) -> tuple[Plan | None, PlanStatistics]:
    """The plan and its figures (``aplan stats``). ``base_part``: count only the sequences whose first
    operation joins it, and their intentions; ``"auto"``: the most connected part (:func:`base_part_of`). With
    ``partial``, a plan past ``limits`` gives the figures that could be counted (the others None, the reason in
    ``refused``) and no plan, instead of :class:`~planner.errors.LimitExceededError`."""
    if isinstance(product, Plan) or not partial:
        plan = product if isinstance(product, Plan) else plan_of(product, technical, limits)
        return plan, plan_statistics(plan, base_part_of(plan, base_part))
    product = product if isinstance(product, Product) else resolve_product(product)
    base = most_connected_part(fold(product).product) if base_part == AUTO_BASE_PART else base_part
    with _gaps_explained(product):
        return statistics_within(product, technical, base, limits)
