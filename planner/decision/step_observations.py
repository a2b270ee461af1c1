"""Observations of the step taken (``--observe step``): the decision model of a camera that reports each
operation once (docs/camera.md).

The paper's Alg. 3 gives an observation the probability ``O(z | s')`` of the state reached: uniform over the
observations of the operations *into* ``s'``, blank at a quarter weight, drawn afresh at every step. A camera
does not work so: it reports the operation the operator did in the step, and nothing when the operator did
nothing. Under the paper's model every blank after an idle step is evidence against the current state (its row
gives blank only 1/(4k + 1) of the time), so a robot reading a camera drifts off the state the operator is in
(bench/bench_camera_filter.py measures it). This model has the camera world's own observation probabilities
(:mod:`~planner.decision.camera_world`), with ``b`` = :data:`~planner.defaults.CAMERA_BLANK` = 1/5:

    O(z | c, a, c') = [z = 0]                                 when the operator did no step,
                      (1 - b) [z = obs(e)] + b [z = 0]        when it did state edge e's operation,

``obs(e)`` the observation of ``e``'s operation (:attr:`~planner.assembly.plan.Plan.operation_observation`: its
loose part and tool; 0 when it has neither, and then the step is never seen). ``--observe join`` is the same model
over a richer alphabet: a camera that also sees the pieces joined, so that ``obs(e)`` names ``e``'s operation
(:func:`~planner.assembly.tags.join_observation_table`; the model's plan carries that alphabet,
:func:`~planner.assembly.plan.with_join_observations`), and no operation is unseen but by a miss. The robot's own
operation is not an observation (the robot knows what it did; the camera watches the operator), as in the camera
world. States, transitions, rewards, the initial belief, habits, the parallel models and the change of mind are the
factored model's, unchanged; mistakes mix as before, ``(1 - mu) O + mu / Z``. With ``observe="state"`` (the
default) the model is the paper's, table for table.

Exactness on the classes. The likelihood depends on the transition, not on the class reached, so the filter
multiplies each *piece* of the prediction (the mass that stayed, the mass each operator step moved, tagged with
that step's observation: :func:`predict_seen`) by its own likelihood before summing by class. Within a class the
completions keep their prior proportions (every piece spreads over the classes at its target by the prior, as
the paper's), so the class belief stays exact: the filter equals the one over whole sequences, to rounding
(tests/decision/test_step_observations.py checks it against an explicit filter over every sequence). A value
function of this POMDP written over (class, last step's observation) is the same for every observation (the
next step and the rewards depend on the class alone), so the online planner's bounds over classes hold as they
are (the revealed-state bound knows every state, hence every step).

Cost. A prediction is the paper's plus one sort of its pieces by (class, observation): O(k log k) for the k
pieces (the classes the belief reaches, each at most once per distinct observation into it). The split of the
online planner costs O(k) per observation branch.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import PlannerError
from ..defaults import CAMERA_BLANK
from .factored_belief import FactoredBelief, _sum_by

__all__ = ["OBSERVE", "STATE", "STEP", "JOIN", "STEPWISE", "check_observe", "of_step", "StepPrediction", "stay_part",
           "operator_advance",
           "predict_seen", "step_likelihood", "step_posterior", "StepSplit", "refuse_step_tables"]

STATE, STEP, JOIN = "state", "step", "join"
#: What an observation depends on: the state reached (Alg. 3, the default), the operator's step as the tray
#: camera sees it (its loose parts and tool), or the step with the pieces it joined (a camera that sees them).
OBSERVE = (STATE, STEP, JOIN)
#: The observation models whose observation depends on the step taken (this module's).
STEPWISE = (STEP, JOIN)


def check_observe(observe: str) -> str:
    """``observe`` when it is one of :data:`OBSERVE`, else a :class:`PlannerError` naming them."""
    if observe not in OBSERVE:
        raise PlannerError(f"unknown observation model {observe!r}: use {STATE!r} (the paper's: the state reached), "
                           f"{STEP!r} (a camera's: the operator's step) or {JOIN!r} (the step and the pieces it "
                           "joined) (--observe)")
    return observe


def of_step(model_or_observe) -> bool:
    """Whether a model (or an ``observe`` value) has observations of the step taken (:data:`STEPWISE`)."""
    observe = model_or_observe if isinstance(model_or_observe, str) else getattr(model_or_observe, "observe", STATE)
    return observe in STEPWISE


def refuse_step_tables(model, what: str, fix: str = "use the online planner (--planner online, the default "
                       "without --policy), or leave out --observe") -> None:
    """A :class:`PlannerError` when ``model`` observes steps and ``what`` (a lumped POMDP, a file) needs tables
    ``O(z | state reached)``, which cannot hold observations of the step: ``fix`` names what can."""
    if of_step(model):
        raise PlannerError(f"--observe {model.observe} gives observations of the operator's step, and {what} holds "
                           f"observations of the state reached only: {fix}")


@dataclass(frozen=True)
class StepPrediction:
    """A prediction's pieces summed by (class, observation of the step that led there): ``classes``, their
    ``mass`` (positive) and ``seen`` (0: no operator step, or one that cannot be seen)."""

    classes: np.ndarray
    mass: np.ndarray
    seen: np.ndarray

    def marginal(self) -> FactoredBelief:
        """The masses summed by class (the prediction before the observation)."""
        return FactoredBelief(*_sum_by(self.classes, self.mass, int(self.classes.max(initial=0)) + 1))


def stay_part(model, classes: np.ndarray, mass: np.ndarray) -> tuple:
    """A piece of a prediction in which the operator did no step: ``(classes, mass)``, with observations of the
    step also its observation, 0 for each."""
    if model.observe == STATE:
        return classes, mass
    return classes, mass, np.zeros(classes.size, dtype=np.int64)


def operator_advance(model, classes: np.ndarray, mass: np.ndarray) -> tuple:
    """The operator's step from ``classes`` (none final): :meth:`advance`, with observations of the step also
    each new class's observation, that of the step taken (mass is summed by target state and observation, so a
    state reached by two operations seen alike is spread once). Cost: O(k log k + the classes reached)."""
    if model.observe == STATE:
        return model.advance(classes, mass)
    Z = len(model.plan.observations)
    seen = model.plan.operation_observation[model.class_operation[classes]].astype(np.int64)
    keys, per_key = np.unique(model.class_target[classes].astype(np.int64) * Z + seen, return_inverse=True)
    per_key_mass = np.bincount(per_key, weights=mass, minlength=keys.size)
    out, count = model.starting_at(keys // Z)
    return out, np.repeat(per_key_mass, count) * model.class_fraction[out], np.repeat(keys % Z, count)


def predict_seen(model, belief: FactoredBelief, action: int) -> StepPrediction:
    """The prediction of ``belief`` after ``action`` by pieces (module docstring), summed by (class, seen).
    Cost: that of the model's prediction plus one sort of its pieces."""
    classes, mass, seen = map(np.concatenate, zip(*model.predict_parts(belief, action)))
    Z = len(model.plan.observations)
    keys, inverse = np.unique(classes.astype(np.int64) * Z + seen, return_inverse=True)
    total = np.bincount(inverse, weights=mass, minlength=keys.size)
    keep = total > 0
    keys = keys[keep]
    return StepPrediction(keys // Z, total[keep], keys % Z)


def step_likelihood(model, seen: np.ndarray, observation: int) -> np.ndarray:
    """O(z | step) for each piece's ``seen`` observation (module docstring), mistakes mixed in. Cost: O(k)."""
    if observation == 0:
        likelihood = np.where(seen == 0, 1.0, CAMERA_BLANK)
    else:
        likelihood = np.where(seen == observation, 1.0 - CAMERA_BLANK, 0.0)
    mistake = model.deviations.mistake if model.deviations is not None else 0.0
    if mistake:
        likelihood = (1.0 - mistake) * likelihood + mistake / len(model.plan.observations)
    return likelihood


def step_posterior(model, prediction: StepPrediction, observation: int) -> FactoredBelief | None:
    """The posterior belief after ``observation``, None when the prediction cannot emit it. Cost: O(k log k)."""
    weighted = prediction.mass * step_likelihood(model, prediction.seen, observation)
    classes, mass = _sum_by(prediction.classes, weighted, model.n_classes)
    total = mass.sum()
    return FactoredBelief(classes, mass / total) if total > 0 else None


class StepSplit:
    """The online planner's split of one action's prediction by observation (the paper's model's is
    :class:`~planner.decision.online._Split`): ``branches`` ``(z, P(z), an upper bound on the posterior's value)``,
    the blank first; with mistakes one more branch stands for every observation no step emits (their posteriors
    are the prediction's marginal, all equal). Posteriors are made when the search enters them. Cost: O(k) to
    build, O(k log k) per posterior."""

    def __init__(self, model, prediction: StepPrediction, value: np.ndarray | None = None):
        self.model, self.prediction = model, prediction
        self.classes, seen, mass = prediction.classes, prediction.seen, prediction.mass
        Z = len(model.plan.observations)
        worth = mass * value[self.classes] if value is not None else np.zeros(mass.size)
        probability = np.bincount(seen, weights=(1.0 - CAMERA_BLANK) * mass, minlength=Z)
        upper = np.bincount(seen, weights=(1.0 - CAMERA_BLANK) * worth, minlength=Z)
        unseen = seen == 0
        probability[0] = mass[unseen].sum() + CAMERA_BLANK * mass[~unseen].sum()
        upper[0] = worth[unseen].sum() + CAMERA_BLANK * worth[~unseen].sum()
        mistake = model.deviations.mistake if model.deviations is not None else 0.0
        total, mean = float(mass.sum()), float(worth.sum())
        if mistake:
            probability = (1.0 - mistake) * probability + mistake * total / Z
            upper = (1.0 - mistake) * upper + mistake * mean / Z
        emitted = np.flatnonzero(np.bincount(seen, minlength=Z) > 0)
        emitted = np.union1d([0], emitted)
        self.branches = [(int(z), float(probability[z]), float(upper[z] / probability[z]))
                         for z in emitted if probability[z] > 0]
        others = np.setdiff1d(np.arange(Z), emitted)
        if mistake and others.size:  # one branch for all of them (the first stands for the rest)
            self.branches.append((int(others[0]), mistake * total * others.size / Z, mean / total))

    def posterior(self, z: int) -> FactoredBelief:
        return step_posterior(self.model, self.prediction, z)
