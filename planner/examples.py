"""The embedded example products (shipped in ``resources/examples``) and PRODUCT argument resolution."""
from __future__ import annotations

import os
from pathlib import Path

from .errors import UnknownProductError
from .product import Product, load_product

__all__ = ["resources_dir", "EXAMPLES", "example_path", "resolve_product"]

EXAMPLES = {"pen": "examples/pen/pen.json"}


def resources_dir() -> Path:
    """The project's ``resources`` folder (``APLAN_RESOURCES`` overrides it)."""
    override = os.environ.get("APLAN_RESOURCES")
    return Path(override) if override else Path(__file__).resolve().parent.parent / "resources"


def example_path(name: str) -> Path:
    """The product file of the embedded example ``name``."""
    if name not in EXAMPLES:
        raise UnknownProductError(f"no embedded example named {name!r}; embedded examples: {', '.join(EXAMPLES)}")
    return resources_dir() / EXAMPLES[name]


def resolve_product(argument: str | os.PathLike) -> Product:
    """Load PRODUCT: a product file, or the name of an embedded example (``pen``)."""
    path = Path(argument)
    if path.is_file():
        return load_product(path)
    if str(argument) in EXAMPLES:
        return load_product(example_path(str(argument)))
    if path.is_dir():
        raise UnknownProductError(f"{argument}: is a folder, not a product file (*.json)")
    raise UnknownProductError(
        f"{argument}: no such file, and no embedded example of that name (embedded: {', '.join(EXAMPLES)})")
