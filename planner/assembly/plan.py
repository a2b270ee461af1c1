"""A plan: the AND/OR graph, assembly state graph, tags and observations of one product, built once."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..product import FastenerGroup, Product, fold
from .andor import AndOrGraph, and_or_graph, connected_sets_bound, liaison_adjacency
from .guards import SizeLimits
from .state_count import StateCount, count_states, count_unconstrained, is_unconstrained
from .states import AssemblyStateGraph, assembly_state_graph, check_counted
from .tags import (Observation, OperationTags, fastener_installs, join_observation_table, observation_table,
                   operation_tags)

__all__ = ["Plan", "make_plan", "with_join_observations", "count_before_andor", "check_before_andor",
           "guarded_state_graph"]


@dataclass(frozen=True)
class Plan:
    """Everything the planner derives from a product before the decision model.

    ``product`` has its technical constraints switched as requested and its fastener groups folded
    (:mod:`planner.product.fasteners`): ``fasteners`` are those groups (hosts resolved), ``installs[k]`` the
    operations that install group ``k``, and ``designed`` the product before folding (what a session log
    stores, so that replaying it folds the same groups). ``operation_observation[j]`` is the index in
    ``observations`` of operation ``j``'s observation (``observations[0]`` is the blank one).
    """

    product: Product
    andor: AndOrGraph
    states: AssemblyStateGraph
    tags: OperationTags
    observations: list[Observation]
    operation_observation: np.ndarray
    fasteners: tuple[FastenerGroup, ...] = ()
    installs: tuple[np.ndarray, ...] = ()
    designed: Product | None = None

    @property
    def folded_parts(self) -> int:
        """The fastener parts folded into operations."""
        return sum(len(group.parts) for group in self.fasteners)


def make_plan(product: Product, technical: bool | None = None, limits: SizeLimits = SizeLimits()) -> Plan:
    """Build the AND/OR graph (reverse cut-set), the assembly state graph (Alg. 1) and the tags of ``product``.

    ``technical``: ``True``/``False`` switches every technical constraint on/off, ``None`` keeps the file's.
    The product's fastener groups are folded into the operations that install them.
    ``limits``: the AND/OR graph's work and the state graph's memory; past them a
    :class:`~planner.errors.LimitExceededError` says how far it got and what helps.
    The intention graph is built on request (:func:`planner.intention_graph`), since it can be huge.
    """
    folding = fold(product.with_technical(technical))
    product, groups = folding.product, folding.groups
    check_before_andor(product, limits)
    andor = and_or_graph(product, limit=limits.subassemblies)
    installs = fastener_installs(andor, groups)
    tags = operation_tags(andor, product, groups, installs)
    observations, operation_observation = observation_table(andor, tags, groups, installs)
    counted = count_states(andor, liaison_adjacency(product))
    states = guarded_state_graph(andor, limits, int(tags.robot.sum()) + 1, counted)
    return Plan(product, andor, states, tags, observations, operation_observation, groups, installs,
                folding.original)


def with_join_observations(plan: Plan) -> Plan:
    """``plan`` with the observations of a camera that sees the pieces joined (one per operation:
    :func:`~planner.assembly.tags.join_observation_table`) in place of the paper's. Cost: O(operations x
    parts)."""
    observations, seen = join_observation_table(plan.andor, plan.tags, plan.fasteners, plan.installs)
    return replace(plan, observations=observations, operation_observation=seen)


def _reserve(limits: SizeLimits, actions: int):
    return None if limits.reserve is None else (lambda states, edges: limits.reserve(states, edges, actions))


def count_before_andor(product: Product, limits: SizeLimits) -> StateCount | None:
    """The states (exact) and state edges (from below) of an unconstrained product, counted on its connection
    diagram (:func:`~planner.assembly.state_count.count_unconstrained`) before the AND/OR graph; None for a
    constrained product, or one whose connected part sets the AND/OR graph refuses at once anyway. Cost: at
    most :data:`~planner.assembly.state_count.COUNT_WORK` subsets."""
    if not is_unconstrained(product) or len(product.parts) < 2:
        return None
    adjacency = liaison_adjacency(product)
    if connected_sets_bound(adjacency) > limits.subassemblies:
        return None
    return count_unconstrained(adjacency)


def check_before_andor(product: Product, limits: SizeLimits, counted: StateCount | None = None) -> None:
    """Refuse at once, before the AND/OR graph, a product whose counted states (``counted``, by default
    :func:`count_before_andor`) would not fit in ``limits`` with what the command builds on them (counted
    with one action: a bound from below)."""
    counted = count_before_andor(product, limits) if counted is None else counted
    if counted is not None:
        check_counted(counted, len(product.parts), limits.memory, _reserve(limits, 1), limits.reserve_for)


def guarded_state_graph(andor: AndOrGraph, limits: SizeLimits, actions: int,
                        counted: StateCount | None) -> AssemblyStateGraph:
    """The assembly state graph of ``andor`` within ``limits``: refused at once past the budget when its
    states were counted (``counted``: :func:`~planner.assembly.state_count.count_states`, None where it cannot
    count), else built level by level with each level guarded; ``actions``: the model's actions, for
    ``limits.reserve``."""
    reserve = _reserve(limits, actions)
    if counted is not None:
        check_counted(counted, len(andor.parts), limits.memory, reserve, limits.reserve_for)
    return assembly_state_graph(andor, limits.memory, reserve, limits.reserve_for)
