"""Operator habits (issue 23; the paper's Sec. V "tuning the model to operator preferences using observations
recorded online"): how often this operator took each next operation at each assembly state, and the weights
that put those choices into the decision model in place of Alg. 3's uniform choice.

Definition. The paper's model holds every full sequence equally likely (uniform initial belief over them).
Read as a choice made step by step, that is choosing state edge ``e`` out of state ``s`` with probability
``p0(e | s) = N(target e) / N(s)``, ``N`` the number of paths to the finished product (each completion equally
likely) -- not ``1 / deg(s)``, which would favour the sequences through states of few choices. Habits are the
Dirichlet-multinomial posterior mean of the choice at ``s`` whose prior mean is that choice and whose weight is
``a(s)`` pseudo-observations at ``s``:

    p(e | s) = (n(s, e) + a(s) p0(e | s)) / (n(s) + a(s)),

``n(s, e)`` the times the operator was seen taking ``e`` at ``s``, ``n(s)`` their sum. The prior's spread
(``prior_per``) says what ``alpha`` counts: ``"edge"`` (the first definition, files written before the choice
existed) ``a(s) = alpha deg(s)``, alpha per next operation; ``"state"`` ``a(s) = alpha``, alpha in all at the
state, spread over its operations as the paper's model chooses -- so that a state of many operations does not
need many more sessions before the operator's own choices weigh (bench/README.md, Operator habits). Without
counts it is the paper's choice exactly; an operation never seen keeps a probability of at least
``a(s) p0 / (n(s) + a(s)) > 0``; with many counts it tends to the observed frequencies. A full sequence's prior
is the product of ``p(e | s)`` along it, i.e. the paper's ``1 / N(initial)`` times the *edge weights*

    w(e) = p(e | s) / p0(e | s) = (n(s, e) / p0(e | s) + a(s)) / (n(s) + a(s))

along it (exactly 1 at a state without counts, so habits without counts give the paper's model, bit for bit).
The models take those weights (``weights``): the flat model's initial belief is proportional to the product of
the weights of each full sequence, the factored and lumped models weigh their path counts by them (a weighted
path sum, the same dynamic programme; :mod:`~planner.decision.factored_model`).

Cost. Counting one observed step is O(1) (an increment of ``n(s, e)``); the weights are rebuilt from the counts
in O(S + E) for S states and E state edges, and so is the factored model's weighted path sum.

Identity. A habits file names the product and the *fingerprint* of its state graph (:func:`state_graph_fingerprint`:
a hash of the parts and of every state edge as ``state -> operation`` text), so habits learned on another
version of the product (other parts, operations or technical constraints) are refused instead of silently
misapplied.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from ..assembly.intentions import paths_to_final
from ..assembly.plan import Plan
from ..defaults import HABITS_PRIOR, ORDERS_CONCENTRATION, ORDERS_DISCOUNT
from ..errors import PlannerError

__all__ = ["Habits", "HabitsError", "state_graph_fingerprint", "edge_keys", "habits_from_counts", "edge_counts",
           "add_sequence", "choice_probabilities", "habit_weights", "habit_weights_from", "check_prior",
           "check_prior_per", "prior_pseudo_counts", "PRIOR_PER", "weighted_fractions"]

PRIOR_PER = ("edge", "state")  # what alpha counts (module docstring): per next operation, or in all per state


class HabitsError(PlannerError):
    """Habits that cannot be used: another product or version, bad counts, a damaged file."""


@dataclass(frozen=True)
class Habits:
    """Counts of the operator's choices: ``counts`` holds ``(state, operation, count)`` with the state and the
    operation as :func:`edge_keys` writes them; ``prior`` is ``alpha`` and ``prior_per`` what it counts
    (``"edge"`` or ``"state"``: module docstring); ``product`` and ``fingerprint`` name the plan they were counted
    on; ``source`` the file they were read from (for messages; "" in memory). ``orders``: the whole sequences
    recorded, each ``((state, operation), ...)`` and its count, with the Pitman-Yor ``concentration`` and
    ``discount`` over them; ``prior_model`` what the model uses, ``"counts"`` (per state, this module) or
    ``"orders"`` (:mod:`~planner.decision.orders`)."""

    product: str
    fingerprint: str
    prior: float
    counts: tuple[tuple[str, str, float], ...]
    source: str = ""
    prior_per: str = "edge"
    orders: tuple = ()
    concentration: float = ORDERS_CONCENTRATION
    discount: float = ORDERS_DISCOUNT
    prior_model: str = "counts"

    @property
    def total(self) -> float:
        """The number of choices counted."""
        return float(sum(c for _, _, c in self.counts))

    @property
    def name(self) -> str:
        return self.source or "the habits"


def check_prior(prior, where: str) -> float:
    """``prior`` (alpha) as a float, or a :class:`HabitsError` naming ``where`` unless finite and above 0."""
    if isinstance(prior, bool) or not isinstance(prior, (int, float)) or not np.isfinite(prior) or prior <= 0:
        raise HabitsError(f"{where}: the prior (alpha) must be a finite number above 0, got {prior!r}; the default "
                          f"is {HABITS_PRIOR:g}")
    return float(prior)


def check_prior_per(prior_per, where: str) -> str:
    """``prior_per`` if one of :data:`PRIOR_PER`, else a :class:`HabitsError` naming ``where``."""
    if prior_per not in PRIOR_PER:
        raise HabitsError(f"{where}: the prior's spread (prior_per) must be \"edge\" (alpha per next operation) or "
                          f"\"state\" (alpha in all per state), got {prior_per!r}")
    return prior_per


def edge_keys(plan: Plan) -> list[tuple[str, str]]:
    """Each state edge as readable text: ``(state, operation)``, e.g. ``("{ink} {cartridge} ...",
    "{ink} + {cartridge}")``; the pair names the edge (a state's operations lead to distinct states). Cost: O(E)."""
    states, describe = plan.states, plan.andor.describe
    names: dict[int, str] = {}
    out = []
    for s, o in zip(states.edge_source.tolist(), states.edge_operation.tolist()):
        if s not in names:
            names[s] = states.describe(s)
        out.append((names[s], describe(o)))
    return out


def state_graph_fingerprint(plan: Plan) -> str:
    """A hash of the plan's parts and state edges (16 hex digits): the same for the same state graph, and
    different, but for a hash collision, when a part, an operation or a technical constraint changes it.
    Cost: O(E log E)."""
    lines = sorted(f"{s} -> {o}" for s, o in edge_keys(plan))
    text = "parts: " + ", ".join(sorted(plan.andor.parts)) + "\n" + "\n".join(lines)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def _product_name(plan: Plan) -> str:
    return plan.product.name or "product"


def habits_from_counts(plan: Plan, counts: np.ndarray, prior: float = HABITS_PRIOR, source: str = "",
                       prior_per: str = "edge") -> Habits:
    """Habits of ``plan`` from per-state-edge ``counts`` (E,), keeping the edges counted (> 0)."""
    counts = np.asarray(counts, dtype=float)
    if counts.shape != (plan.states.n_edges,):
        raise HabitsError(f"{counts.shape[0] if counts.ndim else 0} counts for {plan.states.n_edges} state edges")
    if not np.all(np.isfinite(counts)) or np.any(counts < 0):
        raise HabitsError("habit counts must be finite and at least 0")
    keys = edge_keys(plan)
    kept = tuple((keys[e][0], keys[e][1], float(counts[e])) for e in np.flatnonzero(counts > 0))
    where = source or "habits"
    return Habits(_product_name(plan), state_graph_fingerprint(plan), check_prior(prior, where), kept, source,
                  check_prior_per(prior_per, where))


def _fix(habits: Habits) -> str:
    return ("learn them again for this product: aplan habits LOG... --product PRODUCT -o FILE (with the same "
            "--technical and --fasteners options), or leave out --habits (--model paper)")


def edge_counts(plan: Plan, habits: Habits) -> np.ndarray:
    """The counts of ``habits`` per state edge of ``plan`` (E,), after checking that they belong to it: the same
    product name and state-graph fingerprint, every key a state edge of it, counts finite and at least 0.
    Raises :class:`HabitsError` naming the file and the fix. Cost: O(E log E + entries)."""
    where = habits.name
    if habits.product != _product_name(plan):
        raise HabitsError(f"{where}: habits of the product {habits.product!r}, not of {_product_name(plan)!r}; "
                          + _fix(habits))
    fingerprint = state_graph_fingerprint(plan)
    if habits.fingerprint != fingerprint:
        raise HabitsError(f"{where}: habits of another version of {habits.product!r} (state graph "
                          f"{habits.fingerprint}, this one {fingerprint}: its parts, operations or technical "
                          "constraints differ); " + _fix(habits))
    index = {key: e for e, key in enumerate(edge_keys(plan))}
    out = np.zeros(plan.states.n_edges)
    for k, (state, operation, count) in enumerate(habits.counts):
        place = f"{where}: counts[{k}]"
        if isinstance(count, bool) or not isinstance(count, (int, float)) or not np.isfinite(count) or count < 0:
            raise HabitsError(f"{place}: count {count!r} is not a finite number of at least 0; fix or remove the entry")
        edge = index.get((state, operation))
        if edge is None:
            raise HabitsError(f"{place}: the state {state!r} has no operation {operation!r} in this product's "
                              "state graph; fix the entry, or " + _fix(habits))
        if out[edge]:
            raise HabitsError(f"{place}: the state {state!r} and operation {operation!r} are counted twice; "
                              "keep one entry")
        out[edge] = float(count)
    return out


def add_sequence(plan: Plan, counts: np.ndarray, operations: list[int], start: int | None = None,
                 counted: list[bool] | None = None, path: list[int] | None = None) -> int:
    """Add one to ``counts`` (E,) for each state edge that ``operations`` (AND/OR indices, in order) take from
    ``start`` (default: the initial state), only where ``counted`` is true if given (steps the robot did are
    walked, not counted: they are not the operator's choice); returns the state reached. Cost: O(1) per step
    after finding the edge among the state's out-edges. Raises :class:`HabitsError` when an operation is not
    possible there. ``path``, if given, gets each state edge taken appended (the order, :mod:`.orders`)."""
    states = plan.states
    state = states.initial if start is None else int(start)
    for k, operation in enumerate(operations):
        out = np.flatnonzero((states.edge_source == state) & (states.edge_operation == operation))
        if out.size == 0:
            raise HabitsError(f"step {k + 1}: {plan.andor.describe(int(operation))} is not an operation of the state "
                              f"{states.describe(state)}")
        if counted is None or counted[k]:
            counts[out[0]] += 1
        if path is not None:
            path.append(int(out[0]))
        state = int(states.edge_target[out[0]])
    return state


def _path_counts(plan: Plan) -> np.ndarray:
    levels = paths_to_final(plan.states)
    if any(level.dtype == object for level in levels):
        levels = [level.astype(object) for level in levels]
    return np.concatenate(levels)


def _paper_choice(plan: Plan) -> np.ndarray:
    """``p0(e | s) = N(target e) / N(s)`` per state edge (exact ratios of exact counts)."""
    counts = _path_counts(plan)
    states = plan.states
    return (counts[states.edge_target] / counts[states.edge_source]).astype(float)


def prior_pseudo_counts(plan: Plan, prior: float = HABITS_PRIOR, prior_per: str = "edge") -> np.ndarray:
    """``a(source e)`` per state edge (E,): the prior's pseudo-observations at the edge's state, ``alpha
    deg(s)`` for ``prior_per="edge"``, ``alpha`` for ``"state"`` (module docstring). Cost: O(S + E)."""
    states = plan.states
    if check_prior_per(prior_per, "habits") == "state":
        return np.full(states.n_edges, float(prior))
    return prior * np.bincount(states.edge_source, minlength=states.n_states).astype(float)[states.edge_source]


def choice_probabilities(plan: Plan, counts: np.ndarray, prior: float = HABITS_PRIOR,
                         prior_per: str = "edge") -> np.ndarray:
    """``p(e | s)`` per state edge (module docstring): they sum to 1 over each state's out-edges. Cost: O(S + E)."""
    return habit_weights_from(plan, counts, prior, prior_per) * _paper_choice(plan)


def habit_weights_from(plan: Plan, counts: np.ndarray, prior: float = HABITS_PRIOR,
                       prior_per: str = "edge") -> np.ndarray:
    """The edge weights ``w(e) = p(e | s) / p0(e | s)`` of per-edge ``counts`` (module docstring); exactly 1 at
    every state without counts. Cost: O(S + E)."""
    states = plan.states
    seen = np.bincount(states.edge_source, weights=counts, minlength=states.n_states)[states.edge_source]
    pseudo = prior_pseudo_counts(plan, prior, prior_per)
    return (counts / _paper_choice(plan) + pseudo) / (seen + pseudo)


def habit_weights(plan: Plan, habits: Habits | None) -> np.ndarray | None:
    """The edge weights the models take for ``habits`` on ``plan`` (checked: :func:`edge_counts`), or None
    (the paper's model) for no habits or habits without counts. Cost: O(S + E log E)."""
    if habits is None:
        return None
    counts = edge_counts(plan, habits)
    if not counts.any():
        return None
    return habit_weights_from(plan, counts, check_prior(habits.prior, habits.name),
                              check_prior_per(habits.prior_per, habits.name))


def weighted_fractions(states, target: np.ndarray, fraction: np.ndarray, weights
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The factored model's class fractions weighted by the edge ``weights`` (module docstring of
    :mod:`~planner.decision.factored_model`, Weights), the classes' weights (the final class 1) and
    ``log(w(c) R(target c))``, from the paper's ``fraction`` and the ``target`` (-1: the final class) per class.
    ``R(s) = W(s) / N(s)`` comes from one pass over the levels, the final state first: ``R(s) = sum over e out
    of s of w(e) p0(e) R(target e)``, ``p0`` the paper's fractions. Cost: O(S + E)."""
    E = states.n_edges
    w = np.asarray(weights, dtype=float)
    if w.shape != (E,) or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise HabitsError(f"edge weights must be {E} finite numbers above 0 (one per state edge)")
    edge_source, edge_target = states.edge_source, states.edge_target
    start = states.level_start
    relative = np.ones(states.n_states)
    step = w * fraction[:E]
    for k in range(1, len(start) - 1):  # the edges into level k - 1 come out of level k (sorted by target)
        lo, hi = np.searchsorted(edge_target, [start[k - 1], start[k]])
        size = int(start[k + 1] - start[k])
        if size == 0:
            break
        relative[start[k]:start[k + 1]] = np.bincount(edge_source[lo:hi] - start[k],
                                                      weights=step[lo:hi] * relative[edge_target[lo:hi]],
                                                      minlength=size)
    weighted = np.append(step * relative[edge_target] / relative[edge_source], 1.0)
    class_weights = np.append(w, 1.0)
    log_weight = np.log(class_weights) + np.log(relative[np.maximum(target, 0)])
    log_weight[-1] = 0.0
    return weighted, class_weights, log_weight
