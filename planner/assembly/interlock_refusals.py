"""The designer's refusals of interlock proposals (:mod:`planner.assembly.interlock_proposals`): a proposal
the designer rejected is kept in the product's ``geometry.designer.refused_interlocks`` (``[{"parts": [a, b],
"rule", "text"}]``); while the pair is interlocked, planning it raises the
:class:`~planner.errors.InterlockRefusedError` of ``--interlocks error``. Below both the feasibility checks and
the interlock rules, which raise it, and the proposals, which record it."""
from __future__ import annotations

from ..errors import InterlockRefusedError
from ..product import Product

__all__ = ["REFUSED_KEY", "refused_interlocks", "refusal_message", "refusal_error"]

#: The key of the designer's refusals under ``geometry.designer``.
REFUSED_KEY = "refused_interlocks"


def refused_interlocks(product: Product) -> list[dict]:
    """The designer's refusals of ``product`` (``geometry.designer.refused_interlocks``: module docstring)."""
    designer = product.geometry.get("designer", {})
    found = designer.get(REFUSED_KEY, []) if isinstance(designer, dict) else []
    return [r for r in found if isinstance(r, dict) and len(r.get("parts", ())) == 2]


def refusal_message(where: str, texts: list[str], by: str, remedy: str) -> str:
    """The one line that refuses interlock decisions: how many, who refused them (``by``), what the rules would
    do (``texts``, one per decision) and ``remedy``; the message of ``--interlocks error`` and of a designer's
    refusal alike."""
    return (f"{where}{len(texts)} interlocked pair(s), refused by {by}; the rules would resolve them so: "
            f"{'; '.join(texts)}. {remedy}")


def _short(rule: str, text: str) -> str:
    return text.split(" (")[0] if rule == "component" else text


def refusal_error(product: Product, pairs) -> InterlockRefusedError | None:
    """The :class:`~planner.errors.InterlockRefusedError` for the interlocked ``pairs``
    (:class:`~planner.assembly.feasibility.InterlockedPair`) the designer refused (:func:`refused_interlocks`),
    or None when it refused none of them. Cost: O(P + R)."""
    stuck = {frozenset((p.first, p.second)) for p in pairs}
    refused = [r for r in refused_interlocks(product) if frozenset(r["parts"]) in stuck]
    if not refused:
        return None
    where = f"{product.name}: " if product.name else ""
    texts = [_short(str(r.get("rule", "")), str(r.get("text") or " and ".join(r["parts"]))) for r in refused]
    return InterlockRefusedError(refusal_message(
        where, texts, "the designer (the workbench's interlocks panel)",
        "Accept the proposal in APLAN > Interlocks to apply this, or resolve them in the CAD model (the "
        "workbench's diagrams panel)"), [tuple(r["parts"]) for r in refused])
