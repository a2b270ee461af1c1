"""The embedded example products (shipped in ``resources/examples``)."""
from __future__ import annotations

import os
from pathlib import Path

from ..errors import UnknownProductError

__all__ = ["resources_dir", "EXAMPLES", "example_path"]

EXAMPLES = {"pen": "examples/pen/pen.json"}


def resources_dir() -> Path:
    """The project's ``resources`` folder (``APLAN_RESOURCES`` overrides it)."""
    override = os.environ.get("APLAN_RESOURCES")
    return Path(override) if override else Path(__file__).resolve().parents[2] / "resources"


def example_path(name: str) -> Path:
    """The product file of the embedded example ``name``."""
    if name not in EXAMPLES:
        raise UnknownProductError(f"no embedded example named {name!r}; embedded examples: {', '.join(EXAMPLES)}")
    return resources_dir() / EXAMPLES[name]
