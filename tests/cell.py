"""A simulated cell for the vision and session tests: a synthetic tray filmed while a scripted operator and a
scripted robot take parts and use the tool. Every frame is rendered by planner.tray, so the truth is known."""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from planner.session import Instruction, ScriptedOperator
from planner.tray import Occluder, TrayLayout, render_tray


@dataclass(frozen=True)
class Camera:
    """Image degradations of one camera: Gaussian blur sigma, noise std (grey levels), perspective tilt
    (fraction of the frame), and whether hands pass over the tray."""

    blur: float = 0.0
    noise: float = 0.0
    perspective: float = 0.0
    hands: bool = False
    seed: int = 0


class TrayCell:
    """An iterator of frames. When its queue runs dry it is the operator's turn: the operator performs its
    next operation (takes its single parts, grasps the tool, puts it back) or idles for ``idle`` frames.
    ``robot(instruction)`` (a ScriptedRobot hook) renders the robot's picks and strikes its operation from
    the operator's list. Each change is held for ``hold`` frames."""

    def __init__(self, layout: TrayLayout, operator: ScriptedOperator, camera: Camera = Camera(), hold: int = 8,
                 idle: int = 24):
        self.layout = layout
        self.operator = operator
        self.camera = camera
        self.hold = hold
        self.idle = idle
        self.in_tray = set(layout.slots)
        self.queue: deque = deque()
        self.frames = 0
        self.operator_observations = []  # the truth, in order

    def __iter__(self):
        return self

    def __next__(self):
        if not self.queue:
            self._operator_turn()
        return self.queue.popleft()

    def robot(self, instruction: Instruction) -> None:
        self.operator.robot_acting(instruction)
        for part in instruction.picks:
            self._take(part)
        if instruction.tool is not None:
            self._use_tool(instruction.tool)

    def _operator_turn(self) -> None:
        operation = self.operator.next_operation()
        if operation is None:
            self._show(self.idle)
            return
        observation = self.operator.observation_of(operation)
        self.operator_observations.append(observation)
        for part in observation.parts:
            self._take(part)
        if observation.tool is not None:
            self._use_tool(observation.tool)

    def _take(self, item: str) -> None:
        self.in_tray.discard(item)
        self._show(self.hold, reach=item)

    def _use_tool(self, tool: str) -> None:
        self.in_tray.discard(tool)
        self._show(self.hold, reach=tool)
        self.in_tray.add(tool)
        self._show(self.hold, reach=tool)

    def _show(self, count: int, reach: str | None = None) -> None:
        for k in range(count):
            occluders = ()
            if self.camera.hands and reach is not None and k < 2:
                # a hand over the slot just reached into, and an arm across the tray, for two frames
                x, y = self.layout.slots[reach]
                px = self.layout.marker_px
                occluders = (Occluder((x + px // 2, y + px // 2), (px // 2, px // 3), 30.0),
                             Occluder((self.layout.size[0] // 2, self.layout.size[1] // 2), (px * 3, px // 4), 10.0))
            elif self.camera.hands and k == count // 2 + 1:
                # a corner of every slot covered, for one frame (a marker flickers)
                px = self.layout.marker_px
                occluders = tuple(Occluder((x, y), (px // 3, px // 3)) for x, y in self.layout.slots.values())
            self.frames += 1
            self.queue.append(render_tray(self.layout, self.in_tray, self.camera.blur, self.camera.noise,
                                          self.camera.perspective, occluders,
                                          seed=self.camera.seed * 100_003 + self.frames,
                                          camera_seed=self.camera.seed))
