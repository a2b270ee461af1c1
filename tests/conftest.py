"""Shared fixtures: the repository layout, ../shared, and real FreeCAD."""
from __future__ import annotations

import os
import shutil
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


def require_shared(path: Path) -> Path:
    if not path.exists():
        pytest.fail(f"{path} is missing: the tests expect ../shared beside the repository")
    return path


@pytest.fixture(scope="session")
def pen():
    from planner import resolve_product

    return resolve_product("pen")
