"""``aplan ros``, ``ros-vision``, ``ros-robot``, ``ros-sim``: the cell on ROS 1 (docs/ros.md).

``aplan ros`` runs the loop of ``aplan session`` (:func:`planner.cli.runtime._session`: any product and level,
offline or online planner, the same log, ``aplan replay``) with the robot an ``aplan_msgs/Perform`` action
server and the observations from an ``aplan_msgs/Markers`` topic. Arguments ``name:=value`` (ROS remappings,
``__name:=``, what roslaunch adds) go to rospy, the rest to argparse. The node's private parameters
(``~product``, ``~level``, ``~planner``, ``~policy``, ``~decision_time``, ``~expansions``, ``~log``,
``~max_steps``, ``~debounce``, ``~quiet_frames``, ``~habits``, ``~habits_out``) stand for the options not given
on the command line and are checked as the options are. A product of several levels runs them bottom-up in one
run, as ``aplan session`` does; the latched ``level`` topic (``std_msgs/UInt32``) says which (1, 2, ...), so that
``aplan ros-sim`` switches its cell with it. ROS is imported only when one of these commands runs.
"""
from __future__ import annotations

import argparse

from ..defaults import STEP_LIMIT
from ..errors import UsageError
from .options import (
    PRODUCT_HELP,
    add_decision_options,
    add_policy_options,
    decision_seconds,
    index,
    model_spec_from,
    number,
    planner_choice_from,
)
from .runtime import FRAME_LIMIT, add_habits_out

__all__ = ["add_commands", "split_remaps", "REMAPS"]

REMAPS: list[str] = []  # the ROS arguments of this run (name:=value), for rospy.init_node
COMMANDS = ("ros", "ros-vision", "ros-robot", "ros-sim")
seconds = number(0, 86_400, low_open=True)
# Seconds the planner waits for the next marker message before it ends the session: "the camera went quiet". It
# counts only while the planner waits for a frame (not while it decides or the robot works), and a live camera
# sends 30 a second; the margin is for a detector or simulator on a loaded machine (10 s fired once on one).
FRAME_TIMEOUT = 60.0

# parameter -> (dest, parse, default when neither the option nor the parameter is given)
_PARAMETERS = {
    "product": ("product", str, None), "level": ("level", str, None),
    "planner": ("planner", str, None), "policy": ("policy", str, None),
    "decision_time": ("decision_time", decision_seconds, None),
    "expansions": ("expansions", number(1, 10 ** 9, integer=True), None), "log": ("log", str, None),
    "max_steps": ("max_steps", number(1, STEP_LIMIT, integer=True), 500),
    "debounce": ("debounce", number(1, FRAME_LIMIT, integer=True), 3),
    "quiet_frames": ("quiet_frames", number(1, FRAME_LIMIT, integer=True), 45),
    "habits": ("habits", str, None), "habits_out": ("habits_out", str, None),
}


def split_remaps(argv: list[str]) -> list[str]:
    """``argv`` without its ROS arguments (kept in :data:`REMAPS`) when it runs one of :data:`COMMANDS`."""
    if not argv or argv[0] not in COMMANDS:
        return argv
    REMAPS[:] = [str(a) for a in argv if ":=" in str(a)]
    return [a for a in argv if ":=" not in str(a)]


def _require() -> None:
    from ..runtime.ros.system import require_ros

    require_ros()


def _node(args: argparse.Namespace):
    """Import ROS (or say what to install) and start this command's node; the master watch."""
    from ..runtime.ros.adapters import connect
    from ..runtime.ros.system import require_ros

    require_ros()
    return connect(args.node, ["aplan", *REMAPS])


def _shutdown() -> None:
    import rospy

    rospy.signal_shutdown("aplan is done")


def _apply_parameters(args: argparse.Namespace) -> None:
    """Fill the options left out with the node's private parameters, then the defaults (module docstring)."""
    import rospy

    for name, (dest, parse, default) in _PARAMETERS.items():
        if getattr(args, dest, None) is not None:
            continue
        value = rospy.get_param("~" + name, None)
        if value is not None:
            try:
                value = parse(str(value))
            except (argparse.ArgumentTypeError, ValueError) as exc:
                raise UsageError(f"parameter ~{name} = {value!r}: {exc}") from None
            if name == "planner" and value not in ("offline", "online"):
                raise UsageError(f"parameter ~planner = {value!r}: use offline or online")
        setattr(args, dest, value if value is not None else default)
    if args.product is None:
        raise UsageError("aplan ros: give PRODUCT, or the node's ~product parameter")


def _ros(args: argparse.Namespace) -> int:
    from ..runtime.ros.adapters import BeliefPublisher, MarkerFeed, RosRobot
    from .options import check_outputs
    from .runtime import _session

    watch = _node(args)
    try:
        _apply_parameters(args)
        check_outputs(args)  # again: ~habits_out may have come from a parameter
        import rospy
        from std_msgs.msg import UInt32

        publisher = BeliefPublisher()
        level = rospy.Publisher("level", UInt32, queue_size=1, latch=True)
        robots: list = []  # one action client for every level
        opened: list = []  # the levels started so far

        def open_stream(args, model, markers, detector):
            opened.append(model)
            level.publish(UInt32(len(opened)))
            if not robots:
                robots.append(RosRobot(watch, timeout=args.robot_timeout, server_timeout=args.server_timeout))
            feed = MarkerFeed(watch, frame_timeout=args.frame_timeout, connect_timeout=args.server_timeout)
            args.source_name, args.robot = f"ros {feed.name}", f"ros {robots[0].name}"
            return feed, robots[0]

        args.open_stream, args.on_event = open_stream, publisher
        return _session(args)
    finally:
        _shutdown()


def _vision(args: argparse.Namespace) -> int:
    _require()
    import rospy

    from .. import api
    from ..product import DEFAULT_MARKER_DICTIONARY
    from ..runtime.ros.servers import VisionServer

    dictionary = args.dictionary
    if dictionary is None and args.product:
        product = api.resolve_product(args.product)
        dictionary = product.markers.dictionary if product.markers else None
    _node(args)
    try:
        VisionServer(dictionary or DEFAULT_MARKER_DICTIONARY, queue_size=args.queue_size)
        print(f"aplan ros-vision: {rospy.resolve_name('image')} -> {rospy.resolve_name('markers')} "
              f"({dictionary or DEFAULT_MARKER_DICTIONARY})", flush=True)
        rospy.spin()
    finally:
        _shutdown()
    return 0


def _robot(args: argparse.Namespace) -> int:
    _require()
    import rospy

    from ..runtime.ros.servers import RobotServer, console_answer

    _node(args)
    try:
        RobotServer((lambda instruction, cancelled: (True, "")) if args.auto else console_answer)
        print(f"aplan ros-robot: serving {rospy.resolve_name('perform')}", flush=True)
        rospy.spin()
    finally:
        _shutdown()
    return 0


def _sim(args: argparse.Namespace) -> int:
    _require()
    import rospy

    from ..api import check_cell_observe
    from ..runtime.ros.sim import SimulatedRosCell
    from ..runtime.tray import CameraModel, SimulatedCell, tray_layout
    from ..runtime.vision import marker_map
    from .decision import decision_maker_from, levels_from
    from ..runtime.scripted import ScriptedOperator
    from .runtime import _demo_operations

    spec, choice = model_spec_from(args), planner_choice_from(args)  # once, for every level
    check_cell_observe(spec.observe)

    def cell_of(product) -> SimulatedCell:
        """The cell of aplan session --demo K on one level, frame for frame (planner.cli.runtime._open_stream)."""
        model, _ = decision_maker_from(args, product, spec, choice)
        designed = model.plan.designed or model.plan.product
        operator = ScriptedOperator(model.plan, _demo_operations(model, args.demo))
        camera = CameraModel(blur=1.2, noise=6, perspective=0.04, hands=True, seed=args.demo)
        return SimulatedCell(tray_layout(marker_map(designed), margin=camera.perspective + 0.02), operator, camera,
                             settle=args.quiet_frames + 5)

    cells = [cell_of(product) for _, product in levels_from(args)]  # the levels aplan ros runs, in its order
    watch = _node(args)
    try:
        SimulatedRosCell(cells, watch, args.fail_at, args.hang_at, args.pause_at, args.stop_after, args.cancel_at)
        print(f"aplan ros-sim: {rospy.resolve_name('image')}, {rospy.resolve_name('perform')}", flush=True)
        rospy.spin()
    finally:
        _shutdown()
    return 0


def _add_model_options(parser: argparse.ArgumentParser, defaults: bool) -> None:
    parser.add_argument("product", metavar="PRODUCT", nargs="?" if not defaults else None, help=PRODUCT_HELP)
    add_policy_options(parser)
    add_decision_options(parser)
    parser.add_argument("--debounce", type=number(1, FRAME_LIMIT, integer=True), default=3 if defaults else None,
                        metavar="F", help="frames a marker must stay seen or unseen before it counts (default 3)")
    parser.add_argument("--quiet-frames", type=number(1, FRAME_LIMIT, integer=True),
                        default=45 if defaults else None, metavar="F",
                        help="frames without any marker change that make a blank observation (default 45)")


def add_commands(commands) -> None:
    node = dict(metavar="NAME", help="the ROS node's name (default %(default)s)")
    ros = commands.add_parser(
        "ros", help="the collaboration loop as a ROS 1 node (robot: an action server; camera: a marker topic)",
        description="aplan session on ROS 1 (docs/ros.md): sends each robot instruction to the aplan_msgs/Perform "
                    "action server 'perform', reads the operator's picks from the aplan_msgs/Markers topic "
                    "'markers', publishes the belief on 'belief', and logs every event as aplan session does. "
                    "ROS remappings (name:=value) and private parameters (~product, ~planner, ~log, ...) apply.")
    _add_model_options(ros, defaults=False)
    ros.add_argument("--log", metavar="FILE", help="the JSON-lines log (default: session-DATE-TIME-PID.jsonl, PID "
                                                   "the process id; never overwritten)")
    ros.add_argument("--robot-own-tools", action="store_true",
                     help="the robot has tools of its own (default: it takes its tool from the tray too)")
    ros.add_argument("--max-steps", type=number(1, STEP_LIMIT, integer=True), default=None, metavar="N",
                     help="robot decisions at most (default 500)")
    ros.add_argument("--robot-timeout", type=seconds, default=300.0, metavar="S",
                     help="seconds to wait for the robot's result before cancelling the goal (default 300)")
    ros.add_argument("--frame-timeout", type=seconds, default=FRAME_TIMEOUT, metavar="S",
                     help="seconds the planner waits for the next marker message before it ends the session: the "
                          f"camera or the detector went quiet (default {FRAME_TIMEOUT:g})")
    ros.add_argument("--server-timeout", type=seconds, default=30.0, metavar="S",
                     help="seconds to wait at start for the robot server and the marker topic (default 30)")
    add_habits_out(ros)
    ros.add_argument("--node", default="aplan_planner", **node)
    ros.set_defaults(run=_ros, demo=None, keyboard=False, camera=None, video=None, images=None, robot="ros")

    vision = commands.add_parser("ros-vision", help="ROS vision server: sensor_msgs/Image -> ArUco markers",
                                 description="Detect the tray's ArUco markers in each frame of 'image' "
                                             "(sensor_msgs/Image: bgr8, rgb8, mono8, ...) and publish them on "
                                             "'markers' (aplan_msgs/Markers) for aplan ros.")
    vision.add_argument("product", metavar="PRODUCT", nargs="?", help="the product whose marker dictionary to use")
    vision.add_argument("--dictionary", metavar="DICT", help="the ArUco dictionary (default: the product's, else "
                                                             "DICT_4X4_50)")
    vision.add_argument("--queue-size", type=number(1, 1000, integer=True), default=2, metavar="N",
                        help="frames kept while detection is busy (default 2)")
    vision.add_argument("--node", default="aplan_vision", **node)
    vision.set_defaults(run=_vision)

    robot = commands.add_parser("ros-robot", help="ROS stand-in robot server: prints each instruction, waits "
                                                  "for Enter",
                                description="Serve the 'perform' action (aplan_msgs/Perform) for a person "
                                            "standing in for the robot: print each instruction; Enter answers "
                                            "done, a typed line answers failed with that reason.")
    robot.add_argument("--auto", action="store_true", help="answer done at once (dry runs)")
    robot.add_argument("--node", default="aplan_robot", **node)
    robot.set_defaults(run=_robot)

    sim = commands.add_parser("ros-sim", help="a simulated cell on ROS: the demo's rendered tray and robot",
                              description="Publish the rendered tray of aplan session --demo K on 'image', in "
                                          "step with the planner, and serve 'perform' as its robot. Give the "
                                          "planner's model options (the same sequence numbering).")
    _add_model_options(sim, defaults=True)
    sim.add_argument("--demo", type=index, required=True, metavar="K", help="the operator follows full sequence K")
    sim.add_argument("--fail-at", type=number(1, STEP_LIMIT, integer=True), action="append", default=[],
                     metavar="STEP", help="the robot answers failed at STEP (repeatable)")
    sim.add_argument("--hang-at", type=number(1, STEP_LIMIT, integer=True), action="append", default=[],
                     metavar="STEP", help="the robot never answers at STEP, until cancelled")
    sim.add_argument("--pause-at", type=number(1, STEP_LIMIT, integer=True), action="append", default=[],
                     metavar="STEP", help="the robot answers STEP only after the ROS master has gone")
    sim.add_argument("--cancel-at", type=number(1, STEP_LIMIT, integer=True), action="append", default=[],
                     metavar="STEP", help="the robot server cancels the goal of STEP itself (the operator changed "
                                          "course)")
    sim.add_argument("--stop-after", type=number(0, integer=True), default=None, metavar="N",
                     help="the camera stops after N frames")
    sim.add_argument("--node", default="aplan_cell", **node)
    sim.set_defaults(run=_sim)
