"""The real models of ../shared/models exported once per test session (FreeCAD, about 12 s each), for any
test module that imports the ``real_bundles`` fixture."""
from __future__ import annotations

import atexit
import functools
import shutil
import tempfile
from pathlib import Path

import pytest
from conftest import SHARED, require_freecadcmd, require_shared
from integration.freecad_tools import aplan

__all__ = ["REAL_MODELS", "real_bundles"]

REAL_MODELS = {"toy_truck": "toy_truck/asm_cement_mixer_truck.FCStd",
               "diaphragm_pump": "diaphragm_pump/asm_diaphragm_pump.FCStd"}


@functools.cache
def _exported() -> dict[str, Path]:
    # One folder per session, shared by every module that uses the fixture (a fixture imported into two
    # modules would run once per module).
    folder = Path(tempfile.mkdtemp(prefix="aplan-real-models-"))
    atexit.register(shutil.rmtree, folder, True)
    out = {}
    for name, path in REAL_MODELS.items():
        out[name] = folder / name
        aplan("export-freecad", str(require_shared(SHARED / "models" / path)), "-o", str(out[name]))
    return out


@pytest.fixture(scope="session")
def real_bundles() -> dict[str, Path]:
    """Model name -> its bundle folder, exported with the default settings (skips without FreeCAD, fails
    instead when APLAN_REQUIRE_FREECAD=1)."""
    require_freecadcmd()
    return _exported()
