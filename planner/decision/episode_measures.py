"""What an episode says about the collaboration: who did the operations, the robot's wrong actions, when it
first helped and when it was sure of the operator's intention (an :class:`~.episode.Episode` of any model).

Per episode: ``robot_operations`` (the robot's actions that were the intention's next step),
``operator_operations`` (the operator's), ``wrong_robot_actions`` (the robot's operations that were not: the
reward table's ``wrong`` entries), ``first_help_step`` (the decision step, from 1, of the robot's first
operation; None if it never did one), ``confident_step`` (the decision step, from 1, after which the belief on
the true intention first exceeded ``CONFIDENCE`` while the product was not yet finished, as
``confident_after_operations`` counts it; None if never), ``robot_share`` (robot operations over all
operations; None without any), ``switched_at_step`` (when the operator changed its mind) and
``operator_mistakes`` (wrong parts taken), ``confident_after_switch`` (at some step from the one the operator
changed its mind before, ``switched_at_step``, on, the belief after that step's observation on the true
intention, which is then the new one: the assembly state and the new sequence from there, ``Step.p_true``,
exceeded ``CONFIDENCE``, and that step left the product unfinished; the step that finishes it does not count,
the belief is then on the finished product trivially; None without a switch; docs/deviations.md) and ``resets``
(observations of probability 0 under the belief). A finished episode's operations add up to its sequence's
length. Cost: O(steps).
"""
from __future__ import annotations

from ..defaults import CONFIDENCE

__all__ = ["episode_measures", "run_totals"]


def episode_measures(episode, threshold: float = CONFIDENCE) -> dict:
    """The per-episode measures (module docstring) of an :class:`~.episode.Episode` of any model."""
    steps = episode.steps
    robot = sum(s.robot_operation for s in steps)
    operator = steps[-1].operator_operations if steps else 0
    capable = episode.robot_capable
    return {"robot_operations": robot, "operator_operations": operator,
            "wrong_robot_actions": sum(s.wrong_action for s in steps),
            "first_help_step": next((k for k, s in enumerate(steps, 1) if s.robot_operation), None),
            "confident_step": next((k for k, s in enumerate(steps, 1) if s.p_true > threshold
                                    and episode.unfinished(s)), None),
            "robot_share": round(robot / (robot + operator), 6) if robot + operator else None,
            "robot_capable_operations": capable,
            "robot_capable_share": round(robot / capable, 6) if capable else None,
            "switched_at_step": episode.switched_at,
            "confident_after_switch": _confident_after_switch(episode, threshold),
            "operator_mistakes": sum(s.mistake for s in steps),
            "resets": int(episode.resets)}


def _confident_after_switch(episode, threshold: float) -> bool | None:
    """Whether the belief on the new true intention passed ``threshold`` at or after the step the operator
    changed its mind and before the product was finished; None when it did not change its mind."""
    if episode.switched_at is None:
        return None
    return any(s.p_true > threshold and episode.unfinished(s) for s in episode.steps[episode.switched_at - 1:])


def run_totals(measures: list[dict]) -> dict:
    """A run's totals: the robot's share of all operations and of the operations it is able to do, and its
    wrong actions as a share of its actions (operations it did plus wrong ones; None when it never acted)."""
    robot = sum(m["robot_operations"] for m in measures)
    operator = sum(m["operator_operations"] for m in measures)
    wrong = sum(m["wrong_robot_actions"] for m in measures)
    capable = sum(m["robot_capable_operations"] for m in measures)
    return {"episodes": len(measures), "robot_operations": robot, "operator_operations": operator,
            "wrong_robot_actions": wrong, "robot_capable_operations": capable,
            "robot_share": round(robot / (robot + operator), 6) if robot + operator else None,
            "robot_capable_share": round(robot / capable, 6) if capable else None,
            "wrong_share": round(wrong / (robot + wrong), 6) if robot + wrong else None,
            "operator_mistakes": sum(m["operator_mistakes"] for m in measures),
            "resets": sum(m["resets"] for m in measures),
            "switched": sum(m["switched_at_step"] is not None for m in measures),
            "confident_after_switch": sum(bool(m["confident_after_switch"]) for m in measures),
            "never_helped": sum(m["first_help_step"] is None for m in measures),
            "never_confident": sum(m["confident_step"] is None for m in measures)}
