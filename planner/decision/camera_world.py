"""What a simulated world's camera reports (``--world model|camera``, :data:`WORLDS`).

- ``model`` (the default, the paper's observation model O(z | i), Alg. 3): each step the world emits an
  observation drawn from the table of the state it is in, uniform over the observations of the operations that
  lead *into* that state, the blank one at a quarter weight. So the simulated camera often reports another
  operation into the state than the one the operator did, and reports one again when the operator did nothing.
- ``camera`` (the simulated camera cell's, ``aplan session --demo K``, and a real camera's): the camera sees
  the operation the operator actually did. When the operator does an operation in the step, the observation is
  that operation's (``plan.operation_observation``) with probability ``1 - CAMERA_BLANK``, else blank (a missed
  detection); when it does nothing, blank; when the robot and the operator both act in one step, the
  operator's operation (the camera watches the operator; the robot's own operation is known to the robot).

``CAMERA_BLANK`` = ``BLANK_WEIGHT / (1 + BLANK_WEIGHT)`` = 1/5: the blank share the paper's model gives a state
with one operation into it (its row is that operation's observation at weight 1, blank at 1/4). It is the
model's chance that one operation goes unnoticed; the camera world keeps it whatever the state's fan-in (a
camera's misses do not depend on how many other operations could have led to the state), so on a state with one
in-edge observation the two worlds emit with the same probabilities.

Every camera observation has positive probability under the model's filter at the world's true state: the
operator's operation is an in-edge of the state it leads to (so its observation is in that state's row), and
blank is in every row. So without operator mistakes (``mistakes:Q``, drawn after this as in the model world)
the belief never resets. Each step draws one uniform number from the episode's stream (after the world's
move, as the model world draws its observation), whether or not the operator acted, so the flat and factored
camera worlds stay draw for draw on the same stream.
"""
from __future__ import annotations

import numpy as np

from ..defaults import CAMERA_BLANK
from ..errors import UsageError

__all__ = ["WORLDS", "CAMERA_BLANK", "check_world", "camera_observation", "intention_step_observations"]

#: The simulated worlds' observation sources: the paper's model (default) or the camera that sees what was done.
WORLDS = ("model", "camera")

# CAMERA_BLANK (the chance that the operator's operation goes unnoticed, module docstring: 1/5) is in
# planner.defaults: the decision model of the camera (step_observations.py) reads it too.


def check_world(world: str) -> str:
    """``world`` when it is one of :data:`WORLDS`, else a :class:`~planner.errors.UsageError` naming them."""
    if world not in WORLDS:
        raise UsageError(f"episodes: unknown world {world!r}; use one of {', '.join(WORLDS)} (--world)")
    return world


def camera_observation(seen: int | None, rng: np.random.Generator) -> int:
    """The camera's observation of a step in which the operator did an operation whose observation is ``seen``
    (None: it did nothing): ``seen`` with probability ``1 - CAMERA_BLANK``, else blank (0). One uniform draw
    from ``rng`` whatever happens. Cost: O(1)."""
    missed = rng.random() < CAMERA_BLANK
    return 0 if seen is None or missed else int(seen)


def intention_step_observations(plan, graph) -> np.ndarray:
    """The observation of each intention's next step in ``graph`` (``plan.operation_observation`` of its
    operation; 0 at the finished product): what the flat camera world reports when the operator does that
    step. Cost: O(intentions)."""
    step = graph.operation
    return np.where(step >= 0, plan.operation_observation[np.maximum(step, 0)], 0).astype(np.int64)
