"""The one episode loop (POMDPs.jl's simulator): any world, any policy, any belief updater; and the world over
intentions (a flat model's or a file's POMDP). Their Fig. 7 plot: :mod:`.belief_plot`.

:func:`simulate_episode` runs one episode: at each step the robot acts by the policy on the updater's belief,
the *world* (the operator's side, in the model's own terms) moves its true state and emits an observation, and
the updater folds it in. A world is the generative half of a decision model (POMDPs.jl's ``gen``):

- :class:`IntentionWorld` (here): the true state is an intention (or a file's state); it moves by the tables'
  transitions and emits by their observations, so the operator's timing is random (it acts with probability
  1/2 per step, as the model says); its updater is the :class:`~.belief.DiscreteUpdater`;
- :class:`~.factored_simulate.PathWorld`: the true state is a position along one full sequence's state edges
  (the factored model and the lumped model's policies); its updater is the
  :class:`~.factored_updater.FactoredUpdater`.

:mod:`.episodes` picks the world of a model and draws which ones are played. With a plan at hand, the world
also counts the operator's own operations, to report after how many of them the belief on the true intention
first exceeds a threshold before the product is finished (the paper saw 2, 2 and 4 in its three runs);
:func:`decision_times` sums up the time the policy took per decision. The random draws of a step come in one
order on every world: the world's move, then its observation (then the operator's mistake, from its own
stream), so a seed gives the same episodes whatever the caller.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..defaults import CONFIDENCE
from .belief import DiscreteUpdater
from .camera_world import camera_observation
from .episode import Episode, Step
from .operators import mistaken_observation, switch_intention
from .pomdp import POMDP

__all__ = ["Step", "Episode", "World", "Move", "IntentionWorld", "OPERATORS", "confidence_text", "decision_times",
           "simulate_episode", "operator_mistake"]

#: How the simulated operator times its operations: ``model`` (with the model's probability, 1/2 per step) or
#: ``turns`` (whenever the model lets it: human and robot take turns, as in the paper's experiment).
OPERATORS = ("turns", "model")


def confidence_text(operations: int | None, threshold: float = CONFIDENCE) -> str:
    """What :meth:`~.episode.Episode.first_confident` found, in words: ``belief on the true intention first above 0.9
    after 2 operator operations``, or that it never was before the product was finished."""
    if operations is None:
        return f"belief on the true intention never above {threshold:g} before the product was finished"
    return (f"belief on the true intention first above {threshold:g} after {operations} operator "
            f"operation{'' if operations == 1 else 's'}")


def decision_times(seconds) -> dict[str, float | None]:
    """``decision_seconds_median``, ``decision_seconds_p95`` (the 95th percentile, linear between the closest
    ranks as numpy's default) and ``decision_seconds_max`` of the times ``seconds``, rounded to microseconds;
    None for each when there are none. Cost: O(n log n)."""
    times = np.asarray(list(seconds), dtype=np.float64)
    if times.size == 0:
        return {"decision_seconds_median": None, "decision_seconds_p95": None, "decision_seconds_max": None}
    return {"decision_seconds_median": round(float(np.median(times)), 6),
            "decision_seconds_p95": round(float(np.percentile(times, 95)), 6),
            "decision_seconds_max": round(float(times.max()), 6)}


@dataclass(frozen=True)
class Move:
    """What one robot action did in the world: its ``reward``, whether it was the intention's next step
    (``robot``: the robot helped), the operator's ``operations`` in the move and the operations done that some
    robot action does (``capable``)."""

    reward: float
    robot: bool
    operations: int
    capable: int


class World(Protocol):
    """The operator's side of an episode, in the model's terms (a world is used for one episode).

    ``wait`` (the wait action, -1 without one), ``discount``, ``n_observations``; ``done`` (operations done so
    far, by anyone); :meth:`finished`; :meth:`switch` (the operator changes its mind, by ``draw``; False when
    its state has no other completion); :meth:`act` (the world's move after the robot's action: a
    :class:`Move`); :meth:`observe` (the observation drawn after it); :meth:`p_true` (the belief on the true
    intention); :meth:`truth` (the :class:`~.episode.Step` fields of the true state); :meth:`updater` (its
    Bayes filter); :meth:`record` (the episode's fields of the truth, at the end)."""

    wait: int
    discount: float
    n_observations: int
    done: int

    def finished(self) -> bool: ...

    def switch(self, draw: float) -> bool: ...

    def act(self, action: int, rng: np.random.Generator, operator: str) -> Move: ...

    def observe(self, action: int, rng: np.random.Generator) -> int: ...

    def p_true(self, belief) -> float: ...

    def truth(self) -> dict: ...

    def updater(self, deviating: bool): ...

    def record(self, episode: Episode) -> None: ...


def simulate_episode(world: World, policy, rng: np.random.Generator, max_steps: int = 100, operator: str = "model",
                     switch=None, mistakes=None, updater=None) -> Episode:
    """One episode in ``world`` until the product is finished or ``max_steps``; ``policy.action(belief)`` picks
    the robot's actions on the belief of ``updater`` (default: the world's own Bayes filter).

    ``operator`` (:data:`OPERATORS`): ``"model"`` draws the operator's timing from the model; ``"turns"``
    makes it act whenever the model lets it (on a world over intentions, with the intention graph's
    successors). ``switch`` (an :class:`~planner.decision.operators.Switch`): the operator changes its mind
    once, at the first step with ``switch.after`` operations done, to another completion of its assembly state
    (at a later state when that one has none). ``mistakes`` (rate, generator): at each step, with that
    probability, the observation is a wrong part's (:func:`~planner.decision.operators.mistaken_observation`);
    its draws come from that generator alone. Cost: ``max_steps`` decisions, updates and world moves.
    """
    if operator not in OPERATORS:
        raise ValueError(f"operator must be one of {OPERATORS}, got {operator!r}")
    if updater is None:  # a deviating operator's resets are counted, not warned about
        updater = world.updater(mistakes is not None or switch is not None)
    belief = updater.initialize()
    episode = Episode(beliefs=[belief])
    operations, discount = 0, 1.0
    for _ in range(max_steps):
        if world.finished():
            break
        if switch is not None and episode.switched_at is None and world.done >= switch.after \
                and world.switch(switch.draw):  # else at the next state that has another completion
            episode.switched_at = len(episode.steps) + 1
        started = time.perf_counter()
        action = int(policy.action(belief))
        seconds = time.perf_counter() - started
        move = world.act(action, rng, operator)
        z = world.observe(action, rng)
        z, mistake = operator_mistake(z, world.n_observations, mistakes)
        belief = updater.update(belief, action, z)
        episode.discounted_return += discount * move.reward
        discount *= world.discount
        operations += move.operations
        episode.robot_capable += move.capable
        episode.steps.append(Step(action, z, world.p_true(belief), operations, move.reward, seconds,
                                  robot_operation=move.robot, wrong_action=action != world.wait and not move.robot,
                                  mistake=mistake, **world.truth()))
        episode.beliefs.append(belief)
    episode.resets = len(updater.events)
    world.record(episode)
    return episode


def operator_mistake(observation: int, n_observations: int, mistakes) -> tuple[int, bool]:
    """The observation the camera sees when the operator may take a wrong part (``mistakes``: rate, generator;
    two draws per step whatever happens), and whether it did."""
    if mistakes is None:
        return observation, False
    rate, stream = mistakes
    happens, pick = stream.random(2)
    if happens >= rate:
        return observation, False
    return mistaken_observation(observation, n_observations, float(pick)), True


class IntentionWorld:
    """The world over intentions: the true intention ``start`` of ``model`` (a POMDP: the flat model's tables, or
    a file's) moves by the transitions and emits by the observations of ``world`` (default: ``model``'s own; a
    model with deviations plays the paper's tables, :attr:`~planner.decision.intention_model.IntentionModel.world`,
    the operator deviating itself), the rewards being the robot model's.

    ``final``: the finished product's intention (None: the episode runs to its step limit). ``successor`` (the
    intention graph's successor array) lets it count operator operations (a move of the true intention that
    the robot's action does not explain) and the operator take turns; ``first_state`` (the graph's) lets it
    change its mind. ``camera`` (with ``successor``): the observation of each intention's next step
    (:func:`~.camera_world.intention_step_observations`), for the camera world (:mod:`.camera_world`: the
    observation is the operation the operator did), in place of the tables' observations. Cost per step: a row
    of each table, plus O(length x actions) to count the operations.
    """

    def __init__(self, model: POMDP, start: int, successor: np.ndarray | None = None, final: int | None = None,
                 first_state: np.ndarray | None = None, world: POMDP | None = None, camera: np.ndarray | None = None):
        if camera is not None and successor is None:
            raise ValueError("the camera world needs the intention graph's successors (which step was done)")
        self.model, self.state, self.start, self.final = model, int(start), int(start), final
        self.successor, self.first_state, self.camera, self.seen = successor, first_state, camera, None
        self.tables = world if world is not None else model
        self.transition = [t.tocsr() for t in self.tables.transition]
        self.observation = [o.tocsr() for o in self.tables.observation]
        self.wait = model.actions.index("wait") if "wait" in model.actions else -1
        self.discount, self.n_observations = model.discount, len(model.observations)
        self.done, self.switched_to = 0, None

    def finished(self) -> bool:
        return self.final is not None and self.state == self.final

    def switch(self, draw: float) -> bool:
        other = switch_intention(self.first_state, self.state, draw)
        if other == self.state:
            return False
        self.state = self.switched_to = other
        return True

    def act(self, action: int, rng: np.random.Generator, operator: str) -> Move:
        state, successor = self.state, self.successor
        reward = float(self.model.reward[action, state])
        row = self.transition[action].getrow(state)
        if operator == "turns" and successor is not None:
            nxt = int(max(row.indices, key=lambda t: _moves(successor, state, int(t))))
        else:
            nxt = int(rng.choice(row.indices, p=row.data / row.data.sum()))
        robot = action != self.wait and _moves_intention(self.tables, action, state)
        operations = capable = 0
        self.seen = None  # the observation of the operator's operation of the step (camera world)
        if successor is not None and nxt != state:
            moved = _moves(successor, state, nxt)
            self.done += moved
            operations = moved - (1 if robot else 0)
            capable = _capable_between(self.model, successor, state, nxt, self.wait)
            if self.camera is not None and operations > 0:  # the operator stepped from the intention before nxt
                before = int(successor[state]) if robot else state
                self.seen = int(self.camera[before])
        self.state = nxt
        return Move(reward, robot, operations, capable)

    def observe(self, action: int, rng: np.random.Generator) -> int:
        if self.camera is not None:
            return camera_observation(self.seen, rng)
        row = self.observation[action].getrow(self.state)
        return int(rng.choice(row.indices, p=row.data / row.data.sum()))

    def p_true(self, belief: np.ndarray) -> float:
        return float(belief[self.state])

    def truth(self) -> dict:
        return {"state": self.state}

    def updater(self, deviating: bool) -> DiscreteUpdater:
        return DiscreteUpdater(self.model, on_reset=(lambda event: None) if deviating else None)

    def record(self, episode: Episode) -> None:
        episode.start, episode.final, episode.switched_to = self.start, self.final, self.switched_to


def _moves_intention(model: POMDP, action: int, state: int) -> bool:
    """True when ``action`` is the intention's next step: it moves it (other operations leave it)."""
    row = model.transition[action].getrow(state)
    return not (row.nnz == 1 and row.indices[0] == state)


def _capable_between(model: POMDP, successor: np.ndarray, a: int, b: int, wait: int) -> int:
    """How many of the operations from intention a to b (along the successors) some robot action does: an
    intention's next step is robot-capable when an action other than wait moves it. Cost: O(steps x actions)."""
    count = 0
    while a != b and a >= 0:
        count += any(_moves_intention(model, action, a) for action in range(len(model.actions)) if action != wait)
        a = successor[a]
    return count


def _moves(successor: np.ndarray, a: int, b: int) -> int:
    """Steps from intention a to b along the successors (-1 when b does not follow a)."""
    steps = 0
    while a != b:
        if a < 0:
            return -1
        a = successor[a]
        steps += 1
    return steps
