"""The figures of a plan (the columns of Table I of Cramer et al. 2021, and more), as many as the size
limits allow."""
from __future__ import annotations

from dataclasses import dataclass, field

from ..errors import LimitExceededError, PlannerError
from ..product import FastenerGroup, Product, fold
from .andor import and_or_graph, liaison_adjacency
from .guards import SizeLimits
from .intentions import count_intentions, count_sequences, paths_to_final
from .plan import Plan, check_before_andor, count_before_andor, guarded_state_graph
from .state_count import count_states
from .tags import fastener_installs, observation_table, operation_tags

__all__ = ["STAT_KEYS", "PlanStatistics", "plan_statistics", "statistics_within"]

STAT_KEYS = ("parts", "contacts", "complexity", "subassemblies", "operations", "actions", "states",
             "state_edges", "intentions", "observations", "sequences")


@dataclass(frozen=True)
class PlanStatistics:
    """Figures of a plan.

    ``complexity`` is Lambert & Gupta's index 2K/N (K contacts, N parts), rounded to 2 decimals;
    ``actions`` = robot-capable operations + wait; ``observations`` counts the blank one;
    ``sequences`` counts full assembly sequences, those whose first operation joins ``base_part`` if set;
    ``intentions`` then counts the intentions of those sequences only (paper Sec. V).
    ``states`` and ``sequences`` together are the size of the factored view of paper Sec. V.
    ``fasteners``: the fastener groups folded (their parts are not counted in ``parts``), ``installs`` the
    number of operations that install each (None when the AND/OR graph was not built).
    Figures that could not be computed within the size limits are None, and ``refused`` says why.
    """

    parts: int
    contacts: int
    complexity: float
    subassemblies: int | None
    operations: int | None
    actions: int | None
    states: int | None
    state_edges: int | None
    intentions: int | None
    observations: int | None
    sequences: int | None
    base_part: str | None = None
    refused: LimitExceededError | None = field(default=None, compare=False)
    fasteners: tuple[FastenerGroup, ...] = field(default=(), compare=False)
    installs: tuple[int, ...] | None = field(default=None, compare=False)

    @property
    def folded_parts(self) -> int:
        """The fastener parts folded into operations (not counted in ``parts``)."""
        return sum(len(group.parts) for group in self.fasteners)

    @property
    def not_computed(self) -> tuple[str, ...]:
        """The figures (of :data:`STAT_KEYS`) left out because a size limit was reached."""
        data = self.as_dict()
        return tuple(key for key in STAT_KEYS if data[key] is None)

    def as_dict(self) -> dict:
        """Exactly the keys of :data:`STAT_KEYS` (None for a figure not computed)."""
        return {key: getattr(self, key) for key in STAT_KEYS}


def plan_statistics(plan: Plan, base_part: str | None = None) -> PlanStatistics:
    """Count everything without enumerating intentions or sequences (exact integers)."""
    product = plan.product
    n = len(product.parts)
    paths = paths_to_final(plan.states)
    return PlanStatistics(
        parts=n,
        contacts=len(product.contacts),
        complexity=round(2 * len(product.contacts) / n, 2),
        subassemblies=len(plan.andor.subassemblies),
        operations=len(plan.andor.operations),
        actions=int(plan.tags.robot.sum()) + 1,
        states=plan.states.n_states,
        state_edges=plan.states.n_edges,
        intentions=count_intentions(plan.states, paths, base_part),
        observations=len(plan.observations),
        sequences=count_sequences(plan.states, base_part, paths),
        base_part=base_part,
        fasteners=plan.fasteners,
        installs=tuple(len(operations) for operations in plan.installs) if plan.fasteners else None,
    )


def statistics_within(product: Product, technical: bool | None = None, base_part: str | None = None,
                      limits: SizeLimits = SizeLimits()) -> tuple[Plan | None, PlanStatistics]:
    """The plan of ``product`` and its figures, as far as ``limits`` allow.

    Fastener groups are folded first (:mod:`planner.product.fasteners`): the figures count the parts left.
    The plan is built stage by stage as :func:`~planner.assembly.make_plan` builds it: parts, contacts and
    complexity always; then the AND/OR graph (subassemblies, operations, actions, observations), the
    assembly state graph (states, state edges) and the counts (intentions, sequences). When a stage passes
    a limit (:class:`~planner.errors.LimitExceededError`, raised after at most the limit's worth of work),
    the figures of that stage and the later ones are None, ``refused`` is the error, and the plan is None.
    Other errors (a product that is not connected, not disassemblable, a base part that is not a part)
    are raised. Cost: that of the stages computed.
    """
    folding = fold(product.with_technical(technical))
    product, groups = folding.product, folding.groups
    if base_part is not None and base_part not in product.part_ids:
        raise PlannerError(f"base part {base_part!r} is not a part of the product; parts: "
                           f"{', '.join(product.part_ids)}")
    n = len(product.parts)
    figures = {"parts": n, "contacts": len(product.contacts), "complexity": round(2 * len(product.contacts) / n, 2)}
    try:
        early = count_before_andor(product, limits)
        if early is not None:  # its states are counted exactly: printed even when refused
            figures.update(states=early.states)
            check_before_andor(product, limits, early)
        andor = and_or_graph(product, limit=limits.subassemblies)
        installs = fastener_installs(andor, groups)
        tags = operation_tags(andor, product, groups, installs)
        observations, operation_observation = observation_table(andor, tags, groups, installs)
        figures.update(subassemblies=len(andor.subassemblies), operations=len(andor.operations),
                       actions=int(tags.robot.sum()) + 1, observations=len(observations))
        counted = count_states(andor, liaison_adjacency(product))
        if counted is not None:  # exact: printed even when the graph itself is refused
            figures.update(states=counted.states, state_edges=counted.edges)
        states = guarded_state_graph(andor, limits, figures["actions"], counted)
    except LimitExceededError as refused:
        return None, PlanStatistics(**{key: figures.get(key) for key in STAT_KEYS}, base_part=base_part,
                                    refused=refused, fasteners=groups)
    plan = Plan(product, andor, states, tags, observations, operation_observation, groups, installs, folding.original)
    return plan, plan_statistics(plan, base_part)
