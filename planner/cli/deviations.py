"""``--switch P`` and ``--mistakes Q``: the operator's change of mind and mistakes in the decision model (issue 23
item 3, docs/deviations.md), for every command that builds a model from a PRODUCT."""
from __future__ import annotations

import argparse

from ..decision.deviations import Deviations, deviations_of
from .options import number

__all__ = ["add_deviation_options", "deviations_from"]

_probability = number(0, 1, high_open=True)  # [0, 1): outside is a usage error naming the option (exit 2)


def add_deviation_options(group) -> None:
    """The two probabilities (docs/deviations.md); both 0 by default: the paper's model."""
    group.add_argument("--switch", type=_probability, default=0.0, metavar="P",
                       help="change of mind: each time the operator may act, with probability P in [0, 1) it "
                            "first draws a new completion from the current assembly state by the prior "
                            "(default 0: the paper's model; docs/deviations.md)")
    group.add_argument("--mistakes", type=_probability, default=0.0, metavar="Q",
                       help="mistakes: each observation is, with probability Q in [0, 1), one drawn uniformly "
                            "from all (a wrong part or tool taken), so none resets the belief (default 0)")


def deviations_from(args: argparse.Namespace) -> Deviations | None:
    """The deviations ``args`` ask for, None for the paper's model (both 0, or ``--model paper``)."""
    if getattr(args, "habit_model", None) == "paper":
        return None
    return deviations_of(getattr(args, "switch", 0.0) or 0.0, getattr(args, "mistakes", 0.0) or 0.0)

