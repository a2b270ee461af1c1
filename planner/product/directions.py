"""Motion directions and the obstruction diagram along one (paper Sec. III-A): the values the product, its
designer marks and the geometry engines share. They hold no product, so every module of the product may
import them."""
from __future__ import annotations

from dataclasses import dataclass

from .constants import AXIS_DIRECTIONS, UNIT_TOLERANCE

__all__ = ["Direction", "Obstruction"]


@dataclass(frozen=True)
class Direction:
    """A unit motion direction; ``name`` is ``+X`` ... ``-Z`` for the axes, else the vector written out."""

    name: str
    vector: tuple[float, float, float]

    @classmethod
    def from_vector(cls, vector: tuple[float, float, float]) -> "Direction":
        """The direction of a unit ``vector``, named after the axis it lies on (within ``UNIT_TOLERANCE``)."""
        for name, axis in AXIS_DIRECTIONS.items():
            if all(abs(a - b) <= UNIT_TOLERANCE for a, b in zip(axis, vector)):
                return cls(name, axis)
        return cls("[" + ", ".join(f"{c:g}" for c in vector) + "]", vector)

    @property
    def reverse(self) -> "Direction":
        # Adding 0.0 turns -0.0 into 0.0, so the reverse of an axis prints without negative zeros.
        vector = (-self.vector[0] + 0.0, -self.vector[1] + 0.0, -self.vector[2] + 0.0)
        return Direction.from_vector(vector)


@dataclass(frozen=True)
class Obstruction:
    """The obstruction diagram along one direction: ``blocks`` holds pairs ``(x, y)``: x moving hits y."""

    direction: Direction
    blocks: tuple[tuple[str, str], ...]
