"""Shared fixtures: the repository layout, ../shared, and real FreeCAD."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
SHARED = REPO.parent / "shared"
PEN_MODELS = SHARED / "models" / "bourjault_pen"


def require_freecadcmd() -> str:
    """Path of freecadcmd; skips when FreeCAD is absent, fails instead when APLAN_REQUIRE_FREECAD=1 (CI)."""
    path = shutil.which("freecadcmd") or shutil.which("FreeCADCmd")
    if path is None:
        if os.environ.get("APLAN_REQUIRE_FREECAD") == "1":
            pytest.fail("APLAN_REQUIRE_FREECAD=1 but freecadcmd is not on PATH; install Debian's freecad-python3")
        pytest.skip("FreeCAD is not installed (freecadcmd not on PATH)")
    return path


def run_freecad_gui(tmp_path: Path, script: Path, out: Path) -> dict:
    """Run ``script`` in the real FreeCAD window under Xvfb, with this repository installed as the APLAN
    workbench in a fresh home, and return the JSON the script wrote to ``out`` (asserting that it wrote one
    without an ``error``). Skips without the FreeCAD GUI or xvfb-run; fails instead when
    APLAN_REQUIRE_FREECAD=1 (CI)."""
    require_freecadcmd()
    freecad, xvfb = shutil.which("freecad"), shutil.which("xvfb-run")
    if freecad is None or xvfb is None:
        if os.environ.get("APLAN_REQUIRE_FREECAD") == "1":
            pytest.fail("APLAN_REQUIRE_FREECAD=1 but the FreeCAD GUI or xvfb-run is missing; install freecad and xvfb")
        pytest.skip("the FreeCAD GUI (freecad) or xvfb-run is not installed")
    home = tmp_path / "home"
    mod = home / ".local" / "share" / "FreeCAD" / "Mod"
    mod.mkdir(parents=True)
    (mod / "APLAN").symlink_to(REPO, target_is_directory=True)
    env = {**{k: v for k, v in os.environ.items() if k not in ("DISPLAY", "APLAN_PYTHON")}, "HOME": str(home),
           "QTWEBENGINE_CHROMIUM_FLAGS": "--no-sandbox --disable-gpu", "LANG": "C.UTF-8"}
    done = subprocess.run([xvfb, "-a", "-s", "-screen 0 1280x800x24", freecad, str(script)], capture_output=True,
                          text=True, timeout=300, env=env, stdin=subprocess.DEVNULL, check=False)
    assert out.is_file(), f"the GUI test wrote no result:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    data = json.loads(out.read_text())
    assert "error" not in data, data.get("error")
    return data


def require_shared(path: Path) -> Path:
    if not path.exists():
        pytest.fail(f"{path} is missing: the tests expect ../shared beside the repository")
    return path


@pytest.fixture(scope="session")
def pen():
    from planner import resolve_product

    return resolve_product("pen")
