"""What the belief says after the operator changed its mind (issue 23, "Change of mind"; docs/deviations.md):
the readings of "the belief on the new true sequence passes 0.9 before the end", on an
:class:`~planner.decision.episode.Episode` of the factored model (``Episode.path``: the sequence done, after the
switch the new one; ``Step.position``: how far along it).

Each reading is a probability the belief after a step's observation gives to something true of the new
sequence at that step; it *passes* when it exceeds the threshold at some step from the one the operator changed
its mind before (``Episode.switched_at``) on, that step leaving the product unfinished (the step that finishes
it does not count: the belief is then on the finished product trivially). With ``s`` the true assembly state
and ``e = path[position]`` the new sequence's next state edge:

- ``intention``: the flat model's belief on the whole remaining new sequence (``Step.p_true``: the mass of class
  ``e`` times the intention's prior share within it). Bounded by the belief on ``s`` times that share: under the
  paper's uniform prior ``1 / N(s)``, so it passes only at a state with one completion left.
- ``next_class``: the belief on the lumped model's class ``(s, e)``: the intentions at ``s`` whose next step is
  the new sequence's (the mass of class ``e``).
- ``next_operation``: the belief that the operator's next operation is the new sequence's, at whatever state (the
  mass of the classes whose AND/OR operation is ``e``'s): what decides whether the robot's action is right.
- ``state``: the belief on ``s`` (the mass of the classes that start there): what has been done, not what will be.

So ``intention <= next_class <= next_operation`` and ``next_class <= state`` at every step. Cost: O(steps x
support) per episode.
"""
from __future__ import annotations

import numpy as np

from ..defaults import CONFIDENCE

__all__ = ["READINGS", "step_readings", "passes_after_switch", "switch_totals"]

READINGS = ("intention", "next_class", "next_operation", "state")


def step_readings(model, episode, k: int) -> dict[str, float]:
    """The four readings (module docstring) after step ``k`` (from 1) of ``episode`` on the factored ``model``;
    the position must leave the product unfinished."""
    step, belief = episode.steps[k - 1], episode.beliefs[k]
    edge = int(episode.path[step.position])
    final = model.final_class
    classes, mass = belief.classes, belief.mass
    unfinished = classes != final
    source = np.where(unfinished, model.class_source[np.minimum(classes, final - 1)], model.final_state)
    operation = np.where(unfinished, model.class_operation[np.minimum(classes, final - 1)], -1)
    return {"intention": float(step.p_true),
            "next_class": float(mass[classes == edge].sum()),
            "next_operation": float(mass[operation == model.class_operation[edge]].sum()),
            "state": float(mass[source == model.class_source[edge]].sum())}


def passes_after_switch(model, episode, threshold: float = CONFIDENCE) -> dict[str, bool] | None:
    """Per reading, whether it passed ``threshold`` at or after the switch and before the product was finished
    (module docstring); None when the operator did not change its mind."""
    if episode.switched_at is None:
        return None
    passed = dict.fromkeys(READINGS, False)
    for k in range(episode.switched_at, len(episode.steps) + 1):
        if not episode.unfinished(episode.steps[k - 1]):
            break
        for name, value in step_readings(model, episode, k).items():
            passed[name] = passed[name] or value > threshold
    return passed


def switch_totals(model, episodes, threshold: float = CONFIDENCE) -> dict:
    """Over ``episodes``: the switched ones, per reading those that passed, and the resets (episodes with one and
    their number: an observation of probability 0 under the belief, after which the filter restarts from the
    prior)."""
    results = [passes_after_switch(model, e, threshold) for e in episodes]
    switched = [r for r in results if r is not None]
    return {"switched": len(switched), **{name: sum(r[name] for r in switched) for name in READINGS},
            "reset_episodes": sum(e.resets > 0 for e in episodes), "resets": sum(int(e.resets) for e in episodes)}
