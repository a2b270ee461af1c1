"""The paper's decision model (Cramer et al. 2021, Alg. 3): a POMDP over the operator's intentions, built
from a plan, as an :class:`IntentionModel` that keeps the plan and the intention graph beside the tables.

Definitions (these match the authors' code, checked against the POMDPX files it writes):

- States: the operator intentions (vertices of the intention graph, :mod:`planner.intentions`).
- Actions: the robot-capable operations, in AND/OR graph order, then ``wait``.
- Transitions: after ``wait`` the operator may perform the next step of intention ``i``: uniform over
  ``{i}`` and its successor. After the operation that is ``i``'s next step, the robot has performed it:
  the intention moves to that successor ``i'``, and then uniform over ``{i'}`` and the successor of ``i'``
  (the operator may act too). Any other action leaves ``i`` unchanged. The finished product is absorbing.
- Observations: what the operator is seen picking (:mod:`planner.tags`). In intention ``i``, uniform over the
  distinct observations of the operations that could have led to ``i`` (the steps of ``i``'s predecessors),
  with the blank observation (a missed detection) at a quarter of that weight; blank with certainty when
  nothing leads to ``i`` (the full sequences, where assembly starts). It does not depend on the action.
- Rewards: ``wait`` 0; ``i``'s next step +10 when it is unfavorable to humans, else -2; any other operation
  -50 (all four configurable: the paper's "eagerness").
- Initial belief: uniform over the full sequences.

With operator habits (:mod:`~planner.decision.habits`: a weight per state edge), the initial belief is
proportional to the product of the weights along each full sequence instead, and a reset (an unexplained
observation, :class:`~planner.decision.belief.DiscreteUpdater`) spreads by the same prior weights
(``intention_weights``). The transitions do not change: an intention is a whole path, so the operator's choices
are in the intention itself, and the habits say which paths are likely (in the factored and lumped models,
whose classes sum over completions, they enter the transitions).

With deviations (:mod:`~planner.decision.deviations`: change of mind and mistakes), the operator's steps
redraw the intention among those of its state before they stay or advance, and the observation table mixes in
a uniform one; ``world`` keeps the paper's tables for simulated worlds.

With a base part (paper Sec. V), the states are the intentions of the sequences that start from it
(:func:`~planner.assembly.intentions.intention_graph` with ``base_part``) and the same definitions apply to
that graph: the observations of an intention are those of its predecessors *in it*, and the initial belief is
uniform over the allowed full sequences.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..assembly.guards import OPTIONS, Progress, default_memory_budget, memory_options
from ..assembly.intentions import DEFAULT_INTENTION_LIMIT, IntentionGraph, count_intentions, intention_graph
from ..assembly.plan import Plan
from ..defaults import BLANK_WEIGHT, DISCOUNT, STAY
from ..errors import LimitExceededError, MemoryLimitError, PlannerError
from .deviations import Deviations, flat_deviation_entries, flat_tables
from .pomdp import POMDP
from .orders import check_alone

__all__ = ["Rewards", "WAIT", "IntentionModel", "intention_model", "intention_pomdp", "flat_model_bytes",
           "check_flat_model", "flat_model_fits", "intention_weights"]

WAIT = "wait"

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Rewards:
    """Rewards of Alg. 3: for the intention's next step (unfavorable / favorable to humans), for any other
    operation (the robot's eagerness: the more negative, the longer it waits to be sure), and for waiting."""

    unfavorable: float = 10.0
    favorable: float = -2.0
    wrong: float = -50.0
    wait: float = 0.0


@dataclass(frozen=True)
class IntentionModel:
    """The decision model of one plan: the POMDP of Alg. 3 and what its numbers mean.

    ``pomdp``: the tables (the *model* that solvers, policies and belief updaters work on); its state ``i``
    is intention ``i`` of ``graph`` (0 is the finished product) and its action ``k`` performs the AND/OR
    operation ``action_operations[k]`` of ``plan`` (-1: wait, the last action). ``rewards``: those the
    tables were built with. ``prior_weights``: each intention's prior weight under operator habits (what a
    reset spreads by), None for the paper's model. Build it with :func:`intention_model`.
    """

    plan: Plan
    graph: IntentionGraph
    pomdp: POMDP
    action_operations: np.ndarray
    rewards: Rewards
    prior_weights: np.ndarray | None = None
    deviations: Deviations | None = None  # change of mind and mistakes (deviations.py), None for the paper's
    world: POMDP | None = None  # with deviations: the paper's tables, which a simulated world plays

    @property
    def name(self) -> str:
        return self.pomdp.name

    @property
    def actions(self) -> tuple[str, ...]:
        return self.pomdp.actions

    @property
    def observations(self) -> tuple[str, ...]:
        return self.pomdp.observations

    @property
    def final_state(self) -> int:
        """The finished product's intention (absorbing)."""
        return 0

    @property
    def base_part(self) -> str | None:
        """The part every sequence starts from (paper Sec. V), or None when all sequences are allowed."""
        return self.graph.base_part

    def operation(self, action: int) -> int | None:
        """The AND/OR operation the robot performs for ``action``; None for ``wait``."""
        operation = int(self.action_operations[action])
        return None if operation < 0 else operation

    def full_sequences(self) -> np.ndarray:
        """The intentions that are full assembly sequences (where assembly starts), in increasing order."""
        return self.graph.full_sequences()

    def full_sequence(self, intention: int, what: str = "intention") -> int:
        """``intention`` when it is a full assembly sequence, else a :class:`PlannerError` that lists them
        (``what`` names it in the message, e.g. ``--sequence``)."""
        starts = self.full_sequences()
        if int(intention) not in set(starts.tolist()):
            base = f" --base-part {self.base_part}" if self.base_part else ""
            raise PlannerError(f"{what} {intention} is not a full assembly sequence; the sequences are the "
                               f"intentions {starts[0]}..{starts[-1]} (see aplan intentions PRODUCT --full{base})")
        return int(intention)

    def sequence_operations(self, intention: int) -> list[int]:
        """The operations, in order, that lead from ``intention`` to the finished product."""
        return self.graph.operations(intention)

    def describe_operations(self, intention: int) -> list[str]:
        """:meth:`sequence_operations` as text (``ink+cartridge``, ...)."""
        return [self.plan.andor.describe(o) for o in self.sequence_operations(intention)]


def _transitions(graph: IntentionGraph, robot_ops: np.ndarray) -> list[sp.csr_matrix]:
    """T(i' | i, a) of each action (module docstring), the robot's operations first, then ``wait``."""
    n = graph.n_intentions
    states = np.arange(n)
    step = graph.operation  # operation of each intention's next step (-1 at the finished product)
    has_next = graph.successor >= 0
    after = np.where(has_next, graph.successor, states)  # the intention after one more step (itself at the end)

    def uniform_step(origin: np.ndarray, rows: np.ndarray) -> sp.csr_matrix:
        # From each row: uniform over {origin} and origin's successor (origin alone at the end).
        moves = after[origin] != origin
        cols = np.concatenate([origin, after[origin][moves]])
        rr = np.concatenate([rows, rows[moves]])
        vals = np.concatenate([np.where(moves, STAY, 1.0), np.full(moves.sum(), STAY)])
        return sp.csr_matrix((vals, (rr, cols)), shape=(n, n))

    transition = []
    progress = Progress(log)
    for done, op in enumerate(robot_ops):
        progress.report("flat decision model: transition tables of %d of %d actions", done, len(robot_ops) + 1)
        doing = has_next & (step == op)  # the robot performs the intention's next step
        stay = ~doing
        performed = uniform_step(after[states[doing]], states[doing])
        kept = sp.csr_matrix((np.ones(stay.sum()), (states[stay], states[stay])), shape=(n, n))
        transition.append((performed + kept).tocsr())
    transition.append(uniform_step(states, states))  # wait
    return transition


def _observations(plan: Plan, graph: IntentionGraph) -> sp.csr_matrix:
    """O(z | i) (the same for every action): uniform over the observations of the steps that lead into ``i``
    (its predecessors' next steps), the blank one at a quarter of that weight."""
    n = graph.n_intentions
    states = np.arange(n)
    step, successor = graph.operation, graph.successor
    preds = np.flatnonzero(successor >= 0)
    pairs = np.unique(np.stack([successor[preds], plan.operation_observation[step[preds]]], axis=1), axis=0)
    pairs = pairs[pairs[:, 1] != 0]  # an operation that looks like waiting adds nothing beyond the blank
    count = np.bincount(pairs[:, 0], minlength=n).astype(float)
    weight = 1.0 / (count + BLANK_WEIGHT)
    rows = np.concatenate([pairs[:, 0], states])
    cols = np.concatenate([pairs[:, 1], np.zeros(n, dtype=np.int64)])
    vals = np.concatenate([weight[pairs[:, 0]], BLANK_WEIGHT * weight])
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, len(plan.observations)))


def _rewards(plan: Plan, graph: IntentionGraph, robot_ops: np.ndarray, rewards: Rewards) -> np.ndarray:
    """R(i, a) as an (A, I) array: the intention's next step, any other operation, or waiting."""
    step = graph.operation
    action_of_op = np.full(len(plan.andor.operations), -1)
    action_of_op[robot_ops] = np.arange(len(robot_ops))
    reward = np.full((len(robot_ops) + 1, graph.n_intentions), rewards.wrong, dtype=float)
    reward[-1] = rewards.wait
    nexts = np.flatnonzero((graph.successor >= 0) & (action_of_op[np.maximum(step, 0)] >= 0))
    reward[action_of_op[step[nexts]], nexts] = np.where(plan.tags.unfavorable[step[nexts]], rewards.unfavorable,
                                                        rewards.favorable)
    return reward


def intention_weights(graph: IntentionGraph, weights: np.ndarray) -> np.ndarray:
    """Each intention's prior weight: the product of the edge ``weights`` (one per state edge) along its path
    (1 for the final intention), scaled so that the largest is 1 (exactly 1 everywhere when every weight is 1).
    Cost: O(I x length): intentions are numbered by length, a successor before its intention."""
    log_w = np.log(np.append(np.asarray(weights, dtype=float), 1.0))  # the last entry: no step (final intention)
    step = np.where(graph.step_edge >= 0, graph.step_edge, len(log_w) - 1)
    has_next = graph.successor >= 0
    after = np.maximum(graph.successor, 0)
    total = np.zeros(graph.n_intentions)
    for _ in range(len(graph.states.andor.parts)):  # a path has fewer steps than the product has parts
        total = log_w[step] + np.where(has_next, total[after], 0.0)
    return np.exp(total - total.max())


# Bytes per intention and action (a transition row of 1.02 entries on average: float64 + int32 column, an
# int32 row pointer; a float64 reward) and per intention (the intention graph, its names, the initial belief).
# Measured peaks (chain 7-9, complete 5-6): 25 to 34 bytes per intention and action in all.
_BYTES_PER_INTENTION_ACTION = 28
_BYTES_PER_INTENTION = 200


def flat_model_bytes(plan: Plan, intentions: int | None = None) -> int:
    """The memory :func:`intention_model` would take for ``plan``, from counts alone (nothing is enumerated).

    About ``28 I A + 200 I`` bytes for I intentions and A actions (robot operations + wait): the dense
    reward table (A x I float64) and one sparse transition table per action (about one entry per row).
    ``intentions``: the number of intentions the model would hold, when not all of the plan's (e.g. only
    those of the sequences from a base part); by default :func:`~planner.assembly.count_intentions`.
    Cost: O(state edges).
    """
    count = count_intentions(plan.states) if intentions is None else int(intentions)
    actions = int(plan.tags.robot.sum()) + 1
    return count * (_BYTES_PER_INTENTION_ACTION * actions + _BYTES_PER_INTENTION)


_FLAT_OPTIONS = [OPTIONS[k] for k in ("online", "base_part")]


def check_flat_model(plan: Plan, max_bytes: int | None = None, limit: int | None = DEFAULT_INTENTION_LIMIT,
                     intentions: int | None = None) -> int:
    """The estimate :func:`flat_model_bytes`, after checking it against ``max_bytes`` (by default the
    machine's budget, :func:`~planner.assembly.guards.default_memory_budget`) and the intention count against
    ``limit`` (None: no limit): raises :class:`~planner.errors.MemoryLimitError` or
    :class:`~planner.errors.LimitExceededError` naming the sizes and what helps. Cost: O(state edges)."""
    count = count_intentions(plan.states) if intentions is None else int(intentions)
    needed = flat_model_bytes(plan, count)
    budget = default_memory_budget() if max_bytes is None else max_bytes
    actions = int(plan.tags.robot.sum()) + 1
    hint = ("The flat model enumerates every intention (every path of assembly states to the finished "
            "product); the factored model and the online planner need no enumeration.")
    if needed > budget:
        raise MemoryLimitError("flat decision model", needed, budget,
                               f"{count:,} intentions x {actions:,} actions", hint,
                               _FLAT_OPTIONS + memory_options(needed))
    if limit is not None and count > limit:
        raise LimitExceededError("flat decision model", count, limit, hint, _FLAT_OPTIONS, noun="intentions")
    return needed


def flat_model_fits(plan: Plan, max_bytes: int | None = None, limit: int | None = DEFAULT_INTENTION_LIMIT,
                    intentions: int | None = None) -> bool:
    """Whether :func:`intention_model` would build the flat model within ``max_bytes`` and ``limit`` (the
    arguments of :func:`check_flat_model`), e.g. to choose the online planner instead. Cost: O(state edges)."""
    try:
        check_flat_model(plan, max_bytes, limit, intentions)
    except LimitExceededError:
        return False
    return True


def intention_model(plan: Plan, rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                     graph: IntentionGraph | None = None, limit: int = DEFAULT_INTENTION_LIMIT,
                     base_part: str | None = None, max_bytes: int | None = None,
                     weights: np.ndarray | None = None, deviations: Deviations | None = None,
                     orders=None) -> IntentionModel:
    """The decision model of Alg. 3 over the intentions of ``plan`` (definitions in the module docstring).
    ``weights``: a positive weight per state edge (operator habits, module docstring), None for the paper's.
    ``orders``: the orders' model (:class:`~planner.decision.orders.OrdersPrior` of ``plan``): its prior over
    the full sequences (:meth:`~planner.decision.orders.OrdersPrior.intention_weights`) in place of weights.
    ``deviations``: change of mind and mistakes (:mod:`~planner.decision.deviations`; their tables are checked
    against ``max_bytes`` too), None for the paper's.

    ``graph``: the plan's intention graph when it was built already. Before anything is built the model's
    size is estimated (:func:`check_flat_model`): more than ``limit`` intentions (when ``graph`` is to be
    built), or more than ``max_bytes`` (default: the machine's budget), is refused with
    :class:`~planner.errors.LimitExceededError`. ``base_part``: only the sequences that start from this part
    (the graph must then be restricted to it too; :class:`PlannerError` if not).
    Cost: O(I x A) for the reward table and O(I) for the sparse tables, I intentions, A actions.
    """
    if graph is None:
        check_flat_model(plan, max_bytes, limit, count_intentions(plan.states, base_part=base_part))
    else:  # enumerated already: only its tables are to come
        check_flat_model(plan, max_bytes, None, graph.n_intentions)
    graph = graph if graph is not None else intention_graph(plan.states, limit, base_part)
    if graph.base_part != base_part:
        raise PlannerError(f"the intention graph starts from base part {graph.base_part!r}, the model from "
                           f"{base_part!r}; build them with the same base part")
    robot_ops = np.flatnonzero(plan.tags.robot)
    if deviations is not None:
        _check_deviation_tables(plan, graph, len(robot_ops), deviations, max_bytes)
    transition = _transitions(graph, robot_ops)
    table = _observations(plan, graph)
    initial = np.zeros(graph.n_intentions)
    starts = graph.full_sequences()
    prior = None
    if orders is not None:
        check_alone(weights, base_part, False, deviations)
        prior = orders.intention_weights(graph)
        initial[starts] = prior[starts] / prior[starts].sum()
        prior.flags.writeable = False
    elif weights is None:
        initial[starts] = 1.0 / len(starts)
    else:
        weights = np.asarray(weights, dtype=float)
        if weights.shape != (plan.states.n_edges,) or not np.all(np.isfinite(weights)) or np.any(weights <= 0):
            raise PlannerError(f"edge weights must be {plan.states.n_edges} finite numbers above 0 (one per state "
                               "edge)")
        prior = intention_weights(graph, weights)
        initial[starts] = prior[starts] / prior[starts].sum()
        prior.flags.writeable = False
    names = tuple(f"i{i}" for i in range(graph.n_intentions))
    actions = tuple(f"a{k}:" + plan.andor.describe(int(op)).replace(" ", "") for k, op in enumerate(robot_ops))
    reward = _rewards(plan, graph, robot_ops, rewards)
    world = None
    if deviations is not None:  # the paper's tables stay for a simulated world (its operator deviates itself)
        world = POMDP(names, actions + (WAIT,), tuple(str(o) for o in plan.observations), tuple(transition),
                      tuple(table for _ in transition), reward, initial, discount, name="world")
        transition, table = flat_tables(graph, robot_ops, transition, table, prior, deviations)
    observation = tuple(table for _ in transition)  # one object: solvers and updaters share its products
    pomdp = POMDP(names, actions + (WAIT,), tuple(str(o) for o in plan.observations), tuple(transition),
                  observation, reward, initial, discount, name=plan.product.name or "aplan")
    action_operations = np.append(robot_ops, -1)
    action_operations.flags.writeable = False
    return IntentionModel(plan, graph, pomdp, action_operations, rewards, prior, deviations, world)


def _check_deviation_tables(plan: Plan, graph: IntentionGraph, n_robot: int, deviations: Deviations,
                            max_bytes: int | None) -> None:
    """Refuse, before they are built, the deviations' tables past ``max_bytes`` (12 bytes per entry, twice for
    the sparse products that make them)."""
    entries = flat_deviation_entries(graph, n_robot, len(plan.observations), deviations)
    needed = 24 * entries
    budget = default_memory_budget() if max_bytes is None else max_bytes
    if needed > budget:
        raise MemoryLimitError("flat decision model with change of mind and mistakes", needed, budget,
                               f"{entries:,} table entries (a redraw over every intention of a state)",
                               "The factored model and the online planner (--planner online) hold a change of mind "
                               "in the classes of each state instead.", _FLAT_OPTIONS + memory_options(needed))


def intention_pomdp(plan: Plan, rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                    graph: IntentionGraph | None = None, limit: int = DEFAULT_INTENTION_LIMIT,
                    base_part: str | None = None, max_bytes: int | None = None,
                    weights: np.ndarray | None = None, deviations: Deviations | None = None) -> POMDP:
    """The tables alone of :func:`intention_model` (for solvers, files and comparisons with other planners)."""
    return intention_model(plan, rewards, discount, graph, limit, base_part, max_bytes, weights, deviations).pomdp
