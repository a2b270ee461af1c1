"""Options several commands share, and their conversion into the planner's arguments."""
from __future__ import annotations

import argparse

from ..assembly.guards import SizeLimits, default_memory_budget
from ..assembly.hierarchy import SUBASSEMBLY_MODES
from ..decision.intention_model import Rewards
from ..decision.operators import parse_operator
from ..decision.presets import CONFIDENT, PRESETS, preset_rewards
from ..defaults import (
    CONTACT_CEILING_FRACTION,
    CUTS_PER_SUBASSEMBLY,
    DECISION_TIME,
    DECISION_TIME_MAX,
    DECLARED_LIMIT,
    DISCOUNT,
    EXPANSION_LIMIT,
    INPUT_FILE_LIMIT,
    MAX_COMPONENTS,
    POLICY_TIME_LIMIT,
    RESOLUTION_LIMIT,
    SPREAD_CELL_LIMIT,
    STEP_LIMIT,
    STRUCTURE_DEFAULT,
    SUBASSEMBLY_LIMIT,
    TIME_LIMIT_MAX,
)
from ..errors import LimitExceededError, PlannerError
from ..files import check_output as check_writable
from ..geometry.mesh_engine import Tolerances
from ..geometry.tolerances import AUTO
from ..product.examples import EXAMPLES
from ..validation import InputError, InputLimits, check_number, check_output

__all__ = ["PRODUCT_HELP", "number", "finite", "positive", "whole", "index", "add_force", "check_outputs",
           "add_technical", "add_base_part", "add_hierarchy", "add_fasteners", "add_model_options",
           "model_options_from", "parse_group",
           "product_from", "add_decision_options", "rewards_from", "add_tolerance_options", "tolerances_from",
           "add_contact_options", "contact_tolerances_from", "contact_tolerance", "positive_length",
           "add_policy_options", "add_episode_options", "positive_seconds",
           "decision_seconds", "online_budget", "add_size_options", "limits_from", "offer_options", "advice",
           "add_verbose", "explain", "gibibytes",
           "add_input_options", "inputs_from"]

PRODUCT_HELP = (f"a product file (.json), a bundle folder, a FreeCAD document or STEP file (read through "
                f"FreeCAD), or an embedded example ({', '.join(EXAMPLES)})")


def number(low: float | None = None, high: float | None = None, low_open: bool = False, high_open: bool = False,
           integer: bool = False):
    """An argparse type: a finite number in the range (:func:`planner.validation.check_number`); out of range,
    NaN or infinite is a usage error naming the option (exit status 2)."""
    def parse(text: str):
        try:
            return check_number(text, "value", low, high, low_open, high_open, integer)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc).removeprefix("value: ")) from None
    parse.__name__ = "whole number" if integer else "number"  # argparse names the type in its messages
    return parse


finite = number()                                  # any finite number (rewards)
positive = number(1, integer=True)                  # a whole number of at least 1
whole = number(integer=True)                        # any whole number (seeds)
index = number(0, integer=True)                     # a whole number of at least 0 (cameras, sequences)


def add_force(parser, outputs: tuple[str, ...] = ("output",), stems: tuple[str, ...] = ()) -> None:
    """``--force`` and the outputs :func:`check_outputs` checks before the command starts: the options
    ``outputs`` (a file each) and ``stems`` (``STEM.png`` and ``STEM.svg``), by their ``dest``. The overwrite
    rule: an existing output is replaced only with ``--force`` (atomically); without it the command stops
    before any work, naming the file (:func:`planner.validation.check_output`)."""
    parser.add_argument("--force", action="store_true", help="replace the output if it exists (without it, an "
                                                             "existing output is an error and nothing is done)")
    parser.set_defaults(outputs=outputs, output_stems=stems)


def check_outputs(args: argparse.Namespace) -> None:
    """Check every output of ``args`` (:func:`add_force`) before any work: its folder exists and is writable,
    and it does not exist unless ``--force``. Raises :class:`~planner.validation.InputError`."""
    force = getattr(args, "force", False)
    outputs, stems = getattr(args, "outputs", ()), getattr(args, "output_stems", ())
    for dest in outputs:
        if getattr(args, dest, None):
            check_output(getattr(args, dest), force, "--" + dest.replace("_", "-"))
    for dest in stems:
        stem = getattr(args, dest, None)
        if stem:
            for suffix in (".png", ".svg"):
                check_output(f"{stem}{suffix}", force, "--" + dest.replace("_", "-"))
    # Outputs of commands without --force (a session's --log, appended to by design): their folders at least.
    # export-freecad makes its bundle's parent folders itself.
    if getattr(args, "command", None) == "export-freecad":
        return
    for dest, suffix in (("output", ""), ("plot", ".png"), ("log", "")):
        if dest == "log" and getattr(args, "command", None) != "session":
            continue  # aplan replay's LOG is its input
        value = getattr(args, dest, None)
        if dest not in outputs and dest not in stems and isinstance(value, str) and value and value != "-":
            check_writable(value + suffix)


def add_technical(parser) -> None:
    parser.add_argument("--technical", action=argparse.BooleanOptionalAction, default=None,
                        help="switch every technical constraint on (--technical) or off (--no-technical); "
                             "by default each constraint is as the product file marks it ('active')")


def add_base_part(parser) -> None:
    """``--base-part [PART]`` (paper Sec. V); the value is ``auto`` when PART is left out, None without the option."""
    parser.add_argument("--base-part", nargs="?", const="auto", metavar="PART",
                        help="only the assembly sequences that start from PART (their first operation joins it) "
                             "and their intentions; without PART: the most connected part (paper Sec. V)")


def add_hierarchy(parser, level: bool = True) -> None:
    """``--subassemblies {designer,auto,none}``, ``--max-components N`` and (with ``level``) ``--level ID``."""
    parser.add_argument("--subassemblies", choices=SUBASSEMBLY_MODES, default=STRUCTURE_DEFAULT,
                        help="designer: plan each subassembly of the product file as a workstation of its own (flat "
                             "when it has none); auto: the same, proposing subassemblies when it has none; none: "
                             "plan the whole product flat. Default: designer, or auto when a CAD model (a bundle) "
                             "has neither fastener groups nor subassemblies of its own (a note says so)")
    parser.add_argument("--max-components", type=number(2, integer=True), default=MAX_COMPONENTS, metavar="N",
                        help=f"--subassemblies auto: at most N members per proposed subassembly, at least 2 "
                             f"(default {MAX_COMPONENTS})")
    if level:
        parser.add_argument("--level", metavar="ID",
                            help="plan one subassembly (one workstation; 'top' for the top level): its members "
                                 "are its parts, a built subassembly is one part")


def add_fasteners(parser) -> None:
    """``--fasteners {tagged,auto,none}``: the fastener groups a plan folds into the operations that install them."""
    parser.add_argument("--fasteners", choices=("tagged", "auto", "none"), default=STRUCTURE_DEFAULT,
                        help="fold fasteners into the operations that install them: tagged: the groups of the "
                             "product's 'fasteners' section; auto: those and the planner's proposals (names such "
                             "as screw, bolt, nut; small parts joining two others: see aplan fasteners); none: plan "
                             "every part. Default: tagged, or auto when a CAD model (a bundle) has neither fastener "
                             "groups nor subassemblies of its own (a note says so)")
    add_interlocks(parser)


def add_interlocks(parser) -> None:
    """``--interlocks {resolve,error,keep}``: what to do with parts that block each other along every direction."""
    parser.add_argument("--interlocks", choices=("resolve", "error", "keep"), default="resolve",
                        help="pairs of parts that block each other along every direction, in a product drawn in "
                             "CAD: resolve: from the geometry (an overlap's insertion direction, a direction found "
                             "on the pair, else one component), one line per decision (default); error: refuse, "
                             "naming what would be done; keep: plan the diagrams as they are")


def parse_group(text: str) -> tuple[str, list[str]]:
    """``NAME=A,B,...`` (``--group``): the component's name and its objects' labels or patterns."""
    name, sep, members = text.partition("=")
    if not sep or not name or not members:
        raise argparse.ArgumentTypeError(f"expected NAME=LABEL,LABEL,..., got {text!r}")
    return name, [m for m in members.split(",") if m]


def add_model_options(parser) -> None:
    """``--group`` and ``--exclude`` for a PRODUCT given as a CAD model (export-freecad's, same meaning)."""
    group = parser.add_argument_group("when PRODUCT is a CAD model (.FCStd, STEP), as aplan export-freecad")
    group.add_argument("--group", action="append", type=parse_group, default=[], metavar="NAME=A,B,...",
                       help="make one component NAME of the objects A, B, ... (labels or shell-style patterns; "
                            "repeatable)")
    group.add_argument("--exclude", action="append", default=[], metavar="LABEL",
                       help="leave out the objects with this label or matching this pattern (repeatable)")


def model_options_from(args: argparse.Namespace) -> dict:
    """The CAD model options of ``args`` (:func:`add_model_options`) for :func:`planner.api.resolve_product`."""
    return {"groups": dict(getattr(args, "group", None) or []), "exclude": list(getattr(args, "exclude", None) or [])}


def product_from(args: argparse.Namespace, argument, tolerances=None):
    """PRODUCT resolved with ``--fasteners``, ``--subassemblies`` (``--max-components``) and the CAD model
    options (a Product, its subassemblies chosen: plan it with the ``designer`` mode); a decision model file's
    name stays as it is. ``tolerances``: the geometry analysed again with them (``--contact``)."""
    from .. import api

    if isinstance(argument, api.Product) or str(argument).lower().endswith(api.MODEL_SUFFIXES):
        return argument   # a product already resolved (a level: its fasteners were chosen with the whole)
    return api.resolve_product(argument, tolerances, getattr(args, "fasteners", STRUCTURE_DEFAULT),
                               model_options_from(args), getattr(args, "subassemblies", None),
                               getattr(args, "max_components", MAX_COMPONENTS),
                               getattr(args, "interlocks", "resolve"))


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
    from .deviations import add_deviation_options  # its own module: it imports number from here
    add_deviation_options(group)
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
                            f"{CONFIDENT.act_confidence:g} unless given (docs/habits.md)")


def add_parallel_options(group) -> None:
    """``--parallel``: the parallel model (docs/parallel.md); ``--model paper`` turns it off."""
    group.add_argument("--parallel", action="store_true",
                       help="the parallel model: the robot may do the operator's step after next now, when that "
                            "keeps the operator's next step possible (docs/parallel.md; on the classes: the online "
                            "planner or a lumped policy); --model paper turns it off")


def parallel_from(args: argparse.Namespace) -> bool:
    """Whether ``args`` ask for the parallel model (``--parallel`` without ``--model paper``)."""
    return bool(getattr(args, "parallel", False)) and getattr(args, "habit_model", None) != "paper"


def rewards_from(args: argparse.Namespace) -> Rewards:
    """The rewards of ``args``: ``--reward-wrong``, else ``--act-confidence``'s, else the ``--model`` preset's
    (:func:`planner.decision.presets.preset_rewards`)."""
    return preset_rewards(PRESETS.get(getattr(args, "habit_model", None)), args.reward_unfavorable,
                          args.reward_favorable, args.reward_wait, args.reward_wrong,
                          getattr(args, "act_confidence", None))


def contact_tolerance(text: str) -> float | str:
    """A contact tolerance: a number >= 0, or ``auto`` (an argparse type)."""
    if text.strip().lower() == AUTO:
        return AUTO
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a length or {AUTO!r}, got {text!r}") from None
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite length >= 0, got {text}")
    return value


def positive_length(text: str) -> float:
    """A finite length above 0 (an argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a length, got {text!r}") from None
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite length above 0, got {text}")
    return value


def add_tolerance_options(parser: argparse.ArgumentParser) -> None:
    """The geometry engines' tolerances as options (shared by analyze and export-freecad)."""
    d = Tolerances()
    group = parser.add_argument_group("geometry tolerances (model units)")
    group.add_argument("--contact", type=contact_tolerance, default=d.contact, metavar="T",
                       help=f"surfaces closer than this touch (default {d.contact:g}); auto: the smallest tolerance "
                            f"that connects the product (from the gaps between the part meshes, at least "
                            f"{d.contact:g}, at most --contact-ceiling), recorded in the product file")
    group.add_argument("--contact-ceiling", type=positive_length, default=None, metavar="T",
                       help=f"--contact auto refuses to go above this, naming the gap (default "
                            f"{100 * CONTACT_CEILING_FRACTION:g} %% of the diagonal of the product's bounding box)")
    group.add_argument("--interference", type=number(0), default=d.interference, metavar="V",
                       help=f"report overlaps above this volume (default {d.interference:g})")
    group.add_argument("--depth", type=number(0), default=d.depth, metavar="T",
                       help=f"overlaps shallower than this along the motion do not block (default {d.depth:g})")
    group.add_argument("--resolution", type=number(16, RESOLUTION_LIMIT, integer=True), default=d.resolution,
                       metavar="N", help=f"mesh engine: pixels across the product for the projection test, 16 to "
                                         f"{RESOLUTION_LIMIT:,} (default {d.resolution})")
    group.add_argument("--pair-budget", type=number(0), default=d.pair_budget, metavar="S",
                       help="occt engine: CPU seconds of work per pair of parts, at least 0; a pair not decided in "
                            "time is reported and keeps the mesh engine's answer (counted as touching and blocking "
                            f"when the bundle has no meshes) (default {d.pair_budget:g})")
    group.add_argument("--time-limit", type=positive_seconds, default=d.time_limit, metavar="S",
                       help="occt engine (and the pairs of parts without a good mesh): CPU seconds for all the pairs "
                            "OCCT decides, above 0; the pairs left then keep the mesh engine's answer and are reported "
                            f"(default {d.time_limit:g})")
    group.add_argument("--directions", type=_direction_count, default=d.directions, metavar="N",
                       help="mesh and occt engines: motion directions besides the axes to find on the parts' faces and "
                            f"axes and test like the axes, 0 to 64 (default {d.directions}; 0: the axes only)")
    group.add_argument("--direction", action="append", type=designer_direction, default=[], metavar="X,Y,Z",
                       help="a motion direction of the designer's, tested like the axes at this and every later "
                            "detection (recorded in the product's geometry.designer; normalised; one along an "
                            "axis or within 2 degrees of another is merged, with a note); repeatable")


def designer_direction(text: str) -> tuple[float, float, float]:
    """``X,Y,Z`` (or an axis name) as a unit vector (an argparse type)."""
    from ..product.designer import parse_direction

    try:
        return parse_direction(text, "--direction")
    except PlannerError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _direction_count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number from 0 to 64, got {text!r}") from None
    if not 0 <= value <= 64:
        raise argparse.ArgumentTypeError(f"must be a whole number from 0 to 64, got {value}")
    return value


def add_contact_options(parser) -> None:
    """``--contact T|auto`` and ``--contact-ceiling T`` for commands taking a PRODUCT: its geometry is analysed
    again with them, in memory (the parts need meshes: a bundle, a CAD model)."""
    group = parser.add_argument_group("geometry (a bundle or CAD model, analysed again in memory)")
    group.add_argument("--contact", type=contact_tolerance, default=None, metavar="T",
                       help="analyse the geometry with this contact tolerance (model units) or auto (the smallest "
                            "that connects the product, below --contact-ceiling); default: the product's analysis")
    group.add_argument("--contact-ceiling", type=positive_length, default=None, metavar="T",
                       help=f"--contact auto refuses to go above this (default {100 * CONTACT_CEILING_FRACTION:g} "
                            "%% of the diagonal of the product's bounding box)")


def contact_tolerances_from(args: argparse.Namespace) -> Tolerances | None:
    """The tolerances of :func:`add_contact_options` (None: keep the product's analysis)."""
    if args.contact is None:
        if args.contact_ceiling is not None:
            raise PlannerError("--contact-ceiling only applies with --contact auto")
        return None
    return Tolerances(contact=args.contact, contact_ceiling=args.contact_ceiling)


def tolerances_from(args: argparse.Namespace) -> Tolerances:
    return Tolerances(contact=args.contact, interference=args.interference, depth=args.depth,
                      resolution=args.resolution, directions=args.directions,
                      contact_ceiling=args.contact_ceiling, pair_budget=args.pair_budget, time_limit=args.time_limit)


def positive_seconds(text: str, high: float = TIME_LIMIT_MAX) -> float:
    """A finite number of seconds above 0 and at most ``high`` (an argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number of seconds, got {text!r}") from None
    if not (value > 0 and value <= high):
        raise argparse.ArgumentTypeError(f"must be a number of seconds above 0 and at most {high:,}, got {text}")
    return value


def decision_seconds(text: str) -> float:
    """Seconds per online decision: above 0, at most :data:`~planner.defaults.DECISION_TIME_MAX`."""
    return positive_seconds(text, DECISION_TIME_MAX)


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


def online_budget(args: argparse.Namespace) -> tuple[float | None, int | None]:
    """(decision time, expansions) from --decision-time and --expansions (module defaults when neither)."""
    if args.expansions is not None and args.decision_time is None:
        return None, args.expansions
    return (args.decision_time if args.decision_time is not None else DECISION_TIME), args.expansions


def add_episode_options(parser: argparse.ArgumentParser) -> None:
    """Options shared by simulate and evaluate."""
    parser.add_argument("--seed", type=whole, default=0)
    parser.add_argument("--max-steps", type=number(1, STEP_LIMIT, integer=True), default=100, metavar="N",
                        help=f"steps per episode at most, 1 to {STEP_LIMIT:,} (default 100)")
    parser.add_argument("--operator-sequence", type=operator_model, metavar="SPEC", dest="operator_model",
                        help="which sequences the simulated operator does (needs --random N with simulate): "
                             "uniform (every full sequence equally likely, whatever the robot's model); "
                             "habitual:K:STRENGTH (sequence K, numbered as --sequence numbers them, with "
                             "probability STRENGTH in [0, 1], else uniform); changing:P (with probability P in "
                             "[0, 1) per episode it switches once, after a uniformly drawn number of operations, "
                             "to another completion; after habitual:K:S, as habitual:K:S,changing:P); "
                             ",mistakes:Q last: with probability Q in [0, 1) per step a wrong part is taken and "
                             "put back (the camera sees another observation); drawn from "
                             "--seed before any episode, so two planners face the same operators. Default: the "
                             "model's initial belief (with --habits, the habits)")
    add_decision_options(parser)


def operator_model(text: str):
    """``--operator-sequence``: the operator model (:func:`planner.decision.operators.parse_operator`)."""
    try:
        return parse_operator(text)
    except PlannerError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


gibibytes = number(0, 2 ** 20, low_open=True)  # a positive, finite number of GiB (at most 1 PiB)


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


def add_input_options(parser) -> None:
    """The input limits a model, policy or session log file is read within (README, "Exit status"), for the
    user whose real file is larger: one option per limit that a real file may pass, named in the refusal.
    (JSON nesting has none: a real product or log is a few levels deep.)"""
    group = parser.add_argument_group("input limits (a model, policy or session log file past them is refused at "
                                      "once, naming the option)")
    group.add_argument("--max-input", type=gibibytes, default=INPUT_FILE_LIMIT / 2 ** 30, metavar="GIB",
                       help=f"bytes read from a model, policy or session log file, a .gz counted decompressed "
                            f"(default {INPUT_FILE_LIMIT / 2 ** 30:g} GiB)")
    group.add_argument("--max-declared", type=number(1, 10 ** 9, integer=True), default=DECLARED_LIMIT, metavar="N",
                       help=f"states, actions or observations a model file declares, and the length of a policy's "
                            f"vectors (default {DECLARED_LIMIT:,}; about 60 bytes each)")
    group.add_argument("--max-cells", type=number(1, 10 ** 10, integer=True), default=SPREAD_CELL_LIMIT,
                       metavar="N", help=f"cells a model file's entries spread over per table ('*', uniform, rows, "
                                         f"identity), and the combinations a reward depending on the next state or "
                                         f"observation is evaluated over per action (default {SPREAD_CELL_LIMIT:,}; "
                                         f"about 150 bytes each while the table is built)")


def inputs_from(args: argparse.Namespace) -> InputLimits:
    """The :class:`~planner.validation.InputLimits` of ``args`` (:func:`add_input_options`; defaults without)."""
    d = InputLimits()
    max_input = getattr(args, "max_input", None)
    return InputLimits(int(max_input * 2 ** 30) if max_input is not None else d.file_bytes,
                       getattr(args, "max_declared", d.declared), getattr(args, "max_cells", d.spread_cells))


def offer_options(parser: argparse.ArgumentParser, commands) -> None:
    """Let :func:`advice` know which options each command has (``commands``: the subparsers' action)."""
    parser.set_defaults(offered_options={name: frozenset(sub._option_string_actions)
                                         for name, sub in commands.choices.items()})


# Options worth naming when another command has them (they do the job differently there); the others
# (a limit of this command) help only where the refusal happened.
_ELSEWHERE = ("--exclude", "--group", "--planner")


_CAD_ONLY = ("--exclude", "--group")
_CAD_SUFFIXES = (".fcstd", ".step", ".stp")


def _reads_cad(args: argparse.Namespace) -> bool:
    """Whether the command's PRODUCT (or MODEL) is a CAD model (a FreeCAD document or STEP file), or unknown."""
    argument = getattr(args, "model", None) or getattr(args, "product", None)
    return argument is None or str(argument).lower().endswith(_CAD_SUFFIXES)


def _applying(error: LimitExceededError, args: argparse.Namespace) -> list[tuple[str, str]]:
    """``error.options`` that apply to this command's PRODUCT: ``--exclude`` and ``--group`` choose a CAD
    model's parts, so only for a CAD model."""
    return [(option, text) for option, text in error.options if option not in _CAD_ONLY or _reads_cad(args)]


def _offered_here(args: argparse.Namespace) -> frozenset:
    """The options this command has."""
    return getattr(args, "offered_options", {}).get(getattr(args, "command", None), frozenset())


def advice(error: LimitExceededError, args: argparse.Namespace) -> str:
    """The options of ``error`` that help, as one sentence: those of this command, then those of other
    commands that do the job another way (``--planner online`` in simulate, ...), with their command."""
    offered = getattr(args, "offered_options", {})
    here = _offered_here(args)
    found = []
    for option, text in _applying(error, args):
        if option in here:
            found.append(text)
        elif option in _ELSEWHERE:
            others = [name for name, options in offered.items() if option in options]
            if others:
                found.append(f"aplan {'/'.join(others)} {text}")
    return ("What helps: " + "; ".join(found) + ".") if found else ""


def add_verbose(parser) -> None:
    """``--verbose``: errors and refusals in full (by default one line each, :func:`explain`)."""
    parser.add_argument("--verbose", action="store_true",
                        help="explain errors and refusals in full: why, and what each option that helps does "
                             "(by default one line each)")


def _spelled(text: str) -> str:
    """The option as an advice text spells it: ``--fasteners auto`` of "--fasteners auto folds ...",
    ``--max-memory GIB`` of "--max-memory GIB raises ..." (the option and its value, without the verb)."""
    words = text.split()
    value = words[1] if len(words) > 1 else ""
    return " ".join(words[:2]) if value and (not value.isalpha() or not value.islower() or
                                             value in ("auto", "online", "none")) else words[0]


#: A message longer than this (characters) is printed in its one-line form, the whole of it with --verbose.
LONG_MESSAGE = 200


def explain(error: PlannerError, args: argparse.Namespace, options: bool = True) -> str:
    """``error`` as the command line prints it: its one line (:attr:`~planner.errors.PlannerError.summary`) and,
    for a size limit, the options of this command that help, by name; with ``--verbose`` its whole message and
    what each option does (:func:`advice`); without ``options``, no option is named (a figure only compared)."""
    helps = advice(error, args) if options and isinstance(error, LimitExceededError) else ""
    whole = f"{error} {helps}".strip()
    if getattr(args, "verbose", False) or (len(whole) <= LONG_MESSAGE and "\n" not in whole):
        return whole
    text = error.summary
    if options and isinstance(error, LimitExceededError):
        here = _offered_here(args)
        names = [_spelled(said) for option, said in _applying(error, args) if option in here]
        if names:
            text += f"; try {', '.join(names)}"
    return text + (" (--verbose says why)" if error.summary != str(error) else "")
