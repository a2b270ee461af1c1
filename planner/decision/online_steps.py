"""How long the online planner's steps take, so that a decision ends by its deadline (:mod:`.online`).

A decision's search is made of steps whose cost grows with the classes they touch: the root's bounds and
entering a child (O(k) for k classes), and an expansion (a prediction and a split by observation, O(m log m)
for the m classes the prediction reaches, which on a complete product is hundreds of times k). Timing the
previous step says nothing about the next one, so each step's size is estimated before it starts (in O(k)),
and it is started only if that size times the seconds per class seen so far ends before the deadline. Used
with a deadline only: with ``--expansions`` alone nothing here changes what the search does.
"""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from .factored_model import FactoredBelief, FactoredIntentionModel

__all__ = ["StepTimes"]

# Seconds per class to start from, before a large step was timed: about twice the figures measured on the
# complete product of 11 parts under load (bounds 160-200 ns per class, an expansion 400-1300 ns per class).
_FIRST_RATES = {"bound": 4e-7, "expand": 2e-6}
_LEARN_FROM = 10_000  # classes: below, a step's fixed costs dominate and its rate would mislead
_DECAY = 0.9          # per large step, towards what is seen (a slow step once does not slow every later one)


class StepTimes:
    """Seconds per class of the search's steps (``bound``: a node's per-action bounds, ``expand``: a prediction
    and its split), learnt from the large ones: the rate is the largest of the last one seen and a tenth less
    than before."""

    def __init__(self, model: FactoredIntentionModel):
        self.model = model
        self.rates = dict(_FIRST_RATES)
        self._fan_out = model.final_class / max(1, len(model.paths))  # classes per state, on average
        self._out = np.diff(model.state_class_start)                  # classes out of each state

    def fits(self, step: str, size: int, deadline: float | None) -> bool:
        """Whether a ``step`` over about ``size`` classes is estimated to end before ``deadline`` (None: yes)."""
        return deadline is None or time.perf_counter() + self.rates[step] * size < deadline

    def timed(self, step: str, size: int, work: Callable, *args):
        """``work(*args)``, learning the rate of ``step`` from it when ``size`` is large."""
        began = time.perf_counter()
        out = work(*args)
        if size >= _LEARN_FROM:
            self.rates[step] = max((time.perf_counter() - began) / size, _DECAY * self.rates[step])
        return out

    def predicted_size(self, belief: FactoredBelief, action: int) -> int:
        """About how many classes ``predict(belief, action)`` touches: each class that moves fans out over the
        classes out of its target (a robot step's classes then once more, by the mean fan-out). Cost: O(k)."""
        m, classes = self.model, belief.classes
        if action == m.wait:
            moving = classes[classes != m.final_class]
            return int(classes.size + self._out[m.class_target[moving]].sum())
        performs = classes[m.class_action[classes] == action]
        fan = int(self._out[m.class_target[performs]].sum()) if performs.size else 0
        if m.parallel is not None:  # a right parallel action: to e', then its target's classes
            k, p = m.parallel.find(classes, action)
            fan += k.size + int(self._out[m.class_target[m.parallel.target[p]]].sum())
        return int(classes.size + fan * (2 + self._fan_out))
