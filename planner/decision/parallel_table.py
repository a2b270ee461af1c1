"""The table of a parallel model's pairs (:mod:`.parallel`'s step after next, :mod:`.projected`'s projected
sequences): plain data the factored predict, the rewards, the lumped POMDP and the bounds read, in a module of
its own below both models."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["ParallelTable"]


@dataclass(frozen=True)
class ParallelTable:
    """The parallel pairs, sorted by ``key = class * A + action`` (``A`` the number of actions, wait included):
    per pair the class, the action, ``q`` (``fraction``), the class after a right action (``target``: ``e'``),
    the reward of a right action (``reward``), the operator's edge the robot takes over (``step``: ``e2``) and the
    robot's own edge (``robot_edge``: ``f``). ``start`` (classes + 1): the pairs of class ``c`` are
    ``start[c]:start[c + 1]`` (the keys sort by class first)."""

    n_actions: int
    key: np.ndarray
    pair_class: np.ndarray
    action: np.ndarray
    fraction: np.ndarray
    target: np.ndarray
    reward: np.ndarray
    step: np.ndarray
    robot_edge: np.ndarray
    start: np.ndarray
    #: ``next``: this module's pairs (the step after next); ``projected``: :mod:`.projected`'s (``step`` -1)
    rule: str = "next"
    projector: object = field(default=None, compare=False, repr=False)  # the projected rule's lookups

    @property
    def size(self) -> int:
        return int(self.key.size)

    def find(self, classes: np.ndarray, action: int) -> tuple[np.ndarray, np.ndarray]:
        """``(k, p)``: the positions ``k`` in ``classes`` that have a pair with ``action``, and the pairs ``p``.
        Cost: O(k log P)."""
        if not self.key.size or action < 0:
            empty = np.zeros(0, dtype=np.int64)
            return empty, empty
        keys = np.asarray(classes, dtype=np.int64) * self.n_actions + int(action)
        at = np.minimum(np.searchsorted(self.key, keys), self.key.size - 1)
        hit = np.flatnonzero(self.key[at] == keys)
        return hit, at[hit]

    def of_classes(self, classes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(k, p)``: every pair ``p`` of ``classes``, ``k`` the position of its class. Cost: O(k + pairs)."""
        lo, hi = self.start[classes], self.start[np.asarray(classes) + 1]
        count = hi - lo
        ends = np.cumsum(count)
        total = int(ends[-1]) if ends.size else 0
        return np.repeat(np.arange(len(classes)), count), np.repeat(lo - ends + count, count) + np.arange(total)
