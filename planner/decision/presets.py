"""The robot's eagerness as a confidence, and the named models of ``--model`` (issue 23; docs/habits.md).

Eagerness. The paper (Sec. III, rewards): "By adjusting the latter cost [the wrong action's, -50], the user can
alter the robot's eagerness to act." A user means a confidence, not a cost: *act confidence* ``C`` is the belief
in the operator's next operation at which doing it breaks even with waiting, for one step,

    C r + (1 - C) w = r_wait,   so   w = (r_wait - C r) / (1 - C)   and   C = (r_wait - w) / (r - w),

``r`` the reward of the robot's right operation (the paper's +10, unfavorable to humans: the only one that pays
more than waiting), ``w`` the wrong action's, ``r_wait`` waiting's (0). The paper's +10 / -50 / 0 is ``C = 5/6``;
``C = 0.98`` gives ``w = -490``. The planners weigh the future too, so ``C`` is the one-step threshold, not a
promise: a robot that looks ahead bets at about that belief (bench/README.md, Operator habits, measured).

Presets. ``paper`` is Alg. 3 as published (no habits, the paper's rewards: always selectable, the default);
``habits`` the habits' model with the habits file's own prior and the given rewards; ``confident`` bundles what
the measurements showed best for a habitual operator: the prior spread per state (:mod:`~planner.decision.habits`),
alpha 1, and a robot that acts from a belief of 0.95 in the next operation (bench/README.md, Operator habits: on
the pen, 0.98 halves the work the robot takes for half a point of wrong actions, and on the pump's sa4 it never
acts; an empirical-Bayes alpha, the marginal likelihood's maximum, is 0.14 on the pen's 20 logs: surer, and
more often wrong). ``orders`` is the orders' model (:mod:`~planner.decision.orders`: a Pitman-Yor mixture over the
recorded whole sequences, the paper's prior as its base; the file's concentration and discount) with an act
confidence of 0.9 (bench/README.md, History-dependent habits: on the pen's four seeds the orders' model at 0.9
lands where the oracle of the operator's true prior is at 0.95). ``helpful`` is the robot that helps before the
last step: ``confident``'s habits (alpha 1 per state) in the joins model (``--joins``, docs/parallel.md: the robot
may do any join of the operator's sequence early) at the projected model's own confidence 0.98
(:data:`~planner.decision.projected.PROJECTED_CONFIDENCE`), the more careful of the two, as ``--model confident
--joins`` gives: one name for the robot that helps a habitual operator. ``camera`` is ``helpful`` reading its
observations as a camera gives them, of the operator's step (``--observe step``, docs/camera.md): the model of the
camera cell (``aplan session --demo``, a real camera), where it takes more of the work than ``helpful``, its wrong
actions below 1 % (bench/README.md, "Observations of the step").
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ..errors import UsageError
from .habits import Habits, HabitsError
from .intention_model import Rewards
from .joins import JOINS
from .projected import PROJECTED_CONFIDENCE
from .step_observations import STATE, STEP

__all__ = ["ModelPreset", "PRESETS", "CONFIDENT", "ORDERS", "HELPFUL", "CAMERA", "wrong_for_confidence",
           "act_confidence_of", "preset_habits", "preset_rewards"]


@dataclass(frozen=True)
class ModelPreset:
    """A named model: ``habits`` whether it needs habits (``--habits FILE``); ``prior`` / ``prior_per`` the
    habits' prior it uses in place of the file's (None: the file's); ``act_confidence`` the eagerness it sets
    when the user gives neither ``--act-confidence`` nor ``--reward-wrong`` (None: the paper's -50);
    ``orders`` whether the model is the orders' (:mod:`~planner.decision.orders`) rather than the counts';
    ``parallel`` the model of help before the last step it switches on (``"joins"``: ``--joins``), False for
    none (the flags then choose); ``observe`` what its observations depend on (``"step"``: ``--observe step``),
    the paper's ``"state"`` by default."""

    name: str
    habits: bool
    prior: float | None = None
    prior_per: str | None = None
    act_confidence: float | None = None
    orders: bool = False
    parallel: bool | str = False
    observe: str = STATE


CONFIDENT = ModelPreset("confident", True, prior=1.0, prior_per="state", act_confidence=0.95)
ORDERS = ModelPreset("orders", True, act_confidence=0.9, orders=True)
HELPFUL = ModelPreset("helpful", True, prior=CONFIDENT.prior, prior_per=CONFIDENT.prior_per,
                      act_confidence=PROJECTED_CONFIDENCE, parallel=JOINS)
CAMERA = replace(HELPFUL, name="camera", observe=STEP)
PRESETS = {p.name: p for p in (ModelPreset("paper", False), ModelPreset("habits", True), CONFIDENT, ORDERS, HELPFUL,
                               CAMERA)}


def _check_confidence(confidence: float) -> float:
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float)) or not 0 < confidence < 1:
        raise UsageError(f"--act-confidence must be a number above 0 and below 1, got {confidence!r}")
    return float(confidence)  # NaN fails the range test above


def wrong_for_confidence(confidence: float, right: float = Rewards.unfavorable, wait: float = Rewards.wait) -> float:
    """The wrong action's reward ``w = (wait - C right) / (1 - C)`` (module docstring) that makes a bet on the
    next operation break even at belief ``C`` in (0, 1). Raises :class:`~planner.errors.UsageError` for ``C``
    outside (0, 1) or NaN, or when ``right`` does not pay more than waiting (then no belief makes a bet pay)."""
    confidence = _check_confidence(confidence)
    if not right > wait:
        raise UsageError(f"--act-confidence needs a right operation that pays more than waiting: "
                         f"--reward-unfavorable {right:g} is not above --reward-wait {wait:g}")
    wrong = (wait - confidence * right) / (1 - confidence)
    if not math.isfinite(wrong):
        raise UsageError(f"--act-confidence {confidence!r} is too close to 1 (the wrong action's reward overflows)")
    return wrong


def act_confidence_of(rewards: Rewards) -> float:
    """The belief at which a bet on the next operation breaks even under ``rewards``: ``(wait - wrong) /
    (unfavorable - wrong)`` (5/6 for the paper's rewards). Assumes ``unfavorable > wait > wrong``."""
    return (rewards.wait - rewards.wrong) / (rewards.unfavorable - rewards.wrong)


def preset_rewards(preset: ModelPreset | None, unfavorable: float, favorable: float, wait: float,
                   wrong: float | None, act_confidence: float | None,
                   model_confidence: tuple[str, float] | None = None) -> Rewards:
    """The rewards of a command: ``wrong`` if given, else the one of ``act_confidence`` if given, else the
    larger (the more careful) of the preset's confidence and ``model_confidence`` (``(flag, C)``: the default
    a model sets for itself, e.g. ``("--projected", 0.98)``), else the paper's -50 (the user's explicit choice
    wins over both)."""
    if wrong is None:
        confidence, source = act_confidence, None
        if confidence is None:
            defaults = []
            if preset is not None and preset.act_confidence is not None:
                defaults.append((preset.act_confidence, f"--model {preset.name}"))
            if model_confidence is not None:
                defaults.append((model_confidence[1], model_confidence[0]))
            confidence, source = max(defaults, default=(None, None))
        if confidence is not None and act_confidence is None and not unfavorable > wait:
            raise UsageError(f"{source} sets --act-confidence {confidence:g}, which needs a right "
                             f"operation that pays more than waiting: --reward-unfavorable {unfavorable:g} is not "
                             f"above --reward-wait {wait:g}; give --reward-wrong too")
        wrong = Rewards.wrong if confidence is None else wrong_for_confidence(confidence, unfavorable, wait)
    return Rewards(unfavorable, favorable, wrong, wait)


def preset_habits(preset: ModelPreset | None, habits: Habits | None) -> Habits | None:
    """``habits`` with the preset's prior in place of the file's (the counts are the file's), None for a preset
    without habits; the orders' preset uses the file's recorded orders (refused, naming the file, when it has
    none), any other the counts. The session log records the result, so a replay rebuilds the same model."""
    if habits is None or preset is None or not preset.habits:
        return None if preset is not None and not preset.habits else habits
    if preset.orders:
        if not habits.orders:
            raise HabitsError(f"{habits.name}: --model {preset.name} needs the recorded orders (whole sequences), and "
                              "this habits file has none (written before version 3, or from logs of unfinished "
                              "sessions); learn it again: aplan habits LOG... -o FILE")
        return replace(habits, prior_model="orders")
    if habits.prior_model != "counts":
        habits = replace(habits, prior_model="counts")
    if preset.prior is None:
        return habits
    return replace(habits, prior=preset.prior, prior_per=preset.prior_per)
