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
    """Load PRODUCT: a product file, a bundle folder, a CAD file a plugin reads (``.FCStd``, STEP: through
    FreeCAD), or the name of an embedded example (``pen``).

    A bundle whose geometry has not been analysed yet is analysed in memory with the mesh engine.
    """
    from .bundle import PRODUCT_FILE, analyze_product, apply_report, is_analysed
    from .plugins import registry

    path = Path(argument)
    if path.is_dir():
        if not (path / PRODUCT_FILE).is_file():
            raise UnknownProductError(f"{argument}: is a folder without {PRODUCT_FILE}, so not a product bundle")
        product = load_product(path / PRODUCT_FILE)
        return product if is_analysed(product) else apply_report(product, analyze_product(product))
    if path.is_file():
        loader = registry().loaders.get(path.suffix.lower())
        if loader is not None:
            return loader(path)
        if path.suffix.lower() in (".fcstd", ".step", ".stp"):
            raise UnknownProductError(f"{argument}: reading {path.suffix} files needs APLAN's FreeCAD side "
                                      "(install the project with `pip install -e .` and FreeCAD)")
        return load_product(path)
    if str(argument) in EXAMPLES:
        return load_product(example_path(str(argument)))
    raise UnknownProductError(
        f"{argument}: no such file, and no embedded example of that name (embedded: {', '.join(EXAMPLES)})")
