"""The session's cell over ROS 1: the robot as an actionlib client, the observations from a marker topic, the
belief as a topic, and a watch on the ROS master.

Names are node-relative (remap them as usual): the action ``perform`` (``aplan_msgs/Perform``), the topics
``markers`` (``aplan_msgs/Markers``, subscribed), ``belief`` (``aplan_msgs/Belief``) and ``waiting_for_frames``
(``std_msgs/UInt32``: the marker messages read so far, published while the planner waits for the next one; a
simulator or a player may use it to run in step with the planner, a live camera ignores it).

Faults are :class:`RosError` (a :class:`~planner.errors.PlannerError`, so the session ends with an ``error``
end event and a message) or a robot report ``ok = False`` (``robot failed``), never a traceback.
"""
from __future__ import annotations

import queue
import time
import xmlrpc.client

from ...errors import PlannerError
from ...interrupts import raise_if_swallowed
from ..interfaces import Instruction, RobotReport
from ..vision.markers import VisionError

__all__ = ["RosError", "MasterWatch", "connect", "RosRobot", "MarkerFeed", "BeliefPublisher", "goal_of",
           "instruction_of"]


class RosError(PlannerError):
    """The ROS graph is not as the session needs: no master, no server, a server of another type."""


class _Timeout(xmlrpc.client.Transport):
    def __init__(self, seconds: float):
        super().__init__()
        self.seconds = seconds

    def make_connection(self, host):
        connection = super().make_connection(host)
        connection.timeout = self.seconds
        return connection


class MasterWatch:
    """Whether the ROS master at ``uri`` answers (one XML-RPC ``getPid``, at most ``seconds`` long);
    :meth:`check` raises :class:`RosError` when it does not. Checked at most every ``every`` seconds."""

    def __init__(self, uri: str, seconds: float = 3.0, every: float = 1.0):
        self.uri, self.seconds, self.every = uri, seconds, every
        self._last = float("-inf")

    def online(self) -> bool:
        try:
            code, _, _ = xmlrpc.client.ServerProxy(self.uri, transport=_Timeout(self.seconds)).getPid("/aplan")
            return code == 1
        except (OSError, xmlrpc.client.Error):
            return False

    def check(self, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self._last < self.every:
            return
        if not self.online():
            raise RosError(f"the ROS master at {self.uri} does not answer (it stopped, or the network is down); "
                           "restart roscore and the session (the log holds every step before this)")
        self._last = time.monotonic()


def connect(name: str, argv: list[str]) -> MasterWatch:
    """Start this process's ROS node ``name`` (``argv``: the ``name:=value`` remappings); a master that does not
    answer is a :class:`RosError` at once (rospy would wait for it forever)."""
    import rosgraph
    import rospy

    uri = rosgraph.get_master_uri()
    watch = MasterWatch(uri)
    if not watch.online():
        raise RosError(f"no ROS master answers at {uri} (ROS_MASTER_URI); start roscore first, or set "
                       "ROS_MASTER_URI to the cell's master")
    rospy.init_node(name, argv=argv, anonymous=False, disable_signals=True)  # signals stay aplan's (exit 130)
    return watch


def goal_of(instruction: Instruction, goal_class):
    """The ``PerformGoal`` of ``instruction``. The goal's format is unchanged for an action named by a join
    (``--joins``): its ``name`` and ``instruction`` text carry the join, the other fields are the reported
    operation's (docs/ros.md; :func:`~planner.runtime.interfaces.with_join` gives the join back)."""
    first, second = instruction.inputs or ((), ())
    return goal_class(step=instruction.step, action=instruction.action, name=instruction.name,
                      operation=-1 if instruction.operation is None else instruction.operation,
                      first=list(first), second=list(second), fasteners=list(instruction.fasteners),
                      picks=list(instruction.picks), tool=instruction.tool or "", instruction=instruction.text)


def instruction_of(goal) -> Instruction:
    """The :class:`Instruction` a ``PerformGoal`` carries (a robot server's view of it)."""
    wait = goal.operation < 0
    return Instruction(int(goal.step), int(goal.action), goal.name, None if wait else int(goal.operation),
                       None if wait else (tuple(goal.first), tuple(goal.second)), goal.tool or None,
                       tuple(goal.fasteners))


def _check_type(topic: str, expected: str, what: str) -> None:
    """A :class:`RosError` when ``topic`` is published with a type other than ``expected``."""
    import rospy

    published = dict(rospy.get_published_topics())
    found = published.get(topic)
    if found is not None and found != expected:
        raise RosError(f"{topic} is published as {found}, not {expected}: {what}")


class RosRobot:
    """The robot (:class:`planner.runtime.interfaces.Robot`) as a client of the ``perform`` action.

    :meth:`perform` sends the goal and waits for the result at most ``timeout`` seconds (then cancels it and
    reports a failure). A result with ``done`` false, an aborted, rejected or cancelled goal are failures with
    the server's reason. Waits at most ``server_timeout`` s at start for the server; a server of another
    action type under the name is an error naming both types.
    """

    def __init__(self, watch: MasterWatch, name: str = "perform", timeout: float = 300.0,
                 server_timeout: float = 30.0):
        import actionlib
        import rospy

        from .interfaces import messages

        self.msgs = messages()
        self.watch = watch
        self.timeout = timeout
        self.name = rospy.resolve_name(name)
        _check_type(self.name + "/result", "aplan_msgs/PerformActionResult",
                    f"the action server at {self.name} is not an aplan_msgs/Perform server (docs/ros.md); remap "
                    "perform:=... to the robot's")
        # actionlib's ActionClient, not SimpleActionClient: the latter misses a result that comes before
        # send_goal has returned (a fast server), and then waits for ever
        self.client = actionlib.ActionClient(self.name, self.msgs.PerformAction)
        if not self.client.wait_for_server(rospy.Duration(server_timeout)):
            _check_type(self.name + "/result", "aplan_msgs/PerformActionResult",
                        "it is not an aplan_msgs/Perform server (docs/ros.md)")
            raise RosError(f"no robot action server at {self.name} after {server_timeout:g} s; start one "
                           "(aplan ros-robot, or yours: docs/ros.md) or remap perform:=...")

    def perform(self, instruction: Instruction) -> RobotReport:
        import threading

        from actionlib import CommState, GoalStatus

        self.watch.check(force=True)
        finished = threading.Event()

        def on_transition(handle) -> None:  # this goal's own: a late message of an earlier goal cannot end it
            if handle.get_comm_state() == CommState.DONE:
                finished.set()

        handle = self.client.send_goal(goal_of(instruction, self.msgs.PerformGoal), on_transition)
        try:
            deadline, answered = time.monotonic() + self.timeout, False
            while not answered and time.monotonic() < deadline:
                # an interrupt that rospy or actionlib caught on the way (bare excepts) still ends the wait
                raise_if_swallowed()
                answered = finished.wait(min(0.5, max(0.0, deadline - time.monotonic())))
        except KeyboardInterrupt:  # Ctrl-C, SIGTERM: the robot stops too, then the session's log ends
            handle.cancel()
            raise
        if not answered:
            handle.cancel()
            return RobotReport(False, f"the robot server at {self.name} gave no result within {self.timeout:g} s "
                                      "(--robot-timeout); the goal was cancelled")
        state, result = handle.get_terminal_state(), handle.get_result()
        reason = (result.reason if result is not None else "") or handle.get_goal_status_text()
        if state == GoalStatus.SUCCEEDED and result is not None and result.done:
            return RobotReport(True)
        if state == GoalStatus.SUCCEEDED:
            return RobotReport(False, reason or "the robot server answered not done, without a reason")
        what = {GoalStatus.PREEMPTED: "cancelled", GoalStatus.RECALLED: "cancelled", GoalStatus.ABORTED: "aborted",
                GoalStatus.REJECTED: "rejected"}.get(state, f"ended in state {state}")
        return RobotReport(False, f"the goal was {what} by the robot server" + (f": {reason}" if reason else ""))


class MarkerFeed:
    """The marker ids of each frame from the ``markers`` topic, in order, as the iterator a
    :class:`~planner.runtime.vision.VisionSource` reads (``detections``). Messages are queued as they come
    (none is dropped), so frames seen while the robot works are read in order afterwards, as with a live
    camera. Waiting more than ``frame_timeout`` s for the next one is a :class:`VisionError` (the image topic
    or the detector stopped); a message with ``error`` set (an unreadable frame) is one too.
    """

    def __init__(self, watch: MasterWatch, name: str = "markers", frame_timeout: float = 60.0,
                 connect_timeout: float = 30.0, poll: float = 0.5):
        import rospy
        from std_msgs.msg import UInt32

        from .interfaces import messages

        self.watch, self.frame_timeout, self.poll = watch, frame_timeout, poll
        self.queue: queue.Queue = queue.Queue()
        self.read = 0
        self.name = rospy.resolve_name(name)
        _check_type(self.name, "aplan_msgs/Markers", "remap markers:=... to a topic of aplan_msgs/Markers "
                                                     "(aplan ros-vision publishes one)")
        self.waiting = rospy.Publisher("waiting_for_frames", UInt32, queue_size=10)
        self.subscriber = rospy.Subscriber(self.name, messages().Markers, self.queue.put, queue_size=None,
                                          tcp_nodelay=True)
        deadline = time.monotonic() + connect_timeout
        while self.subscriber.get_num_connections() == 0:
            if time.monotonic() > deadline:
                raise RosError(f"nothing publishes {self.name} after {connect_timeout:g} s; start the vision "
                               "server (aplan ros-vision) or your detector, or remap markers:=...")
            time.sleep(0.05)
        self._uint32 = UInt32

    def __iter__(self):
        return self

    def __next__(self) -> set[int]:
        try:
            message = self.queue.get_nowait()
        except queue.Empty:
            message = self._wait()
        self.read += 1
        if message.error:
            raise VisionError(f"{self.name}, frame {message.frame}: {message.error}")
        return {int(i) for i in message.ids}

    def _wait(self):
        """The next message, saying every ``poll`` s that the planner waits (and that the master answers)."""
        started = time.monotonic()
        while True:
            raise_if_swallowed()  # as in RosRobot.perform
            self.watch.check()
            self.waiting.publish(self._uint32(self.read))
            try:
                return self.queue.get(timeout=self.poll)
            except queue.Empty:
                if time.monotonic() - started >= self.frame_timeout:  # a fault's bound, not a result's
                    raise VisionError(f"no marker message on {self.name} for {self.frame_timeout:g} s "
                                      f"(--frame-timeout) after {self.read} frames: the image topic or the "
                                      "vision server stopped") from None

    def close(self) -> None:
        self.subscriber.unregister()


class BeliefPublisher:
    """Publishes ``belief`` (``aplan_msgs/Belief``) from the session's log events: at each ``action`` event the
    top intentions of the last belief, the action and its decision time; at the ``end`` event, action -1."""

    def __init__(self, name: str = "belief", belief_over: str = "intentions"):
        import rospy

        from .interfaces import messages

        self.msgs = messages()
        self.publisher = rospy.Publisher(name, self.msgs.Belief, queue_size=10, latch=True)
        self.belief_over = belief_over
        self.top: list = []

    def __call__(self, event: dict) -> None:
        import rospy

        kind = event["event"]
        if kind == "start":
            self.belief_over = event.get("belief_over", self.belief_over)
        if kind in ("start", "belief"):
            self.top = event["top"]
            return
        if kind not in ("action", "end"):
            return
        message = self.msgs.Belief(step=event["step"], belief_over=self.belief_over,
                                   top=[self.msgs.Intention(int(i), float(p)) for i, p in self.top])
        message.header.stamp = rospy.Time.now()
        if kind == "action":
            message.next_action, message.next_action_name = event["action"], event["name"]
            message.decision_time = event["decision_ms"] / 1000
        else:
            message.top = [self.msgs.Intention(int(i), float(p)) for i, p in event["top"]]
            message.next_action, message.next_action_name = -1, event["reason"]
        self.publisher.publish(message)
