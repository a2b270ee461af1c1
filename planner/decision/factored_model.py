"""The factored decision model (paper Sec. V): Alg. 3's POMDP without enumerating intentions.

An intention ``i`` is its current assembly state ``s`` and its remaining path of state edges to the final
state. In Alg. 3 (:mod:`planner.decision.intention_model`) the observation table depends on ``i`` only
through ``s`` (the observations of the operations of the edges *into* ``s``), and the transitions and
rewards only through ``s`` and the first edge ``e`` of the remaining path (``wait``: stay or advance one
step, 1/2 each; the robot performing ``e``'s operation: advance one step, then stay or advance one more,
1/2 each; any other action: stay). The initial belief is uniform over the full sequences. So the belief
keeps the property "within the *class* of the edge ``e``, every completion of the path after ``e`` is equally
likely", and it is a vector of masses over the classes: one per state edge (its source is the current
state) plus one for the finished product.

Classes: ``c < E`` is state edge ``c``; ``c == E`` (``model.final_class``) is the finished product. With
``N(t)`` the number of paths from state ``t`` to the final state (:func:`~planner.assembly.paths_to_final`,
exact integers), class ``c`` holds ``N(target(c))`` intentions (1 for the final class), each with the flat
belief ``mass[c] / N(target(c))``. Advancing one step from class ``c`` moves its mass to the classes that
start at ``t = target(c)`` in proportion ``N(target(c2)) / N(t)`` (the final class when ``t`` is final);
those ratios are computed from the exact counts and are at most 1, so nothing overflows however many
intentions there are.

With a base part (paper Sec. V), the flat model's states are the intentions of the sequences that start from
it (:func:`~planner.assembly.intentions.intention_graph`): the initial belief goes to the allowed first classes
only (``initial_classes``, in proportion to their sizes), every class reachable from them holds all its
``N(target)`` intentions as before, and a state's observations are those of its *allowed* in-edges only
(:func:`~planner.assembly.intentions.allowed_edges`), as Alg. 3 on the restricted intention graph gives them.

Weights (operator habits, :mod:`~planner.decision.habits`): with a positive weight ``w(e)`` per state edge, an
intention's prior is proportional to the product of the weights along its path (the paper's model: every
weight 1). Counts become weighted path sums, ``W(s) = sum over the edges e out of s of w(e) W(target e)``
(``W(final) = 1``), the same dynamic programme; the model keeps ``R(s) = W(s) / N(s)`` (no overflow, and 1
everywhere for habit weights, which keep ``W = N``), a class's mass spreads over its completions in
proportion to their weights, and advancing moves it to the classes at ``t`` in proportion ``w(c2) W(target
c2) / W(t)`` (``class_fraction``). Nothing else changes, so the online planner, the lumped model and its
bounds, which read ``class_fraction``, work on the weighted model unchanged.

The parallel model (``parallel=True``, :mod:`~planner.decision.parallel`, docs/parallel.md) is a Markov model on
these classes: a robot action may also do the operator's step after next (``parallel``: the pairs), right with
the operator's chance of taking it then; :meth:`predict` and the rewards read the pairs, nothing else changes.
The projected model (``parallel="projected"``, :mod:`~planner.decision.projected`) has pairs of the same form:
any robot operation, right when the operator's remaining sequence projected onto the new state stays feasible.

The Bayes filter is :class:`~planner.decision.factored_updater.FactoredUpdater`. Beliefs are sparse (:class:`FactoredBelief`: sorted classes and their positive masses); an update costs
O(k log k) for the k classes the belief reaches after the action's steps (support, its out-edges and,
after the robot's action, their out-edges).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..assembly.intentions import allowed_edges, base_part_first_edges, paths_to_final
from ..assembly.plan import Plan, with_join_observations
from ..defaults import BLANK_WEIGHT, DISCOUNT, STAY
from ..errors import PlannerError
from .deviations import Deviations, mix_likelihood, operator_step, switch_share
from .factored_belief import FactoredBelief, _sum_by
from .factored_sequences import FactoredSequences
from .habits import weighted_fractions
from .intention_model import WAIT, Rewards
from .parallel import (ParallelTable, parallel_expected_rewards, parallel_predict, parallel_rewards,
                       parallel_table)
from .joins import JOINS, join_actions
from .orders import OrdersPrior, check_alone, node_keys
from .projected import PROJECTED, projected_table
from .step_observations import JOIN, STATE, check_observe, operator_advance, stay_part

__all__ = ["FactoredBelief", "FactoredIntentionModel", "factored_model", "factored_model_bytes"]


@dataclass(frozen=True)
class FactoredIntentionModel(FactoredSequences):
    """Alg. 3's POMDP over classes (module docstring); the same names as :class:`IntentionModel`.

    Per class (``E + 1`` entries): ``class_source`` (the current assembly state), ``class_target`` (after the
    step; -1 for the final class), ``class_operation`` (the step's AND/OR operation; -1 for the final
    class), ``class_fraction`` (``N(target) / N(source)``, 1 for the final class), ``class_log_size``
    (``log N(target)``, the log of the number of intentions in the class), ``class_action`` (the action that
    performs the step, -1 when none does), ``class_match_reward`` (the reward of performing it). Per state: ``state_classes``,
    ``state_class_start`` (CSR of the classes that start at each state), ``paths`` (``N`` per state, exact:
    int64 or Python ints), ``emit_weight`` (``1 / (k + 1/4)``, ``k`` distinct non-blank observations into the
    state), ``emit_keys`` (sorted ``state * Z + z`` of those observations). ``initial_classes``: the classes
    the full sequences may start with (sorted; all the initial state's out-edges unless ``base_part`` is set).
    ``weights`` (per class, 1 for the final class) and ``class_log_weight`` (``log(w(c) R(target c))``, so
    that ``class_log_size + class_log_weight`` is the log of the class's total prior weight): None for the
    paper's model (module docstring, Weights). Build with :func:`factored_model`.
    """

    plan: Plan
    rewards: Rewards
    discount: float
    action_operations: np.ndarray
    class_source: np.ndarray
    class_target: np.ndarray
    class_operation: np.ndarray
    class_fraction: np.ndarray
    class_log_size: np.ndarray
    state_classes: np.ndarray
    state_class_start: np.ndarray
    paths: np.ndarray
    emit_weight: np.ndarray
    emit_keys: np.ndarray
    class_action: np.ndarray
    class_match_reward: np.ndarray
    initial_classes: np.ndarray
    base_part: str | None = None
    weights: np.ndarray | None = None
    class_log_weight: np.ndarray | None = None
    parallel: ParallelTable | None = None  # the parallel model's pairs (docs/parallel.md); None: the paper's
    deviations: Deviations | None = None  # change of mind and mistakes (deviations.py), None for the paper's
    switch_share: np.ndarray | None = None  # per class, its share of a redraw at its state (with deviations)
    action_names: tuple[str, ...] | None = None  # actions named by joins (joins.py): their names; None: operations
    observe: str = STATE  # what an observation depends on: the state reached, or the step (step_observations.py)

    @property
    def name(self) -> str:
        return self.plan.product.name or "aplan"

    @property
    def actions(self) -> tuple[str, ...]:
        """The robot-capable operations in AND/OR order (named as in the flat model), then ``wait``; with actions
        named by joins (:mod:`~planner.decision.joins`), the joins."""
        if self.action_names is not None:
            return tuple(f"a{k}:{name}" for k, name in enumerate(self.action_names)) + (WAIT,)
        describe = self.plan.andor.describe
        robot = self.action_operations[:-1]
        return tuple(f"a{k}:" + describe(int(op)).replace(" ", "") for k, op in enumerate(robot)) + (WAIT,)

    @property
    def observations(self) -> tuple[str, ...]:
        """What the operator is seen picking; observation 0 is the blank one."""
        return tuple(str(o) for o in self.plan.observations)

    @property
    def n_classes(self) -> int:
        return int(self.class_source.shape[0])

    @property
    def final_class(self) -> int:
        """The finished product's class (absorbing); it holds the final intention alone."""
        return self.n_classes - 1

    @property
    def final_state(self) -> int:
        """The finished product's assembly state."""
        return self.plan.states.final

    @property
    def wait(self) -> int:
        return len(self.action_operations) - 1

    def operation(self, action: int) -> int | None:
        """The AND/OR operation the robot performs for ``action``; None for ``wait``. With actions named by joins,
        the first operation of the join (one of the states it applies in: a session refuses joins for that)."""
        operation = int(self.action_operations[action])
        return None if operation < 0 else operation

    # --- full sequences, named by rank without enumerating them ----------------------------------------

    @property
    def n_sequences(self) -> int:
        """The number of full assembly sequences (exact; those that start from the base part, if set)."""
        if self.base_part is None or self.plan.states.initial == self.final_state:
            return int(self.paths[self.plan.states.initial])
        return sum(int(x) for x in self.paths[self.class_target[self.initial_classes]])

    def class_sizes(self) -> np.ndarray:
        """The number of intentions in each class (exact: int64 or Python ints); they sum to the intentions."""
        sizes = self.paths[np.maximum(self.class_target, 0)]
        sizes[-1] = 1
        return sizes

    def classes_from(self, state: int) -> np.ndarray:
        """The classes that start at ``state`` (its out-edges; the final class at the final state)."""
        return self.state_classes[self.state_class_start[state]:self.state_class_start[state + 1]]

    def check_step(self, action: int, observation: int) -> None:
        """A :class:`PlannerError` unless ``action`` and ``observation`` are indices of this model's."""
        if not 0 <= action < len(self.action_operations):
            raise PlannerError(f"action {action} is not one of the model's {len(self.action_operations)} actions")
        if not 0 <= observation < len(self.plan.observations):
            raise PlannerError(f"observation {observation} is not one of the model's "
                               f"{len(self.plan.observations)} observations")

    # --- the tables, per class ------------------------------------------------------------------------

    def class_log_mass(self, classes: np.ndarray) -> np.ndarray:
        """The log of each class's total prior weight: ``log N(target)`` (its intentions), plus the log of its
        weighted share with weights. Cost: O(k)."""
        log_size = self.class_log_size[classes]
        return log_size if self.class_log_weight is None else log_size + self.class_log_weight[classes]

    def intention_log_share(self, path: list[int], position: int) -> float:
        """The log of the share of the intention ``path[position:]`` in its class's mass (the flat model's
        belief in it is the class's mass times that share): ``-log N(target)`` without weights. Cost: O(len)."""
        c = path[position] if position < len(path) else self.final_class
        if self.weights is None:
            return -float(self.class_log_size[c])
        own = float(np.log(self.weights[np.asarray(path[position:], dtype=np.int64)]).sum())
        return own - float(self.class_log_mass(np.array([c]))[0])

    def initial_belief(self) -> FactoredBelief:
        """Uniform over the full sequences: class ``c`` of :attr:`initial_classes` gets ``N(target(c))`` over
        their total (``N(initial)`` without a base part); with weights, their weighted shares."""
        classes = self.initial_classes
        if self.base_part is None or self.plan.states.initial == self.final_state:
            return FactoredBelief(classes.astype(np.int64), self.class_fraction[classes].copy())
        if self.weights is not None:
            log_mass = self.class_log_mass(classes)
            mass = np.exp(log_mass - log_mass.max())
            return FactoredBelief(classes.astype(np.int64), mass / mass.sum())
        # Ratios of exact counts (Python ints where they pass 2**52): correctly rounded, never overflowing.
        total = self.n_sequences
        mass = np.array([int(x) / total for x in self.paths[self.class_target[classes]]], dtype=float)
        return FactoredBelief(classes.astype(np.int64), mass)

    def advance(self, classes: np.ndarray, mass: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One step of the operator (or robot) along the path: each class's mass goes to the classes that
        start at its target in proportion to their sizes. ``classes`` must not hold the final class. The
        result's classes are distinct, not sorted. Cost: O(k log k + the classes of the distinct targets)."""
        # Mass per target state first: the classes of one state are reached once, however many lead there.
        targets, per_target = _sum_by(self.class_target[classes], mass, len(self.paths))
        out, count = self.starting_at(targets)
        return out, np.repeat(per_target, count) * self.class_fraction[out]

    def _combine(self, classes: np.ndarray, mass: np.ndarray) -> FactoredBelief:
        return FactoredBelief(*_sum_by(classes, mass, self.n_classes))

    def starting_at(self, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The classes that start at each of ``states``, concatenated, and how many per state."""
        start = self.state_class_start[states]
        count = self.state_class_start[states + 1] - start
        ends = np.cumsum(count)
        total = int(ends[-1]) if ends.size else 0
        return self.state_classes[np.repeat(start - ends + count, count) + np.arange(total)], count

    def _wait_step(self, classes: np.ndarray, mass: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        # Stay or advance one step, 1/2 each; the final class stays (with a change of mind: a redraw first).
        if self.deviations is not None:
            return operator_step(self, classes, mass)
        moving = classes != self.final_class
        half = np.where(moving, STAY * mass, mass)
        return [stay_part(self, classes, half), operator_advance(self, classes[moving], half[moving])]

    def predict(self, belief: FactoredBelief, action: int) -> FactoredBelief:
        """The distribution over classes after ``action`` (before the observation), module docstring."""
        return self._combine(*list(map(np.concatenate, zip(*self.predict_parts(belief, action))))[:2])

    def predict_parts(self, belief: FactoredBelief, action: int) -> list[tuple]:
        """:meth:`predict`'s pieces before they are summed by class: ``(classes, mass)``, and with observations
        of the step (:mod:`~planner.decision.step_observations`) the observation of each piece's step third."""
        classes, mass = belief.classes, belief.mass
        if action == self.wait:
            return self._wait_step(classes, mass)
        performs = self.class_action[classes] == action
        parts = [stay_part(self, classes[~performs], mass[~performs])]
        if performs.any():  # the robot's step (never an observation), then the operator's stay or advance
            parts += self._wait_step(*self.advance(classes[performs], mass[performs]))
        if self.parallel is not None:  # a right parallel action: to e', then stay or advance; wrong: stay
            parts = parallel_predict(self, classes, mass, action, performs, parts)
        return parts

    def observation_likelihood(self, observation: int, classes: np.ndarray | None = None) -> np.ndarray:
        """O(z | class) for ``classes`` (default: all), the same for every action: that of the class's
        current state. Cost: O(k log K) for k classes and K (state, observation) pairs."""
        states = self.class_source if classes is None else self.class_source[classes]
        weight = self.emit_weight[states]
        if observation == 0:
            return self._mixed(BLANK_WEIGHT * weight)
        keys = states.astype(np.int64) * len(self.plan.observations) + int(observation)
        at = np.searchsorted(self.emit_keys, keys)
        found = self.emit_keys[np.minimum(at, self.emit_keys.size - 1)] == keys if self.emit_keys.size else \
            np.zeros(keys.shape, dtype=bool)
        return self._mixed(np.where(found, weight, 0.0))

    def _mixed(self, likelihood: np.ndarray) -> np.ndarray:
        if self.deviations is None or not self.deviations.mistake:
            return likelihood
        return mix_likelihood(likelihood, self.deviations.mistake, len(self.plan.observations))

    def state_observations(self, state: int) -> tuple[np.ndarray, np.ndarray]:
        """The observations ``state`` can emit (blank first) and their probabilities, without mistakes (the
        simulated world's: its operator makes its own, :mod:`~planner.decision.operators`)."""
        Z = len(self.plan.observations)
        lo, hi = np.searchsorted(self.emit_keys, [state * Z, (state + 1) * Z])
        observations = np.concatenate([[0], self.emit_keys[lo:hi] - state * Z])
        weight = self.emit_weight[state]
        return observations, np.concatenate([[BLANK_WEIGHT * weight], np.full(hi - lo, weight)])

    def rewards_of(self, classes: np.ndarray, action: int) -> np.ndarray:
        """R(class, action): the class's next step (un)favorable, any other operation wrong, wait."""
        if action == self.wait:
            return np.full(len(classes), self.rewards.wait)
        out = np.where(self.class_action[classes] == action, self.class_match_reward[classes], self.rewards.wrong)
        return out if self.parallel is None else parallel_rewards(self, classes, action, out)

    def expected_rewards(self, belief: FactoredBelief) -> np.ndarray:
        """R(b, a) = sum over classes of mass x R(class, a), for every action at once. Cost: O(support + A)."""
        total = float(belief.mass.sum())
        out = np.full(len(self.action_operations), self.rewards.wrong * total)
        out[-1] = self.rewards.wait * total
        act = self.class_action[belief.classes]
        hit = act >= 0
        out[:-1] += np.bincount(act[hit], weights=belief.mass[hit] * (self.class_match_reward[belief.classes[hit]]
                                                                      - self.rewards.wrong), minlength=out.size - 1)
        return out if self.parallel is None else parallel_expected_rewards(self, belief, out)

    def expected_reward(self, belief: FactoredBelief, action: int) -> float:
        return float(belief.mass @ self.rewards_of(belief.classes, action))

    def reachable(self, classes: np.ndarray) -> np.ndarray:
        """Boolean mask over classes of those reachable from ``classes`` (themselves included): every class
        that starts at a state reachable from one of their targets. Cost: O(S + E)."""
        mask = np.zeros(self.n_classes, dtype=bool)
        mask[classes] = True
        seen = np.zeros(len(self.paths), dtype=bool)
        frontier = np.unique(self.class_target[classes[classes != self.final_class]])
        while frontier.size:
            seen[frontier] = True
            out, _ = self.starting_at(frontier)
            mask[out] = True
            nxt = self.class_target[out]
            frontier = np.unique(nxt[nxt >= 0])
            frontier = frontier[~seen[frontier]]
        return mask


def factored_model_bytes(n_states: int, n_edges: int) -> tuple[int, int]:
    """``(held, peak)``: the bytes :func:`factored_model` holds for ``n_states`` states and ``n_edges`` state
    edges (per class: five int32 and three float64 tables, and at most one int64 observation key; per state:
    the path counts, Python ints past 2**52, the CSR start and the emission weights) and the most it takes
    while building them (the sort of the edges by source, the path counts per class and their ratios: about
    four more int64 a class). From counts alone, before anything is built; measured within 30 % above
    (chain 16 and 20, complete 9 and 10: tests/decision/test_memory_estimates.py)."""
    held = 56 * n_edges + 64 * n_states
    return held, held + 36 * n_edges + 32 * n_states


def _counts_per_state(plan: Plan) -> np.ndarray:
    levels = paths_to_final(plan.states)
    if any(level.dtype == object for level in levels):
        levels = [level.astype(object) for level in levels]
    counts = np.concatenate(levels)
    if counts.shape[0] != plan.states.n_states:
        raise AssertionError("paths_to_final does not cover every state")
    return counts


def factored_model(plan: Plan, rewards: Rewards = Rewards(), discount: float = DISCOUNT,
                   base_part: str | None = None, weights: np.ndarray | None = None,
                   parallel: bool | str = False, deviations: Deviations | None = None,
                   orders: OrdersPrior | None = None, observe: str = STATE) -> FactoredIntentionModel:
    """The factored model of Alg. 3 over ``plan`` (module docstring), without enumerating intentions.

    ``base_part``: only the sequences that start from this part (paper Sec. V); :class:`PlannerError` when it
    is not a part or no sequence starts from it. ``weights``: a positive weight per state edge (operator
    habits, :func:`~planner.decision.habits.habit_weights`; module docstring), None for the paper's model.
    ``parallel``: the parallel model (True or ``"next"``, :mod:`~planner.decision.parallel`: the robot may do the
    step after next) or ``"projected"`` (:mod:`~planner.decision.projected`: any operation, the operator's
    sequence projected onto the new state) or ``"joins"`` (the same, the actions named by the parts they join:
    :mod:`~planner.decision.joins`); False: the paper's.
    ``deviations``: change of mind and mistakes (:mod:`~planner.decision.deviations`), None for the paper's.
    ``orders``: the orders' model (:mod:`~planner.decision.orders`), built on its augmented graph and weights.
    ``observe``: ``"state"`` (the paper's observations), ``"step"`` or ``"join"`` (a camera's:
    :mod:`~planner.decision.step_observations`; ``"join"`` puts the alphabet of the pieces joined in the model's plan).

    Cost: O(S + E log E) time and O(S + E) memory for S states and E state edges (one sort of the edges by
    source, one of the (state, observation) pairs); Python-int arithmetic only where the counts pass 2**52.
    """
    if orders is not None:
        check_alone(weights, base_part, parallel, deviations)
        plan, weights = orders.plan, orders.weights
    if check_observe(observe) == JOIN:  # the camera's alphabet names each operation
        plan = with_join_observations(plan)
    states = plan.states
    S, E, Z = states.n_states, states.n_edges, len(plan.observations)
    final = states.final
    counts = _counts_per_state(plan)
    index = np.int32 if max(E + 1, S, len(plan.andor.operations)) < 2 ** 31 else np.int64  # half the memory
    source = np.append(states.edge_source, final).astype(index)
    target = np.append(states.edge_target, -1).astype(index)
    operation = np.append(states.edge_operation, -1).astype(index)
    size = counts[np.maximum(target, 0)]
    size[-1] = 1
    # Ratios of exact counts: Python-int true division is correctly rounded and never overflows.
    fraction = (size / counts[source]).astype(float)
    if counts.dtype == object:
        log_size = np.array([math.log(x) for x in size], dtype=float)
    else:
        log_size = np.log(size.astype(float))
    order = np.argsort(source, kind="stable").astype(index)
    start = np.searchsorted(source[order], np.arange(S + 1))
    # Observations into each state: the distinct non-blank observations of the operations of its (allowed)
    # in-edges.
    # (On the orders' augmented graph: those of the node's assembly state, as Alg. 3 has them; orders.node_keys.)
    real = getattr(states, "real", states)
    seen = plan.operation_observation[real.edge_operation]
    if base_part is not None:
        seen = np.where(allowed_edges(states, base_part), seen, 0)
    keys = np.sort(real.edge_target.astype(np.int64)[seen != 0] * Z + seen[seen != 0])
    keys = node_keys(states, keys[np.r_[True, keys[1:] != keys[:-1]]] if keys.size else keys, Z)  # distinct
    emit_weight = 1.0 / (np.bincount(keys // Z, minlength=S) + BLANK_WEIGHT)
    if parallel not in (False, True, "next", PROJECTED, JOINS):
        raise PlannerError(f"unknown parallel model {parallel!r}: use False (the paper's), True or 'next' (the step "
                           f"after next), {PROJECTED!r} or {JOINS!r} (the projected model, actions named by joins)")
    robot_ops = np.flatnonzero(plan.tags.robot)
    action_of_op = np.full(len(plan.andor.operations), -1, dtype=np.int64)
    action_names = None
    if parallel == JOINS:  # one action per join (joins.py): the operations that share it share the action
        joined, first, action_names = join_actions(plan, robot_ops)
        action_of_op[robot_ops] = joined
        robot_ops = first
    else:
        action_of_op[robot_ops] = np.arange(len(robot_ops))
    class_action = np.where(operation >= 0, action_of_op[np.maximum(operation, 0)], -1).astype(index)
    match = np.where(plan.tags.unfavorable[np.maximum(operation, 0)], rewards.unfavorable, rewards.favorable)
    action_operations = np.append(robot_ops, -1)
    if base_part is None:
        initial = np.sort(order[start[states.initial]:start[states.initial + 1]]).astype(np.int64)
    else:
        initial = base_part_first_edges(states, base_part).astype(np.int64)  # class c < E is state edge c
        if S == 1:
            initial = np.array([E], dtype=np.int64)  # one part: the finished product is where assembly starts
        elif initial.size == 0:
            raise PlannerError(f"no assembly sequence starts from the base part {base_part!r} (no first "
                               "operation joins it); choose another base part, or check the technical constraints")
    class_weights = log_weight = None
    if weights is not None:
        fraction, class_weights, log_weight = weighted_fractions(states, target, fraction, weights)
    arrays = (action_operations, source, target, operation, fraction, log_size, order, start, counts, emit_weight,
              keys, class_action, match, initial)
    for a in arrays + tuple(a for a in (class_weights, log_weight) if a is not None):
        a.flags.writeable = False
    model = FactoredIntentionModel(plan, rewards, discount, *arrays, base_part=base_part, weights=class_weights,
                                   class_log_weight=log_weight, action_names=action_names,
                                   observe=check_observe(observe))
    if parallel:
        model = dataclasses.replace(model, parallel=projected_table(model, parallel) if parallel in (PROJECTED, JOINS)
                                    else parallel_table(model))
    if deviations is None:
        return model
    share = switch_share(model)
    share.flags.writeable = False
    return dataclasses.replace(model, deviations=deviations, switch_share=share)
