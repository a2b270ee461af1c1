"""Pictures of the three graphs (planner.assembly.figures)."""
from __future__ import annotations

import os

from figure_support import pyplot_untouched

from planner import make_plan, resolve_product
from planner.assembly.figures import draw_plan


def test_pen_pictures_and_the_size_limit(tmp_path, monkeypatch):
    plan = make_plan(resolve_product("pen"))
    with pyplot_untouched(monkeypatch):
        drawn = draw_plan(plan, tmp_path)
    assert sorted(drawn) == ["andor", "intentions", "states"]
    for path in drawn.values():
        with open(path, "rb") as handle:
            assert handle.read(8) == b"\x89PNG\r\n\x1a\n"
    assert sorted(os.listdir(tmp_path)) == ["andor.png", "intentions.png", "states.png"]  # no temporary file left
    # 39 nodes in the AND/OR graph (18 subassemblies + 21 operations), 18 states, 69 intentions.
    limited = draw_plan(plan, tmp_path / "none", limit=30)
    assert "AND/OR graph nodes: 39 would be enumerated" in limited["andor"]
    assert limited["states"].endswith("states.png")
    assert "69 would be enumerated" in limited["intentions"]
