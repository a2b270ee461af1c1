"""Options several commands share, and their conversion into the planner's arguments."""
from __future__ import annotations

import argparse

from ..assembly.guards import SizeLimits, default_memory_budget
from ..decision.intention_model import Rewards
from ..defaults import CUTS_PER_SUBASSEMBLY, DISCOUNT, POLICY_TIME_LIMIT, SUBASSEMBLY_LIMIT
from ..errors import LimitExceededError
from ..geometry.mesh_engine import Tolerances
from ..product.examples import EXAMPLES

__all__ = ["PRODUCT_HELP", "positive", "add_technical", "add_decision_options", "rewards_from",
           "add_tolerance_options", "tolerances_from", "add_policy_options", "add_episode_options",
           "add_size_options", "limits_from", "offer_options", "advice", "gibibytes"]

PRODUCT_HELP = (f"a product file (.json), a bundle folder, a FreeCAD document or STEP file (read through "
                f"FreeCAD), or an embedded example ({', '.join(EXAMPLES)})")


def positive(text: str) -> int:
    """An integer of at least 1 (an argparse type)."""
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def add_technical(parser) -> None:
    parser.add_argument("--technical", action=argparse.BooleanOptionalAction, default=None,
                        help="switch every technical constraint on (--technical) or off (--no-technical); "
                             "by default each constraint is as the product file marks it ('active')")


def add_decision_options(parser: argparse.ArgumentParser) -> None:
    """The decision model's options (when MODEL is a product): technical constraints, discount, rewards."""
    d = Rewards()
    group = parser.add_argument_group("decision model (when MODEL is a product)")
    add_technical(group)
    group.add_argument("--discount", type=float, default=DISCOUNT, help=f"discount factor (default {DISCOUNT:g})")
    group.add_argument("--reward-unfavorable", type=float, default=d.unfavorable, metavar="R",
                       help=f"robot does the next step, unfavorable to humans (default {d.unfavorable:g})")
    group.add_argument("--reward-favorable", type=float, default=d.favorable, metavar="R",
                       help=f"robot does the next step, fine for humans (default {d.favorable:g})")
    group.add_argument("--reward-wrong", type=float, default=d.wrong, metavar="R",
                       help=f"robot does another operation: its eagerness (default {d.wrong:g})")
    group.add_argument("--reward-wait", type=float, default=d.wait, metavar="R", help=f"wait (default {d.wait:g})")
    add_size_options(parser)


def rewards_from(args: argparse.Namespace) -> Rewards:
    return Rewards(args.reward_unfavorable, args.reward_favorable, args.reward_wrong, args.reward_wait)


def add_tolerance_options(parser: argparse.ArgumentParser) -> None:
    """The geometry engines' tolerances as options (shared by analyze and export-freecad)."""
    d = Tolerances()
    group = parser.add_argument_group("geometry tolerances (model units)")
    group.add_argument("--contact", type=float, default=d.contact, metavar="T",
                       help=f"surfaces closer than this touch (default {d.contact:g})")
    group.add_argument("--interference", type=float, default=d.interference, metavar="V",
                       help=f"report overlaps above this volume (default {d.interference:g})")
    group.add_argument("--depth", type=float, default=d.depth, metavar="T",
                       help=f"overlaps shallower than this along the motion do not block (default {d.depth:g})")
    group.add_argument("--resolution", type=int, default=d.resolution, metavar="N",
                       help=f"mesh engine: pixels across the product for the projection test (default {d.resolution})")


def tolerances_from(args: argparse.Namespace) -> Tolerances:
    return Tolerances(contact=args.contact, interference=args.interference, depth=args.depth,
                      resolution=args.resolution)


def add_policy_options(parser: argparse.ArgumentParser) -> None:
    """A policy file, or the solver's time when there is none (simulate, evaluate, session)."""
    parser.add_argument("--policy", metavar="POLICY", help="a .policy file (default: solve for --time-limit s)")
    parser.add_argument("--time-limit", type=float, default=POLICY_TIME_LIMIT,
                        help=f"solver seconds when no --policy (default {POLICY_TIME_LIMIT:g})")


def add_episode_options(parser: argparse.ArgumentParser) -> None:
    """Options shared by simulate and evaluate."""
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-steps", type=positive, default=100)
    add_decision_options(parser)


def gibibytes(text: str) -> float:
    """A positive number of GiB (an argparse type)."""
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be a positive number of GiB, got {text}")
    return value


def add_size_options(parser) -> None:
    """The size limits every command that builds a plan or a model refuses past (with the estimate)."""
    budget = default_memory_budget() / 2 ** 30
    group = parser.add_argument_group("size limits (past them the command refuses at once, saying why)")
    group.add_argument("--max-subassemblies", type=positive, default=SUBASSEMBLY_LIMIT, metavar="N",
                       help=f"the AND/OR graph enumerates at most N connected part sets and examines at most "
                            f"{CUTS_PER_SUBASSEMBLY} N cuts (default {SUBASSEMBLY_LIMIT:,}: about 2 s)")
    group.add_argument("--max-memory", type=gibibytes, default=budget, metavar="GIB",
                       help=f"the memory one graph or model may take, estimated before it is built (default "
                            f"{budget:g} GiB: 4 GiB or a quarter of this machine's memory, if less)")


def limits_from(args: argparse.Namespace) -> SizeLimits:
    return SizeLimits(args.max_subassemblies, int(args.max_memory * 2 ** 30))


def offer_options(parser: argparse.ArgumentParser, commands) -> None:
    """Let :func:`advice` know which options each command has (``commands``: the subparsers' action)."""
    parser.set_defaults(offered_options={name: frozenset(sub._option_string_actions)
                                         for name, sub in commands.choices.items()})


# Options worth naming when another command has them (they do the job differently there); the others
# (a limit of this command) help only where the refusal happened.
_ELSEWHERE = ("--exclude", "--group", "--planner")


def advice(error: LimitExceededError, args: argparse.Namespace) -> str:
    """The options of ``error`` that help, as one sentence: those of this command, then those of other
    commands that do the job another way (``--planner online`` in simulate, ...), with their command."""
    offered = getattr(args, "offered_options", {})
    here = offered.get(getattr(args, "command", None), frozenset())
    found = []
    for option, text in error.options:
        if option in here:
            found.append(text)
        elif option in _ELSEWHERE:
            others = [name for name, options in offered.items() if option in options]
            if others:
                found.append(f"aplan {'/'.join(others)} {text}")
    return ("What helps: " + "; ".join(found) + ".") if found else ""
