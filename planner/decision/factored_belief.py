"""Beliefs of the factored decision model (paper Sec. V): sparse masses over its classes
(:class:`FactoredBelief`), and the sum by class every update and prediction ends with. They hold no model, so
the model, its deviations and its filter all import them."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FactoredBelief"]


@dataclass(frozen=True)
class FactoredBelief:
    """A belief over classes: ``classes`` sorted and distinct, ``mass[k] > 0`` the probability of
    ``classes[k]`` (they sum to 1)."""

    classes: np.ndarray
    mass: np.ndarray

    def dense(self, n_classes: int) -> np.ndarray:
        """The masses as a vector over all ``n_classes`` classes."""
        out = np.zeros(n_classes)
        out[self.classes] = self.mass
        return out


def _sum_by(keys: np.ndarray, values: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """The distinct ``keys`` (sorted, in ``range(size)``) whose ``values`` sum to more than 0, and the sums.

    One sort when the keys are few; one dense ``bincount`` over ``size`` when they are many (it is then the
    cheaper of the two). Cost: O(k log k) or O(k + size) for k keys.
    """
    if keys.size * 8 > size:
        total = np.bincount(keys, weights=values, minlength=size)
        distinct = np.flatnonzero(total > 0)
        return distinct, total[distinct]
    distinct, inverse = np.unique(keys, return_inverse=True)
    total = np.bincount(inverse, weights=values, minlength=distinct.size)
    keep = total > 0
    return distinct[keep], total[keep]
