"""One simulator over every decision model: episodes and evaluation of a policy on the flat model (over
intentions, :mod:`.simulate`), the factored model (over classes, :mod:`.factored_simulate`; a lumped model's
policies run on its factored model) or a file's POMDP (evaluation only), chosen through the decision-model
interface (:mod:`.models`). ``planner.api`` re-exports :func:`simulate`, :func:`evaluate` and
:func:`evaluate_operator`.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..errors import PlannerError
from .factored_model import FactoredIntentionModel
from .episode import Episode
from .factored_simulate import evaluate_factored, simulate_factored_episode
from .intention_model import IntentionModel
from .models import Model, filtered, final_of, is_factored, is_flat, of_product, tables
from .operators import mistake_stream
from .simulate import evaluate_policy, simulate_episode

__all__ = ["simulate", "evaluate", "evaluate_operator"]


def simulate(model: IntentionModel | FactoredIntentionModel, policy, sequences: Sequence[int] | None = None,
             every: bool = False, random: int | None = None, seed: int = 0, max_steps: int = 100,
             operator: str = "model", what: str = "--sequence", operator_model=None
             ) -> list[Episode]:
    """One :class:`~.episode.Episode` per full sequence played (``Episode.start``; ``Episode.path`` on a
    factored model): ``every`` one, ``random`` ones drawn at
    random, the listed ``sequences`` (each checked), or by default the first. The operator follows its
    sequence (``operator``: ``model`` or ``turns``, see :func:`~planner.decision.simulate.simulate_episode`);
    one random stream, seeded by ``seed``, draws the sequences and then every episode.

    On a :class:`FactoredIntentionModel` the sequences are numbered by rank (0 to the number of sequences - 1,
    :meth:`~FactoredIntentionModel.sequence`) and random ones are drawn uniformly without enumerating them.

    ``operator_model`` (:mod:`planner.decision.operators`; with ``random`` only) draws the ``random`` plans
    (sequences and switches) instead of the model's initial belief, before any episode."""
    if operator_model is not None:
        return _simulate_operator(model, policy, operator_model, random, seed, max_steps, operator)
    if is_factored(model):
        return _simulate_factored(model, policy, sequences, every, random, seed, max_steps, operator, what)
    starts = [int(s) for s in model.full_sequences()]
    rng = np.random.default_rng(seed)
    if every:
        chosen = starts
    elif random:  # from the initial belief: uniform, or the operator's habits
        prior = None if model.prior_weights is None else model.pomdp.initial[starts]
        chosen = [int(s) for s in rng.choice(starts, size=random, p=prior)]
    else:
        chosen = [model.full_sequence(s, what) for s in (sequences or [starts[0]])]
    return [simulate_episode(model.pomdp, policy, start, rng, max_steps, model.graph.successor, model.final_state,
                             operator, world=model.world) for start in chosen]


def _simulate_operator(model, policy, operator_model, random, seed, max_steps, operator) -> list:
    if not random:
        raise PlannerError("--operator-sequence draws the sequences the operator does: give --random N "
                           "(not --sequence or --all)")
    rng = np.random.default_rng(seed)  # the plans first, as the default draws, then the episodes
    plans = operator_model.plans(model, random, rng, np.random.default_rng([seed, 1]))
    rate = operator_model.mistakes
    mistakes = [(rate, mistake_stream(seed, k)) if rate > 0 else None for k in range(len(plans))]
    if is_factored(model):
        return [simulate_factored_episode(model, policy, p.sequence, rng, max_steps, operator, p.switch, m)
                for p, m in zip(plans, mistakes)]
    return [simulate_episode(model.pomdp, policy, p.sequence, rng, max_steps, model.graph.successor,
                             model.final_state, operator, p.switch, model.graph.first_state, m, model.world)
            for p, m in zip(plans, mistakes)]


def evaluate_operator(model: Model | FactoredIntentionModel, policy, operator_model, episodes: int, seed: int = 0,
                      max_steps: int = 100) -> tuple[float, float, list]:
    """:func:`evaluate` against ``operator_model``: the episodes of :func:`simulate` with ``random=episodes``
    (the same ones, for the same seed), their mean discounted return, its 95 % half-width and the episodes."""
    model = filtered(model)  # a lumped model's policies are over classes: the factored filter runs them
    if not of_product(model):
        raise PlannerError("--operator-sequence needs a PRODUCT (its sequences), not a model file")
    played = simulate(model, policy, random=episodes, seed=seed, max_steps=max_steps, operator_model=operator_model)
    returns = [e.discounted_return for e in played]
    half = 1.96 * float(np.std(returns, ddof=1)) / math.sqrt(episodes) if episodes > 1 else float("nan")
    return float(np.mean(returns)), half, played


def _simulate_factored(model: FactoredIntentionModel, policy, sequences, every, random, seed, max_steps, operator,
                       what) -> list[Episode]:
    rng = np.random.default_rng(seed)
    if every:
        if model.n_sequences > 10_000:
            raise PlannerError(f"the product has {model.n_sequences:,} full sequences: too many to play every one; "
                               "use --random N or --sequence K")
        paths = [model.sequence(k) for k in range(model.n_sequences)]
    elif random:
        paths = [model.sample_sequence(rng) for _ in range(random)]
    else:
        paths = []
        for k in sequences or [0]:
            if not 0 <= int(k) < model.n_sequences:
                raise PlannerError(f"{what} {k}: with the online planner sequences are numbered by rank, from 0 to "
                                   f"{model.n_sequences - 1:,}")
            paths.append(model.sequence(int(k)))
    return [simulate_factored_episode(model, policy, path, rng, max_steps, operator) for path in paths]


def evaluate(model: Model | FactoredIntentionModel, policy, episodes: int, seed: int = 0,
             max_steps: int = 100) -> tuple[float, float]:
    """The mean discounted return over ``episodes`` simulated episodes and its 95 % confidence half-width;
    episodes of an intention model (flat, factored or lumped) end at the finished product."""
    model = filtered(model)  # a lumped model's policies are over classes: the factored filter runs them
    if is_factored(model):
        mean, half, _ = evaluate_factored(model, policy, episodes, seed, max_steps)
        return mean, half
    final = final_of(model)
    world = model.world if is_flat(model) else None  # deviations: the operator's own
    mean, half, _ = evaluate_policy(tables(model), policy, episodes, seed, max_steps, final, world)
    return mean, half
