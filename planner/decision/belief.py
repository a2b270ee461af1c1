"""The Bayes filter over states (intentions): the *updater* half of the policy / updater seam.

``update(b, a, z)``: ``b'(s') ~ O(z | s', a) * sum_s T(s' | s, a) b(s)``. An observation that no state
explains (probability 0) never produces NaN: the update reports an :class:`UnexplainedObservation` and
resets the belief to the states that are reachable from the previous belief's support and can emit ``z``
(uniform, or by the updater's ``reset_weights``), else to every state that can emit ``z``, else to the uniform belief. The report goes to the
updater's ``on_reset`` (default: a warning on this module's logger) and its ``events`` list.
"""
from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .pomdp import POMDP

__all__ = ["DiscreteUpdater", "UnexplainedObservation", "reset_support"]

DENSE_LIMIT = 50_000_000  # observation-table numbers kept dense (400 MB)

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class UnexplainedObservation:
    """The event of an observation with probability 0 under the current belief, and what was done."""

    action: int
    observation: int
    reset_to: str  # "reachable", "emitting" or "uniform"

    def __str__(self) -> str:
        return (f"observation {self.observation} after action {self.action} has probability 0 under the belief; "
                f"belief reset to the {self.reset_to} states")


def _log_reset(event: UnexplainedObservation) -> None:
    log.warning("%s", event)


def reset_support(emitting: np.ndarray, reachable: np.ndarray, action: int, observation: int,
                  events: list[UnexplainedObservation],
                  on_reset: Callable[[UnexplainedObservation], None]) -> np.ndarray:
    """The reset rule of an unexplained observation, shared by every belief updater: the states (boolean
    masks over the updater's states or classes) that can emit it and are reachable from the previous belief,
    else those that can emit it, else all. The event is appended to ``events`` and passed to ``on_reset``."""
    for name, mask in (("reachable", emitting & reachable), ("emitting", emitting),
                       ("uniform", np.ones_like(emitting))):
        if mask.any():
            event = UnexplainedObservation(action, observation, name)
            events.append(event)
            on_reset(event)
            return mask
    raise AssertionError("unreachable: the uniform mask is never empty")


class DiscreteUpdater:
    """Exact belief updates for a :class:`~planner.decision.pomdp.POMDP` (tables transposed once, sparse).

    Cost per update: O(nnz(T_a) + S); memory: one dense (Z, S) array per distinct observation table (sparse
    columns beyond ``DENSE_LIMIT`` numbers). ``on_reset`` receives each :class:`UnexplainedObservation`
    (default: a warning on the ``planner.decision.belief`` logger); ``events`` keeps them all.
    """

    def __init__(self, model: POMDP, on_reset: Callable[[UnexplainedObservation], None] | None = None,
                 reset_weights: np.ndarray | None = None):
        self.model = model
        self.on_reset = on_reset or _log_reset
        self.reset_weights = reset_weights  # a reset spreads by these (operator habits), else uniformly
        self._transposed = [t.T.tocsr() for t in model.transition]
        # O(z | s', a) as dense rows per observation, once per distinct table (actions often share one), when
        # they fit in DENSE_LIMIT numbers; else sparse columns.
        distinct = {id(o): o for o in model.observation}
        if len(distinct) * model.n_states * model.n_observations <= DENSE_LIMIT:
            dense = {key: np.ascontiguousarray(o.toarray().T) for key, o in distinct.items()}
            self._emit = [dense[id(o)] for o in model.observation]
        else:
            self._emit = [o.tocsc() for o in model.observation]
        self._reach = None
        self.events: list[UnexplainedObservation] = []

    def initialize(self) -> np.ndarray:
        return self.model.initial.copy()

    def predict(self, belief: np.ndarray, action: int) -> np.ndarray:
        """The distribution of the next state after ``action`` (before the observation)."""
        return self._transposed[action] @ belief

    def observation_likelihood(self, action: int, observation: int) -> np.ndarray:
        table = self._emit[action]
        return table[observation] if isinstance(table, np.ndarray) else table[:, observation].toarray().ravel()

    def update(self, belief: np.ndarray, action: int, observation: int) -> np.ndarray:
        """The posterior belief; on an unexplained observation, a reset (see the module docstring)."""
        likelihood = self.observation_likelihood(action, observation)
        posterior = likelihood * self.predict(belief, action)
        total = posterior.sum()
        if total > 0:
            return posterior / total
        return self._reset(belief, action, observation, likelihood)

    def _reset(self, belief, action, observation, likelihood) -> np.ndarray:
        mask = reset_support(likelihood > 0, self._reachable(belief > 0), action, observation, self.events,
                             self.on_reset)
        weight = mask if self.reset_weights is None else mask * self.reset_weights
        return weight / weight.sum()

    def _reachable(self, support: np.ndarray) -> np.ndarray:
        if self._reach is None:
            self._reach = (sum(abs(t) for t in self.model.transition) > 0).astype(np.int8).T.tocsr()
        seen = support.copy()
        frontier = support
        while frontier.any():
            nxt = (self._reach @ frontier.astype(np.int8)) > 0
            frontier = nxt & ~seen
            seen |= nxt
        return seen
