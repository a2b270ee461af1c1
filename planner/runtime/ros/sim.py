"""The simulated cell on ROS (``aplan ros-sim``): the rendered tray of ``aplan session --demo`` published as
``sensor_msgs/Image`` on ``image``, and a robot server on ``perform`` that takes the robot's parts from it.

The camera runs in step with the planner: it publishes the next frame only when the planner says on
``waiting_for_frames`` that it has read every frame published so far, and the operator acts only when the
frames already rendered have run out (what the in-process demo does). So the planner sees exactly the demo's
frames, in the demo's order, and writes the same session log. A product of several levels is a cell per
level: the planner's latched ``level`` topic (``std_msgs/UInt32``, 1, 2, ...) says which one the camera shows. Fault drills for tests and rehearsals:
``fail_at`` (the robot answers "failed" at those steps), ``hang_at`` (it never answers, until cancelled),
``pause_at`` (it answers only once the ROS master has gone), ``cancel_at`` (it cancels the goal itself, as
when the operator changed course), ``stop_after`` (the camera stops after that many
frames).
"""
from __future__ import annotations

import threading
import time

from ..interfaces import Instruction, with_join
from ..tray import SimulatedCell
from .adapters import MasterWatch
from .images import array_to_image
from .servers import RobotServer

__all__ = ["SimulatedRosCell"]


class SimulatedRosCell:
    """Publishes ``cell``'s frames on demand and serves its robot (module docstring)."""

    def __init__(self, cells: list[SimulatedCell], watch: MasterWatch, fail_at=(), hang_at=(), pause_at=(),
                 stop_after: int | None = None, cancel_at=()):
        import rospy
        from sensor_msgs.msg import Image
        from std_msgs.msg import UInt32

        self.cells, self.cell, self.level, self.watch = list(cells), cells[0], 1, watch
        self.fail_at, self.hang_at, self.pause_at = set(fail_at), set(hang_at), set(pause_at)
        self.stop_after, self.cancel_at = stop_after, set(cancel_at)
        self.published = 0
        self.lock = threading.Lock()
        self._image = Image
        self.publisher = rospy.Publisher("image", Image, queue_size=4)
        self.robot = RobotServer(self.answer)
        self.subscriber = rospy.Subscriber("waiting_for_frames", UInt32, self.on_waiting, queue_size=10,
                                           tcp_nodelay=True)
        self.levels = rospy.Subscriber("level", UInt32, self.on_level, queue_size=10)

    def on_level(self, message) -> None:
        """The planner starts level ``message.data`` (from 1): its cell, from its first frame. A level the
        simulation does not have is logged and ignored (the planner then times out waiting for frames)."""
        import rospy

        with self.lock:
            if message.data == self.level:
                return
            if not 1 <= message.data <= len(self.cells):
                rospy.logerr("aplan ros-sim: the planner started level %d of %d", message.data, len(self.cells))
                return
            # frames of the level before are all read (each is published only when asked for), so none mixes in
            self.level, self.cell, self.published = message.data, self.cells[message.data - 1], 0

    def on_waiting(self, message) -> None:
        """The planner has read ``message.data`` frames: publish the next one when it has read them all."""
        import rospy

        with self.lock:
            if message.data != self.published or self.publisher.get_num_connections() == 0:
                return  # a frame is on its way (a repeated request), or nobody would receive it
            if self.stop_after is not None and self.published >= self.stop_after:
                return
            frame = next(self.cell)
            self.published += 1
            self.publisher.publish(array_to_image(frame, self._image, rospy.Time.now()))

    def answer(self, instruction: Instruction, cancelled) -> tuple[bool, str]:
        step = instruction.step
        if step in self.hang_at:
            while not cancelled():
                time.sleep(0.05)
            return False, "cancelled"
        if step in self.pause_at:
            while self.watch.online():
                time.sleep(0.1)
        if step in self.fail_at:
            return False, f"scripted failure at step {step}"
        if step in self.cancel_at:
            return None, "the operator changed course"
        with self.lock:  # a join (its goal's name says so) is done at the cell's true state
            self.cell.robot(with_join(self.cell.operator.plan, instruction))
        return True, ""
