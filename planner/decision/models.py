"""The decision-model interface (POMDPs.jl style): what sessions, replay, evaluation, the command line and the
workbench ask of a decision model, whichever it is.

Four models implement it: the flat :class:`IntentionModel` (beliefs over intentions), the
:class:`FactoredIntentionModel` (beliefs over classes, paper Sec. V), the :class:`LumpedModel` (its POMDP over
classes, for solvers and files; its beliefs are the factored model's) and a bare :class:`POMDP` read from a
file (beliefs over its states). The functions below are the interface: each takes any of the four and tells
them apart here, so no code outside ``planner/decision/`` tests a model's or a belief's type
(tests/test_decision_interface.py checks it). A new model plugs in by adding its case to them.

:class:`DecisionModel`, :class:`Belief` and :class:`BeliefUpdater` state the common surface as protocols.
"""
from __future__ import annotations

from typing import Callable, Protocol, Sequence, Union, runtime_checkable

import numpy as np

from .belief import DiscreteUpdater
from .factored_model import FactoredBelief, FactoredIntentionModel
from .factored_updater import FactoredUpdater
from .intention_model import IntentionModel
from .lumped_model import LumpedModel
from .online import OnlinePlanner
from .policy import AlphaVectorPolicy
from .pomdp import POMDP

__all__ = ["DecisionModel", "Belief", "BeliefUpdater", "Model", "BELIEF_OVER", "tables", "belief_over", "filtered",
           "of_product", "is_flat", "is_factored", "is_lumped", "final_of", "updater_for", "top_intentions", "belief_at", "belief_prefix",
           "is_offline_policy", "solver_plan", "state_mass", "predict", "is_online_planner"]

Model = Union[IntentionModel, FactoredIntentionModel, LumpedModel, POMDP]

# What a belief is over, per model kind (the log's ``belief_over``; replay rebuilds the model from it).
BELIEF_OVER = {"flat": "intentions", "factored": "classes", "file": "states"}


@runtime_checkable
class DecisionModel(Protocol):
    """Any decision model: named actions and observations, a discount, and a name (a file's, or the
    product's); :func:`tables` gives the POMDP a solver takes, :func:`updater_for` its Bayes filter."""

    @property
    def actions(self) -> Sequence[str]: ...

    @property
    def observations(self) -> Sequence[str]: ...


class Belief(Protocol):
    """A belief: a probability vector over intentions or states (``numpy.ndarray``), or a
    :class:`FactoredBelief` (``classes``, ``mass``) over classes. Read through :func:`top_intentions` and
    :func:`belief_at`."""


class BeliefUpdater(Protocol):
    """A Bayes filter: :meth:`initialize` the initial belief, :meth:`update` after an action and an
    observation, :meth:`predict` after an action only (:class:`DiscreteUpdater`, :class:`FactoredUpdater`)."""

    def initialize(self) -> Belief: ...

    def update(self, belief: Belief, action: int, observation: int) -> Belief: ...


def tables(model: Model) -> POMDP:
    """The POMDP tables of a decision model (a :class:`POMDP` is its own tables; the factored model has none and
    is returned as it is: :func:`~planner.decision.lumped_model.lumped_pomdp` builds them). Cost: O(1)."""
    return model.pomdp if isinstance(model, (IntentionModel, LumpedModel)) else model


def filtered(model: Model) -> IntentionModel | FactoredIntentionModel | POMDP:
    """The model whose beliefs a policy of ``model`` reads: the lumped model's are its factored model's
    (policies over class masses), every other model's are its own. Cost: O(1)."""
    return model.factored if isinstance(model, LumpedModel) else model


def is_flat(model: Model) -> bool:
    """Whether ``model`` is the flat model over intentions (a product's, not a file's)."""
    return isinstance(model, IntentionModel)


def is_factored(model: Model) -> bool:
    """Whether ``model`` is the factored model itself (beliefs over classes, no tables; not the lumped model)."""
    return isinstance(model, FactoredIntentionModel)


def is_lumped(model: Model) -> bool:
    """Whether ``model`` is the lumped model (the factored model's POMDP over classes), whose solver starts from
    the relaxed bounds (:mod:`~planner.decision.solvers.warm_start`)."""
    return isinstance(model, LumpedModel)


def of_product(model: Model) -> bool:
    """Whether ``model`` was built from a product (it has a plan, sequences, operations), not read from a file."""
    return isinstance(filtered(model), (IntentionModel, FactoredIntentionModel))


def belief_over(model: Model) -> str:
    """What a belief of ``model`` (of :func:`filtered`) is over: ``intentions``, ``classes`` or ``states``."""
    inner = filtered(model)
    if isinstance(inner, FactoredIntentionModel):
        return BELIEF_OVER["factored"]
    return BELIEF_OVER["flat" if isinstance(inner, IntentionModel) else "file"]


def final_of(model: Model) -> int | None:
    """The index (an intention's state, or the finished class) at which an episode of ``model`` ends, None for a
    file model (its episodes run to the step limit)."""
    inner = filtered(model)
    if isinstance(inner, FactoredIntentionModel):
        return inner.final_class
    return inner.final_state if isinstance(inner, IntentionModel) else None


def solver_plan(model: Model):
    """The plan a solver's memory estimate reads for ``model``'s warm start (the lumped model's), else None."""
    return model.factored.plan if isinstance(model, LumpedModel) else None


def updater_for(model: Model, on_reset: Callable | None = None) -> BeliefUpdater:
    """The exact Bayes filter of ``model``: over intentions, over classes on the factored (and lumped) model, over
    states on a file model; ``on_reset`` sees each observation of probability 0 (its reset of the belief)."""
    inner = filtered(model)
    if isinstance(inner, FactoredIntentionModel):
        return FactoredUpdater(inner, on_reset=on_reset)
    if isinstance(inner, IntentionModel):
        return DiscreteUpdater(inner.pomdp, on_reset=on_reset, reset_weights=inner.prior_weights)
    return DiscreteUpdater(inner, on_reset=on_reset)


def top_intentions(belief: Belief, k: int = 5) -> list[list]:
    """The ``k`` most probable intentions (or classes, for a :class:`FactoredBelief`) with a positive
    probability, as the log's ``top`` field. Cost: O(n log n) in the belief's support."""
    if isinstance(belief, FactoredBelief):
        order = np.argsort(-belief.mass, kind="stable")[:k]
        return [[int(belief.classes[i]), round(float(belief.mass[i]), 6)] for i in order]
    order = np.argsort(-belief, kind="stable")[:k]
    return [[int(i), round(float(belief[i]), 6)] for i in order if belief[i] > 0]


def belief_at(belief: Belief, index: int) -> float:
    """The probability of intention (or class) ``index``. Cost: O(log k) on a factored belief, O(1) else."""
    if isinstance(belief, FactoredBelief):
        at = int(np.searchsorted(belief.classes, index))
        return float(belief.mass[at]) if at < belief.classes.size and belief.classes[at] == index else 0.0
    return float(belief[index])


def belief_prefix(belief: Belief) -> str:
    """How the status line and replay name what ``belief`` is over: ``c`` (classes) or ``i`` (intentions)."""
    return "c" if isinstance(belief, FactoredBelief) else "i"


def is_offline_policy(policy) -> bool:
    """Whether ``policy`` is an offline policy (alpha vectors, read from a file or solved), not an online planner."""
    return isinstance(policy, AlphaVectorPolicy)


def state_mass(model: IntentionModel | FactoredIntentionModel, belief: Belief, state: int) -> float:
    """The belief's mass on the assembly ``state`` (its classes, or its intentions). Cost: O(k) or O(I)."""
    if isinstance(belief, FactoredBelief):
        return float(belief.mass[model.class_source[belief.classes] == state].sum())
    return float(belief[model.graph.first_state == state].sum())


def predict(model: IntentionModel | FactoredIntentionModel, updater: BeliefUpdater, belief: Belief,
            action: int) -> Belief:
    """The belief after ``action`` before any observation (flat or factored). Cost: one prediction step."""
    if isinstance(belief, FactoredBelief):
        return model.predict(belief, action)
    return updater.predict(belief, action)


def is_online_planner(policy) -> bool:
    """Whether ``policy`` is the online planner (:class:`~planner.decision.online.OnlinePlanner`), which searches
    at each decision (within its decision time or expansions)."""
    return isinstance(policy, OnlinePlanner)
