"""A discrete POMDP in sparse tables: the *model* half of the model / solver / policy / updater seam.

Any solver (:mod:`planner.solvers`) runs on any ``POMDP``, whether built from a product
(:func:`planner.decision.intention_pomdp`) or read from a POMDPX or Cassandra ``.pomdp`` file.

Tables, for ``S`` states, ``A`` actions and ``Z`` observations:

- ``transition[a]``: (S, S) CSR, ``T(s' | s, a)``; each row sums to 1;
- ``observation[a]``: (S, Z) CSR, ``O(z | s', a)``, the probability of observing ``z`` after action ``a``
  led to state ``s'``; each row sums to 1;
- ``reward``: (A, S) dense, ``R(s, a)``;
- ``initial``: (S,) dense, the initial belief; ``discount`` in [0, 1).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..defaults import DISCOUNT
from ..errors import PlannerError

__all__ = ["POMDP", "PROBABILITY_TOLERANCE", "ModelError"]

PROBABILITY_TOLERANCE = 1e-6  # a row or the initial belief may sum to 1 within this (APPL's own files: 1.0000008)
_ROUNDING = 1e-12  # initial beliefs closer than this to 1 are left as they are (float rounding: files round-trip)
_NOTE_ABOVE = 1e-9  # further than this from 1, they are normalised with a note; between the two, silently

log = logging.getLogger(__name__)


class ModelError(PlannerError):
    """A POMDP's tables are inconsistent (sizes, probabilities that do not sum to 1, unknown names)."""


@dataclass(frozen=True)
class POMDP:
    """A discrete POMDP with named states, actions and observations and sparse tables (module docstring)."""

    states: tuple[str, ...]
    actions: tuple[str, ...]
    observations: tuple[str, ...]
    transition: tuple[sp.csr_matrix, ...]
    observation: tuple[sp.csr_matrix, ...]
    reward: np.ndarray
    initial: np.ndarray
    discount: float = DISCOUNT
    name: str = "aplan"

    def __post_init__(self) -> None:
        self.check()
        total = float(self.initial.sum())
        if abs(total - 1) > _ROUNDING:  # within the tolerance (check); numpy's sampler needs 1 within 1.5e-8
            if abs(total - 1) > _NOTE_ABOVE:
                log.info("%s: the initial belief sums to %.9g, within %g of 1: normalised", self.name, total,
                         PROBABILITY_TOLERANCE)
            positive = np.clip(self.initial, 0, None)
            object.__setattr__(self, "initial", positive / positive.sum())

    @property
    def n_states(self) -> int:
        return len(self.states)

    @property
    def n_actions(self) -> int:
        return len(self.actions)

    @property
    def n_observations(self) -> int:
        return len(self.observations)

    def check(self, tolerance: float = PROBABILITY_TOLERANCE) -> None:
        """Raise :class:`ModelError` naming the first row whose probabilities do not sum to 1, or a size
        that does not match."""
        S, A, Z = self.n_states, self.n_actions, self.n_observations
        if len(self.transition) != A or len(self.observation) != A:
            raise ModelError(f"{A} actions but {len(self.transition)} transition and {len(self.observation)} "
                             "observation tables")
        if self.reward.shape != (A, S):
            raise ModelError(f"reward table has shape {self.reward.shape}, expected ({A}, {S})")
        if self.initial.shape != (S,):
            raise ModelError(f"initial belief has {self.initial.shape[0]} entries, expected {S}")
        if not 0 <= self.discount < 1:
            raise ModelError(f"discount must be in [0, 1), got {self.discount}")
        self._check_finite()
        for kind, tables, width, names in (("transition", self.transition, S, self.states),
                                           ("observation", self.observation, Z, self.observations)):
            for a, table in enumerate(tables):
                if table.shape != (S, width):
                    raise ModelError(f"{kind} table of action {self.actions[a]!r} has shape {table.shape}, "
                                     f"expected ({S}, {width})")
                if table.nnz and table.data.min() < -tolerance:
                    coo = table.tocoo()
                    k = int(np.argmin(coo.data))
                    row = "from state" if kind == "transition" else "in state"
                    raise ModelError(f"{kind} table of action {self.actions[a]!r} has a negative probability, "
                                     f"{coo.data[k]:.9g} {row} {self.states[coo.row[k]]!r} (column "
                                     f"{names[coo.col[k]]!r})")
                sums = np.asarray(table.sum(axis=1)).ravel()
                bad = np.flatnonzero(np.abs(sums - 1) > tolerance)
                if bad.size:
                    s = int(bad[0])
                    row = "from state" if kind == "transition" else "in state"
                    raise ModelError(f"{kind} probabilities of action {self.actions[a]!r} {row} {self.states[s]!r} "
                                     f"sum to {sums[s]:.9g}, not 1 ({bad.size} such rows)")
        if self.initial.size and self.initial.min() < -tolerance:
            s = int(np.argmin(self.initial))
            raise ModelError(f"initial belief has a negative probability, {self.initial[s]:.9g} on state "
                             f"{self.states[s]!r}")
        if abs(self.initial.sum() - 1) > tolerance or self.initial.min() < -tolerance:
            raise ModelError(f"initial belief sums to {self.initial.sum():.9g}, not 1")

    def _check_finite(self) -> None:
        """Raise :class:`ModelError` naming the first table holding a NaN or an infinity. O(nnz + A S)."""
        tables = [("initial belief", self.initial), ("reward table", self.reward)]
        tables += [(f"transition table of action {a!r}", t.data) for a, t in zip(self.actions, self.transition)]
        tables += [(f"observation table of action {a!r}", o.data) for a, o in zip(self.actions, self.observation)]
        for what, values in tables:
            bad = np.flatnonzero(~np.isfinite(np.asarray(values, dtype=float).ravel()))
            if bad.size:
                raise ModelError(f"the {what} holds {bad.size} value(s) that are not finite numbers (such as "
                                 f"{np.asarray(values).ravel()[bad[0]]}); every number must be finite")

    def dense(self) -> tuple[np.ndarray, np.ndarray]:
        """Dense (A, S, S) transition and (A, S, Z) observation arrays (for small models and tests)."""
        return (np.stack([t.toarray() for t in self.transition]), np.stack([o.toarray() for o in self.observation]))
