"""The real models of ../shared/models exported once per test session (FreeCAD, about 12 s each), for any
test module that imports the ``real_bundles`` fixture (or calls :func:`real_bundle`)."""
from __future__ import annotations

import atexit
import functools
import shutil
import tempfile
from pathlib import Path

import pytest
from conftest import SHARED, require_freecadcmd, require_shared
from integration.freecad_tools import aplan

__all__ = ["REAL_MODELS", "real_bundle", "real_bundles", "real_export_output"]

REAL_MODELS = {"toy_truck": "toy_truck/asm_cement_mixer_truck.FCStd",
               "diaphragm_pump": "diaphragm_pump/asm_diaphragm_pump.FCStd"}


@functools.cache
def _folder() -> Path:
    # One folder per session, shared by every module that uses the fixture (a fixture imported into two
    # modules would run once per module).
    folder = Path(tempfile.mkdtemp(prefix="aplan-real-models-"))
    atexit.register(shutil.rmtree, folder, True)
    return folder


@functools.cache
def _export(name: str) -> tuple[Path, str]:
    bundle = _folder() / name
    done = aplan("export-freecad", str(require_shared(SHARED / "models" / REAL_MODELS[name])), "-o", str(bundle))
    return bundle, done.stdout


def real_bundle(name: str) -> Path:
    """The bundle folder of the real model ``name`` (a key of ``REAL_MODELS``), exported with the default
    settings the first time it is asked for in this session. Tests only read it: copy it before changing it.
    Skips without FreeCAD, fails instead when APLAN_REQUIRE_FREECAD=1."""
    require_freecadcmd()
    return _export(name)[0]


def real_export_output(name: str) -> str:
    """What ``aplan export-freecad`` printed when it exported the real model ``name`` (see ``real_bundle``)."""
    require_freecadcmd()
    return _export(name)[1]


@pytest.fixture(scope="session")
def real_bundles() -> dict[str, Path]:
    """Model name -> its bundle folder, exported with the default settings (skips without FreeCAD, fails
    instead when APLAN_REQUIRE_FREECAD=1)."""
    return {name: real_bundle(name) for name in REAL_MODELS}
