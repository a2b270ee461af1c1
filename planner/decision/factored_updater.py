"""The exact Bayes filter of the factored decision model (:mod:`planner.decision.factored_model`), and the
map from its beliefs to the flat model's (for tests and small models)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..assembly.intentions import IntentionGraph
from .belief import UnexplainedObservation, _log_reset, reset_support
from .factored_model import FactoredBelief, FactoredIntentionModel
from .intention_model import intention_weights
from .step_observations import of_step, predict_seen, step_posterior

__all__ = ["FactoredUpdater", "to_flat"]


class FactoredUpdater:
    """The exact Bayes filter on a :class:`FactoredIntentionModel`, with :class:`DiscreteUpdater`'s interface
    and reset rule: an observation with probability 0 resets the belief to the intentions reachable from the
    previous belief's support that can emit it (uniform over intentions), else to every intention that can
    emit it, else to the uniform belief; the event goes to ``on_reset`` and ``events``.

    Cost per update: that of :meth:`FactoredIntentionModel.predict` plus O(k log K) for the likelihoods; a
    reset costs O(S + E).
    """

    def __init__(self, model: FactoredIntentionModel,
                 on_reset: Callable[[UnexplainedObservation], None] | None = None):
        self.model = model
        self.on_reset = on_reset or _log_reset
        self.events: list[UnexplainedObservation] = []

    def initialize(self) -> FactoredBelief:
        return self.model.initial_belief()

    def update(self, belief: FactoredBelief, action: int, observation: int) -> FactoredBelief:
        """The posterior belief; on an unexplained observation, a reset (class docstring). An action or
        observation that is not the model's raises :class:`PlannerError`."""
        self.model.check_step(action, observation)
        if of_step(self.model):  # the likelihood depends on the step taken: per piece of the prediction
            posterior = step_posterior(self.model, predict_seen(self.model, belief, action), observation)
            return posterior if posterior is not None else self._reset(belief, action, observation)
        predicted = self.model.predict(belief, action)
        posterior = predicted.mass * self.model.observation_likelihood(observation, predicted.classes)
        total = posterior.sum()
        if total > 0:
            keep = posterior > 0
            return FactoredBelief(predicted.classes[keep], posterior[keep] / total)
        return self._reset(belief, action, observation)

    def _reset(self, belief: FactoredBelief, action: int, observation: int) -> FactoredBelief:
        model = self.model
        start = belief.classes
        if model.deviations is not None and model.deviations.switch:  # a redraw reaches its state's classes
            start = model.starting_at(np.unique(model.class_source[belief.classes]).astype(np.int64))[0]
        mask = reset_support(model.observation_likelihood(observation) > 0, model.reachable(start),
                             action, observation, self.events, self.on_reset)
        if model.base_part is not None:  # the flat model's states are the base part's intentions only
            mask &= model.reachable(model.initial_classes)
        classes = np.flatnonzero(mask)
        log_size = model.class_log_mass(classes)
        weight = np.exp(log_size - log_size.max())  # uniform over intentions (by weight): mass ~ class size
        return FactoredBelief(classes, weight / weight.sum())


def to_flat(belief: FactoredBelief, graph: IntentionGraph, weights: np.ndarray | None = None) -> np.ndarray:
    """The flat belief over ``graph``'s intentions: ``mass[class] / size(class)``, intention ``i``'s class being
    its first state edge (the final class for the final intention). With ``weights`` (per state edge: operator
    habits), ``mass[class]`` times the intention's share of its class's weight (:func:`~planner.decision.intention_model.intention_weights`).
    Cost: O(I x length) (for tests and small models)."""
    E = graph.states.n_edges
    of = np.where(graph.step_edge >= 0, graph.step_edge, E)
    mass = belief.dense(E + 1)
    if weights is None:
        size = np.bincount(of, minlength=E + 1).astype(float)
        return mass[of] / size[of]
    prior = intention_weights(graph, weights)
    return mass[of] * prior / np.bincount(of, weights=prior, minlength=E + 1)[of]

