"""The two servers of a cell without one of its own: the vision server (``sensor_msgs/Image`` -> ArUco ->
``aplan_msgs/Markers``) and the stand-in robot server (``aplan_msgs/Perform``: prints the instruction for the
person standing in for the robot and waits for them, as in the paper's experiment).

Names are node-relative: the vision server subscribes ``image`` and publishes ``markers``; the robot server
serves ``perform``. Each runs until the node is shut down (Ctrl-C).
"""
from __future__ import annotations

import select
import sys
from typing import Callable

from ..interfaces import Instruction
from ..vision.markers import MarkerDetector
from .adapters import instruction_of
from .images import ImageError, image_to_array

__all__ = ["VisionServer", "RobotServer", "console_answer"]


class VisionServer:
    """Detects the markers of each frame on ``image`` and publishes them on ``markers``, one message per
    frame (``frame`` counts them from 1). An unreadable frame (an encoding the detector cannot read) is
    published with ``error`` set, so the planner stops with that message, and logged once per encoding.
    ``queue_size``: frames kept while detection is busy (a live camera drops older ones beyond it).
    Cost: one detection per frame (about 15 ms for 1920x1080 on one core)."""

    def __init__(self, dictionary: str, image: str = "image", markers: str = "markers", queue_size: int = 2):
        import rospy
        from sensor_msgs.msg import Image

        from .interfaces import messages

        self.msgs = messages()
        self.detector = MarkerDetector(dictionary)
        self.frames = 0
        self.refused: set[str] = set()
        self.publisher = rospy.Publisher(markers, self.msgs.Markers, queue_size=100)
        self.subscriber = rospy.Subscriber(image, Image, self.on_image, queue_size=queue_size, buff_size=2 ** 25,
                                           tcp_nodelay=True)

    def on_image(self, image) -> None:
        import rospy

        self.frames += 1
        reply = self.msgs.Markers(frame=self.frames)
        reply.header.stamp = image.header.stamp
        try:
            reply.ids = sorted(self.detector.detect(image_to_array(image)))
        except ImageError as exc:
            reply.error = str(exc)
            if image.encoding not in self.refused:
                self.refused.add(image.encoding)
                rospy.logerr("aplan ros-vision: %s", exc)
        self.publisher.publish(reply)


def console_answer(instruction: Instruction, cancelled: Callable[[], bool], stream=None) -> tuple[bool, str]:
    """Print ``instruction`` for the person standing in for the robot and wait for their line: empty (Enter)
    means done, any text is the reason it failed. Returns early (not done) when ``cancelled()`` turns true."""
    stream = stream or sys.stdin
    print(f"step {instruction.step}: robot, {instruction.text}. Enter when done, or type why not: ", end="",
          flush=True)
    while not cancelled():
        ready, _, _ = select.select([stream], [], [], 0.2)
        if ready:
            line = stream.readline()
            if not line:  # end of input: nobody can confirm
                return False, "the stand-in robot's input ended"
            return (True, "") if not line.strip() else (False, line.strip())
    print()
    return False, "cancelled"


class RobotServer:
    """The ``perform`` action server; ``answer(instruction, cancelled)`` -> ``(done, reason)`` decides each
    goal (default :func:`console_answer`); ``done`` None: the server cancels the goal itself (preempted, with
    ``reason``). A goal the planner cancels while ``answer`` runs ends preempted."""

    def __init__(self, answer: Callable[[Instruction, Callable[[], bool]], tuple[bool, str]] = console_answer,
                 name: str = "perform"):
        import actionlib

        from .interfaces import messages

        self.msgs = messages()
        self.answer = answer
        self.server = actionlib.SimpleActionServer(name, self.msgs.PerformAction, execute_cb=self.execute,
                                                   auto_start=False)
        self.server.start()

    def execute(self, goal) -> None:
        done, reason = self.answer(instruction_of(goal), self.server.is_preempt_requested)
        result = self.msgs.PerformResult(done=bool(done), reason=reason)
        if done is None:  # the server's own cancel (the operator changed course)
            self.server.set_preempted(result, reason)
        elif self.server.is_preempt_requested():
            self.server.set_preempted(result, "cancelled by the planner")
        else:
            self.server.set_succeeded(result)
