"""The decision-model bundle (when MODEL is a product): technical constraints, base part, discount, rewards, habits,
the parallel model, change of mind and mistakes, read into one :class:`~planner.api.specs.ModelSpec`
(:func:`model_spec_from`)."""
from __future__ import annotations

import argparse

from ... import api
from ...decision.intention_model import Rewards
from ...decision.deviations import Deviations, deviations_of
from ...decision.habits import Habits
from ...decision.presets import CAMERA, CONFIDENT, HELPFUL, ORDERS, PRESETS, preset_rewards
from ...decision.joins import JOINS
from ...decision.parallel import parallel_flag
from ...decision.projected import PROJECTED, PROJECTED_CONFIDENCE
from ...decision.step_observations import OBSERVE, STATE, of_step
from ...defaults import DISCOUNT
from ...errors import PlannerError, UsageError

from .limits import add_input_options, add_size_options, inputs_from, limits_from
from .products import add_base_part, add_fasteners, add_hierarchy, add_model_options, add_technical
from .values import _probability, finite, number

__all__ = ["add_decision_options", "add_habits_options", "add_parallel_options", "add_deviation_options",
           "parallel_from", "rewards_from", "habits_from", "deviations_from", "model_spec_from",
           "add_observation_options", "observe_from"]


def add_decision_options(parser: argparse.ArgumentParser) -> None:
    """The decision model's options (when MODEL is a product): technical constraints, base part, discount,
    rewards."""
    d = Rewards()
    group = parser.add_argument_group("decision model (when MODEL is a product)")
    add_technical(group)
    add_base_part(group)
    add_fasteners(group)
    add_model_options(parser)
    group.add_argument("--discount", type=number(0, 1, high_open=True), default=DISCOUNT,
                       help=f"discount factor, from 0 to below 1 (default {DISCOUNT:g})")
    group.add_argument("--reward-unfavorable", type=finite, default=d.unfavorable, metavar="R",
                       help=f"robot does the next step, unfavorable to humans (default {d.unfavorable:g})")
    group.add_argument("--reward-favorable", type=finite, default=d.favorable, metavar="R",
                       help=f"robot does the next step, fine for humans (default {d.favorable:g})")
    eager = group.add_mutually_exclusive_group()
    eager.add_argument("--reward-wrong", type=finite, default=None, metavar="R",
                       help=f"robot does another operation: its eagerness (default {d.wrong:g})")
    eager.add_argument("--act-confidence", type=number(0, 1, low_open=True, high_open=True), default=None,
                       metavar="C", help="the robot's eagerness as the belief in the next operation at which doing it "
                                         "breaks even: sets --reward-wrong to (wait - C unfavorable) / (1 - C), e.g. "
                                         "0.98: -490 (default: the paper's -50, C = 5/6; docs/habits.md)")
    group.add_argument("--reward-wait", type=finite, default=d.wait, metavar="R", help=f"wait (default {d.wait:g})")
    add_hierarchy(group)
    add_habits_options(group)
    add_parallel_options(group)
    add_deviation_options(group)
    add_observation_options(group)
    add_size_options(parser)
    add_input_options(parser)


def add_habits_options(group) -> None:
    """``--habits FILE`` and ``--model paper|habits`` (operator habits, docs/habits.md)."""
    group.add_argument("--habits", metavar="FILE",
                       help="the operator's habits (aplan habits LOG... -o FILE) in place of the uniform choice "
                            "of Alg. 3, in every model and planner (docs/habits.md)")
    group.add_argument("--model", dest="habit_model", choices=tuple(PRESETS), default=None,
                       help="paper: the paper's model, ignoring --habits, --switch and --mistakes; habits (the "
                            "default with --habits): the habits' model; confident: the habits' model with the prior "
                            f"spread per state (alpha {CONFIDENT.prior:g} in all) and --act-confidence "
                            f"{CONFIDENT.act_confidence:g} unless given; orders: the habits file's recorded orders "
                            f"(whole sequences, a Pitman-Yor mixture) with --act-confidence {ORDERS.act_confidence:g} "
                            f"unless given (docs/habits.md, Orders); helpful: confident's habits with --joins (the "
                            f"robot may do any join of the operator's sequence early) and --act-confidence "
                            f"{HELPFUL.act_confidence:g} unless given (docs/parallel.md); {CAMERA.name}: helpful with "
                            "--observe step, the model of a camera cell (docs/camera.md)")


def add_parallel_options(group) -> None:
    """``--parallel`` and ``--projected``: the parallel models (docs/parallel.md); ``--model paper`` turns them off."""
    group.add_argument("--parallel", action="store_true",
                       help="the parallel model: the robot may do the operator's step after next now, when that "
                            "keeps the operator's next step possible (docs/parallel.md; on the classes: the online "
                            "planner or a lumped policy); --model paper turns it off")
    group.add_argument("--projected", action="store_true",
                       help="the projected model: the robot may do any operation now, right when the operator's "
                            "sequence projected onto the new state (the parts it joined, joined) stays feasible "
                            "(docs/parallel.md, The projected model; on the classes, as --parallel); acts from a "
                            f"belief of {PROJECTED_CONFIDENCE:g} (--act-confidence {PROJECTED_CONFIDENCE:g}) unless "
                            "--act-confidence or --reward-wrong is given; --model paper turns it off")
    group.add_argument("--joins", action="store_true",
                       help="the projected model with the robot's actions named by the parts they join (join P to "
                            "Q: right in every state where that join is the next or a projected step), so the robot "
                            "can act while unsure of the state (docs/parallel.md, Actions named by the parts they "
                            "join); as --projected otherwise")


def parallel_from(args: argparse.Namespace) -> bool | str:
    """The parallel model ``args`` ask for, as :func:`~planner.decision.factored_model.factored_model` takes it:
    True (``--parallel``), ``"projected"`` (``--projected``), ``"joins"`` (``--joins``, or a ``--model`` preset that
    sets it: ``helpful``) or False (none, or ``--model paper``); two at once is a :class:`~planner.errors.UsageError`,
    and so is a preset's model with another flag; a preset's with a model file or the flat model (``--planner
    offline`` without a policy) is a :class:`~planner.errors.PlannerError` naming the preset."""
    given = [flag for flag in ("parallel", "projected", "joins") if getattr(args, flag, False)]
    if len(given) > 1:
        raise UsageError(f"{' and '.join('--' + f for f in given)} are models of the robot's help before the last "
                         "step: give one of them (docs/parallel.md)")
    preset = PRESETS.get(getattr(args, "habit_model", None))
    if getattr(args, "habit_model", None) == "paper":
        return False
    if preset is not None and preset.parallel:
        flag = parallel_flag(preset.parallel)
        if given and "--" + given[0] != flag:
            raise UsageError(f"--model {preset.name} is the model of {flag}; leave out --{given[0]}, or choose "
                             "another --model (docs/parallel.md)")
        _check_preset_parallel(args, preset.name, flag)
        return preset.parallel
    if not given:
        return False
    return True if given[0] == "parallel" else given[0]


def _check_preset_parallel(args: argparse.Namespace, name: str, flag: str) -> None:
    """Where the preset ``name``'s parallel model (``flag``) cannot go: a model file (fixed tables), the flat
    model over intentions (``--planner offline`` without a policy: :func:`~planner.api.check_parallel_flat`)."""
    model = getattr(args, "model", None) or getattr(args, "product", None)
    if model is not None and api._model_file_kind(model):
        raise PlannerError(f"{model}: --model {name} is the model of {flag} on a PRODUCT's assembly states; a model "
                           "file's tables are fixed: give the PRODUCT, or another --model")
    if getattr(args, "planner", None) == "offline" and not getattr(args, "policy", None):
        raise PlannerError(f"--model {name} is the model of {flag}, over the factored model's classes, and --planner "
                           "offline without a policy builds the flat model over intentions, which cannot hold it: use "
                           f"the online planner (--planner online), or a policy over the classes (aplan solve PRODUCT "
                           f"--model {name} --habits FILE -o P.policy), or another --model")


def rewards_from(args: argparse.Namespace) -> Rewards:
    """The rewards of ``args``: ``--reward-wrong``, else ``--act-confidence``'s, else the more careful of the
    ``--model`` preset's and the projected model's own (``--projected``: :data:`~planner.decision.projected.
    PROJECTED_CONFIDENCE`), else the paper's (:func:`planner.decision.presets.preset_rewards`)."""
    rule = parallel_from(args)
    own = (parallel_flag(rule), PROJECTED_CONFIDENCE) if rule in (PROJECTED, JOINS) else None
    return preset_rewards(PRESETS.get(getattr(args, "habit_model", None)), args.reward_unfavorable,
                          args.reward_favorable, args.reward_wait, args.reward_wrong,
                          getattr(args, "act_confidence", None), own)


def habits_from(args: argparse.Namespace) -> Habits | None:
    """The habits a model-building command is to use: ``--habits`` read and checked, with the ``--model``
    preset's prior in place of the file's (``--model confident``), or None (``--model paper``, or no
    ``--habits``); ``--model habits`` or ``confident`` without ``--habits`` is an error
    (:func:`planner.api.habits_for`, which the workbench's session panel calls too)."""
    return api.habits_for(getattr(args, "habit_model", None), getattr(args, "habits", None), inputs_from(args))


def model_spec_from(args: argparse.Namespace) -> api.ModelSpec:
    """The decision model ``args`` ask for (:func:`add_decision_options`) as one
    :class:`~planner.api.specs.ModelSpec`, built once per command (a session builds it before its first level:
    the habits file is read once) and passed down. Cost: reading ``--habits``, if given."""
    return api.ModelSpec(technical=args.technical, rewards=rewards_from(args), discount=args.discount,
                         base_part=args.base_part, limits=limits_from(args), inputs=inputs_from(args),
                         habits=habits_from(args), parallel=parallel_from(args), deviations=deviations_from(args),
                         observe=observe_from(args))


def add_observation_options(group) -> None:
    """``--observe state|step|join``: what an observation depends on (docs/camera.md); the paper's by default."""
    group.add_argument("--observe", choices=OBSERVE, default=None,
                       help="what the robot's observations depend on: state (the paper's Alg. 3: the state reached, "
                            "drawn afresh each step; the default), step (a camera that reports the operation the "
                            "operator did by its loose parts and tool, missing it with probability 1/5, and blank "
                            "when it did nothing; the online planner or a policy over the lumped model's steps; "
                            f"--model {CAMERA.name} sets it) or join (the same camera seeing the pieces joined too, "
                            "so each operation is told apart: simulated worlds and --keyboard sessions, where the "
                            "person names the pieces; the tray camera cannot see them); docs/camera.md")


def observe_from(args: argparse.Namespace) -> str:
    """``--observe``, else the ``--model`` preset's (``camera``: ``step``), else ``state``; ``--model paper`` with
    ``step`` or ``join`` is a usage error (the paper's model observes the state reached), and so is a preset's
    observation model contradicted (``--model camera --observe state``; ``join`` is a camera's too)."""
    given = getattr(args, "observe", None)
    preset = PRESETS.get(getattr(args, "habit_model", None))
    if given is not None and of_step(given) and preset is not None and preset.name == "paper":
        raise UsageError("--model paper is Alg. 3 as published, whose observations are of the state reached: leave "
                         f"out --observe {given}, or choose another --model")
    if preset is not None and preset.observe != STATE:
        if given is not None and of_step(given) and of_step(preset.observe):
            return given
        if given is not None and given != preset.observe:
            raise UsageError(f"--model {preset.name} reads observations of the {preset.observe} "
                             f"(--observe {preset.observe}); leave out --observe {given}, or choose another --model "
                             "(docs/camera.md)")
        return preset.observe
    return given or STATE


def add_deviation_options(group) -> None:
    """The two probabilities (docs/deviations.md); both 0 by default: the paper's model."""
    group.add_argument("--switch", type=_probability, default=0.0, metavar="P",
                       help="change of mind: each time the operator may act, with probability P in [0, 1) it "
                            "first draws a new completion from the current assembly state by the prior "
                            "(default 0: the paper's model; docs/deviations.md)")
    group.add_argument("--mistakes", type=_probability, default=0.0, metavar="Q",
                       help="mistakes: each observation is, with probability Q in [0, 1), one drawn uniformly "
                            "from all (a wrong part or tool taken), so none resets the belief (default 0)")


def deviations_from(args: argparse.Namespace) -> Deviations | None:
    """The deviations ``args`` ask for, None for the paper's model (both 0, or ``--model paper``)."""
    if getattr(args, "habit_model", None) == "paper":
        return None
    return deviations_of(getattr(args, "switch", 0.0) or 0.0, getattr(args, "mistakes", 0.0) or 0.0)
