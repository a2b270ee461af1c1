"""Shared fixtures: the repository layout, ../shared, and real FreeCAD; the background jobs of the session
(tests/background.py)."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import background
import disk
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
    require_freecad_gui()
    return freecad_gui_result(freecad_gui_run(tmp_path, script), out)


def require_freecad_gui() -> None:
    """Skip without FreeCAD, its GUI or xvfb-run; fail instead when APLAN_REQUIRE_FREECAD=1 (CI)."""
    require_freecadcmd()
    if shutil.which("freecad") is None or shutil.which("xvfb-run") is None:
        if os.environ.get("APLAN_REQUIRE_FREECAD") == "1":
            pytest.fail("APLAN_REQUIRE_FREECAD=1 but the FreeCAD GUI or xvfb-run is missing; install freecad and xvfb")
        pytest.skip("the FreeCAD GUI (freecad) or xvfb-run is not installed")


def freecad_gui_run(folder: Path, script: Path, display: int = 99, timeout: float = 300) -> subprocess.CompletedProcess:
    """The run of :func:`run_freecad_gui` without its checks (a background job may call it): FreeCAD's home in
    ``folder/home``; the X display the first free one from ``display`` on (background jobs start elsewhere
    than the tests, so that two Xvfb never race for one number)."""
    home = folder / "home"
    mod = home / ".local" / "share" / "FreeCAD" / "Mod"
    mod.mkdir(parents=True)
    (mod / "APLAN").symlink_to(REPO, target_is_directory=True)
    kept = {k: v for k, v in background.ENVIRONMENT.items() if k not in ("DISPLAY", "APLAN_PYTHON")}
    env = {**kept, "HOME": str(home), "QTWEBENGINE_CHROMIUM_FLAGS": "--no-sandbox --disable-gpu", "LANG": "C.UTF-8"}
    command = [shutil.which("xvfb-run"), "-n", str(display), "-a", "-s", "-screen 0 1280x800x24",
               shutil.which("freecad"), str(script)]
    return background.run(command, timeout=timeout, env=env)


def freecad_gui_result(done: subprocess.CompletedProcess, out: Path) -> dict:
    """The JSON a GUI script wrote to ``out``, asserting that it wrote one without an ``error``."""
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


_DISK: disk.Watch | None = None  # the disk's free space while the session runs, from the collection's end


def _jobs(item: pytest.Item) -> tuple:
    module = getattr(item, "module", None)
    return tuple(getattr(module, "BACKGROUND", ()))


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(session: pytest.Session, config: pytest.Config, items: list[pytest.Item]) -> None:
    """Modules that read background jobs (a ``BACKGROUND`` attribute) run after the others, whole and in their
    usual order, so that FreeCAD does their slow work while the others run."""
    if background.enabled():
        items[:] = [i for i in items if not _jobs(i)] + [i for i in items if _jobs(i)]


def pytest_collection_finish(session: pytest.Session) -> None:
    """Start the background jobs of the selected tests, in the order the tests will need them (only when
    what a lane runs is there, FreeCAD or ROS: without it those tests skip, or fail under
    APLAN_REQUIRE_FREECAD=1 or APLAN_REQUIRE_ROS=1, as before)."""
    if session.config.option.collectonly:
        return
    global _DISK
    # the whole suite (its background jobs, or hundreds of tests) needs disk.NEEDED_MB; a few tests, little
    needed = disk.NEEDED_MB if len(session.items) > 200 or any(map(_jobs, session.items)) else 50
    short = disk.shortage(needed)
    if short:
        pytest.exit(short, returncode=1)
    _DISK = disk.Watch(needed)
    there = {"freecad": bool(shutil.which("freecadcmd") or shutil.which("FreeCADCmd")),
             "ros": bool(shutil.which("rosmaster"))}
    background.start(job for item in session.items for job in _jobs(item) if there.get(job.lane, True))


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    """The background jobs' wall and CPU seconds, the slowest first, each lane's sums, and how long the tests
    waited for the jobs (where a FreeCAD-bound suite spends its time; on a loaded machine the CPU seconds are
    the figure to trust); and the least free space the disk had."""
    if _DISK is not None:
        terminalreporter.write_line(_DISK.summary())
    if not background.SECONDS:
        return
    terminalreporter.section("background jobs (wall seconds, CPU seconds)")
    for name, seconds in sorted(background.SECONDS.items(), key=lambda item: -item[1])[:25]:
        terminalreporter.write_line(f"{seconds:7.1f} s {background.CPU.get(name, 0.0):7.1f} s  {name}")
    lanes: dict[str, list[float]] = {}  # lane -> wall sum, CPU sum, first begin, last end
    for name, seconds in background.SECONDS.items():
        begun, ended = background.SPANS[name]
        sums = lanes.setdefault(background.LANES.get(name, "?"), [0.0, 0.0, begun, ended])
        sums[0] += seconds
        sums[1] += background.CPU.get(name, 0.0)
        sums[2], sums[3] = min(sums[2], begun), max(sums[3], ended)
    for lane, (seconds, cpu, begun, ended) in sorted(lanes.items()):
        if seconds >= 0.05:  # not test_background's own lanes
            terminalreporter.write_line(f"{seconds:7.1f} s {cpu:7.1f} s  in all, lane {lane} "
                                        f"({ended - begun:.1f} s from its first job's start to its last one's end)")
    waited = {name: s for name, s in background.WAITED.items() if s >= 0.05}
    terminalreporter.write_line(f"the tests waited {sum(waited.values()):.1f} s for jobs, the longest: "
                                + ", ".join(f"{name} {s:.1f} s" for name, s in
                                            sorted(waited.items(), key=lambda item: -item[1])[:5]))


def pytest_sessionfinish(session: pytest.Session) -> None:
    background.stop()
