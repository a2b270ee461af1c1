"""The memory budget of the decision layer: what each model, the online planner and the solver would take,
estimated from counts and checked against ``--max-memory`` before anything large is built.

The budget covers everything a command holds at once: the plan (its state graph), then what is built on it
(the factored model and the online planner's values, or the lumped model, or a solver's tables). Each check
adds the bytes already held to the estimate of the next step and raises
:class:`~planner.errors.MemoryLimitError` with the estimate, the counts it comes from and the options that
help. The reserves (:func:`online_limits`, :func:`lumped_limits`) let the plan itself stop as soon as it
and what comes after would not fit (:class:`~planner.assembly.guards.SizeLimits`), so that a refusal costs
little: the states are counted before they are built where they can be.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..assembly.guards import OPTIONS, SizeLimits, memory_options
from ..assembly.plan import Plan
from ..assembly.states import state_graph_bytes
from ..errors import MemoryLimitError, gib
from .factored_model import factored_model_bytes
from .intention_model import _BYTES_PER_INTENTION, _BYTES_PER_INTENTION_ACTION, flat_model_bytes
from .lumped_model import lumped_pomdp_bytes
from .bounds import VALUE_BLOCK
from .parallel import parallel_bytes, parallel_candidates, parallel_flag
from .joins import JOINS
from .projected import PROJECTED, projected_bytes, projected_candidates
from .pomdp import POMDP
from .solvers.tables import pomdp_bytes, solver_bytes

__all__ = ["class_values_bytes", "online_planner_bytes", "plan_bytes", "online_bytes", "lumped_bytes", "online_limits",
           "lumped_limits", "flat_limits", "check_online_memory",
           "check_lumped_memory", "check_solver_memory", "check_flat_solver_memory", "lumped_start_fits",
           "check_parallel_memory"]

_HINT = "Plan with fewer parts (fold or group the fasteners), or one subassembly (one workstation) at a time."


def plan_bytes(plan: Plan) -> int:
    """The bytes a plan holds: its state graph's arrays and about 300 bytes of Python objects per subassembly
    and operation of its AND/OR graph. Cost: O(1)."""
    states = plan.states
    return state_graph_bytes(states.n_states, states.n_edges, len(plan.andor.parts)) + \
        300 * (len(plan.andor.subassemblies) + len(plan.andor.operations))


def class_values_bytes(n_classes: int, n_states: int) -> tuple[int, int]:
    """``(held, peak)``: the bytes the online planner's values hold
    (:func:`~planner.decision.bounds.revealed_state_values`: four float64 per class, one per state) and the most
    they take while computed, on top of the model: the held ones, the class values they start from (one
    float64 a class is kept) and the temporaries of one block of :data:`~planner.decision.bounds.VALUE_BLOCK`
    classes (about 14 float64 each). Held within 10 % above what is measured (chain 11, complete 7:
    tests/decision/test_memory_estimates.py; 32.8 bytes a class on chain 16 and 20, complete 9 and 10)."""
    held = 32 * n_classes + 8 * n_states + 16384  # and the arrays' headers, the model's caches
    return held, held + 8 * n_classes + 16 * n_states + 112 * min(n_classes, VALUE_BLOCK)


def online_planner_bytes(n_states: int, n_edges: int) -> int:
    """The most the factored model and the online planner's values take together, on top of the plan, for
    ``n_states`` states and ``n_edges`` state edges (the model's peak while built, or the model held and the
    values' peak: :func:`~planner.decision.factored_model.factored_model_bytes`, :func:`class_values_bytes`).
    From counts alone."""
    model_held, model_peak = factored_model_bytes(n_states, n_edges)
    return max(model_peak, model_held + class_values_bytes(n_edges + 1, n_states)[1])


def online_bytes(states: int, edges: int, actions: int = 1) -> int:
    """What the factored model and the online planner's values take on top of the plan
    (:func:`~planner.decision.online.online_planner_bytes`); ``actions`` does not matter."""
    return online_planner_bytes(states, edges)


def lumped_bytes(states: int, edges: int, actions: int) -> int:
    """What the factored model and its lumped POMDP take on top of the plan: the model's building peak, or
    the model held and the lumped tables' (:func:`~planner.decision.lumped_model.lumped_pomdp_bytes`)."""
    held, peak = factored_model_bytes(states, edges)
    return max(peak, held + lumped_pomdp_bytes(edges + 1, actions))


def online_limits(limits: SizeLimits) -> SizeLimits:
    """``limits`` with the factored model and the online planner's values reserved."""
    return limits if limits.reserve is not None else \
        replace(limits, reserve=online_bytes, reserve_for="the online planner (its factored model and values)")


def lumped_limits(limits: SizeLimits) -> SizeLimits:
    """``limits`` with the lumped model reserved."""
    return limits if limits.reserve is not None else \
        replace(limits, reserve=lumped_bytes, reserve_for="the lumped model")


def flat_limits(limits: SizeLimits, solving: bool = False) -> SizeLimits:
    """``limits`` with the flat model reserved (and, ``solving``, the solver beside it), counted from below:
    each of the E state edges' classes holds at least one intention, so the model holds at least E + 1."""
    if limits.reserve is not None:
        return limits

    def reserve(states: int, edges: int, actions: int) -> int:
        per_action = _BYTES_PER_INTENTION_ACTION + (_SOLVER_BYTES_PER_INTENTION_ACTION if solving else 0)
        return (edges + 1) * (per_action * actions + _BYTES_PER_INTENTION)

    return replace(limits, reserve=reserve, reserve_for="the flat decision model" + (" and the solver" if solving
                                                                                      else ""))


# The solver's tables and bounds per intention and action (solver_bytes with one transition entry per
# intention and action: three sparse copies, the block diagonal's triplets, seven dense (A, S) tables).
_SOLVER_BYTES_PER_INTENTION_ACTION = 128


def _check(what: str, needed: int, budget: int, detail: str, hint: str, options=()) -> None:
    if needed > budget:
        raise MemoryLimitError(what, needed, budget, detail, f"{hint} {_HINT}",
                               list(options) + memory_options(needed)
                               + [OPTIONS[k] for k in ("fasteners", "exclude", "group")])


def check_online_memory(plan: Plan, budget: int) -> None:
    """Refuse the factored model and the online planner's values of ``plan`` when, with the plan held, they
    would not fit in ``budget`` bytes. Cost: O(1)."""
    held = plan_bytes(plan)
    S, E = plan.states.n_states, plan.states.n_edges
    _check("online planner (factored model and values)", held + online_bytes(S, E), budget,
           f"{E + 1:,} classes over {S:,} assembly states, with the plan's {gib(held)}",
           "The factored model and the planner's bounds hold a few numbers per state edge.")


def check_lumped_memory(plan: Plan, budget: int) -> None:
    """Refuse the lumped model of ``plan`` when, with the plan held, it would not fit in ``budget`` bytes.
    Cost: O(1)."""
    held = plan_bytes(plan)
    S, E, A = plan.states.n_states, plan.states.n_edges, int(plan.tags.robot.sum()) + 1
    _check("lumped model", held + lumped_bytes(S, E, A), budget,
           f"{E + 1:,} classes x {A:,} actions, with the plan's {gib(held)}",
           "The lumped model has a transition entry and a reward per class and action; the online planner needs "
           "neither (aplan simulate/session --planner online).")


def _lumped_start_bytes(pomdp: POMDP, plan: Plan) -> tuple[int, int, int]:
    """What a lumped model's solver start takes besides the solver: the delayed-reveal graph (a row per class
    and action at least: its relaxed Q-values and rewards, about three (A, classes) float64 tables), the dense
    beliefs of its corner groups (one per state with two classes or more) and its sawtooth points (a dense
    belief per graph node, at least one per class, and their distinct copy)."""
    n, A = pomdp.n_states, pomdp.n_actions
    groups = int((np.bincount(plan.states.edge_source, minlength=plan.states.n_states) >= 2).sum())
    return 3 * 8 * A * n, 8 * groups * n, 16 * n * n


def lumped_start_fits(pomdp: POMDP, plan: Plan, budget: int) -> tuple[bool, bool]:
    """Whether the solver's corner groups and the delayed-reveal points of a lumped model fit in ``budget``
    beside the model, the plan and the solver (:func:`check_solver_memory`): each is an optional tightening
    of the upper bound, left out when it does not fit (the points first)."""
    held = pomdp_bytes(pomdp) + plan_bytes(plan) + solver_bytes(pomdp)
    graph, groups, points = _lumped_start_bytes(pomdp, plan)
    with_groups = held + graph + groups <= budget
    return with_groups, with_groups and held + graph + groups + points <= budget


def check_solver_memory(pomdp: POMDP, budget: int, plan: Plan | None = None, from_product: bool = True) -> None:
    """Refuse to solve ``pomdp`` when the solver's tables and bounds
    (:func:`~planner.decision.solvers.tables.solver_bytes`), with the model (and ``plan``, the lumped model's)
    held, would not fit in ``budget`` bytes; ``from_product``: the model is a product's flat model (the lumped
    one is offered then), not a model file. Cost: O(actions)."""
    held = pomdp_bytes(pomdp) + (plan_bytes(plan) + _lumped_start_bytes(pomdp, plan)[0] if plan is not None else 0)
    lumped = plan is not None or not from_product  # no lumped model to offer
    _check(f"the solver on {pomdp.name or 'the model'}", held + solver_bytes(pomdp), budget,
           f"{pomdp.n_states:,} states x {pomdp.n_actions:,} actions, with the model's {gib(held)}",
           "The solver keeps a few tables of one number per state and action."
           + ("" if lumped else " The lumped model (--lumped) solves the same problem over far fewer states."),
           [] if lumped else [("--lumped", "--lumped solves the lumped model (the same value over the state edges)")])


def check_flat_solver_memory(plan: Plan, intentions: int, budget: int) -> None:
    """Refuse, before the flat model is built, to solve it when the model and the solver would not fit in
    ``budget`` bytes: :func:`~planner.decision.intention_model.flat_model_bytes` and
    :func:`~planner.decision.solvers.tables.solver_bytes` with one transition entry per intention and action
    (what Alg. 3's tables hold, the robot's actions moving a few): about ``128 I A`` bytes. Cost: O(1)."""
    A, Z = int(plan.tags.robot.sum()) + 1, len(plan.observations)
    needed = plan_bytes(plan) + flat_model_bytes(plan, intentions) + \
        _SOLVER_BYTES_PER_INTENTION_ACTION * intentions * A + 8 * Z * intentions
    _check("the solver on the flat decision model", needed, budget, f"{intentions:,} intentions x {A:,} actions",
           "The solver keeps a few tables of one number per intention and action. The lumped model (--lumped) "
           "solves the same problem over far fewer states.",
           [("--lumped", "--lumped solves the lumped model (the same value over the state edges)")])


def check_parallel_memory(plan, budget: int, rule: bool | str = True) -> None:
    """Refuse the parallel model of ``plan`` (``rule``: True or ``next`` for :mod:`.parallel`'s pairs,
    ``projected`` for :mod:`.projected`'s) when the factored model, the online planner's values and the pairs,
    with the plan held, would not fit in ``budget`` bytes (:class:`~planner.errors.MemoryLimitError`, with the
    estimate and the options). Cost: O(E)."""
    states = plan.states
    projected = rule in (PROJECTED, JOINS)
    pairs = projected_bytes(states) if projected else parallel_bytes(states)
    needed = plan_bytes(plan) + online_bytes(states.n_states, states.n_edges) + pairs
    if needed > budget:
        count = projected_candidates(states) if projected else parallel_candidates(states)
        flag = parallel_flag(rule)
        raise MemoryLimitError(f"{'projected' if projected else 'parallel'} model (its pairs)", needed, budget,
                               f"{count:,} candidate pairs ({gib(pairs)}) beside the factored model",
                               f"Leave out {flag}, or plan a smaller product.", memory_options(needed))
