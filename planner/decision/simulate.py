"""Play an operator against a policy: episodes and evaluation (their Fig. 7 plot: :mod:`.belief_plot`).

The true intention evolves by the model's transitions (the operator's timing is random: it acts with
probability 1/2 per step, as the model says) and emits observations by the model's observation table; the
robot acts by the policy on the Bayes filter's belief. With a plan's intention graph at hand, the episode
also counts the operator's own operations, to report after how many of them the belief on the true
intention first exceeds a threshold before the product is finished (the paper saw 2, 2 and 4 in its three
runs); :func:`decision_times` sums up the time the policy took per decision.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..defaults import CONFIDENCE
from .belief import DiscreteUpdater
from .episode import Episode, Step
from .operators import mistaken_observation, switch_intention
from .policy import AlphaVectorPolicy
from .pomdp import POMDP

__all__ = ["Step", "Episode", "confidence_text", "decision_times", "evaluate_policy", "simulate_episode",
           "operator_mistake"]


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


OPERATORS = ("turns", "model")


def simulate_episode(model: POMDP, policy: AlphaVectorPolicy, start: int, rng: np.random.Generator,
                     max_steps: int = 100, successor: np.ndarray | None = None,
                     final: int | None = None, operator: str = "model", switch=None,
                     first_state: np.ndarray | None = None, mistakes=None, world: POMDP | None = None) -> Episode:
    """One episode from the true intention ``start`` until ``final`` (the finished product) or ``max_steps``.

    ``operator``: ``"model"`` draws the operator's timing from the model (it acts with probability 1/2 per
    step); ``"turns"`` makes it act whenever the model lets it (human and robot take turns, as in the
    paper's experiment; needs ``successor``). Observations are always drawn from the model.
    ``successor`` (the intention graph's successor array) lets the episode count operator operations: a
    move of the true intention that the robot's own action does not explain. ``switch`` (an
    :class:`~planner.decision.operators.Switch`; needs ``successor`` and the graph's ``first_state``): the
    operator changes its mind once, after that many operations, to another intention of its assembly state.
    ``mistakes`` (rate, generator): at each step, with that probability, the observation is a wrong part's
    (:func:`~planner.decision.operators.mistaken_observation`); its draws come from that generator alone.
    ``world``: the tables the world plays when they are not the robot's model's (a model with deviations:
    :attr:`~planner.decision.intention_model.IntentionModel.world`, the paper's; the operator deviates itself).
    """
    if operator not in OPERATORS:
        raise ValueError(f"operator must be one of {OPERATORS}, got {operator!r}")
    updater = DiscreteUpdater(model) if mistakes is None and switch is None else \
        DiscreteUpdater(model, on_reset=lambda event: None)  # a deviating operator's resets are counted instead
    belief = updater.initialize()
    episode = Episode(beliefs=[belief], start=start, final=final)
    wait = model.actions.index("wait") if "wait" in model.actions else -1
    state, operations, discount, done = start, 0, 1.0, 0
    tables = world if world is not None else model
    transition = [t.tocsr() for t in tables.transition]
    observation = [o.tocsr() for o in tables.observation]
    for _ in range(max_steps):
        if final is not None and state == final:
            break
        if switch is not None and episode.switched_at is None and done >= switch.after:
            other = switch_intention(first_state, state, switch.draw)
            if other != state:  # else at the next state that has another completion
                state = episode.switched_to = other
                episode.switched_at = len(episode.steps) + 1
        started = time.perf_counter()
        action = policy.action(belief)
        seconds = time.perf_counter() - started
        reward = float(model.reward[action, state])
        row = transition[action].getrow(state)
        if operator == "turns" and successor is not None:
            nxt = int(max(row.indices, key=lambda t: _moves(successor, state, int(t))))
        else:
            nxt = int(rng.choice(row.indices, p=row.data / row.data.sum()))
        robot_did_step = action != wait and _moves_intention(tables, action, state)
        if successor is not None and nxt != state:
            done += _moves(successor, state, nxt)
            operations += _moves(successor, state, nxt) - (1 if robot_did_step else 0)
            episode.robot_capable += _capable_between(model, successor, state, nxt, wait)
        orow = observation[action].getrow(nxt)
        z = int(rng.choice(orow.indices, p=orow.data / orow.data.sum()))
        z, mistake = operator_mistake(z, len(model.observations), mistakes)
        belief = updater.update(belief, action, z)
        episode.discounted_return += discount * reward
        discount *= model.discount
        state = nxt
        episode.steps.append(Step(action, z, float(belief[state]), operations, reward, seconds,
                                  robot_operation=robot_did_step, wrong_action=action != wait and not robot_did_step,
                                  mistake=mistake, state=state))
        episode.beliefs.append(belief)
    episode.resets = len(updater.events)
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


def evaluate_policy(model: POMDP, policy: AlphaVectorPolicy, episodes: int, seed: int = 0, max_steps: int = 100,
                    final: int | None = None, world: POMDP | None = None) -> tuple[float, float, list[float]]:
    """Mean discounted return over ``episodes`` episodes (start drawn from the initial belief) and the
    half-width of its 95 % confidence interval (normal approximation); ``world``: :func:`simulate_episode`'s."""
    rng = np.random.default_rng(seed)
    returns = []
    starts = rng.choice(model.n_states, size=episodes, p=model.initial)
    for start in starts:
        returns.append(simulate_episode(model, policy, int(start), rng, max_steps, final=final,
                                        world=world).discounted_return)
    mean = float(np.mean(returns))
    half = 1.96 * float(np.std(returns, ddof=1)) / math.sqrt(episodes) if episodes > 1 else float("nan")
    return mean, half, returns
