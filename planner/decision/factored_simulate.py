"""The world of the factored model (:class:`PathWorld`): the operator follows one full sequence (a path of state
edges) in the episode loop of :mod:`.simulate`, the robot acting by any policy on the factored Bayes filter's
belief (the online planner, or alpha vectors over classes: the lumped model's policies).

The world is the flat model's (the same transitions, observations and rewards, :mod:`planner.decision.
factored_model`), played along the sequence's edges by position, so an episode never enumerates intentions.
In the parallel model (:mod:`planner.decision.parallel`) a robot action that does the operator's step after
next is right when the sequence takes it there: the sequence then continues with it done (the robot's step,
then the operator's next one, then the rest), and the step counts as the robot's operation. In the projected
model (:mod:`planner.decision.projected`) a pair's action is right when the projection of the rest of the
sequence onto the robot's new state is feasible: the sequence continues with the robot's step, then that
projection.

With ``camera=True`` (``--world camera``, :mod:`.camera_world`) the world's observation is the operation the
operator did in the step (with the model's chance of a missed detection), not a draw from the state's table.
"""
from __future__ import annotations

import math

import numpy as np

from .camera_world import camera_observation
from .episode import Episode
from .factored_model import FactoredBelief, FactoredIntentionModel
from .factored_updater import FactoredUpdater
from .operators import switch_path
from .parallel import parallel_rewrite
from .simulate import Move

__all__ = ["PathWorld", "true_intention_probability"]


def true_intention_probability(model: FactoredIntentionModel, belief: FactoredBelief, path: list[int],
                               position: int) -> float:
    """The flat model's belief on the intention ``path[position:]``: its class's mass over the class size."""
    c = path[position] if position < len(path) else model.final_class
    at = np.searchsorted(belief.classes, c)
    if at >= belief.classes.size or belief.classes[at] != c or belief.mass[at] <= 0:
        return 0.0
    return math.exp(math.log(float(belief.mass[at])) + model.intention_log_share(path, position))


class PathWorld:
    """The world along ``path`` (state edges from the initial state) of ``model``: the true state is the number
    of the path's steps done (``done``; :class:`~.episode.Step` ``position``); the episode's ``path`` is the one
    done (after a change of mind, or a parallel model's robot step, the sequence continued). The
    :class:`~.simulate.World` protocol; its updater is the :class:`FactoredUpdater` (resets counted, not warned
    about). ``camera``: the camera world's observations (:mod:`.camera_world`) instead of the model's. Cost per
    step: that of the model's position transition and observation draw."""

    def __init__(self, model: FactoredIntentionModel, path: list[int], camera: bool = False):
        self.model, self.path, self.done = model, list(path), 0
        self.wait, self.discount, self.n_observations = model.wait, model.discount, len(model.observations)
        self.camera, self.seen = camera, None  # seen: the observation of the operator's operation of the step

    def finished(self) -> bool:
        return self.done >= len(self.path)

    def switch(self, draw: float) -> bool:
        other = switch_path(self.model, self.path, self.done, draw)
        if other == self.path:
            return False
        self.path = other
        return True

    def act(self, action: int, rng: np.random.Generator, operator: str) -> Move:
        model, position = self.model, self.done
        # The parallel model's right action: the robot's step comes first in the sequence (then it matches)
        path = self.path = parallel_rewrite(model, self.path, position, action)
        robot_steps = 1 if action != model.wait and model.class_action[path[position]] == action else 0
        reward = float(model.class_match_reward[path[position]] if robot_steps else
                       model.rewards.wait if action == model.wait else model.rewards.wrong)
        if operator == "turns":
            nxt = max(p for p, _ in model.position_transition(path, position, action))
        else:
            nxt = model.sample_position(path, position, action, rng)
        capable = int(np.count_nonzero(model.class_action[path[position:nxt]] >= 0))
        self.done = nxt
        # The camera world: the operator's operation of the step, the edge after the robot's, if the world moved on
        if self.camera:
            self.seen = int(model.plan.operation_observation[model.class_operation[path[nxt - 1]]]) \
                if nxt - position - robot_steps > 0 else None
        return Move(reward, robot_steps == 1, nxt - position - robot_steps, capable)

    def observe(self, action: int, rng: np.random.Generator) -> int:
        if self.camera:
            return camera_observation(self.seen, rng)
        return self.model.sample_observation(self.path, self.done, rng)

    def p_true(self, belief: FactoredBelief) -> float:
        return true_intention_probability(self.model, belief, self.path, self.done)

    def truth(self) -> dict:
        return {"position": self.done}

    def updater(self, deviating: bool) -> FactoredUpdater:
        return FactoredUpdater(self.model, on_reset=lambda event: None)

    def record(self, episode: Episode) -> None:
        episode.path = self.path
