"""Play an operator against a policy: episodes, the belief over time (Fig. 7), and evaluation.

The true intention evolves by the model's transitions (the operator's timing is random: it acts with
probability 1/2 per step, as the model says) and emits observations by the model's observation table; the
robot acts by the policy on the Bayes filter's belief. With a plan's intention graph at hand, the episode
also counts the operator's own operations, to report after how many of them the belief on the true
intention first exceeds a threshold (the paper saw 2, 2 and 4 in its three runs).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from ..defaults import CONFIDENCE
from ..files import save_figure
from .belief import DiscreteUpdater
from .policy import AlphaVectorPolicy
from .pomdp import POMDP

__all__ = ["Step", "Episode", "simulate_episode", "evaluate_policy", "plot_beliefs"]


@dataclass(frozen=True)
class Step:
    action: int
    observation: int
    state: int              # the true intention after the step
    p_true: float           # the belief on it after the update
    operator_operations: int  # operations the operator has performed so far
    reward: float


@dataclass
class Episode:
    start: int
    steps: list[Step] = field(default_factory=list)
    beliefs: list[np.ndarray] = field(default_factory=list)  # before the first step, then after each
    discounted_return: float = 0.0

    def first_confident(self, threshold: float = CONFIDENCE) -> int | None:
        """Operator operations done when the belief on the true intention first exceeds ``threshold``."""
        return next((s.operator_operations for s in self.steps if s.p_true > threshold), None)


OPERATORS = ("turns", "model")


def simulate_episode(model: POMDP, policy: AlphaVectorPolicy, start: int, rng: np.random.Generator,
                     max_steps: int = 100, successor: np.ndarray | None = None,
                     final: int | None = None, operator: str = "model") -> Episode:
    """One episode from the true intention ``start`` until ``final`` (the finished product) or ``max_steps``.

    ``operator``: ``"model"`` draws the operator's timing from the model (it acts with probability 1/2 per
    step); ``"turns"`` makes it act whenever the model lets it (human and robot take turns, as in the
    paper's experiment; needs ``successor``). Observations are always drawn from the model.
    ``successor`` (the intention graph's successor array) lets the episode count operator operations: a
    move of the true intention that the robot's own action does not explain.
    """
    if operator not in OPERATORS:
        raise ValueError(f"operator must be one of {OPERATORS}, got {operator!r}")
    updater = DiscreteUpdater(model)
    belief = updater.initialize()
    episode = Episode(start, beliefs=[belief])
    wait = model.actions.index("wait") if "wait" in model.actions else -1
    state, operations, discount = start, 0, 1.0
    transition = [t.tocsr() for t in model.transition]
    observation = [o.tocsr() for o in model.observation]
    for _ in range(max_steps):
        if final is not None and state == final:
            break
        action = policy.action(belief)
        reward = float(model.reward[action, state])
        row = transition[action].getrow(state)
        if operator == "turns" and successor is not None:
            nxt = int(max(row.indices, key=lambda t: _moves(successor, state, int(t))))
        else:
            nxt = int(rng.choice(row.indices, p=row.data / row.data.sum()))
        if successor is not None and nxt != state:
            robot_did_step = action != wait and _moves_intention(model, action, state)
            operations += _moves(successor, state, nxt) - (1 if robot_did_step else 0)
        orow = observation[action].getrow(nxt)
        z = int(rng.choice(orow.indices, p=orow.data / orow.data.sum()))
        belief = updater.update(belief, action, z)
        episode.discounted_return += discount * reward
        discount *= model.discount
        state = nxt
        episode.steps.append(Step(action, z, state, float(belief[state]), operations, reward))
        episode.beliefs.append(belief)
    return episode


def _moves_intention(model: POMDP, action: int, state: int) -> bool:
    """True when ``action`` is the intention's next step: it moves it (other operations leave it)."""
    row = model.transition[action].getrow(state)
    return not (row.nnz == 1 and row.indices[0] == state)


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
                    final: int | None = None) -> tuple[float, float, list[float]]:
    """Mean discounted return over ``episodes`` episodes (start drawn from the initial belief) and the
    half-width of its 95 % confidence interval (normal approximation)."""
    rng = np.random.default_rng(seed)
    returns = []
    starts = rng.choice(model.n_states, size=episodes, p=model.initial)
    for start in starts:
        returns.append(simulate_episode(model, policy, int(start), rng, max_steps, final=final).discounted_return)
    mean = float(np.mean(returns))
    half = 1.96 * float(np.std(returns, ddof=1)) / math.sqrt(episodes) if episodes > 1 else float("nan")
    return mean, half, returns


def plot_beliefs(episodes: list[Episode], path_stem: str, titles: list[str] | None = None,
                 line_label: str = "true intention") -> list[str]:
    """Fig. 7-style heat maps (belief over intentions per time step, darker = more probable) with each
    episode's ``start`` and steps' ``state`` drawn as a line (the true intention; a replayed session, which
    does not know it, draws the most probable one and says so in ``line_label``); writes ``path_stem.png``
    and ``path_stem.svg`` (each atomically) and returns their paths."""
    from matplotlib.figure import Figure  # no pyplot: its backend and figures are process-wide state

    fig = Figure(figsize=(3.2 * len(episodes), 4.2))
    axes = fig.subplots(1, len(episodes), squeeze=False)
    for k, (episode, ax) in enumerate(zip(episodes, axes[0])):
        grid = np.stack(episode.beliefs, axis=1)
        ax.imshow(grid, aspect="auto", cmap="Greys", vmin=0, vmax=1, interpolation="nearest", origin="lower")
        truth = [episode.start] + [s.state for s in episode.steps]
        ax.plot(range(len(truth)), truth, color=f"C{k % 10}", linewidth=1.5, label=line_label)
        ax.legend(loc="upper right", fontsize=7)
        ax.set_xlabel("time step")
        ax.set_ylabel("intention")
        ax.set_title(titles[k] if titles else f"episode {k + 1}", fontsize=9)
    fig.tight_layout()
    written: list[str] = []
    try:
        for suffix in (".png", ".svg"):
            written.append(save_figure(fig, path_stem + suffix, dpi=120))
    except BaseException:  # both pictures or neither (a full disk, an interrupt between them)
        for path in written:
            os.unlink(path)
        raise
    return written
