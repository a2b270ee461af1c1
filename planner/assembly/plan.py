"""A plan: the AND/OR graph, assembly state graph, tags and observations of one product, built once."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..product import FastenerGroup, Product, fold
from .andor import AndOrGraph, and_or_graph
from .guards import SizeLimits
from .states import AssemblyStateGraph, assembly_state_graph
from .tags import Observation, OperationTags, fastener_installs, observation_table, operation_tags

__all__ = ["Plan", "make_plan"]


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
    andor = and_or_graph(product, limit=limits.subassemblies)
    states = assembly_state_graph(andor, limits.memory)
    installs = fastener_installs(andor, groups)
    tags = operation_tags(andor, product, groups, installs)
    observations, operation_observation = observation_table(andor, tags, groups, installs)
    return Plan(product, andor, states, tags, observations, operation_observation, groups, installs,
                folding.original)
