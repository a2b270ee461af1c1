"""The arithmetic behind the task panels' layout (freecad_aplan.gui.fitting; plain Python, no Qt): where a cell's
text may break, and how columns share a table's width. The panels themselves are checked in the real FreeCAD
window by test_gui.py (every panel at the default width) and test_gui_truck.py (the truck's proposals)."""
from __future__ import annotations

import itertools

import pytest

from freecad_aplan.gui.fitting import BREAK, breakable, shared_widths


@pytest.mark.parametrize("text", ["cartridge_001", "{head_001, cartridge_001} + {ink_001}", "blocks +X", "",
                                  "wood_screw_001: name ('screw')", "a/b.c,d"])
def test_breakable_only_adds_break_opportunities(text):
    shown = breakable(text)
    assert shown.replace(BREAK, "") == text
    # No piece between two opportunities (or spaces) is longer than 3 characters, plus a separator after it.
    pieces = [p for chunk in shown.split() for p in chunk.split(BREAK)]
    assert all(len(p.rstrip("_,/.")) <= 3 or len(p) <= 1 for p in pieces), pieces


def test_breakable_breaks_names_after_their_separators_and_inside_long_runs():
    assert breakable("ink_001") == f"ink_{BREAK}001"
    assert breakable("head_001") == BREAK.join("head") + f"_{BREAK}001"
    assert breakable("blocks +X") == BREAK.join("blocks") + " +X"  # "+X" stays together


@pytest.mark.parametrize(("needs", "width", "expected"), [
    ([60, 35, 35], 190, {0: 64, 1: 63, 2: 63}),          # all needs below an equal share: equal widths
    ([100, 35, 35], 190, {0: 100, 1: 45, 2: 45}),        # one needs more: it gets its need, the others share
    ([60, 35, 35], 120, {0: 60, 1: 35, 2: 35}),          # too narrow: each its need (a checker reports it)
    ([], 100, {}),
])
def test_shared_widths_known_answers(needs, width, expected):
    assert shared_widths(needs, width) == expected


def test_shared_widths_fill_the_width_and_meet_every_need_when_they_can():
    # Brute force over small cases: the widths sum to the width and meet the needs whenever the needs fit; the
    # columns wider than their need are equal (to a pixel), and a column held at its need needed that share.
    for needs in itertools.product([5, 20, 47], repeat=3):
        for width in (40, 75, 100, 151, 200):
            widths = shared_widths(list(needs), width)
            if sum(needs) <= width:
                assert sum(widths.values()) == width
                assert all(widths[k] >= needs[k] for k in range(3))
                shared = [widths[k] for k in range(3) if widths[k] > needs[k]]
                assert not shared or max(shared) - min(shared) <= 1
                # A column held at its need got no share because its need was at least the others' share.
                assert all(needs[k] >= min(shared) - 1 for k in range(3) if shared and widths[k] == needs[k])
            else:
                assert widths == dict(enumerate(needs))
