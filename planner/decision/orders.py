"""History-dependent operator habits (issue 23): a Pitman-Yor predictive mixture over the recorded *orders* (whole
sequences of state edges seen in the session logs), put into the decision models as a Markov chain on a
trie-augmented state graph (docs/habits.md, Orders).

Definition. With ``n_k`` the times order ``k`` was recorded, ``n`` their sum, ``K`` the distinct orders, ``a``
the concentration (``a > -d``) and ``d`` the discount (``0 <= d < 1``), a full sequence's prior is

    p(sigma) = sum_k pi_k [sigma == sigma_k] + pi_0 U(sigma),
    pi_k = max(n_k - d, 0) / (n + a),   pi_0 = (a + d K) / (n + a),

(fractional counts below ``d``: :func:`mixture_weights`), ``U`` the paper's prior (every full sequence equally likely: ``U(sigma) = 1 / N(initial)``; the base is the
paper's, not the per-state habits', because an operator off its habit draws any sequence, as Alg. 3 assumes).
``d = 0`` is the Dirichlet process; no orders is the paper's model exactly.

Augmented graph. A node is ``(assembly state, trie node)`` while the history so far is a prefix ``h`` of some
recorded order, else ``(assembly state, off)``; the finished product is one node whatever the history. From
the trie node of ``h`` the choice ``e`` has probability ``M(h.e) / M(h)``, ``M(h) = N(initial) sum over k
extending h of pi_k + pi_0 N(state of h)`` (``U(h) = N(state of h) / N(initial)``: the base's mass of the
sequences with prefix ``h``); off the trie it is the paper's ``N(target) / N(state)``. Each real sequence is
exactly one augmented path, and its product of choices is ``p(sigma)``. The factored and lumped models are built
unchanged on the augmented graph with the edge weights ``w = choice / (N(target) / N(state))`` (the weighted
path sums of :mod:`~planner.decision.factored_model`); the one thing taken from the real graph is the
observation table: a node emits what its assembly state emits (:func:`node_keys`), as in Alg. 3. Nodes are
numbered by (level, assembly state, trie node), so a node's out-edges come in the real state's order and a
sequence's rank (:meth:`~planner.decision.factored_sequences.FactoredSequences.sequence`) names the same
sequence as on the real graph. The flat model stays on the real graph with ``p(sigma)`` as its initial belief
(:meth:`OrdersPrior.intention_weights`): the equivalence flat = factored = lumped is checked in the tests.

Cost. Building: O(S + E + L D) for S states, E state edges, L recorded steps and D the largest out-degree
(the augmented graph has at most S + L nodes and E + L D edges); a belief update costs what it costs on the
factored model, over the classes the belief reaches (at most the out-edges of a state per trie node it is on).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..assembly.intentions import paths_to_final
from ..assembly.plan import Plan
from ..assembly.states import AssemblyStateGraph
from ..defaults import ORDERS_CONCENTRATION, ORDERS_DISCOUNT
from ..errors import PlannerError
from .habits import Habits, HabitsError, edge_counts, edge_keys, habit_weights

__all__ = ["OrdersPrior", "orders_prior", "order_edges", "check_orders_parameters", "mixture_weights",
           "prior_inputs", "node_keys", "real_plan", "check_alone", "PRIOR_MODELS"]

PRIOR_MODELS = ("counts", "orders")  # what a habits file's model uses: per-state counts, or the recorded orders


def check_orders_parameters(concentration, discount, where: str) -> tuple[float, float]:
    """``(a, d)`` as floats, or a :class:`HabitsError` naming ``where`` unless finite, ``0 <= d < 1`` and
    ``a > -d``."""
    for name, value in (("discount", discount), ("concentration", concentration)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise HabitsError(f"{where}: the orders' {name} must be a finite number, got {value!r}; the defaults "
                              f"are concentration {ORDERS_CONCENTRATION:g}, discount {ORDERS_DISCOUNT:g}")
    if not 0 <= discount < 1:
        raise HabitsError(f"{where}: the orders' discount d must be at least 0 and below 1, got {discount!r}")
    if not concentration > -discount:
        raise HabitsError(f"{where}: the orders' concentration a must be above -d = {-discount:g}, got "
                          f"{concentration!r}")
    return float(concentration), float(discount)


def mixture_weights(counts, concentration: float, discount: float, where: str = "orders") -> tuple[np.ndarray, float]:
    """``(pi_k, pi_0)`` of the module docstring for the orders' ``counts`` (n_k > 0). Fractional counts (a log
    that several sequences explain records each with its posterior weight, docs/habits.md, Learning from logs)
    are discounted by ``min(n_k, d)``: ``pi_k = (n_k - min(n_k, d)) / (n + a)``, ``pi_0 = (a + sum_k min(n_k, d))
    / (n + a)``, which is the module docstring's for every ``n_k >= d`` (so for every whole count) and still sums
    to 1 (``max(n_k - d, 0)`` with ``pi_0``'s ``d K`` would not, for ``n_k < d``): an order weighing less than
    the discount gives all of it to the base. Raises :class:`HabitsError` when ``a + sum_k min(n_k, d) <= 0``
    (``pi_0`` would not be a probability: a negative concentration with too little recorded), naming ``where``.
    Cost: O(K)."""
    counts = np.asarray(counts, dtype=float)
    n, taken = float(counts.sum()), np.minimum(counts, discount)
    base = concentration + float(taken.sum())
    if not base > 0:
        raise HabitsError(f"{where}: the orders' concentration {concentration:g} with discount {discount:g} and these counts "
                          f"(total {n:g}) leave the base a weight of {base:g}, not above 0; give a concentration above "
                          f"{-float(taken.sum()):g}")
    return (counts - taken) / (n + concentration), base / (n + concentration)


def order_edges(plan: Plan, habits: Habits) -> list[tuple[tuple[int, ...], float]]:
    """The recorded orders of ``habits`` as paths of ``plan``'s state edges from the initial to the final state,
    with their counts; a :class:`HabitsError` naming the file, the order and the fix when one is not such a
    path, its count is not a finite number above 0, or it is recorded twice. Cost: O(E + L)."""
    edge_counts(plan, habits)  # the same product and version, first
    index = {key: e for e, key in enumerate(edge_keys(plan))}
    states, out, seen = plan.states, [], set()
    fix = "fix or remove the order, or learn the habits again (aplan habits LOG... -o FILE)"
    for k, (steps, count) in enumerate(habits.orders):
        place = f"{habits.name}: orders[{k}]"
        if isinstance(count, bool) or not isinstance(count, (int, float)) or not math.isfinite(count) or count <= 0:
            raise HabitsError(f"{place}: count {count!r} is not a finite number above 0; {fix}")
        state, edges = states.initial, []
        for j, key in enumerate(steps):
            edge = index.get(tuple(key))
            if edge is None or int(states.edge_source[edge]) != state:
                raise HabitsError(f"{place}, step {j + 1}: {key[1]!r} at the state {key[0]!r} is not a step of this "
                                  f"product's state graph from {states.describe(state)}; {fix}")
            edges.append(edge)
            state = int(states.edge_target[edge])
        if state != states.final:
            raise HabitsError(f"{place}: the order stops at {states.describe(state)}, before the finished product "
                              f"(an order is a whole sequence); {fix}")
        if tuple(edges) in seen:
            raise HabitsError(f"{place}: the same order is recorded twice; keep one entry with the sum of the counts")
        seen.add(tuple(edges))
        out.append((tuple(edges), float(count)))
    return out


class AugmentedStateGraph(AssemblyStateGraph):
    """An :class:`AssemblyStateGraph` over augmented nodes (module docstring): ``node_state`` the assembly state
    of each node, ``edge_of`` the real state edge of each augmented edge, ``real`` the real graph."""

    def __init__(self, andor, blocks, level_start, edge_source, edge_target, edge_operation, node_state, edge_of,
                 real):
        super().__init__(andor, blocks, level_start, edge_source, edge_target, edge_operation)
        for name, value in (("node_state", node_state), ("edge_of", edge_of), ("real", real)):
            object.__setattr__(self, name, value)


@dataclass(frozen=True)
class OrdersPrior:
    """The orders' model of a plan (module docstring): ``plan`` the augmented plan (its ``states`` an
    :class:`AugmentedStateGraph`), ``weights`` per augmented edge, ``real`` the real plan, ``orders`` the
    recorded orders (real state edges) and counts, ``concentration`` and ``discount``; ``pi`` and ``pi0``
    the mixture weights; ``step`` a cache of :meth:`augmented_path`."""

    plan: Plan
    weights: np.ndarray
    real: Plan
    orders: tuple[tuple[tuple[int, ...], float], ...]
    concentration: float
    discount: float
    pi: np.ndarray
    pi0: float
    step: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)

    def augmented_path(self, edges) -> list[int]:
        """The augmented edges (the factored model's classes) of a path of real state edges from the initial
        state. Cost: O(length) after the first call's O(E') table of the augmented edges by (node, real edge)."""
        states = self.plan.states
        if not self.step:  # built once (the dataclass is frozen, its dict is not)
            self.step.update(((int(n), int(e)), k) for k, (n, e) in enumerate(zip(states.edge_source, states.edge_of)))
        node, out = states.initial, []
        for e in edges:
            k = self.step.get((node, int(e)))
            if k is None:
                raise HabitsError(f"state edge {int(e)} is not a step from the augmented node {node}")
            out.append(k)
            node = int(states.edge_target[k])
        return out

    def intention_weights(self, graph) -> np.ndarray:
        """Each intention's prior weight on the flat model over the real graph (:class:`IntentionGraph`),
        scaled so that the largest is 1: ``p(sigma) N(initial)`` for a full sequence; 1 (the base's choice off
        the trie) for the others, which only an unexplained observation's reset reads. Cost: O(I x length)."""
        out = np.zeros(graph.n_intentions)
        n_initial = float(_paths(self.real.states)[self.real.states.initial])
        orders = {order: pi for (order, _), pi in zip(self.orders, self.pi)}
        for i in graph.full_sequences():
            path, j = [], int(i)
            while graph.step_edge[j] >= 0:
                path.append(int(graph.step_edge[j]))
                j = int(graph.successor[j])
            out[i] = math.log(self.pi0 + n_initial * orders.get(tuple(path), 0.0))
        return np.exp(out - out.max())


def _paths(states) -> np.ndarray:
    levels = paths_to_final(states)
    return np.concatenate([level.astype(float) for level in levels])


def orders_prior(plan: Plan, habits: Habits) -> OrdersPrior | None:
    """The orders' model of ``habits`` on ``plan`` (checked: :func:`order_edges`), or None when no order is
    recorded (then it is the paper's model exactly). Cost: module docstring."""
    orders = order_edges(plan, habits)
    if not orders:
        return None
    a, d = check_orders_parameters(habits.concentration, habits.discount, habits.name)
    pi, pi0 = mixture_weights([c for _, c in orders], a, d, habits.name)
    states = plan.states
    S = states.n_states
    n = _paths(states)
    mass: dict[tuple[int, ...], float] = {}  # sum of pi_k over the orders extending each prefix (the empty one too)
    for (order, _), p in zip(orders, pi):
        for j in range(len(order) + 1):
            mass[order[:j]] = mass.get(order[:j], 0.0) + p
    # Trie nodes: the proper, non-empty prefixes (the empty one is the initial state, a whole order the final).
    prefixes = sorted({order[:j] for order, _ in orders for j in range(1, len(order))})
    prefix_state = [int(states.edge_target[h[-1]]) for h in prefixes]
    node_state = np.concatenate([np.arange(S), prefix_state]).astype(np.int64)
    trie = np.concatenate([np.full(S, -1), np.arange(len(prefixes))])
    order = np.lexsort((trie, node_state))  # by state (hence level), then off before the trie nodes
    new = np.empty_like(order)
    new[order] = np.arange(order.size)
    history = {(): int(new[states.initial])}
    history.update({h: int(new[S + k]) for k, h in enumerate(prefixes)})
    # Off the trie (every real state but the initial one, which is the trie's root): the real edges, weight 1.
    off = states.edge_source != states.initial
    source, target = [new[states.edge_source[off]]], [new[states.edge_target[off]]]
    real_edge, weight = [np.flatnonzero(off)], [np.ones(int(off.sum()))]
    n_initial = n[states.initial]
    by_source = np.argsort(states.edge_source, kind="stable")  # the out-edges of each state, in the edges' order
    out_start = np.searchsorted(states.edge_source[by_source], np.arange(S + 1))
    for h, node in history.items():  # on the trie: the mixture's choice (module docstring), O(L D) in all
        s = states.initial if not h else int(states.edge_target[h[-1]])
        for e in by_source[out_start[s]:out_start[s + 1]]:
            t = int(states.edge_target[e])
            longer = h + (int(e),)
            choice = (n_initial * mass.get(longer, 0.0) + pi0 * n[t]) / (n_initial * mass.get(h, 0.0) + pi0 * n[s])
            source.append([node])
            target.append([history.get(longer, new[t]) if t != states.final else new[t]])
            real_edge.append([int(e)])
            weight.append([choice / (n[t] / n[s])])
    source, target = np.concatenate(source).astype(np.int64), np.concatenate(target).astype(np.int64)
    real_edge, weight = np.concatenate(real_edge).astype(np.int64), np.concatenate(weight)
    by = np.lexsort((source, target))
    levels = np.searchsorted(states.level_start, node_state[order], side="right") - 1
    level_start = np.searchsorted(levels, np.arange(len(states.level_start))).astype(states.level_start.dtype)
    real_edge = real_edge[by]
    graph = AugmentedStateGraph(states.andor, states.blocks[node_state[order]], level_start,
                                source[by].astype(states.edge_source.dtype), target[by].astype(states.edge_target.dtype),
                                states.edge_operation[real_edge], node_state[order], real_edge, states)
    weights = weight[by]
    weights.flags.writeable = False
    return OrdersPrior(dataclasses.replace(plan, states=graph), weights, plan, tuple(orders), a, d, pi, pi0)


def node_keys(states, keys: np.ndarray, n_observations: int) -> np.ndarray:
    """The sorted ``node * Z + z`` observation keys of the augmented ``states`` from the real graph's ``keys``
    (``state * Z + z``, sorted): each node emits what its assembly state emits. Other graphs: ``keys``."""
    node_state = getattr(states, "node_state", None)
    if node_state is None:
        return keys
    Z = n_observations
    start = np.searchsorted(keys // Z, np.arange(states.real.n_states + 1))
    count = np.diff(start)[node_state]
    first = np.repeat(start[node_state] - np.cumsum(count) + count, count) + np.arange(int(count.sum()))
    return np.repeat(np.arange(node_state.size, dtype=np.int64), count) * Z + keys[first] % Z


def check_alone(weights=None, base_part=None, parallel=False, deviations=None) -> None:
    """The orders' model is built alone: a :class:`~planner.errors.PlannerError` naming what was given with it
    (per-state habits' weights, a base part, a parallel model, a change of mind or mistakes), which it does not
    combine with (their tables read the real graph's states)."""
    given = [name for name, on in (("per-state habits weights", weights is not None),
                                   ("--base-part", base_part is not None), ("--parallel/--projected/--joins", parallel),
                                   ("--switch/--mistakes", deviations is not None)) if on]
    if given:
        raise PlannerError(f"the orders' model (--model orders) does not combine with {' and '.join(given)}: leave "
                           f"{'it' if len(given) == 1 else 'them'} out, or use --model habits or confident")


def real_plan(plan: Plan) -> Plan:
    """The plan over the real assembly states: ``plan`` itself, or the real plan of an orders' augmented one (what
    a session's habits, logs and markers are about). Cost: O(1)."""
    real = getattr(plan.states, "real", None)
    return plan if real is None else dataclasses.replace(plan, states=real)


def prior_inputs(plan: Plan, habits: Habits | None) -> tuple[np.ndarray | None, OrdersPrior | None]:
    """What the models take for ``habits`` on ``plan``: ``(edge weights, None)`` for per-state counts
    (:func:`~planner.decision.habits.habit_weights`), ``(None, orders)`` for the orders' model (``habits``
    with ``prior_model == "orders"``), ``(None, None)`` for the paper's. Cost: that of the one built."""
    if habits is None or habits.prior_model != "orders":
        return habit_weights(plan, habits), None
    return None, orders_prior(plan, habits)
