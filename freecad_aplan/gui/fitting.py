"""Plain arithmetic behind the panels' layout (:mod:`.layout`), without Qt so that it is tested anywhere: where
a cell's text may break, and how columns share a table's width."""
from __future__ import annotations

import re

__all__ = ["BREAK", "breakable", "shared_widths"]

BREAK = "\u200b"  # a zero-width space: where a line may break
_LONG = re.compile(r"[^\s_,/.\u200b]{4,}")


def breakable(text: str) -> str:
    """``text`` with line-break opportunities after ``_ , / .`` and between the characters of any run of 4
    or more other characters: ``cartridge_001`` may wrap as ``cartridge_`` / ``001`` or inside ``cartridge``, so
    that even a column a few letters wide shows every letter."""
    text = re.sub(r"([_,/.])", "\\1" + BREAK, text)
    return _LONG.sub(lambda found: BREAK.join(found.group(0)), text)


def shared_widths(needs: list[int], width: int) -> dict[int, int]:
    """Widths for columns that need at least ``needs[k]`` pixels each, filling ``width``: as equal as the needs
    allow (a column that needs more than an equal share gets its need, the others share the rest equally;
    "water filling"); each its need when the width is too small. Cost: O(n^2) for n columns."""
    free, fixed, left = list(range(len(needs))), {}, width
    while free:
        wide = [k for k in free if needs[k] > left / len(free)]
        if not wide:
            break
        for k in wide:
            fixed[k], left = needs[k], left - needs[k]
            free.remove(k)
    for i, k in enumerate(free):
        fixed[k] = left // len(free) + (i < left % len(free))
    return fixed
