"""The real models of ../shared/models exported once per test session (FreeCAD, about 12 s each)."""
from __future__ import annotations

from pathlib import Path

import pytest
from conftest import SHARED, require_freecadcmd, require_shared
from integration.freecad_tools import aplan

__all__ = ["REAL_MODELS", "real_bundles"]

REAL_MODELS = {"toy_truck": "toy_truck/asm_cement_mixer_truck.FCStd",
               "diaphragm_pump": "diaphragm_pump/asm_diaphragm_pump.FCStd"}


@pytest.fixture(scope="session")
def real_bundles(tmp_path_factory) -> dict[str, Path]:
    """Model name -> its bundle folder, exported with the default settings (skips without FreeCAD, fails
    instead when APLAN_REQUIRE_FREECAD=1)."""
    require_freecadcmd()
    out = {}
    for name, path in REAL_MODELS.items():
        bundle = tmp_path_factory.mktemp("real") / name
        aplan("export-freecad", str(require_shared(SHARED / "models" / path)), "-o", str(bundle))
        out[name] = bundle
    return out
