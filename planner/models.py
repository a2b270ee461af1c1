"""Load a decision model from a POMDPX file, a ``.pomdp`` file, or a product (built by Alg. 3)."""
from __future__ import annotations

from pathlib import Path

from .cassandra import read_cassandra, write_cassandra
from .decision import Rewards, intention_pomdp
from .errors import PlannerError
from .examples import resolve_product
from .plan import make_plan
from .pomdp import POMDP
from .pomdpx import read_pomdpx, write_pomdpx

__all__ = ["load_model", "save_model", "MODEL_SUFFIXES"]

MODEL_SUFFIXES = (".pomdpx", ".pomdpx.gz", ".pomdp")


def _kind(path: str | Path) -> str | None:
    name = str(path).lower()
    return next((s for s in MODEL_SUFFIXES if name.endswith(s)), None)


def load_model(argument: str | Path, technical: bool | None = None, rewards: Rewards = Rewards(),
               discount: float = 0.9) -> POMDP:
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
