"""The record of one simulated episode, on any decision model: :class:`Step` and :class:`Episode`.

One type for every model (flat, factored, lumped, a file's POMDP). What the world plays is recorded in the
model's own terms, and only the fields of that kind are set:

- over intentions (the flat model, or a file's POMDP: :mod:`.simulate`): ``Episode.start`` (the true state at
  the start, for an intention model the full sequence's intention), ``Episode.final`` (the finished product's
  intention, when known), ``Episode.switched_to`` (the intention taken at a change of mind) and
  ``Step.state`` (the true state after the step);
- over classes (the factored model, and the lumped model whose policies run on it: :mod:`.factored_simulate`):
  ``Episode.path`` (the full sequence's state edges; after a change of mind, the sequence done) and
  ``Step.position`` (the steps of ``path`` done after the step).

Everything else means the same on every model; :mod:`.episode_measures` reads only that and
:meth:`Episode.unfinished`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..defaults import CONFIDENCE

__all__ = ["Step", "Episode"]


@dataclass(frozen=True)
class Step:
    """One decision step: the robot's ``action``, the ``observation`` after it, ``p_true`` (the belief on the
    true intention after the update: on the factored model the flat model's number, its class's mass times its
    share), ``operator_operations`` (the operator's operations so far), ``reward``, ``decision_seconds`` (the
    time the policy took to choose ``action``), ``robot_operation`` (the action was the intention's next step:
    the robot helped), ``wrong_action`` (an operation that was not), ``mistake`` (the operator took a wrong
    part: the observation is that pick), and the world's truth after the step in the model's terms (module
    docstring): ``state`` over intentions, ``position`` over classes."""

    action: int
    observation: int
    p_true: float
    operator_operations: int
    reward: float
    decision_seconds: float = 0.0
    robot_operation: bool = False
    wrong_action: bool = False
    mistake: bool = False
    state: int | None = None
    position: int | None = None


@dataclass
class Episode:
    """One episode: its ``steps``, the ``beliefs`` (before the first step, then after each; dense over the
    model's states, or a sparse :class:`~planner.decision.factored_model.FactoredBelief`), the
    ``discounted_return``, ``switched_at`` (the decision step, from 1, before which the operator changed its
    mind; None if it did not), ``resets`` (observations of probability 0 under the belief, each of which reset
    it), ``robot_capable`` (operations done, by anyone, that some robot action does), and the world's truth in
    the model's terms (module docstring): ``start``, ``final``, ``switched_to`` over intentions, ``path`` over
    classes."""

    steps: list[Step] = field(default_factory=list)
    beliefs: list = field(default_factory=list)
    discounted_return: float = 0.0
    switched_at: int | None = None
    resets: int = 0
    robot_capable: int = 0
    start: int | None = None
    final: int | None = None
    switched_to: int | None = None
    path: list[int] | None = None

    @property
    def finished(self) -> bool:
        """Whether the product was finished at the end (over intentions: only when ``final`` is known)."""
        if self.path is not None:
            return not self.path or bool(self.steps) and self.steps[-1].position == len(self.path)
        return self.final is not None and (self.steps[-1].state if self.steps else self.start) == self.final

    def unfinished(self, step: Step) -> bool:
        """Whether the product was still unfinished after ``step`` (over intentions: always, when ``final`` is
        not known)."""
        if self.path is not None:
            return step.position < len(self.path)
        return self.final is None or step.state != self.final

    def first_confident(self, threshold: float = CONFIDENCE) -> int | None:
        """Operator operations done when the belief on the true intention first exceeds ``threshold`` before
        the product is finished (after a step that leaves it unfinished); None if it never does. Once the
        product is assembled the belief is on it trivially, so that step does not count."""
        return next((s.operator_operations for s in self.steps if s.p_true > threshold and self.unfinished(s)),
                    None)

    def confident_before_finished(self, threshold: float = CONFIDENCE) -> bool:
        """True when the belief on the true intention passed ``threshold`` before the product was finished."""
        return self.first_confident(threshold) is not None
