"""Load a decision model from a POMDPX file, a ``.pomdp`` file, or a product (built by Alg. 3)."""
from __future__ import annotations

import os
from pathlib import Path

from .assembly.plan import make_plan
from .decision.intention_model import Rewards, intention_pomdp
from .decision.io.cassandra import read_cassandra, write_cassandra
from .decision.io.pomdpx import read_pomdpx, write_pomdpx
from .decision.pomdp import POMDP
from .defaults import DISCOUNT
from .errors import PlannerError, UnknownProductError
from .product.examples import EXAMPLES, example_path
from .product.model import Product, load_product

__all__ = ["resolve_product", "load_model", "save_model", "MODEL_SUFFIXES"]

MODEL_SUFFIXES = (".pomdpx", ".pomdpx.gz", ".pomdp")


def _kind(path: str | Path) -> str | None:
    name = str(path).lower()
    return next((s for s in MODEL_SUFFIXES if name.endswith(s)), None)


def load_model(argument: str | Path, technical: bool | None = None, rewards: Rewards = Rewards(),
               discount: float = DISCOUNT) -> POMDP:
    """MODEL: a ``.pomdpx`` (or ``.pomdpx.gz``) or ``.pomdp`` file, else a PRODUCT (file, bundle, example)."""
    kind = _kind(argument)
    if kind in (".pomdpx", ".pomdpx.gz"):
        return read_pomdpx(argument)
    if kind == ".pomdp":
        return read_cassandra(argument)
    return intention_pomdp(make_plan(resolve_product(argument), technical), rewards, discount)


def save_model(model: POMDP, path: str | Path) -> None:
    """Write POMDPX (``.pomdpx``) or Cassandra (``.pomdp``), by the file name."""
    kind = _kind(path)
    if kind == ".pomdpx":
        write_pomdpx(model, path)
    elif kind == ".pomdp":
        write_cassandra(model, path)
    else:
        raise PlannerError(f"{path}: unknown model file type; use .pomdpx or .pomdp")


def resolve_product(argument: str | os.PathLike) -> Product:
    """Load PRODUCT: a product file, a bundle folder, a CAD file a plugin reads (``.FCStd``, STEP: through
    FreeCAD), or the name of an embedded example (``pen``).

    A bundle whose geometry has not been analysed yet is analysed in memory with the mesh engine.
    """
    from .geometry.bundle import (
        PRODUCT_FILE,
        analyze_product,
        apply_report,
        is_analysed,
    )
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
