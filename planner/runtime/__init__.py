"""The collaboration runtime (the paper's Sec. IV): the decision loop that watches the operator and drives a
robot (or a person standing in for it), its JSON-lines log and replay, marker vision, and simulated trays.

Where things plug in (:mod:`.interfaces`, :class:`typing.Protocol` classes: any class with these methods
fits, no subclassing):

- an *observation source*, :class:`ObservationSource`: ``observe() -> Observation | None`` (the operator's
  operation in this step, BLANK for none, None when the source has ended) and
  ``robot_acting(instruction)`` (told before the robot acts, so the robot's picks are not the operator's).
  Provided: :class:`~.vision.VisionSource` (a camera over the tray's ArUco markers),
  :class:`KeyboardSource` (picks typed in), :class:`ScriptedOperator` (one assembly sequence);
- a *robot*, :class:`Robot`: ``perform(instruction) -> RobotReport``. Provided: :class:`ConsoleRobot` (a
  person confirms each instruction with Enter) and :class:`ScriptedRobot`.

Modules: ``interfaces`` (the protocols, :class:`Instruction`, :class:`RobotReport`), ``session`` (the loop,
:func:`run_session`), ``log`` (:class:`EventLog`, the log format, :func:`replay`), ``console`` and
``scripted`` (the provided robots and sources), ``vision`` (camera -> observations; OpenCV is loaded only
when a detector or a frame source is made) and ``tray`` (rendered trays, a simulated cell, the marker sheet;
import them from their modules).
"""
from .console import ConsoleRobot, KeyboardSource, read_line
from .interfaces import Instruction, ObservationSource, Robot, RobotReport, instruction_for
from .log import LOG_VERSION, EventLog, Replay, SessionError, replay
from .scripted import ScriptedOperator, ScriptedRobot
from .session import SessionResult, run_session, status_line

__all__ = [
    "Instruction", "RobotReport", "ObservationSource", "Robot", "instruction_for",
    "ConsoleRobot", "KeyboardSource", "read_line", "ScriptedOperator", "ScriptedRobot",
    "LOG_VERSION", "EventLog", "Replay", "SessionError", "replay",
    "SessionResult", "run_session", "status_line",
]
