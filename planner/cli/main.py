"""The ``aplan`` command line: ``stats``, ``intentions``, ``synth``, ``analyze``, ``pomdp``, ``solve``,
``simulate``, ``evaluate``, ``session``, ``replay``, ``markers``.

Exit status: 0 on success, 1 when the input is bad (the message says what, where and how to fix it),
2 on a usage error. Nothing is written when a command fails.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Sequence

from ..api import resolve_product
from ..assembly.intentions import (
    DEFAULT_INTENTION_LIMIT,
    intention_graph,
    most_connected_part,
)
from ..assembly.plan import make_plan
from ..assembly.stats import STAT_KEYS, plan_statistics
from ..defaults import (
    CONFIDENCE,
    DISCOUNT,
    POLICY_TIME_LIMIT,
    SOLVE_PRECISION,
    SOLVE_TIME_LIMIT,
)
from ..errors import PlannerError
from ..geometry.bundle import PRODUCT_FILE, analyze_product, apply_report
from ..geometry.mesh_engine import Tolerances
from ..plugins import registry
from ..product.examples import EXAMPLES
from ..product.model import load_product, product_to_dict, save_product, write_atomic
from ..product.synthetic import SYNTHETIC

__all__ = ["main", "build_parser", "add_tolerance_options", "tolerances_from"]

_PRODUCT_HELP = (f"a product file (.json), a bundle folder, a FreeCAD document or STEP file (read through "
                 f"FreeCAD), or an embedded example ({', '.join(EXAMPLES)})")


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


def _add_technical(parser) -> None:
    parser.add_argument("--technical", action=argparse.BooleanOptionalAction, default=None,
                        help="switch every technical constraint on (--technical) or off (--no-technical); "
                             "by default each constraint is as the product file marks it ('active')")


def _stats(args: argparse.Namespace) -> int:
    product = resolve_product(args.product)
    plan = make_plan(product, args.technical)
    base = most_connected_part(plan.product) if args.base_part == "auto" else args.base_part
    stats = plan_statistics(plan, base)
    if args.json:
        print(json.dumps(stats.as_dict()))
        return 0
    title = plan.product.name or str(args.product)
    print(f"{title} ({plan.product.source})")
    values = stats.as_dict()
    for key in STAT_KEYS:
        value = values[key]
        shown = f"{value:.2f}" if isinstance(value, float) else f"{value:,}"
        print(f"  {key:<14}{shown:>22}")
    if base:
        print(f"  (sequences whose first operation joins the base part {base!r})")
    print(f"  factored view: {stats.states:,} assembly states x {stats.sequences:,} sequences "
          f"instead of {stats.intentions:,} intentions")
    for k in plan.tags.unmatched:
        print(f"  warning: operations[{k}] tags an operation that is not in the AND/OR graph", file=sys.stderr)
    return 0


def _intentions(args: argparse.Namespace) -> int:
    plan = make_plan(resolve_product(args.product), args.technical)
    graph = intention_graph(plan.states, limit=args.limit)
    chosen = graph.full_sequences() if args.full else range(graph.n_intentions)
    operations = graph.operation
    for i in chosen:
        path = graph.path(int(i))
        if args.json:
            steps = []
            j = int(i)
            while graph.successor[j] >= 0:
                steps.append(plan.andor.describe(int(operations[j])))
                j = int(graph.successor[j])
            print(json.dumps({"intention": int(i), "states": [plan.states.describe(s) for s in path],
                              "operations": steps}))
        else:
            print(f"{int(i)}: " + " -> ".join(plan.states.describe(s) for s in path))
    return 0


def _analyze(args: argparse.Namespace) -> int:
    target = Path(args.product)
    path = target / PRODUCT_FILE if target.is_dir() else target
    product = load_product(path)
    report = analyze_product(product, args.engine, tolerances_from(args))
    save_product(apply_report(product, report), args.output or path)
    if args.json:
        print(json.dumps(report.as_dict()))
        return 0
    print(f"{path}: {len(report.parts)} parts, {len(report.contacts)} contacts, "
          f"{len(report.interferences)} interferences ({report.engine} engine, {report.seconds:.2f} s)")
    for a, b, volume in report.interferences:
        print(f"  interference {a} / {b}: {volume:.4g} cubic units")
    for axis, pairs in report.obstructions.items():
        print(f"  obstructions {axis}: {len(pairs)} pairs")
    for warning in report.warnings:
        print(f"  warning: {warning}", file=sys.stderr)
    return 0


def _add_decision_options(parser: argparse.ArgumentParser) -> None:
    from ..decision.intention_model import Rewards

    d = Rewards()
    group = parser.add_argument_group("decision model (when MODEL is a product)")
    _add_technical(group)
    group.add_argument("--discount", type=float, default=DISCOUNT, help=f"discount factor (default {DISCOUNT:g})")
    group.add_argument("--reward-unfavorable", type=float, default=d.unfavorable, metavar="R",
                       help=f"robot does the next step, unfavorable to humans (default {d.unfavorable:g})")
    group.add_argument("--reward-favorable", type=float, default=d.favorable, metavar="R",
                       help=f"robot does the next step, fine for humans (default {d.favorable:g})")
    group.add_argument("--reward-wrong", type=float, default=d.wrong, metavar="R",
                       help=f"robot does another operation: its eagerness (default {d.wrong:g})")
    group.add_argument("--reward-wait", type=float, default=d.wait, metavar="R", help=f"wait (default {d.wait:g})")


def _model_from(args: argparse.Namespace):
    from ..api import load_model
    from ..decision.intention_model import Rewards

    rewards = Rewards(args.reward_unfavorable, args.reward_favorable, args.reward_wrong, args.reward_wait)
    return load_model(args.model, args.technical, rewards, args.discount)


def _pomdp(args: argparse.Namespace) -> int:
    from ..api import save_model

    model = _model_from(args)
    save_model(model, args.output)
    print(f"{args.output}: {model.n_states} states, {model.n_actions} actions, {model.n_observations} observations")
    return 0


def _solve(args: argparse.Namespace) -> int:
    from ..decision.policy import write_policy
    from ..decision.solvers import PointBasedSolver

    model = _model_from(args)
    if args.engine == "sarsop":
        from ..decision.solvers.sarsop import solve_with_sarsop

        result = solve_with_sarsop(model, args.time_limit, args.precision)
    else:
        def progress(seconds: float, lower: float, upper: float) -> None:
            if not args.json and not args.quiet:
                print(f"\r  {seconds:7.1f} s  lower {lower:.6f}  upper {upper:.6f}  gap {upper - lower:.6f}",
                      end="", file=sys.stderr, flush=True)

        result = PointBasedSolver(time_limit=args.time_limit, precision=args.precision).solve(model, progress)
        if not args.json and not args.quiet:
            print(file=sys.stderr)
    write_policy(result.policy, args.output, model.name)
    if args.json:
        print(json.dumps(result.as_dict()))
    else:
        print(f"{args.output}: lower bound {result.lower_bound:.6f}, upper bound {result.upper_bound:.6f} "
              f"(gap {result.gap:.6f}), {result.policy.alphas.shape[0]} alpha vectors, {result.seconds:.1f} s")
    return 0


def _policy_for(args: argparse.Namespace, model):
    from ..decision.policy import read_policy
    from ..decision.solvers import PointBasedSolver

    if args.policy:
        return read_policy(args.policy, model)
    result = PointBasedSolver(time_limit=args.time_limit, precision=SOLVE_PRECISION).solve(model)
    print(f"(no --policy: solved for {result.seconds:.1f} s, lower bound {result.lower_bound:.5f}, "
          f"upper bound {result.upper_bound:.5f})", file=sys.stderr)
    return result.policy


def _simulate(args: argparse.Namespace) -> int:
    import numpy as np

    from ..decision.simulate import plot_beliefs, simulate_episode

    model = _model_from(args)
    graph = model.metadata.get("intention_graph")
    if graph is None:
        raise PlannerError("simulate needs a PRODUCT (the intention graph names the sequences), not a model file")
    policy = _policy_for(args, model)
    starts = [int(s) for s in graph.full_sequences()]
    rng = np.random.default_rng(args.seed)
    if args.all:
        chosen = starts
    elif args.random:
        chosen = [int(s) for s in rng.choice(starts, size=args.random)]
    else:
        chosen = args.sequence or [starts[0]]
        unknown = [s for s in chosen if s not in starts]
        if unknown:
            raise PlannerError(f"--sequence {unknown[0]} is not a full assembly sequence; the sequences are the "
                               f"intentions {starts[0]}..{starts[-1]} (see aplan intentions PRODUCT --full)")
    episodes = [simulate_episode(model, policy, start, rng, args.max_steps, graph.successor, 0, args.operator)
                for start in chosen]
    plan_states = graph.states
    for start, episode in zip(chosen, episodes):
        if args.json:
            print(json.dumps({"sequence": start, "operations": [plan_states.andor.describe(int(o))
                                                                for o in _sequence_ops(graph, start)],
                              "confident_after_operations": episode.first_confident(CONFIDENCE),
                              "discounted_return": round(episode.discounted_return, 6)}))
            continue
        print(f"sequence {start}: " + " ; ".join(plan_states.andor.describe(int(o)) for o in _sequence_ops(graph, start)))
        print(f"  {'step':>4}  {'robot action':<44} {'observation':<28} {'p(true)':>7}  operator ops")
        for k, step in enumerate(episode.steps, start=1):
            print(f"  {k:>4}  {model.actions[step.action]:<44} {model.observations[step.observation]:<28} "
                  f"{step.p_true:7.3f}  {step.operator_operations}")
        print(f"  belief on the true intention first above {CONFIDENCE:g} after {episode.first_confident(CONFIDENCE)} operator "
              f"operation(s); discounted return {episode.discounted_return:.3f}")
    if args.plot:
        written = plot_beliefs(episodes, args.plot, [f"sequence {s}" for s in chosen])
        if not args.json:
            print("wrote " + ", ".join(written))
    return 0


def _sequence_ops(graph, start: int) -> list[int]:
    ops, i = [], start
    operations = graph.operation
    while graph.successor[i] >= 0:
        ops.append(operations[i])
        i = int(graph.successor[i])
    return ops


def _evaluate(args: argparse.Namespace) -> int:
    from ..decision.simulate import evaluate_policy

    model = _model_from(args)
    policy = _policy_for(args, model)
    final = 0 if model.metadata.get("intention_graph") is not None else None
    mean, half, _ = evaluate_policy(model, policy, args.episodes, args.seed, args.max_steps, final)
    if args.json:
        print(json.dumps({"mean_return": mean, "ci95": half, "episodes": args.episodes}))
    else:
        print(f"mean discounted return {mean:.4f} +- {half:.4f} (95 % confidence, {args.episodes} episodes)")
    return 0


def _session(args: argparse.Namespace) -> int:
    import time
    import warnings

    from ..decision.intention_model import Rewards, intention_pomdp
    from ..runtime.session import (
        ConsoleRobot,
        EventLog,
        KeyboardSource,
        ScriptedRobot,
        run_session,
    )
    from ..runtime.vision import (
        MarkerDetector,
        VisionSource,
        camera_frames,
        detections,
        image_frames,
        in_background,
        marker_map,
        video_frames,
    )

    plan = make_plan(resolve_product(args.product), args.technical)
    rewards = Rewards(args.reward_unfavorable, args.reward_favorable, args.reward_wrong, args.reward_wait)
    model = intention_pomdp(plan, rewards, args.discount)
    if args.demo is not None and args.robot is not None:
        raise PlannerError("--demo simulates the robot too; leave out --robot")
    policy = _policy_for(args, model)
    stream = None
    robot = ConsoleRobot() if args.robot in (None, "console") else ScriptedRobot()
    if not args.keyboard:  # open the frames first: a camera or file that cannot be read stops before any log
        markers = marker_map(plan.product)
        if plan.product.markers is None:
            print("aplan: note: the product has no 'markers': parts then tools are markers 0, 1, ... in file order "
                  "(see aplan markers)", file=sys.stderr)
        detector = MarkerDetector(markers.dictionary)
        if args.camera is not None:
            stream = in_background(detections(camera_frames(args.camera), detector))
        elif args.demo is not None:
            cell = _demo_cell(plan, model, markers, args.demo)
            stream = detections(cell, detector)
            robot = ScriptedRobot(on_perform=cell.robot)
        else:
            frames = video_frames(args.video) if args.video is not None else image_frames(args.images)
            stream = detections(frames, detector)
    interactive = sys.stderr.isatty()

    def show(event: dict) -> None:
        if event["event"] == "warning":
            print(f"{chr(10) if interactive else ''}aplan: warning: step {event.get('step', '-')}: {event['message']}",
                  file=sys.stderr, flush=True)

    log_path = args.log or f"session-{time.strftime('%Y%m%d-%H%M%S')}.jsonl"
    log = EventLog(log_path, on_event=show)
    if args.keyboard:
        source = KeyboardSource(plan.product)
    else:
        close_without_tool = any(o.parts and o.tool is None for o in plan.observations)
        source = VisionSource((), markers, detector, args.debounce, args.quiet_frames, close_without_tool,
                              on_warning=lambda message: log.write("warning", step=_current_step(log), message=message),
                              detections=stream, robot_uses_tray_tools=not args.robot_own_tools)

    def status(line: str) -> None:
        print(("\r\033[K" if interactive else "") + line, end="" if interactive else "\n", file=sys.stderr,
              flush=True)

    settings = {"policy": args.policy, "technical": args.technical, "discount": args.discount,
                "rewards": vars(rewards), "robot": args.robot,
                "source": (f"camera {args.camera}" if args.camera is not None else f"video {args.video}"
                           if args.video else f"images {args.images}" if args.images else
                           f"demo {args.demo}" if args.demo is not None else "keyboard"),
                "debounce": args.debounce, "quiet_frames": args.quiet_frames,
                "robot_own_tools": args.robot_own_tools}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # logged and shown as warning events instead
            result = run_session(plan, model, policy, source, robot, log, status, args.max_steps, settings=settings)
    finally:
        log.close()
        if stream is not None:
            stream.close()
    if interactive:
        print(file=sys.stderr)
    print(f"{result.reason}: {result.message}")
    print(f"log: {log_path}")
    return 0 if result.assembled else 1


def _demo_cell(plan, model, markers, sequence: int):
    """A simulated cell: an operator following full sequence ``sequence`` on a rendered 1080p tray."""
    from ..runtime.session import ScriptedOperator
    from ..runtime.tray import CameraModel, SimulatedCell, tray_layout

    graph = model.metadata["intention_graph"]
    starts = [int(s) for s in graph.full_sequences()]
    if sequence not in starts:
        raise PlannerError(f"--demo {sequence} is not a full assembly sequence; the sequences are the intentions "
                           f"{starts[0]}..{starts[-1]} (see aplan intentions PRODUCT --full)")
    operator = ScriptedOperator.following(plan, graph, sequence)
    camera = CameraModel(blur=1.2, noise=6, perspective=0.04, hands=True, seed=sequence)
    return SimulatedCell(tray_layout(markers), operator, camera)


def _current_step(log) -> int:
    return next((e["step"] for e in reversed(log.events) if "step" in e), 0)


def _replay(args: argparse.Namespace) -> int:
    import numpy as np

    from ..decision.simulate import Episode, Step, plot_beliefs
    from ..runtime.session import replay

    done = replay(args.log)
    model = done.model
    if args.json:
        for k, (a, z, b) in enumerate(zip(done.actions, done.observations, done.beliefs[1:]), start=1):
            order = np.argsort(-b, kind="stable")[:3]
            print(json.dumps({"step": k, "action": model.actions[a], "observation": model.observations[z],
                              "top": [[int(i), round(float(b[i]), 6)] for i in order]}))
    else:
        print(f"{done.product.name or args.log}: {len(done.actions)} steps, "
              f"ended: {done.end['reason'] + ' (' + done.end['message'] + ')' if done.end else 'no end event'}")
        print(f"  {'step':>4}  {'robot action':<44} {'observation':<28} belief (top 3)")
        for k, (a, z, b) in enumerate(zip(done.actions, done.observations, done.beliefs[1:]), start=1):
            order = np.argsort(-b, kind="stable")[:3]
            top = " ".join(f"i{int(i)} {b[i]:.2f}" for i in order if b[i] > 0)
            print(f"  {k:>4}  {model.actions[a]:<44} {model.observations[z]:<28} {top}")
    if args.plot:
        likely = [int(np.argmax(b)) for b in done.beliefs]
        steps = [Step(a, z, s, float(b[s]), 0, 0.0)
                 for a, z, s, b in zip(done.actions, done.observations, likely[1:], done.beliefs[1:])]
        written = plot_beliefs([Episode(likely[0], steps, done.beliefs)], args.plot, [Path(args.log).name],
                               line_label="most probable intention")
        if not args.json:
            print("wrote " + ", ".join(written))
    if done.mismatches:
        print(f"aplan: error: {args.log}: the logged beliefs differ from the recomputed ones at steps "
              f"{', '.join(map(str, done.mismatches))}", file=sys.stderr)
        return 1
    if not args.json:
        print(f"beliefs reproduced at all {len(done.actions)} steps")
    return 0


def _markers(args: argparse.Namespace) -> int:
    from ..runtime.tray import write_marker_sheet

    product = resolve_product(args.product)
    count = write_marker_sheet(product, args.output, args.size)
    dictionary = product.markers.dictionary if product.markers else "DICT_4X4_50"
    print(f"{args.output}: {count} markers ({dictionary}, {args.size:g} mm)")
    if product.markers is None:
        print("  the product has no 'markers': they are numbered in file order (parts, then tools); add "
              "'markers' to the product file to keep them fixed", file=sys.stderr)
    return 0


def _synth(args: argparse.Namespace) -> int:
    product = SYNTHETIC[args.kind](args.parts)
    text = json.dumps(product_to_dict(product), indent=1) + "\n"
    if args.output:
        write_atomic(args.output, text)
    else:
        sys.stdout.write(text)
    return 0


def _add_episode_options(parser: argparse.ArgumentParser) -> None:
    """Options shared by simulate and evaluate."""
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-steps", type=_positive, default=100)
    parser.add_argument("--time-limit", type=float, default=POLICY_TIME_LIMIT,
                        help=f"solver seconds when no --policy (default {POLICY_TIME_LIMIT:g})")
    _add_decision_options(parser)


def _positive(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="aplan", description="APLAN: assembly plans and operator intentions "
                                     "for human-robot collaborative assembly (Cramer et al., RA-L 2021).")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    stats = commands.add_parser("stats", help="count subassemblies, operations, states, intentions, ...",
                                description="Print the figures of a product's plan: " + ", ".join(STAT_KEYS) + ".")
    stats.add_argument("product", metavar="PRODUCT", help=_PRODUCT_HELP)
    stats.add_argument("--json", action="store_true", help="print one JSON object with exactly those keys")
    _add_technical(stats)
    stats.add_argument("--base-part", nargs="?", const="auto", metavar="PART",
                       help="count only the sequences whose first operation joins PART "
                            "(without PART: the most connected part)")
    stats.set_defaults(run=_stats)

    intentions = commands.add_parser("intentions", help="enumerate operator intentions (paths of assembly states)")
    intentions.add_argument("product", metavar="PRODUCT", help=_PRODUCT_HELP)
    intentions.add_argument("--limit", type=_positive, default=DEFAULT_INTENTION_LIMIT,
                            help=f"refuse to enumerate more intentions than this (default {DEFAULT_INTENTION_LIMIT:,})")
    intentions.add_argument("--full", action="store_true", help="only the full assembly sequences")
    intentions.add_argument("--json", action="store_true", help="one JSON object per line")
    _add_technical(intentions)
    intentions.set_defaults(run=_intentions)

    analyze = commands.add_parser(
        "analyze", help="compute contacts and obstruction diagrams from a bundle's geometry",
        description="Fill in the connection diagram and the +X/+Y/+Z obstruction diagrams of a product bundle "
                    "from its part meshes (mesh engine) or B-reps (occt engine, through FreeCAD).")
    analyze.add_argument("product", metavar="BUNDLE", help="a bundle folder (or its product .json)")
    analyze.add_argument("-o", "--output", metavar="FILE", help="write the product here (default: in place)")
    analyze.add_argument("--engine", default="mesh", help="mesh (default) or occt")
    analyze.add_argument("--json", action="store_true", help="print the analysis as JSON")
    add_tolerance_options(analyze)
    analyze.set_defaults(run=_analyze)

    synth = commands.add_parser("synth", help="write a synthetic product of Table I",
                                description="chain: weakly connected (each part touches the next); "
                                            "complete: strongly connected (every part touches every other).")
    synth.add_argument("kind", choices=sorted(SYNTHETIC))
    synth.add_argument("parts", type=_positive, metavar="N", help="number of parts")
    synth.add_argument("-o", "--output", metavar="FILE", help="write here (default: standard output)")
    synth.set_defaults(run=_synth)
    pomdp = commands.add_parser("pomdp", help="write the operator-intent POMDP (Alg. 3) as POMDPX or .pomdp",
                                description="Build the POMDP over operator intentions and write it: POMDPX "
                                            "(APPL's pomdpsol reads it) or Cassandra's .pomdp, by the file name.")
    pomdp.add_argument("model", metavar="PRODUCT", help=_PRODUCT_HELP)
    pomdp.add_argument("-o", "--output", required=True, metavar="MODEL", help="MODEL.pomdpx or MODEL.pomdp")
    _add_decision_options(pomdp)
    pomdp.set_defaults(run=_pomdp)

    solve = commands.add_parser("solve", help="solve a POMDP offline into a policy (certified bounds)",
                                description="Anytime point-based solver with lower and upper bounds; stops at "
                                            "the time limit or when upper - lower <= precision at the initial belief.")
    solve.add_argument("model", metavar="MODEL", help="a .pomdpx or .pomdp file, or a PRODUCT")
    solve.add_argument("-o", "--output", required=True, metavar="POLICY", help="the policy file (SARSOP's .policy XML)")
    solve.add_argument("--time-limit", type=float, default=SOLVE_TIME_LIMIT, metavar="S",
                       help=f"seconds (default {SOLVE_TIME_LIMIT:g})")
    solve.add_argument("--precision", type=float, default=SOLVE_PRECISION, metavar="E",
                       help=f"target gap (default {SOLVE_PRECISION:g})")
    solve.add_argument("--engine", choices=("builtin", "sarsop"), default="builtin",
                       help="builtin (default) or sarsop (APPL's pomdpsol, when it is on PATH)")
    solve.add_argument("--json", action="store_true", help="print lower_bound, upper_bound, alpha_vectors, seconds")
    solve.add_argument("--quiet", action="store_true", help="no progress line")
    _add_decision_options(solve)
    solve.set_defaults(run=_solve)

    simulate = commands.add_parser("simulate", help="play an operator through assembly sequences against a policy",
                                   description="Per step: the robot's action, the observation, and the belief on "
                                               "the true intention; optionally the Fig. 7 belief heat map.")
    simulate.add_argument("model", metavar="PRODUCT", help=_PRODUCT_HELP)
    simulate.add_argument("--policy", metavar="POLICY", help="a .policy file (default: solve for --time-limit s)")
    which = simulate.add_mutually_exclusive_group()
    which.add_argument("--sequence", type=int, nargs="+", metavar="K",
                       help="full sequences by intention number (aplan intentions PRODUCT --full)")
    which.add_argument("--all", action="store_true", help="every full sequence")
    which.add_argument("--random", type=_positive, metavar="N", help="N sequences drawn at random")
    simulate.add_argument("--plot", metavar="STEM", help="write STEM.png and STEM.svg (belief heat maps)")
    simulate.add_argument("--operator", choices=("model", "turns"), default="model",
                          help="model (default): the operator acts with the model's probability (1/2 per step); "
                               "turns: it acts whenever the model lets it, taking turns with the robot as in the "
                               "paper's experiment")
    simulate.add_argument("--json", action="store_true",
                          help="one JSON line per episode: sequence, confident_after_operations, discounted_return")
    _add_episode_options(simulate)
    simulate.set_defaults(run=_simulate)

    evaluate = commands.add_parser("evaluate", help="mean discounted return of a policy over simulated episodes")
    evaluate.add_argument("model", metavar="MODEL", help="a PRODUCT, or a .pomdpx/.pomdp file")
    evaluate.add_argument("--policy", metavar="POLICY", help="a .policy file (default: solve for --time-limit s)")
    evaluate.add_argument("--episodes", type=_positive, default=1000)
    evaluate.add_argument("--json", action="store_true", help="print mean_return, ci95 and episodes")
    _add_episode_options(evaluate)
    evaluate.set_defaults(run=_evaluate)

    session = commands.add_parser(
        "session", help="run the collaboration loop: observations -> belief -> robot instructions",
        description="Watch the operator (camera, video, images of the parts tray, or picks typed in), update "
                    "the belief over intentions, and tell the robot what to do, until the product is assembled. "
                    "Every event is logged as JSON lines. Exit status 0 when the product was assembled.")
    session.add_argument("product", metavar="PRODUCT", help=_PRODUCT_HELP)
    session.add_argument("--policy", metavar="POLICY", help="a .policy file (default: solve for --time-limit s)")
    source = session.add_mutually_exclusive_group(required=True)
    source.add_argument("--camera", type=int, metavar="N", help="camera index (OpenCV: /dev/videoN)")
    source.add_argument("--video", metavar="FILE", help="a video file of the tray")
    source.add_argument("--images", metavar="DIR", help="a folder of images of the tray, in file-name order")
    source.add_argument("--keyboard", action="store_true", help="type the operator's picks (no camera)")
    source.add_argument("--demo", type=int, metavar="K",
                        help="a simulated cell: an operator following full sequence K (aplan intentions PRODUCT "
                             "--full) and a robot, on a rendered tray seen through the vision pipeline")
    session.add_argument("--robot", choices=("console", "auto"),
                         help="console (default): print each instruction for the person standing in for the "
                              "robot and wait for Enter; auto: confirm every instruction at once (dry runs)")
    session.add_argument("--log", metavar="FILE", help="the JSON-lines log (default: session-DATE-TIME.jsonl; "
                                                       "never overwritten)")
    session.add_argument("--debounce", type=_positive, default=3, metavar="F",
                         help="frames a marker must stay seen or unseen before it counts (default 3)")
    session.add_argument("--quiet-frames", type=_positive, default=45, metavar="F",
                         help="frames without any marker change that make a blank observation (default 45: "
                              "1.5 s at 30 fps)")
    session.add_argument("--robot-own-tools", action="store_true",
                         help="the robot has tools of its own: every tool taken from the tray is the operator's "
                              "(default: the robot takes its tool from the tray too, as in the paper)")
    session.add_argument("--max-steps", type=_positive, default=500)
    session.add_argument("--time-limit", type=float, default=POLICY_TIME_LIMIT,
                         help=f"solver seconds when no --policy (default {POLICY_TIME_LIMIT:g})")
    _add_decision_options(session)
    session.set_defaults(run=_session)

    replay_cmd = commands.add_parser("replay", help="recompute the beliefs of a session log; Fig. 7 plot",
                                     description="Replay a session log: recompute every belief from the logged "
                                                 "actions and observations, check them against the log, and "
                                                 "optionally plot them (exit status 1 on a mismatch).")
    replay_cmd.add_argument("log", metavar="LOG", help="a session log (.jsonl)")
    replay_cmd.add_argument("--plot", metavar="STEM", help="write STEM.png and STEM.svg (belief heat map)")
    replay_cmd.add_argument("--json", action="store_true", help="one JSON line per step")
    replay_cmd.set_defaults(run=_replay)

    markers = commands.add_parser("markers", help="print the tray's markers with part and tool names",
                                  description="Write the ArUco markers of a product's parts and tools, labelled, "
                                              "on A4 pages (PDF, or PNG: the first page).")
    markers.add_argument("product", metavar="PRODUCT", help=_PRODUCT_HELP)
    markers.add_argument("-o", "--output", required=True, metavar="FILE", help="sheet.pdf or sheet.png")
    markers.add_argument("--size", type=float, default=40.0, metavar="MM", help="marker width in mm (default 40)")
    markers.set_defaults(run=_markers)

    for add in registry().commands:
        add(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except PlannerError as exc:
        print(f"aplan: error: {exc}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # e.g. `aplan intentions pen | head`
        return 0


if __name__ == "__main__":
    sys.exit(main())
