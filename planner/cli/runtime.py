"""``aplan session``, ``replay`` and ``markers``: the collaboration runtime (the paper's Sec. IV)."""
from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import time
from pathlib import Path

from .. import api
from ..decision.intention_model import IntentionModel
from ..decision.models import BELIEF_OVER, belief_over, is_flat, is_offline_policy
from ..defaults import HABITS_PRIOR, STEP_LIMIT
from ..errors import PlannerError, UsageError
from ..validation import check_output
from .decision import decision_maker_from, levels_from, model_from
from .options import (
    PRODUCT_HELP,
    add_decision_options,
    add_force,
    add_input_options,
    add_policy_options,
    index,
    inputs_from,
    model_spec_from,
    number,
    planner_choice_from,
)

__all__ = ["add_commands"]

FRAME_LIMIT = 108_000  # an hour of frames at 30 fps: --debounce and --quiet-frames past it would never fire

log = logging.getLogger(__name__)


def _source_name(args: argparse.Namespace) -> str:
    if getattr(args, "source_name", None):  # aplan ros: the marker topic
        return args.source_name
    if args.camera is not None:
        return f"camera {args.camera}"
    if args.video:
        return f"video {args.video}"
    if args.images:
        return f"images {args.images}"
    return f"demo {args.demo}" if args.demo is not None else "keyboard"


def _open_stream(args: argparse.Namespace, model: IntentionModel, markers, detector):
    """The marker detections of each frame, and the robot: a simulated one for ``--demo``, else None."""
    from ..runtime.scripted import ScriptedOperator, ScriptedRobot
    from ..runtime.tray import BENCH, CameraModel, SimulatedCell, scene_box, tray_layout
    from ..runtime.vision import camera_frames, detections, image_frames, in_background, video_frames

    if args.camera is not None:
        return in_background(detections(camera_frames(args.camera), detector)), None
    if args.demo is not None:  # an operator following full sequence K on a rendered 1080p tray
        operator = ScriptedOperator(model.plan, _demo_operations(model, args.demo))
        camera = CameraModel(blur=1.2, noise=6, perspective=0.04, hands=True, seed=args.demo)
        # Operations without a tool end when the tray stays quiet: the simulated operator takes that long.
        # Slots clear of the frame's edges by the camera's tilt and 2 % more (a 35-marker tray reached them).
        layout = tray_layout(markers, margin=camera.perspective + 0.02)
        cell = SimulatedCell(layout, operator, camera, settle=args.quiet_frames + 5)
        # The bench top around the tray holds no marker: detection looks at the tray alone (the same markers)
        return detections(cell, detector.within(scene_box(layout, camera), BENCH)), ScriptedRobot(on_perform=cell.robot)
    frames = video_frames(args.video) if args.video is not None else image_frames(args.images)
    return _Primed(detections(frames, detector)), None


class _Primed:
    """An iterator whose first item is taken at once: a source whose first frame cannot be read fails before
    the session starts and its log exists (the README's promise); ``close`` closes the source."""

    def __init__(self, stream):
        self.stream = stream
        self.first = [next(stream, None)]  # None: no frame at all (the session ends at once, as before)

    def __iter__(self):
        return self

    def __next__(self):
        if self.first:
            item = self.first.pop()
            if item is not None:
                return item
        return next(self.stream)

    def close(self) -> None:
        close = getattr(self.stream, "close", None)
        if close is not None:
            close()


def _demo_operations(model, k: int) -> list[int]:
    """The operations of full sequence ``k``: an intention number on the flat model, a rank on the factored one."""
    if is_flat(model):
        try:
            return model.sequence_operations(model.full_sequence(k, "--demo"))
        except PlannerError as exc:  # a value out of the option's range: a usage error (README, exit status)
            raise UsageError(str(exc)) from None
    if not 0 <= k < model.n_sequences:
        raise UsageError(f"--demo {k}: on the factored model (--planner online) sequences are numbered by rank, "
                           f"from 0 to {model.n_sequences - 1:,}")
    return model.sequence_operations(model.sequence(k))


def _session(args: argparse.Namespace) -> int:
    """One session per level (workstation), bottom-up; with several, each has its own log (``LOG`` with the
    level's id before the suffix), whose start event records the level."""
    if args.demo is not None and args.robot is not None:
        raise UsageError("--demo simulates the robot too; leave out --robot")
    if args.keyboard is False and args.quiet_frames <= args.debounce:
        raise UsageError(f"--quiet-frames {args.quiet_frames} must be more than --debounce {args.debounce} (a quiet "
                         "period is counted in debounced frames); raise --quiet-frames or lower --debounce")
    if api._model_file_kind(args.product):
        model_from(args, product_only=True)  # the error that says a session needs a product
    if args.log:
        check_output(args.log, option="--log", replaceable=False, noun="log")  # before any work; never replaced
    levels = levels_from(args)
    if args.habits_out and len(levels) > 1:
        raise PlannerError("--habits-out: habits are of one workstation's plan; give --level ID")
    log_path = args.log or _default_log_name()
    paths = [log_path if len(levels) == 1 else str(Path(log_path).with_suffix("")) + f"-{level}.jsonl"
             for level, _ in levels]
    for path in paths:  # every level's log before the first level starts: a refusal has done nothing
        check_output(path, option="--log", replaceable=False, noun="log")
    spec, choice = model_spec_from(args), planner_choice_from(args)  # once, for every level
    api.check_cell_observe(spec.observe, keyboard=bool(args.keyboard))
    status = 0
    for k, ((level, product), path) in enumerate(zip(levels, paths), start=1):
        if len(levels) > 1:
            print(f"level {level} ({k} of {len(levels)}): {', '.join(product.part_ids)}")
        status = _session_level(args, product, path, level if args.level or len(levels) > 1 else None, spec, choice)
        if status:
            return status
    return status


def _default_log_name() -> str:
    """``session-DATE-TIME-PID.jsonl`` in the working folder, or ``...-PID-2.jsonl``, ``-3``, ... when that name or
    a level's log of it (``NAME-LEVEL.jsonl``) is there. The process id keeps apart two sessions started in one
    folder within the same second; the number, two sessions of one process (the Python API) in that second."""
    stem = f"session-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}"
    name, k = stem, 1
    while Path(f"{name}.jsonl").exists() or any(Path.cwd().glob(f"{name}-*.jsonl")):
        k += 1
        name = f"{stem}-{k}"
    return f"{name}.jsonl"


def _session_level(args: argparse.Namespace, product, log_path: str, level: str | None, spec: api.ModelSpec,
                   choice: api.PlannerChoice) -> int:
    from ..runtime.console import ConsoleRobot, KeyboardSource
    from ..runtime.log import EventLog
    from ..runtime.scripted import ScriptedRobot
    from ..runtime.session import run_session
    from ..runtime.vision import MarkerDetector, VisionSource, marker_map
    from ..decision.orders import real_plan
    from ..decision.step_observations import JOIN

    model, policy = decision_maker_from(args, product, spec, choice)
    plan = real_plan(model.plan)  # the real assembly states (the orders' model plans on an augmented graph)
    stream, robot = None, ConsoleRobot() if args.robot in (None, "console") else ScriptedRobot()
    if not args.keyboard:  # open the frames first: a camera or file that cannot be read stops before any log
        designed = plan.designed or plan.product  # with its fasteners: the operator picks them from the tray too
        markers = marker_map(designed)
        if designed.markers is None:
            log.info("note: the product has no 'markers': parts then tools are markers 0, 1, ... in file order "
                     "(see aplan markers)")
        detector = MarkerDetector(markers.dictionary)
        # aplan ros opens its marker topic and robot action client instead (planner.cli.ros)
        stream, simulated = getattr(args, "open_stream", _open_stream)(args, model, markers, detector)
        robot = simulated or robot
    interactive = sys.stderr.isatty()

    also = getattr(args, "on_event", None)  # aplan ros: publishes the belief

    def show(event: dict) -> None:
        if also is not None:
            also(event)
        if event["event"] == "warning":
            print(f"{chr(10) if interactive else ''}aplan: warning: step {event.get('step', '-')}: {event['message']}",
                  file=sys.stderr, flush=True)

    def status(line: str) -> None:
        print(("\r\033[K" if interactive else "") + line, end="" if interactive else "\n", file=sys.stderr,
              flush=True)

    events = EventLog(log_path, on_event=show)
    if args.keyboard:
        # the fasteners are picked too; a robot acting by itself says what it does (a console robot's person does)
        # --observe join: the person tells which pieces were joined (the model's alphabet names them)
        joins = plan.observations if spec.observe == JOIN else None
        source = KeyboardSource(plan.designed or plan.product, show_robot=args.robot == "auto", joins=joins)
    else:
        close_without_tool = any(o.parts and o.tool is None for o in plan.observations)
        source = VisionSource((), markers, detector, args.debounce, args.quiet_frames, close_without_tool,
                              on_warning=lambda message: events.write("warning", step=_current_step(events),
                                                                      message=message),
                              detections=stream, robot_uses_tray_tools=not args.robot_own_tools)
    online = not is_offline_policy(policy)
    settings = {"planner": "online" if online else "offline", "policy": choice.policy,
                "decision_time": choice.decision_time if online else None,
                "expansions": choice.expansions if online else None,
                "technical": spec.technical, "base_part": model.base_part, "discount": spec.discount,
                "rewards": vars(model.rewards), "robot": args.robot, "source": _source_name(args),
                "debounce": args.debounce, "quiet_frames": args.quiet_frames,
                "robot_own_tools": args.robot_own_tools, "level": level, "habits": _habits_setting(args, spec.habits),
                "parallel": spec.parallel}
    try:
        result = run_session(model, policy, source, robot, events, status, args.max_steps, settings=settings)
    except KeyboardInterrupt as exc:  # the log holds the session up to the interrupt: say so, exit 128 + N
        print(file=sys.stderr)  # off the prompt or the status line the interrupt came in
        exc.kept = f"the session log {log_path} holds every step before it"
        raise
    finally:
        events.close()
        if stream is not None:
            stream.close()
    if interactive:
        print(file=sys.stderr)
    print(f"{result.reason}: {result.message}")
    print(f"log: {log_path}")
    if args.habits_out:
        _update_habits(args, plan, log_path)
    return 0 if result.assembled else 1


def _update_habits(args: argparse.Namespace, plan, log_path: str) -> None:
    """``--habits-out``: the counts of ``--habits`` (none: empty counts; read even with ``--model paper``, so
    that updating the file in place never loses them) plus the operator's steps the session's log recorded; its
    recorded orders (and their parameters) plus the session's order, if it finished."""
    from dataclasses import replace

    import numpy as np

    from ..decision.habits import edge_counts, habits_from_counts
    from ..decision.io.habits_file import read_habits, write_habits
    from ..runtime.habits_logs import count_log, log_prior

    habits = read_habits(args.habits, inputs_from(args)) if args.habits else None
    counts = edge_counts(plan, habits) if habits is not None else np.zeros(plan.states.n_edges)
    orders = dict(habits.orders) if habits is not None else {}
    notes: list[str] = []
    steps = count_log(plan, counts, log_path, args.technical, inputs_from(args), orders, log_prior(plan, habits),
                      notes)
    for note in notes:
        print(f"note: {note}")
    if not counts.any():
        log.warning("--habits-out %s: the session did no step and there were no habits: nothing written",
                    args.habits_out)
        return
    learned = habits_from_counts(plan, counts, habits.prior if habits else args.habits_prior,
                                 prior_per=habits.prior_per if habits else "edge")
    if habits is not None:
        learned = replace(learned, concentration=habits.concentration, discount=habits.discount)
    write_habits(args.habits_out, replace(learned, orders=tuple(orders.items())))
    print(f"habits: {args.habits_out} ({steps:g} step{'s' if steps != 1 else ''} of this session added)")


def _habits_setting(args: argparse.Namespace, habits) -> dict | None:
    """The habits the session's model used (the file's content: replay rebuilds the same model), or None."""
    from ..decision.io.habits_file import habits_to_dict

    return None if habits is None else {**habits_to_dict(habits), "file": args.habits}


def _current_step(events) -> int:
    return next((e["step"] for e in reversed(events.events) if "step" in e), 0)


def _replay(args: argparse.Namespace) -> int:
    import numpy as np

    from ..decision.belief_plot import BeliefTrace, plot_beliefs, state_trace
    from ..decision.models import top_intentions
    from ..runtime.log import replay

    done = replay(args.log, limits=inputs_from(args))
    model = done.model
    factored = belief_over(model) == BELIEF_OVER["factored"]  # a replayed model is flat or factored
    steps = list(enumerate(zip(done.actions, done.observations, done.beliefs[1:]), start=1))
    if not args.json:
        print(f"{done.product.name or args.log}: {len(done.actions)} steps, "
              f"ended: {done.end['reason'] + ' (' + done.end['message'] + ')' if done.end else 'no end event'}")
        print(f"  {'step':>4}  {'robot action':<44} {'observation':<28} belief (top 3)")
    for k, (a, z, b) in steps:
        best = top_intentions(b, 3)
        seen = f"{done.ignored[k]} (ignored)" if k in done.ignored else done.undone.get(k, str(model.observations[z]))
        if args.json:
            print(json.dumps({"step": k, "action": model.actions[a], "observation": model.observations[z],
                              "top": best, **({"ignored": done.ignored[k]} if k in done.ignored else {}),
                              **({"undone": done.undone[k]} if k in done.undone else {})}))
        else:
            top = " ".join(f"{'c' if factored else 'i'}{i} {p:.2f}" for i, p in best)
            print(f"  {k:>4}  {model.actions[a]:<44} {seen:<28} {top}")
    if args.plot:
        title = f"session {Path(args.log).name}: {len(done.actions)} steps"
        if factored:
            trace = state_trace(model, done.beliefs, None, done.actions, done.observations, title)
        else:
            trace = BeliefTrace(np.stack(done.beliefs, axis=1), [int(np.argmax(b)) for b in done.beliefs],
                                [model.actions[a] for a in done.actions],
                                [str(model.observations[z]) for z in done.observations], title,
                                line_label="most probable intention (a session does not know the true one)")
        written = plot_beliefs([trace], args.plot, done.product.name or model.name)
        if not args.json:
            print("wrote " + ", ".join(written))
    if done.unrecoverable and not args.json:
        print(f"  unrecoverable: {done.unrecoverable}")
    if done.mismatches:
        raise PlannerError(f"{args.log}: the logged beliefs differ from the recomputed ones at steps "
                           f"{', '.join(map(str, done.mismatches))}")
    if done.reported:
        raise PlannerError(f"{args.log}: the logged operations of the robot's joins differ from the ones the "
                           f"recomputed beliefs give at steps {', '.join(map(str, done.reported))}")
    if not args.json:
        joins = sum("join" in e for e in done.events if e["event"] == "action")
        also = f" and the operations of its {joins} joins" if joins else ""
        print(f"beliefs{also} reproduced at all {len(done.actions)} steps")
    return 0


def _markers(args: argparse.Namespace) -> int:
    from ..runtime.sheet import write_marker_sheet
    from ..runtime.vision import default_markers

    product = api.resolve_product(args.product)
    count = write_marker_sheet(product, args.output, args.size)
    dictionary = (product.markers or default_markers(product)).dictionary
    print(f"{args.output}: {count} markers ({dictionary}, {args.size:g} mm)")
    if product.markers is None:
        log.info("the product has no 'markers': they are numbered in file order (parts, then tools); add "
                 "'markers' to the product file to keep them fixed")
    return 0


def add_habits_out(parser) -> None:
    """``--habits-out FILE`` and ``--habits-prior ALPHA`` (the habits a session writes when it ends), with the
    ``--force`` that lets FILE be replaced: the options of every command that runs a session."""
    parser.add_argument("--habits-out", metavar="FILE",
                        help="at the end, write the habits (--habits, or none) plus the steps of this session "
                             "(docs/habits.md); an existing file is replaced only with --force")
    parser.add_argument("--habits-prior", type=number(0, low_open=True), default=HABITS_PRIOR, metavar="ALPHA",
                        help=f"the prior of --habits-out when there is no --habits (default {HABITS_PRIOR:g})")
    add_force(parser, outputs=("habits_out",))


def _add_session(commands) -> None:
    session = commands.add_parser(
        "session", help="run the collaboration loop: observations -> belief -> robot instructions",
        description="Watch the operator (camera, video, images of the parts tray, or picks typed in), update "
                    "the belief over intentions, and tell the robot what to do, until the product is assembled. "
                    "Every event is logged as JSON lines. Exit status 0 when the product was assembled.")
    session.add_argument("product", metavar="PRODUCT", help=PRODUCT_HELP)
    add_policy_options(session)
    source = session.add_mutually_exclusive_group(required=True)
    source.add_argument("--camera", type=index, metavar="N", help="camera index (OpenCV: /dev/videoN)")
    source.add_argument("--video", metavar="FILE", help="a video file of the tray")
    source.add_argument("--images", metavar="DIR", help="a folder of images of the tray, in file-name order")
    source.add_argument("--keyboard", action="store_true", help="type the operator's picks (no camera)")
    source.add_argument("--demo", type=index, metavar="K",
                        help="a simulated cell: an operator following full sequence K (aplan intentions PRODUCT "
                             "--full; by rank from 0 with the online planner) and a robot, on a rendered tray seen "
                             "through the vision pipeline")
    session.add_argument("--robot", choices=("console", "auto"),
                         help="console (default): print each instruction for the person standing in for the "
                              "robot and wait for Enter; auto: confirm every instruction at once (dry runs)")
    session.add_argument("--log", metavar="FILE", help="the JSON-lines log (default: session-DATE-TIME-PID.jsonl, "
                                                       "PID the process id; never overwritten)")
    session.add_argument("--debounce", type=number(1, FRAME_LIMIT, integer=True), default=3, metavar="F",
                         help=f"frames a marker must stay seen or unseen before it counts, 1 to {FRAME_LIMIT:,} "
                              "(default 3)")
    session.add_argument("--quiet-frames", type=number(1, FRAME_LIMIT, integer=True), default=45, metavar="F",
                         help=f"frames without any marker change that make a blank observation, 1 to {FRAME_LIMIT:,} "
                              "(default 45: 1.5 s at 30 fps)")
    session.add_argument("--robot-own-tools", action="store_true",
                         help="the robot has tools of its own: every tool taken from the tray is the operator's "
                              "(default: the robot takes its tool from the tray too, as in the paper)")
    session.add_argument("--max-steps", type=number(1, STEP_LIMIT, integer=True), default=500, metavar="N",
                         help=f"robot decisions at most, 1 to {STEP_LIMIT:,} (default 500)")
    add_habits_out(session)
    add_decision_options(session)
    session.set_defaults(run=_session)


def add_commands(commands) -> None:
    _add_session(commands)
    replay_cmd = commands.add_parser("replay", help="recompute the beliefs of a session log; Fig. 7 plot",
                                     description="Replay a session log: recompute every belief from the logged "
                                                 "actions and observations, check them against the log, and "
                                                 "optionally plot them (exit status 1 on a mismatch).")
    replay_cmd.add_argument("log", metavar="LOG", help="a session log (.jsonl)")
    replay_cmd.add_argument("--plot", metavar="STEM", help="write STEM.png and STEM.svg (belief heat map)")
    replay_cmd.add_argument("--json", action="store_true", help="one JSON line per step")
    add_force(replay_cmd, outputs=(), stems=("plot",))
    add_input_options(replay_cmd)
    replay_cmd.set_defaults(run=_replay)

    markers = commands.add_parser("markers", help="print the tray's markers with part and tool names",
                                  description="Write the ArUco markers of a product's parts and tools, labelled, "
                                              "on A4 pages (PDF, or PNG: the first page).")
    markers.add_argument("product", metavar="PRODUCT", help=PRODUCT_HELP)
    markers.add_argument("-o", "--output", required=True, metavar="FILE", help="sheet.pdf or sheet.png")
    markers.add_argument("--size", type=number(5, 180), default=40.0, metavar="MM",
                         help="marker width in mm, 5 to 180 (an A4 page; default 40)")
    add_force(markers)
    markers.set_defaults(run=_markers)
