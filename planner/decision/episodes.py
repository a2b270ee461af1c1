"""Which episodes are played, and playing them on any decision model: :class:`EpisodeChoice`, :func:`simulate`,
:func:`evaluate` and :func:`evaluate_operator` (``planner.api`` re-exports them).

Every episode runs in the one loop of :func:`~.simulate.simulate_episode`, in the world of its model, told
apart through the decision-model interface (:mod:`.models`): over intentions (the flat model, a file's POMDP:
:class:`~.simulate.IntentionWorld`) or along a full sequence's state edges (the factored model, and the lumped
model, whose policies read the factored filter's beliefs: :class:`~.factored_simulate.PathWorld`).
"""
from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from ..assembly.guards import Progress
from ..defaults import EPISODE_LIMIT, STEP_LIMIT
from ..errors import PlannerError, UsageError
from ..validation import check_number
from .camera_world import check_world, intention_step_observations
from .episode import Episode
from .factored_simulate import PathWorld
from .models import Model, filtered, final_of, is_factored, is_flat, of_product, tables
from .operators import mistake_stream
from .simulate import OPERATORS, IntentionWorld, simulate_episode

__all__ = ["EpisodeChoice", "simulate", "evaluate", "evaluate_operator", "world_of", "world_maker"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class EpisodeChoice:
    """Which episodes a simulation or an evaluation plays, built once by a front end and passed down.

    The full sequences played: the listed ``sequences`` (intention numbers on the flat model, ranks from 0 on
    the factored one; ``what`` names them in errors, e.g. ``--sequence``), ``every`` one, or ``random`` ones
    drawn from the model's initial belief (an evaluation's episodes: it needs ``random``); at most one of the
    three, and by default the first sequence. ``seed`` seeds the one random stream that draws the sequences
    and then every episode; ``max_steps``: the decision steps of an episode at most; ``operator``
    (:data:`~.simulate.OPERATORS`): ``model`` (the operator acts with the model's probability, 1/2 per step) or
    ``turns`` (whenever the model lets it, as in the paper's experiment); ``operator_model``
    (:mod:`~planner.decision.operators`; with ``random`` only): draws the ``random`` plans (sequences, changes
    of mind, mistakes) instead of the initial belief, before any episode. ``world``
    (:data:`~.camera_world.WORLDS`): what the simulated camera reports, ``model`` (the paper's observation
    model, the default) or ``camera`` (the operation the operator did; :mod:`.camera_world`; a product's model
    only).

    Raises :class:`~planner.validation.InputError` for a number that is not a whole number in its range
    (``random`` 1 to ``EPISODE_LIMIT``, ``max_steps`` 1 to ``STEP_LIMIT``, ``seed`` and ``sequences`` from 0)
    and :class:`~planner.errors.UsageError` for choices that do not go together. Cost: O(len(sequences)).
    """

    sequences: tuple[int, ...] = ()
    every: bool = False
    random: int | None = None
    seed: int = 0
    max_steps: int = 100
    operator: str = "model"
    operator_model: object | None = None
    what: str = "--sequence"
    world: str = "model"

    def __post_init__(self) -> None:
        object.__setattr__(self, "sequences", tuple(_whole(k, self.what, 0) for k in self.sequences or ()))
        if self.random is not None:
            object.__setattr__(self, "random", _whole(self.random, "random", 1, EPISODE_LIMIT))
        object.__setattr__(self, "seed", _whole(self.seed, "seed", 0))
        object.__setattr__(self, "max_steps", _whole(self.max_steps, "max_steps", 1, STEP_LIMIT))
        if not isinstance(self.every, bool):
            raise UsageError(f"episodes: every must be True or False, got {self.every!r}")
        check_world(self.world)
        if self.operator not in OPERATORS:
            raise UsageError(f"episodes: unknown operator {self.operator!r}; use one of {', '.join(OPERATORS)}")
        if sum((bool(self.sequences), self.every, self.random is not None)) > 1:
            raise UsageError("episodes: give the listed sequences, every one or random ones, not several")
        if self.operator_model is not None and self.random is None:
            raise PlannerError("--operator-sequence draws the sequences the operator does: give --random N "
                               "(not --sequence or --all)")


def _whole(value, name: str, low: int, high: int | None = None) -> int:
    """``value`` as a whole number in ``[low, high]`` (a bool is not one), else the error naming ``name``."""
    if isinstance(value, (bool, np.bool_)):
        raise UsageError(f"episodes: {name} must be a whole number, got {value!r}")
    return check_number(value, f"episodes: {name}", low, high, integer=True)


def world_of(model: Model, truth, world: str = "model") -> IntentionWorld | PathWorld:
    """The world of ``model`` (of :func:`~.models.filtered`) whose true state starts at ``truth``: an intention
    (a state of a file's POMDP) or a full sequence's state edges (the factored model); ``world``: its camera
    (:data:`~.camera_world.WORLDS`; ``camera`` needs a product's model). Cost: O(tables)."""
    return world_maker(model, world)(truth)


def world_maker(model: Model, world: str = "model") -> Callable[[object], IntentionWorld | PathWorld]:
    """:func:`world_of` for many truths of one model: what every world shares is computed once (the flat camera
    world's observation of each intention's next step, O(intentions)). Raises
    :class:`~planner.errors.PlannerError` for the camera world of a model file."""
    model, camera = filtered(model), check_world(world) == "camera"
    if is_factored(model):
        return lambda truth: PathWorld(model, truth, camera)
    if is_flat(model):
        steps = intention_step_observations(model.plan, model.graph) if camera else None
        return lambda truth: IntentionWorld(model.pomdp, truth, model.graph.successor, model.final_state,
                                            model.graph.first_state, model.world, steps)
    if camera:
        raise PlannerError("--world camera needs a PRODUCT (which operation the operator did), not a model file; "
                           "use --world model")
    return lambda truth: IntentionWorld(model, truth)


def simulate(model: Model, policy, choice: EpisodeChoice = EpisodeChoice()) -> list[Episode]:
    """One :class:`~.episode.Episode` per full sequence ``choice`` plays (:class:`EpisodeChoice`) on a product's
    model (flat, factored or lumped): ``Episode.start`` its intention on the flat model, ``Episode.path`` its
    state edges on the factored one. On the factored model random sequences are drawn uniformly without
    enumerating them. Cost: the episodes' (:func:`~.simulate.simulate_episode`)."""
    model = filtered(model)  # a lumped model's policies are over classes: the factored filter runs them
    if not of_product(model):
        raise PlannerError("simulate needs a PRODUCT (its full sequences), not a model file")
    if choice.operator_model is not None:
        return _simulate_operator(model, policy, choice)
    rng = np.random.default_rng(choice.seed)
    truths = _paths(model, choice, rng) if is_factored(model) else _starts(model, choice, rng)
    make = world_maker(model, choice.world)
    return [simulate_episode(make(truth), policy, rng, choice.max_steps, choice.operator) for truth in truths]


def _starts(model, choice: EpisodeChoice, rng: np.random.Generator) -> list[int]:
    """The flat model's intentions played, drawn before any episode."""
    starts = [int(s) for s in model.full_sequences()]
    if choice.every:
        return starts
    if choice.random:  # from the initial belief: uniform, or the operator's habits
        prior = None if model.prior_weights is None else model.pomdp.initial[starts]
        return [int(s) for s in rng.choice(starts, size=choice.random, p=prior)]
    return [model.full_sequence(s, choice.what) for s in (choice.sequences or [starts[0]])]


def _paths(model, choice: EpisodeChoice, rng: np.random.Generator) -> list[list[int]]:
    """The factored model's full sequences (state edges) played, drawn before any episode."""
    if choice.every:
        if model.n_sequences > 10_000:
            raise PlannerError(f"the product has {model.n_sequences:,} full sequences: too many to play every one; "
                               "use --random N or --sequence K")
        return [model.sequence(k) for k in range(model.n_sequences)]
    if choice.random:
        return [model.sample_sequence(rng) for _ in range(choice.random)]
    paths = []
    for k in choice.sequences or [0]:
        if not 0 <= k < model.n_sequences:
            raise PlannerError(f"{choice.what} {k}: with the online planner sequences are numbered by rank, from 0 "
                               f"to {model.n_sequences - 1:,}")
        paths.append(model.sequence(k))
    return paths


def _simulate_operator(model, policy, choice: EpisodeChoice) -> list[Episode]:
    seed, operator_model = choice.seed, choice.operator_model
    rng = np.random.default_rng(seed)  # the plans first, as the default draws, then the episodes
    plans = operator_model.plans(model, choice.random, rng, np.random.default_rng([seed, 1]))
    rate, make = operator_model.mistakes, world_maker(model, choice.world)
    return [simulate_episode(make(plan.sequence), policy, rng, choice.max_steps, choice.operator,
                             plan.switch, (rate, mistake_stream(seed, k)) if rate > 0 else None)
            for k, plan in enumerate(plans)]


def evaluate(model: Model, policy, choice: EpisodeChoice) -> tuple[float, float]:
    """The mean discounted return over the ``choice.random`` episodes of ``choice`` and its 95 % confidence
    half-width (normal approximation; NaN for one episode). Each episode's start is drawn from the initial
    belief (the flat model's and a file's all at once, the factored model's sequence before each episode);
    episodes of an intention model (flat, factored or lumped) end at the finished product. With
    ``choice.operator_model``: :func:`evaluate_operator`'s. Cost: the episodes'."""
    if choice.operator_model is not None:
        return evaluate_operator(model, policy, choice)[:2]
    if choice.random is None:
        raise UsageError("evaluate draws its episodes from the initial belief: give their number (random=N)")
    model, episodes, camera = filtered(model), choice.random, choice.world == "camera"
    rng = np.random.default_rng(choice.seed)
    if is_factored(model):
        truths = (model.sample_sequence(rng) for _ in range(episodes))  # each drawn before its episode
        worlds = (PathWorld(model, path, camera) for path in truths)
    else:  # the tables' states, all drawn first
        pomdp = tables(model)
        starts = rng.choice(pomdp.n_states, size=episodes, p=pomdp.initial)
        if camera:  # the camera needs the steps done: the world of simulate
            make = world_maker(model, choice.world)
        else:  # the operator's operations are not counted
            final, deviating = final_of(model), model.world if is_flat(model) else None  # deviations: its tables
            make = lambda start: IntentionWorld(pomdp, start, final=final, world=deviating)  # noqa: E731
        worlds = (make(int(start)) for start in starts)
    progress = Progress(log, after=5.0, every=10.0)
    returns, total = [], 0.0
    for k, played in enumerate(worlds):
        returns.append(simulate_episode(played, policy, rng, choice.max_steps, choice.operator).discounted_return)
        total += returns[-1]  # a running sum: the progress line costs O(1) per episode
        progress.report("evaluate: %d of %d episodes, mean return so far %.4f", k + 1, episodes, total / (k + 1))
    return _mean_and_half(returns)


def evaluate_operator(model: Model, policy, choice: EpisodeChoice) -> tuple[float, float, list[Episode]]:
    """:func:`evaluate` against ``choice.operator_model``: the episodes of :func:`simulate` (the same ones, for
    the same choice), their mean discounted return, its 95 % half-width and the episodes."""
    if choice.operator_model is None:
        raise UsageError("evaluate_operator plays an operator model: give EpisodeChoice(operator_model=...)")
    if not of_product(model):
        raise PlannerError("--operator-sequence needs a PRODUCT (its sequences), not a model file")
    played = simulate(model, policy, choice)
    return (*_mean_and_half([e.discounted_return for e in played]), played)


def _mean_and_half(returns: Sequence[float]) -> tuple[float, float]:
    half = 1.96 * float(np.std(returns, ddof=1)) / math.sqrt(len(returns)) if len(returns) > 1 else float("nan")
    return float(np.mean(returns)), half
