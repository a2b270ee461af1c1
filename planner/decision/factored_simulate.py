"""Episodes on the factored model: the operator follows one full sequence (a path of state edges), the robot acts
by any policy on the factored Bayes filter's belief (the online planner, or alpha vectors over classes).

The world is the flat model's (the same transitions, observations and rewards, :mod:`planner.decision.
factored_model`), played along the sequence's edges by position, so an episode never enumerates intentions.
In the parallel model (:mod:`planner.decision.parallel`) a robot action that does the operator's step after
next is right when the sequence takes it there: the sequence then continues with it done (the robot's step,
then the operator's next one, then the rest), and the step counts as the robot's operation. In the projected
model (:mod:`planner.decision.projected`) a pair's action is right when the projection of the rest of the
sequence onto the robot's new state is feasible: the sequence continues with the robot's step, then that
projection.
"""
from __future__ import annotations

import logging
import math
import time

import numpy as np

from ..assembly.guards import Progress
from .episode import Episode, Step
from .factored_model import FactoredBelief, FactoredIntentionModel
from .factored_updater import FactoredUpdater
from .operators import switch_path
from .parallel import parallel_rewrite
from .simulate import operator_mistake

__all__ = ["simulate_factored_episode", "evaluate_factored", "true_intention_probability"]

OPERATORS = ("turns", "model")

log = logging.getLogger(__name__)


def true_intention_probability(model: FactoredIntentionModel, belief: FactoredBelief, path: list[int],
                               position: int) -> float:
    """The flat model's belief on the intention ``path[position:]``: its class's mass over the class size."""
    c = path[position] if position < len(path) else model.final_class
    at = np.searchsorted(belief.classes, c)
    if at >= belief.classes.size or belief.classes[at] != c or belief.mass[at] <= 0:
        return 0.0
    return math.exp(math.log(float(belief.mass[at])) + model.intention_log_share(path, position))


def simulate_factored_episode(model: FactoredIntentionModel, policy, path: list[int], rng: np.random.Generator,
                              max_steps: int = 100, operator: str = "model", switch=None,
                              mistakes=None) -> Episode:
    """One episode along ``path`` (state edges from the initial state) until the product is finished or
    ``max_steps``. ``operator``: ``model`` (it acts with probability 1/2 per step, as the model says) or
    ``turns`` (it acts whenever the model lets it). ``policy.action(belief)`` picks the robot's actions.
    ``switch`` (a :class:`~planner.decision.operators.Switch`): the operator changes its mind once, after that
    many operations, to another completion of its assembly state (``episode.path`` is then the one done).
    ``mistakes``: as :func:`~planner.decision.simulate.simulate_episode`'s (the wrong parts' observations)."""
    if operator not in OPERATORS:
        raise ValueError(f"operator must be one of {OPERATORS}, got {operator!r}")
    updater = FactoredUpdater(model, on_reset=lambda event: None)
    belief = updater.initialize()
    episode = Episode(beliefs=[belief], path=list(path))
    position, operations, discount = 0, 0, 1.0
    for _ in range(max_steps):
        if position >= len(path):
            break
        if switch is not None and episode.switched_at is None and position >= switch.after:
            other = switch_path(model, path, position, switch.draw)
            if other != path:  # else at the next state that has another completion
                path = episode.path = other
                episode.switched_at = len(episode.steps) + 1
        started = time.perf_counter()
        action = int(policy.action(belief))
        seconds = time.perf_counter() - started
        # The parallel model's right action: the robot's step comes first in the sequence (then it matches)
        path = episode.path = parallel_rewrite(model, path, position, action)
        robot_steps = 1 if action != model.wait and model.class_action[path[position]] == action else 0
        reward = float(model.class_match_reward[path[position]] if robot_steps else
                       model.rewards.wait if action == model.wait else model.rewards.wrong)
        options = model.position_transition(path, position, action)
        nxt = max(p for p, _ in options) if operator == "turns" else model.sample_position(path, position, action, rng)
        operations += nxt - position - robot_steps
        episode.robot_capable += int(np.count_nonzero(model.class_action[path[position:nxt]] >= 0))
        z = model.sample_observation(path, nxt, rng)
        z, mistake = operator_mistake(z, len(model.observations), mistakes)
        belief = updater.update(belief, action, z)
        episode.discounted_return += discount * reward
        discount *= model.discount
        position = nxt
        episode.steps.append(Step(action, z, true_intention_probability(model, belief, path, position), operations,
                                  reward, seconds, robot_steps == 1, action != model.wait and robot_steps == 0, mistake,
                                  position=position))
        episode.beliefs.append(belief)
    episode.resets = len(updater.events)
    return episode


def evaluate_factored(model: FactoredIntentionModel, policy, episodes: int, seed: int = 0, max_steps: int = 100
                      ) -> tuple[float, float, list[float]]:
    """Mean discounted return over ``episodes`` episodes (each sequence drawn from the initial belief) and the
    half-width of its 95 % confidence interval (normal approximation)."""
    rng = np.random.default_rng(seed)
    progress = Progress(log, after=5.0, every=10.0)
    returns = []
    for k in range(episodes):
        returns.append(simulate_factored_episode(model, policy, model.sample_sequence(rng), rng,
                                                 max_steps).discounted_return)
        progress.report("evaluate: %d of %d episodes, mean return so far %.4f", k + 1, episodes, np.mean(returns))
    mean = float(np.mean(returns))
    half = 1.96 * float(np.std(returns, ddof=1)) / math.sqrt(episodes) if episodes > 1 else float("nan")
    return mean, half, returns
