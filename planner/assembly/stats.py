"""The figures of a plan (the columns of Table I of Cramer et al. 2021, and more)."""
from __future__ import annotations

from dataclasses import asdict, dataclass

from .intentions import count_intentions, count_sequences, paths_to_final
from .plan import Plan

__all__ = ["STAT_KEYS", "PlanStatistics", "plan_statistics"]

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
    """

    parts: int
    contacts: int
    complexity: float
    subassemblies: int
    operations: int
    actions: int
    states: int
    state_edges: int
    intentions: int
    observations: int
    sequences: int
    base_part: str | None = None

    def as_dict(self) -> dict:
        """Exactly the keys of :data:`STAT_KEYS`."""
        data = asdict(self)
        return {key: data[key] for key in STAT_KEYS}


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
    )
