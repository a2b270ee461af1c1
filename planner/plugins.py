"""Extension points, filled by installed packages through the ``aplan.plugins`` entry point group.

The FreeCAD side registers the ``export-freecad`` command, loaders for ``.FCStd``/STEP files and the
``occt`` geometry engine here, so the planner can offer them without importing FreeCAD itself.
A plugin is a module with ``register(registry: Registry) -> None``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from importlib.metadata import entry_points
from pathlib import Path
from typing import Callable

__all__ = ["Registry", "registry"]


@dataclass
class Registry:
    """``commands``: functions adding a subcommand to the CLI's subparsers; ``loaders``: file suffix (lower
    case, with the dot) -> function reading such a file into a Product; ``engines``: geometry engines."""

    commands: list[Callable] = field(default_factory=list)
    loaders: dict[str, Callable[[Path], object]] = field(default_factory=dict)
    engines: dict[str, Callable] = field(default_factory=dict)


@lru_cache(maxsize=None)
def registry() -> Registry:
    """The registry filled by every installed ``aplan.plugins`` entry point (loaded once)."""
    result = Registry()
    for entry in entry_points(group="aplan.plugins"):
        entry.load().register(result)
    return result
