"""The real models of ../shared/models exported once per test session (FreeCAD, about 12 s each), for any
test module that imports the ``real_bundles`` fixture (or calls :func:`real_bundle`). The exports are
background jobs (tests/background.py): a module that reads them imports ``BACKGROUND`` from here."""
from __future__ import annotations

import functools
import subprocess
from pathlib import Path

import pytest
from background import Job, folder
from conftest import SHARED, require_freecadcmd, require_shared
from integration.freecad_tools import aplan_process, succeeded

__all__ = ["BACKGROUND", "JOBS", "REAL_MODELS", "real_bundle", "real_bundles", "real_export_output"]

REAL_MODELS = {"toy_truck": "toy_truck/asm_cement_mixer_truck.FCStd",
               "diaphragm_pump": "diaphragm_pump/asm_diaphragm_pump.FCStd"}


@functools.cache
def _folder() -> Path:
    # One folder per session, shared by every module that uses the fixture (a fixture imported into two
    # modules would run once per module).
    return folder("real-models")


def _export(name: str) -> tuple[Path, subprocess.CompletedProcess]:
    """``aplan export-freecad`` of the model ``name`` with the default settings, in a process of its own (a
    background job may run it)."""
    bundle = _folder() / name
    model = SHARED / "models" / REAL_MODELS[name]
    return bundle, aplan_process("export-freecad", str(model), "-o", str(bundle))


#: Model name -> the job exporting it.
JOBS = {name: Job(f"export {name}", functools.partial(_export, name)) for name in REAL_MODELS}
#: The jobs of a module reading the real models (tests/background.py).
BACKGROUND = tuple(JOBS.values())


@functools.cache
def _exported(name: str) -> tuple[Path, str]:
    require_freecadcmd()
    require_shared(SHARED / "models" / REAL_MODELS[name])
    bundle, done = JOBS[name].result()
    return bundle, succeeded(done).stdout


def real_bundle(name: str) -> Path:
    """The bundle folder of the real model ``name`` (a key of ``REAL_MODELS``), exported with the default
    settings the first time it is asked for in this session. Tests only read it: copy it before changing it.
    Skips without FreeCAD, fails instead when APLAN_REQUIRE_FREECAD=1."""
    require_freecadcmd()
    return _exported(name)[0]


def real_export_output(name: str) -> str:
    """What ``aplan export-freecad`` printed when it exported the real model ``name`` (see ``real_bundle``)."""
    require_freecadcmd()
    return _exported(name)[1]


@pytest.fixture(scope="session")
def real_bundles() -> dict[str, Path]:
    """Model name -> its bundle folder, exported with the default settings (skips without FreeCAD, fails
    instead when APLAN_REQUIRE_FREECAD=1)."""
    return {name: real_bundle(name) for name in REAL_MODELS}
