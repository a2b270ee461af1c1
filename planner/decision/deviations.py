"""Change of mind and mistakes (issue 23, item 3; docs/deviations.md): two small probabilities that the decision
model gives the operator's deviations from one sequence, so that an observation no sequence explains moves the
belief instead of resetting it.

Definitions (``sigma`` = ``switch``, ``mu`` = ``mistake``; both 0 is the paper's model, table for table):

- Change of mind. Whenever the operator may act (the stay-or-advance step after ``wait``, and after the
  robot has performed the intention's next step), it first, with probability ``sigma``, abandons its sequence
  and draws a completion from the *current* assembly state by the prior (the paper's: every completion equally
  likely; with habits, by their weights); then it stays or advances as before. So the operator step ``W``
  becomes ``S W`` with ``S = (1 - sigma) I + sigma R``: on the flat model ``R`` takes intention ``i`` at state
  ``s`` to the intentions at ``s`` in proportion to their prior weights; on the classes (factored, lumped) it
  takes class ``(s, e)`` to the classes out of ``s`` by their prior share (:func:`switch_share`). A robot
  operation that is not the next step leaves the intention as it is (the operator does not act then). The
  redraw may give the same completion: the chance of a real change at ``s`` is ``sigma (1 - own share)``.
- Mistakes. The observation is, with probability ``mu``, one drawn uniformly from all ``Z`` observations (a
  wrong part or tool taken, blank included), else the model's: ``O'(z | i) = (1 - mu) O(z | i) + mu / Z``.
  No observation then has likelihood 0: the Bayes filter never resets.

Exactness. ``R`` maps any belief to one in proportion to the prior within classes, and ``S`` keeps that
property, so the lumped model stays exact (flat = factored = lumped, tests/decision/test_deviations.py).

Cost. Factored model: a prediction also spreads ``sigma`` of each state's mass over that state's classes:
O(k log k + the classes of the states reached). Lumped model: ``R`` has one row per class over the classes of its
source (nnz = sum over states of deg(s)^2), the observation table becomes dense ((E + 1) x Z numbers). Flat
model: ``R`` is dense per state, sum over states of n(s)^2 entries for n(s) intentions at s, checked before
anything is built (:func:`flat_deviation_entries`); its observation table is dense too (I x Z).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..defaults import STAY
from ..errors import PlannerError
from .factored_belief import FactoredBelief, _sum_by
from .step_observations import operator_advance, stay_part

__all__ = ["Deviations", "deviations_of", "check_probability", "switch_share", "operator_step", "mix_likelihood",
           "flat_deviation_entries", "flat_switch", "mixed_observations", "lumped_switch", "MistakeSplit",
           "switch_wait_values", "switch_terms", "with_mistakes", "belief_at_states", "flat_tables"]


@dataclass(frozen=True)
class Deviations:
    """The probabilities of the operator's deviations (module docstring): ``switch`` (change of mind, per
    operator step) and ``mistake`` (a wrong observation, per step), each in [0, 1)."""

    switch: float = 0.0
    mistake: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "switch", check_probability(self.switch, "the switch probability"))
        object.__setattr__(self, "mistake", check_probability(self.mistake, "the mistake probability"))

    def as_dict(self) -> dict:
        return {"switch": self.switch, "mistake": self.mistake}


def check_probability(value, what: str) -> float:
    """``value`` as a float when it is a finite number in [0, 1), else a :class:`PlannerError` naming ``what``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) \
            or not 0.0 <= value < 1.0:
        raise PlannerError(f"{what} must be a number in [0, 1), got {value!r}")
    return float(value)


def deviations_of(switch: float = 0.0, mistake: float = 0.0) -> Deviations | None:
    """The :class:`Deviations`, or None when both are 0 (the paper's model: nothing changes, byte for byte)."""
    deviations = Deviations(switch, mistake)
    return None if deviations.switch == 0 and deviations.mistake == 0 else deviations


# --- the factored model ----------------------------------------------------------------------------------

def switch_share(model) -> np.ndarray:
    """Per class of a factored model: its share of a redraw at its source state, the prior's ``class_fraction``
    (normalised over the allowed first classes at the initial state with a base part; 0 for the others there).
    Cost: O(E)."""
    share = np.asarray(model.class_fraction, dtype=float).copy()
    if model.base_part is not None:
        first = model.classes_from(model.plan.states.initial)
        share[first] = 0.0
        allowed = model.initial_classes
        share[allowed] = model.class_fraction[allowed] / model.class_fraction[allowed].sum()
    return share


def operator_step(model, classes: np.ndarray, mass: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """``S W`` on a factored belief's (classes, mass), as pieces for the model's ``_combine``: the switch
    (``sigma`` of each unfinished class's mass to its state's classes by :func:`switch_share`), then stay or
    advance one step, 1/2 each (the final class stays). Cost: O(k log k + the classes of the states)."""
    sigma = model.deviations.switch
    final = model.final_class
    if sigma > 0:
        moving = classes != final
        states, per_state = _sum_by(model.class_source[classes[moving]], sigma * mass[moving], len(model.paths))
        drawn, count = model.starting_at(states)
        share = model.switch_share[drawn]
        classes = np.concatenate([classes, drawn])
        mass = np.concatenate([np.where(moving, (1 - sigma) * mass, mass), np.repeat(per_state, count) * share])
    moving = classes != final
    half = np.where(moving, STAY * mass, mass)
    return [stay_part(model, classes, half), operator_advance(model, classes[moving], half[moving])]


def mix_likelihood(likelihood: np.ndarray, mistake: float, n_observations: int) -> np.ndarray:
    """``(1 - mu) O + mu / Z`` (module docstring)."""
    return (1.0 - mistake) * likelihood + mistake / n_observations


# --- the flat model --------------------------------------------------------------------------------------

def _per_state(graph) -> np.ndarray:
    return np.bincount(graph.first_state, minlength=graph.states.n_states).astype(np.int64)


def flat_deviation_entries(graph, n_robot: int, n_observations: int, deviations: Deviations) -> int:
    """The table entries the flat model takes with ``deviations``, from the intentions per state: per switch
    table about ``sum n(s) (2 n(s))`` (a redraw over the ``n(s)`` intentions at ``s``, then a step), for wait
    and each robot action's rows; ``I x Z`` for the dense observation table. Cost: O(I + S)."""
    n = _per_state(graph)
    entries = 0
    if deviations.switch > 0:
        entries += (1 + n_robot) * int((2 * n * n).sum())
    if deviations.mistake > 0:
        entries += graph.n_intentions * n_observations
    return entries


def flat_switch(graph, prior: np.ndarray | None, switch: float) -> sp.csr_matrix:
    """``S`` (I, I) CSR of the flat model: ``(1 - sigma) I + sigma R`` (module docstring), ``prior`` the
    intentions' weights (None: uniform). Cost: O(sum over states of n(s)^2)."""
    n = graph.n_intentions
    state = graph.first_state
    weight = np.ones(n) if prior is None else np.asarray(prior, dtype=float)
    total = np.bincount(state, weights=weight, minlength=graph.states.n_states)
    order = np.argsort(state, kind="stable")
    bounds = np.searchsorted(state[order], np.arange(graph.states.n_states + 1))
    count = np.diff(bounds)
    # Row i spreads over every intention j at i's state: for each state, its members x its members.
    rows = np.repeat(np.arange(n), count[state])
    starts = np.repeat(bounds[state], count[state])
    offsets = np.arange(rows.size) - np.repeat(np.cumsum(count[state]) - count[state], count[state])
    cols = order[starts + offsets]
    values = switch * weight[cols] / total[state[cols]]
    redraw = sp.csr_matrix((values, (rows, cols)), shape=(n, n))
    return (redraw + sp.identity(n, format="csr") * (1.0 - switch)).tocsr()


def mixed_observations(table: sp.csr_matrix, mistake: float) -> sp.csr_matrix:
    """``(1 - mu) O + mu / Z`` as a CSR table (dense: every observation possible in every state). Cost: O(S Z)."""
    dense = table.toarray() * (1.0 - mistake) + mistake / table.shape[1]
    return sp.csr_matrix(dense)


def lumped_switch(model) -> sp.csr_matrix:
    """``S`` over a factored model's classes: ``(1 - sigma) I + sigma R``, ``R`` taking class ``c`` to the classes
    of its source by :func:`switch_share` (the final class stays). Cost: O(sum over states of deg(s)^2)."""
    sigma = model.deviations.switch
    E = model.final_class
    source = model.class_source[:E].astype(np.int64)
    drawn, count = model.starting_at(source)
    rows = np.repeat(np.arange(E), count)
    redraw = sp.csr_matrix((sigma * model.switch_share[drawn], (rows, drawn)), shape=(E + 1, E + 1))
    keep = np.full(E + 1, 1.0 - sigma)
    keep[E] = 1.0
    return (redraw + sp.diags(keep)).tocsr()


# --- the online planner's observation split with mistakes ------------------------------------------------

class MistakeSplit:
    """One action's predicted belief split by observation when ``mu > 0`` (wraps the paper's split ``base``):
    each observation the belief emits has ``P'(z) = (1 - mu) P(z) + mu / Z``; every other observation has
    ``mu / Z`` and leaves the belief as predicted (its likelihood is the same for every class), so they are one
    branch (their posteriors are equal, and so are their values). Upper bounds per branch mix likewise."""

    def __init__(self, model, base, value: np.ndarray | None):
        self.model = model
        self.classes, self.mass = base.classes, base.mass
        mu = model.deviations.mistake
        Z = len(model.plan.observations)
        total = float(self.mass.sum())
        mean = float(self.mass @ value[self.classes]) if value is not None else 0.0
        branches = []
        for z, p, upper in base.branches:
            mixed = (1 - mu) * p + mu * total / Z
            branches.append((z, mixed, ((1 - mu) * p * upper + mu * mean / Z) / mixed))
        emitted = {z for z, _, _ in base.branches}
        others = [z for z in range(Z) if z not in emitted]
        if others:  # one branch for all of them (the first one stands for the rest)
            branches.append((others[0], mu * total * len(others) / Z, mean / total if total > 0 else 0.0))
        self.branches = branches

    def posterior(self, z: int):
        weighted = self.mass * self.model.observation_likelihood(z, self.classes)
        keep = weighted > 0
        return FactoredBelief(self.classes[keep], weighted[keep] / weighted[keep].sum())


def with_mistakes(model, split, value: np.ndarray | None):
    """``split`` (the online planner's split by observation), or with mistakes its :class:`MistakeSplit`."""
    if model.deviations is not None and model.deviations.mistake:
        return MistakeSplit(model, split, value)
    return split


# --- the bounds: waiting's self-loop with a switch -------------------------------------------------------

def switch_terms(model) -> tuple[float, float]:
    """The change-of-mind probability (0 without deviations) and a value at least every class value
    (``max(R, 0) / (1 - g)``), where :func:`switch_wait_values` starts from."""
    sigma = model.deviations.switch if model.deviations is not None else 0.0
    r = model.rewards
    return sigma, max(r.unfavorable, r.favorable, r.wrong, r.wait, 0.0) / (1 - model.discount)


def switch_wait_values(model, classes: np.ndarray, source: np.ndarray, n_states: int, later: np.ndarray,
                       other: np.ndarray, top: float, sweeps: int = 500) -> tuple[np.ndarray, np.ndarray]:
    """The values ``V(c) = max(other(c), Q_wait(c))`` of the classes of one block of states (``source``: their
    state, numbered from 0 within the block) when waiting is ``Q_wait(c) = R_wait + g ((1 - sigma) (V(c) +
    later(c)) / 2 + sigma X(s) / 2)`` with ``X(s) = sum over the classes c' of s of share(c') (V(c') +
    later(c'))`` (``later``: the value when it advances). Per state a scalar fixed point in ``X``, iterated
    from ``2 top`` (``top`` at least every value and at least ``R_wait / (1 - g)``): the map is monotone, so
    every iterate stays above the fixed point and the values are upper bounds wherever it stops. Returns
    ``V`` and ``X`` per class. Cost: O(classes) per sweep, a handful of sweeps for small ``sigma``."""
    g, r_wait, sigma = model.discount, model.rewards.wait, model.deviations.switch
    share = model.switch_share[classes]
    X = np.full(n_states, 2.0 * top)
    for _ in range(sweeps):
        wait = (r_wait + g * (1 - sigma) * later / 2 + g * sigma * X[source] / 2) / (1 - g * (1 - sigma) / 2)
        value = np.maximum(other, wait)
        new = np.bincount(source, weights=share * (value + later), minlength=n_states)
        done = np.all(np.abs(new - X) <= 1e-12 * (1.0 + np.abs(X)))
        X = np.minimum(X, new)  # monotone from above: never let rounding climb
        if done:
            break
    wait = (r_wait + g * (1 - sigma) * later / 2 + g * sigma * X[source] / 2) / (1 - g * (1 - sigma) / 2)
    return np.maximum(other, wait), X[source]


def belief_at_states(model, states: list[int], weights: list[float] | None = None):
    """The prior over the completions of the assembly ``states`` (a step undone: the belief moves there), each
    state weighted by ``weights`` (default equal): on a factored model its classes by :func:`switch_share`, on
    a flat one its intentions by their prior weights. Cost: O(E) or O(I)."""
    weights = [1.0] * len(states) if weights is None else list(weights)
    total = float(sum(weights))
    if hasattr(model, "graph"):  # flat
        graph = model.graph
        prior = np.ones(graph.n_intentions) if model.prior_weights is None else np.asarray(model.prior_weights)
        out = np.zeros(graph.n_intentions)
        for s, w in zip(states, weights):
            at = graph.first_state == s
            out[at] += (w / total) * prior[at] / prior[at].sum()
        return out
    share = switch_share(model) if model.deviations is None else model.switch_share
    parts_c, parts_m = [], []
    for s, w in zip(states, weights):
        classes = model.classes_from(int(s))
        parts_c.append(classes)
        parts_m.append((w / total) * share[classes] / share[classes].sum())
    classes, mass = _sum_by(np.concatenate(parts_c).astype(np.int64), np.concatenate(parts_m), model.n_classes)
    return FactoredBelief(classes, mass)


def flat_tables(graph, robot_ops: np.ndarray, transition: list, observation: sp.csr_matrix,
                prior: np.ndarray | None, deviations: Deviations) -> tuple[list, sp.csr_matrix]:
    """The flat model's transition and observation tables with ``deviations``, from the paper's
    (``transition``: one per robot action, then wait): wait becomes ``S W``; the rows where a robot action
    performs the intention's next step become that step, then ``S W``; the other rows stay. Cost: that of
    :func:`flat_switch` and one sparse product per action."""
    if deviations.switch > 0:
        wait = (flat_switch(graph, prior, deviations.switch) @ transition[-1]).tocsr()
        n = graph.n_intentions
        step = graph.operation
        has_next = graph.successor >= 0
        after = np.where(has_next, graph.successor, np.arange(n))
        tables = []
        for op in robot_ops:
            doing = has_next & (step == op)
            select = sp.csr_matrix((np.ones(n), (np.arange(n), np.where(doing, after, np.arange(n)))), shape=(n, n))
            moved = sp.diags(doing.astype(float)) @ select @ wait
            tables.append((moved + sp.diags((~doing).astype(float))).tocsr())
        transition = tables + [wait]
        for table in transition:
            table.sum_duplicates()
            table.eliminate_zeros()
    if deviations.mistake > 0:
        observation = mixed_observations(observation, deviations.mistake)
    return transition, observation
