"""The class-MDP bounds on the factored model's value (paper Sec. V): what the online planner
(:mod:`~planner.decision.online`) bounds its search with and the lumped model's solver starts from
(:mod:`~planner.decision.solvers.warm_start`).

- :func:`class_values`: QMDP on the classes (the robot knows the operator's every next step in advance);
- :func:`revealed_state_values`: the robot knows the class now and every assembly state from then on, but not
  the operator's next steps; far below QMDP, still above the true value.

Both are one backward pass over the assembly states, level by level from the final state
(:func:`_level_blocks`), sharing their set-up and the finished class (:func:`_backward_pass`); the state graph
is acyclic but for the self-loops of waiting, solved in closed form. Cost: O(S + E).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .deviations import switch_terms, switch_wait_values
from .factored_model import FactoredIntentionModel
from .parallel_values import parallel_level, parallel_q_matrix, parallel_q_values, parallel_tries

__all__ = ["ClassValues", "class_values", "revealed_state_values", "VALUE_BLOCK"]


@dataclass(frozen=True)
class ClassValues:
    """The class MDP's values (QMDP on the factored model): ``value[c]`` and, per class, the Q-values of
    waiting, of performing its next step (``match``: -inf where no robot action performs it) and of any other
    operation (``wrong``)."""

    value: np.ndarray
    wait: np.ndarray
    match: np.ndarray
    wrong: np.ndarray
    state: np.ndarray | None = None  # per assembly state, where known: the value when the robot knows the state
    parallel: np.ndarray | None = None  # per parallel pair (the parallel model): its Q-value

    def q_values(self, model: FactoredIntentionModel, belief: FactoredBelief) -> np.ndarray:
        """``sum_c b(c) Q(c, a)`` for every action (an upper bound on each action's value). Cost: O(k + A)."""
        classes, mass = belief.classes, belief.mass
        out = np.full(len(model.action_operations), float(mass @ self.wrong[classes]))
        out[-1] = float(mass @ self.wait[classes])
        act = model.class_action[classes]
        hit = act >= 0
        out[:-1] += np.bincount(act[hit], weights=mass[hit] * (self.match[classes[hit]] - self.wrong[classes[hit]]),
                                minlength=out.size - 1)
        parallel_q_values(model, self, classes, mass, out)
        return out


    def q_matrix(self, model: FactoredIntentionModel) -> np.ndarray:
        """``Q(c, a)`` as a dense (A, classes) array (a solver's starting upper bound on the lumped model)."""
        out = np.tile(self.wrong, (len(model.action_operations), 1))
        out[-1] = self.wait
        hit = np.flatnonzero(model.class_action >= 0)
        out[model.class_action[hit], hit] = self.match[hit]
        parallel_q_matrix(model, self, out)
        return out


VALUE_BLOCK = 1_000_000  # classes per block of the backward passes: bounds their temporaries (about 100 MB)


def _level_blocks(model: FactoredIntentionModel, block: int = VALUE_BLOCK):
    """Ranges ``[lo, hi)`` of states, level by level from the one next to the final state, each inside one
    level and with at most ``block`` classes (a state with more is a range alone). A level's states depend
    only on earlier levels, so the backward passes give the same values over any split of a level, and
    their temporaries stay within a block's size."""
    level_start = model.plan.states.level_start
    start = model.state_class_start
    for k in range(1, len(level_start) - 1):
        lo, hi = int(level_start[k]), int(level_start[k + 1])
        if lo >= hi:
            return
        while lo < hi:
            end = int(np.searchsorted(start, start[lo] + block, side="right")) - 1  # the most that fit
            end = min(hi, max(end, lo + 1))
            yield lo, end
            lo = end


@dataclass
class _Pass:
    """What both backward passes share: the discount ``g``, rewards ``r``, whether the robot has actions, the
    finished product's value, the change-of-mind terms and the per-class tables, the finished class filled."""

    g: float
    r: object
    has_robot: bool
    final_value: float
    sigma: float
    top: object
    value: np.ndarray
    wait: np.ndarray
    match: np.ndarray
    wrong: np.ndarray
    pair_q: np.ndarray | None

    def values(self, state: np.ndarray | None = None) -> ClassValues:
        """The tables, read-only, as :class:`ClassValues` (``state``: the per-state values, if any)."""
        for array in (self.value, self.wait, self.match, self.wrong) + ((state,) if state is not None else ()):
            array.flags.writeable = False
        return ClassValues(self.value, self.wait, self.match, self.wrong, state, self.pair_q)


def _backward_pass(model: FactoredIntentionModel) -> _Pass:
    """The set-up of a backward pass over ``model``'s assembly states (:func:`_level_blocks` gives its order):
    ``V(final) = max(R_wait, R_wrong) / (1 - g)`` (``R_wait / (1 - g)`` without robot actions), the finished
    class's Q-values from it, empty tables for the others. Cost: O(classes)."""
    g, r = model.discount, model.rewards
    n = model.n_classes
    has_robot = len(model.action_operations) > 1
    final_value = (max(r.wait, r.wrong) if has_robot else r.wait) / (1 - g)
    sigma, top = switch_terms(model)
    value, wait, match, wrong = (np.empty(n) for _ in range(4))
    fc = model.final_class
    value[fc], wait[fc], wrong[fc], match[fc] = final_value, r.wait + g * final_value, r.wrong + g * final_value, -np.inf
    pair_q = np.empty(model.parallel.size) if model.parallel is not None else None
    return _Pass(g, r, has_robot, final_value, sigma, top, value, wait, match, wrong, pair_q)


def class_values(model: FactoredIntentionModel) -> ClassValues:
    """QMDP on the classes, by one backward pass over the assembly states (fewest blocks first).

    Definitions (``t`` the target of class ``c``, ``W(t) = sum over the classes c' from t of fraction(c')
    V(c')`` the value on arriving at ``t`` and ``W2(t) = sum fraction(c') W(target(c'))`` one step later;
    both ``V(final)`` at the final state; ``g`` the discount):

    - ``Q_wait(c) = R_wait + g (V(c) + W(t)) / 2``,
    - ``Q_match(c) = R_match(c) + g (W(t) + W2(t)) / 2`` (the robot performs ``c``'s step; the operator may
      perform one more),
    - ``Q_wrong(c) = R_wrong + g V(c)``,

    and ``V(c)`` is the largest of the three, where each self-loop is solved in closed form: ``(R_wait + g
    W(t) / 2) / (1 - g / 2)`` for waiting, ``R_wrong / (1 - g)`` for stalling. ``V(final) = max(R_wait,
    R_wrong) / (1 - g)`` (``R_wait / (1 - g)`` without robot actions). Cost: O(S + E).
    """
    run = _backward_pass(model)
    g, r, has_robot, sigma, top, pair_q = run.g, run.r, run.has_robot, run.sigma, run.top, run.pair_q
    value, wait, match, wrong = run.value, run.wait, run.match, run.wrong
    arrive = np.full(len(model.paths), np.nan)  # W(t)
    later = np.full(len(model.paths), np.nan)   # W2(t)
    arrive[model.final_state] = later[model.final_state] = run.final_value
    redraws = np.full(len(model.paths), np.nan) if sigma else None  # a redraw's value per state (the pairs')
    for lo, hi in _level_blocks(model):  # states with k + 1 blocks: their targets are done already
        classes = model.state_classes[model.state_class_start[lo]:model.state_class_start[hi]]
        target, source = model.class_target[classes], model.class_source[classes]
        w, w2 = arrive[target], later[target]
        stay_wait = (r.wait + g * w / 2) / (1 - g / 2)
        stall = np.full(classes.size, r.wrong / (1 - g)) if has_robot else np.full(classes.size, -np.inf)
        can = model.class_action[classes] >= 0
        m = np.where(can, model.class_match_reward[classes] + g * (w + w2) / 2, -np.inf)
        v = np.maximum(np.maximum(stay_wait, stall), m)
        other = np.maximum(stall, m)
        parallel_level(model, classes, v, value, arrive, pair_q, redraws, other)
        wait[classes] = r.wait + g * (v + w) / 2
        if sigma:  # a change of mind couples a state's classes: waiting's value by a fixed point per state
            v, x = switch_wait_values(model, classes, source - lo, hi - lo, w, other, top)
            wait[classes] = r.wait + g * ((1 - sigma) * (v + w) + sigma * x) / 2
            if pair_q is not None:  # the pairs' Q-values with the final V(c) (their fixed points are in it)
                redraws[source] = x
                parallel_level(model, classes, v, value, arrive, pair_q, redraws)
        value[classes], match[classes] = v, m
        wrong[classes] = r.wrong + g * v
        fraction = model.class_fraction[classes]
        size = hi - lo
        arrive[lo:hi] = np.bincount(source - lo, weights=fraction * v, minlength=size)
        later[lo:hi] = np.bincount(source - lo, weights=fraction * w, minlength=size)
    return run.values()


def revealed_state_values(model: FactoredIntentionModel, known: ClassValues | None = None) -> ClassValues:
    """A tighter upper bound than :func:`class_values`: the value if the robot knew the class now and, from
    then on, every assembly state (not the operator's next steps), learning the next step outright when an
    operation it tries is not it. That is more than the robot ever knows, so it bounds the value from above;
    and it is far below QMDP, which lets the robot know every next step in advance.

    With ``f(c)`` the fractions of the classes out of a state and ``Q(c)`` the class values of ``known``
    (:func:`class_values`), per state ``t`` (robot knows ``t``, not its next step): ``A(t) = sum_c f(c) VT(target
    c)``; trying the step of class ``c`` is worth ``f(c) M(c) + (1 - f(c)) (R_wrong + g K(c))`` with ``M(c) =
    R_match(c) + g (VT(target c) + A(target c)) / 2`` and ``K(c)`` the mean of ``Q`` over the other classes out
    of ``t``; waiting ``(R_wait + g A(t) / 2) / (1 - g / 2)``; stalling ``R_wrong / (1 - g)``; ``VT(t)`` the
    largest. Per class: ``Q_match(c) = M(c)``, ``Q_wait(c) = R_wait + g (V(c) + VT(target c)) / 2``,
    ``Q_wrong(c) = R_wrong + g V(c)``, ``V(c)`` the largest (self-loops in closed form). One backward pass over
    the assembly states: O(S + E).
    """
    # Only the class values of ``known`` are read: its other tables are dropped at once (24 bytes a class less).
    known_value = (known if known is not None else class_values(model)).value
    run = _backward_pass(model)
    g, r, sigma, top, pair_q = run.g, run.r, run.sigma, run.top, run.pair_q
    value, wait, match, wrong = run.value, run.wait, run.match, run.wrong
    S = len(model.paths)
    stall = r.wrong / (1 - g) if run.has_robot else -np.inf
    revealed = np.full(S, np.nan)   # VT(t)
    arrive = np.full(S, np.nan)     # A(t)
    revealed[model.final_state] = arrive[model.final_state] = run.final_value
    redraws = np.full(S, np.nan) if sigma else None  # a redraw's value per state (the pairs')
    for lo, hi in _level_blocks(model):
        classes = model.state_classes[model.state_class_start[lo]:model.state_class_start[hi]]
        target, source, f = model.class_target[classes], model.class_source[classes] - lo, model.class_fraction[classes]
        can = model.class_action[classes] >= 0
        m = np.where(can, model.class_match_reward[classes] + g * (revealed[target] + arrive[target]) / 2, -np.inf)
        arrive[lo:hi] = np.bincount(source, weights=f * revealed[target], minlength=hi - lo)
        others = np.bincount(source, weights=f * known_value[classes], minlength=hi - lo)[source] - f * known_value[classes]
        rest = 1 - f
        tried = np.where(rest > 1e-12, f * m + rest * r.wrong + g * others, m)  # others already carries the weights
        tried = np.where(can, tried, -np.inf)
        best = np.full(hi - lo, -np.inf)
        np.maximum.at(best, source, tried)
        v = np.maximum(np.maximum((r.wait + g * revealed[target] / 2) / (1 - g / 2), stall), m)
        other = np.maximum(stall, m)
        if sigma:  # after a redraw the robot knows the state, not the class: at most the classes' mean
            if pair_q is not None:
                parallel_level(model, classes, v, value, revealed, pair_q, redraws, other)
            v, x = switch_wait_values(model, classes, source, hi - lo, revealed[target], other, top)
            wait[classes] = r.wait + g * ((1 - sigma) * (v + revealed[target]) + sigma * x) / 2
            if pair_q is not None:
                redraws[lo + source] = x
        if pair_q is not None:  # the parallel model: the pairs in V(c), and every try (a match or a pair) at t
            parallel_level(model, classes, v, value, revealed, pair_q, redraws)
            best = parallel_tries(model, classes, source, hi - lo, m, can, pair_q, known_value)
        revealed[lo:hi] = np.maximum(np.maximum((r.wait + g * arrive[lo:hi] / 2) / (1 - g / 2), stall), best)
        if not sigma:
            wait[classes] = r.wait + g * (v + revealed[target]) / 2
        value[classes], match[classes] = v, m
        wrong[classes] = r.wrong + g * v
    return run.values(revealed)
