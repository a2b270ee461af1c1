"""The lower bound: a set of alpha vectors, each with the action that starts its conditional plan.

``V_(b) = max_k alpha_k . b`` is the value of a policy that can be executed (take the action of the vector
that is best at the current belief), so it never exceeds ``V*(b)``. It starts from the blind policies
(:func:`~planner.decision.solvers.tables.blind_lower_bound`, one vector per action, always kept) and grows
with point-based backups (the trials and the sweeps); :meth:`LowerBound.prune` drops the vectors that are
best at none of a set of beliefs.
"""
from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from ..policy import AlphaVectorPolicy
from .tables import Rows, Tables, best_products, blind_lower_bound

__all__ = ["LowerBound"]


class LowerBound:
    """Alpha vectors (n, S) and their actions (n,); the first ``fixed`` vectors are never pruned."""

    def __init__(self, vectors: np.ndarray, actions: Iterable[int], fixed: int | None = None):
        self._rows = Rows(vectors.shape[1], columns=True)
        self._rows.extend(vectors)
        self.actions: list[int] = [int(a) for a in actions]
        self.fixed = len(vectors) if fixed is None else fixed

    @classmethod
    def blind(cls, m: Tables, deadline: float | None = None, clock=None) -> LowerBound:
        """The blind policies' vectors, one per action (``A`` linear solves of size S; past ``deadline``, a
        ``clock()`` value, the constant floor: :func:`~planner.decision.solvers.tables.blind_lower_bound`)."""
        if deadline is None:
            return cls(blind_lower_bound(m), range(m.A))
        return cls(blind_lower_bound(m, deadline, clock), range(m.A))

    @property
    def n(self) -> int:
        return self._rows.n

    @property
    def vectors(self) -> np.ndarray:
        """(n, S): the alpha vectors (a view: it changes as vectors are added or pruned)."""
        return self._rows.rows

    def at(self, B: np.ndarray, stop=None) -> tuple[np.ndarray, np.ndarray]:
        """The bound at the beliefs ``B`` (m, S) and the index of the best vector at each (``stop``:
        :func:`~.tables.best_products`'). Cost: O(m n S)."""
        return best_products(B, self._rows.rows, stop, self._rows.columns)

    def value(self, b: np.ndarray) -> float:
        """The bound at one belief ``b`` (S,). Cost: O(n S)."""
        return float(self.at(b[None])[0][0])

    def add(self, vector: np.ndarray, action: int) -> None:
        """Append one vector (S,) with its action. Amortised cost: O(S)."""
        self._rows.append(vector)
        self.actions.append(int(action))

    def extend(self, vectors: np.ndarray, actions: Iterable[int]) -> None:
        """Append vectors (k, S) with their actions (k,). Amortised cost: O(k S)."""
        self._rows.extend(vectors)
        self.actions.extend(int(a) for a in actions)

    def prune(self, beliefs: np.ndarray, stop=None) -> None:
        """Keep the vectors that are best at some belief of ``beliefs`` (m, S), and the fixed ones: the bound
        at each of those beliefs stays the same (``stop``: :meth:`at`'s; stopped, nothing is pruned).
        Cost: O(m n S)."""
        mask = np.zeros(self.n, dtype=bool)
        mask[np.unique(self.at(beliefs, stop)[1])] = True
        mask[:self.fixed] = True
        self._rows.keep(mask)
        self.actions[:] = [self.actions[i] for i in np.flatnonzero(mask)]

    def policy(self) -> AlphaVectorPolicy:
        """The policy of the bound (a copy of the vectors)."""
        return AlphaVectorPolicy(self._rows.rows.copy(), np.asarray(self.actions, dtype=np.int64))
