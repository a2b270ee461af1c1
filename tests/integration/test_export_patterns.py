"""aplan export-freecad --exclude and --group take shell-style patterns; a pattern that matches nothing is an
error naming it, and nothing is written."""
from __future__ import annotations

import functools
import json

import pytest
from background import Job, folder
from conftest import PEN_MODELS, SHARED, require_freecadcmd, require_shared

from integration.freecad_tools import aplan, aplan_process, succeeded

TRUCK = SHARED / "models" / "toy_truck" / "asm_cement_mixer_truck.FCStd"


PATTERNS = {"chosen": ("--exclude", "wood_screw*", "--group", "front_tires=tire_00[12]"),
            "no exclude": ("--exclude", "woodscrew*"), "no group": ("--group", "g=tire_9*")}


def _export(options: tuple[str, ...]) -> tuple:
    """`aplan export-freecad` of the truck (no engine) with the pattern options: (bundle, the run)."""
    bundle = folder("patterns") / "truck"
    return bundle, aplan_process("export-freecad", str(TRUCK), "-o", str(bundle), "--engine", "none", *options)


EXPORTS = {name: Job(f"the truck exported with {name!r} patterns", functools.partial(_export, options))
           for name, options in PATTERNS.items()}
#: The exports the tests read, done in the background (tests/background.py).
BACKGROUND = tuple(EXPORTS.values())


@pytest.mark.freecad
def test_patterns_choose_the_truck_components():
    require_freecadcmd()
    require_shared(TRUCK)
    bundle, done = EXPORTS["chosen"].result()
    succeeded(done)
    ids = [p["id"] for p in json.loads((bundle / "product.json").read_text())["parts"]]
    # 61 solids - 39 screws - 2 tires + 1 group
    assert len(ids) == 21 and not any(i.startswith("wood_screw") for i in ids)
    assert "front_tires" in ids and "tire_001" not in ids and "tire_003" in ids


@pytest.mark.freecad
@pytest.mark.parametrize("export, message", [
    ("no exclude", "exclude 'woodscrew*' matches no object"),
    ("no group", "group 'g': 'tire_9*' matches no object")])
def test_a_pattern_that_matches_nothing(export, message):
    require_freecadcmd()
    require_shared(TRUCK)
    bundle, done = EXPORTS[export].result()
    assert done.returncode == 1 and message in done.stderr and "Traceback" not in done.stderr
    assert not bundle.exists()


@pytest.mark.freecad
def test_a_cad_model_read_with_groups_by_any_command(tmp_path):
    """--group on a command given the .FCStd itself reads it as export-freecad --group would: the same parts
    and the same figures as the bundle exported with that group."""
    require_freecadcmd()
    pen = str(require_shared(PEN_MODELS / "simplified" / "asm_bourjault_ballpoint.FCStd"))
    direct = json.loads(aplan("stats", pen, "--group", "refill=cartridge_001,ink_*", "--json").stdout)
    bundle = tmp_path / "pen"
    aplan("export-freecad", pen, "-o", str(bundle), "--group", "refill=cartridge_001,ink_*")
    exported = json.loads(aplan("stats", str(bundle), "--json").stdout)
    assert direct == exported and direct["parts"] == 5    # 6 parts, two of them one component


def test_groups_are_refused_for_a_product_that_is_no_cad_model():
    done = aplan("stats", "pen", "--group", "a=b", check=False)
    assert done.returncode == 1 and "choose the components of a CAD model" in done.stderr
    assert "Traceback" not in done.stderr
