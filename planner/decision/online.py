"""The online planner: the robot's next action from the current belief, by lookahead on the factored model.

Why this search. The factored belief (:mod:`planner.decision.factored_model`) is exact and cheap to update,
and its observations are few per step, so the planner searches the *exact* belief tree (no particles, no
sampling: the same belief and the same amount of work give the same action on any machine) and bounds
what it has not expanded by closed forms over the classes:

- upper bound: ``max_a sum_c b(c) Q(c, a)`` with ``Q`` the value of a better-informed robot, one that knows
  the class now and every assembly state from then on, but not the operator's next steps
  (:func:`~planner.decision.bounds.revealed_state_values`, over QMDP on the classes,
  :func:`~planner.decision.bounds.class_values`). Knowing more never hurts,
  so it bounds the value from above; one backward pass over the state graph computes it (the state graph is
  acyclic but for the self-loops of waiting, which have a closed form). It is 3 to 20 times tighter than
  QMDP at the initial belief (pen 6.2 against 15.8; chain of 9: 0.61 against 14.0);
- lower bound: the best of "do ``a`` now, then wait for ever", a policy the robot can always follow, and,
  when an offline policy over the classes is given (``lower``: the lumped model's alpha vectors), the value
  of each of its vectors for the vector's action (each is a plan that starts with that action). With it the
  planner starts from the offline policy's value and only improves on it.

The search is best-first, as AO* and HSVI: from the root it follows the action with the highest upper bound;
an action not expanded yet is expanded (one prediction and one split by observation: its children are the
posterior beliefs); else it descends into the observation whose probability times gap is the largest. The
bounds are backed up to the root after each expansion. The search stops after ``expansions`` expansions, at
``decision_time`` seconds (if set), or when the root's gap is below ``precision``. The action is the one
with the highest lower bound (the robot never bets on what it has not looked at), ties going to ``wait``.

An action that is the next step of no class in the belief costs the ``wrong`` reward and stops the operator
for a step; only actions with an upper bound above the root's lower bound are expanded, so such actions are
ruled out by their bound, not by a rule.

Cost per expansion: one :meth:`~FactoredIntentionModel.predict` (O(k log k) for k classes in the belief)
and O(k x Z') for the split into the Z' observations the belief can emit.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..defaults import BLANK_WEIGHT, ONLINE_DEPTH, ONLINE_EXPANSIONS, ONLINE_TREE_NUMBERS
from ..errors import PlannerError
from .bounds import VALUE_BLOCK, ClassValues, class_values, revealed_state_values
from .deviations import with_mistakes
from .factored_model import FactoredBelief, FactoredIntentionModel
from .online_steps import StepTimes
from .policy import AlphaVectorPolicy
from .step_observations import StepSplit, of_step, predict_seen, refuse_step_tables

# ClassValues, class_values, revealed_state_values and VALUE_BLOCK live in planner.decision.bounds (the
# online planner's and the solver's warm start's bounds); still importable from here.
__all__ = ["ClassValues", "class_values", "revealed_state_values", "VALUE_BLOCK", "observation_split", "OnlinePlanner",
           "SearchReport"]


def observation_split(model: FactoredIntentionModel, predicted: FactoredBelief
                      ) -> list[tuple[int, float, FactoredBelief]]:
    """The observations ``predicted`` can emit, each with its probability and the posterior belief:
    ``(z, P(z), b_z)``, the blank observation first (what the search's :class:`_Split` makes, all at once).
    Cost: O(k x Z') for k classes and Z' observations. (With observations of the step the split needs the
    prediction's pieces: :class:`~planner.decision.step_observations.StepSplit`.)"""
    refuse_step_tables(model, "a split of the predicted belief alone")
    split = with_mistakes(model, _Split(model, predicted), None)
    return [(z, p, split.posterior(z)) for z, p, _ in split.branches]


def _split_of(model: FactoredIntentionModel, belief: FactoredBelief, action: int, value: np.ndarray | None):
    """The split by observation of ``belief`` after ``action``: :class:`_Split` (with mistakes mixed in), or
    with observations of the step :class:`~planner.decision.step_observations.StepSplit`."""
    if of_step(model):
        return StepSplit(model, predict_seen(model, belief, action), value)
    return with_mistakes(model, _Split(model, model.predict(belief, action), value), value)


def _posterior(classes: np.ndarray, weighted: np.ndarray) -> FactoredBelief:
    keep = weighted > 0
    kept = weighted[keep]
    return FactoredBelief(classes[keep], kept / kept.sum())


class _Split:
    """One action's predicted belief split by observation; each child's posterior is made when the search first
    enters it (most children are never entered). Cost: O(k log k) to build, O(k) per posterior."""

    def __init__(self, model: FactoredIntentionModel, predicted: FactoredBelief, value: np.ndarray | None = None):
        self.classes, self.mass = predicted.classes, predicted.mass
        Z = len(model.plan.observations)
        states, self.inverse = np.unique(model.class_source[self.classes], return_inverse=True)
        state_mass = np.bincount(self.inverse, weights=self.mass, minlength=states.size)
        class_value = self.mass * value[self.classes] if value is not None else np.zeros(self.mass.size)
        state_value = np.bincount(self.inverse, weights=class_value, minlength=states.size)
        self.weight = model.emit_weight[states]
        lo = np.searchsorted(model.emit_keys, states.astype(np.int64) * Z)
        count = np.searchsorted(model.emit_keys, (states.astype(np.int64) + 1) * Z) - lo
        owner = np.repeat(np.arange(states.size), count)
        ends = np.cumsum(count)
        keys = model.emit_keys[np.repeat(lo - ends + count, count) + np.arange(int(ends[-1]) if ends.size else 0)]
        seen = keys - states[owner].astype(np.int64) * Z
        order = np.argsort(seen, kind="stable")
        self.seen, self.owner = seen[order], owner[order]
        w = self.weight[self.owner]
        probability = np.bincount(self.seen, weights=state_mass[self.owner] * w, minlength=Z)
        upper = np.bincount(self.seen, weights=state_value[self.owner] * w, minlength=Z)
        probability[0] = float(state_mass @ (BLANK_WEIGHT * self.weight))
        upper[0] = float(state_value @ (BLANK_WEIGHT * self.weight))
        #: (z, P(z), an upper bound on the posterior's value: sum_c b_z(c) V(c); 0 without ``value``)
        self.branches = [(int(z), float(probability[z]), float(upper[z] / probability[z]))
                         for z in np.flatnonzero(probability > 0)]

    def posterior(self, z: int) -> FactoredBelief:
        if z == 0:
            likelihood = BLANK_WEIGHT * self.weight
        else:
            first, last = np.searchsorted(self.seen, [z, z + 1])
            likelihood = np.zeros(self.weight.size)
            likelihood[self.owner[first:last]] = self.weight[self.owner[first:last]]
        return _posterior(self.classes, self.mass * likelihood[self.inverse])


# What a tree node costs besides its arrays (the Python objects: the node, its lists and array headers, about
# 1 KB), counted in numbers against the tree's cap: on the pen they outweigh the beliefs.
_NODE_NUMBERS = 128


@dataclass
class _Node:
    """A belief in the search tree; ``children[a]``: ``(reward, [(P(z), child), ...])`` once ``a`` is expanded.
    A child's belief is None until the search enters it (``origin``: the split and the observation that make
    it); its bounds are then the cheap ones of :class:`_Split`."""

    belief: FactoredBelief | None
    upper: float
    lower: float
    depth: int
    action_upper: np.ndarray | None = None  # per action: QMDP until expanded, then the backed-up bound
    action_lower: np.ndarray | None = None
    origin: tuple | None = None
    children: dict = field(default_factory=dict)
    closed_actions: set = field(default_factory=set)  # expanded actions with every branch closed
    closed: bool = False  # nothing below can change the bounds (depth limit or gap closed)


@dataclass(frozen=True)
class SearchReport:
    """One decision: the action, the root's bounds, the work done and the time it took."""

    action: int
    lower: float
    upper: float
    expansions: int
    seconds: float


class OnlinePlanner:
    """Best-first lookahead on a :class:`FactoredIntentionModel` (module docstring); a policy: ``action(belief)``
    for a :class:`FactoredBelief`.

    ``expansions``: the work per decision (the result depends only on it when ``decision_time`` is None);
    ``decision_time``: seconds per decision (the search also stops there; the default of the runtime is
    :data:`~planner.defaults.DECISION_TIME`); ``max_depth``: the deepest belief expanded; ``precision``: stop
    when the root's gap is this small. ``last`` holds the :class:`SearchReport` of the latest decision.
    """

    def __init__(self, model: FactoredIntentionModel, expansions: int = ONLINE_EXPANSIONS,
                 decision_time: float | None = None, max_depth: int = ONLINE_DEPTH, precision: float = 1e-3,
                 values: ClassValues | None = None, lower: AlphaVectorPolicy | None = None,
                 max_numbers: int = ONLINE_TREE_NUMBERS):
        if not (isinstance(expansions, int) and expansions >= 1):
            raise PlannerError(f"the online planner's expansions must be a positive integer, got {expansions!r}")
        if decision_time is not None and not (np.isfinite(decision_time) and decision_time > 0):
            raise PlannerError(f"the decision time must be a positive number of seconds, got {decision_time!r}")
        self.model = model
        self.expansions = expansions
        self.decision_time = decision_time
        self.max_depth = max_depth
        self.precision = precision
        self.values = values if values is not None else revealed_state_values(model)
        if lower is not None and lower.alphas.shape[1] != model.n_classes:
            raise PlannerError(f"the online planner's lower bound has vectors of length {lower.alphas.shape[1]:,}; "
                               f"it needs a policy over the model's {model.n_classes:,} classes (aplan solve --lumped)")
        if lower is not None:
            lower.check_sizes(model.n_classes, len(model.action_operations), "the online planner's lower bound")
        self.lower = lower
        r, g = model.rewards, model.discount
        self._after_now = g * r.wait / (1 - g)  # then wait for ever
        self.last: SearchReport | None = None
        self.max_numbers = max_numbers
        self._numbers = 0  # what the current tree holds (beliefs, splits, per-action bounds), in numbers
        self._steps = StepTimes(model)  # with a deadline: which steps still fit (online_steps)
        self._top = float(self.values.value.max())  # the largest class value: an upper bound at every belief

    # --- the policy interface ----------------------------------------------------------------------------

    def action(self, belief: FactoredBelief) -> int:
        """The action with the highest lower bound after the search (module docstring)."""
        return self.search(belief).action

    def value(self, belief: FactoredBelief) -> float:
        """The root's lower bound after the search (the value the robot can count on)."""
        return self.search(belief).lower

    def search(self, belief: FactoredBelief) -> SearchReport:
        """Search from ``belief`` (module docstring) within ``expansions``, ``decision_time`` and the tree's
        ``max_numbers``; with a decision time, a step whose estimated time (its size times the learnt rate)
        would pass the deadline is not started, and a root too large to bound in time gets only its lower
        bounds (and the cheap upper bound ``sum_c b(c) V(c)``)."""
        start = time.perf_counter()
        # 5 % of the budget is kept for the work after the search (choosing, returning, the caller's bookkeeping).
        deadline = None if self.decision_time is None else start + 0.95 * self.decision_time
        self._numbers = 0
        steps = self._steps
        too_large = deadline is not None and not steps.fits("bound", belief.classes.size, deadline)
        root = self._lower_only(belief) if too_large else steps.timed("bound", belief.classes.size, self._node, belief, 0)
        done = 0
        longest = 2 * (time.perf_counter() - start)  # the longest expansion so far (at first: twice the root's time)
        while (not too_large and done < self.expansions and root.upper - root.lower > self.precision
               and self._numbers < self.max_numbers):
            # Stop when one more expansion as long as the longest so far (at most a quarter of the budget: each
            # step's own estimate, in _expand_best, catches the large ones) would pass the deadline.
            now = time.perf_counter()
            if deadline is not None and now + min(longest, 0.25 * self.decision_time) >= deadline:
                break
            if not self._expand_best(root, deadline):
                break
            longest = max(longest, time.perf_counter() - now)
            done += 1
        best = _argmax_prefer_last(root.action_lower)
        self.last = SearchReport(best, root.lower, root.upper, done, time.perf_counter() - start)
        return self.last

    def _lower_only(self, belief: FactoredBelief) -> _Node:
        """A root with its lower bounds ("act, then wait") and the upper bound ``max_c V(c)`` (no gather: on
        chain 23 each gather over a belief of 2 million classes took 0.2-0.3 s): for a belief too large to
        bound per action in time."""
        node = _Node(belief, 0.0, 0.0, 0)
        node.action_lower = self.model.expected_rewards(belief) + self._after_now
        if self.lower is not None:
            np.maximum.at(node.action_lower, self.lower.actions, self.lower.values(belief))
        node.action_upper = np.full(node.action_lower.size, self._top * float(belief.mass.sum()))
        _refresh(node)
        return node

    # --- the tree ----------------------------------------------------------------------------------------

    def _node(self, belief: FactoredBelief, depth: int) -> _Node:
        node = _Node(belief, 0.0, 0.0, depth)
        self._bound(node)
        return node

    def _count(self, node: _Node) -> None:
        """Add a node's belief and per-action bounds to the tree's size."""
        self._numbers += 2 * node.belief.classes.size + 2 * node.action_upper.size + _NODE_NUMBERS

    def _bound(self, node: _Node) -> None:
        """The per-action bounds of a node whose belief is known: QMDP above, "act, then wait" below."""
        node.action_upper = self.values.q_values(self.model, node.belief)
        node.action_lower = self.model.expected_rewards(node.belief) + self._after_now
        if self.lower is not None:  # each alpha vector is a plan that starts with its action: a lower bound
            values = self.lower.values(node.belief)
            np.maximum.at(node.action_lower, self.lower.actions, values)
        _refresh(node)
        node.closed = node.upper - node.lower <= self.precision
        self._count(node)

    def _enter(self, node: _Node) -> None:
        """Make a child's posterior belief and its per-action bounds (the cheap bounds were its only ones)."""
        split, z = node.origin
        node.belief, node.origin = split.posterior(z), None
        upper = node.upper
        self._bound(node)
        node.action_upper = np.minimum(node.action_upper, upper)
        _refresh(node)

    def _expand_best(self, root: _Node, deadline: float | None = None) -> bool:
        """Follow the best upper bounds down to an unexpanded action, expand it and back up the bounds; False
        when nothing is left to expand (every open path ends at ``max_depth`` or is exact), or when the next
        step (entering a child, or the expansion) is estimated to pass ``deadline`` (nothing is started then)."""
        path, node = [], root
        in_time = True
        while True:
            action = self._open_action(node)
            if action is None:  # nothing to learn below this node: close it and back up
                node.closed = True
                break
            if action not in node.children:
                size = self._steps.predicted_size(node.belief, action)
                if not self._steps.fits("expand", size, deadline):
                    in_time = False
                    break
                path.append((node, action))
                self._steps.timed("expand", size, self._expand, node, action)
                break
            path.append((node, action))
            _, branches = node.children[action]
            open_branches = [(p, c) for p, c in branches if not c.closed]
            if not open_branches:
                node.closed_actions.add(action)
                continue
            child = max(open_branches, key=lambda pc: pc[0] * (pc[1].upper - pc[1].lower))[1]
            if child.belief is None:
                size = child.origin[0].classes.size
                if not self._steps.fits("bound", size, deadline):
                    in_time = False
                    break
                self._steps.timed("bound", size, self._enter, child)
            node = child
        for node, action in reversed(path):
            self._backup(node, action)
        return in_time and not root.closed

    def _open_action(self, node: _Node) -> int | None:
        """The action with the highest upper bound that could still beat the node's lower bound."""
        if node.depth >= self.max_depth:
            return None
        upper = node.action_upper
        if node.closed_actions:
            upper = upper.copy()
            upper[list(node.closed_actions)] = -np.inf
        a = int(len(upper) - 1 - np.argmax(upper[::-1]))  # ties to the last action (wait)
        return a if upper[a] > node.lower + self.precision else None

    def _expand(self, node: _Node, action: int) -> None:
        model = self.model
        reward = float(model.expected_rewards(node.belief)[action])
        split = _split_of(model, node.belief, action, self.values.value)
        # the split's arrays (classes, masses, their states and keys) and a node per observation
        self._numbers += 6 * split.classes.size + _NODE_NUMBERS * len(split.branches)
        wait_forever = self._after_now / model.discount
        branches = []
        for z, p, upper in split.branches:
            child = _Node(None, upper, wait_forever, node.depth + 1, origin=(split, z))
            child.closed = upper - wait_forever <= self.precision
            branches.append((p, child))
        node.children[action] = (reward, branches)

    def _backup(self, node: _Node, action: int) -> None:
        if action in node.children:
            reward, branches = node.children[action]
            g = self.model.discount
            upper = reward + g * sum(p * c.upper for p, c in branches)
            lower = reward + g * sum(p * c.lower for p, c in branches)
            node.action_upper[action] = min(node.action_upper[action], upper)
            node.action_lower[action] = max(node.action_lower[action], lower)
        _refresh(node)


def _refresh(node: _Node) -> None:
    node.upper = float(node.action_upper.max())
    node.lower = float(node.action_lower.max())


def _argmax_prefer_last(values: np.ndarray) -> int:
    """The index of the largest value, ties to the last (``wait``)."""
    return int(len(values) - 1 - np.argmax(values[::-1]))
