"""aplan export-freecad --exclude and --group take shell-style patterns; a pattern that matches nothing is an
error naming it, and nothing is written."""
from __future__ import annotations

import json

import pytest
from conftest import SHARED, require_freecadcmd, require_shared

from integration.freecad_tools import aplan

TRUCK = SHARED / "models" / "toy_truck" / "asm_cement_mixer_truck.FCStd"


@pytest.mark.freecad
def test_patterns_choose_the_truck_components(tmp_path):
    require_freecadcmd()
    bundle = tmp_path / "truck"
    aplan("export-freecad", str(require_shared(TRUCK)), "-o", str(bundle), "--engine", "none",
          "--exclude", "wood_screw*", "--group", "front_tires=tire_00[12]")
    ids = [p["id"] for p in json.loads((bundle / "product.json").read_text())["parts"]]
    # 61 solids - 39 screws - 2 tires + 1 group
    assert len(ids) == 21 and not any(i.startswith("wood_screw") for i in ids)
    assert "front_tires" in ids and "tire_001" not in ids and "tire_003" in ids


@pytest.mark.freecad
@pytest.mark.parametrize("option, pattern, message", [
    ("--exclude", "woodscrew*", "exclude 'woodscrew*' matches no object"),
    ("--group", "g=tire_9*", "group 'g': 'tire_9*' matches no object")])
def test_a_pattern_that_matches_nothing(tmp_path, option, pattern, message):
    require_freecadcmd()
    bundle = tmp_path / "truck"
    done = aplan("export-freecad", str(require_shared(TRUCK)), "-o", str(bundle), "--engine", "none",
                 option, pattern, check=False)
    assert done.returncode == 1 and message in done.stderr and "Traceback" not in done.stderr
    assert not bundle.exists()
