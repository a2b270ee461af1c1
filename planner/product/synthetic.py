"""Synthetic products of Table I: weakly (chain) and strongly (complete) connected products of n parts.

Neither has obstruction relations or technical constraints, so every connected split is feasible. Closed
forms for n parts (used by the tests): chain: n(n+1)/2 subassemblies, C(n+1, 3) operations, 2^(n-1) states,
(n-1)! sequences; complete: 2^n - 1 subassemblies, (3^n + 1)/2 - 2^n operations, Bell(n) states,
n!(n-1)!/2^(n-1) sequences.

``fastened_product(parts, screws)`` adds fasteners: a chain of parts, and screws that each touch the two
parts of one joint, as wood screws do in a real product. Each screw doubles the connected part sets that
hold its joint: two parts and m screws give 3 * 2^m + m connected sets (every one a subassembly).
"""
from __future__ import annotations

from ..errors import PlannerError
from .model import Part, Product

__all__ = ["chain_product", "complete_product", "fastened_product", "SYNTHETIC", "synthetic_contacts",
           "synthetic_bytes"]


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


def fastened_product(parts: int, screws: int) -> Product:
    """A chain of ``parts`` parts (``p1``, ...) and ``screws`` screws (``screw_01``, ...), screw ``k`` touching
    the two parts of joint ``k mod (parts - 1)``: the connection diagram of a screwed product."""
    if parts < 2:
        raise PlannerError(f"a fastened product needs at least 2 parts to join, got {parts}")
    chain = chain_product(parts)
    width = len(str(screws))
    fasteners = tuple(Part(f"screw_{k:0{width}d}", f"Screw {k}") for k in range(1, screws + 1))
    joints = [chain.contacts[k % (parts - 1)] for k in range(screws)]
    contacts = chain.contacts + tuple((a, s.id) for (a, _), s in zip(joints, fasteners)) + \
        tuple((b, s.id) for (_, b), s in zip(joints, fasteners))
    return Product(chain.parts + fasteners, contacts, name=f"{parts} parts joined by {screws} screws")


SYNTHETIC = {"chain": chain_product, "complete": complete_product}


def synthetic_contacts(kind: str, n: int) -> int:
    """The contacts of the synthetic product ``kind`` of ``n`` parts: ``n - 1`` (chain), ``n (n - 1) / 2``
    (complete)."""
    return n - 1 if kind == "chain" else n * (n - 1) // 2


def synthetic_bytes(kind: str, n: int) -> int:
    """The most memory writing the synthetic product takes (its objects and their JSON text): about 400 bytes a
    contact and 1,000 a part (measured 391 a contact on complete 300)."""
    return 400 * synthetic_contacts(kind, n) + 1000 * n
