"""Synthetic products of Table I: weakly (chain) and strongly (complete) connected products of n parts.

Neither has obstruction relations or technical constraints, so every connected split is feasible. Closed
forms for n parts (used by the tests): chain: n(n+1)/2 subassemblies, C(n+1, 3) operations, 2^(n-1) states,
(n-1)! sequences; complete: 2^n - 1 subassemblies, (3^n + 1)/2 - 2^n operations, Bell(n) states,
n!(n-1)!/2^(n-1) sequences.
"""
from __future__ import annotations

from ..errors import PlannerError
from .model import Part, Product

__all__ = ["chain_product", "complete_product", "SYNTHETIC"]


def _parts(n: int) -> tuple[Part, ...]:
    if n < 1:
        raise PlannerError(f"a synthetic product needs at least 1 part, got {n}")
    width = len(str(n))
    return tuple(Part(f"p{i:0{width}d}", f"Part {i}") for i in range(1, n + 1))


def chain_product(n: int) -> Product:
    """n parts in a row, each in contact with the next (complexity 2(n-1)/n, the lower bound)."""
    parts = _parts(n)
    contacts = tuple((parts[i].id, parts[i + 1].id) for i in range(n - 1))
    return Product(parts, contacts, name=f"chain of {n} parts (weakly connected)")


def complete_product(n: int) -> Product:
    """n parts, each in contact with every other (complexity n - 1, the upper bound)."""
    parts = _parts(n)
    contacts = tuple((parts[i].id, parts[j].id) for i in range(n) for j in range(i + 1, n))
    return Product(parts, contacts, name=f"complete graph of {n} parts (strongly connected)")


SYNTHETIC = {"chain": chain_product, "complete": complete_product}
