"""An observation source for session tests: the observations of a list, in order, then None (the source has
ended). It ignores the robot (``robot_acting``), so a test decides every observation itself."""
from __future__ import annotations

__all__ = ["ListedSource"]


class ListedSource:
    def __init__(self, observations):
        self.observations = list(observations)

    def observe(self):
        return self.observations.pop(0) if self.observations else None

    def robot_acting(self, instruction):
        pass
