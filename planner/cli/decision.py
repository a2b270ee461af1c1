"""``aplan pomdp``, ``solve``, ``simulate`` and ``evaluate``: the decision model (the paper's Alg. 3), its
policy and episodes against it."""
from __future__ import annotations

import argparse
import json
import logging
import signal
import sys
import time

from .. import api
from ..decision.belief_plot import episode_trace, path_trace, plot_beliefs
from ..decision.episode_measures import episode_measures, run_totals
from ..decision.models import is_flat, is_online_planner
from ..decision.policy import WRITE_SECONDS, write_policy
from ..decision.simulate import confidence_text, decision_times
from ..defaults import (
    CONFIDENCE,
    EPISODE_LIMIT,
    FILE_LIMIT,
    SOLVE_PRECISION,
    SOLVE_TIME_LIMIT,
    TIME_LIMIT_MAX,
    TRIAL_LIMIT,
)
from ..errors import PlannerError, SolveTimeError
from ..interrupts import exit_status
from .options import (
    PRODUCT_HELP,
    add_decision_options,
    add_episode_options,
    add_force,
    add_policy_options,
    episode_choice_from,
    gibibytes,
    index,
    inputs_from,
    limits_from,
    model_spec_from,
    number,
    planner_choice_from,
    positive_seconds,
    product_from,
)

__all__ = ["add_commands", "model_from", "policy_from", "decision_maker_from", "product_argument", "levels_from"]

log = logging.getLogger(__name__)

LUMPED_HELP = ("when MODEL is a product: the model over the factored model's classes (state edges and the "
               "finished product) instead of intentions, with the same value and far fewer states")


def product_argument(args: argparse.Namespace):
    """MODEL or PRODUCT of ``args``: a model file's name as it is, else the product of the workstation that
    ``--subassemblies`` and ``--level`` pick (:func:`planner.api.level_product`)."""
    argument = getattr(args, "model", None) or args.product
    if api._model_file_kind(argument):
        if getattr(args, "level", None):
            raise PlannerError(f"{argument}: --level picks a subassembly of a PRODUCT; a model file is one model")
        return argument
    return api.level_product(product_from(args, argument), "designer", args.level)  # arranged by product_from


def levels_from(args: argparse.Namespace) -> list:
    """The levels ``(id, product)`` a simulation or session runs through: the one ``--level`` names, else every
    level bottom-up (one, the product itself, when it is planned flat)."""
    product = product_from(args, getattr(args, "model", None) or args.product)  # its subassemblies chosen
    ids = [args.level] if args.level is not None else [level.id for level in api.levels_of(product)]
    if len(ids) == 1 and args.level is None:
        return [(ids[0], api.level_product(product))]
    return [(level, api.level_product(product, "designer", level)) for level in ids]


def model_from(args: argparse.Namespace, product_only: bool = False, solving: bool = False,
               spec: api.ModelSpec | None = None):
    """The model of ``args.model`` (or ``args.product``): a PRODUCT's decision model, or a model file; ``spec``:
    the model's :class:`~planner.api.specs.ModelSpec` when the command built it already (default: from ``args``)."""
    raw = getattr(args, "model", None) or args.product
    argument = raw if product_only and str(raw).lower().endswith(api.MODEL_SUFFIXES) else product_argument(args)
    if product_only and str(argument).lower().endswith(api.MODEL_SUFFIXES):
        extra = "; --base-part, too, applies to products only" if args.base_part else ""
        raise PlannerError(f"{argument}: a model file, but this command needs a PRODUCT (its plan names what the "
                           f"operator and the robot do){extra}")
    product = product_from(args, argument)
    spec = model_spec_from(args) if spec is None else spec
    return api.model_of(product, spec, getattr(args, "lumped", False), solving, flat=product_only)


def policy_from(args: argparse.Namespace, model):
    """``--policy``, or the solver's policy after ``--time-limit`` seconds (saying so)."""
    policy, result = api.policy_for(model, args.policy, args.time_limit, inputs_from(args))
    if result is not None:
        log.info("no --policy: solved for %.1f s, lower bound %.5f, upper bound %.5f", result.seconds,
                 result.lower_bound, result.upper_bound)
    return policy


def decision_maker_from(args: argparse.Namespace, product=None, spec: api.ModelSpec | None = None,
                        choice: api.PlannerChoice | None = None):
    """The model and policy of ``args`` (:func:`planner.api.decision_maker`), logging what was chosen;
    ``product``: this one (a level) instead of the one ``args`` names; ``spec`` and ``choice``: the command's
    :class:`~planner.api.specs.ModelSpec` and :class:`~planner.api.specs.PlannerChoice`, built once for all its
    levels (default: from ``args``)."""
    argument = product if product is not None else product_argument(args)
    spec = model_spec_from(args) if spec is None else spec
    choice = planner_choice_from(args) if choice is None else choice
    if not isinstance(argument, api.Product) and api._model_file_kind(argument):
        if choice.planner == "online":
            raise PlannerError(f"{argument}: the online planner needs a PRODUCT (its factored model), not a model file")
        model = model_from(args, spec=spec)
        return model, policy_from(args, model)
    model, policy, note = api.decision_maker(product_from(args, argument), spec, choice)
    if note:
        log.info("%s", note)
    return model, policy


def _pomdp(args: argparse.Namespace) -> int:
    model = model_from(args)
    api.save_model(model, args.output, int(args.max_file * 2 ** 30), limits_from(args).memory)
    tables = api.tables(model)
    print(f"{args.output}: {tables.n_states} states, {tables.n_actions} actions, {tables.n_observations} observations")
    return 0


def _solve(args: argparse.Namespace) -> int:
    # --time-limit covers the whole command from here: reading or building the model, the solver (its set-up
    # and warm start included) and writing the policy (time kept for it at WRITE_SECONDS per number).
    began = time.perf_counter()
    model = model_from(args, solving=args.engine == "builtin")
    built = time.perf_counter() - began
    if args.engine == "builtin" and built >= args.time_limit:
        raise SolveTimeError(f"{args.model}: no policy written: building the model took {built:.1f} s, past "
                             f"--time-limit {args.time_limit:g}; give the solver time too (--time-limit "
                             f"{max(4 * built, built + 30):.0f}), or a smaller model (--lumped on a PRODUCT, --base-part)")
    show = not args.json and not args.quiet and args.engine == "builtin"

    def progress(seconds: float, lower: float, upper: float) -> None:
        print(f"\r  {seconds:7.1f} s  lower {lower:.6f}  upper {upper:.6f}  gap {upper - lower:.6f}",
              end="", file=sys.stderr, flush=True)

    result = api.solve(model, args.time_limit, args.precision, args.engine, progress if show else None,
                       iterations=args.trials, keep_on_interrupt=True, max_bytes=limits_from(args).memory,
                       started=began, write_seconds=WRITE_SECONDS)
    if show:
        print(file=sys.stderr)
    if result.interrupted and not result.improved(1e-9 * max(1.0, abs(result.blind_lower))) \
            and result.gap > args.precision:
        log.info("interrupted (%s) before the solver improved on the blind policies (lower bound %.6f): no policy "
                 "written", signal.Signals(result.interrupted).name, result.lower_bound)
        return exit_status(result.interrupted)
    if not result.interrupted and args.engine == "builtin":
        try:
            warning = api.check_solved(result, args.precision, args.time_limit,
                                       smaller="--base-part" if args.lumped else "--lumped on a PRODUCT, --base-part")
        except SolveTimeError as exc:
            raise SolveTimeError(f"{args.model}: {exc} (the model took {built:.1f} s)") from None
        if warning:
            log.warning("%s: %s", args.output, warning)
    began = time.perf_counter()
    write_policy(result.policy, args.output, api.tables(model).name)
    written = time.perf_counter() - began
    if result.interrupted:  # an anytime solver keeps its work: the policy so far is a valid one
        log.info("interrupted (%s): wrote the best policy so far to %s (lower bound %.6f, upper bound %.6f)",
                 signal.Signals(result.interrupted).name, args.output, result.lower_bound, result.upper_bound)
        return exit_status(result.interrupted)
    if args.json:
        print(json.dumps({**result.as_dict(), "model_seconds": round(built, 3), "write_seconds": round(written, 3)}))
    else:
        print(f"{args.output}: lower bound {result.lower_bound:.6f}, upper bound {result.upper_bound:.6f} "
              f"(gap {result.gap:.6f}), {result.policy.alphas.shape[0]} alpha vectors, {result.seconds:.1f} s "
              f"solving (of which {built:.1f} s the model) and {written:.1f} s writing the policy")
    return 0


def _simulate(args: argparse.Namespace) -> int:
    if api._model_file_kind(args.model):
        raise PlannerError("simulate needs a PRODUCT (the intention graph names the sequences), not a model file")
    levels = levels_from(args)
    spec, choice, episodes = model_spec_from(args), planner_choice_from(args), episode_choice_from(args)  # once
    played = []
    for k, (level, product) in enumerate(levels, start=1):
        if len(levels) > 1 and not args.json:
            print(f"level {level} ({k} of {len(levels)}): {', '.join(product.part_ids)}")
        if args.plot and len(levels) > 1:
            raise PlannerError("--plot draws one product's beliefs: pick one subassembly with --level ID")
        played += _simulate_level(args, product, spec, choice, episodes)
    _print_run(played, args)
    return 0


def _print_run(episodes, args: argparse.Namespace) -> None:
    """The whole run's line: episodes, decisions, the decision time's median, 95th percentile and maximum, and
    how many episodes were confident before the product was finished."""
    seconds = [s.decision_seconds for e in episodes for s in e.steps]
    times = decision_times(seconds)
    confident = sum(e.first_confident(CONFIDENCE) is not None for e in episodes)
    if args.json:
        print(json.dumps({"run": {"episodes": len(episodes), "decisions": len(seconds), **times,
                                  "confident_episodes": confident}}))
    elif seconds:
        print(f"run: {len(episodes)} episode(s), {confident} confident before the product was finished; "
              f"{_times_text(times)} over {len(seconds)} decisions")


def _times_text(times: dict) -> str:
    return (f"decision time median {1000 * times['decision_seconds_median']:.1f} ms, 95th percentile "
            f"{1000 * times['decision_seconds_p95']:.1f} ms, max {1000 * times['decision_seconds_max']:.1f} ms")


def _simulate_level(args: argparse.Namespace, product, spec: api.ModelSpec, choice: api.PlannerChoice,
                    played: api.EpisodeChoice) -> list:
    model, policy = decision_maker_from(args, product, spec, choice)
    episodes = api.simulate(model, policy, played)
    if not is_flat(model):
        return _print_factored(model, episodes, args)
    for episode in episodes:
        operations = model.describe_operations(episode.start)
        times = decision_times(s.decision_seconds for s in episode.steps)
        if episode.switched_to is not None:  # the operations done: the start's up to the switch, then the new
            after = model.describe_operations(episode.switched_to)
            operations = operations[:len(operations) - len(after)] + after
        if args.json:
            print(json.dumps({"sequence": episode.start, "operations": operations,
                              "confident_after_operations": episode.first_confident(CONFIDENCE),
                              "discounted_return": round(episode.discounted_return, 6), **times,
                              **episode_measures(episode)}))
            continue
        print(f"sequence {episode.start}: " + " ; ".join(operations))
        _print_steps(model, episode.steps, episode.switched_at)
        print(f"  {confidence_text(episode.first_confident(CONFIDENCE))}; discounted return "
              f"{episode.discounted_return:.3f}" + (f"; {_times_text(times)}" if episode.steps else ""))
    _print_totals(args, episodes)
    if not args.json:
        _say_sampled(model, episodes, args.world)
    if args.plot:
        traces = [episode_trace(model, e, f"sequence {e.start}: " + " ; ".join(model.describe_operations(e.start)))
                  for e in episodes]
        _write_plot(args, traces, model.plan.product.name or model.name)
    return episodes


def _print_totals(args: argparse.Namespace, episodes) -> None:
    """With --operator-sequence, the run's totals: one last JSON line ``{"totals": ...}``, or one text line."""
    if args.operator_model is None:
        return
    totals = run_totals([episode_measures(e) for e in episodes])
    if args.json:
        print(json.dumps({"totals": {"operator": repr(args.operator_model), **totals}}))
    else:
        print(_totals_line(args.operator_model, totals))


def _totals_line(operator, totals: dict) -> str:
    share = "-" if totals["robot_share"] is None else f"{100 * totals['robot_share']:.1f} %"
    wrong = "-" if totals["wrong_share"] is None else f"{100 * totals['wrong_share']:.1f} %"
    capable = "-" if totals["robot_capable_share"] is None else f"{100 * totals['robot_capable_share']:.1f} %"
    return (f"operator {operator!r}, {totals['episodes']} episodes: the robot did {share} of the operations "
            f"({totals['robot_operations']} of {totals['robot_operations'] + totals['operator_operations']}; "
            f"{capable} of the {totals['robot_capable_operations']} it is able to do); "
            f"wrong robot actions {totals['wrong_robot_actions']} ({wrong} of its actions); never helped in "
            f"{totals['never_helped']}, never confident in {totals['never_confident']}")


def _say_sampled(model, episodes, world: str = "model") -> None:
    """Say where the printed observations come from, when they are not just the sequence's operations."""
    names = {model.observations[s.observation] for e in episodes for s in e.steps}
    if names - {"blank"} and world == "model":
        print("  (observations are sampled from the model: the operator's picks of the parts and tools of its "
              "next operation, with the model's missed detections (blank) and observation noise, so some "
              "differ from the sequence's operations)")


def _write_plot(args: argparse.Namespace, traces, title: str) -> None:
    written = plot_beliefs(traces, args.plot, title)
    if not args.json:
        print("wrote " + ", ".join(written))


def _print_steps(model, steps, switched_at: int | None = None) -> None:
    """The per-step table of an episode (flat or factored): action, observation, belief on the truth; the step
    before which the operator changed its mind (--operator-sequence changing:P), if it did."""
    print(f"  {'step':>4}  {'robot action':<44} {'observation':<28} {'p(true)':>7}  operator ops")
    for k, step in enumerate(steps, start=1):
        print(f"  {k:>4}  {model.actions[step.action]:<44} {model.observations[step.observation]:<28} "
              f"{step.p_true:7.3f}  {step.operator_operations}")
    if switched_at is not None:
        print(f"  the operator changed its mind before step {switched_at} (the sequence shown is the one it did)")


def _print_factored(model, episodes, args: argparse.Namespace) -> list:
    """Episodes on the factored model (online planner, or a policy over classes): the same report, sequences
    named by their operations; the plot shows the belief summed over assembly states."""
    for episode in episodes:
        operations = model.describe_operations(episode.path)
        times = decision_times(s.decision_seconds for s in episode.steps)
        if args.json:
            print(json.dumps({"operations": operations, "finished": episode.finished,
                              "confident_after_operations": episode.first_confident(CONFIDENCE),
                              "discounted_return": round(episode.discounted_return, 6), **times,
                              **episode_measures(episode)}))
            continue
        print("sequence: " + " ; ".join(operations))
        _print_steps(model, episode.steps, episode.switched_at)
        print(f"  {confidence_text(episode.first_confident(CONFIDENCE))}; discounted return "
              f"{episode.discounted_return:.3f}; {_times_text(times)}" if episode.steps else "  no step")
    _print_totals(args, episodes)
    if not args.json:
        _say_sampled(model, episodes, args.world)
    if args.plot:
        traces = [path_trace(model, e, "sequence: " + " ; ".join(model.describe_operations(e.path)))
                  for e in episodes]
        _write_plot(args, traces, model.plan.product.name or model.name)
    return episodes


def _evaluate(args: argparse.Namespace) -> int:
    if (args.operator_model is not None or args.world == "camera") and api._model_file_kind(args.model):
        what = "--operator-sequence" if args.operator_model is not None else "--world camera"  # before any solving
        raise PlannerError(f"{args.model}: {what} needs a PRODUCT (its full sequences), not a model file")
    played = episode_choice_from(args)
    model, policy = decision_maker_from(args)
    if is_online_planner(policy) and policy.decision_time is not None:
        log.info("the online planner takes up to %g s per decision: %d episodes can take minutes (progress below); "
                 "--expansions N bounds the work per decision instead", policy.decision_time, args.episodes)
    if args.operator_model is not None:
        mean, half, episodes = api.evaluate_operator(model, policy, played)
        totals = run_totals([episode_measures(e) for e in episodes])
    else:
        (mean, half), totals = api.evaluate(model, policy, played), None
    if args.json:
        extra = {} if totals is None else {"operator": repr(args.operator_model), **totals}
        print(json.dumps({"mean_return": mean, "ci95": half, "episodes": args.episodes, **extra}))
    else:
        print(f"mean discounted return {mean:.4f} +- {half:.4f} (95 % confidence, {args.episodes} episodes)")
        if totals is not None:
            print(_totals_line(args.operator_model, totals))
    return 0


def add_commands(commands) -> None:
    pomdp = commands.add_parser("pomdp", help="write the operator-intent POMDP (Alg. 3) as POMDPX or .pomdp",
                                description="Build the POMDP over operator intentions and write it: POMDPX "
                                            "(APPL's pomdpsol reads it) or Cassandra's .pomdp, by the file name.")
    pomdp.add_argument("model", metavar="PRODUCT", help=PRODUCT_HELP)
    pomdp.add_argument("-o", "--output", required=True, metavar="MODEL", help="MODEL.pomdpx or MODEL.pomdp")
    pomdp.add_argument("--max-file", type=gibibytes, default=FILE_LIMIT / 2 ** 30, metavar="GIB",
                       help=f"refuse to write a file estimated larger than this, or than the free disk space "
                            f"(default {FILE_LIMIT / 2 ** 30:g} GiB)")
    pomdp.add_argument("--lumped", action="store_true", help=LUMPED_HELP)
    add_decision_options(pomdp)
    add_force(pomdp)
    pomdp.set_defaults(run=_pomdp)

    solve = commands.add_parser("solve", help="solve a POMDP offline into a policy (certified bounds)",
                                description="Anytime point-based solver with lower and upper bounds; stops at "
                                            "the time limit or when upper - lower <= precision at the initial belief.")
    solve.add_argument("model", metavar="MODEL", help="a .pomdpx or .pomdp file, or a PRODUCT")
    solve.add_argument("-o", "--output", required=True, metavar="POLICY", help="the policy file (SARSOP's .policy XML)")
    solve.add_argument("--time-limit", type=positive_seconds, default=SOLVE_TIME_LIMIT, metavar="S",
                       help=f"seconds for the whole command: reading or building the model, solving (its set-up "
                            f"included) and writing the policy (default {SOLVE_TIME_LIMIT:g}; at most "
                            f"{TIME_LIMIT_MAX:,}); a policy no better than the blind ones is not written")
    solve.add_argument("--trials", type=number(1, TRIAL_LIMIT, integer=True), default=None, metavar="N",
                       help=f"stop after N trials (1 to {TRIAL_LIMIT:,}; or at --time-limit, whichever comes first): "
                            "a fixed amount of work, the same policy on any machine")
    solve.add_argument("--precision", type=number(0), default=SOLVE_PRECISION, metavar="E",
                       help=f"target gap (default {SOLVE_PRECISION:g})")
    solve.add_argument("--engine", choices=api.SOLVER_ENGINES, default="builtin",
                       help="builtin (default) or sarsop (APPL's pomdpsol, when it is on PATH)")
    solve.add_argument("--json", action="store_true", help="print lower_bound, upper_bound, alpha_vectors, seconds")
    solve.add_argument("--quiet", action="store_true", help="no progress line")
    solve.add_argument("--lumped", action="store_true",
                       help=LUMPED_HELP + "; the policy's vectors are over the classes (its model attribute "
                            "ends in :lumped)")
    add_decision_options(solve)
    add_force(solve)
    solve.set_defaults(run=_solve)

    simulate = commands.add_parser("simulate", help="play an operator through assembly sequences against a policy",
                                   description="Per step: the robot's action, the observation, and the belief on "
                                               "the true intention; optionally the Fig. 7 belief heat map. The "
                                               "observations are sampled from the model (missed detections and "
                                               "observation noise), so some differ from the sequence's operations; "
                                               "--world camera reports the operations done instead.")
    simulate.add_argument("model", metavar="PRODUCT", help=PRODUCT_HELP)
    add_policy_options(simulate)
    which = simulate.add_mutually_exclusive_group()
    which.add_argument("--sequence", type=index, nargs="+", metavar="K",
                       help="full sequences by intention number (aplan intentions PRODUCT --full); on the factored "
                            "model (--planner online) by rank, from 0")
    which.add_argument("--all", action="store_true", help="every full sequence")
    which.add_argument("--random", type=number(1, EPISODE_LIMIT, integer=True), metavar="N",
                       help=f"N sequences drawn at random (at most {EPISODE_LIMIT:,})")
    simulate.add_argument("--plot", metavar="STEM", help="write STEM.png and STEM.svg (belief heat maps)")
    simulate.add_argument("--operator", choices=("model", "turns"), default="model",
                          help="model (default): the operator acts with the model's probability (1/2 per step); "
                               "turns: it acts whenever the model lets it, taking turns with the robot as in the "
                               "paper's experiment")
    simulate.add_argument("--json", action="store_true",
                          help="one JSON line per episode (sequence, confident_after_operations, discounted_return, "
                               "decision_seconds_median, _p95, _max), then one for the run (README)")
    add_episode_options(simulate)
    add_force(simulate, outputs=(), stems=("plot",))
    simulate.set_defaults(run=_simulate)

    evaluate = commands.add_parser("evaluate", help="mean discounted return of a policy over simulated episodes")
    evaluate.add_argument("model", metavar="MODEL", help="a PRODUCT, or a .pomdpx/.pomdp file")
    add_policy_options(evaluate)
    evaluate.add_argument("--episodes", type=number(1, EPISODE_LIMIT, integer=True), default=1000,
                          help=f"episodes to simulate, 1 to {EPISODE_LIMIT:,} (default 1000)")
    evaluate.add_argument("--json", action="store_true", help="print mean_return, ci95 and episodes")
    add_episode_options(evaluate)
    evaluate.set_defaults(run=_evaluate)
