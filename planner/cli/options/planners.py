"""The planner bundle (who decides: ``--planner``, ``--policy``, ``--time-limit``, ``--decision-time``,
``--expansions``, read into one :class:`~planner.api.specs.PlannerChoice`) and the episode options of simulate and
evaluate (read with simulate's ``--sequence``, ``--all``, ``--random`` and ``--operator``, or evaluate's
``--episodes``, into one :class:`~planner.api.specs.EpisodeChoice`)."""
from __future__ import annotations

import argparse

from ... import api
from ...decision.camera_world import CAMERA_BLANK, WORLDS
from ...decision.operators import parse_operator
from ...defaults import DECISION_TIME, DECISION_TIME_MAX, EXPANSION_LIMIT, POLICY_TIME_LIMIT, STEP_LIMIT, TIME_LIMIT_MAX
from ...errors import PlannerError

from .models import add_decision_options
from .values import decision_seconds, index, number, positive_seconds

__all__ = ["add_policy_options", "planner_choice_from", "online_budget", "add_episode_options", "episode_choice_from",
           "operator_model"]


def add_policy_options(parser: argparse.ArgumentParser) -> None:
    """Who decides (simulate, evaluate, session): the offline policy in a file, the offline solver's after
    --time-limit, or the online planner within --decision-time per decision."""
    group = parser.add_argument_group("planner")
    group.add_argument("--planner", choices=("offline", "online"), default=None,
                       help="offline: follow a policy (--policy, or solve the flat model for --time-limit s); "
                            "online: search the factored model at every decision (any product size). Default: "
                            "offline with --policy, else online")
    group.add_argument("--policy", metavar="POLICY",
                       help="a .policy file over the model's intentions, or over its classes (aplan solve --lumped); "
                            "with --planner online, a policy over the classes is the lower bound the search starts "
                            "from")
    group.add_argument("--time-limit", type=positive_seconds, default=POLICY_TIME_LIMIT,
                       help=f"offline solver seconds when --planner offline and no --policy "
                            f"(default {POLICY_TIME_LIMIT:g}; at most {TIME_LIMIT_MAX:,})")
    group.add_argument("--decision-time", type=decision_seconds, default=None, metavar="S",
                       help=f"online planner: seconds per decision (default {DECISION_TIME:g}; at most "
                            f"{DECISION_TIME_MAX:g})")
    group.add_argument("--expansions", type=number(1, EXPANSION_LIMIT, integer=True), default=None, metavar="N",
                       help=f"online planner: expansions per decision, 1 to {EXPANSION_LIMIT:,}; alone, a fixed amount "
                            "of work without a clock (the same actions on any machine)")


def planner_choice_from(args: argparse.Namespace) -> api.PlannerChoice:
    """Who decides, as ``args`` ask (:func:`add_policy_options`), as one :class:`~planner.api.specs.PlannerChoice`."""
    decision_time, expansions = online_budget(args)
    return api.PlannerChoice(args.planner, args.policy, decision_time, expansions, args.time_limit)


def online_budget(args: argparse.Namespace) -> tuple[float | None, int | None]:
    """(decision time, expansions) from --decision-time and --expansions (module defaults when neither)."""
    if args.expansions is not None and args.decision_time is None:
        return None, args.expansions
    return (args.decision_time if args.decision_time is not None else DECISION_TIME), args.expansions


def add_episode_options(parser: argparse.ArgumentParser) -> None:
    """Options shared by simulate and evaluate."""
    parser.add_argument("--seed", type=index, default=0, help="the random stream's seed, a whole number from 0 "
                        "(default 0): the same seed plays the same episodes")
    parser.add_argument("--max-steps", type=number(1, STEP_LIMIT, integer=True), default=100, metavar="N",
                        help=f"steps per episode at most, 1 to {STEP_LIMIT:,} (default 100)")
    parser.add_argument("--operator-sequence", type=operator_model, metavar="SPEC", dest="operator_model",
                        help="which sequences the simulated operator does (needs --random N with simulate): "
                             "uniform (every full sequence equally likely, whatever the robot's model); "
                             "habitual:K:STRENGTH (sequence K, numbered as --sequence numbers them, with "
                             "probability STRENGTH in [0, 1], else uniform); changing:P (with probability P in "
                             "[0, 1) per episode it switches once, at a point of its sequence drawn uniformly among "
                             "those whose state has another completion, to another one; after habitual:K:S, as "
                             "habitual:K:S,changing:P); "
                             ",mistakes:Q last: with probability Q in [0, 1) per step a wrong part is taken and "
                             "put back (the camera sees another observation); drawn from "
                             "--seed before any episode, so two planners face the same operators. Default: the "
                             "model's initial belief (with --habits, the habits)")
    parser.add_argument("--world", choices=WORLDS, default="model",
                        help="what the simulated camera reports: model (default, the paper's observation model: an "
                             "observation of any operation into the current state, blank at a quarter weight, even "
                             "when the operator did nothing) or camera (the operation the operator did, blank with "
                             f"probability {CAMERA_BLANK:g}; blank when it did nothing), as the camera cell sees it")
    add_decision_options(parser)


def episode_choice_from(args: argparse.Namespace) -> api.EpisodeChoice:
    """The episodes ``args`` ask for, as one :class:`~planner.api.specs.EpisodeChoice`: simulate's
    ``--sequence``, ``--all`` or ``--random`` and ``--operator``, or evaluate's ``--episodes`` (drawn at random),
    with :func:`add_episode_options`' ``--seed``, ``--max-steps``, ``--operator-sequence`` and ``--world``."""
    return api.EpisodeChoice(sequences=tuple(getattr(args, "sequence", None) or ()), every=getattr(args, "all", False),
                             random=getattr(args, "random", None) or getattr(args, "episodes", None), seed=args.seed,
                             max_steps=args.max_steps, operator=getattr(args, "operator", "model"),
                             operator_model=args.operator_model, world=args.world)


def operator_model(text: str):
    """``--operator-sequence``: the operator model (:func:`planner.decision.operators.parse_operator`)."""
    try:
        return parse_operator(text)
    except PlannerError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
